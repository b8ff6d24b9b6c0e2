//! Rays, shading frames and robust spawning of secondary rays.
//!
//! Ray origins are offset with pbrt-v4's conservative method (Pharr, Jakob & Humphreys,
//! *Physically Based Rendering*, 4th ed., section 6.8.6): the intersection point carries an
//! absolute error bound, and a spawned ray starts just outside that error box on the side of
//! the surface it leaves. This is scale invariant, so scenes modelled in millimetres or
//! kilometres behave alike.

use glam::{Vec2, Vec3};

/// A ray `o + t d` for `t` in `(0, t_max)`. `d` is unit length everywhere in the renderer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub t_max: f32,
}

impl Ray {
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray {
            o,
            d,
            t_max: f32::INFINITY,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds3 {
    pub const EMPTY: Bounds3 = Bounds3 {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn union_point(self, p: Vec3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn diagonal(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    pub fn center(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            0.5 * (self.min + self.max)
        }
    }

    /// Centre and radius of a sphere that encloses the box.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let c = self.center();
        (c, 0.5 * self.diagonal().length())
    }
}

/// Orthonormal frame; `n` is the local +z axis, the convention of every BSDF.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// Branchless basis of Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017).
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// Frame with normal `n` whose first axis follows `s` (Gram-Schmidt), for normal maps.
    pub fn from_normal_tangent(n: Vec3, s: Vec3) -> Frame {
        let s = s - n * n.dot(s);
        let len_sq = s.length_squared();
        if !(len_sq > 1e-12) || !len_sq.is_finite() {
            return Frame::from_z(n);
        }
        let s = s / len_sq.sqrt();
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Bound on the relative rounding error of `n` floating-point operations (pbrt-v4 eq. 6.7).
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}

fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 {
        return v;
    }
    let v = if v == 0.0 { -0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v > 0.0 { bits - 1 } else { bits + 1 };
    f32::from_bits(bits)
}

/// Origin for a ray leaving `p` (absolute error `p_error`, geometric normal `n`) towards `w`:
/// pbrt-v4's `OffsetRayOrigin`, section 6.8.6.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    // Round away from p so that the offset is not lost to rounding.
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

/// Reflection of `wo` about `n` (both pointing away from the surface).
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refraction of `wi` through an interface with normal `n` on `wi`'s side and relative index
/// `eta` = eta_transmitted / eta_incident (pbrt-v4 eq. 9.4). Returns the refracted direction and
/// the eta actually used (inverted when `wi` arrives from below), or None for total internal
/// reflection.
pub fn refract(wi: Vec3, mut n: Vec3, mut eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let wt = -wi / eta + (cos_i / eta - cos_t) * n;
    Some((wt, eta))
}

/// Luminance of linear Rec. 709 RGB.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Interpolates three per-vertex values with barycentrics `(b0, b1, b2)`.
pub fn interpolate2(v: &[Vec2; 3], b: Vec3) -> Vec2 {
    v[0] * b.x + v[1] * b.y + v[2] * b.z
}

pub fn interpolate3(v: &[Vec3; 3], b: Vec3) -> Vec3 {
    v[0] * b.x + v[1] * b.y + v[2] * b.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_every_normal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(0.0, 0.0, -0.9999).normalize(),
        ] {
            let f = Frame::from_z(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5 && (f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(f.n).abs() < 1e-5 && f.t.dot(f.n).abs() < 1e-5
            );
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.from_local(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn refraction_obeys_snell_and_reverses() {
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let (wt, eta) = refract(wi, Vec3::Z, 1.5).unwrap();
        assert_eq!(eta, 1.5);
        let sin_i = 0.6;
        let sin_t = (wt.x * wt.x + wt.y * wt.y).sqrt();
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-5);
        // Leaving the glass along the refracted ray retraces the incident one.
        let (back, back_eta) = refract(wt, Vec3::Z, 1.5).unwrap();
        assert!((back - wi).length() < 1e-5);
        assert!((back_eta - 1.0 / 1.5).abs() < 1e-6);
        // Total internal reflection from inside beyond the critical angle.
        assert!(refract(Vec3::new(0.8, 0.0, -0.6), Vec3::Z, 1.5).is_none());
    }

    #[test]
    fn offset_origin_leaves_the_error_box() {
        let p = Vec3::new(1000.0, 1.0, -3.0);
        let err = Vec3::splat(1e-3);
        let o = offset_ray_origin(p, err, Vec3::Y, Vec3::Y);
        assert!(o.y > p.y + 1e-3 * 0.99);
        let o = offset_ray_origin(p, err, Vec3::Y, -Vec3::Y);
        assert!(o.y < p.y - 1e-3 * 0.99);
    }
}
