//! Progressive sessions: frames while rendering, pause and resume, cancellation, parameters,
//! and the bundled assets being exactly what their generator writes.

use caustica_renderer::procedural::{bundled_assets, cornell_box};
use caustica_renderer::scene::Scene;
use caustica_renderer::session::{RunState, Session, SessionConfig, SessionError};
use std::sync::Arc;
use std::time::Duration;

fn config(passes: Option<u64>) -> SessionConfig {
    let scene = Arc::new(Scene::build(cornell_box(true)).unwrap());
    SessionConfig {
        seed: 1,
        threads: 2,
        max_passes: passes,
        ..SessionConfig::new(scene, "pt", 64, 64)
    }
}

fn wait_for(session: &Session, what: impl Fn(&caustica_renderer::session::Frame) -> bool) {
    for _ in 0..2000 {
        if what(&session.frame()) {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("the session never reached the expected state");
}

#[test]
fn frames_arrive_while_rendering_and_cancel_stops_the_session() {
    let session = Session::start(config(None)).unwrap();
    wait_for(&session, |f| f.passes >= 3);
    let frame = session.frame();
    assert_eq!(frame.samples, frame.passes * 64 * 64);
    assert!(frame.rays >= frame.samples && frame.image.mean_luminance() > 0.0);
    session.cancel();
    let last = session.wait();
    assert_eq!(last.state, RunState::Cancelled);
    assert!(last.passes >= frame.passes);
}

#[test]
fn pause_holds_the_pass_count_and_resume_continues() {
    let session = Session::start(config(None)).unwrap();
    wait_for(&session, |f| f.passes >= 1);
    session.set_paused(true);
    wait_for(&session, |f| f.state == RunState::Paused);
    let held = session.frame().passes;
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(session.frame().passes, held, "a paused session rendered");
    session.set_paused(false);
    wait_for(&session, |f| {
        f.passes > held && f.state == RunState::Running
    });
}

#[test]
fn a_pass_limit_finishes_with_exactly_that_many_passes() {
    let frame = Session::start(config(Some(5))).unwrap().wait();
    assert_eq!((frame.passes, frame.state), (5, RunState::Finished));
}

#[test]
fn bad_configurations_are_refused_before_any_thread_starts() {
    let mut c = config(Some(1));
    c.integrator = "nope".into();
    assert!(matches!(
        Session::start(c),
        Err(SessionError::UnknownIntegrator(..))
    ));
    let mut c = config(Some(1));
    c.params.insert("max_depth".into(), -3.0);
    assert!(matches!(
        Session::start(c),
        Err(SessionError::InvalidParameter(_))
    ));
    let mut c = config(Some(1));
    c.width = 0;
    assert!(matches!(
        Session::start(c),
        Err(SessionError::InvalidResolution(0, 64))
    ));
}

#[test]
fn only_live_parameters_in_range_change_a_running_session() {
    let mut session = Session::start(config(Some(1))).unwrap();
    let e = session.set_live_param("max_depth", 3.0).unwrap_err();
    assert!(e.contains("restart"), "{e}");
    assert!(session.set_live_param("no_such_thing", 1.0).is_err());

    // A live parameter out of its range is refused, and nothing changes.
    let mut c = config(Some(1));
    c.integrator = "sppm".into();
    let mut session = Session::start(c).unwrap();
    for bad in [0.0, 1.5, f64::NAN] {
        let e = session.set_live_param("alpha", bad).unwrap_err();
        assert!(e.contains("alpha"), "{e}");
    }
    assert_eq!(session.params()["alpha"], 2.0 / 3.0);
    session.set_live_param("alpha", 0.5).unwrap();
    assert_eq!(session.params()["alpha"], 0.5);
}

#[test]
fn bundled_assets_are_regenerable() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
    for (name, text) in bundled_assets() {
        let committed = std::fs::read_to_string(dir.join(name)).unwrap_or_default();
        assert!(
            committed == text,
            "assets/{name} differs from its generator: run `cargo run -p caustica-renderer --example make_assets -- assets`"
        );
    }
}

#[test]
fn the_scene_is_shared_safely_between_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Scene>();
    assert_send_sync::<caustica_renderer::session::Frame>();
    // Many threads querying one scene at once see the same answers as one thread.
    let scene = Arc::new(Scene::build(cornell_box(true)).unwrap());
    let camera = caustica_renderer::camera::Camera::new(&scene.camera, 64, 64);
    let trace = move |scene: &Scene| -> Vec<Option<(u32, u32)>> {
        (0..64 * 64)
            .map(|i| {
                let r = camera.generate_ray(glam::Vec2::new(
                    (i % 64) as f32 + 0.5,
                    (i / 64) as f32 + 0.5,
                ));
                scene.intersect(&r).map(|s| (s.triangle, s.t.to_bits()))
            })
            .collect()
    };
    let reference = trace(&scene);
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let scene = scene.clone();
            std::thread::spawn(move || trace(&scene))
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), reference);
    }
}

/// The header every saved image carries comes from the session itself: the integrator, its
/// parameters as they stand after a live change, the seed, the worker threads it resolved
/// (not the 0 that asked for one per core) and the frame's counters.
#[test]
fn run_metadata_describes_the_session_as_it_stands() {
    use caustica_renderer::metadata::exr_metadata;
    let mut c = config(Some(2));
    (c.integrator, c.threads, c.seed) = ("sppm".into(), 0, 42);
    c.params.insert("photons".into(), 1000.0);
    let mut session = Session::start(c).unwrap();
    session.set_live_param("alpha", 0.5).unwrap();
    let run = session.run_description(std::path::Path::new("box.gltf"));
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert_eq!((run.threads, run.seed), (cores, 42));
    let frame = session.wait();
    let m = exr_metadata(&run, &frame);
    let params: serde_json::Value = serde_json::from_str(&m["parameters"]).unwrap();
    assert_eq!(
        (params["alpha"].as_f64(), params["photons"].as_f64()),
        (Some(0.5), Some(1000.0))
    );
    let expected = [
        ("integrator", "sppm".to_string()),
        ("seed", "42".to_string()),
        ("scene", "box.gltf".to_string()),
        ("threads", cores.to_string()),
        ("passes", frame.passes.to_string()),
        ("samples", frame.samples.to_string()),
        ("rays", frame.rays.to_string()),
        ("dropped_samples", frame.dropped.to_string()),
    ];
    for (key, value) in expected {
        assert_eq!(m[key], value, "{key}");
    }
    assert!(m["elapsed_seconds"].parse::<f64>().unwrap() > 0.0);
    assert!(
        m["estimated_relmse"].parse::<f64>().unwrap() > 0.0,
        "two passes estimate their error"
    );
}

/// Before the first pass ends, the session shows a coarse preview of the scene, marked as
/// such and counting no pass: the door, lit only through a slit, shows its geometry (short
/// paths find no light there); the Cornell box its lit image. The first pass replaces it.
/// (BDPT at 256 x 256, whose first pass takes far longer than the preview.)
#[test]
fn a_preview_of_the_scene_comes_before_the_first_pass() {
    use caustica_renderer::procedural::door;
    for desc in [door(), cornell_box(false)] {
        let mut c = config(Some(1));
        c.scene = Arc::new(Scene::build(desc).unwrap());
        (c.integrator, c.width, c.height) = ("bdpt".into(), 256, 256);
        c.params.insert("max_depth".into(), 5.0);
        let session = Session::start(c).unwrap();
        wait_for(&session, |f| f.preview || f.passes > 0);
        let preview = session.frame();
        assert!(preview.preview, "the first frame is the preview");
        assert_eq!((preview.passes, preview.samples), (0, 0));
        let lit = preview
            .image
            .pixels
            .iter()
            .filter(|p| p.max_element() > 0.0)
            .count();
        assert!(
            lit * 2 > preview.image.pixels.len(),
            "the preview shows the scene"
        );
        let last = session.wait();
        assert!(!last.preview && last.passes == 1);
    }
}

/// MMLT's bootstrap runs in preparation steps before the first pass, and its samples' own
/// image is shown meanwhile, counting samples but no pass: an unbiased image, as bright as
/// the chains' image that follows (measured: within 5 %; a wrong scale of the bootstrap image,
/// pixels over samples, would be off by a factor).
#[test]
fn mmlt_shows_its_bootstrap_before_the_first_pass() {
    let mut c = config(Some(1));
    c.integrator = "mmlt".into();
    c.params.insert("max_depth".into(), 5.0);
    c.params.insert("bootstrap".into(), 20_000.0);
    let session = Session::start(c).unwrap();
    wait_for(&session, |f| {
        (f.preparation.is_some() && !f.preview) || f.passes > 0
    });
    let boot = session.frame();
    assert_eq!(
        boot.passes, 0,
        "the bootstrap is shown before the first pass"
    );
    let done = boot.preparation.unwrap();
    assert!(done > 0.0 && done < 1.0, "{done}");
    assert!(boot.samples > 0 && boot.error.is_none());
    let last = session.wait();
    assert_eq!(last.passes, 1);
    let (b, m) = (boot.image.mean_luminance(), last.image.mean_luminance());
    eprintln!("mean luminance: bootstrap image {b:.4}, chains' image {m:.4}");
    assert!(
        (b / m - 1.0).abs() < 0.15,
        "bootstrap image {b}, chains' image {m}"
    );
}

/// Every integrator counts its own buffers: the path tracer and BDPT exactly their film (sum,
/// sum of squares and odd passes' sum, in doubles) and one pass's buffer; the others at least
/// that much per pixel (photon mappers: per-pixel statistics, hit points and grid; MMLT: its
/// path-traced film and the chains' splat images) and, on 64 x 64 pixels, far below 100 MB.
#[test]
fn every_integrator_reports_the_memory_of_its_buffers() {
    use caustica_renderer::integrators::registry::registry;
    let pixels = 64 * 64;
    let film = pixels * 3 * std::mem::size_of::<glam::DVec3>();
    let pass_buffer = pixels * std::mem::size_of::<glam::Vec3>();
    for info in registry() {
        let frame = Session::start(SessionConfig {
            integrator: info.name.into(),
            ..config(Some(2))
        })
        .unwrap()
        .wait();
        let bytes = frame.integrator_memory_bytes;
        // The estimate a session checks before it starts bounds what the buffers take, and
        // is not far above it (a factor 2 per pixel).
        assert!(
            bytes as u64 <= info.memory_bytes(64, 64),
            "{}: {bytes}",
            info.name
        );
        let large = Session::start(SessionConfig {
            integrator: info.name.into(),
            ..SessionConfig::new(config(None).scene, info.name, 256, 256)
        })
        .unwrap();
        wait_for(&large, |f| f.passes >= 1);
        let per_pixel = large.frame().integrator_memory_bytes as f64 / (256.0 * 256.0);
        assert!(
            (info.bytes_per_pixel as f64) >= per_pixel
                && (info.bytes_per_pixel as f64) < 2.0 * per_pixel,
            "{}: {per_pixel} bytes a pixel, {} declared",
            info.name,
            info.bytes_per_pixel
        );
        match info.name {
            "pt" | "bdpt" => assert_eq!(bytes, film + pass_buffer, "{}", info.name),
            _ => assert!(
                bytes > film + pass_buffer && bytes < 100 << 20,
                "{}: {bytes}",
                info.name
            ),
        }
    }
}

/// A pass that panics on a worker thread ends the session as `Failed`, saying where and why,
/// with exactly the image of the passes before it (the same as a run stopped there); a panic
/// in the first pass leaves no estimate; either way the next session renders.
#[test]
fn a_panicking_pass_fails_the_session_and_keeps_the_passes_before() {
    for integrator in ["pt", "sppm", "mmlt"] {
        let of = |passes, panic_in_pass| SessionConfig {
            integrator: integrator.into(),
            panic_in_pass,
            ..config(Some(passes))
        };
        let failed = Session::start(of(10, Some(3))).unwrap().wait();
        assert_eq!(
            (failed.state, failed.passes),
            (RunState::Failed, 3),
            "{integrator}"
        );
        assert_eq!(
            failed.failure.as_deref(),
            Some("the renderer failed after 3 passes: fault injected in pass 3"),
            "{integrator}"
        );
        let stopped = Session::start(of(3, None)).unwrap().wait();
        assert_eq!(stopped.state, RunState::Finished);
        assert_eq!(failed.image.pixels, stopped.image.pixels, "{integrator}");
        assert!(failed.image.mean_luminance() > 0.0, "{integrator}");

        let first = Session::start(of(10, Some(0))).unwrap().wait();
        assert_eq!(
            (first.state, first.passes),
            (RunState::Failed, 0),
            "{integrator}"
        );
    }
}

/// A session whose buffers would take more memory than there is (or than it is allowed) is
/// refused before anything is allocated, saying how much it needs and what to do.
#[test]
fn a_session_too_large_for_the_memory_is_refused_before_it_starts() {
    let refused = Session::start(SessionConfig {
        integrator: "sppm".into(),
        memory_limit: Some(1 << 30),
        ..SessionConfig::new(config(None).scene, "sppm", 4096, 4096)
    });
    let Err(e @ SessionError::TooLarge { .. }) = refused else {
        panic!("a 4096 x 4096 sppm session started within 1 GiB");
    };
    assert_eq!(
        e.to_string(),
        "sppm at 4096 x 4096 needs about 11.0 GiB for its buffers, more than the 1.0 GiB \
         allowed: render a smaller image (--max-memory raises the limit)"
    );
    // Within the limit it starts.
    Session::start(SessionConfig {
        memory_limit: Some(1 << 30),
        ..SessionConfig::new(config(None).scene, "sppm", 256, 256)
    })
    .unwrap();
}
