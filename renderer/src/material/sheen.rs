//! KHR_materials_sheen: the back-scattering of velvet-like fibres as a layer over the
//! metallic-roughness material, with the extension's reference model:
//!
//! ```text
//!     D(h)  = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi)          ("Charlie", Conty
//!             Estevez & Kulla 2017), alpha = sheenRoughness^2
//!     V     = 1 / ((1 + Lambda(mu_o) + Lambda(mu_i)) 4 mu_o mu_i)  (their fitted Lambda)
//!     f_sheen = sheenColor D V                                      (no Fresnel)
//!     f     = f_sheen + f_base min(1 - max3(sheenColor) E(mu_o), 1 - max3(sheenColor) E(mu_i))
//! ```
//!
//! with E(mu) the lobe's directional albedo at sheenColor 1. The minimum keeps it reciprocal
//! and never gains energy: the albedo is at most max3(C) E(mu_o) + (1 - max3(C) E(mu_o)) = 1.
//! E is tabulated by quadrature the first time a scene needs it. The lobe is sampled by the
//! cosine distribution (it spreads over the hemisphere; its peak at grazing angles is broad).
//! Roughness is kept at or above 0.07, where the fitted Lambda and a 32-node table still
//! resolve the lobe (three.js clamps the same way).

use glam::Vec3;
use std::f32::consts::PI;
use std::sync::OnceLock;

const N_MU: usize = 32;
const N_ROUGHNESS: usize = 32;
const MIN_ROUGHNESS: f32 = 0.07;

#[derive(Clone, Copy, Debug)]
pub struct Sheen {
    /// sheenColorFactor (times its texture): zero is no sheen.
    pub color: Vec3,
    /// sheenRoughness (times its texture's alpha), in [MIN_ROUGHNESS, 1].
    pub roughness: f32,
}

impl Sheen {
    pub const NONE: Sheen = Sheen {
        color: Vec3::ZERO,
        roughness: 1.0,
    };

    pub fn new(color: Vec3, roughness: f32) -> Sheen {
        Sheen {
            color: color.max(Vec3::ZERO),
            roughness: roughness.clamp(MIN_ROUGHNESS, 1.0),
        }
    }

    pub fn is_present(&self) -> bool {
        self.color.max_element() > 0.0
    }

    /// max3(C) E(mu): the most any channel of the sheen reflects at cosine `mu`.
    fn reflected(&self, mu: f32) -> f32 {
        self.color.max_element() * albedo(mu, self.roughness)
    }

    /// The factor on the base beneath the sheen.
    pub fn base_scale(&self, mu_o: f32, mu_i: f32) -> f32 {
        if !self.is_present() {
            return 1.0;
        }
        1.0 - self.reflected(mu_o).max(self.reflected(mu_i))
    }

    /// The sheen lobe for an upper-hemisphere pair.
    pub fn f(&self, uo: Vec3, ui: Vec3) -> Vec3 {
        self.color * lobe(uo, ui, self.roughness)
    }

    /// Probability of sampling the sheen lobe rather than the base: its share of the light at
    /// `mu_o` over a white base, at least 10 %.
    pub fn sample_prob(&self, mu_o: f32) -> f32 {
        if !self.is_present() {
            return 0.0;
        }
        self.reflected(mu_o).clamp(0.1, 0.9)
    }
}

/// D V of the lobe at sheenColor 1 (zero outside the upper hemisphere).
fn lobe(uo: Vec3, ui: Vec3, roughness: f32) -> f32 {
    let wm = (uo + ui).normalize_or_zero();
    if uo.z <= 0.0 || ui.z <= 0.0 || wm == Vec3::ZERO {
        return 0.0;
    }
    let alpha = roughness * roughness;
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - wm.z * wm.z).max(0.0);
    let d = (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI);
    let v = 1.0 / ((1.0 + lambda(uo.z, alpha) + lambda(ui.z, alpha)) * 4.0 * uo.z * ui.z);
    d * v
}

/// Conty Estevez & Kulla's fit of the Charlie distribution's Smith Lambda (their table 1,
/// interpolated in (1 - alpha)^2 as the extension gives it).
fn lambda(mu: f32, alpha: f32) -> f32 {
    let l = |x: f32| {
        let t = (1.0 - alpha) * (1.0 - alpha);
        let mix = |a: f32, b: f32| a + (b - a) * t;
        let (a, b, c) = (
            mix(21.5473, 25.3245),
            mix(3.82987, 3.32435),
            mix(0.19823, 0.16801),
        );
        let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
        a / (1.0 + b * x.powf(c)) + d * x + e
    };
    if mu < 0.5 {
        l(mu).exp()
    } else {
        (2.0 * l(0.5) - l(1.0 - mu)).exp()
    }
}

// The grids: mu uniform in sqrt(mu) (nodes crowd towards grazing angles, where the lobe
// lives), roughness uniform on [MIN_ROUGHNESS, 1].
fn grid_mu(i: usize) -> f32 {
    let x = i as f32 / (N_MU - 1) as f32;
    (x * x).max(1e-4)
}

fn grid_roughness(j: usize) -> f32 {
    MIN_ROUGHNESS + (1.0 - MIN_ROUGHNESS) * j as f32 / (N_ROUGHNESS - 1) as f32
}

/// E(mu) = ∫ D V cos dwi by the midpoint rule in (cos theta_i^2, phi): cos dw = d(cos^2)/2
/// dphi, so the cosine weight is absorbed. 128 x 128 strata per node.
fn integrate(mu: f32, roughness: f32) -> f32 {
    const STRATA: usize = 128;
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for i in 0..STRATA {
        let cos2 = (i as f32 + 0.5) / STRATA as f32;
        let (cos, sin) = (cos2.sqrt(), (1.0 - cos2).sqrt());
        for k in 0..STRATA {
            let phi = 2.0 * PI * (k as f32 + 0.5) / STRATA as f32;
            let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
            sum += lobe(wo, wi, roughness) as f64;
        }
    }
    // Each stratum covers d(cos^2) dphi = (1/STRATA)(2 pi/STRATA), and cos dw is half that.
    (sum * std::f64::consts::PI / (STRATA * STRATA) as f64) as f32
}

fn table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        use rayon::prelude::*;
        (0..N_MU * N_ROUGHNESS)
            .into_par_iter()
            .map(|c| integrate(grid_mu(c % N_MU), grid_roughness(c / N_MU)).min(1.0))
            .collect()
    })
}

/// The lobe's directional albedo E(mu) at sheenColor 1, bilinear in the table.
pub fn albedo(mu: f32, roughness: f32) -> f32 {
    let t = table();
    let x = mu.abs().clamp(0.0, 1.0).sqrt() * (N_MU - 1) as f32;
    let y = ((roughness - MIN_ROUGHNESS) / (1.0 - MIN_ROUGHNESS)).clamp(0.0, 1.0)
        * (N_ROUGHNESS - 1) as f32;
    let (i0, j0) = (
        (x.floor() as usize).min(N_MU - 2),
        (y.floor() as usize).min(N_ROUGHNESS - 2),
    );
    let (fx, fy) = (x - i0 as f32, y - j0 as f32);
    let at = |i: usize, j: usize| t[j * N_MU + i];
    let r0 = at(i0, j0) * (1.0 - fx) + at(i0 + 1, j0) * fx;
    let r1 = at(i0, j0 + 1) * (1.0 - fx) + at(i0 + 1, j0 + 1) * fx;
    r0 * (1.0 - fy) + r1 * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lobe is reciprocal, its albedo stays below 1 and grows towards grazing angles
    /// (velvet's rim), and the table agrees with Monte Carlo integration of the lobe (cosine
    /// sampling, 10^6 directions) off its nodes.
    #[test]
    fn the_lobe_is_reciprocal_and_the_table_is_its_albedo() {
        use crate::sampling::sampler::Sampler;
        use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
        let (a, b) = (
            Vec3::new(0.6, 0.1, 0.79).normalize(),
            Vec3::new(-0.3, 0.5, 0.2).normalize(),
        );
        assert!((lobe(a, b, 0.4) - lobe(b, a, 0.4)).abs() < 1e-6);
        for roughness in [0.1f32, 0.45, 0.93] {
            assert!(albedo(0.05, roughness) > albedo(0.9, roughness));
            for mu in [0.13f32, 0.55, 0.97] {
                let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let mut sampler = Sampler::new(9);
                let n = 1_000_000u64;
                let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
                for k in 0..n {
                    sampler.start_pixel_sample(k, 0);
                    let wi = sample_cosine_hemisphere(sampler.get_2d());
                    let v = (lobe(wo, wi, roughness) * wi.z / cosine_hemisphere_pdf(wi.z)) as f64;
                    sum += v;
                    sum_sq += v * v;
                }
                let mean = sum / n as f64;
                let se = ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt();
                let e = albedo(mu, roughness) as f64;
                assert!(e < 1.0, "albedo {e}");
                // Bilinear interpolation between nodes: 1 % of the albedo, or 1e-4 where the
                // albedo itself is nil (a smooth sheen seen from above).
                assert!(
                    (mean - e).abs() <= 5.0 * se + 0.01 * e + 1e-4,
                    "roughness {roughness}, mu {mu}: table {e}, Monte Carlo {mean} ± {se}"
                );
            }
        }
    }
}
