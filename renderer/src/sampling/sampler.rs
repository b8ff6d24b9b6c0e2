//! The sampler: every random number of the renderer is a hash of (seed, pixel, sample index,
//! dimension), so the image never depends on which thread rendered which pixel or in what
//! order (DESIGN.md section 7). Independent uniform numbers; stratified or low-discrepancy
//! sequences can replace the hash behind the same interface.

use glam::Vec2;

/// A 64-bit finaliser with good avalanche (the `splitmix64` output function).
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Largest f32 below one: a primary sample is always in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A source of uniform primary samples in [0, 1): the hashed `Sampler` here, or MMLT's
/// primary-sample-space state (`sampling::pss`), behind which the same path-generation code
/// runs (Kelemen et al. 2002: a path is a function of its primary samples).
pub trait SampleSource {
    fn get_1d(&mut self) -> f32;
    fn get_2d(&mut self) -> Vec2 {
        let x = self.get_1d();
        Vec2::new(x, self.get_1d())
    }
}

#[derive(Clone, Debug)]
pub struct Sampler {
    seed: u64,
    stream: u64,
    dimension: u64,
}

impl Sampler {
    pub fn new(seed: u64) -> Self {
        Sampler {
            seed: mix64(seed ^ 0x9e37_79b9_7f4a_7c15),
            stream: 0,
            dimension: 0,
        }
    }

    /// Starts the sample `sample_index` of pixel `pixel_index`; dimensions restart at 0.
    pub fn start_pixel_sample(&mut self, pixel_index: u64, sample_index: u64) {
        self.stream = mix64(
            mix64(self.seed ^ pixel_index.wrapping_mul(0xd1b5_4a32_d192_ed03)) ^ sample_index,
        );
        self.dimension = 0;
    }

    pub fn get_1d(&mut self) -> f32 {
        SampleSource::get_1d(self)
    }

    pub fn get_2d(&mut self) -> Vec2 {
        SampleSource::get_2d(self)
    }
}

impl SampleSource for Sampler {
    fn get_1d(&mut self) -> f32 {
        let h = mix64(self.stream ^ self.dimension.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        self.dimension += 1;
        // 24 high bits give every f32 in [0,1) with spacing 2^-24, never 1.0.
        ((h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)).min(ONE_MINUS_EPSILON)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_coordinates_give_same_numbers() {
        let mut a = Sampler::new(7);
        let mut b = Sampler::new(7);
        a.start_pixel_sample(12, 3);
        b.start_pixel_sample(99, 0);
        b.start_pixel_sample(12, 3);
        for _ in 0..10 {
            assert_eq!(a.get_1d(), b.get_1d());
        }
    }

    #[test]
    fn numbers_are_uniform_in_unit_interval() {
        let mut s = Sampler::new(1);
        let bins = 16;
        let mut counts = vec![0u32; bins];
        let n = 160_000;
        for i in 0..n {
            s.start_pixel_sample(i, 0);
            let x = s.get_1d();
            assert!((0.0..1.0).contains(&x));
            counts[(x * bins as f32) as usize] += 1;
        }
        crate::sampling::chi2::chi2_uniform("sampler", &counts, 0.001).unwrap();
    }
}
