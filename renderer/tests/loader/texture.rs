//! Textures: their decoding, the texel limit read from an image's header, texture
//! transforms and second coordinates, and the normal texture's transform.

use super::{base_colour_at, temp_dir, write_json};
use caustica_renderer::material::Material;
use caustica_renderer::procedural::{cornell_box, quad};
use caustica_renderer::scene::SceneDescription;
use caustica_renderer::scene::gltf::export::to_gltf;
use caustica_renderer::scene::gltf::{load, load_description};
use glam::{Vec2, Vec3};
use serde_json::{Value, json};

/// A PNG of a few bytes whose header declares 20000 x 20000 texels (1.6 GB decoded): the
/// texture is refused from its header, with a warning naming the size and the limit, before
/// anything is decoded; the scene loads without it.
#[test]
fn an_image_declaring_too_many_texels_is_refused_before_decoding() {
    use base64::Engine;
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
        out
    }
    let mut header = 20000u32.to_be_bytes().to_vec();
    header.extend_from_slice(&20000u32.to_be_bytes());
    header.extend_from_slice(&[8, 6, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &header));
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    let uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png)
    );
    let dir = temp_dir("huge-image");
    let mut v = to_gltf(&cornell_box(false));
    v["images"] = json!([{"uri": uri}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let scene = load(&write_json(&dir, "huge.gltf", &v)).unwrap();
    assert!(scene.textures.is_empty());
    assert!(
        scene
            .info
            .warnings
            .iter()
            .any(|w| w.starts_with("image 0: declares 20000 x 20000 texels, over the limit")),
        "{:?}",
        scene.info.warnings
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn textures_are_decoded_as_the_spec_says() {
    use caustica_renderer::geometry::Ray;
    use caustica_renderer::material::Bsdf;
    let dir = temp_dir("textures");
    let png = |name: &str, rgb: [u8; 3]| {
        image::RgbImage::from_pixel(2, 2, image::Rgb(rgb))
            .save(dir.join(name))
            .unwrap();
    };
    png("base.png", [128, 64, 255]);
    png("mr.png", [0, 128, 255]);
    png("emit.png", [255, 128, 0]);
    // A normal map tilted towards +u: about (0.5, 0, 0.866) in tangent space.
    png("normal.png", [191, 128, 238]);
    let floor = |name: &str, x: f32, material| {
        let c = |dx: f32, dz: f32| Vec3::new(x + dx, 0.0, dz);
        quad(
            name,
            [c(-1., 1.), c(1., 1.), c(1., -1.), c(-1., -1.)],
            material,
        )
    };
    let desc = SceneDescription {
        meshes: vec![floor("textured", 0.0, 0), floor("metal", 3.0, 1)],
        materials: vec![Material::diffuse(Vec3::ONE), Material::diffuse(Vec3::ONE)],
        ..Default::default()
    };
    let mut v = to_gltf(&desc);
    v["images"] =
        json!([{"uri": "base.png"}, {"uri": "mr.png"}, {"uri": "emit.png"}, {"uri": "normal.png"}]);
    v["samplers"] = json!([{}]);
    v["textures"] =
        json!([{"source": 0, "sampler": 0}, {"source": 1}, {"source": 2}, {"source": 3}]);
    v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    v["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    v["materials"][0]["emissiveTexture"] = json!({"index": 2});
    v["materials"][0]["normalTexture"] = json!({"index": 3});
    v["materials"][1]["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    v["materials"][1]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({"index": 1});
    let scene = load(&write_json(&dir, "textured.gltf", &v)).unwrap();
    let srgb = |v: u8| caustica_renderer::color::srgb_to_linear(v as f32 / 255.0);

    // Base colour and emission are sRGB-encoded.
    let r = base_colour_at(&scene, 0.1, 0.2);
    assert!(
        (r - Vec3::new(srgb(128), srgb(64), srgb(255)))
            .abs()
            .max_element()
            < 1e-5,
        "{r:?}"
    );
    let textured = scene
        .intersect(&Ray::new(Vec3::new(0.1, 1.0, 0.2), Vec3::NEG_Y))
        .unwrap();
    let e = scene.emitted(&textured, Vec3::Y);
    assert!(
        (e - Vec3::new(1.0, srgb(128), 0.0)).abs().max_element() < 1e-5,
        "emission {e}"
    );
    // The normal map tilts the shading normal by 30 degrees, staying on the front side.
    assert!(
        (textured.shading.n.dot(textured.n) - 0.866).abs() < 0.01,
        "{:?}",
        textured.shading.n
    );

    // Metallic-roughness is linear: roughness from G (alpha = roughness^2), metalness from B.
    let metal = scene
        .intersect(&Ray::new(Vec3::new(3.1, 1.0, 0.2), Vec3::NEG_Y))
        .unwrap();
    match scene.bsdf(&metal) {
        Bsdf::MetallicRoughness(m) => {
            assert!(
                (m.distrib.alpha - (128.0f32 / 255.0).powi(2)).abs() < 1e-5,
                "alpha {}",
                m.distrib.alpha
            );
            assert!((m.metallic - 1.0).abs() < 1e-6);
        }
        other => panic!("expected the textured metal, got {other:?}"),
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn texture_transforms_and_second_coordinates_read_as_pretransformed_coordinates() {
    let dir = temp_dir("texture-transform");
    // A 4 x 4 texture of distinct colours, repeated.
    let texels = image::RgbImage::from_fn(4, 4, |x, y| {
        image::Rgb([
            (x * 60 + 20) as u8,
            (y * 60 + 20) as u8,
            ((x + y) * 25 + 10) as u8,
        ])
    });
    texels.save(dir.join("grid.png")).unwrap();
    let floor = quad(
        "floor",
        [
            Vec3::new(-1., 0., 1.),
            Vec3::new(1., 0., 1.),
            Vec3::new(1., 0., -1.),
            Vec3::new(-1., 0., -1.),
        ],
        0,
    );
    let uvs = floor.uvs.clone().unwrap();
    let textured = |mesh: caustica_renderer::scene::MeshDesc, info: Value| {
        let desc = SceneDescription {
            meshes: vec![mesh],
            materials: vec![Material::diffuse(Vec3::ONE)],
            ..Default::default()
        };
        let mut v = to_gltf(&desc);
        v["images"] = json!([{"uri": "grid.png"}]);
        v["samplers"] = json!([{"wrapS": 10497, "wrapT": 10497}]);
        v["textures"] = json!([{"source": 0, "sampler": 0}]);
        v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = info;
        v
    };
    // KHR_texture_transform's GLSL, written out: uv' = offset + R(rotation) (scale * uv),
    // R = mat3(cos, -sin, 0, sin, cos, 0, 0, 0, 1), column by column.
    let (offset, rotation, scale) = (
        glam::Vec2::new(0.3, -0.2),
        0.7f32,
        glam::Vec2::new(1.7, 0.6),
    );
    let transformed: Vec<glam::Vec2> = uvs
        .iter()
        .map(|&uv| {
            let s = uv * scale;
            let (sin, cos) = rotation.sin_cos();
            offset + glam::Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
        })
        .collect();
    let mut pretransformed = floor.clone();
    pretransformed.uvs = Some(transformed.clone());
    let reference = textured(pretransformed, json!({"index": 0}));
    let mut with_transform = textured(
        floor.clone(),
        json!({"index": 0, "extensions": {"KHR_texture_transform": {
            "offset": offset.to_array(), "rotation": rotation, "scale": scale.to_array()}}}),
    );
    with_transform["extensionsUsed"] = json!(["KHR_texture_transform"]);
    with_transform["extensionsRequired"] = json!(["KHR_texture_transform"]);
    // TEXCOORD_1 holds the coordinates; TEXCOORD_0 something else.
    let mut second_set = floor.clone();
    second_set.uvs = Some(uvs.iter().map(|uv| glam::Vec2::ONE - *uv).collect());
    second_set.uvs1 = Some(transformed);
    let second_set = textured(second_set, json!({"index": 0, "texCoord": 1}));

    let load_in = |name: &str, v: &Value| load(&write_json(&dir, name, v)).unwrap();
    let reference = load_in("reference.gltf", &reference);
    let others = [
        load_in("transform.gltf", &with_transform),
        load_in("texcoord1.gltf", &second_set),
    ];
    let mut distinct = std::collections::HashSet::new();
    for i in 0..400 {
        let (x, z) = ((i % 20) as f32 / 10.0 - 0.95, (i / 20) as f32 / 10.0 - 0.95);
        let expected = base_colour_at(&reference, x, z);
        distinct.insert(expected.to_array().map(f32::to_bits));
        for (name, scene) in ["transform", "texcoord 1"].iter().zip(&others) {
            let got = base_colour_at(scene, x, z);
            assert!(
                (got - expected).abs().max_element() < 1e-4,
                "{name} at ({x}, {z}): {got} against {expected}"
            );
        }
    }
    // The comparison means something only if the texture varies over the floor.
    assert!(distinct.len() > 100, "{} distinct colours", distinct.len());
    std::fs::remove_dir_all(dir).unwrap();
}

/// A normal texture's KHR_texture_transform (which the gltf crate does not read there) is
/// read like any other texture's: the map and the texCoord override, and the tangent frame
/// follows the transformed coordinates (`Scene::intersect`).
#[test]
fn a_normal_texture_reads_its_texture_transform() {
    let dir = temp_dir("normal-transform");
    image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255]))
        .save(dir.join("flat.png"))
        .unwrap();
    let mut v = to_gltf(&cornell_box(false));
    v["images"] = json!([{"uri": "flat.png"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"][0]["normalTexture"] = json!({"index": 0, "scale": 0.5,
        "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0], "scale": [2.0, 4.0], "texCoord": 1}}});
    v["extensionsUsed"] = json!(["KHR_texture_transform"]);
    let desc = load_description(&write_json(&dir, "normal.gltf", &v)).unwrap();
    let (r, scale) = desc.materials[0].normal_texture.unwrap();
    assert_eq!((r.tex_coord, scale), (1, 0.5));
    assert_eq!(
        r.uv(&[Vec2::ZERO, Vec2::new(0.25, 0.25)]),
        Vec2::new(1.0, 1.0)
    );
    std::fs::remove_dir_all(dir).unwrap();
}
