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
//! Remaining error (`error_estimate`), after Hachisuka, Jarosz & Jensen 2010 ("A progressive
//! error estimation framework for photon density estimation"): every variant's image is the
//! mean over passes of one-pass estimates L_k = direct_k + tau_M,k / (pi R_k^2 P) (for PPM and
//! SPPM because eq. 7's rescaling telescopes: tau_n / R_n^2 = sum of tau_M,k / R_k^2), so
//!
//! - the noise is the sample variance of the L_k over n, as in HJJ 2010 section 4.1. The L_k
//!   are independent given the radii, with variances that grow as R_k shrinks; the sample
//!   variance estimates their mean, which is what the variance of the mean needs.
//! - the kernel bias is estimated by Richardson extrapolation on the same photons: each pass
//!   also sums the photons within R_k / 2 (a quarter of the disc's area), and
//!   b_k = c (L_R - L_{R/2}) estimates the pass's bias, their mean the image's. Where radiance
//!   is smooth, E[L_R] - L = a R^2 + O(R^4) (HJJ 2010 eq. 9, the Laplacian term), and
//!   c = 1 / (1 - 1/4) = 4/3; at a step in radiance (a shadow's or a caustic's edge, a wall's
//!   corner) the bias is first order in R, and over the pixels within R of a straight edge
//!   the sum of squared biases equals that of c (L_R - L_{R/2}) for c = 2.08 (quadrature of
//!   the disc's segment areas). The measured bias of a Cornell box with a glass sphere is
//!   dominated by such edges (with the smooth case's factor it was 3.6 times too small), so
//!   `BIAS_FACTOR` is the geometric mean of the two, 1.665: the squared bias is then within a
//!   factor 1.56 of the truth in both regimes. The inner radius R / 2 rather than R / sqrt(2)
//!   keeps the two regimes' factors 1.5 apart rather than 1.8, at the same noise. This replaces
//!   HJJ 2010's Laplacian estimated with a smooth kernel's second derivative, which assumes the
//!   smooth regime everywhere: the same leading term where radiance is smooth, measured with
//!   the kernel the image actually uses, at the cost of one comparison per photon already found.
//!   b's mean is noisy (about three times the image's standard deviation), so its square is
//!   corrected by its own variance of the mean, b^2 = mean(b)^2 - Var(mean(b)), or noise would
//!   pass for bias; only the sum over the image is clamped at zero (a clamp per pixel would
//!   keep the noise's positive half: measured, it doubled the estimate on a scene without any
//!   bias). Where b stands out of its noise it is clamped at x: radiance is not negative, so
//!   E[x] = r + bias bounds it, while Richardson's estimate reaches 1.665 L_R where only the
//!   outer disc reaches a bright region.
//! - PPM gathers at one hit point per pixel for the whole run, so its photon part converges to
//!   the radiance at that point, not to the pixel's mean: an error whose expected square is the
//!   variance of the indirect radiance over the pixel's footprint. It is estimated from the
//!   image's second differences (the nugget of a variogram): for a pixel whose neighbours' hit
//!   points are independent draws, E[(I_p - (I_l + I_r) / 2)^2] = 1.5 V + their noise +
//!   curvature^2, so V is 2/3 of the mean of the horizontal and vertical squared second
//!   differences less the noise variances. The pixel's converged value is the mean over its
//!   footprint, so this variance is divided by the square of that mean, estimated by the 3x3
//!   mean of the image, not by the pixel's own value: a feature thinner than a pixel (the lit
//!   gap of the door) is missed by most pixels' hit points, whose own values are then far
//!   below the truth. (Dividing by the pixel's own value overestimated the door's relMSE 49
//!   times; an earlier correction for edge pixels counted twice, calibrated with that
//!   denominator, proved to be compensating it, and is gone.) Across a sharp edge a pixel's
//!   neighbours see its variance too, which counts it up to 1.5 times over; detail finer than
//!   a pixel with no edge is counted once.
//!
//! Photon splats are accumulated per worker without locks and merged after the pass; the
//! merge order is fixed, so a given seed and thread count give the same image, and other
//! thread counts differ only in the order of floating-point sums (DESIGN.md section 6).

pub mod hash_grid;
pub mod hit_points;

use crate::error_estimate::{self, ErrorEstimate, PixelError};
use crate::film::sanitize;
use crate::geometry::luminance;
use crate::image::Image;
use crate::integrators::scatter;
use crate::integrators::{
    Cancelled, Integrator, ParamSpec, ParamValues, PassStats, PixelLayer, PlotKind, PlotSeries,
    RenderContext,
};
use crate::light::emission::emit_photon;
use crate::material::TransportMode;
use crate::sampling::sampler::Sampler;
use glam::{BVec3, DVec3, Vec2, Vec3};
use hash_grid::HashGrid;
use hit_points::{HitPoint, trace_eye_path};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Hit points from the first eye pass, kept for the whole run.
    Ppm,
    /// Hit points re-traced every pass with new jitter; statistics per pixel.
    Sppm,
    /// One global radius per pass; independent estimates averaged.
    Pppm,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonMappingSettings {
    pub alpha: f64,
    /// Initial radius in scene units; 0 chooses it automatically (see `auto_radius`).
    pub radius: f64,
    pub photons: u64,
    pub max_depth: u32,
}

impl PhotonMappingSettings {
    pub const PARAMS: &'static [ParamSpec] = &[
        ParamSpec {
            name: "alpha",
            doc: "Share of new photons kept per pass (0, 1]: smaller shrinks the radius faster (less bias, more noise); 1 never shrinks it.",
            default: 2.0 / 3.0,
            min: 1e-3,
            max: 1.0,
            integer: false,
            live: true,
        },
        ParamSpec {
            name: "radius",
            doc: "Initial gather radius in scene units; 0 picks four pixel footprints at the median distance of the surfaces the camera sees.",
            default: 0.0,
            min: 0.0,
            max: 1e6,
            integer: false,
            live: false,
        },
        ParamSpec {
            name: "photons",
            doc: "Photons traced per pass.",
            default: 100_000.0,
            min: 1.0,
            max: 1e7,
            integer: true,
            live: true,
        },
        ParamSpec {
            name: "max_depth",
            doc: "Maximum bounces of eye paths (through specular surfaces) and of photon paths; Russian roulette ends most photons earlier.",
            default: 64.0,
            min: 1.0,
            max: 1024.0,
            integer: true,
            live: false,
        },
    ];

    pub fn from_params(p: &ParamValues) -> Self {
        let get = |name: &str| crate::integrators::param_or_default(Self::PARAMS, p, name);
        PhotonMappingSettings {
            alpha: get("alpha"),
            radius: get("radius"),
            photons: get("photons") as u64,
            max_depth: get("max_depth") as u32,
        }
    }
}

/// The automatic initial radius: four pixel footprints at the median distance at which the
/// camera's rays, followed through specular surfaces, meet the surfaces that hold hit points
/// (`transport::pixel_footprint_radius`, from 1024 camera paths). Measured where hit points
/// are rather than at the scene's centre, it stays right for a camera inside a room, or one
/// seeing most of the scene through glass. A view that meets no surface falls back to the
/// distance to the centre of the scene's bounds.
pub fn auto_radius(ctx: &RenderContext) -> f64 {
    let view = crate::transport::survey_view(&ctx.scene, &ctx.camera, 1024, ctx.seed);
    let distance = if view.median_hit_distance > 0.0 {
        view.median_hit_distance
    } else {
        (ctx.scene.bounds.center() - ctx.camera.position()).length() as f64
    };
    crate::transport::pixel_footprint_radius(distance, ctx.camera.height, ctx.scene.camera.yfov)
}

#[derive(Clone, Copy, Debug, Default)]
struct PixelStats {
    /// Accumulated photon count N (fractional after the alpha reduction).
    n: f64,
    radius_sq: f64,
    tau: DVec3,
    direct_sum: DVec3,
    photons_counted: u64,
    /// Sums over passes of the one-pass estimates L_k and of their squares (PPPM's image is
    /// their mean; for all variants their spread is the noise).
    estimate_sum: DVec3,
    estimate_sum_sq: DVec3,
    /// The sum over odd passes: two independent halves for a robust r^2 (`error_estimate`).
    odd_estimate_sum: DVec3,
    /// Sums over passes of the one-pass bias estimates b_k and of their squares.
    bias_sum: DVec3,
    bias_sum_sq: DVec3,
}

/// What a photon pass gathered at each pixel's hit point.
struct Gathered {
    /// New photon count M.
    m: Vec<u32>,
    /// Flux sum tau_M (beta f flux, not yet divided by anything).
    tau: Vec<DVec3>,
    /// The part of tau_M from photons within R / 2 (`INNER_RADIUS_RATIO`).
    tau_inner: Vec<DVec3>,
}

impl Gathered {
    fn new(n: usize) -> Self {
        Gathered {
            m: vec![0; n],
            tau: vec![DVec3::ZERO; n],
            tau_inner: vec![DVec3::ZERO; n],
        }
    }
}

pub struct PhotonMapper {
    ctx: RenderContext,
    variant: Variant,
    settings: PhotonMappingSettings,
    initial_radius_sq: f64,
    radius_floor_sq: f64,
    pixels: Vec<PixelStats>,
    hit_points: Vec<Option<HitPoint>>,
    /// PPPM: the current global radius.
    global_radius_sq: f64,
    photons_emitted: u64,
    passes: u64,
    /// (passes, mean radius, standard deviation of the radius), thinned to stay bounded.
    radius_history: Vec<[f64; 3]>,
    history_stride: u64,
    /// The grid over the hit points, and the mean radius it was built for.
    grid: Option<(HashGrid, f64)>,
    grid_builds: u64,
}

pub fn create_ppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    Box::new(PhotonMapper::new(
        ctx,
        Variant::Ppm,
        PhotonMappingSettings::from_params(p),
    ))
}

pub fn create_sppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    Box::new(PhotonMapper::new(
        ctx,
        Variant::Sppm,
        PhotonMappingSettings::from_params(p),
    ))
}

pub fn create_pppm(ctx: RenderContext, p: &ParamValues) -> Box<dyn Integrator> {
    Box::new(PhotonMapper::new(
        ctx,
        Variant::Pppm,
        PhotonMappingSettings::from_params(p),
    ))
}

const PHOTON_STREAM: u64 = 0x5eed_0f_9407_0715;
/// Eye paths draw from their own stream, so that next-event estimation at the hit point
/// (keyed by pixel and pass too) is independent of the jitter and the specular choices.
const EYE_STREAM: u64 = 0x0e7e_0a7b_5eed_0001;
const MAX_HISTORY: usize = 2048;
/// The inner disc of the bias estimate, as a fraction of the gather radius (module docs).
const INNER_RADIUS_RATIO: f64 = 0.5;
/// c in b = c (L_R - L_{R/2}): the geometric mean of 4/3 (smooth radiance) and 2.08 (a step).
const BIAS_FACTOR: f64 = 1.665;

/// A pixel's kernel-bias estimate counts as its own, rather than noise, when its square
/// exceeds this many times its variance of the mean (three standard deviations), and the
/// variance comes from at least `SIGNIFICANT_PASSES` passes: from fewer, it is itself too
/// noisy (with two passes a third of pure noise stands two of its standard deviations out).
const SIGNIFICANT_BIAS: f64 = 9.0;
const SIGNIFICANT_PASSES: u64 = 8;

/// The pixel's kernel-bias estimate, per channel at most its value x where it stands above
/// its noise (and which channels do): the radiance is not negative, so E[x] = r + bias
/// bounds the bias. Richardson's estimate exceeds it where the inner disc misses a bright
/// region the outer one reaches (a hit point beside a lit gap: 1.665 L_R for a bias of at
/// most L_R). Where the estimate is noise, clamping it would keep only its negative half, and
/// it is left as it is.
fn significant_bias(bias: DVec3, variance: DVec3, x: DVec3, passes: u64) -> (DVec3, BVec3) {
    let significant = BVec3::from_array(std::array::from_fn(|c| {
        passes >= SIGNIFICANT_PASSES && bias[c] * bias[c] > SIGNIFICANT_BIAS * variance[c]
    }));
    let clamped = DVec3::select(significant, bias.min(x.max(DVec3::ZERO)), bias);
    (clamped, significant)
}

impl PhotonMapper {
    pub fn new(ctx: RenderContext, variant: Variant, settings: PhotonMappingSettings) -> Self {
        let pixels = (ctx.camera.width * ctx.camera.height) as usize;
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
            global_radius_sq: initial_radius_sq,
            photons_emitted: 0,
            passes: 0,
            radius_history: Vec::new(),
            history_stride: 1,
            grid: None,
            grid_builds: 0,
            ctx,
        }
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
        let reusable = self.variant == Variant::Ppm
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
        match self.variant {
            Variant::Pppm => self.global_radius_sq,
            _ => self.pixels[pixel].radius_sq,
        }
    }

    /// Eye pass: each pixel's direct estimate for this pass (emission seen through specular
    /// chains plus next-event estimation at the first non-specular vertex), from a camera ray
    /// with fresh jitter, and the hit points the photons are gathered at: new every pass for
    /// SPPM and PPPM, the first pass's kept for the whole run by PPM. PPM's direct estimate
    /// re-jitters too (as SPPM's does): the image's high frequencies (light edges, texture)
    /// then converge to the pixel integral; only the photon-carried part, the smooth one, is
    /// point-sampled at the fixed hit points, as in Hachisuka et al. 2008.
    fn eye_pass(
        &mut self,
        pass: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Vec<Vec3>, Cancelled> {
        let width = self.ctx.camera.width as usize;
        let (scene, camera, seed, max_depth) = (
            &*self.ctx.scene,
            &self.ctx.camera,
            self.ctx.seed,
            self.settings.max_depth,
        );
        let keep_hit_points = self.variant == Variant::Ppm && pass > 0;
        let mut direct = vec![Vec3::ZERO; self.pixels.len()];
        let rows: Vec<PassStats> = direct
            .par_chunks_mut(width)
            .zip(self.hit_points.par_chunks_mut(width))
            .enumerate()
            .map(|(y, (direct_row, hp_row))| {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                let mut sampler = Sampler::new(seed);
                let mut eye = Sampler::new(seed ^ EYE_STREAM);
                let mut row = PassStats::default();
                for x in 0..width {
                    let pixel = (y * width + x) as u64;
                    sampler.start_pixel_sample(pixel, pass);
                    eye.start_pixel_sample(pixel, pass);
                    let film = Vec2::new(x as f32, y as f32) + eye.get_2d();
                    let path = trace_eye_path(
                        scene,
                        camera.generate_ray(film),
                        &mut eye,
                        max_depth,
                        &mut row.rays,
                    );
                    let nee = path.hit_point.as_ref().map_or(Vec3::ZERO, |hp| {
                        hp.direct(scene, &mut sampler, &mut row.rays)
                    });
                    direct_row[x] = sanitize(path.emitted + nee).unwrap_or_else(|| {
                        row.dropped += 1;
                        Vec3::ZERO
                    });
                    if !keep_hit_points {
                        hp_row[x] = path.hit_point;
                    }
                    row.samples += 1;
                }
                Ok(row)
            })
            .collect::<Result<_, _>>()?;
        for r in rows {
            *stats = *stats + r;
        }
        Ok(direct)
    }

    /// Photon pass: traces `photons` photons and returns what each pixel's hit point gathered.
    fn photon_pass(
        &self,
        pass: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        let n = self.pixels.len();
        let Some((grid, _)) = &self.grid else {
            return Ok(Gathered::new(n));
        };
        let photons = self.settings.photons;
        let chunks = rayon::current_num_threads().max(1) as u64;
        let results: Vec<(Gathered, PassStats)> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let mut gathered = Gathered::new(n);
                let mut st = PassStats::default();
                let mut sampler = Sampler::new(self.ctx.seed ^ PHOTON_STREAM);
                for i in (c * photons / chunks)..((c + 1) * photons / chunks) {
                    if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                        return Err(Cancelled);
                    }
                    sampler.start_pixel_sample(i, pass);
                    self.trace_photon(grid, &mut sampler, &mut gathered, &mut st);
                }
                Ok((gathered, st))
            })
            .collect::<Result<_, _>>()?;
        // Merge in chunk order, in parallel over pixels: the sums do not depend on scheduling.
        let mut merged = Gathered::new(n);
        merged
            .m
            .par_iter_mut()
            .zip(merged.tau.par_iter_mut())
            .zip(merged.tau_inner.par_iter_mut())
            .enumerate()
            .for_each(|(i, ((mi, ti), ii))| {
                for (g, _) in &results {
                    *mi += g.m[i];
                    *ti += g.tau[i];
                    *ii += g.tau_inner[i];
                }
            });
        for (_, st) in &results {
            *stats = *stats + *st;
        }
        Ok(merged)
    }

    fn trace_photon(
        &self,
        grid: &HashGrid,
        sampler: &mut Sampler,
        gathered: &mut Gathered,
        st: &mut PassStats,
    ) {
        let scene = &*self.ctx.scene;
        let Some((_, mut ray, mut flux)) = emit_photon(scene, sampler) else {
            return;
        };
        for depth in 0..self.settings.max_depth {
            st.rays += 1;
            let Some(si) = scene.intersect(&ray) else {
                break;
            };
            let bsdf = scene.bsdf(&si);
            // Direct light is next-event estimation's: photons count from their second hit on.
            if depth > 0 && !bsdf.is_delta() {
                let wi = -ray.d;
                for &c in grid.candidates(si.p) {
                    let c = c as usize;
                    let Some(hp) = &self.hit_points[c] else {
                        continue;
                    };
                    let dist_sq = (si.p - hp.si.p).length_squared() as f64;
                    let radius_sq = self.radius_sq(c);
                    if dist_sq > radius_sq {
                        continue;
                    }
                    let r = hp.response(wi, si.n);
                    if r == Vec3::ZERO {
                        continue;
                    }
                    let contribution = (r * flux).as_dvec3();
                    if contribution.is_finite() && contribution.min_element() >= 0.0 {
                        gathered.m[c] += 1;
                        gathered.tau[c] += contribution;
                        if dist_sq <= INNER_RADIUS_RATIO * INNER_RADIUS_RATIO * radius_sq {
                            gathered.tau_inner[c] += contribution;
                        }
                    } else {
                        st.dropped += 1;
                    }
                }
            }
            let wo = si.shading.to_local(-ray.d);
            let Some(next) = scatter(&si, &bsdf, wo, sampler, TransportMode::Importance) else {
                break;
            };
            let new_flux = flux * next.weight;
            // Russian roulette on the change of power (pbrt-v4 SPPM, section 13.8.3).
            let q = (1.0 - luminance(new_flux) / luminance(flux).max(f32::MIN_POSITIVE)).max(0.0);
            if sampler.get_1d() < q {
                break;
            }
            flux = new_flux / (1.0 - q);
            if !flux.is_finite() || flux == Vec3::ZERO {
                break;
            }
            ray = next.ray;
        }
    }

    /// The photon-carried radiance of a PPM or SPPM pixel: tau / (pi R^2 N_emitted).
    fn indirect(&self, pixel: usize) -> DVec3 {
        let px = &self.pixels[pixel];
        if self.photons_emitted > 0 && px.radius_sq > 0.0 {
            px.tau / (std::f64::consts::PI * px.radius_sq * self.photons_emitted as f64)
        } else {
            DVec3::ZERO
        }
    }

    /// PPM's error from gathering at one fixed point per pixel (module docs): the variance of
    /// the indirect radiance over each pixel's footprint, from the squared second differences
    /// of the indirect image less the noise in them. Added to the pixels' variance, as the
    /// hit point's position is random like the noise. A pixel whose eye path found no hit
    /// point counts with an indirect radiance of zero: that is what its footprint gave there
    /// (through glass, where the one specular choice PPM keeps per pixel decides it, this
    /// took the estimate on the caustic pool from a third of the truth to within 10 %).
    fn add_footprint_variance(&self, pixels: &mut [PixelError]) {
        let (w, h) = (
            self.ctx.camera.width as usize,
            self.ctx.camera.height as usize,
        );
        let indirect: Vec<DVec3> = (0..self.pixels.len())
            .into_par_iter()
            .map(|i| self.indirect(i))
            .collect();
        let noise: Vec<DVec3> = pixels.iter().map(|p| p.variance).collect();
        // The pixel's converged value is the mean over its footprint, which its neighbours
        // sample too: the footprint error is relative to the neighbourhood's mean, not to the
        // pixel's own value, which misses a bright feature thinner than a pixel whenever its
        // hit point does (measured on the door, whose lit gap is a pixel wide: dividing by the
        // pixel's own r^2 overestimated the relMSE 49 times).
        let n = self.passes.max(1) as f64;
        let values: Vec<DVec3> = (0..self.pixels.len())
            .map(|i| self.pixels[i].direct_sum / n + indirect[i])
            .collect();
        let footprint_mean = error_estimate::box_filter_3x3(&values, w, h);
        pixels
            .par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, pixel) in row.iter_mut().enumerate() {
                    let i = y * w + x;
                    let mut sum = DVec3::ZERO;
                    let mut count = 0.0;
                    let horizontal = (x > 0 && x + 1 < w).then(|| (i - 1, i + 1));
                    let vertical = (y > 0 && y + 1 < h).then(|| (i - w, i + w));
                    for b in [horizontal, vertical].into_iter().flatten() {
                        let d = indirect[i] - 0.5 * (indirect[b.0] + indirect[b.1]);
                        sum += d * d - noise[i] - 0.25 * (noise[b.0] + noise[b.1]);
                        count += 1.0;
                    }
                    if count > 0.0 {
                        let variance = (sum / (1.5 * count)).max(DVec3::ZERO);
                        // Expressed over the pixel's own denominator, as the film's variance is.
                        let own = pixel.reference_sq + error_estimate::REL_MSE_EPSILON;
                        let mean_sq = footprint_mean[i] * footprint_mean[i];
                        let footprint = mean_sq + error_estimate::REL_MSE_EPSILON;
                        pixel.variance += variance * own / footprint;
                    }
                }
            });
    }

    fn record_radius(&mut self) {
        let radii: Vec<f64> = (0..self.pixels.len())
            .filter(|&i| self.hit_points[i].is_some())
            .map(|i| self.radius_sq(i).sqrt())
            .collect();
        if radii.is_empty() || self.passes % self.history_stride != 0 {
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
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let mut stats = PassStats::default();
        let direct = self.eye_pass(pass, cancel, &mut stats)?;
        self.update_grid(pass);
        let gathered = self.photon_pass(pass, cancel, &mut stats)?;
        let alpha = self.settings.alpha;
        let photons = self.settings.photons;
        for (i, px) in self.pixels.iter_mut().enumerate() {
            // This pass's estimate with the radius it gathered with, and its bias estimate
            // (module docs): both before the radius shrinks.
            let radius_sq = match self.variant {
                Variant::Pppm => self.global_radius_sq,
                _ => px.radius_sq,
            };
            let area = std::f64::consts::PI * radius_sq * photons as f64;
            let indirect = gathered.tau[i] / area;
            let estimate = direct[i].as_dvec3() + indirect;
            let inner_area = INNER_RADIUS_RATIO * INNER_RADIUS_RATIO * area;
            let bias = BIAS_FACTOR * (indirect - gathered.tau_inner[i] / inner_area);
            px.estimate_sum += estimate;
            px.estimate_sum_sq += estimate * estimate;
            if pass % 2 == 1 {
                px.odd_estimate_sum += estimate;
            }
            px.bias_sum += bias;
            px.bias_sum_sq += bias * bias;
            px.photons_counted += gathered.m[i] as u64;
            px.direct_sum += direct[i].as_dvec3();
            if self.variant == Variant::Pppm || gathered.m[i] == 0 {
                continue;
            }
            // Hachisuka et al. 2008, eqs. 5-7.
            let (n, mf) = (px.n, gathered.m[i] as f64);
            let ratio = (n + alpha * mf) / (n + mf);
            px.n = n + alpha * mf;
            px.radius_sq = (px.radius_sq * ratio).max(self.radius_floor_sq);
            px.tau = (px.tau + gathered.tau[i]) * ratio;
        }
        if self.variant == Variant::Pppm {
            // Knaus & Zwicker 2011: the next pass's global radius, eq. 20.
            let k = (pass + 1) as f64;
            self.global_radius_sq =
                (self.global_radius_sq * (k + alpha) / (k + 1.0)).max(self.radius_floor_sq);
        }
        self.photons_emitted += photons;
        self.passes += 1;
        self.record_radius();
        Ok(stats)
    }

    fn image(&self) -> Image {
        let w = self.ctx.camera.width as usize;
        let h = self.ctx.camera.height as usize;
        let n = self.passes.max(1) as f64;
        let pixels = (0..self.pixels.len())
            .map(|i| {
                let l = match self.variant {
                    // Knaus & Zwicker 2011: the mean of independent photon-map estimates.
                    Variant::Pppm => self.pixels[i].estimate_sum / n,
                    _ => self.pixels[i].direct_sum / n + self.indirect(i),
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

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        if self.passes < 2 {
            return None;
        }
        let n = self.passes;
        let image = self.image();
        let (n_odd, n_even) = ((n / 2) as f64, n.div_ceil(2) as f64);
        let odd: Vec<DVec3> = self
            .pixels
            .par_iter()
            .map(|p| p.odd_estimate_sum / n_odd)
            .collect();
        let even: Vec<DVec3> = self
            .pixels
            .par_iter()
            .map(|p| (p.estimate_sum - p.odd_estimate_sum) / n_even)
            .collect();
        let (w, h) = (image.width, image.height);
        let robust = error_estimate::robust_reference_sq(&[odd, even], w, h);
        // The kernel bias lifts x on the dark side of every edge, just where the squared bias
        // is largest relative to r^2: r is taken below x by the bias estimate there, the
        // pixel's own where it stands out of its noise, else the neighbourhood's mean (the
        // estimate is three times noisier than x). The own one matters where a bias is the
        // pixel's alone: a fixed PPM hit point beside the door's lit gap reads several times
        // its converged value for the whole run, and the neighbourhood's mean, a ninth of
        // it, left the estimate at a sixth of the true relMSE.
        let own_bias: Vec<(DVec3, DVec3, BVec3)> = self
            .pixels
            .par_iter()
            .zip(&image.pixels)
            .map(|(p, x)| {
                let variance = error_estimate::variance_of_mean(p.bias_sum, p.bias_sum_sq, n);
                let (bias, significant) =
                    significant_bias(p.bias_sum / n as f64, variance, x.as_dvec3(), n);
                (bias, variance, significant)
            })
            .collect();
        let smoothed_bias: Vec<DVec3> = own_bias.iter().map(|b| b.0).collect();
        let smoothed_bias = error_estimate::box_filter_3x3(&smoothed_bias, w, h);
        let reference_sq: Vec<DVec3> = (0..self.pixels.len())
            .into_par_iter()
            .map(|i| {
                // A bias well above its noise is the pixel's own (PPM's fixed hit point beside
                // a bright region); below it, the neighbourhood's is less noisy.
                let (own, _, significant) = own_bias[i];
                let bias = DVec3::select(significant, own, smoothed_bias[i]);
                let corrected = (image.pixels[i].as_dvec3() - bias).max(DVec3::ZERO);
                let r = robust[i].map(f64::sqrt).min(corrected);
                r * r
            })
            .collect();
        let mut pixels: Vec<PixelError> = self
            .pixels
            .par_iter()
            .zip(reference_sq.into_par_iter())
            .zip(&own_bias)
            .map(
                |((px, reference_sq), &(bias, bias_variance, _))| PixelError {
                    variance: error_estimate::variance_of_mean(
                        px.estimate_sum,
                        px.estimate_sum_sq,
                        n,
                    ),
                    bias_sq: bias * bias - bias_variance,
                    reference_sq,
                },
            )
            .collect();
        if self.variant == Variant::Ppm {
            self.add_footprint_variance(&mut pixels);
        }
        ErrorEstimate::from_pixels(image.width, image.height, &pixels)
    }

    fn set_live_param(&mut self, name: &str, value: f64) -> bool {
        match name {
            "alpha" => self.settings.alpha = value.clamp(1e-3, 1.0),
            "photons" => self.settings.photons = value.max(1.0) as u64,
            _ => return false,
        }
        true
    }

    fn plots(&self) -> Vec<PlotSeries> {
        let series = |name: &str, f: fn(&[f64; 3]) -> f64| PlotSeries {
            plot: "Radius".into(),
            name: name.into(),
            kind: PlotKind::Line,
            x_label: "passes".into(),
            y_label: "radius".into(),
            points: self.radius_history.iter().map(|h| [h[0], f(h)]).collect(),
        };
        vec![
            series("mean", |h| h[1]),
            series("mean - sd", |h| h[1] - h[2]),
            series("mean + sd", |h| h[1] + h[2]),
        ]
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_significant_bias_is_bounded_by_the_value_and_noise_is_left_alone() {
        let x = DVec3::new(4.0, 4.0, 0.1);
        // Red: 7 +- 0.3, clamped at x; green: 7 +- 10, noise, kept; blue: -2 +- 0.1, a
        // negative bias (the bright side of an edge), which the value does not bound.
        let bias = DVec3::new(7.0, 7.0, -2.0);
        let variance = DVec3::new(0.09, 100.0, 0.01);
        assert_eq!(
            significant_bias(bias, variance, x, 8),
            (DVec3::new(4.0, 7.0, -2.0), BVec3::new(true, false, true))
        );
        // From too few passes nothing is significant.
        assert_eq!(significant_bias(bias, variance, x, 4), (bias, BVec3::FALSE));
    }
}
