//! Linear RGB images: EXR and PNG output (DESIGN.md section 3), EXR input for references, and
//! the error metrics every part of the project shares.

use crate::color::linear_to_srgb;
use crate::geometry::luminance;
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Linear Rec. 709 RGB, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Vec3>,
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: {message}", path.display())]
    Io { path: PathBuf, message: String },
    #[error("{0}")]
    Invalid(String),
}

fn io_error(path: &Path, message: impl std::fmt::Display) -> ImageError {
    ImageError::Io {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Prefix of the EXR header attributes Caustica writes.
pub const ATTRIBUTE_PREFIX: &str = "caustica:";

impl Image {
    pub fn new(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width * height],
        }
    }

    pub fn pixel(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    pub fn mean_luminance(&self) -> f64 {
        if self.pixels.is_empty() {
            return 0.0;
        }
        self.pixels
            .iter()
            .map(|p| luminance(*p) as f64)
            .sum::<f64>()
            / self.pixels.len() as f64
    }

    pub fn count_non_finite(&self) -> usize {
        self.pixels.iter().filter(|p| !p.is_finite()).count()
    }
}

/// Saves `path` by way of a temporary file beside it, written by `encode`, flushed to the disk
/// and only then renamed over `path` (a rename within a directory is atomic): a save that
/// fails or is interrupted at any point (a full disk, a crash, a power cut) leaves the old
/// file or the new one, never part of one. The error names `path`; no temporary file stays.
pub fn save_atomically(
    path: &Path,
    encode: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<(), String>,
) -> Result<(), ImageError> {
    use std::io::Write;
    let name = path
        .file_name()
        .ok_or_else(|| io_error(path, "not a file name"))?
        .to_string_lossy()
        .into_owned();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let written = std::fs::File::create(&tmp)
        .map_err(|e| e.to_string())
        .and_then(|file| {
            let mut out = std::io::BufWriter::new(file);
            encode(&mut out)?;
            // Flushed here, not on drop, where an error (the disk filling up) would be lost.
            out.flush().map_err(|e| e.to_string())?;
            out.get_ref().sync_all().map_err(|e| e.to_string())
        })
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_error(path, e)
    })
}

/// EXR: float32 RGB, ZIP compression, `metadata` as text attributes named `caustica:KEY`,
/// saved atomically.
pub fn write_exr(
    path: &Path,
    image: &Image,
    metadata: &BTreeMap<String, String>,
) -> Result<(), ImageError> {
    if image.count_non_finite() > 0 {
        return Err(ImageError::Invalid(format!(
            "{} pixels are NaN or infinite",
            image.count_non_finite()
        )));
    }
    save_atomically(path, |out| encode_exr(out, image, metadata))
}

/// `write_exr`'s encoding, to any writer.
pub fn encode_exr(
    out: impl std::io::Write + std::io::Seek,
    image: &Image,
    metadata: &BTreeMap<String, String>,
) -> Result<(), String> {
    use exr::prelude::*;
    let (w, h) = (image.width, image.height);
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = image.pixels[pos.y() * w + pos.x()];
        (p.x, p.y, p.z)
    });
    let mut attributes = LayerAttributes::named("");
    attributes.software_name = Some(Text::from("Caustica"));
    for (k, v) in metadata {
        let key = Text::new_or_none(format!("{ATTRIBUTE_PREFIX}{k}"));
        let value = Text::new_or_none(v.as_str());
        if let (Some(key), Some(value)) = (key, value) {
            attributes.other.insert(key, AttributeValue::Text(value));
        }
    }
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new((w, h), attributes, encoding, channels);
    Image::from_layer(layer)
        .write()
        .to_buffered(out)
        .map_err(|e| e.to_string())
}

/// The most pixels an EXR read here may have (16384 x 8192, an equirectangular 16K
/// environment: 1.5 GiB as float RGB).
pub const MAX_EXR_PIXELS: usize = 16384 * 8192;

/// Reads the first RGB(A) layer of an EXR and its `caustica:` attributes; errors name the
/// file.
pub fn read_exr(path: &Path) -> Result<(Image, BTreeMap<String, String>), ImageError> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
    exr_from_bytes(&bytes).map_err(|e| io_error(path, e))
}

/// The first RGB(A) layer of the EXR file `bytes` and its `caustica:` attributes. Every
/// header's size is checked against `MAX_EXR_PIXELS` before any pixel is allocated: a small
/// file can declare a huge image.
pub fn exr_from_bytes(bytes: &[u8]) -> Result<(Image, BTreeMap<String, String>), String> {
    use exr::prelude::*;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| e.to_string())?;
    for header in &meta.headers {
        let size = header.layer_size;
        if size
            .0
            .checked_mul(size.1)
            .is_none_or(|n| n > MAX_EXR_PIXELS)
        {
            return Err(format!(
                "declares {} x {} pixels, over the limit of {MAX_EXR_PIXELS} (16384 x 8192)",
                size.0, size.1
            ));
        }
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| crate::image::Image::new(resolution.width(), resolution.height()),
            |img: &mut crate::image::Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let w = img.width;
                img.pixels[pos.y() * w + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let mut metadata = BTreeMap::new();
    for (k, v) in &image.layer_data.attributes.other {
        if let (Some(key), AttributeValue::Text(text)) =
            (k.to_string().strip_prefix(ATTRIBUTE_PREFIX), v)
        {
            metadata.insert(key.to_string(), text.to_string());
        }
    }
    Ok((image.layer_data.channel_data.pixels, metadata))
}

/// How linear radiance becomes display values in [0, 1] after exposure. The viewer's shader
/// (app/viewer/tonemap.wgsl) implements the same curves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ToneCurve {
    /// Clamp to [0, 1].
    #[default]
    Linear,
    /// x / (1 + x) per channel (Reinhard et al. 2002, eq. 3).
    Reinhard,
    /// Narkowicz's 2015 fit of the ACES reference rendering transform.
    Filmic,
}

impl ToneCurve {
    pub const ALL: [ToneCurve; 3] = [ToneCurve::Linear, ToneCurve::Reinhard, ToneCurve::Filmic];

    pub fn name(self) -> &'static str {
        match self {
            ToneCurve::Linear => "Linear (clamp)",
            ToneCurve::Reinhard => "Reinhard",
            ToneCurve::Filmic => "Filmic (ACES fit)",
        }
    }

    /// Index passed to the viewer's shader.
    pub fn index(self) -> u32 {
        self as u32
    }

    pub fn apply(self, x: f32) -> f32 {
        let x = x.max(0.0);
        match self {
            ToneCurve::Linear => x.min(1.0),
            ToneCurve::Reinhard => x / (1.0 + x),
            ToneCurve::Filmic => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }
}

/// 8-bit sRGB of what a viewer shows: exposure (in stops), the tone curve, the sRGB curve.
pub fn display_rgb8(image: &Image, exposure: f32, curve: ToneCurve) -> Vec<u8> {
    let scale = 2f32.powf(exposure);
    let mut bytes = Vec::with_capacity(image.pixels.len() * 3);
    for p in &image.pixels {
        for c in [p.x, p.y, p.z] {
            let v = if c.is_finite() {
                linear_to_srgb(curve.apply(c * scale))
            } else {
                0.0
            };
            bytes.push((v * 255.0 + 0.5) as u8);
        }
    }
    bytes
}

/// PNG of what a viewer shows: exposure (in stops) then the sRGB curve, clamped.
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    write_png_tone_mapped(path, image, exposure, ToneCurve::Linear)
}

/// PNG with a tone curve between exposure and the sRGB curve.
pub fn write_png_tone_mapped(
    path: &Path,
    image: &Image,
    exposure: f32,
    curve: ToneCurve,
) -> Result<(), ImageError> {
    let bytes = display_rgb8(image, exposure, curve);
    let buffer = ::image::RgbImage::from_raw(image.width as u32, image.height as u32, bytes)
        .ok_or_else(|| ImageError::Invalid("image size does not match its pixels".into()))?;
    save_atomically(path, |out| {
        buffer
            .write_to(out, ::image::ImageFormat::Png)
            .map_err(|e| e.to_string())
    })
}

/// Error of an image against a reference (DESIGN.md section 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Mean over pixels and channels of (x - r)^2 / (r^2 + 0.01).
    pub rel_mse: f64,
    pub rmse: f64,
    /// Mean luminance of the image over that of the reference.
    pub mean_luminance_ratio: f64,
}

/// Each pixel's term of relMSE against `reference` (the mean over its channels of
/// (x - r)^2 / (r^2 + 0.01)): the true error the viewer maps, whose mean is `compare`'s
/// `rel_mse`.
pub fn rel_mse_terms(image: &Image, reference: &Image) -> Result<Vec<f32>, ImageError> {
    compare(image, reference)?;
    Ok(image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(x, r)| {
            let term = |c: usize| {
                let (x, r) = (x[c] as f64, r[c] as f64);
                (x - r) * (x - r) / (r * r + 0.01)
            };
            ((term(0) + term(1) + term(2)) / 3.0) as f32
        })
        .collect())
}

pub fn compare(image: &Image, reference: &Image) -> Result<ErrorMetrics, ImageError> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(ImageError::Invalid(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        )));
    }
    for (what, img) in [("image", image), ("reference", reference)] {
        let bad = img.count_non_finite();
        if bad > 0 {
            return Err(ImageError::Invalid(format!(
                "{what} has {bad} NaN or infinite pixels"
            )));
        }
    }
    let (mut rel, mut sq) = (0.0f64, 0.0f64);
    for (x, r) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            rel += (x - r) * (x - r) / (r * r + 0.01);
            sq += (x - r) * (x - r);
        }
    }
    let n = (image.pixels.len() * 3).max(1) as f64;
    let ref_lum = reference.mean_luminance();
    Ok(ErrorMetrics {
        rel_mse: rel / n,
        rmse: (sq / n).sqrt(),
        mean_luminance_ratio: if ref_lum > 0.0 {
            image.mean_luminance() / ref_lum
        } else {
            f64::NAN
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_pixel_terms_average_to_rel_mse() {
        let (mut a, mut b) = (Image::new(3, 2), Image::new(3, 2));
        for (i, (p, q)) in a.pixels.iter_mut().zip(b.pixels.iter_mut()).enumerate() {
            *p = glam::Vec3::new(i as f32 * 0.3, 0.5, 2.0 - i as f32 * 0.1);
            *q = glam::Vec3::new(0.2, 0.1 * i as f32, 1.5);
        }
        let terms = rel_mse_terms(&a, &b).unwrap();
        let mean = terms.iter().map(|&t| t as f64).sum::<f64>() / terms.len() as f64;
        let rel = compare(&a, &b).unwrap().rel_mse;
        assert!((mean - rel).abs() < 1e-6 * rel, "{mean} vs {rel}");
        assert!(rel_mse_terms(&a, &Image::new(2, 2)).is_err());
    }

    #[test]
    fn exr_round_trip_keeps_pixels_and_metadata() {
        let dir = std::env::temp_dir().join(format!("caustica-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.exr");
        let mut img = Image::new(3, 2);
        img.pixels[4] = Vec3::new(1.5, 0.25, 1e-3);
        let meta = BTreeMap::from([("integrator".to_string(), "pt".to_string())]);
        write_exr(&path, &img, &meta).unwrap();
        let (back, m) = read_exr(&path).unwrap();
        assert_eq!(back, img);
        assert_eq!(m.get("integrator").map(String::as_str), Some("pt"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn metrics_follow_their_definitions() {
        let r = Image {
            width: 1,
            height: 1,
            pixels: vec![Vec3::splat(1.0)],
        };
        let x = Image {
            width: 1,
            height: 1,
            pixels: vec![Vec3::splat(2.0)],
        };
        let m = compare(&x, &r).unwrap();
        assert!((m.rel_mse - 1.0 / 1.01).abs() < 1e-12);
        assert!((m.rmse - 1.0).abs() < 1e-12);
        assert!((m.mean_luminance_ratio - 2.0).abs() < 1e-6);
        let nan = Image {
            width: 1,
            height: 1,
            pixels: vec![Vec3::NAN],
        };
        assert!(compare(&nan, &r).is_err());
    }

    #[test]
    fn tone_curves_are_monotone_and_bounded() {
        for curve in ToneCurve::ALL {
            let mut last = 0.0;
            for i in 0..1000 {
                let y = curve.apply(i as f32 * 0.05);
                assert!(
                    (0.0..=1.0).contains(&y) && y >= last,
                    "{curve:?} at {}",
                    i as f32 * 0.05
                );
                last = y;
            }
            assert_eq!(curve.apply(0.0), 0.0);
        }
        assert!((ToneCurve::Reinhard.apply(1.0) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn failed_write_names_the_file() {
        let e = write_exr(
            Path::new("/nonexistent-dir/x.exr"),
            &Image::new(1, 1),
            &BTreeMap::new(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("/nonexistent-dir/x.exr"));
    }

    /// A writer that takes `left` bytes and then fails as a full disk does.
    struct FullAfter<W> {
        inner: W,
        left: usize,
    }

    impl<W: std::io::Write> std::io::Write for FullAfter<W> {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.left == 0 {
                return Err(std::io::ErrorKind::StorageFull.into());
            }
            let n = buf.len().min(self.left);
            self.left -= n;
            self.inner.write(&buf[..n])
        }

        fn flush(&mut self) -> std::io::Result<()> {
            self.inner.flush()
        }
    }

    impl<W: std::io::Seek> std::io::Seek for FullAfter<W> {
        fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
            self.inner.seek(pos)
        }
    }

    /// A save that fails at any byte of the new file (a disk that fills up there) reports the
    /// file and the cause, and leaves the old file whole and no temporary file beside it.
    #[test]
    fn a_save_failing_at_any_byte_leaves_the_old_file() {
        let dir = std::env::temp_dir().join(format!("caustica-save-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("snapshot.exr");
        let mut old = Image::new(16, 8);
        old.pixels.fill(Vec3::new(0.25, 0.5, 1.0));
        let metadata = BTreeMap::from([("passes".to_string(), "1".to_string())]);
        write_exr(&path, &old, &metadata).unwrap();
        let mut new = Image::new(16, 8);
        for (i, p) in new.pixels.iter_mut().enumerate() {
            *p = Vec3::splat(i as f32 / 7.0);
        }
        let mut encoded = std::io::Cursor::new(Vec::new());
        encode_exr(&mut encoded, &new, &metadata).unwrap();
        let length = encoded.get_ref().len();
        let offsets: Vec<usize> = (0..length)
            .step_by(length / 50)
            .chain([length - 1])
            .collect();
        for &k in &offsets {
            let e = save_atomically(&path, |out| {
                encode_exr(
                    FullAfter {
                        inner: out,
                        left: k,
                    },
                    &new,
                    &metadata,
                )
            })
            .unwrap_err()
            .to_string();
            assert!(e.contains("snapshot.exr"), "{e}");
            assert!(e.contains("storage full") || e.contains("space"), "{e}");
            assert_eq!(
                read_exr(&path).unwrap().0.pixels,
                old.pixels,
                "failed at {k}"
            );
            assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "failed at {k}");
        }
        let e = save_atomically(&dir.join("view.png"), |out| {
            let png = FullAfter {
                inner: out,
                left: 40,
            };
            let bytes = display_rgb8(&new, 0.0, ToneCurve::Linear);
            ::image::RgbImage::from_raw(16, 8, bytes)
                .unwrap()
                .write_to(&mut { png }, ::image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        });
        assert!(e.is_err());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        write_exr(&path, &new, &metadata).unwrap();
        assert_eq!(read_exr(&path).unwrap().0.pixels, new.pixels);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
