//! What the viewer remembers between runs (eframe storage): the render and display settings
//! and the recent scenes.

use caustica_renderer::exposure::EXPOSURE_RANGE;
use caustica_renderer::image::ToneCurve;
use caustica_renderer::integrators::{self, ParamValues};
use caustica_renderer::session::MAX_RESOLUTION;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

pub const STORAGE_KEY: &str = "caustica-viewer";
const MAX_RECENT: usize = 10;
/// The most worker threads the viewer starts (a stored value beyond it is someone else's).
pub const MAX_THREADS: usize = 1024;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewerSettings {
    pub integrator: String,
    /// Values of the current integrator's parameters.
    pub params: ParamValues,
    pub width: u32,
    pub height: u32,
    /// Worker threads; 0 means one per core.
    pub threads: usize,
    pub seed: u64,
    pub exposure: f32,
    /// Set the exposure from the first frame of each scene opened (`exposure::auto_exposure`);
    /// off once the user moves the exposure.
    pub auto_exposure: bool,
    pub tone_curve: ToneCurve,
    pub recent_scenes: Vec<PathBuf>,
    pub show_plots: bool,
    /// Lay the estimated-error heat map over the image.
    pub show_error_map: bool,
    /// What lights scenes from outside: `auto`, `none`, `uniform`, `studio` or an image file
    /// (`EnvironmentSettings::resolve` reads it).
    pub environment: String,
    pub environment_strength: f32,
    /// Degrees about +Y.
    pub environment_rotation: f32,
    /// The last view the user moved to and its scene (the camera as the EXR header's JSON),
    /// restored when that scene is opened again.
    pub view: Option<(PathBuf, String)>,
}

impl Default for ViewerSettings {
    fn default() -> Self {
        let pt = integrators::registry()[0].name.to_string();
        ViewerSettings {
            params: Self::defaults_of(&pt),
            integrator: pt,
            width: 640,
            height: 480,
            threads: 0,
            seed: 0,
            exposure: 0.0,
            auto_exposure: true,
            tone_curve: ToneCurve::Linear,
            recent_scenes: Vec::new(),
            show_plots: true,
            show_error_map: false,
            environment: "auto".into(),
            environment_strength: 1.0,
            environment_rotation: 0.0,
            view: None,
        }
    }
}

impl ViewerSettings {
    pub fn defaults_of(integrator: &str) -> ParamValues {
        integrators::find(integrator)
            .map(|info| {
                info.params
                    .iter()
                    .map(|p| (p.name.to_string(), p.default))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Repairs settings read from an older or foreign store: unknown integrator, parameters
    /// out of range, absurd sizes.
    pub fn sanitized(mut self) -> Self {
        let Some(info) = integrators::find(&self.integrator) else {
            return ViewerSettings {
                recent_scenes: self.recent_scenes,
                ..Default::default()
            };
        };
        self.params = integrators::resolve_params(info, &self.params)
            .unwrap_or_else(|_| Self::defaults_of(&self.integrator));
        self.width = self.width.clamp(1, MAX_RESOLUTION);
        self.height = self.height.clamp(1, MAX_RESOLUTION);
        self.threads = self.threads.min(MAX_THREADS);
        self.recent_scenes.truncate(MAX_RECENT);
        self.exposure = if self.exposure.is_finite() {
            self.exposure.clamp(-EXPOSURE_RANGE, EXPOSURE_RANGE)
        } else {
            0.0
        };
        if !(self.environment_strength.is_finite() && self.environment_strength >= 0.0) {
            self.environment_strength = 1.0;
        }
        if !self.environment_rotation.is_finite() {
            self.environment_rotation = 0.0;
        }
        if self.environment.is_empty() {
            self.environment = "auto".into();
        }
        self
    }

    pub fn remember_scene(&mut self, path: PathBuf) {
        self.recent_scenes.retain(|p| p != &path);
        self.recent_scenes.insert(0, path);
        self.recent_scenes.truncate(MAX_RECENT);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn settings_survive_a_round_trip_and_bad_stores_are_repaired() {
        let mut s = ViewerSettings {
            exposure: 1.5,
            tone_curve: ToneCurve::Filmic,
            width: 320,
            ..Default::default()
        };
        s.remember_scene(PathBuf::from("a.gltf"));
        s.remember_scene(PathBuf::from("b.gltf"));
        s.remember_scene(PathBuf::from("a.gltf"));
        assert_eq!(
            s.recent_scenes,
            vec![PathBuf::from("a.gltf"), PathBuf::from("b.gltf")]
        );
        let text = serde_json::to_string(&s).unwrap();
        let back: ViewerSettings = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);

        let mut bad = s.clone();
        bad.integrator = "gone".into();
        assert_eq!(bad.sanitized().integrator, "pt");
        let mut bad = s.clone();
        bad.params.insert("max_depth".into(), 1e9);
        bad.exposure = f32::NAN;
        bad.environment_strength = -1.0;
        bad.environment_rotation = f32::INFINITY;
        let fixed = bad.sanitized();
        assert_eq!(fixed.params["max_depth"], 64.0);
        assert_eq!(fixed.exposure, 0.0);
        assert_eq!(
            (fixed.environment_strength, fixed.environment_rotation),
            (1.0, 0.0)
        );
    }

    /// What a sanitized store always satisfies, whatever the file said.
    fn assert_usable(s: &ViewerSettings, what: &str) {
        let info = integrators::find(&s.integrator).unwrap_or_else(|| panic!("{what}"));
        integrators::resolve_params(info, &s.params).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!((1..=MAX_RESOLUTION).contains(&s.width), "{what}");
        assert!((1..=MAX_RESOLUTION).contains(&s.height), "{what}");
        assert!(s.threads <= MAX_THREADS, "{what}");
        assert!(s.recent_scenes.len() <= MAX_RECENT, "{what}");
        assert!(s.exposure.abs() <= EXPOSURE_RANGE, "{what}");
        assert!(s.environment_strength.is_finite() && s.environment_strength >= 0.0);
        assert!(s.environment_rotation.is_finite(), "{what}");
        assert!(!s.environment.is_empty(), "{what}");
    }

    /// A structured mutation loop over the settings file (the stable stand-in for fuzzing a
    /// serde struct): every field, and a parameter, set to each of a set of hostile values
    /// (wrong types, negative, zero, huge, an enormous list, an unknown name). Each store
    /// either fails to parse (the viewer then starts from the defaults) or is sanitized into
    /// settings the viewer can start a session with.
    #[test]
    fn hostile_settings_files_are_refused_or_repaired() {
        let long_list: Vec<String> = (0..10_000).map(|i| format!("scene-{i}.gltf")).collect();
        let hostile = [
            json!(null),
            json!(-1),
            json!(0),
            json!(1),
            json!(1e300),
            json!(-1e300),
            json!(u64::MAX),
            json!(i64::MIN),
            json!(0.5),
            json!("sppm"),
            json!("no-such-thing"),
            json!(""),
            json!(true),
            json!([]),
            json!({}),
            json!(long_list),
            json!(["a.gltf", "{\"position\": [1e30, 0, 0]}"]),
        ];
        let base = serde_json::to_value(ViewerSettings::default()).unwrap();
        let fields: Vec<String> = base.as_object().unwrap().keys().cloned().collect();
        let (mut parsed, mut refused) = (0, 0);
        for field in &fields {
            for value in &hostile {
                let mut v = base.clone();
                v[field.as_str()] = value.clone();
                let what = format!("{field} = {value:.40}");
                match serde_json::from_value::<ViewerSettings>(v) {
                    Ok(s) => {
                        assert_usable(&s.sanitized(), &what);
                        parsed += 1;
                    }
                    Err(_) => refused += 1,
                }
            }
        }
        for integrator in integrators::registry() {
            for spec in integrator.params {
                for value in [-1e300, -1.0, 0.0, 1e300, f64::NAN, f64::INFINITY] {
                    let mut s = ViewerSettings {
                        integrator: integrator.name.into(),
                        params: ViewerSettings::defaults_of(integrator.name),
                        ..Default::default()
                    };
                    s.params.insert(spec.name.into(), value);
                    s.params.insert("no_such_parameter".into(), 1.0);
                    assert_usable(&s.sanitized(), &format!("{}: {value}", spec.name));
                    parsed += 1;
                }
            }
        }
        assert!(
            parsed > 100 && refused > 100,
            "{parsed} parsed, {refused} refused"
        );
    }
}
