//! Texture references (glTF 2.0 section 3.8) with KHR_texture_transform, their samplers'
//! wrap modes and filters, and their images: each decoded once to RGBA8 (8- and 16-bit
//! PNGs and JPEGs), its size read from the header and refused above the texel limit before
//! anything is decoded; an image that cannot be read is a warning, not an error.

use super::{Loader, TransformParts, err};
use crate::material::TextureRef;
use crate::scene::SceneError;
use crate::scene::limits::LoadLimits;
use crate::texture::{Texture, Wrap};
use glam::{Affine2, Vec2};

impl Loader<'_> {
    /// A textureInfo (spec 5.29) `info`, named `name` inside the extension at JSON path `at`,
    /// that the gltf crate does not parse.
    pub(super) fn json_texture_info(
        &mut self,
        info: &serde_json::Value,
        at: &str,
        name: &str,
        srgb: bool,
    ) -> Result<Option<TextureRef>, SceneError> {
        let info: gltf::json::texture::Info =
            serde_json::from_value(info.clone()).map_err(|e| err(format!("{at}.{name}: {e}")))?;
        let Some(texture) = self.document.textures().nth(info.index.value()) else {
            return Err(err(format!(
                "{at}.{name}: texture {} does not exist",
                info.index.value()
            )));
        };
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        let parts = transform.map(|t| (t.offset.0, t.rotation.0, t.scale.0, t.tex_coord));
        let (transform, tex_coord) = self.transform(texture.index(), parts, info.tex_coord);
        Ok(self.texture(&texture, tex_coord, transform, srgb))
    }

    /// The size an image's header declares, refused above the texel limit before anything is
    /// decoded: a few hundred kilobytes of PNG can declare 20000 x 20000 texels, gigabytes
    /// once decoded. Headers that cannot be read are left to the decoder to report.
    fn check_image_size(&self, image: &gltf::Image) -> Result<(), String> {
        let from_uri;
        let bytes: &[u8] = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                &buffer[view.offset()..view.offset() + view.length()]
            }
            gltf::image::Source::Uri { uri, .. } => {
                match gltf::buffer::Data::from_source_and_blob(
                    gltf::buffer::Source::Uri(uri),
                    Some(self.base),
                    &mut None,
                ) {
                    Ok(data) => {
                        from_uri = data.0;
                        &from_uri
                    }
                    Err(_) => return Ok(()),
                }
            }
        };
        let Ok(reader) = image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format()
        else {
            return Ok(());
        };
        let Ok((width, height)) = reader.into_dimensions() else {
            return Ok(());
        };
        let texels = u64::from(width) * u64::from(height);
        if texels > self.limits.max_texels {
            return Err(LoadLimits::refusal(
                &format!("declares {width} x {height} texels"),
                self.limits.max_texels,
                "--max-texels",
            ));
        }
        Ok(())
    }

    /// Decodes an image once, to RGBA8; None (with a warning) when it cannot be read.
    fn image_rgba8(&mut self, image: &gltf::Image) -> Option<(usize, usize, Vec<u8>)> {
        if let Some(cached) = self.images.get(&image.index()) {
            return cached.clone();
        }
        if let Err(problem) = self.check_image_size(image) {
            self.desc.warnings.push(format!(
                "image {}: {problem}; texture ignored",
                image.index()
            ));
            self.images.insert(image.index(), None);
            return None;
        }
        let decoded =
            match gltf::image::Data::from_source(image.source(), Some(self.base), self.buffers) {
                Ok(data) => to_rgba8(&data),
                Err(e) => {
                    self.desc.warnings.push(format!(
                        "image {}: cannot be read ({e}); texture ignored",
                        image.index()
                    ));
                    None
                }
            };
        self.images.insert(image.index(), decoded.clone());
        decoded
    }

    /// A texture reference with KHR_texture_transform's offset, rotation and scale, applied
    /// as the ratified extension's GLSL says: uv' = T(offset) R(rotation) S(scale) uv, where R
    /// has columns (cos, -sin) and (sin, cos): a rotation by -rotation in (u, v), which is
    /// counter-clockwise on the image since v points down (the Khronos TextureTransformTest
    /// model's markers confirm the direction). The extension's texCoord overrides the
    /// reference's.
    pub(super) fn texture_info(
        &mut self,
        info: &gltf::texture::Info,
        srgb: bool,
    ) -> Option<TextureRef> {
        let parts = info
            .texture_transform()
            .map(|t| (t.offset(), t.rotation(), t.scale(), t.tex_coord()));
        let (transform, tex_coord) =
            self.transform(info.texture().index(), parts, info.tex_coord());
        self.texture(&info.texture(), tex_coord, transform, srgb)
    }

    /// The map and TEXCOORD set of a texture reference from KHR_texture_transform's
    /// (offset, rotation, scale, texCoord), when it has one (see `texture_info`).
    pub(super) fn transform(
        &mut self,
        texture: usize,
        parts: Option<TransformParts>,
        tex_coord: u32,
    ) -> (Affine2, u32) {
        let Some((offset, rotation, scale, set)) = parts else {
            return (Affine2::IDENTITY, tex_coord);
        };
        let transform =
            Affine2::from_scale_angle_translation(Vec2::from(scale), -rotation, Vec2::from(offset));
        let tex_coord = set.unwrap_or(tex_coord);
        if transform.is_finite() {
            (transform, tex_coord)
        } else {
            self.desc.warnings.push(format!(
                "texture {texture}: KHR_texture_transform is not finite, ignored"
            ));
            (Affine2::IDENTITY, tex_coord)
        }
    }

    pub(super) fn texture(
        &mut self,
        texture: &gltf::Texture,
        tex_coord: u32,
        transform: Affine2,
        srgb: bool,
    ) -> Option<TextureRef> {
        let tex_coord = if tex_coord > 1 {
            self.desc.warnings.push(format!(
                "textures[{}]: TEXCOORD_{tex_coord} is not supported (only 0 and 1), read at TEXCOORD_0",
                texture.index()
            ));
            0
        } else {
            tex_coord
        };
        let reference = |texture| TextureRef {
            texture,
            tex_coord,
            transform,
        };
        let key = (texture.index(), srgb);
        if let Some(&i) = self.texture_index.get(&key) {
            return Some(reference(i));
        }
        let (w, h, rgba) = self.image_rgba8(&texture.source())?;
        let wrap = |m: gltf::texture::WrappingMode| match m {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        let sampler = texture.sampler();
        let mut tex = Texture::from_rgba8(
            w,
            h,
            &rgba,
            srgb,
            wrap(sampler.wrap_s()),
            wrap(sampler.wrap_t()),
        );
        tex.nearest = sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest);
        let i = self.desc.textures.len() as u32;
        self.desc.textures.push(tex);
        self.texture_index.insert(key, i);
        Some(reference(i))
    }
}

fn to_rgba8(data: &gltf::image::Data) -> Option<(usize, usize, Vec<u8>)> {
    use gltf::image::Format;
    let (w, h) = (data.width as usize, data.height as usize);
    let px = &data.pixels;
    let n = w.checked_mul(h)?;
    let (channels, bytes) = match data.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        _ => return None,
    };
    if px.len() < n * channels * bytes || n == 0 {
        return None;
    }
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        // 16-bit channels are little-endian; their high byte is the 8-bit value.
        let c = |k: usize| px[(i * channels + k) * bytes + bytes - 1];
        let rgba = match channels {
            1 => [c(0), c(0), c(0), 255],
            2 => [c(0), c(1), 0, 255],
            3 => [c(0), c(1), c(2), 255],
            _ => [c(0), c(1), c(2), c(3)],
        };
        out.extend_from_slice(&rgba);
    }
    Some((w, h, out))
}
