//! The eye pass of the photon mappers that re-trace it (SPPM, PPPM, amcppm; PPM keeps its
//! first): a camera ray per pixel with fresh jitter, its direct light and its hit point
//! (`hit_points.rs`).

use super::hit_points::trace_eye_path;
use super::trapped_light::SpecularPoint;
use super::{EYE_STREAM, PhotonMapper};
use crate::film::sanitize;
use crate::integrators::{Cancelled, PassStats};
use crate::sampling::sampler::Sampler;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

impl PhotonMapper {
    /// Eye pass: each pixel's direct estimate for this pass (emission seen through specular
    /// chains plus next-event estimation at the first non-specular vertex), from a camera ray
    /// with fresh jitter, and the hit points the photons are gathered at: new every pass for
    /// SPPM and PPPM, the first pass's kept for the whole run by PPM. PPM's direct estimate
    /// re-jitters too (as SPPM's does): the image's high frequencies (light edges, texture)
    /// then converge to the pixel integral; only the photon-carried part, the smooth one, is
    /// point-sampled at the fixed hit points, as in Hachisuka et al. 2008.
    pub(super) fn eye_pass(
        &mut self,
        pass: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Vec<Vec3>, Cancelled> {
        let width = self.ctx.camera.width as usize;
        let (scene, camera, seed, max_depth) = (
            &*self.ctx.scene,
            &self.ctx.camera,
            self.ctx.seed,
            self.settings.max_depth,
        );
        let keep_hit_points = self.variant.fixed_hit_points() && pass > 0;
        let mut direct = vec![Vec3::ZERO; self.pixels.len()];
        // Each row's first specular vertices, where merges at them are asked for
        // (`trapped_light.rs`); empty rows otherwise.
        let trapped_light = self.trapped.is_some();
        let mut specular_rows: Vec<&mut [Option<SpecularPoint>]> = match &mut self.trapped {
            Some(t) => t.points.chunks_mut(width).collect(),
            None => (0..self.pixels.len().div_ceil(width))
                .map(|_| &mut [][..])
                .collect(),
        };
        let rows: Vec<PassStats> = direct
            .par_chunks_mut(width)
            .zip(self.hit_points.par_chunks_mut(width))
            .zip(specular_rows.par_iter_mut())
            .enumerate()
            .map(|(y, ((direct_row, hp_row), specular_row))| {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                let mut sampler = Sampler::new(seed);
                let mut eye = Sampler::new(seed ^ EYE_STREAM);
                let mut row = PassStats::default();
                for x in 0..width {
                    let pixel = (y * width + x) as u64;
                    sampler.start_pixel_sample(pixel, pass);
                    eye.start_pixel_sample(pixel, pass);
                    let film = Vec2::new(x as f32, y as f32) + eye.get_2d();
                    let path = trace_eye_path(
                        scene,
                        camera.generate_ray(film),
                        &mut eye,
                        &mut sampler,
                        max_depth,
                        trapped_light,
                        &mut row.rays,
                    );
                    if trapped_light {
                        specular_row[x] = path.specular;
                    }
                    let nee = path.hit_point.as_ref().map_or(Vec3::ZERO, |hp| {
                        hp.direct(scene, &mut sampler, &mut row.rays)
                    });
                    direct_row[x] = sanitize(path.emitted + nee).unwrap_or_else(|| {
                        row.dropped += 1;
                        Vec3::ZERO
                    });
                    if !keep_hit_points {
                        hp_row[x] = path.hit_point;
                    }
                    row.samples += 1;
                }
                Ok(row)
            })
            .collect::<Result<_, _>>()?;
        for r in rows {
            *stats = *stats + r;
        }
        Ok(direct)
    }
}
