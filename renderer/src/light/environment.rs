//! The environment: radiance arriving from infinitely far away, either the same from every
//! direction (pbrt-v4's `UniformInfiniteLight`, section 12.5.1, sampled uniformly over the
//! sphere) or from an equirectangular map (`ImageInfiniteLight`, section 12.5.2, sampled in
//! proportion to the map's radiance), scaled by a strength and turned about the world's up
//! axis (+Y) by a rotation.

use crate::light::environment_map::EnvironmentMap;
use crate::light::{LightLiSample, LightSampleContext};
use crate::sampling::warp::{sample_uniform_sphere, uniform_sphere_pdf};
use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// What lights a scene from outside, as the user chose it.
#[derive(Clone, Debug, Default)]
pub enum EnvironmentChoice {
    /// The studio for a model meant to be lit by its viewer, nothing for a scene with its own
    /// lighting (`scene::build::has_own_lighting` states the rule).
    #[default]
    Auto,
    None,
    /// Radiance 1 from every direction.
    Uniform,
    /// The built-in studio (`light::studio`).
    Studio,
    Map(Arc<EnvironmentMap>),
}

impl EnvironmentChoice {
    /// The choices that have a name (all but a map, which is named by its file).
    pub const NAMED: [&'static str; 4] = ["auto", "none", "uniform", "studio"];

    pub fn from_name(name: &str) -> Option<EnvironmentChoice> {
        match name {
            "auto" => Some(EnvironmentChoice::Auto),
            "none" => Some(EnvironmentChoice::None),
            "uniform" => Some(EnvironmentChoice::Uniform),
            "studio" => Some(EnvironmentChoice::Studio),
            _ => None,
        }
    }

    /// The name `from_name` reads, or the map's file.
    pub fn name(&self) -> String {
        match self {
            EnvironmentChoice::Auto => "auto".into(),
            EnvironmentChoice::None => "none".into(),
            EnvironmentChoice::Uniform => "uniform".into(),
            EnvironmentChoice::Studio => "studio".into(),
            EnvironmentChoice::Map(map) => map.name.clone(),
        }
    }
}

/// The environment a scene is built with: the choice, a strength multiplying its radiance and
/// a rotation about +Y in degrees.
#[derive(Clone, Debug)]
pub struct EnvironmentSettings {
    pub choice: EnvironmentChoice,
    pub strength: f32,
    pub rotation_degrees: f32,
}

impl EnvironmentSettings {
    /// Settings from what the user typed or picked: a choice's name (`EnvironmentChoice::NAMED`)
    /// or an image file, which is read here (the error names the file and the problem).
    pub fn resolve(
        choice: &str,
        strength: f32,
        rotation_degrees: f32,
    ) -> Result<EnvironmentSettings, String> {
        let choice = match EnvironmentChoice::from_name(choice) {
            Some(named) => named,
            None => EnvironmentChoice::Map(Arc::new(EnvironmentMap::load(std::path::Path::new(
                choice,
            ))?)),
        };
        if !(strength.is_finite() && strength >= 0.0 && rotation_degrees.is_finite()) {
            return Err(format!(
                "environment strength {strength} and rotation {rotation_degrees}: the strength \
                 must be 0 or more and both finite"
            ));
        }
        Ok(EnvironmentSettings {
            choice,
            strength,
            rotation_degrees,
        })
    }
}

impl Default for EnvironmentSettings {
    fn default() -> Self {
        EnvironmentSettings {
            choice: EnvironmentChoice::Auto,
            strength: 1.0,
            rotation_degrees: 0.0,
        }
    }
}

#[derive(Clone, Debug)]
pub enum EnvironmentRadiance {
    Uniform(Vec3),
    Map(Arc<EnvironmentMap>),
}

#[derive(Clone, Debug)]
pub struct Environment {
    pub radiance: EnvironmentRadiance,
    /// Multiplies the radiance.
    pub strength: f32,
    /// The map's frame in the world: a rotation about +Y; and back.
    to_world: Mat3,
    to_map: Mat3,
    pub scene_radius: f32,
}

impl Environment {
    /// `rotation_degrees` turns the environment about +Y (counter-clockwise seen from above).
    pub fn new(
        radiance: EnvironmentRadiance,
        strength: f32,
        rotation_degrees: f32,
        scene_radius: f32,
    ) -> Environment {
        let to_world = Mat3::from_rotation_y(rotation_degrees.to_radians());
        Environment {
            radiance,
            strength,
            to_world,
            to_map: to_world.transpose(),
            scene_radius,
        }
    }

    pub fn uniform(radiance: Vec3, scene_radius: f32) -> Environment {
        Environment::new(
            EnvironmentRadiance::Uniform(radiance),
            1.0,
            0.0,
            scene_radius,
        )
    }

    /// Radiance arriving from the world direction `w` (unit, pointing away from the scene).
    #[inline]
    pub fn le(&self, w: Vec3) -> Vec3 {
        self.strength
            * match &self.radiance {
                EnvironmentRadiance::Uniform(l) => *l,
                EnvironmentRadiance::Map(map) => map.radiance(self.to_map * w),
            }
    }

    /// A direction towards the environment, with its solid-angle density (uniform over the
    /// sphere, or in proportion to the map's radiance).
    pub fn sample_direction(&self, u: Vec2) -> Option<(Vec3, f32)> {
        match &self.radiance {
            EnvironmentRadiance::Uniform(_) => {
                Some((sample_uniform_sphere(u), uniform_sphere_pdf()))
            }
            EnvironmentRadiance::Map(map) => {
                let (w, pdf) = map.sample(u)?;
                Some((self.to_world * w, pdf))
            }
        }
    }

    pub fn sample_li(&self, ctx: &LightSampleContext, u: Vec2) -> Option<LightLiSample> {
        let (wi, pdf) = self.sample_direction(u)?;
        Some(LightLiSample {
            l: self.le(wi),
            wi,
            pdf,
            p_light: ctx.p + wi * (2.0 * self.scene_radius),
            n_light: Vec3::ZERO,
            dist: f32::INFINITY,
            is_delta: false,
        })
    }

    /// Solid-angle density of `sample_li` (and `sample_direction`) for the direction `wi`.
    #[inline]
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        match &self.radiance {
            EnvironmentRadiance::Uniform(_) => uniform_sphere_pdf(),
            EnvironmentRadiance::Map(map) => map.pdf(self.to_map * wi),
        }
    }

    /// Power through the scene's bounding sphere: pi r^2 times radiance integrated over the
    /// sphere of directions (pbrt-v4's `Phi` for infinite lights).
    pub fn power(&self) -> Vec3 {
        let integral = match &self.radiance {
            EnvironmentRadiance::Uniform(l) => 4.0 * PI * *l,
            EnvironmentRadiance::Map(map) => map.integral(),
        };
        PI * self.scene_radius * self.scene_radius * self.strength * integral
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::test_directions;

    /// A 64 x 32 map of smooth variation with a bright spot and a black band, like a sky with
    /// a sun over dark ground.
    fn test_map() -> Arc<EnvironmentMap> {
        let (w, h) = (64, 32);
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                if (20..23).contains(&(y as usize)) {
                    Vec3::ZERO
                } else if (x - 40.0).abs() < 2.0 && (y - 8.0).abs() < 2.0 {
                    Vec3::new(200.0, 180.0, 150.0)
                } else {
                    Vec3::new(1.0 + (x * 0.3).sin() * 0.5, 0.8, 0.5 + y / h as f32)
                }
            })
            .collect();
        Arc::new(EnvironmentMap::new("test", w, h, texels).unwrap())
    }

    #[test]
    fn sampled_directions_match_the_solid_angle_pdf() {
        for rotation in [0.0, 70.0] {
            let env = Environment::new(EnvironmentRadiance::Map(test_map()), 1.5, rotation, 1.0);
            test_directions(
                "environment map",
                |u, _| env.sample_direction(u).map(|(w, _)| w),
                &|w| env.pdf_li(w),
                1e-3,
            )
            .unwrap();
            // The density returned with a sample is the one pdf_li gives for its direction.
            for k in 0..1000 {
                let u = Vec2::new(
                    ((k as f32 + 0.5) * 0.618_034).fract(),
                    (k as f32 + 0.5) / 1000.0,
                );
                if let Some((w, pdf)) = env.sample_direction(u) {
                    assert!((pdf - env.pdf_li(w)).abs() <= 1e-3 * pdf, "{w}: {pdf}");
                }
            }
        }
    }

    #[test]
    fn importance_sampling_lowers_the_second_moment() {
        // The estimator L / pdf of the map's integral: its relative second moment
        // E[(L/pdf)^2] / E[L/pdf]^2 under the map's sampling is far below uniform sampling's
        // (about 50 for this map, where a spot of 9 texels holds half the light).
        let map = test_map();
        let by_map = Environment::new(EnvironmentRadiance::Map(map.clone()), 1.0, 0.0, 1.0);
        let moments = |sample: &dyn Fn(Vec2) -> Option<(Vec3, f32)>| {
            let (mut m1, mut m2, n) = (0.0f64, 0.0f64, 1 << 16);
            for k in 0..n {
                let u = Vec2::new(
                    ((k as f32 + 0.5) * 0.754_877_7).fract(),
                    (k as f32 + 0.5) / n as f32,
                );
                if let Some((w, pdf)) = sample(u) {
                    let f = f64::from(crate::geometry::luminance(by_map.le(w)) / pdf);
                    m1 += f;
                    m2 += f * f;
                }
            }
            let (m1, m2) = (m1 / n as f64, m2 / n as f64);
            (m1, m2 / (m1 * m1))
        };
        let (mean_map, ratio_map) = moments(&|u| by_map.sample_direction(u));
        let (mean_uniform, ratio_uniform) =
            moments(&|u| Some((sample_uniform_sphere(u), uniform_sphere_pdf())));
        let integral = f64::from(crate::geometry::luminance(map.integral()));
        assert!(
            (mean_map - integral).abs() < 0.01 * integral,
            "{mean_map} for {integral}"
        );
        assert!(
            (mean_uniform - integral).abs() < 0.05 * integral,
            "{mean_uniform} for {integral}"
        );
        assert!(
            ratio_map < 1.5 && ratio_uniform > 10.0 * ratio_map,
            "relative second moments: map {ratio_map}, uniform {ratio_uniform}"
        );
    }

    #[test]
    fn a_uniform_map_gives_the_uniform_environment() {
        let map = EnvironmentMap::new("grey", 8, 4, vec![Vec3::splat(0.5); 32]).unwrap();
        let env = Environment::new(EnvironmentRadiance::Map(Arc::new(map)), 2.0, 10.0, 3.0);
        let uniform = Environment::uniform(Vec3::ONE, 3.0);
        assert!((env.power() - uniform.power()).abs().max_element() < 1e-3 * uniform.power().x);
        assert!((env.le(Vec3::new(0.3, 0.4, -0.866).normalize()) - Vec3::ONE).length() < 1e-6);
    }

    #[test]
    fn the_mapping_puts_the_centre_ahead_and_the_top_up() {
        use crate::light::environment_map::{direction_to_uv, uv_to_direction};
        assert!((direction_to_uv(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((direction_to_uv(Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(direction_to_uv(Vec3::Y).y < 1e-6);
        for k in 0..100 {
            let uv = Vec2::new((k as f32 * 0.618).fract(), (k as f32 + 0.5) / 100.0);
            let (w, _) = uv_to_direction(uv);
            let back = direction_to_uv(w);
            let du = (back.x - uv.x).abs();
            assert!(
                du.min(1.0 - du) < 1e-4 && (back.y - uv.y).abs() < 1e-4,
                "{uv}"
            );
        }
        // Turned 90 degrees counter-clockwise seen from above, what the map has at +X is seen
        // ahead (-Z), and any world direction reads the map at that direction turned back.
        let map = EnvironmentMap::new(
            "halves",
            4,
            2,
            vec![
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ONE,
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ONE,
            ],
        )
        .unwrap();
        let env = Environment::new(EnvironmentRadiance::Map(Arc::new(map)), 1.0, 90.0, 1.0);
        let unturned = Environment::new(env.radiance.clone(), 1.0, 0.0, 1.0);
        assert!((env.le(Vec3::NEG_Z) - unturned.le(Vec3::X)).length() < 1e-6);
        let w = Vec3::new(0.3, -0.5, 0.8).normalize();
        let back = Mat3::from_rotation_y(-90f32.to_radians()) * w;
        assert!((env.le(w) - unturned.le(back)).length() < 1e-6);
    }
}
