//! `caustica converge`: the speed/accuracy trade, measured. Runs each integrator (and each
//! value of swept parameters) on one scene for the same time, records at log-spaced
//! checkpoints of one progressive run the error against a reference (when given) and the
//! error each frame estimates of itself, and writes `convergence.csv`, `convergence.png`
//! (log-log error against time) and a table on stdout: which run wins at each time, and the
//! fitted slope of each run's error. With `--seeds N` each run is repeated with N seeds: one
//! run of a Markov-chain estimator can be several times better or worse than the next, so
//! the plot and the table give the median over the seeds at each checkpoint, and the table
//! the range of the last errors.

mod chart;
mod record;

use anyhow::{Context, anyhow};
use caustica_renderer::image::{Image, compare, read_exr};
use caustica_renderer::integrators::{self, ParamValues};
use caustica_renderer::scene::Scene;
use caustica_renderer::session::{Frame, MAX_RESOLUTION, Session, SessionConfig};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
pub use record::{Record, checkpoints, fitted_slope, median, median_over_seeds, winner_at};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

#[derive(Args, Debug)]
pub struct ConvergeArgs {
    /// Scene to render (.gltf or .glb).
    pub scene: PathBuf,
    /// Converged image (EXR) of the same view and size, for the true error.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Integrators to compare (repeat the flag or separate with commas); `recommended` is the
    /// integrator and parameters `caustica info` recommends for the scene at this size.
    #[arg(long = "integrator", required = true, value_delimiter = ',', num_args = 1..)]
    pub integrators: Vec<String>,
    /// A parameter and the values to sweep, NAME=V1,V2,...; repeat for several (every
    /// combination runs); integrators without that parameter run once.
    #[arg(long = "param", value_name = "NAME=V1,V2...")]
    pub params: Vec<String>,
    /// Seconds each run renders.
    #[arg(long, value_parser = crate::render::parse_seconds)]
    pub time: f64,
    /// Directory for convergence.csv and convergence.png (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Image width [default: the reference's, else 256].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    pub width: Option<u32>,
    /// Image height [default: the reference's, else from the width and the camera].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    pub height: Option<u32>,
    /// Seed of every run (the first seed with --seeds).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Repeats every run with this many seeds (--seed, --seed + 1, ...): the plot and the
    /// table show the median over them, the table their range.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub seeds: u64,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    #[command(flatten)]
    pub scene_flags: crate::scene_flags::SceneFlags,
    /// Checkpoints per decade of time.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub checkpoints_per_decade: u32,
}

/// One run: an integrator with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSpec {
    pub integrator: String,
    /// The parameters given on the command line (the rest are the defaults).
    pub given: ParamValues,
    /// The run `caustica info` recommends for the scene.
    pub recommended: bool,
}

impl RunSpec {
    pub fn label(&self) -> String {
        let mut label = self.integrator.clone();
        for (k, v) in &self.given {
            label += &format!(" {k}={}", crate::info::format_value(*v));
        }
        if self.recommended {
            label += " (recommended)";
        }
        label
    }
}

/// The integrator name that stands for the scene's recommended integrator and parameters.
pub const RECOMMENDED: &str = "recommended";

/// Parses `NAME=V1,V2,...`.
fn parse_sweep(text: &str) -> Result<(String, Vec<f64>), String> {
    let (name, values) = text
        .split_once('=')
        .ok_or_else(|| format!("--param {text}: expected NAME=V1,V2,..."))?;
    let values = values
        .split(',')
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .map_err(|_| format!("--param {text}: '{v}' is not a number"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((name.trim().replace('-', "_"), values))
}

/// Every run the arguments ask for, each validated against its integrator's parameters.
pub fn runs(integrators_given: &[String], sweeps: &[String]) -> Result<Vec<RunSpec>, String> {
    let sweeps: Vec<(String, Vec<f64>)> = sweeps
        .iter()
        .map(|s| parse_sweep(s))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for name in integrators_given {
        if name == RECOMMENDED {
            // Resolved once the scene is loaded (`run`).
            out.push(RunSpec {
                integrator: RECOMMENDED.into(),
                given: ParamValues::new(),
                recommended: true,
            });
            continue;
        }
        let info = integrators::find(name).ok_or_else(|| {
            let known: Vec<_> = integrators::registry().iter().map(|i| i.name).collect();
            format!("--integrator {name}: unknown (known: {})", known.join(", "))
        })?;
        let mut combinations = vec![ParamValues::new()];
        for (param, values) in &sweeps {
            if !info.params.iter().any(|p| p.name == param) {
                continue;
            }
            combinations = combinations
                .iter()
                .flat_map(|c| {
                    values.iter().map(move |v| {
                        let mut c = c.clone();
                        c.insert(param.clone(), *v);
                        c
                    })
                })
                .collect();
        }
        for given in combinations {
            integrators::resolve_params(info, &given)
                .map_err(|e| format!("--param for {name}: {e}"))?;
            out.push(RunSpec {
                integrator: name.clone(),
                given,
                recommended: false,
            });
        }
    }
    for (param, _) in &sweeps {
        let used = out.iter().any(|r| r.given.contains_key(param));
        if !used {
            return Err(format!(
                "--param {param}: none of the integrators has this parameter"
            ));
        }
    }
    Ok(out)
}

fn record(
    spec: &RunSpec,
    seed: u64,
    frame: &Frame,
    reference: Option<&Image>,
) -> anyhow::Result<Record> {
    let metrics = reference
        .map(|r| compare(&frame.image, r))
        .transpose()
        .context("comparing with the reference")?;
    let estimate = frame.error.as_ref().as_ref();
    Ok(Record {
        run: spec.label(),
        integrator: spec.integrator.clone(),
        parameters: spec
            .given
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" "),
        seconds: frame.elapsed.as_secs_f64(),
        passes: frame.passes,
        rel_mse: metrics.map(|m| m.rel_mse),
        rmse: metrics.map(|m| m.rmse),
        estimated_rel_mse: estimate.map(|e| e.rel_mse),
        estimated_bias_rel_mse: estimate.map(|e| e.bias_rel_mse),
        seed,
    })
}

/// Settings shared by every run.
pub struct Measurement<'a> {
    pub scene: Arc<Scene>,
    pub reference: Option<&'a Image>,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub seconds: f64,
    pub checkpoints: Vec<f64>,
}

/// Renders one run with one seed for the measurement's time and records it at each
/// checkpoint that a frame reached (a frame standing for several checkpoints is recorded once).
pub fn measure(
    m: &Measurement,
    spec: &RunSpec,
    seed: u64,
    progress: &dyn Fn(f64),
) -> anyhow::Result<Vec<Record>> {
    let session = Session::start(SessionConfig {
        params: spec.given.clone(),
        seed,
        threads: m.threads,
        time_limit: Some(Duration::from_secs_f64(m.seconds)),
        ..SessionConfig::new(m.scene.clone(), &spec.integrator, m.width, m.height)
    })
    .map_err(|e| anyhow!("{}: {e}", spec.label()))?;
    let mut records = Vec::new();
    let mut next = 0;
    let mut last_passes = 0;
    loop {
        let done = session.is_done();
        let frame = session.frame();
        let mut due = false;
        while next < m.checkpoints.len()
            && frame.passes > 0
            && frame.elapsed.as_secs_f64() >= m.checkpoints[next]
        {
            due = true;
            next += 1;
        }
        if (due || done) && frame.passes > last_passes {
            records.push(record(spec, seed, &frame, m.reference)?);
            last_passes = frame.passes;
        }
        progress(frame.elapsed.as_secs_f64().min(m.seconds));
        if done {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(records)
}

fn image_size(args: &ConvergeArgs, scene: &Scene, reference: Option<&Image>) -> (u32, u32) {
    if let Some(r) = reference {
        return (
            args.width.unwrap_or(r.width as u32),
            args.height.unwrap_or(r.height as u32),
        );
    }
    crate::render::output_size(
        Some(args.width.unwrap_or(256)),
        args.height,
        scene.camera.aspect,
    )
}

pub fn run(args: &ConvergeArgs) -> Result<(), crate::render::Failure> {
    use crate::render::Failure;
    let specs = runs(&args.integrators, &args.params).map_err(Failure::Usage)?;
    let reference = args
        .reference
        .as_ref()
        .map(|p| read_exr(p).map(|(image, _)| image))
        .transpose()
        .map_err(|e| anyhow!("reference: {e}"))?;
    let scene = Arc::new(args.scene_flags.load(&args.scene)?);
    let (width, height) = image_size(args, &scene, reference.as_ref());
    let mut specs = specs;
    for spec in specs.iter_mut().filter(|s| s.recommended) {
        let (_, r) = caustica_renderer::advisor::analyse(&scene, width, height);
        spec.integrator = r.integrator.to_string();
        spec.given = r.params;
    }
    if let Some(r) = &reference
        && (r.width as u32, r.height as u32) != (width, height)
    {
        return Err(Failure::Usage(format!(
            "--reference {}: it is {}x{}, the runs {width}x{height}",
            args.reference.as_deref().unwrap_or(Path::new("")).display(),
            r.width,
            r.height
        )));
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create the directory", args.out.display()))?;
    let m = Measurement {
        scene,
        reference: reference.as_ref(),
        width,
        height,
        threads: args.threads,
        seconds: args.time,
        checkpoints: checkpoints(args.time, args.checkpoints_per_decade),
    };
    let seeds: Vec<u64> = (0..args.seeds).map(|i| args.seed + i).collect();
    let total = args.time * (specs.len() * seeds.len()) as f64;
    let bar = ProgressBar::new((total * 10.0).ceil() as u64).with_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut all = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let mut by_seed = Vec::new();
        for (j, &seed) in seeds.iter().enumerate() {
            bar.set_message(format!(
                "{} seed {seed} ({}/{})",
                spec.label(),
                i + 1,
                specs.len()
            ));
            let done_before = args.time * (i * seeds.len() + j) as f64;
            let records = measure(&m, spec, seed, &|t| {
                bar.set_position(((done_before + t) * 10.0) as u64)
            })?;
            by_seed.push(records);
        }
        all.push(by_seed);
    }
    bar.finish_and_clear();

    let csv_path = args.out.join("convergence.csv");
    write_csv(&csv_path, &all)?;
    let medians: Vec<Vec<Record>> = all
        .iter()
        .map(|by_seed| median_over_seeds(by_seed, &m.checkpoints))
        .collect();
    let png_path = args.out.join("convergence.png");
    let title = format!(
        "{} at {width} x {height}",
        args.scene.file_name().unwrap_or_default().to_string_lossy()
    );
    let title = if seeds.len() > 1 {
        format!("{title}, median of {} seeds", seeds.len())
    } else {
        title
    };
    chart::draw_convergence(&png_path, &title, &medians, reference.is_some())
        .map_err(|e| anyhow!("{}: cannot draw the plot: {e}", png_path.display()))?;
    print!(
        "{}",
        summary(&all, &medians, &m.checkpoints, reference.is_some())
    );
    eprintln!("wrote {} and {}", csv_path.display(), png_path.display());
    Ok(())
}

fn write_csv(path: &Path, all: &[Vec<Vec<Record>>]) -> anyhow::Result<()> {
    let mut w = csv::Writer::from_path(path)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    for r in all.iter().flatten().flatten() {
        w.serialize(r)
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    w.flush()
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// The table printed at the end: per run, its last record and fitted slope from `medians`
/// (`median_over_seeds` of each run's records in `all`), with the range of the seeds' last
/// errors when there are several; then the winner at each decade of time (and at the end).
pub fn summary(
    all: &[Vec<Vec<Record>>],
    medians: &[Vec<Record>],
    checkpoints: &[f64],
    have_reference: bool,
) -> String {
    let what = if have_reference {
        "relMSE"
    } else {
        "estimated relMSE"
    };
    let several = all.iter().any(|by_seed| by_seed.len() > 1);
    let width = medians
        .iter()
        .filter_map(|r| r.first())
        .map(|r| r.run.len())
        .max()
        .unwrap_or(3)
        .max(3);
    let mut out = format!(
        "{:<width$} {:>8} {:>9} {:>12} {:>12} {:>8} {:>7}",
        "run", "seconds", "passes", "relMSE", "estimated", "est/true", "slope"
    );
    if several {
        out += &format!(" {:>21}", "seeds' range");
    }
    out += "\n";
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3e}"));
    for (records, by_seed) in medians.iter().zip(all) {
        let Some(last) = records.last() else { continue };
        let lasts: Vec<&Record> = by_seed.iter().filter_map(|r| r.last()).collect();
        let ratios: Option<Vec<f64>> = lasts
            .iter()
            .map(|r| match (r.estimated_rel_mse, r.rel_mse) {
                (Some(e), Some(t)) if t > 0.0 => Some(e / t),
                _ => None,
            })
            .collect();
        let ratio = ratios
            .and_then(median)
            .map_or("-".into(), |r| format!("{r:.2}"));
        let from = (last.seconds / 10.0).min(1.0);
        out += &format!(
            "{:<width$} {:>8.1} {:>9} {:>12} {:>12} {:>8} {:>7}",
            last.run,
            last.seconds,
            last.passes,
            fmt(last.rel_mse),
            fmt(last.estimated_rel_mse),
            ratio,
            fitted_slope(records, from).map_or("-".into(), |s| format!("{s:.2}"))
        );
        if several {
            let errors: Vec<f64> = lasts.iter().filter_map(|r| r.error()).collect();
            let lo = errors.iter().copied().reduce(f64::min);
            let hi = errors.iter().copied().reduce(f64::max);
            out += &format!(" {:>21}", format!("{}..{}", fmt(lo), fmt(hi)));
        }
        out += "\n";
    }
    out += &format!("lowest {what}:\n");
    let mut shown = Vec::new();
    for &t in checkpoints {
        // One line a decade, and the last checkpoint.
        let decade = t.log10().floor();
        if shown.contains(&decade) && t != *checkpoints.last().unwrap_or(&t) {
            continue;
        }
        shown.push(decade);
        if let Some((i, e)) = winner_at(medians, t) {
            out += &format!("  at {t:>8.2} s: {} ({e:.3e})\n", medians[i][0].run);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweeps_expand_per_integrator_and_bad_ones_are_refused() {
        let runs = runs(
            &["pt".into(), "sppm".into()],
            &["alpha=0.5,1".into(), "max-depth=5".into()],
        )
        .unwrap();
        let labels: Vec<String> = runs.iter().map(RunSpec::label).collect();
        assert_eq!(
            labels,
            [
                "pt max_depth=5",
                "sppm alpha=0.5 max_depth=5",
                "sppm alpha=1 max_depth=5"
            ]
        );
        assert!(super::runs(&["pt".into()], &["alpha=0.5".into()]).is_err());
        assert!(super::runs(&["sppm".into()], &["alpha=2".into()]).is_err());
        assert!(super::runs(&["sppm".into()], &["alpha".into()]).is_err());
        assert!(super::runs(&["nope".into()], &[]).is_err());
        let r = super::runs(&["recommended".into()], &[]).unwrap();
        assert!(r[0].recommended);
    }

    #[test]
    fn seeds_reduce_to_their_median_at_each_checkpoint() {
        let rec = |seed: u64, t: f64, e: f64| Record {
            run: "mmlt".into(),
            integrator: "mmlt".into(),
            parameters: String::new(),
            seconds: t,
            passes: seed + 1,
            rel_mse: Some(e),
            rmse: None,
            estimated_rel_mse: Some(2.0 * e),
            estimated_bias_rel_mse: None,
            seed,
        };
        let by_seed = vec![
            vec![rec(0, 1.0, 4.0), rec(0, 10.0, 1.0)],
            vec![rec(1, 1.1, 8.0), rec(1, 10.0, 3.0)],
            vec![rec(2, 1.2, 2.0), rec(2, 10.1, 0.5)],
        ];
        // Nobody reached 0.5 s before 1 s: the first checkpoint's records are the first ones.
        let m = median_over_seeds(&by_seed, &[0.5, 1.0, 10.0]);
        assert_eq!(m.len(), 2, "{m:?}");
        assert_eq!(
            (m[0].seconds, m[0].rel_mse, m[0].passes),
            (1.1, Some(4.0), 2)
        );
        assert_eq!(
            (m[1].rel_mse, m[1].estimated_rel_mse),
            (Some(1.0), Some(2.0))
        );
        // A checkpoint one seed never reached is left out.
        assert_eq!(median_over_seeds(&by_seed, &[10.05]).len(), 0);
        assert_eq!(median(vec![3.0, 1.0, 2.0, 10.0]), Some(2.5));
        let table = summary(&[by_seed], &[m], &[1.0, 10.0], true);
        assert!(table.contains("5.000e-1..3.000e0"), "{table}");
    }
}
