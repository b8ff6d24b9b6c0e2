//! The bundled scenes (`assets/`, written by `examples/make_assets.rs`; a test checks the
//! committed files are what this writes): the Cornell boxes, the material spheres, the caustic
//! pool, the door, and the gap with glass.

use super::{camera_looking, cuboid, horizontal_quad, push_quad, quad, uv_sphere};
use crate::material::Material;
use crate::scene::{MeshDesc, SceneDescription};
use glam::{Affine3A, Quat, Vec2, Vec3};

/// The Cornell box: white, red and green diffuse walls in [-1, 1] x [0, 2] x [-1, 1], a square
/// area light under the ceiling, and two blocks; with `glass`, a smooth glass sphere (ior 1.5)
/// stands in place of the short block and throws a caustic on the floor.
pub fn cornell_box(glass: bool) -> SceneDescription {
    let white = Material::diffuse(Vec3::new(0.725, 0.71, 0.68)).named("white");
    let red = Material::diffuse(Vec3::new(0.63, 0.065, 0.05)).named("red");
    let green = Material::diffuse(Vec3::new(0.14, 0.45, 0.091)).named("green");
    let light = Material::emitter(Vec3::new(17.0, 12.0, 4.0), Vec3::splat(0.78)).named("light");
    let glass_material = Material::glass(1.5).named("glass");
    let v = Vec3::new;
    // The walls (counter-clockwise seen from inside the box) and the light: name, corners,
    // material.
    #[rustfmt::skip]
    let quads: [(&str, [Vec3; 4], u32); 6] = [
        ("floor", [v(-1., 0., 1.), v(1., 0., 1.), v(1., 0., -1.), v(-1., 0., -1.)], 0),
        ("ceiling", [v(-1., 2., -1.), v(1., 2., -1.), v(1., 2., 1.), v(-1., 2., 1.)], 0),
        ("back", [v(-1., 0., -1.), v(1., 0., -1.), v(1., 2., -1.), v(-1., 2., -1.)], 0),
        ("left", [v(-1., 0., 1.), v(-1., 0., -1.), v(-1., 2., -1.), v(-1., 2., 1.)], 1),
        ("right", [v(1., 0., -1.), v(1., 0., 1.), v(1., 2., 1.), v(1., 2., -1.)], 2),
        ("light", [v(-0.25, 1.98, -0.25), v(0.25, 1.98, -0.25), v(0.25, 1.98, 0.25),
                   v(-0.25, 1.98, 0.25)], 3),
    ];
    let mut meshes: Vec<MeshDesc> = quads
        .iter()
        .map(|(name, corners, material)| quad(name, *corners, *material))
        .collect();
    meshes.push(cuboid(
        "tall block",
        Affine3A::from_scale_rotation_translation(
            v(0.6, 1.2, 0.6),
            Quat::from_rotation_y(0.3),
            v(-0.35, 0.6, -0.3),
        ),
        0,
    ));
    if glass {
        meshes.push(uv_sphere(
            "glass sphere",
            v(0.4, 0.4, 0.35),
            0.4,
            64,
            32,
            false,
            4,
        ));
    } else {
        meshes.push(cuboid(
            "short block",
            Affine3A::from_scale_rotation_translation(
                v(0.6, 0.6, 0.6),
                Quat::from_rotation_y(-0.3),
                v(0.35, 0.3, 0.35),
            ),
            0,
        ));
    }
    let mut materials = vec![white, red, green, light];
    if glass {
        materials.push(glass_material);
    }
    SceneDescription {
        name: if glass {
            "cornell-glass"
        } else {
            "cornell-box"
        }
        .into(),
        meshes,
        materials,
        camera: Some(camera_looking(v(0.0, 1.0, 3.9), v(0.0, 1.0, 0.0), 39.3)),
        ..Default::default()
    }
}

/// The scenes shipped in `assets/`, as (file name, glTF text).
pub fn bundled_assets() -> Vec<(&'static str, String)> {
    use crate::scene::gltf::export::to_gltf_string;
    vec![
        ("cornell-box.gltf", to_gltf_string(&cornell_box(false))),
        ("cornell-glass.gltf", to_gltf_string(&cornell_box(true))),
        ("caustic-pool.gltf", to_gltf_string(&caustic_pool())),
        ("door.gltf", to_gltf_string(&door())),
        ("gap-glass.gltf", to_gltf_string(&gap_glass())),
        ("material-spheres.gltf", to_gltf_string(&material_spheres())),
    ]
}

/// A model meant to be lit by its viewer, after the Khronos metal-rough sphere grid: two rows
/// of five spheres, metal above and red plastic below, roughness 0 to 1 from left to right.
/// It has no light: the default rule lights it with the studio, whose reflections grade with
/// roughness.
pub fn material_spheres() -> SceneDescription {
    let mut meshes = Vec::new();
    let mut materials = Vec::new();
    for (row, (y, color, metallic)) in [
        (0.55, Vec3::new(0.95, 0.93, 0.88), 1.0),
        (-0.55, Vec3::new(0.7, 0.05, 0.04), 0.0),
    ]
    .into_iter()
    .enumerate()
    {
        for i in 0..5 {
            let roughness = i as f32 / 4.0;
            let material = (row * 5 + i) as u32;
            materials.push(
                Material::metallic_roughness(color, metallic, roughness).named(&format!(
                    "{} roughness {roughness}",
                    ["metal", "plastic"][row]
                )),
            );
            let center = Vec3::new(1.1 * (i as f32 - 2.0), y, 0.0);
            meshes.push(uv_sphere(
                &format!("sphere {row} {i}"),
                center,
                0.5,
                48,
                24,
                false,
                material,
            ));
        }
    }
    SceneDescription {
        name: "material-spheres".into(),
        meshes,
        materials,
        camera: Some(camera_looking(Vec3::new(0.0, 0.4, 7.5), Vec3::ZERO, 35.0)),
        ..Default::default()
    }
}

/// A slab of rippled glass: the top is a height field y = top + ripple(x, z) with smooth
/// normals, the bottom a plane at `bottom`, the sides closed, over [-half, half]^2 in x and z.
fn rippled_axis_box(
    name: &str,
    half: f32,
    bottom: f32,
    top: f32,
    n: u32,
    material: u32,
) -> MeshDesc {
    let ripple = |x: f32, z: f32| {
        0.045 * (4.0 * x).sin() * (5.0 * z).cos() + 0.02 * (9.0 * x + 3.0 * z).sin()
    };
    let slope = |x: f32, z: f32| {
        let dx = 0.045 * 4.0 * (4.0 * x).cos() * (5.0 * z).cos()
            + 0.02 * 9.0 * (9.0 * x + 3.0 * z).cos();
        let dz = -0.045 * 5.0 * (4.0 * x).sin() * (5.0 * z).sin()
            + 0.02 * 3.0 * (9.0 * x + 3.0 * z).cos();
        Vec3::new(-dx, 1.0, -dz).normalize()
    };
    let mut mesh = MeshDesc {
        name: name.into(),
        material,
        ..Default::default()
    };
    let mut normals = Vec::new();
    let v = Vec3::new;
    let coord = |i: u32| -half + 2.0 * half * i as f32 / n as f32;
    // Top height field, counter-clockwise seen from above.
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (coord(i), coord(j));
            mesh.positions.push(Vec3::new(x, top + ripple(x, z), z));
            normals.push(slope(x, z));
        }
    }
    let row = n + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i + 1,
                (j + 1) * row + i,
            );
            mesh.indices.extend_from_slice(&[a, d, c, a, c, b]);
        }
    }
    // Bottom and sides, flat-shaded: their vertices carry their face normal.
    let h = half;
    let bottom_face = [
        v(-h, bottom, -h),
        v(h, bottom, -h),
        v(h, bottom, h),
        v(-h, bottom, h),
    ];
    push_quad(&mut mesh, bottom_face);
    normals.extend_from_slice(&[Vec3::NEG_Y; 4]);
    let top_at = |(x, z): (f32, f32)| Vec3::new(x, top + ripple(x, z), z);
    for i in 0..n {
        let (a, b) = (coord(i), coord(i + 1));
        // Each side's strip from one (x, z) on the rim to the next, walked so that it faces out.
        for (from, to, normal) in [
            ((a, h), (b, h), Vec3::Z),
            ((b, -h), (a, -h), Vec3::NEG_Z),
            ((h, b), (h, a), Vec3::X),
            ((-h, a), (-h, b), Vec3::NEG_X),
        ] {
            let strip = [
                v(from.0, bottom, from.1),
                v(to.0, bottom, to.1),
                top_at(to),
                top_at(from),
            ];
            push_quad(&mut mesh, strip);
            normals.extend_from_slice(&[normal; 4]);
        }
    }
    mesh.normals = Some(normals);
    mesh
}

/// Light reaching the camera mostly through specular surfaces: a small, bright light above a
/// slab of rippled glass over a diffuse floor, which the glass covers with caustics.
pub fn caustic_pool() -> SceneDescription {
    caustic_pool_tessellated(64)
}

/// The caustic pool with its rippled surface an `n` x `n` grid (2 n^2 + 2 + 8 n triangles of
/// glass): `n = 64` is the bundled scene, `n = 707` a million triangles for the ray-casting
/// benchmarks.
pub fn caustic_pool_tessellated(n: u32) -> SceneDescription {
    let floor = Material::diffuse(Vec3::new(0.8, 0.78, 0.72)).named("floor");
    let glass = Material::glass(1.5).named("rippled glass");
    let light = Material::emitter(Vec3::new(60.0, 55.0, 45.0), Vec3::ZERO).named("light");
    let v = Vec3::new;
    let s = 3.0;
    SceneDescription {
        name: "caustic-pool".into(),
        meshes: vec![
            horizontal_quad("floor", 0.0, Vec2::splat(-s), Vec2::splat(s), true, 0),
            rippled_axis_box("glass", 1.2, 0.35, 0.6, n, 1),
            horizontal_quad(
                "light",
                2.6,
                Vec2::splat(-0.15),
                Vec2::splat(0.15),
                false,
                2,
            ),
        ],
        materials: vec![floor, glass, light],
        camera: Some(camera_looking(v(0.0, 2.4, 3.4), v(0.0, 0.2, 0.0), 45.0)),
        ..Default::default()
    }
}

/// Veach's door scene, in our words: two rooms joined by a doorway whose door is shut but for
/// a 3 cm slit; the only light is an uplight in the far room, which lights that room's
/// ceiling. Everything the camera sees in the near room is lit through the slit after at
/// least one bounce in the far room, on a glossy floor and a glossy metal sphere: next-event
/// estimation from the near room never sees the light, and a path tracer must pass the slit
/// and then hit the far ceiling by chance, so its image is mostly noise, while Metropolis
/// chains keep the paths that pass the slit once they have found them.
pub fn door() -> SceneDescription {
    let white = Material::diffuse(Vec3::new(0.7, 0.7, 0.68)).named("wall");
    let floor = Material::metallic_roughness(Vec3::new(0.55, 0.45, 0.35), 0.0, 0.3);
    let metal = Material::metallic_roughness(Vec3::new(0.9, 0.85, 0.7), 1.0, 0.2);
    let (floor, metal) = (floor.named("glossy floor"), metal.named("glossy metal"));
    let door_material = Material::diffuse(Vec3::new(0.45, 0.3, 0.2)).named("door");
    let light = Material::emitter(Vec3::new(2500.0, 2250.0, 1875.0), Vec3::ZERO).named("light");
    let v = Vec3::new;
    let (x0, x1, xw, z, h) = (-2.0, 5.0, 2.0, 2.0, 2.5);
    let t = 0.1;
    let mut meshes = room_shell((x0, x1), z, h, t, (1, 0));
    meshes.extend([
        // The dividing wall with a doorway in z [-0.5, 0.5], 2 m high.
        axis_box("dividing wall -z", v(xw, 0.0, -z), v(xw + t, h, -0.5), 0),
        axis_box("dividing wall +z", v(xw, 0.0, 0.5), v(xw + t, h, z), 0),
        axis_box("lintel", v(xw, 2.0, -0.5), v(xw + t, h, 0.5), 0),
        // The door fills the doorway but for a 3 cm slit along its free edge.
        axis_box("door", v(xw + 0.02, 0.0, -0.5), v(xw + 0.07, 2.0, 0.47), 3),
        uv_sphere("metal sphere", v(0.3, 0.45, -0.9), 0.45, 48, 24, false, 2),
        cuboid(
            "block",
            Affine3A::from_scale_rotation_translation(
                v(0.6, 0.9, 0.6),
                Quat::from_rotation_y(0.5),
                v(-0.6, 0.45, 0.9),
            ),
            0,
        ),
        // The uplight faces the far room's ceiling.
        horizontal_quad(
            "light",
            2.0,
            Vec2::new(3.8, -0.4),
            Vec2::new(4.6, 0.4),
            true,
            4,
        ),
    ]);
    SceneDescription {
        name: "door".into(),
        meshes,
        materials: vec![white, floor, metal, door_material, light],
        camera: Some(camera_looking(v(-1.8, 1.5, 1.7), v(1.6, 0.5, -0.3), 60.0)),
        ..Default::default()
    }
}

/// What each estimator fails alone: a room lit only through a narrow gap in a partition from
/// a closet whose light faces the gap, with a slab of rippled glass on low feet where the beam
/// through the gap falls. The floor under the slab is lit through the gap and the glass and
/// seen through the glass (a caustic seen through glass, which only merges sample), and the
/// rest of the room by light that passed the gap (which photons reach rarely and Metropolis
/// chains keep once found). The camera sees the room, not the closet.
pub fn gap_glass() -> SceneDescription {
    let white = Material::diffuse(Vec3::new(0.7, 0.7, 0.68)).named("wall");
    let floor = Material::diffuse(Vec3::new(0.75, 0.72, 0.65)).named("floor");
    let glass = Material::glass(1.5).named("rippled glass");
    let light = Material::emitter(Vec3::new(400.0, 370.0, 320.0), Vec3::ZERO).named("light");
    let v = Vec3::new;
    // The room is x in [-2, 2], the partition at x = 2, the closet behind it to x = 3;
    // z in [-2, 2], 2.5 high. The gap is 4 cm wide, floor to ceiling, at z = 0.
    let (x0, xp, x1, z, h, t) = (-2.0, 2.0, 3.0, 2.0, 2.5, 0.1);
    let gap = 0.02;
    let mut glass_slab = rippled_axis_box("glass", 0.8, 0.2, 0.4, 64, 2);
    for p in &mut glass_slab.positions {
        *p += v(1.0, 0.0, 0.0);
    }
    let mut meshes = room_shell((x0, x1), z, h, t, (1, 0));
    meshes.extend([
        axis_box("partition -z", v(xp, 0.0, -z), v(xp + t, h, -gap), 0),
        axis_box("partition +z", v(xp, 0.0, gap), v(xp + t, h, z), 0),
        glass_slab,
        // Four feet hold the slab 0.2 above the floor.
        axis_box("foot 1", v(0.25, 0.0, -0.75), v(0.3, 0.2, -0.7), 0),
        axis_box("foot 2", v(1.7, 0.0, -0.75), v(1.75, 0.2, -0.7), 0),
        axis_box("foot 3", v(0.25, 0.0, 0.7), v(0.3, 0.2, 0.75), 0),
        axis_box("foot 4", v(1.7, 0.0, 0.7), v(1.75, 0.2, 0.75), 0),
        // The light on the closet's back wall, high, facing the gap.
        quad_facing_neg_x("light", x1 - 0.01, 1.7, 2.3, -0.4, 0.4, 3),
    ]);
    SceneDescription {
        name: "gap-glass".into(),
        meshes,
        materials: vec![white, floor, glass, light],
        camera: Some(camera_looking(v(-1.2, 1.5, 1.6), v(1.1, 0.3, -0.1), 55.0)),
        ..Default::default()
    }
}

/// A rectangle in the plane x = `x`, over y in [y0, y1] and z in [z0, z1], facing -x.
fn quad_facing_neg_x(
    name: &str,
    x: f32,
    y0: f32,
    y1: f32,
    z0: f32,
    z1: f32,
    material: u32,
) -> MeshDesc {
    let v = Vec3::new;
    quad(
        name,
        [v(x, y0, z0), v(x, y0, z1), v(x, y1, z1), v(x, y1, z0)],
        material,
    )
}

/// An axis-aligned box from corner `lo` to corner `hi`.
fn axis_box(name: &str, lo: Vec3, hi: Vec3, material: u32) -> MeshDesc {
    cuboid(
        name,
        Affine3A::from_scale_rotation_translation(hi - lo, Quat::IDENTITY, 0.5 * (lo + hi)),
        material,
    )
}

/// A closed room of walls `t` thick around x in [x0, x1], z in [-z, z], y in [0, h]: its
/// floor of material `floor` and the rest of `wall`.
fn room_shell(
    (x0, x1): (f32, f32),
    z: f32,
    h: f32,
    t: f32,
    (floor, wall): (u32, u32),
) -> Vec<MeshDesc> {
    let v = Vec3::new;
    vec![
        axis_box("floor", v(x0 - t, -t, -z - t), v(x1 + t, 0.0, z + t), floor),
        axis_box(
            "ceiling",
            v(x0 - t, h, -z - t),
            v(x1 + t, h + t, z + t),
            wall,
        ),
        axis_box("wall -z", v(x0 - t, 0.0, -z - t), v(x1 + t, h, -z), wall),
        axis_box("wall +z", v(x0 - t, 0.0, z), v(x1 + t, h, z + t), wall),
        axis_box("wall near end", v(x0 - t, 0.0, -z), v(x0, h, z), wall),
        axis_box("wall far end", v(x1, 0.0, -z), v(x1 + t, h, z), wall),
    ]
}
