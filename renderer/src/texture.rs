//! Image textures: linear RGBA in f32, bilinear lookup with glTF's wrap modes.
//! glTF's texture origin is the top-left corner of the image (spec section 3.8.4.1).

use crate::color::srgb_to_linear;
use glam::{Vec2, Vec3, Vec4};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

#[derive(Clone, Debug)]
pub struct Texture {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec4>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

fn wrap_index(i: i64, n: usize, wrap: Wrap) -> usize {
    let n = n as i64;
    let i = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    };
    i as usize
}

impl Texture {
    /// A texture from 8-bit RGBA, decoding the sRGB curve on RGB when `srgb` (alpha is linear).
    pub fn from_rgba8(
        width: usize,
        height: usize,
        rgba: &[u8],
        srgb: bool,
        wrap_s: Wrap,
        wrap_t: Wrap,
    ) -> Texture {
        let texels = rgba
            .chunks_exact(4)
            .map(|c| {
                let f = |v: u8| {
                    let x = v as f32 / 255.0;
                    if srgb { srgb_to_linear(x) } else { x }
                };
                Vec4::new(f(c[0]), f(c[1]), f(c[2]), c[3] as f32 / 255.0)
            })
            .collect();
        Texture {
            width,
            height,
            texels,
            wrap_s,
            wrap_t,
        }
    }

    fn texel(&self, x: i64, y: i64) -> Vec4 {
        self.texels[wrap_index(y, self.height, self.wrap_t) * self.width
            + wrap_index(x, self.width, self.wrap_s)]
    }

    /// Bilinear lookup at texture coordinate `uv`.
    pub fn lookup(&self, uv: Vec2) -> Vec4 {
        if self.texels.is_empty() || !uv.is_finite() {
            return Vec4::ONE;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean RGB, used to estimate the power of textured emitters.
    pub fn mean_rgb(&self) -> Vec3 {
        if self.texels.is_empty() {
            return Vec3::ONE;
        }
        let sum: Vec4 = self.texels.iter().copied().sum();
        (sum / self.texels.len() as f32).truncate()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap_index(-1, 4, Wrap::Repeat), 3);
        assert_eq!(wrap_index(5, 4, Wrap::ClampToEdge), 3);
        assert_eq!(wrap_index(4, 4, Wrap::MirroredRepeat), 3);
        assert_eq!(wrap_index(-1, 4, Wrap::MirroredRepeat), 0);
    }

    #[test]
    fn bilinear_lookup_interpolates_between_texel_centres() {
        let t = Texture::from_rgba8(
            2,
            1,
            &[0, 0, 0, 255, 255, 255, 255, 255],
            false,
            Wrap::ClampToEdge,
            Wrap::ClampToEdge,
        );
        let mid = t.lookup(Vec2::new(0.5, 0.5));
        assert!((mid.x - 0.5).abs() < 1e-6);
        assert!((t.lookup(Vec2::new(0.25, 0.5)).x).abs() < 1e-6);
    }
}
