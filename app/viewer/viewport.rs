//! The image view: fit to the panel or a chosen zoom, zoom about the cursor with the wheel,
//! pan by dragging, and a pixel inspector on hover; the camera's gestures (right drag, middle
//! drag, Ctrl + wheel) are collected for the app to turn into camera moves. The pixels are drawn by the GPU tone
//! mapper (`tonemap`); the frame is uploaded only when a new one arrived.

use crate::viewer::error_map;
use crate::viewer::tonemap::{self, TonemapCallback};
use caustica_renderer::error_estimate::ErrorEstimate;
use caustica_renderer::image::{Image, ToneCurve};
use caustica_renderer::integrators::PixelLayer;
use eframe::egui::{self, Pos2, Rect, Sense, Vec2};
use eframe::egui_wgpu;
use std::sync::Arc;
use std::time::Duration;

/// Mouse moves that move the camera, in fractions of the view's height (wheel: its points).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraGesture {
    pub orbit: Vec2,
    pub pan: Vec2,
    pub dolly: f32,
}

impl CameraGesture {
    pub fn is_empty(&self) -> bool {
        *self == CameraGesture::default()
    }
}

/// The pixel under the cursor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoveredPixel {
    pub x: u32,
    pub y: u32,
    pub rgb: glam::Vec3,
}

#[derive(Default)]
pub struct Viewport {
    /// Screen points per image pixel; None fits the image to the panel.
    zoom: Option<f32>,
    /// Camera gestures since the app last took them.
    gesture: CameraGesture,
    /// Image coordinates at the panel's centre (used when not fitting).
    center: Vec2,
    uploaded: Option<Arc<Image>>,
    /// Where the image was last drawn, in screen points, and the image drawn there.
    pub shown: Option<(Rect, Arc<Image>)>,
    /// Duration of the last frame upload (conversion and copy to the GPU).
    pub last_upload: Option<Duration>,
    pub uploads: u64,
}

impl Viewport {
    /// The camera gestures made since the last call.
    pub fn take_gesture(&mut self) -> CameraGesture {
        std::mem::take(&mut self.gesture)
    }

    pub fn fit(&mut self) {
        self.zoom = None;
    }

    /// One image pixel per physical screen pixel.
    pub fn one_to_one(&mut self, pixels_per_point: f32, image_size: Vec2) {
        if self.zoom.is_none() {
            self.center = image_size / 2.0;
        }
        self.zoom = Some(1.0 / pixels_per_point);
    }

    pub fn is_fit(&self) -> bool {
        self.zoom.is_none()
    }

    /// Draws `image` (and over it, if given, the `overlay` texture of the same size, the
    /// estimated-error map, with its scale); the inspector shows the integrator's `layers`
    /// and the pixel's estimated error.
    #[allow(clippy::too_many_arguments)]
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        render_state: Option<&egui_wgpu::RenderState>,
        image: Option<&Arc<Image>>,
        layers: &[PixelLayer],
        error: Option<&ErrorEstimate>,
        overlay: Option<(egui::TextureId, &str)>,
        exposure: f32,
        curve: ToneCurve,
    ) -> Option<HoveredPixel> {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let image = image?;
        let size = Vec2::new(image.width as f32, image.height as f32);
        let fit = (rect.width() / size.x)
            .min(rect.height() / size.y)
            .max(1e-6);
        let mut zoom = self.zoom.unwrap_or(fit);
        if self.zoom.is_none() {
            self.center = size / 2.0;
        }

        // The camera's gestures: right drag orbits, middle (or Shift + right) drag pans,
        // Ctrl + wheel dollies; as fractions of the view's height.
        let height = rect.height().max(1.0);
        let shift = ui.input(|i| i.modifiers.shift);
        if response.dragged_by(egui::PointerButton::Secondary) && !shift {
            self.gesture.orbit += response.drag_delta() / height;
        }
        if response.dragged_by(egui::PointerButton::Middle)
            || (response.dragged_by(egui::PointerButton::Secondary) && shift)
        {
            self.gesture.pan += response.drag_delta() / height;
        }
        let ctrl = ui.input(|i| i.modifiers.command);
        if let Some(cursor) = response.hover_pos() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 && ctrl {
                self.gesture.dolly += scroll;
            } else if scroll != 0.0 {
                // Zoom about the cursor: the image point under it stays under it.
                let under = self.center + (cursor - rect.center()) / zoom;
                let new_zoom = (zoom * (scroll * 0.002).exp()).clamp(fit.min(1.0) * 0.1, 256.0);
                self.center = under - (cursor - rect.center()) / new_zoom;
                zoom = new_zoom;
                self.zoom = Some(zoom);
            }
        }
        if response.dragged_by(egui::PointerButton::Primary) {
            self.center -= response.drag_delta() / zoom;
            self.zoom = Some(zoom);
        }

        if let Some(rs) = render_state
            && !self
                .uploaded
                .as_ref()
                .is_some_and(|u| Arc::ptr_eq(u, image))
        {
            self.last_upload = Some(tonemap::upload(rs, image));
            self.uploads += 1;
            self.uploaded = Some(image.clone());
        }

        let image_rect = Rect::from_min_size(rect.center() - self.center * zoom, size * zoom);
        let visible = image_rect.intersect(rect);
        self.shown = Some((image_rect, image.clone()));
        if visible.is_positive() {
            match render_state {
                Some(_) => {
                    let uv = |p: Pos2| ((p - image_rect.min) / image_rect.size()).into();
                    let callback = TonemapCallback {
                        uv_min: uv(visible.min),
                        uv_max: uv(visible.max),
                        exposure,
                        curve,
                    };
                    ui.painter()
                        .add(egui_wgpu::Callback::new_paint_callback(visible, callback));
                }
                None => {
                    ui.painter().text(
                        rect.center(),
                        egui::Align2::CENTER_CENTER,
                        "no GPU display",
                        Default::default(),
                        ui.visuals().text_color(),
                    );
                }
            }
            if let Some((texture, title)) = overlay {
                let uv = |p: Pos2| ((p - image_rect.min) / image_rect.size()).to_pos2();
                ui.painter().image(
                    texture,
                    visible,
                    Rect::from_min_max(uv(visible.min), uv(visible.max)),
                    egui::Color32::WHITE,
                );
                error_map::legend(ui.painter(), rect, title, egui::Color32::WHITE);
            }
        }

        let pos = response.hover_pos()?;
        let p = self.center + (pos - rect.center()) / zoom;
        if p.x < 0.0 || p.y < 0.0 || p.x >= size.x || p.y >= size.y {
            return None;
        }
        let (x, y) = (p.x as u32, p.y as u32);
        let hovered = HoveredPixel {
            x,
            y,
            rgb: image.pixel(x as usize, y as usize),
        };
        response.on_hover_ui_at_pointer(|ui| {
            ui.label(format!("pixel ({x}, {y})"));
            ui.monospace(format!(
                "R {:.4}\nG {:.4}\nB {:.4}",
                hovered.rgb.x, hovered.rgb.y, hovered.rgb.z
            ));
            let index = y as usize * image.width + x as usize;
            for layer in layers {
                if let Some(v) = layer.values.get(index) {
                    ui.monospace(format!("{} {v:.6}", layer.name));
                }
            }
            if let Some(v) = error
                .filter(|e| (e.width, e.height) == (image.width, image.height))
                .and_then(|e| e.per_pixel.get(index))
            {
                let text = egui::RichText::new(format!("est. relMSE {v:.3e}")).monospace();
                ui.add(egui::Label::new(text).extend());
            }
        });
        Some(hovered)
    }
}
