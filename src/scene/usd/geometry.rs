//! Geometry: `UsdGeomMesh` polygons fan-triangulated (holes left out,
//! `leftHanded` turned around), its normals, texture coordinates and
//! display colours read with their interpolation (`constant`, `uniform`,
//! `vertex`/`varying`, `faceVarying`) and indices, and split by
//! `GeomSubset`s of the `materialBind` family; and the intrinsic gprims
//! (`Sphere`, `Cube`, `Cylinder`, `Cone`, `Capsule`, `Plane`) tessellated.
//! Every mesh is in its prim's own space; the import places it.

use std::collections::HashSet;

use glam::{DVec2, DVec3, Vec2, Vec3};

use super::schema::Reader;
use super::stage::{Failure, Stage};
use crate::scene::mesh::Mesh;
use crate::scene::subdivision::{self, Boundary, Cage, Corner, Crease, Refinement, Scheme};

/// Where an error is: (prim.attribute, message).
pub(super) type Located = (String, Failure);

/// One material's part of a prim's surface: its mesh (in the prim's space)
/// and the `material:binding` of the subset it came from, if any.
pub(super) struct Piece {
    pub mesh: Mesh,
    /// The GeomSubset whose binding applies (None: the prim's own).
    pub subset: Option<String>,
}

/// Segments around a tessellated gprim (and its rings from pole to pole:
/// half as many): a sphere of 48 is within 0.2% of its true area.
const SEGMENTS: u32 = 48;

/// How a primvar's values map onto the mesh (UsdGeomPrimvar's
/// interpolation; `varying` is `vertex` for a polygon mesh).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Interpolation {
    Constant,
    Uniform,
    Vertex,
    FaceVarying,
}

/// A primvar's values with its indices: element k reads values[indices[k]]
/// (values[k] without indices).
struct Primvar<T> {
    values: Vec<T>,
    indices: Option<Vec<u32>>,
    interpolation: Interpolation,
}

impl<T: Copy> Primvar<T> {
    /// The value index at a face's corner: face `face`, corner number
    /// `corner` (in faceVertexIndices order), point `point`.
    fn index(&self, face: usize, corner: usize, point: usize) -> u32 {
        let element = match self.interpolation {
            Interpolation::Constant => 0,
            Interpolation::Uniform => face,
            Interpolation::Vertex => point,
            Interpolation::FaceVarying => corner,
        };
        self.indices.as_ref().map_or(element as u32, |i| i[element])
    }
}

/// The sizes a primvar's elements are checked against.
struct Counts {
    faces: usize,
    points: usize,
    corners: usize,
}

/// Reads primvar `name` (values, `:indices` and `interpolation`), checking
/// that it covers the mesh. `fallback` is the interpolation without
/// metadata (`normals`' is vertex).
fn primvar<T: Copy>(
    stage: &Stage,
    prim: &str,
    name: &str,
    time: f64,
    counts: &Counts,
    fallback: Interpolation,
    read: impl Fn(&Stage, &str, &str, f64) -> Result<Option<Vec<T>>, Failure>,
) -> Result<Option<Primvar<T>>, Located> {
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let Some(values) = read(stage, prim, name, time).map_err(|e| (at(name), e))? else { return Ok(None) };
    let interpolation = match stage.interpolation(prim, name).map_err(|e| (at(name), e))?.as_deref() {
        None => fallback,
        Some("constant") => Interpolation::Constant,
        Some("uniform") => Interpolation::Uniform,
        Some("vertex" | "varying") => Interpolation::Vertex,
        Some("faceVarying") => Interpolation::FaceVarying,
        Some(other) => return Err((at(name), format!("interpolation '{other}' is not a UsdGeom interpolation"))),
    };
    let elements = match interpolation {
        Interpolation::Constant => 1,
        Interpolation::Uniform => counts.faces,
        Interpolation::Vertex => counts.points,
        Interpolation::FaceVarying => counts.corners,
    };
    let indices_name = format!("{name}:indices");
    let indices = stage.ints(prim, &indices_name, time).map_err(|e| (at(&indices_name), e))?;
    let indices = match indices {
        None => {
            if values.len() < elements {
                return Err((
                    at(name),
                    format!("has {} values; its {interpolation:?} interpolation needs {elements}", values.len()),
                ));
            }
            None
        }
        Some(indices) => {
            if indices.len() < elements {
                return Err((
                    at(&indices_name),
                    format!("has {} indices; the {interpolation:?} interpolation needs {elements}", indices.len()),
                ));
            }
            if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= values.len()) {
                return Err((at(&indices_name), format!("index {bad} is outside the {} values", values.len())));
            }
            Some(indices.iter().map(|&i| i as u32).collect())
        }
    };
    if values.is_empty() {
        return Ok(None);
    }
    Ok(Some(Primvar { values, indices, interpolation }))
}

/// The primvars a mesh's shading reads.
pub(super) struct Wanted<'a> {
    /// The texture coordinates' primvar (`st`, or the material's reader's `varname`).
    pub st: &'a str,
    /// The primvar the material reads as its colour (a primvar reader's
    /// `varname`), and its value where the mesh lacks it; else
    /// `displayColor` (drawn where no material is bound).
    pub colour: Option<(&'a str, DVec3)>,
}

/// A `Mesh` prim's triangles, split by its materialBind subsets, and why
/// the mesh keeps its control polygons where it asks for subdivision and
/// cannot have it.
pub(super) fn mesh(
    stage: &Stage,
    prim: &str,
    time: f64,
    wanted: &Wanted<'_>,
) -> Result<(Vec<Piece>, Option<&'static str>), Located> {
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let read = Reader { stage, prim, schema: "Mesh", time };
    let points = stage.vec3s(prim, "points", time).map_err(|e| (at("points"), e))?.unwrap_or_default();
    let counts =
        stage.ints(prim, "faceVertexCounts", time).map_err(|e| (at("faceVertexCounts"), e))?.unwrap_or_default();
    let indices =
        stage.ints(prim, "faceVertexIndices", time).map_err(|e| (at("faceVertexIndices"), e))?.unwrap_or_default();
    check_points(prim, &points)?;
    if let Some((face, count)) = counts.iter().enumerate().find(|(_, &c)| c < 0) {
        return Err((at("faceVertexCounts"), format!("face {face}'s count is {count}: a count cannot be negative")));
    }
    let total: i64 = counts.iter().sum();
    if total != indices.len() as i64 {
        return Err((
            at("faceVertexCounts"),
            format!("the counts add up to {total}, but faceVertexIndices holds {} indices", indices.len()),
        ));
    }
    if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= points.len()) {
        return Err((at("faceVertexIndices"), format!("index {bad} is outside the {} points", points.len())));
    }
    let left_handed = match read.token("orientation")?.as_str() {
        "rightHanded" => false,
        "leftHanded" => true,
        other => return Err((at("orientation"), format!("must be rightHanded or leftHanded, got '{other}'"))),
    };
    let mut holes: HashSet<i64> = stage
        .ints(prim, "holeIndices", time)
        .map_err(|e| (at("holeIndices"), e))?
        .unwrap_or_default()
        .into_iter()
        .collect();
    let sizes = Counts { faces: counts.len(), points: points.len(), corners: indices.len() };
    let normals = match primvar(stage, prim, "primvars:normals", time, &sizes, Interpolation::Vertex, Stage::vec3s)? {
        Some(n) => Some(n),
        None => primvar(stage, prim, "normals", time, &sizes, Interpolation::Vertex, Stage::vec3s)?,
    };
    let st_name = format!("primvars:{}", wanted.st);
    let st = primvar(stage, prim, &st_name, time, &sizes, Interpolation::FaceVarying, Stage::vec2s)?;
    let colour_name =
        wanted.colour.map_or_else(|| "primvars:displayColor".to_string(), |(n, _)| format!("primvars:{n}"));
    let mut colors = primvar(stage, prim, &colour_name, time, &sizes, Interpolation::Constant, Stage::colours)?;
    if let (None, Some((_, fallback))) = (&colors, wanted.colour) {
        colors = Some(Primvar { values: vec![fallback], indices: None, interpolation: Interpolation::Constant });
    }
    // A primvar's values reach the film (a texture lookup, a colour): each
    // must be finite.
    let finite3 = |p: &Option<Primvar<DVec3>>| p.as_ref().is_none_or(|p| p.values.iter().all(|v| v.is_finite()));
    for (ok, name) in [
        (finite3(&normals), "primvars:normals"),
        (st.as_ref().is_none_or(|p| p.values.iter().all(|v| v.is_finite())), st_name.as_str()),
        (finite3(&colors), "primvars:displayColor"),
    ] {
        if !ok {
            return Err((at(name), "holds a value that is not finite".into()));
        }
    }

    let cage_faces = counts.len();
    let mut surface = Surface { points, counts, indices, normals, st, colors, parents: None };
    let kept_cage = subdivide(&read, &mut surface, &mut holes, left_handed)?;
    let subsets = material_subsets(stage, prim, time, cage_faces)?;
    Ok((split_by_subsets(&surface, cage_faces, &subsets, &holes, left_handed), kept_cage))
}

/// A mesh's polygons and the primvars its shading reads: as authored, or
/// its limit surface's.
struct Surface {
    points: Vec<DVec3>,
    counts: Vec<i64>,
    indices: Vec<i64>,
    normals: Option<Primvar<DVec3>>,
    st: Option<Primvar<DVec2>>,
    colors: Option<Primvar<DVec3>>,
    /// The authored face each face lies in (None: the faces are the authored ones).
    parents: Option<Vec<u32>>,
}

/// The surface's triangles, one piece per materialBind subset (an authored
/// face's subset) and one for the faces in none; holes left out.
fn split_by_subsets(
    surface: &Surface,
    authored_faces: usize,
    subsets: &[(String, Vec<usize>)],
    holes: &HashSet<i64>,
    left_handed: bool,
) -> Vec<Piece> {
    let Surface { points, counts, indices, normals, st, colors, parents } = surface;
    let authored = |f: usize| parents.as_ref().map_or(f, |p| p[f] as usize);
    let mut owner: Vec<Option<usize>> = vec![None; authored_faces];
    for (k, (_, faces)) in subsets.iter().enumerate() {
        for &f in faces {
            owner[f].get_or_insert(k);
        }
    }
    let mut starts = Vec::with_capacity(counts.len());
    let mut start = 0usize;
    for &c in counts {
        starts.push(start);
        start += c as usize;
    }
    let mut pieces = Vec::new();
    for group in (0..subsets.len()).map(Some).chain(std::iter::once(None)) {
        let mut builder = Builder::default();
        for face in (0..counts.len()).filter(|&f| owner[authored(f)] == group && !holes.contains(&(authored(f) as i64)))
        {
            let n = counts[face] as usize;
            if n < 3 {
                continue;
            }
            let corner = |builder: &mut Builder, k: usize| {
                let c = starts[face] + k;
                let point = indices[c] as usize;
                builder.vertex(
                    point,
                    [
                        normals.as_ref().map(|p| p.index(face, c, point)),
                        st.as_ref().map(|p| p.index(face, c, point)),
                        colors.as_ref().map(|p| p.index(face, c, point)),
                    ],
                )
            };
            let first = corner(&mut builder, 0);
            for k in 1..n - 1 {
                let (b, c) = (corner(&mut builder, k), corner(&mut builder, k + 1));
                builder.triangles.push(if left_handed { [first, c, b] } else { [first, b, c] });
            }
        }
        if builder.triangles.is_empty() {
            continue;
        }
        let mesh = builder.mesh(points, normals.as_ref(), st.as_ref(), colors.as_ref(), left_handed);
        pieces.push(Piece { mesh, subset: group.map(|k| subsets[k].0.clone()) });
    }
    pieces
}

/// Replaces a subdivision mesh's polygons by its limit surface (docs/design.md
/// §4.2): `subdivisionScheme`, `interpolateBoundary`,
/// `faceVaryingLinearInterpolation`, creases and corners as UsdGeomMesh
/// defines them. Authored normals are ignored, as USD says they are on a
/// subdivision surface: the limit surface's own are used. Returns why a
/// mesh asking for subdivision keeps its polygons, if it does.
fn subdivide(
    read: &Reader<'_>,
    surface: &mut Surface,
    holes: &mut HashSet<i64>,
    left_handed: bool,
) -> Result<Option<&'static str>, Located> {
    let at = |attribute: &str| format!("{}.{attribute}", read.prim);
    let scheme = match read.token("subdivisionScheme")?.as_str() {
        // A bilinear limit surface is the polygons (to within a non-planar
        // quad's bilinear patch against its two triangles).
        "none" | "bilinear" => return Ok(None),
        "catmullClark" => Scheme::CatmullClark,
        "loop" if surface.counts.iter().all(|&c| c == 3) => Scheme::Loop,
        "loop" => return Ok(Some("Loop subdivision asked of faces that are not all triangles")),
        other => {
            return Err((
                at("subdivisionScheme"),
                format!("must be catmullClark, loop, bilinear or none, got '{other}'"),
            ));
        }
    };
    if surface.counts.is_empty() {
        return Ok(None);
    }
    if surface.counts.iter().any(|&c| c < 3) {
        return Ok(Some("a face of fewer than three corners"));
    }
    let interpolate_boundary = read.token("interpolateBoundary")?;
    let boundary = match interpolate_boundary.as_str() {
        "edgeAndCorner" => Boundary::EdgeAndCorner,
        "edgeOnly" | "none" => Boundary::EdgeOnly,
        other => {
            return Err((at("interpolateBoundary"), format!("must be none, edgeOnly or edgeAndCorner, got '{other}'")));
        }
    };
    let (linear, face_varying_boundary) = match read.token("faceVaryingLinearInterpolation")?.as_str() {
        "all" => (true, Boundary::EdgeAndCorner),
        "none" => (false, Boundary::EdgeOnly),
        "boundaries" => (false, Boundary::Linear),
        "cornersOnly" | "cornersPlus1" | "cornersPlus2" => (false, Boundary::EdgeAndCorner),
        other => {
            return Err((
                at("faceVaryingLinearInterpolation"),
                format!("must be all, none, boundaries, cornersOnly, cornersPlus1 or cornersPlus2, got '{other}'"),
            ));
        }
    };
    let (creases, corners) = sharpness(read, surface.points.len())?;
    let cage = Cage {
        counts: surface.counts.iter().map(|&c| c as u32).collect(),
        indices: surface.indices.iter().map(|&i| i as u32).collect(),
        vertices: surface.points.len(),
        creases,
        corners,
        boundary,
        scheme,
    };
    if interpolate_boundary == "none" {
        // No boundary rule: the faces at a boundary only support their
        // neighbours (OpenSubdiv's VTX_BOUNDARY_NONE makes them holes).
        holes.extend(subdivision::boundary_faces(&cage).into_iter().map(|f| f as i64));
    }
    let levels = subdivision::levels_for(cage.counts.len());
    let refined = subdivision::refine(&cage, levels);
    let points = refined.limit(&surface.points);
    // A left-handed mesh winds the other way round its front.
    let sign = if left_handed { -1.0 } else { 1.0 };
    let (normals, corner_normals) = refined.corner_normals(&points);
    let normals = normals.into_iter().map(|n| n * sign).collect();
    let face_varying = FaceVarying {
        scheme: match (linear, scheme) {
            (true, Scheme::Loop) => Scheme::LoopLinear,
            (true, _) => Scheme::Bilinear,
            (false, s) => s,
        },
        boundary: face_varying_boundary,
        levels,
    };
    surface.normals =
        Some(Primvar { values: normals, indices: Some(corner_normals), interpolation: Interpolation::FaceVarying });
    surface.st = surface.st.take().map(|p| refined_primvar(p, &cage, &refined, &face_varying));
    surface.colors = surface.colors.take().map(|p| refined_primvar(p, &cage, &refined, &face_varying));
    surface.points = points;
    surface.counts = refined.counts.iter().map(|&c| i64::from(c)).collect();
    surface.indices = refined.indices.iter().map(|&i| i64::from(i)).collect();
    surface.parents = Some(refined.parents);
    Ok(None)
}

/// How face-varying data is refined: its scheme and boundary rule from
/// `faceVaryingLinearInterpolation`, and the mesh's depth.
struct FaceVarying {
    scheme: Scheme,
    boundary: Boundary,
    levels: u32,
}

/// A primvar carried onto the limit surface: a constant stays, a uniform
/// value follows its face, a vertex value is refined as the points are,
/// and face-varying values are refined on their own cage (the faces with
/// the value indices as vertices, so a seam is that cage's boundary).
fn refined_primvar<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>>(
    primvar: Primvar<T>,
    cage: &Cage,
    refined: &Refinement,
    face_varying: &FaceVarying,
) -> Primvar<T> {
    let value = |element: usize| primvar.values[primvar.indices.as_ref().map_or(element, |i| i[element] as usize)];
    match primvar.interpolation {
        Interpolation::Constant => primvar,
        Interpolation::Uniform => Primvar {
            values: refined.parents.iter().map(|&f| value(f as usize)).collect(),
            indices: None,
            interpolation: Interpolation::Uniform,
        },
        Interpolation::Vertex => {
            let values: Vec<T> = (0..cage.vertices).map(value).collect();
            Primvar { values: refined.limit(&values), indices: None, interpolation: Interpolation::Vertex }
        }
        Interpolation::FaceVarying => {
            let corners = cage.indices.len() as u32;
            let own = Cage {
                counts: cage.counts.clone(),
                indices: primvar.indices.clone().unwrap_or_else(|| (0..corners).collect()),
                vertices: primvar.values.len(),
                creases: Vec::new(),
                corners: Vec::new(),
                boundary: face_varying.boundary,
                scheme: face_varying.scheme,
            };
            let own_refined = subdivision::refine(&own, face_varying.levels);
            Primvar {
                values: own_refined.limit(&primvar.values),
                indices: Some(own_refined.indices),
                interpolation: Interpolation::FaceVarying,
            }
        }
    }
}

/// A mesh's creases (each edge of each crease with its sharpness) and
/// corners, checked: counts that disagree or indices past the points are
/// errors, as are sharpnesses that are not finite.
fn sharpness(read: &Reader<'_>, points: usize) -> Result<(Vec<Crease>, Vec<Corner>), Located> {
    let (stage, prim, time) = (read.stage, read.prim, read.time);
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let ints = |name: &str| stage.ints(prim, name, time).map_err(|e| (at(name), e)).map(Option::unwrap_or_default);
    let numbers =
        |name: &str| stage.numbers(prim, name, time).map_err(|e| (at(name), e)).map(Option::unwrap_or_default);
    let (indices, lengths, sharpnesses) =
        (ints("creaseIndices")?, ints("creaseLengths")?, numbers("creaseSharpnesses")?);
    let (corner_indices, corner_sharpnesses) = (ints("cornerIndices")?, numbers("cornerSharpnesses")?);
    for (name, values) in [("creaseIndices", &indices), ("cornerIndices", &corner_indices)] {
        if let Some(bad) = values.iter().find(|&&i| i < 0 || i as usize >= points) {
            return Err((at(name), format!("index {bad} is outside the {points} points")));
        }
    }
    for (name, values) in [("creaseSharpnesses", &sharpnesses), ("cornerSharpnesses", &corner_sharpnesses)] {
        if let Some(bad) = values.iter().find(|s| !s.is_finite()) {
            return Err((at(name), format!("a sharpness must be finite, got {bad}")));
        }
    }
    if let Some(bad) = lengths.iter().find(|&&l| l < 2) {
        return Err((at("creaseLengths"), format!("a crease runs through at least two points, got a length of {bad}")));
    }
    let total: i64 = lengths.iter().sum();
    if total != indices.len() as i64 {
        return Err((
            at("creaseLengths"),
            format!("the lengths add up to {total}, but creaseIndices holds {} indices", indices.len()),
        ));
    }
    let edges = (total - lengths.len() as i64) as usize;
    if sharpnesses.len() != lengths.len() && sharpnesses.len() != edges {
        return Err((
            at("creaseSharpnesses"),
            format!(
                "holds {} values: one per crease ({}) or one per crease edge ({edges})",
                sharpnesses.len(),
                lengths.len()
            ),
        ));
    }
    let mut creases = Vec::with_capacity(edges);
    let mut start = 0usize;
    for (k, &length) in lengths.iter().enumerate() {
        let run = &indices[start..start + length as usize];
        for pair in run.windows(2) {
            let s = if sharpnesses.len() == lengths.len() { sharpnesses[k] } else { sharpnesses[creases.len()] };
            creases.push(([pair[0] as u32, pair[1] as u32], s));
        }
        start += length as usize;
    }
    if corner_indices.len() != corner_sharpnesses.len() {
        return Err((
            at("cornerSharpnesses"),
            format!("holds {} values for {} cornerIndices", corner_sharpnesses.len(), corner_indices.len()),
        ));
    }
    let corners = corner_indices.iter().zip(&corner_sharpnesses).map(|(&v, &s)| (v as u32, s)).collect();
    Ok((creases, corners))
}

/// The mesh's GeomSubsets of the `materialBind` family (element type
/// `face`): each subset's path and faces.
fn material_subsets(stage: &Stage, prim: &str, time: f64, faces: usize) -> Result<Vec<(String, Vec<usize>)>, Located> {
    let mut subsets = Vec::new();
    for child in stage.children(prim).map_err(|e| (prim.to_string(), e))? {
        let info = stage.prim(&child).map_err(|e| (child.clone(), e))?;
        if info.type_name != "GeomSubset" || !info.present {
            continue;
        }
        let family = stage.token(&child, "familyName", time).map_err(|e| (format!("{child}.familyName"), e))?;
        let element = stage.token(&child, "elementType", time).map_err(|e| (format!("{child}.elementType"), e))?;
        if family.as_deref() != Some("materialBind") || element.as_deref().is_some_and(|e| e != "face") {
            continue;
        }
        let indices =
            stage.ints(&child, "indices", time).map_err(|e| (format!("{child}.indices"), e))?.unwrap_or_default();
        if let Some(bad) = indices.iter().find(|&&i| i < 0 || i as usize >= faces) {
            return Err((format!("{child}.indices"), format!("face {bad} is outside the mesh's {faces} faces")));
        }
        subsets.push((child, indices.into_iter().map(|i| i as usize).collect()));
    }
    Ok(subsets)
}

/// Vertices made unique by (point, normal, uv, colour) index, and triangles.
#[derive(Default)]
struct Builder {
    /// The point and primvar indices of each vertex.
    vertices: Vec<(usize, [Option<u32>; 3])>,
    known: rustc_hash::FxHashMap<(usize, [Option<u32>; 3]), u32>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, point: usize, primvars: [Option<u32>; 3]) -> u32 {
        let next = self.vertices.len() as u32;
        *self.known.entry((point, primvars)).or_insert_with(|| {
            self.vertices.push((point, primvars));
            next
        })
    }

    fn mesh(
        &self,
        points: &[DVec3],
        normals: Option<&Primvar<DVec3>>,
        st: Option<&Primvar<DVec2>>,
        colors: Option<&Primvar<DVec3>>,
        left_handed: bool,
    ) -> Mesh {
        let positions = self.vertices.iter().map(|&(p, _)| points[p].as_vec3()).collect();
        // A left-handed mesh's normals point the way its winding does once
        // turned around: they are kept as authored.
        let _ = left_handed;
        let normals = normals.map(|n| {
            self.vertices
                .iter()
                .map(|&(_, [k, _, _])| {
                    let v = n.values[k.unwrap_or(0) as usize].as_vec3();
                    v.try_normalize().unwrap_or(Vec3::Y)
                })
                .collect()
        });
        let uvs = st
            .map(|s| self.vertices.iter().map(|&(_, [_, k, _])| s.values[k.unwrap_or(0) as usize].as_vec2()).collect());
        let colors = colors.map(|c| {
            self.vertices
                .iter()
                .map(|&(_, [_, _, k])| c.values[k.unwrap_or(0) as usize].as_vec3().clamp(Vec3::ZERO, Vec3::splat(1e6)))
                .collect()
        });
        Mesh {
            positions,
            normals,
            uvs,
            uvs1: None,
            colors,
            tangents: None,
            triangles: self.triangles.clone(),
            material: 0,
            name: String::new(),
            strands: None,
        }
    }
}

/// MikkTSpace tangents for a normal-mapped mesh (its `uvs` hold USD's st,
/// v up the image; the tangent generator takes glTF's, v down).
pub(super) fn add_tangents(mesh: &mut Mesh) {
    let (Some(uvs), Some(normals)) = (&mesh.uvs, &mesh.normals) else { return };
    let down: Vec<Vec2> = uvs.iter().map(|uv| Vec2::new(uv.x, 1.0 - uv.y)).collect();
    match crate::scene::gltf::mikktspace_tangents(&mesh.positions, normals, &down, &mesh.triangles) {
        Some(crate::scene::gltf::Tangents::PerCorner(corners)) => mesh.set_corner_tangents(&corners),
        Some(crate::scene::gltf::Tangents::PerVertex(tangents)) => mesh.tangents = Some(tangents),
        None => {}
    }
}

/// The mesh an intrinsic gprim stands for, in its own space; None for a
/// type that is not one.
/// Every point of `prim` finite and within the scene's coordinate limit.
pub(super) fn check_points(prim: &str, points: &[DVec3]) -> Result<(), Located> {
    match points.iter().find(|p| !p.is_finite() || p.abs().max_element() > f64::from(crate::scene::MAX_COORDINATE)) {
        Some(p) => Err((
            format!("{prim}.points"),
            format!(
                "a point must be finite and within +/-{:e} (before the stage's metersPerUnit), got {p}",
                crate::scene::MAX_COORDINATE
            ),
        )),
        None => Ok(()),
    }
}

pub(super) fn gprim(stage: &Stage, prim: &str, type_name: &str, time: f64) -> Result<Option<Mesh>, Located> {
    let read = Reader { stage, prim, schema: type_name, time };
    let positive = |attribute: &str| -> Result<f32, Located> {
        let v = read.number(attribute)?;
        if v >= 0.0 && v <= f64::from(crate::scene::MAX_COORDINATE) {
            Ok(v as f32)
        } else {
            Err((
                format!("{prim}.{attribute}"),
                format!(
                    "must be from 0 to {:e} (before the stage's metersPerUnit), got {v}",
                    crate::scene::MAX_COORDINATE
                ),
            ))
        }
    };
    let axis = |read: &Reader<'_>| -> Result<usize, Located> {
        match read.token("axis")?.as_str() {
            "X" => Ok(0),
            "Y" => Ok(1),
            "Z" => Ok(2),
            other => Err((format!("{prim}.axis"), format!("must be X, Y or Z, got '{other}'"))),
        }
    };
    let mesh = match type_name {
        "Sphere" => Mesh::sphere(Vec3::ZERO, positive("radius")?, SEGMENTS, 0),
        "Cube" => {
            let h = 0.5 * positive("size")?;
            Mesh::cuboid(Vec3::splat(-h), Vec3::splat(h), 0)
        }
        "Cylinder" => {
            let (r, h) = (positive("radius")?, 0.5 * positive("height")?);
            along(lathe(&[(0.0, -h), (r, -h), (r, -h), (r, h), (r, h), (0.0, h)]), axis(&read)?)
        }
        "Cone" => {
            let (r, h) = (positive("radius")?, 0.5 * positive("height")?);
            along(lathe(&[(0.0, -h), (r, -h), (r, -h), (0.0, h)]), axis(&read)?)
        }
        "Capsule" => {
            let (r, h) = (positive("radius")?, 0.5 * positive("height")?);
            let quarter = (SEGMENTS / 4).max(2);
            let mut profile = Vec::new();
            for k in 0..=quarter {
                let a = std::f32::consts::FRAC_PI_2 * k as f32 / quarter as f32;
                profile.push((r * a.sin(), -h - r * a.cos()));
            }
            for k in 0..=quarter {
                let a = std::f32::consts::FRAC_PI_2 * k as f32 / quarter as f32;
                profile.push((r * a.cos(), h + r * a.sin()));
            }
            along(lathe(&profile), axis(&read)?)
        }
        "Plane" => {
            let (w, l) = (positive("width")?, positive("length")?);
            // Width along the first axis after `axis`, length along the second.
            let quad =
                Mesh::quad(Vec3::new(-0.5 * w, -0.5 * l, 0.0), Vec3::new(w, 0.0, 0.0), Vec3::new(0.0, l, 0.0), 0);
            along(quad, axis(&read)?)
        }
        _ => return Ok(None),
    };
    Ok(Some(mesh))
}

/// A surface of revolution about z through the profile's (radius, z)
/// points, from the first to the last; consecutive equal points make a
/// crease (flat shading across it). Normals point away from the axis.
fn lathe(profile: &[(f32, f32)]) -> Mesh {
    let mut mesh = Mesh::default();
    let (mut positions, mut normals, mut uvs, mut triangles) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for s in 0..profile.len() - 1 {
        let (a, b) = (profile[s], profile[s + 1]);
        if a == b {
            continue;
        }
        // The segment's outward normal in the (radius, z) plane.
        let (dr, dz) = (b.0 - a.0, b.1 - a.1);
        let n = Vec2::new(dz, -dr).normalize();
        let base = positions.len() as u32;
        for i in 0..=SEGMENTS {
            let phi = std::f32::consts::TAU * i as f32 / SEGMENTS as f32;
            let (c, s_) = (phi.cos(), phi.sin());
            for (r, z) in [a, b] {
                positions.push(Vec3::new(r * c, r * s_, z));
                normals.push(Vec3::new(n.x * c, n.x * s_, n.y));
                uvs.push(Vec2::new(
                    i as f32 / SEGMENTS as f32,
                    (s as f32 + f32::from(u8::from(z == b.1))) / (profile.len() - 1) as f32,
                ));
            }
        }
        for i in 0..SEGMENTS {
            let (p0, p1, q0, q1) = (base + 2 * i, base + 2 * i + 1, base + 2 * i + 2, base + 2 * i + 3);
            triangles.push([p0, q0, q1]);
            triangles.push([p0, q1, p1]);
        }
    }
    // The triangles that meet at the axis with two corners there have no area.
    let area = |t: &[u32; 3]| crate::util::triangle::area(t.map(|i| positions[i as usize]));
    mesh.triangles = triangles.into_iter().filter(|t| area(t) > 0.0).collect();
    mesh.positions = positions;
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    mesh
}

/// A mesh built along z turned to lie along axis `axis` (0 = x, 1 = y, 2 =
/// z), as UsdGeom's `axis` (a cyclic permutation, so winding is kept).
fn along(mut mesh: Mesh, axis: usize) -> Mesh {
    let turn = |v: Vec3| match axis {
        0 => Vec3::new(v.z, v.x, v.y),
        1 => Vec3::new(v.y, v.z, v.x),
        _ => v,
    };
    for p in &mut mesh.positions {
        *p = turn(*p);
    }
    if let Some(normals) = &mut mesh.normals {
        for n in normals {
            *n = turn(*n);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed surface's area and its normals' orientation: the lathe's
    /// cylinder has the area 2 pi r h + 2 pi r^2 of a cylinder, within the
    /// polygon's, and every triangle faces away from the axis.
    #[test]
    fn a_lathed_cylinder_is_closed_and_faces_out() {
        let (r, h) = (1.0f32, 1.0f32);
        let mesh = lathe(&[(0.0, -h), (r, -h), (r, -h), (r, h), (r, h), (0.0, h)]);
        let polygon = 0.5 * SEGMENTS as f64 * (std::f64::consts::TAU / f64::from(SEGMENTS)).sin();
        let want = polygon * 2.0 + (2.0 * SEGMENTS as f64 * (std::f64::consts::PI / f64::from(SEGMENTS)).sin()) * 2.0;
        assert!((mesh.surface_area() - want).abs() < 1e-4 * want, "{} vs {want}", mesh.surface_area());
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0;
            let out = if centre.z.abs() > 0.99 * h { Vec3::new(0.0, 0.0, centre.z) } else { centre.with_z(0.0) };
            assert!(n.dot(out) > 0.0, "a triangle faces the axis at {centre}");
        }
    }

    #[test]
    fn along_turns_z_onto_the_axis() {
        let mesh = Mesh { positions: vec![Vec3::Z], ..Mesh::default() };
        assert_eq!(along(mesh.clone(), 0).positions[0], Vec3::X);
        assert_eq!(along(mesh, 1).positions[0], Vec3::Y);
    }
}
