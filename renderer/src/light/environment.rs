//! Uniform environment: constant radiance from every direction, sampled uniformly over the
//! sphere (pbrt-v4 section 12.5.1). Scenes without an emitter get one of radiance 1.

use crate::light::{LightLiSample, LightSampleContext};
use crate::sampling::warp::{sample_uniform_sphere, uniform_sphere_pdf};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct UniformEnvironment {
    pub radiance: Vec3,
    pub scene_radius: f32,
}

impl UniformEnvironment {
    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2) -> Option<LightLiSample> {
        let wi = sample_uniform_sphere(u);
        Some(LightLiSample {
            l: self.radiance,
            wi,
            pdf: uniform_sphere_pdf(),
            p_light: ctx.p + wi * (2.0 * self.scene_radius),
            n_light: Vec3::ZERO,
            dist: f32::INFINITY,
            is_delta: false,
        })
    }

    /// Solid-angle pdf of `sample_li` for any direction.
    pub fn pdf_li(&self) -> f32 {
        uniform_sphere_pdf()
    }

    pub fn power(&self) -> Vec3 {
        4.0 * PI * PI * self.scene_radius * self.scene_radius * self.radiance
    }
}
