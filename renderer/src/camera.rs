//! Perspective pinhole camera (glTF spec 3.10: looks down its local -Z with +Y up).
//! Film coordinates run from the top-left corner in pixels, x right and y down.

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
    /// The default camera for a scene without one (design.md section 2): looking down -Z at
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
    tan_half_y: f32,
    aspect: f32,
}

impl PerspectiveCamera {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let aspect = desc
            .aspect
            .filter(|a| a.is_finite() && *a > 0.0)
            .unwrap_or(width as f32 / height.max(1) as f32);
        PerspectiveCamera {
            camera_to_world: desc.camera_to_world,
            width,
            height,
            tan_half_y: (desc.yfov.clamp(1e-4, 3.1) / 2.0).tan(),
            aspect,
        }
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
}
