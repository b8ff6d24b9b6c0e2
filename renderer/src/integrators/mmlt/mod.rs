//! Multiplexed Metropolis light transport (Hachisuka, Kaplanyan & Dachsbacher 2014, "primary
//! space serial tempering"): Metropolis chains in primary sample space over bidirectional
//! paths of a fixed length, whose state also selects the technique (s, t) that maps it to a
//! path, targeting the MIS-weighted contribution, so a chain settles on the techniques that
//! suit each region (DESIGN.md section 5).
//!
//! Light that reaches the camera in fewer than `FIRST_CHAIN_LENGTH` bounces (emitters seen
//! directly, direct illumination) is not left to the chains: each pass also renders it by path
//! tracing to that depth, one stratified sample per pixel (Mitsuba's MLT integrators do the
//! same, their `directSamples`), because the chains' target is brightness, not difficulty.
//! The two parts estimate disjoint sets of paths, so the image is their sum and its variance
//! the sum of theirs.
//!
//! A pass is width x height steps shared equally among the chains; chains run in parallel
//! and their splats are merged in chain order. Before the first pass the bootstrap runs in
//! preparation steps (`Integrator::preparing`) of growing size, and the image meanwhile is the
//! bootstrap samples' own: independent samples of every path length, an unbiased estimate
//! (each pixel: width x height over the samples, times the sum of the contributions that
//! landed in it), so the first image comes at once however large the bootstrap.
//!
//! The chains are dealt into `CHAIN_GROUPS` groups with the same mix of path lengths, each
//! group's chains starting from its own disjoint share of the bootstrap samples
//! (`bootstrap::Seeding`), so that the groups are independent and identically distributed
//! estimates of the image; the image is their mean. Every estimate is normalised (pbrt-v3
//! section 16.4.4: b over the steps per pixel) per path length: in group g, a pass's splats
//! from a chain of length k carry weight b_k / c_{k,g}, c_{k,g} the group's number of chains
//! of that length, so the image does not depend on how the random seeding happened to split
//! the chains between lengths. b_k starts as the bootstrap's mean and is refined after every
//! pass with the target values of the pass's large-step proposals, which are independent
//! uniform samples (Kelemen et al. 2002), so the bootstrap's error fades as the run goes on.
//! What each of these choices was measured against is in DESIGN.md section 5.
//!
//! Remaining error: `error.rs`.

pub mod bootstrap;
pub mod chain;
mod error;
pub mod histogram;
pub mod path_sample;
mod report;
mod settings;
pub mod technique_choice;

use crate::error_estimate::ErrorEstimate;
use crate::film::Film;
use crate::image::Image;
use crate::integrators::path_tracer::PathSettings;
use crate::integrators::pixel_pass::{PixelEstimator, Row, pixel_pass};
use crate::integrators::{
    Cancelled, Integrator, ParamValues, PassStats, PlotSeries, RenderContext,
};
use crate::sampling::sampler::Sampler;
use chain::{Chain, ChainOutput};
use glam::{DVec3, Vec3};
use histogram::TechniqueHistogram;
use path_sample::{Subpaths, slot_count};
use rayon::prelude::*;
pub use report::technique_name;
pub use settings::MmltSettings;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(Mmlt::new(ctx, MmltSettings::from_params(params)))
}

const CHAIN_SEEDING: u64 = 0x3e7a_0c4a_1a55_0001;
/// Independent groups of chains (module docs): 4 gives the error estimate 3 degrees of freedom
/// per pixel for the cost of 4 splat buffers (96 bytes a pixel).
pub const CHAIN_GROUPS: usize = 4;
const CHAIN_KEYS: u64 = 1 << 62;
/// The shortest path, in bounces, that chains sample; shorter ones are path traced per pixel
/// (module docs).
pub const FIRST_CHAIN_LENGTH: usize = 2;
/// More chains per distinct start path than this, in a slot, and the user is told
/// (`Mmlt::few_starts`).
const CHAINS_PER_START: f64 = 4.0;
/// Keeps the direct pass's random numbers apart from the chains' and the bootstrap's.
const DIRECT_SEEDING: u64 = 0x5d1e_c7a1_1d1e_0002;

enum Phase {
    /// The bootstrap runs, a chunk of samples per preparation step: the target values so far
    /// (every slot of each sample), summed per path length, with the rays traced and samples
    /// dropped, and the samples' contributions summed per pixel.
    Bootstrapping {
        luminance: Vec<f64>,
        per_path_length: Vec<f64>,
        rays: u64,
        dropped: u64,
        splats: Vec<DVec3>,
    },
    /// Nothing reaches the camera: every bootstrap sample was black.
    Black,
    Running {
        chains: Vec<Chain>,
        /// The group of each chain.
        chain_groups: Vec<usize>,
        /// c_{k,g}: chains of each length in each group ([g][k]).
        chains_per_length: Vec<Vec<u64>>,
        groups: usize,
        /// Sum, sum of squares and count of the target values behind each b_k.
        b_sum: Vec<f64>,
        b_sum_sq: Vec<f64>,
        b_count: Vec<u64>,
    },
}

pub struct Mmlt {
    ctx: RenderContext,
    settings: MmltSettings,
    phase: Phase,
    /// Weighted splats of each group of chains.
    group_splats: Vec<Vec<DVec3>>,
    steps: u64,
    steps_per_chain: u64,
    /// Share of b in path lengths that got no chain (lost to the image).
    unsampled_share: f64,
    b_standard_error: f64,
    histogram: TechniqueHistogram,
    bootstrap_per_length: Vec<f64>,
    /// b per path length from the bootstrap (the shared slot's lengths apart).
    bootstrap_per_path_length: Vec<f64>,
    /// Per slot, the bootstrap samples with light and how many distinct paths they amount to
    /// as chain starts (`Bootstrap::effective_samples`).
    bootstrap_lit: Vec<u64>,
    bootstrap_effective: Vec<f64>,
    /// Paths shorter than `FIRST_CHAIN_LENGTH`, path traced one sample per pixel and pass.
    direct: Film,
    direct_buffer: Vec<Vec3>,
    /// Some direct pass found light.
    direct_lit: bool,
    /// Sum over passes of each pass's image from its large-step proposals alone, and how many
    /// passes it holds: an estimate of the chains' part independent of where they linger,
    /// for the error estimate's denominator (module docs).
    large_step_image: Vec<DVec3>,
    large_step_passes: u64,
    /// Wall-clock seconds spent in the bootstrap, the chains and the direct part (for the
    /// statistics: how much of a run the bootstrap takes).
    seconds: PhaseSeconds,
}

#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
struct PhaseSeconds {
    bootstrap: f64,
    chains: f64,
    direct: f64,
}

impl Mmlt {
    pub fn new(ctx: RenderContext, settings: MmltSettings) -> Self {
        let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
        let pixels = w * h;
        let phase = if (settings.max_depth as usize) < FIRST_CHAIN_LENGTH {
            // Every path is short enough for the direct pass: no chain has anything to do.
            Phase::Black
        } else {
            Phase::Bootstrapping {
                luminance: Vec::new(),
                per_path_length: vec![0.0; settings.max_depth as usize + 1],
                rays: 0,
                dropped: 0,
                splats: vec![DVec3::ZERO; pixels],
            }
        };
        Mmlt {
            ctx,
            settings,
            phase,
            group_splats: vec![vec![DVec3::ZERO; pixels]; CHAIN_GROUPS],
            steps: 0,
            steps_per_chain: 0,
            unsampled_share: 0.0,
            b_standard_error: 0.0,
            histogram: TechniqueHistogram::new(settings.max_depth as usize),
            bootstrap_per_length: Vec::new(),
            bootstrap_per_path_length: Vec::new(),
            bootstrap_lit: Vec::new(),
            bootstrap_effective: Vec::new(),
            direct: Film::new(w, h),
            direct_buffer: vec![Vec3::ZERO; pixels],
            direct_lit: false,
            large_step_image: vec![DVec3::ZERO; pixels],
            large_step_passes: 0,
            seconds: PhaseSeconds::default(),
        }
    }

    /// One pass of the paths the chains leave out (module docs): path tracing to
    /// `FIRST_CHAIN_LENGTH - 1` bounces, one sample per pixel. Its rays and dropped samples
    /// count in the pass's statistics, its samples do not (MMLT's samples are chain steps).
    fn direct_pass(&mut self, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let settings = PathSettings {
            max_depth: self.settings.max_depth.min(FIRST_CHAIN_LENGTH as u32 - 1),
            rr_depth: FIRST_CHAIN_LENGTH as u32,
        };
        let ctx = &self.ctx;
        let stats = pixel_pass(
            &mut self.direct_buffer,
            self.direct.width,
            ctx.seed ^ DIRECT_SEEDING,
            self.direct.passes(),
            cancel,
            |film, row: &mut Row<()>| settings.sample_pixel(ctx, film, row),
        )?;
        self.direct.add_pass(&self.direct_buffer);
        self.direct_lit |= self.direct_buffer.iter().any(|v| *v != Vec3::ZERO);
        Ok(PassStats {
            samples: 0,
            ..stats
        })
    }

    /// What turns a group's weighted splats into its estimate of the image: pixels over the
    /// steps per chain (splats carry b_k / c_{k,g}; the steps of length k in group g are
    /// c_{k,g} times the steps per chain). The image is the mean of the groups' estimates.
    fn group_scale(&self) -> Option<f64> {
        let (w, h) = (self.ctx.camera.width, self.ctx.camera.height);
        (matches!(self.phase, Phase::Running { .. }) && self.steps_per_chain > 0)
            .then(|| (w * h) as f64 / self.steps_per_chain as f64)
    }

    fn groups(&self) -> usize {
        match &self.phase {
            Phase::Running { groups, .. } => *groups,
            _ => 0,
        }
    }

    pub fn histogram(&self) -> &TechniqueHistogram {
        &self.histogram
    }

    /// The normalisation b (None before the bootstrap).
    pub fn normalisation(&self) -> Option<f64> {
        match &self.phase {
            Phase::Bootstrapping { .. } => None,
            Phase::Black => Some(0.0),
            Phase::Running { b_sum, b_count, .. } => Some(
                b_sum
                    .iter()
                    .zip(b_count)
                    .map(|(s, &n)| s / n.max(1) as f64)
                    .sum(),
            ),
        }
    }

    /// One preparation step: the next chunk of bootstrap samples; after the last, the chains
    /// start from them.
    fn bootstrap_step(
        &mut self,
        stats: &mut PassStats,
        cancel: &AtomicBool,
    ) -> Result<(), Cancelled> {
        let (scene, camera, seed) = (&*self.ctx.scene, &self.ctx.camera, self.ctx.seed);
        let max_depth = self.settings.max_depth as usize;
        let (lengths, total) = (slot_count(max_depth), self.settings.bootstrap as usize);
        let Phase::Bootstrapping {
            luminance,
            per_path_length,
            rays,
            dropped,
            splats,
        } = &mut self.phase
        else {
            return Ok(());
        };
        let chunk = bootstrap::next_chunk(luminance.len() / lengths, total);
        let evaluated =
            bootstrap::evaluate_samples(scene, camera, seed, chunk.clone(), max_depth, cancel)?;
        let width = camera.width as usize;
        for e in &evaluated {
            luminance.push(e.luminance);
            per_path_length[e.k] += e.luminance;
            *rays += e.rays;
            *dropped += u64::from(e.invalid);
            let (x, y) = (e.raster.x as usize, e.raster.y as usize);
            if let Some(pixel) = splats.get_mut(y * width + x.min(width - 1)) {
                *pixel += e.l.as_dvec3();
            }
        }
        stats.rays += evaluated.iter().map(|e| e.rays).sum::<u64>();
        stats.dropped += evaluated.iter().filter(|e| e.invalid).count() as u64;
        stats.samples += (chunk.len() * (lengths - FIRST_CHAIN_LENGTH)) as u64;
        if chunk.end < total {
            return Ok(());
        }
        let boot = bootstrap::Bootstrap::from_luminance(
            std::mem::take(luminance),
            lengths,
            *rays,
            *dropped,
        );
        let samples = total as f64;
        self.bootstrap_per_path_length = per_path_length.iter().map(|l| l / samples).collect();
        self.start(boot, stats)
    }

    /// Seeds the chains from the finished bootstrap.
    fn start(
        &mut self,
        boot: bootstrap::Bootstrap,
        stats: &mut PassStats,
    ) -> Result<(), Cancelled> {
        let (scene, camera, seed) = (&*self.ctx.scene, &self.ctx.camera, self.ctx.seed);
        let max_depth = self.settings.max_depth as usize;
        self.bootstrap_per_length = boot.per_length.clone();
        self.bootstrap_lit = boot.lit_per_length.clone();
        self.bootstrap_effective = boot.effective_samples();
        if !(boot.b > 0.0) {
            self.phase = Phase::Black;
            return Ok(());
        }
        let lengths = slot_count(max_depth);
        let groups = CHAIN_GROUPS.min(self.settings.chains as usize);
        let seeding = bootstrap::Seeding::new(&boot.luminance, lengths, groups);
        // Every chain's length first; chains of each length are then dealt to the groups in
        // turn, so that all groups get the same mix of lengths.
        let mut picks: Vec<Sampler> = (0..self.settings.chains)
            .map(|c| {
                let mut pick = Sampler::new(seed ^ CHAIN_SEEDING);
                pick.start_pixel_sample(c, 0);
                pick
            })
            .collect();
        // Every group first gets one chain of each slot the bootstrap found light in, so that
        // no group's image misses a slot (a group without one would differ from the others by
        // that slot's whole light, and their spread is the error estimate); the rest are drawn
        // in proportion to the light.
        let lit: Vec<usize> = (0..lengths).filter(|&k| boot.per_length[k] > 0.0).collect();
        let reserved = if lit.len() * groups <= picks.len() {
            lit.len() * groups
        } else {
            0
        };
        let mut dealt = vec![0usize; lengths];
        let assignments: Vec<(usize, usize, f32)> = picks
            .iter_mut()
            .enumerate()
            .map(|(c, pick)| {
                let u = pick.get_1d();
                let k = if c < reserved {
                    lit[c / groups]
                } else {
                    seeding.length(u)
                };
                let group = dealt[k] % groups;
                dealt[k] += 1;
                (group, k, pick.get_1d())
            })
            .collect();
        let chains: Vec<(Chain, usize, u64)> = assignments
            .par_iter()
            .enumerate()
            .map_init(Subpaths::default, |scratch, (c, &(group, k, u))| {
                let i = seeding.start(group, k, u);
                let mut rays = 0;
                let chain = Chain::start(
                    scene,
                    camera,
                    seed,
                    bootstrap::bootstrap_key(i, k, max_depth),
                    CHAIN_KEYS + c as u64,
                    k,
                    max_depth,
                    scratch,
                    &mut rays,
                );
                (chain, group, rays)
            })
            .collect();
        stats.rays += chains.iter().map(|c| c.2).sum::<u64>();
        let mut per_length = vec![vec![0u64; lengths]; groups];
        for (chain, group, _) in &chains {
            per_length[*group][chain.slot] += 1;
        }
        // Each group's image misses the lengths it has no chain of; the image, their mean,
        // misses the mean share.
        self.unsampled_share = per_length
            .iter()
            .map(|group| {
                (0..lengths)
                    .filter(|&k| group[k] == 0)
                    .map(|k| boot.per_length[k])
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (boot.b * groups as f64);
        self.b_standard_error = boot.standard_error;
        let samples = self.settings.bootstrap;
        self.phase = Phase::Running {
            chain_groups: chains.iter().map(|c| c.1).collect(),
            chains: chains.into_iter().map(|c| c.0).collect(),
            chains_per_length: per_length,
            groups,
            b_sum: boot.per_length.iter().map(|b| b * samples as f64).collect(),
            b_sum_sq: boot
                .per_length_mean_sq
                .iter()
                .map(|m| m * samples as f64)
                .collect(),
            b_count: vec![samples; lengths],
        };
        Ok(())
    }

    /// One pass of the chains: width x height steps shared among them, their splats added to
    /// their groups' images, their large steps to b and the large-step image.
    fn chains_pass(&mut self, stats: &mut PassStats, cancel: &AtomicBool) -> Result<(), Cancelled> {
        let Phase::Running {
            chains,
            chain_groups,
            chains_per_length,
            groups: _,
            b_sum,
            b_sum_sq,
            b_count,
        } = &mut self.phase
        else {
            return Ok(());
        };
        let (scene, camera) = (&*self.ctx.scene, &self.ctx.camera);
        let pixels = (camera.width * camera.height) as u64;
        let n = chains.len() as u64;
        let steps = pixels.div_ceil(n);
        let (p_large, sigma) = (
            self.settings.large_step_prob as f32,
            self.settings.sigma as f32,
        );
        let max_depth = self.settings.max_depth as usize;
        // One histogram per piece of work rayon splits the chains into, not one per chain:
        // a histogram is (max_depth + 1)(max_depth + 4) / 2 counters, and a small image gives
        // each chain only a step or two a pass (24 x 24 pixels over 1000 chains at depth 64:
        // allocating, zeroing and merging a histogram per chain was half of the pass). Counts
        // add up in any order, so the histogram does not depend on the split.
        let mut outputs: Vec<ChainOutput> = chains.iter().map(|_| ChainOutput::default()).collect();
        let histogram = chains
            .par_iter_mut()
            .zip(outputs.par_iter_mut())
            .try_fold(
                || (Subpaths::default(), TechniqueHistogram::new(max_depth)),
                |(mut scratch, mut histogram), (chain, out)| {
                    if cancel.load(Ordering::Relaxed) {
                        return Err(Cancelled);
                    }
                    chain.run(
                        scene,
                        camera,
                        steps,
                        p_large,
                        sigma,
                        &mut scratch,
                        &mut histogram,
                        out,
                        cancel,
                    )?;
                    Ok((scratch, histogram))
                },
            )
            .map(|piece| piece.map(|(_, histogram)| histogram))
            .try_reduce_with(|mut a, b| {
                a.merge(&b);
                Ok(a)
            })
            .transpose()?;
        if let Some(histogram) = histogram {
            self.histogram.merge(&histogram);
        }
        // This pass's weights, b_k / c_{k,g}, come from b_k as it was before the pass.
        let b: Vec<f64> = (0..b_sum.len())
            .map(|k| b_sum[k] / b_count[k] as f64)
            .collect();
        // A large step is proposed with probability p_large at each of a slot's steps, so the
        // pass proposes chains_k x steps x p_large of them in expectation: each one landing in
        // a pixel adds L times pixels over that count, an unbiased image (as the bootstrap's).
        let large_steps_expected: Vec<f64> = chains_per_slot(chains_per_length)
            .iter()
            .map(|&chains_k| (chains_k * steps) as f64 * p_large as f64)
            .collect();
        let large_step_pass = p_large > 0.0;
        self.large_step_passes += u64::from(large_step_pass);
        for (c, (out, chain)) in outputs.into_iter().zip(chains.iter()).enumerate() {
            let g = chain_groups[c];
            if large_step_pass {
                let weight = pixels as f64 / large_steps_expected[chain.slot];
                for (i, v) in &out.large_step_splats {
                    self.large_step_image[*i] += v.as_dvec3() * weight;
                }
            }
            let weight = b[chain.slot] / chains_per_length[g][chain.slot].max(1) as f64;
            add_splats(&mut self.group_splats[g], &out.splats, weight);
            b_sum[chain.slot] += out.large_step_sum;
            b_sum_sq[chain.slot] += out.large_step_sum_sq;
            b_count[chain.slot] += out.large_steps;
            self.steps += steps;
            stats.samples += steps;
            stats.rays += out.rays;
            stats.dropped += out.dropped;
        }
        self.steps_per_chain += steps;
        Ok(())
    }
}

/// A chain's splats, each weighted by b_k / c_{k,g}, added to its group's sums (f64: they
/// grow for as long as the render runs).
fn add_splats(group: &mut [DVec3], splats: &[(usize, Vec3)], weight: f64) {
    for &(i, v) in splats {
        group[i] += v.as_dvec3() * weight;
    }
}

/// Chains of each slot over all groups, from c_{k,g} ([g][k]).
fn chains_per_slot(chains_per_length: &[Vec<u64>]) -> Vec<u64> {
    let slots = chains_per_length.first().map_or(0, Vec::len);
    (0..slots)
        .map(|k| chains_per_length.iter().map(|g| g[k]).sum())
        .collect()
}

impl Integrator for Mmlt {
    fn preparing(&self) -> Option<f32> {
        match &self.phase {
            Phase::Bootstrapping { luminance, .. } => {
                let lengths = slot_count(self.settings.max_depth as usize);
                Some((luminance.len() / lengths) as f32 / self.settings.bootstrap.max(1) as f32)
            }
            _ => None,
        }
    }

    fn memory_bytes(&self) -> usize {
        use std::mem::size_of_val;
        let phase = match &self.phase {
            Phase::Bootstrapping {
                luminance,
                per_path_length,
                splats,
                ..
            } => {
                size_of_val(luminance.as_slice())
                    + size_of_val(per_path_length.as_slice())
                    + size_of_val(splats.as_slice())
            }
            Phase::Black => 0,
            Phase::Running {
                chains,
                chain_groups,
                chains_per_length,
                b_sum,
                b_sum_sq,
                b_count,
                ..
            } => {
                chains.iter().map(Chain::memory_bytes).sum::<usize>()
                    + size_of_val(chain_groups.as_slice())
                    + chains_per_length
                        .iter()
                        .map(|c| size_of_val(c.as_slice()))
                        .sum::<usize>()
                    + size_of_val(b_sum.as_slice())
                    + size_of_val(b_sum_sq.as_slice())
                    + size_of_val(b_count.as_slice())
            }
        };
        let histogram: usize = (self.histogram.lengths.iter())
            .map(|l| size_of_val(l) + size_of_val(l.steps_in_technique.as_slice()))
            .sum();
        phase
            + histogram
            + (self.group_splats.iter())
                .map(|g| size_of_val(g.as_slice()))
                .sum::<usize>()
            + self.direct.memory_bytes()
            + size_of_val(self.direct_buffer.as_slice())
            + size_of_val(self.large_step_image.as_slice())
    }

    fn render_pass(&mut self, _pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let started = Instant::now();
        let mut stats = self.direct_pass(cancel)?;
        self.seconds.direct += started.elapsed().as_secs_f64();
        let started = Instant::now();
        if self.preparing().is_some() {
            self.bootstrap_step(&mut stats, cancel)?;
            self.seconds.bootstrap += started.elapsed().as_secs_f64();
            return Ok(stats);
        }
        let result = self.chains_pass(&mut stats, cancel);
        self.seconds.chains += started.elapsed().as_secs_f64();
        result.map(|()| stats)
    }

    fn image(&self) -> Image {
        let (w, h) = (
            self.ctx.camera.width as usize,
            self.ctx.camera.height as usize,
        );
        let mut img = self.direct.image();
        if let Phase::Bootstrapping {
            luminance, splats, ..
        } = &self.phase
        {
            let done = luminance.len() / slot_count(self.settings.max_depth as usize);
            let scale = (w * h) as f64 / done.max(1) as f64;
            for (p, s) in img.pixels.iter_mut().zip(splats) {
                *p += crate::film::sanitize((*s * scale).as_vec3()).unwrap_or_default();
            }
        }
        if let Some(scale) = self.group_scale() {
            let scale = scale / self.groups().max(1) as f64;
            for (i, p) in img.pixels.iter_mut().enumerate() {
                let s: DVec3 = self.group_splats.iter().map(|g| g[i]).sum();
                *p += crate::film::sanitize((s * scale).as_vec3()).unwrap_or_default();
            }
        }
        img
    }

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.estimate_error()
    }

    fn set_live_param(&mut self, name: &str, value: f64) {
        match name {
            "large_step" => self.settings.large_step_prob = value,
            "sigma" => self.settings.sigma = value,
            _ => debug_assert!(false, "{name} is not live"),
        }
    }

    fn plots(&self) -> Vec<PlotSeries> {
        self.technique_plots()
    }

    fn messages(&self) -> Vec<String> {
        self.warnings()
    }

    fn statistics(&self) -> Option<serde_json::Value> {
        Some(self.statistics_json())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten million passes of splats into one pixel (two groups, three steps a chain each pass,
    /// every step splatting 0.1 with weight b_k / c_{k,g} = 0.3): the image, the sums times
    /// pixels over steps per chain over groups (`group_scale`), stays at 0.03 within 1e-6 and
    /// the step counters (6 x 10^7) are exact.
    #[test]
    fn ten_million_splat_passes_keep_the_image() {
        let (passes, steps, groups) = (10_000_000u64, 3u64, 2usize);
        let mut group_splats = vec![vec![DVec3::ZERO; 1]; groups];
        let splats = vec![(0usize, Vec3::splat(0.1)); steps as usize];
        let (mut steps_per_chain, mut all_steps) = (0u64, 0u64);
        for _ in 0..passes {
            for group in &mut group_splats {
                add_splats(group, &splats, 0.3);
                all_steps += steps;
            }
            steps_per_chain += steps;
        }
        let scale = 1.0 / steps_per_chain as f64 / groups as f64;
        let pixel: DVec3 = group_splats.iter().map(|g| g[0]).sum::<DVec3>() * scale;
        let exact = f64::from(0.1f32) * 0.3;
        assert!(
            ((pixel.x - exact) / exact).abs() < 1e-6,
            "{pixel} against {exact}"
        );
        assert_eq!(all_steps, passes * steps * groups as u64);
    }
}
