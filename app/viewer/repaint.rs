//! How often the render's progress redraws the window. A redraw costs a UI frame on the same
//! cores the render uses. On a GPU that is a millisecond, and progress redraws up to 30 times
//! a second. With software rendering (lavapipe, llvmpipe) a frame of a 1280 x 800 window
//! costs some 40 to 50 ms of CPU on a two-core machine (the rasteriser's threads, the UI
//! thread and the X server's copy, measured per thread), so progress redraws twice a second
//! there, which keeps the UI's share of the cores near a twentieth. A frame that comes after a quiet spell (the first image of a new
//! render) redraws at once, and input redraws at once, as egui always does.

use eframe::egui;
use std::sync::Mutex;
use std::time::{Duration, Instant};

pub struct ProgressRepaint {
    ctx: egui::Context,
    interval: Duration,
    /// When the UI last drew a frame.
    last_frame: Mutex<Instant>,
}

impl ProgressRepaint {
    /// `software`: the window is drawn on the CPU.
    pub fn new(ctx: egui::Context, software: bool) -> Self {
        ProgressRepaint {
            ctx,
            interval: Duration::from_millis(if software { 500 } else { 33 }),
            last_frame: Mutex::new(Instant::now()),
        }
    }

    /// A new frame of the render is ready (called on the session's thread).
    pub fn request(&self) {
        let last = *self.last_frame.lock().unwrap_or_else(|e| e.into_inner());
        let due = (last + self.interval).saturating_duration_since(Instant::now());
        self.ctx.request_repaint_after(due);
    }

    /// The UI drew a frame.
    pub fn record_frame(&self) {
        *self.last_frame.lock().unwrap_or_else(|e| e.into_inner()) = Instant::now();
    }

    pub fn interval(&self) -> Duration {
        self.interval
    }
}
