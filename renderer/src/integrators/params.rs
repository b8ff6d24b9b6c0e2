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
pub const MAX_DEPTH: ParamSpec = ParamSpec {
    name: "max_depth",
    doc: "Maximum number of bounces of a path; Russian roulette ends most paths earlier.",
    default: 64.0,
    min: 0.0,
    max: 1024.0,
    integer: true,
    live: false,
};

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
