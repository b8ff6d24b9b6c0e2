//! Lambertian reflection (pbrt-v4 section 9.2): f = R / pi on the side of wo, both faces.

use crate::material::BsdfSample;
use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct DiffuseBsdf {
    pub r: Vec3,
}

impl DiffuseBsdf {
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z * wi.z > 0.0 {
            self.r * FRAC_1_PI
        } else {
            Vec3::ZERO
        }
    }

    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let mut wi = sample_cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample::reflection(self.f(wo, wi), wi, pdf, false))
    }

    /// Solid-angle pdf.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z * wi.z > 0.0 {
            cosine_hemisphere_pdf(wi.z.abs())
        } else {
            0.0
        }
    }
}
