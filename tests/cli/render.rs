//! `caustica render`: the bundled scenes to EXR and PNG with their metadata, MMLT's
//! statistics, rendering until an estimated error, environment images, `--camera-from`.

use super::{render, render_ok, stderr, temp_dir};
use caustica_renderer::image::read_exr;

#[test]
fn renders_the_cornell_box_to_exr_with_metadata() {
    let dir = temp_dir("exr");
    let out = dir.join("box.exr");
    let o = render_ok(
        "assets/cornell-box.gltf",
        &out,
        "--spp 4 --width 48 --height 32 --seed 9",
    );
    assert!(
        stderr(&o).contains("Mrays/s"),
        "the summary gives rays per second: {}",
        stderr(&o)
    );
    let (image, meta) = read_exr(&out).unwrap();
    assert_eq!((image.width, image.height), (48, 32));
    assert_eq!(image.count_non_finite(), 0);
    assert!(image.mean_luminance() > 0.01, "the box is lit");
    assert_eq!(meta["integrator"], "pt");
    assert_eq!(meta["passes"], "4");
    assert_eq!(meta["seed"], "9");
    let params: serde_json::Value = serde_json::from_str(&meta["parameters"]).unwrap();
    assert_eq!(params["max_depth"], 64.0);
    assert!(meta["elapsed_seconds"].parse::<f64>().unwrap() > 0.0);
    // The path tracer chooses nothing; vcm chooses its radius, which the header records
    // beside the 0 that asked for it.
    assert!(!meta.contains_key("automatic"));
    let out = dir.join("vcm.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &out,
        "--spp 1 --width 16 --height 16 --integrator vcm",
    );
    let (_, meta) = read_exr(&out).unwrap();
    let params: serde_json::Value = serde_json::from_str(&meta["parameters"]).unwrap();
    let chosen: serde_json::Value = serde_json::from_str(&meta["automatic"]).unwrap();
    assert_eq!(params["radius"], 0.0);
    assert!(chosen["radius"].as_f64().unwrap() > 0.0, "{chosen}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn renders_png_and_honours_max_depth() {
    let dir = temp_dir("png");
    let out = dir.join("glass.png");
    render_ok(
        "assets/cornell-glass.gltf",
        &out,
        "--spp 2 --width 16 --height 16 --max-depth 3",
    );
    let png = std::fs::read(&out).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn mmlt_on_the_door_writes_its_technique_histogram() {
    let dir = temp_dir("mmlt");
    let (out, stats) = (dir.join("door.exr"), dir.join("door.json"));
    render_ok(
        "assets/door.gltf",
        &out,
        &format!(
            "--integrator mmlt --spp 4 --width 40 --large-step 0.5 --sigma 0.02 \
             --bootstrap 2000 --chains 50 --max-depth 5 --stats {}",
            stats.display()
        ),
    );
    let (image, meta) = read_exr(&out).unwrap();
    assert_eq!(image.count_non_finite(), 0);
    assert!(image.mean_luminance() > 0.0, "light comes through the slit");
    assert!(
        meta["parameters"].contains("\"large_step\":0.5"),
        "{}",
        meta["parameters"]
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let h = &json["integrator_statistics"];
    let lengths = h["path_lengths"].as_array().unwrap();
    assert_eq!(lengths.len(), 6, "path lengths 0 to 5");
    let counted: u64 = lengths
        .iter()
        .flat_map(|l| l["steps_in_technique"].as_array().unwrap())
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(counted, h["total_steps"].as_u64().unwrap());
    // Four passes of 40 x 40 steps (the door's camera has no aspect ratio: square), shared
    // by 50 chains of 32 steps each.
    assert_eq!((image.width, image.height), (40, 40));
    assert_eq!(counted, 4 * 50 * 32);

    // bdpt renders too, and an MMLT flag given to another integrator is refused.
    render_ok(
        "assets/cornell-box.gltf",
        &dir.join("b.exr"),
        "--integrator bdpt --spp 2 --width 24",
    );
    let o = render(
        "assets/cornell-box.gltf",
        &dir.join("c.exr"),
        "--integrator pt --sigma 0.1",
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("sigma"), "{}", stderr(&o));
}

/// `--until-error` stops once the estimated relMSE falls below its value (here within a 30 s
/// cap that a working stop never reaches), and the estimate goes to the header and --stats
/// (which also reports the scene's and the integrator's memory).
#[test]
fn render_until_an_estimated_error_and_record_it() {
    let dir = temp_dir("until");
    let (out, stats) = (dir.join("box.exr"), dir.join("box.json"));
    let o = render_ok(
        "assets/cornell-box.gltf",
        &out,
        &format!(
            "--width 32 --until-error 0.02 --time 30 --stats {}",
            stats.display()
        ),
    );
    assert!(stderr(&o).contains("is below 2e-2"), "{}", stderr(&o));
    let (image, meta) = read_exr(&out).unwrap();
    let estimated: f64 = meta["estimated_relmse"].parse().unwrap();
    assert!(estimated < 0.02, "{estimated}");
    assert!(meta["elapsed_seconds"].parse::<f64>().unwrap() < 30.0);
    // It stopped at the first pass below: the pass before was above (relMSE falls like 1/n,
    // so with n passes the estimate is at least 0.02 (n - 1) / n, give or take its noise).
    let passes: f64 = meta["passes"].parse().unwrap();
    assert!(
        estimated > 0.02 * (passes - 1.0) / passes * 0.7,
        "{estimated} after {passes}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["estimated_relmse"].as_f64(), Some(estimated));
    // The path tracer's memory: a film of three double sums per pixel and a pass buffer of
    // single-precision RGB.
    let pixels = (image.width * image.height) as u64;
    assert_eq!(
        json["integrator_memory_bytes"].as_u64(),
        Some(pixels * (3 * 24 + 12))
    );
    // The scene's memory by part: triangles and BVH but no texels.
    let memory = &json["scene_memory_bytes"];
    assert!(memory["geometry"].as_u64() > Some(0), "{memory}");
    assert!(memory["bvh"].as_u64() > Some(0), "{memory}");
    assert_eq!(memory["textures"].as_u64(), Some(0), "{memory}");
    let o = render("assets/cornell-box.gltf", &out, "--until-error -1");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_environment_image_lights_the_scene_and_is_named_in_the_header() {
    // The Cornell box under a uniform grey .exr environment of 0.5, strength 2, is lit as
    // under `--environment uniform` (radiance 1): the same seed gives images that agree to
    // the Monte Carlo noise of their different light sampling (well within 5 % in the mean).
    use caustica_renderer::image::{Image, write_exr};
    let dir = temp_dir("environment");
    let sky = dir.join("grey.exr");
    let mut grey = Image::new(8, 4);
    grey.pixels.fill(glam::Vec3::splat(0.5));
    write_exr(&sky, &grey, &Default::default()).unwrap();
    let flags = "--spp 16 --width 32 --height 32";
    let by_map = dir.join("map.exr");
    let o = render_ok(
        "assets/cornell-box.gltf",
        &by_map,
        &format!(
            "{flags} --environment {} --environment-strength 2 --environment-rotation 30",
            sky.display()
        ),
    );
    assert!(!stderr(&o).contains("default rule"), "{}", stderr(&o));
    let uniform = dir.join("uniform.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &uniform,
        &format!("{flags} --environment uniform"),
    );
    let none = dir.join("none.exr");
    render_ok("assets/cornell-box.gltf", &none, flags);
    let (a, meta) = read_exr(&by_map).unwrap();
    let (b, _) = read_exr(&uniform).unwrap();
    let (c, none_meta) = read_exr(&none).unwrap();
    let (ma, mb, mc) = (a.mean_luminance(), b.mean_luminance(), c.mean_luminance());
    assert!((ma - mb).abs() < 0.05 * mb, "map {ma}, uniform {mb}");
    assert!(
        mb > 1.2 * mc,
        "the environment adds light: {mb} against {mc}"
    );
    assert!(
        meta["environment"].contains("grey.exr (strength 2, rotation 30 degrees)"),
        "{meta:?}"
    );
    assert!(none_meta["environment"].starts_with("none; chosen by the default rule"));
    // PNG output is exposed automatically, and says by how much.
    let png = dir.join("box.png");
    let o = render_ok("assets/cornell-box.gltf", &png, flags);
    assert!(stderr(&o).contains("exposure: auto"), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn camera_from_renders_the_view_an_image_recorded() {
    // The header records the view; rendering with --camera-from that image and the same seed
    // gives the same pixels, and a view moved in the header moves the image.
    use caustica_renderer::image::write_exr;
    use caustica_renderer::metadata::{camera_from_json, camera_to_json};
    let dir = temp_dir("camera-from");
    let first = dir.join("first.exr");
    let flags = "--spp 2 --width 24 --height 24 --seed 3";
    render_ok("assets/cornell-box.gltf", &first, flags);
    let (image, meta) = read_exr(&first).unwrap();
    let mut camera = camera_from_json(&meta["camera"]).unwrap();
    let again = dir.join("again.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &again,
        &format!("{flags} --camera-from {}", first.display()),
    );
    assert_eq!(read_exr(&again).unwrap().0.pixels, image.pixels);
    // Moved back 3 units: the box looks smaller, more of the view is the dark outside.
    camera.camera_to_world.translation += camera.camera_to_world.matrix3.z_axis * 3.0;
    let moved = dir.join("moved.exr");
    let mut header = meta.clone();
    header.insert("camera".into(), camera_to_json(&camera));
    write_exr(&moved, &image, &header).unwrap();
    let far = dir.join("far.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &far,
        &format!("{flags} --camera-from {}", moved.display()),
    );
    let (far_image, far_meta) = read_exr(&far).unwrap();
    assert!(far_image.mean_luminance() < 0.8 * image.mean_luminance());
    let recorded = camera_from_json(&far_meta["camera"]).unwrap();
    assert!(
        recorded
            .camera_to_world
            .abs_diff_eq(camera.camera_to_world, 1e-4)
    );
    // An image without a recorded view is named.
    let bare = dir.join("bare.exr");
    write_exr(&bare, &image, &Default::default()).unwrap();
    let o = render(
        "assets/cornell-box.gltf",
        &dir.join("x.exr"),
        &format!("{flags} --camera-from {}", bare.display()),
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("bare.exr") && stderr(&o).contains("caustica:camera"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}
