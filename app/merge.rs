//! `caustica merge`: independent runs of one scene (other seeds, on this machine or on many)
//! combined into one image, each weighted by its passes: a pass is one sample per pixel for
//! pt and bdpt, one eye and photon pass for the photon mappers, width x height mutations for
//! MMLT, so the weighted mean is the image one run of all the passes would give, with the
//! variance of all of them. For PPPM this is exact by design (Knaus & Zwicker 2011: its passes
//! are independent estimates); for SPPM and PPM the kernel bias is that of the runs' own
//! radii, not of a run as long as all of them together; for MMLT each run brings its own
//! normalisation, which averages too.

use anyhow::{Context, anyhow};
use caustica_renderer::error_estimate::ErrorEstimate;
use caustica_renderer::image::{Image, read_exr, write_exr};
use clap::Args;
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// EXR images written by `caustica render` (or saved by the viewer) from independent runs.
    #[arg(required = true, num_args = 2..)]
    pub inputs: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short, long)]
    pub output: PathBuf,
}

struct Run {
    path: PathBuf,
    image: Image,
    metadata: BTreeMap<String, String>,
    passes: f64,
}

fn number(run: &Run, key: &str) -> Option<f64> {
    run.metadata.get(key).and_then(|v| v.parse::<f64>().ok())
}

pub fn run(args: &MergeArgs) -> Result<(), crate::render::Failure> {
    use crate::render::Failure;
    let mut runs = Vec::new();
    for path in &args.inputs {
        let (image, metadata) = read_exr(path).map_err(|e| anyhow!(e))?;
        let passes = metadata
            .get("passes")
            .and_then(|p| p.parse::<f64>().ok())
            .filter(|p| p.is_finite() && *p > 0.0)
            .ok_or_else(|| {
                anyhow!(
                    "{}: no caustica:passes in its header, so its weight is unknown (merge only images Caustica wrote)",
                    path.display()
                )
            })?;
        runs.push(Run {
            path: path.clone(),
            image,
            metadata,
            passes,
        });
    }
    let first = &runs[0];
    for r in &runs[1..] {
        if (r.image.width, r.image.height) != (first.image.width, first.image.height) {
            return Err(Failure::Usage(format!(
                "{} is {}x{} but {} is {}x{}: runs to merge must have one size",
                r.path.display(),
                r.image.width,
                r.image.height,
                first.path.display(),
                first.image.width,
                first.image.height
            )));
        }
        for key in ["scene", "integrator", "parameters"] {
            if r.metadata.get(key) != first.metadata.get(key) {
                return Err(Failure::Usage(format!(
                    "{} and {} differ in their {key} ({} / {}): only runs of one scene, integrator and parameters merge",
                    first.path.display(),
                    r.path.display(),
                    first.metadata.get(key).map_or("none", String::as_str),
                    r.metadata.get(key).map_or("none", String::as_str),
                )));
            }
        }
    }
    let mut seeds: Vec<&str> = Vec::new();
    for r in &runs {
        let seed = r.metadata.get("seed").map_or("", String::as_str);
        if let Some(other) = runs.iter().find(|o| {
            !std::ptr::eq(*o, r) && o.metadata.get("seed").map(String::as_str) == Some(seed)
        }) {
            return Err(Failure::Usage(format!(
                "{} and {} have the same seed {seed}: they hold the same samples, not independent ones (render each with its own --seed)",
                r.path.display(),
                other.path.display()
            )));
        }
        seeds.push(seed);
    }

    let total: f64 = runs.iter().map(|r| r.passes).sum();
    let mut merged = Image::new(first.image.width, first.image.height);
    for (i, p) in merged.pixels.iter_mut().enumerate() {
        let sum: glam::DVec3 = runs
            .iter()
            .map(|r| r.image.pixels[i].as_dvec3() * r.passes)
            .sum();
        *p = (sum / total).as_vec3();
    }

    let sum_of =
        |key: &str| -> Option<f64> { runs.iter().map(|r| number(r, key)).sum::<Option<f64>>() };
    let mut metadata = BTreeMap::new();
    for key in ["integrator", "parameters", "scene"] {
        if let Some(v) = first.metadata.get(key) {
            metadata.insert(key.to_string(), v.clone());
        }
    }
    metadata.insert("passes".into(), format!("{total}"));
    metadata.insert("samples_per_pixel".into(), format!("{total}"));
    metadata.insert("seed".into(), seeds.join(","));
    metadata.insert("merged_runs".into(), runs.len().to_string());
    for key in ["samples", "rays", "dropped_samples"] {
        if let Some(v) = sum_of(key) {
            metadata.insert(key.into(), format!("{v}"));
        }
    }
    if let Some(v) = sum_of("elapsed_seconds") {
        // The compute time of all runs together (they may have run side by side).
        metadata.insert("elapsed_seconds".into(), format!("{v:.3}"));
    }
    let parts: Option<Vec<(f64, f64, f64)>> = runs
        .iter()
        .map(|r| {
            Some((
                r.passes,
                number(r, "estimated_relmse")?,
                number(r, "estimated_bias_relmse").unwrap_or(0.0),
            ))
        })
        .collect();
    let estimate = parts.and_then(|p| ErrorEstimate::merged_rel_mse(&p));
    if let Some(e) = estimate {
        metadata.insert("estimated_relmse".into(), format!("{e:e}"));
    }
    write_exr(&args.output, &merged, &metadata)
        .with_context(|| "cannot write the merged image".to_string())?;
    eprintln!(
        "merged {} runs, {total} passes, estimated relMSE {} -> {}",
        runs.len(),
        estimate.map_or("unknown".into(), |e| format!("{e:.3e}")),
        args.output.display()
    );
    Ok(())
}
