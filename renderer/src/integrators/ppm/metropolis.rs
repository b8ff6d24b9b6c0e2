//! Metropolis photon paths: robust adaptive photon tracing (Hachisuka & Jensen 2011, "Robust
//! adaptive photon tracing using photon path visibility"). Each photon worker runs a Markov
//! chain in primary sample space whose target is the photon path's visibility V(u): 1 when the
//! path deposits at any hit point of this pass, 0 otherwise; the proposals, the adaptation and
//! the normalisation are every visibility chain's (`visibility_chain.rs`). The chain's state
//! deposits its photon every iteration, and at the end of the pass the chains' flux is
//! weighted by their normalisation.
//!
//! Deviations from the paper, each for a reason:
//! - Hit points change every pass (SPPM), so the target does too: the visible fraction is
//!   counted per pass, and a chain starts each pass afresh at its first visible uniform
//!   sample (an exact draw from the pass's target), not from last pass's state; that search
//!   comes before the pass's iterations.
//! - The small step is Kelemen's (a normal of standard deviation delta per coordinate,
//!   wrapped, `PssSampler`).
//! - Uniform samples and mutations are a mixture (`large_step`), not a uniform sample at
//!   every iteration (DESIGN.md section 5b).
//! - The uniform samples are a technique of their own: a visible one deposits as a uniform
//!   photon, and every other iteration deposits the chain's state; the two are weighted by
//!   their balance heuristic, so that with only uniform proposals the pass is SPPM's. The
//!   large-step probability follows the visible fraction (`automatic_large_step`): where most
//!   photon paths are visible the chains only add correlation.

use super::hash_grid::HashGrid;
use super::photon_tracing::Deposit;
use super::pixel_stats::Gathered;
use super::{PHOTON_STREAM, PhotonMapper, photons_per_pass};
use crate::integrators::visibility_chain::{ChainCounters, ChainHistory, automatic_large_step};
use crate::integrators::{Cancelled, ParamSpec, PassStats, PlotSeries};
use crate::sampling::pss::{LIGHT_STREAM, PssSampler};
use crate::sampling::sampler::Sampler;
use std::sync::atomic::{AtomicBool, Ordering};

const CHAIN_STREAM: u64 = 0x3c4a_1e5e_ed00_0035;

/// amcppm's share of uniform proposals; 0 lets each pass choose (`automatic_large_step`).
pub const LARGE_STEP: ParamSpec = ParamSpec::new(
    "large_step",
    "Probability that a chain proposes a uniform photon path (which also measures the visible fraction) instead of a small step from its state; 1 is uniform photon tracing; 0 picks ten times the visible fraction, within 0.3 and 1, each pass (fixed values below 0.01 count as 0.01).",
    0.0,
    (0.0, 1.0),
)
.live()
.automatic_at_zero();

/// One worker's visibility chain with its counters.
#[derive(Clone, Debug)]
pub(super) struct VisibilityChain {
    state: PssSampler,
    /// The deposits of the current state (empty until the pass's first visible sample).
    current: Vec<Deposit>,
    proposal: Vec<Deposit>,
    pub(super) counters: ChainCounters,
}

impl VisibilityChain {
    pub(super) fn new(seed: u64, index: u64) -> Self {
        let counters = ChainCounters::default();
        VisibilityChain {
            state: PssSampler::new(seed ^ CHAIN_STREAM, index, counters.mutation_size, 1.0),
            current: Vec::new(),
            proposal: Vec::new(),
            counters,
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.state.memory_bytes()
            + (self.current.capacity() + self.proposal.capacity()) * size_of::<Deposit>()
    }

    /// One iteration: a proposal traced into `proposal`, taken when visible, and one sample
    /// deposited, of the uniform technique or of the chain's; the pass weighs both by their
    /// balance heuristic (`MetropolisPhotons::photon_pass`). The search for the pass's first
    /// visible sample deposits nothing: it stops at a success.
    fn iterate(
        &mut self,
        mapper: &PhotonMapper,
        grid: &HashGrid,
        gathered: &mut Gathered,
        large_step_prob: f32,
        st: &mut PassStats,
    ) {
        let c = &mut self.counters;
        let searching = self.current.is_empty();
        c.start_step(&mut self.state, searching, large_step_prob);
        self.state.start_stream(LIGHT_STREAM, 0);
        self.proposal.clear();
        let proposal = &mut self.proposal;
        mapper.trace_photon(grid, &mut self.state, st, &mut |d| proposal.push(d));
        let visible = !self.proposal.is_empty();
        let large = self.state.is_large_step();
        c.record(searching, large, visible);
        if visible {
            self.state.accept();
            std::mem::swap(&mut self.current, &mut self.proposal);
        } else {
            self.state.reject();
        }
        if searching {
            return;
        }
        // A visible uniform proposal is a sample of the uniform technique (and the chain's
        // new state). Otherwise the chain's state is a sample of the chain's technique: after a
        // small step, and after an invisible uniform proposal too, whose rejection does not
        // depend on the state (so the state kept is still a draw from the target).
        if !(large && visible) {
            c.chain_samples += 1;
        }
        for d in &self.current {
            gathered.add(d);
        }
    }
}

/// The Metropolis light paths of a photon mapper: a chain per photon worker, and what the
/// viewer plots of them.
#[derive(Clone, Debug, Default)]
pub struct MetropolisPhotons {
    /// Probability of a uniform proposal (`LARGE_STEP`; 0: automatic).
    pub large_step_prob: f32,
    /// The probability the last pass used.
    pub(super) last_large_step: f32,
    chains: Vec<VisibilityChain>,
    history: ChainHistory,
}

impl MetropolisPhotons {
    pub fn new(large_step_prob: f32) -> Self {
        MetropolisPhotons {
            large_step_prob,
            ..Default::default()
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.chains.iter().map(|c| c.memory_bytes()).sum::<usize>() + self.history.memory_bytes()
    }

    fn counters(&self) -> impl Iterator<Item = &ChainCounters> + Clone {
        self.chains.iter().map(|c| &c.counters)
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
        self.history
            .start_pass(self.chains.iter().map(|c| &c.counters));
        let large_step_prob = self.large_step_this_pass();
        self.last_large_step = large_step_prob;
        let mut gathered =
            mapper.metropolis_photon_pass(&mut self.chains, large_step_prob, cancel, stats)?;
        let scale = self.balance_scale(mapper.settings.photons);
        gathered.tau.iter_mut().for_each(|t| *t *= scale);
        gathered.tau_inner.iter_mut().for_each(|t| *t *= scale);
        gathered.tau_sq.iter_mut().for_each(|t| *t *= scale * scale);
        gathered.trapped.iter_mut().for_each(|t| *t *= scale);
        self.history
            .end_pass(self.chains.iter().map(|c| &c.counters));
        Ok(gathered)
    }

    /// This pass's probability of a uniform proposal: the user's, or chosen from the run's
    /// visible fraction so far (`automatic_large_step`).
    fn large_step_this_pass(&self) -> f32 {
        automatic_large_step(
            self.large_step_prob,
            self.history.running_visible_fraction(),
        )
    }

    /// The weight of every deposit of this pass: the balance heuristic over its two
    /// techniques, N_u uniform photon paths (density 1 in primary sample space) and N_c chain
    /// states (density V / v), for the P photons a uniform pass would trace:
    /// P / (N_u + N_c / v) (Veach 1997, eq. 9.8, with each technique's sample count). With
    /// no chain states it is uniform photon tracing; with no uniform ones, Hachisuka & Jensen
    /// 2011's P v / N_c.
    fn balance_scale(&self, photons: u64) -> f64 {
        let v = self
            .history
            .visible_fraction(self.chains.iter().map(|c| &c.counters));
        let n_u = self.counters().map(|c| c.uniform).sum::<u64>() as f64;
        let n_c = self.counters().map(|c| c.chain_samples).sum::<u64>() as f64;
        let chain = if n_c > 0.0 { n_c / v } else { 0.0 };
        let denominator = n_u + chain;
        if denominator > 0.0 && denominator.is_finite() {
            photons as f64 / denominator
        } else {
            0.0
        }
    }

    /// The run's counters for `--stats` (`ChainHistory::statistics`).
    pub(super) fn statistics(&self) -> serde_json::Value {
        self.history.statistics(self.counters())
    }

    /// The chains' plots: visible fraction, acceptance and mutation size, exchanges.
    pub(super) fn plots(&self) -> Vec<PlotSeries> {
        self.history.plots("photon paths")
    }
}

impl PhotonMapper {
    /// The photon pass with Metropolis photon paths: `photons` iterations shared among the
    /// chains (one per worker), their deposits not yet weighted (the caller's balance
    /// heuristic needs every chain's counts).
    pub(super) fn metropolis_photon_pass(
        &self,
        chains: &mut [VisibilityChain],
        large_step_prob: f32,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        let pass = self.passes;
        self.photon_pass_over(chains, stats, |chain, grid, photons, gathered, st| {
            chain.current.clear();
            chain.counters.start_pass();
            if large_step_prob >= 1.0 {
                // Uniform photon tracing, as SPPM's (the same stream), counting the visible
                // fraction that the next pass's large-step probability follows.
                let mut sampler = Sampler::new(self.ctx.seed ^ PHOTON_STREAM);
                for i in photons {
                    if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                        return Err(Cancelled);
                    }
                    sampler.start_pixel_sample(i, pass);
                    let mut visible = false;
                    self.trace_photon(grid, &mut sampler, st, &mut |d| {
                        visible = true;
                        gathered.add(&d);
                    });
                    chain.counters.record(false, true, visible);
                }
                return Ok(());
            }
            // The search for the pass's first visible sample comes before the pass's
            // iterations, not out of them: counted in, a chain that had not found a state
            // when they ran out deposited nothing, and a pass whose chains all failed lost its
            // photons' light while its photons counted as emitted (DESIGN.md 5b, "A bias at
            // small counts"). Its rays count in the photons' cost all the same
            // (`photon_budget`). It is capped at a uniform pass's count, past which a chain
            // that has found nothing searches on within the pass's iterations.
            let cap = photons_per_pass(self.ctx.camera.width, self.ctx.camera.height);
            for i in 0..cap {
                if !chain.current.is_empty() {
                    break;
                }
                if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                chain.iterate(self, grid, gathered, large_step_prob, st);
            }
            for i in photons {
                if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                chain.iterate(self, grid, gathered, large_step_prob, st);
            }
            // The radii shrink by every photon that fell (each a sample of the density;
            // Hachisuka & Jensen 2011 count the chain's so): denser photons where the camera
            // looks shrink the radii faster, which is the bias half of the gain.
            Ok(())
        })
    }
}
