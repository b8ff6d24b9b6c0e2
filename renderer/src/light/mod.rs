//! Lights (DESIGN.md section 2): emissive triangles as area lights, glTF's punctual lights
//! (point, spot, directional; delta lights that no technique can hit), and the environment
//! (uniform or an equirectangular map) around the scene. Sampling follows pbrt-v4 chapter 12: `sample_li`
//! picks a point on the light as seen from a reference point and returns a solid-angle pdf
//! (1 for delta lights); `pdf_li` is the same density for a direction that hit the light.

pub mod area;
pub mod emission;
pub mod environment;
pub mod environment_map;
pub mod punctual;
pub mod sampler;
pub mod studio;

use glam::Vec3;

/// The point lit: position with its error bound and geometric normal (zero for a point in
/// space), so shadow rays start outside the surface.
#[derive(Clone, Copy, Debug)]
pub struct LightSampleContext {
    pub p: Vec3,
    pub p_error: Vec3,
    pub n: Vec3,
}

/// Incident radiance `l` from direction `wi`, sampled with solid-angle density `pdf`.
/// `p_light` is the point on the light (at infinity: `dist` is infinite).
#[derive(Clone, Copy, Debug)]
pub struct LightLiSample {
    pub l: Vec3,
    pub wi: Vec3,
    pub pdf: f32,
    pub p_light: Vec3,
    pub n_light: Vec3,
    pub dist: f32,
    pub is_delta: bool,
}

#[derive(Clone, Debug)]
pub enum Light {
    Area(area::AreaLight),
    Point(punctual::PointLight),
    Spot(punctual::SpotLight),
    Directional(punctual::DirectionalLight),
    Environment(environment::Environment),
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Directional(_)
        )
    }

    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Directional(_) | Light::Environment(_))
    }
}
