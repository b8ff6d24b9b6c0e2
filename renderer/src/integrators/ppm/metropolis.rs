//! Metropolis photon paths: robust adaptive photon tracing (Hachisuka & Jensen 2011, "Robust
//! adaptive photon tracing using photon path visibility"). Each photon worker runs a Markov
//! chain in primary sample space whose target is the photon path's visibility V(u): 1 when the
//! path deposits at any hit point of this pass, 0 otherwise. Each iteration proposes, with
//! probability `large_step_prob`, a uniform sample (the replica at infinite temperature: its
//! exchange with the chain is accepted when it is visible, as the chain's state is) and
//! otherwise a small step of size delta, accepted when visible. The chain's state deposits its
//! photon every iteration. Its estimate of the mean photon contribution is (visible uniform
//! samples V_u / uniform samples N_u) x (the mean over the chain's photons), so over a range
//! of P iterations each chain photon's flux is weighted by P V_u / (N_u n_chain), with n_chain
//! the photons the chain deposited this pass: the pass keeps the normalisation by the P
//! photons of a uniform pass.
//!
//! Deviations from the paper, each for a reason:
//! - The paper draws a uniform sample at every iteration and mutates only when it is
//!   invisible, two photon paths an iteration at a visible fraction of a few per cent; a
//!   mixture of the two (Kelemen et al. 2002's large step) traces one. At 0.3 the door's
//!   error fell by a fifth at equal time (DESIGN.md section 5b).
//! - Hit points change every pass (SPPM), so the target does too: the visible fraction is
//!   counted per pass, and a chain starts each pass afresh at its first visible uniform
//!   sample (an exact draw from the pass's target), not from last pass's state.
//! - The small step is Kelemen's (a normal of standard deviation delta per coordinate,
//!   wrapped, `PssSampler`), and delta adapts by a Robbins-Monro step towards an acceptance
//!   of 0.234, as the paper adapts its own: delta += (accepted - 0.234) / mutations.

use super::PhotonMapper;
use super::hash_grid::HashGrid;
use super::photon_tracing::Deposit;
use super::pixel_stats::Gathered;
use crate::integrators::{Cancelled, ParamSpec, PassStats, PlotKind, PlotSeries};
use crate::sampling::pss::{LIGHT_STREAM, PssSampler};
use std::sync::atomic::{AtomicBool, Ordering};

/// The acceptance the mutation size adapts towards (Roberts, Gelman & Gilks 1997).
pub const TARGET_ACCEPTANCE: f64 = 0.234;
const INITIAL_MUTATION_SIZE: f32 = 0.05;
const MUTATION_SIZE_RANGE: (f32, f32) = (1e-5, 0.5);
const CHAIN_STREAM: u64 = 0x3c4a_1e5e_ed00_0035;

/// amcppm's share of uniform proposals.
pub const LARGE_STEP: ParamSpec = ParamSpec::new(
    "large_step",
    "Probability that a chain proposes a uniform photon path (which also measures the visible fraction) instead of a small step from its state; 1 is uniform photon tracing with repeats.",
    0.3,
    (1e-3, 1.0),
)
.live();

/// One worker's visibility chain with its counters.
#[derive(Clone, Debug)]
pub(super) struct VisibilityChain {
    state: PssSampler,
    /// The deposits of the current state (empty until the pass's first visible sample).
    current: Vec<Deposit>,
    proposal: Vec<Deposit>,
    pub(super) mutation_size: f32,
    /// Over the whole run.
    pub(super) mutations: u64,
    pub(super) accepted: u64,
    /// This pass: uniform samples, the visible ones among them, the chain's photons.
    pub(super) uniform: u64,
    pub(super) uniform_visible: u64,
    pub(super) chain_photons: u64,
}

impl VisibilityChain {
    pub(super) fn new(seed: u64, index: u64) -> Self {
        VisibilityChain {
            state: PssSampler::new(seed ^ CHAIN_STREAM, index, INITIAL_MUTATION_SIZE, 1.0),
            current: Vec::new(),
            proposal: Vec::new(),
            mutation_size: INITIAL_MUTATION_SIZE,
            mutations: 0,
            accepted: 0,
            uniform: 0,
            uniform_visible: 0,
            chain_photons: 0,
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.state.memory_bytes()
            + (self.current.capacity() + self.proposal.capacity()) * size_of::<Deposit>()
    }

    /// The weight of this pass's chain photons over `photons` iterations (module docs).
    fn scale(&self, photons: u64) -> f64 {
        if self.chain_photons == 0 || self.uniform == 0 {
            0.0
        } else {
            photons as f64 * self.uniform_visible as f64
                / (self.uniform as f64 * self.chain_photons as f64)
        }
    }

    /// One step of the chain, a uniform sample with probability `large_step_prob` and
    /// otherwise a mutation, its deposits traced into `proposal`; (large, visible).
    fn propose(
        &mut self,
        mapper: &PhotonMapper,
        grid: &HashGrid,
        large_step_prob: f32,
        st: &mut PassStats,
    ) -> (bool, bool) {
        self.state.large_step_prob = large_step_prob;
        self.state.sigma = self.mutation_size;
        self.state.start_iteration();
        self.state.start_stream(LIGHT_STREAM, 0);
        self.proposal.clear();
        let proposal = &mut self.proposal;
        mapper.trace_photon(grid, &mut self.state, st, &mut |d| proposal.push(d));
        (self.state.is_large_step(), !self.proposal.is_empty())
    }

    /// Takes the proposal as the state, or restores the state.
    fn decide(&mut self, accept: bool) {
        if accept {
            self.state.accept();
            std::mem::swap(&mut self.current, &mut self.proposal);
        } else {
            self.state.reject();
        }
    }

    /// One iteration (module docs); the state's deposits go to `gathered`.
    fn iterate(
        &mut self,
        mapper: &PhotonMapper,
        grid: &HashGrid,
        gathered: &mut Gathered,
        large_step_prob: f32,
        st: &mut PassStats,
    ) {
        // Before the pass's first visible sample every step is uniform.
        let large_step_prob = if self.current.is_empty() {
            1.0
        } else {
            large_step_prob
        };
        let (large, visible) = self.propose(mapper, grid, large_step_prob, st);
        self.decide(visible);
        if large {
            self.uniform += 1;
            self.uniform_visible += u64::from(visible);
        } else {
            self.mutations += 1;
            self.accepted += u64::from(visible);
            let step = (f64::from(u8::from(visible)) - TARGET_ACCEPTANCE) / self.mutations as f64;
            self.mutation_size = (self.mutation_size + step as f32)
                .clamp(MUTATION_SIZE_RANGE.0, MUTATION_SIZE_RANGE.1);
        }
        if !self.current.is_empty() {
            self.chain_photons += 1;
            for d in &self.current {
                gathered.add(d);
            }
        }
    }
}

/// The Metropolis light paths of a photon mapper: a chain per photon worker, and what the
/// viewer plots of them.
#[derive(Clone, Debug, Default)]
pub struct MetropolisPhotons {
    /// Probability of a uniform proposal (`LARGE_STEP`).
    pub large_step_prob: f32,
    chains: Vec<VisibilityChain>,
    /// (passes, visible fraction of the uniform samples, acceptance of the mutations this
    /// pass, mean mutation size, replica exchanges per chain photon), thinned to stay bounded.
    history: Vec<[f64; 5]>,
    history_stride: u64,
    passes: u64,
    /// Over the run: uniform samples, the visible ones among them.
    pub uniform: u64,
    pub uniform_visible: u64,
}

const MAX_HISTORY: usize = 2048;

impl MetropolisPhotons {
    pub fn new(large_step_prob: f32) -> Self {
        MetropolisPhotons {
            large_step_prob,
            ..Default::default()
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.chains.iter().map(|c| c.memory_bytes()).sum::<usize>()
            + std::mem::size_of_val(self.history.as_slice())
    }

    /// The photon pass of `mapper` with these chains (one per worker of its last pass).
    pub(super) fn photon_pass(
        &mut self,
        mapper: &PhotonMapper,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        let workers = mapper.photon_workers.max(1);
        if self.chains.len() != workers {
            self.chains = (0..workers as u64)
                .map(|i| VisibilityChain::new(mapper.ctx.seed, i))
                .collect();
        }
        let before: Vec<(u64, u64)> = self
            .chains
            .iter()
            .map(|c| (c.mutations, c.accepted))
            .collect();
        let gathered =
            mapper.metropolis_photon_pass(&mut self.chains, self.large_step_prob, cancel, stats)?;
        self.passes += 1;
        let sum = |f: fn(&VisibilityChain) -> u64| self.chains.iter().map(f).sum::<u64>();
        let (uniform, visible) = (sum(|c| c.uniform), sum(|c| c.uniform_visible));
        self.uniform += uniform;
        self.uniform_visible += visible;
        let (mutations, accepted) = self
            .chains
            .iter()
            .zip(&before)
            .fold((0, 0), |(m, a), (c, b)| {
                (m + c.mutations - b.0, a + c.accepted - b.1)
            });
        if self.passes.is_multiple_of(self.history_stride.max(1)) {
            let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
            let size = self
                .chains
                .iter()
                .map(|c| f64::from(c.mutation_size))
                .sum::<f64>()
                / self.chains.len() as f64;
            self.history.push([
                self.passes as f64,
                ratio(visible, uniform),
                ratio(accepted, mutations),
                size,
                ratio(visible, sum(|c| c.chain_photons)),
            ]);
            if self.history.len() > MAX_HISTORY {
                self.history = self.history.iter().copied().step_by(2).collect();
                self.history_stride = self.history_stride.max(1) * 2;
            }
        }
        Ok(gathered)
    }

    /// The run's counters for `--stats`: uniform samples and the visible ones, mutations
    /// and the accepted ones, and each chain's current mutation size.
    pub(super) fn statistics(&self) -> serde_json::Value {
        let sum = |f: fn(&VisibilityChain) -> u64| self.chains.iter().map(f).sum::<u64>();
        let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        let (mutations, accepted) = (sum(|c| c.mutations), sum(|c| c.accepted));
        serde_json::json!({
            "uniform_samples": self.uniform,
            "uniform_visible": self.uniform_visible,
            "visible_fraction": ratio(self.uniform_visible, self.uniform),
            "mutations": mutations,
            "accepted": accepted,
            "acceptance": ratio(accepted, mutations),
            "mutation_sizes": self.chains.iter().map(|c| c.mutation_size).collect::<Vec<_>>(),
        })
    }

    /// The chains' plots: visible fraction, acceptance and mutation size, exchanges.
    pub(super) fn plots(&self) -> Vec<PlotSeries> {
        let series = |plot: &str, name: &str, y: &str, i: usize| PlotSeries {
            plot: plot.into(),
            name: name.into(),
            kind: PlotKind::Line,
            x_label: "passes".into(),
            y_label: y.into(),
            points: self.history.iter().map(|h| [h[0], h[i]]).collect(),
            point_names: Vec::new(),
        };
        vec![
            series(
                "Visibility",
                "visible fraction",
                "share of uniform photon paths",
                1,
            ),
            series(
                "Chains",
                "acceptance",
                "mutations accepted (target 0.234)",
                2,
            ),
            series("Chains", "mutation size", "delta", 3),
            series(
                "Chains",
                "replica exchanges",
                "exchanges per chain photon",
                4,
            ),
        ]
    }
}

impl PhotonMapper {
    /// The photon pass with Metropolis photon paths: `photons` iterations shared among the
    /// chains (one per worker), each chain's deposits weighted by its normalisation.
    pub(super) fn metropolis_photon_pass(
        &self,
        chains: &mut [VisibilityChain],
        large_step_prob: f32,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        self.photon_pass_over(chains, stats, |chain, grid, photons, gathered, st| {
            chain.current.clear();
            (chain.uniform, chain.uniform_visible, chain.chain_photons) = (0, 0, 0);
            let count = photons.end - photons.start;
            for i in photons {
                if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                chain.iterate(self, grid, gathered, large_step_prob, st);
            }
            let scale = chain.scale(count);
            gathered.tau.iter_mut().for_each(|t| *t *= scale);
            gathered.tau_inner.iter_mut().for_each(|t| *t *= scale);
            // The radii shrink by the chain's photons as they fall (each a sample of the
            // density; Hachisuka & Jensen 2011 count them so): denser photons where the
            // camera looks shrink the radii faster, which is the bias half of the gain.
            Ok(())
        })
    }
}

