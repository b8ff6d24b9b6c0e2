//! Primary sample space for Metropolis light transport (Kelemen et al. 2002; pbrt-v3 section
//! 16.4.2, `MLTSampler`): a chain's state is a vector of uniform numbers, drawn lazily as the
//! path asks for them and split into interleaved streams (camera, light, connection) so that
//! the coordinates one stream uses never move another's. A step is either large (every
//! coordinate drawn anew) or small (each moved by a normal of standard deviation sigma,
//! wrapped into [0, 1)); rejecting a step restores what it changed.
//!
//! The randomness that drives mutations comes from the hashed `Sampler`, keyed by (key,
//! iteration): a chain's history depends on nothing but its key and the parameters.

use crate::sampling::sampler::{ONE_MINUS_EPSILON, SampleSource, Sampler};

pub const CAMERA_STREAM: usize = 0;
pub const LIGHT_STREAM: usize = 1;
pub const CONNECTION_STREAM: usize = 2;
const STREAM_COUNT: usize = 3;

#[derive(Clone, Copy, Debug, Default)]
struct PrimarySample {
    /// Whether the coordinate has ever been read (unread ones are independent uniforms).
    drawn: bool,
    value: f32,
    /// Iteration that last set `value`.
    last_modified: u64,
    backup_value: f32,
    backup_modified: u64,
}

#[derive(Clone, Debug)]
pub struct PssSampler {
    rng: Sampler,
    key: u64,
    pub sigma: f32,
    pub large_step_prob: f32,
    samples: Vec<PrimarySample>,
    /// The coordinates this step changed: a rejection restores only these (a photon path of
    /// many bounces reads a few hundred coordinates, and a scan of them all at every
    /// rejection was 2 % of amcppm's time on gap-glass).
    changed: Vec<u32>,
    /// Iteration of the state: a rejected step takes it back.
    iteration: u64,
    /// Steps taken, rejected or not: keys the mutation randomness, which must never repeat.
    steps: u64,
    large_step: bool,
    last_large_step: u64,
    stream: usize,
    index: usize,
}

/// Maps x - floor(x) into [0, 1): in f32 it can round to exactly 1 (DESIGN.md section 5).
fn wrap(x: f32) -> f32 {
    let v = x - x.floor();
    if (0.0..1.0).contains(&v) { v } else { 0.0 }
}

impl PssSampler {
    /// Bytes of the sampler with its primary samples.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + std::mem::size_of_val(self.samples.as_slice())
            + self.changed.capacity() * std::mem::size_of::<u32>()
    }

    /// A state whose coordinates will all be drawn fresh, keyed by `key` (a bootstrap
    /// sample's index reproduces that sample).
    pub fn new(seed: u64, key: u64, sigma: f32, large_step_prob: f32) -> Self {
        let mut rng = Sampler::new(seed);
        rng.start_pixel_sample(key, 0);
        PssSampler {
            rng,
            key,
            sigma,
            large_step_prob,
            samples: Vec::new(),
            changed: Vec::new(),
            iteration: 0,
            steps: 0,
            large_step: true,
            last_large_step: 0,
            stream: 0,
            index: 0,
        }
    }

    /// From now on mutations are keyed by `key` (chains that start from the same bootstrap
    /// sample must not move in lockstep).
    pub fn rekey(&mut self, key: u64) {
        self.key = key;
    }

    /// The key its mutations are drawn by.
    pub fn key(&self) -> u64 {
        self.key
    }

    pub fn is_large_step(&self) -> bool {
        self.large_step
    }

    /// Starts a step: decides large or small; coordinates change as they are read.
    pub fn start_iteration(&mut self) {
        self.iteration += 1;
        self.steps += 1;
        self.changed.clear();
        self.rng.start_pixel_sample(self.key, self.steps);
        self.large_step = self.rng.get_1d() < self.large_step_prob;
    }

    /// A uniform number for the accept/reject decision of this step.
    pub fn accept_uniform(&mut self) -> f32 {
        self.rng.get_1d()
    }

    pub fn accept(&mut self) {
        if self.large_step {
            self.last_large_step = self.iteration;
        }
        self.changed.clear();
    }

    pub fn reject(&mut self) {
        for &i in &self.changed {
            let x = &mut self.samples[i as usize];
            debug_assert_eq!(x.last_modified, self.iteration);
            x.value = x.backup_value;
            x.last_modified = x.backup_modified;
        }
        self.changed.clear();
        self.iteration -= 1;
    }

    /// Reads coordinates of `stream` from its `index`-th on.
    pub fn start_stream(&mut self, stream: usize, index: usize) {
        debug_assert!(stream < STREAM_COUNT);
        self.stream = stream;
        self.index = index;
    }

    fn ensure_ready(&mut self, i: usize) {
        if i >= self.samples.len() {
            self.samples.resize(i + 1, PrimarySample::default());
        }
        let iteration = self.iteration;
        let x = &mut self.samples[i];
        // A coordinate read for the first time, or one that missed the last accepted large
        // step, is a fresh uniform as of that step.
        if !x.drawn || x.last_modified < self.last_large_step {
            x.drawn = true;
            x.value = self.rng.get_1d();
            x.last_modified = self.last_large_step;
        }
        if x.last_modified == iteration {
            return;
        }
        x.backup_value = x.value;
        x.backup_modified = x.last_modified;
        self.changed.push(i as u32);
        if self.large_step {
            x.value = self.rng.get_1d();
        } else {
            // Kelemen's small step, n missed small steps at once: a normal of standard
            // deviation sigma sqrt(n) (Box-Muller), wrapped around the unit interval.
            let n_small = (iteration - x.last_modified) as f32;
            let (u1, u2) = (self.rng.get_1d(), self.rng.get_1d());
            let normal = (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
            x.value = wrap(x.value + normal * self.sigma * n_small.sqrt());
        }
        x.last_modified = iteration;
    }
}

impl SampleSource for PssSampler {
    fn get_1d(&mut self) -> f32 {
        let i = self.stream + STREAM_COUNT * self.index;
        self.index += 1;
        self.ensure_ready(i);
        self.samples[i].value.min(ONE_MINUS_EPSILON)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping_never_gives_one() {
        assert_eq!(wrap(-1e-9), 0.0);
        assert_eq!(wrap(1.0), 0.0);
        assert!((wrap(1.25) - 0.25).abs() < 1e-7);
        assert!((wrap(-0.25) - 0.75).abs() < 1e-7);
    }

    #[test]
    fn a_rejected_step_restores_the_state_and_streams_are_independent() {
        let mut s = PssSampler::new(1, 5, 0.01, 0.0);
        let read = |s: &mut PssSampler, stream| {
            s.start_stream(stream, 0);
            (0..4).map(|_| s.get_1d()).collect::<Vec<f32>>()
        };
        let camera = read(&mut s, CAMERA_STREAM);
        let light = read(&mut s, LIGHT_STREAM);
        s.accept();
        s.start_iteration();
        let moved = read(&mut s, CAMERA_STREAM);
        assert!(
            moved
                .iter()
                .zip(&camera)
                .all(|(a, b)| a != b && (a - b).abs() < 0.1)
        );
        s.reject();
        let stored = |s: &PssSampler, stream: usize| -> Vec<f32> {
            (0..4)
                .map(|i| s.samples[stream + STREAM_COUNT * i].value)
                .collect()
        };
        assert_eq!(stored(&s, CAMERA_STREAM), camera, "rejection restores");
        // The next proposal is a new one: the randomness of a rejected step never repeats
        // (keying it by the state's iteration, which rejection takes back, stuck chains).
        s.start_iteration();
        let again = read(&mut s, CAMERA_STREAM);
        assert!(again.iter().zip(&moved).all(|(a, b)| a != b));
        s.reject();
        // A step that reads only the camera stream leaves the light stream as it was.
        s.start_iteration();
        read(&mut s, CAMERA_STREAM);
        s.accept();
        assert_eq!(stored(&s, LIGHT_STREAM), light);
        // A large step, once accepted, renews every coordinate, even those read later.
        s.large_step_prob = 1.0;
        s.start_iteration();
        let fresh = read(&mut s, CAMERA_STREAM);
        s.accept();
        s.large_step_prob = 0.0;
        s.start_iteration();
        let light_after = read(&mut s, LIGHT_STREAM);
        assert!(fresh.iter().zip(&moved).all(|(a, b)| a != b));
        assert!(
            light_after
                .iter()
                .zip(&light)
                .all(|(a, b)| (a - b).abs() > 1e-6)
        );
    }

    /// Small and large steps leave the uniform distribution invariant: chains that accept
    /// every step (a constant target) keep their coordinates uniform. One value per chain
    /// after 500 steps from 4000 independent chains; chi-square with 19 degrees of freedom,
    /// 43.8 is its 0.001 quantile.
    #[test]
    fn steps_keep_coordinates_uniform() {
        let bins = 20;
        let mut counts = vec![0u32; bins];
        let chains = 4000u64;
        for chain in 0..chains {
            let mut s = PssSampler::new(2, chain, 0.05, 0.1);
            let mut x = 0.0;
            for _ in 0..500 {
                s.start_iteration();
                s.start_stream(CAMERA_STREAM, 0);
                x = s.get_1d();
                assert!((0.0..1.0).contains(&x));
                s.accept();
            }
            counts[(x * bins as f32) as usize] += 1;
        }
        crate::sampling::chi2::chi2_uniform("pss coordinates", &counts, 0.001).unwrap();
    }
}
