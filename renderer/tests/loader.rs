//! The glTF loader: valid files in every container (.gltf with embedded or external buffers,
//! .glb), the design's interpretation of materials, lights and cameras, and a set of broken
//! files that must give an error naming the file and the problem, never a panic.

use caustica_renderer::light::Light;
use caustica_renderer::material::{Material, MaterialKind};
use caustica_renderer::procedural::{cornell_box, quad};
use caustica_renderer::scene::gltf::{load, load_description};
use caustica_renderer::scene::gltf_export::{to_glb, to_gltf};
use caustica_renderer::scene::{PunctualLightDesc, SceneDescription};
use glam::{Vec2, Vec3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-loader-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(v).unwrap()).unwrap();
    path
}

/// Splits an exported file's embedded buffer out: (JSON without the data URI, the bytes).
fn split_buffer(mut v: Value) -> (Value, Vec<u8>) {
    use base64::Engine;
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let data = base64::engine::general_purpose::STANDARD
        .decode(uri.split(',').nth(1).unwrap())
        .unwrap();
    v["buffers"][0].as_object_mut().unwrap().remove("uri");
    (v, data)
}

fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

fn expect_error(path: &Path, fragment: &str) {
    match load(path) {
        Ok(_) => panic!(
            "{} loaded, expected an error about '{fragment}'",
            path.display()
        ),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.contains(&path.display().to_string()),
                "error does not name the file: {msg}"
            );
            assert!(
                msg.to_lowercase().contains(&fragment.to_lowercase()),
                "error does not say '{fragment}': {msg}"
            );
        }
    }
}

#[test]
fn embedded_external_and_binary_containers_load_alike() {
    let dir = temp_dir("containers");
    let v = to_gltf(&cornell_box(false));
    let embedded = load(&write_json(&dir, "embedded.gltf", &v)).unwrap();
    let (mut j, bin) = split_buffer(v);
    let g = load_glb(&dir, "scene.glb", &j, &bin);
    // The exporter's .glb is the container this file's own writer makes, byte for byte.
    assert!(to_glb(&cornell_box(false)) == glb(&j, &bin));
    j["buffers"][0]["uri"] = json!("scene.bin");
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    let external = load(&write_json(&dir, "external.gltf", &j)).unwrap();
    for s in [&external, &g] {
        assert_eq!(s.positions, embedded.positions);
        assert_eq!(s.lights.len(), embedded.lights.len());
    }
    assert_eq!(embedded.info.triangles, 2 * 6 + 12 * 2);
    assert!(!embedded.info.default_camera && !embedded.info.default_environment);
    std::fs::remove_dir_all(dir).unwrap();
}

fn load_glb(dir: &Path, name: &str, j: &Value, bin: &[u8]) -> caustica_renderer::scene::Scene {
    let path = dir.join(name);
    std::fs::write(&path, glb(j, bin)).unwrap();
    load(&path).unwrap()
}

#[test]
fn materials_lights_and_camera_follow_the_design() {
    let dir = temp_dir("semantics");
    let v = to_gltf(&cornell_box(true));
    let scene = load(&write_json(&dir, "glass.gltf", &v)).unwrap();
    let kinds: Vec<MaterialKind> = scene.materials.iter().map(Material::kind).collect();
    assert!(kinds.contains(&MaterialKind::Dielectric) && kinds.contains(&MaterialKind::Diffuse));
    let glass = scene
        .materials
        .iter()
        .find(|m| m.kind() == MaterialKind::Dielectric)
        .unwrap();
    assert_eq!(glass.ior, 1.5);
    // The light quad: two triangles, emission through KHR_materials_emissive_strength.
    let area: Vec<_> = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Area(_)))
        .collect();
    assert_eq!(area.len(), 2);
    if let Light::Area(a) = area[0] {
        assert!(a.normal.y < -0.99, "the ceiling light faces down");
        assert_eq!(a.emission, Vec3::new(17.0, 12.0, 4.0));
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// An orthographic camera is read with its film size: ymag is half the height, xmag / ymag
/// the aspect (spec 3.10.3); the export writes it back the same.
#[test]
fn orthographic_cameras_are_read_with_their_film_size() {
    use caustica_renderer::camera::Projection;
    let dir = temp_dir("orthographic");
    let mut desc = cornell_box(false);
    let camera = desc.camera.as_mut().unwrap();
    camera.projection = Projection::Orthographic { ymag: 0.8 };
    camera.aspect = Some(1.5);
    let mut v = to_gltf(&desc);
    let written = &v["cameras"][0]["orthographic"];
    assert_eq!(
        (written["xmag"].as_f64(), written["ymag"].as_f64()),
        (Some(1.2000000476837158), Some(0.800000011920929))
    );
    let scene = load(&write_json(&dir, "ortho.gltf", &v)).unwrap();
    assert_eq!(
        scene.camera.projection,
        Projection::Orthographic { ymag: 0.8 }
    );
    assert_eq!(scene.camera.aspect, Some(1.5));
    assert!(
        scene.info.warnings.iter().all(|w| !w.contains("camera")),
        "{:?}",
        scene.info.warnings
    );
    // A film of no size is ignored with a warning (the default camera frames the scene),
    // not turned into NaN rays.
    v["cameras"][0]["orthographic"]["ymag"] = json!(0.0);
    let scene = load(&write_json(&dir, "flat.gltf", &v)).unwrap();
    assert!(scene.info.default_camera);
    assert!(
        scene
            .info
            .warnings
            .iter()
            .any(|w| w.starts_with("cameras[0]: a film of no size")),
        "{:?}",
        scene.info.warnings
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Every camera of the file is read, named, in the order of the nodes; the first is the
/// scene's camera.
#[test]
fn every_camera_is_read_and_the_first_is_the_scenes() {
    use caustica_renderer::camera::Projection;
    let dir = temp_dir("cameras");
    let mut v = to_gltf(&cornell_box(false));
    v["cameras"][0]["name"] = json!("front");
    v["cameras"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.0, "znear": 0.1, "zfar": 100.0}}));
    let nodes = v["nodes"].as_array_mut().unwrap();
    nodes.push(
        json!({"name": "top view", "camera": 1, "translation": [0.0, 5.0, 0.0],
        "rotation": [-0.70710677, 0.0, 0.0, 0.70710677]}),
    );
    let node = nodes.len() - 1;
    v["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(node));
    let scene = load(&write_json(&dir, "two-cameras.gltf", &v)).unwrap();
    let names: Vec<&str> = scene.cameras.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["front", "top view"]);
    assert_eq!(scene.camera, scene.cameras[0].1);
    let top = scene.cameras[1].1;
    assert_eq!(top.projection, Projection::Orthographic { ymag: 1.0 });
    let forward = top.camera_to_world.matrix3 * glam::Vec3A::NEG_Z;
    assert!(forward.abs_diff_eq(glam::Vec3A::NEG_Y, 1e-5), "{forward}");
    std::fs::remove_dir_all(dir).unwrap();
}

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
fn punctual_lights_transforms_and_mirrored_nodes() {
    let dir = temp_dir("punctual");
    let desc = SceneDescription {
        meshes: vec![quad(
            "floor",
            [
                Vec3::new(-1., 0., 1.),
                Vec3::new(1., 0., 1.),
                Vec3::new(1., 0., -1.),
                Vec3::new(-1., 0., -1.),
            ],
            0,
        )],
        materials: vec![Material::diffuse(Vec3::splat(0.5))],
        lights: vec![
            PunctualLightDesc::Point {
                position: Vec3::new(0., 2., 0.),
                intensity: Vec3::new(3., 2., 1.),
            },
            PunctualLightDesc::Spot {
                position: Vec3::new(0., 3., 0.),
                direction: Vec3::NEG_Y,
                intensity: Vec3::ONE,
                inner_cone: 0.2,
                outer_cone: 0.5,
            },
            PunctualLightDesc::Directional {
                direction: Vec3::new(0., -1., -1.).normalize(),
                irradiance: Vec3::splat(2.0),
            },
        ],
        ..Default::default()
    };
    let mut v = to_gltf(&desc);
    // Put the mesh under a parent that mirrors x and lifts by 1: positions move, and the
    // winding flips so the front face still faces up.
    let mesh_node = v["nodes"][0].clone();
    v["nodes"][0] = json!({"name": "parent", "scale": [-1.0, 1.0, 1.0], "translation": [0.0, 1.0, 0.0], "children": [v["nodes"].as_array().unwrap().len()]});
    v["nodes"].as_array_mut().unwrap().push(mesh_node);
    let scene = load(&write_json(&dir, "lights.gltf", &v)).unwrap();
    assert!(
        scene.info.default_camera,
        "no camera in the file: the default one frames the scene"
    );
    assert!(
        scene
            .positions
            .iter()
            .flatten()
            .all(|p| (p.y - 1.0).abs() < 1e-6)
    );
    let p = &scene.positions[0];
    assert!(
        (p[1] - p[0]).cross(p[2] - p[0]).y > 0.0,
        "mirroring must not turn the floor's front face down"
    );
    match &scene.lights[0] {
        Light::Point(l) => assert_eq!(
            (l.position, l.intensity),
            (Vec3::new(0., 2., 0.), Vec3::new(3., 2., 1.))
        ),
        other => panic!("expected the point light, got {other:?}"),
    }
    match &scene.lights[1] {
        Light::Spot(s) => {
            assert!((s.frame.n - Vec3::NEG_Y).length() < 1e-5);
            assert!(
                (s.cos_outer - 0.5f32.cos()).abs() < 1e-6
                    && s.falloff(1.0) == 1.0
                    && s.falloff(0.5f32.cos() - 0.01) == 0.0
            );
        }
        other => panic!("expected the spot light, got {other:?}"),
    }
    match &scene.lights[2] {
        Light::Directional(d) => {
            assert!((d.direction - Vec3::new(0., -1., -1.).normalize()).length() < 1e-5)
        }
        other => panic!("expected the directional light, got {other:?}"),
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_scene_without_emitters_gets_the_studio_environment() {
    let dir = temp_dir("noemit");
    let mut desc = cornell_box(false);
    desc.materials
        .iter_mut()
        .for_each(|m| m.emission = Vec3::ZERO);
    desc.camera = None;
    let scene = load(&write_json(&dir, "dark.gltf", &to_gltf(&desc))).unwrap();
    assert!(scene.info.default_environment && scene.environment.is_some());
    assert!(
        scene
            .info
            .warnings
            .iter()
            .any(|w| w.contains("built-in studio environment (no light sources)"))
    );
    assert!(
        scene
            .info
            .lighting
            .starts_with("studio; chosen by the default rule")
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn broken_files_give_errors_naming_file_and_problem() {
    let dir = temp_dir("broken");
    let good = to_gltf(&cornell_box(false));

    let path = dir.join("truncated.gltf");
    let text = serde_json::to_vec(&good).unwrap();
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    expect_error(&path, "not a valid glTF");

    let (j, bin) = split_buffer(good.clone());
    let path = dir.join("truncated.glb");
    let bytes = glb(&j, &bin);
    std::fs::write(&path, &bytes[..bytes.len() - 4096]).unwrap();
    expect_error(&path, "glTF");

    let mut v = j.clone();
    v["buffers"][0]["uri"] = json!("missing.bin");
    expect_error(&write_json(&dir, "missing-buffer.gltf", &v), "buffer");

    let mut v = j.clone();
    v["buffers"][0]["uri"] = json!("short.bin");
    std::fs::write(dir.join("short.bin"), &bin[..bin.len() / 2]).unwrap();
    expect_error(&write_json(&dir, "short-buffer.gltf", &v), "buffer");

    let mut v = good.clone();
    v["accessors"][0]["count"] = json!(1_000_000);
    expect_error(&write_json(&dir, "accessor-overrun.gltf", &v), "accessor 0");

    let mut v = good.clone();
    v["meshes"][0]["primitives"][0]["material"] = json!(99);
    expect_error(
        &write_json(&dir, "bad-material-index.gltf", &v),
        "invalid glTF",
    );

    let mut bad = cornell_box(false);
    bad.meshes[0].indices[1] = 4000;
    expect_error(
        &write_json(&dir, "bad-vertex-index.gltf", &to_gltf(&bad)),
        "vertex index 4000 out of range",
    );

    let mut nan = cornell_box(false);
    nan.meshes[2].positions[1].y = f32::NAN;
    let mut v = to_gltf(&nan);
    // JSON cannot hold NaN: give the accessor finite bounds, as a careless exporter might.
    v["accessors"][6]["min"] = json!([0.0, 0.0, 0.0]);
    v["accessors"][6]["max"] = json!([1.0, 1.0, 1.0]);
    expect_error(
        &write_json(&dir, "nan-position.gltf", &v),
        "NaN or infinite",
    );

    let mut v = good.clone();
    v["scenes"][0]["nodes"] = json!([]);
    expect_error(
        &write_json(&dir, "no-meshes.gltf", &v),
        "no triangle meshes",
    );

    let mut v = good.clone();
    v["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
    v["extensionsRequired"] = json!(["EXT_meshopt_compression"]);
    expect_error(
        &write_json(&dir, "required-extension.gltf", &v),
        "unsupported extension EXT_meshopt_compression: export the model again without mesh \
         compression",
    );

    let mut v = good.clone();
    v["nodes"][0]["children"] = json!([0]);
    expect_error(&write_json(&dir, "cyclic.gltf", &v), "has a cycle");

    expect_error(&dir.join("does-not-exist.gltf"), "cannot read file");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let dir = temp_dir("degenerate");
    let mut desc = cornell_box(false);
    let m = &mut desc.meshes[0];
    m.positions.push(m.positions[0]);
    m.uvs.as_mut().unwrap().push(glam::Vec2::ZERO);
    m.indices.extend_from_slice(&[0, 4, 1]);
    let scene = load(&write_json(&dir, "degenerate.gltf", &to_gltf(&desc))).unwrap();
    assert_eq!(scene.info.degenerate_triangles_dropped, 1);
    assert!(scene.info.warnings.iter().any(|w| w.contains("degenerate")));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn random_corruption_never_panics() {
    // Byte flips in a binary file reach every part of the reader: headers, chunk lengths,
    // JSON, accessors and buffers. Each must load or fail with an error naming the file.
    let dir = temp_dir("fuzz");
    let (j, bin) = split_buffer(to_gltf(&cornell_box(false)));
    let original = glb(&j, &bin);
    let mut s = caustica_renderer::sampling::sampler::Sampler::new(17);
    let path = dir.join("fuzz.glb");
    for case in 0..300u64 {
        s.start_pixel_sample(case, 0);
        let mut bytes = original.clone();
        let flips = 1 + (s.get_1d() * 8.0) as usize;
        for _ in 0..flips {
            let at = (s.get_1d() * bytes.len() as f32) as usize % bytes.len();
            bytes[at] = (s.get_1d() * 256.0) as u8;
        }
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = load(&path) {
            assert!(e.to_string().contains("fuzz.glb"), "{e}");
        }
    }
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
fn non_triangle_primitives_are_skipped_with_a_warning_naming_the_mesh() {
    let dir = temp_dir("modes");
    let mut v = to_gltf(&cornell_box(false));
    v["meshes"][1]["primitives"][0]["mode"] = json!(1); // LINES
    let scene = load(&write_json(&dir, "lines.gltf", &v)).unwrap();
    assert!(
        scene
            .info
            .warnings
            .iter()
            .any(|w| w.contains("ceiling") && w.contains("skipped")),
        "{:?}",
        scene.info.warnings
    );
    assert_eq!(scene.info.triangles, 2 * 5 + 12 * 2);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Each mesh's triangles as the bits of their vertices' positions, each triangle rotated to
/// start at its smallest vertex (rotation keeps the winding) and the mesh's list sorted.
fn triangle_sets(desc: &SceneDescription) -> Vec<Vec<[[u32; 3]; 3]>> {
    desc.meshes
        .iter()
        .map(|m| {
            let mut tris: Vec<[[u32; 3]; 3]> = m
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let p = [t[0], t[1], t[2]]
                        .map(|i| m.positions[i as usize].to_array().map(f32::to_bits));
                    (0..3)
                        .map(|r| [p[r], p[(r + 1) % 3], p[(r + 2) % 3]])
                        .min()
                        .unwrap()
                })
                .collect();
            tris.sort();
            tris
        })
        .collect()
}

#[test]
fn strips_and_fans_load_as_the_triangles_they_list() {
    let dir = temp_dir("strips");
    let desc = cornell_box(false);
    let listed =
        triangle_sets(&load_description(&write_json(&dir, "list.gltf", &to_gltf(&desc))).unwrap());
    // Meshes 0-5 are quads (0 1 2, 0 2 3): the strip 1 2 0 3 and the fan 0 1 2 3 list the
    // same two triangles with the same winding.
    for (mode, order) in [(5, [1, 2, 0, 3]), (6, [0, 1, 2, 3])] {
        let mut d = desc.clone();
        for m in &mut d.meshes[..6] {
            assert_eq!(m.indices, [0, 1, 2, 0, 2, 3]);
            m.indices = order.to_vec();
        }
        let mut v = to_gltf(&d);
        for i in 0..6 {
            v["meshes"][i]["primitives"][0]["mode"] = json!(mode);
        }
        let path = write_json(&dir, &format!("mode-{mode}.gltf"), &v);
        let loaded = load_description(&path).unwrap();
        assert_eq!(triangle_sets(&loaded), listed, "mode {mode}");
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Appends `bytes` to the exported file as a new buffer (data URI) with one view; its index.
fn push_buffer_view(v: &mut Value, bytes: &[u8]) -> usize {
    use base64::Engine;
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    );
    let buffers = v["buffers"].as_array_mut().unwrap();
    buffers.push(json!({"uri": uri, "byteLength": bytes.len()}));
    let buffer = buffers.len() - 1;
    let views = v["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": buffer, "byteLength": bytes.len()}));
    views.len() - 1
}

#[test]
fn sparse_accessors_load_as_the_dense_arrays_they_stand_for() {
    let dir = temp_dir("sparse");
    let desc = cornell_box(false);
    // The dense truth: the floor's vertices 1 and 3 raised.
    let mut moved = desc.clone();
    let lift = Vec3::new(0.0, 0.25, 0.0);
    moved.meshes[0].positions[1] += lift;
    moved.meshes[0].positions[3] += lift;
    let dense = to_gltf(&moved);
    let truth = load_description(&write_json(&dir, "dense.gltf", &dense)).unwrap();
    let floats = |ps: &[Vec3]| -> Vec<u8> {
        ps.iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes)
            .collect()
    };
    let position = |v: &Value| {
        v["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize
    };

    // Over the unmoved positions: indices 1 and 3 (u16) replaced.
    let mut v = to_gltf(&desc);
    let a = position(&v);
    let indices = push_buffer_view(&mut v, &[1, 0, 3, 0]);
    let values = push_buffer_view(
        &mut v,
        &floats(&[moved.meshes[0].positions[1], moved.meshes[0].positions[3]]),
    );
    v["accessors"][a]["sparse"] = json!({"count": 2,
        "indices": {"bufferView": indices, "componentType": 5123},
        "values": {"bufferView": values}});
    v["accessors"][a]["min"] = dense["accessors"][a]["min"].clone();
    v["accessors"][a]["max"] = dense["accessors"][a]["max"].clone();
    let over_base = load_description(&write_json(&dir, "sparse.gltf", &v)).unwrap();
    assert_eq!(triangle_sets(&over_base), triangle_sets(&truth));

    // Without a buffer view the base is zeros: every vertex given sparsely (u8 indices).
    let mut w = v.clone();
    w["accessors"][a]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    let all = push_buffer_view(&mut w, &[0, 1, 2, 3]);
    let values = push_buffer_view(&mut w, &floats(&moved.meshes[0].positions));
    w["accessors"][a]["sparse"] = json!({"count": 4,
        "indices": {"bufferView": all, "componentType": 5121},
        "values": {"bufferView": values}});
    let from_zeros = load_description(&write_json(&dir, "sparse-no-base.gltf", &w)).unwrap();
    assert_eq!(triangle_sets(&from_zeros), triangle_sets(&truth));

    // Indices out of order, or values past their view: refused with the JSON path.
    let mut bad = v.clone();
    let backwards = push_buffer_view(&mut bad, &[3, 0, 1, 0]);
    bad["accessors"][a]["sparse"]["indices"]["bufferView"] = json!(backwards);
    expect_error(
        &write_json(&dir, "sparse-unsorted.gltf", &bad),
        &format!("accessors[{a}].sparse.indices: index 1"),
    );
    let mut bad = v.clone();
    bad["accessors"][a]["sparse"]["count"] = json!(3);
    let three = push_buffer_view(&mut bad, &[0, 0, 1, 0, 3, 0]);
    bad["accessors"][a]["sparse"]["indices"]["bufferView"] = json!(three);
    expect_error(
        &write_json(&dir, "sparse-short-values.gltf", &bad),
        &format!("accessors[{a}].sparse.values: 3 values of 12 bytes run past"),
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn scenes_without_nodes_and_files_without_scenes() {
    let dir = temp_dir("no-nodes");
    let good = to_gltf(&cornell_box(false));
    // `scene.nodes` is optional in glTF 2.0: an empty scene is read, and has nothing to show.
    let mut v = good.clone();
    v["scenes"][0].as_object_mut().unwrap().remove("nodes");
    expect_error(
        &write_json(&dir, "empty-scene.gltf", &v),
        "no triangle meshes",
    );
    // No scenes at all: every root node is shown, with a warning saying so.
    let mut v = good.clone();
    v.as_object_mut().unwrap().remove("scenes");
    v.as_object_mut().unwrap().remove("scene");
    let scene = load(&write_json(&dir, "no-scenes.gltf", &v)).unwrap();
    let all = load(&write_json(&dir, "good.gltf", &good)).unwrap();
    assert_eq!(scene.info.triangles, all.info.triangles);
    assert!(scene.info.warnings.iter().any(|w| w.contains("no scenes")));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn errors_are_one_short_line_with_the_json_path_and_the_buffer_named() {
    let dir = temp_dir("messages");
    let good = to_gltf(&cornell_box(false));
    let (j, _) = split_buffer(good.clone());
    let mut v = j.clone();
    v["buffers"][0]["uri"] = json!("missing.bin");
    let path = write_json(&dir, "missing-buffer.gltf", &v);
    expect_error(&path, "buffers[0] (missing.bin): cannot load");

    let mut v = good.clone();
    for mesh in 0..3 {
        v["meshes"][mesh]["primitives"][0]["material"] = json!(99);
    }
    let path = write_json(&dir, "bad-material-index.gltf", &v);
    expect_error(&path, "invalid glTF: meshes[0].primitives[0].material");
    expect_error(&path, "(and 2 more problems)");
    for path in [path, dir.join("missing-buffer.gltf")] {
        let msg = load(&path).err().unwrap().to_string();
        let problem = msg.replace(&path.display().to_string(), "");
        assert!(!msg.contains('\n') && problem.len() < 200, "{msg}");
        assert!(msg.matches("invalid glTF").count() <= 1, "{msg}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// The base colour a ray straight down at (x, z) finds on a diffuse floor.
fn base_colour_at(scene: &caustica_renderer::scene::Scene, x: f32, z: f32) -> Vec3 {
    use caustica_renderer::geometry::Ray;
    use caustica_renderer::material::Bsdf;
    let si = scene
        .intersect(&Ray::new(Vec3::new(x, 1.0, z), Vec3::NEG_Y))
        .unwrap();
    match scene.bsdf(&si) {
        Bsdf::Diffuse(d) => d.r,
        other => panic!("expected the diffuse floor, got {other:?}"),
    }
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

#[test]
fn an_unlit_material_emits_its_base_colour_and_reflects_nothing() {
    use caustica_renderer::geometry::Ray;
    use caustica_renderer::material::Bsdf;
    let dir = temp_dir("unlit");
    let mut v = to_gltf(&cornell_box(false));
    let colour = [0.2, 0.5, 0.8];
    v["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([0.2, 0.5, 0.8, 1.0]);
    v["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    v["materials"][0]["extensions"] = json!({"KHR_materials_unlit": {}});
    // Used but not required: read without it, and said so.
    v["extensionsUsed"] = json!(["KHR_materials_unlit", "KHR_materials_iridescence"]);
    v["extensionsRequired"] = json!(["KHR_materials_unlit"]);
    let scene = load(&write_json(&dir, "unlit.gltf", &v)).unwrap();
    for expected in [
        "asks for an unlit look",
        "KHR_materials_iridescence, which is not read",
    ] {
        assert!(
            scene.info.warnings.iter().any(|w| w.contains(expected)),
            "{:?}",
            scene.info.warnings
        );
    }
    // The floor (material 0) seen from above.
    let floor = scene
        .intersect(&Ray::new(Vec3::new(0.5, 1.0, 0.5), Vec3::NEG_Y))
        .unwrap();
    assert_eq!(scene.emitted(&floor, Vec3::Y), Vec3::from(colour));
    match scene.bsdf(&floor) {
        Bsdf::Diffuse(d) => assert_eq!(d.r, Vec3::ZERO),
        other => panic!("expected a black diffuse surface, got {other:?}"),
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn alpha_modes_and_cutoffs_are_read() {
    use caustica_renderer::material::AlphaMode;
    let dir = temp_dir("alpha");
    let mut v = to_gltf(&cornell_box(false));
    v["materials"][0]["alphaMode"] = json!("MASK");
    v["materials"][0]["alphaCutoff"] = json!(0.3);
    v["materials"][1]["alphaMode"] = json!("BLEND");
    v["materials"][1]["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 0.25]);
    v["materials"][2]["alphaMode"] = json!("MASK");
    let desc = load_description(&write_json(&dir, "alpha.gltf", &v)).unwrap();
    let m = &desc.materials;
    assert_eq!(m[0].alpha_mode, AlphaMode::Mask(0.3));
    assert_eq!((m[1].alpha_mode, m[1].alpha), (AlphaMode::Blend, 0.25));
    // The spec's default cutoff.
    assert_eq!(m[2].alpha_mode, AlphaMode::Mask(0.5));
    assert_eq!((m[3].alpha_mode, m[3].alpha), (AlphaMode::Opaque, 1.0));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    use caustica_renderer::scene::MeshDesc;
    let dir = temp_dir("colours");
    let floor = || {
        quad(
            "floor",
            [
                Vec3::new(-1., 0., 1.),
                Vec3::new(1., 0., 1.),
                Vec3::new(1., 0., -1.),
                Vec3::new(-1., 0., -1.),
            ],
            0,
        )
    };
    let scene_of = |mesh: MeshDesc, base: Vec3, name: &str| {
        let desc = SceneDescription {
            meshes: vec![mesh],
            materials: vec![Material::diffuse(base)],
            ..Default::default()
        };
        load(&write_json(&dir, name, &to_gltf(&desc))).unwrap()
    };
    // A constant COLOR_0 on a white material reads like the same colour as the factor.
    let c = glam::Vec4::new(0.2, 0.6, 0.9, 1.0);
    let mut coloured = floor();
    coloured.colors = Some(vec![c; 4]);
    let by_vertex = scene_of(coloured, Vec3::ONE, "vertex.gltf");
    let by_factor = scene_of(floor(), c.truncate(), "factor.gltf");
    for (x, z) in [(0.3, 0.2), (-0.7, 0.5), (0.9, -0.9)] {
        // Equal but for the rounding of interpolating three equal colours (a few ulps).
        let (v, f) = (
            base_colour_at(&by_vertex, x, z),
            base_colour_at(&by_factor, x, z),
        );
        assert!((v - f).abs().max_element() <= 1e-6, "{v} against {f}");
    }
    // Different colours at the corners: at the centre (on the diagonal 0-2 both triangles
    // share) the colour is the mean of corners 0 and 2, times the factor.
    let corners = [
        glam::Vec4::new(1.0, 0.0, 0.0, 1.0),
        glam::Vec4::new(0.0, 1.0, 0.0, 1.0),
        glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
        glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
    ];
    let mut graded = floor();
    graded.colors = Some(corners.to_vec());
    let factor = Vec3::new(0.5, 0.8, 1.0);
    let scene = scene_of(graded, factor, "graded.gltf");
    let expected = (corners[0] + corners[2]).truncate() * 0.5 * factor;
    let got = base_colour_at(&scene, 0.0, 0.0);
    assert!(
        (got - expected).abs().max_element() < 1e-5,
        "{got} against {expected}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn morph_targets_at_their_default_weights_load_as_the_displaced_mesh() {
    let dir = temp_dir("morph");
    let desc = cornell_box(false);
    let lift = Vec3::new(0.0, 0.25, 0.0);
    // Target 0 lifts the floor's vertex 1, target 1 vertex 3; weights 0.5 and 1.
    let mut moved = desc.clone();
    moved.meshes[0].positions[1] += lift * 0.5;
    moved.meshes[0].positions[3] += lift;
    let truth = load_description(&write_json(&dir, "moved.gltf", &to_gltf(&moved))).unwrap();

    let mut v = to_gltf(&desc);
    let mut targets = Vec::new();
    for vertex in [1, 3] {
        let mut deltas = [Vec3::ZERO; 4];
        deltas[vertex] = lift;
        let bytes: Vec<u8> = deltas
            .iter()
            .flat_map(|d| d.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let view = push_buffer_view(&mut v, &bytes);
        let accessors = v["accessors"].as_array_mut().unwrap();
        accessors.push(
            json!({"bufferView": view, "componentType": 5126, "count": 4,
            "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [0.0, 0.25, 0.0]}),
        );
        targets.push(json!({"POSITION": accessors.len() - 1}));
    }
    v["meshes"][0]["primitives"][0]["targets"] = json!(targets);
    v["meshes"][0]["weights"] = json!([0.5, 1.0]);
    let morphed = load_description(&write_json(&dir, "morphed.gltf", &v)).unwrap();
    assert_eq!(triangle_sets(&morphed), triangle_sets(&truth));

    // The node's weights override the mesh's: all zero is the undisplaced mesh.
    v["nodes"][0]["weights"] = json!([0.0, 0.0]);
    let rest = load_description(&write_json(&dir, "rest.gltf", &v)).unwrap();
    let original = load_description(&write_json(&dir, "original.gltf", &to_gltf(&desc))).unwrap();
    assert_eq!(triangle_sets(&rest), triangle_sets(&original));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn volume_attenuation_becomes_an_absorption_coefficient() {
    let dir = temp_dir("volume");
    let mut v = to_gltf(&cornell_box(true));
    let glass = v["materials"]
        .as_array()
        .unwrap()
        .iter()
        .position(|m| m["name"] == "glass")
        .unwrap();
    let volume = |thickness: f32| {
        json!({"KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": {"thicknessFactor": thickness,
                "attenuationDistance": 2.0, "attenuationColor": [0.5, 0.25, 1.0]}})
    };
    v["materials"][glass]["extensions"] = volume(1.0);
    v["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
    let desc = load_description(&write_json(&dir, "volume.gltf", &v)).unwrap();
    // sigma_a = -ln(color) / distance: half the light left after 2 units in red.
    let expected = Vec3::new(0.5f32.ln(), 0.25f32.ln(), 0.0) / -2.0;
    let got = desc.materials[glass].absorption;
    assert!((got - expected).abs().max_element() < 1e-6, "{got}");
    // Thickness zero is thin-walled: no volume.
    v["materials"][glass]["extensions"] = volume(0.0);
    let thin = load_description(&write_json(&dir, "thin.gltf", &v)).unwrap();
    assert_eq!(thin.materials[glass].absorption, Vec3::ZERO);
    std::fs::remove_dir_all(dir).unwrap();
}

/// KHR_materials_specular, _clearcoat and _sheen are read into the material's layers:
/// factors, textures with their channel's colour space, texCoord and texture transform (the
/// clearcoat's and sheen's from the material's raw JSON, which the gltf crate does not
/// parse); the coat's
/// normal texture is named in a warning; a bad factor or texture index is an error naming the
/// JSON path.
#[test]
fn specular_and_clearcoat_layers_are_read() {
    let dir = temp_dir("layers");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 128, 0, 64]))
        .save(dir.join("layer.png"))
        .unwrap();
    let mut v = to_gltf(&cornell_box(false));
    v["images"] = json!([{"uri": "layer.png"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"][0]["extensions"] = json!({
        "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1.0, 0.5, 0.25],
            "specularTexture": {"index": 0}, "specularColorTexture": {"index": 0}},
        "KHR_materials_clearcoat": {"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.3,
            "clearcoatTexture": {"index": 0, "texCoord": 1,
                "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}},
            "clearcoatRoughnessTexture": {"index": 0},
            "clearcoatNormalTexture": {"index": 0}},
        "KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.25, 1.0], "sheenRoughnessFactor": 0.75,
            "sheenColorTexture": {"index": 0}, "sheenRoughnessTexture": {"index": 0}}
    });
    v["extensionsUsed"] = json!([
        "KHR_materials_specular",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen"
    ]);
    v["extensionsRequired"] = json!(["KHR_materials_clearcoat", "KHR_materials_sheen"]);
    let desc = load_description(&write_json(&dir, "layers.gltf", &v)).unwrap();
    let m = &desc.materials[0];
    assert_eq!(
        (m.specular, m.specular_color),
        (0.5, Vec3::new(1.0, 0.5, 0.25))
    );
    assert_eq!((m.clearcoat, m.clearcoat_roughness), (0.8, 0.3));
    assert_eq!(
        (m.sheen_color, m.sheen_roughness),
        (Vec3::new(0.5, 0.25, 1.0), 0.75)
    );
    assert_eq!(m.kind(), MaterialKind::MetallicRoughness);
    let coat = m.clearcoat_texture.expect("the clearcoat texture is read");
    assert_eq!(coat.tex_coord, 1);
    assert_eq!(
        coat.uv(&[Vec2::ZERO, Vec2::new(0.25, 0.5)]),
        Vec2::new(0.5, 1.0)
    );
    // One image, read linear for the clearcoat and specular factors and sRGB for the
    // specular colour: two textures.
    let (linear, srgb) = (coat.texture, m.specular_color_texture.unwrap().texture);
    assert_eq!(m.specular_texture.unwrap().texture, linear);
    assert_eq!(m.clearcoat_roughness_texture.unwrap().texture, linear);
    assert_eq!(m.sheen_roughness_texture.unwrap().texture, linear);
    assert_eq!(m.sheen_color_texture.unwrap().texture, srgb);
    assert_ne!(linear, srgb);
    assert!(
        desc.warnings
            .iter()
            .any(|w| w.contains("clearcoatNormalTexture ignored")),
        "{:?}",
        desc.warnings
    );
    // The export writes the factors back.
    let mut layered = cornell_box(false);
    layered.materials[0] = Material {
        specular: 0.25,
        specular_color: Vec3::new(0.5, 1.0, 2.0),
        clearcoat: 0.5,
        clearcoat_roughness: 0.125,
        sheen_color: Vec3::new(0.75, 0.5, 0.25),
        sheen_roughness: 0.375,
        ..Material::diffuse(Vec3::ONE)
    };
    let back = load_description(&write_json(&dir, "export.gltf", &to_gltf(&layered))).unwrap();
    let m = &back.materials[0];
    assert_eq!(
        (m.specular, m.specular_color),
        (0.25, Vec3::new(0.5, 1.0, 2.0))
    );
    assert_eq!((m.clearcoat, m.clearcoat_roughness), (0.5, 0.125));
    assert_eq!(
        (m.sheen_color, m.sheen_roughness),
        (Vec3::new(0.75, 0.5, 0.25), 0.375)
    );
    v["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"] = json!("x");
    expect_error(
        &write_json(&dir, "bad-factor.gltf", &v),
        "materials[0].extensions.KHR_materials_clearcoat.clearcoatFactor: not a number",
    );
    v["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"] = json!(1.0);
    v["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"] =
        json!({"index": 7});
    expect_error(
        &write_json(&dir, "bad-texture.gltf", &v),
        "clearcoatTexture: texture 7 does not exist",
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The Cornell box with every primitive written as a Draco bitstream (by draco-core's
/// encoder; positions quantized to `bits` bits, or lossless without) and its accessors left
/// with counts only, as the extension lays files out.
fn draco_cornell_box(bits: Option<i32>) -> Value {
    use draco_core::{
        DataType, EncoderBuffer, EncoderOptions, FaceIndex, GeometryAttributeType, MeshEncoder,
        PointAttribute,
    };
    let desc = cornell_box(false);
    let mut v = to_gltf(&desc);
    for (m, mesh) in desc.meshes.iter().enumerate() {
        let mut draco = draco_core::Mesh::new();
        let mut positions = PointAttribute::new();
        let n = mesh.positions.len();
        positions.init(
            GeometryAttributeType::Position,
            3,
            DataType::Float32,
            false,
            n,
        );
        for (i, p) in mesh.positions.iter().enumerate() {
            for (c, x) in p.to_array().iter().enumerate() {
                positions
                    .buffer_mut()
                    .write((i * 3 + c) * 4, &x.to_le_bytes());
            }
        }
        draco.add_attribute(positions);
        draco.set_num_faces(mesh.indices.len() / 3);
        for (f, t) in mesh.indices.chunks_exact(3).enumerate() {
            draco.set_face(FaceIndex(f as u32), [t[0].into(), t[1].into(), t[2].into()]);
        }
        let mut encoder = MeshEncoder::new();
        encoder.set_mesh(draco);
        let mut bytes = EncoderBuffer::new();
        let mut options = EncoderOptions::new();
        if let Some(bits) = bits {
            options.set_attribute_int(0, "quantization_bits", bits);
        }
        encoder.encode(&options, &mut bytes).unwrap();
        let view = push_buffer_view(&mut v, bytes.data());
        let prim = &mut v["meshes"][m]["primitives"][0];
        prim["extensions"] = json!({"KHR_draco_mesh_compression":
            {"bufferView": view, "attributes": {"POSITION": 0}}});
        let accessors = [
            prim["attributes"]["POSITION"].clone(),
            prim["indices"].clone(),
        ];
        for a in accessors {
            v["accessors"][a.as_u64().unwrap() as usize]
                .as_object_mut()
                .unwrap()
                .remove("bufferView");
        }
    }
    v["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    v
}

/// KHR_draco_mesh_compression: a lossless bitstream loads as the same triangles, winding
/// included, as the plain file; one quantized to 14 bits (as exporters write them) puts every
/// vertex within a quantization step (the box's extent, 2, over 2^14) of the plain one and
/// keeps the total area; a corrupt bitstream is an error naming the mesh and the extension,
/// not a panic.
#[test]
fn draco_compressed_primitives_load_as_the_meshes_they_encode() {
    let dir = temp_dir("draco");
    let plain = load_description(&write_json(
        &dir,
        "plain.gltf",
        &to_gltf(&cornell_box(false)),
    ))
    .unwrap();
    let mut v = draco_cornell_box(None);
    let compressed = load_description(&write_json(&dir, "draco.gltf", &v)).unwrap();
    assert_eq!(triangle_sets(&compressed), triangle_sets(&plain));
    let quantized =
        load_description(&write_json(&dir, "q.gltf", &draco_cornell_box(Some(14)))).unwrap();
    let step = 2.0 / 16384.0;
    let area = |d: &SceneDescription| -> f64 {
        d.meshes
            .iter()
            .flat_map(|m| {
                m.indices.chunks_exact(3).map(|t| {
                    let p = t
                        .iter()
                        .map(|&i| m.positions[i as usize])
                        .collect::<Vec<_>>();
                    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64
                })
            })
            .sum()
    };
    assert!((area(&quantized) / area(&plain) - 1.0).abs() < 1e-3);
    for (q, p) in quantized.meshes.iter().zip(&plain.meshes) {
        for x in &q.positions {
            let nearest = p.positions.iter().map(|y| (*x - *y).abs().max_element());
            assert!(nearest.fold(f32::MAX, f32::min) <= step, "{}: {x}", q.name);
        }
    }
    // A bitstream cut short.
    let view =
        v["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"]
            .as_u64()
            .unwrap() as usize;
    v["bufferViews"][view]["byteLength"] = json!(12);
    expect_error(
        &write_json(&dir, "cut.gltf", &v),
        "floor: KHR_draco_mesh_compression: the Draco bitstream cannot be decoded",
    );
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

/// A camera enclosed by a mesh (a skybox, a room without lamps) in a scene whose only light
/// is the default environment sees nothing lit: the build says so, naming the material. Not
/// when a light is inside, nor when the camera is outside.
#[test]
fn an_enclosed_camera_without_light_inside_is_named_in_a_warning() {
    use caustica_renderer::procedural::sphere_with_point_light;
    use caustica_renderer::scene::Scene;
    let enclosed = |desc: SceneDescription| {
        Scene::build(desc)
            .unwrap()
            .info
            .warnings
            .iter()
            .any(|w| w.starts_with("the camera is enclosed") && w.contains("'sky'"))
    };
    let mut sky = sphere_with_point_light(32);
    sky.materials[0] = sky.materials[0].clone().named("sky");
    assert!(!enclosed(sky.clone()), "a light inside: nothing to say");
    sky.lights.clear();
    assert!(enclosed(sky.clone()));
    sky.camera = None;
    assert!(!enclosed(sky), "the default camera is outside the model");
}

/// Nodes that share children, each level referring twice to the next (40 levels, 2^40 paths
/// to the mesh): each node is walked once, with a warning, not 2^40 times.
#[test]
fn shared_nodes_are_walked_once() {
    let dir = temp_dir("shared-nodes");
    let mut v = to_gltf(&cornell_box(false));
    let meshes = v["meshes"].as_array().unwrap().len();
    let levels = 40;
    let mut nodes = v["nodes"].as_array().unwrap().clone();
    // Level i holds nodes first + 2i and first + 2i + 1, both parents of both at level i + 1.
    let first = nodes.len();
    for i in 0..levels {
        let next = first + 2 * (i + 1);
        let children = if i + 1 < levels {
            json!([next, next + 1])
        } else {
            json!((0..meshes).collect::<Vec<_>>())
        };
        nodes.push(json!({"children": children}));
        nodes.push(json!({"children": children}));
    }
    v["nodes"] = Value::Array(nodes);
    v["scenes"][0]["nodes"] = json!([first, first + 1]);
    let desc = load_description(&write_json(&dir, "shared.gltf", &v)).unwrap();
    let plain = cornell_box(false);
    let triangles = |d: &SceneDescription| d.meshes.iter().map(|m| m.indices.len()).sum::<usize>();
    assert_eq!(triangles(&desc), triangles(&plain));
    assert_eq!(
        desc.warnings
            .iter()
            .filter(|w| w.contains("reached a second time"))
            .count(),
        1,
        "{:?}",
        desc.warnings
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Each limit refuses what exceeds it, naming the size, the limit and the flag that raises
/// it; the same file loads within the default limits.
#[test]
fn files_over_a_load_limit_are_refused_naming_the_limit_and_its_flag() {
    use caustica_renderer::scene::gltf::load_description_with;
    use caustica_renderer::scene::limits::LoadLimits;
    let dir = temp_dir("limits");
    let refusal = |path: &Path, limits: LoadLimits| {
        load_description_with(path, &limits)
            .unwrap_err()
            .to_string()
    };
    let defaults = LoadLimits::default();

    // Triangles, counted per instance: every mesh instanced 30 more times.
    let mut v = to_gltf(&cornell_box(false));
    let meshes = v["meshes"].as_array().unwrap().len();
    let mut nodes = v["nodes"].as_array().unwrap().clone();
    for copy in 0..30 {
        for m in 0..meshes {
            nodes.push(json!({"mesh": m, "translation": [copy as f32 * 3.0, 0.0, 0.0]}));
        }
    }
    v["nodes"] = Value::Array(nodes.clone());
    v["scenes"][0]["nodes"] = json!((0..nodes.len()).collect::<Vec<_>>());
    let path = write_json(&dir, "instances.gltf", &v);
    let one = cornell_box(false)
        .meshes
        .iter()
        .map(|m| m.indices.len() as u64 / 3)
        .sum::<u64>();
    let limits = LoadLimits {
        max_triangles: one * 10,
        ..defaults
    };
    let e = refusal(&path, limits);
    assert!(e.starts_with(&path.display().to_string()), "{e}");
    assert!(
        e.contains(&format!("over the limit of {}", one * 10)),
        "{e}"
    );
    assert!(e.contains("(raise it with --max-triangles)"), "{e}");
    let desc = load_description_with(&path, &defaults).unwrap();
    assert_eq!(
        desc.meshes
            .iter()
            .map(|m| m.indices.len() as u64 / 3)
            .sum::<u64>(),
        one * 31
    );

    // Buffers: the declared length, and an external file's size, before anything is read.
    let (json, bin) = split_buffer(to_gltf(&cornell_box(false)));
    let mut external = json.clone();
    external["buffers"][0]["uri"] = json!("box.bin");
    std::fs::write(dir.join("box.bin"), &bin).unwrap();
    let path = write_json(&dir, "external.gltf", &external);
    let limits = LoadLimits {
        max_buffer_bytes: bin.len() as u64 - 1,
        ..defaults
    };
    let e = refusal(&path, limits);
    assert!(
        e.contains(&format!("the buffers hold {} bytes", bin.len())),
        "{e}"
    );
    assert!(e.contains("(raise it with --max-buffer-bytes)"), "{e}");
    let mut declared = external.clone();
    declared["buffers"][0]["byteLength"] = json!(1u64 << 40);
    let e = refusal(&write_json(&dir, "declared.gltf", &declared), defaults);
    assert!(
        e.contains(&format!("the buffers hold {} bytes", 1u64 << 40)),
        "{e}"
    );
    load_description_with(&path, &defaults).unwrap();

    // Node depth: the box's meshes under a chain of 20 nodes.
    let mut v = to_gltf(&cornell_box(false));
    let mut nodes = v["nodes"].as_array().unwrap().clone();
    let roots = v["scenes"][0]["nodes"].clone();
    let first = nodes.len();
    for level in 0..20 {
        let children = if level == 19 {
            roots.clone()
        } else {
            json!([first + level + 1])
        };
        nodes.push(json!({ "children": children }));
    }
    v["nodes"] = Value::Array(nodes);
    v["scenes"][0]["nodes"] = json!([first]);
    let path = write_json(&dir, "deep.gltf", &v);
    let limits = LoadLimits {
        max_node_depth: 10,
        ..defaults
    };
    let e = refusal(&path, limits);
    assert!(
        e.contains(
            "the node hierarchy is deeper, over the limit of 10 (raise it with \
             --max-node-depth)"
        ),
        "{e}"
    );
    load_description_with(&path, &defaults).unwrap();
    std::fs::remove_dir_all(dir).unwrap();
}
