//! Each estimator's own controls and plots: photon mapping's live alpha, radius plot and
//! inspector; MMLT's live large-step probability, technique histogram and warning.

use super::{asset, harness, rendering, set_slider, step_until};
use caustica::viewer::{Command, ViewerApp};
use egui_kittest::kittest::Queryable;

#[test]
fn photon_mapping_in_the_viewer_with_live_alpha_radius_plot_and_inspector() {
    let mut h = harness(Some(asset("cornell-glass.gltf")));
    step_until(&mut h, "the first frames", rendering);
    let sessions = h.state().controller.sessions_started();
    h.state_mut().apply(Command::SetIntegrator("sppm".into()));
    assert_eq!(
        h.state().controller.sessions_started(),
        sessions + 1,
        "changing the integrator restarts"
    );
    h.state_mut()
        .apply(Command::SetParam("photons".into(), 5000.0));
    step_until(&mut h, "photon-mapping frames", rendering);
    let sessions = h.state().controller.sessions_started();

    // alpha is live: the slider changes the running session's parameter without a restart.
    set_slider(&mut h, "alpha", 0.5);
    assert_eq!(
        h.state().controller.sessions_started(),
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
    let sessions = h.state().controller.sessions_started();
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
        h.state().controller.sessions_started(),
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
    assert_eq!(h.state().controller.sessions_started(), sessions + 1);
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
        state.controller.sessions_started(),
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
