//! The real binary in a real window: under Xvfb, `caustica assets/cornell-glass.gltf` renders
//! for a few seconds, saves a screenshot through eframe, and quits. The image area of the
//! screenshot must show a render: neither blank nor uniform. Needs Xvfb and a software
//! Vulkan or GL driver (.ci/run installs them).

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

#[test]
fn the_window_shows_the_render_of_cornell_glass() {
    let dir = std::env::temp_dir().join(format!("caustica-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    let display_number = 90 + std::process::id() % 9;
    let display = format!(":{display_number}");
    let socket = format!("/tmp/.X11-unix/X{display_number}");
    let _ = std::fs::remove_file(&socket);
    let xvfb = Command::new("Xvfb")
        .args([display.as_str(), "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start Xvfb ({e}): install xvfb and a software Vulkan/GL driver, as .ci/run does"));
    let _xvfb = KillOnDrop(xvfb);
    let start = Instant::now();
    while !Path::new(&socket).exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "Xvfb did not start"
        );
        std::thread::sleep(Duration::from_millis(50));
    }

    let shot = dir.join("window.png");
    let mut viewer = KillOnDrop(
        Command::new(env!("CARGO_BIN_EXE_caustica"))
            .args([
                "assets/cornell-glass.gltf",
                "--screenshot",
                shot.to_str().unwrap(),
                "--screenshot-after",
                "3",
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("DISPLAY", &display)
            .env("XDG_RUNTIME_DIR", &runtime)
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
            "the viewer did not quit after its screenshot"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "the viewer exited with {status}");

    let image = image::open(&shot)
        .expect("the screenshot was saved")
        .to_rgb8();
    let (w, h) = image.dimensions();
    assert!(w >= 800 && h >= 500, "window of {w}x{h}");
    // The image area: left of the settings panel, above the status bar.
    let lum: Vec<f64> = (20..h - 60)
        .flat_map(|y| (20..w - 360).map(move |x| (x, y)))
        .map(|(x, y)| {
            let p = image.get_pixel(x, y);
            0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
        })
        .collect();
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    let sd = (lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64).sqrt();
    assert!(mean > 10.0, "the image area is blank (mean {mean:.1})");
    assert!(
        sd > 10.0,
        "the image area is uniform (standard deviation {sd:.1})"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
