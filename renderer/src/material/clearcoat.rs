//! KHR_materials_clearcoat: a thin dielectric coat (index 1.5, so Schlick f0 = 0.04) over the
//! base material, with its own roughness. The extension's reference model is
//!
//! ```text
//!     coated = mix(base, clearcoat_brdf, clearcoat * fresnel(0.04, N.V))
//! ```
//!
//! which, like glTF's `fresnel_mix`, is not reciprocal and gains energy at grazing angles. We
//! keep the coat's lobe exactly and couple the base beneath it reciprocally, with c = clearcoat,
//! E_c the coat lobe's directional albedo and t(mu) = 1 - c E_c(mu) the light it lets through:
//!
//! ```text
//!     f = c f_coat + f_diffuse' + f_glossy min(t(mu_o), t(mu_i))
//! ```
//!
//! The base's diffuse part (the plastic's, under glTF's specular layer of albedo E_s) is scaled
//! by the albedo scaling of Kelemen & Szirmay-Kalos (2001, eq. 5) through both layers at once:
//!
//! ```text
//!     f_diffuse' = base / pi  T(mu_o) T(mu_i) / T_avg,   T = (1 - E_s) (1 - c E_c),
//!     T_avg = 2 ∫ T(mu) mu dmu          (`layering::transmitted_average_of_two`)
//! ```
//!
//! so that over a white base its albedo is exactly T(mu_o) (the two albedos rise together
//! towards grazing angles, so T_avg is not the product of the layers' averages, which would
//! gain half a percent). The glossy parts (metal, the specular layer, glass) send light out
//! near the mirror direction, where an albedo scaling would give them up to t(1) / t_avg, 5 %
//! more than they have; the minimum is exact for a mirror (t(mu_i) = t(mu_o)) and never gains.
//! Measured, a coated white plastic reflects 0.984 to 1.000 of the light at every angle and
//! nothing exceeds 1 (white furnace tests in `material::tests`). The coat's normal
//! texture is not read: the coat shares the base's shading frame.

use crate::material::layering::specular_albedo;
use crate::material::microfacet::{TrowbridgeReitz, fresnel_schlick};
use glam::{Vec2, Vec3};

/// Schlick reflectance of the coat at normal incidence: ((1.5 - 1) / (1.5 + 1))^2.
const COAT_F0: f32 = 0.04;

#[derive(Clone, Copy, Debug)]
pub struct Clearcoat {
    /// clearcoatFactor (times its texture's R): 0 is no coat.
    pub weight: f32,
    pub distrib: TrowbridgeReitz,
}

impl Clearcoat {
    pub const NONE: Clearcoat = Clearcoat {
        weight: 0.0,
        distrib: TrowbridgeReitz { alpha: 1.0 },
    };

    pub fn is_present(&self) -> bool {
        self.weight > 0.0
    }

    /// c E_c(mu): the share of light at cosine `mu` that the coat reflects (0 without a coat).
    pub fn reflected(&self, mu: f32) -> f32 {
        if !self.is_present() {
            return 0.0;
        }
        self.weight * specular_albedo(mu, self.distrib.alpha, Vec3::splat(COAT_F0), 1.0).x
    }

    /// The factor on the base's glossy parts beneath the coat.
    pub fn glossy_scale(&self, mu_o: f32, mu_i: f32) -> f32 {
        1.0 - self.reflected(mu_o).max(self.reflected(mu_i))
    }

    /// c times the coat's lobe D G F / (4 cos_o cos_i), for an upper-hemisphere pair.
    pub fn f(&self, uo: Vec3, ui: Vec3) -> f32 {
        let wm = (uo + ui).normalize_or_zero();
        if uo.z <= 0.0 || ui.z <= 0.0 || wm == Vec3::ZERO {
            return 0.0;
        }
        let fresnel = fresnel_schlick(Vec3::splat(COAT_F0), uo.dot(wm)).x;
        self.weight * self.distrib.d(wm) * self.distrib.g(uo, ui) * fresnel / (4.0 * uo.z * ui.z)
    }

    /// Solid-angle pdf of `sample` (visible normals, reflected).
    pub fn pdf(&self, uo: Vec3, ui: Vec3) -> f32 {
        let wm = (uo + ui).normalize_or_zero();
        if uo.z <= 0.0 || ui.z <= 0.0 || wm == Vec3::ZERO {
            return 0.0;
        }
        self.distrib.d_visible(uo, wm) / (4.0 * uo.dot(wm))
    }

    pub fn sample(&self, uo: Vec3, u: Vec2) -> Vec3 {
        crate::geometry::reflect(uo, self.distrib.sample_wm(uo, u))
    }

    /// Probability of sampling the coat's lobe rather than the base: its share of the light
    /// at `mu_o` over a white base, at least 10 % so the coat's highlight is always found.
    pub fn sample_prob(&self, mu_o: f32) -> f32 {
        if !self.is_present() {
            return 0.0;
        }
        self.reflected(mu_o).clamp(0.1, 0.9)
    }
}
