//! Integrators and their registry. Every integrator describes its parameters once (name,
//! documentation, default, range, whether it can change while running); the command line,
//! the viewer and the EXR header all read that one description (DESIGN.md section 7).

pub mod bdpt;
pub mod mmlt;
pub mod path;
pub mod ppm;

use crate::camera::PerspectiveCamera;
use crate::error_estimate::ErrorEstimate;
use crate::geometry::Ray;
use crate::image::Image;
use crate::material::{Bsdf, BsdfSample, TransportMode};
use crate::sampling::sampler::SampleSource;
use crate::scene::Scene;
use crate::scene::SurfaceInteraction;
use glam::Vec3;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The next segment of a path leaving `si`: the BSDF sample, its throughput factor
/// f |cos| / pdf, and the spawned ray.
pub(crate) struct Scatter {
    pub sample: BsdfSample,
    pub weight: Vec3,
    pub ray: Ray,
}

/// Samples the BSDF for the next direction of a path (camera paths in radiance mode, photons
/// in importance mode). None ends the path: no sample, or a direction the geometric surface
/// contradicts (`SurfaceInteraction::consistent`), which would leak light.
pub(crate) fn scatter(
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    wo: Vec3,
    sampler: &mut impl SampleSource,
    mode: TransportMode,
) -> Option<Scatter> {
    let uc = sampler.get_1d();
    let u = sampler.get_2d();
    let sample = bsdf.sample_f(wo, uc, u, mode)?;
    let wi = si.shading.from_local(sample.wi).normalize();
    if !si.consistent(wo, sample.wi, wi) {
        return None;
    }
    let weight = match mode {
        TransportMode::Radiance => sample.f * sample.wi.z.abs() / sample.pdf,
        // Importance flows the other way, and with shading normals the adjoint BSDF is not f:
        // f*(wo, wi) |wi.ns| = f(wo, wi) |wo.ns| |wi.ng| / |wo.ng| (Veach 1997, eq. 5.19),
        // without which photons and light subpaths gain or lose energy wherever interpolated
        // normals depart from the faces.
        TransportMode::Importance => {
            let wo_ng = si.wo.dot(si.n).abs();
            if wo_ng == 0.0 {
                return None;
            }
            sample.f * (wo.z.abs() * wi.dot(si.n).abs() / wo_ng) / sample.pdf
        }
    };
    Some(Scatter {
        weight,
        ray: si.spawn_ray(wi),
        sample,
    })
}

/// One parameter of an integrator.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub doc: &'static str,
    pub default: f64,
    pub min: f64,
    pub max: f64,
    pub integer: bool,
    /// Changes apply to the passes still to come without a restart.
    pub live: bool,
}

pub type ParamValues = BTreeMap<String, f64>;

/// What an integrator needs to start: the scene, the camera at the output resolution, the seed.
#[derive(Clone)]
pub struct RenderContext {
    pub scene: Arc<Scene>,
    pub camera: PerspectiveCamera,
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
    /// The current normalised estimate.
    fn image(&self) -> Image;
    /// Applies a live parameter; false if the name is not live for this integrator.
    fn set_live_param(&mut self, name: &str, value: f64) -> bool;
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
}

/// A named per-pixel value (row-major, the image's size).
#[derive(Clone, Debug, PartialEq)]
pub struct PixelLayer {
    pub name: String,
    pub values: Vec<f64>,
}

pub struct IntegratorInfo {
    pub name: &'static str,
    pub title: &'static str,
    pub description: &'static str,
    pub params: &'static [ParamSpec],
    pub create: fn(RenderContext, &ParamValues) -> Box<dyn Integrator>,
}

static REGISTRY: &[IntegratorInfo] = &[
    IntegratorInfo {
        name: "pt",
        title: "Path tracer",
        description: "Unidirectional path tracing with next-event estimation and MIS (reference).",
        params: path::PathSettings::PARAMS,
        create: path::create,
    },
    IntegratorInfo {
        name: "bdpt",
        title: "Bidirectional path tracer",
        description: "Veach 1997: camera and light subpaths joined by every strategy, balance-heuristic MIS.",
        params: bdpt::BdptSettings::PARAMS,
        create: bdpt::create,
    },
    IntegratorInfo {
        name: "mmlt",
        title: "Multiplexed Metropolis light transport",
        description: "Hachisuka et al. 2014: Metropolis chains over primary samples and bidirectional techniques.",
        params: mmlt::MmltSettings::PARAMS,
        create: mmlt::create,
    },
    IntegratorInfo {
        name: "ppm",
        title: "Progressive photon mapping",
        description: "Hachisuka et al. 2008: hit points from one eye pass, radii shrinking per hit point.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_ppm,
    },
    IntegratorInfo {
        name: "sppm",
        title: "Stochastic progressive photon mapping",
        description: "Hachisuka & Jensen 2009: hit points re-traced every pass, statistics per pixel.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_sppm,
    },
    IntegratorInfo {
        name: "pppm",
        title: "Probabilistic progressive photon mapping",
        description: "Knaus & Zwicker 2011: one global radius per pass, independent passes averaged.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_pppm,
    },
];

pub fn registry() -> &'static [IntegratorInfo] {
    REGISTRY
}

pub fn find(name: &str) -> Option<&'static IntegratorInfo> {
    REGISTRY.iter().find(|i| i.name == name)
}

/// Parameter values for `info`: defaults overridden by `given`, each checked against its range.
pub fn resolve_params(info: &IntegratorInfo, given: &ParamValues) -> Result<ParamValues, String> {
    for name in given.keys() {
        if !info.params.iter().any(|p| p.name == name) {
            let known: Vec<_> = info.params.iter().map(|p| p.name).collect();
            return Err(format!(
                "integrator '{}' has no parameter '{name}' (it has: {})",
                info.name,
                known.join(", ")
            ));
        }
    }
    let mut values = ParamValues::new();
    for p in info.params {
        let v = given.get(p.name).copied().unwrap_or(p.default);
        check_param(p, v)?;
        values.insert(p.name.to_string(), v);
    }
    Ok(values)
}

/// The value of parameter `name` in `values`, else its default from `specs` (0 if unknown).
pub fn param_or_default(specs: &[ParamSpec], values: &ParamValues, name: &str) -> f64 {
    values.get(name).copied().unwrap_or_else(|| {
        specs
            .iter()
            .find(|s| s.name == name)
            .map_or(0.0, |s| s.default)
    })
}

pub fn check_param(p: &ParamSpec, v: f64) -> Result<(), String> {
    if !v.is_finite() || v < p.min || v > p.max {
        return Err(format!(
            "{} = {v} is outside its range [{}, {}]",
            p.name, p.min, p.max
        ));
    }
    if p.integer && v.fract() != 0.0 {
        return Err(format!("{} = {v} must be a whole number", p.name));
    }
    Ok(())
}

/// Parameters as a JSON object, for EXR headers and logs.
pub fn params_json(values: &ParamValues) -> String {
    let map: serde_json::Map<String, serde_json::Value> = values
        .iter()
        .map(|(k, v)| (k.clone(), serde_json::json!(v)))
        .collect();
    serde_json::Value::Object(map).to_string()
}
