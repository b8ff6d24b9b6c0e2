//! Worker priority: a background session's workers run below normal priority. In a file of
//! its own, so that no other test's workers run in the process while it counts them.

use caustica_renderer::procedural::cornell_box;
use caustica_renderer::scene::Scene;
use caustica_renderer::session::{Session, SessionConfig};
use std::sync::Arc;
use std::time::Duration;

fn config(background: bool) -> SessionConfig {
    let scene = Arc::new(Scene::build(cornell_box(false)).unwrap());
    SessionConfig {
        seed: 1,
        threads: 2,
        background,
        ..SessionConfig::new(scene, "pt", 32, 32)
    }
}

/// A background session's workers run at the lowest priority (nice 19 on Linux), so that a UI
/// on the same cores goes first; others at the priority they were started with.
#[cfg(target_os = "linux")]
#[test]
fn background_workers_run_below_normal_priority() {
    let nice_of_workers = || -> Vec<i64> {
        std::fs::read_dir("/proc/self/task")
            .unwrap()
            .filter_map(|t| {
                let dir = t.ok()?.path();
                let comm = std::fs::read_to_string(dir.join("comm")).ok()?;
                let stat = std::fs::read_to_string(dir.join("stat")).ok()?;
                // Fields after the parenthesised name; nice is the 19th field of the line.
                let rest = &stat[stat.rfind(')')? + 2..];
                let nice = rest.split_whitespace().nth(16)?.parse().ok()?;
                comm.starts_with("caustica-worker").then_some(nice)
            })
            .collect()
    };
    for background in [true, false] {
        let session = Session::start(config(background)).unwrap();
        while session.frame().passes < 1 {
            std::thread::sleep(Duration::from_millis(5));
        }
        let nice = nice_of_workers();
        drop(session);
        // A dropped pool's threads end soon after, not at once.
        for _ in 0..1000 {
            if nice_of_workers().is_empty() {
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(nice.len(), 2, "two workers: {nice:?}");
        let expected = if background { 19 } else { 0 };
        assert!(
            nice.iter().all(|&n| n == expected),
            "background {background}: {nice:?}"
        );
    }
}
