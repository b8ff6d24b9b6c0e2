//! Spatial hash grid over hit points (Hachisuka et al. 2008, section 4.2; pbrt-v4 section
//! 13.8.3): each hit point is entered in every cell its disc of radius R overlaps; a photon
//! looks up its own cell only. The table has a fixed number of buckets per hit point, so its
//! size stays bounded however small the radii get.

use glam::{IVec3, Vec3};

pub struct HashGrid {
    origin: Vec3,
    inv_cell: f32,
    mask: usize,
    /// bucket b holds entries[starts[b]..starts[b + 1]].
    starts: Vec<u32>,
    entries: Vec<u32>,
}

fn hash(c: IVec3) -> usize {
    // Teschner et al., "Optimized Spatial Hashing for Collision Detection" (2003).
    ((c.x as i64 as u64).wrapping_mul(73_856_093)
        ^ (c.y as i64 as u64).wrapping_mul(19_349_663)
        ^ (c.z as i64 as u64).wrapping_mul(83_492_791)) as usize
}

impl HashGrid {
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.starts.as_slice())
            + std::mem::size_of_val(self.entries.as_slice())
    }

    /// Builds the grid over points with radii (`None` entries are skipped).
    pub fn build(points: &[Option<(Vec3, f32)>]) -> HashGrid {
        let live: Vec<(usize, Vec3, f32)> = points
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.map(|(q, r)| (i, q, r)))
            .collect();
        let mean_radius = live.iter().map(|l| l.2 as f64).sum::<f64>() / live.len().max(1) as f64;
        let cell = (2.0 * mean_radius as f32).max(f32::MIN_POSITIVE);
        let origin = live
            .iter()
            .fold(Vec3::INFINITY, |m, l| m.min(l.1 - Vec3::splat(l.2)));
        let buckets = (2 * live.len()).next_power_of_two().max(1);
        let mut grid = HashGrid {
            origin: if origin.is_finite() {
                origin
            } else {
                Vec3::ZERO
            },
            inv_cell: 1.0 / cell,
            mask: buckets - 1,
            starts: vec![0; buckets + 1],
            entries: Vec::new(),
        };
        // Two passes: count per bucket, then fill (a counting sort).
        let cells_of = |p: Vec3, r: f32, visit: &mut dyn FnMut(usize)| {
            let lo = grid.cell_of(p - Vec3::splat(r));
            let hi = grid.cell_of(p + Vec3::splat(r));
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        visit(hash(IVec3::new(x, y, z)) & grid.mask);
                    }
                }
            }
        };
        let mut counts = vec![0u32; buckets];
        for &(_, p, r) in &live {
            cells_of(p, r, &mut |b| counts[b] += 1);
        }
        let mut starts = vec![0u32; buckets + 1];
        for b in 0..buckets {
            starts[b + 1] = starts[b] + counts[b];
        }
        let mut fill = starts.clone();
        let mut entries = vec![0u32; starts[buckets] as usize];
        for &(i, p, r) in &live {
            cells_of(p, r, &mut |b| {
                entries[fill[b] as usize] = i as u32;
                fill[b] += 1;
            });
        }
        grid.starts = starts;
        grid.entries = entries;
        grid
    }

    fn cell_of(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) * self.inv_cell).floor().as_ivec3()
    }

    /// Candidate hit points near `p` (a superset: callers check distance and side).
    pub fn candidates(&self, p: Vec3) -> &[u32] {
        if self.entries.is_empty() || !p.is_finite() {
            return &[];
        }
        let b = hash(self.cell_of(p)) & self.mask;
        &self.entries[self.starts[b] as usize..self.starts[b + 1] as usize]
    }

    pub fn bucket_count(&self) -> usize {
        self.mask + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::Sampler;

    #[test]
    fn every_point_within_a_radius_is_a_candidate() {
        let mut s = Sampler::new(4);
        let points: Vec<Option<(Vec3, f32)>> = (0..2000)
            .map(|i| {
                s.start_pixel_sample(i, 0);
                (i % 7 != 0).then(|| {
                    (
                        Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) * 4.0,
                        0.02 + 0.1 * s.get_1d(),
                    )
                })
            })
            .collect();
        let grid = HashGrid::build(&points);
        assert!(grid.bucket_count() <= 4096);
        for k in 0..5000u64 {
            s.start_pixel_sample(k, 1);
            let q = Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) * 4.0;
            let found = grid.candidates(q);
            for (i, p) in points.iter().enumerate() {
                if let Some((c, r)) = p
                    && (q - *c).length() <= *r
                {
                    assert!(
                        found.contains(&(i as u32)),
                        "point {i} within its radius of {q} was not found"
                    );
                }
            }
        }
    }
}
