//! The pass of the integrators that take one sample per pixel (the path tracer, BDPT), after
//! pbrt-v4's `ImageTileIntegrator`: image rows in parallel on the caller's rayon pool, each
//! with its own sampler keyed by (seed, pixel, pass) so the image does not depend on the
//! scheduling, cancellation checked per row, and splats to other pixels (BDPT's t = 1
//! strategy) merged in row order after the rows are done.

use crate::camera::PerspectiveCamera;
use crate::error_estimate::ErrorEstimate;
use crate::film::Film;
use crate::image::Image;
use crate::integrators::{Cancelled, PassStats};
use crate::sampling::sampler::Sampler;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// The film of an integrator that takes one sample per pixel, and the buffer each pass fills
/// before it is added: every pass is an independent estimate of every pixel, which the film's
/// error estimate relies on.
pub(crate) struct PixelFilm {
    film: Film,
    pass_buffer: Vec<Vec3>,
}

impl PixelFilm {
    pub fn new(camera: &PerspectiveCamera) -> Self {
        let (w, h) = (camera.width as usize, camera.height as usize);
        PixelFilm {
            film: Film::new(w, h),
            pass_buffer: vec![Vec3::ZERO; w * h],
        }
    }

    /// One pass of `pixel_pass`, added to the film.
    pub fn render_pass<S: Default>(
        &mut self,
        seed: u64,
        pass: u64,
        cancel: &AtomicBool,
        sample_pixel: impl Fn(Vec2, &mut Sampler, &mut S, &mut RowOutput) -> Vec3 + Sync,
    ) -> Result<PassStats, Cancelled> {
        let width = self.film.width;
        let stats = pixel_pass(
            &mut self.pass_buffer,
            width,
            seed,
            pass,
            cancel,
            sample_pixel,
        )?;
        self.film.add_pass(&self.pass_buffer);
        Ok(stats)
    }

    pub fn image(&self) -> Image {
        self.film.image()
    }

    pub fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.film.error_estimate()
    }
}

/// What the samples of one row give besides their pixels' own values.
#[derive(Default)]
pub(crate) struct RowOutput {
    pub stats: PassStats,
    /// Contributions to other pixels: (pixel index, value).
    pub splats: Vec<(usize, Vec3)>,
}

/// Fills `buffer` (row-major, `width` wide) with one sample per pixel for pass `pass`:
/// `sample_pixel(film, sampler, scratch, row)` gets the sample's film position (the pixel
/// corner plus the sampler's first 2D draw) and returns the pixel's value; `scratch` is
/// reused from pixel to pixel of a row (path vertex buffers). Splats are added to `buffer`
/// after every row is done, in row order.
pub(crate) fn pixel_pass<S: Default>(
    buffer: &mut [Vec3],
    width: usize,
    seed: u64,
    pass: u64,
    cancel: &AtomicBool,
    sample_pixel: impl Fn(Vec2, &mut Sampler, &mut S, &mut RowOutput) -> Vec3 + Sync,
) -> Result<PassStats, Cancelled> {
    let rows: Vec<RowOutput> = buffer
        .par_chunks_mut(width.max(1))
        .enumerate()
        .map(|(y, row)| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let mut sampler = Sampler::new(seed);
            let mut scratch = S::default();
            let mut output = RowOutput::default();
            for (x, out) in row.iter_mut().enumerate() {
                sampler.start_pixel_sample((y * width + x) as u64, pass);
                let film = Vec2::new(x as f32, y as f32) + sampler.get_2d();
                *out = sample_pixel(film, &mut sampler, &mut scratch, &mut output);
            }
            Ok(output)
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
