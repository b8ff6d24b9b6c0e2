//! Caustica's command line: `caustica [SCENE]` opens the viewer (on that scene, rendering at
//! once); `caustica render` renders a scene headless to EXR or PNG.
//!
//! Exit codes: 0 success, 1 runtime error (unreadable or invalid scene, unwritable output,
//! no window), 2 bad arguments. Each error is one line naming the file or argument.

mod converge;
mod info;
mod merge;
mod param_flags;
mod reference;
mod render;
mod scene_flags;

use caustica::viewer::{self, Automation, ViewerOptions};
use caustica_renderer::session::MAX_RESOLUTION;
use clap::{CommandFactory, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "caustica",
    version,
    about = "Interactive viewer for progressive, physically based light transport",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Scene to open in the viewer (.gltf or .glb); rendering starts at once.
    scene: Option<PathBuf>,
    /// Reference image (EXR) for the viewer's convergence plot.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Integrator in the viewer (otherwise the remembered one).
    #[arg(long, value_parser = render::integrator_names())]
    integrator: Option<String>,
    /// Render width in the viewer (otherwise the remembered one).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    width: Option<u32>,
    /// Render height in the viewer (otherwise the remembered one).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RESOLUTION)))]
    height: Option<u32>,
    /// Window size in logical points, WIDTHxHEIGHT (otherwise the remembered one, at first
    /// 1280x800).
    #[arg(long, value_parser = parse_window_size)]
    window_size: Option<[f32; 2]>,
    /// Save a screenshot of the window to this PNG once the render has been shown for
    /// --screenshot-after seconds, then quit (for scripted runs).
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Seconds of rendering before --screenshot is taken.
    #[arg(long, default_value_t = 3.0, requires = "screenshot")]
    screenshot_after: f64,
    /// With --screenshot: redraw continuously meanwhile, as while the user drags a slider
    /// (to measure the UI frame rate the render leaves).
    #[arg(long, requires = "screenshot")]
    animate: bool,
    #[command(flatten)]
    limits: scene_flags::LimitFlags,
    /// Memory the integrator's buffers may take, in bytes or with a suffix K, M, G (binary)
    /// [default: what the system has available].
    #[arg(long, value_name = "BYTES", value_parser = render::parse_bytes)]
    max_memory: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a glTF scene without a window and write the image (EXR or PNG).
    Render(render::RenderArgs),
    /// Measure error against time for integrators and parameter values on one scene.
    Converge(converge::ConvergeArgs),
    /// Combine independent runs (other seeds) of one scene into one image, weighted by passes.
    Merge(merge::MergeArgs),
    /// Describe a scene's light transport and recommend the estimator it needs.
    Info(info::InfoArgs),
    /// Render a reference image with the estimator the scene needs, its error in the header.
    Reference(reference::ReferenceArgs),
}

/// Exit code and message of a subcommand's outcome: bad arguments the way clap reports them
/// (exit code 2), runtime errors as one line (exit code 1).
fn finish(subcommand: &str, result: Result<(), render::Failure>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(render::Failure::Usage(msg)) => {
            let cmd = Cli::command();
            let mut sub = cmd
                .find_subcommand(subcommand)
                .cloned()
                .unwrap_or(cmd)
                .bin_name(format!("caustica {subcommand}"));
            sub.error(clap::error::ErrorKind::ValueValidation, msg)
                .exit()
        }
        Err(render::Failure::Runtime(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn parse_window_size(text: &str) -> Result<[f32; 2], String> {
    let parsed = text
        .split_once('x')
        .and_then(|(w, h)| Some([w.parse::<u16>().ok()?, h.parse::<u16>().ok()?]))
        .filter(|[w, h]| *w >= 200 && *h >= 150);
    parsed
        .map(|[w, h]| [f32::from(w), f32::from(h)])
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT with both at least 200x150"))
}

fn main() -> ExitCode {
    let launched = std::time::Instant::now();
    let cli = Cli::parse();
    match cli.command {
        Some(Command::Render(args)) => finish("render", render::run(&args)),
        Some(Command::Converge(args)) => finish("converge", converge::run(&args)),
        Some(Command::Merge(args)) => finish("merge", merge::run(&args)),
        Some(Command::Info(args)) => finish("info", info::run(&args)),
        Some(Command::Reference(args)) => finish("reference", reference::run(&args)),
        None => {
            let automation = cli.screenshot.map(|screenshot| Automation {
                screenshot,
                after: Duration::from_secs_f64(cli.screenshot_after.max(0.0)),
                continuous: cli.animate,
            });
            let options = ViewerOptions {
                scene: cli.scene,
                reference: cli.reference,
                integrator: cli.integrator,
                width: cli.width,
                height: cli.height,
                window_size: cli.window_size,
                launched: Some(launched),
                automation,
                limits: cli.limits.limits(),
                memory_limit: cli.max_memory,
            };
            match viewer::run(options) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: cannot open the viewer window: {e}");
                    ExitCode::from(1)
                }
            }
        }
    }
}
