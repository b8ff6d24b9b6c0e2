//! The glTF loader: valid files in every container (.gltf with embedded or external buffers,
//! .glb), the design's interpretation of materials, lights and cameras, and a set of broken
//! files that must give an error naming the file and the problem, never a panic.

use caustica_renderer::light::Light;
use caustica_renderer::material::{Material, MaterialKind};
use caustica_renderer::procedural::{cornell_box, quad};
use caustica_renderer::scene::gltf::load;
use caustica_renderer::scene::gltf_export::{to_glb, to_gltf};
use caustica_renderer::scene::{PunctualLightDesc, SceneDescription};
use glam::Vec3;
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
fn a_scene_without_emitters_gets_the_uniform_environment() {
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
            .any(|w| w.contains("uniform environment"))
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
    v["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    expect_error(
        &write_json(&dir, "required-extension.gltf", &v),
        "unsupported extension KHR_draco_mesh_compression",
    );

    let mut v = good.clone();
    v["nodes"][0]["children"] = json!([0]);
    expect_error(&write_json(&dir, "cyclic.gltf", &v), "glTF");

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
    let textured = scene
        .intersect(&Ray::new(Vec3::new(0.1, 1.0, 0.2), Vec3::NEG_Y))
        .unwrap();
    match scene.bsdf(&textured) {
        Bsdf::Diffuse(d) => assert!(
            (d.r - Vec3::new(srgb(128), srgb(64), srgb(255)))
                .abs()
                .max_element()
                < 1e-5,
            "{:?}",
            d.r
        ),
        other => panic!("expected the diffuse floor, got {other:?}"),
    }
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
