//! Integrator parameters: each described once (`ParamSpec`), checked once (`resolve_params`
//! for a new run, `check_param` for a live change); integrators read the checked values.

use super::IntegratorInfo;
use std::collections::BTreeMap;

/// One parameter of an integrator.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub doc: &'static str,
    pub default: f64,
    pub min: f64,
    pub max: f64,
    pub integer: bool,
    /// Changes apply to the passes still to come without a restart.
    pub live: bool,
    /// 0 asks the integrator to choose the value; the value it chose is its
    /// `Integrator::automatic` of this name.
    pub zero_is_automatic: bool,
}

impl ParamSpec {
    /// A real-valued parameter fixed for a run, with its default and range `(min, max)`.
    pub const fn new(
        name: &'static str,
        doc: &'static str,
        default: f64,
        range: (f64, f64),
    ) -> Self {
        ParamSpec {
            name,
            doc,
            default,
            min: range.0,
            max: range.1,
            integer: false,
            live: false,
            zero_is_automatic: false,
        }
    }

    /// The same parameter, where 0 lets the integrator choose.
    pub const fn automatic_at_zero(self) -> Self {
        ParamSpec {
            zero_is_automatic: true,
            ..self
        }
    }

    /// The same parameter, taking whole numbers only.
    pub const fn integer(self) -> Self {
        ParamSpec {
            integer: true,
            ..self
        }
    }

    /// The same parameter, changeable while rendering.
    pub const fn live(self) -> Self {
        ParamSpec { live: true, ..self }
    }
}

pub type ParamValues = BTreeMap<String, f64>;

/// Parameter values for `info`: defaults overridden by `given`, each checked against its range.
pub fn resolve_params(info: &IntegratorInfo, given: &ParamValues) -> Result<ParamValues, String> {
    for name in given.keys() {
        if !info.params.iter().any(|p| p.name == name) {
            let known: Vec<_> = info.params.iter().map(|p| p.name).collect();
            return Err(format!(
                "integrator '{}' has no parameter '{name}' (it has: {})",
                info.name,
                known.join(", ")
            ));
        }
    }
    let mut values = ParamValues::new();
    for p in info.params {
        let v = given.get(p.name).copied().unwrap_or(p.default);
        check_param(p, v)?;
        values.insert(p.name.to_string(), v);
    }
    Ok(values)
}

/// The value of parameter `name` for an integrator whose parameters are `specs`: from
/// `values`, which `resolve_params` has checked, else the default. The integrators read their
/// settings through this and trust the range (a debug build asserts it), so each range is
/// written once, in the `ParamSpec`.
pub fn param_value(specs: &[ParamSpec], values: &ParamValues, name: &str) -> f64 {
    let spec = specs.iter().find(|s| s.name == name);
    debug_assert!(spec.is_some(), "no parameter '{name}'");
    let value = values
        .get(name)
        .copied()
        .unwrap_or_else(|| spec.map_or(0.0, |s| s.default));
    debug_assert!(
        spec.is_none_or(|s| check_param(s, value).is_ok()),
        "{name} = {value} was not checked against its range"
    );
    value
}

/// An integrator's settings read from checked `values`, defaults filling the gaps: the
/// fields of `T` are named as its parameters (or renamed to them with `#[serde(rename)]`),
/// whole-number parameters land in integer fields, and fields that are no parameter are
/// `#[serde(skip)]`. So a new parameter is a `ParamSpec` and a field, nothing else.
pub fn read_settings<T: serde::de::DeserializeOwned>(
    specs: &[ParamSpec],
    values: &ParamValues,
) -> T {
    let fields = specs
        .iter()
        .map(|s| {
            let v = param_value(specs, values, s.name);
            let value = if s.integer {
                serde_json::Value::from(v as i64)
            } else {
                serde_json::Value::from(v)
            };
            (s.name.to_string(), value)
        })
        .collect();
    serde_json::from_value(serde_json::Value::Object(fields))
        .expect("an integrator's settings fields match its ParamSpecs")
}

/// Checks a change of parameter `name` to `value` while `info` renders: the parameter must
/// exist, be live and be in range. The session applies only what passes.
pub fn check_live_change(info: &IntegratorInfo, name: &str, value: f64) -> Result<(), String> {
    let spec = info
        .params
        .iter()
        .find(|p| p.name == name)
        .ok_or_else(|| format!("integrator '{}' has no parameter '{name}'", info.name))?;
    if !spec.live {
        return Err(format!(
            "{name} cannot change while rendering: restart the session"
        ));
    }
    check_param(spec, value)
}

/// `max_depth` of the path tracer and the bidirectional one, which read it alike.
pub const MAX_DEPTH: ParamSpec = ParamSpec::new(
    "max_depth",
    "Maximum number of bounces of a path; Russian roulette ends most paths earlier.",
    64.0,
    (0.0, 1024.0),
)
.integer();

/// Checks `v` against `p`'s range and, for a whole-number parameter, that it is whole.
pub fn check_param(p: &ParamSpec, v: f64) -> Result<(), String> {
    if !v.is_finite() || v < p.min || v > p.max {
        return Err(format!(
            "{} = {v} is outside its range [{}, {}]",
            p.name, p.min, p.max
        ));
    }
    if p.integer && v.fract() != 0.0 {
        return Err(format!("{} = {v} must be a whole number", p.name));
    }
    Ok(())
}

/// Parameters as a JSON object, for EXR headers and logs.
pub fn params_json(values: &ParamValues) -> String {
    let map: serde_json::Map<String, serde_json::Value> = values
        .iter()
        .map(|(k, v)| (k.clone(), serde_json::json!(v)))
        .collect();
    serde_json::Value::Object(map).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::{bdpt, mmlt, path_tracer, ppm};

    /// Every parameter at its minimum, then at its maximum.
    fn extremes(specs: &[ParamSpec]) -> [ParamValues; 2] {
        let at = |f: fn(&ParamSpec) -> f64| specs.iter().map(|s| (s.name.into(), f(s))).collect();
        [at(|s| s.min), at(|s| s.max)]
    }

    /// `read_settings` puts each parameter in its field, whole numbers in integer fields,
    /// renamed fields included: a field that does not match its `ParamSpec` panics here.
    #[test]
    fn settings_read_every_parameter_into_its_field() {
        let [lo, hi] = extremes(mmlt::MmltSettings::PARAMS);
        let (a, b) = (
            mmlt::MmltSettings::from_params(&lo),
            mmlt::MmltSettings::from_params(&hi),
        );
        assert_eq!(
            (a.large_step_prob, a.sigma, a.bootstrap, a.chains),
            (0.0, 1e-5, 1, 1)
        );
        assert_eq!((b.large_step_prob, b.max_depth), (1.0, 64));
        let [lo, hi] = extremes(ppm::PhotonMappingSettings::PARAMS);
        let p = ppm::PhotonMappingSettings::from_params(&hi);
        assert_eq!(
            (p.alpha, p.radius, p.photons, p.max_depth),
            (1.0, 1e6, 10_000_000, 1024)
        );
        assert_eq!(ppm::PhotonMappingSettings::from_params(&lo).alpha, 1e-3);
        let [lo, _] = extremes(path_tracer::PathSettings::PARAMS);
        let pt = path_tracer::PathSettings::from_params(&lo);
        assert_eq!((pt.max_depth, pt.rr_depth), (0, 0));
        assert_eq!(path_tracer::PathSettings::default().rr_depth, 1);
        let bdpt = bdpt::BdptSettings::from_params(&ParamValues::new());
        assert_eq!((bdpt.max_depth, bdpt.only_strategy), (64, None));
    }
}
