//! Sampling: warps from the unit square with their pdfs, discrete distributions, and the
//! deterministic sampler every random number of the renderer comes from.

pub mod distribution;
pub mod pss;
pub mod sampler;
pub mod warp;

#[cfg(test)]
pub mod chi2;
