//! The viewer's state on the UI thread (settings, view, messages, the background controller)
//! and `apply`, which carries out a `Command`. Nothing here waits for the renderer.

use crate::viewer::app;
use crate::viewer::automation::{Automation, ViewerTimings};
use crate::viewer::command::{Command, Message};
use crate::viewer::controller::{ParamEffect, RenderController};
use crate::viewer::convergence::Convergence;
use crate::viewer::dialogs::DialogPurpose;
use crate::viewer::error_map::ErrorMap;
use crate::viewer::navigation::Orbit;
use crate::viewer::repaint::ProgressRepaint;
use crate::viewer::settings::{STORAGE_KEY, ViewerSettings};
use crate::viewer::tonemap;
use crate::viewer::viewport::{HoveredPixel, Viewport};
use caustica_renderer::camera::CameraDesc;
use caustica_renderer::exposure::EXPOSURE_RANGE;
use caustica_renderer::integrators;
use caustica_renderer::metadata::{camera_from_json, camera_to_json};
use caustica_renderer::scene::limits::LoadLimits;
use caustica_renderer::session::{MAX_RESOLUTION, RunState};
use eframe::egui;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Instant;

/// What a snapshot saved on a background thread reports: the file written, or why not.
pub(super) type SaveOutcome = Result<PathBuf, String>;

/// What the viewer was started with.
#[derive(Clone, Debug, Default)]
pub struct ViewerOptions {
    pub scene: Option<PathBuf>,
    pub reference: Option<PathBuf>,
    /// When the program started, so the time to the first frame includes opening the window.
    pub launched: Option<Instant>,
    /// Integrator, overriding the remembered one.
    pub integrator: Option<String>,
    /// Render size, overriding the remembered one.
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Window size in logical points, overriding the remembered one.
    pub window_size: Option<[f32; 2]>,
    /// Scripted run for tests: save a screenshot after some seconds of rendering, then quit.
    pub automation: Option<Automation>,
    /// What a scene file may ask for.
    pub limits: LoadLimits,
    /// Memory a session's buffers may take (None: what the system has available).
    pub memory_limit: Option<u64>,
}

/// The viewer: its settings and view on the UI thread, the render and the loads in the
/// background (`controller`), what it measures and what it tells the user.
pub struct ViewerApp {
    pub settings: ViewerSettings,
    pub controller: RenderController,
    pub convergence: Convergence,
    pub error_map: ErrorMap,
    pub viewport: Viewport,
    pub messages: Vec<Message>,
    /// Where snapshots go.
    pub snapshot_dir: PathBuf,
    pub hovered: Option<HoveredPixel>,
    pub(super) timings: ViewerTimings,
    /// Show process readouts (memory, UI frame rate); snapshot tests turn them off because
    /// they change from run to run.
    pub show_process_stats: bool,
    pub(super) saves: (Sender<SaveOutcome>, Receiver<SaveOutcome>),
    pub(super) open_dialog: Option<(DialogPurpose, egui_file::FileDialog)>,
    pub(super) sessions_seen: u64,
    pub(super) automation: Option<Automation>,
    pub(super) screenshot_requested: bool,
    pub(super) started: Instant,
    /// The view shows the reference in place of the render.
    pub show_reference: bool,
    /// Paces the redraws that show the render's progress.
    pub(super) progress: Arc<ProgressRepaint>,
    /// The camera as the user moved it; None shows the scene's own.
    pub view: Option<Orbit>,
    /// The next frame with a finished pass sets the exposure (a scene was opened with
    /// automatic exposure on, or the user turned it on).
    pub(super) expose_next_frame: bool,
}

impl ViewerApp {
    pub fn new(cc: &eframe::CreationContext<'_>, options: ViewerOptions) -> Self {
        let settings: ViewerSettings = cc
            .storage
            .and_then(|s| eframe::get_value(s, STORAGE_KEY))
            .unwrap_or_default();
        if let Some(rs) = cc.wgpu_render_state.as_ref() {
            tonemap::init(rs);
        }
        let software = cc
            .wgpu_render_state
            .as_ref()
            .is_some_and(|rs| rs.adapter.get_info().device_type == eframe::wgpu::DeviceType::Cpu);
        let progress = Arc::new(ProgressRepaint::new(cc.egui_ctx.clone(), software));
        if software {
            app::square_corners(&cc.egui_ctx);
        }
        // The render's frames and the convergence thread's measurements redraw at its pace.
        let (on_frame, on_measured) = (progress.clone(), progress.clone());
        let mut app = ViewerApp {
            settings: settings.sanitized(),
            controller: RenderController::new(Arc::new(move || on_frame.request())),
            progress,
            expose_next_frame: false,
            view: None,
            show_reference: false,
            convergence: Convergence::new(Arc::new(move || on_measured.request())),
            error_map: ErrorMap::default(),
            viewport: Viewport::default(),
            messages: Vec::new(),
            snapshot_dir: PathBuf::from("."),
            hovered: None,
            timings: ViewerTimings::default(),
            show_process_stats: true,
            saves: channel(),
            open_dialog: None,
            sessions_seen: 0,
            automation: options.automation,
            screenshot_requested: false,
            started: options.launched.unwrap_or_else(Instant::now),
        };
        app.controller.set_limits(options.limits);
        app.controller.set_memory_limit(options.memory_limit);
        if let Some(name) = options.integrator {
            app.apply(Command::SetIntegrator(name.clone()));
            if app.settings.integrator != name {
                app.error(format!("unknown integrator '{name}'"));
            }
        }
        app.settings.width = options.width.unwrap_or(app.settings.width);
        app.settings.height = options.height.unwrap_or(app.settings.height);
        if let Some(scene) = options.scene {
            app.apply(Command::OpenScene(scene));
        }
        if let Some(reference) = options.reference {
            app.apply(Command::LoadReference(reference));
        }
        app
    }

    pub(super) fn info(&mut self, text: impl Into<String>) {
        self.messages.push(Message {
            text: text.into(),
            is_error: false,
        });
    }

    pub(super) fn error(&mut self, text: impl Into<String>) {
        self.messages.push(Message {
            text: text.into(),
            is_error: true,
        });
    }

    fn restart(&mut self) {
        if let Err(e) = self.controller.restart(&self.settings) {
            self.error(e);
        }
    }

    /// Carries out a command.
    pub fn apply(&mut self, command: Command) {
        match command {
            Command::OpenScene(path) => self.controller.open_scene(path, &self.settings),
            Command::SetEnvironment(choice) => {
                self.settings.environment = choice;
                self.controller.relight(&self.settings);
            }
            Command::SetEnvironmentStrength(strength) => {
                if strength.is_finite() && strength >= 0.0 {
                    self.settings.environment_strength = strength;
                    self.controller.relight(&self.settings);
                }
            }
            Command::SetEnvironmentRotation(degrees) => {
                if degrees.is_finite() {
                    self.settings.environment_rotation = degrees;
                    self.controller.relight(&self.settings);
                }
            }
            Command::ShowEnvironmentDialog => self.show_dialog(DialogPurpose::Environment),
            Command::MoveCamera { orbit, pan, dolly } => {
                let Some(loaded) = self.controller.scene() else {
                    return;
                };
                let scene = &loaded.scene;
                let view = self
                    .view
                    .get_or_insert_with(|| Orbit::from_camera(&scene.camera, &scene.bounds));
                view.rotate(orbit[0], orbit[1]);
                view.pan(pan[0], pan[1]);
                view.dolly(dolly);
                let camera = view.camera();
                self.settings.view = Some((loaded.path.clone(), camera_to_json(&camera)));
                self.controller.set_camera(Some(camera));
                self.restart();
            }
            Command::ChooseCamera(choice) => {
                let Some(loaded) = self.controller.scene() else {
                    return;
                };
                let scene = &loaded.scene;
                let camera = match choice {
                    Some(i) => match scene.cameras.get(i) {
                        Some((_, camera)) => *camera,
                        None => return,
                    },
                    None => CameraDesc::framing(&scene.bounds),
                };
                self.view = Some(Orbit::from_camera(&camera, &scene.bounds));
                self.settings.view = Some((loaded.path.clone(), camera_to_json(&camera)));
                self.controller.set_camera(Some(camera));
                self.restart();
            }
            Command::ResetCamera => {
                self.view = None;
                self.settings.view = None;
                if self.controller.set_camera(None).is_some() {
                    self.restart();
                }
            }
            Command::UseRecommended => {
                let Some(r) = self
                    .controller
                    .scene()
                    .and_then(|s| s.recommendation().cloned())
                else {
                    return;
                };
                let mut params = ViewerSettings::defaults_of(r.integrator);
                params.extend(r.params.clone());
                self.settings.integrator = r.integrator.to_string();
                self.settings.params = params;
                self.restart();
            }
            Command::ShowOpenDialog => self.show_dialog(DialogPurpose::Scene),
            Command::ShowReferenceDialog => self.show_dialog(DialogPurpose::Reference),
            Command::LoadReference(path) => self.convergence.load_reference(path),
            Command::SetIntegrator(name) => {
                if integrators::find(&name).is_some() && name != self.settings.integrator {
                    self.settings.params = ViewerSettings::defaults_of(&name);
                    self.settings.integrator = name;
                    self.restart();
                }
            }
            Command::SetParam(name, value) => {
                let old = self.settings.params.insert(name.clone(), value);
                match self.controller.set_param(&self.settings, &name, value) {
                    Ok(ParamEffect::Live | ParamEffect::Restarted) => {}
                    Err(e) => {
                        match old {
                            Some(v) => self.settings.params.insert(name, v),
                            None => self.settings.params.remove(&name),
                        };
                        self.error(e);
                    }
                }
            }
            Command::SetResolution(w, h) => {
                let before = (self.settings.width, self.settings.height);
                self.settings.width = w.clamp(1, MAX_RESOLUTION);
                self.settings.height = h.clamp(1, MAX_RESOLUTION);
                // A size refused (too large for the memory) leaves the one that renders.
                if let Err(e) = self.controller.restart(&self.settings) {
                    (self.settings.width, self.settings.height) = before;
                    self.error(e);
                }
            }
            Command::SetThreads(t) => {
                self.settings.threads = t;
                self.restart();
            }
            Command::SetSeed(s) => {
                self.settings.seed = s;
                self.restart();
            }
            Command::TogglePause => {
                if let Some(f) = self.controller.frame() {
                    self.controller.set_paused(f.state != RunState::Paused);
                }
            }
            Command::Restart => self.restart(),
            Command::SetExposure(ev) => {
                self.settings.exposure = ev.clamp(-EXPOSURE_RANGE, EXPOSURE_RANGE);
                self.settings.auto_exposure = false;
                self.expose_next_frame = false;
            }
            Command::SetAutoExposure(on) => {
                self.settings.auto_exposure = on;
                self.expose_next_frame = on;
            }
            Command::SetToneCurve(c) => self.settings.tone_curve = c,
            Command::Fit => self.viewport.fit(),
            Command::OneToOne => {
                if let Some(f) = self.controller.frame() {
                    self.viewport
                        .one_to_one(1.0, egui::vec2(f.image.width as f32, f.image.height as f32));
                }
            }
            Command::SaveExr => self.save_snapshot(false),
            Command::SavePng => self.save_snapshot(true),
            Command::TogglePlots => self.settings.show_plots = !self.settings.show_plots,
            Command::ToggleReference => {
                if self.convergence.reference_image.is_some() {
                    self.show_reference = !self.show_reference;
                } else {
                    self.error("no reference to compare with: load one first");
                }
            }
            Command::ToggleErrorMap => {
                self.settings.show_error_map = !self.settings.show_error_map;
                self.error_map.clear();
            }
            Command::SceneLoaded(path) => {
                self.timings
                    .scene_loaded
                    .get_or_insert(self.started.elapsed());
                self.viewport.fit();
                self.expose_next_frame = self.settings.auto_exposure;
                self.restore_view(&path);
                self.info(format!("opened {}", path.display()));
                self.settings.remember_scene(path);
            }
            Command::SceneRelit => {
                if let Some(loaded) = self.controller.scene() {
                    let text = format!("environment: {}", loaded.scene.info.lighting);
                    self.info(text);
                }
            }
            Command::SceneFailed(e) => {
                // A failed relight leaves the scene lit as it was: say so in the panel too.
                if let Some(loaded) = self.controller.scene() {
                    self.settings.environment = loaded.lit_by.choice.clone();
                    self.settings.environment_strength = loaded.lit_by.strength;
                    self.settings.environment_rotation = loaded.lit_by.rotation;
                }
                self.error(e)
            }
            Command::RenderFailed(e) => self.error(format!(
                "{e}. The image so far is kept (Ctrl+S saves it); R restarts"
            )),
            Command::ExposeFrame(exposure) => {
                self.expose_next_frame = false;
                if exposure.is_finite() {
                    self.settings.exposure = exposure;
                }
            }
        }
    }

    /// The view saved for `path`, if any, replaces the scene's camera.
    fn restore_view(&mut self, path: &std::path::Path) {
        self.view = None;
        let saved = self.settings.view.clone();
        let Some((_, json)) = saved.filter(|(p, _)| p == path) else {
            return;
        };
        let (Ok(camera), Some(loaded)) = (camera_from_json(&json), self.controller.scene()) else {
            return;
        };
        self.view = Some(Orbit::from_camera(&camera, &loaded.scene.bounds));
        self.controller.set_camera(self.view.map(|v| v.camera()));
        if let Err(e) = self.controller.restart(&self.settings) {
            self.error(e);
        }
    }
}
