//! KHR_lights_punctual: point, spot and directional lights. Photometric numbers are taken as
//! radiometric as they stand (DESIGN.md section 1): a point or spot light's intensity is
//! radiant intensity (W/sr), a directional light's is irradiance (W/m^2) at normal incidence.

use crate::geometry::Frame;
use crate::light::{LightLiSample, LightSampleContext};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Vec3,
}

impl PointLight {
    pub fn sample_li(&self, ctx: &LightSampleContext) -> Option<LightLiSample> {
        let d = self.position - ctx.p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        Some(LightLiSample {
            l: self.intensity / dist2,
            wi: d / dist,
            pdf: 1.0,
            p_light: self.position,
            n_light: Vec3::ZERO,
            dist,
            is_delta: true,
        })
    }

    pub fn power(&self) -> Vec3 {
        4.0 * PI * self.intensity
    }
}

/// Spot light along `frame.n`, with the smooth falloff of the KHR_lights_punctual spec
/// (the square of a linear ramp in cos theta between the outer and inner cone).
#[derive(Clone, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    pub frame: Frame,
    pub intensity: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl SpotLight {
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta <= self.cos_outer {
            return 0.0;
        }
        let range = self.cos_inner - self.cos_outer;
        if range <= 1e-6 {
            return 1.0;
        }
        let t = ((cos_theta - self.cos_outer) / range).clamp(0.0, 1.0);
        t * t
    }

    /// A point light's sample, scaled by the falloff towards the reference point.
    pub fn sample_li(&self, ctx: &LightSampleContext) -> Option<LightLiSample> {
        let point = PointLight {
            position: self.position,
            intensity: self.intensity,
        };
        let mut sample = point.sample_li(ctx)?;
        let falloff = self.falloff((-sample.wi).dot(self.frame.n));
        if falloff == 0.0 {
            return None;
        }
        sample.l *= falloff;
        Some(sample)
    }

    /// pbrt-v4's estimate (section 12.2.2): the cone's solid angle at the mean cut-off.
    pub fn power(&self) -> Vec3 {
        self.intensity * 2.0 * PI * (1.0 - 0.5 * (self.cos_inner + self.cos_outer))
    }
}

/// Directional light travelling along `direction` (unit).
#[derive(Clone, Debug)]
pub struct DirectionalLight {
    pub direction: Vec3,
    pub irradiance: Vec3,
    pub scene_radius: f32,
}

impl DirectionalLight {
    pub fn sample_li(&self, ctx: &LightSampleContext) -> Option<LightLiSample> {
        let wi = -self.direction;
        Some(LightLiSample {
            l: self.irradiance,
            wi,
            pdf: 1.0,
            p_light: ctx.p + wi * (2.0 * self.scene_radius),
            n_light: Vec3::ZERO,
            dist: f32::INFINITY,
            is_delta: true,
        })
    }

    pub fn power(&self) -> Vec3 {
        PI * self.scene_radius * self.scene_radius * self.irradiance
    }
}
