//! Trowbridge-Reitz (GGX) microfacet distribution with height-correlated Smith masking and
//! visible-normal sampling (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT
//! 2018), in pbrt-v4's formulation (section 9.6). Isotropic: glTF has one roughness.

use crate::sampling::warp::sample_uniform_disk_concentric;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Smallest alpha used: below it the lobe is numerically a delta, which the smooth variants
/// (mirror, smooth dielectric) model exactly.
pub const MIN_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug)]
pub struct TrowbridgeReitz {
    pub alpha: f32,
}

impl TrowbridgeReitz {
    pub fn new(alpha: f32) -> Self {
        TrowbridgeReitz {
            alpha: alpha.max(MIN_ALPHA),
        }
    }

    /// Distribution of normals D(wm), per unit solid angle of wm projected (∫ D cos = 1).
    pub fn d(&self, wm: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = wm.z * wm.z;
        let denom = c2 * (a2 - 1.0) + 1.0;
        a2 / (PI * denom * denom)
    }

    /// Smith's Lambda (pbrt-v4 eq. 9.19).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let c2 = w.z * w.z;
        if c2 == 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (1.0 - c2).max(0.0) / c2;
        ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0) / 2.0
    }

    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing (pbrt-v4 eq. 9.22).
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Distribution of visible normals D_w(wm) (pbrt-v4 eq. 9.23); the solid-angle pdf of
    /// `sample_wm`. From below the surface (w.z < 0) the facets are seen from their back, as
    /// `sample_wm` samples them; facets turned away from the viewer have density zero.
    pub fn d_visible(&self, w: Vec3, wm: Vec3) -> f32 {
        if w.z == 0.0 {
            return 0.0;
        }
        let cos_visible = (w.dot(wm) * w.z.signum()).max(0.0);
        self.g1(w) / w.z.abs() * self.d(wm) * cos_visible
    }

    /// Samples a visible normal seen from `w` (either hemisphere); the result is in +z.
    pub fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        let mut wh = Vec3::new(self.alpha * w.x, self.alpha * w.y, w.z).normalize_or(Vec3::Z);
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        let mut p = sample_uniform_disk_concentric(u);
        let h = (1.0 - p.x * p.x).max(0.0).sqrt();
        let s = (1.0 + wh.z) / 2.0;
        p.y = (1.0 - s) * h + s * p.y;
        let pz = (1.0 - p.length_squared()).max(0.0).sqrt();
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v4 eq. 9.9); `eta` is the
/// relative index inside/outside, `cos_theta_i` signed (negative means from inside).
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parl * r_parl + r_perp * r_perp) / 2.0
}

/// Schlick's approximation, as glTF specifies (spec appendix B.3.4).
pub fn fresnel_schlick(f0: Vec3, cos_theta: f32) -> Vec3 {
    fresnel_schlick_f90(f0, 1.0, cos_theta)
}

/// Schlick's approximation with a grazing reflectance f90 other than 1
/// (KHR_materials_specular): f0 + (f90 - f0) (1 - cos)^5.
pub fn fresnel_schlick_f90(f0: Vec3, f90: f32, cos_theta: f32) -> Vec3 {
    let m = (1.0 - cos_theta.abs()).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3::splat(f90) - f0) * m5
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::{sidak_significance, test_directions};

    #[test]
    fn projected_normals_integrate_to_one() {
        // ∫ D(wm) cos(theta_m) dwm = 1, by midpoint rule in theta.
        for alpha in [0.05f32, 0.3, 1.0] {
            let tr = TrowbridgeReitz::new(alpha);
            let n = 200_000;
            let mut sum = 0.0f64;
            for i in 0..n {
                let theta = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                let wm = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
                sum += tr.d(wm) as f64 * theta.cos() * theta.sin();
            }
            let integral =
                sum * 2.0 * std::f64::consts::PI * std::f64::consts::FRAC_PI_2 / n as f64;
            assert!((integral - 1.0).abs() < 2e-3, "alpha {alpha}: {integral}");
        }
    }

    #[test]
    fn visible_normals_match_their_pdf() {
        let cases = [(0.2f32, 0.3f32), (0.5, 0.9), (0.9, -0.6)];
        let alpha = sidak_significance(cases.len());
        for (a, cos_o) in cases {
            let tr = TrowbridgeReitz::new(a);
            let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
            test_directions(
                "ggx visible normals",
                |u, _| Some(tr.sample_wm(wo, u)),
                &|wm| {
                    if wm.z > 0.0 {
                        tr.d_visible(wo, wm)
                    } else {
                        0.0
                    }
                },
                alpha,
            )
            .unwrap();
        }
    }

    #[test]
    fn fresnel_limits() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(-0.2, 1.5), 1.0); // total internal reflection
        assert!((fresnel_dielectric(1e-4, 1.5) - 1.0).abs() < 1e-3);
    }
}
