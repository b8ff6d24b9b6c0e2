//! The Metropolised bidirectional estimator over vcm (`mvcm`; Šik, Otsu, Hachisuka &
//! Křivánek 2016, "Robust light transport simulation via Metropolised bidirectional
//! estimators"): light subpaths from two chains per worker, one whose target is their
//! visibility V (amcvcm's, `metropolis.rs`) and one whose target is their contribution C to
//! the image, combined by multiple importance sampling over the chains; camera subpaths stay
//! independent per pixel, and connections and merges are vcm's, as in amcvcm.
//!
//! The state and what a proposal brings are amcvcm's: (u, k), a light subpath and a camera
//! subpath drawn uniformly, evaluated whole as g(u, k) (`Proposer`). C is the luminance of g
//! (every technique with its MIS weight and normalisation). Both targets change every pass
//! with the camera subpaths, so both chains start afresh each pass from an exact (or
//! exactly weighted) draw of this pass's target, and iterations alternate between them:
//!
//! - The visibility chain is amcvcm's: it searches uniform samples for its first visible
//!   one (an exact draw from V / b_v), then proposes uniform samples with probability
//!   `large_step` and small steps otherwise, accepted when visible. b_v is this pass's
//!   visible fraction of uniform samples.
//! - The contribution chain is a Kelemen chain over C: the same mixture of uniform samples
//!   and small steps, accepted with probability min(1, C' / C). It starts from a bootstrap
//!   (Veach 1997, section 11.3.3, start-up bias elimination): B uniform samples (an eighth
//!   of the worker's iterations), one of them picked with probability proportional to C,
//!   and the chain's states weighted by b_B, the mean C of the bootstrap, in place of the
//!   unknown b_c. A chain started from the visibility chain's state instead (as the paper's
//!   public implementation does) is distributed like V, not C, for the many iterations its
//!   small steps need to mix; the MIS weights then read its few bright states as a density
//!   it does not have (the door 15 % dark at 32 x 32, 4 % at 128; DESIGN.md section 5d).
//!
//! Markov-chain MIS (the paper's section 4), the balance heuristic over three sets of
//! samples: the bootstrap's n_u uniform ones (density 1: they are vcm's light subpaths, and
//! where the chains gain nothing they keep vcm's estimate), and the chains' planned
//! iterations n_v and n_c with p_v = V / b~_v and p_c = C / b~_c. Each sample is weighted by
//! its set's normalisation over its count times n_j p_j / (n_u + n_v p_v + n_c p_c). Any
//! weights that add up to one keep the estimate unbiased, so b~_v and b~_c are the means of
//! b_v and b_B over earlier passes (independent of this pass's samples); this pass's own
//! come in only as each chain's normalisation. The sum over a worker's states, times its
//! iterations, estimates what its share of N_L independent light subpaths would bring.
//! No replica exchange: it would couple the visibility chain to the contribution chain's
//! weighted start, and no weight then keeps the visibility chain's half unbiased.
//!
//! The error estimate's r comes partly from an independent image (DESIGN.md 5d): the same
//! states weighted without the contribution chain, whose concentration of a pass's
//! iterations in a pixel or two the robust r otherwise takes for fireflies.

use super::Pass;
use super::metropolis::{CameraVertices, ChainGather, Contribution, LightSubpathChain, Proposer};
use crate::integrators::visibility_chain::{
    ChainCounters, ChainHistory, INITIAL_MUTATION_SIZE, one_per_worker, worker_share,
};
use crate::integrators::{Cancelled, PassStats, PlotSeries};
use crate::sampling::pss::PssSampler;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

const CHAIN_STREAM: u64 = 0x5ca1_ab1e_0035_0013;
const CONTRIBUTION_KEY: u64 = 1 << 40;
/// The bootstrap's share of a worker's iterations this pass: 1 / BOOTSTRAP_SHARE.
const BOOTSTRAP_SHARE: u64 = 8;

/// A chain's state: its primary samples, what they bring and their C, and the iterations
/// held since that was last recorded.
#[derive(Clone, Debug)]
struct ChainState {
    pss: PssSampler,
    current: Vec<Contribution>,
    c: f32,
    held: u32,
}

impl ChainState {
    fn new(seed: u64, key: u64) -> Self {
        ChainState {
            pss: PssSampler::new(seed ^ CHAIN_STREAM, key, INITIAL_MUTATION_SIZE, 1.0),
            current: Vec::new(),
            c: 0.0,
            held: 0,
        }
    }

    /// Takes the proposal in `proposal` (its C `c`), recording what the state held.
    fn take(&mut self, proposal: &mut Vec<Contribution>, c: f32, out: &mut Records, chain: Chain) {
        self.pss.accept();
        out.record(self, chain);
        std::mem::swap(&mut self.current, proposal);
        self.c = c;
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Chain {
    /// A bootstrap sample: uniform.
    Uniform,
    Visibility,
    Contribution,
}

/// A state a chain held: its contributions' range in the arena, the iterations it was
/// held, its C, the chain.
#[derive(Clone, Copy, Debug)]
struct Record {
    start: u32,
    len: u32,
    held: u32,
    c: f32,
    chain: Chain,
}

/// A worker's states this pass.
#[derive(Clone, Debug, Default)]
struct Records {
    records: Vec<Record>,
    arena: Vec<Contribution>,
}

impl Records {
    /// Records what `state` held since it was last recorded.
    fn record(&mut self, state: &mut ChainState, chain: Chain) {
        if state.held > 0 {
            self.push(&state.current, state.held, state.c, chain);
        }
        state.held = 0;
    }

    fn push(&mut self, contributions: &[Contribution], held: u32, c: f32, chain: Chain) {
        if contributions.is_empty() {
            return;
        }
        self.records.push(Record {
            start: self.arena.len() as u32,
            len: contributions.len() as u32,
            held,
            c,
            chain,
        });
        self.arena.extend_from_slice(contributions);
    }

    fn clear(&mut self) {
        self.records.clear();
        self.arena.clear();
    }

    fn memory_bytes(&self) -> usize {
        self.records.capacity() * size_of::<Record>()
            + self.arena.capacity() * size_of::<Contribution>()
    }
}

fn total_c(contributions: &[Contribution], merge_normalization: f32) -> f32 {
    contributions
        .iter()
        .map(|c| c.luminance(merge_normalization))
        .sum()
}

/// The MIS quantities a pass's states are weighted by: the chains' planned iterations and
/// the earlier passes' normalisations (module docs).
#[derive(Clone, Copy, Debug)]
struct Balance {
    n_u: f64,
    n_v: f64,
    n_c: f64,
    b_v: f64,
    b_c: f64,
}

impl Balance {
    /// n_u + n_v p_v + n_c p_c at a visible state of contribution `c`.
    fn density(&self, c: f32) -> f64 {
        self.n_u + self.n_v / self.b_v + self.n_c * f64::from(c) / self.b_c
    }
}

/// One worker's two chains.
#[derive(Clone, Debug)]
struct ChainPair {
    /// amcvcm's chain, with its own proposer and counters.
    visibility: LightSubpathChain,
    contribution: ChainState,
    /// The bootstrap's and the contribution chain's proposals.
    proposer: Proposer,
    proposal: Vec<Contribution>,
    /// The contribution chain's counters: its uniform proposals that brought anything, its
    /// steps and its mutation size.
    contribution_counters: ChainCounters,
    /// This pass: the bootstrap's samples and sum of C, each chain's planned iterations, the
    /// states held (the iterations the visibility chain held a state are its
    /// `chain_samples`).
    bootstrap: u64,
    bootstrap_c: f64,
    planned: (u64, u64),
    records: Records,
}

impl ChainPair {
    fn new(seed: u64, index: u64) -> Self {
        ChainPair {
            visibility: LightSubpathChain::new(seed, index),
            contribution: ChainState::new(seed, index | CONTRIBUTION_KEY),
            proposer: Proposer::new(seed ^ CHAIN_STREAM, index),
            proposal: Vec::new(),
            contribution_counters: ChainCounters::default(),
            bootstrap: 0,
            bootstrap_c: 0.0,
            planned: (0, 0),
            records: Records::default(),
        }
    }

    fn memory_bytes(&self) -> usize {
        let contributions = self.contribution.current.capacity() + self.proposal.capacity();
        self.visibility.memory_bytes()
            + self.contribution.pss.memory_bytes()
            + self.proposer.memory_bytes()
            + contributions * size_of::<Contribution>()
            + self.records.memory_bytes()
    }

    /// Runs a pass of `iterations`: the bootstrap, then the chains in turn.
    fn run(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        iterations: u64,
        large_step_prob: f32,
        cancel: &AtomicBool,
    ) -> Result<PassStats, Cancelled> {
        let mut st = PassStats::default();
        self.visibility.start_pass();
        self.contribution_counters.start_pass();
        self.contribution.current.clear();
        self.contribution.held = 0;
        (self.bootstrap, self.bootstrap_c) = (0, 0.0);
        self.records.clear();
        let bootstrap = iterations.div_ceil(BOOTSTRAP_SHARE);
        let rest = iterations - bootstrap;
        self.planned = (rest.div_ceil(2), rest / 2);
        for j in 0..iterations {
            if j % 256 == 0 && cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            if j < bootstrap {
                self.bootstrap_step(setup, cameras, &mut st);
            } else if (j - bootstrap).is_multiple_of(2) {
                self.visibility_step(setup, cameras, large_step_prob, &mut st);
            } else {
                self.contribution_step(setup, cameras, large_step_prob, &mut st);
            }
        }
        let (records, norm) = (&mut self.records, setup.merge_normalization);
        self.visibility.finish_pass(|state, held| {
            records.push(state, held, total_c(state, norm), Chain::Visibility)
        });
        self.records
            .record(&mut self.contribution, Chain::Contribution);
        Ok(st)
    }

    /// One bootstrap sample: uniform, counted for the visible fraction and b_B, and taken as
    /// the contribution chain's start with probability C / (the bootstrap's sum of C so far)
    /// (weighted reservoir sampling: the pick is proportional to C over the bootstrap).
    fn bootstrap_step(&mut self, setup: &Pass, cameras: &CameraVertices, st: &mut PassStats) {
        let s = &mut self.contribution;
        s.pss.large_step_prob = 1.0;
        s.pss.start_iteration();
        self.proposer
            .propose(setup, cameras, &mut s.pss, &mut self.proposal, st);
        let c = total_c(&self.proposal, setup.merge_normalization);
        let counters = &mut self.visibility.counters;
        counters.uniform += 1;
        counters.uniform_visible += u64::from(!self.proposal.is_empty());
        self.bootstrap += 1;
        self.bootstrap_c += f64::from(c);
        self.records.push(&self.proposal, 1, c, Chain::Uniform);
        if c > 0.0 && f64::from(self.proposer.uniform()) * self.bootstrap_c < f64::from(c) {
            s.pss.accept();
            std::mem::swap(&mut s.current, &mut self.proposal);
            s.c = c;
        } else {
            s.pss.reject();
        }
    }

    /// One iteration of the visibility chain (amcvcm's), its states recorded for the weights.
    fn visibility_step(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        large_step_prob: f32,
        st: &mut PassStats,
    ) {
        let (records, norm) = (&mut self.records, setup.merge_normalization);
        self.visibility
            .iterate(setup, cameras, large_step_prob, st, |state, held| {
                records.push(state, held, total_c(state, norm), Chain::Visibility)
            });
    }

    /// One iteration of the contribution chain: a uniform sample with probability
    /// `large_step_prob`, else a small step; accepted with min(1, C' / C). Its small steps'
    /// size adapts towards acceptance 0.234 as the visibility chain's.
    fn contribution_step(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        large_step_prob: f32,
        st: &mut PassStats,
    ) {
        let s = &mut self.contribution;
        if s.current.is_empty() {
            // Nothing in the bootstrap brought anything: b_B = 0 weighs this chain out.
            return;
        }
        let counters = &mut self.contribution_counters;
        counters.start_step(&mut s.pss, false, large_step_prob);
        self.proposer
            .propose(setup, cameras, &mut s.pss, &mut self.proposal, st);
        let c = total_c(&self.proposal, setup.merge_normalization);
        let accept = c > 0.0 && self.proposer.uniform() < c / s.c;
        if s.pss.is_large_step() {
            counters.uniform += 1;
            counters.uniform_visible += u64::from(!self.proposal.is_empty());
        } else {
            counters.count_mutation(accept);
        }
        if accept {
            s.take(
                &mut self.proposal,
                c,
                &mut self.records,
                Chain::Contribution,
            );
        } else {
            s.pss.reject();
        }
        s.held += 1;
        counters.chain_samples += 1;
    }

    /// The bootstrap's uniform samples alone, each standing for iterations / n_u light
    /// subpaths: vcm's estimate from fewer light subpaths, unbiased, its noise apart from the
    /// chains'.
    fn uniform_only(
        &self,
        pixels: usize,
        iterations: u64,
        merge_normalization: f32,
    ) -> ChainGather {
        let mut gather = ChainGather::new(pixels);
        let weight = iterations as f64 / self.bootstrap.max(1) as f64;
        for r in &self.records.records {
            if r.chain == Chain::Uniform {
                let contributions =
                    &self.records.arena[r.start as usize..(r.start + r.len) as usize];
                gather.add(
                    contributions,
                    (weight * f64::from(r.held)) as f32,
                    merge_normalization,
                );
            }
        }
        gather
    }

    /// This pass's states weighted by the balance heuristic over both chains (module docs),
    /// times the worker's `iterations`, into a gather. `b_v` is this pass's visible
    /// fraction.
    fn gather(
        &self,
        pixels: usize,
        iterations: u64,
        b_v: f64,
        balance: Balance,
        merge_normalization: f32,
    ) -> ChainGather {
        let mut gather = ChainGather::new(pixels);
        let b_b = if self.bootstrap == 0 {
            0.0
        } else {
            self.bootstrap_c / self.bootstrap as f64
        };
        let n = iterations as f64;
        for r in &self.records.records {
            let density = balance.density(r.c);
            if !(density > 0.0) {
                continue;
            }
            // Uniform: 1 / n_u x n_u / density; visibility: b_v / (iterations held) x
            // n_v p_v / density, with V = 1; contribution: b_B / n_c x n_c p_c / (C density),
            // p_c = C / b~_c.
            let weight = match r.chain {
                Chain::Visibility if self.visibility.counters.chain_samples > 0 => {
                    let held = self.visibility.counters.chain_samples as f64;
                    b_v / held * balance.n_v / balance.b_v / density
                }
                Chain::Visibility => 0.0,
                Chain::Uniform => 1.0 / density,
                Chain::Contribution if balance.n_c > 0.0 => b_b / balance.b_c / density,
                Chain::Contribution => 0.0,
            };
            if weight == 0.0 {
                // The visibility chain with no state held, or the contribution chain where
                // the weights leave it out (the independent image's).
                continue;
            }
            let weight = n * f64::from(r.held) * weight;
            let contributions = &self.records.arena[r.start as usize..(r.start + r.len) as usize];
            gather.add(contributions, weight as f32, merge_normalization);
        }
        gather
    }
}

/// mvcm's light subpaths: a pair of chains per worker, and what the viewer plots of them.
#[derive(Clone, Debug, Default)]
pub struct MetropolisedLightSubpaths {
    /// Both chains' probability of a uniform proposal.
    pub large_step_prob: f32,
    pairs: Vec<ChainPair>,
    history: ChainHistory,
    contribution_history: ChainHistory,
    /// Earlier passes: their count and the sums of their b_v and b_B (the MIS weights').
    passes: u64,
    b_v_sum: f64,
    b_c_sum: f64,
}

impl MetropolisedLightSubpaths {
    pub fn new(large_step_prob: f32) -> Self {
        MetropolisedLightSubpaths {
            large_step_prob,
            ..Default::default()
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.pairs.iter().map(|p| p.memory_bytes()).sum::<usize>()
            + self.history.memory_bytes()
            + self.contribution_history.memory_bytes()
    }

    /// The light half of a pass: `light_paths` iterations shared among the workers' pairs
    /// of chains, weighted by the balance heuristic over the chains.
    pub(super) fn light_subpaths(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        light_paths: u64,
        seed: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<ChainGather, Cancelled> {
        one_per_worker(&mut self.pairs, |i| ChainPair::new(seed, i));
        self.history
            .start_pass(self.pairs.iter().map(|p| &p.visibility.counters));
        self.contribution_history
            .start_pass(self.pairs.iter().map(|p| &p.contribution_counters));
        let count = self.pairs.len() as u64;
        let share = |i: usize| worker_share(light_paths, count, i as u64);
        let large_step_prob = self.large_step_prob;
        let results: Vec<PassStats> = self
            .pairs
            .par_iter_mut()
            .enumerate()
            .map(|(i, pair)| pair.run(setup, cameras, share(i), large_step_prob, cancel))
            .collect::<Result<_, _>>()?;
        let b_v = self
            .history
            .visible_fraction(self.pairs.iter().map(|p| &p.visibility.counters));
        self.history
            .end_pass(self.pairs.iter().map(|p| &p.visibility.counters));
        self.contribution_history
            .end_pass(self.pairs.iter().map(|p| &p.contribution_counters));
        let (bootstrap, bootstrap_c) = self
            .pairs
            .iter()
            .fold((0, 0.0), |(n, c), p| (n + p.bootstrap, c + p.bootstrap_c));
        let b_c = if bootstrap == 0 {
            0.0
        } else {
            bootstrap_c / bootstrap as f64
        };
        // The weights' normalisations are earlier passes' (the first pass has only its own).
        let (b_v_w, b_c_w) = if self.passes == 0 {
            (b_v, b_c)
        } else {
            let n = self.passes as f64;
            (self.b_v_sum / n, self.b_c_sum / n)
        };
        (self.passes, self.b_v_sum, self.b_c_sum) =
            (self.passes + 1, self.b_v_sum + b_v, self.b_c_sum + b_c);
        let pixels = cameras.ends.len();
        let mut total = ChainGather::new(pixels);
        for st in results {
            *stats = *stats + st;
        }
        if !(b_v_w > 0.0 && b_c_w > 0.0) {
            // Nothing was visible before this pass; the weights below need both, and the
            // bootstrap's uniform samples alone estimate the light subpaths' part.
            for (i, pair) in self.pairs.iter().enumerate() {
                total.add_gather(&pair.uniform_only(pixels, share(i), setup.merge_normalization));
            }
            total.independent = total.value.clone();
            return Ok(total);
        }
        let gathers: Vec<ChainGather> = self
            .pairs
            .par_iter()
            .enumerate()
            .map(|(i, pair)| {
                let (n_v, n_c) = pair.planned;
                let balance = Balance {
                    n_u: pair.bootstrap as f64,
                    n_v: n_v as f64,
                    n_c: n_c as f64,
                    b_v: b_v_w,
                    b_c: b_c_w,
                };
                let norm = setup.merge_normalization;
                let mut gather = pair.gather(pixels, share(i), b_v, balance, norm);
                // The same samples without the contribution chain (amcvcm's estimate, with
                // the bootstrap's uniform samples): unbiased, and free of the contribution
                // chain's concentration (many iterations on one bright state, all in a pixel
                // or two), which made the robust r of the error estimate a third of the
                // truth on the door (the estimate 3 times the true relMSE at 16 passes).
                let without = Balance {
                    n_c: 0.0,
                    ..balance
                };
                gather.independent = pair.gather(pixels, share(i), b_v, without, norm).value;
                gather
            })
            .collect();
        for g in &gathers {
            total.add_gather(g);
        }
        Ok(total)
    }

    /// The run's counters for `--stats`: the visibility chains' (amcvcm's), and the
    /// contribution chains' under `contribution_chain` with the mean C of the bootstraps.
    pub fn statistics(&self) -> serde_json::Value {
        let mut s = self
            .history
            .statistics(self.pairs.iter().map(|p| &p.visibility.counters));
        let mut c = self
            .contribution_history
            .statistics(self.pairs.iter().map(|p| &p.contribution_counters));
        c["mean_bootstrap_contribution"] = if self.passes == 0 {
            0.0
        } else {
            self.b_c_sum / self.passes as f64
        }
        .into();
        s["contribution_chain"] = c;
        s
    }

    /// amcvcm's plots of the visibility chains, and the contribution chains' acceptance and
    /// mutation size beside them.
    pub fn plots(&self) -> Vec<PlotSeries> {
        let mut plots = self.history.plots("light subpaths");
        for mut p in self.contribution_history.plots("light subpaths") {
            if p.plot == "Chains" && p.name != "replica exchanges" {
                p.name = format!("{} (contribution chain)", p.name);
                plots.push(p);
            }
        }
        plots
    }
}
