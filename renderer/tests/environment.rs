//! Environment maps: a diffuse surface under an environment of constant patches, whose
//! irradiance has a closed form, through every integrator. The map (turned and scaled, to
//! check both) has a dim lower hemisphere, a brighter upper one and a small, very bright
//! patch like a sun, so importance sampling matters; the surface is tilted so that it sees
//! part of the lower hemisphere and all of the patch.

use caustica_renderer::light::environment::{EnvironmentChoice, EnvironmentSettings};
use caustica_renderer::light::environment_map::EnvironmentMap;
use caustica_renderer::material::Material;
use caustica_renderer::procedural::{camera_looking, quad};
use caustica_renderer::scene::SceneDescription;
use glam::{Mat3, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

use crate::common;

const WIDTH: usize = 128;
const HEIGHT: usize = 64;
const L_LOWER: f32 = 0.1;
const L_UPPER: f32 = 0.5;
const L_PATCH: f32 = 20.0;
/// The patch's texel rows and columns (end exclusive): theta in [33.75, 45] degrees, phi in
/// [22.5, 45] degrees.
const PATCH_ROWS: (usize, usize) = (12, 16);
const PATCH_COLUMNS: (usize, usize) = (72, 80);
const STRENGTH: f32 = 2.0;
const ROTATION_DEGREES: f32 = 30.0;
const ALBEDO: f32 = 0.7;

fn patch_map() -> EnvironmentMap {
    let mut texels = Vec::with_capacity(WIDTH * HEIGHT);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let in_patch = (PATCH_ROWS.0..PATCH_ROWS.1).contains(&y)
                && (PATCH_COLUMNS.0..PATCH_COLUMNS.1).contains(&x);
            let l = if in_patch {
                L_PATCH
            } else if y < HEIGHT / 2 {
                L_UPPER
            } else {
                L_LOWER
            };
            texels.push(Vec3::splat(l));
        }
    }
    EnvironmentMap::new("patches", WIDTH, HEIGHT, texels).unwrap()
}

/// Irradiance on a surface of normal `n` (in the map's frame) whose hemisphere holds the
/// whole patch: the two hemispheres' uniform parts, pi (1 +- n_y) / 2 each (the projected
/// solid angle of the part of n's hemisphere above or below the horizon), plus the patch's
/// excess over the upper hemisphere times its integral of n . w over theta and phi, with
/// w = (sin t sin p, cos t, -sin t cos p) and dw = sin t dt dp.
fn irradiance(n: Vec3) -> f64 {
    let (n_x, n_y, n_z) = (n.x as f64, n.y as f64, n.z as f64);
    let angle = |index: usize, count: usize, span: f64| index as f64 / count as f64 * span;
    let (t0, t1) = (
        angle(PATCH_ROWS.0, HEIGHT, PI),
        angle(PATCH_ROWS.1, HEIGHT, PI),
    );
    let (p0, p1) = (
        angle(PATCH_COLUMNS.0, WIDTH, 2.0 * PI) - PI,
        angle(PATCH_COLUMNS.1, WIDTH, 2.0 * PI) - PI,
    );
    let sin2 = |t: f64| t / 2.0 - (2.0 * t).sin() / 4.0;
    let sin_cos = |t: f64| t.sin().powi(2) / 2.0;
    let patch = n_x * (sin2(t1) - sin2(t0)) * (p0.cos() - p1.cos())
        + n_y * (sin_cos(t1) - sin_cos(t0)) * (p1 - p0)
        - n_z * (sin2(t1) - sin2(t0)) * (p1.sin() - p0.sin());
    let uniform = L_UPPER as f64 * PI * (1.0 + n_y) / 2.0 + L_LOWER as f64 * PI * (1.0 - n_y) / 2.0;
    STRENGTH as f64 * (uniform + (L_PATCH - L_UPPER) as f64 * patch)
}

/// A diffuse square of half size 2 through the origin, facing `n` (world), seen at its centre
/// by a narrow camera, lit by the patch map only.
fn tilted_plane(n: Vec3) -> SceneDescription {
    let frame = caustica_renderer::geometry::Frame::from_z(n);
    let corner = |a: f32, b: f32| 2.0 * (a * frame.s + b * frame.t);
    let eye = 3.0 * (n + 0.3 * frame.s).normalize();
    SceneDescription {
        meshes: vec![quad(
            "plane",
            [
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ],
            0,
        )],
        materials: vec![Material::diffuse(Vec3::splat(ALBEDO))],
        camera: Some(camera_looking(eye, Vec3::ZERO, 0.05)),
        environment: EnvironmentSettings {
            choice: EnvironmentChoice::Map(Arc::new(patch_map())),
            strength: STRENGTH,
            rotation_degrees: ROTATION_DEGREES,
        },
        ..Default::default()
    }
}

/// The surface's normal in the world: 40 degrees from up, towards the map's -Z (phi = 0)
/// turned by the environment's rotation, so the patch lies 20 to 50 degrees from it.
fn normal_in_world() -> (Vec3, Vec3) {
    let theta = 40f32.to_radians();
    let n_map = Vec3::new(0.0, theta.cos(), -theta.sin());
    let n_world = Mat3::from_rotation_y(ROTATION_DEGREES.to_radians()) * n_map;
    (n_map, n_world)
}

#[test]
fn the_closed_form_holds_for_the_map_as_read() {
    // The irradiance of the bilinear map by a fine deterministic quadrature agrees with the
    // closed form of its constant patches (bilinear smoothing of the edges is antisymmetric
    // about them, so it cancels to second order).
    let map = patch_map();
    let (n_map, _) = normal_in_world();
    let (nt, np) = (2048, 4096);
    let mut sum = 0.0f64;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * PI;
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * PI - PI;
            let w = Vec3::new(
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
                (-theta.sin() * phi.cos()) as f32,
            );
            let cos = n_map.dot(w).max(0.0) as f64;
            sum += map.radiance(w).x as f64 * cos * theta.sin();
        }
    }
    let quadrature = STRENGTH as f64 * sum * (PI / nt as f64) * (2.0 * PI / np as f64);
    let exact = irradiance(n_map);
    assert!(
        (quadrature - exact).abs() < 1e-3 * exact,
        "quadrature {quadrature}, closed form {exact}"
    );
}

/// Mean of the x channel over the image and its standard error over pixels.
fn mean_and_error(image: &caustica_renderer::image::Image) -> (f64, f64) {
    let v: Vec<f64> = image.pixels.iter().map(|p| p.x as f64).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn every_integrator_reproduces_the_irradiance_of_a_patch_environment() {
    // L = rho / pi E(n). The image's pixels all see the same point, so their spread gives the
    // standard error of the mean; each integrator must land within four of them and within
    // 1 % (the bound; the photon mappers' kernel has no bias on a uniformly lit plane).
    let (n_map, n_world) = normal_in_world();
    let exact = ALBEDO as f64 / PI * irradiance(n_map);
    // The photon mappers' direct light is next-event estimation, as the path tracer's; their
    // photons from the environment are checked by the mirror test below.
    let cases: [(&str, common::Params, u64); 5] = [
        ("pt", &[], 160),
        ("bdpt", &[], 160),
        ("mmlt", &[], 160),
        ("vcm", &[], 160),
        ("sppm", &[("photons", 1000.0)], 160),
    ];
    for (integrator, params, passes) in cases {
        let (image, dropped) =
            common::render(tilted_plane(n_world), integrator, params, passes, 32, 5, 0);
        assert_eq!(dropped, 0, "{integrator}");
        let (mean, se) = mean_and_error(&image);
        eprintln!("{integrator}: {mean} ± {se}, exact {exact}");
        assert!(
            (mean - exact).abs() <= (4.0 * se).max(2e-4 * exact)
                && (mean - exact).abs() < 0.01 * exact,
            "{integrator}: {mean} ± {se}, exact {exact}"
        );
    }
}

#[test]
fn photon_mappers_direct_light_on_a_glossy_plane_agrees_with_the_path_tracer() {
    // The tilted plane as a rough plastic (alpha 0.25, so it holds hit points): alone under
    // the map it has no indirect light, so the photon mappers' image is their direct light
    // at the hit point, next-event estimation and a BSDF-sampled ray weighted by MIS
    // (`ppm/hit_points.rs`). Every pixel sees the same point, so the spread over pixels is
    // each image's standard error; they agree within four of them (combined) and 1 %.
    let (_, n_world) = normal_in_world();
    let mut desc = tilted_plane(n_world);
    desc.materials[0] = Material::metallic_roughness(Vec3::new(0.7, 0.3, 0.2), 0.0, 0.5);
    let (pt, pt_se) = mean_and_error(&common::render(desc.clone(), "pt", &[], 256, 32, 3, 0).0);
    // Every photon mapper shares this eye pass (amcppm's image here is sppm's to the bit).
    for integrator in ["sppm", "pppm"] {
        let params = [("photons", 1000.0)];
        let (image, dropped) = common::render(desc.clone(), integrator, &params, 128, 32, 4, 0);
        assert_eq!(dropped, 0, "{integrator}");
        let (mean, se) = mean_and_error(&image);
        eprintln!("{integrator}: {mean} ± {se}, path tracer {pt} ± {pt_se}");
        let bound = (4.0 * (se * se + pt_se * pt_se).sqrt()).min(0.01 * pt);
        assert!(
            (mean - pt).abs() < bound,
            "{integrator}: {mean} ± {se}, path tracer {pt} ± {pt_se}"
        );
    }
    // With no indirect light photons bring nothing: amcppm's automatic count (`photon_budget`)
    // falls from one per pixel (10^4 at this size), a fifth at most a photon pass from the
    // eighth pass on, below an eighth of that (1,250) at the 17th; from there passes save
    // theirs up for one that traces 1,250 or more, and the average falls on to its floor, a
    // sixty-fourth (156), by the 51st (measured: 34 photon passes in 128). Its image is still
    // the path tracer's.
    use caustica_renderer::camera::Camera;
    use caustica_renderer::integrators::{RenderContext, find};
    let scene = Arc::new(caustica_renderer::scene::Scene::build(desc).unwrap());
    let camera = Camera::new(&scene.camera, 32, 32);
    let context = RenderContext {
        scene,
        camera,
        seed: 5,
    };
    let mut amcppm = (find("amcppm").unwrap().create)(context, &Default::default());
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let photons = |it: &dyn caustica_renderer::integrators::Integrator| {
        it.automatic()
            .into_iter()
            .find(|(name, _)| *name == "photons")
            .map(|(_, value)| value)
    };
    assert_eq!(photons(&*amcppm), Some(10_000.0));
    for pass in 0..128 {
        amcppm.render_counted_pass(pass, &cancel).unwrap();
    }
    assert_eq!(photons(&*amcppm), Some(156.0));
    let photon_passes = amcppm.statistics().unwrap()["photon_passes"]
        .as_u64()
        .unwrap();
    eprintln!("amcppm: {photon_passes} photon passes of 128");
    assert!(photon_passes < 64, "{photon_passes} photon passes of 128");
    let (mean, se) = mean_and_error(&amcppm.image());
    let bound = (4.0 * (se * se + pt_se * pt_se).sqrt()).min(0.01 * pt);
    assert!(
        (mean - pt).abs() < bound,
        "amcppm: {mean} ± {se}, path tracer {pt} ± {pt_se}"
    );
}

/// The tilted plane with a wall of `material` standing on its far edge, facing back across it.
fn plane_and_wall(name: &str, material: Material) -> SceneDescription {
    let (_, n_world) = normal_in_world();
    let frame = caustica_renderer::geometry::Frame::from_z(n_world);
    let (a, b) = (-2.0 * frame.t, 2.0 * frame.t);
    let (base, up) = (-2.0 * frame.s, 3.0 * n_world);
    let mut desc = tilted_plane(n_world);
    desc.meshes.push(quad(
        name,
        [base + a, base + b, base + b + up, base + a + up],
        1,
    ));
    desc.materials.push(material);
    desc
}

#[test]
fn each_bdpt_strategy_alone_sees_the_same_environment_light() {
    // Light subpaths that start at the environment (s >= 2) and the camera's escaping paths
    // (s = 0) against next-event estimation, path length by path length, in a view of the
    // plane and its diffuse wall.
    let mut desc = plane_and_wall("diffuse wall", Material::diffuse(Vec3::splat(0.8)));
    let (_, n_world) = normal_in_world();
    let frame = caustica_renderer::geometry::Frame::from_z(n_world);
    desc.camera = Some(camera_looking(
        5.0 * n_world + 3.0 * frame.s,
        Vec3::ZERO,
        50.0,
    ));
    common::assert_strategies_agree(desc, 2);
}

#[test]
fn light_subpaths_and_photons_from_the_environment_agree_with_the_path_tracer() {
    // The tilted plane beside a wall standing on its far edge, lit by the patch environment:
    // a mirror wall brings light that reaches the photon mappers only as photons emitted by the
    // environment, a diffuse wall light that BDPT also gathers by connecting light subpaths
    // that start at the environment. The path tracer (its standard error held under 0.25 %)
    // is the reference: BDPT, MMLT and VCM must agree within four standard errors and 1 %, the
    // photon mappers within 1 % (their pixels share photons, so the spread over pixels says
    // little of their error).
    let walls = [
        ("mirror", Material::metallic_roughness(Vec3::ONE, 1.0, 0.0)),
        ("diffuse wall", Material::diffuse(Vec3::splat(0.8))),
    ];
    for (wall, material) in walls {
        let desc = plane_and_wall(wall, material);
        let (pt, pt_se) = mean_and_error(&common::render(desc.clone(), "pt", &[], 256, 32, 7, 0).0);
        eprintln!("{wall}, pt: {pt} ± {pt_se}");
        assert!(
            pt_se < 0.0025 * pt,
            "{wall}: the reference is too noisy: {pt} ± {pt_se}"
        );
        for integrator in ["bdpt", "mmlt", "vcm"] {
            let (image, dropped) = common::render(desc.clone(), integrator, &[], 256, 32, 9, 0);
            assert_eq!(dropped, 0, "{wall}, {integrator}");
            let (mean, se) = mean_and_error(&image);
            eprintln!("{wall}, {integrator}: {mean} ± {se}");
            let bound = (4.0 * (se * se + pt_se * pt_se).sqrt()).min(0.01 * pt);
            assert!(
                (mean - pt).abs() < bound,
                "{wall}, {integrator}: {mean} ± {se}, path tracer {pt} ± {pt_se}"
            );
        }
        for integrator in ["sppm", "pppm"] {
            let params = [("photons", 100_000.0), ("radius", 0.3)];
            let (image, dropped) = common::render(desc.clone(), integrator, &params, 64, 16, 9, 0);
            assert_eq!(dropped, 0, "{wall}, {integrator}");
            let (mean, _) = mean_and_error(&image);
            eprintln!("{wall}, {integrator}: {mean}");
            assert!(
                (mean - pt).abs() < 0.01 * pt,
                "{wall}, {integrator}: {mean}, path tracer {pt} ± {pt_se}"
            );
        }
    }
}

#[test]
fn maps_load_from_hdr_and_exr_files_and_bad_files_are_named() {
    use caustica_renderer::image::{Image, write_exr};
    let dir = std::env::temp_dir().join(format!("caustica-environment-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A 4 x 2 image whose texels all differ; RGBE keeps 8 bits of mantissa, so the .hdr copy
    // agrees within 1 %.
    let mut image = Image::new(4, 2);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        *p = Vec3::new(0.5 + i as f32, 0.25 * i as f32, 3.0 - 0.3 * i as f32);
    }
    let exr = dir.join("sky.exr");
    write_exr(&exr, &image, &Default::default()).unwrap();
    let hdr = dir.join("sky.hdr");
    let rgb: Vec<image::Rgb<f32>> = image
        .pixels
        .iter()
        .map(|p| image::Rgb(p.to_array()))
        .collect();
    image::codecs::hdr::HdrEncoder::new(std::fs::File::create(&hdr).unwrap())
        .encode(&rgb, 4, 2)
        .unwrap();
    for (path, tolerance) in [(&exr, 1e-6), (&hdr, 1e-2)] {
        let map = EnvironmentMap::load(path).unwrap();
        assert_eq!((map.width(), map.height()), (4, 2));
        for (i, p) in image.pixels.iter().enumerate() {
            // The texel's centre reads the texel itself.
            let uv = glam::Vec2::new((i % 4) as f32 + 0.5, (i / 4) as f32 + 0.5)
                / glam::Vec2::new(4.0, 2.0);
            let read = map.lookup(uv);
            assert!(
                (read - *p).abs().max_element() <= tolerance * p.max_element(),
                "{path:?} texel {i}: {read}"
            );
        }
    }
    // Bad files: the error names the file and says what is wrong.
    let missing = dir.join("missing.hdr");
    let text = dir.join("notes.txt");
    std::fs::write(&text, "not an image").unwrap();
    let truncated = dir.join("cut.exr");
    std::fs::write(&truncated, &std::fs::read(&exr).unwrap()[..40]).unwrap();
    let garbage = dir.join("garbage.hdr");
    std::fs::write(
        &garbage,
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\nxx",
    )
    .unwrap();
    for (path, says) in [
        (&missing, "cannot open"),
        (&text, "not an environment image"),
        (&truncated, ""),
        (&garbage, ""),
    ] {
        let error = EnvironmentMap::load(path).unwrap_err();
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(
            error.contains(name.as_ref()) && error.contains(says),
            "{error}"
        );
    }
    // An EXR whose header declares 20000 x 20000 pixels is refused from its header, before
    // any pixel is allocated (its data window patched into a 4 x 2 file).
    let mut bytes = std::fs::read(&exr).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    bytes[at + 8..at + 12].copy_from_slice(&19999i32.to_le_bytes());
    bytes[at + 12..at + 16].copy_from_slice(&19999i32.to_le_bytes());
    let huge = dir.join("huge.exr");
    std::fs::write(&huge, &bytes).unwrap();
    let error = EnvironmentMap::load(&huge).unwrap_err();
    assert!(
        error.contains("huge.exr") && error.contains("declares 20000 x 20000"),
        "{error}"
    );
    // Radiance that is not finite or negative is refused, naming the texel.
    let mut bad = vec![Vec3::ONE; 8];
    bad[5] = Vec3::new(1.0, f32::NAN, 1.0);
    let error = EnvironmentMap::new("nan.exr", 4, 2, bad).unwrap_err();
    assert!(
        error.contains("nan.exr") && error.contains("(1, 1)"),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_default_rule_lights_models_meant_for_a_viewer_and_leaves_lit_scenes_alone() {
    use caustica_renderer::procedural::{
        caustic_pool, cornell_box, door, gap_glass, sphere_with_point_light,
    };
    use caustica_renderer::scene::Scene;
    let studio_lit = |desc: SceneDescription| {
        let scene = Scene::build(desc).unwrap();
        assert!(
            scene.info.lighting.contains("chosen by the default rule"),
            "{}",
            scene.info.lighting
        );
        scene.info.lighting.starts_with("studio")
    };
    // Scenes with their own lighting: the bundled ones, a point light.
    for (name, desc) in [
        ("cornell box", cornell_box(false)),
        ("caustic pool", caustic_pool()),
        ("door", door()),
        ("gap and glass", gap_glass()),
        ("point-lit sphere", sphere_with_point_light(16)),
    ] {
        assert!(!studio_lit(desc), "{name}");
    }
    // A model without light sources, and one whose only emitter is a small detail: a glowing
    // square of 1 cm^2 on a 2 m^2 plate, emitting 5 (radiosity 5e-4 / 2 = 2.5e-4).
    let plate = |emitter: bool| {
        let mut desc = tilted_plane(Vec3::Y);
        desc.environment = EnvironmentSettings::default();
        if emitter {
            let c = |x: f32, z: f32| Vec3::new(x, 0.01, z);
            desc.meshes.push(quad(
                "lamp",
                [c(0.0, 0.1), c(0.1, 0.1), c(0.1, 0.0), c(0.0, 0.0)],
                1,
            ));
            desc.materials
                .push(Material::emitter(Vec3::splat(5.0), Vec3::ZERO));
        }
        desc
    };
    assert!(studio_lit(plate(false)));
    assert!(studio_lit(plate(true)));
    // The same detail a hundred times brighter lights the plate on its own.
    let mut bright = plate(true);
    bright.materials[1] = Material::emitter(Vec3::splat(500.0), Vec3::ZERO);
    assert!(!studio_lit(bright));
}

#[test]
fn a_chosen_environment_overrides_the_rule_and_can_be_replaced() {
    use caustica_renderer::procedural::cornell_box;
    use caustica_renderer::scene::Scene;
    let mut desc = cornell_box(false);
    desc.environment.choice = EnvironmentChoice::Studio;
    let scene = Scene::build(desc).unwrap();
    let area_lights = scene.lights.len() - 1;
    assert!(scene.environment.is_some() && scene.info.lighting == "studio");
    let warnings = scene.info.warnings.len();
    // Replaced: no environment, then a uniform one turned and scaled, then back; the geometry's
    // lights stay, the environment's warnings do not pile up.
    let none = scene.with_environment(EnvironmentSettings {
        choice: EnvironmentChoice::None,
        ..Default::default()
    });
    assert_eq!((none.lights.len(), none.environment), (area_lights, None));
    let uniform = none.with_environment(EnvironmentSettings {
        choice: EnvironmentChoice::Uniform,
        strength: 3.0,
        rotation_degrees: 45.0,
    });
    assert_eq!(uniform.environment, Some(area_lights));
    assert_eq!(uniform.environment_radiance(Vec3::X), Vec3::splat(3.0));
    assert!(
        uniform.info.lighting.contains("strength 3"),
        "{}",
        uniform.info.lighting
    );
    let back = uniform.with_environment(EnvironmentSettings {
        choice: EnvironmentChoice::Studio,
        ..Default::default()
    });
    assert_eq!(back.info.warnings.len(), warnings);
    assert_eq!(back.lights.len(), scene.lights.len());
    // Strength 0 is no environment at all (nothing to sample).
    let dark = scene.with_environment(EnvironmentSettings {
        choice: EnvironmentChoice::Studio,
        strength: 0.0,
        rotation_degrees: 0.0,
    });
    assert_eq!(dark.environment, None);
}
