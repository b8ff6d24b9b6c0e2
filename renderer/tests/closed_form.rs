//! Scenes with closed-form radiance, rendered by the path tracer through the session API.
//! Tolerances come from the estimator's own variance: every pixel has the same expectation,
//! so the spread of pixel values estimates the per-pixel standard deviation.

use caustica_renderer::image::Image;
use caustica_renderer::procedural::{emissive_sphere, sphere_with_point_light};
use caustica_renderer::scene::SceneDescription;

use crate::common;

/// The path tracer's image, which must drop no sample.
fn render(
    desc: SceneDescription,
    params: &[(&str, f64)],
    passes: u64,
    size: u32,
    threads: usize,
) -> Image {
    let (image, dropped) = common::render(desc, "pt", params, passes, size, 7, threads);
    assert_eq!(
        dropped, 0,
        "no sample may be NaN, infinite or negative here"
    );
    image
}

/// Checks that every pixel's estimate of `expected` is within what its noise allows, and
/// that the image mean is within `bias` (a known systematic error) plus 4 standard errors.
fn assert_uniform_radiance(img: &Image, expected: f64, bias: f64) {
    let values: Vec<f64> = img
        .pixels
        .iter()
        .flat_map(|p| [p.x as f64, p.y as f64, p.z as f64])
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - expected).powi(2)).sum::<f64>() / n).sqrt();
    let worst = values
        .iter()
        .map(|v| (v - expected).abs())
        .fold(0.0, f64::max);
    assert!(
        (mean - expected).abs() <= bias + 4.0 * sd / n.sqrt(),
        "image mean {mean} vs exact {expected} (pixel sd {sd}, {} values)",
        n
    );
    // 5.5 sigma: with a few thousand pixels a Gaussian tail this far has odds below 1e-4.
    assert!(
        worst <= bias + 5.5 * sd,
        "a pixel is {worst} from {expected}, pixel sd {sd}"
    );
    assert!(
        sd < 0.2 * expected,
        "the estimate is too noisy to test anything: sd {sd}"
    );
}

#[test]
fn point_light_in_diffuse_sphere_gives_unit_radiance() {
    // rho = 0.5, I = pi at the centre of the unit sphere: L = rho E / (pi (1 - rho)) = 1.
    // A tessellated sphere's facets are nearer than 1 by at most 1 - cos(pi / 128): the
    // direct irradiance is high by at most 2 (1 - cos(pi/128)) / cos^2 = 6e-4 of it.
    let img = render(sphere_with_point_light(128), &[], 64, 48, 0);
    assert_uniform_radiance(&img, 1.0, 2e-3);
}

#[test]
fn closed_emissive_sphere_converges_to_le_over_one_minus_rho() {
    // rho = 0.8 needs ~5 bounces on average and exercises Russian roulette; exact for any
    // closed surface: L = Le + rho L.
    let (le, rho) = (0.2, 0.8);
    let img = render(emissive_sphere(le, rho, 64), &[], 64, 48, 0);
    assert_uniform_radiance(&img, (le / (1.0 - rho)) as f64, 1e-6);
}

#[test]
fn russian_roulette_from_any_depth_keeps_the_closed_form() {
    // rr_depth 0 lets roulette end a path at its first hit; 1024, beyond max_depth 64, never
    // does: paths run to max_depth and leave out rho^65 / (1 - rho) Le = 5e-7 of L = 1. The
    // facets are shaded flat: interpolated normals lose the directions the geometric surface
    // contradicts (`SurfaceInteraction::consistent`), 0.2 % of L on this sphere, which the
    // noise of roulette hides in the test above but not without it. Without roulette every
    // path brings the same sum of rho^k Le (a cosine-sampled diffuse bounce keeps rho of the
    // throughput whatever its direction), so a few passes test it as well as many; they were
    // 64 bounces each for 64 passes, nine tenths of this test.
    let (le, rho) = (0.2, 0.8);
    let mut sphere = emissive_sphere(le, rho, 64);
    sphere.meshes[0].normals = None;
    for (rr_depth, passes) in [(0.0, 64), (1024.0, 4)] {
        let img = render(sphere.clone(), &[("rr_depth", rr_depth)], passes, 48, 0);
        assert_uniform_radiance(&img, 1.0, 1e-6);
    }
}

#[test]
fn same_seed_gives_identical_images_on_one_and_two_threads() {
    let desc = caustica_renderer::procedural::cornell_box(true);
    let one = render(desc.clone(), &[], 4, 40, 1);
    let two = render(desc, &[], 4, 40, 2);
    assert!(one.mean_luminance() > 0.0);
    assert_eq!(one, two, "thread count changed the image");
}
