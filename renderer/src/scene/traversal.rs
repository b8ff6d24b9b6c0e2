//! CWBVH traversal with our watertight triangle test at the leaves, compiled twice: once for
//! the baseline x86-64 (SSE2) every build targets, once for AVX2-era CPUs (AVX2, FMA, BMI,
//! LZCNT, POPCNT) and chosen at run time, so one portable binary still traces at the speed a
//! `-C target-cpu=native` build reaches.
//!
//! Why it pays: obvhs' node test is written with SSE intrinsics and its stack walk counts bits
//! (`count_ones`, `leading_zeros`) for every node; without POPCNT and LZCNT those become
//! multi-instruction sequences, and without VEX encoding every SSE operation needs extra
//! register copies. The AVX2 version also tests the node's eight children at once
//! (`intersect_node_avx2`) where obvhs' test takes two groups of four and converts their
//! quantised bounds one byte at a time. Both versions do the same arithmetic in the same
//! order (Rust never fuses `a * b + c` into an FMA on its own, and the AVX2 node test keeps
//! obvhs' order of min and max, which decides what a NaN gives), so they visit the same nodes
//! and find bit-identical hits (a unit test checks it); only the instructions differ.
//!
//! The walk itself is obvhs' `traverse!` macro, which expands here rather than in obvhs so
//! that it is compiled under the caller's target features.

use crate::scene::triangle::{RayShear, TriangleHit, intersect_triangle};
use glam::{UVec2, Vec3, Vec3A};
use obvhs::{
    cwbvh::{CwBvh, node::CwBvhNode},
    ray::Ray,
};

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

/// The BVH primitive index and the hit of a triangle in `(0, ray.tmax)` that `accept` takes
/// (it turns down hits on the transparent parts of cut-outs): the nearest, or with `ANY_HIT`
/// the first found (for shadow rays, which only ask whether there is one).
pub fn walk<const ANY_HIT: bool>(
    isa: Isa,
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    ray: Ray,
    shear: &RayShear,
    accept: &impl Fn(u32, &TriangleHit) -> bool,
) -> Option<(u32, TriangleHit)> {
    match isa {
        Isa::Baseline => {
            walk_kernel::<ANY_HIT>(bvh, tris, ray, shear, CwBvhNode::intersect_ray, accept)
        }
        // SAFETY: `Isa::Avx2` is only produced by `Isa::detect` when the CPU has every feature
        // the function is compiled for.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { walk_avx2::<ANY_HIT>(bvh, tris, ray, shear, accept) },
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn walk_avx2<const ANY_HIT: bool>(
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    ray: Ray,
    shear: &RayShear,
    accept: &impl Fn(u32, &TriangleHit) -> bool,
) -> Option<(u32, TriangleHit)> {
    walk_kernel::<ANY_HIT>(
        bvh,
        tris,
        ray,
        shear,
        |node, ray, oct| intersect_node_avx2(node, ray, oct),
        accept,
    )
}

/// obvhs' `CwBvhNode::intersect_ray_simd` for eight children at once: the slab test of the
/// ray against each child's quantised box, returning the hit mask `traverse!` expects (inner
/// children's bits in the top byte, ordered by the ray's octant; leaves' primitives below).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn intersect_node_avx2(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    use std::arch::x86_64::*;
    let dir_inv = node.compute_extent() * ray.inv_direction;
    let origin = (Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // The eight quantised planes of one axis side as floats (exact: they are bytes).
    let planes = |q: &[u8; 8]| {
        let bytes = _mm_set1_epi64x(i64::from_le_bytes(*q));
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes))
    };
    // Entry and exit distances along one axis, near plane first for the ray's direction.
    let slab = |lo: &[u8; 8], hi: &[u8; 8], negative: bool, d: f32, o: f32| {
        let (near, far) = if negative { (hi, lo) } else { (lo, hi) };
        let (d, o) = (_mm256_set1_ps(d), _mm256_set1_ps(o));
        (
            _mm256_add_ps(_mm256_mul_ps(planes(near), d), o),
            _mm256_add_ps(_mm256_mul_ps(planes(far), d), o),
        )
    };
    let dir = ray.direction;
    let (tmin_x, tmax_x) = slab(
        &node.child_min_x,
        &node.child_max_x,
        dir.x < 0.0,
        dir_inv.x,
        origin.x,
    );
    let (tmin_y, tmax_y) = slab(
        &node.child_min_y,
        &node.child_max_y,
        dir.y < 0.0,
        dir_inv.y,
        origin.y,
    );
    let (tmin_z, tmax_z) = slab(
        &node.child_min_z,
        &node.child_max_z,
        dir.z < 0.0,
        dir_inv.z,
        origin.z,
    );
    // obvhs' order of operands (a NaN lane takes the second one) and its 1e-4 entry clamp.
    let tmin = _mm256_max_ps(tmin_x, _mm256_max_ps(tmin_y, tmin_z));
    let tmax = _mm256_min_ps(tmax_x, _mm256_min_ps(tmax_y, tmax_z));
    let tmin = _mm256_max_ps(tmin, _mm256_set1_ps(NODE_ENTRY_EPSILON));
    let tmax = _mm256_min_ps(tmax, _mm256_set1_ps(ray.tmax));
    let mut hits = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tmin, tmax)) as u32;
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0;
    while hits != 0 {
        let child = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        let byte = |x: u64| ((x >> (child * 8)) as u32) & 0xff;
        hit_mask |= byte(child_bits8) << byte(bit_index8);
    }
    hit_mask
}

/// obvhs' clamp of a child's entry distance (`cwbvh::node::EPSILON`, not public).
#[cfg(target_arch = "x86_64")]
const NODE_ENTRY_EPSILON: f32 = 0.0001;

/// Always inlined, so that it takes the target features of the function it is expanded into.
#[inline(always)]
fn walk_kernel<const ANY_HIT: bool>(
    bvh: &CwBvh,
    tris: &[[Vec3; 3]],
    mut ray: Ray,
    shear: &RayShear,
    intersect_node: impl Fn(&CwBvhNode, &Ray, u32) -> u32,
    accept: &impl Fn(u32, &TriangleHit) -> bool,
) -> Option<(u32, TriangleHit)> {
    let mut best = None;
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    'walk: {
        obvhs::traverse!(
            bvh,
            node,
            state,
            intersect_node(node, &ray, state.oct_inv4),
            {
                let [p0, p1, p2] = tris[state.primitive_id as usize];
                // A hit is only reported inside (0, tmax), and tmax then shrinks to it, so the
                // last hit kept is the nearest.
                if let Some(h) = intersect_triangle(shear, ray.tmax, p0, p1, p2)
                    && accept(state.primitive_id, &h)
                {
                    best = Some((state.primitive_id, h));
                    if ANY_HIT {
                        break 'walk;
                    }
                    ray.tmax = h.t;
                }
            }
        );
    }
    best
}
