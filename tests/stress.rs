//! The viewer's controller driven as a restless user drives it: a thousand integrator,
//! parameter, size and environment changes and scene opens in quick succession, without a
//! window. No thread may be left behind, nothing may deadlock, the heap may not grow. In its own
//! test binary, so that the threads and the memory counted are this test's alone.

use caustica::viewer::controller::RenderController;
use caustica::viewer::settings::ViewerSettings;
use caustica_renderer::integrators::registry;
use caustica_renderer::process::thread_count;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The system allocator, counting the bytes live on the heap. A leak is heap that stays
/// live; resident memory also holds what the allocator's arenas keep cached after frees,
/// which rose by 16 to 58 MiB over the same 900 changes from run to run, in steps, not
/// in proportion to the changes.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is passed to the system allocator unchanged; only a counter is added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn live_heap_bytes() -> u64 {
    LIVE.load(Ordering::Relaxed) as u64
}

const CHANGES: usize = 1000;
const WARM_UP: usize = 100;

/// Waits (up to 30 s) for the threads to fall back to `count`: dropped sessions wind down,
/// and loads and surveys finish, on threads of their own.
fn settle_threads(count: usize) -> usize {
    let start = Instant::now();
    while thread_count().unwrap() > count && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(20));
    }
    thread_count().unwrap()
}

fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

/// Polls until no load is under way.
fn loaded(c: &mut RenderController, settings: &ViewerSettings) {
    let start = Instant::now();
    while c.loading().is_some() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the load never ended"
        );
        c.poll(settings);
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// (changes a second, live heap after the warm-up, live heap at the end, threads before, after)
fn churn() -> (f64, u64, u64, usize, usize) {
    let threads_before = thread_count().unwrap();
    let mut settings = ViewerSettings {
        width: 64,
        height: 48,
        threads: 2,
        ..Default::default()
    };
    let mut c = RenderController::new(Arc::new(|| {}));
    c.open_scene(asset("cornell-box.gltf"), &settings);
    loaded(&mut c, &settings);
    let scenes = ["cornell-box.gltf", "cornell-glass.gltf", "door.gltf"];
    let environments = ["auto", "uniform", "studio", "none"];
    let mut resident_after_warm_up = 0;
    let start = Instant::now();
    for i in 0..CHANGES {
        if i == WARM_UP {
            loaded(&mut c, &settings);
            resident_after_warm_up = live_heap_bytes();
        }
        match i % 10 {
            // Another integrator, with its defaults.
            0..=3 => {
                let info = &registry()[(i / 10 + i) % registry().len()];
                settings.integrator = info.name.to_string();
                settings.params = ViewerSettings::defaults_of(info.name);
                c.restart(&settings).unwrap();
            }
            // A parameter, live or restarting, between its minimum and its default.
            4..=6 => {
                let info = registry()
                    .iter()
                    .find(|r| r.name == settings.integrator)
                    .unwrap();
                let spec = &info.params[i % info.params.len()];
                let t = (i % 7) as f64 / 6.0;
                let value = spec.min + t * (spec.default.max(spec.min) - spec.min);
                let value = if spec.integer { value.round() } else { value };
                settings.params.insert(spec.name.to_string(), value);
                c.set_param(&settings, spec.name, value).unwrap();
            }
            // Another image size.
            7 => {
                (settings.width, settings.height) = if i % 20 == 7 { (48, 64) } else { (64, 48) };
                c.restart(&settings).unwrap();
            }
            // Another environment, relit while the next change comes.
            8 => {
                settings.environment = environments[(i / 10) % environments.len()].into();
                c.relight(&settings);
            }
            // Another scene, opened while the last one may still be loading.
            _ => c.open_scene(asset(scenes[(i / 10) % scenes.len()]), &settings),
        }
        c.poll(&settings);
    }
    loaded(&mut c, &settings);
    let per_second = CHANGES as f64 / start.elapsed().as_secs_f64();
    let resident_at_end = live_heap_bytes();
    drop(c);
    (
        per_second,
        resident_after_warm_up,
        resident_at_end,
        threads_before,
        settle_threads(threads_before),
    )
}

#[test]
fn a_thousand_changes_through_the_controller_leave_nothing_behind() {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(churn()).unwrap());
    // Bounded: a deadlock fails the test instead of hanging it.
    let (per_second, warm, end, before, after) = rx
        .recv_timeout(Duration::from_secs(600))
        .expect("the controller deadlocked: 1000 changes did not finish in 10 minutes");
    eprintln!(
        "{CHANGES} changes, {per_second:.0} a second; live heap {:.1} MiB after {WARM_UP}, \
         {:.1} MiB at the end; threads {before} before, {after} after",
        warm as f64 / 1048576.0,
        end as f64 / 1048576.0,
    );
    assert_eq!(after, before, "threads left behind");
    // A scene, its BVH and a session's buffers are each over 1 MiB: a leak of any of them
    // over 900 changes is far above 48 MiB.
    let growth = end as f64 - warm as f64;
    assert!(
        growth < 48.0 * 1048576.0,
        "live heap grew by {:.1} MiB",
        growth / 1048576.0
    );
}
