//! The side panel. It shows the state it is given and returns the user's actions as
//! commands; it never calls the renderer (egui's and rerun's separation of UI and work).

use crate::viewer::command::Command;
use crate::viewer::settings::ViewerSettings;
use caustica_renderer::advisor::Recommendation;
use caustica_renderer::camera::CameraDesc;
use caustica_renderer::image::ToneCurve;
use caustica_renderer::integrators::{self, ParamSpec};
use caustica_renderer::light::environment::EnvironmentChoice;
use caustica_renderer::scene::SceneInfo;
use caustica_renderer::session::{Frame, MAX_RESOLUTION, RunState};
use eframe::egui::{self, RichText};
use std::path::Path;

/// What the panel displays besides the settings.
pub struct PanelStatus<'a> {
    pub scene: Option<(&'a Path, &'a SceneInfo)>,
    /// The estimator the scene needs, and those that cannot converge on it.
    pub recommendation: Option<&'a Recommendation>,
    pub loading: Option<&'a Path>,
    pub frame: Option<&'a Frame>,
    pub resident_bytes: Option<u64>,
    /// Worker threads of the running render.
    pub threads: Option<usize>,
    /// The user has moved the camera away from the scene's.
    pub camera_moved: bool,
    /// The file's cameras, named.
    pub cameras: &'a [(String, CameraDesc)],
}

/// A numeric control that reports a value once the user is done with it: at once for live
/// parameters, on release of a drag for those that restart the render.
fn commit_value(response: &egui::Response, live: bool) -> bool {
    if live {
        response.changed()
    } else {
        response.drag_stopped() || (response.changed() && !response.dragged())
    }
}

/// `add` in a scope whose id is `name`'s, whatever came before it. A widget's automatic id
/// counts the widgets laid out before it in its parent (`ui.push_id` does not reset that count),
/// and the panel's rows come and go (the lighting label, a loading row): a slider's id then
/// changes for a frame, and a drag or an accessibility action aimed at it is lost or lands on
/// its neighbour (measured: the environment's strength or rotation, in 11 of 12 runs of the
/// panel's test run alone). Every slider of the panel goes through here.
fn with_stable_id<R>(ui: &mut egui::Ui, name: &str, add: impl FnOnce(&mut egui::Ui) -> R) -> R {
    ui.scope_builder(egui::UiBuilder::new().scope_id(egui::Id::unique(name)), add)
        .inner
}

/// The slider of one integrator parameter, its range and meaning in the hover text; at 0,
/// where 0 is automatic, it reads "auto (the value chosen)".
fn param_widget(
    ui: &mut egui::Ui,
    spec: &ParamSpec,
    value: f64,
    chosen: Option<f64>,
    out: &mut Vec<Command>,
) {
    let mut v = value;
    let tag = if spec.live { "live" } else { "restarts" };
    ui.horizontal(|ui| {
        let slider = egui::Slider::new(&mut v, spec.min..=spec.max)
            .text(spec.name)
            .logarithmic(spec.max / spec.min.max(1.0) > 100.0);
        let slider = if spec.zero_is_automatic {
            slider.custom_formatter(move |v, _| match (v == 0.0, chosen) {
                (true, Some(c)) => format!("auto ({c:.3e})"),
                (true, None) => "auto".to_string(),
                _ => format!("{v:.4}"),
            })
        } else {
            slider
        };
        let slider = if spec.integer {
            slider.integer()
        } else {
            slider
        };
        let response = with_stable_id(ui, &format!("parameter {}", spec.name), |ui| ui.add(slider))
            .on_hover_text(format!(
                "{}\nrange {} to {}{} ({tag})",
                spec.doc,
                spec.min,
                spec.max,
                if spec.integer { ", whole numbers" } else { "" }
            ));
        ui.label(RichText::new(if spec.live { "live" } else { "restarts" }).weak())
            .on_hover_text(if spec.live {
                "changes apply to the passes still to come"
            } else {
                "changing this restarts the render"
            });
        if commit_value(&response, spec.live) && v != value {
            out.push(Command::SetParam(spec.name.to_string(), v));
        }
    });
}

/// The side panel: the scene, the render's settings, the display, the statistics.
pub fn side_panel(
    ui: &mut egui::Ui,
    settings: &ViewerSettings,
    status: &PanelStatus,
) -> Vec<Command> {
    let mut out = Vec::new();
    egui::ScrollArea::vertical().show(ui, |ui| {
        ui.heading("Scene");
        scene_section(ui, settings, status, &mut out);
        ui.separator();
        ui.heading("Environment");
        environment_section(ui, settings, status, &mut out);
        ui.separator();
        ui.heading("Render");
        render_section(ui, settings, status, &mut out);
        ui.separator();
        ui.heading("Display");
        display_section(ui, settings, &mut out);
        ui.separator();
        ui.heading("Statistics");
        statistics(ui, status);
    });
    out
}

/// The scene shown or loading, what its light transport needs, opening another.
fn scene_section(
    ui: &mut egui::Ui,
    settings: &ViewerSettings,
    status: &PanelStatus,
    out: &mut Vec<Command>,
) {
    match (status.scene, status.loading) {
        (_, Some(loading)) => {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("loading {}", loading.display()));
            });
        }
        (None, None) => {
            ui.label("No scene: open a .gltf or .glb, or drop one on the window.");
        }
        _ => {}
    }
    if let Some((path, info)) = status.scene {
        ui.label(
            RichText::new(
                path.file_name()
                    .map(|n| n.to_string_lossy())
                    .unwrap_or_default(),
            )
            .strong(),
        )
        .on_hover_text(path.display().to_string());
        ui.label(format!(
            "{} triangles, {} lights, loaded in {:.0} ms",
            info.triangles,
            info.lights,
            info.load_time.as_secs_f64() * 1e3
        ));
        for w in &info.warnings {
            ui.label(RichText::new(format!("warning: {w}")).small());
        }
        camera_row(ui, status, info, out);
    }
    if let Some(r) = status.recommendation {
        recommendation(ui, settings, r, out);
    }
    ui.horizontal(|ui| {
        if ui.button("Open…").on_hover_text("Ctrl+O").clicked() {
            out.push(Command::ShowOpenDialog);
        }
        if !settings.recent_scenes.is_empty() {
            ui.menu_button("Recent", |ui| {
                for p in &settings.recent_scenes {
                    if ui.button(p.display().to_string()).clicked() {
                        out.push(Command::OpenScene(p.clone()));
                        ui.close();
                    }
                }
            });
        }
    });
}

/// The camera: which one, the file's cameras and the default view to choose from, and a reset
/// once the user has moved it.
fn camera_row(ui: &mut egui::Ui, status: &PanelStatus, info: &SceneInfo, out: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        let shown = match (status.camera_moved, info.default_camera) {
            (true, _) => "moved".to_string(),
            (false, true) => "default view".to_string(),
            (false, false) => status
                .cameras
                .first()
                .map_or("the file's".to_string(), |(name, _)| name.clone()),
        };
        egui::ComboBox::from_label("camera")
            .selected_text(shown)
            .show_ui(ui, |ui| {
                for (i, (name, _)) in status.cameras.iter().enumerate() {
                    if ui.selectable_label(false, name).clicked() {
                        out.push(Command::ChooseCamera(Some(i)));
                    }
                }
                if ui
                    .selectable_label(false, "default view")
                    .on_hover_text("a three-quarter view that frames the scene")
                    .clicked()
                {
                    out.push(Command::ChooseCamera(None));
                }
            })
            .response
            .on_hover_text(
                "right drag orbits, middle or Shift + right drag pans, Ctrl + wheel dollies; \
                 arrow keys orbit, Page Up and Down dolly; Home resets",
            );
        if status.camera_moved && ui.button("Reset").on_hover_text("Home").clicked() {
            out.push(Command::ResetCamera);
        }
    });
}

/// The default-lighting rule, as the panel explains it.
const AUTO_RULE: &str = "Auto lights a model meant to be lit by its viewer with the studio: one \
without light sources, or whose emitters are small details (their power spread over the \
scene's surface gives under 5 % of the studio's light). A scene with punctual lights or \
brighter emitters keeps its own lighting and gets no environment.";

/// What lights the scene from outside: the choice (the rule's, or the user's), an image file,
/// the strength and rotation (each change relights the scene and restarts the render).
fn environment_section(
    ui: &mut egui::Ui,
    settings: &ViewerSettings,
    status: &PanelStatus,
    out: &mut Vec<Command>,
) {
    let named = EnvironmentChoice::NAMED;
    let is_file = !named.contains(&settings.environment.as_str());
    let shown = if is_file {
        Path::new(&settings.environment)
            .file_name()
            .map_or(settings.environment.clone(), |n| {
                n.to_string_lossy().into_owned()
            })
    } else {
        settings.environment.clone()
    };
    egui::ComboBox::from_label("environment")
        .selected_text(shown)
        .show_ui(ui, |ui| {
            for name in named {
                if ui
                    .selectable_label(settings.environment == name, name)
                    .on_hover_text(match name {
                        "auto" => AUTO_RULE,
                        "none" => "nothing: only the scene's own lights",
                        "uniform" => "radiance 1 from every direction",
                        _ => "the built-in studio: soft boxes over a gradient, so metals show reflections",
                    })
                    .clicked()
                    && settings.environment != name
                {
                    out.push(Command::SetEnvironment(name.to_string()));
                }
            }
            if ui.button("Image file…").on_hover_text("an equirectangular .hdr or .exr").clicked() {
                out.push(Command::ShowEnvironmentDialog);
                ui.close();
            }
        })
        .response
        .on_hover_text(AUTO_RULE);
    if let Some((_, info)) = status.scene {
        ui.label(RichText::new(format!("lit by {}", info.lighting)).small());
    }
    let mut strength = settings.environment_strength;
    let response = with_stable_id(ui, "environment strength", |ui| {
        ui.add(
            egui::Slider::new(&mut strength, 0.0..=100.0)
                .logarithmic(true)
                .text("strength"),
        )
    })
    .on_hover_text("multiplies the environment's radiance (restarts)");
    if commit_value(&response, false) && strength != settings.environment_strength {
        out.push(Command::SetEnvironmentStrength(strength));
    }
    let mut rotation = settings.environment_rotation;
    let response = with_stable_id(ui, "environment rotation", |ui| {
        ui.add(
            egui::Slider::new(&mut rotation, -180.0..=180.0)
                .suffix("°")
                .text("rotation"),
        )
    })
    .on_hover_text(
        "turns the environment about the up axis, counter-clockwise seen from above (restarts)",
    );
    if commit_value(&response, false) && rotation != settings.environment_rotation {
        out.push(Command::SetEnvironmentRotation(rotation));
    }
}

/// The integrator and its parameters, size, threads, seed; pause and restart.
fn render_section(
    ui: &mut egui::Ui,
    settings: &ViewerSettings,
    status: &PanelStatus,
    out: &mut Vec<Command>,
) {
    let mut integrator = settings.integrator.clone();
    egui::ComboBox::from_label("integrator")
        .selected_text(&integrator)
        .show_ui(ui, |ui| {
            for info in integrators::registry() {
                ui.selectable_value(&mut integrator, info.name.to_string(), info.title)
                    .on_hover_text(info.description);
            }
        });
    if integrator != settings.integrator {
        out.push(Command::SetIntegrator(integrator));
    }
    if let Some(info) = integrators::find(&settings.integrator) {
        for spec in info.params {
            let value = settings
                .params
                .get(spec.name)
                .copied()
                .unwrap_or(spec.default);
            let chosen = status
                .frame
                .and_then(|f| f.automatic.iter().find(|(n, _)| *n == spec.name))
                .map(|(_, v)| *v);
            param_widget(ui, spec, value, chosen, out);
        }
    }
    // What the integrator says of its state (a sticking chain, a black scene).
    if let Some(f) = status.frame {
        for m in f.messages.iter() {
            ui.colored_label(ui.visuals().warn_fg_color, format!("warning: {m}"));
        }
    }
    ui.horizontal(|ui| {
        let (mut w, mut h) = (settings.width, settings.height);
        let pixels = |ui: &mut egui::Ui, value: &mut u32, what: &str| {
            let drag = egui::DragValue::new(value).range(1..=MAX_RESOLUTION);
            let r = ui.add(drag.suffix(" px"));
            commit_value(&r.on_hover_text(format!("{what} (restarts)")), false)
        };
        let width_done = pixels(ui, &mut w, "width");
        ui.label("×");
        let height_done = pixels(ui, &mut h, "height");
        ui.label(RichText::new("restarts").weak());
        if (width_done || height_done) && (w, h) != (settings.width, settings.height) {
            out.push(Command::SetResolution(w, h));
        }
    });
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads = settings.threads;
    let running = status.threads;
    let slider = egui::Slider::new(&mut threads, 0..=cores.max(1) * 2)
        .text("threads")
        .custom_formatter(move |v, _| match (v == 0.0, running) {
            (true, Some(n)) => format!("auto ({n} threads)"),
            (true, None) => "auto".to_string(),
            _ => format!("{v}"),
        });
    let r = with_stable_id(ui, "threads", |ui| ui.add(slider))
        .on_hover_text("worker threads, 0 for one per core (restarts)");
    if commit_value(&r, false) && threads != settings.threads {
        out.push(Command::SetThreads(threads));
    }
    let mut seed = settings.seed;
    let r = ui
        .add(egui::DragValue::new(&mut seed).prefix("seed "))
        .on_hover_text("random seed (restarts)");
    if commit_value(&r, false) && seed != settings.seed {
        out.push(Command::SetSeed(seed));
    }
    ui.horizontal(|ui| {
        let paused = status.frame.is_some_and(|f| f.state == RunState::Paused);
        if ui
            .button(if paused { "Resume" } else { "Pause" })
            .on_hover_text("Space")
            .clicked()
        {
            out.push(Command::TogglePause);
        }
        if ui.button("Restart").on_hover_text("R").clicked() {
            out.push(Command::Restart);
        }
    });
}

/// Exposure and tone curve, the view, saving, and what is drawn.
fn display_section(ui: &mut egui::Ui, settings: &ViewerSettings, out: &mut Vec<Command>) {
    let mut exposure = settings.exposure;
    ui.horizontal(|ui| {
        if with_stable_id(ui, "exposure", |ui| {
            ui.add(egui::Slider::new(&mut exposure, -20.0..=20.0).text("exposure (EV)"))
        })
        .changed()
        {
            out.push(Command::SetExposure(exposure));
        }
        let mut auto = settings.auto_exposure;
        if ui
            .checkbox(&mut auto, "auto")
            .on_hover_text(
                "set from the first frame of each scene opened: the 97th percentile of the lit \
                 pixels' luminance at 90 % of white; moving the exposure turns it off",
            )
            .changed()
        {
            out.push(Command::SetAutoExposure(auto));
        }
    });
    let mut curve = settings.tone_curve;
    egui::ComboBox::from_label("tone curve")
        .selected_text(curve.name())
        .show_ui(ui, |ui| {
            for c in ToneCurve::ALL {
                ui.selectable_value(&mut curve, c, c.name());
            }
        });
    if curve != settings.tone_curve {
        out.push(Command::SetToneCurve(curve));
    }
    ui.horizontal(|ui| {
        if ui.button("Fit").on_hover_text("F").clicked() {
            out.push(Command::Fit);
        }
        if ui.button("1:1").on_hover_text("1").clicked() {
            out.push(Command::OneToOne);
        }
    });
    ui.horizontal(|ui| {
        if ui
            .button("Save EXR")
            .on_hover_text("Ctrl+S: the linear estimate with its metadata")
            .clicked()
        {
            out.push(Command::SaveExr);
        }
        if ui
            .button("Save PNG")
            .on_hover_text("what the window shows: exposure and tone curve applied")
            .clicked()
        {
            out.push(Command::SavePng);
        }
    });
    ui.horizontal(|ui| {
        if ui.selectable_label(settings.show_plots, "Plots").clicked() {
            out.push(Command::TogglePlots);
        }
        if ui
            .selectable_label(settings.show_error_map, "Error map")
            .on_hover_text(
                "E: each pixel's estimated remaining error (relMSE) over the image, on a log scale",
            )
            .clicked()
        {
            out.push(Command::ToggleErrorMap);
        }
    });
}

/// What the scene's light transport needs: the recommended estimator (with its reasons on
/// hover and a button to switch to it) and the estimators that cannot converge here.
fn recommendation(
    ui: &mut egui::Ui,
    settings: &ViewerSettings,
    r: &Recommendation,
    out: &mut Vec<Command>,
) {
    ui.horizontal(|ui| {
        ui.label(format!("recommended: {}", r.integrator))
            .on_hover_text(r.reasons.join("\n"));
        if settings.integrator != r.integrator
            && ui
                .button(format!("Use {}", r.integrator))
                .on_hover_text("switch to it, with the radius and photons chosen for this scene")
                .clicked()
        {
            out.push(Command::UseRecommended);
        }
    });
    for (name, why) in &r.cannot_converge {
        ui.colored_label(
            ui.visuals().warn_fg_color,
            format!("{name} cannot converge here"),
        )
        .on_hover_text(why);
    }
}

fn statistics(ui: &mut egui::Ui, status: &PanelStatus) {
    egui::Grid::new("statistics").num_columns(2).show(ui, |ui| {
        if let Some(f) = status.frame {
            let secs = f.elapsed.as_secs_f64();
            let pixels = (f.image.width * f.image.height).max(1) as f64;
            let rows = [
                (
                    "state",
                    match (f.preview, f.preparation) {
                        (true, _) => "preview (first pass under way)".to_string(),
                        (_, Some(done)) => format!("preparing ({:.0} %)", done * 100.0),
                        _ => format!("{:?}", f.state),
                    },
                ),
                ("elapsed", format!("{secs:.1} s")),
                ("passes", f.passes.to_string()),
                (
                    "samples per pixel",
                    format!("{:.0}", f.samples as f64 / pixels),
                ),
                (
                    "rays per second",
                    format!(
                        "{:.2} M",
                        if secs > 0.0 {
                            f.rays as f64 / secs / 1e6
                        } else {
                            0.0
                        }
                    ),
                ),
                ("dropped samples", f.dropped.to_string()),
            ];
            for (k, v) in rows {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            }
            ui.label("estimated relMSE").on_hover_text(
                "the remaining error without a reference: mean over pixels of (x - r)^2 / (r^2 + 0.01), \
                 estimated from the render's own samples (noise, and the kernel bias of photon mapping)",
            );
            match f.error.as_ref() {
                Some(e) if e.bias_rel_mse > 0.0 => ui.label(format!(
                    "{:.3e} ({:.0} % bias)",
                    e.rel_mse,
                    100.0 * e.bias_rel_mse / e.rel_mse
                )),
                Some(e) => ui.label(format!("{:.3e}", e.rel_mse)),
                None => ui.label("after two passes"),
            };
            ui.end_row();
        }
        if let Some(bytes) = status.resident_bytes {
            ui.label("memory in use");
            ui.label(format!("{:.0} MiB", bytes as f64 / (1024.0 * 1024.0)));
            ui.end_row();
        }
    });
}
