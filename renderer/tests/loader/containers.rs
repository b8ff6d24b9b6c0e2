//! Containers (.gltf with embedded or external buffers, .glb), broken and corrupted files,
//! files without nodes or scenes, the errors' form, and the load limits.

use super::{expect_error, glb, load_glb, split_buffer, temp_dir, write_json};
use caustica_renderer::procedural::cornell_box;
use caustica_renderer::scene::gltf::export::{to_glb, to_gltf};
use caustica_renderer::scene::gltf::load;
use serde_json::{Value, json};
use std::path::Path;

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
