//! Image textures: texels kept as stored (8-bit RGBA, 4 bytes each, not 16 as linear f32),
//! decoded on lookup through a table (the sRGB curve for colour, /255 for data), with
//! bilinear filtering in linear space and glTF's wrap modes. glTF's texture origin is the
//! top-left corner of the image (spec section 3.8.4.1).

use crate::color::srgb_to_linear;
use glam::{DVec3, Vec2, Vec3, Vec4};
use std::sync::LazyLock;

/// Linear value of each 8-bit code: `[srgb, data]`.
static DECODE: LazyLock<[[f32; 256]; 2]> = LazyLock::new(|| {
    let data = std::array::from_fn(|v| v as f32 / 255.0);
    [data.map(srgb_to_linear), data]
});

/// A texel's linear RGBA; RGB through the sRGB curve when `srgb`.
fn decode([r, g, b, a]: [u8; 4], srgb: bool) -> Vec4 {
    let [srgb_table, data] = &*DECODE;
    let rgb = if srgb { srgb_table } else { data };
    Vec4::new(
        rgb[r as usize],
        rgb[g as usize],
        rgb[b as usize],
        data[a as usize],
    )
}

/// A point's texture coordinates in the sets TEXCOORD_0 and TEXCOORD_1 (the first repeated
/// where a mesh has no second set).
pub type TexCoords = [Vec2; 2];

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
    /// RGBA as stored, row by row from the top.
    texels: Vec<[u8; 4]>,
    /// RGB is sRGB-encoded colour (alpha is always linear).
    srgb: bool,
    /// Mean linear RGB, computed once: every emissive triangle of a textured emitter asks for
    /// it, and summing a 2048^2 texture per triangle took a minute on a 15,000-triangle model.
    mean_rgb: Vec3,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// The sampler's magnification filter: bilinear, or the nearest texel (pixel art,
    /// masks). Minification without mipmaps reads the same way.
    pub nearest: bool,
}

/// The texel index `i` stands for under `wrap`, in `0..n`.
pub(crate) fn wrap_index(i: i64, n: usize, wrap: Wrap) -> usize {
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
    /// A texture from 8-bit RGBA, whose RGB is sRGB-encoded colour when `srgb` (alpha is
    /// linear).
    pub fn from_rgba8(
        width: usize,
        height: usize,
        rgba: &[u8],
        srgb: bool,
        wrap_s: Wrap,
        wrap_t: Wrap,
    ) -> Texture {
        let texels: Vec<[u8; 4]> = rgba
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        // In f64: millions of f32 terms summed in order lose digits.
        let sum = texels.iter().fold(DVec3::ZERO, |sum, &t| {
            sum + decode(t, srgb).truncate().as_dvec3()
        });
        let mean_rgb = if texels.is_empty() {
            Vec3::ONE
        } else {
            (sum / texels.len() as f64).as_vec3()
        };
        Texture {
            width,
            height,
            texels,
            srgb,
            mean_rgb,
            wrap_s,
            wrap_t,
            nearest: false,
        }
    }

    /// Bytes the texels take.
    pub fn texel_bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<[u8; 4]>()
    }

    /// Linear RGB of texel (x, y), both inside the image.
    pub(crate) fn texel_rgb(&self, x: usize, y: usize) -> Vec3 {
        decode(self.texels[y * self.width + x], self.srgb).truncate()
    }

    fn texel(&self, x: i64, y: i64) -> Vec4 {
        decode(
            self.texels[wrap_index(y, self.height, self.wrap_t) * self.width
                + wrap_index(x, self.width, self.wrap_s)],
            self.srgb,
        )
    }

    /// Bilinear lookup at texture coordinate `uv`.
    pub fn lookup(&self, uv: Vec2) -> Vec4 {
        if self.texels.is_empty() || !uv.is_finite() {
            return Vec4::ONE;
        }
        // Texel coordinates kept where i64 and its + 1 stay exact (a file's texture transform
        // can scale by 1e30, found by fuzzing); f32 has no fraction left long before.
        let limit = 1e15;
        let x = (uv.x * self.width as f32).clamp(-limit, limit);
        let y = (uv.y * self.height as f32).clamp(-limit, limit);
        if self.nearest {
            return self.texel(x.floor() as i64, y.floor() as i64);
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean linear RGB, used to estimate the power of textured emitters.
    pub fn mean_rgb(&self) -> Vec3 {
        self.mean_rgb
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
        // Coordinates far outside the image wrap without overflowing.
        for far in [1e30, -1e30, f32::MAX] {
            assert!(t.lookup(Vec2::splat(far)).is_finite());
        }
        let mid = t.lookup(Vec2::new(0.5, 0.5));
        assert!((mid.x - 0.5).abs() < 1e-6);
        assert!((t.lookup(Vec2::new(0.25, 0.5)).x).abs() < 1e-6);
    }

    #[test]
    fn texels_keep_their_bytes_and_decode_colour_through_the_srgb_curve_and_mean() {
        let rgba = [0u8, 64, 128, 255, 200, 17, 255, 99];
        let wrap = Wrap::ClampToEdge;
        let colour = Texture::from_rgba8(2, 1, &rgba, true, wrap, wrap);
        let data = Texture::from_rgba8(2, 1, &rgba, false, wrap, wrap);
        assert_eq!(colour.texel_bytes(), 8);
        for (i, t) in rgba.chunks_exact(4).enumerate() {
            let centre = Vec2::new((i as f32 + 0.5) / 2.0, 0.5);
            let (c, d) = (colour.lookup(centre), data.lookup(centre));
            for k in 0..3 {
                let v = t[k] as f32 / 255.0;
                assert!((c[k] - srgb_to_linear(v)).abs() < 1e-6, "colour {i}.{k}");
                assert!((d[k] - v).abs() < 1e-6, "data {i}.{k}");
            }
            // Alpha is linear in both.
            assert!((c.w - t[3] as f32 / 255.0).abs() < 1e-6);
        }
        let mean = |f: fn(f32) -> f32, k: usize| {
            0.5 * (f(rgba[k] as f32 / 255.0) + f(rgba[4 + k] as f32 / 255.0))
        };
        for k in 0..3 {
            assert!((colour.mean_rgb()[k] - mean(srgb_to_linear, k)).abs() < 1e-6);
            assert!((data.mean_rgb()[k] - mean(|v| v, k)).abs() < 1e-6);
        }
    }

    #[test]
    fn nearest_filtering_reads_one_texel_and_bilinear_blends_two() {
        let texels = [0, 0, 0, 255, 255, 255, 255, 255];
        let mut t = Texture::from_rgba8(2, 1, &texels, false, Wrap::Repeat, Wrap::Repeat);
        assert_eq!(t.lookup(Vec2::new(0.5, 0.5)).x, 0.5);
        t.nearest = true;
        assert_eq!(t.lookup(Vec2::new(0.49, 0.5)).x, 0.0);
        assert_eq!(t.lookup(Vec2::new(0.51, 0.5)).x, 1.0);
        // Wrapped like bilinear lookups: u = 1.2 is texel 0 again.
        assert_eq!(t.lookup(Vec2::new(1.2, 0.5)).x, 0.0);
    }
}
