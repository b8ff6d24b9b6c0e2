//! Perspective pinhole camera (glTF spec 3.10: looks down its local -Z with +Y up).
//! Film coordinates run from the top-left corner in pixels, x right and y down.
//!
//! For light tracing the camera is also a sensor with importance W_e (pbrt-v3 section 16.1.1):
//! W_e(w) = 1 / (A cos^4 theta) inside the field of view, A the image's area on the plane at
//! distance 1, so that the importance of one pixel integrates (times cos) to 1 / pixel count.
//! The pinhole is a delta in position (pdf 1 by convention); directions have the solid-angle
//! pdf 1 / (A cos^3 theta) of `generate_ray` with a uniform film position.

use crate::geometry::{Bounds3, Ray};
use glam::{Affine3A, Vec2, Vec3};

/// The scene's camera, independent of the output resolution.
#[derive(Clone, Copy, Debug)]
pub struct CameraDesc {
    /// Rigid transform (rotation and translation only).
    pub camera_to_world: Affine3A,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Width over height, when the scene gives one; else the output's.
    pub aspect: Option<f32>,
}

impl CameraDesc {
    /// The default camera for a scene without one (DESIGN.md section 2): looking down -Z at
    /// the centre of the bounds from far enough that the bounding sphere fits a 45 degree view.
    pub fn framing(bounds: &Bounds3) -> CameraDesc {
        let (center, radius) = bounds.bounding_sphere();
        let yfov = 45f32.to_radians();
        let radius = if radius > 0.0 && radius.is_finite() {
            radius
        } else {
            1.0
        };
        let distance = radius / (yfov / 2.0).sin();
        CameraDesc {
            camera_to_world: Affine3A::from_translation(center + Vec3::Z * distance),
            yfov,
            aspect: None,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct PerspectiveCamera {
    pub camera_to_world: Affine3A,
    pub width: u32,
    pub height: u32,
    world_to_camera: Affine3A,
    tan_half_y: f32,
    aspect: f32,
}

/// A connection from a point to the camera (pbrt-v3's `Camera::Sample_Wi`).
#[derive(Clone, Copy, Debug)]
pub struct CameraWiSample {
    /// Unit direction from the reference point towards the pinhole.
    pub wi: Vec3,
    pub importance: f32,
    /// Solid-angle density at the reference point: distance^2 / cos at the camera.
    pub pdf: f32,
    pub p_camera: Vec3,
    pub dist: f32,
    /// Where the connection lands on the film (pixels).
    pub raster: Vec2,
}

impl PerspectiveCamera {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let aspect = desc
            .aspect
            .filter(|a| a.is_finite() && *a > 0.0)
            .unwrap_or(width as f32 / height.max(1) as f32);
        PerspectiveCamera {
            camera_to_world: desc.camera_to_world,
            world_to_camera: desc.camera_to_world.inverse(),
            width,
            height,
            tan_half_y: (desc.yfov.clamp(1e-4, 3.1) / 2.0).tan(),
            aspect,
        }
    }

    /// Width over height of the film.
    pub fn aspect(&self) -> f32 {
        self.aspect
    }

    pub fn position(&self) -> Vec3 {
        self.camera_to_world.translation.into()
    }

    /// Primary ray through continuous film position `film` (pixels).
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let ndc_x = 2.0 * film.x / self.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * film.y / self.height as f32;
        let d_cam = Vec3::new(
            ndc_x * self.tan_half_y * self.aspect,
            ndc_y * self.tan_half_y,
            -1.0,
        )
        .normalize();
        Ray::new(
            self.position(),
            self.camera_to_world.transform_vector3(d_cam).normalize(),
        )
    }
}

impl PerspectiveCamera {
    pub fn forward(&self) -> Vec3 {
        self.camera_to_world
            .transform_vector3(Vec3::NEG_Z)
            .normalize()
    }

    /// Area of the image on the plane at distance 1 in front of the pinhole.
    fn film_area(&self) -> f32 {
        4.0 * self.tan_half_y * self.tan_half_y * self.aspect
    }

    /// Film position (pixels) of a ray leaving the pinhole in direction `w`; None outside.
    pub fn raster(&self, w: Vec3) -> Option<Vec2> {
        let local = self.world_to_camera.transform_vector3(w);
        if !(local.z < 0.0) {
            return None;
        }
        let ndc_x = local.x / -local.z / (self.tan_half_y * self.aspect);
        let ndc_y = local.y / -local.z / self.tan_half_y;
        let film = Vec2::new(
            (ndc_x + 1.0) * 0.5 * self.width as f32,
            (1.0 - ndc_y) * 0.5 * self.height as f32,
        );
        (film.x >= 0.0
            && film.y >= 0.0
            && film.x < self.width as f32
            && film.y < self.height as f32)
            .then_some(film)
    }

    /// Importance W_e of the ray leaving the pinhole in direction `w` (unit), and where it
    /// lands on the film.
    pub fn importance(&self, w: Vec3) -> Option<(f32, Vec2)> {
        let raster = self.raster(w)?;
        let cos = w.dot(self.forward());
        let we = 1.0 / (self.film_area() * cos * cos * cos * cos);
        we.is_finite().then_some((we, raster))
    }

    /// Solid-angle density with which `generate_ray` picks direction `w` (zero outside the
    /// film); the position's density is a delta, 1 by convention.
    pub fn pdf_we_dir(&self, w: Vec3) -> f32 {
        if self.raster(w).is_none() {
            return 0.0;
        }
        let cos = w.dot(self.forward());
        1.0 / (self.film_area() * cos * cos * cos)
    }

    /// Connects `p_ref` to the pinhole.
    pub fn sample_wi(&self, p_ref: Vec3) -> Option<CameraWiSample> {
        let d = self.position() - p_ref;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let wi = d / dist;
        let (importance, raster) = self.importance(-wi)?;
        let cos = (-wi).dot(self.forward());
        Some(CameraWiSample {
            wi,
            importance,
            pdf: dist * dist / cos,
            p_camera: self.position(),
            dist,
            raster,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_down_minus_z_and_corners_span_the_fov() {
        let desc = CameraDesc {
            camera_to_world: Affine3A::IDENTITY,
            yfov: 90f32.to_radians(),
            aspect: None,
        };
        let cam = PerspectiveCamera::new(&desc, 200, 100);
        let r = cam.generate_ray(Vec2::new(100.0, 50.0));
        assert!((r.d - Vec3::NEG_Z).length() < 1e-6);
        let top = cam.generate_ray(Vec2::new(100.0, 0.0));
        assert!(
            (top.d.y - top.d.z.abs()).abs() < 1e-5,
            "45 degrees up at the top edge"
        );
        let right = cam.generate_ray(Vec2::new(200.0, 50.0));
        assert!(
            (right.d.x / right.d.z.abs() - 2.0).abs() < 1e-5,
            "aspect 2 widens x"
        );
    }

    fn tilted_camera() -> PerspectiveCamera {
        let desc = CameraDesc {
            camera_to_world: Affine3A::from_rotation_translation(
                glam::Quat::from_euler(glam::EulerRot::YXZ, 0.4, -0.3, 0.1),
                Vec3::new(1.0, 2.0, 3.0),
            ),
            yfov: 50f32.to_radians(),
            aspect: None,
        };
        PerspectiveCamera::new(&desc, 64, 48)
    }

    #[test]
    fn raster_inverts_generate_ray_and_sample_wi_points_back() {
        let cam = tilted_camera();
        for film in [
            Vec2::new(0.5, 0.5),
            Vec2::new(63.2, 10.0),
            Vec2::new(31.0, 47.5),
        ] {
            let ray = cam.generate_ray(film);
            let back = cam.raster(ray.d).unwrap();
            assert!((back - film).length() < 1e-3, "{film} -> {back}");
            let p = ray.o + ray.d * 3.7;
            let s = cam.sample_wi(p).unwrap();
            assert!((s.raster - film).length() < 1e-3);
            assert!((s.dist - 3.7).abs() < 1e-4 && (s.wi + ray.d).length() < 1e-5);
        }
        assert!(cam.raster(-cam.forward()).is_none());
    }

    /// The importance is normalised: the integral of W_e cos over all directions is 1 (one
    /// unit of importance over the whole film), and over a pixel 1 / pixel count. Estimated
    /// with 10^6 directions uniform on the sphere; the standard error is about 0.3 %.
    #[test]
    fn importance_integrates_to_one_over_the_film_and_its_pdf_matches_generate_ray() {
        use crate::sampling::warp::{sample_uniform_sphere, uniform_sphere_pdf};
        let cam = tilted_camera();
        let mut sampler = crate::sampling::sampler::Sampler::new(3);
        let n = 1_000_000;
        let (mut total, mut pixel) = (0.0f64, 0.0f64);
        for i in 0..n {
            sampler.start_pixel_sample(i, 0);
            let w = sample_uniform_sphere(sampler.get_2d());
            if let Some((we, raster)) = cam.importance(w) {
                let v = (we * w.dot(cam.forward()) / uniform_sphere_pdf()) as f64;
                total += v;
                if raster.x < 8.0 && raster.y < 6.0 {
                    pixel += v;
                }
            }
        }
        let (total, block) = (total / n as f64, pixel / n as f64);
        assert!((total - 1.0).abs() < 0.012, "integral {total}");
        // An 8 x 6 block of the 64 x 48 film holds 1/64 of the importance.
        assert!((block * 64.0 - 1.0).abs() < 0.1, "block {block}");
        // pdf_we_dir is generate_ray's density: 1 / (A cos^3) against a uniform film sample.
        let w = cam.generate_ray(Vec2::new(10.0, 40.0)).d;
        let cos = w.dot(cam.forward());
        let (we, _) = cam.importance(w).unwrap();
        assert!((cam.pdf_we_dir(w) / (we * cos) - 1.0).abs() < 1e-5);
    }
}
