//! Progressive photon mapping: PPM (Hachisuka, Ogaki & Jensen 2008), stochastic PPM
//! (Hachisuka & Jensen 2009) and probabilistic PPM (Knaus & Zwicker 2011), sharing one eye
//! pass (`hit_points`), one photon tracer and one spatial hash grid (`hash_grid`).
//!
//! After every photon pass each hit point with M > 0 new photons is updated by Hachisuka et
//! al. 2008, eqs. 5-7, in area form (DESIGN.md section 4):
//!
//! ```text
//! N' = N + alpha M
//! R'^2 = R^2 (N + alpha M) / (N + M)
//! tau' = (tau + tau_M) (N + alpha M) / (N + M)
//! ```
//!
//! and radiance is L = direct_sum / n + tau / (pi R^2 N_emitted). PPPM instead shrinks one
//! global radius, r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1) (Knaus & Zwicker 2011, eq. 20), and
//! averages independent photon-map estimates.
//!
//! Remaining error (`error_estimate`): see `error.rs`, after Hachisuka, Jarosz & Jensen 2010.
//!
//! Photon splats are accumulated per worker without locks and merged after the pass; the
//! merge order is fixed, so a given seed and thread count give the same image, and other
//! thread counts differ only in the order of floating-point sums (DESIGN.md section 6).

mod error;
mod eye_pass;
pub mod hash_grid;
pub mod hit_points;
pub mod metropolis;
mod photon_budget;
mod photon_tracing;
mod pixel_stats;
mod pixel_update;
mod trapped_light;

use crate::camera::CameraDesc;
use crate::error_estimate::ErrorEstimate;
use crate::film::sanitize;
use crate::image::Image;
use crate::integrators::{
    Cancelled, Integrator, ParamSpec, ParamValues, PassStats, PixelLayer, PlotKind, PlotSeries,
    RenderContext,
};
use glam::{DVec3, Vec3};
use hash_grid::HashGrid;
use hit_points::HitPoint;
use metropolis::MetropolisPhotons;
use photon_budget::{PhotonBudget, PhotonSchedule, photon_pass_floor};
use pixel_stats::PixelStats;
use std::sync::atomic::AtomicBool;
use trapped_light::{Kernel, TrappedLight};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Hit points from the first eye pass, kept for the whole run.
    Ppm,
    /// Hit points re-traced every pass with new jitter; statistics per pixel.
    Sppm,
    /// One global radius per pass; independent estimates averaged.
    Pppm,
}

impl Variant {
    /// PPM gathers at the first eye pass's hit points for the whole run (and so may reuse
    /// its grid, and carries the footprint error of one point per pixel).
    fn fixed_hit_points(self) -> bool {
        self == Variant::Ppm
    }
}

/// How the gather radii shrink.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Radii {
    /// PPM, SPPM: each pixel's own radius (`PixelStats::radius_sq`), shrunk by its photon
    /// statistics (Hachisuka et al. 2008, eqs. 5-7); the image is the progressive estimate.
    PerPixel,
    /// PPPM: one radius for every pixel, shrunk after every pass (Knaus & Zwicker 2011,
    /// eq. 20); the image is the mean of the passes' independent estimates.
    Global { radius_sq: f64 },
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub struct PhotonMappingSettings {
    pub alpha: f64,
    /// Initial radius in scene units; 0 chooses it automatically (see `auto_radius`).
    pub radius: f64,
    pub photons: u64,
    pub max_depth: u32,
}

const ALPHA: ParamSpec = ParamSpec::new(
    "alpha",
    "Share of new photons kept per pass (0, 1]: smaller shrinks the radius faster (less bias, more noise); 1 never shrinks it.",
    2.0 / 3.0,
    (1e-3, 1.0),
)
.live();
const RADIUS: ParamSpec = ParamSpec::new(
    "radius",
    "Initial gather radius in scene units; 0 picks four pixel footprints at the median distance of the surfaces the camera sees.",
    0.0,
    (0.0, 1e6),
)
.automatic_at_zero();
const PHOTONS: ParamSpec =
    ParamSpec::new("photons", "Photons traced per pass.", 100_000.0, (1.0, 1e7))
        .integer()
        .live();
/// amcppm's photons: chosen each pass unless given (`photon_budget`), from one per pixel
/// (`photons_per_pass`). Measured with `caustica converge` at 30 s, 128 x 128, three seeds'
/// medians: on gap-glass one per pixel had relMSE 4.8e-3 against 6.0e-3 at 10^5, its error
/// estimate 1.5 times the truth against 4.2 (DESIGN.md 5b for the chosen count's).
const PHOTONS_PER_PIXEL: ParamSpec = ParamSpec::new(
    "photons",
    "Photons traced per pass; 0 chooses them each pass: one per pixel at first, then the count whose split of the pass between camera paths and photons leaves the least variance per ray traced, down to a sixty-fourth of that on average (below an eighth, passes without photons save theirs up for one that traces at least an eighth).",
    0.0,
    (0.0, 1e7),
)
.integer()
.live()
.automatic_at_zero();
const MAX_DEPTH: ParamSpec = ParamSpec::new(
    "max_depth",
    "Maximum bounces of eye paths (through specular surfaces) and of photon paths; Russian roulette ends most photons earlier.",
    64.0,
    (1.0, 1024.0),
)
.integer();

impl PhotonMappingSettings {
    pub const PARAMS: &'static [ParamSpec] = &[ALPHA, RADIUS, PHOTONS, MAX_DEPTH];
    /// amcppm's: the photon mappers' and the chains' large-step probability.
    pub const METROPOLIS_PARAMS: &'static [ParamSpec] = &[
        ALPHA,
        RADIUS,
        PHOTONS_PER_PIXEL,
        MAX_DEPTH,
        metropolis::LARGE_STEP,
    ];

    pub fn from_params(p: &ParamValues) -> Self {
        crate::integrators::params::read_settings(Self::PARAMS, p)
    }
}

/// Photons per pass: one per pixel, so that the photon pass and the eye pass cost about the
/// same (each is one path per item), within 10^4 and 10^6 (amcppm's first pass, and what
/// `info` recommends for the photon mappers).
pub fn photons_per_pass(width: u32, height: u32) -> u64 {
    (width as u64 * height as u64).clamp(10_000, 1_000_000)
}

/// The automatic initial radius: four pixel footprints at the median distance at which the
/// camera's rays, followed through specular surfaces, meet the surfaces that hold hit points
/// (`pixel_footprint_radius`, from 1024 camera paths, `survey::survey_view`). Measured where hit points
/// are rather than at the scene's centre, it stays right for a camera inside a room, or one
/// seeing most of the scene through glass. A view that meets no surface falls back to the
/// distance to the centre of the scene's bounds.
pub fn auto_radius(ctx: &RenderContext) -> f64 {
    let view = crate::survey::survey_view(&ctx.scene, &ctx.camera, 1024, ctx.seed);
    let distance = if view.median_hit_distance > 0.0 {
        view.median_hit_distance
    } else {
        (ctx.scene.bounds.center() - ctx.camera.position()).length() as f64
    };
    pixel_footprint_radius(distance, ctx.camera.height, ctx.camera.desc())
}

/// The initial gather radius: four pixel footprints at the median distance the camera sees
/// surfaces at (a pixel there is 2 d tan(fov / 2) / height wide), through specular chains.
pub fn pixel_footprint_radius(distance: f64, height: u32, camera: &CameraDesc) -> f64 {
    4.0 * camera.pixel_size(distance, height)
}

pub struct PhotonMapper {
    ctx: RenderContext,
    variant: Variant,
    settings: PhotonMappingSettings,
    /// Whether the photon count is chosen here (amcppm's 0): one per pixel at first, then
    /// by `budget`; `settings.photons` is then the current photon pass's count, which the
    /// `schedule` draws from the chosen average, `photon_average`.
    photons_automatic: bool,
    budget: PhotonBudget,
    photon_average: u64,
    schedule: PhotonSchedule,
    /// Passes that traced photons (all of them unless the count is chosen here).
    photon_passes: u64,
    initial_radius_sq: f64,
    radius_floor_sq: f64,
    pixels: Vec<PixelStats>,
    hit_points: Vec<Option<HitPoint>>,
    radii: Radii,
    photons_emitted: u64,
    passes: u64,
    /// (passes, mean radius, standard deviation of the radius), thinned to stay bounded.
    radius_history: Vec<[f64; 3]>,
    history_stride: u64,
    /// The grid over the hit points, and the mean radius it was built for.
    grid: Option<(HashGrid, f64)>,
    grid_builds: u64,
    /// Workers of the last photon pass (the threads of the pool it ran on), each of which
    /// gathered into its own buffer.
    photon_workers: usize,
    /// Metropolis photon paths (`metropolis.rs`) in place of uniform ones.
    metropolis: Option<MetropolisPhotons>,
    /// Merges at the camera's first specular vertices for light trapped by total internal
    /// reflection (`trapped_light.rs`).
    trapped: Option<TrappedLight>,
}

fn create(ctx: RenderContext, variant: Variant, p: &ParamValues) -> Box<dyn Integrator> {
    let settings = PhotonMappingSettings::from_params(p);
    Box::new(PhotonMapper::new(ctx, variant, settings))
}

pub fn create_ppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    create(ctx, Variant::Ppm, p)
}

pub fn create_sppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    create(ctx, Variant::Sppm, p)
}

pub fn create_pppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    create(ctx, Variant::Pppm, p)
}

/// SPPM whose photon paths come from visibility chains (Hachisuka & Jensen 2011).
pub fn create_amcppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    let settings =
        crate::integrators::params::read_settings(PhotonMappingSettings::METROPOLIS_PARAMS, p);
    let large_step_prob = crate::integrators::params::param_value(
        PhotonMappingSettings::METROPOLIS_PARAMS,
        p,
        "large_step",
    );
    Box::new(
        PhotonMapper::new(ctx, Variant::Sppm, settings)
            .with_metropolis_light_paths(large_step_prob as f32),
    )
}

pub(super) const PHOTON_STREAM: u64 = 0x005e_ed0f_9407_0715;
/// Eye paths draw from their own stream, so that next-event estimation at the hit point
/// (keyed by pixel and pass too) is independent of the jitter and the specular choices.
pub(super) const EYE_STREAM: u64 = 0x0e7e_0a7b_5eed_0001;
const MAX_HISTORY: usize = 2048;

impl PhotonMapper {
    pub fn new(ctx: RenderContext, variant: Variant, mut settings: PhotonMappingSettings) -> Self {
        let pixels = (ctx.camera.width * ctx.camera.height) as usize;
        let photons_automatic = settings.photons == 0;
        if photons_automatic {
            settings.photons = photons_per_pass(ctx.camera.width, ctx.camera.height);
        }
        let radius = if settings.radius > 0.0 {
            settings.radius
        } else {
            auto_radius(&ctx)
        };
        let diagonal = ctx.scene.bounds.diagonal().length().max(1e-12) as f64;
        let initial_radius_sq = radius * radius;
        PhotonMapper {
            variant,
            settings,
            photons_automatic,
            budget: PhotonBudget::default(),
            photon_average: settings.photons,
            schedule: PhotonSchedule::default(),
            photon_passes: 0,
            initial_radius_sq,
            // The radius never falls below a millionth of the scene: f32 positions cannot
            // resolve less, and the grid's cells stay meaningful.
            radius_floor_sq: (1e-6 * diagonal).powi(2),
            pixels: vec![
                PixelStats {
                    radius_sq: initial_radius_sq,
                    ..Default::default()
                };
                pixels
            ],
            hit_points: vec![None; pixels],
            radii: match variant {
                Variant::Pppm => Radii::Global {
                    radius_sq: initial_radius_sq,
                },
                Variant::Ppm | Variant::Sppm => Radii::PerPixel,
            },
            photons_emitted: 0,
            passes: 0,
            radius_history: Vec::new(),
            history_stride: 1,
            grid: None,
            grid_builds: 0,
            photon_workers: 0,
            metropolis: None,
            trapped: None,
            ctx,
        }
    }

    /// The same photon mapper with Metropolis photon paths (`metropolis.rs`).
    pub fn with_metropolis_light_paths(mut self, large_step_prob: f32) -> Self {
        self.metropolis = Some(MetropolisPhotons::new(large_step_prob));
        self.trapped = Some(TrappedLight::new(self.pixels.len()));
        self
    }

    /// Its Metropolis photon paths' counters, if it has them.
    pub fn metropolis(&self) -> Option<&MetropolisPhotons> {
        self.metropolis.as_ref()
    }

    pub fn initial_radius(&self) -> f64 {
        self.initial_radius_sq.sqrt()
    }

    /// The smallest radius allowed (a millionth of the scene's diagonal).
    pub fn radius_floor(&self) -> f64 {
        self.radius_floor_sq.sqrt()
    }

    /// Current gather radius of a pixel's hit point.
    pub fn radius(&self, pixel: usize) -> f64 {
        self.radius_sq(pixel).sqrt()
    }

    pub fn photons_emitted(&self) -> u64 {
        self.photons_emitted
    }

    pub fn radius_history_len(&self) -> usize {
        self.radius_history.len()
    }

    /// How many times the hash grid was built so far.
    pub fn grid_builds(&self) -> u64 {
        self.grid_builds
    }

    /// Rebuilds the hash grid when the hit points moved (SPPM, PPPM: every pass) or PPM's
    /// radii have shrunk to half of those it was built for. Radii only shrink, so a grid built
    /// for larger discs still finds every candidate; it only gets less selective.
    fn update_grid(&mut self, pass: u64) {
        if let Some(t) = &mut self.trapped {
            t.start_pass(Kernel::at(
                self.photon_passes,
                self.initial_radius_sq,
                self.settings.alpha,
            ));
        }
        let radii: Vec<f64> = (0..self.pixels.len())
            .map(|i| self.radius_sq(i).sqrt())
            .collect();
        let live = self
            .hit_points
            .iter()
            .filter(|h| h.is_some())
            .count()
            .max(1);
        let mean = self
            .hit_points
            .iter()
            .zip(&radii)
            .filter(|(h, _)| h.is_some())
            .map(|(_, r)| r)
            .sum::<f64>()
            / live as f64;
        let reusable = self.variant.fixed_hit_points()
            && pass > 0
            && self
                .grid
                .as_ref()
                .is_some_and(|(_, built)| mean >= 0.5 * built);
        if reusable {
            return;
        }
        let points: Vec<Option<(Vec3, f32)>> = self
            .hit_points
            .iter()
            .zip(&radii)
            .map(|(hp, r)| hp.map(|h| (h.si.p, *r as f32)))
            .collect();
        self.grid = Some((HashGrid::build(&points), mean));
        self.grid_builds += 1;
    }

    fn radius_sq(&self, pixel: usize) -> f64 {
        match self.radii {
            Radii::Global { radius_sq } => radius_sq,
            Radii::PerPixel => self.pixels[pixel].radius_sq,
        }
    }

    /// The photon-carried radiance of a PPM or SPPM pixel: tau / (pi R^2 N_emitted).
    fn indirect(&self, pixel: usize) -> DVec3 {
        self.pixels[pixel].indirect(self.photons_emitted)
    }

    fn record_radius(&mut self) {
        // Only the passes the history keeps pay for the radii (a pass over every pixel).
        if !self.passes.is_multiple_of(self.history_stride) {
            return;
        }
        let radii: Vec<f64> = (0..self.pixels.len())
            .filter(|&i| self.hit_points[i].is_some())
            .map(|i| self.radius_sq(i).sqrt())
            .collect();
        if radii.is_empty() {
            return;
        }
        let mean = radii.iter().sum::<f64>() / radii.len() as f64;
        let sd =
            (radii.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / radii.len() as f64).sqrt();
        self.radius_history.push([self.passes as f64, mean, sd]);
        if self.radius_history.len() > MAX_HISTORY {
            // Keep every other point and record half as often: the history stays bounded.
            self.radius_history = self.radius_history.iter().copied().step_by(2).collect();
            self.history_stride *= 2;
        }
    }
}

impl Integrator for PhotonMapper {
    fn memory_bytes(&self) -> usize {
        use std::mem::{size_of, size_of_val};
        let n = self.pixels.len();
        // A pass holds the eye pass's direct light and, during the photon pass, one `Gathered`
        // per worker plus the merged one (none before the first pass).
        let variance = if self.photons_automatic {
            size_of::<f64>()
        } else {
            0
        };
        // With merges at specular vertices (`trapped_light.rs`) a gather may hold their sums.
        let trapped = if self.trapped.is_some() {
            size_of::<DVec3>()
        } else {
            0
        };
        let gathered = n * (size_of::<u32>() + 2 * size_of::<DVec3>() + variance + trapped);
        let pass = n * size_of::<DVec3>() + (self.photon_workers + 1) * gathered;
        size_of_val(self.pixels.as_slice())
            + size_of_val(self.hit_points.as_slice())
            + size_of_val(self.radius_history.as_slice())
            + self.grid.as_ref().map_or(0, |(g, _)| g.memory_bytes())
            + self.metropolis.as_ref().map_or(0, |m| m.memory_bytes())
            + self.trapped.as_ref().map_or(0, |t| t.memory_bytes())
            + pass
    }

    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let mut stats = PassStats::default();
        let direct = self.eye_pass(pass, cancel, &mut stats)?;
        let eye_rays = stats.rays;
        // The passes this one's photons stand for (`photon_budget`): the schedule is kept
        // only once the pass is done, so a cancelled one leaves it as it was.
        let mut schedule = self.schedule;
        let stands_for = if self.photons_automatic && self.passes > 0 {
            let first = photons_per_pass(self.ctx.camera.width, self.ctx.camera.height);
            match schedule.next(self.photon_average, photon_pass_floor(first)) {
                Some((photons, passes)) => {
                    self.settings.photons = photons;
                    passes
                }
                None => {
                    self.schedule = schedule;
                    self.pass_without_photons(pass, &direct);
                    return Ok(stats);
                }
            }
        } else {
            1
        };
        self.update_grid(pass);
        self.photon_workers = rayon::current_num_threads();
        let gathered = match self.metropolis.take() {
            Some(mut metropolis) => {
                let gathered = metropolis.photon_pass(self, cancel, &mut stats);
                self.metropolis = Some(metropolis);
                gathered?
            }
            None => self.photon_pass(pass, cancel, &mut stats)?,
        };
        let photon_rays = stats.rays - eye_rays;
        self.update_pixels(
            pass,
            &direct,
            &gathered,
            stands_for,
            (eye_rays, photon_rays),
        );
        self.schedule = schedule;
        Ok(stats)
    }

    fn image(&self) -> Image {
        let w = self.ctx.camera.width as usize;
        let h = self.ctx.camera.height as usize;
        let n = self.passes.max(1) as f64;
        let pixels = (0..self.pixels.len())
            .map(|i| {
                let l = match self.radii {
                    // Knaus & Zwicker 2011: the mean of independent photon-map estimates.
                    Radii::Global { .. } => self.pixels[i].passes.estimate_sum / n,
                    Radii::PerPixel => {
                        (self.pixels[i].direct_sum + self.pixels[i].trapped_sum) / n
                            + self.indirect(i)
                    }
                };
                if self.passes == 0 {
                    Vec3::ZERO
                } else {
                    sanitize(l.as_vec3()).unwrap_or(Vec3::ZERO)
                }
            })
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    fn automatic(&self) -> Vec<(&'static str, f64)> {
        let mut chosen = vec![("radius", self.initial_radius())];
        if self.photons_automatic {
            chosen.push(("photons", self.photon_average as f64));
        }
        if let Some(m) = self
            .metropolis
            .as_ref()
            .filter(|m| m.large_step_prob == 0.0)
        {
            chosen.push(("large_step", f64::from(m.last_large_step)));
        }
        chosen
    }

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.estimate_error()
    }

    fn statistics(&self) -> Option<serde_json::Value> {
        // The passes that traced photons, beside the chains' counters: fewer than the passes
        // where the chosen count fell below a photon pass's floor (`photon_budget`).
        self.metropolis.as_ref().map(|m| {
            let mut statistics = m.statistics();
            statistics["photon_passes"] = self.photon_passes.into();
            statistics
        })
    }

    fn set_live_param(&mut self, name: &str, value: f64) {
        match name {
            "alpha" => self.settings.alpha = value,
            "photons" => {
                let (w, h) = (self.ctx.camera.width, self.ctx.camera.height);
                self.photons_automatic = value < 1.0;
                self.settings.photons = if self.photons_automatic {
                    photons_per_pass(w, h)
                } else {
                    value as u64
                };
                self.photon_average = self.settings.photons;
                self.schedule = PhotonSchedule::default();
            }
            "large_step" => {
                if let Some(m) = &mut self.metropolis {
                    m.large_step_prob = value as f32;
                }
            }
            _ => debug_assert!(false, "{name} is not live"),
        }
    }

    fn plots(&self) -> Vec<PlotSeries> {
        let series = |name: &str, f: fn(&[f64; 3]) -> f64| PlotSeries {
            plot: "Radius".into(),
            name: name.into(),
            kind: PlotKind::Line,
            x_label: "passes".into(),
            y_label: "radius".into(),
            points: self.radius_history.iter().map(|h| [h[0], f(h)]).collect(),
            point_names: Vec::new(),
        };
        let mut plots = vec![
            series("mean", |h| h[1]),
            series("mean - sd", |h| h[1] - h[2]),
            series("mean + sd", |h| h[1] + h[2]),
        ];
        plots.extend(self.metropolis.iter().flat_map(|m| m.plots()));
        plots
    }

    fn pixel_layers(&self) -> Vec<PixelLayer> {
        vec![
            PixelLayer {
                name: "radius".into(),
                values: (0..self.pixels.len())
                    .map(|i| self.radius_sq(i).sqrt())
                    .collect(),
            },
            PixelLayer {
                name: "N".into(),
                values: self.pixels.iter().map(|p| p.n).collect(),
            },
            PixelLayer {
                name: "photons".into(),
                values: self
                    .pixels
                    .iter()
                    .map(|p| p.photons_counted as f64)
                    .collect(),
            },
        ]
    }
}
