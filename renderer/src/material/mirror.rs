//! Perfect mirror (pbrt-v4 section 9.3, smooth conductor with a constant reflectance): a delta
//! BSDF, so `f` and `pdf` are zero and only `sample_f` reflects.

use crate::material::BsdfSample;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct MirrorBsdf {
    pub r: Vec3,
}

impl MirrorBsdf {
    pub fn sample_f(&self, wo: Vec3) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
        Some(BsdfSample::reflection(self.r / wi.z.abs(), wi, 1.0, true))
    }
}
