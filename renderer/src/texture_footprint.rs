//! How much a triangle of a textured emitter emits: the mean luminance of the emissive
//! texture over the triangle's footprint in texture space, for choosing lights by power, and
//! whether the texture is black everywhere the triangle's lookups can reach, in which case the
//! triangle is no light at all (most of a typical emissive map is black, and a light sampler
//! that gave every such triangle the texture's mean power spent most next-event samples on
//! triangles that emit nothing).
//!
//! Per-row prefix sums of each texel's quantised luminance make every row's share of a
//! footprint two lookups, so a triangle costs one step per texel row it covers, whatever its
//! width, and building the table is linear in texels (pbrt-v4 sums texels the same way for its
//! piecewise-constant image distributions).
//!
//! Luminance is quantised up to a multiple of 1/65535 (`ceil`), so sums are exact integers and
//! a sum is zero exactly when every texel in it is black.

use crate::geometry::luminance;
use crate::texture::{Texture, Wrap, wrap_index};
use glam::Vec2;

const QUANTUM: f64 = 65535.0;

/// Prefix sums of quantised luminance along each row of one texture.
pub struct LuminancePrefix {
    width: i64,
    height: usize,
    wrap_s: Wrap,
    wrap_t: Wrap,
    /// `width + 1` sums per row: entry c is the sum over columns 0..c.
    prefix: Vec<u32>,
    /// Mean luminance of the whole texture.
    mean: f32,
}

impl LuminancePrefix {
    /// None for a texture too wide for 32-bit row sums (a fallback, never seen in practice).
    pub fn new(texture: &Texture) -> Option<LuminancePrefix> {
        let (w, h) = (texture.width, texture.height);
        if w == 0 || h == 0 || w >= 65536 {
            return None;
        }
        let mut prefix = Vec::with_capacity((w + 1) * h);
        let mut total = 0u64;
        for y in 0..h {
            let mut sum = 0u32;
            prefix.push(0);
            for x in 0..w {
                let l = luminance(texture.texel_rgb(x, y)).max(0.0) as f64;
                sum += (l * QUANTUM).ceil().min(QUANTUM) as u32;
                prefix.push(sum);
            }
            total += sum as u64;
        }
        Some(LuminancePrefix {
            width: w as i64,
            height: h,
            wrap_s: texture.wrap_s,
            wrap_t: texture.wrap_t,
            prefix,
            mean: (total as f64 / QUANTUM / (w * h) as f64) as f32,
        })
    }

    /// Mean luminance of the whole texture.
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// Sum over texel columns `..c` of stored row `row`, with the wrap mode carrying columns
    /// outside the image (negative for c < 0 under clamping).
    fn columns_before(&self, row: usize, c: i64) -> i64 {
        let w = self.width;
        let p = |i: i64| self.prefix[row * (w as usize + 1) + i as usize] as i64;
        let total = p(w);
        match self.wrap_s {
            Wrap::Repeat => c.div_euclid(w) * total + p(c.rem_euclid(w)),
            Wrap::ClampToEdge if c < 0 => c * p(1),
            Wrap::ClampToEdge if c > w => total + (c - w) * (total - p(w - 1)),
            Wrap::ClampToEdge => p(c),
            Wrap::MirroredRepeat => {
                let m = c.rem_euclid(2 * w);
                let within = if m <= w {
                    p(m)
                } else {
                    2 * total - p(2 * w - m)
                };
                c.div_euclid(2 * w) * 2 * total + within
            }
        }
    }

    /// Sum over texel columns `c0..c1` of texel row `y` (any integer, wrapped).
    fn row_sum(&self, y: i64, c0: i64, c1: i64) -> u64 {
        let row = wrap_index(y, self.height, self.wrap_t);
        (self.columns_before(row, c1) - self.columns_before(row, c0)).max(0) as u64
    }

    /// Mean luminance of the texture over the triangle with texture coordinates `uv`, or None
    /// when every texel a bilinear lookup inside it can touch is black.
    ///
    /// The mean is over the texels whose centres lie inside the footprint (exact for a texture
    /// that is constant on each texel, up to the texels the edges cut); a footprint that holds
    /// no texel centre takes the mean over the texels around it.
    pub fn footprint_mean(&self, uv: [Vec2; 3]) -> Option<f32> {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let p = uv.map(|t| t * size);
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        // Bilinear lookups at x read texels floor(x - 0.5) and the one after.
        let (c0, r0) = ((lo.x - 0.5).floor(), (lo.y - 0.5).floor());
        let (c1, r1) = ((hi.x - 0.5).floor() + 2.0, (hi.y - 0.5).floor() + 2.0);
        let too_large = |span: f32, n: f32| !(span <= 4.0 * n + 4.0);
        if too_large(c1 - c0, size.x) || too_large(r1 - r0, size.y) {
            // Tiled many times over (or not finite): the texture's own mean.
            return (self.mean > 0.0).then_some(self.mean);
        }
        let (c0, c1, r0, r1) = (c0 as i64, c1 as i64, r0 as i64, r1 as i64);
        let around: u64 = (r0..r1).map(|y| self.row_sum(y, c0, c1)).sum();
        if around == 0 {
            return None;
        }
        let (mut inside, mut count) = (0u64, 0i64);
        let first_row = (lo.y - 0.5).ceil() as i64;
        let last_row = (hi.y - 0.5).floor() as i64;
        for row in first_row..=last_row {
            let y = row as f32 + 0.5;
            let Some((xa, xb)) = crossing(&p, y) else {
                continue;
            };
            let (i0, i1) = ((xa - 0.5).ceil() as i64, (xb - 0.5).floor() as i64 + 1);
            if i1 > i0 {
                inside += self.row_sum(row, i0, i1);
                count += i1 - i0;
            }
        }
        let mean = if count > 0 && inside > 0 {
            inside as f64 / count as f64
        } else {
            around as f64 / ((c1 - c0) * (r1 - r0)) as f64
        };
        Some((mean / QUANTUM) as f32)
    }
}

/// Where the horizontal line at height `y` enters and leaves the triangle `p`, if it meets it.
fn crossing(p: &[Vec2; 3], y: f32) -> Option<(f32, f32)> {
    let mut range: Option<(f32, f32)> = None;
    for (a, b) in [(p[0], p[1]), (p[1], p[2]), (p[2], p[0])] {
        let (low, high) = if a.y < b.y { (a, b) } else { (b, a) };
        if !(low.y <= y && y <= high.y) || low.y == high.y {
            continue;
        }
        let x = low.x + (y - low.y) * (high.x - low.x) / (high.y - low.y);
        range = Some(range.map_or((x, x), |(l, h)| (l.min(x), h.max(x))));
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::sample_uniform_triangle;

    /// A data (not sRGB) texture with a pseudo-random grey per texel, black where `black`.
    fn texture(w: usize, h: usize, wrap: Wrap, black: impl Fn(usize, usize) -> bool) -> Texture {
        let mut rgba = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = if black(x, y) {
                    0
                } else {
                    1 + ((x * 7919 + y * 104_729) % 255) as u8
                };
                rgba.extend_from_slice(&[v, v, v, 255]);
            }
        }
        Texture::from_rgba8(w, h, &rgba, false, wrap, wrap)
    }

    /// Deterministic triangles in texture space: small, large, crossing the image's edges.
    fn triangles() -> Vec<[Vec2; 3]> {
        let mut state = 0x2545_f491_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..300)
            .map(|i| {
                let scale = [0.02, 0.3, 1.5][i % 3];
                let c = Vec2::new(next() * 2.0 - 0.5, next() * 2.0 - 0.5);
                [(); 3].map(|_| c + Vec2::new(next() - 0.5, next() - 0.5) * scale)
            })
            .collect()
    }

    fn inside(p: &[Vec2; 3], q: Vec2) -> bool {
        let edge = |a: Vec2, b: Vec2| (b - a).perp_dot(q - a);
        let e = [edge(p[0], p[1]), edge(p[1], p[2]), edge(p[2], p[0])];
        e.iter().all(|&e| e > 0.0) || e.iter().all(|&e| e < 0.0)
    }

    #[test]
    fn the_footprint_mean_is_the_mean_over_the_texel_centres_inside_for_every_wrap_mode() {
        for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
            let t = texture(13, 9, wrap, |_, _| false);
            let prefix = LuminancePrefix::new(&t).unwrap();
            let size = Vec2::new(13.0, 9.0);
            let mut checked = 0;
            for uv in triangles() {
                let p = uv.map(|t| t * size);
                // Brute force: every texel centre of the bounding box, wrapped like a lookup.
                let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
                let (mut sum, mut count) = (0.0f64, 0);
                for y in (lo.y.floor() as i64 - 1)..=(hi.y.ceil() as i64) {
                    for x in (lo.x.floor() as i64 - 1)..=(hi.x.ceil() as i64) {
                        let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        if inside(&p, centre) {
                            let (wx, wy) = (wrap_index(x, 13, wrap), wrap_index(y, 9, wrap));
                            let l = luminance(t.texel_rgb(wx, wy)) as f64;
                            sum += (l * QUANTUM).ceil() / QUANTUM;
                            count += 1;
                        }
                    }
                }
                if count == 0 {
                    continue;
                }
                let expected = sum / count as f64;
                let got = prefix.footprint_mean(uv).unwrap() as f64;
                assert!(
                    (got - expected).abs() <= 1e-6 * expected,
                    "{wrap:?} {uv:?}: {got} against {expected} over {count} texels"
                );
                checked += 1;
            }
            assert!(
                checked >= 100,
                "{wrap:?}: only {checked} triangles held a texel centre"
            );
        }
    }

    #[test]
    fn a_triangle_is_dark_only_where_every_lookup_inside_it_is_black() {
        // Black but for a lit block of texels: triangles far from it must give None, and a
        // triangle that gives None must read black at every point a lookup can hit.
        for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
            let t = texture(16, 16, wrap, |x, y| {
                !(5..8).contains(&x) || !(9..11).contains(&y)
            });
            let prefix = LuminancePrefix::new(&t).unwrap();
            let (mut dark, mut lit) = (0, 0);
            for uv in triangles() {
                let lookups_lit = (0..400).any(|i| {
                    let u = Vec2::new((i % 20) as f32 + 0.5, (i / 20) as f32 + 0.5) / 20.0;
                    let b = sample_uniform_triangle(u);
                    let q = uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2];
                    t.lookup(q).truncate().max_element() > 0.0
                });
                match prefix.footprint_mean(uv) {
                    None => {
                        assert!(!lookups_lit, "{wrap:?} {uv:?} emits but was called dark");
                        dark += 1;
                    }
                    Some(mean) => {
                        assert!(mean > 0.0);
                        lit += 1;
                    }
                }
            }
            assert!(dark >= 20 && lit >= 20, "{wrap:?}: {dark} dark, {lit} lit");
        }
    }

    #[test]
    fn a_uniform_texture_gives_its_value_and_a_black_one_none() {
        let grey = texture(8, 8, Wrap::Repeat, |_, _| false);
        let uniform = Texture::from_rgba8(4, 4, &[200; 64], true, Wrap::Repeat, Wrap::Repeat);
        let prefix = LuminancePrefix::new(&uniform).unwrap();
        let value = luminance(uniform.texel_rgb(0, 0));
        for uv in triangles() {
            let got = prefix.footprint_mean(uv).unwrap();
            assert!(
                (got - value).abs() <= 1.0 / 65535.0,
                "{uv:?}: {got} against {value}"
            );
        }
        let black = Texture::from_rgba8(4, 4, &[0; 64], true, Wrap::Repeat, Wrap::Repeat);
        let prefix = LuminancePrefix::new(&black).unwrap();
        assert!(
            triangles()
                .into_iter()
                .all(|uv| prefix.footprint_mean(uv).is_none())
        );
        assert!(LuminancePrefix::new(&grey).unwrap().mean() > 0.0);
    }
}
