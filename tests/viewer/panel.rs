//! The side panel: settings that change the session live or by restarting it, snapshots,
//! the estimator recommendation, and failures (a broken scene, a panicking pass, a size too
//! large for the memory) that keep what the user had.

use super::{as_in_window, asset, harness, keeps_rendering, rendering, set_slider, step_until};
use caustica::viewer::{Command, Message};
use caustica_renderer::image::read_exr;
use caustica_renderer::session::RunState;
use eframe::egui;
use egui_kittest::kittest::Queryable;

#[test]
fn the_panel_drives_the_session_live_or_by_restart() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let sessions = h.state().controller.sessions_started();

    // Exposure is a display setting: it changes at once and the render goes on.
    set_slider(&mut h, "exposure (EV)", 2.0);
    assert_eq!(h.state().settings.exposure, 2.0);
    assert_eq!(
        h.state().controller.sessions_started(),
        sessions,
        "a live setting restarted the render"
    );

    // Max depth invalidates the estimate: the session restarts with the new value.
    set_slider(&mut h, "max_depth", 3.0);
    assert_eq!(
        h.state().controller.sessions_started(),
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
            .scene()
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

/// The side panel says which estimator the scene's light transport needs, and one click
/// switches to it with the parameters chosen for the scene.
#[test]
fn the_panel_recommends_the_estimator_the_scene_needs() {
    let mut h = harness(Some(asset("caustic-pool.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // The survey comes after the first image, from the loading thread.
    step_until(&mut h, "the survey", |a| {
        a.controller.scene().is_some_and(|s| s.survey.is_some())
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
        .scene()
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

/// A pass that panics on a worker thread: the viewer says so in its status line, keeps the
/// image of the passes before (which Ctrl+S still saves), and a restart renders again.
#[test]
fn a_panicking_pass_is_reported_and_the_render_restarts() {
    let dir = std::env::temp_dir().join(format!("caustica-viewer-panic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut h = harness(Some(asset("cornell-box.gltf")));
    h.state_mut().snapshot_dir = dir.clone();
    step_until(&mut h, "the first frames", rendering);
    h.state_mut().controller.set_panic_in_pass(Some(2));
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

    h.state_mut().controller.set_panic_in_pass(None);
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
    h.state_mut().controller.set_memory_limit(Some(8 << 30));
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
