//! The scene: the environment panel relighting it, and the camera moving over it.

use super::{asset, harness, keeps_rendering, rendering, set_slider, step_until};
use caustica::viewer::{Command, Message, ViewerApp};
use eframe::egui;
use egui_kittest::kittest::Queryable;

#[test]
fn the_environment_panel_relights_the_scene_and_a_bad_image_keeps_the_light() {
    let mut h = harness(Some(asset("cornell-box.gltf")));
    step_until(&mut h, "the first frames", rendering);
    // The default rule leaves the Cornell box to its own light, and the panel says why.
    let lighting = |a: &ViewerApp| a.controller.scene().unwrap().scene.info.lighting.clone();
    assert!(
        lighting(h.state()).starts_with("none; chosen by the default rule"),
        "{}",
        lighting(h.state())
    );
    assert!(h.query_by_label_contains("lit by none").is_some());

    // Choosing the studio in the combo box relights it and restarts the render.
    let sessions = h.state().controller.sessions_started();
    h.get_by_label("environment").click();
    h.run_steps(2);
    h.get_by_label("studio").click();
    step_until(&mut h, "the studio", |a| {
        lighting(a) == "studio" && rendering(a)
    });
    assert_eq!(h.state().settings.environment, "studio");
    assert!(h.state().controller.sessions_started() > sessions);

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
        let lit_by = &a.controller.scene().unwrap().lit_by;
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
fn the_camera_orbits_pans_and_dollies_and_the_view_is_saved() {
    use caustica_renderer::metadata::camera_from_json;
    let mut h = harness(Some(asset("cornell-glass.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let position = |a: &ViewerApp| {
        a.controller
            .camera()
            .map(|c| glam::Vec3::from(c.camera_to_world.translation))
    };
    assert_eq!(position(h.state()), None, "the file's camera at first");
    let file_camera = h.state().controller.scene().unwrap().scene.camera;
    let eye = glam::Vec3::from(file_camera.camera_to_world.translation);

    // A right drag to the right orbits: the camera swings left about the target, at the same
    // distance, and the render restarts with it.
    let sessions = h.state().controller.sessions_started();
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
    assert!(h.state().controller.sessions_started() > sessions);
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
            .abs_diff_eq(h.state().controller.camera().unwrap().camera_to_world, 1e-4)
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
    let scene = h.state().controller.scene().unwrap().scene.clone();
    let framing = caustica_renderer::camera::CameraDesc::framing(&scene.bounds);
    assert_eq!(h.state().controller.camera(), Some(framing));
}
