//! The real binary in a real window: under Xvfb, `caustica SCENE --integrator I` renders for a
//! moment, saves a screenshot through eframe with the image it showed and where (see
//! `Automation`), and quits. For the path tracer, SPPM and MMLT, with the plots shown, at two
//! window sizes, the screenshot must show that image over most of the window. Needs Xvfb and
//! a software Vulkan or GL driver (.ci/run installs them).

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

struct KillOnDrop(Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// An X server of its own for this test process; dropped, it stops.
fn start_xvfb() -> (KillOnDrop, String) {
    let display_number = 90 + std::process::id() % 9;
    let display = format!(":{display_number}");
    let socket = format!("/tmp/.X11-unix/X{display_number}");
    let _ = std::fs::remove_file(&socket);
    let xvfb = Command::new("Xvfb")
        .args([display.as_str(), "-screen", "0", "1600x1000x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start Xvfb ({e}): install xvfb and a software Vulkan/GL driver, as .ci/run does"));
    let xvfb = KillOnDrop(xvfb);
    let start = Instant::now();
    while !Path::new(&socket).exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "Xvfb did not start"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    (xvfb, display)
}

/// Luminance (0-255) of an 8-bit RGB pixel.
fn luminance(p: &image::Rgb<u8>) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// Pearson correlation of two equally long series.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt().max(1e-12)
}

/// Runs the viewer on `scene` with `integrator` in a window of `window` points with fresh
/// settings (plots shown), and checks its screenshot against the image it says it showed.
fn check_window(display: &str, dir: &Path, scene: &str, integrator: &str, window: &str) {
    let case = format!("{integrator}-{window}");
    let home = dir.join(format!("home-{case}"));
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    let shot = dir.join(format!("{case}.png"));
    let mut viewer = KillOnDrop(
        Command::new(env!("CARGO_BIN_EXE_caustica"))
            .args([
                scene,
                "--integrator",
                integrator,
                "--width",
                "320",
                "--height",
                "240",
            ])
            .args(["--window-size", window, "--screenshot-after", "1"])
            .arg("--screenshot")
            .arg(&shot)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("DISPLAY", display)
            .env("XDG_RUNTIME_DIR", &runtime)
            .env("HOME", &home)
            .env("XDG_DATA_HOME", home.join("data"))
            .env("XDG_CONFIG_HOME", home.join("config"))
            .env_remove("WAYLAND_DISPLAY")
            .spawn()
            .unwrap(),
    );
    let start = Instant::now();
    let status = loop {
        if let Some(status) = viewer.0.try_wait().unwrap() {
            break status;
        }
        assert!(
            start.elapsed() < Duration::from_secs(180),
            "{case}: the viewer did not quit after its screenshot"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "{case}: the viewer exited with {status}");

    let screen = image::open(&shot)
        .expect("the screenshot was saved")
        .to_rgb8();
    let frame = image::open(shot.with_extension("frame.png"))
        .expect("the frame shown was saved")
        .to_rgb8();
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shot.with_extension("json")).unwrap())
            .unwrap();
    eprintln!("{case}: {record}");
    // Something of the scene comes first: the preview, before the integrator's first pass
    // (however long the machine takes for either, the order holds).
    let first = record["first_frame_seconds"]
        .as_f64()
        .expect("a frame was shown");
    if let Some(pass) = record["first_pass_seconds"].as_f64() {
        assert!(
            first <= pass,
            "{case}: the first pass came before the first frame"
        );
    }
    let rect: Vec<f64> = record["image_rect"]
        .as_array()
        .expect("an image was shown")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let (sw, sh) = (screen.width() as f64, screen.height() as f64);
    assert!(
        rect[0] >= -1.0 && rect[1] >= -1.0 && rect[2] <= sw + 1.0 && rect[3] <= sh + 1.0,
        "{case}: the image {rect:?} lies outside the {sw} x {sh} window"
    );
    // Fitted to the space the panels leave, a 4:3 image covers a third of the window or more.
    let area = (rect[2] - rect[0]) * (rect[3] - rect[1]) / (sw * sh);
    assert!(
        area > 0.3,
        "{case}: the image covers only {area:.2} of the window"
    );
    // The screenshot at each frame pixel's centre shows that pixel: the two agree but for
    // the passes added between the frame's capture and the screenshot.
    let (fw, fh) = frame.dimensions();
    let (mut shown, mut expected) = (Vec::new(), Vec::new());
    for y in 0..fh {
        for x in 0..fw {
            let sx = rect[0] + (x as f64 + 0.5) / fw as f64 * (rect[2] - rect[0]);
            let sy = rect[1] + (y as f64 + 0.5) / fh as f64 * (rect[3] - rect[1]);
            shown.push(luminance(screen.get_pixel(sx as u32, sy as u32)));
            expected.push(luminance(frame.get_pixel(x, y)));
        }
    }
    let r = correlation(&shown, &expected);
    let mean = shown.iter().sum::<f64>() / shown.len() as f64;
    eprintln!("{case}: image covers {area:.2} of the window, correlation {r:.3}, mean {mean:.1}");
    assert!(
        mean > 2.0,
        "{case}: the image area is black (mean {mean:.1})"
    );
    assert!(
        r > 0.8,
        "{case}: the screen does not show the frame (correlation {r:.3})"
    );
}

#[test]
fn the_window_shows_the_render_over_most_of_it() {
    let dir = std::env::temp_dir().join(format!("caustica-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (_xvfb, display) = start_xvfb();
    for window in ["1280x800", "900x600"] {
        for (scene, integrator) in [
            ("assets/cornell-box.gltf", "pt"),
            ("assets/cornell-glass.gltf", "sppm"),
            ("assets/door.gltf", "mmlt"),
        ] {
            check_window(&display, &dir, scene, integrator, window);
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}
