//! How much of the image each technique of vcm brings, per path length: connections by the
//! number s of light vertices (s = 0 a camera path that finds a light, s = 1 next-event
//! estimation, t = 1 light tracing), merges by the light subpath's edges. The MIS weights
//! decide these shares, so they show where merging takes over from connections (the caustics
//! seen through glass) and where it only adds its bias. The viewer plots them as MMLT's
//! technique histogram.

use crate::geometry::luminance;
use crate::integrators::{PlotKind, PlotSeries};
use glam::Vec3;

/// Path lengths (bounces) the shares are kept for; longer paths are counted in the last.
pub const MAX_BOUNCES: usize = 8;

/// Luminance brought by each technique of one path length k (bounces; k + 1 edges).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LengthShares {
    /// By s, 0..=k + 1 (t = k + 2 - s camera vertices).
    pub connections: Vec<f64>,
    /// By the light subpath's edges j, 1..=k (index j - 1): merged at the path's vertex j.
    pub merges: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct TechniqueShares {
    /// Index k: bounces.
    pub lengths: Vec<LengthShares>,
}

impl Default for TechniqueShares {
    fn default() -> Self {
        TechniqueShares {
            lengths: (0..=MAX_BOUNCES)
                .map(|k| LengthShares {
                    connections: vec![0.0; k + 2],
                    merges: vec![0.0; k],
                })
                .collect(),
        }
    }
}

impl TechniqueShares {
    /// A connection technique's weighted value on a path of `edges` edges with `s` light
    /// vertices.
    pub fn connection(&mut self, edges: u32, s: u32, value: Vec3) {
        let k = (edges.max(1) as usize - 1).min(MAX_BOUNCES);
        let l = &mut self.lengths[k];
        // Paths longer than the last length are pooled there by their last techniques.
        let s = (s as usize).min(l.connections.len() - 1);
        l.connections[s] += f64::from(luminance(value));
    }

    /// A merge's weighted value on a path of `edges` edges whose light subpath has
    /// `light_edges` of them.
    pub fn merge(&mut self, edges: u32, light_edges: u32, value: Vec3) {
        let k = (edges.max(1) as usize - 1).min(MAX_BOUNCES);
        let l = &mut self.lengths[k];
        if l.merges.is_empty() {
            return;
        }
        let j = (light_edges.max(1) as usize).min(l.merges.len());
        l.merges[j - 1] += f64::from(luminance(value));
    }

    /// Every share times `s` (a chain's normalisation).
    pub fn scale(&mut self, s: f64) {
        for l in &mut self.lengths {
            l.connections
                .iter_mut()
                .chain(&mut l.merges)
                .for_each(|x| *x *= s);
        }
    }

    pub fn add(&mut self, other: &TechniqueShares) {
        for (a, b) in self.lengths.iter_mut().zip(&other.lengths) {
            for (x, y) in a.connections.iter_mut().zip(&b.connections) {
                *x += y;
            }
            for (x, y) in a.merges.iter_mut().zip(&b.merges) {
                *x += y;
            }
        }
    }

    /// One bar series per path length that brought any light: each technique's share of it.
    pub fn plots(&self) -> Vec<PlotSeries> {
        let mut plots = Vec::new();
        for (k, l) in self.lengths.iter().enumerate() {
            let total: f64 = l.connections.iter().chain(&l.merges).sum();
            if !(total > 0.0) {
                continue;
            }
            let last = if k == MAX_BOUNCES { "+" } else { "" };
            let mut names: Vec<String> = (0..l.connections.len())
                .map(|s| format!("s = {s}, t = {}", k + 2 - s))
                .collect();
            names.extend((1..=l.merges.len()).map(|j| format!("merge at vertex {j}")));
            plots.push(PlotSeries {
                plot: "Techniques".into(),
                name: format!("k = {k}{last}"),
                kind: PlotKind::Bars,
                x_label: format!(
                    "connections by s (t = {} - s), then merges by the light's edges",
                    k + 2
                ),
                y_label: "share of the light".into(),
                points: l
                    .connections
                    .iter()
                    .chain(&l.merges)
                    .enumerate()
                    .map(|(i, v)| [i as f64, v / total])
                    .collect(),
                point_names: names,
            });
        }
        plots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_of_a_length_sum_to_one_and_long_paths_pool_in_the_last() {
        let mut t = TechniqueShares::default();
        t.connection(3, 1, Vec3::ONE);
        t.connection(3, 3, Vec3::ONE);
        t.merge(3, 2, Vec3::splat(2.0));
        t.connection(40, 40, Vec3::ONE);
        let plots = t.plots();
        assert_eq!(plots.len(), 2);
        let k2 = &plots[0];
        assert_eq!(k2.name, "k = 2");
        let shares: Vec<f64> = k2.points.iter().map(|p| p[1]).collect();
        assert_eq!(shares, vec![0.0, 0.25, 0.0, 0.25, 0.0, 0.5]);
        assert_eq!(k2.point_names[5], "merge at vertex 2");
        assert_eq!(plots[1].name, format!("k = {MAX_BOUNCES}+"));
    }
}
