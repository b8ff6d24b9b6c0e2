//! The viewer's frame: background events and keyboard input become commands, then the
//! panels are laid out (status bar, settings, plots, the image) and the commands they return
//! are applied. State and its changes live in `state.rs`.

use crate::viewer::ViewerApp;
use crate::viewer::command::Command;
use crate::viewer::panels::{self, PanelStatus};
use crate::viewer::plots;
use crate::viewer::settings::STORAGE_KEY;
use caustica_renderer::exposure::auto_exposure;
use caustica_renderer::process::resident_bytes;
use caustica_renderer::session::Frame;
use eframe::egui::{self, Color32, Key, KeyboardShortcut, Modifiers, RichText};
use std::path::PathBuf;

/// Square widget corners, for a window drawn by a software rasteriser. epaint fills a rounded
/// rectangle as a fan of thin triangles from one corner, and llvmpipe shades every 4 x 4 block
/// a triangle touches, each time with egui's costly shader (see `App::clear_color`): the
/// rounded backgrounds of the side panel's widgets cost 6 ms of CPU a frame (measured, 1280 x
/// 800 window), a sixth of the frame; square ones are two triangles each.
pub(super) fn square_corners(ctx: &egui::Context) {
    ctx.all_styles_mut(|style| {
        let v = &mut style.visuals;
        for w in [
            &mut v.widgets.noninteractive,
            &mut v.widgets.inactive,
            &mut v.widgets.hovered,
            &mut v.widgets.active,
            &mut v.widgets.open,
        ] {
            w.corner_radius = egui::CornerRadius::ZERO;
        }
        v.menu_corner_radius = egui::CornerRadius::ZERO;
        v.window_corner_radius = egui::CornerRadius::ZERO;
        // A shadow is a rectangle feathered over its blur width: a wide band of slivers.
        v.popup_shadow = egui::Shadow::NONE;
        v.window_shadow = egui::Shadow::NONE;
    });
}

/// How far an arrow key turns the camera (radians), and a Page key's dolly factor.
const KEY_TURN: f32 = std::f32::consts::PI / 12.0;
const KEY_DOLLY: f32 = 1.25;
/// Radians of orbit for a drag across the whole height of the view.
const DRAG_TURN: f32 = std::f32::consts::PI;

fn turn(yaw: f32, pitch: f32) -> Command {
    Command::MoveCamera {
        orbit: [yaw, pitch],
        pan: [0.0; 2],
        dolly: 1.0,
    }
}

fn dolly(factor: f32) -> Command {
    Command::MoveCamera {
        orbit: [0.0; 2],
        pan: [0.0; 2],
        dolly: factor,
    }
}

impl ViewerApp {
    /// The camera gestures on the image as one move (the scene follows the mouse: dragging
    /// right turns it to the right, Blender's convention), once per UI frame so a drag
    /// restarts the render at most once a frame, each restart showing the quick preview.
    fn move_camera_by_gestures(&mut self) {
        let g = self.viewport.take_gesture();
        if g.is_empty() {
            return;
        }
        self.apply(Command::MoveCamera {
            orbit: [-g.orbit.x * DRAG_TURN, -g.orbit.y * DRAG_TURN],
            pan: [-g.pan.x, g.pan.y],
            dolly: (-g.dolly * 0.002).exp(),
        });
    }

    /// Background results, dropped files and keyboard shortcuts.
    fn handle_input_and_events(&mut self, ctx: &egui::Context) {
        let mut commands: Vec<Command> = self
            .controller
            .poll(&self.settings)
            .into_iter()
            .map(Command::from)
            .collect();
        self.poll_saves();
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(path) = dropped.into_iter().next() {
            commands.push(Command::OpenScene(path));
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
                commands.push(command);
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let keys = [
                (Key::Space, Command::TogglePause),
                (Key::R, Command::Restart),
                (Key::F, Command::Fit),
                (Key::Num1, Command::OneToOne),
                (Key::E, Command::ToggleErrorMap),
                (Key::C, Command::ToggleReference),
                (Key::Home, Command::ResetCamera),
                (Key::ArrowLeft, turn(KEY_TURN, 0.0)),
                (Key::ArrowRight, turn(-KEY_TURN, 0.0)),
                (Key::ArrowUp, turn(0.0, -KEY_TURN)),
                (Key::ArrowDown, turn(0.0, KEY_TURN)),
                (Key::PageUp, dolly(1.0 / KEY_DOLLY)),
                (Key::PageDown, dolly(KEY_DOLLY)),
            ];
            for (key, command) in keys {
                if ctx.input(|i| i.key_pressed(key) && i.modifiers.is_none()) {
                    commands.push(command);
                }
            }
        }
        for command in commands {
            self.apply(command);
        }
    }
}

impl ViewerApp {
    /// Follows the newest frame: a new session clears the plots and the heat map; the frame
    /// feeds the convergence plot (true error against the reference, estimated error).
    fn track_frame(&mut self, ctx: &egui::Context, current: Option<&Frame>) {
        if self.controller.sessions_started() != self.sessions_seen {
            self.sessions_seen = self.controller.sessions_started();
            self.convergence.reset();
            self.error_map.clear();
        }
        self.convergence.poll();
        if let Some(f) = current
            && f.passes > 0
        {
            if self.expose_next_frame {
                self.apply(Command::ExposeFrame(auto_exposure(&f.image)));
            }
            self.convergence.offer(&f.image, f.elapsed.as_secs_f64());
            if let Some(e) = f.error.as_ref() {
                self.convergence
                    .record_estimate(f.elapsed.as_secs_f64(), e.rel_mse);
            }
            if self.settings.show_error_map {
                match &self.convergence.true_error {
                    Some(truth) => self.error_map.show_true_error(ctx, truth),
                    None => self.error_map.show_estimate(ctx, &f.error),
                }
            }
        }
    }

    /// The last message (errors in the error colour), else the keyboard shortcuts.
    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if let Some(m) = self.messages.last() {
                let color = if m.is_error {
                    ui.visuals().error_fg_color
                } else {
                    ui.visuals().text_color()
                };
                ui.colored_label(color, &m.text);
                if ui.small_button("x").clicked() {
                    self.messages.clear();
                }
            } else {
                ui.label(
                    "Space pause · R restart · Ctrl+O open · Ctrl+S save · F fit · 1 one-to-one · E error map · C reference · right drag orbit · Home camera",
                );
            }
        });
    }

    fn settings_panel(&self, ui: &mut egui::Ui, current: Option<&Frame>) -> Vec<Command> {
        let scene = self.controller.scene();
        let status = PanelStatus {
            scene: scene.map(|s| (s.path.as_path(), &s.scene.info)),
            recommendation: scene.and_then(|s| s.recommendation()),
            loading: self.controller.loading(),
            frame: current,
            resident_bytes: self.show_process_stats.then(resident_bytes).flatten(),
            threads: self.controller.session().map(|s| s.threads()),
            camera_moved: self.view.is_some(),
            cameras: scene.map_or(&[], |s| s.scene.cameras.as_slice()),
        };
        // In a short window the panel scrolls rather than cutting its statistics off.
        egui::ScrollArea::vertical()
            .show(ui, |ui| {
                let commands = panels::side_panel(ui, &self.settings, &status);
                if self.show_process_stats {
                    let t = &self.timings;
                    ui.label(format!(
                        "UI {:.0} frames/s, {:.0} ms a frame on its thread",
                        t.ui_fps,
                        t.ui_frame_cost * 1e3
                    ));
                }
                commands
            })
            .inner
    }

    /// The image, with the error heat map over it when it is on; sets the hovered pixel.
    fn image_view(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame, current: Option<&Frame>) {
        let layers = current.map(|f| f.pixel_layers.clone()).unwrap_or_default();
        let title = if self.error_map.shows_true_error() {
            "relMSE per pixel against the reference"
        } else {
            "estimated relMSE per pixel"
        };
        let overlay = self
            .settings
            .show_error_map
            .then(|| self.error_map.texture().map(|t| (t, title)))
            .flatten();
        // C flips to the reference (same size), as tev does.
        let reference = self.convergence.reference_image.as_ref().filter(|r| {
            current.is_some_and(|f| (f.image.width, f.image.height) == (r.width, r.height))
        });
        let shown = match (self.show_reference, reference) {
            (true, Some(r)) => Some(r),
            _ => current.map(|f| &f.image),
        };
        self.hovered = self.viewport.show(
            ui,
            frame.wgpu_render_state(),
            shown,
            &layers,
            current.and_then(|f| f.error.as_ref().as_ref()),
            overlay,
            self.settings.exposure,
            self.settings.tone_curve,
        );
        if self.show_reference && reference.is_some() {
            let corner = ui.max_rect().right_top() + egui::vec2(-250.0, 8.0);
            let text = RichText::new("reference (C: back to the render)")
                .color(ui.visuals().warn_fg_color);
            ui.put(
                egui::Rect::from_min_size(corner, egui::vec2(240.0, 20.0)),
                egui::Label::new(text),
            );
        }
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let cost = frame.info().cpu_usage.unwrap_or_default();
        self.progress.record_frame();
        self.handle_input_and_events(&ctx);
        self.update_timings(&ctx, cost);
        let current = self.controller.frame();
        let current = current.as_deref();
        self.track_frame(&ctx, current);

        let mut commands = Vec::new();
        let panel_frame = egui::Frame::side_top_panel(ui.style()).fill(Color32::TRANSPARENT);
        egui::Panel::bottom("status")
            .frame(panel_frame)
            .show(ui, |ui| self.status_bar(ui));
        egui::Panel::right("settings")
            .frame(panel_frame)
            .resizable(true)
            .default_size(300.0)
            .show(ui, |ui| commands = self.settings_panel(ui, current));
        if self.settings.show_plots {
            // A quarter of the window at first, resizable (egui remembers the size with the
            // window's state), and never more than half: the image keeps most of the window.
            let window_height = ui.max_rect().height();
            egui::Panel::bottom("plots")
                .frame(panel_frame)
                .resizable(true)
                .default_size(0.25 * window_height)
                .size_range(80.0..=(0.5 * window_height).max(80.0))
                .show(ui, |ui| {
                    let integrator_plots = current.map(|f| f.plots.clone()).unwrap_or_default();
                    commands.extend(plots::plots_panel(ui, &self.convergence, &integrator_plots));
                });
        }
        egui::CentralPanel::default()
            .frame(egui::Frame::central_panel(ui.style()).fill(Color32::TRANSPARENT))
            .show(ui, |ui| self.image_view(ui, frame, current));
        for c in commands {
            self.apply(c);
        }
        self.move_camera_by_gestures();
        self.file_dialog(&ctx);
        self.automate(&ctx);
    }

    /// The panels' background, as the render pass's clear, and the panels have transparent
    /// frames. Why: with software rendering (lavapipe, llvmpipe: what a machine without a GPU
    /// runs) a UI frame costs the pixels egui's fragment shader fills. That shader holds a
    /// hardware-filtered and a hand-filtered texture path behind a uniform branch, and
    /// llvmpipe's SIMD code runs both: about 40 ns of wall time per filled pixel on two cores,
    /// so the panel fills of a 1280 x 800 window cost some 40 ms a frame, while the clear is
    /// a memset. egui then shades only widgets, text and plots.
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        visuals.panel_fill.to_normalized_gamma_f32()
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, STORAGE_KEY, &self.settings);
    }
}
