//! Merging at the camera's first specular vertex, for light trapped by total internal
//! reflection: paths E S* L (every vertex a smooth dielectric or mirror) with at least two
//! total internal reflections. No merge or connection reaches them, so the photon mappers had
//! only the camera path's own hit on the emitter, and where such a path is a light pipe (a
//! glass slab that carries the light by total internal reflection to a face the camera sees)
//! the exit direction is a chaotic function of the pixel position: a pixel sees the emitter
//! once in thousands of passes, at the emitter's full radiance. On gap-glass those samples
//! were a third of amcppm's error (DESIGN.md 5b, "Light trapped in the glass").
//!
//! Here the path space is split between two techniques by that one property, which both ends
//! of a path agree on (total internal reflection is reciprocal, `Bsdf::totally_reflects`):
//! - the camera path counts the emitter it finds through specular vertices only if fewer
//!   than two of them totally reflected (`TRAPPED_REFLECTIONS`; `hit_points::trace_eye_path`);
//! - the others are estimated from photons that left an emitter and met only specular
//!   vertices, at least two of them total internal reflections: at each of their scattering
//!   events they merge with the camera's first vertices (`SpecularPoint`, one per pixel whose
//!   camera ray meets a specular surface first) within a disc of radius r on the surface and a
//!   cone of half-angle theta about the direction to the camera, a kernel density estimate in
//!   position and direction of the radiance leaving that vertex towards the camera:
//!
//! ```text
//! L(x, w_c) ~ sum_j Phi_j / (pi r^2 * 2 pi (1 - cos theta) * cos(n, w_j) * P)
//! ```
//!
//! for P photons a pass leaving in directions w_j. Where the camera sees the surface at a
//! grazing angle there is no merge (`MIN_COS`), and the camera path keeps those paths. Both
//! kernels shrink with the photon passes k as the 4-D kernel's volume does k^(alpha - 1)
//! (the disc's area and the cone's solid angle each as k^((alpha - 1) / 2), the rate of
//! PPPM's disc, Knaus & Zwicker 2011 eq. 20 in its asymptotic form), so the estimate is
//! consistent. The
//! light it carries is dim and smooth where it matters (it has passed through many curved
//! bounces), so the kernel's bias is small next to the variance it removes. Photons of delta
//! lights (points, spots, directional lights) do not merge here: the camera path could never
//! find those paths, and the image would gain light that the path tracer does not have.

use super::hash_grid::HashGrid;
use glam::{DVec3, Vec3};
use std::sync::OnceLock;

/// Total internal reflections that make a path trapped light. One is not enough: a single
/// one off a flat face shows a sharp image of the emitter (the caustic pool's light seen
/// through its slab's bottom), which the camera path samples well and the merges' cone
/// blurs: merged from one on, the pool's relMSE at 60 s was 6.3e-4 and 6.1e-4 (seeds 0, 1)
/// against 1.7e-4 and 1.8e-4, pixels at the slab's edge three times too bright; from two on,
/// as before (DESIGN.md 5b, "Light trapped in the glass").
pub const TRAPPED_REFLECTIONS: u32 = 2;

/// The initial cone's half-angle about the direction to the camera, in radians.
const INITIAL_HALF_ANGLE: f64 = 0.2;

/// The camera sees a surface at a grazing angle below this cosine (75.5 degrees from its
/// normal): no merges there, and the camera path keeps all of E S* L. Within the cone the
/// photons' own cosines, by which each is divided, then stay above 0.05; at grazing views
/// they approach zero. (Dividing by the camera's cosine instead, as the first version did,
/// is biased wherever the cosine varies across the cone, most at grazing views.)
const MIN_COS: f32 = 0.25;

/// A pixel's first camera vertex on a specular surface.
#[derive(Clone, Copy, Debug)]
pub struct SpecularPoint {
    pub p: Vec3,
    /// Geometric normal turned towards the camera.
    pub n: Vec3,
    /// Unit direction from the vertex to the camera.
    pub to_camera: Vec3,
    /// The camera path's throughput to the vertex.
    pub beta: Vec3,
    /// Whether the camera sees the surface's back (from inside a closed dielectric).
    pub from_back: bool,
}

impl SpecularPoint {
    /// The first vertex, unless the camera sees it at a grazing angle (`MIN_COS`).
    pub fn new(p: Vec3, geometric_normal: Vec3, to_camera: Vec3, beta: Vec3) -> Option<Self> {
        let from_back = geometric_normal.dot(to_camera) < 0.0;
        let n = if from_back {
            -geometric_normal
        } else {
            geometric_normal
        };
        (n.dot(to_camera) >= MIN_COS).then_some(SpecularPoint {
            p,
            n,
            to_camera,
            beta,
            from_back,
        })
    }
}

/// This pass's kernel: the disc's squared radius and the cone's cosine.
#[derive(Clone, Copy, Debug)]
pub struct Kernel {
    pub radius_sq: f64,
    pub cos_theta: f64,
}

impl Kernel {
    /// The kernel of photon pass `k` (from 0) for an initial radius r_0 and `alpha`.
    pub fn at(k: u64, initial_radius_sq: f64, alpha: f64) -> Kernel {
        let shrink = ((k + 1) as f64).powf(0.5 * (alpha - 1.0));
        Kernel {
            radius_sq: initial_radius_sq * shrink,
            cos_theta: 1.0 - (1.0 - INITIAL_HALF_ANGLE.cos()) * shrink,
        }
    }

    /// The kernel's volume in position and direction, pi r^2 2 pi (1 - cos theta).
    pub fn volume(&self) -> f64 {
        std::f64::consts::PI * self.radius_sq * std::f64::consts::TAU * (1.0 - self.cos_theta)
    }
}

/// The specular points of a pass and the grid over them, built for that pass's kernel by
/// the first photon that merges (most scenes have none: their passes never build it).
pub struct TrappedLight {
    pub points: Vec<Option<SpecularPoint>>,
    pub kernel: Kernel,
    /// Whether any point is seen from its surface's back: if none, a photon leaving a surface
    /// backwards (into a dielectric, or reflected inside it) merges nowhere, and most
    /// trapped photons' events are such (`merges_leaving`).
    seen_from_back: bool,
    grid: OnceLock<Option<HashGrid>>,
}

impl TrappedLight {
    pub fn new(pixels: usize) -> Self {
        TrappedLight {
            points: vec![None; pixels],
            kernel: Kernel {
                radius_sq: 0.0,
                cos_theta: 1.0,
            },
            grid: OnceLock::new(),
            seen_from_back: false,
        }
    }

    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.points.as_slice())
            + self
                .grid
                .get()
                .and_then(Option::as_ref)
                .map_or(0, HashGrid::memory_bytes)
    }

    /// Starts a photon pass with `kernel` over the eye pass's points.
    pub fn start_pass(&mut self, kernel: Kernel) {
        self.kernel = kernel;
        self.grid = OnceLock::new();
        self.seen_from_back = self.points.iter().flatten().any(|s| s.from_back);
    }

    /// Whether a photon leaving a surface of front normal `n` in direction `dir` can merge
    /// with any point this pass (the test before the grid's).
    pub fn merges_leaving(&self, n: Vec3, dir: Vec3) -> bool {
        dir.dot(n) > 0.0 || self.seen_from_back
    }

    /// The grid over this pass's points (none when no pixel has one).
    fn grid(&self) -> Option<&HashGrid> {
        self.grid
            .get_or_init(|| {
                let r = self.kernel.radius_sq.sqrt() as f32;
                let entries: Vec<Option<(Vec3, f32)>> =
                    self.points.iter().map(|s| s.map(|s| (s.p, r))).collect();
                entries
                    .iter()
                    .any(Option::is_some)
                    .then(|| HashGrid::build(&entries))
            })
            .as_ref()
    }

    /// A photon of flux `flux` leaving a specular vertex at `p` (geometric normal `n`) in
    /// direction `dir`: calls `deposit(pixel, contribution)` for every specular point whose
    /// kernel holds it, the contribution not yet divided by the kernel's volume or the photon
    /// count (`radiance`).
    pub fn merge(
        &self,
        p: Vec3,
        n: Vec3,
        dir: Vec3,
        flux: Vec3,
        deposit: &mut impl FnMut(u32, DVec3),
    ) {
        let Some(grid) = self.grid() else {
            return;
        };
        let (radius_sq, cos_theta) = (self.kernel.radius_sq, self.kernel.cos_theta);
        for &c in grid.candidates(p) {
            let Some(s) = &self.points[c as usize] else {
                continue;
            };
            if ((p - s.p).length_squared() as f64) > radius_sq
                || (dir.dot(s.to_camera) as f64) < cos_theta
                || dir.dot(s.n) <= 0.0
                // The same side of a surface facing the same way: not the photons of a face
                // that meets this one at an edge.
                || n.dot(s.n).abs() < 0.5
            {
                continue;
            }
            // Radiance is flux per area, solid angle and projected area: each photon is
            // divided by its own cosine (the camera's differs within the cone).
            let contribution = (s.beta * flux / dir.dot(s.n)).as_dvec3();
            if contribution.is_finite() {
                deposit(c, contribution);
            }
        }
    }

    /// The radiance a pass's summed contributions at a pixel estimate, for `photons` photons.
    pub fn radiance(&self, sum: DVec3, photons: u64) -> DVec3 {
        let v = self.kernel.volume() * photons as f64;
        if v > 0.0 { sum / v } else { DVec3::ZERO }
    }
}
