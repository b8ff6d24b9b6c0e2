//! Diffuse area light on one emissive triangle (pbrt-v4 section 12.3): emitted radiance from
//! the material (emissiveFactor x strength x emissiveTexture), one-sided on the front face
//! (counter-clockwise winding) unless the material is double-sided. Points are sampled
//! uniformly by area and the pdf converted to solid angle.

use crate::light::{LightLiSample, LightSampleContext};
use crate::sampling::warp::sample_uniform_triangle;
use crate::scene::Scene;
use glam::{Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub triangle: u32,
    pub area: f32,
    /// Unit geometric normal of the front face.
    pub normal: Vec3,
    pub two_sided: bool,
    /// Mean emitted radiance, for the power estimate.
    pub mean_radiance: Vec3,
}

impl AreaLight {
    /// Radiance leaving point `uv` of the light in direction `w`.
    pub fn l(&self, scene: &Scene, uv: Vec2, w: Vec3) -> Vec3 {
        if !self.two_sided && self.normal.dot(w) <= 0.0 {
            return Vec3::ZERO;
        }
        let material = scene.triangle_material(self.triangle);
        material.emitted(&scene.textures, uv)
    }

    pub fn sample_li(
        &self,
        scene: &Scene,
        ctx: &LightSampleContext,
        u: Vec2,
    ) -> Option<LightLiSample> {
        let b = sample_uniform_triangle(u);
        let (p_light, uv) = scene.triangle_point(self.triangle, b);
        let d = p_light - ctx.p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_light = self.normal.dot(-wi).abs();
        if cos_light == 0.0 {
            return None;
        }
        let pdf = dist2 / (cos_light * self.area);
        let l = self.l(scene, uv, -wi);
        if l == Vec3::ZERO || !pdf.is_finite() {
            return None;
        }
        Some(LightLiSample {
            l,
            wi,
            pdf,
            p_light,
            n_light: self.normal,
            dist,
            is_delta: false,
        })
    }

    /// Solid-angle pdf of `sample_li` from `p_ref` for the point `p_light` on the light.
    pub fn pdf_li(&self, p_ref: Vec3, p_light: Vec3) -> f32 {
        let d = p_light - p_ref;
        let dist2 = d.length_squared();
        let cos_light = self.normal.dot(d).abs() / dist2.sqrt();
        if cos_light == 0.0 || dist2 == 0.0 {
            return 0.0;
        }
        dist2 / (cos_light * self.area)
    }

    pub fn power(&self) -> Vec3 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        std::f32::consts::PI * self.area * sides * self.mean_radiance
    }
}
