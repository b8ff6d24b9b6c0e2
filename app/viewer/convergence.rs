//! Error against a reference as the render converges, measured on a background thread with
//! the one metric implementation of the renderer (DESIGN.md section 3). The UI sends each new
//! frame; the thread drops all but the newest, so it never falls behind and the UI never waits.
//! Beside it, with or without a reference, the error each frame estimates of itself
//! (`Frame::error`), recorded on the UI thread since it costs nothing to read. The thread also
//! gives each measured frame's true error per pixel (`rel_mse_terms`), which the error map
//! shows while a reference is loaded, and the reference itself, which the view can flip to.

use caustica_renderer::image::{ErrorMetrics, Image, compare, read_exr, rel_mse_terms};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvergencePoint {
    pub seconds: f64,
    pub metrics: ErrorMetrics,
}

enum Job {
    LoadReference(PathBuf),
    Measure {
        image: Arc<Image>,
        seconds: f64,
        run: u64,
    },
}

/// A frame's true error per pixel against the reference, row-major.
#[derive(Debug)]
pub struct TrueError {
    pub width: usize,
    pub height: usize,
    pub terms: Vec<f32>,
}

enum Reply {
    ReferenceLoaded(PathBuf, Arc<Image>),
    Failed(String),
    Point(u64, ConvergencePoint, Arc<TrueError>),
}

pub struct Convergence {
    jobs: Sender<Job>,
    replies: Receiver<Reply>,
    pub reference: Option<PathBuf>,
    pub reference_image: Option<Arc<Image>>,
    /// The newest measured frame's error per pixel.
    pub true_error: Option<Arc<TrueError>>,
    pub points: Vec<ConvergencePoint>,
    /// (seconds, estimated relMSE) of the frames seen, thinned to at most about 230 points a
    /// decade of time so that hours of rendering stay a short list.
    pub estimated: Vec<[f64; 2]>,
    /// Set when the reference could not be loaded or does not match the render.
    pub problem: Option<String>,
    run: u64,
    last_sent: Option<Arc<Image>>,
}

fn worker(jobs: Receiver<Job>, replies: Sender<Reply>, notify: Arc<dyn Fn() + Send + Sync>) {
    let mut reference: Option<Arc<Image>> = None;
    while let Ok(mut job) = jobs.recv() {
        // Newest wins: skip measurements that a later one has made stale.
        loop {
            match jobs.try_recv() {
                Ok(next @ Job::Measure { .. }) if matches!(job, Job::Measure { .. }) => job = next,
                Ok(next) => {
                    if handle(job, &mut reference, &replies) {
                        notify();
                    }
                    job = next;
                }
                Err(_) => break,
            }
        }
        // The UI redraws only for a reply: without a reference, frames come and go unmeasured.
        if handle(job, &mut reference, &replies) {
            notify();
        }
    }
}

/// Does the job; whether it replied.
fn handle(job: Job, reference: &mut Option<Arc<Image>>, replies: &Sender<Reply>) -> bool {
    let reply = match job {
        Job::LoadReference(path) => match read_exr(&path) {
            Ok((image, _)) => {
                let image = Arc::new(image);
                *reference = Some(image.clone());
                Reply::ReferenceLoaded(path, image)
            }
            Err(e) => Reply::Failed(format!("reference: {e}")),
        },
        Job::Measure {
            image,
            seconds,
            run,
        } => match reference
            .as_ref()
            .map(|r| compare(&image, r).and_then(|m| Ok((m, rel_mse_terms(&image, r)?))))
        {
            None => return false,
            Some(Ok((metrics, terms))) => {
                let error = TrueError {
                    width: image.width,
                    height: image.height,
                    terms,
                };
                Reply::Point(run, ConvergencePoint { seconds, metrics }, Arc::new(error))
            }
            Some(Err(e)) => Reply::Failed(format!("reference: {e}")),
        },
    };
    replies.send(reply).is_ok()
}

impl Convergence {
    pub fn new(notify: Arc<dyn Fn() + Send + Sync>) -> Self {
        let (jobs, job_rx) = channel();
        let (reply_tx, replies) = channel();
        std::thread::Builder::new()
            .name("caustica-convergence".into())
            .spawn(move || worker(job_rx, reply_tx, notify))
            .expect("a thread for the convergence plot");
        Convergence {
            jobs,
            replies,
            reference: None,
            reference_image: None,
            true_error: None,
            points: Vec::new(),
            estimated: Vec::new(),
            problem: None,
            run: 0,
            last_sent: None,
        }
    }

    pub fn load_reference(&mut self, path: PathBuf) {
        self.points.clear();
        self.problem = None;
        let _ = self.jobs.send(Job::LoadReference(path));
    }

    /// A new render started: its error curve starts afresh.
    pub fn reset(&mut self) {
        self.run += 1;
        self.points.clear();
        self.estimated.clear();
        self.true_error = None;
        self.last_sent = None;
    }

    /// Records a frame's own error estimate.
    pub fn record_estimate(&mut self, seconds: f64, rel_mse: f64) {
        if !(seconds > 0.0 && rel_mse > 0.0 && rel_mse.is_finite()) {
            return;
        }
        match self.estimated.last_mut() {
            // Within 1 % of the last point's time: the newer value replaces it.
            Some(last) if seconds < last[0] * 1.01 => *last = [last[0], rel_mse],
            _ => self.estimated.push([seconds, rel_mse]),
        }
    }

    /// Offers the current frame; only new frames are measured.
    pub fn offer(&mut self, image: &Arc<Image>, seconds: f64) {
        if self.reference.is_none()
            || self
                .last_sent
                .as_ref()
                .is_some_and(|l| Arc::ptr_eq(l, image))
        {
            return;
        }
        self.last_sent = Some(image.clone());
        let _ = self.jobs.send(Job::Measure {
            image: image.clone(),
            seconds,
            run: self.run,
        });
    }

    /// Collects the thread's replies.
    pub fn poll(&mut self) {
        loop {
            match self.replies.try_recv() {
                Ok(Reply::ReferenceLoaded(path, image)) => {
                    self.reference = Some(path);
                    self.reference_image = Some(image);
                    self.last_sent = None;
                }
                Ok(Reply::Failed(e)) => self.problem = Some(e),
                Ok(Reply::Point(run, p, error)) if run == self.run && p.seconds > 0.0 => {
                    self.problem = None;
                    self.points.push(p);
                    self.true_error = Some(error);
                }
                Ok(Reply::Point(..)) => {}
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => break,
            }
        }
    }
}
