//! What the viewer measures about itself (time to the first frame, UI frame rate, resident
//! memory) and the scripted run of the end-to-end test: a screenshot after some seconds of
//! rendering, then quit.

use crate::viewer::ViewerApp;
use caustica_renderer::image::write_png_tone_mapped;
use eframe::egui;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A scripted run: save a screenshot of the window to `screenshot` once the render has been
/// shown for `after`, then close. Beside it go the image that was on screen, tone-mapped as
/// shown (`NAME.frame.png`), and `NAME.json`: where on the screenshot that image was
/// (`image_rect`, in pixels), the time to the first frame and the UI frame rate, so a test
/// can check that the window shows the render and how fluidly.
#[derive(Clone, Debug)]
pub struct Automation {
    pub screenshot: PathBuf,
    pub after: Duration,
    /// Redraw continuously, as while the user drags a slider, to measure the UI frame rate
    /// the render leaves (otherwise progress redraws are paced, see `repaint`).
    pub continuous: bool,
}

/// Timings the viewer measures about itself (shown in the panel, printed by automation).
#[derive(Clone, Debug, Default)]
pub struct ViewerTimings {
    /// From launch to the first scene's load (as the UI learns of it), to the first image of
    /// the scene (the preview, or a pass if that came first) and to the first pass of the
    /// integrator.
    pub scene_loaded: Option<Duration>,
    pub first_frame_shown: Option<Duration>,
    pub first_pass_shown: Option<Duration>,
    pub ui_frames: u64,
    /// Over the last second or so (the panel's figure).
    pub ui_fps: f32,
    /// UI frames counted when the first image was shown, for the mean rate since then.
    frames_at_first_frame: u64,
    /// The render's samples and elapsed time in the first pass shown, so the render's rate
    /// can be measured in its steady state, from there on (start-up excluded), and the CPU
    /// time the process's threads had used by then.
    first_pass_progress: Option<(u64, Duration)>,
    first_pass_cpu: Option<(Instant, CpuTicks)>,
    /// Mean cost of the UI frames (eframe's `cpu_usage`), in seconds.
    pub ui_frame_cost: f32,
    window: (u64, Option<Instant>),
}

impl ViewerApp {
    /// Counts a UI frame; `cost` is what the one before cost (eframe's `cpu_usage`). A frame
    /// whose layout egui runs twice (a discarded first pass) is counted once.
    pub(super) fn update_timings(&mut self, ctx: &egui::Context, cost: f32) {
        if ctx.current_pass_index() > 0 {
            return;
        }
        let t = &mut self.timings;
        t.ui_frames += 1;
        // An exponential mean over the last ten frames or so.
        t.ui_frame_cost += (cost - t.ui_frame_cost) * if t.ui_frames <= 2 { 1.0 } else { 0.1 };
        let now = Instant::now();
        match t.window {
            (_, None) => t.window = (t.ui_frames, Some(now)),
            (start_frames, Some(start)) if now - start >= Duration::from_secs(1) => {
                t.ui_fps = (t.ui_frames - start_frames) as f32 / (now - start).as_secs_f32();
                t.window = (t.ui_frames, Some(now));
            }
            _ => {}
        }
        let frame = self.controller.frame();
        if t.first_frame_shown.is_none()
            && frame
                .as_ref()
                .is_some_and(|f| f.passes > 0 || f.preview || f.preparation.is_some())
        {
            t.first_frame_shown = Some(self.started.elapsed());
            t.frames_at_first_frame = t.ui_frames;
        }
        if t.first_pass_shown.is_none()
            && let Some(f) = frame.filter(|f| f.passes > 0)
        {
            t.first_pass_shown = Some(self.started.elapsed());
            t.first_pass_progress = Some((f.samples, f.elapsed));
            t.first_pass_cpu = CpuTicks::now().map(|c| (Instant::now(), c));
        }
    }

    /// Scripted screenshot for the end-to-end test: eframe's own screenshot, saved as PNG,
    /// then the window closes.
    pub(super) fn automate(&mut self, ctx: &egui::Context) {
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
            // The mean UI frame rate while the render was shown (steadier than the last second).
            let ui_fps = (t.ui_frames - t.frames_at_first_frame) as f64
                / shown_for.unwrap_or_default().as_secs_f64().max(1e-9);
            let upload = self.viewport.last_upload.unwrap_or_default();
            let shown = self.viewport.shown.clone();
            let (exposure, curve) = (self.settings.exposure, self.settings.tone_curve);
            let pixels_per_point = ctx.pixels_per_point();
            let interval = self.progress.interval();
            let current = self.controller.frame();
            let rendered = current.as_ref().map(|f| (f.passes, f.samples, f.elapsed));
            let steady_rate = current
                .zip(t.first_pass_progress)
                .and_then(|(f, first)| f.samples_per_second_since(first));
            let ui_cpu_share = t
                .first_pass_cpu
                .as_ref()
                .zip(CpuTicks::now())
                .map(|((then, before), now)| now.ui_share_since(before, then.elapsed()));
            let closer = ctx.clone();
            let callback = egui::ScreenshotCallback::new(move |image: Arc<egui::ColorImage>| {
                let [w, h] = image.size;
                let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                let result = ::image::RgbaImage::from_raw(w as u32, h as u32, rgba)
                    .ok_or_else(|| "bad screenshot".to_string())
                    .and_then(|img| img.save(&auto.screenshot).map_err(|e| e.to_string()))
                    .and_then(|()| {
                        let rect = shown.as_ref().map(|(r, _)| {
                            [r.min.x, r.min.y, r.max.x, r.max.y].map(|v| v * pixels_per_point)
                        });
                        let record = serde_json::json!({
                            "window": [w, h],
                            "image_rect": rect,
                            "scene_loaded_seconds": t.scene_loaded.map(|d| d.as_secs_f64()),
                            "first_frame_seconds": t.first_frame_shown.map(|d| d.as_secs_f64()),
                            "first_pass_seconds": t.first_pass_shown.map(|d| d.as_secs_f64()),
                            "ui_fps": ui_fps,
                            "ui_frame_ms": t.ui_frame_cost * 1e3,
                            "progress_interval_ms": interval.as_secs_f64() * 1e3,
                            "passes": rendered.map(|r| r.0),
                            "samples_per_second": rendered.map(|r| r.1 as f64 / r.2.as_secs_f64().max(1e-9)),
                            "steady_samples_per_second": steady_rate,
                            "ui_cpu_share": ui_cpu_share,
                        });
                        let json = auto.screenshot.with_extension("json");
                        std::fs::write(&json, record.to_string()).map_err(|e| e.to_string())?;
                        match &shown {
                            Some((_, frame)) => write_png_tone_mapped(
                                &auto.screenshot.with_extension("frame.png"),
                                frame,
                                exposure,
                                curve,
                            )
                            .map_err(|e| e.to_string()),
                            None => Ok(()),
                        }
                    });
                eprintln!(
                    "automation: screenshot {} ({result:?}); first frame shown after {:.2} s, first pass after {:.2} s; {:.1} UI frames/s; last upload {:.2} ms",
                    auto.screenshot.display(),
                    t.first_frame_shown.unwrap_or_default().as_secs_f64(),
                    t.first_pass_shown.unwrap_or_default().as_secs_f64(),
                    ui_fps,
                    upload.as_secs_f64() * 1e3
                );
                closer.send_viewport_cmd(egui::ViewportCommand::Close);
                closer.request_repaint();
            });
            ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(callback));
        }
        // Wake for the screenshot; redraw every frame when measuring the UI under interaction.
        if auto.continuous {
            ctx.request_repaint();
        } else if let Some(shown) = shown_for {
            ctx.request_repaint_after(auto.after.saturating_sub(shown));
        }
    }
}

/// CPU time used so far by this process's threads (Linux), split into the render's (its
/// workers and session thread) and everything else: the UI thread, the software rasteriser's
/// threads (llvmpipe runs in the process), the convergence thread. In clock ticks.
#[derive(Clone, Copy, Debug)]
pub struct CpuTicks {
    render: u64,
    other: u64,
}

impl CpuTicks {
    pub fn now() -> Option<CpuTicks> {
        let mut ticks = CpuTicks {
            render: 0,
            other: 0,
        };
        for task in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
            let comm = std::fs::read_to_string(task.path().join("comm")).unwrap_or_default();
            let stat = std::fs::read_to_string(task.path().join("stat")).unwrap_or_default();
            // utime and stime are fields 14 and 15; the name in parentheses may hold spaces.
            let after_name = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
            let fields: Vec<&str> = after_name.split_whitespace().collect();
            let used: u64 = fields
                .get(11..13)
                .map_or(0, |f| f.iter().filter_map(|v| v.parse::<u64>().ok()).sum());
            if comm.starts_with("caustica-worker") || comm.starts_with("caustica-sessio") {
                ticks.render += used;
            } else {
                ticks.other += used;
            }
        }
        Some(ticks)
    }

    /// The share of all cores the threads other than the render's used since `before`,
    /// `elapsed` ago (100 clock ticks a second, as Linux reports them to processes).
    pub fn ui_share_since(&self, before: &CpuTicks, elapsed: Duration) -> f64 {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let used = self.other.saturating_sub(before.other) as f64 / 100.0;
        used / (cores * elapsed.as_secs_f64()).max(1e-9)
    }
}
