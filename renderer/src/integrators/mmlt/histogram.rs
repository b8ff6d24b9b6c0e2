//! What the chains did: for every path length k and technique s, the steps spent there (the
//! technique histogram the viewer plots), and acceptance counts per path length for large
//! steps, small steps and steps that proposed another technique.

/// Proposed and accepted counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Acceptance {
    pub proposed: u64,
    pub accepted: u64,
}

impl Acceptance {
    pub fn record(&mut self, accepted: bool) {
        self.proposed += 1;
        self.accepted += accepted as u64;
    }

    pub fn rate(&self) -> f64 {
        if self.proposed == 0 {
            0.0
        } else {
            self.accepted as f64 / self.proposed as f64
        }
    }

    fn add(&mut self, o: &Acceptance) {
        self.proposed += o.proposed;
        self.accepted += o.accepted;
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct LengthStats {
    /// Steps the chains of this length spent in each technique s (index s).
    pub steps_in_technique: Vec<u64>,
    pub large: Acceptance,
    pub small: Acceptance,
    /// Steps whose proposal used another technique than the current state.
    pub technique_change: Acceptance,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TechniqueHistogram {
    /// Index k: path length in bounces.
    pub lengths: Vec<LengthStats>,
}

impl TechniqueHistogram {
    pub fn new(max_depth: usize) -> Self {
        TechniqueHistogram {
            lengths: (0..=max_depth)
                .map(|k| LengthStats {
                    steps_in_technique: vec![0; k + 2],
                    ..Default::default()
                })
                .collect(),
        }
    }

    /// Records one step of a chain from state (k, s) `current` to proposal `proposed`: the
    /// proposal's kind and acceptance under its own length, a change of technique (or of
    /// length) if it was one, and the step under the state the chain is in afterwards.
    pub fn record(
        &mut self,
        current: (usize, usize),
        proposed: (usize, usize),
        large: bool,
        accepted: bool,
    ) {
        let stats = &mut self.lengths[proposed.0];
        if large {
            stats.large.record(accepted);
        } else {
            stats.small.record(accepted);
        }
        if proposed != current {
            stats.technique_change.record(accepted);
        }
        let (k, s) = if accepted { proposed } else { current };
        self.lengths[k].steps_in_technique[s] += 1;
    }

    pub fn merge(&mut self, o: &TechniqueHistogram) {
        for (a, b) in self.lengths.iter_mut().zip(&o.lengths) {
            for (x, y) in a.steps_in_technique.iter_mut().zip(&b.steps_in_technique) {
                *x += y;
            }
            a.large.add(&b.large);
            a.small.add(&b.small);
            a.technique_change.add(&b.technique_change);
        }
    }

    pub fn total_steps(&self) -> u64 {
        self.lengths
            .iter()
            .flat_map(|l| &l.steps_in_technique)
            .sum()
    }

    /// The histogram as JSON (for `caustica render --stats FILE.json`).
    pub fn to_json(&self) -> serde_json::Value {
        let rate = |a: &Acceptance| serde_json::json!({"proposed": a.proposed, "accepted": a.accepted, "rate": a.rate()});
        let lengths: Vec<serde_json::Value> = self
            .lengths
            .iter()
            .enumerate()
            .map(|(k, l)| {
                serde_json::json!({
                    "k": k,
                    "steps_in_technique": l.steps_in_technique,
                    "large_steps": rate(&l.large),
                    "small_steps": rate(&l.small),
                    "technique_changes": rate(&l.technique_change),
                })
            })
            .collect();
        serde_json::json!({"total_steps": self.total_steps(), "path_lengths": lengths})
    }
}
