//! The BVH against brute force, watertightness, and invariance to the scene's units.

use caustica_renderer::geometry::Ray;
use caustica_renderer::procedural::{cornell_box, scaled, uv_sphere};
use caustica_renderer::sampling::sampler::Sampler;
use caustica_renderer::sampling::warp::{sample_uniform_sphere, sample_uniform_triangle};
use caustica_renderer::scene::triangle::{RayShear, intersect_triangle};
use caustica_renderer::scene::{MeshDesc, Scene, SceneDescription};
use glam::{Vec2, Vec3};

fn soup(n: usize, seed: u64) -> SceneDescription {
    let mut s = Sampler::new(seed);
    let mut mesh = MeshDesc {
        name: "soup".into(),
        ..Default::default()
    };
    for i in 0..n {
        s.start_pixel_sample(i as u64, 0);
        let c = Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) * 10.0 - 5.0;
        for _ in 0..3 {
            mesh.positions
                .push(c + (Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) - 0.5) * 1.5);
        }
        mesh.indices
            .extend_from_slice(&[3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2]);
    }
    SceneDescription {
        meshes: vec![mesh],
        ..Default::default()
    }
}

fn brute_force(scene: &Scene, ray: &Ray) -> Option<(f32, u32)> {
    let shear = RayShear::new(ray.o, ray.d);
    let mut best: Option<(f32, u32)> = None;
    for (i, p) in scene.positions.iter().enumerate() {
        let t_max = best.map_or(ray.t_max, |b| b.0);
        if let Some(h) = intersect_triangle(&shear, t_max, p[0], p[1], p[2]) {
            best = Some((h.t, i as u32));
        }
    }
    best
}

/// Random rays: from random points, from points on triangles (as spawned by shading), and
/// aimed at triangle edges (grazing, the hard case for a traversal).
fn test_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let mut s = Sampler::new(99);
    let mut rays = Vec::with_capacity(n);
    for i in 0..n {
        s.start_pixel_sample(i as u64, 1);
        let tri = &scene.positions[(s.get_1d() * scene.positions.len() as f32) as usize];
        let d = sample_uniform_sphere(s.get_2d());
        let ray = match i % 3 {
            0 => Ray::new(
                (Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) - 0.5) * 14.0,
                d,
            ),
            1 => {
                let b = sample_uniform_triangle(s.get_2d());
                let p = tri[0] * b.x + tri[1] * b.y + tri[2] * b.z;
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                let err = Vec3::splat(1e-5) * p.abs().max(Vec3::ONE);
                Ray::new(
                    caustica_renderer::geometry::offset_ray_origin(p, err, n, d),
                    d,
                )
            }
            _ => {
                let t = s.get_1d();
                let target = tri[0] * (1.0 - t) + tri[1] * t;
                let o = target - d * 8.0;
                Ray::new(o, d)
            }
        };
        let mut ray = ray;
        if i % 5 == 0 {
            ray.t_max = 3.0;
        }
        rays.push(ray);
    }
    rays
}

#[test]
fn closest_hit_and_occlusion_match_brute_force() {
    let scene = Scene::build(soup(2000, 5)).unwrap();
    let mut hits = 0;
    for ray in test_rays(&scene, 20_000) {
        let expected = brute_force(&scene, &ray);
        let got = scene.intersect(&ray);
        match (expected, got) {
            (None, None) => {}
            (Some((t, tri)), Some(si)) => {
                hits += 1;
                assert!(
                    (si.t - t).abs() <= 1e-5 * t.max(1.0),
                    "t {} vs brute force {t}",
                    si.t
                );
                // Another triangle at the same distance (a shared point) is as good an answer.
                if si.triangle != tri {
                    assert!((si.t - t).abs() <= 1e-6 * t.max(1.0));
                }
            }
            (e, g) => panic!(
                "BVH and brute force disagree on {ray:?}: {e:?} vs {:?}",
                g.map(|s| (s.t, s.triangle))
            ),
        }
        assert_eq!(
            scene.occluded(&ray),
            expected.is_some(),
            "occlusion disagrees on {ray:?}"
        );
    }
    assert!(hits > 5_000, "the test rays should mostly hit ({hits})");
}

#[test]
fn no_ray_escapes_a_closed_mesh() {
    // 262,144 rays from inside a closed sphere mesh, through its shared edges and vertices.
    let sphere = uv_sphere("s", Vec3::ZERO, 1.0, 64, 32, false, 0);
    let scene = Scene::build(SceneDescription {
        meshes: vec![sphere],
        ..Default::default()
    })
    .unwrap();
    let mut s = Sampler::new(3);
    let mut escaped = 0;
    for i in 0..262_144u64 {
        s.start_pixel_sample(i, 0);
        let o = (Vec3::new(s.get_1d(), s.get_1d(), s.get_1d()) - 0.5) * 0.2;
        // Aim half the rays exactly at vertices, where many triangles meet.
        let d = if i % 2 == 0 {
            sample_uniform_sphere(s.get_2d())
        } else {
            let tri = &scene.positions[(i as usize / 2) % scene.positions.len()];
            (tri[(i as usize / 2) % 3] - o).normalize()
        };
        if scene.intersect(&Ray::new(o, d)).is_none() {
            escaped += 1;
        }
    }
    assert_eq!(escaped, 0, "{escaped} rays escaped a closed mesh");
}

#[test]
fn scenes_in_millimetres_and_kilometres_trace_like_metres() {
    let base = Scene::build(cornell_box(true)).unwrap();
    let mut s = Sampler::new(11);
    let rays: Vec<(Vec3, Vec3)> = (0..20_000u64)
        .map(|i| {
            s.start_pixel_sample(i, 0);
            // Origins on surfaces, as secondary rays start.
            let tri = &base.positions[(s.get_1d() * base.positions.len() as f32) as usize];
            let b = sample_uniform_triangle(s.get_2d());
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
            let mut d = sample_uniform_sphere(Vec2::new(s.get_1d(), s.get_1d()));
            if d.dot(n) < 0.0 {
                d = -d;
            }
            (tri[0] * b.x + tri[1] * b.y + tri[2] * b.z + n * 1e-4, d)
        })
        .collect();
    for scale in [1e-3f32, 1e3] {
        let scene = Scene::build(scaled(cornell_box(true), scale)).unwrap();
        let mut mismatches = 0;
        for (o, d) in &rays {
            let a = base.intersect(&Ray::new(*o, *d));
            let b = scene.intersect(&Ray::new(*o * scale, *d));
            match (a, b) {
                (Some(a), Some(b))
                    if a.triangle == b.triangle
                        && (a.t - b.t / scale).abs() <= 1e-4 * a.t.max(1e-3) => {}
                (None, None) => {}
                _ => mismatches += 1,
            }
        }
        // Only rays grazing an edge may resolve differently after rounding.
        assert!(
            mismatches <= rays.len() / 1000,
            "scale {scale}: {mismatches} of {} rays differ",
            rays.len()
        );
    }
}

/// The memory report counts what the parts hold: positions alone are 36 bytes a triangle, the
/// BVH keeps its own copy of them and its nodes, an untextured scene has no texels, and the
/// lights' part holds at least the triangle-to-light map.
#[test]
fn scene_memory_counts_each_part() {
    let scene = Scene::build(soup(1000, 3)).unwrap();
    let m = scene.memory();
    let triangles = scene.positions.len();
    assert_eq!(triangles, 1000);
    assert!(m.geometry >= 36 * triangles, "{m:?}");
    assert!(m.bvh > 36 * triangles, "{m:?}");
    assert_eq!(m.textures, 0);
    assert!(m.lights >= 4 * triangles, "{m:?}");
}

/// A floor, and above it a unit quad over [0, 1] x [0, 1] at height 1 whose material is
/// `cover`; texture 0 (if the material reads it) has an opaque left texel and a transparent
/// right one, so bilinear alpha falls from 1 to 0 across u in [0.25, 0.75] and crosses 0.5 at
/// u = 0.5.
fn covered_floor(cover: caustica_renderer::material::Material, quad_u: (f32, f32)) -> Scene {
    use caustica_renderer::material::Material;
    use caustica_renderer::procedural::quad;
    use caustica_renderer::texture::{Texture, Wrap};
    let v = Vec3::new;
    let (u0, u1) = quad_u;
    let mut top = quad(
        "cover",
        [v(u0, 1., 1.), v(u1, 1., 1.), v(u1, 1., 0.), v(u0, 1., 0.)],
        1,
    );
    top.uvs = Some(vec![
        Vec2::new(u0, 1.),
        Vec2::new(u1, 1.),
        Vec2::new(u1, 0.),
        Vec2::new(u0, 0.),
    ]);
    let floor = quad(
        "floor",
        [
            v(-2., 0., 2.),
            v(3., 0., 2.),
            v(3., 0., -2.),
            v(-2., 0., -2.),
        ],
        0,
    );
    let texels = [255, 255, 255, 255, 255, 255, 255, 0];
    Scene::build(SceneDescription {
        meshes: vec![floor, top],
        materials: vec![Material::diffuse(Vec3::ONE), cover],
        textures: vec![Texture::from_rgba8(
            2,
            1,
            &texels,
            true,
            Wrap::ClampToEdge,
            Wrap::ClampToEdge,
        )],
        ..Default::default()
    })
    .unwrap()
}

/// Rays from above the cover towards the floor, in random directions.
fn downward_rays(n: usize) -> Vec<Ray> {
    let mut s = Sampler::new(41);
    (0..n)
        .map(|i| {
            s.start_pixel_sample(i as u64, 0);
            let o = Vec3::new(s.get_1d() * 2.0 - 0.5, 2.0, s.get_1d() * 2.0 - 0.5);
            let target = Vec3::new(s.get_1d() * 2.0 - 0.5, 0.0, s.get_1d() * 2.0 - 0.5);
            Ray::new(o, (target - o).normalize())
        })
        .collect()
}

#[test]
fn a_mask_cut_out_traces_like_the_geometry_with_the_hole_cut() {
    use caustica_renderer::material::{AlphaMode, Material, TextureRef};
    let masked = Material {
        base_color_texture: Some(TextureRef::new(0)),
        alpha_mode: AlphaMode::Mask(0.5),
        ..Material::diffuse(Vec3::ONE)
    };
    let cut_out = covered_floor(masked, (0.0, 1.0));
    // The hole cut: only the half u < 0.5 of the quad, opaque.
    let cut = covered_floor(Material::diffuse(Vec3::ONE), (0.0, 0.5));
    let (mut through, mut stopped) = (0, 0);
    for ray in downward_rays(20_000) {
        // Where the ray crosses the cover's plane; rays within rounding of the cut line are
        // left out (alpha is exactly 0.5 there).
        let at = ray.o + ray.d * ((1.0 - ray.o.y) / ray.d.y);
        if (at.x - 0.5).abs() < 1e-4 {
            continue;
        }
        let (a, b) = (cut_out.intersect(&ray), cut.intersect(&ray));
        let (ta, tb) = (a.map(|h| h.t), b.map(|h| h.t));
        assert!(
            ta.zip(tb).is_some_and(|(x, y)| (x - y).abs() <= 1e-5 * y),
            "{ray:?}: {ta:?} against {tb:?}"
        );
        let mut shadow = ray;
        shadow.t_max = tb.unwrap() * 0.999;
        assert_eq!(cut_out.occluded(&shadow), cut.occluded(&shadow), "{ray:?}");
        if tb.unwrap() < 1.5 / ray.d.y.abs() - 0.1 {
            stopped += 1;
        } else {
            through += 1;
        }
    }
    assert!(
        through > 1000 && stopped > 1000,
        "{through} through, {stopped} stopped"
    );
}

#[test]
fn a_blended_surface_stops_the_share_of_rays_its_alpha_says() {
    use caustica_renderer::material::{AlphaMode, Material};
    let alpha = 0.3;
    let blended = Material {
        alpha,
        alpha_mode: AlphaMode::Blend,
        ..Material::diffuse(Vec3::ONE)
    };
    let scene = covered_floor(blended, (0.0, 1.0));
    let (mut crossing, mut stopped) = (0u32, 0u32);
    for ray in downward_rays(40_000) {
        let at = ray.o + ray.d * ((1.0 - ray.o.y) / ray.d.y);
        if !(0.0..1.0).contains(&at.x) || !(0.0..1.0).contains(&at.z) {
            continue;
        }
        crossing += 1;
        let hit = scene.intersect(&ray).unwrap();
        let on_cover = hit.p.y > 0.5;
        stopped += on_cover as u32;
        // The same ray always finds the same answer, and a shadow ray agrees with it.
        assert_eq!(scene.intersect(&ray).unwrap().t, hit.t);
        let mut shadow = ray;
        shadow.t_max = (2.0 - 0.5) / -ray.d.y; // ends between the cover and the floor
        assert_eq!(scene.occluded(&shadow), on_cover, "{ray:?}");
    }
    // Binomial: the share stopped is alpha within four standard deviations.
    let n = crossing as f64;
    let share = stopped as f64 / n;
    let sd = (alpha as f64 * (1.0 - alpha as f64) / n).sqrt();
    assert!(crossing > 5000, "{crossing} rays crossed the cover");
    assert!(
        (share - alpha as f64).abs() < 4.0 * sd,
        "{share} stopped, alpha {alpha}"
    );
}
