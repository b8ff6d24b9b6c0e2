//! `caustica info`: what a scene holds, what light transport it has, which estimators can
//! render it and which one to use, with the command line that does.

use caustica_renderer::advisor;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene to examine (.gltf or .glb).
    pub scene: PathBuf,
    #[command(flatten)]
    pub size: crate::render::SizeArgs,
    #[command(flatten)]
    pub scene_flags: crate::scene_flags::SceneFlags,
}

pub fn run(args: &InfoArgs) -> Result<(), crate::render::Failure> {
    let scene = args.scene_flags.load(&args.scene)?;
    let (width, height) = args.size.resolve(scene.camera.aspect);
    let started = Instant::now();
    let (s, r) = advisor::analyse(&scene, width, height);
    let i = &scene.info;
    println!("{}", args.scene.display());
    println!(
        "  {} triangles, {} lights ({:.0} % of their power in point, spot or directional lights), {}",
        i.triangles,
        i.lights,
        100.0 * s.delta_light_power + 0.0,
        if i.default_camera {
            "a default camera"
        } else {
            "the file's camera"
        }
    );
    println!("  environment: {}", i.lighting);
    for w in &i.warnings {
        println!("  warning: {w}");
    }
    println!(
        "light transport ({} camera and {} light paths in {:.0} ms, at {width} x {height}):",
        s.camera_paths,
        s.light_paths,
        started.elapsed().as_secs_f64() * 1e3
    );
    let pct = |x: f64| format!("{:5.1} %", 100.0 * x);
    println!("  {} of the view is background", pct(s.background));
    println!(
        "  {} of the surfaces seen are seen through specular ones (glass, mirrors)",
        pct(s.seen_through_specular)
    );
    println!("  {} of the surfaces seen are glossy", pct(s.glossy));
    println!(
        "  {} of the surfaces seen have a light in direct view",
        pct(s.directly_lit)
    );
    println!(
        "  {} of the light reaching diffuse or glossy surfaces is caustic (passed a specular surface), {} from point, spot or directional lights",
        pct(s.caustic_flux),
        pct(s.delta_caustic_flux).trim()
    );
    println!(
        "  {} of the light reaching the surfaces the camera sees (directly or through specular ones) is caustic; they get {} of the light",
        pct(s.seen_caustic_flux),
        pct(s.seen_flux).trim()
    );
    for (name, why) in &r.cannot_converge {
        println!("cannot converge: {name}: {why}");
    }
    println!("recommended: {}", r.integrator);
    for reason in &r.reasons {
        println!("  {reason}");
    }
    let mut command = format!(
        "caustica render {} -o out.exr --integrator {} --width {width} --height {height}",
        args.scene.display(),
        r.integrator
    );
    for (k, v) in &r.params {
        command += &format!(" --{} {}", k.replace('_', "-"), format_value(*v));
    }
    println!("  {command}");
    let reference = s.reference(width, height, &scene.camera);
    println!(
        "a reference image (caustica reference) renders with {}",
        reference.integrator
    );
    Ok(())
}

/// A parameter value as a flag takes it: whole numbers without a fraction, others to four
/// significant digits.
pub fn format_value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.4e}")
            .parse::<f64>()
            .map_or(v.to_string(), |x| x.to_string())
    }
}
