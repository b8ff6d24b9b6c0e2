//! The integrators Caustica offers, each with its name, description and parameters: the
//! command line, the viewer and the EXR header all read this one list.

use super::{Integrator, ParamSpec, ParamValues, RenderContext, bdpt, mmlt, path_tracer, ppm, vcm};

pub struct IntegratorInfo {
    pub name: &'static str,
    pub title: &'static str,
    pub description: &'static str,
    pub params: &'static [ParamSpec],
    pub create: fn(RenderContext, &ParamValues) -> Box<dyn Integrator>,
    /// Bytes of its buffers per pixel once it runs (`Integrator::memory_bytes` over the
    /// pixels, measured; a session checks it against the memory there is before it starts).
    pub bytes_per_pixel: u64,
}

/// Bytes an integrator's buffers take whatever the image size (MMLT's chains and bootstrap
/// are the most, about 1.5 MiB), beside `IntegratorInfo::bytes_per_pixel`.
pub const FIXED_BYTES: u64 = 16 << 20;

impl IntegratorInfo {
    /// The memory its buffers take at `width` x `height`, an upper bound.
    pub fn memory_bytes(&self, width: u32, height: u32) -> u64 {
        self.bytes_per_pixel * u64::from(width) * u64::from(height) + FIXED_BYTES
    }
}

static REGISTRY: &[IntegratorInfo] = &[
    IntegratorInfo {
        name: "pt",
        title: "Path tracer",
        description: "Unidirectional path tracing with next-event estimation and MIS (reference).",
        params: path_tracer::PathSettings::PARAMS,
        create: path_tracer::create,
        bytes_per_pixel: 84,
    },
    IntegratorInfo {
        name: "bdpt",
        title: "Bidirectional path tracer",
        description: "Veach 1997: camera and light subpaths joined by every strategy, balance-heuristic MIS.",
        params: bdpt::BdptSettings::PARAMS,
        create: bdpt::create,
        bytes_per_pixel: 84,
    },
    IntegratorInfo {
        name: "mmlt",
        title: "Multiplexed Metropolis light transport",
        description: "Hachisuka et al. 2014: Metropolis chains over primary samples and bidirectional techniques.",
        params: mmlt::MmltSettings::PARAMS,
        create: mmlt::create,
        bytes_per_pixel: 400,
    },
    IntegratorInfo {
        name: "ppm",
        title: "Progressive photon mapping",
        description: "Hachisuka et al. 2008: hit points from one eye pass, radii shrinking per hit point.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_ppm,
        bytes_per_pixel: 700,
    },
    IntegratorInfo {
        name: "sppm",
        title: "Stochastic progressive photon mapping",
        description: "Hachisuka & Jensen 2009: hit points re-traced every pass, statistics per pixel.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_sppm,
        bytes_per_pixel: 700,
    },
    IntegratorInfo {
        name: "pppm",
        title: "Probabilistic progressive photon mapping",
        description: "Knaus & Zwicker 2011: one global radius per pass, independent passes averaged.",
        params: ppm::PhotonMappingSettings::PARAMS,
        create: ppm::create_pppm,
        bytes_per_pixel: 700,
    },
    IntegratorInfo {
        name: "amcppm",
        title: "SPPM with Metropolis photon paths",
        description: "Hachisuka & Jensen 2011: photon paths from Markov chains whose target is their visibility to this pass's hit points.",
        params: ppm::PhotonMappingSettings::METROPOLIS_PARAMS,
        create: ppm::create_amcppm,
        bytes_per_pixel: 900,
    },
    IntegratorInfo {
        name: "vcm",
        title: "Vertex connection and merging",
        description: "Georgiev et al. 2012: bidirectional connections and photon merges in one estimator, one MIS.",
        params: vcm::VcmSettings::PARAMS,
        create: vcm::create,
        bytes_per_pixel: 1000,
    },
    IntegratorInfo {
        name: "amcvcm",
        title: "VCM with Metropolis light subpaths",
        description: "vcm whose light subpaths come from Markov chains whose target is their visibility to this pass's camera subpaths (Hachisuka & Jensen 2011's chains).",
        params: vcm::VcmSettings::METROPOLIS_PARAMS,
        create: vcm::create_amcvcm,
        bytes_per_pixel: 1200,
    },
    IntegratorInfo {
        name: "mvcm",
        title: "Metropolised bidirectional estimator",
        description: "Šik et al. 2016: vcm whose light subpaths come from a visibility chain and a contribution chain, combined by their MIS.",
        params: vcm::VcmSettings::METROPOLIS_PARAMS,
        create: vcm::create_mvcm,
        bytes_per_pixel: 1600,
    },
];

pub fn registry() -> &'static [IntegratorInfo] {
    REGISTRY
}

pub fn find(name: &str) -> Option<&'static IntegratorInfo> {
    REGISTRY.iter().find(|i| i.name == name)
}
