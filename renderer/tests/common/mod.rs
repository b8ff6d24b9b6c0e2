//! What several test files share: scenes with closed-form radiance and the helpers that
//! compute it. (Not every test module uses all of it.)
#![allow(dead_code)]

use caustica_renderer::image::Image;
use caustica_renderer::integrators::ParamValues;
use caustica_renderer::scene::{Scene, SceneDescription};
use caustica_renderer::session::{RunState, Session, SessionConfig};
use std::sync::Arc;

/// Renders `passes` passes of `integrator` with `params` (over its defaults) at `size` x
/// `size` on `threads` worker threads (0: one per core), and returns the image (checked free
/// of NaN and Inf) and the count of samples dropped at their source.
/// An integrator's parameters, as the tables of runs name them.
pub type Params<'a> = &'a [(&'a str, f64)];

pub fn render(
    desc: SceneDescription,
    integrator: &str,
    params: &[(&str, f64)],
    passes: u64,
    size: u32,
    seed: u64,
    threads: usize,
) -> (Image, u64) {
    let scene = Arc::new(Scene::build(desc).unwrap());
    let session = Session::start(SessionConfig {
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<ParamValues>(),
        seed,
        threads,
        max_passes: Some(passes),
        ..SessionConfig::new(scene, integrator, size, size)
    })
    .unwrap();
    let frame = session.wait();
    assert_eq!(frame.state, RunState::Finished);
    assert_eq!(frame.image.count_non_finite(), 0);
    ((*frame.image).clone(), frame.dropped)
}

/// Per-block means of the image (blocks of `block` x `block` pixels) with their standard
/// errors, from the spread of the per-pass block means over `passes` independent passes.
pub fn block_means(
    integrator: &str,
    desc: &SceneDescription,
    passes: u64,
    size: u32,
    block: usize,
    seed: u64,
    params: &[(&str, f64)],
) -> Vec<(f64, f64)> {
    use caustica_renderer::camera::Camera;
    use caustica_renderer::integrators::{RenderContext, find};
    let scene = Arc::new(Scene::build(desc.clone()).unwrap());
    let camera = Camera::new(&scene.camera, size, size);
    let mut it = (find(integrator).unwrap().create)(
        RenderContext {
            scene,
            camera,
            seed,
        },
        &params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
    );
    block_means_of(&mut *it, passes, size, block)
}

/// `block_means` of an integrator already made (square images of `size` pixels).
pub fn block_means_of(
    it: &mut dyn caustica_renderer::integrators::Integrator,
    passes: u64,
    size: u32,
    block: usize,
) -> Vec<(f64, f64)> {
    use std::sync::atomic::AtomicBool;
    let cancel = AtomicBool::new(false);
    let blocks_per_row = size as usize / block;
    let nb = blocks_per_row * blocks_per_row;
    let (mut sum, mut sum_sq) = (vec![0.0f64; nb], vec![0.0f64; nb]);
    let mut previous = vec![0.0f64; nb];
    let lum = |p: glam::Vec3| caustica_renderer::geometry::luminance(p) as f64;
    for pass in 0..passes {
        it.render_counted_pass(pass, &cancel).unwrap();
        let img = it.image();
        let mut totals = vec![0.0f64; nb];
        for (i, p) in img.pixels.iter().enumerate() {
            let (x, y) = (i % size as usize / block, i / size as usize / block);
            totals[y * blocks_per_row + x] += lum(*p) * (pass + 1) as f64 / (block * block) as f64;
        }
        for b in 0..nb {
            let this_pass = totals[b] - previous[b];
            sum[b] += this_pass;
            sum_sq[b] += this_pass * this_pass;
        }
        previous.copy_from_slice(&totals);
    }
    let n = passes as f64;
    (0..nb)
        .map(|b| {
            let m = sum[b] / n;
            let var = (sum_sq[b] / n - m * m).max(0.0) * n / (n - 1.0);
            (m, (var / n).sqrt())
        })
        .collect()
}

/// The z-scores of the differences of two sets of block means (with standard errors), and
/// the ratio of their totals (b over a).
pub fn z_scores(a: &[(f64, f64)], b: &[(f64, f64)]) -> (Vec<f64>, f64) {
    let z = a
        .iter()
        .zip(b)
        .map(|((x, sx), (y, sy))| (x - y) / (sx * sx + sy * sy).sqrt().max(1e-12))
        .collect();
    let total = |m: &[(f64, f64)]| m.iter().map(|v| v.0).sum::<f64>();
    (z, total(b) / total(a))
}

/// The foundation's closed forms, each of exact radiance 1 everywhere: inside the point-lit
/// sphere L = 1, inside the emissive sphere Le / (1 - rho) = 1, each through the perspective
/// and the orthographic camera.
pub fn closed_form_scenes() -> Vec<(&'static str, SceneDescription)> {
    use caustica_renderer::procedural::{emissive_sphere, sphere_with_point_light};
    vec![
        ("point-lit sphere", sphere_with_point_light(64)),
        ("emissive sphere", emissive_sphere(0.2, 0.8, 64)),
        (
            "point-lit sphere, orthographic camera",
            with_orthographic_camera(sphere_with_point_light(64), 0.5),
        ),
        (
            "emissive sphere, orthographic camera",
            with_orthographic_camera(emissive_sphere(0.2, 0.8, 64), 0.5),
        ),
    ]
}

/// Two estimates agree block by block: their luminance within 1 %, the mean squared z-score
/// of the blocks' differences below 2 (about 1 without bias; its own spread at 64 blocks is
/// about 0.2) and no block beyond 4.5 standard errors (Sidak for 64 blocks at 0.1 % is 4.0,
/// allowing for the error of the estimated standard errors).
pub fn assert_blocks_agree(name: &str, z: &[f64], ratio: f64) {
    let chi = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
    let worst = z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    eprintln!("{name}: luminance ratio {ratio:.4}, mean z^2 {chi:.3}, worst |z| {worst:.2}");
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "{name}: luminance ratio {ratio}"
    );
    assert!(
        chi < 2.0 && worst < 4.5,
        "{name}: mean z^2 {chi}, worst |z| {worst}"
    );
}

/// The mean over pixels of the mean over channels.
pub fn mean(img: &Image) -> f64 {
    img.pixels
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64 / 3.0)
        .sum::<f64>()
        / img.pixels.len() as f64
}

/// `desc` seen by an orthographic camera in place of its own: same position and direction, a
/// film `2 ymag` high.
pub fn with_orthographic_camera(mut desc: SceneDescription, ymag: f32) -> SceneDescription {
    use caustica_renderer::camera::Projection;
    let camera = desc.camera.as_mut().expect("the scene has a camera");
    camera.projection = Projection::Orthographic { ymag };
    desc
}

/// Least-squares slope of log y against log x.
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

/// A diffuse floor (y = 0) lit by a point light of intensity I at height 1 both directly and
/// through a perfect mirror facing down at height 2: the mirror's image of the light, at
/// height H = 3, gives the floor an irradiance E(x) = I H / (H^2 + |x|^2)^(3/2) that reaches
/// the camera only through photons (light, mirror, floor), and whose curvature is known. With
/// max depth 2 no other photon path deposits (light, floor, mirror would need a third hit).
pub struct MirroredLight {
    pub desc: SceneDescription,
    pub intensity: f64,
    pub albedo: f64,
}

impl MirroredLight {
    pub const IMAGE_HEIGHT: f64 = 3.0;

    pub fn new() -> Self {
        use caustica_renderer::material::Material;
        use caustica_renderer::procedural::{camera_looking, quad};
        use caustica_renderer::scene::PunctualLightDesc;
        use glam::Vec3;
        let v = Vec3::new;
        let s = 20.0;
        let (intensity, albedo) = (10.0, 0.5);
        let desc = SceneDescription {
            meshes: vec![
                quad(
                    "floor",
                    [v(-s, 0., s), v(s, 0., s), v(s, 0., -s), v(-s, 0., -s)],
                    0,
                ),
                quad(
                    "mirror",
                    [v(-s, 2., -s), v(s, 2., -s), v(s, 2., s), v(-s, 2., s)],
                    1,
                ),
            ],
            materials: vec![
                Material::diffuse(Vec3::splat(albedo as f32)),
                Material {
                    roughness: 0.0,
                    ..Material::default()
                },
            ],
            lights: vec![PunctualLightDesc::Point {
                position: v(0., 1., 0.),
                intensity: Vec3::splat(intensity as f32),
            }],
            // Sees the floor within 0.05 of the light's foot.
            camera: Some(camera_looking(v(0., 1.5, 0.), v(0., 0., 0.), 3.8)),
            ..Default::default()
        };
        MirroredLight {
            desc,
            intensity,
            albedo,
        }
    }

    /// Irradiance from the light's mirror image at distance `d` from its foot.
    pub fn mirrored_irradiance(&self, d: f64) -> f64 {
        let h = Self::IMAGE_HEIGHT;
        let q = h * h + d * d;
        self.intensity * h / (q * q.sqrt())
    }

    /// The exact radiance the mirror contributes, averaged over pixels seeing `footprints`.
    pub fn mirrored_radiance(&self, footprints: &[glam::DVec2]) -> f64 {
        self.albedo / std::f64::consts::PI
            * footprints
                .iter()
                .map(|x| self.mirrored_irradiance(x.length()))
                .sum::<f64>()
            / footprints.len() as f64
    }

    /// Direct irradiance at distance `d` from the light's foot.
    pub fn direct_irradiance(&self, d: f64) -> f64 {
        self.intensity / (1.0 + d * d).powf(1.5)
    }

    /// The exact direct radiance, averaged over pixels seeing `footprints`.
    pub fn direct_radiance(&self, footprints: &[glam::DVec2]) -> f64 {
        self.albedo / std::f64::consts::PI
            * footprints
                .iter()
                .map(|x| self.direct_irradiance(x.length()))
                .sum::<f64>()
            / footprints.len() as f64
    }

    /// The mean of the mirrored irradiance (and the direct one `with_direct`) over the disc of
    /// radius `r` about `x`: the expected value of a photon density estimate with a uniform
    /// kernel of that radius. Midpoint rule in the radius, the trapezoid rule (spectrally
    /// accurate for periodic integrands) in angle.
    pub fn disc_mean(&self, x: glam::DVec2, r: f64, with_direct: bool) -> f64 {
        let (nr, nphi) = (16, 16);
        let mut sum = 0.0;
        for i in 0..nr {
            let rho = r * (i as f64 + 0.5) / nr as f64;
            for j in 0..nphi {
                let phi = std::f64::consts::TAU * j as f64 / nphi as f64;
                let p = x + rho * glam::DVec2::new(phi.cos(), phi.sin());
                let d = p.length();
                let direct = if with_direct {
                    self.direct_irradiance(d)
                } else {
                    0.0
                };
                sum += (self.mirrored_irradiance(d) + direct) * rho;
            }
        }
        sum * (r / nr as f64) * (std::f64::consts::TAU / nphi as f64)
            / (std::f64::consts::PI * r * r)
    }

    /// Where each pixel's centre sees the floor, as an offset from the light's foot.
    pub fn pixel_footprints(&self, camera: &caustica_renderer::camera::Camera) -> Vec<glam::DVec2> {
        let (w, h) = (camera.width, camera.height);
        (0..w * h)
            .map(|i| {
                let film = glam::Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                let ray = camera.generate_ray(film);
                let t = -ray.o.y / ray.d.y;
                let p = ray.o + t * ray.d;
                glam::DVec2::new(p.x as f64, p.z as f64)
            })
            .collect()
    }
}

impl MirroredLight {
    /// The exact image: each pixel's radiance (direct and through the mirror) averaged over
    /// `n` x `n` points of the pixel (the radiance is smooth, so 4 x 4 is exact to 1e-5).
    pub fn reference_image(&self, camera: &caustica_renderer::camera::Camera, n: u32) -> Image {
        let (w, h) = (camera.width, camera.height);
        let pixels = (0..w * h)
            .map(|i| {
                let mut sum = 0.0;
                for sy in 0..n {
                    for sx in 0..n {
                        let film = glam::Vec2::new(
                            (i % w) as f32 + (sx as f32 + 0.5) / n as f32,
                            (i / w) as f32 + (sy as f32 + 0.5) / n as f32,
                        );
                        let ray = camera.generate_ray(film);
                        let t = -ray.o.y / ray.d.y;
                        let p = ray.o + t * ray.d;
                        let d = glam::DVec2::new(p.x as f64, p.z as f64).length();
                        sum += self.albedo / std::f64::consts::PI
                            * (self.direct_irradiance(d) + self.mirrored_irradiance(d));
                    }
                }
                glam::Vec3::splat((sum / (n * n) as f64) as f32)
            })
            .collect();
        Image {
            width: w as usize,
            height: h as usize,
            pixels,
        }
    }
}

/// The mean over the image after each of `passes` passes of `integrator`, and the standard
/// error of their average, from the spread of the per-pass means.
pub fn mean_and_standard_error(
    integrator: &mut dyn caustica_renderer::integrators::Integrator,
    passes: u64,
) -> (f64, f64) {
    use std::sync::atomic::AtomicBool;
    let cancel = AtomicBool::new(false);
    let mut per_pass = Vec::new();
    let mut previous_total = 0.0;
    for pass in 0..passes {
        integrator.render_counted_pass(pass, &cancel).unwrap();
        let total = mean(&integrator.image()) * (pass + 1) as f64;
        per_pass.push(total - previous_total);
        previous_total = total;
    }
    let n = passes as f64;
    let m = per_pass.iter().sum::<f64>() / n;
    let var = per_pass.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Each BDPT strategy (s, t) alone, for every path length up to `max_depth` bounces, gives
/// the image mean of next-event estimation (s = 1) within four combined standard errors.
pub fn assert_strategies_agree(desc: SceneDescription, max_depth: usize) {
    use caustica_renderer::camera::Camera;
    use caustica_renderer::integrators::RenderContext;
    use caustica_renderer::integrators::bdpt::{Bdpt, BdptSettings};
    let scene = Arc::new(Scene::build(desc).unwrap());
    let camera = Camera::new(&scene.camera, 16, 16);
    for depth in 1..=max_depth {
        let mut results = Vec::new();
        for s in 0..=depth + 2 {
            let t = depth + 2 - s;
            if t == 0 || (s, t) == (1, 1) {
                continue;
            }
            let mut bdpt = Bdpt::new(
                RenderContext {
                    scene: scene.clone(),
                    camera,
                    seed: 7,
                },
                BdptSettings {
                    max_depth: depth as u32,
                    only_strategy: Some((s, t)),
                },
            );
            let (m, se) = mean_and_standard_error(&mut bdpt, 1024);
            eprintln!("depth {depth}, (s, t) = ({s}, {t}): {m:.5} +- {se:.5}");
            results.push(((s, t), m, se));
        }
        let &(_, m_ref, se_ref) = results.iter().find(|r| r.0.0 == 1).unwrap();
        for &((s, t), m, se) in &results {
            let tolerance = 4.0 * (se * se + se_ref * se_ref).sqrt();
            assert!(
                (m - m_ref).abs() < tolerance,
                "depth {depth}: strategy ({s}, {t}) gives {m}, next-event estimation {m_ref} (tolerance {tolerance})"
            );
        }
    }
}

/// The expected density estimate and its variance on the mirrored light (the mirrored part,
/// as photons carry it, or with the direct part too, as vcm's merges alone do), accumulated
/// pass by pass from the radii
/// each pixel gathered with. All three variants' indirect estimates are the mean over passes
/// of one-pass estimates tau_k / (pi R_k^2 P): for PPPM by construction (Knaus & Zwicker 2011,
/// eq. 21), for PPM and SPPM because eq. 7's rescaling of tau by R_{k+1}^2 / R_k^2 telescopes
/// (Hachisuka et al. 2008). R_k is fixed before pass k's photons are traced, so given it the
/// pass's expected estimate is rho / pi times the disc mean of E, and its variance, the
/// estimate being c M with M binomial (P photons, probability p = the disc's share of the
/// emitted flux), is c^2 P p (1 - p). The pixels' estimates are correlated, so the standard
/// deviation of their mean is bounded by the mean of theirs; passes are independent given
/// the radii, so their variances add.
#[derive(Default)]
pub struct ExpectedEstimate {
    passes: u64,
    mean_sum: f64,
    variance_sum: f64,
}

impl ExpectedEstimate {
    pub fn add_pass(
        &mut self,
        setup: &MirroredLight,
        footprints: &[glam::DVec2],
        radii: &[f64],
        photons: u64,
        with_direct: bool,
    ) {
        use std::f64::consts::PI;
        let f = setup.albedo / PI;
        let pixels = footprints.len() as f64;
        let mut sd = 0.0;
        for (x, r) in footprints.iter().zip(radii) {
            let a = setup.disc_mean(*x, *r, with_direct);
            self.mean_sum += f * a / pixels;
            let c = f * 4.0 * PI * setup.intensity / (PI * r * r * photons as f64);
            let p = a * PI * r * r / (4.0 * PI * setup.intensity);
            sd += (c * c * photons as f64 * p * (1.0 - p)).sqrt() / pixels;
        }
        self.variance_sum += sd * sd;
        self.passes += 1;
    }

    /// Expected kernel bias of the mean over pixels, and its standard deviation.
    pub fn bias_and_sigma(
        &self,
        setup: &MirroredLight,
        footprints: &[glam::DVec2],
        with_direct: bool,
    ) -> (f64, f64) {
        let n = self.passes as f64;
        let direct = if with_direct {
            setup.direct_radiance(footprints)
        } else {
            0.0
        };
        (
            self.mean_sum / n - setup.mirrored_radiance(footprints) - direct,
            self.variance_sum.sqrt() / n,
        )
    }
}
