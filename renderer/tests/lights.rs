//! Closed-form radiance of a plane lit by each kind of light, through the path tracer and the
//! bidirectional path tracer: this checks light sampling and emission, pdf conversions,
//! one-sided emission, shadow rays and the MIS weights between strategies. A very narrow camera looks at one point p0 of the
//! plane, so every pixel estimates the same radiance and their spread gives the tolerance.

use caustica_renderer::light::environment::{EnvironmentChoice, EnvironmentSettings};
use caustica_renderer::material::{Material, TextureRef, TransportMode};
use caustica_renderer::procedural::{camera_looking, quad};
use caustica_renderer::sampling::sampler::Sampler;
use caustica_renderer::scene::{PunctualLightDesc, Scene, SceneDescription};
use caustica_renderer::texture::{Texture, Wrap};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

use crate::common;
use common::render;

const EYE: Vec3 = Vec3::new(0.0, 1.5, 3.0);

fn plane_scene(material: Material) -> SceneDescription {
    let s = 50.0;
    SceneDescription {
        meshes: vec![quad(
            "plane",
            [
                Vec3::new(-s, 0., s),
                Vec3::new(s, 0., s),
                Vec3::new(s, 0., -s),
                Vec3::new(-s, 0., -s),
            ],
            0,
        )],
        materials: vec![material],
        camera: Some(camera_looking(EYE, Vec3::ZERO, 0.05)),
        // Only the lights each test adds: the plane is large, so a small light over it would
        // not count as the scene's own lighting by the default rule.
        environment: EnvironmentSettings {
            choice: EnvironmentChoice::None,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The plane lit by the uniform environment of radiance 1 alone.
fn uniform_plane_scene(material: Material) -> SceneDescription {
    let mut desc = plane_scene(material);
    desc.environment.choice = EnvironmentChoice::Uniform;
    desc
}

/// Mean radiance over the image (luminance channel x) and its standard error, for each
/// integrator that must reproduce the closed forms.
fn render_mean(desc: SceneDescription, passes: u64) -> Vec<(&'static str, (f64, f64))> {
    ["pt", "bdpt", "vcm"]
        .into_iter()
        .map(|integrator| {
            let (image, dropped) = render(desc.clone(), integrator, &[], passes, 32, 3, 0);
            assert_eq!(dropped, 0);
            let v: Vec<f64> = image.pixels.iter().map(|p| p.x as f64).collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (integrator, (mean, (var / n).sqrt()))
        })
        .collect()
}

fn assert_close(name: &str, results: Vec<(&str, (f64, f64))>, exact: f64) {
    for (integrator, (mean, se)) in results {
        assert!(
            (mean - exact).abs() <= 4.0 * se + 2e-4 * exact,
            "{name}, {integrator}: {mean} ± {se}, exact {exact}"
        );
        assert!(
            se < 0.05 * exact,
            "{name}, {integrator}: too noisy to test ({se})"
        );
    }
}

#[test]
fn directional_light_on_a_diffuse_plane() {
    // L = rho / pi * E * cos(theta) for irradiance E at normal incidence.
    let (rho, e, theta) = (0.6f32, 2.0f32, 60f32.to_radians());
    let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
    desc.lights.push(PunctualLightDesc::Directional {
        direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
        irradiance: Vec3::splat(e),
    });
    let exact = rho as f64 / PI * e as f64 * (theta as f64).cos();
    assert_close("directional", render_mean(desc, 16), exact);
}

#[test]
fn spot_light_inside_and_outside_its_cone() {
    let (rho, i, h) = (0.5f32, 4.0f32, 2.0f32);
    let spot = |direction: Vec3| PunctualLightDesc::Spot {
        position: Vec3::new(0.0, h, 0.0),
        direction,
        intensity: Vec3::splat(i),
        inner_cone: 0.3,
        outer_cone: 0.5,
    };
    let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
    desc.lights.push(spot(Vec3::NEG_Y));
    assert_close(
        "spot, axis",
        render_mean(desc, 16),
        rho as f64 / PI * i as f64 / (h * h) as f64,
    );
    // Tilted by 0.4 rad: p0 sits between the cones, where the falloff is ((cos 0.4 - cos 0.5) /
    // (cos 0.3 - cos 0.5))^2 of full intensity.
    let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
    desc.lights
        .push(spot(Vec3::new(0.4f32.sin(), -0.4f32.cos(), 0.0)));
    let t = ((0.4f64.cos() - 0.5f64.cos()) / (0.3f64.cos() - 0.5f64.cos())).powi(2);
    assert_close(
        "spot, penumbra",
        render_mean(desc, 16),
        rho as f64 / PI * i as f64 * t / (h * h) as f64,
    );
}

/// Irradiance at a point below the centre of an emitting square of half-side `a` at height `h`,
/// from the form factor of a rectangle to a parallel differential area (four quadrants).
fn square_irradiance(le: f64, a: f64, h: f64) -> f64 {
    let x = a / h;
    let s = (1.0 + x * x).sqrt();
    let f_quadrant = 1.0 / (2.0 * PI) * 2.0 * (x / s * (x / s).atan());
    PI * le * 4.0 * f_quadrant
}

#[test]
fn square_area_light_on_a_diffuse_plane() {
    let (rho, le, a, h) = (0.7f32, 3.0f32, 0.5f32, 0.8f32);
    let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
    // Black emitter, facing down (counter-clockwise seen from below).
    let light = Material {
        emission: Vec3::splat(le),
        ..Material::diffuse(Vec3::ZERO)
    };
    desc.materials.push(light);
    desc.meshes.push(quad(
        "light",
        [
            Vec3::new(-a, h, -a),
            Vec3::new(a, h, -a),
            Vec3::new(a, h, a),
            Vec3::new(-a, h, a),
        ],
        1,
    ));
    let exact = rho as f64 / PI * square_irradiance(le as f64, a as f64, h as f64);
    assert_close("area light", render_mean(desc.clone(), 64), exact);
    // Turned upside down, the one-sided light sends nothing to the plane.
    let m = desc.meshes.last_mut().unwrap();
    m.indices = vec![0, 2, 1, 0, 3, 2];
    for (integrator, (mean, _)) in render_mean(desc, 4) {
        assert_eq!(
            mean, 0.0,
            "{integrator}: a one-sided emitter lit the side it faces away from"
        );
    }
}

/// An 8 x 8 sRGB texture of texels `left` where u < 0.5 and `right` elsewhere.
fn half_texture(left: [u8; 4], right: [u8; 4]) -> Texture {
    let texels: Vec<u8> = (0..64)
        .flat_map(|i| if i % 8 < 4 { left } else { right })
        .collect();
    Texture::from_rgba8(8, 8, &texels, true, Wrap::ClampToEdge, Wrap::ClampToEdge)
}

#[test]
fn textured_area_light_whose_black_triangles_are_no_lights() {
    // The square light of the test above, its emission from the white half of a texture that
    // is black on the other half, beside a second quad of the same material that maps to
    // the black half: that quad's triangles emit nothing, so they are no lights, and the
    // plane's radiance is still the square's closed form.
    let (rho, le, a, h) = (0.7f32, 3.0f32, 0.5f32, 0.8f32);
    let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
    desc.textures = vec![half_texture([0, 0, 0, 255], [255; 4])];
    desc.materials.push(Material {
        emission: Vec3::splat(le),
        emissive_texture: Some(TextureRef::new(0)),
        ..Material::diffuse(Vec3::ZERO)
    });
    let corners = |x0: f32| {
        [
            Vec3::new(x0 - a, h, -a),
            Vec3::new(x0 + a, h, -a),
            Vec3::new(x0 + a, h, a),
            Vec3::new(x0 - a, h, a),
        ]
    };
    // Bilinear lookups read only white texels for u >= 0.5625 and only black ones for
    // u <= 0.3125.
    for (x0, (u0, u1)) in [(0.0, (0.7, 0.9)), (2.5, (0.05, 0.3))] {
        let mut m = quad("light", corners(x0), 1);
        m.uvs = Some(vec![
            Vec2::new(u0, 0.1),
            Vec2::new(u1, 0.1),
            Vec2::new(u1, 0.9),
            Vec2::new(u0, 0.9),
        ]);
        desc.meshes.push(m);
    }
    let scene = Scene::build(desc.clone()).unwrap();
    assert_eq!(
        scene.lights.len(),
        2,
        "only the white square's two triangles are lights"
    );
    let exact = rho as f64 / PI * square_irradiance(le as f64, a as f64, h as f64);
    assert_close("textured area light", render_mean(desc, 64), exact);
}

#[test]
fn an_absorbing_glass_slab_in_front_of_an_area_light() {
    // Seen head-on through a slab of glass (ior 1.5) of thickness 1 whose inside keeps tau of
    // the light crossing it (KHR_materials_volume), a uniform emitter of radiance 1 gives
    // the slab's transmittance with its internal reflections summed:
    // (1 - R)^2 tau / (1 - R^2 tau^2), R = ((1.5 - 1) / (1.5 + 1))^2 at normal incidence.
    use caustica_renderer::procedural::cuboid;
    let tau = 0.5f64;
    let glass = Material {
        absorption: Vec3::splat(-(tau.ln() as f32)),
        ..Material::glass(1.5)
    };
    let emitter = Material {
        emission: Vec3::ONE,
        ..Material::diffuse(Vec3::ZERO)
    };
    let s = 10.0;
    let desc = SceneDescription {
        meshes: vec![
            cuboid(
                "slab",
                glam::Affine3A::from_scale(Vec3::new(4.0, 4.0, 1.0)),
                0,
            ),
            quad(
                "light",
                [
                    Vec3::new(-s, -s, -2.),
                    Vec3::new(s, -s, -2.),
                    Vec3::new(s, s, -2.),
                    Vec3::new(-s, s, -2.),
                ],
                1,
            ),
        ],
        materials: vec![glass, emitter],
        camera: Some(camera_looking(Vec3::new(0., 0., 5.), Vec3::ZERO, 0.05)),
        ..Default::default()
    };
    let r = 0.04f64;
    let exact = (1.0 - r).powi(2) * tau / (1.0 - r * r * tau * tau);
    assert_close("absorbing slab", render_mean(desc, 64), exact);
}

#[test]
fn uniform_environment_on_diffuse_and_glossy_planes() {
    // No emitter: the environment of radiance 1 lights the upper hemisphere. A diffuse plane
    // reflects rho; a glossy one its directional albedo, computed here independently by
    // sampling its BSDF alone.
    assert_close(
        "environment, diffuse",
        render_mean(uniform_plane_scene(Material::diffuse(Vec3::splat(0.4))), 32),
        0.4,
    );
    let glossy = Material {
        base_color: Vec3::splat(0.8),
        metallic: 0.5,
        roughness: 0.3,
        ..Default::default()
    };
    let bsdf = glossy.bsdf(&[], &[Vec2::ZERO; 2], Vec3::ONE);
    // Local frame of the plane: normal +y maps to +z; only the angle to the normal matters.
    let to_eye = EYE.normalize();
    let wo = Vec3::new((1.0 - to_eye.y * to_eye.y).sqrt(), 0.0, to_eye.y);
    let mut s = Sampler::new(5);
    let n = 2_000_000u64;
    let mut sum = 0.0f64;
    for k in 0..n {
        s.start_pixel_sample(k, 0);
        let (uc, u) = (s.get_1d(), s.get_2d());
        if let Some(bs) = bsdf.sample_f(wo, uc, u, TransportMode::Radiance) {
            sum += (bs.f.x * bs.wi.z.abs() / bs.pdf) as f64;
        }
    }
    assert_close(
        "environment, glossy",
        render_mean(uniform_plane_scene(glossy), 64),
        sum / n as f64,
    );
}

/// KHR_materials_clearcoat, _specular and _sheen under the environment of radiance 1: a
/// plane of clearcoat c over a base that reflects nothing (black, specular 0) reflects the
/// coat lobe's albedo c E(mu_o) at f0 = 0.04; a black plastic whose specular layer has
/// specularFactor s and specularColorFactor k reflects that layer's albedo E(mu_o) at
/// f0 = min(0.04 k, 1) s, f90 = s (the red channel here); a sheen of colour C over a base that
/// reflects nothing reflects C E_sheen(mu_o). The specular E comes from the layering tables,
/// which a unit test checks against their quadrature, the sheen's from its table, checked
/// against Monte Carlo integration.
#[test]
fn uniform_environment_on_layered_planes() {
    use caustica_renderer::material::layering::specular_albedo;
    use caustica_renderer::material::sheen;
    let mu_o = EYE.normalize().y;
    let coat = Material {
        base_color: Vec3::ZERO,
        metallic: 0.0,
        roughness: 0.5,
        specular: 0.0,
        clearcoat: 0.8,
        clearcoat_roughness: 0.3,
        ..Default::default()
    };
    let exact = 0.8 * specular_albedo(mu_o, 0.09, Vec3::splat(0.04), 1.0).x;
    assert_close(
        "environment, clearcoat",
        render_mean(uniform_plane_scene(coat), 64),
        exact as f64,
    );
    let tinted = Material {
        base_color: Vec3::ZERO,
        metallic: 0.0,
        roughness: 0.4,
        specular: 0.7,
        specular_color: Vec3::new(10.0, 2.0, 1.0),
        ..Default::default()
    };
    let f0 = (0.04 * tinted.specular_color).min(Vec3::ONE) * 0.7;
    let exact = specular_albedo(mu_o, 0.16, f0, 0.7).x;
    assert_close(
        "environment, tinted specular",
        render_mean(uniform_plane_scene(tinted.clone()), 64),
        exact as f64,
    );
    let velvet = Material {
        specular: 0.0,
        specular_color: Vec3::ONE,
        sheen_color: Vec3::new(0.9, 0.5, 0.2),
        sheen_roughness: 0.5,
        ..tinted
    };
    let exact = 0.9 * sheen::albedo(mu_o, 0.5);
    assert_close(
        "environment, sheen",
        render_mean(uniform_plane_scene(velvet), 64),
        exact as f64,
    );
}

/// An emitter cut out by alphaMode MASK emits only where it is: the square light above, its
/// base colour texture's alpha 0 on the half x < 0 and 1 on the other (bilinear alpha crosses
/// the cutoff 0.5 at x = 0), lights the point below its centre with half the square's
/// irradiance, by symmetry; so does the same square whose emissive texture is black on that
/// half, and the whole square with alphaMode BLEND at alpha 0.5 (there half the time). Every
/// strategy must agree: hitting the light (only where it is), sampling a point on it (none in
/// the hole; weighted by alpha when blended) and leaving it (light paths start only where it
/// is, or carry alpha). BDPT once lost
/// its s = 1 strategy whenever the light subpath's origin fell where nothing is emitted,
/// which this caught (0.22 for 0.35).
#[test]
fn a_half_masked_or_half_black_area_light_lights_with_half_the_square() {
    use caustica_renderer::material::AlphaMode;
    for (name, alpha_cut, blend) in [
        ("alpha-masked", true, false),
        ("half-black", false, false),
        ("blended at alpha 0.5", false, true),
    ] {
        let mut desc = half_square_light(alpha_cut);
        if blend {
            let m = desc.materials.last_mut().unwrap();
            (m.emissive_texture, m.alpha, m.alpha_mode) = (None, 0.5, AlphaMode::Blend);
        }
        let (rho, le, a, h) = (0.7f64, 3.0f64, 0.5f64, 0.8f64);
        let exact = rho / PI * square_irradiance(le, a, h) / 2.0;
        assert_close(name, render_mean(desc, 64), exact);
    }

    /// The square light above, cut (alpha) or dark (emission) on its half x < 0.
    fn half_square_light(alpha_cut: bool) -> SceneDescription {
        let (rho, le, a, h) = (0.7f32, 3.0f32, 0.5f32, 0.8f32);
        let mut desc = plane_scene(Material::diffuse(Vec3::splat(rho)));
        desc.textures = vec![if alpha_cut {
            half_texture([0; 4], [0, 0, 0, 255])
        } else {
            half_texture([0, 0, 0, 255], [255; 4])
        }];
        desc.materials.push(if alpha_cut {
            Material {
                emission: Vec3::splat(le),
                base_color_texture: Some(TextureRef::new(0)),
                alpha_mode: AlphaMode::Mask(0.5),
                ..Material::diffuse(Vec3::ZERO)
            }
        } else {
            Material {
                emission: Vec3::splat(le),
                emissive_texture: Some(TextureRef::new(0)),
                ..Material::diffuse(Vec3::ZERO)
            }
        });
        let mut light = quad(
            "light",
            [
                Vec3::new(-a, h, -a),
                Vec3::new(a, h, -a),
                Vec3::new(a, h, a),
                Vec3::new(-a, h, a),
            ],
            1,
        );
        light.uvs = Some(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]);
        desc.meshes.push(light);
        desc
    }
}
