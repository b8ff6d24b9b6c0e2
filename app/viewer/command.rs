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
    /// Set by the user: automatic exposure stops.
    SetExposure(f32),
    /// Expose the next frame automatically, and each scene opened after.
    SetAutoExposure(bool),
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
    /// Light the scene from outside with `auto`, `none`, `uniform`, `studio` or an image file.
    SetEnvironment(String),
    SetEnvironmentStrength(f32),
    SetEnvironmentRotation(f32),
    ShowEnvironmentDialog,
    /// Move the camera: orbit by (yaw, pitch) radians, pan by (right, up) fractions of the
    /// view's height, dolly by a factor on the distance.
    MoveCamera {
        orbit: [f32; 2],
        pan: [f32; 2],
        dolly: f32,
    },
    /// Back to the scene's camera (the file's, or the default one).
    ResetCamera,
    /// Look through the file's camera of this index, or (None) the default view that frames
    /// the scene.
    ChooseCamera(Option<usize>),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub is_error: bool,
}
