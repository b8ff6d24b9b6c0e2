//! What the user can ask of the viewer (`Command`, returned by the panels and the keyboard
//! and carried out by `ViewerApp::apply`), and what the viewer tells the user (`Message`).

use caustica_renderer::image::ToneCurve;
use std::path::PathBuf;

/// Everything the user can ask for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    OpenScene(PathBuf),
    ShowOpenDialog,
    SetIntegrator(String),
    /// Switch to the integrator and parameters the scene's survey recommends.
    UseRecommended,
    SetParam(String, f64),
    SetResolution(u32, u32),
    SetThreads(usize),
    SetSeed(u64),
    TogglePause,
    Restart,
    SetExposure(f32),
    SetToneCurve(ToneCurve),
    Fit,
    OneToOne,
    SaveExr,
    SavePng,
    TogglePlots,
    ToggleErrorMap,
    /// Show the reference in place of the render (or back).
    ToggleReference,
    ShowReferenceDialog,
    LoadReference(PathBuf),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub is_error: bool,
}
