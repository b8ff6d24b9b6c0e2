//! The viewer application: UI state (settings, view, messages) on the UI thread, rendering
//! and loading in the background (`controller`), panels that return commands which `apply`
//! carries out. The UI thread never waits for the renderer.

use crate::metadata::{RunDescription, exr_metadata};
use crate::viewer::controller::{ControllerEvent, ParamEffect, RenderController};
use crate::viewer::convergence::Convergence;
use crate::viewer::error_map::ErrorMap;
use crate::viewer::panels::{self, PanelStatus};
use crate::viewer::plots;
use crate::viewer::settings::{STORAGE_KEY, ViewerSettings};
use crate::viewer::tonemap;
use crate::viewer::viewport::{HoveredPixel, Viewport};
use caustica_renderer::image::{ToneCurve, write_exr, write_png_tone_mapped};
use caustica_renderer::integrators;
use eframe::egui::{self, Key, KeyboardShortcut, Modifiers};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

/// Everything the user can ask for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    OpenScene(PathBuf),
    ShowOpenDialog,
    SetIntegrator(String),
    /// Switch to the integrator and parameters the scene's survey recommends.
    UseRecommended,
    SetParam(String, f64),
    SetResolution(u32, u32),
    SetThreads(usize),
    SetSeed(u64),
    TogglePause,
    Restart,
    SetExposure(f32),
    SetToneCurve(ToneCurve),
    Fit,
    OneToOne,
    SaveExr,
    SavePng,
    TogglePlots,
    ToggleErrorMap,
    ShowReferenceDialog,
    LoadReference(PathBuf),
}

/// What an open file dialog is choosing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DialogPurpose {
    Scene,
    Reference,
}

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
    /// Scripted run for tests: save a screenshot after some seconds of rendering, then quit.
    pub automation: Option<Automation>,
}

#[derive(Clone, Debug)]
pub struct Automation {
    pub screenshot: PathBuf,
    pub after: Duration,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub is_error: bool,
}

/// Timings the viewer measures about itself (shown in the panel, printed by automation).
#[derive(Clone, Debug, Default)]
pub struct ViewerTimings {
    pub first_frame_shown: Option<Duration>,
    pub ui_frames: u64,
    pub ui_fps: f32,
    window: (u64, Option<Instant>),
}

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
    pub timings: ViewerTimings,
    /// Show process readouts (memory, UI frame rate); snapshot tests turn them off because
    /// they change from run to run.
    pub show_process_stats: bool,
    saves: (
        Sender<Result<PathBuf, String>>,
        Receiver<Result<PathBuf, String>>,
    ),
    open_dialog: Option<(DialogPurpose, egui_file::FileDialog)>,
    sessions_seen: u64,
    automation: Option<Automation>,
    screenshot_requested: bool,
    started: Instant,
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
        let ctx = cc.egui_ctx.clone();
        let repaint: Arc<dyn Fn() + Send + Sync> = Arc::new(move || ctx.request_repaint());
        let mut app = ViewerApp {
            settings: settings.sanitized(),
            controller: RenderController::new(repaint.clone()),
            convergence: Convergence::new(repaint),
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

    fn info(&mut self, text: impl Into<String>) {
        self.messages.push(Message {
            text: text.into(),
            is_error: false,
        });
    }

    fn error(&mut self, text: impl Into<String>) {
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
            Command::OpenScene(path) => {
                self.controller
                    .open_scene(path, self.settings.width, self.settings.height)
            }
            Command::UseRecommended => {
                let Some(r) = self
                    .controller
                    .scene
                    .as_ref()
                    .map(|s| s.recommendation.clone())
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
                self.settings.width = w.clamp(1, 16384);
                self.settings.height = h.clamp(1, 16384);
                self.restart();
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
                    self.controller
                        .set_paused(f.state != caustica_renderer::session::RunState::Paused);
                }
            }
            Command::Restart => self.restart(),
            Command::SetExposure(ev) => self.settings.exposure = ev.clamp(-20.0, 20.0),
            Command::SetToneCurve(c) => self.settings.tone_curve = c,
            Command::Fit => self.viewport.fit(),
            Command::OneToOne => {
                if let Some(f) = self.controller.frame() {
                    self.viewport
                        .one_to_one(1.0, egui::vec2(f.image.width as f32, f.image.height as f32));
                }
            }
            Command::SaveExr => self.save(false),
            Command::SavePng => self.save(true),
            Command::TogglePlots => self.settings.show_plots = !self.settings.show_plots,
            Command::ToggleErrorMap => {
                self.settings.show_error_map = !self.settings.show_error_map;
                self.error_map.clear();
            }
        }
    }

    /// Default snapshot name: scene, integrator and UTC time.
    pub fn snapshot_path(&self, extension: &str) -> PathBuf {
        let scene = self
            .controller
            .scene
            .as_ref()
            .and_then(|s| s.path.file_stem())
            .map_or("render".to_string(), |s| s.to_string_lossy().into_owned());
        let time = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
            .to_string()
            .replace(':', "-");
        self.snapshot_dir.join(format!(
            "{scene}-{}-{time}.{extension}",
            self.settings.integrator
        ))
    }

    /// Writes the current estimate on a helper thread; the result comes back as a message.
    fn save(&mut self, png: bool) {
        let Some(frame) = self.controller.frame() else {
            self.error("nothing to save: no render is running");
            return;
        };
        let path = self.snapshot_path(if png { "png" } else { "exr" });
        let (exposure, curve) = (self.settings.exposure, self.settings.tone_curve);
        let scene = self
            .controller
            .scene
            .as_ref()
            .map(|s| s.path.clone())
            .unwrap_or_default();
        let session = self.controller.session();
        let metadata = exr_metadata(
            &RunDescription {
                integrator: &self.settings.integrator,
                params: session.map_or(&self.settings.params, |s| s.params()),
                seed: self.settings.seed,
                scene: &scene,
                threads: session.map_or(0, |s| s.threads()),
            },
            &frame,
        );
        let tx = self.saves.0.clone();
        std::thread::spawn(move || {
            let result = if png {
                write_png_tone_mapped(&path, &frame.image, exposure, curve)
            } else {
                write_exr(&path, &frame.image, &metadata)
            };
            let _ = tx.send(
                result
                    .map(|()| path)
                    .map_err(|e| format!("cannot save: {e}")),
            );
        });
    }

    /// Background results, dropped files and keyboard shortcuts.
    fn handle_input_and_events(&mut self, ctx: &egui::Context) {
        for event in self.controller.poll(&self.settings) {
            match event {
                ControllerEvent::SceneLoaded(path) => {
                    self.viewport.fit();
                    self.info(format!("opened {}", path.display()));
                    self.settings.remember_scene(path);
                }
                ControllerEvent::SceneFailed(e) => self.error(e),
            }
        }
        while let Ok(result) = self.saves.1.try_recv() {
            match result {
                Ok(path) => self.info(format!("saved {}", path.display())),
                Err(e) => self.error(e),
            }
        }
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(path) = dropped.into_iter().next() {
            self.apply(Command::OpenScene(path));
        }
        let shortcuts = [
            (
                KeyboardShortcut::new(Modifiers::COMMAND, Key::O),
                Command::ShowOpenDialog,
            ),
            (
                KeyboardShortcut::new(Modifiers::COMMAND, Key::S),
                Command::SaveExr,
            ),
        ];
        for (shortcut, command) in shortcuts {
            if ctx.input_mut(|i| i.consume_shortcut(&shortcut)) {
                self.apply(command);
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let keys = [
                (Key::Space, Command::TogglePause),
                (Key::R, Command::Restart),
                (Key::F, Command::Fit),
                (Key::Num1, Command::OneToOne),
                (Key::E, Command::ToggleErrorMap),
            ];
            for (key, command) in keys {
                if ctx.input(|i| i.key_pressed(key) && i.modifiers.is_none()) {
                    self.apply(command);
                }
            }
        }
    }

    fn show_dialog(&mut self, purpose: DialogPurpose) {
        let start = self
            .settings
            .recent_scenes
            .first()
            .and_then(|p| p.parent())
            .map(Path::to_path_buf);
        let filter: egui_file::Filter<PathBuf> = match purpose {
            DialogPurpose::Scene => {
                Box::new(|p: &Path| p.extension().is_some_and(|e| e == "gltf" || e == "glb"))
            }
            DialogPurpose::Reference => {
                Box::new(|p: &Path| p.extension().is_some_and(|e| e == "exr"))
            }
        };
        let mut dialog = egui_file::FileDialog::open_file().show_files_filter(filter);
        if let Some(start) = start {
            dialog = dialog.initial_path(start);
        }
        dialog.open();
        self.open_dialog = Some((purpose, dialog));
    }

    fn file_dialog(&mut self, ctx: &egui::Context) {
        let Some((purpose, dialog)) = &mut self.open_dialog else {
            return;
        };
        let purpose = *purpose;
        if dialog.show(ctx).selected() {
            if let Some(path) = dialog.path().map(Path::to_path_buf) {
                self.apply(match purpose {
                    DialogPurpose::Scene => Command::OpenScene(path),
                    DialogPurpose::Reference => Command::LoadReference(path),
                });
            }
            self.open_dialog = None;
        } else if !dialog.visible() {
            self.open_dialog = None;
        }
    }

    fn update_timings(&mut self) {
        let t = &mut self.timings;
        t.ui_frames += 1;
        let now = Instant::now();
        match t.window {
            (_, None) => t.window = (t.ui_frames, Some(now)),
            (start_frames, Some(start)) if now - start >= Duration::from_secs(1) => {
                t.ui_fps = (t.ui_frames - start_frames) as f32 / (now - start).as_secs_f32();
                t.window = (t.ui_frames, Some(now));
            }
            _ => {}
        }
        if t.first_frame_shown.is_none() && self.controller.frame().is_some_and(|f| f.passes > 0) {
            t.first_frame_shown = Some(self.started.elapsed());
        }
    }

    /// Scripted screenshot for the end-to-end test: eframe's own screenshot, saved as PNG,
    /// then the window closes.
    fn automate(&mut self, ctx: &egui::Context) {
        let Some(auto) = self.automation.clone() else {
            return;
        };
        let shown_for = self
            .timings
            .first_frame_shown
            .map(|t| self.started.elapsed().saturating_sub(t));
        if !self.screenshot_requested && shown_for.is_some_and(|d| d >= auto.after) {
            self.screenshot_requested = true;
            let t = self.timings.clone();
            let upload = self.viewport.last_upload.unwrap_or_default();
            let closer = ctx.clone();
            let callback = egui::ScreenshotCallback::new(move |image: Arc<egui::ColorImage>| {
                let [w, h] = image.size;
                let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                let result = ::image::RgbaImage::from_raw(w as u32, h as u32, rgba)
                    .ok_or_else(|| "bad screenshot".to_string())
                    .and_then(|img| img.save(&auto.screenshot).map_err(|e| e.to_string()));
                eprintln!(
                    "automation: screenshot {} ({result:?}); first frame shown after {:.2} s; {:.1} UI frames/s; last upload {:.2} ms",
                    auto.screenshot.display(),
                    t.first_frame_shown.unwrap_or_default().as_secs_f64(),
                    t.ui_fps,
                    upload.as_secs_f64() * 1e3
                );
                closer.send_viewport_cmd(egui::ViewportCommand::Close);
                closer.request_repaint();
            });
            ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(callback));
        }
        ctx.request_repaint_after(Duration::from_millis(50));
    }
}

/// Resident memory of this process (Linux), for the statistics panel.
pub fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.handle_input_and_events(&ctx);
        self.update_timings();
        let current = self.controller.frame();
        let mut commands = Vec::new();
        if self.controller.sessions_started != self.sessions_seen {
            self.sessions_seen = self.controller.sessions_started;
            self.convergence.reset();
            self.error_map.clear();
        }
        self.convergence.poll();
        if let Some(f) = &current
            && f.passes > 0
        {
            self.convergence.offer(&f.image, f.elapsed.as_secs_f64());
            if let Some(e) = f.error.as_ref() {
                self.convergence
                    .record_estimate(f.elapsed.as_secs_f64(), e.rel_mse);
            }
            if self.settings.show_error_map {
                self.error_map.update(&ctx, &f.error);
            }
        }

        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                if let Some(m) = self.messages.last() {
                    let color = if m.is_error { ui.visuals().error_fg_color } else { ui.visuals().text_color() };
                    ui.colored_label(color, &m.text);
                    if ui.small_button("x").clicked() {
                        self.messages.clear();
                    }
                } else {
                    ui.label("Space pause · R restart · Ctrl+O open · Ctrl+S save · F fit · 1 one-to-one");
                }
            });
        });
        egui::Panel::right("settings")
            .resizable(true)
            .default_size(300.0)
            .show(ui, |ui| {
                let status = PanelStatus {
                    scene: self
                        .controller
                        .scene
                        .as_ref()
                        .map(|s| (s.path.as_path(), &s.scene.info)),
                    recommendation: self.controller.scene.as_ref().map(|s| &s.recommendation),
                    loading: self.controller.loading(),
                    frame: current.as_deref(),
                    resident_bytes: if self.show_process_stats {
                        resident_bytes()
                    } else {
                        None
                    },
                };
                commands = panels::side_panel(ui, &self.settings, &status);
                if self.show_process_stats {
                    ui.label(format!("UI {:.0} frames/s", self.timings.ui_fps));
                }
            });
        if self.settings.show_plots {
            egui::Panel::bottom("plots")
                .resizable(true)
                .default_size(200.0)
                .show(ui, |ui| {
                    let integrator_plots = current
                        .as_ref()
                        .map(|f| f.plots.clone())
                        .unwrap_or_default();
                    commands.extend(plots::plots_panel(ui, &self.convergence, &integrator_plots));
                });
        }
        egui::CentralPanel::default().show(ui, |ui| {
            let image = current.as_ref().map(|f| &f.image);
            let layers = current
                .as_ref()
                .map(|f| f.pixel_layers.clone())
                .unwrap_or_default();
            let error = current.as_ref().and_then(|f| f.error.as_ref().as_ref());
            let overlay = self
                .settings
                .show_error_map
                .then(|| self.error_map.texture())
                .flatten();
            self.hovered = self.viewport.show(
                ui,
                frame.wgpu_render_state(),
                image,
                &layers,
                error,
                overlay,
                self.settings.exposure,
                self.settings.tone_curve,
            );
        });
        for c in commands {
            self.apply(c);
        }
        self.file_dialog(&ctx);
        self.automate(&ctx);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, STORAGE_KEY, &self.settings);
    }
}
