//! What lights a scene from outside: the environment the user chose, or the one the
//! default-lighting rule gives (`own_lighting`), set at build time and replaceable later
//! (`Scene::with_environment`) without rebuilding the geometry or its BVH.

use crate::geometry::luminance;
use crate::light::Light;
use crate::light::environment::{
    Environment, EnvironmentChoice, EnvironmentRadiance, EnvironmentSettings,
};
use crate::light::sampler::PowerLightSampler;
use crate::light::studio::studio;
use crate::scene::Scene;
use glam::Vec3;
use std::collections::HashMap;

impl Scene {
    /// The same scene lit from outside by `settings`: geometry, materials and BVH are copied,
    /// not rebuilt.
    pub fn with_environment(&self, settings: EnvironmentSettings) -> Scene {
        let mut scene = self.clone();
        scene.set_environment(settings);
        scene
    }

    /// Replaces the environment (always the last light) and what the scene's info says of it.
    pub(crate) fn set_environment(&mut self, settings: EnvironmentSettings) {
        if let Some(i) = self.environment.take() {
            self.lights.truncate(i);
        }
        self.info
            .warnings
            .truncate(self.info.environment_warnings_from);
        let surface_area: f32 = self
            .positions
            .iter()
            .map(|p| 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length())
            .sum();
        let own = own_lighting(&self.lights, surface_area);
        let EnvironmentSettings {
            choice,
            strength,
            rotation_degrees,
        } = settings;
        let auto = matches!(choice, EnvironmentChoice::Auto);
        let mut warnings = Vec::new();
        let radiance = match choice {
            EnvironmentChoice::Auto if own.lit => None,
            EnvironmentChoice::Auto | EnvironmentChoice::Studio => {
                Some(EnvironmentRadiance::Map(studio()))
            }
            EnvironmentChoice::None => None,
            EnvironmentChoice::Uniform => Some(EnvironmentRadiance::Uniform(Vec3::ONE)),
            EnvironmentChoice::Map(map) => {
                warnings.extend(map.aspect_warning());
                Some(EnvironmentRadiance::Map(map))
            }
        };
        let mut lighting = match &radiance {
            None => "none".to_string(),
            Some(EnvironmentRadiance::Uniform(_)) => "uniform".to_string(),
            Some(EnvironmentRadiance::Map(map)) => map.name.clone(),
        };
        if radiance.is_some() && (strength != 1.0 || rotation_degrees != 0.0) {
            lighting += &format!(" (strength {strength}, rotation {rotation_degrees} degrees)");
        }
        if auto {
            lighting += &format!("; chosen by the default rule: {}", own.reason);
            if radiance.is_some() {
                warnings.push(format!(
                    "lit by the built-in studio environment ({}); --environment chooses another",
                    own.reason
                ));
            }
        }
        if let Some(radiance) = radiance
            && strength > 0.0
        {
            let (_, scene_radius) = self.bounds.bounding_sphere();
            self.environment = Some(self.lights.len());
            self.lights.push(Light::Environment(Environment::new(
                radiance,
                strength,
                rotation_degrees,
                scene_radius,
            )));
        }
        if self.lights.is_empty() {
            warnings.push("nothing lights the scene: the image will be black".to_string());
        }
        self.light_sampler = PowerLightSampler::new(&self.lights);
        self.info.lights = self.lights.len();
        self.info.lighting = lighting;
        // The enclosure warning is for the environment the user did not choose.
        self.info.default_environment = auto && self.environment.is_some();
        if self.info.default_environment
            && let Some(warning) = enclosure_warning(self)
        {
            warnings.push(warning);
        }
        self.info.warnings.extend(warnings);
    }
}

/// Whether a scene has its own lighting, and why.
struct OwnLighting {
    lit: bool,
    reason: String,
}

/// The radiosity, in units of radiance, below which a scene's emitters count as details (a
/// glowing screen, an indicator lamp, a bottle's label) rather than its lighting: 5 % of what
/// the studio gives a white surface facing up (radiance 1).
pub const OWN_LIGHTING_RADIOSITY: f32 = 0.05;

/// The default-lighting rule: a scene has its own lighting when it has a punctual light, or
/// when its emitters' power spread over all of its surface area would give a radiosity
/// B = Phi / (pi A) of at least `OWN_LIGHTING_RADIOSITY` (B is the radiance a white diffuse
/// scene would show lit by its emitters' first bounce, on average). A model meant to be lit by
/// its viewer has no light sources or only small emissive details, and gets the studio.
fn own_lighting(lights: &[Light], surface_area: f32) -> OwnLighting {
    let punctual = lights
        .iter()
        .filter(|l| !matches!(l, Light::Area(_)))
        .count();
    if punctual > 0 {
        return OwnLighting {
            lit: true,
            reason: format!("{punctual} punctual light(s)"),
        };
    }
    let flux: f32 = lights
        .iter()
        .map(|l| match l {
            Light::Area(a) => luminance(a.power()),
            _ => 0.0,
        })
        .sum();
    if flux <= 0.0 {
        return OwnLighting {
            lit: false,
            reason: "no light sources".into(),
        };
    }
    let radiosity = flux / (std::f32::consts::PI * surface_area.max(f32::MIN_POSITIVE));
    let lit = radiosity >= OWN_LIGHTING_RADIOSITY;
    OwnLighting {
        lit,
        reason: format!(
            "emitters' radiosity {radiosity:.3} {} {OWN_LIGHTING_RADIOSITY}: {}",
            if lit { "at least" } else { "below" },
            if lit {
                "their own lighting"
            } else {
                "emissive details"
            }
        ),
    }
}

/// Directions from the camera that must all meet a surface for it to count as enclosed.
const ENCLOSURE_RAYS: u32 = 256;

/// When the only light is the default environment, whose light comes from outside, and the
/// camera is enclosed (every one of `ENCLOSURE_RAYS` directions spread over the sphere meets
/// a surface: a skybox mesh, a closed room without lamps), no light reaches what it sees: the
/// image is black. Says so, naming the material most of those rays meet.
fn enclosure_warning(scene: &Scene) -> Option<String> {
    let eye = Vec3::from(scene.camera.camera_to_world.translation);
    let mut hits: HashMap<u32, u32> = HashMap::new();
    for i in 0..ENCLOSURE_RAYS {
        // A Fibonacci lattice: evenly spread, deterministic.
        let z = 1.0 - (2.0 * i as f32 + 1.0) / ENCLOSURE_RAYS as f32;
        let phi = i as f32 * std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let r = (1.0 - z * z).max(0.0).sqrt();
        let ray = crate::geometry::Ray::new(eye, Vec3::new(r * phi.cos(), r * phi.sin(), z));
        let si = scene.intersect(&ray)?;
        let material = scene.attributes[si.triangle as usize].material;
        *hits.entry(material).or_default() += 1;
    }
    let (&material, _) = hits
        .iter()
        .max_by_key(|(m, n)| (**n, std::cmp::Reverse(**m)))?;
    let name = &scene.materials[material as usize].name;
    Some(format!(
        "the camera is enclosed (every direction from it meets a surface, mostly material \
         '{name}') and the only light is the environment outside: the image will be \
         black; add a light inside or move the camera"
    ))
}
