//! `caustica reference`: a converged image to measure against, rendered with the most robust
//! estimator for the scene (`TransportSurvey::reference`: the one `caustica info` recommends,
//! but unbiased wherever an unbiased one converges, so that photon mappers measured against
//! the reference do not find their own bias in it), its remaining error estimated and written
//! into the header (`caustica:estimated_relmse`), so a user knows how far it can be trusted.

use crate::param_flags::ParamFlags;
use caustica_renderer::survey;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    /// Scene to render (.gltf or .glb).
    pub scene: PathBuf,
    /// Output EXR.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Seconds to render.
    #[arg(long, value_parser = crate::render::parse_seconds)]
    pub time: f64,
    #[command(flatten)]
    pub size: crate::render::SizeArgs,
    #[command(flatten)]
    pub scene_flags: crate::scene_flags::SceneFlags,
    /// Seed (a reference for runs of seed 0 is best rendered with another).
    #[arg(long, default_value_t = 1_000_000)]
    pub seed: u64,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Write the run's statistics as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// Integrator with its defaults, in place of the one the scene's survey picks (for a
    /// scene whose best estimator the survey cannot yet tell).
    #[arg(long, value_parser = crate::render::integrator_names())]
    pub integrator: Option<String>,
}

pub fn run(args: &ReferenceArgs) -> Result<(), crate::render::Failure> {
    use crate::render::{Failure, RenderArgs};
    if !args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        return Err(Failure::Usage(format!(
            "--output {}: a reference is linear: the file name must end in .exr",
            args.output.display()
        )));
    }
    let scene = args.scene_flags.load(&args.scene)?;
    let (width, height) = args.size.resolve(scene.camera.aspect);
    let survey = survey::survey_at(&scene, width, height);
    let mut r = survey.reference(width, height, &scene.camera);
    match &args.integrator {
        Some(name) => {
            eprintln!(
                "reference with {name}: chosen by --integrator (the survey's: {})",
                r.integrator
            );
            r.params.clear();
        }
        None => eprintln!("reference with {}: {}", r.integrator, r.reasons.join("; ")),
    }
    let render = RenderArgs {
        scene: args.scene.clone(),
        output: args.output.clone(),
        integrator: args.integrator.clone().unwrap_or(r.integrator.to_string()),
        spp: None,
        time: Some(args.time),
        until_error: None,
        size: crate::render::SizeArgs {
            width: Some(width),
            height: Some(height),
        },
        seed: args.seed,
        threads: args.threads,
        params: ParamFlags {
            given: r.params.clone(),
        },
        stats: args.stats.clone(),
        exposure: crate::render::Exposure::Auto,
        scene_flags: args.scene_flags.clone(),
        camera_from: None,
        panic_in_pass: None,
        max_memory: None,
    };
    crate::render::run(&render)
}
