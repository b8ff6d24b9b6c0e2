//! Primitives: degenerate triangles, modes other than triangles, strips and fans, sparse
//! accessors, vertex colours, morph targets and Draco-compressed primitives.

use super::{base_colour_at, expect_error, push_buffer_view, temp_dir, triangle_sets, write_json};
use caustica_renderer::material::Material;
use caustica_renderer::procedural::{cornell_box, quad};
use caustica_renderer::scene::SceneDescription;
use caustica_renderer::scene::gltf::export::to_gltf;
use caustica_renderer::scene::gltf::{load, load_description};
use glam::Vec3;
use serde_json::{Value, json};

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
