//! CWBVH traversal with our watertight triangle test at the leaves, compiled twice: once for
//! the baseline x86-64 (SSE2) every build targets, once for AVX2-era CPUs (AVX2, FMA, BMI,
//! LZCNT, POPCNT) and chosen at run time, so one portable binary still traces at the speed a
//! `-C target-cpu=native` build reaches.
//!
//! Why it pays: obvhs' node test is written with SSE intrinsics and its stack walk counts bits
//! (`count_ones`, `leading_zeros`) for every node; without POPCNT and LZCNT those become
//! multi-instruction sequences, and without VEX encoding every SSE operation needs extra
//! register copies. Rust never fuses `a * b + c` into an FMA on its own, so both versions
//! compute bit-identical results (a unit test checks it); only the instructions differ.
//!
//! The walk itself is obvhs' `traverse!` macro, which expands here rather than in obvhs so
//! that it is compiled under the caller's target features.

use crate::scene::triangle::{RayShear, TriangleHit, intersect_triangle};
use glam::{UVec2, Vec3};
use obvhs::{cwbvh::CwBvh, ray::Ray};

/// Instruction set the traversal runs with, detected once when the BVH is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// What every x86-64 (or other) target has.
    Baseline,
    /// AVX2, FMA, BMI1/2, LZCNT and POPCNT (Intel Haswell, AMD Excavator and later).
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Isa {
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            return Isa::Avx2;
        }
        Isa::Baseline
    }
}

/// Nearest triangle hit in `(0, ray.tmax)`: the BVH primitive index and the hit.
pub fn closest_hit(
    isa: Isa,
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    ray: Ray,
    shear: &RayShear,
) -> Option<(u32, TriangleHit)> {
    match isa {
        Isa::Baseline => closest_hit_kernel(bvh, tris, ray, shear),
        // SAFETY: `Isa::Avx2` is only produced by `Isa::detect` when the CPU has every feature
        // the function is compiled for.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { closest_hit_avx2(bvh, tris, ray, shear) },
    }
}

/// True if any triangle blocks the ray in `(0, ray.tmax)`.
pub fn any_hit(isa: Isa, bvh: &CwBvh, tris: &[[Vec3; 3]], ray: Ray, shear: &RayShear) -> bool {
    match isa {
        Isa::Baseline => any_hit_kernel(bvh, tris, ray, shear),
        // SAFETY: as in `closest_hit`.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { any_hit_avx2(bvh, tris, ray, shear) },
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_hit_avx2(
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    ray: Ray,
    shear: &RayShear,
) -> Option<(u32, TriangleHit)> {
    closest_hit_kernel(bvh, tris, ray, shear)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn any_hit_avx2(bvh: &CwBvh, tris: &[[Vec3; 3]], ray: Ray, shear: &RayShear) -> bool {
    any_hit_kernel(bvh, tris, ray, shear)
}

/// Always inlined, so that it takes the target features of the function it is expanded into.
#[inline(always)]
fn closest_hit_kernel(
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    mut ray: Ray,
    shear: &RayShear,
) -> Option<(u32, TriangleHit)> {
    let mut best = None;
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    obvhs::traverse!(
        bvh,
        node,
        state,
        node.intersect_ray(&ray, state.oct_inv4),
        {
            let [p0, p1, p2] = tris[state.primitive_id as usize];
            // A hit is only reported inside (0, tmax), and tmax then shrinks to it, so the
            // last hit kept is the nearest.
            if let Some(h) = intersect_triangle(shear, ray.tmax, p0, p1, p2) {
                best = Some((state.primitive_id, h));
                ray.tmax = h.t;
            }
        }
    );
    best
}

#[inline(always)]
fn any_hit_kernel(bvh: &CwBvh, tris: &[[Vec3; 3]], ray: Ray, shear: &RayShear) -> bool {
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    let mut hit = false;
    'walk: {
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_ray(&ray, state.oct_inv4),
            {
                let [p0, p1, p2] = tris[state.primitive_id as usize];
                if intersect_triangle(shear, ray.tmax, p0, p1, p2).is_some() {
                    hit = true;
                    break 'walk;
                }
            }
        );
    }
    hit
}
