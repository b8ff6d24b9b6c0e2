//! The Caustica desktop program: the viewer (egui/eframe on wgpu). The command line in
//! `main.rs` opens it, or renders headless through the renderer's session API.

pub mod viewer;
