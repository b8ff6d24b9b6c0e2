//! What a session publishes after every pass: a `Frame`, the normalised estimate with its
//! counters, statistics and error estimate, and the `RunState` it was in.

use crate::error_estimate::ErrorEstimate;
use crate::image::Image;
use crate::integrators::{PixelLayer, PlotSeries};
use std::sync::Arc;
use std::time::Duration;

/// Where a session's run stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunState {
    Running,
    Paused,
    /// Reached its pass or time limit, or its target error.
    Finished,
    Cancelled,
    /// A pass panicked (`Frame::failure` says where and why); the image is that of the
    /// passes before it, and a new session starts afresh.
    Failed,
}

/// A snapshot of a session: the normalised estimate and its counters.
#[derive(Clone, Debug)]
pub struct Frame {
    pub image: Arc<Image>,
    /// Plots the integrator offers (drawn by the viewer beside the convergence plot).
    pub plots: Arc<Vec<PlotSeries>>,
    /// Per-pixel statistics of the integrator (shown by the viewer's pixel inspector).
    pub pixel_layers: Arc<Vec<PixelLayer>>,
    /// Warnings and notes of the integrator about its current state (shown to the user).
    pub messages: Arc<Vec<String>>,
    /// The integrator's statistics as JSON, if it keeps any (MMLT's technique histogram).
    pub statistics: Arc<Option<serde_json::Value>>,
    /// The values the integrator chose for parameters left automatic (`Integrator::automatic`).
    pub automatic: Arc<Vec<(&'static str, f64)>>,
    /// Bytes of the integrator's own buffers (`Integrator::memory_bytes`).
    pub integrator_memory_bytes: usize,
    /// The image's remaining error estimated without a reference (None until the integrator
    /// has enough samples to estimate it). Renewed after every pass where that costs little,
    /// else as often as it costs a tenth of the time, and at least whenever the passes have
    /// grown by a tenth (so it may be a few passes old), and always for a run's last frame.
    pub error: Arc<Option<ErrorEstimate>>,
    pub passes: u64,
    pub samples: u64,
    pub rays: u64,
    pub dropped: u64,
    pub elapsed: Duration,
    pub state: RunState,
    /// The image is the quick, coarse look at the scene shown until the first pass ends
    /// (`preview`), not the integrator's estimate.
    pub preview: bool,
    /// While the integrator prepares (MMLT's bootstrap), the share done; its image is then
    /// already an estimate, but no pass is counted yet.
    pub preparation: Option<f32>,
    /// Why the session failed, when `state` is `Failed`.
    pub failure: Option<Arc<str>>,
}

impl Frame {
    /// Samples per second from an earlier frame's `(samples, elapsed)` to this one: the
    /// render's steady rate when the earlier frame is the first pass (start-up excluded).
    pub fn samples_per_second_since(&self, (samples, elapsed): (u64, Duration)) -> Option<f64> {
        let seconds = self.elapsed.saturating_sub(elapsed).as_secs_f64();
        (seconds > 0.0).then(|| self.samples.saturating_sub(samples) as f64 / seconds)
    }
}
