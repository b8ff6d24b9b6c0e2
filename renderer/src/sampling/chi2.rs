//! Chi-square goodness-of-fit tests of sampling routines against their pdfs, after pbrt-v4's
//! and Mitsuba's: about 10^6 samples binned on a (theta, phi) grid of odd resolution, the
//! expected count of each cell from the pdf integrated by Simpson's rule, cells with an
//! expected count below 5 pooled, significance 0.01 with a Sidak correction over the tests
//! of one family.

use crate::sampling::sampler::Sampler;
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

pub const SAMPLES: usize = 1_000_000;
pub const THETA_RES: usize = 41;
pub const PHI_RES: usize = 81;

/// Significance of one test among `tests` so that the family's level is 0.01 (Sidak).
pub fn sidak_significance(tests: usize) -> f64 {
    1.0 - (1.0 - 0.01f64).powf(1.0 / tests as f64)
}

fn direction(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new((st * cp) as f32, (st * sp) as f32, ct as f32)
}

/// Expected frequencies on the sphere grid: the solid-angle `pdf` integrated over each cell
/// (the sin(theta) Jacobian included) by composite Gauss-Legendre quadrature. Its nodes lie
/// strictly inside the cells, so a pdf whose discontinuities fall on cell edges (a cone's rim,
/// a hemisphere's horizon) is integrated as accurately as a smooth one.
fn expected_sphere(pdf: &dyn Fn(Vec3) -> f32, samples: usize) -> Vec<f64> {
    const SUB: usize = 4; // sub-cells per cell and axis
    // 4-point Gauss-Legendre nodes and weights on [-1, 1].
    const NODES: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const WEIGHTS: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let d_theta = PI / THETA_RES as f64;
    let d_phi = 2.0 * PI / PHI_RES as f64;
    let (ht, hp) = (d_theta / SUB as f64, d_phi / SUB as f64);
    let mut expected = vec![0.0; THETA_RES * PHI_RES];
    for i in 0..THETA_RES {
        for j in 0..PHI_RES {
            let mut sum = 0.0;
            for a in 0..SUB * 4 {
                let theta = i as f64 * d_theta + ((a / 4) as f64 + 0.5 * (NODES[a % 4] + 1.0)) * ht;
                for b in 0..SUB * 4 {
                    let phi = j as f64 * d_phi + ((b / 4) as f64 + 0.5 * (NODES[b % 4] + 1.0)) * hp;
                    sum += WEIGHTS[a % 4]
                        * WEIGHTS[b % 4]
                        * pdf(direction(theta, phi)) as f64
                        * theta.sin();
                }
            }
            expected[i * PHI_RES + j] = sum * 0.25 * ht * hp * samples as f64;
        }
    }
    expected
}

fn sphere_cell(w: Vec3) -> Option<usize> {
    if !w.is_finite() || (w.length() - 1.0).abs() > 1e-3 {
        return None;
    }
    let theta = (w.z as f64).clamp(-1.0, 1.0).acos();
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let i = ((theta / PI * THETA_RES as f64) as usize).min(THETA_RES - 1);
    let j = ((phi / (2.0 * PI) * PHI_RES as f64) as usize).min(PHI_RES - 1);
    Some(i * PHI_RES + j)
}

/// Tests a direction sampler against its solid-angle pdf. `sample` gets two uniform numbers
/// and a third one (for lobe selection) and may fail (None). Returns Err with the statistic
/// when the hypothesis is rejected at `significance`.
pub fn test_directions(
    name: &str,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: &dyn Fn(Vec3) -> f32,
    significance: f64,
) -> Result<(), String> {
    let mut observed = vec![0.0; THETA_RES * PHI_RES];
    let mut sampler = Sampler::new(0x000C_4150_u64 + name.len() as u64);
    for k in 0..SAMPLES {
        sampler.start_pixel_sample(k as u64, 0);
        let u = sampler.get_2d();
        let uc = sampler.get_1d();
        if let Some(w) = sample(u, uc) {
            match sphere_cell(w) {
                Some(c) => observed[c] += 1.0,
                None => return Err(format!("{name}: sample {w:?} is not a unit direction")),
            }
        }
    }
    let expected = expected_sphere(pdf, SAMPLES);
    chi2_test(name, &observed, &expected, significance)
}

/// Pearson's chi-square test that `counts` are draws from equally likely bins.
pub fn chi2_uniform(name: &str, counts: &[u32], significance: f64) -> Result<(), String> {
    let observed: Vec<f64> = counts.iter().map(|&c| c as f64).collect();
    let expected = observed.iter().sum::<f64>() / counts.len() as f64;
    chi2_test(name, &observed, &vec![expected; counts.len()], significance)
}

/// Pearson's chi-square test with pooling of low-expectation cells (pbrt-v4's `Chi2Test`).
pub fn chi2_test(
    name: &str,
    observed: &[f64],
    expected: &[f64],
    significance: f64,
) -> Result<(), String> {
    const MIN_EXPECTED: f64 = 5.0;
    let mut cells: Vec<(f64, f64)> = expected
        .iter()
        .copied()
        .zip(observed.iter().copied())
        .collect();
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut pooled_e, mut pooled_o) = (0.0, 0.0);
    let (mut chsq, mut dof) = (0.0, 0usize);
    for &(e, o) in &cells {
        if e <= 0.0 {
            if o > expected.iter().sum::<f64>() * 1e-5 {
                return Err(format!(
                    "{name}: {o} samples landed where the pdf integrates to zero"
                ));
            }
        } else if e < MIN_EXPECTED {
            pooled_e += e;
            pooled_o += o;
        } else {
            chsq += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pooled_e > 0.0 {
        chsq += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        dof += 1;
    }
    if dof < 2 {
        return Err(format!("{name}: too few degrees of freedom ({dof})"));
    }
    let dof = dof - 1;
    let p_value = 1.0 - regularized_gamma_p(dof as f64 / 2.0, chsq / 2.0);
    if p_value < significance || !p_value.is_finite() {
        return Err(format!(
            "{name}: chi2 = {chsq:.1} with {dof} degrees of freedom, p = {p_value:.3e} < {significance:.3e}"
        ));
    }
    Ok(())
}

fn ln_gamma(x: f64) -> f64 {
    // Lanczos approximation (g = 7, n = 9), accurate to ~1e-15 for x > 0.
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised lower incomplete gamma P(a, x): series below a + 1, continued fraction above
/// (Numerical Recipes, section 6.2).
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        1.0 - (-x + a * x.ln() - gln).exp() * h
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::*;

    #[test]
    fn gamma_matches_known_chi2_quantiles() {
        // 95th percentile of chi2 with 10 dof is 18.307.
        let p = regularized_gamma_p(5.0, 18.307 / 2.0);
        assert!((p - 0.95).abs() < 1e-4, "{p}");
        // 0.1 percentile with 2 dof: P = 1 - exp(-x/2).
        assert!((regularized_gamma_p(1.0, 0.7) - (1.0 - (-0.7f64).exp())).abs() < 1e-12);
    }

    #[test]
    fn the_test_rejects_a_wrong_pdf() {
        // Cosine samples judged against the uniform hemisphere pdf must fail.
        let r = test_directions(
            "cosine vs uniform",
            |u, _| Some(sample_cosine_hemisphere(u)),
            &|w| {
                if w.z > 0.0 {
                    1.0 / (2.0 * std::f32::consts::PI)
                } else {
                    0.0
                }
            },
            0.01,
        );
        assert!(r.is_err());
    }

    #[test]
    fn warps_match_their_pdfs() {
        let alpha = sidak_significance(4);
        test_directions(
            "cosine hemisphere",
            |u, _| Some(sample_cosine_hemisphere(u)),
            &|w| cosine_hemisphere_pdf(w.z),
            alpha,
        )
        .unwrap();
        test_directions(
            "uniform sphere",
            |u, _| Some(sample_uniform_sphere(u)),
            &|_| uniform_sphere_pdf(),
            alpha,
        )
        .unwrap();
        // Cone edges on theta cell boundaries, so each cell's pdf is smooth for Simpson's rule.
        for cells in [3.0f32, 13.0] {
            let cos_max = (cells * std::f32::consts::PI / THETA_RES as f32).cos();
            test_directions(
                "uniform cone",
                |u, _| Some(sample_uniform_cone(u, cos_max)),
                &|w| {
                    if w.z >= cos_max {
                        uniform_cone_pdf(cos_max)
                    } else {
                        0.0
                    }
                },
                alpha,
            )
            .unwrap();
        }
    }

    #[test]
    fn triangle_samples_are_uniform_by_area() {
        // Bin (b0, b1) on an n x n grid of the unit square; the line b0 + b1 = 1 runs through
        // cell corners, so each cell is inside, outside, or exactly halved. pdf = 2 inside.
        let n = 31;
        let mut observed = vec![0.0; n * n];
        let mut sampler = Sampler::new(5);
        for k in 0..SAMPLES {
            sampler.start_pixel_sample(k as u64, 0);
            let b = sample_uniform_triangle(sampler.get_2d());
            assert!(b.min_element() >= 0.0 && (b.x + b.y + b.z - 1.0).abs() < 1e-6);
            let i = ((b.x * n as f32) as usize).min(n - 1);
            let j = ((b.y * n as f32) as usize).min(n - 1);
            observed[i * n + j] += 1.0;
        }
        let cell = 1.0 / (n * n) as f64;
        let expected: Vec<f64> = (0..n * n)
            .map(|c| {
                let (i, j) = (c / n, c % n);
                let frac = if i + j < n - 1 {
                    1.0
                } else if i + j == n - 1 {
                    0.5
                } else {
                    0.0
                };
                2.0 * frac * cell * SAMPLES as f64
            })
            .collect();
        chi2_test("uniform triangle", &observed, &expected, 0.01).unwrap();
    }
}
