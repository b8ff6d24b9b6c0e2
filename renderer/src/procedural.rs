//! Scenes the project generates itself: meshes (spheres, boxes, quads), the closed-form test
//! scenes, and the bundled Cornell boxes written to `assets/` by `examples/make_assets.rs`.

use crate::camera::CameraDesc;
use crate::material::Material;
use crate::scene::{MeshDesc, PunctualLightDesc, SceneDescription};
use glam::{Affine3A, Quat, Vec2, Vec3};
use std::f32::consts::PI;

/// UV sphere with `segments` around and `rings` from pole to pole. With `inward`, triangles
/// face the centre (counter-clockwise seen from inside) and normals point inward.
pub fn uv_sphere(
    name: &str,
    center: Vec3,
    radius: f32,
    segments: u32,
    rings: u32,
    inward: bool,
    material: u32,
) -> MeshDesc {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(center + radius * n);
            normals.push(if inward { -n } else { n });
            uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    let mut indices = Vec::new();
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (
                r * row + s,
                (r + 1) * row + s,
                (r + 1) * row + s + 1,
                r * row + s + 1,
            );
            // Counter-clockwise seen from outside; the poles' zero-area triangles are skipped.
            let mut tris = Vec::new();
            if r != 0 {
                tris.push([a, b, d]);
            }
            if r != rings - 1 {
                tris.push([d, b, c]);
            }
            for mut t in tris {
                if inward {
                    t.swap(1, 2);
                }
                indices.extend_from_slice(&t);
            }
        }
    }
    MeshDesc {
        name: name.into(),
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
        material,
    }
}

/// Quad p0 p1 p2 p3, counter-clockwise seen from its front.
pub fn quad(name: &str, p: [Vec3; 4], material: u32) -> MeshDesc {
    MeshDesc {
        name: name.into(),
        positions: p.to_vec(),
        normals: None,
        uvs: Some(vec![
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ]),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
    }
}

/// The unit cube [-0.5, 0.5]^3 transformed by `xf`, faces outward.
pub fn cuboid(name: &str, xf: Affine3A, material: u32) -> MeshDesc {
    let c = |x: f32, y: f32, z: f32| xf.transform_point3(Vec3::new(x, y, z) * 0.5);
    let faces = [
        [
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ], // +z
        [
            c(1., -1., -1.),
            c(-1., -1., -1.),
            c(-1., 1., -1.),
            c(1., 1., -1.),
        ], // -z
        [
            c(1., -1., 1.),
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(1., 1., 1.),
        ], // +x
        [
            c(-1., -1., -1.),
            c(-1., -1., 1.),
            c(-1., 1., 1.),
            c(-1., 1., -1.),
        ], // -x
        [
            c(-1., 1., 1.),
            c(1., 1., 1.),
            c(1., 1., -1.),
            c(-1., 1., -1.),
        ], // +y
        [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., -1., 1.),
            c(-1., -1., 1.),
        ], // -y
    ];
    let mut mesh = MeshDesc {
        name: name.into(),
        material,
        ..Default::default()
    };
    for f in faces {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(&f);
        mesh.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    mesh
}

pub fn camera_looking(from: Vec3, to: Vec3, yfov_degrees: f32) -> CameraDesc {
    let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, (to - from).normalize());
    CameraDesc {
        camera_to_world: Affine3A::from_rotation_translation(rotation, from),
        yfov: yfov_degrees.to_radians(),
        aspect: None,
    }
}

/// Closed form: inside a sphere of radius 1 and diffuse albedo 0.5, a point light of intensity
/// pi at the centre. Direct irradiance is pi everywhere, and the enclosure's interreflection
/// gives L = rho E / (pi (1 - rho)) = 1 in every direction.
pub fn sphere_with_point_light(segments: u32) -> SceneDescription {
    SceneDescription {
        name: "sphere-point-light".into(),
        meshes: vec![uv_sphere(
            "sphere",
            Vec3::ZERO,
            1.0,
            segments,
            segments / 2,
            true,
            0,
        )],
        materials: vec![Material::diffuse(Vec3::splat(0.5))],
        lights: vec![PunctualLightDesc::Point {
            position: Vec3::ZERO,
            intensity: Vec3::splat(PI),
        }],
        camera: Some(camera_looking(Vec3::ZERO, Vec3::NEG_Z, 60.0)),
        ..Default::default()
    }
}

/// Closed form: inside a closed sphere that emits `le` and reflects diffusely with albedo
/// `rho`, radiance is le / (1 - rho) everywhere (the Neumann series of a uniform enclosure).
pub fn emissive_sphere(le: f32, rho: f32, segments: u32) -> SceneDescription {
    let mut m = Material::diffuse(Vec3::splat(rho));
    m.emission = Vec3::splat(le);
    SceneDescription {
        name: "emissive-sphere".into(),
        meshes: vec![uv_sphere(
            "sphere",
            Vec3::ZERO,
            1.0,
            segments,
            segments / 2,
            true,
            0,
        )],
        materials: vec![m],
        camera: Some(camera_looking(
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.5, 0.0, -1.0),
            60.0,
        )),
        ..Default::default()
    }
}

/// The Cornell box: white, red and green diffuse walls in [-1, 1] x [0, 2] x [-1, 1], a square
/// area light under the ceiling, and two blocks; with `glass`, a smooth glass sphere (ior 1.5)
/// stands in place of the short block and throws a caustic on the floor.
pub fn cornell_box(glass: bool) -> SceneDescription {
    let white = Material {
        name: "white".into(),
        ..Material::diffuse(Vec3::new(0.725, 0.71, 0.68))
    };
    let red = Material {
        name: "red".into(),
        ..Material::diffuse(Vec3::new(0.63, 0.065, 0.05))
    };
    let green = Material {
        name: "green".into(),
        ..Material::diffuse(Vec3::new(0.14, 0.45, 0.091))
    };
    let light = Material {
        name: "light".into(),
        emission: Vec3::new(17.0, 12.0, 4.0),
        ..Material::diffuse(Vec3::splat(0.78))
    };
    let glass_material = Material {
        name: "glass".into(),
        base_color: Vec3::ONE,
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Default::default()
    };
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

/// Every mesh of a description scaled by `s` about the origin, camera included.
pub fn scaled(mut desc: SceneDescription, s: f32) -> SceneDescription {
    for m in &mut desc.meshes {
        for p in &mut m.positions {
            *p *= s;
        }
    }
    if let Some(c) = &mut desc.camera {
        c.camera_to_world.translation *= s;
    }
    desc
}

/// The scenes shipped in `assets/`, as (file name, glTF text).
pub fn bundled_assets() -> Vec<(&'static str, String)> {
    use crate::scene::gltf_export::to_gltf_string;
    vec![
        ("cornell-box.gltf", to_gltf_string(&cornell_box(false))),
        ("cornell-glass.gltf", to_gltf_string(&cornell_box(true))),
        ("caustic-pool.gltf", to_gltf_string(&caustic_pool())),
        ("door.gltf", to_gltf_string(&door())),
    ]
}

/// A slab of rippled glass: the top is a height field y = top + ripple(x, z) with smooth
/// normals, the bottom a plane at `bottom`, the sides closed, over [-half, half]^2 in x and z.
fn rippled_slab(name: &str, half: f32, bottom: f32, top: f32, n: u32, material: u32) -> MeshDesc {
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
    let mut face = |p: [Vec3; 4], normal: Vec3| {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(&p);
        normals.extend_from_slice(&[normal; 4]);
        mesh.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    };
    let h = half;
    face(
        [
            Vec3::new(-h, bottom, -h),
            Vec3::new(h, bottom, -h),
            Vec3::new(h, bottom, h),
            Vec3::new(-h, bottom, h),
        ],
        Vec3::NEG_Y,
    );
    for i in 0..n {
        let (x0, x1) = (coord(i), coord(i + 1));
        let top_at = |x: f32, z: f32| Vec3::new(x, top + ripple(x, z), z);
        // Front (+z) and back (-z) strips.
        face(
            [
                Vec3::new(x0, bottom, h),
                Vec3::new(x1, bottom, h),
                top_at(x1, h),
                top_at(x0, h),
            ],
            Vec3::Z,
        );
        face(
            [
                Vec3::new(x1, bottom, -h),
                Vec3::new(x0, bottom, -h),
                top_at(x0, -h),
                top_at(x1, -h),
            ],
            Vec3::NEG_Z,
        );
        // Right (+x) and left (-x) strips.
        face(
            [
                Vec3::new(h, bottom, x1),
                Vec3::new(h, bottom, x0),
                top_at(h, x0),
                top_at(h, x1),
            ],
            Vec3::X,
        );
        face(
            [
                Vec3::new(-h, bottom, x0),
                Vec3::new(-h, bottom, x1),
                top_at(-h, x1),
                top_at(-h, x0),
            ],
            Vec3::NEG_X,
        );
    }
    mesh.normals = Some(normals);
    mesh
}

/// Light reaching the camera mostly through specular surfaces: a small, bright light above a
/// slab of rippled glass over a diffuse floor, which the glass covers with caustics.
pub fn caustic_pool() -> SceneDescription {
    let floor = Material {
        name: "floor".into(),
        ..Material::diffuse(Vec3::new(0.8, 0.78, 0.72))
    };
    let glass = Material {
        name: "rippled glass".into(),
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Default::default()
    };
    let light = Material {
        name: "light".into(),
        emission: Vec3::new(60.0, 55.0, 45.0),
        ..Material::diffuse(Vec3::ZERO)
    };
    let v = Vec3::new;
    let s = 3.0;
    SceneDescription {
        name: "caustic-pool".into(),
        meshes: vec![
            quad(
                "floor",
                [v(-s, 0., s), v(s, 0., s), v(s, 0., -s), v(-s, 0., -s)],
                0,
            ),
            rippled_slab("glass", 1.2, 0.35, 0.6, 64, 1),
            quad(
                "light",
                [
                    v(-0.15, 2.6, -0.15),
                    v(0.15, 2.6, -0.15),
                    v(0.15, 2.6, 0.15),
                    v(-0.15, 2.6, 0.15),
                ],
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
    let white = Material {
        name: "wall".into(),
        ..Material::diffuse(Vec3::new(0.7, 0.7, 0.68))
    };
    let floor = Material {
        name: "glossy floor".into(),
        base_color: Vec3::new(0.55, 0.45, 0.35),
        metallic: 0.0,
        roughness: 0.3,
        ..Default::default()
    };
    let metal = Material {
        name: "glossy metal".into(),
        base_color: Vec3::new(0.9, 0.85, 0.7),
        metallic: 1.0,
        roughness: 0.2,
        ..Default::default()
    };
    let door_material = Material {
        name: "door".into(),
        ..Material::diffuse(Vec3::new(0.45, 0.3, 0.2))
    };
    let light = Material {
        name: "light".into(),
        emission: Vec3::new(2500.0, 2250.0, 1875.0),
        ..Material::diffuse(Vec3::ZERO)
    };
    let v = Vec3::new;
    // An axis-aligned slab from `lo` to `hi`.
    let slab = |name: &str, lo: Vec3, hi: Vec3, material: u32| {
        cuboid(
            name,
            Affine3A::from_scale_rotation_translation(hi - lo, Quat::IDENTITY, 0.5 * (lo + hi)),
            material,
        )
    };
    let (x0, x1, xw, z, h) = (-2.0, 5.0, 2.0, 2.0, 2.5);
    let t = 0.1;
    let meshes = vec![
        slab("floor", v(x0 - t, -t, -z - t), v(x1 + t, 0.0, z + t), 1),
        slab("ceiling", v(x0 - t, h, -z - t), v(x1 + t, h + t, z + t), 0),
        slab("wall -z", v(x0 - t, 0.0, -z - t), v(x1 + t, h, -z), 0),
        slab("wall +z", v(x0 - t, 0.0, z), v(x1 + t, h, z + t), 0),
        slab("wall near end", v(x0 - t, 0.0, -z), v(x0, h, z), 0),
        slab("wall far end", v(x1, 0.0, -z), v(x1 + t, h, z), 0),
        // The dividing wall with a doorway in z [-0.5, 0.5], 2 m high.
        slab("dividing wall -z", v(xw, 0.0, -z), v(xw + t, h, -0.5), 0),
        slab("dividing wall +z", v(xw, 0.0, 0.5), v(xw + t, h, z), 0),
        slab("lintel", v(xw, 2.0, -0.5), v(xw + t, h, 0.5), 0),
        // The door fills the doorway but for a 3 cm slit along its free edge.
        slab("door", v(xw + 0.02, 0.0, -0.5), v(xw + 0.07, 2.0, 0.47), 3),
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
        quad(
            "light",
            [
                v(3.8, 2.0, 0.4),
                v(4.6, 2.0, 0.4),
                v(4.6, 2.0, -0.4),
                v(3.8, 2.0, -0.4),
            ],
            4,
        ),
    ];
    SceneDescription {
        name: "door".into(),
        meshes,
        materials: vec![white, floor, metal, door_material, light],
        camera: Some(camera_looking(v(-1.8, 1.5, 1.7), v(1.6, 0.5, -0.3), 60.0)),
        ..Default::default()
    }
}
