//! Triangle meshes: generated quads, boxes and spheres, and OBJ files (tobj).

use std::path::Path;

use glam::{Vec2, Vec3, Vec4};

use super::error::SceneError;
use super::material::TexCoords;

/// A triangle mesh in world space with one material.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length), when the shape has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, when the shape has them.
    pub uvs: Option<Vec<Vec2>>,
    /// A second set of texture coordinates (glTF's `TEXCOORD_1`).
    pub uvs1: Option<Vec<Vec2>>,
    /// Per-vertex colours (linear RGB) multiplying the base colour (glTF's
    /// `COLOR_0`), when the shape has them.
    pub colors: Option<Vec<Vec3>>,
    /// Per-vertex tangents (unit xyz along increasing u; w = +1 or -1, the
    /// bitangent being w (normal x tangent), up the texture), for a normal
    /// map: glTF's `TANGENT`s, or MikkTSpace's.
    pub tangents: Option<Vec<Vec4>>,
    pub triangles: Vec<[u32; 3]>,
    /// Index into `Scene::materials`.
    pub material: usize,
    /// The object's name (a shape's `name` or `shapes[i]`, a glTF node's
    /// name): what Cryptomatte's object mattes are keyed by.
    pub name: String,
    /// Curves or points instead of triangles (then `triangles` is empty
    /// and `positions` are their control points or centres).
    pub strands: Option<Strands>,
}

/// Curves or points, drawn by Embree's own curve and sphere primitives
/// rather than as triangles (docs/design.md §4.3).
#[derive(Debug, Clone)]
pub struct Strands {
    /// The radius at each position, metres (half USD's `widths`).
    pub radii: Vec<f32>,
    pub kind: StrandKind,
}

/// What a mesh's strands are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StrandKind {
    /// A sphere around each position (USD's `Points`).
    Spheres,
    /// Cubic or linear curves (USD's `BasisCurves`); `segments` holds the
    /// first control point of each segment, which reads `basis.order()`
    /// consecutive positions.
    Curves { basis: CurveBasis, ribbon: bool, segments: Vec<u32> },
}

/// The basis of a curve's control points (USD's `basis`; `type =
/// linear`): Embree's curve bases are the schema's.
pub use crate::embree::CurveBasis;

impl Strands {
    /// The value of a per-position quantity at parameter `u` of primitive
    /// `primitive` (a sphere, or a curve segment).
    #[must_use]
    pub fn interpolate<T>(&self, values: &[T], primitive: usize, u: f32) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        match &self.kind {
            StrandKind::Spheres => values[primitive],
            StrandKind::Curves { basis, segments, .. } => {
                let first = segments[primitive] as usize;
                let (a, b) = basis.ends();
                let u = u.clamp(0.0, 1.0);
                values[first + a] * (1.0 - u) + values[first + b] * u
            }
        }
    }
}

impl Strands {
    /// The direction along curve segment `primitive` at parameter `u`
    /// (dP/du of its basis over `positions`, not normalised); None for a
    /// sphere. B-spline: dB/du = (-(1-u)^2, 3u^2 - 4u, -3u^2 + 2u + 1,
    /// u^2) / 2; Catmull-Rom: the derivative of its cubic in u; Bezier:
    /// 3 the quadratic of the control polygon's legs.
    #[must_use]
    pub fn tangent(&self, positions: &[Vec3], primitive: usize, u: f32) -> Option<Vec3> {
        let StrandKind::Curves { basis, segments, .. } = &self.kind else { return None };
        let first = segments[primitive] as usize;
        let p = |k: usize| positions[first + k];
        let u = u.clamp(0.0, 1.0);
        let s = 1.0 - u;
        Some(match basis {
            CurveBasis::Linear => p(1) - p(0),
            CurveBasis::Bezier => 3.0 * (s * s * (p(1) - p(0)) + 2.0 * u * s * (p(2) - p(1)) + u * u * (p(3) - p(2))),
            CurveBasis::BSpline => {
                0.5 * (-s * s * p(0)
                    + (3.0 * u * u - 4.0 * u) * p(1)
                    + (-3.0 * u * u + 2.0 * u + 1.0) * p(2)
                    + u * u * p(3))
            }
            CurveBasis::CatmullRom => {
                let (p0, p1, p2, p3) = (p(0), p(1), p(2), p(3));
                0.5 * ((p2 - p0)
                    + 2.0 * u * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3)
                    + 3.0 * u * u * (-p0 + 3.0 * p1 - 3.0 * p2 + p3))
            }
        })
    }
}

impl Mesh {
    /// Whether some triangle has an area (an emitter of none emits nothing).
    #[must_use]
    pub fn has_area(&self) -> bool {
        self.triangles.iter().any(|t| crate::util::triangle::area(t.map(|i| self.positions[i as usize])) > 0.0)
    }

    /// The area of its triangles, square metres (f64: a mesh may span
    /// 1e16 m, whose squares overflow f32).
    #[must_use]
    pub fn surface_area(&self) -> f64 {
        self.triangles.iter().map(|t| crate::util::triangle::area(t.map(|i| self.positions[i as usize]))).sum()
    }

    /// Texture coordinates (sets 0 and 1) at barycentric coordinates (u,
    /// v) of triangle `triangle` (u weighs its second vertex, v its third,
    /// as Embree's hits do); (u, v) itself where the mesh has no texture
    /// coordinates, and set 0 where it has no set 1.
    #[must_use]
    pub fn tex_coords(&self, triangle: usize, u: f32, v: f32) -> TexCoords {
        let tri = self.triangles[triangle];
        let w = 1.0 - u - v;
        let interpolate = |uvs: &Option<Vec<Vec2>>| {
            uvs.as_ref().map(|uvs| {
                let [t0, t1, t2] = tri.map(|i| uvs[i as usize]);
                w * t0 + u * t1 + v * t2
            })
        };
        let uv = interpolate(&self.uvs).unwrap_or(Vec2::new(u, v));
        TexCoords::at([uv, interpolate(&self.uvs1).unwrap_or(uv)])
    }

    /// The texture coordinates of triangle `triangle`'s corners, sets 0
    /// and 1, as [`Mesh::tex_coords`] interpolates them (the barycentric
    /// corners (0, 0), (1, 0), (0, 1) where the mesh has none).
    #[must_use]
    pub fn corner_tex_coords(&self, triangle: usize) -> [[Vec2; 3]; 2] {
        let tri = self.triangles[triangle];
        let corners = |uvs: &Option<Vec<Vec2>>| uvs.as_ref().map(|uvs| tri.map(|i| uvs[i as usize]));
        let set0 = corners(&self.uvs).unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]);
        [set0, corners(&self.uvs1).unwrap_or(set0)]
    }

    /// Sets per-vertex tangents from per-corner ones (MikkTSpace's: one per
    /// triangle corner). A vertex whose corners carry different tangents
    /// (a mirrored-uv seam, a hard tangent edge) is split into one vertex
    /// per tangent, every per-vertex attribute copied, as MikkTSpace's own
    /// welding would leave it; corners that agree keep sharing their vertex.
    pub fn set_corner_tangents(&mut self, corners: &[[Vec4; 3]]) {
        debug_assert_eq!(corners.len(), self.triangles.len());
        let mut tangents: Vec<Option<Vec4>> = vec![None; self.positions.len()];
        // The vertex each new vertex copies, and the new vertex of each
        // (vertex, tangent) pair already split off.
        let mut copies_of: Vec<usize> = Vec::new();
        let mut split: std::collections::HashMap<(u32, [u32; 4]), u32> = std::collections::HashMap::new();
        for (tri, corner) in self.triangles.iter_mut().zip(corners) {
            for (index, &tangent) in tri.iter_mut().zip(corner) {
                let v = *index as usize;
                match tangents[v] {
                    None => tangents[v] = Some(tangent),
                    Some(t) if t.to_array().map(f32::to_bits) == tangent.to_array().map(f32::to_bits) => {}
                    Some(_) => {
                        let key = (*index, tangent.to_array().map(f32::to_bits));
                        *index = *split.entry(key).or_insert_with(|| {
                            copies_of.push(v);
                            tangents.push(Some(tangent));
                            (tangents.len() - 1) as u32
                        });
                    }
                }
            }
        }
        fn copy<T: Copy>(values: &mut Option<Vec<T>>, copies_of: &[usize]) {
            if let Some(values) = values {
                for &v in copies_of {
                    values.push(values[v]);
                }
            }
        }
        for &v in &copies_of {
            self.positions.push(self.positions[v]);
        }
        copy(&mut self.normals, &copies_of);
        copy(&mut self.uvs, &copies_of);
        copy(&mut self.uvs1, &copies_of);
        copy(&mut self.colors, &copies_of);
        // A vertex no triangle uses keeps the default frame's tangent.
        self.tangents = Some(tangents.into_iter().map(|t| t.unwrap_or(Vec4::new(1.0, 0.0, 0.0, 1.0))).collect());
    }

    /// A parallelogram with corners c, c+u, c+u+v, c+v; uv spans [0,1]^2.
    #[must_use]
    pub fn quad(corner: Vec3, u: Vec3, v: Vec3, material: usize) -> Self {
        Self {
            positions: vec![corner, corner + u, corner + u + v, corner + v],
            normals: None,
            colors: None,
            tangents: None,
            uvs1: None,
            uvs: Some(vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)]),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material,
            name: String::new(),
            strands: None,
        }
    }

    /// An axis-aligned box, six faces with their own vertices (flat shading),
    /// each face's uv spanning [0,1]^2.
    #[must_use]
    pub fn cuboid(min: Vec3, max: Vec3, material: usize) -> Self {
        let d = max - min;
        let faces = [
            (min, Vec3::new(0.0, 0.0, d.z), Vec3::new(0.0, d.y, 0.0)), // -x
            (Vec3::new(max.x, min.y, min.z), Vec3::new(0.0, d.y, 0.0), Vec3::new(0.0, 0.0, d.z)), // +x
            (min, Vec3::new(d.x, 0.0, 0.0), Vec3::new(0.0, 0.0, d.z)), // -y
            (Vec3::new(min.x, max.y, min.z), Vec3::new(0.0, 0.0, d.z), Vec3::new(d.x, 0.0, 0.0)), // +y
            (min, Vec3::new(0.0, d.y, 0.0), Vec3::new(d.x, 0.0, 0.0)), // -z
            (Vec3::new(min.x, min.y, max.z), Vec3::new(d.x, 0.0, 0.0), Vec3::new(0.0, d.y, 0.0)), // +z
        ];
        let mut mesh = Self { material, uvs: Some(Vec::new()), ..Self::default() };
        for (corner, u, v) in faces {
            mesh.append(&Self::quad(corner, u, v, material));
        }
        mesh
    }

    /// A UV sphere with `segments` longitudes and `segments / 2` latitudes,
    /// smooth normals and (longitude, latitude) texture coordinates.
    #[must_use]
    pub fn sphere(center: Vec3, radius: f32, segments: u32, material: usize) -> Self {
        let slices = segments.max(3);
        let stacks = (segments / 2).max(2);
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        for j in 0..=stacks {
            let theta = std::f32::consts::PI * j as f32 / stacks as f32;
            for i in 0..=slices {
                let phi = std::f32::consts::TAU * i as f32 / slices as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                positions.push(center + radius * n);
                normals.push(n);
                uvs.push(Vec2::new(i as f32 / slices as f32, j as f32 / stacks as f32));
            }
        }
        let row = slices + 1;
        let mut triangles = Vec::new();
        for j in 0..stacks {
            for i in 0..slices {
                let a = j * row + i;
                let b = a + row;
                // Skip the degenerate triangles at the poles.
                if j != 0 {
                    triangles.push([a, a + 1, b]);
                }
                if j + 1 != stacks {
                    triangles.push([a + 1, b + 1, b]);
                }
            }
        }
        Self { positions, normals: Some(normals), uvs: Some(uvs), triangles, material, ..Self::default() }
    }

    /// Appends another mesh's triangles (same material), keeping attributes
    /// only where both meshes have them.
    fn append(&mut self, other: &Self) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        match (&mut self.uvs, &other.uvs) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            _ => self.uvs = None,
        }
        match (&mut self.normals, &other.normals) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            _ => self.normals = None,
        }
        match (&mut self.colors, &other.colors) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            _ => self.colors = None,
        }
        match (&mut self.uvs1, &other.uvs1) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            _ => self.uvs1 = None,
        }
        match (&mut self.tangents, &other.tangents) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            _ => self.tangents = None,
        }
    }

    /// Loads every object of an OBJ file into one mesh, scaled then translated.
    pub fn load_obj(path: &Path, scale: f32, translate: Vec3, material: usize) -> Result<Self, SceneError> {
        let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
        let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| match locate_obj_error(path) {
            Some((line, message)) => SceneError::new(path, format!("line {line}"), message),
            None => SceneError::new(path, "OBJ", format!("cannot load mesh: {e}")),
        })?;
        let mut mesh = Self { material, ..Self::default() };
        let mut all_normals = true;
        let mut all_uvs = true;
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        for model in &models {
            let m = &model.mesh;
            let base = mesh.positions.len();
            let count = m.positions.len() / 3;
            for (i, p) in m.positions.chunks_exact(3).enumerate() {
                let v = Vec3::new(p[0], p[1], p[2]);
                if !v.is_finite() {
                    return Err(SceneError::new(
                        path,
                        format!("object '{}', vertex {}", model.name, i + 1),
                        "coordinate is not a finite number",
                    ));
                }
                mesh.positions.push(v * scale + translate);
            }
            if m.normals.len() == m.positions.len() {
                normals.extend(m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or_zero()));
            } else {
                all_normals = false;
            }
            if m.texcoords.len() / 2 == count {
                uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
            } else {
                all_uvs = false;
            }
            for (t, tri) in m.indices.chunks_exact(3).enumerate() {
                for &index in tri {
                    if index as usize >= count {
                        return Err(SceneError::new(
                            path,
                            format!("object '{}', face {}", model.name, t + 1),
                            format!("vertex index {} out of range (the object has {count} vertices)", index + 1),
                        ));
                    }
                }
                mesh.triangles.push([tri[0], tri[1], tri[2]].map(|i| i + base as u32));
            }
        }
        if mesh.triangles.is_empty() {
            return Err(SceneError::new(path, "OBJ", "the mesh has no faces"));
        }
        // Shading normals must be usable everywhere, or not at all.
        if all_normals && normals.iter().all(|n| n.is_finite() && *n != Vec3::ZERO) {
            mesh.normals = Some(normals);
        }
        if all_uvs && uvs.iter().all(|t| t.is_finite()) {
            mesh.uvs = Some(uvs);
        }
        Ok(mesh)
    }

    /// Axis-aligned bounds of the positions, grown by strands' radii:
    /// (min, max). (A cubic curve lies within its control points' hull,
    /// but for a Catmull-Rom curve's slight overshoot.)
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let radius = |i: usize| self.strands.as_ref().map_or(0.0, |s| s.radii[i]);
        self.positions
            .iter()
            .enumerate()
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), (i, &p)| {
                (lo.min(p - radius(i)), hi.max(p + radius(i)))
            })
    }
}

/// Finds the first line of an OBJ file that tobj would reject (tobj's errors
/// carry no position): vertex coordinates that are not numbers, and face
/// indices that are not integers or refer past the vertices defined so far.
/// Returns (1-based line, message).
fn locate_obj_error(path: &Path) -> Option<(usize, String)> {
    let bytes = std::fs::read(path).ok()?;
    let Ok(text) = std::str::from_utf8(&bytes) else {
        let line =
            bytes[..std::str::from_utf8(&bytes).err()?.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        return Some((line, "not UTF-8 text: not an OBJ file".into()));
    };
    let mut vertices = 0i64;
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let coordinates: Vec<&str> = words.collect();
                if coordinates.len() < 3 || coordinates.iter().any(|c| c.parse::<f32>().is_err()) {
                    return Some((number + 1, format!("vertex '{}' needs three numbers", line.trim())));
                }
                vertices += 1;
            }
            Some("f") => {
                let refs: Vec<&str> = words.collect();
                if refs.len() < 3 {
                    return Some((number + 1, format!("face '{}' needs at least three vertices", line.trim())));
                }
                for r in refs {
                    let index = r.split('/').next().unwrap_or("");
                    let Ok(i) = index.parse::<i64>() else {
                        return Some((number + 1, format!("face index '{index}' is not an integer")));
                    };
                    let resolved = if i < 0 { vertices + i + 1 } else { i };
                    if resolved < 1 || resolved > vertices {
                        return Some((
                            number + 1,
                            format!("face index {i} is out of range ({vertices} vertices defined so far)"),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing an edge (vertices 0 and 2) whose corners there
    /// disagree on the tangent's handedness (a mirrored-uv seam): the
    /// shared vertices split in two, attributes copied; corners that agree
    /// keep one vertex.
    #[test]
    fn corners_with_different_tangents_split_their_vertex() {
        let mut mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]),
            colors: Some(vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        };
        let (right, left) = (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(1.0, 0.0, 0.0, -1.0));
        mesh.set_corner_tangents(&[[right; 3], [left, left, left]]);
        assert_eq!(mesh.triangles, [[0, 1, 2], [4, 5, 3]]);
        assert_eq!(mesh.positions.len(), 6);
        assert_eq!((mesh.positions[4], mesh.positions[5]), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(mesh.uvs.as_ref().unwrap()[5], Vec2::ONE);
        assert_eq!(mesh.colors.as_ref().unwrap()[4], Vec3::X);
        assert_eq!(mesh.tangents.as_ref().unwrap(), &[right, right, right, left, left, left]);
        // Corners that agree share their vertex.
        let mut same =
            Mesh { triangles: vec![[0, 1, 2], [0, 2, 3]], positions: vec![Vec3::ZERO; 4], ..Mesh::default() };
        same.set_corner_tangents(&[[right; 3], [right; 3]]);
        assert_eq!((same.positions.len(), same.triangles[1]), (4, [0, 2, 3]));
    }

    #[test]
    fn obj_errors_name_their_line() {
        let dir = tempfile::tempdir().unwrap();
        for (name, text, expect) in [
            ("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "line 4"),
            ("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -7\n", "line 4"),
            ("text.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", "line 2"),
            ("face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4"),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            let e = Mesh::load_obj(&path, 1.0, Vec3::ZERO, 0).expect_err(name).to_string();
            assert!(e.contains(name) && e.contains(expect), "{e}");
        }
    }

    fn area(mesh: &Mesh) -> f32 {
        mesh.surface_area() as f32
    }

    #[test]
    fn generated_shapes_have_the_right_area_and_valid_indices() {
        let q = Mesh::quad(Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 3.0, 0);
        assert!((area(&q) - 6.0).abs() < 1e-5);
        let b = Mesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), 0);
        assert!((area(&b) - 22.0).abs() < 1e-4);
        assert_eq!(b.triangles.len(), 12);
        let s = Mesh::sphere(Vec3::ONE, 2.0, 96, 0);
        let exact = 4.0 * std::f32::consts::PI * 4.0;
        assert!((area(&s) - exact).abs() / exact < 0.01);
        for m in [&q, &b, &s] {
            assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
            assert_eq!(m.uvs.as_ref().unwrap().len(), m.positions.len());
        }
        for (p, n) in s.positions.iter().zip(s.normals.as_ref().unwrap()) {
            assert!(((*p - Vec3::ONE) / 2.0 - *n).length() < 1e-5);
        }
    }

    #[test]
    fn box_faces_point_outwards() {
        let b = Mesh::cuboid(Vec3::splat(-1.0), Vec3::splat(1.0), 0);
        for t in &b.triangles {
            let [p0, p1, p2] = t.map(|i| b.positions[i as usize]);
            let n = (p1 - p0).cross(p2 - p0);
            let centre = (p0 + p1 + p2) / 3.0;
            assert!(n.dot(centre) > 0.0, "face at {centre} points inwards");
        }
    }

    /// Each basis's tangent is the derivative of its curve: a central
    /// difference of the curve's points, evaluated from the basis
    /// functions written out, matches it at interior parameters, and the
    /// known end tangents hold (Bezier: 3 (P1 - P0); Catmull-Rom: (P2 -
    /// P0) / 2).
    #[test]
    fn a_curve_s_tangent_is_the_derivative_of_its_points() {
        let points =
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(3.0, 2.5, 1.0), Vec3::new(4.0, 0.0, 2.0)];
        let position = |basis: CurveBasis, u: f32| -> Vec3 {
            let s = 1.0 - u;
            let w = match basis {
                CurveBasis::Linear => [s, u, 0.0, 0.0],
                CurveBasis::Bezier => [s * s * s, 3.0 * u * s * s, 3.0 * u * u * s, u * u * u],
                CurveBasis::BSpline => [
                    s * s * s / 6.0,
                    (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0,
                    (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
                    u * u * u / 6.0,
                ],
                CurveBasis::CatmullRom => [
                    0.5 * (-u + 2.0 * u * u - u * u * u),
                    0.5 * (2.0 - 5.0 * u * u + 3.0 * u * u * u),
                    0.5 * (u + 4.0 * u * u - 3.0 * u * u * u),
                    0.5 * (-u * u + u * u * u),
                ],
            };
            points.iter().zip(w).map(|(p, w)| *p * w).sum()
        };
        for basis in [CurveBasis::Linear, CurveBasis::Bezier, CurveBasis::BSpline, CurveBasis::CatmullRom] {
            let strands =
                Strands { radii: vec![0.1; 4], kind: StrandKind::Curves { basis, ribbon: false, segments: vec![0] } };
            for u in [0.2f32, 0.5, 0.8] {
                let h = 1e-3;
                let difference = (position(basis, u + h) - position(basis, u - h)) / (2.0 * h);
                let tangent = strands.tangent(&points, 0, u).unwrap();
                assert!((tangent - difference).length() < 1e-2, "{basis:?} at {u}: {tangent} against {difference}");
            }
            let start = strands.tangent(&points, 0, 0.0).unwrap();
            match basis {
                CurveBasis::Bezier => assert_eq!(start, 3.0 * (points[1] - points[0])),
                CurveBasis::CatmullRom => assert_eq!(start, 0.5 * (points[2] - points[0])),
                _ => {}
            }
        }
        let spheres = Strands { radii: vec![0.1], kind: StrandKind::Spheres };
        assert_eq!(spheres.tangent(&points, 0, 0.5), None);
    }
}
