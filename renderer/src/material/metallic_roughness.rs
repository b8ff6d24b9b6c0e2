//! The glTF 2.0 metallic-roughness BRDF (glTF spec, appendix B): Trowbridge-Reitz with
//! alpha = roughness^2, height-correlated Smith masking, Schlick Fresnel, and
//!
//! ```text
//!     dielectric_brdf = fresnel_mix(ior, diffuse_brdf(base), specular_brdf)      (B.3.5)
//!     metal_brdf      = conductor_fresnel(base, specular_brdf)
//!     material        = mix(dielectric_brdf, metal_brdf, metallic)
//! ```
//!
//! Deviation: `fresnel_mix` gains energy at grazing angles, so the diffuse base of the
//! dielectric part is coupled to the specular layer by albedo scaling instead
//! (`material::layering`, Kelemen & Szirmay-Kalos 2001); the specular layer is glTF's.
//!
//! With KHR_materials_transmission the dielectric part is split once more: a share
//! `transmission` of it is a rough dielectric interface (Walter et al. 2007) tinted by the base
//! colour, refracting as a solid of index `ior`, as DESIGN.md section 2 asks. The BSDF is a
//! linear mixture of three components and is sampled as a mixture of its lobes: a component is
//! chosen by its weight, then a lobe within it; the pdf is the same mixture of lobe pdfs, so
//! `sample_f` and `pdf` agree exactly.
//!
//! KHR_materials_specular changes the dielectric (plastic) component's specular layer as the
//! extension defines (its section "Implementation"):
//!
//! ```text
//!     f0  = min(((ior - 1) / (ior + 1))^2 specularColor, 1) specular
//!     f90 = specular
//!     F   = f0 + (f90 - f0) (1 - V.H)^5
//! ```
//!
//! and the albedo coupling follows, per channel, from the layer's albedo at that (f0, f90)
//! (`layering::specular_albedo`). The rough glass of the transmission component keeps its
//! exact Fresnel of `ior`. KHR_materials_sheen puts a fibre layer over the base
//! (`material::sheen`) and KHR_materials_clearcoat a coat over everything, the sheen included
//! (`material::clearcoat`), as the extensions order them; each is sampled as one more lobe of
//! the mixture:
//!
//! ```text
//!     f = c f_coat + f_diffuse' S + min(t_o, t_i) (f_glossy S + f_sheen),  S = sheen's base scale
//! ```

use crate::material::clearcoat::Clearcoat;
use crate::material::dielectric::RoughDielectricBsdf;
use crate::material::layering::{
    specular_albedo, specular_albedo_average, transmitted_average_of_two,
};
use crate::material::microfacet::{TrowbridgeReitz, fresnel_schlick, fresnel_schlick_f90};
use crate::material::sheen::Sheen;
use crate::material::{BsdfSample, TransportMode};
use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct MetallicRoughnessBsdf {
    pub base_color: Vec3,
    pub metallic: f32,
    pub transmission: f32,
    pub eta: f32,
    pub distrib: TrowbridgeReitz,
    /// The plastic's specular reflectance at normal and grazing incidence, from `ior` and
    /// KHR_materials_specular (`dielectric_reflectance`).
    pub specular_f0: Vec3,
    pub specular_f90: f32,
    pub coat: Clearcoat,
    pub sheen: Sheen,
}

/// Mirrors a reflection pair into the upper hemisphere so reflection lobes serve both faces.
fn to_upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 {
        (Vec3::new(wo.x, wo.y, -wo.z), Vec3::new(wi.x, wi.y, -wi.z))
    } else {
        (wo, wi)
    }
}

impl MetallicRoughnessBsdf {
    /// Whether a lobe spreads light over the whole hemisphere (the plastic's diffuse base or
    /// a sheen), where a glossy-only material (a metal, rough glass) has only peaks.
    pub fn has_diffuse_lobe(&self) -> bool {
        let (_, plastic, _) = self.weights();
        plastic > 0.0 || self.sheen.color != Vec3::ZERO
    }

    fn weights(&self) -> (f32, f32, f32) {
        let metal = self.metallic.clamp(0.0, 1.0);
        let tr = self.transmission.clamp(0.0, 1.0);
        (metal, (1.0 - metal) * (1.0 - tr), (1.0 - metal) * tr)
    }

    fn glass(&self) -> RoughDielectricBsdf {
        RoughDielectricBsdf {
            eta: self.eta,
            tint: self.base_color,
            distrib: self.distrib,
        }
    }

    /// The plastic component's specular reflectance (f0, f90) for index `eta` and
    /// KHR_materials_specular's factor and colour ((f0 of ior, 1) for 1 and white).
    pub fn dielectric_reflectance(eta: f32, specular: f32, specular_color: Vec3) -> (Vec3, f32) {
        let f0_ior = ((eta - 1.0) / (eta + 1.0)).powi(2);
        let f0 = (f0_ior * specular_color).min(Vec3::ONE) * specular;
        (f0, specular)
    }

    fn dielectric_f0_f90(&self) -> (Vec3, f32) {
        (self.specular_f0, self.specular_f90)
    }

    /// Probability of the specular lobe within the dielectric (plastic) component: the
    /// specular layer's share of the component's albedo, kept in [0.1, 0.9].
    fn plastic_specular_prob(&self, wo: Vec3) -> f32 {
        let (f0, f90) = self.dielectric_f0_f90();
        let e = specular_albedo(wo.z, self.distrib.alpha, f0, f90);
        let diffuse = crate::geometry::luminance((Vec3::ONE - e) * self.base_color);
        let e = crate::geometry::luminance(e);
        (e / (e + diffuse).max(1e-6)).clamp(0.1, 0.9)
    }

    /// The albedo-scaled diffuse base (Kelemen & Szirmay-Kalos 2001, eq. 5), per channel,
    /// beneath the specular layer and, where there is one, the clearcoat: the scale is the
    /// light both let through at mu_o and at mu_i over its cosine-weighted average
    /// (`material::clearcoat`).
    fn coupled_diffuse(&self, uo: Vec3, ui: Vec3) -> Vec3 {
        let alpha = self.distrib.alpha;
        let (f0, f90) = self.dielectric_f0_f90();
        let through = |mu: f32| {
            (Vec3::ONE - specular_albedo(mu, alpha, f0, f90)) * (1.0 - self.coat.reflected(mu))
        };
        let average = if self.coat.is_present() {
            let coat = (self.coat.distrib.alpha, 0.04, self.coat.weight);
            transmitted_average_of_two((alpha, f0, f90), coat)
        } else {
            Vec3::ONE - specular_albedo_average(alpha, f0, f90)
        };
        let scale = through(uo.z) * through(ui.z) / average.max(Vec3::splat(1e-3));
        self.base_color * scale * FRAC_1_PI
    }

    /// D G / (4 |cos_o cos_i|) for an upper-hemisphere pair, and the half vector.
    fn specular(&self, wo: Vec3, wi: Vec3) -> Option<(f32, Vec3)> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return None;
        }
        let wm = (wo + wi).normalize_or_zero();
        if wm == Vec3::ZERO {
            return None;
        }
        Some((
            self.distrib.d(wm) * self.distrib.g(wo, wi) / (4.0 * wo.z * wi.z),
            wm,
        ))
    }

    fn specular_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let wm = (wo + wi).normalize_or_zero();
        if wo.z <= 0.0 || wi.z <= 0.0 || wm == Vec3::ZERO {
            return 0.0;
        }
        self.distrib.d_visible(wo, wm) / (4.0 * wo.dot(wm))
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        let (diffuse, glossy) = self.f_base(wo, wi, mode);
        if !self.coat.is_present() && !self.sheen.is_present() {
            return diffuse + glossy;
        }
        let (mu_o, mu_i) = (wo.z.abs(), wi.z.abs());
        let s = self.sheen.base_scale(mu_o, mu_i);
        let t = self.coat.glossy_scale(mu_o, mu_i);
        let mut f = (diffuse + glossy * t) * s;
        if wo.z * wi.z > 0.0 {
            let (uo, ui) = to_upper(wo, wi);
            f += self.sheen.f(uo, ui) * t + Vec3::splat(self.coat.f(uo, ui));
        }
        f
    }

    /// Solid-angle pdf of `sample_f`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let base = self.pdf_base(wo, wi);
        if !self.coat.is_present() && !self.sheen.is_present() {
            return base;
        }
        let p_coat = self.coat.sample_prob(wo.z.abs());
        let p_sheen = self.sheen.sample_prob(wo.z.abs());
        let mut pdf = (1.0 - p_coat) * (1.0 - p_sheen) * base;
        if wo.z * wi.z > 0.0 {
            let (uo, ui) = to_upper(wo, wi);
            pdf += p_coat * self.coat.pdf(uo, ui);
            pdf += (1.0 - p_coat) * p_sheen * cosine_hemisphere_pdf(ui.z);
        }
        pdf
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let p_coat = self.coat.sample_prob(wo.z.abs());
        let p_sheen = self.sheen.sample_prob(wo.z.abs());
        // uc picks the coat, then (rescaled) the sheen, then (rescaled) the base's lobe.
        let uc_sheen = (uc - p_coat) / (1.0 - p_coat);
        let wi = if uc < p_coat || uc_sheen < p_sheen {
            let (uo, _) = to_upper(wo, wo);
            let ui = if uc < p_coat {
                self.coat.sample(uo, u)
            } else {
                sample_cosine_hemisphere(u)
            };
            if ui.z <= 0.0 {
                return None;
            }
            Vec3::new(ui.x, ui.y, ui.z.copysign(wo.z))
        } else {
            self.sample_base_wi(wo, (uc_sheen - p_sheen) / (1.0 - p_sheen), u, mode)?
        };
        let pdf = self.pdf(wo, wi);
        let f = self.f(wo, wi, mode);
        if !(pdf > 0.0) || !f.is_finite() {
            return None;
        }
        if wo.z * wi.z > 0.0 {
            Some(BsdfSample::reflection(f, wi, pdf, false))
        } else {
            let etap = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
            Some(BsdfSample::transmission(f, wi, pdf, false, etap))
        }
    }

    /// The base material (metal, plastic and glass components), as its diffuse part (coupled
    /// to the layers above it in `coupled_diffuse`) and its glossy part (which a coat scales
    /// by `glossy_scale`).
    fn f_base(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (Vec3, Vec3) {
        let (w_metal, w_plastic, w_glass) = self.weights();
        let (mut diffuse, mut f) = (Vec3::ZERO, Vec3::ZERO);
        if w_glass > 0.0 {
            f += w_glass * self.glass().f(wo, wi, mode);
        }
        if wo.z * wi.z > 0.0 {
            let (uo, ui) = to_upper(wo, wi);
            if let Some((spec, wm)) = self.specular(uo, ui) {
                let cos_h = uo.dot(wm);
                if w_metal > 0.0 {
                    f += w_metal * spec * fresnel_schlick(self.base_color, cos_h);
                }
                if w_plastic > 0.0 {
                    let (f0, f90) = self.dielectric_f0_f90();
                    let fr = fresnel_schlick_f90(f0, f90, cos_h);
                    diffuse = w_plastic * self.coupled_diffuse(uo, ui);
                    f += w_plastic * fr * spec;
                }
            }
        }
        (diffuse, f)
    }

    fn pdf_base(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (w_metal, w_plastic, w_glass) = self.weights();
        let mut pdf = 0.0;
        if w_glass > 0.0 {
            pdf += w_glass * self.glass().pdf(wo, wi);
        }
        if wo.z * wi.z > 0.0 {
            let (uo, ui) = to_upper(wo, wi);
            let spec = self.specular_pdf(uo, ui);
            pdf += w_metal * spec;
            if w_plastic > 0.0 {
                let ps = self.plastic_specular_prob(uo);
                pdf += w_plastic * (ps * spec + (1.0 - ps) * cosine_hemisphere_pdf(ui.z));
            }
        }
        pdf
    }

    /// A direction from the base's mixture of lobes (`uc` picks the lobe).
    fn sample_base_wi(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<Vec3> {
        let (w_metal, w_plastic, w_glass) = self.weights();
        let wi = if uc < w_glass {
            // Reuse uc, rescaled, for the interface's reflect/refract choice.
            let sample = self.glass().sample_f(wo, uc / w_glass, u, mode)?;
            sample.wi
        } else {
            let (uo, _) = to_upper(wo, wo);
            let ur = (uc - w_glass) / (w_metal + w_plastic).max(f32::MIN_POSITIVE);
            let specular = ur * (w_metal + w_plastic) < w_metal || {
                let up = (ur * (w_metal + w_plastic) - w_metal) / w_plastic.max(f32::MIN_POSITIVE);
                up < self.plastic_specular_prob(uo)
            };
            let ui = if specular {
                let wm = self.distrib.sample_wm(uo, u);
                crate::geometry::reflect(uo, wm)
            } else {
                sample_cosine_hemisphere(u)
            };
            if ui.z <= 0.0 {
                return None;
            }
            if wo.z < 0.0 {
                Vec3::new(ui.x, ui.y, -ui.z)
            } else {
                ui
            }
        };
        Some(wi)
    }
}
