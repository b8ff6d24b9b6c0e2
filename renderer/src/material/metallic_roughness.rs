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

use crate::material::dielectric::RoughDielectricBsdf;
use crate::material::layering::{specular_albedo, specular_albedo_average};
use crate::material::microfacet::{TrowbridgeReitz, fresnel_schlick};
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

    fn f0_dielectric(&self) -> f32 {
        ((self.eta - 1.0) / (self.eta + 1.0)).powi(2)
    }

    /// Probability of the specular lobe within the dielectric (plastic) component: the
    /// specular layer's share of the component's albedo, kept in [0.1, 0.9].
    fn plastic_specular_prob(&self, wo: Vec3) -> f32 {
        let e = specular_albedo(wo.z, self.distrib.alpha, self.f0_dielectric());
        let diffuse = (1.0 - e) * crate::geometry::luminance(self.base_color);
        (e / (e + diffuse).max(1e-6)).clamp(0.1, 0.9)
    }

    /// The albedo-scaled diffuse base (Kelemen & Szirmay-Kalos 2001, eq. 5).
    fn coupled_diffuse(&self, uo: Vec3, ui: Vec3) -> Vec3 {
        let (alpha, f0) = (self.distrib.alpha, self.f0_dielectric());
        let e_avg = specular_albedo_average(alpha, f0);
        let scale = (1.0 - specular_albedo(uo.z, alpha, f0))
            * (1.0 - specular_albedo(ui.z, alpha, f0))
            / (1.0 - e_avg).max(1e-3);
        self.base_color * (FRAC_1_PI * scale)
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
        let (w_metal, w_plastic, w_glass) = self.weights();
        let mut f = Vec3::ZERO;
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
                    let fr = fresnel_schlick(Vec3::splat(self.f0_dielectric()), cos_h).x;
                    f += w_plastic * (self.coupled_diffuse(uo, ui) + Vec3::splat(fr * spec));
                }
            }
        }
        f
    }

    /// Solid-angle pdf of `sample_f`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
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

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
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
}
