//! Scenes the project generates itself: meshes (spheres, boxes, quads) and the closed-form
//! test scenes here; the bundled scenes written to `assets/` by `examples/make_assets.rs` in
//! `bundled.rs`.

mod bundled;

pub use bundled::{
    bundled_assets, caustic_pool, caustic_pool_tessellated, cornell_box, door, gap_glass,
    material_spheres,
};

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
        uvs1: None,
        colors: None,
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
        uvs1: None,
        colors: None,
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
    }
}

/// A horizontal rectangle at height `y` over [min.x, max.x] x [min.y, max.y] in x and z,
/// facing up (+y) or down.
pub fn horizontal_quad(
    name: &str,
    y: f32,
    min: Vec2,
    max: Vec2,
    up: bool,
    material: u32,
) -> MeshDesc {
    let (x0, z0, x1, z1) = (min.x, min.y, max.x, max.y);
    let corners = if up {
        [[x0, z1], [x1, z1], [x1, z0], [x0, z0]]
    } else {
        [[x0, z0], [x1, z0], [x1, z1], [x0, z1]]
    };
    quad(name, corners.map(|[x, z]| Vec3::new(x, y, z)), material)
}

/// Appends quad p0 p1 p2 p3 (counter-clockwise seen from its front) as two triangles.
pub(crate) fn push_quad(mesh: &mut MeshDesc, p: [Vec3; 4]) {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&p);
    mesh.indices
        .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
}

/// The unit cube [-0.5, 0.5]^3 transformed by `xf`, faces outward.
pub fn cuboid(name: &str, xf: Affine3A, material: u32) -> MeshDesc {
    // Each face's corners in units of half the edge, counter-clockwise seen from outside.
    #[rustfmt::skip]
    const FACES: [[[f32; 3]; 4]; 6] = [
        [[-1., -1., 1.], [1., -1., 1.], [1., 1., 1.], [-1., 1., 1.]], // +z
        [[1., -1., -1.], [-1., -1., -1.], [-1., 1., -1.], [1., 1., -1.]], // -z
        [[1., -1., 1.], [1., -1., -1.], [1., 1., -1.], [1., 1., 1.]], // +x
        [[-1., -1., -1.], [-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.]], // -x
        [[-1., 1., 1.], [1., 1., 1.], [1., 1., -1.], [-1., 1., -1.]], // +y
        [[-1., -1., -1.], [1., -1., -1.], [1., -1., 1.], [-1., -1., 1.]], // -y
    ];
    let mut mesh = MeshDesc {
        name: name.into(),
        material,
        ..Default::default()
    };
    for face in FACES {
        push_quad(
            &mut mesh,
            face.map(|c| xf.transform_point3(Vec3::from(c) * 0.5)),
        );
    }
    mesh
}

pub fn camera_looking(from: Vec3, to: Vec3, yfov_degrees: f32) -> CameraDesc {
    let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, (to - from).normalize());
    CameraDesc::perspective(
        Affine3A::from_rotation_translation(rotation, from),
        yfov_degrees.to_radians(),
    )
}

/// The unit sphere about the origin, facing inward, with material 0: the enclosure of the
/// closed-form scenes.
fn enclosing_unit_sphere(segments: u32) -> MeshDesc {
    uv_sphere("sphere", Vec3::ZERO, 1.0, segments, segments / 2, true, 0)
}

/// Closed form: inside a sphere of radius 1 and diffuse albedo 0.5, a point light of intensity
/// pi at the centre. Direct irradiance is pi everywhere, and the enclosure's interreflection
/// gives L = rho E / (pi (1 - rho)) = 1 in every direction.
pub fn sphere_with_point_light(segments: u32) -> SceneDescription {
    SceneDescription {
        name: "sphere-point-light".into(),
        meshes: vec![enclosing_unit_sphere(segments)],
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
    let m = Material::emitter(Vec3::splat(le), Vec3::splat(rho));
    SceneDescription {
        name: "emissive-sphere".into(),
        meshes: vec![enclosing_unit_sphere(segments)],
        materials: vec![m],
        camera: Some(camera_looking(
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.5, 0.0, -1.0),
            60.0,
        )),
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
