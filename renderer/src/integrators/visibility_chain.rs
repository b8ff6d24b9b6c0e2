//! What every visibility chain keeps (Hachisuka & Jensen 2011, "Robust adaptive photon
//! tracing using photon path visibility"): the counters of its uniform proposals and
//! mutations, the adaptation of its mutation size, the normalisation of its pass, and the
//! run's history of them for the viewer's plots and `render --stats`. amcppm's photon chains
//! (`ppm/metropolis.rs`) and amcvcm's light-subpath chains (`vcm/metropolis.rs`) differ only
//! in what a state is and what it brings to the image.
//!
//! A chain's target is a path's visibility V(u) in primary sample space: 1 when the path
//! brings anything to this pass's image, 0 otherwise. Each pass a chain starts at its first
//! visible uniform sample (an exact draw from the pass's target); then each iteration
//! proposes a uniform sample with probability `large_step_prob` (the replica at infinite
//! temperature, whose exchange with the chain is accepted when it is visible) and otherwise a
//! small step of size delta, accepted when visible. The estimate of a path's mean
//! contribution is v x (the mean over the chain's states, each counted for every iteration it
//! was held), so over P iterations each state's contribution is weighted by
//! P v / n_chain, with n_chain the iterations since the chain's first visible sample: the
//! normalisation by the P paths of a uniform pass is kept. v is the visible fraction V_u / N_u
//! of the uniform proposals of all chains this pass, counted from each chain's first visible
//! sample on (`ChainCounters::record`, `ChainHistory::visible_fraction`). amcppm instead
//! counts its visible uniform samples as a technique of their own, weighted with the chain's
//! by their balance heuristic, and lets the visible fraction set its large-step probability
//! (`automatic_large_step`, `ppm/metropolis.rs`).

use crate::integrators::{ParamSpec, PlotKind, PlotSeries};
use crate::sampling::pss::PssSampler;

/// The acceptance the mutation size adapts towards (Roberts, Gelman & Gilks 1997).
pub const TARGET_ACCEPTANCE: f64 = 0.234;
pub const INITIAL_MUTATION_SIZE: f32 = 0.05;
const MUTATION_SIZE_RANGE: (f32, f32) = (1e-5, 0.5);
const MAX_HISTORY: usize = 2048;

/// The paper draws a uniform sample at every iteration and mutates only when it is
/// invisible: two paths an iteration at a visible fraction of a few per cent. A mixture of the
/// two (Kelemen et al. 2002's large step) traces one (DESIGN.md section 5b).
/// Below 0.01 a chain draws a handful of uniform proposals in a pass of 10^3 iterations and
/// holds one neighbourhood for all of it (amcppm's closed form at 10^-3 came out 1.84 for 1).
pub const fn large_step_param(doc: &'static str) -> ParamSpec {
    ParamSpec::new("large_step", doc, 0.3, (MIN_LARGE_STEP as f64, 1.0)).live()
}

/// The large-step probability below which a chain holds one neighbourhood for a pass
/// (`large_step_param`).
pub const MIN_LARGE_STEP: f32 = 0.01;
/// amcppm's automatic large-step probability where the visible fraction is small.
pub const AUTOMATIC_LARGE_STEP: f32 = 0.3;

/// A pass's probability of a uniform proposal where uniform samples and chain states are
/// combined by their balance heuristic (amcppm): `setting` if the user gave one, else
/// automatic: ten times the visible fraction `v` of the passes before, within 0.3 and 1. A
/// chain's state stands for 1 / v uniform samples but repeats its neighbours' for many
/// iterations (its states are held about four iterations at acceptance 0.234, and small steps
/// move little), so below one in ten visible the chains gain and above it uniform photons do.
/// Measured `v` (`render --stats`, 128 wide): the Cornell boxes and the caustic pool 0.24 to
/// 0.35, where the pass is then uniform photon tracing (the Cornell box at 30 s: relMSE
/// 1.6e-4 against 2.1e-4 at twice v and 2.5e-4 at 0.3); the door, gap-glass and the material
/// spheres under the studio 0.005 to 0.013, where the chains run with 0.3. Unknown `v` (the
/// first pass) keeps 0.3.
pub fn automatic_large_step(setting: f32, v: Option<f64>) -> f32 {
    if setting > 0.0 {
        return setting.max(MIN_LARGE_STEP);
    }
    let wanted = v.map_or(0.0, |v| (10.0 * v).min(1.0) as f32);
    AUTOMATIC_LARGE_STEP.max(wanted)
}

/// A chain (or whatever a worker runs) for each of this pass's workers, made anew when their
/// number changed.
pub fn one_per_worker<T>(chains: &mut Vec<T>, new: impl Fn(u64) -> T) {
    let workers = rayon::current_num_threads().max(1);
    if chains.len() != workers {
        *chains = (0..workers as u64).map(new).collect();
    }
}

/// Worker `i`'s share of `total` iterations split among `workers`.
pub fn worker_share(total: u64, workers: u64, i: u64) -> u64 {
    total / workers + u64::from(i < total % workers)
}

/// One chain's counters and mutation size.
#[derive(Clone, Debug)]
pub struct ChainCounters {
    pub mutation_size: f32,
    /// Over the whole run.
    pub mutations: u64,
    pub accepted: u64,
    /// This pass: uniform samples, the visible ones among them, the iterations that held a
    /// visible state.
    pub uniform: u64,
    pub uniform_visible: u64,
    pub chain_samples: u64,
    /// This pass: uniform samples drawn while searching for the first visible one.
    pub searched: u64,
}

impl Default for ChainCounters {
    fn default() -> Self {
        ChainCounters {
            mutation_size: INITIAL_MUTATION_SIZE,
            mutations: 0,
            accepted: 0,
            uniform: 0,
            uniform_visible: 0,
            chain_samples: 0,
            searched: 0,
        }
    }
}

impl ChainCounters {
    pub fn start_pass(&mut self) {
        (self.uniform, self.uniform_visible) = (0, 0);
        (self.chain_samples, self.searched) = (0, 0);
    }

    /// The probability of a uniform proposal this iteration: 1 until the pass's first visible
    /// sample, whose exact draw from the target starts the chain.
    fn large_step_prob(&self, has_state: bool, large_step_prob: f32) -> f32 {
        if has_state { large_step_prob } else { 1.0 }
    }

    /// Starts a step of `state`: uniform with the pass's probability (always while
    /// `searching`), else a small step of this chain's size.
    pub fn start_step(&self, state: &mut PssSampler, searching: bool, large_step_prob: f32) {
        state.large_step_prob = self.large_step_prob(!searching, large_step_prob);
        state.sigma = self.mutation_size;
        state.start_iteration();
    }

    /// Counts a proposal of a chain whose target is visibility (a mutation as
    /// `count_mutation`). `searching`: the chain had no state yet, and the uniform samples it drew until the
    /// first visible one are not counted. That search stops at a success, so counted it would
    /// estimate the visible fraction high (by about one sample in the count: 4 % on the door
    /// at 32 x 32, where a chain saw three visible uniform samples a pass); after it, uniform
    /// proposals come with a fixed probability whatever they hit, and V_u / N_u is unbiased.
    pub fn record(&mut self, searching: bool, large: bool, visible: bool) {
        if searching {
            self.searched += 1;
            return;
        }
        if large {
            self.uniform += 1;
            self.uniform_visible += u64::from(visible);
        } else {
            self.count_mutation(visible);
        }
    }

    /// Counts a small step, taken or not, and moves delta by a Robbins-Monro step towards the
    /// target acceptance (the paper's adaptation): delta += (accepted - 0.234) / mutations.
    pub fn count_mutation(&mut self, accepted: bool) {
        self.mutations += 1;
        self.accepted += u64::from(accepted);
        let step = (f64::from(u8::from(accepted)) - TARGET_ACCEPTANCE) / self.mutations as f64;
        self.mutation_size =
            (self.mutation_size + step as f32).clamp(MUTATION_SIZE_RANGE.0, MUTATION_SIZE_RANGE.1);
    }

    /// The weight of this pass's states over `iterations` iterations before the visible
    /// fraction: P / n_chain (module docs).
    pub fn scale(&self, iterations: u64) -> f64 {
        if self.chain_samples == 0 {
            0.0
        } else {
            iterations as f64 / self.chain_samples as f64
        }
    }
}

/// The run's record of a set of chains: totals, and per pass (thinned to stay bounded) the
/// visible fraction, acceptance, mean mutation size and exchanges per chain sample.
#[derive(Clone, Debug, Default)]
pub struct ChainHistory {
    history: Vec<[f64; 5]>,
    stride: u64,
    passes: u64,
    /// Over the run: uniform samples, the visible ones among them.
    pub uniform: u64,
    pub uniform_visible: u64,
    /// (mutations, accepted) over all chains when the current pass started.
    before: (u64, u64),
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

fn sum<'a>(chains: impl Iterator<Item = &'a ChainCounters>, f: fn(&ChainCounters) -> u64) -> u64 {
    chains.map(f).sum()
}

impl ChainHistory {
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.history.as_slice())
    }

    /// Call before a pass runs its chains.
    pub fn start_pass<'a>(&mut self, chains: impl Iterator<Item = &'a ChainCounters> + Clone) {
        self.before = (
            sum(chains.clone(), |c| c.mutations),
            sum(chains, |c| c.accepted),
        );
    }

    /// This pass's visible fraction (module docs), from all chains' uniform proposals: the
    /// target changes every pass, and a visible fraction from other passes' camera paths is
    /// off by their covariance with this pass's (the door at 32 x 32 came out 5 % bright with
    /// the running fraction). A pass without any counted uniform proposal (a large-step
    /// probability near 0 on a small image) takes the run's so far, and before any the
    /// searches' own count (slightly high: each search stopped at its success).
    pub fn visible_fraction<'a>(
        &self,
        chains: impl Iterator<Item = &'a ChainCounters> + Clone,
    ) -> f64 {
        let uniform = sum(chains.clone(), |c| c.uniform);
        if uniform > 0 {
            return ratio(sum(chains, |c| c.uniform_visible), uniform);
        }
        if self.uniform > 0 {
            return ratio(self.uniform_visible, self.uniform);
        }
        let found = chains.clone().filter(|c| c.chain_samples > 0).count() as u64;
        ratio(found, sum(chains, |c| c.searched))
    }

    /// The visible fraction of all uniform samples of the passes before, if there were any.
    pub fn running_visible_fraction(&self) -> Option<f64> {
        (self.uniform > 0).then(|| ratio(self.uniform_visible, self.uniform))
    }

    /// Call after a pass ran its chains.
    pub fn end_pass<'a>(&mut self, chains: impl Iterator<Item = &'a ChainCounters> + Clone) {
        self.passes += 1;
        let uniform = sum(chains.clone(), |c| c.uniform);
        let visible = sum(chains.clone(), |c| c.uniform_visible);
        self.uniform += uniform;
        self.uniform_visible += visible;
        if !self.passes.is_multiple_of(self.stride.max(1)) {
            return;
        }
        let mutations = sum(chains.clone(), |c| c.mutations) - self.before.0;
        let accepted = sum(chains.clone(), |c| c.accepted) - self.before.1;
        let (count, size) = chains.clone().fold((0usize, 0.0f64), |(n, s), c| {
            (n + 1, s + f64::from(c.mutation_size))
        });
        self.history.push([
            self.passes as f64,
            ratio(visible, uniform),
            ratio(accepted, mutations),
            size / count.max(1) as f64,
            ratio(visible, sum(chains, |c| c.chain_samples)),
        ]);
        if self.history.len() > MAX_HISTORY {
            self.history = self.history.iter().copied().step_by(2).collect();
            self.stride = self.stride.max(1) * 2;
        }
    }

    /// The run's counters for `--stats`: uniform samples and the visible ones, mutations
    /// and the accepted ones, and each chain's current mutation size.
    pub fn statistics<'a>(
        &self,
        chains: impl Iterator<Item = &'a ChainCounters> + Clone,
    ) -> serde_json::Value {
        let (mutations, accepted) = (
            sum(chains.clone(), |c| c.mutations),
            sum(chains.clone(), |c| c.accepted),
        );
        serde_json::json!({
            "uniform_samples": self.uniform,
            "uniform_visible": self.uniform_visible,
            "visible_fraction": ratio(self.uniform_visible, self.uniform),
            "mutations": mutations,
            "accepted": accepted,
            "acceptance": ratio(accepted, mutations),
            "mutation_sizes": chains.map(|c| c.mutation_size).collect::<Vec<_>>(),
        })
    }

    /// The chains' plots: visible fraction, acceptance and mutation size, exchanges.
    /// `paths` names what the chains sample ("photon paths", "light subpaths").
    pub fn plots(&self, paths: &str) -> Vec<PlotSeries> {
        let series = |plot: &str, name: &str, y: String, i: usize| PlotSeries {
            plot: plot.into(),
            name: name.into(),
            kind: PlotKind::Line,
            x_label: "passes".into(),
            y_label: y,
            points: self.history.iter().map(|h| [h[0], h[i]]).collect(),
            point_names: Vec::new(),
        };
        vec![
            series(
                "Visibility",
                "visible fraction",
                format!("share of uniform {paths}"),
                1,
            ),
            series(
                "Chains",
                "acceptance",
                "mutations accepted (target 0.234)".into(),
                2,
            ),
            series("Chains", "mutation size", "delta".into(), 3),
            series(
                "Chains",
                "replica exchanges",
                "exchanges per chain sample".into(),
                4,
            ),
        ]
    }
}
