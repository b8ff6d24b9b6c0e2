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
//!   sample (an exact draw from the pass's target), not from last pass's state.
//! - The small step is Kelemen's (a normal of standard deviation delta per coordinate,
//!   wrapped, `PssSampler`).
//! - Uniform samples and mutations are a mixture (`large_step`), not a uniform sample at
//!   every iteration (DESIGN.md section 5b).

use super::PhotonMapper;
use super::hash_grid::HashGrid;
use super::photon_tracing::Deposit;
use super::pixel_stats::Gathered;
use crate::integrators::visibility_chain::{ChainCounters, ChainHistory, large_step_param};
use crate::integrators::{Cancelled, ParamSpec, PassStats, PlotSeries};
use crate::sampling::pss::{LIGHT_STREAM, PssSampler};
use std::sync::atomic::{AtomicBool, Ordering};

const CHAIN_STREAM: u64 = 0x3c4a_1e5e_ed00_0035;

/// amcppm's share of uniform proposals.
pub const LARGE_STEP: ParamSpec = large_step_param(
    "Probability that a chain proposes a uniform photon path (which also measures the visible fraction) instead of a small step from its state; 1 is uniform photon tracing with repeats.",
);

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

    /// One iteration: a proposal traced into `proposal`, taken when visible; the state's
    /// deposits go to `gathered`.
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
        c.record(searching, self.state.is_large_step(), visible);
        if visible {
            self.state.accept();
            std::mem::swap(&mut self.current, &mut self.proposal);
        } else {
            self.state.reject();
        }
        if !self.current.is_empty() {
            c.chain_samples += 1;
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
        let mut gathered =
            mapper.metropolis_photon_pass(&mut self.chains, self.large_step_prob, cancel, stats)?;
        let v = self
            .history
            .visible_fraction(self.chains.iter().map(|c| &c.counters));
        gathered.tau.iter_mut().for_each(|t| *t *= v);
        gathered.tau_inner.iter_mut().for_each(|t| *t *= v);
        self.history
            .end_pass(self.chains.iter().map(|c| &c.counters));
        Ok(gathered)
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
    /// chains (one per worker), each chain's deposits weighted by its normalisation but for
    /// the visible fraction, which the caller applies.
    pub(super) fn metropolis_photon_pass(
        &self,
        chains: &mut [VisibilityChain],
        large_step_prob: f32,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        self.photon_pass_over(chains, stats, |chain, grid, photons, gathered, st| {
            chain.current.clear();
            chain.counters.start_pass();
            let count = photons.end - photons.start;
            for i in photons {
                if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                chain.iterate(self, grid, gathered, large_step_prob, st);
            }
            let scale = chain.counters.scale(count);
            gathered.tau.iter_mut().for_each(|t| *t *= scale);
            gathered.tau_inner.iter_mut().for_each(|t| *t *= scale);
            // The radii shrink by the chain's photons as they fall (each a sample of the
            // density; Hachisuka & Jensen 2011 count them so): denser photons where the
            // camera looks shrink the radii faster, which is the bias half of the gain.
            Ok(())
        })
    }
}
