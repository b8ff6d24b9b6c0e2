//! The viewer through egui_kittest, on wgpu (lavapipe or llvmpipe without a GPU): panels
//! drive the session, live settings do not restart it and restarting ones do, snapshots save
//! readable EXRs, and a broken scene shows its error while the old scene keeps rendering.
//! One file per part of the window; this one holds the harness and what the files share.

mod image_view;
mod integrators;
mod panel;
mod scene;

use caustica::viewer::{Command, ViewerApp, ViewerOptions};
use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn harness(scene: Option<PathBuf>) -> Harness<'static, ViewerApp> {
    Harness::builder()
        .with_size(egui::vec2(1100.0, 700.0))
        .wgpu()
        .build_eframe(move |cc| {
            let mut app = ViewerApp::new(
                cc,
                ViewerOptions {
                    scene,
                    ..Default::default()
                },
            );
            // Small renders keep the tests quick.
            app.apply(Command::SetResolution(96, 72));
            app
        })
}

/// Steps the UI until `done` holds (the renderer works on its own threads meanwhile).
fn step_until(h: &mut Harness<'static, ViewerApp>, what: &str, done: impl Fn(&ViewerApp) -> bool) {
    let start = Instant::now();
    while !done(h.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what}"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Moves the slider labelled `label` to `value` (as assistive technology would) and lets the
/// UI apply it.
fn set_slider(h: &mut Harness<'static, ViewerApp>, label: &str, value: f64) {
    h.query_all_by_label(label)
        .next()
        .unwrap_or_else(|| panic!("the {label} slider"))
        .set_value_accesskit(value);
    h.run_steps(2);
}

/// Steps until the render has finished another pass.
fn keeps_rendering(h: &mut Harness<'static, ViewerApp>, what: &str) {
    let passes = h.state().controller.frame().unwrap().passes;
    step_until(h, what, |a| {
        a.controller.frame().is_some_and(|f| f.passes > passes)
    });
}

fn rendering(app: &ViewerApp) -> bool {
    app.controller.frame().is_some_and(|f| f.passes >= 2)
}

/// The screen as the window shows it. The window clears to the panel colour
/// (`App::clear_color`; the panels themselves are transparent) where egui_kittest clears to
/// transparent black, so the test composites its image over that colour as the window does:
/// egui blends premultiplied colours, in gamma space.
fn as_in_window(h: &mut Harness<'static, ViewerApp>) -> image::RgbaImage {
    let visuals = h.ctx.global_style().visuals.clone();
    let background = eframe::App::clear_color(h.state(), &visuals);
    let mut screen = h.render().expect("the harness renders");
    for p in screen.pixels_mut() {
        let coverage = p[3] as f32 / 255.0;
        for c in 0..3 {
            let under = background[c] * 255.0 * (1.0 - coverage);
            p[c] = (p[c] as f32 + under).round().min(255.0) as u8;
        }
        p[3] = 255;
    }
    screen
}

#[derive(Debug)]
struct DroppedPath(PathBuf);

impl egui::DroppedFile for DroppedPath {
    fn path(&self) -> &Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}
