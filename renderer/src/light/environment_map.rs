//! An equirectangular (latitude-longitude) environment image: radiance by direction, and the
//! distribution that samples directions in proportion to it.
//!
//! The mapping, in the map's own frame (+Y up): the top row looks straight up, the bottom row
//! straight down, and the centre column faces -Z, the direction a glTF camera looks by
//! default, with u growing towards +X (to the right of that view), so a panorama appears as
//! it does in an image viewer. For a unit direction (x, y, z):
//! theta = acos(y), phi = atan2(x, -z), (u, v) = (1/2 + phi / 2 pi, theta / pi).
//!
//! Radiance is bilinear between texel centres (wrapping in u, clamped in v). The sampling
//! density over (u, v) is piecewise constant per texel, proportional to the mean of that
//! bilinear radiance over the texel times the solid angle the texel covers; the mean is the
//! separable kernel (1/8, 3/4, 1/8) over the texel and its neighbours, so the density is
//! positive wherever the radiance is (pbrt-v4 builds its distribution the same way; within a
//! texel next to a bright one the radiance still varies, so L / pdf is not constant there). A direction's solid-angle
//! density is p(u, v) / (2 pi^2 sin theta) (pbrt-v4 section 12.5.2, eq. 12.7, with its
//! (u, v) to sphere Jacobian for the latitude-longitude map).

use crate::geometry::luminance;
use crate::sampling::distribution::Distribution2D;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::path::Path;

#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    /// Where it came from: a file name, or what generated it.
    pub name: String,
    width: usize,
    height: usize,
    /// Linear RGB radiance, row after row from the top.
    texels: Vec<Vec3>,
    distribution: Distribution2D,
    /// The integral of luminance over the sphere, for the light's power.
    integral: Vec3,
}

impl EnvironmentMap {
    /// A map from linear RGB texels, row after row from the top. Non-finite or negative
    /// values are an error naming the first one.
    pub fn new(
        name: impl Into<String>,
        width: usize,
        height: usize,
        texels: Vec<Vec3>,
    ) -> Result<EnvironmentMap, String> {
        let name = name.into();
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(format!(
                "{name}: {} texels for a {width} x {height} image",
                texels.len()
            ));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(format!(
                "{name}: texel ({}, {}) is {} (radiance must be finite and not negative)",
                i % width,
                i / width,
                texels[i]
            ));
        }
        let texel = |x: isize, y: isize| -> Vec3 {
            let x = x.rem_euclid(width as isize) as usize;
            let y = y.clamp(0, height as isize - 1) as usize;
            texels[y * width + x]
        };
        const KERNEL: [(isize, f32); 3] = [(-1, 0.125), (0, 0.75), (1, 0.125)];
        let mut weights = Vec::with_capacity(width * height);
        let mut integral = Vec3::ZERO;
        for y in 0..height {
            // The solid angle of the texel's row, exactly: 2 pi (cos theta0 - cos theta1) / width.
            let cos = |row: usize| (PI * row as f32 / height as f32).cos();
            let solid_angle = 2.0 * PI * (cos(y) - cos(y + 1)) / width as f32;
            for x in 0..width {
                let mut mean = Vec3::ZERO;
                for (dy, wy) in KERNEL {
                    for (dx, wx) in KERNEL {
                        mean += wx * wy * texel(x as isize + dx, y as isize + dy);
                    }
                }
                integral += mean * solid_angle;
                weights.push(f64::from(luminance(mean) * solid_angle));
            }
        }
        Ok(EnvironmentMap {
            name,
            distribution: Distribution2D::new(&weights, width, height),
            width,
            height,
            texels,
            integral,
        })
    }

    /// Reads an equirectangular Radiance `.hdr` or OpenEXR `.exr` image. Errors name the
    /// file and the problem.
    pub fn load(path: &Path) -> Result<EnvironmentMap, String> {
        let shown = path.display();
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let (width, height, texels) = match extension.as_str() {
            "exr" => {
                let (image, _) = crate::image::read_exr(path).map_err(|e| e.to_string())?;
                (image.width, image.height, image.pixels)
            }
            "hdr" => read_hdr(path).map_err(|e| format!("{shown}: {e}"))?,
            _ => {
                return Err(format!(
                    "{shown}: not an environment image (expected an equirectangular .hdr or .exr)"
                ));
            }
        };
        EnvironmentMap::new(shown.to_string(), width, height, texels)
    }

    /// Says so when the image is not 2:1, as an equirectangular image is (it is read as one
    /// anyway, stretched).
    pub fn aspect_warning(&self) -> Option<String> {
        (self.width != 2 * self.height).then(|| {
            format!(
                "environment {}: {} x {} is not 2:1 as an equirectangular image is; stretched",
                self.name, self.width, self.height
            )
        })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.texels.as_slice()) + self.distribution.memory_bytes()
    }

    /// Radiance integrated over the sphere (W m^-2 per unit of radiance scale).
    pub fn integral(&self) -> Vec3 {
        self.integral
    }

    /// Radiance towards the map's-frame direction `w` (unit), as seen looking along it.
    pub fn radiance(&self, w: Vec3) -> Vec3 {
        self.lookup(direction_to_uv(w))
    }

    /// Bilinear radiance at (u, v).
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = (uv.y * self.height as f32 - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xi = |dx: i64| (x0 as i64 + dx).rem_euclid(self.width as i64) as usize;
        let yi = |dy: usize| (y0 as usize + dy).min(self.height - 1);
        let t = |xx: usize, yy: usize| self.texels[yy * self.width + xx];
        let top = t(xi(0), yi(0)) * (1.0 - fx) + t(xi(1), yi(0)) * fx;
        let bottom = t(xi(0), yi(1)) * (1.0 - fx) + t(xi(1), yi(1)) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// A map's-frame direction in proportion to radiance times solid angle, with its
    /// solid-angle density; None on the poles' measure-zero set.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (uv, pdf_uv) = self.distribution.sample(u);
        let (w, sin_theta) = uv_to_direction(uv);
        (pdf_uv > 0.0 && sin_theta > 0.0).then(|| (w, pdf_uv / (2.0 * PI * PI * sin_theta)))
    }

    /// Solid-angle density of `sample` for the map's-frame direction `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let sin_theta = (1.0 - w.y * w.y).max(0.0).sqrt();
        if sin_theta == 0.0 {
            return 0.0;
        }
        self.distribution.pdf(direction_to_uv(w)) / (2.0 * PI * PI * sin_theta)
    }
}

/// (u, v) in [0,1]^2 for a unit direction in the map's frame.
pub fn direction_to_uv(w: Vec3) -> Vec2 {
    let theta = w.y.clamp(-1.0, 1.0).acos();
    let phi = w.x.atan2(-w.z);
    Vec2::new(
        (0.5 + phi / (2.0 * PI)).clamp(0.0, 1.0),
        (theta / PI).clamp(0.0, 1.0),
    )
}

/// The unit direction at (u, v), and sin theta there.
pub fn uv_to_direction(uv: Vec2) -> (Vec3, f32) {
    let (phi, theta) = ((uv.x - 0.5) * 2.0 * PI, uv.y * PI);
    let (sin_theta, cos_theta) = theta.sin_cos();
    let (sin_phi, cos_phi) = phi.sin_cos();
    (
        Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi),
        sin_theta,
    )
}

/// A Radiance RGBE (`.hdr`) image as linear RGB. A header claiming more than 2 GiB of
/// texels is refused before anything is allocated.
fn read_hdr(path: &Path) -> Result<(usize, usize, Vec<Vec3>), String> {
    let mut reader = image::ImageReader::open(path).map_err(|e| format!("cannot open: {e}"))?;
    reader.set_format(image::ImageFormat::Hdr);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(2 << 30);
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| format!("cannot decode: {e}"))?
        .into_rgb32f();
    let (width, height) = (image.width() as usize, image.height() as usize);
    let texels = image
        .pixels()
        .map(|p| Vec3::new(p.0[0], p.0[1], p.0[2]))
        .collect();
    Ok((width, height, texels))
}
