//! Statistical tests of every BSDF: chi-square of `sample_f` against `pdf`, consistency of the
//! pdf `sample_f` reports, and white-furnace energy tests (albedo never above 1, equal to 1
//! where the BSDF is lossless).

use super::*;
use crate::sampling::chi2::{sidak_significance, test_directions};
use crate::sampling::sampler::Sampler;

fn wo_at(cos_theta: f32) -> Vec3 {
    Vec3::new(
        (1.0 - cos_theta * cos_theta).max(0.0).sqrt(),
        0.0,
        cos_theta,
    )
}

fn mr(base: Vec3, metallic: f32, roughness: f32, transmission: f32) -> Bsdf {
    Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
        base_color: base,
        metallic,
        transmission,
        eta: 1.5,
        distrib: TrowbridgeReitz::new(roughness * roughness),
    })
}

/// Non-delta BSDFs with the directions they are tested from.
fn non_delta_cases() -> Vec<(&'static str, Bsdf, f32)> {
    vec![
        (
            "diffuse",
            Bsdf::Diffuse(DiffuseBsdf {
                r: Vec3::splat(0.7),
            }),
            0.6,
        ),
        (
            "diffuse from below",
            Bsdf::Diffuse(DiffuseBsdf {
                r: Vec3::splat(0.7),
            }),
            -0.4,
        ),
        (
            "plastic rough",
            mr(Vec3::new(0.8, 0.2, 0.2), 0.0, 0.6, 0.0),
            0.7,
        ),
        (
            "plastic glossy grazing",
            mr(Vec3::splat(0.5), 0.0, 0.3, 0.0),
            0.15,
        ),
        ("metal", mr(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.4, 0.0), 0.5),
        (
            "half metal from below",
            mr(Vec3::splat(0.8), 0.5, 0.5, 0.0),
            -0.8,
        ),
        ("rough glass outside", rough_dielectric(1.5, 0.3), 0.8),
        ("rough glass inside", rough_dielectric(1.5, 0.3), -0.7),
        (
            "rough glass inside grazing",
            rough_dielectric(1.33, 0.5),
            -0.3,
        ),
        (
            "translucent mixture",
            mr(Vec3::splat(0.9), 0.2, 0.5, 0.5),
            0.45,
        ),
    ]
}

#[test]
fn bsdf_sampling_matches_pdf_chi2() {
    let cases = non_delta_cases();
    let alpha = sidak_significance(cases.len());
    for (name, bsdf, cos_o) in cases {
        let wo = wo_at(cos_o);
        test_directions(
            name,
            |u, uc| {
                bsdf.sample_f(wo, uc, u, TransportMode::Radiance)
                    .map(|s| s.wi)
            },
            &|wi| bsdf.pdf(wo, wi),
            alpha,
        )
        .unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn sampled_values_agree_with_f_and_pdf() {
    for (name, bsdf, cos_o) in non_delta_cases() {
        let wo = wo_at(cos_o);
        let mut sampler = Sampler::new(3);
        for k in 0..20_000 {
            sampler.start_pixel_sample(k, 0);
            let (uc, u) = (sampler.get_1d(), sampler.get_2d());
            if let Some(s) = bsdf.sample_f(wo, uc, u, TransportMode::Radiance) {
                let pdf = bsdf.pdf(wo, s.wi);
                let f = bsdf.f(wo, s.wi, TransportMode::Radiance);
                assert!(
                    (pdf - s.pdf).abs() <= 1e-3 * pdf.max(1.0),
                    "{name}: pdf {pdf} vs {}",
                    s.pdf
                );
                assert!(
                    (f - s.f).abs().max_element() <= 1e-3 * f.max_element().max(1.0),
                    "{name}: f {f} vs {}",
                    s.f
                );
            }
        }
    }
}

/// Monte Carlo albedo ∫ f |cos| dwi from `n` BSDF samples, with its standard error.
fn albedo(bsdf: &Bsdf, wo: Vec3, mode: TransportMode, n: u64) -> (Vec3, f32) {
    let mut sampler = Sampler::new(11);
    let (mut sum, mut sum_sq) = (Vec3::ZERO.as_dvec3(), 0.0f64);
    for k in 0..n {
        sampler.start_pixel_sample(k, 0);
        let (uc, u) = (sampler.get_1d(), sampler.get_2d());
        if let Some(s) = bsdf.sample_f(wo, uc, u, mode) {
            let w = (s.f * s.wi.z.abs() / s.pdf).as_dvec3();
            sum += w;
            sum_sq += w.x * w.x;
        }
    }
    let mean = sum / n as f64;
    let var = (sum_sq / n as f64 - mean.x * mean.x).max(0.0);
    (mean.as_vec3(), (var / n as f64).sqrt() as f32)
}

#[test]
fn white_furnace_albedo_never_exceeds_one() {
    let n = 200_000;
    for cos_o in [1.0f32, 0.7, 0.3, 0.05, -0.5] {
        let wo = wo_at(cos_o);
        let cases = [
            mr(Vec3::ONE, 0.0, 0.2, 0.0),
            mr(Vec3::ONE, 0.0, 0.8, 0.0),
            mr(Vec3::ONE, 1.0, 0.5, 0.0),
            mr(Vec3::ONE, 0.5, 0.05, 0.0),
            mr(Vec3::ONE, 0.0, 0.5, 1.0),
            mr(Vec3::ONE, 0.3, 0.4, 0.6),
        ];
        for bsdf in cases {
            let (a, err) = albedo(&bsdf, wo, TransportMode::Importance, n);
            // Five standard errors above one would be a real energy gain.
            assert!(
                a.max_element() <= 1.0 + 5.0 * err + 1e-4,
                "{bsdf:?} at cos {cos_o}: albedo {a} ± {err}"
            );
            assert!(
                a.min_element() > 0.0,
                "{bsdf:?} at cos {cos_o}: no energy at all"
            );
        }
    }
}

#[test]
fn white_furnace_lossless_bsdfs_conserve_energy() {
    let n = 200_000;
    for cos_o in [0.9f32, 0.4, -0.3, -0.9] {
        let wo = wo_at(cos_o);
        let lossless = [
            Bsdf::Diffuse(DiffuseBsdf { r: Vec3::ONE }),
            Bsdf::Mirror(MirrorBsdf { r: Vec3::ONE }),
            Bsdf::Dielectric(DielectricBsdf {
                eta: 1.5,
                tint: Vec3::ONE,
            }),
            Bsdf::Dielectric(DielectricBsdf {
                eta: 1.0,
                tint: Vec3::ONE,
            }),
        ];
        for bsdf in lossless {
            // Importance transport: no 1/eta^2 radiance compression, so lossless means 1.
            let (a, err) = albedo(&bsdf, wo, TransportMode::Importance, n);
            assert!(
                (a.x - 1.0).abs() <= 5.0 * err + 1e-4,
                "{bsdf:?} at cos {cos_o}: albedo {a} ± {err}"
            );
        }
    }
}

#[test]
fn radiance_through_glass_is_compressed_by_eta_squared() {
    // Normal incidence from outside: T = 0.96, radiance transmitted scales by 1/1.5^2.
    let glass = DielectricBsdf {
        eta: 1.5,
        tint: Vec3::ONE,
    };
    let s = glass
        .sample_f(Vec3::Z, 0.99, TransportMode::Radiance)
        .unwrap();
    assert!(s.wi.z < 0.0);
    assert!((s.f.x * s.wi.z.abs() / s.pdf - 1.0 / 2.25).abs() < 1e-5);
}

#[test]
fn material_kinds_follow_the_design() {
    let mut m = Material::diffuse(Vec3::ONE);
    assert_eq!(m.kind(), MaterialKind::Diffuse);
    m.metallic = 1.0;
    m.roughness = 0.0;
    assert_eq!(m.kind(), MaterialKind::Mirror);
    m.metallic = 0.0;
    m.transmission = 1.0;
    assert_eq!(m.kind(), MaterialKind::Dielectric);
    m.roughness = 0.3;
    assert_eq!(m.kind(), MaterialKind::MetallicRoughness);
}
