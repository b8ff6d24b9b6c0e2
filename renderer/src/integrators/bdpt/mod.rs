//! Bidirectional path tracing (Veach 1997, chapter 10; pbrt-v3 section 16.3): per pixel
//! sample, one camera subpath and one light subpath, joined by every connection strategy
//! (s light vertices, t camera vertices) of each path length, weighted by the balance
//! heuristic. Strategies with t = 1 land anywhere on the film: they are splatted into
//! per-row buffers merged in row order into the pass's own image, so the image depends only on
//! the seed and the pass count, up to the order of the splats' floating-point sums (DESIGN.md
//! section 6), and every pass, splats included, is an independent estimate of every pixel:
//! the film estimates the remaining error from their spread, as for the path tracer.
//!
//! Paths end by Russian roulette on each bounce's throughput factor from the third vertex
//! of a subpath on; MIS weights ignore it (every strategy stays unbiased and the weights
//! still sum to one for every path).

pub mod connect;
pub mod subpath;
pub mod vertex;

use crate::error_estimate::ErrorEstimate;
use crate::film::{Film, sanitize};
use crate::image::Image;
use crate::integrators::{Cancelled, Integrator, ParamSpec, ParamValues, PassStats, RenderContext};
use crate::sampling::sampler::Sampler;
use connect::connect;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use subpath::{Termination, camera_subpath, light_subpath};
use vertex::Vertex;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptSettings {
    /// Maximum number of bounces (s + t - 2) of a path.
    pub max_depth: u32,
    /// Evaluate only strategy (s, t), unweighted: for testing that each strategy alone
    /// converges to the same image (how MIS bugs are found).
    pub only_strategy: Option<(usize, usize)>,
}

impl BdptSettings {
    pub const PARAMS: &'static [ParamSpec] = &[ParamSpec {
        name: "max_depth",
        doc: "Maximum number of bounces of a path; Russian roulette ends most subpaths earlier.",
        default: 64.0,
        min: 0.0,
        max: 1024.0,
        integer: true,
        live: false,
    }];

    pub fn from_params(p: &ParamValues) -> Self {
        BdptSettings {
            max_depth: p
                .get("max_depth")
                .copied()
                .unwrap_or(Self::PARAMS[0].default) as u32,
            only_strategy: None,
        }
    }
}

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(BdptIntegrator::new(ctx, BdptSettings::from_params(params)))
}

pub struct BdptIntegrator {
    ctx: RenderContext,
    settings: BdptSettings,
    film: Film,
    pass_buffer: Vec<Vec3>,
}

impl BdptIntegrator {
    pub fn new(ctx: RenderContext, settings: BdptSettings) -> Self {
        let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
        BdptIntegrator {
            ctx,
            settings,
            film: Film::new(w, h),
            pass_buffer: vec![Vec3::ZERO; w * h],
        }
    }
}

/// Per-row results of a pass: statistics and the t = 1 splats (pixel, value).
struct RowResult {
    stats: PassStats,
    splats: Vec<(usize, Vec3)>,
}

impl Integrator for BdptIntegrator {
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let width = self.film.width;
        let (scene, camera, seed, settings) = (
            &*self.ctx.scene,
            &self.ctx.camera,
            self.ctx.seed,
            self.settings,
        );
        let max_depth = settings.max_depth as usize;
        let rows: Vec<RowResult> = self
            .pass_buffer
            .par_chunks_mut(width)
            .enumerate()
            .map(|(y, row)| {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                let mut sampler = Sampler::new(seed);
                let mut result = RowResult {
                    stats: PassStats::default(),
                    splats: Vec::new(),
                };
                let (mut camera_path, mut light_path) =
                    (Vec::<Vertex>::new(), Vec::<Vertex>::new());
                for (x, out) in row.iter_mut().enumerate() {
                    sampler.start_pixel_sample((y * width + x) as u64, pass);
                    let film = Vec2::new(x as f32, y as f32) + sampler.get_2d();
                    let st = &mut result.stats;
                    camera_subpath(
                        scene,
                        camera,
                        film,
                        &mut sampler,
                        max_depth + 2,
                        Termination::Roulette,
                        &mut st.rays,
                        &mut camera_path,
                    );
                    light_subpath(
                        scene,
                        &mut sampler,
                        max_depth + 1,
                        Termination::Roulette,
                        &mut st.rays,
                        &mut light_path,
                    );
                    let mut l = Vec3::ZERO;
                    for t in 1..=camera_path.len() {
                        for s in 0..=light_path.len() {
                            let depth = (s + t) as i64 - 2;
                            if (s == 1 && t == 1) || depth < 0 || depth > max_depth as i64 {
                                continue;
                            }
                            if settings.only_strategy.is_some_and(|o| o != (s, t)) {
                                continue;
                            }
                            let Some(c) = connect(
                                scene,
                                camera,
                                &light_path,
                                &camera_path,
                                s,
                                t,
                                &mut sampler,
                                &mut st.rays,
                                settings.only_strategy.is_none(),
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
                                    result.splats.push((py * width + px, v));
                                }
                                None => l += v,
                            }
                        }
                    }
                    *out = l;
                    st.samples += 1;
                }
                Ok(result)
            })
            .collect::<Result<_, _>>()?;
        let mut stats = PassStats::default();
        for r in rows {
            stats = stats + r.stats;
            for (i, v) in r.splats {
                self.pass_buffer[i] += v;
            }
        }
        self.film.add_pass(&self.pass_buffer);
        Ok(stats)
    }

    fn image(&self) -> Image {
        self.film.image()
    }

    fn set_live_param(&mut self, _name: &str, _value: f64) -> bool {
        false
    }

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.film.error_estimate()
    }
}
