//! Materials: the metallic-roughness base as the design reads it, the default lighting rule,
//! the unlit look, alpha modes, and the layers (specular, clearcoat, sheen, volume).

use super::{expect_error, temp_dir, write_json};
use caustica_renderer::light::Light;
use caustica_renderer::material::{Material, MaterialKind};
use caustica_renderer::procedural::cornell_box;
use caustica_renderer::scene::gltf::export::to_gltf;
use caustica_renderer::scene::gltf::{load, load_description};
use glam::{Vec2, Vec3};
use serde_json::json;

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
