//! End-to-end tests of the `caustica` binary: rendering a bundled scene to EXR and PNG, the
//! metadata written, and the exit codes and messages of bad input.

use caustica_renderer::image::read_exr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn caustica(args: &[&str]) -> Output {
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

#[test]
fn renders_the_cornell_box_to_exr_with_metadata() {
    let dir = temp_dir("exr");
    let out = dir.join("box.exr");
    let o = caustica(&[
        "render",
        "assets/cornell-box.gltf",
        "-o",
        path_str(&out),
        "--spp",
        "4",
        "--width",
        "48",
        "--height",
        "32",
        "--seed",
        "9",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
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
    let o = caustica(&[
        "render",
        "assets/cornell-glass.gltf",
        "-o",
        path_str(&out),
        "--spp",
        "2",
        "--width",
        "16",
        "--height",
        "16",
        "--max-depth",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let png = std::fs::read(&out).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_arguments_exit_2_naming_the_argument() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["render", "assets/cornell-box.gltf", "-o", "x.txt"],
            "--output",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--spp",
                "0",
            ],
            "--spp",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--spp",
                "4",
                "--time",
                "1",
            ],
            "--time",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--time",
                "-1",
            ],
            "--time",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--integrator",
                "magic",
            ],
            "--integrator",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--width",
                "0",
            ],
            "--width",
        ),
        (
            &[
                "render",
                "assets/cornell-box.gltf",
                "-o",
                "x.exr",
                "--max-depth",
                "5000",
            ],
            "max_depth",
        ),
        (&["render", "assets/cornell-box.gltf"], "--output"),
        (&["render", "--frobnicate"], "--frobnicate"),
    ];
    for (args, fragment) in cases {
        let o = caustica(args);
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
    let o = caustica(&["render", "assets/no-such-scene.gltf", "-o", path_str(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("assets/no-such-scene.gltf"),
        "{}",
        stderr(&o)
    );

    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, "{ not json").unwrap();
    let o = caustica(&["render", path_str(&broken), "-o", path_str(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("broken.gltf"), "{}", stderr(&o));

    let o = caustica(&[
        "render",
        "assets/cornell-box.gltf",
        "-o",
        "/nonexistent-dir/x.exr",
        "--spp",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("/nonexistent-dir"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing is written on failure");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn help_documents_every_option() {
    let o = caustica(&["render", "--help"]);
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    for option in [
        "--output",
        "--integrator",
        "--spp",
        "--time",
        "--width",
        "--height",
        "--seed",
        "--threads",
        "--max-depth",
        "--alpha",
        "--radius",
        "--photons",
        "--large-step",
        "--sigma",
        "--bootstrap",
        "--chains",
        "--stats",
    ] {
        assert!(help.contains(option), "help lacks {option}");
    }
    let o = caustica(&["--help"]);
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
    let o = caustica(&[
        "render",
        "assets/door.gltf",
        "-o",
        path_str(&out),
        "--integrator",
        "mmlt",
        "--spp",
        "4",
        "--width",
        "40",
        "--large-step",
        "0.5",
        "--sigma",
        "0.02",
        "--bootstrap",
        "2000",
        "--chains",
        "50",
        "--max-depth",
        "5",
        "--stats",
        path_str(&stats),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
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
    let o = caustica(&[
        "render",
        "assets/cornell-box.gltf",
        "-o",
        path_str(&dir.join("b.exr")),
        "--integrator",
        "bdpt",
        "--spp",
        "2",
        "--width",
        "24",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = caustica(&[
        "render",
        "assets/cornell-box.gltf",
        "-o",
        path_str(&dir.join("c.exr")),
        "--integrator",
        "pt",
        "--sigma",
        "0.1",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("sigma"), "{}", stderr(&o));
}
