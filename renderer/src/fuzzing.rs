//! What the fuzz targets (`renderer/fuzz`, cargo-fuzz on nightly) run on each input, here so
//! that the inputs they found are replayed by a plain `cargo test` on stable
//! (`renderer/tests/fuzz.rs`). Nothing here catches a panic: a panic is the finding.

use crate::light::environment::{EnvironmentChoice, EnvironmentSettings};
use crate::scene::gltf::description_from_bytes;
use crate::scene::limits::LoadLimits;
use crate::scene::{Scene, SceneDescription};
use crate::session::{RunState, Session, SessionConfig};
use std::path::Path;
use std::sync::Arc;

/// Limits far below the defaults, so that a fuzzed input reaching one is refused in
/// milliseconds, and any allocation libFuzzer's limit (2 GB) catches is one no limit bounds.
pub const FUZZ_LIMITS: LoadLimits = LoadLimits {
    max_texels: 1 << 20,
    max_buffer_bytes: 1 << 24,
    max_triangles: 1 << 16,
    max_node_depth: 64,
};

/// Reads `bytes` as a .gltf or .glb file (external files resolved in a folder that does not
/// exist), builds the scene and renders one pass of 8 x 6 pixels with each kind of integrator
/// on one thread. Ok with the image's mean, or Err with the message a user would see.
pub fn load_and_render_gltf(bytes: &[u8]) -> Result<f64, String> {
    let base = Path::new("/nonexistent-caustica-fuzz");
    let mut desc =
        description_from_bytes(bytes, base, "fuzz", &FUZZ_LIMITS).map_err(|e| e.to_string())?;
    // The studio's 512 x 256 map would be built for every unlit input.
    desc.environment = EnvironmentSettings {
        choice: EnvironmentChoice::Uniform,
        ..Default::default()
    };
    render_each_kind(desc)
}

fn render_each_kind(desc: SceneDescription) -> Result<f64, String> {
    let scene = Arc::new(Scene::build(desc).map_err(|e| e.to_string())?);
    let mut sum = 0.0;
    // Photons per pass cut from 100000 to 1000 for throughput: a pass still traces some.
    for (integrator, params) in [("pt", vec![]), ("bdpt", vec![]), ("sppm", vec![1000.0])] {
        let session = Session::start(SessionConfig {
            params: params
                .into_iter()
                .map(|n| ("photons".to_string(), n))
                .collect(),
            threads: 1,
            max_passes: Some(1),
            ..SessionConfig::new(scene.clone(), integrator, 8, 6)
        })
        .map_err(|e| e.to_string())?;
        let frame = session.wait();
        assert_eq!(frame.state, RunState::Finished, "{integrator}");
        assert_eq!(frame.image.count_non_finite(), 0, "{integrator}");
        sum += frame.image.mean_luminance();
    }
    Ok(sum)
}
