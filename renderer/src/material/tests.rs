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
        specular_f0: Vec3::splat(0.04),
        specular_f90: 1.0,
        coat: clearcoat::Clearcoat::NONE,
        sheen: sheen::Sheen::NONE,
    })
}

/// `bsdf` (a metallic-roughness one) under a sheen of `color` and `roughness`.
fn with_sheen(bsdf: Bsdf, color: Vec3, roughness: f32) -> Bsdf {
    let Bsdf::MetallicRoughness(b) = bsdf else {
        unreachable!("layers belong to the metallic-roughness BSDF")
    };
    Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
        sheen: sheen::Sheen::new(color, roughness),
        ..b
    })
}

/// `bsdf` (a metallic-roughness one) with KHR_materials_specular's factors.
fn with_specular(bsdf: Bsdf, specular: f32, specular_color: Vec3) -> Bsdf {
    let Bsdf::MetallicRoughness(b) = bsdf else {
        unreachable!("layers belong to the metallic-roughness BSDF")
    };
    let (specular_f0, specular_f90) =
        MetallicRoughnessBsdf::dielectric_reflectance(b.eta, specular, specular_color);
    Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
        specular_f0,
        specular_f90,
        ..b
    })
}

/// `bsdf` (a metallic-roughness one) under a clearcoat of `weight` and `roughness`.
fn coated(bsdf: Bsdf, weight: f32, roughness: f32) -> Bsdf {
    let Bsdf::MetallicRoughness(b) = bsdf else {
        unreachable!("layers belong to the metallic-roughness BSDF")
    };
    Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
        coat: clearcoat::Clearcoat {
            weight,
            distrib: TrowbridgeReitz::new(roughness * roughness),
        },
        ..b
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
        (
            "plastic, tinted specular",
            with_specular(
                mr(Vec3::splat(0.3), 0.0, 0.4, 0.0),
                0.7,
                Vec3::new(3.0, 1.0, 0.2),
            ),
            0.5,
        ),
        (
            "clearcoat over rough plastic",
            coated(mr(Vec3::new(0.8, 0.1, 0.1), 0.0, 0.7, 0.0), 1.0, 0.1),
            0.6,
        ),
        (
            "clearcoat over metal, from below",
            coated(mr(Vec3::new(0.9, 0.6, 0.3), 1.0, 0.4, 0.0), 0.5, 0.3),
            -0.35,
        ),
        (
            "clearcoat over rough glass",
            coated(mr(Vec3::ONE, 0.0, 0.3, 1.0), 0.8, 0.05),
            0.8,
        ),
        (
            "sheen over plastic, grazing",
            with_sheen(
                mr(Vec3::new(0.2, 0.1, 0.5), 0.0, 0.8, 0.0),
                Vec3::new(1.0, 0.8, 0.9),
                0.3,
            ),
            0.2,
        ),
        (
            "sheen and clearcoat over metal, from below",
            coated(
                with_sheen(mr(Vec3::splat(0.9), 1.0, 0.3, 0.0), Vec3::splat(0.5), 0.8),
                0.7,
                0.2,
            ),
            -0.6,
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
            with_specular(mr(Vec3::ONE, 0.0, 0.3, 0.0), 1.0, Vec3::splat(30.0)),
            with_specular(mr(Vec3::ONE, 0.0, 0.6, 0.0), 0.5, Vec3::new(2.0, 1.0, 0.0)),
            coated(mr(Vec3::ONE, 0.0, 0.3, 0.0), 1.0, 0.1),
            coated(mr(Vec3::ONE, 1.0, 0.2, 0.0), 1.0, 0.5),
            coated(mr(Vec3::ONE, 0.0, 0.4, 1.0), 0.5, 0.2),
            with_sheen(mr(Vec3::ONE, 0.0, 1.0, 0.0), Vec3::ONE, 0.1),
            with_sheen(mr(Vec3::ONE, 1.0, 0.3, 0.0), Vec3::ONE, 0.6),
            coated(
                with_sheen(mr(Vec3::ONE, 0.0, 0.5, 0.0), Vec3::ONE, 1.0),
                1.0,
                0.1,
            ),
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

/// KHR_materials_specular at its limits: specular 0 leaves the plastic component a pure
/// Lambertian base / pi (no layer, nothing to couple); over a black base the layer's albedo
/// at normal incidence is f0 = min(0.04 specularColor, 1) specular per channel (the tables'
/// E, whose grazing term B is nil there), measured by Monte Carlo within five standard errors
/// plus the tables' accuracy (2e-3).
#[test]
fn specular_factor_and_colour_set_the_plastic_reflectance() {
    let base = Vec3::new(0.6, 0.3, 0.1);
    let bare = with_specular(mr(base, 0.0, 0.5, 0.0), 0.0, Vec3::ONE);
    for (wo, wi) in [
        (wo_at(0.9), wo_at(0.2)),
        (wo_at(0.3), Vec3::new(-0.5, 0.5, 0.707)),
    ] {
        let f = bare.f(wo, wi.normalize(), TransportMode::Radiance);
        assert!(
            (f - base / std::f32::consts::PI).abs().max_element() < 1e-6,
            "{f}"
        );
    }
    let colour = Vec3::new(10.0, 5.0, 1.0);
    let black = with_specular(mr(Vec3::ZERO, 0.0, 0.1, 0.0), 0.8, colour);
    let (a, err) = albedo(&black, wo_at(1.0), TransportMode::Radiance, 400_000);
    let f0 = (0.04 * colour).min(Vec3::ONE) * 0.8;
    assert!(
        (a - f0).abs().max_element() <= 5.0 * err + 2e-3,
        "albedo {a} ± {err}, f0 {f0}"
    );
}

/// A clearcoat over a base that reflects nothing (black, specular 0) reflects what its own
/// lobe does: c E_c(mu) with E_c the specular layer's albedo at f0 = 0.04. Over a lossless
/// diffuse base (white plastic of roughness 1, whose layers conserve energy to the tables'
/// accuracy) the albedo stays 1: the diffuse base is scaled by the light both layers let
/// through, normalised by its exact average (`material::clearcoat`). Glossy bases under a
/// coat are in `white_furnace_albedo_never_exceeds_one`.
#[test]
fn a_clearcoat_reflects_its_own_lobe_and_keeps_a_lossless_base_lossless() {
    use crate::material::layering::specular_albedo;
    let n = 400_000;
    for (weight, roughness) in [(1.0f32, 0.1f32), (0.5, 0.5)] {
        for cos_o in [0.95f32, 0.5, 0.15, 0.05] {
            let wo = wo_at(cos_o);
            let dark = coated(
                with_specular(mr(Vec3::ZERO, 0.0, 0.5, 0.0), 0.0, Vec3::ONE),
                weight,
                roughness,
            );
            let (a, err) = albedo(&dark, wo, TransportMode::Radiance, n);
            let alpha = roughness * roughness;
            let expected = weight * specular_albedo(cos_o, alpha, Vec3::splat(0.04), 1.0).x;
            assert!(
                (a.x - expected).abs() <= 5.0 * err + 2e-3,
                "coat {weight}, {roughness} at cos {cos_o}: albedo {} ± {err}, expected {expected}",
                a.x
            );
            let white = coated(mr(Vec3::ONE, 0.0, 1.0, 0.0), weight, roughness);
            let (a, err) = albedo(&white, wo, TransportMode::Radiance, n);
            assert!(
                (a.x - 1.0).abs() <= 5.0 * err + 2e-3,
                "coat {weight}, {roughness} over white at cos {cos_o}: albedo {} ± {err}",
                a.x
            );
        }
    }
}

/// A sheen over a base that reflects nothing (black, specular 0) reflects its own lobe:
/// sheenColor E(mu) per channel, E from its table (checked against Monte Carlo in
/// `material::sheen`). Sheens over white bases are in `white_furnace_albedo_never_exceeds_one`.
#[test]
fn a_sheen_reflects_its_own_lobe_over_a_black_base() {
    let colour = Vec3::new(1.0, 0.5, 0.25);
    for roughness in [0.2f32, 0.7] {
        for cos_o in [0.9f32, 0.4, 0.1] {
            let dark = with_sheen(
                with_specular(mr(Vec3::ZERO, 0.0, 0.5, 0.0), 0.0, Vec3::ONE),
                colour,
                roughness,
            );
            let (a, err) = albedo(&dark, wo_at(cos_o), TransportMode::Radiance, 400_000);
            let expected = colour * sheen::albedo(cos_o, roughness);
            assert!(
                (a - expected).abs().max_element() <= 5.0 * err + 2e-3,
                "sheen {roughness} at cos {cos_o}: albedo {a} ± {err}, expected {expected}"
            );
        }
    }
}
