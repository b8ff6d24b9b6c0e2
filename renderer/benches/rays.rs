//! Ray-tracing and path-tracing throughput:
//!
//! ```text
//! cargo bench -p caustica-renderer --bench rays
//! ```
//!
//! Closest-hit and occlusion queries for camera rays (coherent) and for diffuse-bounce rays
//! (cosine-distributed from the camera rays' hits, incoherent), on one thread and on all
//! cores, on every bundled scene and on the caustic pool tessellated to a million triangles
//! (with the time to load it from a .glb and build its BVH); path-tracer samples per second on every bundled scene;
//! photon-mapping, bidirectional and MMLT throughput on cornell-glass and door. Throughput is
//! reported as elements (rays, samples, photons or mutations) per second.

use caustica_renderer::camera::Camera;
use caustica_renderer::geometry::Ray;
use caustica_renderer::integrators::path_tracer::{PathSettings, PathTracer};
use caustica_renderer::integrators::{Integrator, RenderContext};
use caustica_renderer::sampling::sampler::Sampler;
use caustica_renderer::sampling::warp::sample_cosine_hemisphere;
use caustica_renderer::scene::Scene;
use caustica_renderer::scene::gltf::load;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec2;
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

const SIZE: u32 = 256;

/// The bundled scenes, by file stem.
const BUNDLED: [&str; 4] = ["cornell-box", "cornell-glass", "caustic-pool", "door"];

fn bundled(name: &str) -> Arc<Scene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../assets/{name}.gltf"));
    Arc::new(load(&path).expect("the bundled scene loads"))
}

fn scene() -> Arc<Scene> {
    bundled("cornell-glass")
}

/// The caustic pool with a rippled surface of a million triangles.
fn million_triangle_pool() -> Arc<Scene> {
    let desc = caustica_renderer::procedural::caustic_pool_tessellated(707);
    Arc::new(Scene::build(desc).expect("the generated scene builds"))
}

fn camera_rays(scene: &Scene) -> Vec<Ray> {
    let camera = Camera::new(&scene.camera, SIZE, SIZE);
    let mut s = Sampler::new(1);
    (0..SIZE * SIZE)
        .map(|i| {
            s.start_pixel_sample(i as u64, 0);
            camera.generate_ray(Vec2::new((i % SIZE) as f32, (i / SIZE) as f32) + s.get_2d())
        })
        .collect()
}

fn bounce_rays(scene: &Scene, camera: &[Ray]) -> Vec<Ray> {
    let mut s = Sampler::new(2);
    camera
        .iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let si = scene.intersect(r)?;
            s.start_pixel_sample(i as u64, 1);
            let local = sample_cosine_hemisphere(s.get_2d());
            let n = if si.n.dot(si.wo) < 0.0 { -si.n } else { si.n };
            let frame = caustica_renderer::geometry::Frame::from_z(n);
            Some(si.spawn_ray(frame.from_local(local)))
        })
        .collect()
}

/// A pool of one thread and one with a thread per core: every figure is measured on both.
fn pools() -> Vec<(usize, rayon::ThreadPool)> {
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    [1, all]
        .into_iter()
        .map(|t| {
            (
                t,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap(),
            )
        })
        .collect()
}

fn bench_rays(c: &mut Criterion) {
    let mut scenes: Vec<(String, Arc<Scene>)> = BUNDLED
        .iter()
        .map(|name| (name.to_string(), bundled(name)))
        .collect();
    scenes.push(("pool-1M".into(), million_triangle_pool()));
    for (name, scene) in &scenes {
        let camera = camera_rays(scene);
        let bounce = bounce_rays(scene, &camera);
        for (threads, pool) in pools() {
            for (kind, rays) in [("camera", &camera), ("diffuse-bounce", &bounce)] {
                let mut group =
                    c.benchmark_group(format!("{name}: {kind} rays, {threads} thread(s)"));
                group.throughput(Throughput::Elements(rays.len() as u64));
                group.sample_size(20);
                group.warm_up_time(Duration::from_secs(1));
                group.measurement_time(Duration::from_secs(3));
                group.bench_function("closest hit", |b| {
                    b.iter(|| {
                        pool.install(|| {
                            rays.par_iter()
                                .with_min_len(1024)
                                .filter(|r| scene.intersect(r).is_some())
                                .count()
                        })
                    })
                });
                group.bench_function("occlusion", |b| {
                    b.iter(|| {
                        pool.install(|| {
                            rays.par_iter()
                                .with_min_len(1024)
                                .filter(|r| scene.occluded(r))
                                .count()
                        })
                    })
                });
                group.finish();
            }
        }
    }
}

/// Times whole passes of an integrator on one thread and on all cores; throughput in
/// `elements` (samples or photons) per pass.
fn bench_passes(
    c: &mut Criterion,
    name: &str,
    elements: u64,
    make: impl Fn() -> Box<dyn Integrator>,
) {
    for (threads, pool) in pools() {
        let mut integrator = make();
        let cancel = AtomicBool::new(false);
        let mut group = c.benchmark_group(format!("{name}, {threads} thread(s)"));
        group.throughput(Throughput::Elements(elements));
        group.sample_size(10);
        let mut pass = 0;
        group.bench_function("pass", |b| {
            b.iter(|| {
                pass += 1;
                pool.install(|| integrator.render_counted_pass(pass, &cancel))
                    .unwrap()
            })
        });
        group.finish();
    }
}

/// Path-tracer samples per second on every bundled scene (64 x 64, max depth 64).
fn bench_path_tracer(c: &mut Criterion) {
    let size = 64;
    for name in BUNDLED {
        let scene = bundled(name);
        bench_passes(
            c,
            &format!("path tracer samples, {name}"),
            (size * size) as u64,
            || {
                let ctx = RenderContext {
                    scene: scene.clone(),
                    camera: Camera::new(&scene.camera, size, size),
                    seed: 0,
                };
                Box::new(PathTracer::new(ctx, PathSettings::default()))
            },
        );
    }
}

fn bench_load(c: &mut Criterion) {
    let mut group = c.benchmark_group("scene");
    group.sample_size(20);
    for name in BUNDLED {
        group.bench_function(format!("load {name} and build its BVH"), |b| {
            b.iter(|| bundled(name))
        });
    }
    group.sample_size(10);
    group.bench_function("build the 1 M triangle pool and its BVH", |b| {
        b.iter(million_triangle_pool)
    });
    // As a user opens a large model: a binary glTF read from disk (the page cache, after the
    // first iteration), its meshes checked and flattened, the BVH built.
    let desc = caustica_renderer::procedural::caustic_pool_tessellated(707);
    let glb = std::env::temp_dir().join(format!("caustica-bench-{}-pool.glb", std::process::id()));
    std::fs::write(&glb, caustica_renderer::scene::gltf::export::to_glb(&desc))
        .expect("the temporary directory is writable");
    group.bench_function(
        "load the 1 M triangle pool from a .glb and build its BVH",
        |b| b.iter(|| load(&glb).expect("the exported pool loads")),
    );
    let _ = std::fs::remove_file(&glb);
    group.finish();
}

/// Latency of `Session::cancel` while all cores render 512 x 512 passes of cornell-glass:
/// from the call until the session has stopped (DESIGN.md section 6 asks for 50 ms at most).
fn bench_cancel(c: &mut Criterion) {
    use caustica_renderer::session::{Session, SessionConfig};
    let scene = scene();
    let mut group = c.benchmark_group("session");
    group.sample_size(10);
    group.bench_function("cancel latency, 512x512 cornell-glass", |b| {
        b.iter_custom(|iters| {
            let mut total = std::time::Duration::ZERO;
            for _ in 0..iters {
                let session =
                    Session::start(SessionConfig::new(scene.clone(), "pt", 512, 512)).unwrap();
                std::thread::sleep(std::time::Duration::from_millis(150));
                let start = std::time::Instant::now();
                session.cancel();
                session.wait();
                total += start.elapsed();
            }
            total
        })
    });
    group.finish();
}

/// Photon-mapping passes (SPPM, 100,000 photons, cornell-glass at 256 x 256): photons per
/// second including the eye pass, the grid build and the update.
fn bench_photon_mapping(c: &mut Criterion) {
    use caustica_renderer::integrators::ppm::{PhotonMapper, PhotonMappingSettings, Variant};
    let scene = scene();
    let settings = PhotonMappingSettings {
        alpha: 2.0 / 3.0,
        radius: 0.0,
        photons: 100_000,
        max_depth: 64,
    };
    bench_passes(c, "sppm photons", settings.photons, || {
        let ctx = RenderContext {
            scene: scene.clone(),
            camera: Camera::new(&scene.camera, SIZE, SIZE),
            seed: 0,
        };
        Box::new(PhotonMapper::new(ctx, Variant::Sppm, settings))
    });
}

/// Bidirectional path tracing samples per second (cornell-glass, 64 x 64, max depth 64), and
/// MMLT mutations per second (a pass is one mutation per pixel; door and cornell-glass at
/// 64 x 64, default parameters but max depth 10, as first measured: 1000 chains; the bootstrap
/// runs in the warm-up).
fn bench_bidirectional(c: &mut Criterion) {
    use caustica_renderer::integrators::bdpt::{Bdpt, BdptSettings};
    use caustica_renderer::integrators::mmlt::{Mmlt, MmltSettings};
    let size = 64;
    let glass = scene();
    let door = bundled("door");
    let ctx = |scene: &Arc<Scene>| RenderContext {
        scene: scene.clone(),
        camera: Camera::new(&scene.camera, size, size),
        seed: 0,
    };
    bench_passes(c, "bdpt samples", (size * size) as u64, || {
        Box::new(Bdpt::new(
            ctx(&glass),
            BdptSettings {
                max_depth: 64,
                only_strategy: None,
            },
        ))
    });
    for (name, scene) in [("door", &door), ("cornell-glass", &glass)] {
        bench_passes(
            c,
            &format!("mmlt mutations, {name}"),
            (size * size) as u64,
            || {
                let settings = MmltSettings {
                    max_depth: 10,
                    ..MmltSettings::default()
                };
                Box::new(Mmlt::new(ctx(scene), settings))
            },
        );
    }
}

criterion_group!(
    benches,
    bench_rays,
    bench_path_tracer,
    bench_load,
    bench_cancel,
    bench_photon_mapping,
    bench_bidirectional
);
criterion_main!(benches);
