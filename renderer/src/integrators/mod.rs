//! Integrators: the progressive `Integrator` trait every estimator implements, what it is
//! given to start (`RenderContext`) and what it reports (pass counters, plots, per-pixel
//! layers). The registry (`registry.rs`) lists them; each describes its parameters once
//! (`params.rs`: name, documentation, default, range, whether it can change while running),
//! and the command line, the viewer and the EXR header all read that one description
//! (DESIGN.md section 7).

pub mod bdpt;
pub mod kernel_bias;
pub mod mmlt;
pub mod params;
pub mod path_tracer;
pub mod pixel_pass;
pub mod ppm;
pub mod registry;
pub(crate) mod scatter;
pub mod vcm;
pub mod visibility_chain;

pub use params::{
    ParamSpec, ParamValues, check_live_change, check_param, param_value, params_json,
    resolve_params,
};
pub use registry::{IntegratorInfo, find, registry};
pub(crate) use scatter::scatter;

use crate::camera::Camera;
use crate::error_estimate::ErrorEstimate;
use crate::image::Image;
use crate::scene::Scene;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// What an integrator needs to start: the scene, the camera at the output resolution, the seed.
#[derive(Clone)]
pub struct RenderContext {
    pub scene: Arc<Scene>,
    pub camera: Camera,
    pub seed: u64,
}

/// Counters of one pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassStats {
    pub samples: u64,
    pub rays: u64,
    /// Estimates that were NaN, infinite or negative and were dropped at their source.
    pub dropped: u64,
}

impl std::ops::Add for PassStats {
    type Output = PassStats;
    fn add(self, o: PassStats) -> PassStats {
        PassStats {
            samples: self.samples + o.samples,
            rays: self.rays + o.rays,
            dropped: self.dropped + o.dropped,
        }
    }
}

/// A pass stopped by cancellation; nothing of it reached the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// A progressive integrator: runs pass after pass (each on the caller's rayon pool) and can
/// give its current estimate at any time.
pub trait Integrator: Send {
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled>;
    /// Bytes of the integrator's own buffers (films, hit points and their grid, chains),
    /// counting a pass's temporary buffers at their largest; the scene's are `Scene::memory`.
    fn memory_bytes(&self) -> usize;
    /// While the integrator prepares before its first pass (MMLT's bootstrap), the share of
    /// the preparation done: `render_pass` then takes one preparation step, which the session
    /// shows (`image` is already an estimate) but does not count as a pass.
    fn preparing(&self) -> Option<f32> {
        None
    }
    /// One pass as the session counts it: whatever preparation is left, then the pass (for
    /// callers that want passes, not the preparation's steps, such as tests).
    fn render_counted_pass(
        &mut self,
        pass: u64,
        cancel: &AtomicBool,
    ) -> Result<PassStats, Cancelled> {
        let mut stats = PassStats::default();
        while self.preparing().is_some() {
            stats = stats + self.render_pass(pass, cancel)?;
        }
        Ok(stats + self.render_pass(pass, cancel)?)
    }
    /// The current normalised estimate.
    fn image(&self) -> Image;
    /// Applies a change of a live parameter, already checked by `check_live_change` (the
    /// session calls it between passes; it never sees a name or value that failed).
    fn set_live_param(&mut self, _name: &str, _value: f64) {}
    /// Plots of the integrator's own statistics (radius against passes, technique histograms).
    fn plots(&self) -> Vec<PlotSeries> {
        Vec::new()
    }
    /// Per-pixel statistics for the pixel inspector (photon count, radius, ...).
    fn pixel_layers(&self) -> Vec<PixelLayer> {
        Vec::new()
    }
    /// Warnings about the current state or parameters, for the user.
    fn messages(&self) -> Vec<String> {
        Vec::new()
    }
    /// The values it chose for parameters given as 0 where 0 means automatic
    /// (`ParamSpec::zero_is_automatic`), by name, for the user to see.
    fn automatic(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// Statistics worth saving beside the image (`caustica render --stats`).
    fn statistics(&self) -> Option<serde_json::Value> {
        None
    }
    /// The remaining error of `image()` estimated from the integrator's own samples (see
    /// `error_estimate`); None while there is too little to estimate it from.
    fn error_estimate(&self) -> Option<ErrorEstimate> {
        None
    }
}

/// How a plot series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotKind {
    Line,
    Bars,
}

/// One series of a plot an integrator offers; series with the same `plot` share axes.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSeries {
    pub plot: String,
    pub name: String,
    pub kind: PlotKind,
    pub x_label: String,
    pub y_label: String,
    pub points: Vec<[f64; 2]>,
    /// A name for each point (bars: MMLT's technique "s = 1, t = 3"), or none.
    pub point_names: Vec<String>,
}

/// A named per-pixel value (row-major, the image's size).
#[derive(Clone, Debug, PartialEq)]
pub struct PixelLayer {
    pub name: String,
    pub values: Vec<f64>,
}
