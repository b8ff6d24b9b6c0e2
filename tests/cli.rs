//! End-to-end tests of the `caustica` binary: rendering a bundled scene to EXR and PNG, the
//! metadata written, and the exit codes and messages of bad input.

use caustica_renderer::image::read_exr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn caustica<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustica"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `render`, which must succeed.
fn render_ok(scene: &str, out: &Path, flags: &str) -> Output {
    let o = render(scene, out, flags);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

/// The binary run with a command line given as one string, split at whitespace (no argument
/// here contains any: the temporary directories are named without).
fn run(line: &str) -> Output {
    caustica(&line.split_whitespace().collect::<Vec<_>>())
}

/// `caustica render SCENE -o OUT FLAGS...`, the flags as one string.
fn render(scene: &str, out: &Path, flags: &str) -> Output {
    run(&format!("render {scene} -o {} {flags}", out.display()))
}

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
fn bad_arguments_exit_2_naming_the_argument() {
    let render = "render assets/cornell-box.gltf -o x.exr";
    let cases = [
        (
            "render assets/cornell-box.gltf -o x.txt".to_string(),
            "--output",
        ),
        (format!("{render} --spp 0"), "--spp"),
        (format!("{render} --spp 4 --time 1"), "--time"),
        (format!("{render} --time -1"), "--time"),
        (format!("{render} --integrator magic"), "--integrator"),
        (format!("{render} --width 0"), "--width"),
        (format!("{render} --max-depth 5000"), "max_depth"),
        ("render assets/cornell-box.gltf".to_string(), "--output"),
        ("render --frobnicate".to_string(), "--frobnicate"),
        (format!("{render} --exposure bright"), "--exposure"),
        (
            format!("{render} --environment-strength -1"),
            "--environment-strength",
        ),
        (
            format!("{render} --environment-rotation nan"),
            "--environment-rotation",
        ),
    ];
    for (args, fragment) in &cases {
        let o = run(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(fragment),
            "{args:?} should name {fragment}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn runtime_errors_exit_1_naming_the_file() {
    let dir = temp_dir("runtime");
    let out = dir.join("x.exr");
    let o = render("assets/no-such-scene.gltf", &out, "");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("assets/no-such-scene.gltf"),
        "{}",
        stderr(&o)
    );

    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, "{ not json").unwrap();
    let o = render(path_str(&broken), &out, "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("broken.gltf"), "{}", stderr(&o));

    let o = render(
        "assets/cornell-box.gltf",
        &out,
        "--environment no-such-sky.hdr",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no-such-sky.hdr"), "{}", stderr(&o));

    let o = run("render assets/cornell-box.gltf -o /nonexistent-dir/x.exr --spp 1");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("/nonexistent-dir"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing is written on failure");

    // A limit names itself, the size asked for and the flag that raises it.
    let o = render("assets/door.gltf", &out, "--max-triangles 100 --spp 1");
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("assets/door.gltf"), "{e}");
    assert!(
        e.contains("over the limit of 100 (raise it with --max-triangles)"),
        "{e}"
    );
    assert!(!out.exists(), "nothing is written on failure");

    // An image whose buffers would not fit is refused before anything is allocated (an
    // argument too large for this machine: exit 2).
    let o = render(
        "assets/cornell-box.gltf",
        &out,
        "--integrator sppm --width 4096 --height 4096 --max-memory 1G",
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "sppm at 4096 x 4096 needs about 11.0 GiB for its buffers, more \
             than the 1.0 GiB allowed"
        ),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists(), "nothing is written on failure");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A worker thread that panics in pass 3 of 10: exit 1 with the reason, and the image of the
/// 3 passes before it saved where -o said, its header saying 3 passes.
#[test]
fn a_panicking_pass_exits_1_and_saves_the_passes_before() {
    let dir = temp_dir("panic");
    let out = dir.join("partial.exr");
    let o = render(
        "assets/cornell-box.gltf",
        &out,
        "--spp 10 --width 32 --height 24 --panic-in-pass 3",
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(&format!(
            "error: the renderer failed after 3 passes: fault injected in pass 3; the image of \
             those passes was saved to {}",
            out.display()
        )),
        "{e}"
    );
    let (image, meta) = read_exr(&out).unwrap();
    assert_eq!(meta["passes"], "3");
    assert!(image.mean_luminance() > 0.0);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn help_documents_every_option() {
    let o = run("render --help");
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    let options = "--output --integrator --spp --time --width --height --seed --threads \
                   --max-depth --alpha --radius --photons --large-step --sigma --bootstrap \
                   --chains --stats";
    for option in options.split_whitespace() {
        assert!(help.contains(option), "help lacks {option}");
    }
    let o = run("--help");
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    for item in ["render", "[SCENE]", "--reference", "--screenshot"] {
        assert!(help.contains(item), "top-level help lacks {item}");
    }
}

#[test]
fn the_viewer_without_a_display_fails_clearly() {
    let o = Command::new(env!("CARGO_BIN_EXE_caustica"))
        .arg("assets/cornell-box.gltf")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("cannot open the viewer window"),
        "{}",
        stderr(&o)
    );
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

/// `converge` with a reference and a swept parameter: the CSV has a row per checkpoint of every
/// run with true and estimated error, the PNG is an image, and stdout names the winners and
/// the slopes.
#[test]
fn converge_measures_every_run_against_the_reference() {
    let dir = temp_dir("converge");
    let reference = dir.join("ref.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &reference,
        "--width 32 --spp 1024 --seed 77",
    );
    let out = dir.join("measured");
    let converge = format!(
        "converge assets/cornell-box.gltf --reference {} --out {}",
        reference.display(),
        out.display()
    );
    let o = run(&format!(
        "{converge} --integrator pt,sppm --param photons=2000,8000 --time 1.5"
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    for run in ["pt", "sppm photons=2000", "sppm photons=8000"] {
        assert!(stdout.contains(run), "{stdout}");
    }
    assert!(stdout.contains("lowest relMSE"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header.join(" "),
        "run integrator parameters seconds passes rel_mse rmse estimated_rel_mse \
         estimated_bias_rel_mse seed"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    for run in ["pt", "sppm photons=2000", "sppm photons=8000"] {
        let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == run).collect();
        assert!(mine.len() >= 3, "{run}: {csv}");
        let errors: Vec<f64> = mine.iter().map(|r| r[5].parse().unwrap()).collect();
        assert!(
            errors.last().unwrap() < errors.first().unwrap(),
            "{run}: the error falls: {errors:?}"
        );
        // Every frame of two passes or more estimates its error (one pass cannot).
        assert!(
            mine.iter()
                .filter(|r| r[4].parse::<u64>().unwrap() >= 2)
                .all(|r| r[7].parse::<f64>().unwrap() > 0.0),
            "{csv}"
        );
    }
    let png = image::open(out.join("convergence.png")).unwrap();
    assert!(png.width() > 400 && png.height() > 300);
    // Several seeds: every seed's rows, the median and the seeds' range in the table.
    let o = run(&format!(
        "{converge} --integrator pt --time 0.5 --seeds 2 --seed 7"
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("seeds' range"));
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    for seed in ["7", "8"] {
        assert!(
            csv.lines()
                .skip(1)
                .any(|l| l.ends_with(&format!(",{seed}"))),
            "{csv}"
        );
    }
    // A reference of another size is refused before anything renders.
    let o = run(&format!("{converge} --integrator pt --time 1 --width 40"));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("ref.exr"), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

/// `info` describes the transport and recommends what the bundled scenes need; `reference`
/// renders with it and writes its estimated error.
#[test]
fn info_recommends_and_reference_renders_with_the_recommendation() {
    for (scene, expected, reference) in [
        ("assets/cornell-box.gltf", "pt", "pt"),
        ("assets/caustic-pool.gltf", "sppm", "sppm"),
        ("assets/door.gltf", "mmlt", "bdpt"),
    ] {
        let o = run(&format!("info {scene} --width 64"));
        assert!(o.status.success(), "{}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            stdout.contains(&format!("recommended: {expected}\n")),
            "{scene}: {stdout}"
        );
        assert!(
            stdout.contains(&format!("--integrator {expected}")),
            "{stdout}"
        );
        assert!(
            stdout.contains(&format!("renders with {reference}\n")),
            "{stdout}"
        );
    }
    let dir = temp_dir("reference");
    let out = dir.join("pool.exr");
    let o = run(&format!(
        "reference assets/caustic-pool.gltf -o {} --time 1 --width 32",
        out.display()
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, meta) = read_exr(&out).unwrap();
    assert_eq!(meta["integrator"], "sppm");
    assert!(meta["estimated_relmse"].parse::<f64>().unwrap() > 0.0);
    let o = run("reference assets/door.gltf -o x.png --time 1");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

/// Merging k independent runs gives what one run k times as long gives: against a long
/// reference their errors agree within the statistics (both are means of the same number of
/// independent passes; at 32 x 32 the relative spread of relMSE is about 10 %, so we allow
/// 30 %), while averaging the runs unweighted (passes 2, 4, 6, 12) or summing them would not.
/// The header adds up the passes and carries the merged error estimate.
#[test]
fn merging_runs_equals_one_longer_run() {
    let dir = temp_dir("merge");
    let render_box = |name: &str, spp: u32, seed: u32| {
        let path = dir.join(name);
        render_ok(
            "assets/cornell-box.gltf",
            &path,
            &format!("--width 32 --spp {spp} --seed {seed}"),
        );
        path
    };
    let reference = render_box("ref.exr", 4096, 1000);
    let long = render_box("long.exr", 24, 50);
    let parts: Vec<PathBuf> = [(2, 1), (4, 2), (6, 3), (12, 4)]
        .iter()
        .map(|(spp, seed)| render_box(&format!("part{seed}.exr"), *spp, *seed))
        .collect();
    let merged_path = dir.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| path_str(p)));
    args.extend(["-o", path_str(&merged_path)]);
    let o = caustica(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (reference, _) = read_exr(&reference).unwrap();
    let (long, long_meta) = read_exr(&long).unwrap();
    let (merged, meta) = read_exr(&merged_path).unwrap();
    assert_eq!(meta["passes"], "24");
    assert_eq!(meta["seed"], "1,2,3,4");
    let error = |img| {
        caustica_renderer::image::compare(img, &reference)
            .unwrap()
            .rel_mse
    };
    let (e_long, e_merged) = (error(&long), error(&merged));
    eprintln!("relMSE: one run of 24 passes {e_long:.4e}, four merged {e_merged:.4e}");
    assert!(
        (e_merged / e_long - 1.0).abs() < 0.3,
        "{e_merged} vs {e_long}"
    );
    let estimated: f64 = meta["estimated_relmse"].parse().unwrap();
    let long_estimated: f64 = long_meta["estimated_relmse"].parse().unwrap();
    assert!(
        (estimated / long_estimated - 1.0).abs() < 0.3,
        "{estimated} vs {long_estimated}"
    );
    // Two runs with one seed are the same samples: refused.
    let o = caustica(&[
        "merge",
        path_str(&parts[0]),
        path_str(&parts[0]),
        "-o",
        path_str(&merged_path),
    ]);
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

/// A disk that fills up while the image is written (the file size limit of `ulimit -f`, whose
/// signal is ignored, so writes fail as on a full disk): exit 1 naming the file and the cause,
/// the old image untouched, no temporary file left.
#[test]
fn a_full_disk_fails_the_save_and_keeps_the_old_image() {
    let dir = temp_dir("full-disk");
    let out = dir.join("box.exr");
    render_ok(
        "assets/cornell-box.gltf",
        &out,
        "--spp 1 --width 16 --height 16",
    );
    let old = std::fs::read(&out).unwrap();
    let line = format!(
        "ulimit -f 4; trap '' XFSZ; exec {} render assets/cornell-box.gltf -o {} --spp 1 \
         --width 256 --height 256",
        env!("CARGO_BIN_EXE_caustica"),
        out.display()
    );
    let o = Command::new("bash")
        .args(["-c", &line])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("cannot write the image") && e.contains(&out.display().to_string()),
        "{e}"
    );
    assert!(e.contains("File too large"), "{e}");
    assert_eq!(std::fs::read(&out).unwrap(), old);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Renders killed at moments spread over the run, saving included: each leaves the image that
/// was there before or the whole new one, never part of one.
#[test]
fn a_save_killed_at_any_moment_leaves_the_old_image_or_the_new() {
    let dir = temp_dir("killed");
    let (out, new) = (dir.join("image.exr"), dir.join("new.exr"));
    let flags = "--spp 2 --width 640 --height 640 --seed 3 --threads 1";
    render_ok(
        "assets/cornell-box.gltf",
        &out,
        "--spp 1 --width 64 --height 64",
    );
    let start = std::time::Instant::now();
    render_ok("assets/cornell-box.gltf", &new, flags);
    let whole = start.elapsed();
    let (old_pixels, new_pixels) = (
        read_exr(&out).unwrap().0.pixels,
        read_exr(&new).unwrap().0.pixels,
    );
    let mut replaced = 0;
    for i in 1..=16 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_caustica"))
            .args(
                format!(
                    "render assets/cornell-box.gltf -o {} {flags}",
                    out.display()
                )
                .split(' '),
            )
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        // From a little before the render's end (the save comes last) to a little after.
        std::thread::sleep(whole.mul_f64(0.7 + 0.4 * i as f64 / 16.0));
        let _ = child.kill();
        child.wait().unwrap();
        let pixels = read_exr(&out)
            .unwrap_or_else(|e| panic!("kill {i}: {e}"))
            .0
            .pixels;
        if pixels == new_pixels {
            replaced += 1;
        } else {
            assert_eq!(
                pixels, old_pixels,
                "kill {i}: neither the old image nor the new"
            );
        }
        // The next kill starts from the old image again.
        render_ok(
            "assets/cornell-box.gltf",
            &out,
            "--spp 1 --width 64 --height 64",
        );
    }
    eprintln!("{replaced} of 16 killed renders had saved the new image");
    std::fs::remove_dir_all(dir).unwrap();
}
