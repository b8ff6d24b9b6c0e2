//! `caustica render`: one progressive session, a progress bar on stderr, then the image.

use crate::param_flags::{ParamFlags, flag_of};
use anyhow::{Context, anyhow};
use caustica_renderer::camera::CameraDesc;
use caustica_renderer::exposure::auto_exposure;
use caustica_renderer::image::{read_exr, write_exr, write_png};
use caustica_renderer::integrators;
use caustica_renderer::metadata::camera_from_json;
use caustica_renderer::metadata::exr_metadata;
use caustica_renderer::session::{MAX_RESOLUTION, Session, SessionConfig, SessionError};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene to render (.gltf or .glb).
    pub scene: PathBuf,
    /// Output image: .exr (linear float32 RGB with metadata) or .png (tone-mapped sRGB).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Integrator (`caustica info SCENE` says which one the scene needs).
    #[arg(long, default_value = "pt", value_parser = integrator_names())]
    pub integrator: String,
    /// Samples per pixel (one per pass); the default when --time is not given is 16.
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u64).range(1..))]
    pub spp: Option<u64>,
    /// Render for this many seconds instead of a number of samples.
    #[arg(long, value_parser = parse_seconds, allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Stop once the estimated remaining relMSE falls below E (--time or --spp, if given,
    /// still cap the run).
    #[arg(long, value_name = "E", value_parser = parse_positive, allow_negative_numbers = true)]
    pub until_error: Option<f64>,
    #[command(flatten)]
    pub size: SizeArgs,
    #[command(flatten)]
    pub scene_flags: crate::scene_flags::SceneFlags,
    /// Render the view saved in this EXR's header (`caustica:camera`, written by the viewer's
    /// and the command line's snapshots) in place of the scene's camera.
    #[arg(long, value_name = "FILE.exr")]
    pub camera_from: Option<PathBuf>,
    /// Seed of every random number; the same seed gives the same image on any thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Integrator parameters (each integrator reads its own; see `caustica info` for what
    /// the scene needs).
    #[command(flatten)]
    pub params: ParamFlags,
    /// Write the run's statistics as JSON (counters; for MMLT the technique histogram and
    /// acceptance rates per path length).
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// Exposure in stops applied to PNG output, or `auto`: the 97th percentile of the lit
    /// pixels' luminance shown at 90 % of white (README, "Exposure").
    #[arg(long, default_value = "auto", value_parser = parse_exposure, allow_negative_numbers = true)]
    pub exposure: Exposure,
    /// Memory the integrator's buffers may take, in bytes or with a suffix K, M, G
    /// (binary) [default: what the system has available].
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes)]
    pub max_memory: Option<u64>,
    /// Fault injection for the tests: a worker thread panics during this pass.
    #[arg(long, hide = true, value_name = "PASS")]
    pub panic_in_pass: Option<u64>,
}

/// An exposure in stops, or automatic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    Auto,
    Stops(f32),
}

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    if s == "auto" {
        return Ok(Exposure::Auto);
    }
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= 20.0 => Ok(Exposure::Stops(v)),
        _ => Err(format!(
            "'{s}' is not `auto` or a number of stops from -20 to 20"
        )),
    }
}

/// The registered integrators' names, as the values an `--integrator` flag accepts.
pub fn integrator_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(integrators::registry().iter().map(|i| i.name))
}

/// A number of bytes, plain or with a binary suffix: 512M, 8G.
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let (digits, shift) = match s.char_indices().last() {
        Some((i, 'K' | 'k')) => (&s[..i], 10),
        Some((i, 'M' | 'm')) => (&s[..i], 20),
        Some((i, 'G' | 'g')) => (&s[..i], 30),
        _ => (s, 0),
    };
    digits
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(1 << shift))
        .ok_or_else(|| format!("'{s}' is not a number of bytes (like 512M or 8G)"))
}

pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("'{s}' must be a positive number of seconds"))
    }
}

/// The image size flags of the subcommands that render.
#[derive(Args, Debug, Clone, Copy)]
pub struct SizeArgs {
    /// Image width in pixels [default: 512, or from --height and the camera's aspect ratio].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    pub width: Option<u32>,
    /// Image height in pixels [default: from the width and the camera's aspect ratio, else square].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    pub height: Option<u32>,
}

impl SizeArgs {
    /// The size for a camera of aspect ratio `aspect` (`output_size`).
    pub fn resolve(&self, aspect: Option<f32>) -> (u32, u32) {
        output_size(self.width, self.height, aspect)
    }
}

fn parse_positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' must be a positive number")),
    }
}

pub enum Failure {
    /// Bad arguments: exit code 2.
    Usage(String),
    /// Everything else: exit code 1.
    Runtime(anyhow::Error),
}

impl From<anyhow::Error> for Failure {
    fn from(e: anyhow::Error) -> Self {
        Failure::Runtime(e)
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Exr,
    Png,
}

fn output_format(path: &Path) -> Result<Format, Failure> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") => Ok(Format::Exr),
        Some("png") => Ok(Format::Png),
        _ => Err(Failure::Usage(format!(
            "--output {}: the file name must end in .exr or .png",
            path.display()
        ))),
    }
}

/// The output size: what was given, the rest from the camera's aspect ratio (width over
/// height) when the scene has one, else square; 512 wide when neither is given.
pub fn output_size(width: Option<u32>, height: Option<u32>, aspect: Option<f32>) -> (u32, u32) {
    let aspect = aspect.filter(|a| a.is_finite() && *a > 0.0).unwrap_or(1.0) as f64;
    let fit = |v: f64| (v.round() as u32).clamp(1, MAX_RESOLUTION);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, fit(w as f64 / aspect)),
        (None, Some(h)) => (fit(h as f64 * aspect), h),
        (None, None) => (512, fit(512.0 / aspect)),
    }
}

pub fn run(args: &RenderArgs) -> Result<(), Failure> {
    let format = output_format(&args.output)?;
    let info = integrators::find(&args.integrator).ok_or_else(|| {
        let known: Vec<_> = integrators::registry().iter().map(|i| i.name).collect();
        Failure::Usage(format!(
            "--integrator {}: unknown (known: {})",
            args.integrator,
            known.join(", ")
        ))
    })?;
    let out_dir = args
        .output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !out_dir.is_dir() {
        return Err(anyhow!(
            "{}: the output directory {} does not exist",
            args.output.display(),
            out_dir.display()
        )
        .into());
    }

    let scene = Arc::new(args.scene_flags.load(&args.scene)?);
    let si = &scene.info;
    eprintln!(
        "{}: {} triangles, {} lights, loaded in {:.1} ms (BVH {:.1} ms)",
        args.scene.display(),
        si.triangles,
        si.lights,
        si.load_time.as_secs_f64() * 1e3,
        si.bvh_build_time.as_secs_f64() * 1e3
    );
    let camera = args.camera_from.as_deref().map(camera_from).transpose()?;
    let (width, height) = args
        .size
        .resolve(camera.map_or(scene.camera.aspect, |c| c.aspect));
    for w in &si.warnings {
        eprintln!("warning: {w}");
    }

    // Without a time, a pass count or a target error, 16 passes.
    let spp = match (args.spp, args.time, args.until_error) {
        (Some(n), _, _) => Some(n),
        (None, None, None) => Some(16),
        _ => None,
    };
    let session = Session::start(SessionConfig {
        params: args.params.given.clone(),
        seed: args.seed,
        threads: args.threads,
        max_passes: spp,
        time_limit: args.time.map(Duration::from_secs_f64),
        target_rel_mse: args.until_error,
        camera,
        panic_in_pass: args.panic_in_pass,
        memory_limit: args.max_memory,
        ..SessionConfig::new(scene.clone(), info.name, width, height)
    })
    .map_err(|e| match e {
        // The parameters are checked here, once, against this integrator's ranges.
        SessionError::InvalidParameter(e) => {
            let flag = args
                .params
                .given
                .keys()
                .find(|k| e.starts_with(k.as_str()) || e.contains(&format!("'{k}'")))
                .map(|k| flag_of(k));
            Failure::Usage(flag.map_or(e.clone(), |f| format!("{f}: {e}")))
        }
        e => Failure::Usage(e.to_string()),
    })?;
    let params = session.params().clone();

    let bar = match spp {
        Some(n) => ProgressBar::new(n).with_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} passes  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        ),
        None => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {pos} passes  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        ),
    };
    // Where the first pass was seen, for the steady rate (start-up excluded) in the statistics.
    let mut first_pass: Option<(u64, Duration)> = None;
    while !session.is_done() {
        std::thread::sleep(Duration::from_millis(100));
        let frame = session.frame();
        if first_pass.is_none() && frame.passes > 0 {
            first_pass = Some((frame.samples, frame.elapsed));
        }
        bar.set_position(frame.passes);
        let secs = frame.elapsed.as_secs_f64().max(1e-9);
        let error = frame.error.as_ref().as_ref().map_or(String::new(), |e| {
            format!("  est. relMSE {:.3e}", e.rel_mse)
        });
        bar.set_message(format!(
            "{:.2} Mrays/s{error}",
            frame.rays as f64 / secs / 1e6
        ));
    }
    let run = session.run_description(&args.scene);
    let frame = session.wait();
    bar.finish_and_clear();
    for m in frame.messages.iter() {
        eprintln!("note: {m}");
    }

    let secs = frame.elapsed.as_secs_f64().max(1e-9);
    let metadata = exr_metadata(&run, &frame);
    let estimate = frame.error.as_ref().as_ref();
    match format {
        Format::Exr => write_exr(&args.output, &frame.image, &metadata),
        Format::Png => {
            let exposure = match args.exposure {
                Exposure::Stops(ev) => ev,
                Exposure::Auto => {
                    let ev = auto_exposure(&frame.image);
                    eprintln!("exposure: auto, {ev:+.2} stops");
                    ev
                }
            };
            write_png(&args.output, &frame.image, exposure)
        }
    }
    .with_context(|| "cannot write the image".to_string())?;
    if let Some(failure) = &frame.failure {
        // The image of the passes before the failure was saved above: hours of rendering are
        // not lost to one bad pass.
        return Err(anyhow!(
            "{failure}; the image of those passes was saved to {}",
            args.output.display()
        )
        .into());
    }
    if let Some(path) = &args.stats {
        let stats = serde_json::json!({
            "integrator": info.name,
            "parameters": params,
            "passes": frame.passes,
            "samples": frame.samples,
            "rays": frame.rays,
            "dropped_samples": frame.dropped,
            "elapsed_seconds": secs,
            "steady_samples_per_second": first_pass.and_then(|p| frame.samples_per_second_since(p)),
            "threads": run.threads,
            "messages": *frame.messages,
            "estimated_relmse": estimate.map(|e| e.rel_mse),
            "estimated_bias_relmse": estimate.map(|e| e.bias_rel_mse),
            "integrator_statistics": *frame.statistics,
            "scene_memory_bytes": scene.memory(),
            "integrator_memory_bytes": frame.integrator_memory_bytes,
        });
        let text = serde_json::to_string_pretty(&stats).unwrap_or_default();
        std::fs::write(path, text + "\n")
            .with_context(|| format!("{}: cannot write the statistics", path.display()))?;
    }
    if let Some(target) = args.until_error {
        match estimate {
            Some(e) if e.rel_mse < target => {
                eprintln!("estimated relMSE {:.3e} is below {target:e}", e.rel_mse)
            }
            _ => eprintln!("note: stopped before the estimated relMSE fell below {target:e}"),
        }
    }
    eprintln!(
        "{} passes, {} samples in {:.2} s on {} threads: {:.2} Mrays/s, {} dropped samples, estimated relMSE {} -> {}",
        frame.passes,
        frame.samples,
        secs,
        run.threads,
        frame.rays as f64 / secs / 1e6,
        frame.dropped,
        estimate.map_or("unknown".to_string(), |e| format!("{:.3e}", e.rel_mse)),
        args.output.display()
    );
    Ok(())
}

/// The camera saved in an EXR's header.
fn camera_from(path: &Path) -> anyhow::Result<CameraDesc> {
    let (_, metadata) = read_exr(path).map_err(|e| anyhow!(e))?;
    let json = metadata.get("camera").ok_or_else(|| {
        anyhow!(
            "{}: the header has no caustica:camera (an image saved by Caustica records its view)",
            path.display()
        )
    })?;
    camera_from_json(json).map_err(|e| anyhow!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::output_size;

    #[test]
    fn output_size_follows_the_camera_aspect() {
        assert_eq!(output_size(None, None, None), (512, 512));
        assert_eq!(output_size(None, None, Some(16.0 / 9.0)), (512, 288));
        assert_eq!(output_size(Some(100), None, Some(2.0)), (100, 50));
        assert_eq!(output_size(None, Some(100), Some(2.0)), (200, 100));
        assert_eq!(output_size(Some(30), Some(40), Some(2.0)), (30, 40));
    }
}
