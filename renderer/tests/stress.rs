//! Thousands of sessions started, changed and dropped in quick succession, as a user who drags
//! every slider does: no thread is left behind, nothing deadlocks, memory does not grow. In its
//! own test binary, so that the threads and the memory counted are this test's alone.

use caustica_renderer::integrators::registry;
use caustica_renderer::procedural::cornell_box;
use caustica_renderer::process::{resident_bytes, thread_count};
use caustica_renderer::scene::{Scene, gltf};
use caustica_renderer::session::{Session, SessionConfig};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

const RESTARTS: usize = 2000;
const WARM_UP: usize = 200;

/// Waits (up to 10 s) for the process's threads to fall back to `count`: a dropped session's
/// worker pool winds down after the drop returns.
fn settle_threads(count: usize) -> usize {
    let start = Instant::now();
    while thread_count().unwrap() > count && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(10));
    }
    thread_count().unwrap()
}

/// A small xorshift generator: the sequence of actions is the same every run.
struct Choices(u64);

impl Choices {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

struct Figures {
    restarts_per_second: f64,
    resident_after_warm_up: u64,
    resident_at_end: u64,
    threads_before: usize,
    threads_after: usize,
}

fn churn() -> Figures {
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell-box.gltf");
    let built = Arc::new(Scene::build(cornell_box(true)).unwrap());
    let threads_before = thread_count().unwrap();
    let mut rng = Choices(0x9e37_79b9_7f4a_7c15);
    let mut kept: Option<Session> = None;
    let mut scene = built.clone();
    let mut resident_after_warm_up = 0;
    let start = Instant::now();
    for i in 0..RESTARTS {
        if i == WARM_UP {
            drop(kept.take());
            settle_threads(threads_before);
            resident_after_warm_up = resident_bytes().unwrap();
        }
        // A scene load every 20 restarts, from the file or built anew.
        if i % 20 == 0 {
            scene = if i % 40 == 0 {
                Arc::new(gltf::load(&asset).unwrap())
            } else {
                built.clone()
            };
        }
        let info = &registry()[rng.below(registry().len())];
        let mut config = SessionConfig {
            seed: i as u64,
            threads: 2,
            ..SessionConfig::new(scene.clone(), info.name, 64, 48)
        };
        // A parameter away from its default, between its minimum and its default (the
        // cheap side: more photons or chains would only make each start slower).
        let spec = &info.params[rng.below(info.params.len())];
        let value = rng.uniform(spec.min, spec.default.max(spec.min));
        let value = if spec.integer { value.round() } else { value };
        config.params.insert(spec.name.to_string(), value);
        let mut session = Session::start(config).unwrap();
        match rng.below(5) {
            // Dropped at once.
            0 => {}
            // Dropped after its first frame.
            1 => {
                let shown = Instant::now();
                while session.frame().passes == 0
                    && !session.frame().preview
                    && shown.elapsed() < Duration::from_secs(2)
                {
                    std::thread::sleep(Duration::from_micros(200));
                }
            }
            // A live parameter changed while it runs.
            2 => {
                if let Some(live) = info.params.iter().find(|p| p.live) {
                    let v = rng.uniform(live.min, live.default.max(live.min));
                    let v = if live.integer { v.round() } else { v };
                    session.set_live_param(live.name, v).unwrap();
                }
            }
            // Paused and resumed.
            3 => {
                session.set_paused(true);
                session.set_paused(false);
            }
            // Kept running while the next one starts (the viewer drops the old session only
            // once the new one has started).
            _ => {
                kept = Some(session);
                continue;
            }
        }
        drop(kept.take());
        drop(session);
    }
    drop(kept);
    let restarts_per_second = RESTARTS as f64 / start.elapsed().as_secs_f64();
    let threads_after = settle_threads(threads_before);
    Figures {
        restarts_per_second,
        resident_after_warm_up,
        resident_at_end: resident_bytes().unwrap(),
        threads_before,
        threads_after,
    }
}

#[test]
fn thousands_of_restarts_leave_no_thread_deadlock_or_memory_behind() {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(churn()).unwrap());
    // Bounded: a deadlock fails the test instead of hanging it (the churn takes under a
    // minute; a tenth of this bound).
    let f = rx
        .recv_timeout(Duration::from_secs(600))
        .expect("the sessions deadlocked: 2000 restarts did not finish in 10 minutes");
    eprintln!(
        "{RESTARTS} restarts, {:.0} a second; resident {:.1} MiB after {WARM_UP}, {:.1} MiB \
         at the end; threads {} before, {} after",
        f.restarts_per_second,
        f.resident_after_warm_up as f64 / 1048576.0,
        f.resident_at_end as f64 / 1048576.0,
        f.threads_before,
        f.threads_after
    );
    assert_eq!(f.threads_after, f.threads_before, "threads left behind");
    // Each session holds about 0.5 MiB of buffers at 64 x 48 (film, hit points, splats): a
    // leak of any of them over 1800 sessions is far above 32 MiB.
    let growth = f.resident_at_end as f64 - f.resident_after_warm_up as f64;
    assert!(
        growth < 32.0 * 1048576.0,
        "resident memory grew by {:.1} MiB",
        growth / 1048576.0
    );
}
