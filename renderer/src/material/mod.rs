//! Materials and BSDFs. A `Material` is the scene's description (glTF factors and textures);
//! at a surface hit it becomes a `Bsdf`, a closed enum of the four kinds DESIGN.md section 2
//! names, each modelling only what it needs. All BSDFs work in the local shading frame (+z is
//! the shading normal) and serve both faces of a surface.

pub mod clearcoat;
pub mod dielectric;
pub mod diffuse;
pub mod layering;
mod layering_table;
pub mod metallic_roughness;
pub mod microfacet;
pub mod mirror;
pub mod sheen;

#[cfg(test)]
mod tests;

use crate::texture::{TexCoords, Texture};
use clearcoat::Clearcoat;
use dielectric::DielectricBsdf;
use diffuse::DiffuseBsdf;
use glam::{Affine2, Vec2, Vec3};
use metallic_roughness::MetallicRoughnessBsdf;
use microfacet::TrowbridgeReitz;
use mirror::MirrorBsdf;
use sheen::Sheen;

/// Whether a path carries radiance (from the camera) or importance (from a light); it matters
/// for refraction's 1/eta^2 scaling (Veach's thesis, section 5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// A sampled direction: `f` the BSDF value, `pdf` its solid-angle density (the discrete
/// probability for a delta lobe), `eta` the relative index crossed (1 for reflection).
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub f: Vec3,
    pub wi: Vec3,
    pub pdf: f32,
    pub is_delta: bool,
    pub eta: f32,
}

impl BsdfSample {
    pub fn reflection(f: Vec3, wi: Vec3, pdf: f32, is_delta: bool) -> Self {
        BsdfSample {
            f,
            wi,
            pdf,
            is_delta,
            eta: 1.0,
        }
    }

    pub fn transmission(f: Vec3, wi: Vec3, pdf: f32, is_delta: bool, eta: f32) -> Self {
        BsdfSample {
            f,
            wi,
            pdf,
            is_delta,
            eta,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub enum Bsdf {
    Diffuse(DiffuseBsdf),
    Mirror(MirrorBsdf),
    Dielectric(DielectricBsdf),
    MetallicRoughness(MetallicRoughnessBsdf),
}

impl Bsdf {
    /// True when every lobe is a delta distribution (no point in next-event estimation).
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror(_) | Bsdf::Dielectric(_))
    }

    /// True when light arriving from `wo` (shading frame) at a smooth dielectric is all
    /// reflected: beyond the critical angle, total internal reflection. Reciprocal (the
    /// reflected direction makes the same angle), so a camera path and a photon path through
    /// the same vertex agree on it (`ppm/trapped_light.rs` relies on that).
    pub fn totally_reflects(&self, wo: Vec3) -> bool {
        match self {
            Bsdf::Dielectric(d) => {
                d.eta != 1.0 && microfacet::fresnel_dielectric(wo.z, d.eta) >= 1.0
            }
            _ => false,
        }
    }

    /// True when a lobe spreads light over the whole hemisphere (diffuse, or the diffuse
    /// base of a plastic): where photon mapping leaves its hit points (`ppm/hit_points.rs`).
    pub fn has_diffuse_lobe(&self) -> bool {
        match self {
            Bsdf::Diffuse(_) => true,
            Bsdf::MetallicRoughness(b) => b.has_diffuse_lobe(),
            Bsdf::Mirror(_) | Bsdf::Dielectric(_) => false,
        }
    }

    /// The roughness (alpha) of its microfacet lobes, if it has any.
    pub fn microfacet_alpha(&self) -> Option<f32> {
        match self {
            Bsdf::MetallicRoughness(b) => Some(b.distrib.alpha),
            _ => None,
        }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        match self {
            Bsdf::Diffuse(b) => b.f(wo, wi),
            Bsdf::MetallicRoughness(b) => b.f(wo, wi, mode),
            Bsdf::Mirror(_) | Bsdf::Dielectric(_) => Vec3::ZERO,
        }
    }

    /// Samples wi given wo; `uc` picks a lobe, `u` the direction within it.
    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let s = match self {
            Bsdf::Diffuse(b) => b.sample_f(wo, u),
            Bsdf::Mirror(b) => b.sample_f(wo),
            Bsdf::Dielectric(b) => b.sample_f(wo, uc, mode),
            Bsdf::MetallicRoughness(b) => b.sample_f(wo, uc, u, mode),
        }?;
        (s.pdf > 0.0 && s.f.is_finite() && s.wi.is_finite()).then_some(s)
    }

    /// Solid-angle pdf of `sample_f` choosing wi (zero for delta BSDFs).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(b) => b.pdf(wo, wi),
            Bsdf::MetallicRoughness(b) => b.pdf(wo, wi),
            Bsdf::Mirror(_) | Bsdf::Dielectric(_) => 0.0,
        }
    }
}

/// A texture reference: index into the scene's textures, the TEXCOORD set it reads (0 or 1)
/// and the affine map KHR_texture_transform applies to that set's coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: u32,
    pub tex_coord: u32,
    pub transform: Affine2,
}

impl TextureRef {
    /// Texture `texture` read at TEXCOORD_0 as it stands.
    pub fn new(texture: u32) -> TextureRef {
        TextureRef {
            texture,
            tex_coord: 0,
            transform: Affine2::IDENTITY,
        }
    }

    /// Where this reference looks its texture up at a point with coordinates `uv`.
    pub fn uv(&self, uv: &TexCoords) -> Vec2 {
        let set = uv[(self.tex_coord as usize).min(1)];
        self.transform.transform_point2(set)
    }
}

/// Which BSDF a material needs, decided once from its factors (DESIGN.md section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    Diffuse,
    Mirror,
    Dielectric,
    MetallicRoughness,
}

/// A glTF material, with the defaults of the glTF spec.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color: Vec3,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Roughness in G, metalness in B (glTF spec 3.9.2).
    pub metallic_roughness_texture: Option<TextureRef>,
    pub transmission: f32,
    pub ior: f32,
    /// emissiveFactor x KHR_materials_emissive_strength.
    pub emission: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub normal_texture: Option<(TextureRef, f32)>,
    pub double_sided: bool,
    /// Absorption coefficient (per scene unit) inside a closed mesh of this material
    /// (KHR_materials_volume); zero outside the extension.
    pub absorption: Vec3,
    /// baseColorFactor's alpha (times the base colour texture's alpha where there is one).
    pub alpha: f32,
    pub alpha_mode: AlphaMode,
    /// KHR_materials_specular: specularFactor and its texture (alpha channel).
    pub specular: f32,
    pub specular_texture: Option<TextureRef>,
    /// KHR_materials_specular: specularColorFactor and its texture (sRGB).
    pub specular_color: Vec3,
    pub specular_color_texture: Option<TextureRef>,
    /// KHR_materials_clearcoat: clearcoatFactor and its texture (R channel).
    pub clearcoat: f32,
    pub clearcoat_texture: Option<TextureRef>,
    /// KHR_materials_clearcoat: clearcoatRoughnessFactor and its texture (G channel).
    pub clearcoat_roughness: f32,
    pub clearcoat_roughness_texture: Option<TextureRef>,
    /// KHR_materials_sheen: sheenColorFactor and its texture (sRGB).
    pub sheen_color: Vec3,
    pub sheen_color_texture: Option<TextureRef>,
    /// KHR_materials_sheen: sheenRoughnessFactor and its texture (alpha channel).
    pub sheen_roughness: f32,
    pub sheen_roughness_texture: Option<TextureRef>,
}

/// glTF's alphaMode (spec 3.9.4): how a surface's alpha decides where it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha ignored: the surface is everywhere.
    Opaque,
    /// A cut-out: the surface is where alpha >= the cutoff, and nothing elsewhere.
    Mask(f32),
    /// Partly there: a ray finds the surface with probability alpha (stochastic
    /// transparency), so on average it lets 1 - alpha of the light through.
    Blend,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: Vec3::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            transmission: 0.0,
            ior: 1.5,
            emission: Vec3::ZERO,
            emissive_texture: None,
            normal_texture: None,
            double_sided: false,
            absorption: Vec3::ZERO,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            specular: 1.0,
            specular_texture: None,
            specular_color: Vec3::ONE,
            specular_color_texture: None,
            clearcoat: 0.0,
            clearcoat_texture: None,
            clearcoat_roughness: 0.0,
            clearcoat_roughness_texture: None,
            sheen_color: Vec3::ZERO,
            sheen_color_texture: None,
            sheen_roughness: 0.0,
            sheen_roughness_texture: None,
        }
    }
}

impl Material {
    pub fn diffuse(base_color: Vec3) -> Material {
        Material {
            base_color,
            metallic: 0.0,
            roughness: 1.0,
            ..Default::default()
        }
    }

    /// glTF's metallic-roughness model with constant factors.
    pub fn metallic_roughness(base_color: Vec3, metallic: f32, roughness: f32) -> Material {
        Material {
            base_color,
            metallic,
            roughness,
            ..Default::default()
        }
    }

    /// Smooth, clear glass (KHR_materials_transmission at 1) of index of refraction `ior`.
    pub fn glass(ior: f32) -> Material {
        Material {
            transmission: 1.0,
            ior,
            ..Material::metallic_roughness(Vec3::ONE, 0.0, 0.0)
        }
    }

    /// A diffuse emitter of radiance `emission` that reflects with albedo `albedo`.
    pub fn emitter(emission: Vec3, albedo: Vec3) -> Material {
        Material {
            emission,
            ..Material::diffuse(albedo)
        }
    }

    /// The same material under `name`.
    pub fn named(self, name: &str) -> Material {
        Material {
            name: name.into(),
            ..self
        }
    }

    /// Whether KHR_materials_specular, _clearcoat or _sheen change the metallic-roughness
    /// model (only that BSDF has their layers).
    fn has_layers(&self) -> bool {
        self.specular != 1.0
            || self.specular_texture.is_some()
            || self.specular_color != Vec3::ONE
            || self.specular_color_texture.is_some()
            || self.clearcoat > 0.0
            || self.sheen_color.max_element() > 0.0
    }

    pub fn kind(&self) -> MaterialKind {
        let factors_only = self.metallic_roughness_texture.is_none() && !self.has_layers();
        if factors_only && self.transmission > 0.0 && self.roughness == 0.0 && self.metallic == 0.0
        {
            MaterialKind::Dielectric
        } else if factors_only && self.metallic == 1.0 && self.roughness == 0.0 {
            MaterialKind::Mirror
        } else if factors_only
            && self.metallic == 0.0
            && self.roughness == 1.0
            && self.transmission == 0.0
        {
            MaterialKind::Diffuse
        } else {
            MaterialKind::MetallicRoughness
        }
    }

    /// Alpha at a point with texture coordinates `uv`.
    pub fn alpha_at(&self, textures: &[Texture], uv: &TexCoords) -> f32 {
        self.alpha * Self::texture_rgba(textures, self.base_color_texture, uv).w
    }

    /// Every texture the material reads.
    pub fn texture_refs(&self) -> impl Iterator<Item = TextureRef> {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.emissive_texture,
            self.normal_texture.map(|(r, _)| r),
            self.specular_texture,
            self.specular_color_texture,
            self.clearcoat_texture,
            self.clearcoat_roughness_texture,
            self.sheen_color_texture,
            self.sheen_roughness_texture,
        ]
        .into_iter()
        .flatten()
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    fn texture_rgba(textures: &[Texture], t: Option<TextureRef>, uv: &TexCoords) -> glam::Vec4 {
        t.and_then(|t| Some((textures.get(t.texture as usize)?, t.uv(uv))))
            .map_or(glam::Vec4::ONE, |(tex, uv)| tex.lookup(uv))
    }

    /// The BSDF at a point with texture coordinates `uv` and vertex colour `vertex_color`.
    pub fn bsdf(&self, textures: &[Texture], uv: &TexCoords, vertex_color: Vec3) -> Bsdf {
        let base = (self.base_color
            * vertex_color
            * Self::texture_rgba(textures, self.base_color_texture, uv).truncate())
        .clamp(Vec3::ZERO, Vec3::ONE);
        match self.kind() {
            MaterialKind::Diffuse => Bsdf::Diffuse(DiffuseBsdf { r: base }),
            MaterialKind::Mirror => Bsdf::Mirror(MirrorBsdf { r: base }),
            MaterialKind::Dielectric => Bsdf::Dielectric(DielectricBsdf {
                eta: self.ior,
                tint: base,
            }),
            MaterialKind::MetallicRoughness => {
                let mr = Self::texture_rgba(textures, self.metallic_roughness_texture, uv);
                let roughness = (self.roughness * mr.y).clamp(0.0, 1.0);
                let metallic = (self.metallic * mr.z).clamp(0.0, 1.0);
                let rgba = |t| Self::texture_rgba(textures, t, uv);
                let (specular_f0, specular_f90) = MetallicRoughnessBsdf::dielectric_reflectance(
                    self.ior,
                    (self.specular * rgba(self.specular_texture).w).clamp(0.0, 1.0),
                    (self.specular_color * rgba(self.specular_color_texture).truncate())
                        .max(Vec3::ZERO),
                );
                let coat = if self.clearcoat > 0.0 {
                    let weight = self.clearcoat * rgba(self.clearcoat_texture).x;
                    let roughness =
                        self.clearcoat_roughness * rgba(self.clearcoat_roughness_texture).y;
                    let roughness = roughness.clamp(0.0, 1.0);
                    Clearcoat {
                        weight: weight.clamp(0.0, 1.0),
                        distrib: TrowbridgeReitz::new(roughness * roughness),
                    }
                } else {
                    Clearcoat::NONE
                };
                Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
                    base_color: base,
                    metallic,
                    transmission: self.transmission.clamp(0.0, 1.0),
                    eta: self.ior,
                    distrib: TrowbridgeReitz::new(roughness * roughness),
                    specular_f0,
                    specular_f90,
                    coat,
                    sheen: if self.sheen_color.max_element() > 0.0 {
                        Sheen::new(
                            self.sheen_color * rgba(self.sheen_color_texture).truncate(),
                            self.sheen_roughness * rgba(self.sheen_roughness_texture).w,
                        )
                    } else {
                        Sheen::NONE
                    },
                })
            }
        }
    }
}

/// A rough dielectric interface (glTF: transmission 1, metallic 0, roughness sqrt(alpha)).
pub fn rough_dielectric(eta: f32, alpha: f32) -> Bsdf {
    let (specular_f0, specular_f90) =
        MetallicRoughnessBsdf::dielectric_reflectance(eta, 1.0, Vec3::ONE);
    Bsdf::MetallicRoughness(MetallicRoughnessBsdf {
        base_color: Vec3::ONE,
        metallic: 0.0,
        transmission: 1.0,
        eta,
        distrib: TrowbridgeReitz::new(alpha),
        specular_f0,
        specular_f90,
        coat: Clearcoat::NONE,
        sheen: Sheen::NONE,
    })
}
