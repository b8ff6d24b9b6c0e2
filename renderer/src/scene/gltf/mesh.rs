//! A mesh's triangle primitives (glTF 2.0 section 3.7.2): attributes read from accessors
//! (their types checked first) or decoded from a Draco bitstream (`draco.rs`), morph targets
//! applied at the node's weights, strips and fans turned into lists, everything moved to
//! world space (winding kept under a mirroring transform) and counted against the triangle
//! limit.

use super::{Loader, checks, draco, err};
use crate::scene::limits::LoadLimits;
use crate::scene::{MeshDesc, SceneError};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

/// A primitive's vertex attributes in the model's space, from accessors or a decoded Draco
/// bitstream; indices None means the vertices in order.
struct VertexData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    uvs1: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec4>>,
    indices: Option<Vec<u32>>,
}

impl Loader<'_> {
    /// The mesh's triangle primitives in world space, morphed by `weights` (spec 3.7.2.2:
    /// each target's displacements, times its weight, added to the base attributes).
    pub(super) fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: Mat4,
        weights: &[f32],
    ) -> Result<(), SceneError> {
        let name = mesh
            .name()
            .map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.desc.warnings.push(format!(
                    "{name}: primitive with mode {mode:?} skipped (points and lines have no area)"
                ));
                continue;
            }
            let material = self.material(prim.material())?;
            // The second set only where a texture reads it (files often carry lightmap
            // coordinates we have no use for).
            let want_uvs1 = self.desc.materials[material as usize]
                .texture_refs()
                .any(|r| r.tex_coord == 1);
            let draco = prim.extension_value("KHR_draco_mesh_compression");
            let data = match draco {
                Some(ext) => {
                    if weights.iter().any(|&w| w != 0.0) {
                        self.desc.warnings.push(format!(
                            "{name}: morph targets of a Draco-compressed primitive ignored"
                        ));
                    }
                    let d = draco::decode(self.document, self.buffers, ext)
                        .map_err(|e| err(format!("{name}: KHR_draco_mesh_compression: {e}")))?;
                    let [uvs, uvs1] = d.tex_coords;
                    VertexData {
                        positions: d.positions,
                        normals: d.normals,
                        uvs,
                        uvs1: uvs1.filter(|_| want_uvs1),
                        colors: d.colors,
                        indices: Some(d.indices),
                    }
                }
                None => self.read_accessors(&prim, weights, want_uvs1, &name)?,
            };
            let VertexData {
                positions,
                normals,
                uvs,
                uvs1,
                colors,
                indices,
            } = data;
            let positions: Vec<Vec3> = positions
                .into_iter()
                .map(|p| world.transform_point3(p))
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(err(format!("{name}: position {i} is NaN or infinite")));
            }
            let normals = normals.map(|ns| {
                ns.into_iter()
                    .map(|n| (normal_matrix * n).normalize_or_zero())
                    .collect::<Vec<_>>()
            });
            let mut indices = indices.unwrap_or_else(|| (0..positions.len() as u32).collect());
            // A Draco bitstream decodes to a triangle list whatever the mode says.
            match mode {
                _ if draco.is_some() => {}
                Mode::TriangleStrip => indices = strip_to_list(&indices),
                Mode::TriangleFan => indices = fan_to_list(&indices),
                _ => {}
            }
            if indices.len() % 3 != 0 {
                self.desc.warnings.push(format!(
                    "{name}: {} trailing indices ignored",
                    indices.len() % 3
                ));
                indices.truncate(indices.len() / 3 * 3);
            }
            self.triangles += indices.len() as u64 / 3;
            if self.triangles > self.limits.max_triangles {
                return Err(err(LoadLimits::refusal(
                    &format!(
                        "{name}: the scene holds {} triangles so far, each instance counted",
                        self.triangles
                    ),
                    self.limits.max_triangles,
                    "--max-triangles",
                )));
            }
            if flip {
                for tri in indices.chunks_exact_mut(3) {
                    tri.swap(1, 2);
                }
            }
            self.desc.meshes.push(MeshDesc {
                name: name.clone(),
                positions,
                normals,
                uvs,
                uvs1,
                colors,
                indices,
                material,
            });
        }
        Ok(())
    }

    /// A primitive's vertex attributes from its accessors, displaced by its morph targets at
    /// `weights` (spec 3.7.2.2).
    fn read_accessors(
        &self,
        prim: &gltf::Primitive,
        weights: &[f32],
        want_uvs1: bool,
        name: &str,
    ) -> Result<VertexData, SceneError> {
        checks::check_accessor_types(prim).map_err(|e| err(format!("{name}: {e}")))?;
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let Some(positions) = reader.read_positions() else {
            return Err(err(format!("{name}: primitive without POSITION")));
        };
        let mut positions: Vec<Vec3> = positions.map(Vec3::from).collect();
        let mut normals: Option<Vec<Vec3>> =
            reader.read_normals().map(|ns| ns.map(Vec3::from).collect());
        for (target, &weight) in reader.read_morph_targets().zip(weights) {
            if weight == 0.0 || !weight.is_finite() {
                continue;
            }
            let (dp, dn, _) = target;
            for (p, d) in positions.iter_mut().zip(dp.into_iter().flatten()) {
                *p += weight * Vec3::from(d);
            }
            if let Some(normals) = normals.as_mut() {
                for (n, d) in normals.iter_mut().zip(dn.into_iter().flatten()) {
                    *n += weight * Vec3::from(d);
                }
            }
        }
        let tex_coords = |set| {
            reader
                .read_tex_coords(set)
                .map(|t| t.into_f32().map(Vec2::from).collect())
        };
        Ok(VertexData {
            positions,
            normals,
            uvs: tex_coords(0),
            uvs1: want_uvs1.then(|| tex_coords(1)).flatten(),
            // COLOR_0 is linear (spec 3.7.2.1); RGB colours have alpha 1.
            colors: reader
                .read_colors(0)
                .map(|c| c.into_rgba_f32().map(Vec4::from).collect()),
            indices: reader.read_indices().map(|i| i.into_u32().collect()),
        })
    }
}

/// Triangle i of a strip is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), glTF 2.0 section 3.7.2.1:
/// every other triangle swaps its last two vertices so that all keep the strip's winding.
fn strip_to_list(strip: &[u32]) -> Vec<u32> {
    (0..strip.len().saturating_sub(2))
        .flat_map(|i| [strip[i], strip[i + 1 + i % 2], strip[i + 2 - i % 2]])
        .collect()
}

/// Triangle i of a fan is (v_{i+1}, v_{i+2}, v_0), glTF 2.0 section 3.7.2.1.
fn fan_to_list(fan: &[u32]) -> Vec<u32> {
    (0..fan.len().saturating_sub(2))
        .flat_map(|i| [fan[i + 1], fan[i + 2], fan[0]])
        .collect()
}
