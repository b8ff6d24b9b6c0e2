//! The node graph (glTF 2.0 section 3.5): each node walked once from the scene's roots with
//! its world transform, a cycle or a hierarchy deeper than the limit refused, and what a
//! node carries taken: meshes (`mesh.rs`), cameras and KHR_lights_punctual lights.

use super::{Loader, err};
use crate::camera::{CameraDesc, Projection};
use crate::scene::limits::LoadLimits;
use crate::scene::{PunctualLightDesc, SceneError};
use glam::{Affine3A, Mat4, Quat, Vec3};

/// Where the walk of the node graph is with a node.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Visit {
    NotYet,
    /// Its subtree is being walked: reaching it again is a cycle.
    Walking,
    Done,
}

/// The rotation and translation of a node's world transform: a camera or a light ignores
/// scale, and a rotation that is not finite becomes none.
fn rigid(m: Mat4) -> Affine3A {
    let (_, rotation, translation) = m.to_scale_rotation_translation();
    let rotation = if rotation.is_finite() {
        rotation.normalize()
    } else {
        Quat::IDENTITY
    };
    Affine3A::from_rotation_translation(rotation, translation)
}

impl Loader<'_> {
    pub(super) fn visit(
        &mut self,
        node: &gltf::Node,
        parent: Mat4,
        depth: usize,
    ) -> Result<(), SceneError> {
        if depth as u64 > self.limits.max_node_depth {
            return Err(err(LoadLimits::refusal(
                &format!("node {}: the node hierarchy is deeper", node.index()),
                self.limits.max_node_depth,
                "--max-node-depth",
            )));
        }
        match self.visited[node.index()] {
            Visit::NotYet => {}
            Visit::Walking => {
                return Err(err(format!(
                    "node {} is its own ancestor: the node hierarchy has a cycle",
                    node.index()
                )));
            }
            Visit::Done if !self.revisited => {
                self.revisited = true;
                self.desc.warnings.push(format!(
                    "node {} is reached a second time and shown once: a node has one parent \
                     at most, and a scene's roots none (glTF 2.0, 3.5.2)",
                    node.index()
                ));
                return Ok(());
            }
            Visit::Done => return Ok(()),
        }
        self.visited[node.index()] = Visit::Walking;
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(err(format!(
                "node {}: transform is NaN or infinite",
                node.index()
            )));
        }
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                self.desc.warnings.push(format!(
                    "nodes[{}]: skin ignored, the mesh is shown in its bind pose",
                    node.index()
                ));
            }
            // The node's morph weights override the mesh's (spec 3.7.2.2).
            let weights = node.weights().or(mesh.weights()).unwrap_or(&[]);
            self.add_mesh(&mesh, world, weights)?;
        }
        if let Some(camera) = node.camera() {
            let (projection, aspect) = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    (Projection::Perspective { yfov: p.yfov() }, p.aspect_ratio())
                }
                // xmag and ymag are half the film's width and height (spec 3.10.3).
                gltf::camera::Projection::Orthographic(o) => (
                    Projection::Orthographic { ymag: o.ymag() },
                    Some(o.xmag() / o.ymag()),
                ),
            };
            let film = match projection {
                Projection::Perspective { yfov } => yfov > 0.0 && yfov < std::f32::consts::PI,
                Projection::Orthographic { ymag } => ymag > 0.0 && ymag.is_finite(),
            } && aspect.is_none_or(|a| a > 0.0 && a.is_finite());
            if film {
                let desc = CameraDesc {
                    camera_to_world: rigid(world),
                    projection,
                    aspect,
                };
                // The first is the scene's camera; all are offered to the viewer.
                self.desc.camera.get_or_insert(desc);
                let name = camera
                    .name()
                    .or(node.name())
                    .map_or_else(|| format!("camera {}", camera.index()), str::to_string);
                self.desc.cameras.push((name, desc));
            } else {
                self.desc.warnings.push(format!(
                    "cameras[{}]: a film of no size ({projection:?}, aspect {aspect:?}) is ignored",
                    camera.index()
                ));
            }
        }
        if let Some(light) = node.light() {
            self.add_light(&light, world);
        }
        for child in node.children() {
            self.visit(&child, world, depth + 1)?;
        }
        self.visited[node.index()] = Visit::Done;
        Ok(())
    }

    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4) {
        let color = Vec3::from(light.color()) * light.intensity();
        let xf = rigid(world);
        let position = Vec3::from(xf.translation);
        let direction = xf.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        if !color.is_finite() || color.min_element() < 0.0 {
            self.desc.warnings.push(format!(
                "light {}: negative or non-finite intensity, ignored",
                light.index()
            ));
            return;
        }
        use gltf::khr_lights_punctual::Kind;
        self.desc.lights.push(match light.kind() {
            Kind::Point => PunctualLightDesc::Point {
                position,
                intensity: color,
            },
            Kind::Directional => PunctualLightDesc::Directional {
                direction,
                irradiance: color,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => PunctualLightDesc::Spot {
                position,
                direction,
                intensity: color,
                inner_cone: inner_cone_angle.clamp(0.0, outer_cone_angle),
                outer_cone: outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2),
            },
        });
    }
}
