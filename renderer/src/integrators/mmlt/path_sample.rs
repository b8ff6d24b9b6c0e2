//! The function a Metropolis chain samples (Hachisuka, Kaplanyan & Dachsbacher 2014,
//! section 4): a point of primary sample space and a path length k map to one bidirectional
//! technique (s, t), chosen by the connection stream's first number, and its MIS-weighted
//! contribution times the number of techniques n = k + 2 (their eq. 7: the techniques'
//! weights sum to one, so the expectation over the technique number is the full
//! contribution). Subpaths have exactly the lengths the technique needs, or contribute
//! nothing.
//!
//! Deviation: for k = 0 only (s, t) = (0, 2) is used (n = 1): (1, 1) would connect a light
//! point to the pinhole directly, which BDPT never evaluates, and (2, 0) cannot hit a pinhole.
//!
//! Long paths carry little of the image, but a chain of every length up to a maximum depth of
//! 64 would cost a bootstrap per length (most of the time before the first image, for a few
//! percent of the light) and chains that starve. So the lengths from `MULTIPLEXED_FROM` on
//! share one family of chains the same way the techniques of one length do: the connection
//! stream's first number picks (k, s) among all techniques of all those lengths
//! (`technique_choice`), and the contribution is divided by the pick's probability (the same
//! argument as eq. 7, over k as well as s). A chain then moves between long lengths as it
//! moves between techniques, and spends its steps on each in proportion to its share of the
//! light.

use crate::camera::Camera;
use crate::geometry::luminance;
use crate::integrators::bdpt::connect::connect;
use crate::integrators::bdpt::subpath::{Termination, Walker};
use crate::integrators::bdpt::vertex::Vertex;
use crate::integrators::mmlt::technique_choice::{Pick, TechniqueChoice};
use crate::sampling::pss::{CAMERA_STREAM, CONNECTION_STREAM, LIGHT_STREAM, PssSampler};
use crate::sampling::sampler::SampleSource;
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::ops::RangeInclusive;

/// The first path length whose chains sample every longer length too (module docs).
pub const MULTIPLEXED_FROM: usize = 10;

/// The number of slots, sets of path lengths with chains of their own, for `max_depth`:
/// one per length below `MULTIPLEXED_FROM` and one for all the others.
pub fn slot_count(max_depth: usize) -> usize {
    max_depth.min(MULTIPLEXED_FROM) + 1
}

/// The path lengths that the chains of slot `slot` sample.
pub fn slot_lengths(slot: usize, max_depth: usize) -> RangeInclusive<usize> {
    if slot < MULTIPLEXED_FROM {
        slot..=slot
    } else {
        MULTIPLEXED_FROM..=max_depth
    }
}

/// One evaluation: the path length and technique chosen, the contribution and where it
/// lands on the film.
#[derive(Clone, Copy, Debug)]
pub struct PathSample {
    pub k: usize,
    pub s: usize,
    pub l: Vec3,
    pub raster: Vec2,
}

impl PathSample {
    /// The chain's target: the contribution's luminance (zero for invalid values, which the
    /// caller counts as dropped).
    pub fn luminance(&self) -> f32 {
        let y = luminance(self.l);
        if y.is_finite() && y > 0.0 && self.l.min_element() >= 0.0 {
            y
        } else {
            0.0
        }
    }

    pub fn is_valid(&self) -> bool {
        self.l.is_finite() && self.l.min_element() >= 0.0
    }

    /// Replaces a NaN, infinite or negative contribution by zero (a zero-target state the
    /// chain will leave); true if it did, for the dropped count.
    pub fn drop_if_invalid(&mut self) -> bool {
        if self.is_valid() {
            return false;
        }
        self.l = Vec3::ZERO;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_contributions_are_dropped_and_have_zero_target() {
        for l in [
            Vec3::new(f32::NAN, 1.0, 1.0),
            Vec3::new(1.0, f32::INFINITY, 1.0),
            Vec3::new(1.0, 1.0, -1e-3),
        ] {
            let mut s = PathSample {
                k: 1,
                s: 1,
                l,
                raster: Vec2::ZERO,
            };
            assert_eq!(s.luminance(), 0.0);
            assert!(s.drop_if_invalid());
            assert_eq!(s.l, Vec3::ZERO);
        }
        let mut ok = PathSample {
            k: 0,
            s: 0,
            l: Vec3::ONE,
            raster: Vec2::ZERO,
        };
        assert!(!ok.drop_if_invalid());
        assert!((ok.luminance() - 1.0).abs() < 1e-6);
    }
}

/// Scratch space for the subpaths, reused between evaluations.
#[derive(Default)]
pub struct Subpaths {
    camera: Vec<Vertex>,
    light: Vec<Vertex>,
}

/// Evaluates the state of `sampler` as a path of one of `choice`'s lengths.
pub fn evaluate(
    scene: &Scene,
    camera: &Camera,
    sampler: &mut PssSampler,
    choice: &TechniqueChoice,
    scratch: &mut Subpaths,
    rays: &mut u64,
) -> PathSample {
    sampler.start_stream(CONNECTION_STREAM, 0);
    let Pick { k, s, weight } = if choice.is_choice() {
        choice.pick(sampler.get_1d())
    } else {
        choice.pick(0.0)
    };
    let t = k + 2 - s;
    sampler.start_stream(CAMERA_STREAM, 0);
    let film = sampler.get_2d() * Vec2::new(camera.width as f32, camera.height as f32);
    let zero = PathSample {
        k,
        s,
        l: Vec3::ZERO,
        raster: film,
    };
    let mut walker = Walker {
        scene,
        sampler,
        termination: Termination::Fixed,
        rays,
    };
    walker.camera_subpath(camera, film, t, &mut scratch.camera);
    if scratch.camera.len() != t {
        return zero;
    }
    walker.sampler.start_stream(LIGHT_STREAM, 0);
    walker.light_subpath(s, &mut scratch.light);
    // s = 1 samples its own light vertex, whether or not the subpath's origin emits.
    if s != 1 && scratch.light.len() != s {
        return zero;
    }
    sampler.start_stream(CONNECTION_STREAM, 1);
    match connect(
        scene,
        camera,
        &scratch.light,
        &scratch.camera,
        s,
        t,
        sampler,
        rays,
        true,
    ) {
        Some(c) => PathSample {
            k,
            s,
            l: c.l * (c.mis * weight),
            raster: c.raster.unwrap_or(film),
        },
        None => zero,
    }
}
