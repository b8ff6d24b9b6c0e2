//! Progressive render sessions (DESIGN.md section 6): passes run on a background thread that
//! drives a rayon pool; after every pass the newest frame is published through an `ArcSwap`,
//! so a reader (the viewer's UI thread, the command line's progress bar) gets it without
//! waiting on any lock the workers hold, and frames are never queued: the newest wins.
//! Cancellation is checked per image row, so it takes effect within a fraction of a pass.

mod frame;

pub use frame::{Frame, RunState};

use crate::camera::{Camera, CameraDesc};
use crate::error_estimate::ErrorEstimate;
use crate::image::Image;
use crate::integrators::{
    self, Integrator, ParamValues, PassStats, PixelLayer, PlotSeries, RenderContext,
};
use crate::preview;
use crate::scene::Scene;
use arc_swap::ArcSwap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The largest width or height a session renders; the command line and the viewer offer
/// no more.
pub const MAX_RESOLUTION: u32 = 16384;

#[derive(Clone)]
pub struct SessionConfig {
    pub scene: Arc<Scene>,
    pub integrator: String,
    /// Overrides of the integrator's defaults.
    pub params: ParamValues,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    /// Worker threads; 0 means one per core.
    pub threads: usize,
    /// Stop after this many passes.
    pub max_passes: Option<u64>,
    /// Stop after the pass during which this much time has passed.
    pub time_limit: Option<Duration>,
    /// Stop once the estimated remaining relMSE (`Frame::error`) falls below this.
    pub target_rel_mse: Option<f64>,
    /// Run the workers below normal OS priority (the lowest niceness where the OS has it), so
    /// that a UI sharing the cores with them stays responsive: the viewer sets it, the
    /// command line does not.
    pub background: bool,
    /// Called on the session's thread whenever a new frame is published (a viewer asks for a
    /// repaint here, so it redraws exactly when there is something new).
    pub on_frame: Option<FrameCallback>,
    /// A view in place of the scene's camera (the viewer's orbit, `--camera-from`).
    pub camera: Option<CameraDesc>,
    /// Fault injection, for the tests of what a failure leaves: a worker thread panics during
    /// this pass (counted from 0).
    pub panic_in_pass: Option<u64>,
    /// Bytes the integrator's buffers may take; None: the memory the system has available.
    pub memory_limit: Option<u64>,
}

/// The run an image came from: the integrator with its parameters as they stand (live
/// changes included), the seed, the scene file and the worker threads actually used.
#[derive(Clone, Debug, PartialEq)]
pub struct RunDescription {
    pub integrator: String,
    pub params: ParamValues,
    pub seed: u64,
    pub scene: std::path::PathBuf,
    /// What lit the scene from outside (`SceneInfo::lighting`), with its strength and
    /// rotation when it has them.
    pub environment: String,
    /// The view rendered.
    pub camera: CameraDesc,
    pub threads: usize,
}

pub type FrameCallback = Arc<dyn Fn() + Send + Sync>;

impl SessionConfig {
    /// `integrator` on `scene` at `width` x `height` with its default parameters, seed 0, a
    /// thread per core, no limit (it renders until cancelled), at normal priority and with no
    /// callback: callers change what they need with struct update syntax.
    pub fn new(scene: Arc<Scene>, integrator: &str, width: u32, height: u32) -> SessionConfig {
        SessionConfig {
            scene,
            integrator: integrator.to_string(),
            params: ParamValues::default(),
            width,
            height,
            seed: 0,
            threads: 0,
            max_passes: None,
            time_limit: None,
            target_rel_mse: None,
            background: false,
            on_frame: None,
            camera: None,
            panic_in_pass: None,
            memory_limit: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error("unknown integrator '{0}' (known: {1})")]
    UnknownIntegrator(String, String),
    #[error("{0}")]
    InvalidParameter(String),
    #[error("invalid resolution {0}x{1}: width and height must be 1 to {MAX_RESOLUTION}")]
    InvalidResolution(u32, u32),
    #[error("cannot start worker threads: {0}")]
    Threads(String),
    #[error(
        "{integrator} at {width} x {height} needs about {} for its buffers, more than the {} \
         {limit_is}: render a smaller image (--max-memory raises the limit)",
        gib(*needed),
        gib(*limit)
    )]
    TooLarge {
        integrator: &'static str,
        width: u32,
        height: u32,
        needed: u64,
        limit: u64,
        limit_is: &'static str,
    },
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1 << 30))
}

struct Shared {
    frame: ArcSwap<Frame>,
    cancel: AtomicBool,
    paused: Mutex<bool>,
    resume: Condvar,
    live_changes: Mutex<Vec<(String, f64)>>,
}

pub struct Session {
    shared: Arc<Shared>,
    worker: Option<JoinHandle<()>>,
    params: ParamValues,
    integrator: &'static integrators::IntegratorInfo,
    threads: usize,
    seed: u64,
    /// The scene's `SceneInfo::lighting`, for the image's header.
    environment: String,
    /// The view rendered (the scene's camera or the one given).
    camera: CameraDesc,
}

impl Session {
    /// Validates the configuration and starts rendering at once.
    pub fn start(config: SessionConfig) -> Result<Session, SessionError> {
        let info = integrators::find(&config.integrator).ok_or_else(|| {
            let known: Vec<_> = integrators::registry().iter().map(|i| i.name).collect();
            SessionError::UnknownIntegrator(config.integrator.clone(), known.join(", "))
        })?;
        let params = integrators::resolve_params(info, &config.params)
            .map_err(SessionError::InvalidParameter)?;
        let (w, h) = (config.width, config.height);
        if !(1..=MAX_RESOLUTION).contains(&w) || !(1..=MAX_RESOLUTION).contains(&h) {
            return Err(SessionError::InvalidResolution(w, h));
        }
        // Checked before anything is allocated: at 16384 x 16384 photon mapping's buffers
        // alone would take 180 GB, and an allocation that fails aborts the process.
        let limit = match config.memory_limit {
            Some(limit) => Some((limit, "allowed")),
            None => crate::process::available_memory().map(|m| (m, "available")),
        };
        let needed = info.memory_bytes(w, h);
        if let Some((limit, limit_is)) = limit
            && needed > limit
        {
            return Err(SessionError::TooLarge {
                integrator: info.name,
                width: w,
                height: h,
                needed,
                limit,
                limit_is,
            });
        }
        let threads = if config.threads == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            config.threads
        };
        let background = config.background;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("caustica-worker-{i}"))
            .start_handler(move |_| {
                if background {
                    // Best effort: an OS that refuses leaves the worker at normal priority.
                    let _ = thread_priority::set_current_thread_priority(
                        thread_priority::ThreadPriority::Min,
                    );
                }
            })
            .build()
            .map_err(|e| SessionError::Threads(e.to_string()))?;
        let camera = Camera::new(&config.camera.unwrap_or(config.scene.camera), w, h);
        let ctx = RenderContext {
            scene: config.scene.clone(),
            camera,
            seed: config.seed,
        };
        let shared = Arc::new(Shared {
            frame: ArcSwap::from_pointee(Frame {
                image: Arc::new(Image::new(w as usize, h as usize)),
                plots: Arc::new(Vec::new()),
                pixel_layers: Arc::new(Vec::new()),
                messages: Arc::new(Vec::new()),
                statistics: Arc::new(None),
                automatic: Arc::new(Vec::new()),
                integrator_memory_bytes: 0,
                error: Arc::new(None),
                passes: 0,
                samples: 0,
                rays: 0,
                dropped: 0,
                elapsed: Duration::ZERO,
                state: RunState::Running,
                preview: false,
                preparation: None,
                failure: None,
            }),
            cancel: AtomicBool::new(false),
            paused: Mutex::new(false),
            resume: Condvar::new(),
            live_changes: Mutex::new(Vec::new()),
        });
        let worker_shared = shared.clone();
        let worker_params = params.clone();
        let worker = std::thread::Builder::new()
            .name("caustica-session".into())
            .spawn(move || {
                let limits = Limits {
                    passes: config.max_passes,
                    time: config.time_limit,
                    rel_mse: config.target_rel_mse,
                };
                let on_frame = config.on_frame.clone();
                // A panic anywhere in the run (the integrator's buffers, a pass on any worker
                // thread, an estimate) ends this session with the image it had, and says why;
                // the pool and the integrator, in whatever state the panic left them, go.
                let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let integrator = (info.create)(ctx.clone(), &worker_params);
                    run(
                        worker_shared.clone(),
                        ctx,
                        integrator,
                        pool,
                        limits,
                        config.panic_in_pass,
                        on_frame,
                    )
                }));
                if let Err(payload) = outcome {
                    fail(&worker_shared, payload.as_ref(), config.on_frame.as_ref());
                }
            })
            .map_err(|e| SessionError::Threads(e.to_string()))?;
        Ok(Session {
            environment: config.scene.info.lighting.clone(),
            camera: *camera.desc(),
            shared,
            worker: Some(worker),
            params,
            integrator: info,
            threads,
            seed: config.seed,
        })
    }

    /// The newest frame; never blocks on the workers.
    pub fn frame(&self) -> Arc<Frame> {
        self.shared.frame.load_full()
    }

    pub fn params(&self) -> &ParamValues {
        &self.params
    }

    pub fn integrator(&self) -> &'static integrators::IntegratorInfo {
        self.integrator
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    /// What this session renders, for the header of an image of it (`metadata`): its
    /// parameters as they stand now, the worker threads it uses; `scene` names the file.
    pub fn run_description(&self, scene: &std::path::Path) -> RunDescription {
        RunDescription {
            integrator: self.integrator.name.to_string(),
            params: self.params.clone(),
            seed: self.seed,
            scene: scene.to_path_buf(),
            environment: self.environment.clone(),
            camera: self.camera,
            threads: self.threads,
        }
    }

    pub fn is_done(&self) -> bool {
        matches!(
            self.frame().state,
            RunState::Finished | RunState::Cancelled | RunState::Failed
        )
    }

    /// Asks the workers to stop; the pass under way is abandoned.
    pub fn cancel(&self) {
        self.shared.cancel.store(true, Ordering::Relaxed);
        self.set_paused(false);
    }

    pub fn set_paused(&self, paused: bool) {
        let mut p = self.shared.paused.lock().unwrap_or_else(|e| e.into_inner());
        *p = paused;
        self.shared.resume.notify_all();
    }

    /// Changes a parameter that is live for this integrator, from the next pass on.
    pub fn set_live_param(&mut self, name: &str, value: f64) -> Result<(), String> {
        integrators::check_live_change(self.integrator, name, value)?;
        self.params.insert(name.to_string(), value);
        self.shared
            .live_changes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((name.to_string(), value));
        Ok(())
    }

    /// Waits until the session has finished or was cancelled, and returns its last frame.
    pub fn wait(mut self) -> Arc<Frame> {
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
        self.frame()
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        self.cancel();
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

/// What a frame shows of the integrator's state, shared cheaply between frames.
#[derive(Clone)]
struct Estimate {
    image: Arc<Image>,
    plots: Arc<Vec<PlotSeries>>,
    pixel_layers: Arc<Vec<PixelLayer>>,
    messages: Arc<Vec<String>>,
    statistics: Arc<Option<serde_json::Value>>,
    automatic: Arc<Vec<(&'static str, f64)>>,
    memory_bytes: usize,
    error: Arc<Option<ErrorEstimate>>,
}

impl Estimate {
    /// The integrator's state; the error estimate anew only if `error` is None (else kept).
    fn of(integrator: &dyn Integrator, error: Option<Arc<Option<ErrorEstimate>>>) -> Estimate {
        Estimate::with_image(integrator, integrator.image(), error)
    }

    /// The same, with the integrator's `image` already taken.
    fn with_image(
        integrator: &dyn Integrator,
        image: Image,
        error: Option<Arc<Option<ErrorEstimate>>>,
    ) -> Estimate {
        Estimate {
            image: Arc::new(image),
            plots: Arc::new(integrator.plots()),
            pixel_layers: Arc::new(integrator.pixel_layers()),
            messages: Arc::new(integrator.messages()),
            statistics: Arc::new(integrator.statistics()),
            automatic: Arc::new(integrator.automatic()),
            memory_bytes: integrator.memory_bytes(),
            error: error.unwrap_or_else(|| Arc::new(integrator.error_estimate())),
        }
    }
}

/// The shortest time between two estimates renewed for their cost alone (see
/// `ErrorSchedule`).
const MIN_ESTIMATE_INTERVAL: Duration = Duration::from_millis(1000);

/// When to estimate the remaining error anew. The estimate reads every pixel's sums a few
/// times; on a small image whose passes take a millisecond it would slow the render down by
/// half. So it is renewed once it has cost at most a tenth of the time since the last one
/// and a second has passed (every pass where passes are slow; the second because the
/// renders stop for it: on the material spheres at 128 wide, amcppm's kernel-bias estimate
/// took 5.3 % of a 10 s render's samples under `perf` with a tenth alone, 2.5 % with the
/// second), or once the passes have grown by a tenth since (the
/// error falls about like 1 / passes, so the estimate is never more than a tenth stale, and
/// `--until-error` stops within a tenth of the passes it needed, however a busy machine
/// stretched one estimate's cost: that costs O(log passes) estimates), and always for the
/// last frame of a run.
struct ErrorSchedule {
    last: Option<(Instant, u64)>,
    cost: Duration,
}

impl ErrorSchedule {
    fn due(&self, passes: u64) -> bool {
        self.last.is_none_or(|(t, at)| {
            t.elapsed() >= self.cost.saturating_mul(10).max(MIN_ESTIMATE_INTERVAL)
                || passes >= at + at.div_ceil(10)
        })
    }

    /// The estimate for the state after `passes` passes: a new one when due or `last_frame`.
    fn estimate(
        &mut self,
        integrator: &dyn Integrator,
        previous: &Estimate,
        passes: u64,
        last_frame: bool,
    ) -> Estimate {
        if !(last_frame || self.due(passes)) {
            return Estimate::of(integrator, Some(previous.error.clone()));
        }
        let started = Instant::now();
        let error = Arc::new(integrator.error_estimate());
        self.cost = started.elapsed();
        self.last = Some((Instant::now(), passes));
        Estimate::of(integrator, Some(error))
    }
}

/// Whether a preparation's image, after `samples` samples, is too sparse to replace the
/// preview: less than a sample per pixel, or less than a twentieth of the pixels lit.
fn too_sparse(image: &Image, samples: u64) -> bool {
    let pixels = image.pixels.len() as u64;
    let lit = image
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count() as u64;
    samples < pixels || lit * 20 < pixels
}

/// When a session stops by itself.
struct Limits {
    passes: Option<u64>,
    time: Option<Duration>,
    rel_mse: Option<f64>,
}

impl Limits {
    fn reached(&self, passes: u64, elapsed: Duration, estimate: &Estimate) -> bool {
        self.passes.is_some_and(|m| passes >= m)
            || self.time.is_some_and(|t| elapsed >= t)
            || self.rel_mse.is_some_and(|target| {
                estimate
                    .error
                    .as_ref()
                    .as_ref()
                    .is_some_and(|e| e.rel_mse < target)
            })
    }
}

/// Publishes the last frame of a session whose run panicked with `payload`: the image of the
/// passes before, the state `Failed` and the panic's message.
fn fail(shared: &Shared, payload: &(dyn std::any::Any + Send), on_frame: Option<&FrameCallback>) {
    let message = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into());
    let last = shared.frame.load_full();
    let passes = last.passes;
    shared.frame.store(Arc::new(Frame {
        state: RunState::Failed,
        failure: Some(format!("the renderer failed after {passes} passes: {message}").into()),
        ..(*last).clone()
    }));
    if let Some(notify) = on_frame {
        notify();
    }
}

fn run(
    shared: Arc<Shared>,
    ctx: RenderContext,
    mut integrator: Box<dyn Integrator>,
    pool: rayon::ThreadPool,
    limits: Limits,
    panic_in_pass: Option<u64>,
    on_frame: Option<FrameCallback>,
) {
    let start = Instant::now();
    let mut paused_for = Duration::ZERO;
    let mut totals = PassStats::default();
    let mut passes = 0u64;
    // Every frame goes out the same way: stored for the UI, which is told.
    let show = |frame: Frame| {
        shared.frame.store(Arc::new(frame));
        if let Some(notify) = &on_frame {
            notify();
        }
    };
    let publish = |estimate: &Estimate,
                   passes: u64,
                   totals: PassStats,
                   elapsed: Duration,
                   state: RunState,
                   preparation: Option<f32>| {
        show(Frame {
            image: estimate.image.clone(),
            plots: estimate.plots.clone(),
            pixel_layers: estimate.pixel_layers.clone(),
            messages: estimate.messages.clone(),
            statistics: estimate.statistics.clone(),
            automatic: estimate.automatic.clone(),
            integrator_memory_bytes: estimate.memory_bytes,
            error: estimate.error.clone(),
            passes,
            samples: totals.samples,
            rays: totals.rays,
            dropped: totals.dropped,
            elapsed,
            state,
            preview: false,
            preparation,
            failure: None,
        });
    };
    // Something of the scene at once, however long the first pass takes.
    let preview = pool.install(|| preview::render(&ctx, &shared.cancel)).ok();
    let previewed = preview.is_some();
    if let Some(image) = preview {
        let first = shared.frame.load_full();
        show(Frame {
            image: Arc::new(image),
            elapsed: start.elapsed(),
            preview: true,
            ..(*first).clone()
        });
    }
    let mut estimate = Estimate::of(integrator.as_ref(), None);
    let mut schedule = ErrorSchedule {
        last: None,
        cost: Duration::ZERO,
    };
    loop {
        let elapsed = start.elapsed() - paused_for;
        if shared.cancel.load(Ordering::Relaxed) {
            publish(
                &estimate,
                passes,
                totals,
                elapsed,
                RunState::Cancelled,
                None,
            );
            return;
        }
        if limits.reached(passes, elapsed, &estimate) {
            publish(&estimate, passes, totals, elapsed, RunState::Finished, None);
            return;
        }
        {
            let mut paused = shared.paused.lock().unwrap_or_else(|e| e.into_inner());
            if *paused {
                let pause_start = Instant::now();
                publish(&estimate, passes, totals, elapsed, RunState::Paused, None);
                while *paused && !shared.cancel.load(Ordering::Relaxed) {
                    paused = shared
                        .resume
                        .wait(paused)
                        .unwrap_or_else(|e| e.into_inner());
                }
                paused_for += pause_start.elapsed();
                continue;
            }
        }
        let changes = std::mem::take(
            &mut *shared
                .live_changes
                .lock()
                .unwrap_or_else(|e| e.into_inner()),
        );
        for (name, value) in changes {
            integrator.set_live_param(&name, value);
        }
        let preparing = integrator.preparing().is_some();
        let pass = || {
            if panic_in_pass == Some(passes) {
                rayon::scope(|s| s.spawn(|_| panic!("fault injected in pass {passes}")));
            }
            integrator.render_pass(passes, &shared.cancel)
        };
        match pool.install(pass) {
            // A preparation step: shown, counted in the totals, but not a pass.
            Ok(stats) if preparing => {
                totals = totals + stats;
                let elapsed = start.elapsed() - paused_for;
                let progress = integrator.preparing();
                // The preparation's own image replaces the preview once it holds a sample per
                // pixel and lights a twentieth of them, as the preview's path tracer must
                // (before, it is sparser than the preview: a room lit through a slit stays
                // black for long), and stays up from the end of the preparation to the end
                // of the first pass.
                let image = progress
                    .map(|_| integrator.image())
                    .filter(|image| !previewed || !too_sparse(image, totals.samples));
                let Some(image) = image else {
                    let shown = shared.frame.load_full();
                    show(Frame {
                        preparation: progress,
                        samples: totals.samples,
                        rays: totals.rays,
                        elapsed,
                        ..(*shown).clone()
                    });
                    continue;
                };
                estimate = Estimate::with_image(integrator.as_ref(), image, Some(Arc::new(None)));
                publish(
                    &estimate,
                    passes,
                    totals,
                    elapsed,
                    RunState::Running,
                    progress,
                );
            }
            Ok(stats) => {
                passes += 1;
                totals = totals + stats;
                let elapsed = start.elapsed() - paused_for;
                let last_frame = limits.passes.is_some_and(|m| passes >= m)
                    || limits.time.is_some_and(|t| elapsed >= t);
                // On the session's pool, so that an estimate that uses rayon uses its threads.
                // (A mutable borrow: the integrator is Send but not Sync.)
                let (renderer, previous, due) = (&mut integrator, &estimate, &mut schedule);
                estimate = pool
                    .install(move || due.estimate(renderer.as_ref(), previous, passes, last_frame));
                publish(
                    &estimate,
                    passes,
                    totals,
                    start.elapsed() - paused_for,
                    RunState::Running,
                    None,
                );
            }
            Err(integrators::Cancelled) => continue,
        }
    }
}
