//! Measures that photon mapping's storage is bounded: the resident size after 10 and after
//! 1000 passes of SPPM on cornell-glass (Linux, /proc/self/statm).
//!
//! ```text
//! cargo run --release -p caustica-renderer --example ppm_memory
//! ```

use caustica_renderer::camera::Camera;
use caustica_renderer::integrators::ppm::{PhotonMapper, PhotonMappingSettings, Variant};
use caustica_renderer::integrators::{Integrator, RenderContext};
use caustica_renderer::scene::gltf::load;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

fn resident_mib() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: f64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0.0);
    pages * 4096.0 / (1024.0 * 1024.0)
}

fn main() {
    let scene = Arc::new(
        load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell-glass.gltf"))
            .expect("the bundled scene"),
    );
    for variant in [Variant::Ppm, Variant::Sppm, Variant::Pppm] {
        let ctx = RenderContext {
            scene: scene.clone(),
            camera: Camera::new(&scene.camera, 256, 256),
            seed: 0,
        };
        let settings = PhotonMappingSettings {
            alpha: 2.0 / 3.0,
            radius: 0.0,
            photons: 20_000,
            max_depth: 64,
        };
        let mut pm = PhotonMapper::new(ctx, variant, settings);
        let cancel = AtomicBool::new(false);
        let mut at_10 = 0.0;
        for pass in 0..1000 {
            pm.render_pass(pass, &cancel).expect("not cancelled");
            // What a session publishes after every pass.
            let _ = (pm.image(), pm.plots(), pm.pixel_layers());
            if pass + 1 == 10 {
                at_10 = resident_mib();
            }
        }
        let at_1000 = resident_mib();
        println!(
            "{variant:?}: resident {at_10:.1} MiB after 10 passes, {at_1000:.1} MiB after 1000 ({:+.2} %)",
            100.0 * (at_1000 - at_10) / at_10
        );
    }
}
