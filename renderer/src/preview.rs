//! A first look at the scene while the first pass of a slow estimator runs (MMLT's bootstrap
//! takes seconds, one BDPT pass about a second at 640 x 480): one sample per pixel of a short
//! path tracer at a quarter of the resolution each way, shown enlarged, as Blender's Cycles
//! viewport starts coarse and refines. It costs about a sixtieth of a path-tracing pass at
//! full resolution. Where short paths find almost no light (a room lit through a slit), it
//! shows the geometry instead, shaded by its base colour facing the camera as Blender's solid
//! view does. It is no estimate of the image: the frame that carries it says so
//! (`Frame::preview`), and measurements skip it (its pass count is 0).

use crate::camera::Camera;
use crate::image::Image;
use crate::integrators::path_tracer::{PathSettings, PathTracer};
use crate::integrators::{Cancelled, Integrator, RenderContext};
use glam::{Vec2, Vec3};
use std::sync::atomic::AtomicBool;

/// Pixels of the full image per preview pixel, each way.
const COARSENESS: u32 = 4;

/// Bounces of the preview's paths: enough to see through a glass sphere, and short.
const PREVIEW_DEPTH: u32 = 4;

/// The preview of what `ctx` renders, at `ctx`'s resolution (each preview pixel repeated
/// over the block of pixels it stands for).
pub fn render(ctx: &RenderContext, cancel: &AtomicBool) -> Result<Image, Cancelled> {
    let (w, h) = (ctx.camera.width, ctx.camera.height);
    let (pw, ph) = (w.div_ceil(COARSENESS), h.div_ceil(COARSENESS));
    // The full image's aspect, which rounding the size down would change.
    let desc = *ctx.camera.desc();
    let coarse_ctx = RenderContext {
        camera: Camera::new(&desc, pw, ph),
        ..ctx.clone()
    };
    let settings = PathSettings {
        max_depth: PREVIEW_DEPTH,
        ..PathSettings::default()
    };
    let mut tracer = PathTracer::new(coarse_ctx.clone(), settings);
    tracer.render_pass(0, cancel)?;
    let mut coarse = tracer.image();
    let lit = coarse
        .pixels
        .iter()
        .filter(|p| p.max_element() > 1e-4)
        .count();
    if lit * 20 < coarse.pixels.len() {
        coarse = solid_view(&coarse_ctx);
    }
    let mut image = Image::new(w as usize, h as usize);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let (cx, cy) = (x * pw / w, y * ph / h);
        *p = coarse.pixels[(cy * pw + cx) as usize];
    }
    Ok(image)
}

/// Each pixel's first surface in its material's base colour, darker as it turns away from
/// the camera.
fn solid_view(ctx: &RenderContext) -> Image {
    let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
    let mut image = Image::new(w, h);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let film = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
        let ray = ctx.camera.generate_ray(film);
        *p = ctx.scene.intersect(&ray).map_or(Vec3::ZERO, |si| {
            let facing = si.shading.n.dot(ray.d).abs();
            ctx.scene.triangle_material(si.triangle).base_color * (0.05 + 0.25 * facing)
        });
    }
    image
}
