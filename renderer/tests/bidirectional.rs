//! Bidirectional path tracing (bdpt) and multiplexed Metropolis light transport (mmlt) on
//! scenes with closed-form radiance, against the path tracer, strategy by strategy, and at
//! the extremes of their parameters.

use caustica_renderer::image::Image;
use caustica_renderer::integrators::ParamValues;
use caustica_renderer::procedural::{cornell_box, emissive_sphere, sphere_with_point_light};
use caustica_renderer::scene::{Scene, SceneDescription};
use caustica_renderer::session::{Session, SessionConfig};
use std::sync::Arc;

fn render(
    desc: SceneDescription,
    integrator: &str,
    params: &[(&str, f64)],
    passes: u64,
    size: u32,
    seed: u64,
) -> (Image, u64) {
    let session = Session::start(SessionConfig {
        scene: Arc::new(Scene::build(desc).unwrap()),
        integrator: integrator.into(),
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<ParamValues>(),
        width: size,
        height: size,
        seed,
        threads: 0,
        max_passes: Some(passes),
        time_limit: None,
        on_frame: None,
    })
    .unwrap();
    let frame = session.wait();
    assert_eq!(frame.image.count_non_finite(), 0);
    ((*frame.image).clone(), frame.dropped)
}

fn mean(img: &Image) -> f64 {
    img.pixels
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64 / 3.0)
        .sum::<f64>()
        / img.pixels.len() as f64
}

/// The mean over the image after each of `passes` passes of `integrator`, and the standard
/// error of their average, from the spread of the per-pass means.
fn mean_and_standard_error(
    integrator: &mut dyn caustica_renderer::integrators::Integrator,
    passes: u64,
) -> (f64, f64) {
    use std::sync::atomic::AtomicBool;
    let cancel = AtomicBool::new(false);
    let mut per_pass = Vec::new();
    let mut previous_total = 0.0;
    for pass in 0..passes {
        integrator.render_pass(pass, &cancel).unwrap();
        let total = mean(&integrator.image()) * (pass + 1) as f64;
        per_pass.push(total - previous_total);
        previous_total = total;
    }
    let n = passes as f64;
    let m = per_pass.iter().sum::<f64>() / n;
    let var = per_pass.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Every strategy on its own (unweighted) converges to the same image for each path length
/// it can sample: on the Cornell box (diffuse, one area light) every strategy samples every
/// path, so for bounces 1 to 3 the image mean of each (s, t) must match next-event
/// estimation's (s = 1) within four combined standard errors (estimated from the spread of
/// per-pass means). This is how an error in one strategy's contribution shows; the weighted
/// sum is tested against the path tracer below.
#[test]
fn each_strategy_alone_converges_to_the_same_image() {
    use caustica_renderer::camera::PerspectiveCamera;
    use caustica_renderer::integrators::RenderContext;
    use caustica_renderer::integrators::bdpt::{BdptIntegrator, BdptSettings};
    let scene = Arc::new(Scene::build(cornell_box(false)).unwrap());
    let camera = PerspectiveCamera::new(&scene.camera, 16, 16);
    for depth in 1..=3usize {
        let mut results = Vec::new();
        for s in 0..=depth + 2 {
            let t = depth + 2 - s;
            if t == 0 || (s, t) == (1, 1) {
                continue;
            }
            let mut bdpt = BdptIntegrator::new(
                RenderContext {
                    scene: scene.clone(),
                    camera,
                    seed: 7,
                },
                BdptSettings {
                    max_depth: depth as u32,
                    only_strategy: Some((s, t)),
                },
            );
            let (m, se) = mean_and_standard_error(&mut bdpt, 1024);
            eprintln!("depth {depth}, (s, t) = ({s}, {t}): {m:.5} +- {se:.5}");
            results.push(((s, t), m, se));
        }
        let &(_, m_ref, se_ref) = results.iter().find(|r| r.0.0 == 1).unwrap();
        for &((s, t), m, se) in &results {
            let tolerance = 4.0 * (se * se + se_ref * se_ref).sqrt();
            assert!(
                (m - m_ref).abs() < tolerance,
                "depth {depth}: strategy ({s}, {t}) gives {m}, next-event estimation {m_ref} (tolerance {tolerance})"
            );
        }
    }
}

/// bdpt reproduces the foundation's closed forms: inside the point-lit sphere L = 1, inside
/// the emissive sphere Le / (1 - rho) = 1. Standard error of the image mean at 64 passes of
/// 24 x 24 pixels: below 0.2 % (measured from the spread of per-pass means); we allow 1 %.
#[test]
fn bdpt_reproduces_the_closed_forms() {
    for (name, desc) in [
        ("point-lit sphere", sphere_with_point_light(64)),
        ("emissive sphere", emissive_sphere(0.2, 0.8, 64)),
    ] {
        let (img, dropped) = render(desc, "bdpt", &[], 64, 24, 1);
        assert_eq!(dropped, 0);
        let m = mean(&img);
        assert!((m - 1.0).abs() < 0.01, "{name}: mean {m}, exact 1");
    }
}

/// Per-block means of the image (blocks of `block` x `block` pixels) with their standard
/// errors, from the spread of the per-pass block means over `passes` independent passes.
fn block_means(
    integrator: &str,
    desc: &SceneDescription,
    passes: u64,
    size: u32,
    block: usize,
    seed: u64,
) -> Vec<(f64, f64)> {
    use caustica_renderer::camera::PerspectiveCamera;
    use caustica_renderer::integrators::{RenderContext, find};
    use std::sync::atomic::AtomicBool;
    let scene = Arc::new(Scene::build(desc.clone()).unwrap());
    let camera = PerspectiveCamera::new(&scene.camera, size, size);
    let mut it = (find(integrator).unwrap().create)(
        RenderContext {
            scene,
            camera,
            seed,
        },
        &ParamValues::new(),
    );
    let cancel = AtomicBool::new(false);
    let blocks_per_row = size as usize / block;
    let nb = blocks_per_row * blocks_per_row;
    let (mut sum, mut sum_sq) = (vec![0.0f64; nb], vec![0.0f64; nb]);
    let mut previous = vec![0.0f64; nb];
    let lum = |p: glam::Vec3| caustica_renderer::geometry::luminance(p) as f64;
    for pass in 0..passes {
        it.render_pass(pass, &cancel).unwrap();
        let img = it.image();
        let mut totals = vec![0.0f64; nb];
        for (i, p) in img.pixels.iter().enumerate() {
            let (x, y) = (i % size as usize / block, i / size as usize / block);
            totals[y * blocks_per_row + x] += lum(*p) * (pass + 1) as f64 / (block * block) as f64;
        }
        for b in 0..nb {
            let this_pass = totals[b] - previous[b];
            sum[b] += this_pass;
            sum_sq[b] += this_pass * this_pass;
            previous[b] = totals[b];
        }
    }
    let n = passes as f64;
    (0..nb)
        .map(|b| {
            let m = sum[b] / n;
            let var = (sum_sq[b] / n - m * m).max(0.0) * n / (n - 1.0);
            (m, (var / n).sqrt())
        })
        .collect()
}

/// Agreement of two integrators block by block: the z-scores of the differences of block
/// means, and the ratio of the image means (b over a).
fn agreement(
    desc: &SceneDescription,
    a: (&str, u64),
    b: (&str, u64),
    size: u32,
) -> (Vec<f64>, f64) {
    // Different seeds: the same seed gives both integrators the same first random numbers
    // in every pixel, and common random numbers would correlate them.
    let (ma, mb) = (
        block_means(a.0, desc, a.1, size, 4, 1),
        block_means(b.0, desc, b.1, size, 4, 2),
    );
    let z = ma
        .iter()
        .zip(&mb)
        .map(|((x, sx), (y, sy))| (x - y) / (sx * sx + sy * sy).sqrt().max(1e-12))
        .collect();
    let total = |m: &[(f64, f64)]| m.iter().map(|v| v.0).sum::<f64>();
    (z, total(&mb) / total(&ma))
}

/// pt and bdpt agree on the bundled Cornell boxes: mean luminance within 1 percent and
/// per-pixel differences consistent with noise, judged on 4 x 4 blocks (single pixels'
/// fireflies make per-pixel variance estimates useless): the mean squared z-score of the 64
/// blocks' differences must be below 2 (about 1 without bias; its own spread at 64 blocks is
/// about 0.2) and no block may differ by more than 4.5 standard errors (Sidak for 64 blocks
/// at 0.1 % is 4.0, allowing for the error of the estimated standard errors).
#[test]
fn bdpt_agrees_with_the_path_tracer_on_the_cornell_boxes() {
    for (name, desc) in [
        ("cornell-box", cornell_box(false)),
        ("cornell-glass", cornell_box(true)),
    ] {
        let (z, ratio) = agreement(&desc, ("pt", 1024), ("bdpt", 1024), 32);
        let chi = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
        let worst = z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
        eprintln!(
            "{name}: bdpt / pt luminance {ratio:.4}, mean z^2 {chi:.3}, worst |z| {worst:.2}"
        );
        assert!(
            (ratio - 1.0).abs() < 0.01,
            "{name}: luminance ratio {ratio}"
        );
        assert!(
            chi < 2.0 && worst < 4.5,
            "{name}: mean z^2 {chi}, worst |z| {worst}"
        );
    }
}
#[test]
fn scratch_mmlt() {
    for seed in 1..4 {
        let p: ParamValues = [
            ("bootstrap", 100000.0),
            ("chains", 1000.0),
            ("max_depth", 10.0),
        ]
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
        let session = Session::start(SessionConfig {
            scene: Arc::new(Scene::build(cornell_box(false)).unwrap()),
            integrator: "mmlt".into(),
            params: p,
            width: 32,
            height: 32,
            seed,
            threads: 0,
            max_passes: Some(512),
            time_limit: None,
            on_frame: None,
        })
        .unwrap();
        let f = session.wait();
        let st = (*f.statistics).clone().unwrap();
        eprintln!(
            "mmlt: cornell {:.5} b {} se {} per length {}",
            mean(&f.image),
            st["normalisation_b"],
            st["normalisation_standard_error"],
            st["bootstrap_b_per_length"]
        );
    }
}
