//! What Caustica writes beside every image it saves: the EXR header attributes (DESIGN.md
//! section 3), built in this one place for the command line and the viewer from the
//! session's own account of its run (`Session::run_description`).

use crate::integrators::{ParamValues, params_json};
use crate::session::Frame;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The run an image came from: the integrator with its parameters as they stand (live
/// changes included), the seed, the scene file and the worker threads actually used.
#[derive(Clone, Debug, PartialEq)]
pub struct RunDescription {
    pub integrator: String,
    pub params: ParamValues,
    pub seed: u64,
    pub scene: PathBuf,
    pub threads: usize,
}

/// Header attributes (written as `caustica:KEY`) of `frame`, rendered by `run`.
///
/// `passes` and `samples_per_pixel` count passes (one sample per pixel each for pt and bdpt,
/// one eye pass and a photon pass for the photon mappers, width x height mutations for mmlt);
/// `samples` counts every sample the integrator took; `estimated_relmse` is the remaining
/// error estimated without a reference, and `estimated_bias_relmse` its squared-bias part.
pub fn exr_metadata(run: &RunDescription, frame: &Frame) -> BTreeMap<String, String> {
    let mut m = BTreeMap::from([
        ("integrator".to_string(), run.integrator.clone()),
        ("parameters".to_string(), params_json(&run.params)),
        (
            "elapsed_seconds".to_string(),
            format!("{:.3}", frame.elapsed.as_secs_f64()),
        ),
        ("passes".to_string(), frame.passes.to_string()),
        ("samples_per_pixel".to_string(), frame.passes.to_string()),
        ("samples".to_string(), frame.samples.to_string()),
        ("seed".to_string(), run.seed.to_string()),
        ("scene".to_string(), run.scene.display().to_string()),
        ("threads".to_string(), run.threads.to_string()),
        ("rays".to_string(), frame.rays.to_string()),
        ("dropped_samples".to_string(), frame.dropped.to_string()),
    ]);
    if let Some(e) = frame.error.as_ref() {
        m.insert("estimated_relmse".into(), format!("{:e}", e.rel_mse));
        m.insert(
            "estimated_bias_relmse".into(),
            format!("{:e}", e.bias_rel_mse),
        );
    }
    m
}
