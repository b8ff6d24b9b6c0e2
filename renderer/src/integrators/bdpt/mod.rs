//! Bidirectional path tracing (Veach 1997, chapter 10; pbrt-v3 section 16.3): per pixel
//! sample, one camera subpath and one light subpath, joined by every connection strategy
//! (s light vertices, t camera vertices) of each path length, weighted by the balance
//! heuristic. Strategies with t = 1 land anywhere on the film: they are splatted into
//! per-row buffers merged in row order into the pass's own image, so the image depends only on
//! the seed and the pass count, up to the order of the splats' floating-point sums (DESIGN.md
//! section 6), and every pass, splats included, is an independent estimate of every pixel:
//! the film estimates the remaining error from their spread, as for the path tracer.
//!
//! Paths end by Russian roulette from the third vertex of a subpath on, on the subpath's
//! throughput relative to its start with refraction's 1/eta^2 factored out, as the path
//! tracer's; MIS weights ignore it (every strategy stays unbiased and the weights still sum
//! to one for every path). Roulette on each bounce's own throughput factor, as first built,
//! ended half the camera paths at every refraction into glass: where only s = 0 samples
//! the light (a floor seen and lit through glass) that made BDPT 2.6 times as noisy per
//! sample as the path tracer, whose estimate it is there.

pub mod connect;
pub mod subpath;
pub mod vertex;

use crate::film::sanitize;
use crate::integrators::pixel_pass::{PixelEstimator, PixelIntegrator, Row};
use crate::integrators::{Integrator, ParamSpec, ParamValues, RenderContext, params};
use connect::connect;
use glam::{Vec2, Vec3};
use subpath::{Termination, Walker};
use vertex::Vertex;

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub struct BdptSettings {
    /// Maximum number of bounces (s + t - 2) of a path.
    pub max_depth: u32,
    /// Evaluate only strategy (s, t), unweighted: for testing that each strategy alone
    /// converges to the same image (how MIS bugs are found).
    #[serde(skip)]
    pub only_strategy: Option<(usize, usize)>,
}

impl BdptSettings {
    pub const PARAMS: &'static [ParamSpec] = &[params::MAX_DEPTH];

    pub fn from_params(p: &ParamValues) -> Self {
        params::read_settings(Self::PARAMS, p)
    }
}

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(Bdpt::new(ctx, BdptSettings::from_params(params)))
}

/// Bidirectional path tracing: one camera and one light subpath per pixel sample.
pub type Bdpt = PixelIntegrator<BdptSettings>;

/// A row's camera and light subpath buffers, reused from pixel to pixel.
type Subpaths = (Vec<Vertex>, Vec<Vertex>);

impl PixelEstimator for BdptSettings {
    type Scratch = Subpaths;

    /// One pixel sample: a camera and a light subpath joined by every strategy; returns the
    /// pixel's own value and splats the t = 1 strategies' into `row`.
    fn sample_pixel(&self, ctx: &RenderContext, film: Vec2, row: &mut Row<Subpaths>) -> Vec3 {
        let (scene, camera) = (&*ctx.scene, &ctx.camera);
        let max_depth = self.max_depth as usize;
        let width = camera.width as usize;
        let Row {
            sampler,
            scratch: (camera_path, light_path),
            stats: st,
            splats,
        } = row;
        let mut walker = Walker {
            scene,
            sampler,
            termination: Termination::Roulette,
            rays: &mut st.rays,
        };
        walker.camera_subpath(camera, film, max_depth + 2, camera_path);
        walker.light_subpath(max_depth + 1, light_path);
        let mut l = Vec3::ZERO;
        for t in 1..=camera_path.len() {
            // s = 1 samples its own light vertex: it is there even when the light subpath
            // is not (its origin fell on a black texel or a cut-out's hole).
            for s in 0..=light_path.len().max(1) {
                let depth = (s + t) as i64 - 2;
                if (s == 1 && t == 1) || depth < 0 || depth > max_depth as i64 {
                    continue;
                }
                if self.only_strategy.is_some_and(|o| o != (s, t)) {
                    continue;
                }
                let Some(c) = connect(
                    scene,
                    camera,
                    light_path,
                    camera_path,
                    s,
                    t,
                    sampler,
                    &mut st.rays,
                    self.only_strategy.is_none(),
                ) else {
                    continue;
                };
                let Some(v) = sanitize(c.l * c.mis) else {
                    st.dropped += 1;
                    continue;
                };
                match c.raster {
                    Some(r) => {
                        let (px, py) = (r.x as usize, r.y as usize);
                        splats.push((py * width + px, v));
                    }
                    None => l += v,
                }
            }
        }
        st.samples += 1;
        l
    }
}
