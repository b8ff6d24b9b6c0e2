//! Vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek 2012; the same
//! estimator as Hachisuka, Pantaleoni & Jensen 2012's unified path sampling): bidirectional
//! path tracing's connections and photon mapping's merges as techniques of one estimator,
//! weighted by one MIS (`mis.rs`, Georgiev's recursive quantities).
//!
//! Each pass: one light subpath per pixel (`light_pass.rs`), its non-specular vertices stored
//! and indexed in the photon mappers' hash grid, each also joined to the camera (t = 1); then
//! one camera subpath per pixel (`camera_pass.rs`) that at each non-specular vertex uses
//! next-event estimation, connects to every vertex of its pixel's light subpath and merges
//! with the light vertices of all subpaths within the pass's radius. The radius shrinks pass
//! by pass as r_i = r_0 (i + 1)^((alpha - 1) / 2) (Knaus & Zwicker 2011's rate, in SmallVCM's
//! form), kept as a running product so that alpha can change while rendering; every pass is
//! an estimate of each pixel with the pass's radius, and the image is their mean.

mod camera_pass;
pub mod light_densities;
mod light_pass;
pub mod metropolis;
pub mod metropolised;
pub mod mis;
pub mod techniques;

use crate::camera::Camera;
use crate::error_estimate::ErrorEstimate;
use crate::image::Image;
use crate::integrators::kernel_bias::{self, INNER_RADIUS_RATIO, PassSums};
use crate::integrators::ppm::auto_radius;
use crate::integrators::ppm::hash_grid::HashGrid;
use crate::integrators::{
    Cancelled, Integrator, ParamSpec, ParamValues, PassStats, PlotKind, PlotSeries, RenderContext,
    params,
};
use crate::scene::Scene;
use camera_pass::CameraSample;
use glam::{DVec3, Vec3};
use light_pass::LightVertex;
use metropolis::MetropolisLightSubpaths;
use metropolised::MetropolisedLightSubpaths;
use mis::MisWeights;
use std::sync::atomic::AtomicBool;
use techniques::TechniqueShares;

/// Which techniques a run uses: both in `vcm`; one alone for tests (connections alone are
/// bdpt, merges alone a bidirectional photon mapper).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    pub connections: bool,
    pub merges: bool,
}

impl Default for Techniques {
    fn default() -> Self {
        Techniques {
            connections: true,
            merges: true,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub struct VcmSettings {
    pub alpha: f64,
    /// Initial merge radius in scene units; 0 chooses it as the photon mappers do.
    pub radius: f64,
    pub max_depth: u32,
    #[serde(skip)]
    pub techniques: Techniques,
}

impl VcmSettings {
    pub const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::new(
            "alpha",
            "Radius reduction (0, 1]: the merge radius shrinks as pass^((alpha - 1) / 2); smaller shrinks faster (less bias, noisier merges), 1 keeps it.",
            0.75,
            (1e-3, 1.0),
        )
        .live(),
        ParamSpec::new(
            "radius",
            "Merge radius in scene units, shrinking from there by alpha's schedule; 0 picks one pixel footprint at the median distance of the surfaces the camera sees. Live: sets the next pass's radius.",
            0.0,
            (0.0, 1e6),
        )
        .automatic_at_zero()
        .live(),
        params::MAX_DEPTH,
    ];

    /// amcvcm's: vcm's and the chains' large-step probability.
    pub const METROPOLIS_PARAMS: &'static [ParamSpec] = &[
        Self::PARAMS[0],
        Self::PARAMS[1],
        Self::PARAMS[2],
        metropolis::LARGE_STEP,
    ];

    pub fn from_params(p: &ParamValues) -> Self {
        params::read_settings(Self::PARAMS, p)
    }
}

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(Vcm::new(ctx, VcmSettings::from_params(params)))
}

/// vcm whose light subpaths come from visibility chains (`metropolis.rs`).
pub fn create_amcvcm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    let large_step_prob = params::param_value(VcmSettings::METROPOLIS_PARAMS, p, "large_step");
    Box::new(
        Vcm::new(ctx, VcmSettings::from_params(p))
            .with_metropolis_light_subpaths(large_step_prob as f32),
    )
}

/// vcm whose light subpaths come from a visibility and a contribution chain combined by
/// their MIS (`metropolised.rs`).
pub fn create_mvcm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    let large_step_prob = params::param_value(VcmSettings::METROPOLIS_PARAMS, p, "large_step");
    Box::new(
        Vcm::new(ctx, VcmSettings::from_params(p))
            .with_metropolised_light_subpaths(large_step_prob as f32),
    )
}

/// Where a pass's light subpaths come from when not independent.
#[derive(Clone, Debug)]
pub enum ChainedLightSubpaths {
    /// Visibility chains (amcvcm).
    Visibility(MetropolisLightSubpaths),
    /// Visibility and contribution chains (mvcm).
    Metropolised(MetropolisedLightSubpaths),
}

impl ChainedLightSubpaths {
    fn memory_bytes(&self) -> usize {
        match self {
            Self::Visibility(m) => m.memory_bytes(),
            Self::Metropolised(m) => m.memory_bytes(),
        }
    }

    fn set_large_step_prob(&mut self, p: f32) {
        match self {
            Self::Visibility(m) => m.large_step_prob = p,
            Self::Metropolised(m) => m.large_step_prob = p,
        }
    }

    fn statistics(&self) -> serde_json::Value {
        match self {
            Self::Visibility(m) => m.statistics(),
            Self::Metropolised(m) => m.statistics(),
        }
    }

    fn plots(&self) -> Vec<PlotSeries> {
        match self {
            Self::Visibility(m) => m.plots(),
            Self::Metropolised(m) => m.plots(),
        }
    }

    fn light_subpaths(
        &mut self,
        setup: &Pass,
        cameras: &metropolis::CameraVertices,
        light_paths: u64,
        seed: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<metropolis::ChainGather, Cancelled> {
        match self {
            Self::Visibility(m) => {
                m.light_subpaths(setup, cameras, light_paths, seed, cancel, stats)
            }
            Self::Metropolised(m) => {
                m.light_subpaths(setup, cameras, light_paths, seed, cancel, stats)
            }
        }
    }
}

const MAX_HISTORY: usize = 2048;
/// The automatic radius as a share of the photon mappers' (four pixel footprints): one
/// footprint. Where connections sample a path well, a merge only adds its kernel's bias and
/// noise; where only merges reach (caustics seen through glass) a larger radius pays. Measured
/// at 15 s, 128 pixels wide (DESIGN.md section 5a): on the Cornell boxes and the door the
/// error grows with the radius from a quarter footprint on (1.1 to 1.3 times the best at one
/// footprint, 1.6 to 2.5 times at three or four); on the caustic pool it falls (3 times the
/// best at one footprint, which is at three).
const AUTO_RADIUS_SCALE: f64 = 0.25;

/// What the two halves of a pass share.
pub(crate) struct Pass<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    weights: MisWeights,
    /// Most edges of a path: max_depth + 1.
    max_path_length: u32,
    connections: bool,
    merges: bool,
    radius_sq: f32,
    /// The inner disc of the kernel-bias estimate (`kernel_bias`).
    inner_radius_sq: f32,
    /// 1 / (pi r^2 N_L): a merge is a density estimate over the disc among N_L subpaths.
    merge_normalization: f32,
    light_vertices: &'a [LightVertex],
    grid: Option<&'a HashGrid>,
}

pub struct Vcm {
    ctx: RenderContext,
    settings: VcmSettings,
    /// Per pixel, the passes' estimates and kernel-bias estimates: the image is their mean.
    sums: Vec<PassSums>,
    /// Per pixel, the sum over passes of an unbiased estimate whose noise does not follow the
    /// contribution chains' (the camera half and mvcm's states weighted without those
    /// chains), for the error estimate's r; empty where there is none.
    independent_sums: Vec<DVec3>,
    /// The same over odd passes only.
    independent_odd_sums: Vec<DVec3>,
    pass_buffer: Vec<CameraSample>,
    initial_radius: f64,
    radius_sq: f64,
    radius_floor_sq: f64,
    passes: u64,
    /// Bytes of the last pass's light vertices and grid (they live only during a pass).
    pass_bytes: usize,
    /// What each technique brought so far.
    shares: TechniqueShares,
    /// (passes, radius), thinned to stay bounded.
    radius_history: Vec<[f64; 2]>,
    history_stride: u64,
    /// Light subpaths from chains (`metropolis.rs`, `metropolised.rs`) in place of
    /// independent ones.
    metropolis: Option<ChainedLightSubpaths>,
}

impl Vcm {
    /// The independent image for the error estimate's r (`independent_sums`): per channel
    /// the lower of its odd and even passes' 3 x 3 means, so that its own noise does not
    /// lift r (empty where there is none). `robust_reference_sq` takes a 3 x 3 mean of it
    /// again: the ratios in DESIGN.md 5d were measured with both.
    fn independent_image(&self, width: usize, height: usize) -> Vec<DVec3> {
        if self.independent_sums.is_empty() || self.passes < 2 {
            return Vec::new();
        }
        let (n_odd, n_even) = ((self.passes / 2) as f64, self.passes.div_ceil(2) as f64);
        let odd: Vec<DVec3> = self
            .independent_odd_sums
            .iter()
            .map(|s| *s / n_odd)
            .collect();
        let even: Vec<DVec3> = self
            .independent_sums
            .iter()
            .zip(&self.independent_odd_sums)
            .map(|(s, o)| (*s - *o) / n_even)
            .collect();
        let odd = crate::error_estimate::box_filter_3x3(&odd, width, height);
        let even = crate::error_estimate::box_filter_3x3(&even, width, height);
        odd.iter().zip(&even).map(|(a, b)| a.min(*b)).collect()
    }

    pub fn new(ctx: RenderContext, settings: VcmSettings) -> Self {
        let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
        let initial_radius = if settings.radius > 0.0 {
            settings.radius
        } else {
            AUTO_RADIUS_SCALE * auto_radius(&ctx)
        };
        let diagonal = ctx.scene.bounds.diagonal().length().max(1e-12) as f64;
        Vcm {
            settings,
            sums: vec![PassSums::default(); w * h],
            independent_sums: Vec::new(),
            independent_odd_sums: Vec::new(),
            pass_buffer: vec![CameraSample::default(); w * h],
            initial_radius,
            radius_sq: initial_radius * initial_radius,
            // As the photon mappers: f32 positions resolve no less than a millionth of the
            // scene.
            radius_floor_sq: (1e-6 * diagonal).powi(2),
            passes: 0,
            pass_bytes: 0,
            shares: TechniqueShares::default(),
            radius_history: Vec::new(),
            history_stride: 1,
            metropolis: None,
            ctx,
        }
    }

    /// The same estimator with light subpaths from visibility chains (`metropolis.rs`).
    pub fn with_metropolis_light_subpaths(mut self, large_step_prob: f32) -> Self {
        self.metropolis = Some(ChainedLightSubpaths::Visibility(
            MetropolisLightSubpaths::new(large_step_prob),
        ));
        self
    }

    /// mvcm: light subpaths from visibility and contribution chains (`metropolised.rs`).
    pub fn with_metropolised_light_subpaths(mut self, large_step_prob: f32) -> Self {
        self.metropolis = Some(ChainedLightSubpaths::Metropolised(
            MetropolisedLightSubpaths::new(large_step_prob),
        ));
        self
    }

    /// What each technique brought to the image so far.
    pub fn technique_shares(&self) -> &TechniqueShares {
        &self.shares
    }

    /// The merge radius the next pass uses.
    pub fn radius(&self) -> f64 {
        self.radius_sq.sqrt()
    }

    pub fn initial_radius(&self) -> f64 {
        self.initial_radius
    }

    fn record_radius(&mut self) {
        if !self.passes.is_multiple_of(self.history_stride) {
            return;
        }
        self.radius_history
            .push([self.passes as f64, self.radius_sq.sqrt()]);
        if self.radius_history.len() > MAX_HISTORY {
            self.radius_history = self.radius_history.iter().copied().step_by(2).collect();
            self.history_stride *= 2;
        }
    }
}

impl Integrator for Vcm {
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let (scene, camera) = (&*self.ctx.scene, &self.ctx.camera);
        let pixels = (camera.width * camera.height) as usize;
        let techniques = self.settings.techniques;
        let radius_sq = self.radius_sq as f32;
        let light_paths = pixels as f32;
        let weights = MisWeights::new(
            1.0,
            radius_sq.sqrt(),
            light_paths,
            pixels as f32,
            techniques.connections,
            techniques.merges,
        );
        let setup = Pass {
            scene,
            camera,
            weights,
            max_path_length: self.settings.max_depth + 1,
            connections: techniques.connections,
            merges: techniques.merges,
            radius_sq,
            inner_radius_sq: radius_sq * (INNER_RADIUS_RATIO * INNER_RADIUS_RATIO) as f32,
            merge_normalization: 1.0 / (std::f32::consts::PI * radius_sq * light_paths),
            light_vertices: &[],
            grid: None,
        };
        let mut stats = PassStats::default();
        let merge_normalization = setup.merge_normalization;
        if let Some(metropolis) = &mut self.metropolis {
            let (cameras, camera_stats, camera_shares) = metropolis::camera_subpaths(
                &mut self.pass_buffer,
                &setup,
                self.ctx.seed,
                pass,
                cancel,
            )?;
            stats = stats + camera_stats;
            let gather = metropolis.light_subpaths(
                &setup,
                &cameras,
                pixels as u64,
                self.ctx.seed,
                cancel,
                &mut stats,
            )?;
            self.shares.add(&camera_shares);
            self.shares.add(&gather.shares);
            if !gather.independent.is_empty() {
                self.independent_sums.resize(pixels, DVec3::ZERO);
                self.independent_odd_sums.resize(pixels, DVec3::ZERO);
                for (i, (out, light)) in
                    self.pass_buffer.iter().zip(&gather.independent).enumerate()
                {
                    let v = (out.value + *light).as_dvec3();
                    self.independent_sums[i] += v;
                    if pass % 2 == 1 {
                        self.independent_odd_sums[i] += v;
                    }
                }
            }
            for (i, out) in self.pass_buffer.iter_mut().enumerate() {
                out.value += gather.value[i];
                out.merged += gather.merged[i];
                out.merged_inner += gather.merged_inner[i];
            }
            self.pass_bytes = cameras.memory_bytes();
        } else {
            self.pass_bytes = uniform_pass(
                &mut self.pass_buffer,
                &mut self.shares,
                setup,
                (self.ctx.seed, pass),
                cancel,
                &mut stats,
            )?;
        }
        let area = 1.0 / f64::from(merge_normalization);
        for (sums, sample) in self.sums.iter_mut().zip(&self.pass_buffer) {
            let bias = kernel_bias::pass_bias(
                sample.merged.as_dvec3(),
                sample.merged_inner.as_dvec3(),
                area,
            );
            sums.add(pass, sample.value.as_dvec3(), bias);
        }
        // The next pass's radius: r_{i+1}^2 = r_i^2 ((i + 1) / (i + 2))^(1 - alpha).
        let i = self.passes as f64;
        self.radius_sq = (self.radius_sq * ((i + 1.0) / (i + 2.0)).powf(1.0 - self.settings.alpha))
            .max(self.radius_floor_sq);
        self.passes += 1;
        self.record_radius();
        Ok(stats)
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.sums.as_slice())
            + std::mem::size_of_val(self.independent_sums.as_slice())
            + std::mem::size_of_val(self.independent_odd_sums.as_slice())
            + std::mem::size_of_val(self.pass_buffer.as_slice())
            + std::mem::size_of_val(self.radius_history.as_slice())
            + self.pass_bytes
            + self.metropolis.as_ref().map_or(0, |m| m.memory_bytes())
    }

    fn statistics(&self) -> Option<serde_json::Value> {
        self.metropolis.as_ref().map(|m| m.statistics())
    }

    fn image(&self) -> Image {
        let inv = 1.0 / self.passes.max(1) as f64;
        Image {
            width: self.ctx.camera.width as usize,
            height: self.ctx.camera.height as usize,
            pixels: self
                .sums
                .iter()
                .map(|s| (s.estimate_sum * inv).as_vec3())
                .collect(),
        }
    }

    /// Each pass is an estimate with its own radius, as PPPM's: the noise from their spread,
    /// the merges' kernel bias by Richardson extrapolation on the same light vertices
    /// (`kernel_bias`).
    fn error_estimate(&self) -> Option<ErrorEstimate> {
        if self.passes < 2 {
            return None;
        }
        let image = self.image();
        let independent = self.independent_image(image.width, image.height);
        let independent = (!independent.is_empty()).then_some(independent.as_slice());
        let pixels = kernel_bias::pixel_errors(&image, self.passes, |i| &self.sums[i], independent);
        ErrorEstimate::from_pixels(image.width, image.height, &pixels)
    }

    fn automatic(&self) -> Vec<(&'static str, f64)> {
        vec![("radius", self.initial_radius)]
    }

    fn set_live_param(&mut self, name: &str, value: f64) {
        match name {
            "alpha" => self.settings.alpha = value,
            // The schedule goes on from the new radius; 0 returns to the automatic one,
            // shrunk as far as the passes so far would have shrunk it.
            "large_step" => {
                if let Some(m) = &mut self.metropolis {
                    m.set_large_step_prob(value as f32);
                }
            }
            "radius" => {
                self.settings.radius = value;
                let radius = if value > 0.0 {
                    value
                } else {
                    self.initial_radius = AUTO_RADIUS_SCALE * auto_radius(&self.ctx);
                    let shrink = (self.passes as f64 + 1.0).powf(self.settings.alpha - 1.0);
                    self.initial_radius * shrink.sqrt()
                };
                self.radius_sq = (radius * radius).max(self.radius_floor_sq);
            }
            _ => debug_assert!(false, "{name} is not live"),
        }
    }

    fn plots(&self) -> Vec<PlotSeries> {
        let mut plots = self.shares.plots();
        plots.push(PlotSeries {
            plot: "Radius".into(),
            name: "merge radius".into(),
            kind: PlotKind::Line,
            x_label: "passes".into(),
            y_label: "radius".into(),
            points: self.radius_history.clone(),
            point_names: Vec::new(),
        });
        plots.extend(self.metropolis.iter().flat_map(|m| m.plots()));
        plots
    }
}

/// Samples the next direction of a subpath at `si` (`scatter`) and carries its MIS quantities
/// over the bounce (`SubpathMis::scatter`): a delta lobe's reverse density is its forward one.
pub(super) fn scatter_with_mis(
    w: &MisWeights,
    mis: &mut mis::SubpathMis,
    si: &crate::scene::SurfaceInteraction,
    bsdf: &crate::material::Bsdf,
    sampler: &mut impl crate::sampling::sampler::SampleSource,
    mode: crate::material::TransportMode,
) -> Option<crate::integrators::scatter::Scatter> {
    let wo = si.shading.to_local(si.wo);
    let next = crate::integrators::scatter(si, bsdf, wo, sampler, mode)?;
    let delta = next.sample.is_delta;
    let rev_pdf = if delta {
        next.sample.pdf
    } else {
        bsdf.pdf(next.sample.wi, wo)
    };
    mis.scatter(w, next.sample.pdf, rev_pdf, si.n.dot(next.ray.d), delta);
    Some(next)
}

/// The light and camera halves of a pass with independent light subpaths (module docs) into
/// `buffer`; the bytes its light vertices and grid took.
fn uniform_pass(
    buffer: &mut [CameraSample],
    technique_shares: &mut TechniqueShares,
    setup: Pass,
    (seed, pass): (u64, u64),
    cancel: &AtomicBool,
    stats: &mut PassStats,
) -> Result<usize, Cancelled> {
    let light_pass::LightPaths {
        vertices,
        ends,
        splats,
        shares,
    } = light_pass::light_pass(&setup, seed, pass, cancel, stats)?;
    let grid = setup.merges.then(|| {
        let points: Vec<Option<(Vec3, f32)>> = vertices
            .iter()
            .map(|v| Some((v.vertex.p, setup.radius_sq.sqrt())))
            .collect();
        HashGrid::build(&points)
    });
    let setup = Pass {
        light_vertices: &vertices,
        grid: grid.as_ref(),
        ..setup
    };
    let (camera_stats, camera_shares) = camera_pass(buffer, &setup, &ends, seed, pass, cancel)?;
    *stats = *stats + camera_stats;
    technique_shares.add(&shares);
    technique_shares.add(&camera_shares);
    for (i, v) in splats {
        buffer[i].value += v;
    }
    Ok(std::mem::size_of_val(vertices.as_slice())
        + std::mem::size_of_val(ends.as_slice())
        + grid.as_ref().map_or(0, |g| g.memory_bytes()))
}

/// The camera half of pass `pass` into `buffer` (`camera_pass::camera_rows`).
fn camera_pass(
    buffer: &mut [CameraSample],
    setup: &Pass,
    ends: &[u32],
    seed: u64,
    pass: u64,
    cancel: &AtomicBool,
) -> Result<(PassStats, TechniqueShares), Cancelled> {
    let rows = camera_pass::camera_rows(
        buffer,
        setup,
        (seed, pass),
        cancel,
        || (),
        |_, pixel, film, sampler, stats, shares| {
            let start = if pixel == 0 {
                0
            } else {
                ends[pixel - 1] as usize
            };
            let own = &setup.light_vertices[start..ends[pixel] as usize];
            camera_pass::trace_camera_subpath(setup, film, own, sampler, stats, shares)
        },
    )?;
    let mut total = (PassStats::default(), TechniqueShares::default());
    for ((), stats, shares) in rows {
        total.0 = total.0 + stats;
        total.1.add(&shares);
    }
    Ok(total)
}
