//! Vertex connection and merging (vcm) against the closed forms, the path tracer and bdpt,
//! technique by technique.

use caustica_renderer::camera::Camera;
use caustica_renderer::integrators::ppm::auto_radius;
use caustica_renderer::integrators::vcm::{Techniques, Vcm, VcmSettings};
use caustica_renderer::integrators::{ParamValues, RenderContext};
use caustica_renderer::procedural::cornell_box;
use caustica_renderer::scene::{Scene, SceneDescription};
use std::sync::Arc;

use crate::common::{block_means, block_means_of, mean, render, z_scores};

fn context(desc: SceneDescription, size: u32, seed: u64) -> RenderContext {
    let scene = Arc::new(Scene::build(desc).unwrap());
    let camera = Camera::new(&scene.camera, size, size);
    RenderContext {
        scene,
        camera,
        seed,
    }
}

fn vcm(ctx: RenderContext, techniques: Techniques, extra: &[(&str, f64)]) -> Vcm {
    let params: ParamValues = extra.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    Vcm::new(
        ctx,
        VcmSettings {
            techniques,
            ..VcmSettings::from_params(&params)
        },
    )
}

const CONNECTIONS: Techniques = Techniques {
    connections: true,
    merges: false,
};
const MERGES: Techniques = Techniques {
    connections: false,
    merges: true,
};

/// vcm, and each of its halves alone, reproduce the foundation's closed forms: inside the
/// point-lit sphere L = 1, inside the emissive sphere Le / (1 - rho) = 1. Both are lit
/// uniformly, so merging has no kernel bias there and the default radius serves. Standard
/// error of the image mean at 64 passes of 24 x 24 pixels: below 0.3 % (the spread of
/// per-pass means, merges alone the noisiest); we allow 1 %.
#[test]
fn vcm_reproduces_the_closed_forms() {
    for (name, desc) in crate::common::closed_form_scenes() {
        let (img, dropped) = render(desc.clone(), "vcm", &[], 64, 24, 1, 0);
        assert_eq!(dropped, 0);
        let m = mean(&img);
        assert!((m - 1.0).abs() < 0.01, "{name}: vcm mean {m}, exact 1");
        for (label, techniques) in [("connections", CONNECTIONS), ("merges", MERGES)] {
            let mut it = vcm(context(desc.clone(), 24, 1), techniques, &[]);
            let (m, _) = crate::common::mean_and_standard_error(&mut it, 64);
            assert!(
                (m - 1.0).abs() < 0.01,
                "{name}: {label} alone, mean {m}, exact 1"
            );
        }
    }
}

/// Block by block (4 x 4 pixels of 32 x 32), `it` agrees with `reference` as bdpt with pt
/// (`common::assert_blocks_agree`).
fn assert_agree(name: &str, reference: &[(f64, f64)], it: &mut Vcm, passes: u64) {
    let (z, ratio) = z_scores(reference, &block_means_of(it, passes, 32, 4));
    crate::common::assert_blocks_agree(name, &z, ratio);
}

/// Connections alone are bdpt (the same techniques, weighted by the same balance heuristic
/// through Georgiev's recursive quantities instead of pbrt's ratios): on the Cornell boxes
/// they agree with bdpt block by block. Measured at 1024 passes: mean z^2 1.13 and 1.18.
#[test]
fn connections_alone_agree_with_bdpt() {
    for (name, desc) in [
        ("cornell-box", cornell_box(false)),
        ("cornell-glass", cornell_box(true)),
    ] {
        let bdpt = block_means("bdpt", &desc, 1024, 32, 4, 1, &[]);
        let mut it = vcm(context(desc, 32, 2), CONNECTIONS, &[]);
        assert_agree(
            &format!("{name}, connections alone vs bdpt"),
            &bdpt,
            &mut it,
            1024,
        );
    }
}

/// Merges alone, and vcm, converge to the path tracer: with a radius small enough that the
/// kernel's bias is below the noise of 1024 passes (a quarter of the photon mappers' automatic
/// radius, which is vcm's own) they agree with pt block by block, on the diffuse box and where
/// light reaches the floor through the glass sphere (merges' own caustic). With the photon
/// mappers' radius, at 32 x 32 pixels a sixth of the box, both show the kernel's bias (mean z^2
/// 6.7 to 11.8, the image 0.8 to 1.2 % dark): which is what breaking the radius's schedule
/// would look like.
#[test]
fn merges_and_vcm_converge_to_the_path_tracer() {
    for (name, desc) in [
        ("cornell-box", cornell_box(false)),
        ("cornell-glass", cornell_box(true)),
    ] {
        let pt = block_means("pt", &desc, 1024, 32, 4, 1, &[]);
        for (label, techniques) in [("merges alone", MERGES), ("vcm", Techniques::default())] {
            let ctx = context(desc.clone(), 32, 2);
            let radius = auto_radius(&ctx) / 4.0;
            let mut it = vcm(ctx, techniques, &[("radius", radius)]);
            assert_agree(&format!("{name}, {label} vs pt"), &pt, &mut it, 1024);
        }
    }
}

/// The technique shares the viewer plots account for the whole image: over every path length
/// and technique they add up to the image's luminance times the passes (each technique's
/// weighted value is recorded once, where it is added), merges have none with connections
/// alone, and on the Cornell box with glass merges bring part of the light (the caustic).
#[test]
fn the_technique_shares_add_up_to_the_image() {
    for (techniques, merges_expected) in [(Techniques::default(), true), (CONNECTIONS, false)] {
        let mut it = vcm(
            context(cornell_box(true), 24, 3),
            techniques,
            &[("max_depth", 5.0)],
        );
        let (_, merges, total) = shares_add_up_to_the_image(&mut it, 8);
        assert_eq!(
            merges > 0.01 * total,
            merges_expected,
            "{techniques:?}: merges {merges}"
        );
    }
}

/// Renders `passes` passes of `it` and checks that its technique shares add up to its image's
/// luminance times the passes, with a plot per path length; (connections, merges, that total).
pub(crate) fn shares_add_up_to_the_image(it: &mut Vcm, passes: u64) -> (f64, f64, f64) {
    use caustica_renderer::geometry::luminance;
    use caustica_renderer::integrators::Integrator;
    let cancel = std::sync::atomic::AtomicBool::new(false);
    for pass in 0..passes {
        it.render_counted_pass(pass, &cancel).unwrap();
    }
    let image: f64 = it
        .image()
        .pixels
        .iter()
        .map(|p| f64::from(luminance(*p)))
        .sum();
    let shares = it.technique_shares();
    let connections: f64 = shares.lengths.iter().flat_map(|l| &l.connections).sum();
    let merges: f64 = shares.lengths.iter().flat_map(|l| &l.merges).sum();
    let total = image * passes as f64;
    eprintln!("connections {connections:.3}, merges {merges:.3}, image x passes {total:.3}");
    assert!(
        ((connections + merges) / total - 1.0).abs() < 1e-4,
        "shares {} against {total}",
        connections + merges
    );
    assert_eq!(
        it.plots().iter().filter(|p| p.plot == "Techniques").count(),
        6
    );
    (connections, merges, total)
}

/// The radius schedule, and its live controls: r_{i+1}^2 = r_i^2 ((i + 1) / (i + 2))^(1 - alpha)
/// (r_0^2 (i + 1)^(alpha - 1) while alpha stays), alpha = 1 keeps the radius, a radius set
/// live is the next pass's and shrinks on from there, and 0 returns to the automatic radius
/// shrunk as far as the passes so far would have.
#[test]
fn the_radius_follows_its_schedule_and_its_live_changes() {
    use caustica_renderer::integrators::Integrator;
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let mut it = vcm(
        context(cornell_box(false), 8, 1),
        Techniques::default(),
        &[],
    );
    let r0 = it.radius();
    assert!(r0 > 0.0 && (r0 - it.initial_radius()).abs() < 1e-12);
    for pass in 0..4 {
        it.render_counted_pass(pass, &cancel).unwrap();
    }
    let expected = r0 * 5f64.powf(-0.25 / 2.0);
    assert!(
        (it.radius() / expected - 1.0).abs() < 1e-9,
        "{} {expected}",
        it.radius()
    );
    it.set_live_param("alpha", 1.0);
    let before = it.radius();
    it.render_counted_pass(4, &cancel).unwrap();
    assert!((it.radius() / before - 1.0).abs() < 1e-12);
    it.set_live_param("radius", 0.05);
    assert_eq!(it.radius(), 0.05);
    it.set_live_param("alpha", 0.5);
    it.render_counted_pass(5, &cancel).unwrap();
    let expected = 0.05 * (6.0f64 / 7.0).powf(0.5 / 2.0);
    assert!((it.radius() / expected - 1.0).abs() < 1e-9);
    it.set_live_param("radius", 0.0);
    let expected = r0 * 7f64.powf(-0.5 / 2.0);
    assert!(
        (it.radius() / expected - 1.0).abs() < 1e-9,
        "{} {expected}",
        it.radius()
    );
}

/// vcm's kernel bias, measured directly, falls at the rate its radius schedule gives: on the
/// mirrored light with merges alone (each path has one merge, of weight 1, so this is density
/// estimation of the direct and the mirrored light with N_L = 1024 light subpaths a pass) the
/// image's mean less the exact radiance must match the expectation computed from the radii
/// the passes used (`ExpectedEstimate`, as for the photon mappers) within four standard
/// deviations at every checkpoint, and its slope from 8 to 256 passes that expectation's
/// slope; alpha 1/2, 3/4 and 1 have distinct rates (r_i^2 like i^(alpha - 1)).
#[test]
fn the_kernel_bias_of_merges_falls_as_the_radius_schedule_gives() {
    use crate::common::{ExpectedEstimate, MirroredLight};
    use caustica_renderer::integrators::Integrator;
    let setup = MirroredLight::new();
    let scene = Arc::new(Scene::build(setup.desc.clone()).unwrap());
    let camera = Camera::new(&scene.camera, 32, 32);
    let footprints = setup.pixel_footprints(&camera);
    let pixels = footprints.len() as f64;
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let (first, last) = (8u64, 256u64);
    for alpha in [0.5, 0.75, 1.0] {
        let ctx = RenderContext {
            scene: scene.clone(),
            camera,
            seed: 5,
        };
        let mut it = vcm(
            ctx,
            MERGES,
            &[("radius", 1.0), ("alpha", alpha), ("max_depth", 2.0)],
        );
        let mut expected = ExpectedEstimate::default();
        let mut ends = Vec::new();
        for pass in 0..last {
            let radii = vec![it.radius(); footprints.len()];
            it.render_pass(pass, &cancel).unwrap();
            expected.add_pass(&setup, &footprints, &radii, pixels as u64, true);
            let n = pass + 1;
            if n >= first && n.is_power_of_two() {
                let img = it.image();
                let mean = img.pixels.iter().map(|p| p.x as f64).sum::<f64>() / pixels;
                let measured = mean
                    - setup.direct_radiance(&footprints)
                    - setup.mirrored_radiance(&footprints);
                let (expected_bias, sigma) = expected.bias_and_sigma(&setup, &footprints, true);
                eprintln!(
                    "alpha {alpha:.2}, n {n}: bias {measured:.5}, expected {expected_bias:.5} +- {sigma:.5}"
                );
                assert!(
                    (measured - expected_bias).abs() < 4.0 * sigma,
                    "alpha {alpha}, n {n}: bias {measured}, expected {expected_bias} +- {sigma}"
                );
                if n == first || n == last {
                    ends.push((measured, expected_bias, sigma));
                }
            }
        }
        let span = (last as f64 / first as f64).ln();
        let slope = (ends[1].0 / ends[0].0).ln() / span;
        let expected_slope = (ends[1].1 / ends[0].1).ln() / span;
        let tolerance =
            4.0 * ((ends[0].2 / ends[0].1).powi(2) + (ends[1].2 / ends[1].1).powi(2)).sqrt() / span;
        eprintln!(
            "alpha {alpha:.2}: bias slope {slope:.3}, expected {expected_slope:.3} +- {:.3}",
            tolerance / 4.0
        );
        assert!(
            (slope - expected_slope).abs() < tolerance,
            "alpha {alpha}: slope {slope}, expected {expected_slope} within {tolerance}"
        );
    }
}
