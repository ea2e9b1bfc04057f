//! A glTF mesh's geometry: its primitives' triangles and attributes read
//! from their accessors (positions, normals, texture coordinates, vertex
//! colours, tangents or MikkTSpace's), morph targets and skins applied,
//! placed in the world or kept in the mesh's own space for instancing
//! (docs/design.md §6.6).

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::mesh::Mode;

use super::{Importer, MAX_JOINTS, MAX_TRIANGLES};
use crate::scene::groups::GltfLightNames;
use crate::scene::mesh::Mesh;
use crate::scene::{within_limits, SceneError, MAX_COORDINATE};

/// A primitive's triangles: its POSITIONs in its mesh's space, and the
/// vertex indices of each triangle.
struct Triangles {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Importer<'_, '_> {
    pub(super) fn import_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        placement: &Placement,
        weights: &[f32],
        node_name: &str,
    ) -> Result<(), SceneError> {
        for primitive in mesh.primitives() {
            self.import_primitive(&primitive, mesh.index(), placement, weights, node_name)?;
        }
        Ok(())
    }

    /// One primitive as a mesh placed by `placement` (world space; its own
    /// space for the identity) and named `node_name`, an area light when
    /// it emits. Returns the mesh's index, None for a primitive that is
    /// not triangles (skipped).
    pub(super) fn import_primitive(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        mesh_index: usize,
        placement: &Placement,
        weights: &[f32],
        node_name: &str,
    ) -> Result<Option<usize>, SceneError> {
        let location = format!("meshes[{mesh_index}].primitives[{}]", primitive.index());
        let mode = primitive.mode();
        if matches!(mode, Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
            self.skipped_primitives += 1;
            return Ok(None);
        }
        let Triangles { mut positions, mut triangles } = self.read_triangles(primitive, &location)?;
        let count = positions.len();
        let mut normals = self.attribute::<3>(primitive, &location, gltf::Semantic::Normals, "normals", count)?;
        self.morph(primitive, &location, weights, &mut positions, normals.as_mut())?;
        let transforms = self.vertex_transforms(primitive, &location, placement, count)?;
        if transforms.mirrored() {
            // A mirroring transform turns the winding around; keep the
            // front (emitting) side where the file's author saw it.
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let world_positions: Vec<Vec3> =
            positions.iter().enumerate().map(|(i, p)| transforms.point(i, Vec3::from_array(*p))).collect();
        if let Some(bad) = world_positions.iter().position(|p| !within_limits(*p)) {
            return Err(self.error(
                format!("{location}.attributes.POSITION"),
                format!(
                    "vertex {bad} is at {} in the world: coordinates must be finite and within +/-{MAX_COORDINATE:e} m",
                    world_positions[bad]
                ),
            ));
        }
        let normals = match normals {
            None => None,
            Some(normals) => {
                let normals: Vec<Vec3> = normals
                    .iter()
                    .enumerate()
                    .map(|(i, n)| transforms.normal(i, Vec3::from_array(*n)).normalize_or_zero())
                    .collect();
                if normals.iter().any(|n| *n == Vec3::ZERO || !n.is_finite()) {
                    self.warn(&format!("{location}.attributes.NORMAL"), "has zero or non-finite normals: shaded flat");
                    None
                } else {
                    Some(normals)
                }
            }
        };
        let uvs = self.texture_coordinates(primitive, &location, count, 0)?;
        let uvs1 = self.texture_coordinates(primitive, &location, count, 1)?;
        let colors = self.vertex_colors(primitive, &location, count)?;
        let material = self.material(primitive.material())?;
        let normal_set =
            self.parts.scene.materials[material].pbr.as_ref().and_then(|p| p.normal_map.as_ref()).map(|m| m.set);
        let tangents = if let Some(set) = normal_set {
            // MikkTSpace works in the normal map's own texture coordinates.
            let uvs = if set == 1 { uvs1.as_deref() } else { uvs.as_deref() };
            let frame = Frame { transforms: &transforms, weights, normals: normals.as_deref(), uvs };
            self.tangents(primitive, &location, count, &frame, &world_positions, &triangles)?
        } else {
            None
        };
        let emission = self.parts.scene.materials[material].emission;
        let both_sides = self.parts.scene.materials[material].emits_both_sides;
        let mut mesh = Mesh {
            positions: world_positions,
            normals,
            uvs,
            uvs1,
            colors,
            tangents: None,
            triangles,
            material,
            name: node_name.to_string(),
            strands: None,
        };
        match tangents {
            None => {}
            Some(Tangents::PerVertex(tangents)) => mesh.tangents = Some(tangents),
            Some(Tangents::PerCorner(corners)) => mesh.set_corner_tangents(&corners),
        }
        let has_area = mesh.has_area();
        self.parts.scene.meshes.push(mesh);
        if emission != Vec3::ZERO && has_area {
            let mesh = self.parts.scene.meshes.len() - 1;
            let light = self.emitters.light(mesh, emission, self.spec.emitter_samples, both_sides);
            self.parts.scene.lights.push(light);
            self.parts.light_names.push(GltfLightNames {
                light: None,
                node: Some(node_name.to_string()),
                material: Some(self.parts.scene.materials[material].name.clone()),
            });
        }
        Ok(Some(self.parts.scene.meshes.len() - 1))
    }

    /// A primitive's POSITIONs (in its mesh's space) and its triangles,
    /// every index checked, the import's triangle count kept under
    /// `MAX_TRIANGLES`.
    fn read_triangles(&mut self, primitive: &gltf::Primitive<'_>, location: &str) -> Result<Triangles, SceneError> {
        let Some(positions) = primitive.get(&gltf::Semantic::Positions) else {
            return Err(self.error(format!("{location}.attributes"), "has no POSITION"));
        };
        let positions = self.data.read_floats::<3>(&positions, &format!("{location}.attributes.POSITION"))?;
        let count = positions.len();
        let indices = match primitive.indices() {
            Some(a) => {
                let at = format!("{location}.indices");
                let indices = self.data.read_indices(&a, &at)?;
                if let Some(k) = indices.iter().position(|&i| i as usize >= count) {
                    return Err(self.error(at, format!("index {k} is {}, past the {count} vertices", indices[k])));
                }
                indices
            }
            None => (0..count as u32).collect(),
        };
        let triangles = triangulate(primitive.mode(), &indices);
        self.triangles = self.triangles.saturating_add(triangles.len());
        if self.triangles > MAX_TRIANGLES {
            return Err(self.error(
                location,
                format!(
                    "the scene expands to more than {MAX_TRIANGLES} triangles (copies counted, an instanced mesh once)"
                ),
            ));
        }
        Ok(Triangles { positions, triangles })
    }

    /// glTF's morph targets at `weights` (the node's, else the mesh's; 0
    /// where none is given): POSITION and NORMAL displaced by the weighted
    /// sum of the targets' (the specification's section 3.7.2.2), in the mesh's
    /// own space.
    pub(super) fn morph(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        weights: &[f32],
        positions: &mut [[f32; 3]],
        mut normals: Option<&mut Vec<[f32; 3]>>,
    ) -> Result<(), SceneError> {
        for (k, target) in primitive.morph_targets().enumerate() {
            let weight = weights.get(k).copied().unwrap_or(0.0);
            if !weight.is_finite() {
                return Err(self.error(format!("{location} (weights[{k}])"), "morph target weights must be finite"));
            }
            if weight == 0.0 {
                continue;
            }
            self.add_deltas(target.positions(), &format!("{location}.targets[{k}].POSITION"), weight, positions)?;
            if let Some(normals) = normals.as_deref_mut() {
                self.add_deltas(target.normals(), &format!("{location}.targets[{k}].NORMAL"), weight, normals)?;
            }
        }
        Ok(())
    }

    /// Adds `weight` times a morph target's displacements (`accessor`, at
    /// JSON location `at`; nothing when absent) to `into`, one per vertex.
    pub(super) fn add_deltas(
        &self,
        accessor: Option<gltf::Accessor<'_>>,
        at: &str,
        weight: f32,
        into: &mut [[f32; 3]],
    ) -> Result<(), SceneError> {
        let Some(a) = accessor else { return Ok(()) };
        let deltas = self.data.read_floats::<3>(&a, at)?;
        if deltas.len() != into.len() {
            return Err(self.error(at, format!("has {} elements for {} vertices", deltas.len(), into.len())));
        }
        for (v, d) in into.iter_mut().zip(&deltas) {
            for c in 0..3 {
                v[c] += weight * d[c];
            }
        }
        Ok(())
    }

    /// The transforms that place a primitive's vertices: the node's, or
    /// for a skin each vertex's JOINTS_0 matrices blended by its WEIGHTS_0
    /// (the specification's section 3.7.3: the skinned node's own transform is
    /// not applied).
    pub(super) fn vertex_transforms(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        placement: &Placement,
        count: usize,
    ) -> Result<VertexTransforms, SceneError> {
        let joints = match placement {
            Placement::Rigid(matrix) => return Ok(VertexTransforms::rigid(*matrix)),
            Placement::Skinned(joints) => joints,
        };
        let (Some(indices), Some(weights)) =
            (primitive.get(&gltf::Semantic::Joints(0)), primitive.get(&gltf::Semantic::Weights(0)))
        else {
            return Err(self.error(format!("{location}.attributes"), "is skinned but has no JOINTS_0 and WEIGHTS_0"));
        };
        let at_joints = format!("{location}.attributes.JOINTS_0");
        let indices = self.data.read_floats::<4>(&indices, &at_joints)?;
        let at_weights = format!("{location}.attributes.WEIGHTS_0");
        let weights = self.data.read_floats::<4>(&weights, &at_weights)?;
        if indices.len() != count || weights.len() != count {
            return Err(
                self.error(at_joints, format!("JOINTS_0 and WEIGHTS_0 must have {count} elements, one a vertex"))
            );
        }
        let mut matrices = Vec::with_capacity(count);
        for (v, (j, w)) in indices.iter().zip(&weights).enumerate() {
            let mut m = Mat4::ZERO;
            for k in 0..4 {
                if w[k] == 0.0 {
                    continue;
                }
                let Some(joint) = joints.get(j[k] as usize) else {
                    return Err(self.error(
                        &at_joints,
                        format!("vertex {v} names joint {}, but the skin has {}", j[k], joints.len()),
                    ));
                };
                if !w[k].is_finite() {
                    return Err(self.error(&at_weights, format!("vertex {v}'s weights are not finite")));
                }
                m += *joint * w[k];
            }
            matrices.push(m);
        }
        Ok(VertexTransforms::of(matrices))
    }

    /// A skin's joint matrices: each joint node's world transform times its
    /// inverse bind matrix (identity without them).
    pub(super) fn joint_matrices(
        &mut self,
        skin: &gltf::Skin<'_>,
        worlds: &[Option<Mat4>],
    ) -> Result<Vec<Mat4>, SceneError> {
        let location = format!("skins[{}]", skin.index());
        let joints: Vec<gltf::Node<'_>> = skin.joints().collect();
        if joints.is_empty() || joints.len() > MAX_JOINTS {
            return Err(self.error(
                format!("{location}.joints"),
                format!("has {} joints: a skin has 1 to {MAX_JOINTS}", joints.len()),
            ));
        }
        let inverse_binds = match skin.inverse_bind_matrices() {
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(a) => {
                let at = format!("{location}.inverseBindMatrices");
                let m = self.data.read_floats::<16>(&a, &at)?;
                if m.len() < joints.len() {
                    return Err(self.error(at, format!("has {} matrices for {} joints", m.len(), joints.len())));
                }
                m.iter().map(Mat4::from_cols_array).collect()
            }
        };
        let mut matrices = Vec::with_capacity(joints.len());
        for (k, (joint, inverse_bind)) in joints.iter().zip(&inverse_binds).enumerate() {
            let Some(world) = worlds[joint.index()] else {
                return Err(self.error(
                    format!("{location}.joints[{k}]"),
                    format!("nodes[{}] is not in the rendered scene", joint.index()),
                ));
            };
            let m = world * *inverse_bind;
            if !m.is_finite() {
                return Err(self.error(format!("{location}.inverseBindMatrices"), format!("matrix {k} is not finite")));
            }
            matrices.push(m);
        }
        Ok(matrices)
    }

    /// A normal-mapped primitive's tangents in world space: its `TANGENT`s
    /// (displaced by its morph targets' at the weights, transformed by the
    /// node's matrix; w flipped by a mirroring one),
    /// or MikkTSpace's from its normals and texture coordinates, as the
    /// specification asks. None, with a warning, without normals or
    /// texture coordinates (the normal map is then not used).
    pub(super) fn tangents(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
        frame: &Frame<'_>,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<Option<Tangents>, SceneError> {
        let (Some(normals), Some(uvs)) = (frame.normals, frame.uvs) else {
            self.warn(location, "normalTexture unused: the primitive has no NORMAL or not the TEXCOORD it reads");
            return Ok(None);
        };
        let Some(mut tangents) =
            self.attribute::<4>(primitive, location, gltf::Semantic::Tangents, "tangents", count)?
        else {
            return Ok(mikktspace_tangents(positions, normals, uvs, triangles));
        };
        // Morph targets displace the tangent's xyz (glTF section 3.7.2.2); w stays.
        let mut xyz: Vec<[f32; 3]> = tangents.iter().map(|t| [t[0], t[1], t[2]]).collect();
        for (k, target) in primitive.morph_targets().enumerate() {
            let weight = frame.weights.get(k).copied().unwrap_or(0.0);
            if weight != 0.0 {
                self.add_deltas(target.tangents(), &format!("{location}.targets[{k}].TANGENT"), weight, &mut xyz)?;
            }
        }
        for (t, v) in tangents.iter_mut().zip(&xyz) {
            t[..3].copy_from_slice(v);
        }
        let sign = if frame.transforms.mirrored() { -1.0 } else { 1.0 };
        let tangents: Vec<Vec4> = tangents
            .iter()
            .enumerate()
            .map(|(i, t)| {
                frame.transforms.vector(i, Vec3::new(t[0], t[1], t[2])).normalize_or_zero().extend(sign * t[3].signum())
            })
            .collect();
        if tangents.iter().any(|t| !t.is_finite() || t.truncate() == Vec3::ZERO) {
            self.warn(
                &format!("{location}.attributes.TANGENT"),
                "has zero or non-finite tangents: MikkTSpace's are used",
            );
            return Ok(mikktspace_tangents(positions, normals, uvs, triangles));
        }
        Ok(Some(Tangents::PerVertex(tangents)))
    }

    /// A primitive's float attribute `semantic` of N components, one per
    /// vertex (`noun` names its elements in the error); None when absent.
    pub(super) fn attribute<const N: usize>(
        &self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        semantic: gltf::Semantic,
        noun: &str,
        count: usize,
    ) -> Result<Option<Vec<[f32; N]>>, SceneError> {
        let Some(a) = primitive.get(&semantic) else { return Ok(None) };
        let at = format!("{location}.attributes.{}", semantic.to_string());
        let values = self.data.read_floats::<N>(&a, &at)?;
        if values.len() != count {
            return Err(self.error(at, format!("has {} {noun} for {count} vertices", values.len())));
        }
        Ok(Some(values))
    }

    /// A primitive's `TEXCOORD_<set>`, finite, one per vertex.
    pub(super) fn texture_coordinates(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
        set: u32,
    ) -> Result<Option<Vec<Vec2>>, SceneError> {
        let semantic = gltf::Semantic::TexCoords(set);
        let Some(uvs) = self.attribute::<2>(primitive, location, semantic, "coordinates", count)? else {
            return Ok(None);
        };
        if uvs.iter().flatten().any(|x| !x.is_finite()) {
            return Err(
                self.error(format!("{location}.attributes.TEXCOORD_{set}"), "has non-finite texture coordinates")
            );
        }
        Ok(Some(uvs.iter().map(|uv| Vec2::from_array(*uv)).collect()))
    }

    /// A primitive's `COLOR_0` (VEC3 or VEC4 of floats or normalized
    /// integers, linear; the alpha is not used): the colours that multiply
    /// its base colour.
    pub(super) fn vertex_colors(
        &mut self,
        primitive: &gltf::Primitive<'_>,
        location: &str,
        count: usize,
    ) -> Result<Option<Vec<Vec3>>, SceneError> {
        let Some(a) = primitive.get(&gltf::Semantic::Colors(0)) else { return Ok(None) };
        let at = format!("{location}.attributes.COLOR_0");
        let colors: Vec<Vec3> = if a.dimensions() == gltf::accessor::Dimensions::Vec4 {
            self.data.read_floats::<4>(&a, &at)?.iter().map(|c| Vec3::new(c[0], c[1], c[2])).collect()
        } else {
            self.data.read_floats::<3>(&a, &at)?.iter().map(|c| Vec3::from_array(*c)).collect()
        };
        if colors.len() != count {
            return Err(self.error(at, format!("has {} colours for {count} vertices", colors.len())));
        }
        if colors.iter().any(|c| !c.is_finite() || c.min_element() < 0.0) {
            return Err(self.error(at, "has colours that are not finite and >= 0"));
        }
        // A float colour may exceed 1, but it multiplies the base colour, a
        // reflectance the BRDF (and its bound: docs/design.md §8.3) needs
        // within [0, 1].
        let brightest = colors.iter().map(|c| c.max_element()).fold(0.0, f32::max);
        if brightest > 1.0 {
            self.warn(
                &at,
                &format!(
                    "colours above 1 (up to {brightest}) clamped to 1: they multiply the base colour, a reflectance"
                ),
            );
            return Ok(Some(colors.iter().map(|c| c.min(Vec3::ONE)).collect()));
        }
        Ok(Some(colors))
    }
}

/// Where a mesh's vertices go: one node transform, or (a skin) each
/// vertex's blend of its joints' matrices.
pub(super) enum Placement {
    Rigid(Mat4),
    /// Each joint's world transform times its inverse bind matrix.
    Skinned(Vec<Mat4>),
}

/// A primitive's object-to-world transform, for all its vertices or one
/// per vertex (skinned), with the inverse transposes for normals.
pub(super) enum VertexTransforms {
    Rigid { matrix: Mat4, normal: Mat3 },
    PerVertex { matrices: Vec<Mat4>, normals: Vec<Mat3> },
}

impl VertexTransforms {
    fn of(matrices: Vec<Mat4>) -> Self {
        let normals = matrices.iter().map(|m| Mat3::from_mat4(*m).inverse().transpose()).collect();
        Self::PerVertex { matrices, normals }
    }

    fn rigid(matrix: Mat4) -> Self {
        Self::Rigid { matrix, normal: Mat3::from_mat4(matrix).inverse().transpose() }
    }

    fn matrix(&self, vertex: usize) -> &Mat4 {
        match self {
            Self::Rigid { matrix, .. } => matrix,
            Self::PerVertex { matrices, .. } => &matrices[vertex],
        }
    }

    fn point(&self, vertex: usize, p: Vec3) -> Vec3 {
        self.matrix(vertex).transform_point3(p)
    }

    fn vector(&self, vertex: usize, v: Vec3) -> Vec3 {
        self.matrix(vertex).transform_vector3(v)
    }

    fn normal(&self, vertex: usize, n: Vec3) -> Vec3 {
        match self {
            Self::Rigid { normal, .. } => *normal * n,
            Self::PerVertex { normals, .. } => normals[vertex] * n,
        }
    }

    /// Whether the transform mirrors (a skin: its first vertex's does).
    fn mirrored(&self) -> bool {
        match self {
            Self::Rigid { matrix, .. } => Mat3::from_mat4(*matrix).determinant() < 0.0,
            Self::PerVertex { matrices, .. } => {
                matrices.first().is_some_and(|m| Mat3::from_mat4(*m).determinant() < 0.0)
            }
        }
    }
}

/// What a primitive's tangents are made from: its node's transform, its
/// morph weights, and its world-space normals and (glTF) texture
/// coordinates.
pub(super) struct Frame<'a> {
    transforms: &'a VertexTransforms,
    weights: &'a [f32],
    normals: Option<&'a [Vec3]>,
    uvs: Option<&'a [Vec2]>,
}

/// A primitive's tangents: the file's, one per vertex, or MikkTSpace's,
/// one per triangle corner (`Mesh::set_corner_tangents` splits the
/// vertices whose corners disagree).
pub(crate) enum Tangents {
    PerVertex(Vec<Vec4>),
    PerCorner(Vec<[Vec4; 3]>),
}

/// MikkTSpace tangents of a triangle mesh, one per triangle corner, from
/// glTF's texture coordinates with v turned up, so that the bitangent
/// points up the image as glTF's normal maps expect. None if MikkTSpace
/// fails.
pub(crate) fn mikktspace_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Option<Tangents> {
    struct Faces<'a> {
        positions: &'a [Vec3],
        normals: &'a [Vec3],
        uvs: &'a [Vec2],
        triangles: &'a [[u32; 3]],
        tangents: Vec<[Vec4; 3]>,
    }
    impl bevy_mikktspace::Geometry for Faces<'_> {
        fn num_faces(&self) -> usize {
            self.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.positions[self.triangles[face][vert] as usize].to_array()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            self.normals[self.triangles[face][vert] as usize].to_array()
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            let uv = self.uvs[self.triangles[face][vert] as usize];
            [uv.x, 1.0 - uv.y]
        }
        fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
            self.tangents[face][vert] = Vec4::from_array(tangent);
        }
    }
    let mut faces = Faces {
        positions,
        normals,
        uvs,
        triangles,
        tangents: vec![[Vec4::new(1.0, 0.0, 0.0, 1.0); 3]; triangles.len()],
    };
    bevy_mikktspace::generate_tangents(&mut faces).then_some(Tangents::PerCorner(faces.tangents))
}

/// Triangles of a primitive: lists as they are, strips and fans converted
/// (alternate strip triangles reversed to keep one winding).
pub(super) fn triangulate(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                if i % 2 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len()).map(|i| [indices[0], indices[i - 1], indices[i]]).collect(),
        _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}
