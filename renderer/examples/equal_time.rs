//! Equal-time error of several integrators against a long reference: the measurement behind
//! "users trade speed for accuracy". Renders the reference with one integrator for a long
//! time, then each competitor for the same short time (seeds differ from the reference's),
//! and prints relMSE against the reference. All use one maximum depth.
//!
//! ```text
//! cargo run --release -p caustica-renderer --example equal_time -- \
//!     assets/door.gltf 128 600 30 bdpt pt,bdpt,mmlt
//! ```
//! Arguments: scene, width (the height follows the camera), reference seconds, seconds per
//! competitor, reference integrator, competitors. The reference is kept as
//! `<scene>-reference-<width>.exr` beside the working directory and reused when present.

use caustica_renderer::image::{compare, read_exr, write_exr};
use caustica_renderer::scene::gltf::load;
use caustica_renderer::session::{Session, SessionConfig};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let scene_path = PathBuf::from(arg(0, "assets/door.gltf"));
    let width: u32 = arg(1, "128").parse().expect("width");
    let reference_secs: f64 = arg(2, "600").parse().expect("reference seconds");
    let secs: f64 = arg(3, "30").parse().expect("seconds");
    let reference_integrator = arg(4, "bdpt");
    let competitors = arg(5, "pt,bdpt,mmlt");
    let max_depth = 10.0;
    let scene = Arc::new(load(&scene_path).expect("the scene loads"));
    let height = scene
        .camera
        .aspect
        .map_or(width, |a| (width as f32 / a).round().max(1.0) as u32);
    let params = |name: &str| {
        caustica_renderer::integrators::resolve_params(
            caustica_renderer::integrators::find(name).expect("a known integrator"),
            &[("max_depth".to_string(), max_depth)].into_iter().collect(),
        )
        .expect("valid parameters")
    };
    let run = |name: &str, seconds: f64, seed: u64| {
        let session = Session::start(SessionConfig {
            scene: scene.clone(),
            integrator: name.into(),
            params: params(name),
            width,
            height,
            seed,
            threads: 0,
            max_passes: None,
            time_limit: Some(Duration::from_secs_f64(seconds)),
            on_frame: None,
            target_rel_mse: None,
        })
        .expect("the session starts");
        session.wait()
    };
    let stem = scene_path
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let reference_path = PathBuf::from(format!("{stem}-reference-{width}.exr"));
    let reference = match read_exr(Path::new(&reference_path)) {
        Ok((image, _)) => image,
        Err(_) => {
            eprintln!("rendering the reference: {reference_integrator} for {reference_secs} s");
            let frame = run(&reference_integrator, reference_secs, 1000);
            let meta = BTreeMap::from([
                ("integrator".to_string(), reference_integrator.clone()),
                ("passes".to_string(), frame.passes.to_string()),
            ]);
            write_exr(&reference_path, &frame.image, &meta).expect("the reference is written");
            (*frame.image).clone()
        }
    };
    println!(
        "{} at {width}x{height}, {secs} s each, max depth {max_depth}:",
        scene_path.display()
    );
    for name in competitors.split(',') {
        let frame = run(name, secs, 1);
        let m = compare(&frame.image, &reference).expect("comparable images");
        println!(
            "  {name:5} relMSE {:.4e}  RMSE {:.4e}  mean luminance ratio {:.4}  ({} passes)",
            m.rel_mse, m.rmse, m.mean_luminance_ratio, frame.passes
        );
    }
}
