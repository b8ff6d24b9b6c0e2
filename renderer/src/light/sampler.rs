//! Chooses lights in proportion to their power (DESIGN.md section 2; pbrt-v4's
//! `PowerLightSampler`, section 12.6.2), by luminance.

use crate::geometry::luminance;
use crate::light::Light;
use crate::sampling::distribution::Distribution1D;

#[derive(Clone, Debug)]
pub struct PowerLightSampler {
    distribution: Distribution1D,
}

impl PowerLightSampler {
    pub fn new(lights: &[Light]) -> Self {
        let powers: Vec<f64> = lights
            .iter()
            .map(|l| {
                let phi = match l {
                    Light::Area(a) => a.power(),
                    Light::Point(p) => p.power(),
                    Light::Spot(s) => s.power(),
                    Light::Directional(d) => d.power(),
                    Light::Environment(e) => e.power(),
                };
                luminance(phi) as f64
            })
            .collect();
        PowerLightSampler {
            distribution: Distribution1D::new(&powers),
        }
    }

    /// A light index and its probability.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        self.distribution.sample(u)
    }

    /// Bytes of its table.
    pub fn memory_bytes(&self) -> usize {
        self.distribution.memory_bytes()
    }

    pub fn pmf(&self, light: usize) -> f32 {
        self.distribution.pmf(light)
    }
}
