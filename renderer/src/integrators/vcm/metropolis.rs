//! Metropolis light subpaths for vertex connection and merging (`amcvcm`): vcm whose light
//! subpaths come from visibility chains (Hachisuka & Jensen 2011, as amcppm's photons; the
//! chains' counters, adaptation and normalisation are `visibility_chain.rs`).
//!
//! A pass turns vcm's around. First the camera subpaths, one per pixel, with the techniques
//! of their own vertices (emission found, next-event estimation); their non-specular vertices
//! are stored and indexed in the hash grid. Then each worker runs a chain over (u, k): a
//! light subpath u in primary sample space and a camera subpath k, drawn uniformly among the
//! pass's at every proposal. A proposal is evaluated whole: g(u, k) is what its vertices bring
//! joined to the camera (t = 1), connected to the vertices of camera subpath k and merged
//! with every stored camera vertex within the radius, each weighted by vcm's MIS for N_L
//! independent light subpaths. The mean of g over uniform (u, k), times N_L, is what vcm's
//! light subpaths bring to the image, so any estimate of that mean serves; the chain's is the
//! visibility chain's, whose target is V = [g != 0]. Each state's contributions are added
//! once when the chain leaves it, weighted by the iterations it was held, and at the end of
//! the pass a chain's sum is scaled by its normalisation.
//!
//! A light subpath that a chain keeps is connected to a new camera subpath at each iteration
//! it is proposed with, and merged with every camera vertex near it: where few light
//! subpaths reach what the camera sees (light through a gap), the chains keep them there.

use super::Pass;
use super::camera_pass::{self, CameraSample, CameraVertex, connect, merge_pair};
use super::light_pass::{LightVertex, trace_light_subpath};
use super::mis::SubpathMis;
use super::techniques::TechniqueShares;
use crate::film::sanitize;
use crate::integrators::bdpt::vertex::Vertex;
use crate::integrators::ppm::hash_grid::HashGrid;
use crate::integrators::visibility_chain::{
    ChainCounters, ChainHistory, large_step_param, one_per_worker, worker_share,
};
use crate::integrators::{Cancelled, ParamSpec, PassStats, PlotSeries};
use crate::sampling::pss::{LIGHT_STREAM, PssSampler};
use crate::sampling::sampler::Sampler;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

const CHAIN_STREAM: u64 = 0x5ca1_ab1e_0035_0002;
const PICK_STREAM: u64 = 0x5ca1_ab1e_0035_0003;

/// amcvcm's share of uniform proposals.
pub const LARGE_STEP: ParamSpec = large_step_param(
    "Probability that a chain proposes a uniform light subpath (which also measures the visible fraction) instead of a small step from its state; 1 is vcm's independent light subpaths with repeats.",
);

/// A stored non-specular vertex of a camera subpath.
#[derive(Clone, Copy, Debug)]
pub(super) struct StoredCameraVertex {
    pub vertex: Vertex,
    pub mis: SubpathMis,
    pub path_length: u32,
    pub pixel: u32,
}

impl StoredCameraVertex {
    fn as_camera_vertex(&self) -> CameraVertex<'_> {
        CameraVertex {
            vertex: &self.vertex,
            mis: &self.mis,
            path_length: self.path_length,
        }
    }
}

/// A pass's camera subpaths: their stored vertices, subpath after subpath, where each
/// subpath's end, and the grid over the vertices for merges.
pub(super) struct CameraVertices {
    pub vertices: Vec<StoredCameraVertex>,
    pub ends: Vec<u32>,
    pub grid: Option<HashGrid>,
}

impl CameraVertices {
    fn subpath(&self, k: usize) -> &[StoredCameraVertex] {
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.vertices[start..self.ends[k] as usize]
    }

    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.vertices.as_slice())
            + std::mem::size_of_val(self.ends.as_slice())
            + self.grid.as_ref().map_or(0, |g| g.memory_bytes())
    }
}

/// The camera half of an amcvcm pass into `buffer` (emission found and next-event
/// estimation), the subpaths' vertices stored (`camera_pass::camera_rows`).
pub(super) fn camera_subpaths(
    buffer: &mut [CameraSample],
    setup: &Pass,
    seed: u64,
    pass: u64,
    cancel: &AtomicBool,
) -> Result<(CameraVertices, PassStats, TechniqueShares), Cancelled> {
    let rows = camera_pass::camera_rows(
        buffer,
        setup,
        (seed, pass),
        cancel,
        || (Vec::new(), Vec::new()),
        |(vertices, ends): &mut (Vec<StoredCameraVertex>, Vec<u32>),
         pixel,
         film,
         sampler,
         stats,
         shares| {
            let out = camera_pass::trace_camera_techniques(
                setup,
                film,
                sampler,
                stats,
                shares,
                |x, _, _, _| {
                    vertices.push(StoredCameraVertex {
                        vertex: *x.vertex,
                        mis: *x.mis,
                        path_length: x.path_length,
                        pixel: pixel as u32,
                    })
                },
            );
            ends.push(vertices.len() as u32);
            out
        },
    )?;
    let mut all = CameraVertices {
        vertices: Vec::with_capacity(rows.iter().map(|r| r.0.0.len()).sum()),
        ends: Vec::with_capacity(buffer.len()),
        grid: None,
    };
    let (mut stats, mut shares) = (PassStats::default(), TechniqueShares::default());
    for ((vertices, ends), st, sh) in rows {
        let offset = all.vertices.len() as u32;
        all.ends.extend(ends.iter().map(|e| e + offset));
        all.vertices.extend(vertices);
        stats = stats + st;
        shares.add(&sh);
    }
    if setup.merges {
        let radius = setup.radius_sq.sqrt();
        let points: Vec<Option<(Vec3, f32)>> = all
            .vertices
            .iter()
            .map(|v| Some((v.vertex.p, radius)))
            .collect();
        all.grid = Some(HashGrid::build(&points));
    }
    Ok((all, stats, shares))
}

/// What a light subpath brings to one pixel by one technique.
#[derive(Clone, Copy, Debug)]
pub(super) struct Contribution {
    pixel: u32,
    value: Vec3,
    technique: Technique,
}

impl Contribution {
    /// Its value in the image (a merge's with its normalisation).
    pub(super) fn image_value(&self, merge_normalization: f32) -> Vec3 {
        match self.technique {
            Technique::Connection { .. } => self.value,
            Technique::Merge { .. } => self.value * merge_normalization,
        }
    }

    /// Its luminance in the image.
    pub(super) fn luminance(&self, merge_normalization: f32) -> f32 {
        crate::geometry::luminance(self.image_value(merge_normalization))
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Technique {
    /// A connection (t = 1 included) on a path of `edges` edges with `s` light vertices.
    Connection { edges: u32, s: u32 },
    /// A merge, its value before the normalisation 1 / (pi r^2 N_L); `inner` whether within
    /// the kernel-bias estimate's inner radius.
    Merge {
        edges: u32,
        light_edges: u32,
        inner: bool,
    },
}

/// What a worker's chain brought to each pixel this pass, and to each technique.
pub(super) struct ChainGather {
    pub value: Vec<Vec3>,
    pub merged: Vec<Vec3>,
    pub merged_inner: Vec<Vec3>,
    pub shares: TechniqueShares,
    /// Where the light subpaths include uniform ones (mvcm's bootstrap), what they alone
    /// bring, weighted to stand for all of them: an unbiased image whose noise does not
    /// follow the chains' (for the error estimate's r); empty otherwise.
    pub independent: Vec<Vec3>,
}

impl ChainGather {
    pub(super) fn new(pixels: usize) -> Self {
        ChainGather {
            value: vec![Vec3::ZERO; pixels],
            merged: vec![Vec3::ZERO; pixels],
            merged_inner: vec![Vec3::ZERO; pixels],
            shares: TechniqueShares::default(),
            independent: Vec::new(),
        }
    }

    /// A state's contributions, each `weight` times.
    pub(super) fn add(
        &mut self,
        contributions: &[Contribution],
        weight: f32,
        merge_normalization: f32,
    ) {
        for c in contributions {
            let (p, v) = (c.pixel as usize, c.value * weight);
            match c.technique {
                Technique::Connection { edges, s } => {
                    self.value[p] += v;
                    self.shares.connection(edges, s, v);
                }
                Technique::Merge {
                    edges,
                    light_edges,
                    inner,
                } => {
                    self.value[p] += v * merge_normalization;
                    self.merged[p] += v;
                    if inner {
                        self.merged_inner[p] += v;
                    }
                    self.shares
                        .merge(edges, light_edges, v * merge_normalization);
                }
            }
        }
    }

    /// Adds another worker's gather.
    pub(super) fn add_gather(&mut self, g: &ChainGather) {
        for (t, v) in self.value.iter_mut().zip(&g.value) {
            *t += *v;
        }
        for (t, v) in self.merged.iter_mut().zip(&g.merged) {
            *t += *v;
        }
        for (t, v) in self.merged_inner.iter_mut().zip(&g.merged_inner) {
            *t += *v;
        }
        if self.independent.is_empty() {
            self.independent = vec![Vec3::ZERO; g.independent.len()];
        }
        for (t, v) in self.independent.iter_mut().zip(&g.independent) {
            *t += *v;
        }
        self.shares.add(&g.shares);
    }

    pub(super) fn scale(&mut self, s: f32) {
        for v in self
            .value
            .iter_mut()
            .chain(&mut self.merged)
            .chain(&mut self.merged_inner)
            .chain(&mut self.independent)
        {
            *v *= s;
        }
        self.shares.scale(f64::from(s));
    }
}

/// Draws a chain's proposals: the light subpath its primary samples give, joined with a
/// camera subpath drawn uniformly at each proposal, evaluated whole.
#[derive(Clone, Debug)]
pub(super) struct Proposer {
    pick: Sampler,
    key: u64,
    steps: u64,
    vertices: Vec<LightVertex>,
}

impl Proposer {
    pub(super) fn new(seed: u64, key: u64) -> Self {
        Proposer {
            pick: Sampler::new(seed ^ PICK_STREAM),
            key,
            steps: 0,
            vertices: Vec::new(),
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.vertices.capacity() * size_of::<LightVertex>()
    }

    /// A uniform number for this proposal's accept/reject decision.
    pub(super) fn uniform(&mut self) -> f32 {
        self.pick.get_1d()
    }

    /// Traces the light subpath of `state` (whose step has started) and evaluates it with a
    /// camera subpath drawn uniformly into `out`: empty when it brings nothing.
    pub(super) fn propose(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        state: &mut PssSampler,
        out: &mut Vec<Contribution>,
        st: &mut PassStats,
    ) {
        state.start_stream(LIGHT_STREAM, 0);
        self.steps += 1;
        self.pick.start_pixel_sample(self.key, self.steps);
        let subpaths = cameras.ends.len();
        let k = ((self.pick.get_1d() * subpaths as f32) as usize).min(subpaths.saturating_sub(1));
        out.clear();
        self.vertices.clear();
        trace_light_subpath(
            setup,
            state,
            &mut self.vertices,
            &mut |edges, pixel, value| {
                out.push(Contribution {
                    pixel: pixel as u32,
                    value,
                    technique: Technique::Connection { edges, s: edges },
                })
            },
            st,
        );
        if subpaths > 0 {
            evaluate(setup, cameras, k, &self.vertices, out, st);
        }
    }
}

/// One worker's chain over (light subpath, camera subpath).
#[derive(Clone, Debug)]
pub(super) struct LightSubpathChain {
    state: PssSampler,
    proposer: Proposer,
    /// The current state's contributions (empty until the pass's first visible sample), and
    /// the iterations it has been held since they were last added.
    current: Vec<Contribution>,
    held: u32,
    proposal: Vec<Contribution>,
    pub(super) counters: ChainCounters,
}

impl LightSubpathChain {
    pub(super) fn new(seed: u64, index: u64) -> Self {
        let counters = ChainCounters::default();
        LightSubpathChain {
            state: PssSampler::new(seed ^ CHAIN_STREAM, index, counters.mutation_size, 1.0),
            proposer: Proposer::new(seed, index),
            current: Vec::new(),
            held: 0,
            proposal: Vec::new(),
            counters,
        }
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.state.memory_bytes()
            + (self.current.capacity() + self.proposal.capacity()) * size_of::<Contribution>()
            + self.proposer.memory_bytes()
    }

    /// Starts a pass: no state yet (the targets changed with the camera subpaths).
    pub(super) fn start_pass(&mut self) {
        self.current.clear();
        self.held = 0;
        self.counters.start_pass();
    }

    /// One iteration: a proposal evaluated into `proposal`, taken when visible; `leave`
    /// receives the state it leaves, with the iterations it was held (amcvcm adds it to its
    /// gather, mvcm records it for its weights).
    pub(super) fn iterate(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        large_step_prob: f32,
        st: &mut PassStats,
        mut leave: impl FnMut(&[Contribution], u32),
    ) {
        let c = &mut self.counters;
        let searching = self.current.is_empty();
        c.start_step(&mut self.state, searching, large_step_prob);
        self.proposer
            .propose(setup, cameras, &mut self.state, &mut self.proposal, st);
        let visible = !self.proposal.is_empty();
        c.record(searching, self.state.is_large_step(), visible);
        if visible {
            self.state.accept();
            if self.held > 0 {
                leave(&self.current, self.held);
            }
            std::mem::swap(&mut self.current, &mut self.proposal);
            self.held = 0;
        } else {
            self.state.reject();
        }
        if !self.current.is_empty() {
            self.held += 1;
            self.counters.chain_samples += 1;
        }
    }

    /// Ends a pass: `leave` receives the state held.
    pub(super) fn finish_pass(&mut self, mut leave: impl FnMut(&[Contribution], u32)) {
        if self.held > 0 {
            leave(&self.current, self.held);
        }
        self.held = 0;
    }
}

/// The connections of light subpath `light` with camera subpath `k` and its merges with every
/// stored camera vertex within the radius, into `out`.
fn evaluate(
    setup: &Pass,
    cameras: &CameraVertices,
    k: usize,
    light: &[LightVertex],
    out: &mut Vec<Contribution>,
    st: &mut PassStats,
) {
    let own = cameras.subpath(k);
    for y in light {
        if setup.connections {
            for x in own {
                if y.path_length + 1 + x.path_length > setup.max_path_length {
                    break;
                }
                let v = connect(setup, &x.as_camera_vertex(), y, st);
                match sanitize(v) {
                    Some(v) if v != Vec3::ZERO => out.push(Contribution {
                        pixel: x.pixel,
                        value: v,
                        technique: Technique::Connection {
                            edges: y.path_length + 1 + x.path_length,
                            s: y.path_length + 1,
                        },
                    }),
                    Some(_) => {}
                    None => st.dropped += 1,
                }
            }
        }
        let Some(grid) = &cameras.grid else {
            continue;
        };
        for &c in grid.candidates(y.vertex.p) {
            let x = &cameras.vertices[c as usize];
            let Some((v, inner)) = merge_pair(setup, &x.as_camera_vertex(), y) else {
                continue;
            };
            match sanitize(v) {
                Some(v) if v != Vec3::ZERO => out.push(Contribution {
                    pixel: x.pixel,
                    value: v,
                    technique: Technique::Merge {
                        edges: y.path_length + x.path_length,
                        light_edges: y.path_length,
                        inner,
                    },
                }),
                Some(_) => {}
                None => st.dropped += 1,
            }
        }
    }
}

/// vcm's Metropolis light subpaths: a chain per worker, and what the viewer plots of them.
#[derive(Clone, Debug, Default)]
pub struct MetropolisLightSubpaths {
    /// Probability of a uniform proposal (`LARGE_STEP`).
    pub large_step_prob: f32,
    chains: Vec<LightSubpathChain>,
    history: ChainHistory,
}

impl MetropolisLightSubpaths {
    pub fn new(large_step_prob: f32) -> Self {
        MetropolisLightSubpaths {
            large_step_prob,
            ..Default::default()
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.chains.iter().map(|c| c.memory_bytes()).sum::<usize>() + self.history.memory_bytes()
    }

    /// The light half of a pass: `light_paths` iterations shared among the chains (one per
    /// worker), each chain's sum weighted by its normalisation, summed in chain order.
    pub(super) fn light_subpaths(
        &mut self,
        setup: &Pass,
        cameras: &CameraVertices,
        light_paths: u64,
        seed: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<ChainGather, Cancelled> {
        one_per_worker(&mut self.chains, |i| LightSubpathChain::new(seed, i));
        self.history
            .start_pass(self.chains.iter().map(|c| &c.counters));
        let pixels = cameras.ends.len();
        let count = self.chains.len() as u64;
        let large_step_prob = self.large_step_prob;
        let results: Vec<(ChainGather, PassStats)> = self
            .chains
            .par_iter_mut()
            .enumerate()
            .map(|(i, chain)| {
                let i = i as u64;
                let iterations = worker_share(light_paths, count, i);
                let mut gather = ChainGather::new(pixels);
                let mut st = PassStats::default();
                let norm = setup.merge_normalization;
                chain.start_pass();
                for j in 0..iterations {
                    if j % 256 == 0 && cancel.load(Ordering::Relaxed) {
                        return Err(Cancelled);
                    }
                    chain.iterate(setup, cameras, large_step_prob, &mut st, |state, held| {
                        gather.add(state, held as f32, norm)
                    });
                }
                chain.finish_pass(|state, held| gather.add(state, held as f32, norm));
                gather.scale(chain.counters.scale(iterations) as f32);
                Ok((gather, st))
            })
            .collect::<Result<_, _>>()?;
        let v = self
            .history
            .visible_fraction(self.chains.iter().map(|c| &c.counters));
        self.history
            .end_pass(self.chains.iter().map(|c| &c.counters));
        let mut total = ChainGather::new(pixels);
        for (g, st) in results {
            total.add_gather(&g);
            *stats = *stats + st;
        }
        total.scale(v as f32);
        Ok(total)
    }

    /// The run's counters for `--stats`.
    pub fn statistics(&self) -> serde_json::Value {
        self.history
            .statistics(self.chains.iter().map(|c| &c.counters))
    }

    pub fn plots(&self) -> Vec<PlotSeries> {
        self.history.plots("light subpaths")
    }
}
