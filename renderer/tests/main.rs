//! The renderer's integration tests, one binary: every file beside this one is a module of it,
//! so the crate is linked once, not once per file, and the harness shares both cores across
//! all of them. Tests that count the process's own threads or memory are binaries of their
//! own (`stress.rs`, `priority.rs`; see `Cargo.toml`).

mod accel;
mod bidirectional;
mod closed_form;
mod common;
mod convergence_rates;
mod environment;
mod error_estimate;
mod fuzz;
mod lights;
mod loader;
mod metropolis_light_subpaths;
mod photon_mapping;
mod session;
mod trapped_light;
mod vertex_merging;
