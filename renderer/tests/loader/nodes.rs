//! The node walk: cameras (perspective, orthographic, several), punctual lights, mirrored
//! and shared nodes, and the warning for a camera enclosed without light.

use super::{temp_dir, write_json};
use caustica_renderer::light::Light;
use caustica_renderer::material::Material;
use caustica_renderer::procedural::{cornell_box, quad};
use caustica_renderer::scene::gltf::export::to_gltf;
use caustica_renderer::scene::gltf::{load, load_description};
use caustica_renderer::scene::{PunctualLightDesc, SceneDescription};
use glam::Vec3;
use serde_json::{Value, json};

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
