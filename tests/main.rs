//! The product's end-to-end tests, one binary: every file beside this one is a module of it,
//! so the GUI stack is linked once, not once per file, and the harness shares both cores
//! across all of them. `stress.rs` counts its own process's threads and memory, which the
//! other tests' sessions would disturb: a binary of its own (see `Cargo.toml`).

mod cli;
mod docs;
mod viewer;
mod viewer_window;
