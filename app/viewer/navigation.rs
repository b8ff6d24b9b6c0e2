//! Moving the camera in the viewer, turntable style as in Blender and the Khronos sample
//! viewer: the camera orbits a target point (yaw about the world's up axis, +Y, and pitch held
//! short of the poles, so the view stays upright and never rolls), pans the target across the
//! view, and dollies towards or away from it (an orthographic camera's film shrinks and grows
//! with the distance instead, so dollying still zooms it).

use caustica_renderer::camera::{CameraDesc, Projection};
use caustica_renderer::geometry::Bounds3;
use glam::{Affine3A, EulerRot, Quat, Vec3};

/// Pitch stays this far from straight up or down, where yaw would lose its meaning.
const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    pub distance: f32,
    /// About +Y, radians; 0 looks down -Z.
    pub yaw: f32,
    /// Up from the horizontal, radians.
    pub pitch: f32,
    projection: Projection,
    aspect: Option<f32>,
    /// The orthographic film's half height per unit of distance.
    ymag_per_distance: f32,
}

impl Orbit {
    /// The orbit that shows what `camera` shows (less any roll), about the point on its
    /// axis nearest the centre of `bounds` (or one bounding radius ahead when that point is
    /// behind it).
    pub fn from_camera(camera: &CameraDesc, bounds: &Bounds3) -> Orbit {
        let (_, rotation, position) = camera.camera_to_world.to_scale_rotation_translation();
        let forward = (rotation * Vec3::NEG_Z).normalize();
        let (center, radius) = bounds.bounding_sphere();
        let radius = radius.max(1e-3);
        let along = (center - position).dot(forward);
        let distance = if along > 1e-3 * radius { along } else { radius };
        let ymag_per_distance = match camera.projection {
            Projection::Orthographic { ymag } => ymag / distance,
            Projection::Perspective { .. } => 0.0,
        };
        Orbit {
            target: position + forward * distance,
            distance,
            yaw: (-forward.x).atan2(-forward.z),
            pitch: forward
                .y
                .clamp(-1.0, 1.0)
                .asin()
                .clamp(-MAX_PITCH, MAX_PITCH),
            projection: camera.projection,
            aspect: camera.aspect,
            ymag_per_distance,
        }
    }

    fn rotation(&self) -> Quat {
        Quat::from_euler(EulerRot::YXZ, self.yaw, self.pitch, 0.0)
    }

    /// The camera at this point of the orbit, looking at the target.
    pub fn camera(&self) -> CameraDesc {
        let rotation = self.rotation();
        let position = self.target - rotation * Vec3::NEG_Z * self.distance;
        let projection = match self.projection {
            Projection::Orthographic { .. } => Projection::Orthographic {
                ymag: self.ymag_per_distance * self.distance,
            },
            p => p,
        };
        CameraDesc {
            camera_to_world: Affine3A::from_rotation_translation(rotation, position),
            projection,
            aspect: self.aspect,
        }
    }

    /// Turns about the target by `yaw` and `pitch` radians: positive yaw carries the camera
    /// counter-clockwise about +Y seen from above, positive pitch raises its view.
    pub fn rotate(&mut self, yaw: f32, pitch: f32) {
        self.yaw = (self.yaw + yaw).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + pitch).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target (and the camera with it) across the view, by fractions of the view's
    /// height at the target's distance: `right` to the camera's right, `up` to its up.
    pub fn pan(&mut self, right: f32, up: f32) {
        let height = match self.projection {
            Projection::Perspective { yfov } => 2.0 * self.distance * (0.5 * yfov).tan(),
            Projection::Orthographic { .. } => 2.0 * self.ymag_per_distance * self.distance,
        };
        let rotation = self.rotation();
        self.target += (rotation * Vec3::X * right + rotation * Vec3::Y * up) * height;
    }

    /// Multiplies the distance to the target by `factor` (below 1 moves closer).
    pub fn dolly(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).clamp(1e-4, 1e7);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounds() -> Bounds3 {
        Bounds3::EMPTY
            .union_point(Vec3::splat(-1.0))
            .union_point(Vec3::splat(1.0))
    }

    fn looking(from: Vec3, to: Vec3) -> CameraDesc {
        let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, (to - from).normalize());
        CameraDesc::perspective(Affine3A::from_rotation_translation(rotation, from), 0.8)
    }

    #[test]
    fn an_orbit_starts_where_the_camera_is_and_keeps_the_target_in_view() {
        let camera = looking(Vec3::new(3.0, 2.0, 4.0), Vec3::ZERO);
        let mut orbit = Orbit::from_camera(&camera, &bounds());
        let start = orbit.camera();
        let position = |c: &CameraDesc| Vec3::from(c.camera_to_world.translation);
        let forward = |c: &CameraDesc| c.camera_to_world.matrix3 * Vec3::NEG_Z;
        assert!(position(&start).abs_diff_eq(Vec3::new(3.0, 2.0, 4.0), 1e-4));
        assert!(forward(&start).abs_diff_eq(forward(&camera), 1e-4));
        assert!(
            orbit.target.length() < 1e-4,
            "the target is the bounds' centre"
        );
        // Orbiting keeps the distance and the target ahead, and the horizon level (no roll).
        for (yaw, pitch) in [(0.5, 0.0), (2.0, -0.4), (0.1, 3.0)] {
            orbit.rotate(yaw, pitch);
            let c = orbit.camera();
            assert!((position(&c) - orbit.target).length() - orbit.distance < 1e-4);
            let ahead = (orbit.target - position(&c)).normalize();
            assert!(ahead.abs_diff_eq(forward(&c), 1e-4));
            let right = c.camera_to_world.matrix3 * Vec3::X;
            assert!(right.y.abs() < 1e-5, "rolled: {right}");
            assert!(orbit.pitch <= MAX_PITCH);
        }
        // Yaw alone turns the camera about +Y, counter-clockwise from above.
        let mut o = Orbit::from_camera(&looking(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO), &bounds());
        o.rotate(std::f32::consts::FRAC_PI_2, 0.0);
        assert!(
            position(&o.camera()).abs_diff_eq(Vec3::new(5.0, 0.0, 0.0), 1e-4),
            "{:?}",
            position(&o.camera())
        );
    }

    #[test]
    fn panning_moves_the_view_sideways_and_dolly_scales_the_distance() {
        let mut o = Orbit::from_camera(&looking(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO), &bounds());
        let height = 2.0 * 5.0 * (0.4f32).tan();
        o.pan(0.5, 0.25);
        assert!(
            o.target
                .abs_diff_eq(Vec3::new(0.5 * height, 0.25 * height, 0.0), 1e-4)
        );
        o.dolly(0.5);
        assert!((o.distance - 2.5).abs() < 1e-5);
        o.dolly(f32::NAN);
        o.dolly(-1.0);
        assert!((o.distance - 2.5).abs() < 1e-5);
        // An orthographic camera's film follows the distance.
        let mut ortho = looking(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO);
        ortho.projection = Projection::Orthographic { ymag: 2.0 };
        let mut o = Orbit::from_camera(&ortho, &bounds());
        o.dolly(0.5);
        assert_eq!(
            o.camera().projection,
            Projection::Orthographic { ymag: 1.0 }
        );
    }
}
