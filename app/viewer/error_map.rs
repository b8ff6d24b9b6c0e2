//! The error heat map the user can lay over the image: each pixel's relMSE term on a
//! logarithmic viridis scale, the true one against the reference while one is loaded (as tev
//! shows an image's error against its reference), else the estimated one
//! (`ErrorEstimate::per_pixel`). It becomes an egui texture
//! only while shown, only when a new estimate arrived, and at most four times a second, so a
//! fast integrator's stream of frames costs the UI thread nothing when the map is off.

use crate::viewer::convergence::TrueError;
use caustica_renderer::error_estimate::ErrorEstimate;
use eframe::egui::{self, Color32, ColorImage, TextureHandle, TextureOptions};
use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The decades the colour scale spans: relMSE terms of 1e-4 and below are dark, 10 and above
/// bright yellow.
pub const LOG10_RANGE: (f32, f32) = (-4.0, 1.0);
const MIN_INTERVAL: Duration = Duration::from_millis(250);

/// The colour of a pixel's relMSE term.
pub fn colour(term: f32) -> Color32 {
    let log = if term > 0.0 {
        term.log10()
    } else {
        LOG10_RANGE.0
    };
    let h = ((log - LOG10_RANGE.0) / (LOG10_RANGE.1 - LOG10_RANGE.0)).clamp(0.0, 1.0);
    let c = ViridisRGB.get_color(h);
    Color32::from_rgb(c.0, c.1, c.2)
}

#[derive(Default)]
pub struct ErrorMap {
    texture: Option<TextureHandle>,
    /// The source shown: the address of the estimate or true error the texture was made
    /// from, and whether it is the true error.
    shown: Option<(usize, bool)>,
    updated: Option<Instant>,
}

impl ErrorMap {
    /// Shows a frame's estimated error, if it is new and the last update is old enough.
    pub fn show_estimate(&mut self, ctx: &egui::Context, estimate: &Arc<Option<ErrorEstimate>>) {
        if let Some(e) = estimate.as_ref() {
            let key = Arc::as_ptr(estimate) as usize;
            self.show(ctx, (key, false), e.width, e.height, &e.per_pixel);
        }
    }

    /// Shows a frame's true error against the reference, likewise.
    pub fn show_true_error(&mut self, ctx: &egui::Context, error: &Arc<TrueError>) {
        let key = Arc::as_ptr(error) as usize;
        self.show(ctx, (key, true), error.width, error.height, &error.terms);
    }

    fn show(
        &mut self,
        ctx: &egui::Context,
        source: (usize, bool),
        width: usize,
        height: usize,
        terms: &[f32],
    ) {
        if self.shown == Some(source) {
            return;
        }
        if self.updated.is_some_and(|t| t.elapsed() < MIN_INTERVAL) {
            ctx.request_repaint_after(MIN_INTERVAL);
            return;
        }
        let pixels: Vec<Color32> = terms.iter().map(|t| colour(*t)).collect();
        let image = ColorImage::new([width, height], pixels);
        // Nearest texels, as for the image: a pixel's error belongs to that pixel.
        match &mut self.texture {
            Some(t) if t.size() == [width, height] => t.set(image, TextureOptions::NEAREST),
            _ => self.texture = Some(ctx.load_texture("error map", image, TextureOptions::NEAREST)),
        }
        self.shown = Some(source);
        self.updated = Some(Instant::now());
    }

    /// Whether the texture shows `estimate` (tests wait for it).
    pub fn shows(&self, estimate: &Arc<Option<ErrorEstimate>>) -> bool {
        self.texture.is_some() && self.shown == Some((Arc::as_ptr(estimate) as usize, false))
    }

    /// Whether the map shows the true error against a reference (else an estimate).
    pub fn shows_true_error(&self) -> bool {
        self.texture.is_some() && self.shown.is_some_and(|(_, truth)| truth)
    }

    pub fn texture(&self) -> Option<egui::TextureId> {
        self.texture.as_ref().map(TextureHandle::id)
    }

    /// Forgets the texture (a new render started, or the map was hidden).
    pub fn clear(&mut self) {
        *self = ErrorMap::default();
    }
}

/// A colour bar for the map's scale, drawn in the top-left corner of `rect`.
pub fn legend(painter: &egui::Painter, rect: egui::Rect, title: &str, text_color: Color32) {
    let (steps, width, height) = (40, 160.0, 10.0);
    let origin = rect.min + egui::vec2(8.0, 22.0);
    painter.rect_filled(
        egui::Rect::from_min_size(
            origin - egui::vec2(4.0, 18.0),
            egui::vec2(width + 8.0, 48.0),
        ),
        3.0,
        Color32::from_black_alpha(160),
    );
    painter.text(
        origin - egui::vec2(0.0, 4.0),
        egui::Align2::LEFT_BOTTOM,
        title,
        egui::FontId::proportional(11.0),
        text_color,
    );
    for i in 0..steps {
        let h = (i as f32 + 0.5) / steps as f32;
        let log = LOG10_RANGE.0 + h * (LOG10_RANGE.1 - LOG10_RANGE.0);
        let x = origin.x + width * i as f32 / steps as f32;
        painter.rect_filled(
            egui::Rect::from_min_size(
                egui::pos2(x, origin.y),
                egui::vec2(width / steps as f32 + 0.5, height),
            ),
            0.0,
            colour(10f32.powf(log)),
        );
    }
    let font = egui::FontId::proportional(10.0);
    for (i, label) in ["1e-4", "1e-2", "1", "10"].iter().enumerate() {
        let log = [-4.0, -2.0, 0.0, 1.0][i];
        let x = origin.x + width * (log - LOG10_RANGE.0) / (LOG10_RANGE.1 - LOG10_RANGE.0);
        painter.text(
            egui::pos2(x, origin.y + height + 2.0),
            egui::Align2::CENTER_TOP,
            *label,
            font.clone(),
            text_color,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_runs_dark_to_bright_and_clamps() {
        let luma = |c: Color32| c.r() as u32 + c.g() as u32 + c.b() as u32;
        assert!(luma(colour(1e-4)) < luma(colour(1e-2)));
        assert!(luma(colour(1e-2)) < luma(colour(10.0)));
        assert_eq!(colour(0.0), colour(1e-9));
        assert_eq!(colour(1e3), colour(10.0));
        assert_eq!(colour(f32::NAN), colour(1e-4));
    }
}
