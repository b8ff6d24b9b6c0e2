//! The pass of the integrators that take one sample per pixel (the path tracer, BDPT), after
//! pbrt-v4's `ImageTileIntegrator`: image rows in parallel on the caller's rayon pool, each
//! with its own sampler keyed by (seed, pixel, pass) so the image does not depend on the
//! scheduling, cancellation checked per row, and splats to other pixels (BDPT's t = 1
//! strategy) merged in row order after the rows are done.

use crate::error_estimate::ErrorEstimate;
use crate::film::Film;
use crate::image::Image;
use crate::integrators::{Cancelled, Integrator, PassStats, RenderContext};
use crate::sampling::sampler::Sampler;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// What an integrator that takes one sample per pixel and pass computes for each sample
/// (pbrt-v4's `RayIntegrator::Li`, given the whole film position so that BDPT can build its
/// camera subpath and splat its t = 1 strategies).
pub trait PixelEstimator: Send + Sync {
    /// Buffers reused from pixel to pixel of a row (path vertices).
    type Scratch: Default + Send;

    /// The value of one sample at film position `film`, drawing from `row.sampler`: counts
    /// it (and any estimate it dropped) in `row.stats` and pushes contributions to other
    /// pixels to `row.splats`.
    fn sample_pixel(&self, ctx: &RenderContext, film: Vec2, row: &mut Row<Self::Scratch>) -> Vec3;
}

/// An integrator that takes one sample per pixel and pass with estimator `E` (the path
/// tracer, BDPT): its film and the buffer each pass fills before it is added. Every pass is
/// an independent estimate of every pixel, which the film's error estimate relies on.
pub struct PixelIntegrator<E> {
    ctx: RenderContext,
    estimator: E,
    film: Film,
    pass_buffer: Vec<Vec3>,
}

impl<E: PixelEstimator> PixelIntegrator<E> {
    pub fn new(ctx: RenderContext, estimator: E) -> Self {
        let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
        PixelIntegrator {
            ctx,
            estimator,
            film: Film::new(w, h),
            pass_buffer: vec![Vec3::ZERO; w * h],
        }
    }
}

impl<E: PixelEstimator> Integrator for PixelIntegrator<E> {
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let (ctx, estimator) = (&self.ctx, &self.estimator);
        let stats = pixel_pass(
            &mut self.pass_buffer,
            self.film.width,
            ctx.seed,
            pass,
            cancel,
            |film, row: &mut Row<E::Scratch>| estimator.sample_pixel(ctx, film, row),
        )?;
        self.film.add_pass(&self.pass_buffer);
        Ok(stats)
    }

    fn memory_bytes(&self) -> usize {
        self.film.memory_bytes() + std::mem::size_of_val(self.pass_buffer.as_slice())
    }

    fn image(&self) -> Image {
        self.film.image()
    }

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.film.error_estimate()
    }
}

/// The state of the image row being sampled: its sampler, the estimator's scratch buffers,
/// and what its samples give besides their pixels' own values.
pub struct Row<S> {
    pub sampler: Sampler,
    pub scratch: S,
    pub stats: PassStats,
    /// Contributions to other pixels: (pixel index, value).
    pub splats: Vec<(usize, Vec3)>,
}

/// Fills `buffer` (row-major, `width` wide) with one sample per pixel for pass `pass`:
/// `sample_pixel(film, sampler, scratch, row)` gets the sample's film position (the pixel
/// corner plus the sampler's first 2D draw) and returns the pixel's value; `scratch` is
/// reused from pixel to pixel of a row (path vertex buffers). Splats are added to `buffer`
/// after every row is done, in row order.
pub(crate) fn pixel_pass<S: Default + Send>(
    buffer: &mut [Vec3],
    width: usize,
    seed: u64,
    pass: u64,
    cancel: &AtomicBool,
    sample_pixel: impl Fn(Vec2, &mut Row<S>) -> Vec3 + Sync,
) -> Result<PassStats, Cancelled> {
    let rows: Vec<Row<S>> = buffer
        .par_chunks_mut(width.max(1))
        .enumerate()
        .map(|(y, row)| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let mut state = Row {
                sampler: Sampler::new(seed),
                scratch: S::default(),
                stats: PassStats::default(),
                splats: Vec::new(),
            };
            for (x, out) in row.iter_mut().enumerate() {
                state
                    .sampler
                    .start_pixel_sample((y * width + x) as u64, pass);
                let film = Vec2::new(x as f32, y as f32) + state.sampler.get_2d();
                *out = sample_pixel(film, &mut state);
            }
            Ok(state)
        })
        .collect::<Result<_, _>>()?;
    let mut stats = PassStats::default();
    for row in rows {
        stats = stats + row.stats;
        for (i, v) in row.splats {
            buffer[i] += v;
        }
    }
    Ok(stats)
}
