//! MMLT's parameters (the registry's entries) and the settings read from them.

use crate::integrators::{ParamSpec, ParamValues};

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub struct MmltSettings {
    #[serde(rename = "large_step")]
    pub large_step_prob: f64,
    pub sigma: f64,
    /// Bootstrap samples per path length.
    pub bootstrap: u64,
    pub chains: u64,
    /// Longest path, in bounces.
    pub max_depth: u32,
}

impl MmltSettings {
    pub const PARAMS: &'static [ParamSpec] = &[
        ParamSpec::new(
            "large_step",
            "Probability of a large step (every coordinate drawn anew). 1 is an independent sampler; 0 is valid but chains can stick.",
            0.3,
            (0.0, 1.0),
        )
        .live(),
        ParamSpec::new(
            "sigma",
            "Standard deviation of a small step in primary sample space (Kelemen et al. 2002).",
            0.01,
            (1e-5, 1.0),
        )
        .live(),
        ParamSpec::new(
            "bootstrap",
            "Independent samples per path length that estimate the normalisation and seed the chains.",
            100_000.0,
            (1.0, 1e8),
        )
        .integer(),
        ParamSpec::new(
            "chains",
            "Number of Markov chains.",
            1000.0,
            (1.0, 1e6),
        )
        .integer(),
        ParamSpec::new(
            "max_depth",
            "Longest path, in bounces. Paths of 0 and 1 bounce are path traced; each longer length up to 9 has its own chains, and the lengths from 10 on share one family, which visits the shorter ones more often.",
            64.0,
            (0.0, 64.0),
        )
        .integer(),
    ];

    pub fn from_params(p: &ParamValues) -> Self {
        crate::integrators::params::read_settings(Self::PARAMS, p)
    }
}

impl Default for MmltSettings {
    fn default() -> Self {
        Self::from_params(&ParamValues::new())
    }
}
