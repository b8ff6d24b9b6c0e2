//! Directional albedo of the glTF specular layer, for energy-conserving layering.
//!
//! glTF's `fresnel_mix` (spec appendix B.3.5) weights the diffuse base by 1 - F(V.H); the
//! white-furnace test measured that this reflects up to 14 % more energy than it receives at
//! grazing angles. We keep the specular layer exactly as glTF defines it and couple the
//! diffuse base with the albedo scaling of Kelemen & Szirmay-Kalos, "A Microfacet Based
//! Coupled Specular-Matte BRDF Model with Importance Sampling" (Eurographics 2001, eq. 5):
//!
//! ```text
//!     f_diffuse = base / pi * (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg)
//! ```
//!
//! with E(mu) the specular layer's directional albedo and E_avg = 2 ∫ E(mu) mu dmu. It is
//! reciprocal, and the total albedo is E(mu_o) + base (1 - E(mu_o)) <= 1.
//!
//! Schlick's Fresnel is linear in f0, so E = f0 A(mu, alpha) + (1 - f0) B(mu, alpha) with
//! A = ∫ s cos and B = ∫ (1 - wo.h)^5 s cos over the unfresnelled lobe s = D G / (4 cos cos).
//! Both are tabulated by quadrature over visible normals (Heitz 2018: the estimator of
//! ∫ s cos is G2 / G1) and looked up bilinearly. The quadrature takes a second on two cores,
//! which the first image of a scene must not wait for, so its result ships as generated data
//! (`layering_table.rs`, written by `examples/make_layering_table.rs`; a test checks that it
//! is what the quadrature gives).

use crate::material::layering_table::{SPECULAR_A, SPECULAR_B};
use crate::material::microfacet::TrowbridgeReitz;
use glam::{Vec2, Vec3};
use std::sync::OnceLock;

pub const N_MU: usize = 32;
pub const N_ALPHA: usize = 32;
/// Midpoint strata per axis of the quadrature: the reflected direction's horizon makes the
/// integrand non-smooth in sample space and the error falls only like 1/STRATA (measured:
/// 1.3e-3 at 32, 2e-4 at 128, against 4M-sample Monte Carlo).
const STRATA: usize = 128;

struct Tables {
    a: &'static [f32],
    b: &'static [f32],
    a_avg: Vec<f32>,
    b_avg: Vec<f32>,
}

// The grids are uniform in sqrt(mu) and in roughness sqrt(alpha): nodes crowd towards grazing
// angles and smooth surfaces, where E changes fastest.
fn grid_mu(i: usize) -> f32 {
    let x = i as f32 / (N_MU - 1) as f32;
    (x * x).max(1e-4)
}

fn grid_alpha(j: usize) -> f32 {
    let r = j as f32 / (N_ALPHA - 1) as f32;
    r * r
}

fn integrate(mu: f32, alpha: f32) -> (f32, f32) {
    let strata = STRATA;
    let tr = TrowbridgeReitz::new(alpha);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for i in 0..strata {
        for k in 0..strata {
            let u = Vec2::new(
                (i as f32 + 0.5) / strata as f32,
                (k as f32 + 0.5) / strata as f32,
            );
            let wm = tr.sample_wm(wo, u);
            let wi = crate::geometry::reflect(wo, wm);
            if wi.z <= 0.0 {
                continue;
            }
            let weight = (tr.g(wo, wi) / tr.g1(wo)) as f64;
            let m = (1.0 - wo.dot(wm)).clamp(0.0, 1.0) as f64;
            a += weight;
            b += weight * m.powi(5);
        }
    }
    let n = (strata * strata) as f64;
    ((a / n) as f32, (b / n) as f32)
}

/// A and B on the (mu, alpha) grid, index j N_MU + i, by quadrature: what
/// `layering_table.rs` holds.
pub fn quadrature_tables() -> (Vec<f32>, Vec<f32>) {
    use rayon::prelude::*;
    (0..N_MU * N_ALPHA)
        .into_par_iter()
        .map(|c| integrate(grid_mu(c % N_MU), grid_alpha(c / N_MU)))
        .unzip()
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let (a, b) = (&SPECULAR_A[..], &SPECULAR_B[..]);
        // E_avg = 2 ∫ E(mu) mu dmu = 4 ∫ E(x^2) x^3 dx (mu = x^2), trapezoid rule in x.
        let avg = |t: &[f32], j: usize| -> f32 {
            let h = 1.0 / (N_MU - 1) as f32;
            (0..N_MU)
                .map(|i| {
                    let w = if i == 0 || i == N_MU - 1 { 0.5 } else { 1.0 };
                    let x = i as f32 * h;
                    w * t[j * N_MU + i] * x * x * x
                })
                .sum::<f32>()
                * 4.0
                * h
        };
        let a_avg = (0..N_ALPHA).map(|j| avg(a, j)).collect();
        let b_avg = (0..N_ALPHA).map(|j| avg(b, j)).collect();
        Tables { a, b, a_avg, b_avg }
    })
}

fn lerp_index(x: f32, n: usize) -> (usize, usize, f32) {
    let f = (x.clamp(0.0, 1.0)) * (n - 1) as f32;
    let i0 = (f.floor() as usize).min(n - 2);
    (i0, i0 + 1, f - i0 as f32)
}

/// Directional albedo E(mu) of the specular layer with Schlick's reflectance
/// F = f0 + (f90 - f0) (1 - cos)^5 per channel: E = f0 (A - B) + f90 B (glTF's layer has
/// f90 = 1; KHR_materials_specular scales it).
pub fn specular_albedo(mu: f32, alpha: f32, f0: Vec3, f90: f32) -> Vec3 {
    let t = tables();
    let (i0, i1, fi) = lerp_index(mu.abs().sqrt(), N_MU);
    let (j0, j1, fj) = lerp_index(alpha.sqrt(), N_ALPHA);
    let look = |g: &[f32]| {
        let r0 = g[j0 * N_MU + i0] * (1.0 - fi) + g[j0 * N_MU + i1] * fi;
        let r1 = g[j1 * N_MU + i0] * (1.0 - fi) + g[j1 * N_MU + i1] * fi;
        r0 * (1.0 - fj) + r1 * fj
    };
    let (a, b) = (look(t.a), look(t.b));
    (f0 * (a - b) + Vec3::splat(f90 * b)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Cosine-weighted hemispherical average E_avg of the specular layer's albedo.
pub fn specular_albedo_average(alpha: f32, f0: Vec3, f90: f32) -> Vec3 {
    let t = tables();
    let (j0, j1, fj) = lerp_index(alpha.sqrt(), N_ALPHA);
    let a = t.a_avg[j0] * (1.0 - fj) + t.a_avg[j1] * fj;
    let b = t.b_avg[j0] * (1.0 - fj) + t.b_avg[j1] * fj;
    (f0 * (a - b) + Vec3::splat(f90 * b)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// The cosine-weighted average 2 ∫ (1 - E_1(mu)) (1 - E_2(mu)) mu dmu of the light two
/// stacked specular layers both let through: layer 1 at (alpha_1, f0_1, f90_1), layer 2 at
/// (alpha_2, f0_2, f90 = 1) weighted by `weight_2`. Their albedos rise together towards grazing
/// angles, so this is more than the product of the two averages; it normalises the albedo
/// scaling of a base beneath both (`material::clearcoat`). The same trapezoid rule on the
/// same nodes as `specular_albedo_average`, so with `weight_2` 0 it is 1 - that average.
pub fn transmitted_average_of_two(
    (alpha_1, f0_1, f90_1): (f32, Vec3, f32),
    (alpha_2, f0_2, weight_2): (f32, f32, f32),
) -> Vec3 {
    let t = tables();
    let (a0, a1, fa) = lerp_index(alpha_1.sqrt(), N_ALPHA);
    let (b0, b1, fb) = lerp_index(alpha_2.sqrt(), N_ALPHA);
    let at = |g: &[f32], j0: usize, j1: usize, f: f32, i: usize| {
        g[j0 * N_MU + i] * (1.0 - f) + g[j1 * N_MU + i] * f
    };
    let h = 1.0 / (N_MU - 1) as f32;
    let mut sum = Vec3::ZERO;
    for i in 0..N_MU {
        let w = if i == 0 || i == N_MU - 1 { 0.5 } else { 1.0 };
        let x = i as f32 * h;
        let (a, b) = (at(t.a, a0, a1, fa, i), at(t.b, a0, a1, fa, i));
        let e1 = (f0_1 * (a - b) + Vec3::splat(f90_1 * b)).clamp(Vec3::ZERO, Vec3::ONE);
        let (a, b) = (at(t.a, b0, b1, fb, i), at(t.b, b0, b1, fb, i));
        let e2 = (weight_2 * (f0_2 * (a - b) + b)).clamp(0.0, 1.0);
        // What the two reflect together; the constant 1 is integrated exactly.
        sum += w * x * x * x * (Vec3::ONE - (Vec3::ONE - e1) * (1.0 - e2));
    }
    Vec3::ONE - sum * 4.0 * h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped table is the quadrature's result (regenerate it with
    /// `cargo run -p caustica-renderer --example make_layering_table`).
    #[test]
    fn the_shipped_table_is_what_the_quadrature_gives() {
        let (a, b) = quadrature_tables();
        for (shipped, computed) in [(&SPECULAR_A[..], &a), (&SPECULAR_B[..], &b)] {
            for (i, (s, c)) in shipped.iter().zip(computed.iter()).enumerate() {
                assert!(
                    (s - c).abs() <= 1e-6,
                    "cell {i}: shipped {s}, quadrature {c}"
                );
            }
        }
    }

    #[test]
    fn albedo_limits() {
        // A perfect reflector (f0 = 1) with little roughness reflects nearly everything.
        let e = |mu, alpha, f0| specular_albedo(mu, alpha, Vec3::splat(f0), 1.0).x;
        assert!((e(0.8, 0.01, 1.0) - 1.0).abs() < 0.01);
        // f0 = 0.04 at normal incidence reflects about 4 %; more at grazing angles.
        let normal = e(1.0, 0.1, 0.04);
        assert!((normal - 0.04).abs() < 0.01, "{normal}");
        assert!(e(0.1, 0.1, 0.04) > normal);
        let avg = specular_albedo_average(0.3, Vec3::splat(0.04), 1.0).x;
        assert!(avg > 0.04 && avg < 0.2, "{avg}");
        // f90 scales the grazing part: with f0 = f90 = 0 nothing is reflected, and the
        // albedo is linear in (f0, f90).
        assert_eq!(specular_albedo(0.3, 0.2, Vec3::ZERO, 0.0), Vec3::ZERO);
        let half = specular_albedo(0.3, 0.2, Vec3::splat(0.02), 0.5).x;
        assert!((half - 0.5 * e(0.3, 0.2, 0.04)).abs() < 1e-6, "{half}");
        // Two layers: with the second absent, one minus the first's average; together, more
        // than the product of what each lets through (their albedos rise together).
        let one = (0.09, Vec3::splat(0.04), 1.0);
        let alone = transmitted_average_of_two(one, (0.01, 0.04, 0.0)).x;
        let avg = specular_albedo_average(0.09, Vec3::splat(0.04), 1.0).x;
        assert!(
            (alone - (1.0 - avg)).abs() < 1e-6,
            "{alone} vs {}",
            1.0 - avg
        );
        let both = transmitted_average_of_two(one, (0.01, 0.04, 1.0)).x;
        let coat = specular_albedo_average(0.01, Vec3::splat(0.04), 1.0).x;
        assert!(both > (1.0 - avg) * (1.0 - coat), "{both}");
    }
}
