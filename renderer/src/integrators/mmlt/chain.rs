//! One Markov chain of fixed path length in primary sample space (Hachisuka et al. 2014,
//! section 4; Kelemen et al. 2002): Metropolis-Hastings with the symmetric Kelemen proposals,
//! acceptance a = min(1, Y(proposed) / Y(current)), and expected-value splatting of both
//! states (Veach 1997, section 11.5): the proposal with a L / Y, the current state with
//! (1 - a) L / Y.

use crate::camera::Camera;
use crate::integrators::Cancelled;
use crate::integrators::mmlt::histogram::TechniqueHistogram;
use crate::integrators::mmlt::path_sample::{PathSample, Subpaths, evaluate, slot_lengths};
use crate::integrators::mmlt::technique_choice::TechniqueChoice;
use crate::sampling::pss::PssSampler;
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::sync::atomic::{AtomicBool, Ordering};

pub struct Chain {
    sampler: PssSampler,
    /// The slot (`path_sample::slot_lengths`) whose path lengths the chain samples.
    pub slot: usize,
    choice: TechniqueChoice,
    current: PathSample,
    current_y: f32,
}

/// What a run of steps produced: splats (pixel, value) and counters.
#[derive(Default)]
pub struct ChainOutput {
    pub splats: Vec<(usize, Vec3)>,
    /// Large steps' proposals are independent uniform samples of the chain's length: their
    /// target values refine the normalisation b_k (Kelemen et al. 2002, section 4).
    pub large_step_sum: f64,
    pub large_step_sum_sq: f64,
    pub large_steps: u64,
    /// The large steps' proposals that reach the camera (pixel, L): independent of the
    /// chain's state, so an unbiased image of the chain's lengths, as the bootstrap's.
    pub large_step_splats: Vec<(usize, Vec3)>,
    pub rays: u64,
    pub dropped: u64,
}

fn pixel_of(camera: &Camera, raster: Vec2) -> usize {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let x = (raster.x.max(0.0) as usize).min(w - 1);
    let y = (raster.y.max(0.0) as usize).min(h - 1);
    y * w + x
}

impl Chain {
    /// Bytes of the chain with its primary samples and technique choice.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() - std::mem::size_of::<PssSampler>()
            + self.sampler.memory_bytes()
            + self.choice.heap_bytes()
    }

    /// A chain started from the bootstrap state `bootstrap_key` of slot `slot`, mutated from
    /// then on by its own `chain_key`; it picks techniques as the bootstrap did.
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        scene: &Scene,
        camera: &Camera,
        seed: u64,
        bootstrap_key: u64,
        chain_key: u64,
        slot: usize,
        max_depth: usize,
        scratch: &mut Subpaths,
        rays: &mut u64,
    ) -> Chain {
        let choice = TechniqueChoice::for_slot(slot_lengths(slot, max_depth));
        let mut sampler = PssSampler::new(seed, bootstrap_key, 0.01, 0.3);
        let current = evaluate(scene, camera, &mut sampler, &choice, scratch, rays);
        sampler.accept();
        sampler.rekey(chain_key);
        Chain {
            sampler,
            slot,
            choice,
            current_y: current.luminance(),
            current,
        }
    }

    /// The target value of the current state.
    pub fn current_luminance(&self) -> f32 {
        self.current_y
    }

    /// `steps` Metropolis steps with the given large-step probability and sigma.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        steps: u64,
        large_step_prob: f32,
        sigma: f32,
        scratch: &mut Subpaths,
        histogram: &mut TechniqueHistogram,
        out: &mut ChainOutput,
        cancel: &AtomicBool,
    ) -> Result<(), Cancelled> {
        self.sampler.large_step_prob = large_step_prob;
        self.sampler.sigma = sigma;
        for step in 0..steps {
            if step % 256 == 255 && cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            self.sampler.start_iteration();
            let mut proposed = evaluate(
                scene,
                camera,
                &mut self.sampler,
                &self.choice,
                scratch,
                &mut out.rays,
            );
            if proposed.drop_if_invalid() {
                out.dropped += 1;
            }
            let y = proposed.luminance();
            if self.sampler.is_large_step() {
                out.large_step_sum += y as f64;
                out.large_step_sum_sq += (y as f64) * (y as f64);
                out.large_steps += 1;
                if y > 0.0 {
                    out.large_step_splats
                        .push((pixel_of(camera, proposed.raster), proposed.l));
                }
            }
            // A current state of zero luminance accepts any proposal (DESIGN.md section 5).
            let a = if self.current_y > 0.0 {
                (y / self.current_y).min(1.0)
            } else {
                1.0
            };
            if y > 0.0 && a > 0.0 {
                out.splats
                    .push((pixel_of(camera, proposed.raster), proposed.l * (a / y)));
            }
            if self.current_y > 0.0 && a < 1.0 {
                out.splats.push((
                    pixel_of(camera, self.current.raster),
                    self.current.l * ((1.0 - a) / self.current_y),
                ));
            }
            let accepted = self.sampler.accept_uniform() < a;
            histogram.record(
                (self.current.k, self.current.s),
                (proposed.k, proposed.s),
                self.sampler.is_large_step(),
                accepted,
            );
            if accepted {
                self.current = proposed;
                self.current_y = y;
                self.sampler.accept();
            } else {
                self.sampler.reject();
            }
        }
        Ok(())
    }
}
