//! The viewer through egui_kittest, on wgpu (lavapipe or llvmpipe without a GPU): panels
//! drive the session, live settings do not restart it and restarting ones do, snapshots save
//! readable EXRs, and a broken scene shows its error while the old scene keeps rendering.

use caustica::viewer::{Command, Message, ViewerApp, ViewerOptions};
use caustica_renderer::image::read_exr;
use caustica_renderer::session::RunState;
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

#[test]
fn the_panel_drives_the_session_live_or_by_restart() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let sessions = h.state().controller.sessions_started;

    // Exposure is a display setting: it changes at once and the render goes on.
    set_slider(&mut h, "exposure (EV)", 2.0);
    assert_eq!(h.state().settings.exposure, 2.0);
    assert_eq!(
        h.state().controller.sessions_started,
        sessions,
        "a live setting restarted the render"
    );

    // Max depth invalidates the estimate: the session restarts with the new value.
    set_slider(&mut h, "max_depth", 3.0);
    assert_eq!(
        h.state().controller.sessions_started,
        sessions + 1,
        "max_depth must restart the render"
    );
    let params = h.state().controller.session().unwrap().params().clone();
    assert_eq!(params["max_depth"], 3.0);

    // Space pauses, and pausing holds the pass count.
    step_until(&mut h, "frames after the restart", rendering);
    h.key_press(egui::Key::Space);
    step_until(&mut h, "the pause", |a| {
        a.controller
            .frame()
            .is_some_and(|f| f.state == RunState::Paused)
    });
}

#[test]
fn ctrl_s_saves_a_readable_exr_snapshot_with_metadata() {
    let dir = std::env::temp_dir().join(format!("caustica-viewer-save-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut h = harness(Some(asset("cornell-box.gltf")));
    h.state_mut().snapshot_dir = dir.clone();
    step_until(&mut h, "the first frames", rendering);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    step_until(&mut h, "the save", |a| {
        a.messages.iter().any(|m| m.text.starts_with("saved"))
    });
    let saved: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(saved.len(), 1, "{saved:?}");
    let name = saved[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        name.starts_with("cornell-box-pt-") && name.ends_with(".exr"),
        "{name}"
    );
    let (image, meta) = read_exr(&saved[0]).unwrap();
    assert_eq!((image.width, image.height), (96, 72));
    assert!(image.mean_luminance() > 0.0 && image.count_non_finite() == 0);
    assert_eq!(meta["integrator"], "pt");
    assert!(meta["passes"].parse::<u64>().unwrap() >= 2);
    // The same header as the command line's (one builder): threads resolved, rays counted.
    assert!(meta["threads"].parse::<usize>().unwrap() >= 1, "{meta:?}");
    assert!(meta["rays"].parse::<u64>().unwrap() > 0 && meta.contains_key("dropped_samples"));

    // Save PNG writes what the window shows.
    h.state_mut().apply(Command::SavePng);
    step_until(&mut h, "the PNG", |a| {
        a.messages
            .iter()
            .filter(|m| m.text.starts_with("saved"))
            .count()
            == 2
    });
    let png = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "png"));
    let png = image::open(png.expect("a PNG was saved")).unwrap();
    assert_eq!((png.width(), png.height()), (96, 72));

    // A save that fails says so, and the render goes on.
    h.state_mut().snapshot_dir = dir.join("missing/deeper");
    h.state_mut().apply(Command::SaveExr);
    step_until(&mut h, "the failed save", |a| {
        a.messages.last().is_some_and(|m| m.is_error)
    });
    assert!(
        h.state()
            .messages
            .last()
            .unwrap()
            .text
            .contains("missing/deeper")
    );
    keeps_rendering(&mut h, "more passes");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_broken_scene_shows_its_error_and_the_old_scene_stays() {
    let dir = std::env::temp_dir().join(format!("caustica-viewer-broken-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [").unwrap();
    let mut h = harness(Some(asset("cornell-glass.gltf")));
    step_until(&mut h, "the first frames", rendering);
    h.state_mut().apply(Command::OpenScene(broken.clone()));
    step_until(&mut h, "the load to fail", |a| {
        a.controller.loading().is_none()
    });
    let last: &Message = h.state().messages.last().unwrap();
    assert!(
        last.is_error && last.text.contains("broken.gltf"),
        "{last:?}"
    );
    let app = h.state();
    assert!(
        app.controller
            .scene
            .as_ref()
            .unwrap()
            .path
            .ends_with("cornell-glass.gltf")
    );
    assert!(
        !app.settings.recent_scenes.contains(&broken),
        "a failed scene is not a recent one"
    );
    keeps_rendering(&mut h, "the old scene to keep rendering");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn empty_viewer_snapshot() {
    // No scene: what a user sees first. Deterministic, so it can be compared to a snapshot.
    let mut h = harness(None);
    h.state_mut().show_process_stats = false;
    h.run_steps(3);
    egui_kittest::image_snapshot(&as_in_window(&mut h), "viewer_empty");
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

#[test]
fn the_convergence_plot_measures_the_render_against_a_reference() {
    use caustica_renderer::image::write_exr;
    use caustica_renderer::scene::gltf::load;
    use caustica_renderer::session::{Session, SessionConfig};
    use std::sync::Arc;
    // A reference of the same view: 256 passes of the path tracer at the viewer's size.
    let dir = std::env::temp_dir().join(format!("caustica-viewer-ref-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let reference = dir.join("reference.exr");
    let scene = Arc::new(load(&asset("cornell-box.gltf")).unwrap());
    let frame = Session::start(SessionConfig {
        seed: 1234,
        max_passes: Some(256),
        ..SessionConfig::new(scene, "pt", 96, 72)
    })
    .unwrap()
    .wait();
    write_exr(&reference, &frame.image, &Default::default()).unwrap();

    let mut h = Harness::builder()
        .with_size(egui::vec2(1100.0, 700.0))
        .wgpu()
        .build_eframe(|cc| {
            ViewerApp::new(
                cc,
                ViewerOptions {
                    scene: Some(asset("cornell-box.gltf")),
                    reference: Some(reference.clone()),
                    width: Some(96),
                    height: Some(72),
                    ..Default::default()
                },
            )
        });
    step_until(&mut h, "error points", |a| a.convergence.points.len() >= 5);
    let points = h.state().convergence.points.clone();
    assert!(
        points
            .iter()
            .all(|p| p.metrics.rel_mse.is_finite() && p.seconds > 0.0)
    );
    assert!(
        points.windows(2).all(|w| w[1].seconds >= w[0].seconds),
        "points in time order"
    );
    // Independent estimates of the same image: the mean luminance ratio is near one.
    let last = points.last().unwrap().metrics;
    assert!((last.mean_luminance_ratio - 1.0).abs() < 0.1, "{last:?}");

    // As in tev: C flips the view to the reference and back.
    h.key_press(egui::Key::C);
    h.run_steps(2);
    let shown = |h: &Harness<'static, ViewerApp>| h.state().viewport.shown.clone().unwrap().1;
    let reference_image = h.state().convergence.reference_image.clone().unwrap();
    assert!(h.state().show_reference);
    assert!(std::sync::Arc::ptr_eq(&shown(&h), &reference_image));
    h.get_by_label("reference (C: back to the render)");
    h.key_press(egui::Key::C);
    h.run_steps(2);
    assert!(!std::sync::Arc::ptr_eq(&shown(&h), &reference_image));
    // With a reference the error map (E) shows each pixel's true relMSE term, whose mean is
    // the plotted relMSE.
    h.state_mut().apply(Command::ToggleErrorMap);
    step_until(&mut h, "the true error map", |a| {
        a.error_map.shows_true_error()
    });
    let truth = h.state().convergence.true_error.clone().unwrap();
    let mean = truth.terms.iter().map(|&t| t as f64).sum::<f64>() / truth.terms.len() as f64;
    let plotted = h.state().convergence.points.last().unwrap().metrics.rel_mse;
    assert!(
        (mean / plotted - 1.0).abs() < 1e-4,
        "{mean} against {plotted}"
    );
    // A reference of another size is refused with a message, not a crash.
    h.state_mut().apply(Command::SetResolution(50, 50));
    step_until(&mut h, "the size mismatch", |a| {
        a.convergence
            .problem
            .as_deref()
            .is_some_and(|p| p.contains("reference"))
    });
    std::fs::remove_dir_all(dir).unwrap();
}

/// Without any reference the render estimates its own error: a number in the statistics,
/// a falling line on the convergence plot, and (E) a heat map over the image whose colours are
/// the frame's per-pixel estimates.
#[test]
fn the_estimated_error_is_shown_as_a_number_a_line_and_a_heat_map() {
    use caustica::viewer::error_map;
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "estimated points", |a| {
        a.convergence.estimated.len() >= 4
    });
    // The statistics' row and the convergence plot's legend.
    assert_eq!(h.query_all_by_label("estimated relMSE").count(), 2);
    let estimated = h.state().convergence.estimated.clone();
    assert!(
        estimated
            .iter()
            .all(|p| p[0] > 0.0 && p[1].is_finite() && p[1] > 0.0),
        "{estimated:?}"
    );
    assert!(
        estimated.windows(2).all(|w| w[1][0] > w[0][0]),
        "points in time order"
    );
    step_until(&mut h, "the estimate to fall", |a| {
        let e = &a.convergence.estimated;
        e.len() >= 2 && e.last().unwrap()[1] < 0.5 * e[0][1]
    });

    // Paused, the frame and its estimate stay put while the map is compared with them.
    h.state_mut().apply(Command::TogglePause);
    step_until(&mut h, "the pause", |a| {
        a.controller
            .frame()
            .is_some_and(|f| f.state == RunState::Paused)
    });
    h.key_press(egui::Key::E);
    h.run_steps(1);
    assert!(h.state().settings.show_error_map);
    step_until(&mut h, "the heat map", |a| {
        a.controller
            .frame()
            .is_some_and(|f| a.error_map.shows(&f.error))
    });
    // The image is fitted in the central panel (the screen's left 800 points, above the plots);
    // find a pixel there through the inspector and compare the screen with the map's colour.
    let central = egui::pos2((1100.0 - 300.0) / 2.0, (700.0 - 200.0 - 24.0) / 2.0);
    h.hover_at(central);
    h.run_steps(2);
    let p = h.state().hovered.expect("the cursor is over the image");
    let frame = h.state().controller.frame().unwrap();
    let estimate = frame.error.as_ref().as_ref().unwrap();
    let expected = error_map::colour(estimate.per_pixel[p.y as usize * 96 + p.x as usize]);
    // The inspector's tooltip would cover the pixel: move away before looking.
    h.hover_at(egui::pos2(1090.0, 690.0));
    h.run_steps(2);
    let screen = h.render().expect("a rendered screen");
    let ppp = h.ctx.pixels_per_point();
    let shown = screen.get_pixel((central.x * ppp) as u32, (central.y * ppp) as u32);
    for c in 0..3 {
        assert!(
            (shown[c] as i32 - expected[c] as i32).abs() <= 3,
            "screen {shown:?}, map colour {expected:?}"
        );
    }
    h.key_press(egui::Key::E);
    h.run_steps(1);
    assert!(!h.state().settings.show_error_map);
}

#[test]
fn hovering_the_image_inspects_its_pixel() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // Paused, the frame stays put while we compare.
    h.state_mut().apply(Command::TogglePause);
    step_until(&mut h, "the pause", |a| {
        a.controller
            .frame()
            .is_some_and(|f| f.state == RunState::Paused)
    });
    // The image is fitted into the central panel; its centre is the image's centre.
    let central = egui::pos2((1100.0 - 300.0) / 2.0, (700.0 - 200.0 - 24.0) / 2.0);
    let mut found = None;
    for dy in [-40.0, 0.0, 40.0] {
        h.hover_at(central + egui::vec2(0.0, dy));
        h.run_steps(2);
        if let Some(p) = h.state().hovered {
            found = Some(p);
            break;
        }
    }
    let p = found.expect("hovering the image shows a pixel");
    assert!(p.x < 96 && p.y < 72);
    let frame = h.state().controller.frame().unwrap();
    assert_eq!(
        frame.image.pixel(p.x as usize, p.y as usize),
        p.rgb,
        "the inspector shows the pixel under the cursor"
    );
}

#[test]
fn wheel_zooms_about_the_cursor_drag_pans_and_f_fits() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let cursor = egui::pos2(420.0, 230.0);
    h.hover_at(cursor);
    h.run_steps(2);
    let before = h.state().hovered.expect("the cursor is over the image");
    assert!(h.state().viewport.is_fit());
    for _ in 0..5 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, 60.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers: egui::Modifiers::NONE,
        });
        h.run_steps(3);
    }
    h.run_steps(10);
    h.hover_at(cursor);
    h.run_steps(2);
    let after = h.state().hovered.expect("still over the image");
    assert!(!h.state().viewport.is_fit(), "the wheel zoomed in");
    assert!(
        before.x.abs_diff(after.x) <= 1 && before.y.abs_diff(after.y) <= 1,
        "{before:?} moved to {after:?}"
    );

    // Dragging left by 60 points moves the image under the cursor: a pixel further right.
    h.drag_at(cursor);
    h.run_steps(1);
    h.hover_at(cursor - egui::vec2(60.0, 0.0));
    h.run_steps(1);
    h.drop_at(cursor - egui::vec2(60.0, 0.0));
    h.run_steps(2);
    h.hover_at(cursor);
    h.run_steps(2);
    let panned = h.state().hovered.expect("still over the image");
    assert!(
        panned.x > after.x,
        "dragging left shows pixels further right: {after:?} -> {panned:?}"
    );

    h.key_press(egui::Key::F);
    h.run_steps(2);
    assert!(h.state().viewport.is_fit());
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

#[test]
fn dropping_a_scene_on_the_window_opens_it_and_remembers_it() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let glass = asset("cornell-glass.gltf");
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(DroppedPath(glass.clone())));
    step_until(&mut h, "the dropped scene", |a| {
        a.controller.scene.as_ref().is_some_and(|s| s.path == glass)
    });
    step_until(&mut h, "frames of the dropped scene", rendering);
    let recent = &h.state().settings.recent_scenes;
    assert_eq!(
        recent.first(),
        Some(&glass),
        "the newest scene comes first in the recent list"
    );
    assert!(recent.contains(&asset("cornell-box.gltf")));
}

#[test]
fn photon_mapping_in_the_viewer_with_live_alpha_radius_plot_and_inspector() {
    let mut h = harness(Some(asset("cornell-glass.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let sessions = h.state().controller.sessions_started;
    h.state_mut().apply(Command::SetIntegrator("sppm".into()));
    assert_eq!(
        h.state().controller.sessions_started,
        sessions + 1,
        "changing the integrator restarts"
    );
    h.state_mut()
        .apply(Command::SetParam("photons".into(), 5000.0));
    step_until(&mut h, "photon-mapping frames", rendering);
    let sessions = h.state().controller.sessions_started;

    // alpha is live: the slider changes the running session's parameter without a restart.
    set_slider(&mut h, "alpha", 0.5);
    assert_eq!(
        h.state().controller.sessions_started,
        sessions,
        "alpha must not restart the render"
    );
    assert_eq!(
        h.state().controller.session().unwrap().params()["alpha"],
        0.5
    );

    // The integrator's radius plot and per-pixel statistics travel with the frames, and so
    // does the radius it chose for "auto", which the radius slider shows.
    let frame = h.state().controller.frame().unwrap();
    let ppm = caustica_renderer::integrators::ppm::PhotonMappingSettings::PARAMS;
    assert!(
        ppm.iter()
            .any(|p| p.name == "radius" && p.zero_is_automatic)
    );
    let chosen = frame.automatic.iter().find(|(n, _)| *n == "radius");
    assert!(
        chosen.is_some_and(|(_, r)| *r > 0.0),
        "{:?}",
        frame.automatic
    );
    assert!(
        frame
            .plots
            .iter()
            .any(|p| p.plot == "Radius" && !p.points.is_empty())
    );
    let names: Vec<&str> = frame.pixel_layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["radius", "N", "photons"]);
    h.get_by_label("Radius");
}

#[test]
fn mmlt_in_the_viewer_with_live_large_step_histogram_and_warning() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    h.state_mut().apply(Command::SetIntegrator("mmlt".into()));
    h.state_mut()
        .apply(Command::SetParam("bootstrap".into(), 2000.0));
    h.state_mut()
        .apply(Command::SetParam("chains".into(), 64.0));
    step_until(&mut h, "MMLT frames", rendering);
    let sessions = h.state().controller.sessions_started;
    let technique_plot = |app: &ViewerApp| {
        app.controller.frame().map(|f| {
            f.plots
                .iter()
                .filter(|p| p.plot == "Techniques")
                .map(|p| (p.name.clone(), p.points.clone()))
                .collect::<Vec<_>>()
        })
    };
    // The first MMLT frames carry the histogram (earlier ones may still be the old session's).
    step_until(&mut h, "the technique histogram", |a| {
        technique_plot(a).is_some_and(|p| !p.is_empty())
    });
    let before = technique_plot(h.state()).unwrap();
    h.run_steps(2);
    h.get_by_label("Techniques");

    // p_large is live: moving it to 0 changes the running chains without a restart, the
    // histogram keeps changing, and the panel warns that chains can stick.
    set_slider(&mut h, "large_step", 0.0);
    assert_eq!(
        h.state().controller.sessions_started,
        sessions,
        "large_step must not restart the render"
    );
    assert_eq!(
        h.state().controller.session().unwrap().params()["large_step"],
        0.0
    );
    step_until(&mut h, "the histogram to change", |a| {
        technique_plot(a).is_some_and(|p| p != before)
    });
    step_until(&mut h, "the warning", |a| {
        a.controller
            .frame()
            .is_some_and(|f| f.messages.iter().any(|m| m.contains("stick")))
    });
    h.run_steps(2);
    h.get_by_label_contains("chains never jump");

    // A restart resets the histogram.
    h.state_mut()
        .apply(Command::SetParam("chains".into(), 32.0));
    assert_eq!(h.state().controller.sessions_started, sessions + 1);
    step_until(&mut h, "frames after the restart", rendering);
    let steps: u64 = h
        .state()
        .controller
        .frame()
        .and_then(|f| (*f.statistics).clone())
        .and_then(|s| s["total_steps"].as_u64())
        .unwrap();
    let frame = h.state().controller.frame().unwrap();
    assert!(
        steps <= frame.samples,
        "the histogram restarted with the session"
    );

    // A value out of range is refused where it would take effect, and the render goes on.
    h.state_mut().apply(Command::SetParam("chains".into(), 0.0));
    let state = h.state();
    assert_eq!(
        state.controller.sessions_started,
        sessions + 1,
        "no restart"
    );
    assert_eq!(state.settings.params["chains"], 32.0, "the setting is kept");
    assert_eq!(state.controller.session().unwrap().params()["chains"], 32.0);
    let last = state.messages.last().unwrap();
    assert!(
        last.is_error && last.text.contains("chains"),
        "{}",
        last.text
    );
    let passes = frame.passes;
    step_until(&mut h, "the same session to render on", |a| {
        a.controller.frame().is_some_and(|f| f.passes > passes)
    });
}

/// The side panel says which estimator the scene's light transport needs, and one click
/// switches to it with the parameters chosen for the scene.
#[test]
fn the_panel_recommends_the_estimator_the_scene_needs() {
    let mut h = harness(Some(asset("caustic-pool.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // The survey comes after the first image, from the loading thread.
    step_until(&mut h, "the survey", |a| {
        a.controller
            .scene
            .as_ref()
            .is_some_and(|s| s.survey.is_some())
    });
    h.run_steps(1);
    assert_eq!(h.state().settings.integrator, "pt");
    h.get_by_label("recommended: sppm");
    h.get_by_label("Use sppm").click();
    h.run_steps(2);
    let state = h.state();
    assert_eq!(state.settings.integrator, "sppm");
    let recommended = state
        .controller
        .scene
        .as_ref()
        .unwrap()
        .recommendation()
        .unwrap()
        .params
        .clone();
    let session = state.controller.session().unwrap();
    assert_eq!(session.integrator().name, "sppm");
    assert_eq!(session.params()["radius"], recommended["radius"]);
    assert_eq!(session.params()["photons"], recommended["photons"]);
    // Once it is in use there is nothing to switch to.
    h.run_steps(2);
    assert_eq!(h.query_all_by_label("Use sppm").count(), 0);
}

#[test]
fn the_environment_panel_relights_the_scene_and_a_bad_image_keeps_the_light() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // The default rule leaves the Cornell box to its own light, and the panel says why.
    let lighting = |a: &ViewerApp| {
        a.controller
            .scene
            .as_ref()
            .unwrap()
            .scene
            .info
            .lighting
            .clone()
    };
    assert!(
        lighting(h.state()).starts_with("none; chosen by the default rule"),
        "{}",
        lighting(h.state())
    );
    assert!(h.query_by_label_contains("lit by none").is_some());

    // Choosing the studio in the combo box relights it and restarts the render.
    let sessions = h.state().controller.sessions_started;
    h.get_by_label("environment").click();
    h.run_steps(2);
    h.get_by_label("studio").click();
    step_until(&mut h, "the studio", |a| {
        lighting(a) == "studio" && rendering(a)
    });
    assert_eq!(h.state().settings.environment, "studio");
    assert!(h.state().controller.sessions_started > sessions);

    // Strength and rotation restart it too, and say so.
    set_slider(&mut h, "strength", 2.0);
    set_slider(&mut h, "rotation", 90.0);
    let (strength, rotation) = (
        h.state().settings.environment_strength,
        h.state().settings.environment_rotation,
    );
    assert!(
        (strength - 2.0).abs() < 1e-3 && rotation == 90.0,
        "{strength} {rotation}"
    );
    step_until(&mut h, "the stronger, turned studio", |a| {
        let lit_by = &a.controller.scene.as_ref().unwrap().lit_by;
        (lit_by.strength, lit_by.rotation) == (strength, rotation)
            && a.controller.loading().is_none()
    });
    assert!(
        lighting(h.state()).contains(&format!("strength {strength}, rotation 90 degrees")),
        "{}",
        lighting(h.state())
    );

    // An image that cannot be read: the error names it, the scene stays lit as it was and
    // keeps rendering, and the panel shows the environment it has.
    let dir = std::env::temp_dir().join(format!("caustica-viewer-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("sky.hdr");
    std::fs::write(&bad, "#?RADIANCE\nnot really").unwrap();
    h.state_mut()
        .apply(Command::SetEnvironment(bad.display().to_string()));
    step_until(&mut h, "the image to fail", |a| {
        a.controller.loading().is_none()
    });
    let last: &Message = h.state().messages.last().unwrap();
    assert!(last.is_error && last.text.contains("sky.hdr"), "{last:?}");
    assert_eq!(h.state().settings.environment, "studio");
    assert!(lighting(h.state()).contains(&format!("strength {strength}")));
    keeps_rendering(&mut h, "the scene to keep rendering");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exposure_is_automatic_on_a_scenes_first_frame_until_the_user_moves_it() {
    use caustica_renderer::exposure::auto_exposure;
    let mut h = harness(Some(asset("caustic-pool.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // Set from a frame of this render (the statistic itself is tested in the renderer).
    let near_auto = |a: &ViewerApp| {
        let image = &a.controller.frame().unwrap().image;
        (a.settings.exposure - auto_exposure(image)).abs() < 0.5
    };
    assert!(h.state().settings.auto_exposure && h.state().settings.exposure != 0.0);
    assert!(
        near_auto(h.state()),
        "exposure {}",
        h.state().settings.exposure
    );
    // The user's exposure stays, and turns the automatic one off.
    set_slider(&mut h, "exposure (EV)", 5.0);
    assert_eq!(h.state().settings.exposure, 5.0);
    assert!(!h.state().settings.auto_exposure);
    h.run_steps(3);
    assert_eq!(h.state().settings.exposure, 5.0);
    // Ticking "auto" exposes the next frame again.
    h.get_by_label("auto").click();
    step_until(&mut h, "the automatic exposure", |a| {
        a.settings.exposure != 5.0
    });
    assert!(h.state().settings.auto_exposure && near_auto(h.state()));
}

#[test]
fn the_camera_orbits_pans_and_dollies_and_the_view_is_saved() {
    use caustica_renderer::metadata::camera_from_json;
    let mut h = harness(Some(asset("cornell-glass.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let position = |a: &ViewerApp| {
        a.controller
            .camera
            .map(|c| glam::Vec3::from(c.camera_to_world.translation))
    };
    assert_eq!(position(h.state()), None, "the file's camera at first");
    let file_camera = h.state().controller.scene.as_ref().unwrap().scene.camera;
    let eye = glam::Vec3::from(file_camera.camera_to_world.translation);

    // A right drag to the right orbits: the camera swings left about the target, at the same
    // distance, and the render restarts with it.
    let sessions = h.state().controller.sessions_started;
    let cursor = egui::pos2(420.0, 230.0);
    h.event(egui::Event::PointerMoved(cursor));
    h.event(egui::Event::PointerButton {
        pos: cursor,
        button: egui::PointerButton::Secondary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    h.run_steps(1);
    for step in 1..=4 {
        h.event(egui::Event::PointerMoved(
            cursor + egui::vec2(20.0 * step as f32, 0.0),
        ));
        h.run_steps(1);
    }
    h.event(egui::Event::PointerButton {
        pos: cursor + egui::vec2(80.0, 0.0),
        button: egui::PointerButton::Secondary,
        pressed: false,
        modifiers: egui::Modifiers::NONE,
    });
    h.run_steps(2);
    let view = h.state().view.expect("the camera moved");
    let orbited = position(h.state()).unwrap();
    assert!((orbited - eye).length() > 0.1, "{eye} -> {orbited}");
    assert!(((orbited - view.target).length() - view.distance).abs() < 1e-3);
    assert!(((eye - view.target).length() - view.distance).abs() < 1e-3);
    let seen_from_above = |p: glam::Vec3| (p - view.target).cross(glam::Vec3::Y);
    assert!(
        seen_from_above(eye).dot(orbited - eye) > 0.0,
        "dragging right carries the camera clockwise seen from above: {eye} -> {orbited}"
    );
    assert!(h.state().controller.sessions_started > sessions);
    step_until(&mut h, "frames from the new view", rendering);

    // Page Down dollies out by 1.25; the panel says the camera moved; the view is remembered
    // with the scene and written into snapshots' headers (checked by the CLI tests).
    let distance = h.state().view.unwrap().distance;
    h.key_press(egui::Key::PageDown);
    h.run_steps(2);
    assert!((h.state().view.unwrap().distance - 1.25 * distance).abs() < 1e-4);
    assert!(
        h.query_by_label("Reset").is_some(),
        "the panel offers to reset the moved camera"
    );
    let (path, json) = h.state().settings.view.clone().expect("the view is saved");
    assert!(path.ends_with("cornell-glass.gltf"));
    let saved = camera_from_json(&json).unwrap();
    assert!(
        saved
            .camera_to_world
            .abs_diff_eq(h.state().controller.camera.unwrap().camera_to_world, 1e-4)
    );
    let recorded = h
        .state()
        .controller
        .session()
        .unwrap()
        .run_description(&path)
        .camera;
    let recorded = glam::Vec3::from(recorded.camera_to_world.translation);
    assert!(recorded.abs_diff_eq(position(h.state()).unwrap(), 1e-4));

    // Reopening the scene restores the view; Home goes back to the file's camera.
    h.state_mut()
        .apply(Command::OpenScene(asset("cornell-glass.gltf")));
    step_until(&mut h, "the scene reopened", |a| {
        a.controller.loading().is_none() && rendering(a)
    });
    assert!(
        position(h.state())
            .unwrap()
            .abs_diff_eq(saved.camera_to_world.translation.into(), 1e-3)
    );
    h.key_press(egui::Key::Home);
    h.run_steps(2);
    assert_eq!(position(h.state()), None);
    assert!(h.state().view.is_none() && h.state().settings.view.is_none());

    // The camera box offers the file's cameras and the default view that frames the scene.
    h.get_by_label("camera").click();
    h.run_steps(2);
    h.get_by_label("default view").click();
    h.run_steps(2);
    let scene = h.state().controller.scene.as_ref().unwrap().scene.clone();
    let framing = caustica_renderer::camera::CameraDesc::framing(&scene.bounds);
    assert_eq!(h.state().controller.camera, Some(framing));
}

/// A pass that panics on a worker thread: the viewer says so in its status line, keeps the
/// image of the passes before (which Ctrl+S still saves), and a restart renders again.
#[test]
fn a_panicking_pass_is_reported_and_the_render_restarts() {
    let dir = std::env::temp_dir().join(format!("caustica-viewer-panic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut h = harness(Some(asset("cornell-box.gltf")));
    h.state_mut().snapshot_dir = dir.clone();
    step_until(&mut h, "the first frames", rendering);
    h.state_mut().controller.panic_in_pass = Some(2);
    h.state_mut().apply(Command::Restart);
    step_until(&mut h, "the failure reported", |a| {
        a.messages.last().is_some_and(|m| m.is_error)
    });
    let text = h.state().messages.last().unwrap().text.clone();
    assert!(
        text.starts_with("the renderer failed after 2 passes: fault injected in pass 2"),
        "{text}"
    );
    h.get_by_label_contains("the renderer failed after 2 passes");
    let frame = h.state().controller.frame().unwrap();
    assert_eq!((frame.state, frame.passes), (RunState::Failed, 2));
    assert!(frame.image.mean_luminance() > 0.0);

    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    step_until(&mut h, "the save", |a| {
        a.messages.iter().any(|m| m.text.starts_with("saved"))
    });
    let saved = std::fs::read_dir(&dir)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let (image, _) = read_exr(&saved).unwrap();
    assert_eq!(image.pixels, frame.image.pixels);

    h.state_mut().controller.panic_in_pass = None;
    h.key_press(egui::Key::R);
    step_until(&mut h, "rendering again", |a| {
        a.controller
            .frame()
            .is_some_and(|f| f.state == RunState::Running && f.passes >= 3)
    });
    std::fs::remove_dir_all(dir).unwrap();
}

/// An image size whose buffers would not fit in memory is refused with a message saying what
/// it needs, and the render the user had goes on.
#[test]
fn a_size_too_large_for_the_memory_is_refused_and_the_render_goes_on() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    h.state_mut().controller.memory_limit = Some(8 << 30);
    h.state_mut().apply(Command::SetIntegrator("sppm".into()));
    step_until(&mut h, "the first frames", rendering);
    h.state_mut().apply(Command::SetResolution(16384, 16384));
    step_until(&mut h, "the refusal", |a| {
        a.messages.last().is_some_and(|m| m.is_error)
    });
    let text = h.state().messages.last().unwrap().text.clone();
    assert!(
        text.contains("sppm at 16384 x 16384 needs about 175.0 GiB for its buffers, more than the 8.0 GiB allowed"),
        "{text}"
    );
    keeps_rendering(&mut h, "the render the user had");
    let frame = h.state().controller.frame().unwrap();
    assert_eq!((frame.image.width, frame.image.height), (96, 72));
    let settings = &h.state().settings;
    assert_eq!((settings.width, settings.height), (96, 72));
}
