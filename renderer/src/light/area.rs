//! Diffuse area light on one emissive triangle (pbrt-v4 section 12.3): emitted radiance from
//! the material (emissiveFactor x strength x emissiveTexture), one-sided on the front face
//! (counter-clockwise winding) unless the material is double-sided. Points are sampled
//! uniformly by area and the pdf converted to solid angle.

use crate::geometry::{interpolate2, interpolate3};
use crate::light::{LightLiSample, LightSampleContext};
use crate::material::{AlphaMode, TextureRef};
use crate::sampling::warp::sample_uniform_triangle;
use crate::texture::{TexCoords, Texture};
use glam::{Vec2, Vec3};

/// The light of one emissive triangle: its geometry and its material's emission, copied out
/// of the scene so that the light needs nothing else (but the textures) to be sampled.
#[derive(Clone, Debug)]
pub struct AreaLight {
    pub positions: [Vec3; 3],
    /// TEXCOORD_0 and TEXCOORD_1 at the corners.
    pub uvs: [[Vec2; 3]; 2],
    /// The material's emitted radiance, scaled by `emissive_texture` where there is one.
    pub emission: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub area: f32,
    /// Unit geometric normal of the front face.
    pub normal: Vec3,
    pub two_sided: bool,
    /// Mean emitted radiance, for the power estimate.
    pub mean_radiance: Vec3,
    /// Where the material's alphaMode is MASK or BLEND: the light emits only where the
    /// surface is (rays pass through the rest, so nothing there could emit). Boxed: most
    /// lights have none, and every light is as large as the largest kind.
    pub cutout: Option<Box<Cutout>>,
}

/// An emitter's alpha (baseColorFactor's alpha times its base colour texture's) and mode
/// (MASK or BLEND). Vertex colours' alpha is not read here: emitters cut out by vertex alpha
/// emit everywhere.
#[derive(Clone, Copy, Debug)]
pub struct Cutout {
    pub alpha: f32,
    pub texture: Option<TextureRef>,
    pub mode: AlphaMode,
}

impl Cutout {
    fn alpha_at(&self, textures: &[Texture], uv: &TexCoords) -> f32 {
        let texture = self
            .texture
            .and_then(|t| Some(textures.get(t.texture as usize)?.lookup(t.uv(uv)).w));
        self.alpha * texture.unwrap_or(1.0)
    }
}

impl AreaLight {
    /// Radiance leaving the point with texture coordinates `uv` in direction `w`.
    pub fn l(&self, textures: &[Texture], uv: &TexCoords, w: Vec3) -> Vec3 {
        if !self.two_sided && self.normal.dot(w) <= 0.0 {
            return Vec3::ZERO;
        }
        if let Some(c) = &self.cutout
            && let AlphaMode::Mask(cutoff) = c.mode
            && c.alpha_at(textures, uv) < cutoff
        {
            return Vec3::ZERO;
        }
        let texture = self
            .emissive_texture
            .and_then(|t| Some((textures.get(t.texture as usize)?, t.uv(uv))));
        self.emission * texture.map_or(Vec3::ONE, |(t, uv)| t.lookup(uv).truncate())
    }

    /// Radiance leaving a point that was sampled on the light rather than hit: a BLEND
    /// emitter is there with probability alpha, which a hit has already decided and a
    /// sample must weigh in, so that both estimate alpha Le.
    pub fn l_sampled(&self, textures: &[Texture], uv: &TexCoords, w: Vec3) -> Vec3 {
        let l = self.l(textures, uv, w);
        match &self.cutout {
            Some(c) if c.mode == AlphaMode::Blend => l * c.alpha_at(textures, uv).clamp(0.0, 1.0),
            _ => l,
        }
    }

    /// The point and texture coordinates at barycentric coordinates `b`.
    pub fn point(&self, b: Vec3) -> (Vec3, TexCoords) {
        let uv = self.uvs.map(|set| interpolate2(&set, b));
        (interpolate3(&self.positions, b), uv)
    }

    pub fn sample_li(
        &self,
        textures: &[Texture],
        ctx: &LightSampleContext,
        u: Vec2,
    ) -> Option<LightLiSample> {
        let b = sample_uniform_triangle(u);
        let (p_light, uv) = self.point(b);
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
        let l = self.l_sampled(textures, &uv, -wi);
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

#[cfg(test)]
mod tests {
    use crate::light::{Light, LightSampleContext};
    use crate::material::Material;
    use crate::procedural::quad;
    use crate::sampling::chi2::test_directions;
    use crate::scene::triangle::{RayShear, intersect_triangle};
    use crate::scene::{Scene, SceneDescription};
    use glam::Vec3;

    #[test]
    fn sampled_directions_match_the_solid_angle_pdf() {
        // A tilted emitting quad seen from a point: directions from sample_li against pdf_li
        // (zero where a direction misses the light).
        let light = Material {
            emission: Vec3::ONE,
            ..Material::diffuse(Vec3::ZERO)
        };
        let corners = [
            Vec3::new(-0.6, 0.4, -0.3),
            Vec3::new(0.5, 0.7, -0.5),
            Vec3::new(0.7, 0.9, 0.4),
            Vec3::new(-0.4, 0.6, 0.5),
        ];
        let desc = SceneDescription {
            meshes: vec![quad("light", corners, 0)],
            materials: vec![light],
            ..Default::default()
        };
        let scene = Scene::build(desc).unwrap();
        let ctx = LightSampleContext {
            p: Vec3::new(0.1, -0.2, 0.05),
            p_error: Vec3::ZERO,
            n: Vec3::Y,
        };
        let pdf = |w: Vec3| -> f32 {
            let shear = RayShear::new(ctx.p, w);
            scene
                .lights
                .iter()
                .enumerate()
                .filter_map(|(i, l)| match l {
                    Light::Area(a) => {
                        let p = &a.positions;
                        intersect_triangle(&shear, f32::INFINITY, p[0], p[1], p[2])
                            .map(|h| scene.light_sampler.pmf(i) * a.pdf_li(ctx.p, ctx.p + w * h.t))
                    }
                    _ => None,
                })
                .sum()
        };
        test_directions(
            "area light",
            |u, uc| {
                let (i, _) = scene.light_sampler.sample(uc)?;
                match &scene.lights[i] {
                    Light::Area(a) => a.sample_li(&scene.textures, &ctx, u).map(|s| s.wi),
                    _ => None,
                }
            },
            &pdf,
            0.01,
        )
        .unwrap();
    }
}
