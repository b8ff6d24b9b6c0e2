//! What the user can ask of the viewer, and what its background work reports (`Command`,
//! returned by the panels, the keyboard and the controller's events, and carried out by
//! `ViewerApp::apply`, the one place the viewer's state changes), and what the viewer tells
//! the user (`Message`).

use crate::viewer::controller::ControllerEvent;
use caustica_renderer::image::ToneCurve;
use std::path::PathBuf;

/// Everything the user can ask for, and what the background work reports.
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
    /// A scene opened (from this file) has loaded and renders.
    SceneLoaded(PathBuf),
    /// The scene was rebuilt with another environment.
    SceneRelit,
    /// Loading or relighting failed (the message names the file and the problem); the scene
    /// shown stays as it was.
    SceneFailed(String),
    /// The session's render failed (a pass panicked): why. Its image stays.
    RenderFailed(String),
    /// A scene's first frame measured for automatic exposure: show it at these stops.
    ExposeFrame(f32),
}

impl From<ControllerEvent> for Command {
    fn from(event: ControllerEvent) -> Self {
        match event {
            ControllerEvent::SceneLoaded(path) => Command::SceneLoaded(path),
            ControllerEvent::SceneRelit => Command::SceneRelit,
            ControllerEvent::SceneFailed(e) => Command::SceneFailed(e),
            ControllerEvent::RenderFailed(e) => Command::RenderFailed(e),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub is_error: bool,
}
