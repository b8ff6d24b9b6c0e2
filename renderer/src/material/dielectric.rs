//! Dielectric interfaces: smooth (a delta BSDF, pbrt-v4 section 9.5) and rough (Walter,
//! Marschner, Li & Torrance, "Microfacet Models for Refraction through Rough Surfaces", EGSR
//! 2007, eqs. 20-21 and 38-41, in pbrt-v4's formulation of section 9.7).
//!
//! `eta` is the index inside over outside; +z points outside. Transmitted radiance is scaled by
//! 1/eta'^2 in radiance transport (pbrt-v4 section 9.5.2) and not in importance transport.
//! `tint` multiplies transmission only (glTF's baseColor on transmissive materials).

use crate::geometry::refract;
use crate::material::microfacet::{TrowbridgeReitz, fresnel_dielectric};
use crate::material::{BsdfSample, TransportMode};
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct DielectricBsdf {
    pub eta: f32,
    pub tint: Vec3,
}

impl DielectricBsdf {
    pub fn sample_f(&self, wo: Vec3, uc: f32, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.eta == 1.0 {
            // Index-matched: light passes straight through.
            return Some(BsdfSample::transmission(
                self.tint / wo.z.abs(),
                -wo,
                1.0,
                true,
                1.0,
            ));
        }
        let r = fresnel_dielectric(wo.z, self.eta);
        let t = 1.0 - r;
        if uc < r / (r + t) {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample::reflection(
                Vec3::splat(r / wi.z.abs()),
                wi,
                r / (r + t),
                true,
            ));
        }
        let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
        let mut ft = self.tint * (t / wi.z.abs());
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        Some(BsdfSample::transmission(ft, wi, t / (r + t), true, etap))
    }
}

#[derive(Clone, Copy, Debug)]
pub struct RoughDielectricBsdf {
    pub eta: f32,
    pub tint: Vec3,
    pub distrib: TrowbridgeReitz,
}

/// Generalised half vector of a reflection or refraction pair (Walter et al. eq. 16), facing +z,
/// and eta' of the pair; None for configurations no microfacet can produce.
fn half_vector(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
    let (cos_o, cos_i) = (wo.z, wi.z);
    if cos_o == 0.0 || cos_i == 0.0 {
        return None;
    }
    let reflect = cos_o * cos_i > 0.0;
    let etap = if reflect {
        1.0
    } else if cos_o > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if wm.length_squared() == 0.0 {
        return None;
    }
    let mut wm = wm.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    // Back-facing microfacets contribute nothing.
    if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

impl RoughDielectricBsdf {
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        let Some((wm, etap, reflect)) = half_vector(wo, wi, self.eta) else {
            return Vec3::ZERO;
        };
        let fr = fresnel_dielectric(wo.dot(wm), self.eta);
        let d = self.distrib.d(wm);
        let g = self.distrib.g(wo, wi);
        if reflect {
            return Vec3::splat(d * g * fr / (4.0 * wi.z * wo.z).abs());
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
        if denom == 0.0 {
            return Vec3::ZERO;
        }
        let mut ft = d * (1.0 - fr) * g * (wi.dot(wm) * wo.dot(wm) / denom).abs();
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        self.tint * ft
    }

    /// Solid-angle pdf of `sample_f`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((wm, etap, reflect)) = half_vector(wo, wi, self.eta) else {
            return 0.0;
        };
        let r = fresnel_dielectric(wo.dot(wm), self.eta);
        let t = 1.0 - r;
        if reflect {
            self.distrib.d_visible(wo, wm) / (4.0 * wo.dot(wm).abs()) * r / (r + t)
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            self.distrib.d_visible(wo, wm) * dwm_dwi * t / (r + t)
        }
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let r = fresnel_dielectric(wo.dot(wm), self.eta);
        let t = 1.0 - r;
        let wi = if uc < r / (r + t) {
            let wi = crate::geometry::reflect(wo, wm);
            if wo.z * wi.z <= 0.0 {
                return None;
            }
            wi
        } else {
            let (wi, _) = refract(wo, wm, self.eta)?;
            if wo.z * wi.z >= 0.0 || wi.z == 0.0 {
                return None;
            }
            wi
        };
        let pdf = self.pdf(wo, wi);
        let f = self.f(wo, wi, mode);
        if !(pdf > 0.0) || !f.is_finite() {
            return None;
        }
        let etap = if wo.z * wi.z > 0.0 {
            1.0
        } else if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        Some(if etap == 1.0 {
            BsdfSample::reflection(f, wi, pdf, false)
        } else {
            BsdfSample::transmission(f, wi, pdf, false, etap)
        })
    }
}
