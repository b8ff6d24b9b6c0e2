//! The flags every command that loads a scene shares: what lights the scene from outside (how
//! strongly, turned how far about the up axis), and how much the file may ask for.

use anyhow::anyhow;
use caustica_renderer::light::environment::EnvironmentSettings;
use caustica_renderer::scene::limits::{
    DEFAULT_MAX_BUFFER_BYTES, DEFAULT_MAX_NODE_DEPTH, DEFAULT_MAX_TEXELS, DEFAULT_MAX_TRIANGLES,
    LoadLimits, MAX_NODE_DEPTH,
};
use caustica_renderer::scene::{Scene, gltf};
use clap::Args;
use std::path::Path;

#[derive(Args, Debug, Clone, Default)]
pub struct SceneFlags {
    /// What lights the scene from outside: `auto` (the built-in studio for a model meant to be
    /// lit by its viewer, nothing for a scene with its own lights; README says the rule),
    /// `none`, `uniform` (radiance 1 everywhere), `studio`, or an equirectangular .hdr or .exr
    /// image.
    #[arg(
        long,
        value_name = "auto|none|uniform|studio|FILE",
        default_value = "auto"
    )]
    pub environment: String,
    /// Multiplies the environment's radiance.
    #[arg(long, value_name = "S", default_value_t = 1.0, value_parser = parse_strength, allow_negative_numbers = true)]
    pub environment_strength: f32,
    /// Turns the environment about the up axis (+Y), counter-clockwise seen from above.
    #[arg(long, value_name = "DEGREES", default_value_t = 0.0, value_parser = parse_degrees, allow_negative_numbers = true)]
    pub environment_rotation: f32,
    #[command(flatten)]
    pub limits: LimitFlags,
}

/// What a scene file may ask for; a file over a limit is refused with a message naming it and
/// its flag. The defaults admit every model in common use.
#[derive(Args, Debug, Clone)]
pub struct LimitFlags {
    /// Texels one texture may declare (refused from its header, before decoding).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_TEXELS)]
    pub max_texels: u64,
    /// Bytes of the scene's buffers together.
    #[arg(long, value_name = "BYTES", default_value_t = DEFAULT_MAX_BUFFER_BYTES)]
    pub max_buffer_bytes: u64,
    /// Triangles in the scene, each instance of a mesh counted.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_TRIANGLES)]
    pub max_triangles: u64,
    /// Levels of the node hierarchy.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_NODE_DEPTH,
          value_parser = clap::value_parser!(u64).range(1..=MAX_NODE_DEPTH))]
    pub max_node_depth: u64,
}

impl Default for LimitFlags {
    fn default() -> Self {
        LimitFlags::from(LoadLimits::default())
    }
}

impl From<LoadLimits> for LimitFlags {
    fn from(l: LoadLimits) -> Self {
        LimitFlags {
            max_texels: l.max_texels,
            max_buffer_bytes: l.max_buffer_bytes,
            max_triangles: l.max_triangles,
            max_node_depth: l.max_node_depth,
        }
    }
}

impl LimitFlags {
    pub fn limits(&self) -> LoadLimits {
        LoadLimits {
            max_texels: self.max_texels,
            max_buffer_bytes: self.max_buffer_bytes,
            max_triangles: self.max_triangles,
            max_node_depth: self.max_node_depth,
        }
    }
}

impl SceneFlags {
    /// The settings, with an environment image read (an error names the file and the problem).
    pub fn settings(&self) -> anyhow::Result<EnvironmentSettings> {
        EnvironmentSettings::resolve(
            &self.environment,
            self.environment_strength,
            self.environment_rotation,
        )
        .map_err(|e| anyhow!(e))
    }

    /// Loads and builds `scene` lit as these flags say.
    pub fn load(&self, scene: &Path) -> anyhow::Result<Scene> {
        let settings = self.settings()?;
        gltf::load_with(scene, settings, &self.limits.limits()).map_err(|e| anyhow!(e))
    }
}

fn parse_strength(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a strength (a number, 0 or more)")),
    }
}

fn parse_degrees(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{s}' is not an angle in degrees")),
    }
}
