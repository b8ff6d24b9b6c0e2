//! Light trapped by total internal reflection (`ppm/trapped_light.rs`): amcppm estimates the
//! paths E S* L with a total internal reflection by merging photons at the camera's first
//! specular vertex, and leaves the rest of E S* L to the camera path; the two together must
//! give the path tracer's image.

use caustica_renderer::material::Material;
use caustica_renderer::procedural::{camera_looking, cuboid, quad};
use caustica_renderer::scene::SceneDescription;
use glam::{Affine3A, Quat, Vec3};

use crate::common;

/// A light pipe: a glass bar 2 long and 0.3 square along x, its far end against an emitter of
/// radiance 1 larger than the end, the camera 0.35 from the near end looking into it a little
/// off its axis, the view filled by the end face. Camera rays nearly along the axis cross the
/// bar with at most one reflection off its sides; the others are carried to the emitter by
/// two or more total internal reflections (the sides are beyond the critical angle for every
/// ray that entered an end), the paths the merges estimate.
fn light_pipe() -> SceneDescription {
    let glass = Material::glass(1.5).named("glass");
    let light = Material::emitter(Vec3::ONE, Vec3::ZERO).named("light");
    let v = Vec3::new;
    let x = -2.02;
    SceneDescription {
        name: "light pipe".into(),
        meshes: vec![
            cuboid(
                "bar",
                Affine3A::from_scale_rotation_translation(
                    v(2.0, 0.3, 0.3),
                    Quat::IDENTITY,
                    v(-1.0, 0.0, 0.0),
                ),
                0,
            ),
            quad(
                "light",
                [
                    v(x, -0.5, 0.5),
                    v(x, -0.5, -0.5),
                    v(x, 0.5, -0.5),
                    v(x, 0.5, 0.5),
                ],
                1,
            ),
        ],
        materials: vec![glass, light],
        camera: Some(camera_looking(v(0.35, 0.06, 0.04), v(0.0, 0.0, 0.0), 40.0)),
        ..Default::default()
    }
}

/// The mean luminance of the image's central `size / 2` square, inside the end face by more
/// than the merges' radius.
fn central_mean(img: &caustica_renderer::image::Image, size: usize) -> f64 {
    let (lo, hi) = (size / 4, 3 * size / 4);
    let mut sum = 0.0;
    for y in lo..hi {
        for x in lo..hi {
            sum += caustica_renderer::geometry::luminance(img.pixels[y * size + x]) as f64;
        }
    }
    sum / ((hi - lo) * (hi - lo)) as f64
}

/// amcppm's image of the light pipe agrees with the path tracer's over the end face. The
/// merges carry 40.5 % of that light there (with their estimate left out, the ratio is 0.595
/// on every seed). Their kernel's cone mixes directions of two or more reflections with
/// directions of fewer, which the camera path counts, so at the default alpha (2/3, the cone
/// about 0.13 rad after 256 passes) the merged light is 12 % high (ratios 1.042 to 1.075 over
/// four seeds); with alpha 0.2 the kernel shrinks faster, and after 1024 passes seeds 0 and 1
/// give 1.004 and 1.010 (the path tracer's seeds 4 and 5 against 3: 1.000 and 0.998). We
/// allow 2 % a seed and 1.5 % for their mean: a merge off by a tenth fails.
#[test]
fn light_carried_by_total_internal_reflection_agrees_with_the_path_tracer() {
    let size = 32;
    let (pt, _) = common::render(light_pipe(), "pt", &[], 1024, size, 3, 0);
    let reference = central_mean(&pt, size as usize);
    let ratios: Vec<f64> = (0..2)
        .map(|seed| {
            let (amcppm, _) = common::render(
                light_pipe(),
                "amcppm",
                &[("photons", 1e4), ("radius", 0.05), ("alpha", 0.2)],
                1024,
                size,
                seed,
                0,
            );
            central_mean(&amcppm, size as usize) / reference
        })
        .collect();
    eprintln!("amcppm / pt over the end face, seeds 0 and 1: {ratios:.4?}");
    for r in &ratios {
        assert!((r - 1.0).abs() < 0.02, "amcppm / pt {ratios:?}");
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(
        (mean - 1.0).abs() < 0.015,
        "mean amcppm / pt {mean} ({ratios:?})"
    );
}
