//! Bad input and faults: exit codes and one-line messages, help, a viewer without a display,
//! a panicking pass, a full disk, a save killed at any moment.

use super::{path_str, render, render_ok, run, stderr, temp_dir};
use caustica_renderer::image::read_exr;
use std::process::Command;

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
