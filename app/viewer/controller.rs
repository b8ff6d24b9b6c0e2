//! The background side of the viewer: loads scenes on a thread of their own, owns the render
//! session, and turns setting changes into live parameter updates or restarts. Nothing here
//! blocks the UI thread: loads report through a channel, sessions publish frames through the
//! renderer's lock-free frame slot, and a replaced session is cancelled and joined on a
//! helper thread.

use crate::viewer::settings::ViewerSettings;
use caustica_renderer::advisor::{self, Recommendation};
use caustica_renderer::camera::CameraDesc;
use caustica_renderer::integrators;
use caustica_renderer::light::environment::EnvironmentSettings;
use caustica_renderer::scene::limits::LoadLimits;
use caustica_renderer::scene::{Scene, SceneError, gltf};
use caustica_renderer::session::{Frame, FrameCallback, Session, SessionConfig};
use caustica_renderer::survey::TransportSurvey;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};

pub struct LoadedScene {
    pub path: PathBuf,
    pub scene: Arc<Scene>,
    /// The environment it was built with, as the settings named it.
    pub lit_by: EnvironmentRequest,
    /// Its light transport and the estimator it needs: surveyed on the loading thread after
    /// the scene has started rendering (the survey traces paths for a second or two, which the
    /// first image must not wait for); None until then.
    pub survey: Option<(TransportSurvey, Recommendation)>,
    survey_arrives: Option<Receiver<(TransportSurvey, Recommendation)>>,
}

impl LoadedScene {
    pub fn recommendation(&self) -> Option<&Recommendation> {
        self.survey.as_ref().map(|(_, r)| r)
    }
}

/// What the loading thread sends: the scene, then a receiver for its survey.
type Loaded = (Arc<Scene>, Receiver<(TransportSurvey, Recommendation)>);

/// An environment as the viewer's settings name it.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentRequest {
    pub choice: String,
    pub strength: f32,
    pub rotation: f32,
}

impl EnvironmentRequest {
    pub fn of(settings: &ViewerSettings) -> Self {
        EnvironmentRequest {
            choice: settings.environment.clone(),
            strength: settings.environment_strength,
            rotation: settings.environment_rotation,
        }
    }

    fn resolve(&self) -> Result<EnvironmentSettings, String> {
        EnvironmentSettings::resolve(&self.choice, self.strength, self.rotation)
    }
}

/// A scene being loaded or relit.
struct Loading {
    path: PathBuf,
    lit_by: EnvironmentRequest,
    relight: bool,
    arrives: Receiver<Result<Loaded, SceneError>>,
}

/// What happened in the background since the last poll.
#[derive(Debug, Clone, PartialEq)]
pub enum ControllerEvent {
    SceneLoaded(PathBuf),
    /// The scene was rebuilt with another environment.
    SceneRelit,
    /// The load failed; the message names the file and the problem. The old scene stays.
    SceneFailed(String),
    /// The session's render failed (a pass panicked): why. Its image stays, and any restart
    /// starts a new session.
    RenderFailed(String),
}

/// How a parameter change took effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamEffect {
    Live,
    Restarted,
}

/// The scene and the render session behind the viewer, driven by `ViewerApp::apply`; its
/// state is read through its methods and changed only by them.
pub struct RenderController {
    scene: Option<LoadedScene>,
    session: Option<Session>,
    loading: Option<Loading>,
    on_frame: FrameCallback,
    /// Sessions started so far, so tests and the status line can tell a restart happened.
    sessions_started: u64,
    /// The view the user moved to, in place of the scene's camera; a newly opened scene
    /// starts without one.
    camera: Option<CameraDesc>,
    /// What a scene file may ask for (the command line can raise each limit).
    limits: LoadLimits,
    /// The current session's failure has been reported.
    failure_reported: bool,
    /// Fault injection for the tests: the sessions started panic during this pass.
    panic_in_pass: Option<u64>,
    /// Memory a session's buffers may take (None: what the system has available).
    memory_limit: Option<u64>,
}

fn drop_in_background(session: Session) {
    session.cancel();
    std::thread::spawn(move || drop(session));
}

impl RenderController {
    pub fn new(on_frame: FrameCallback) -> Self {
        RenderController {
            scene: None,
            session: None,
            loading: None,
            on_frame,
            sessions_started: 0,
            camera: None,
            limits: LoadLimits::default(),
            failure_reported: false,
            panic_in_pass: None,
            memory_limit: None,
        }
    }

    /// The scene shown, once one has loaded.
    pub fn scene(&self) -> Option<&LoadedScene> {
        self.scene.as_ref()
    }

    /// Sessions started so far, so tests and the status line can tell a restart happened.
    pub fn sessions_started(&self) -> u64 {
        self.sessions_started
    }

    /// The view the user moved to, if any, in place of the scene's camera.
    pub fn camera(&self) -> Option<CameraDesc> {
        self.camera
    }

    /// Sets the view the next session renders (None: the scene's camera); returns the last.
    pub fn set_camera(&mut self, camera: Option<CameraDesc>) -> Option<CameraDesc> {
        std::mem::replace(&mut self.camera, camera)
    }

    /// What scene files opened from now on may ask for.
    pub fn set_limits(&mut self, limits: LoadLimits) {
        self.limits = limits;
    }

    /// The memory the buffers of sessions started from now on may take (None: what the
    /// system has available).
    pub fn set_memory_limit(&mut self, limit: Option<u64>) {
        self.memory_limit = limit;
    }

    /// Fault injection for the tests: sessions started from now on panic during this pass.
    pub fn set_panic_in_pass(&mut self, pass: Option<u64>) {
        self.panic_in_pass = pass;
    }

    /// Starts loading a scene, lit as `settings` say, and surveying its light transport for
    /// the settings' image size; the current one keeps rendering until the new one is ready.
    pub fn open_scene(&mut self, path: PathBuf, settings: &ViewerSettings) {
        let lit_by = EnvironmentRequest::of(settings);
        let (load_path, limits) = (path.clone(), self.limits);
        self.build_in_background(path, settings, lit_by.clone(), false, move || {
            let environment = lit_by.resolve().map_err(SceneError::new)?;
            gltf::load_with(&load_path, environment, &limits)
        });
    }

    /// Relights the current scene with the environment `settings` name (an image file is read
    /// on the loading thread); the scene renders on as it was until the new one is ready, and
    /// stays as it was if the image cannot be read.
    pub fn relight(&mut self, settings: &ViewerSettings) {
        let Some(loaded) = &self.scene else {
            return;
        };
        let (scene, path) = (loaded.scene.clone(), loaded.path.clone());
        let lit_by = EnvironmentRequest::of(settings);
        self.build_in_background(path, settings, lit_by.clone(), true, move || {
            let environment = lit_by.resolve().map_err(SceneError::new)?;
            Ok(scene.with_environment(environment))
        });
    }

    /// Runs `build` on a thread of its own, then surveys what it built; `poll` collects both.
    fn build_in_background(
        &mut self,
        path: PathBuf,
        settings: &ViewerSettings,
        lit_by: EnvironmentRequest,
        relight: bool,
        build: impl FnOnce() -> Result<Scene, SceneError> + Send + 'static,
    ) {
        let (tx, rx) = channel();
        let notify = self.on_frame.clone();
        let (width, height) = (settings.width, settings.height);
        std::thread::spawn(move || {
            let scene = match build() {
                Ok(scene) => Arc::new(scene),
                Err(e) => {
                    let _ = tx.send(Err(e));
                    notify();
                    return;
                }
            };
            let (survey_tx, survey_rx) = channel();
            let _ = tx.send(Ok((scene.clone(), survey_rx)));
            notify();
            let _ = survey_tx.send(advisor::analyse(&scene, width, height));
            notify();
        });
        self.loading = Some(Loading {
            path,
            lit_by,
            relight,
            arrives: rx,
        });
    }

    pub fn loading(&self) -> Option<&Path> {
        self.loading.as_ref().map(|l| l.path.as_path())
    }

    /// Collects finished loads; a loaded scene replaces the current one and starts rendering.
    pub fn poll(&mut self, settings: &ViewerSettings) -> Vec<ControllerEvent> {
        let mut events = Vec::new();
        if !self.failure_reported
            && let Some(failure) = self.frame().and_then(|f| f.failure.clone())
        {
            self.failure_reported = true;
            events.push(ControllerEvent::RenderFailed(failure.to_string()));
        }
        if let Some(loaded) = &mut self.scene
            && let Some(Ok(survey)) = loaded.survey_arrives.as_ref().map(|rx| rx.try_recv())
        {
            loaded.survey = Some(survey);
            loaded.survey_arrives = None;
        }
        let Some(Loading {
            path,
            lit_by,
            relight,
            arrives,
        }) = &self.loading
        else {
            return events;
        };
        match arrives.try_recv() {
            Err(TryRecvError::Empty) => {}
            Err(TryRecvError::Disconnected) => {
                events.push(ControllerEvent::SceneFailed(format!(
                    "{}: the loader stopped unexpectedly",
                    path.display()
                )));
                self.loading = None;
            }
            Ok(Err(e)) => {
                events.push(ControllerEvent::SceneFailed(e.to_string()));
                self.loading = None;
            }
            Ok(Ok((scene, survey_arrives))) => {
                let (path, lit_by, relight) = (path.clone(), lit_by.clone(), *relight);
                self.loading = None;
                if !relight {
                    self.camera = None;
                }
                self.scene = Some(LoadedScene {
                    path: path.clone(),
                    scene,
                    lit_by,
                    survey: None,
                    survey_arrives: Some(survey_arrives),
                });
                match (self.restart(settings), relight) {
                    (Ok(()), false) => events.push(ControllerEvent::SceneLoaded(path)),
                    (Ok(()), true) => events.push(ControllerEvent::SceneRelit),
                    (Err(e), _) => events.push(ControllerEvent::SceneFailed(e)),
                }
            }
        }
        events
    }

    /// Starts a fresh session of the current scene with `settings`, replacing any running one.
    pub fn restart(&mut self, settings: &ViewerSettings) -> Result<(), String> {
        let Some(loaded) = &self.scene else {
            return Ok(());
        };
        // The old session renders on until the new one has started: a start that fails (a
        // parameter out of range) keeps what the user had.
        let scene = loaded.scene.clone();
        let session = Session::start(SessionConfig {
            params: settings.params.clone(),
            seed: settings.seed,
            threads: settings.threads,
            on_frame: Some(self.on_frame.clone()),
            background: true,
            camera: self.camera,
            panic_in_pass: self.panic_in_pass,
            memory_limit: self.memory_limit,
            ..SessionConfig::new(scene, &settings.integrator, settings.width, settings.height)
        })
        .map_err(|e| e.to_string())?;
        if let Some(old) = self.session.replace(session) {
            drop_in_background(old);
        }
        self.failure_reported = false;
        self.sessions_started += 1;
        Ok(())
    }

    /// Applies a parameter: live parameters change the running session, the others restart it.
    pub fn set_param(
        &mut self,
        settings: &ViewerSettings,
        name: &str,
        value: f64,
    ) -> Result<ParamEffect, String> {
        let info = integrators::find(&settings.integrator).ok_or("no integrator")?;
        let spec = info
            .params
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| format!("no parameter {name}"))?;
        // Checked once, where it takes effect: the session's live change or its restart.
        if spec.live
            && let Some(session) = &mut self.session
        {
            session.set_live_param(name, value)?;
            return Ok(ParamEffect::Live);
        }
        self.restart(settings)?;
        Ok(ParamEffect::Restarted)
    }

    pub fn session(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    pub fn frame(&self) -> Option<Arc<Frame>> {
        self.session.as_ref().map(Session::frame)
    }

    pub fn set_paused(&self, paused: bool) {
        if let Some(s) = &self.session {
            s.set_paused(paused);
        }
    }
}

impl Drop for RenderController {
    fn drop(&mut self) {
        if let Some(s) = self.session.take() {
            s.cancel();
        }
    }
}
