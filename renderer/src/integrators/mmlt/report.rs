//! What MMLT reports of its run: the technique histogram and acceptance rates the viewer
//! plots, the warnings it shows, and the counters `--stats` writes.

use super::{CHAINS_PER_START, Mmlt, Phase, chains_per_slot, histogram, path_sample};
use crate::integrators::{PlotKind, PlotSeries};
use glam::DVec3;

/// Technique (s, t) of path length k, as the plots name it. For k = 0 the only technique is
/// (0, 2) (see `path_sample`).
pub fn technique_name(k: usize, s: usize) -> String {
    if k == 0 {
        "s = 0, t = 2".to_string()
    } else {
        format!("s = {s}, t = {}", k + 2 - s)
    }
}

impl Mmlt {
    /// The share of pixels where some chain has splatted anything: where it is below the share
    /// of pixels that paths of 2 bounces or more reach, chains have not found the rest yet.
    pub fn chain_coverage(&self) -> f64 {
        let pixels = self.direct.width * self.direct.height;
        let reached = (0..pixels)
            .filter(|&i| self.group_splats.iter().any(|g| g[i] != DVec3::ZERO))
            .count();
        reached as f64 / pixels.max(1) as f64
    }

    /// The slots whose chains outnumber `CHAINS_PER_START` times the distinct paths they
    /// start from (`Bootstrap::effective_samples`), named for the user, e.g. "5 bounces
    /// (456 chains, about 10 paths)"; None if there are none.
    fn few_starts(&self) -> Option<String> {
        let Phase::Running {
            chains_per_length, ..
        } = &self.phase
        else {
            return None;
        };
        let max_depth = self.settings.max_depth as usize;
        let per_slot = chains_per_slot(chains_per_length);
        let few: Vec<String> = (0..self.bootstrap_effective.len())
            .filter_map(|k| {
                let chains = per_slot[k];
                let starts = self.bootstrap_effective[k];
                (chains as f64 > CHAINS_PER_START * starts).then(|| {
                    let lengths = path_sample::slot_lengths(k, max_depth);
                    let bounces = if lengths.start() == lengths.end() {
                        format!("{k} bounces")
                    } else {
                        format!("{} bounces and more", lengths.start())
                    };
                    let paths = if starts.round() == 1.0 {
                        "path"
                    } else {
                        "paths"
                    };
                    format!("{bounces} ({chains} chains, about {starts:.0} {paths})")
                })
            })
            .collect();
        (!few.is_empty()).then(|| few.join(", "))
    }

    /// The technique histogram per path length and the acceptance rates, for the viewer.
    pub(super) fn technique_plots(&self) -> Vec<PlotSeries> {
        let mut plots = Vec::new();
        for (k, l) in self.histogram.lengths.iter().enumerate() {
            let total: u64 = l.steps_in_technique.iter().sum();
            if total == 0 {
                continue;
            }
            plots.push(PlotSeries {
                plot: "Techniques".into(),
                name: format!("k = {k}"),
                kind: PlotKind::Bars,
                x_label: format!("s light vertices, t = {} - s camera vertices", k + 2),
                y_label: "share of steps".into(),
                points: l
                    .steps_in_technique
                    .iter()
                    .enumerate()
                    .map(|(s, &c)| [s as f64, c as f64 / total as f64])
                    .collect(),
                point_names: (0..l.steps_in_technique.len())
                    .map(|s| technique_name(k, s))
                    .collect(),
            });
        }
        let rates = |name: &str, f: fn(&histogram::LengthStats) -> f64| PlotSeries {
            plot: "Acceptance".into(),
            name: name.into(),
            kind: PlotKind::Line,
            x_label: "path length k".into(),
            y_label: "acceptance rate".into(),
            points: self
                .histogram
                .lengths
                .iter()
                .enumerate()
                .filter(|(_, l)| l.large.proposed + l.small.proposed > 0)
                .map(|(k, l)| [k as f64, f(l)])
                .collect(),
            point_names: Vec::new(),
        };
        if self.steps > 0 {
            plots.push(rates("large steps", |l| l.large.rate()));
            plots.push(rates("small steps", |l| l.small.rate()));
            plots.push(rates("technique changes", |l| l.technique_change.rate()));
        }
        plots
    }

    /// What the user should know of this run (`Integrator::messages`).
    pub(super) fn warnings(&self) -> Vec<String> {
        let mut m = Vec::new();
        if matches!(self.phase, Phase::Black) && !self.direct_lit {
            m.push("Nothing reaches the camera: every bootstrap path was black.".into());
        }
        if self.unsampled_share > 0.0 {
            m.push(format!(
                "{:.2} % of the image's energy is in path lengths no chain samples: use more chains.",
                100.0 * self.unsampled_share
            ));
        }
        if let Some(few) = self.few_starts() {
            m.push(format!(
                "Chains start on few distinct paths at {few}: that light stays blotchy until \
                 the chains spread; a larger --bootstrap gives them more starts."
            ));
        }
        if self.settings.large_step_prob == 0.0 {
            m.push(
                "Large-step probability 0: chains never jump and can stick in one region.".into(),
            );
        }
        m
    }

    /// The run's counters for `--stats` (`Integrator::statistics`).
    pub(super) fn statistics_json(&self) -> serde_json::Value {
        let mut v = self.histogram.to_json();
        v["normalisation_b"] = serde_json::json!(self.normalisation());
        v["bootstrap_b_per_length"] = serde_json::json!(self.bootstrap_per_length);
        v["bootstrap_b_per_path_length"] = serde_json::json!(self.bootstrap_per_path_length);
        v["normalisation_standard_error"] = serde_json::json!(self.b_standard_error);
        v["share_of_b_without_chains"] = serde_json::json!(self.unsampled_share);
        v["chains"] = serde_json::json!(self.settings.chains);
        v["seconds"] = serde_json::json!(self.seconds);
        if let Phase::Running {
            chains_per_length,
            b_sum,
            b_count,
            ..
        } = &self.phase
        {
            let chains = chains_per_slot(chains_per_length);
            let b: Vec<f64> = b_sum
                .iter()
                .zip(b_count)
                .map(|(s, &n)| s / n.max(1) as f64)
                .collect();
            v["chains_per_slot"] = serde_json::json!(chains);
            v["bootstrap_lit_per_slot"] = serde_json::json!(self.bootstrap_lit);
            v["bootstrap_effective_starts_per_slot"] = serde_json::json!(self.bootstrap_effective);
            v["b_per_slot"] = serde_json::json!(b);
        }
        v["share_of_pixels_reached_by_chains"] = serde_json::json!(self.chain_coverage());
        v
    }
}
