//! Subdivision surfaces (docs/design.md §4.2): a polygon cage refined a few
//! times by Catmull-Clark's rules (Loop's for a triangle cage), with
//! semi-sharp and infinitely sharp creases and corners and USD's boundary
//! rules, then every vertex pushed to its place on the limit surface. The
//! result is a polygon mesh whose vertices lie on the limit surface, with
//! per-corner normals smooth everywhere but across a crease.
//!
//! Every step is linear in the cage's values, so a refinement is kept as
//! stencils (new value = sum of weights x old values) and applied alike to
//! the points and to every vertex-interpolated primvar.

use rustc_hash::FxHashMap as HashMap;
use std::ops::{Add, Mul};

use glam::DVec3;

/// USD's `subdivisionScheme` values (and OpenSubdiv's schemes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Catmull and Clark 1978: any polygons, quads after one step.
    CatmullClark,
    /// Loop 1987: triangles only, triangles after each step.
    Loop,
    /// Linear interpolation: faces split as Catmull-Clark's are, every new
    /// vertex the average of what it splits (face-varying data kept linear).
    Bilinear,
    /// Linear interpolation on Loop's split (a Loop mesh's face-varying data).
    LoopLinear,
}

impl Scheme {
    fn linear(self) -> bool {
        matches!(self, Self::Bilinear | Self::LoopLinear)
    }
}

/// USD's `interpolateBoundary` (and, for face-varying data, what
/// `faceVaryingLinearInterpolation` makes of a boundary).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// Boundary edges are infinitely sharp creases.
    EdgeOnly,
    /// Boundary edges are creases and a boundary vertex of one face is an
    /// infinitely sharp corner (USD's default).
    EdgeAndCorner,
    /// Every boundary vertex is a corner: the boundary stays piecewise
    /// linear (face-varying `boundaries`).
    Linear,
}

/// The sharpness at or above which a crease never softens (USD's and
/// OpenSubdiv's "infinitely sharp", `Sdc::Crease::SHARPNESS_INFINITE`).
pub const INFINITELY_SHARP: f64 = 10.0;

/// An edge (its two vertices, either order) and its sharpness.
pub type Crease = ([u32; 2], f64);
/// A vertex and its corner sharpness.
pub type Corner = (u32, f64);

/// A polygon cage: faces as vertex counts and indices, with sharpness tags.
#[derive(Debug, Clone)]
pub struct Cage {
    pub counts: Vec<u32>,
    pub indices: Vec<u32>,
    pub vertices: usize,
    /// Edges (either vertex order) and their sharpness (>= INFINITELY_SHARP: for ever).
    pub creases: Vec<Crease>,
    /// Vertices and their corner sharpness.
    pub corners: Vec<Corner>,
    pub boundary: Boundary,
    pub scheme: Scheme,
}

/// New values as weighted sums of old ones, one row per new value.
#[derive(Debug, Clone, Default)]
struct Stencils {
    offsets: Vec<u32>,
    entries: Vec<(u32, f64)>,
}

impl Stencils {
    fn row(&mut self, entries: impl IntoIterator<Item = (u32, f64)>) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.entries.extend(entries);
        self.offsets.push(self.entries.len() as u32);
    }

    fn apply<T: Copy + Add<Output = T> + Mul<f64, Output = T>>(&self, old: &[T]) -> Vec<T> {
        self.offsets
            .windows(2)
            .map(|w| {
                let row = &self.entries[w[0] as usize..w[1] as usize];
                let (&(first, weight), rest) = row.split_first().expect("a stencil row is never empty");
                rest.iter().fold(old[first as usize] * weight, |sum, &(i, w)| sum + old[i as usize] * w)
            })
            .collect()
    }
}

/// A refined cage: its faces (each traced to the cage face it came from),
/// and the stencils that carry the cage's values to the limit surface.
#[derive(Debug, Clone)]
pub struct Refinement {
    pub counts: Vec<u32>,
    pub indices: Vec<u32>,
    /// The cage face each refined face lies in.
    pub parents: Vec<u32>,
    /// The refined mesh's edges: the corners along each, and whether each
    /// is still sharp (a boundary, or a crease not yet worn down) after the
    /// last step.
    edge_corners: Csr,
    edge_sharp: Vec<bool>,
    steps: Vec<Stencils>,
    limit: Stencils,
}

impl Refinement {
    /// The values at the refined vertices' limit positions, from the cage's.
    #[must_use]
    pub fn limit<T: Copy + Add<Output = T> + Mul<f64, Output = T>>(&self, cage: &[T]) -> Vec<T> {
        let mut values = cage.to_vec();
        for step in &self.steps {
            values = step.apply(&values);
        }
        self.limit.apply(&values)
    }

    /// Unit normals from the limit points, and each refined face corner's
    /// (in `indices` order): the area-weighted average of the faces around
    /// the vertex that no sharp edge parts from this corner's face, so
    /// corners that share a normal share its index.
    #[must_use]
    pub fn corner_normals(&self, points: &[DVec3]) -> (Vec<DVec3>, Vec<u32>) {
        let starts = starts(&self.counts);
        let mut next = vec![0u32; self.indices.len()];
        let mut face_normals = Vec::with_capacity(self.counts.len());
        for (f, &count) in self.counts.iter().enumerate() {
            let corners = starts[f]..starts[f] + count as usize;
            // Newell's normal: twice the area along the face's normal.
            let mut n = DVec3::ZERO;
            for c in corners.clone() {
                let d = if c + 1 == corners.end { corners.start } else { c + 1 };
                next[c] = d as u32;
                n += points[self.indices[c] as usize].cross(points[self.indices[d] as usize]);
            }
            face_normals.push(n);
        }
        // Corners joined across every smooth edge their faces share.
        let mut groups = UnionFind::new(self.indices.len());
        for (e, &sharp) in self.edge_sharp.iter().enumerate() {
            let along = self.edge_corners.get(e);
            if sharp || along.len() != 2 {
                continue;
            }
            let (c0, c1) = (along[0] as usize, along[1] as usize);
            for a in [c0, next[c0] as usize] {
                for b in [c1, next[c1] as usize] {
                    if self.indices[a] == self.indices[b] {
                        groups.join(a, b);
                    }
                }
            }
        }
        let mut sums = vec![DVec3::ZERO; self.indices.len()];
        for (f, &count) in self.counts.iter().enumerate() {
            for corner in starts[f]..starts[f] + count as usize {
                sums[groups.root(corner)] += face_normals[f];
            }
        }
        let mut normal_of_root = vec![u32::MAX; self.indices.len()];
        let mut normals = Vec::new();
        let mut corner_normal = Vec::with_capacity(self.indices.len());
        for (f, &count) in self.counts.iter().enumerate() {
            for corner in starts[f]..starts[f] + count as usize {
                let root = groups.root(corner);
                if normal_of_root[root] == u32::MAX {
                    normal_of_root[root] = normals.len() as u32;
                    let n = sums[root].try_normalize().or_else(|| face_normals[f].try_normalize());
                    normals.push(n.unwrap_or(DVec3::Z));
                }
                corner_normal.push(normal_of_root[root]);
            }
        }
        (normals, corner_normal)
    }
}

fn starts(counts: &[u32]) -> Vec<usize> {
    let mut start = 0;
    counts
        .iter()
        .map(|&c| {
            let s = start;
            start += c as usize;
            s
        })
        .collect()
}

fn sorted(a: u32, b: u32) -> [u32; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        Self((0..n).collect())
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }

    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        // The smaller root wins, so the grouping is the same whatever the order.
        let (low, high) = if ra < rb { (ra, rb) } else { (rb, ra) };
        self.0[high] = low;
    }
}

/// Lists of items per key, stored flat (compressed rows).
#[derive(Debug, Clone, Default)]
struct Csr {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl Csr {
    /// From (key, item) pairs, keys below `keys`; each key's items in the
    /// pairs' order.
    fn new(keys: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Self {
        let mut offsets = vec![0u32; keys + 1];
        for (k, _) in pairs.clone() {
            offsets[k as usize + 1] += 1;
        }
        for k in 0..keys {
            offsets[k + 1] += offsets[k];
        }
        let mut fill = offsets.clone();
        let mut items = vec![0u32; offsets[keys] as usize];
        for (k, item) in pairs {
            items[fill[k as usize] as usize] = item;
            fill[k as usize] += 1;
        }
        Self { offsets, items }
    }

    fn get(&self, key: usize) -> &[u32] {
        &self.items[self.offsets[key] as usize..self.offsets[key + 1] as usize]
    }
}

/// A level of the refinement: its faces and what is sharp on it.
struct Level {
    counts: Vec<u32>,
    indices: Vec<u32>,
    vertices: usize,
    /// Sharpness per edge (f64::INFINITY: for ever); absent edges are smooth.
    crease: HashMap<[u32; 2], f64>,
    corner: Vec<f64>,
}

/// A level's adjacency.
struct Topology {
    starts: Vec<usize>,
    /// The face of each corner.
    corner_face: Vec<u32>,
    /// Edges in order of their (sorted) vertex pairs.
    edges: Vec<[u32; 2]>,
    /// Each face corner's edge (to the next corner).
    corner_edge: Vec<u32>,
    /// The corners whose edge each edge is (one per face along it).
    edge_corners: Csr,
    vertex_edges: Csr,
    /// The corners at each vertex (one per face around it).
    vertex_corners: Csr,
    /// Each edge's sharpness, boundaries and non-manifold edges infinite.
    sharpness: Vec<f64>,
}

impl Topology {
    fn new(level: &Level) -> Self {
        let starts = starts(&level.counts);
        let mut corner_face = Vec::with_capacity(level.indices.len());
        let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(level.indices.len());
        for (f, &count) in level.counts.iter().enumerate() {
            let corners = &level.indices[starts[f]..starts[f] + count as usize];
            for (k, &a) in corners.iter().enumerate() {
                let [lo, hi] = sorted(a, corners[(k + 1) % corners.len()]);
                keyed.push(((u64::from(lo) << 32) | u64::from(hi), (starts[f] + k) as u32));
                corner_face.push(f as u32);
            }
        }
        keyed.sort_unstable();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut corner_edge = vec![0u32; level.indices.len()];
        let mut edge_of_keyed = Vec::with_capacity(keyed.len());
        for (i, &(key, corner)) in keyed.iter().enumerate() {
            if i == 0 || keyed[i - 1].0 != key {
                edges.push([(key >> 32) as u32, key as u32]);
            }
            corner_edge[corner as usize] = edges.len() as u32 - 1;
            edge_of_keyed.push((edges.len() as u32 - 1, corner));
        }
        let edge_corners = Csr::new(edges.len(), edge_of_keyed.iter().copied());
        let vertex_edges =
            Csr::new(level.vertices, edges.iter().enumerate().flat_map(|(e, &[a, b])| [(a, e as u32), (b, e as u32)]));
        let vertex_corners = Csr::new(level.vertices, level.indices.iter().enumerate().map(|(c, &v)| (v, c as u32)));
        let sharpness = edges
            .iter()
            .enumerate()
            .map(|(e, key)| {
                if edge_corners.get(e).len() != 2 {
                    f64::INFINITY
                } else if level.crease.is_empty() {
                    0.0
                } else {
                    level.crease.get(key).copied().unwrap_or(0.0)
                }
            })
            .collect();
        Self { starts, corner_face, edges, corner_edge, edge_corners, vertex_edges, vertex_corners, sharpness }
    }

    fn face<'a>(&self, level: &'a Level, f: u32) -> &'a [u32] {
        let start = self.starts[f as usize];
        &level.indices[start..start + level.counts[f as usize] as usize]
    }

    fn other_end(&self, e: u32, v: u32) -> u32 {
        let [a, b] = self.edges[e as usize];
        if a == v {
            b
        } else {
            a
        }
    }
}

/// How a vertex moves (OpenSubdiv's `Sdc::Crease::Rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rule {
    Smooth,
    /// Along its two sharp edges.
    Crease([u32; 2]),
    Corner,
}

/// The rule for vertex `v` when edges sharper than `above` count as sharp
/// and its corner sharpness is `corner`.
fn rule(topology: &Topology, v: u32, corner: f64, above: f64) -> Rule {
    let mut sharp = 0;
    let mut ends = [v; 2];
    for &e in topology.vertex_edges.get(v as usize) {
        if topology.sharpness[e as usize] > above {
            if sharp < 2 {
                ends[sharp] = topology.other_end(e, v);
            }
            sharp += 1;
        }
    }
    if corner > above || sharp > 2 {
        Rule::Corner
    } else if sharp == 2 {
        Rule::Crease(ends)
    } else {
        Rule::Smooth
    }
}

/// Refines `cage` `levels` times and ends on the limit surface.
#[must_use]
pub fn refine(cage: &Cage, levels: u32) -> Refinement {
    let mut level = Level {
        counts: cage.counts.clone(),
        indices: cage.indices.clone(),
        vertices: cage.vertices,
        crease: HashMap::default(),
        corner: vec![0.0; cage.vertices],
    };
    let as_sharpness = |s: f64| if s >= INFINITELY_SHARP { f64::INFINITY } else { s.max(0.0) };
    for &([a, b], s) in &cage.creases {
        if a != b && s > 0.0 {
            level.crease.insert(sorted(a, b), as_sharpness(s));
        }
    }
    for &(v, s) in &cage.corners {
        if let Some(c) = level.corner.get_mut(v as usize) {
            *c = c.max(as_sharpness(s));
        }
    }
    let mut topology = Topology::new(&level);
    mark_boundary_corners(&mut level, &topology, cage.boundary);
    let mut parents: Vec<u32> = (0..level.counts.len() as u32).collect();
    let mut steps = Vec::new();
    for _ in 0..levels {
        let (next, stencils, children) = match cage.scheme {
            Scheme::Loop | Scheme::LoopLinear => split_triangles(&level, &topology, cage.scheme),
            Scheme::CatmullClark | Scheme::Bilinear => split_quads(&level, &topology, cage.scheme),
        };
        parents = children.iter().map(|&c| parents[c as usize]).collect();
        steps.push(stencils);
        level = next;
        topology = Topology::new(&level);
    }
    let limit = limit_stencils(&level, &topology, cage.scheme);
    let edge_sharp = topology.sharpness.iter().map(|&s| s > 0.0).collect();
    Refinement {
        counts: level.counts,
        indices: level.indices,
        parents,
        edge_corners: topology.edge_corners,
        edge_sharp,
        steps,
        limit,
    }
}

/// USD's boundary rules: `edgeAndCorner` makes a boundary vertex of one
/// face a corner; face-varying `boundaries` makes every boundary vertex one.
fn mark_boundary_corners(level: &mut Level, topology: &Topology, boundary: Boundary) {
    if boundary == Boundary::EdgeOnly {
        return;
    }
    for v in 0..level.vertices {
        let edges = topology.vertex_edges.get(v);
        let on_boundary = edges.iter().any(|&e| topology.edge_corners.get(e as usize).len() == 1);
        let single_face = topology.vertex_corners.get(v).len() == 1;
        if on_boundary && (boundary == Boundary::Linear || single_face) {
            level.corner[v] = f64::INFINITY;
        }
    }
}

/// The faces of `cage` with a vertex on its boundary (an edge of one face).
#[must_use]
pub fn boundary_faces(cage: &Cage) -> Vec<usize> {
    let level = Level {
        counts: cage.counts.clone(),
        indices: cage.indices.clone(),
        vertices: cage.vertices,
        crease: HashMap::default(),
        corner: Vec::new(),
    };
    let topology = Topology::new(&level);
    let mut on_boundary = vec![false; cage.vertices];
    for (e, edge) in topology.edges.iter().enumerate() {
        if topology.edge_corners.get(e).len() == 1 {
            on_boundary[edge[0] as usize] = true;
            on_boundary[edge[1] as usize] = true;
        }
    }
    (0..cage.counts.len() as u32)
        .filter(|&f| topology.face(&level, f).iter().any(|&v| on_boundary[v as usize]))
        .map(|f| f as usize)
        .collect()
}

/// Appends to `row` the stencil of a rule at vertex `v` under `scheme`'s
/// smooth rule, its weights times `scale`.
fn vertex_row(
    level: &Level,
    topology: &Topology,
    v: u32,
    rule: Rule,
    scheme: Scheme,
    scale: f64,
    row: &mut Vec<(u32, f64)>,
) {
    let edges = topology.vertex_edges.get(v as usize);
    if scheme.linear() || edges.is_empty() {
        // A point no face uses stays where it is.
        row.push((v, scale));
        return;
    }
    match (rule, scheme) {
        (Rule::Corner, _) | (_, Scheme::Bilinear | Scheme::LoopLinear) => row.push((v, scale)),
        (Rule::Crease([a, b]), _) => row.extend([(v, 0.75 * scale), (a, 0.125 * scale), (b, 0.125 * scale)]),
        (Rule::Smooth, Scheme::Loop) => {
            let n = edges.len() as f64;
            let beta = loop_beta(edges.len());
            row.push((v, (1.0 - n * beta) * scale));
            row.extend(edges.iter().map(|&e| (topology.other_end(e, v), beta * scale)));
        }
        (Rule::Smooth, Scheme::CatmullClark) => {
            // (F + 2R + (n - 3) v) / n: F the mean of the face points, R of
            // the edge midpoints (Catmull and Clark 1978).
            let corners = topology.vertex_corners.get(v as usize);
            let n = edges.len() as f64;
            row.push((v, (n - 3.0) / n * scale));
            for &c in corners {
                let face = topology.face(level, topology.corner_face[c as usize]);
                let w = scale / (n * corners.len() as f64 * face.len() as f64);
                row.extend(face.iter().map(|&u| (u, w)));
            }
            for &e in edges {
                let [a, b] = topology.edges[e as usize];
                row.extend([(a, scale / (n * n)), (b, scale / (n * n))]);
            }
        }
    }
}

/// Loop's smooth vertex weight for valence n: (5/8 - (3/8 + cos(2 pi/n)/4)^2) / n.
fn loop_beta(valence: usize) -> f64 {
    let n = valence.max(1) as f64;
    let c = 0.375 + 0.25 * (std::f64::consts::TAU / n).cos();
    (0.625 - c * c) / n
}

/// Appends to `row` the stencil of a vertex's new position: its rule,
/// blended with the rule it takes after this step where a crease wears out
/// part-way (OpenSubdiv's fractional weight: the mean sharpness of what
/// wears out).
fn vertex_point(level: &Level, topology: &Topology, v: u32, scheme: Scheme, row: &mut Vec<(u32, f64)>) {
    let corner = level.corner[v as usize];
    let before = rule(topology, v, corner, 0.0);
    let after = rule(topology, v, corner, 1.0);
    if before == after || before == Rule::Smooth {
        vertex_row(level, topology, v, before, scheme, 1.0, row);
        return;
    }
    let (mut sum, mut count) = (0.0, 0usize);
    for &e in topology.vertex_edges.get(v as usize) {
        let s = topology.sharpness[e as usize];
        if s > 0.0 && s <= 1.0 {
            sum += s;
            count += 1;
        }
    }
    if corner > 0.0 && corner <= 1.0 {
        sum += corner;
        count += 1;
    }
    let w = if count == 0 { 1.0 } else { sum / count as f64 };
    vertex_row(level, topology, v, before, scheme, w, row);
    vertex_row(level, topology, v, after, scheme, 1.0 - w, row);
}

/// Appends to `row` an edge's new point: the midpoint where sharp, the
/// scheme's smooth rule where smooth, blended by the sharpness in between.
fn edge_point(level: &Level, topology: &Topology, e: u32, scheme: Scheme, row: &mut Vec<(u32, f64)>) {
    let [a, b] = topology.edges[e as usize];
    let s = topology.sharpness[e as usize].min(1.0);
    if s >= 1.0 || scheme.linear() {
        row.extend([(a, 0.5), (b, 0.5)]);
        return;
    }
    row.extend([(a, 0.5 * s), (b, 0.5 * s)]);
    let smooth = 1.0 - s;
    let along = topology.edge_corners.get(e as usize);
    match scheme {
        Scheme::Loop => {
            row.extend([(a, 0.375 * smooth), (b, 0.375 * smooth)]);
            for &c in along {
                let face = topology.face(level, topology.corner_face[c as usize]);
                let opposite = face.iter().copied().find(|&u| u != a && u != b).unwrap_or(a);
                row.push((opposite, 0.125 * smooth));
            }
        }
        _ => {
            row.extend([(a, 0.25 * smooth), (b, 0.25 * smooth)]);
            for &c in along {
                let face = topology.face(level, topology.corner_face[c as usize]);
                let w = 0.25 * smooth / face.len() as f64;
                row.extend(face.iter().map(|&u| (u, w)));
            }
        }
    }
}

/// The sharpness a child edge inherits (USD's `uniform` crease method).
fn worn(s: f64) -> f64 {
    (s - 1.0).max(0.0)
}

/// The child level's creases: each half of a parent edge keeps its sharpness less one.
fn child_creases(topology: &Topology, level: &Level, edge_vertex: impl Fn(u32) -> u32) -> HashMap<[u32; 2], f64> {
    let mut crease = HashMap::default();
    if level.crease.is_empty() {
        return crease;
    }
    for (e, key) in topology.edges.iter().enumerate() {
        let s = level.crease.get(key).copied().unwrap_or(0.0);
        if s > 1.0 {
            let mid = edge_vertex(e as u32);
            crease.insert(sorted(key[0], mid), worn(s));
            crease.insert(sorted(mid, key[1]), worn(s));
        }
    }
    crease
}

/// The rows of a step's vertex points (then face points, then edge points).
fn vertex_and_edge_rows(level: &Level, topology: &Topology, scheme: Scheme, stencils: &mut Stencils, faces: bool) {
    let mut row = Vec::new();
    for v in 0..level.vertices as u32 {
        row.clear();
        vertex_point(level, topology, v, scheme, &mut row);
        stencils.row(row.iter().copied());
    }
    if faces {
        for f in 0..level.counts.len() as u32 {
            let corners = topology.face(level, f);
            let w = 1.0 / corners.len() as f64;
            stencils.row(corners.iter().map(|&u| (u, w)));
        }
    }
    for e in 0..topology.edges.len() as u32 {
        row.clear();
        edge_point(level, topology, e, scheme, &mut row);
        stencils.row(row.iter().copied());
    }
}

/// One Catmull-Clark (or bilinear) step: vertex points keep their indices,
/// then one point per face, then one per edge; a face of n corners becomes
/// n quads (corner, next edge, face, previous edge), in face order.
fn split_quads(level: &Level, topology: &Topology, scheme: Scheme) -> (Level, Stencils, Vec<u32>) {
    let (nv, nf) = (level.vertices as u32, level.counts.len() as u32);
    let mut stencils = Stencils::default();
    vertex_and_edge_rows(level, topology, scheme, &mut stencils, true);
    let edge_vertex = |e: u32| nv + nf + e;
    let mut counts = Vec::with_capacity(level.indices.len());
    let mut indices = Vec::with_capacity(4 * level.indices.len());
    let mut children = Vec::with_capacity(level.indices.len());
    for f in 0..nf {
        let start = topology.starts[f as usize];
        let n = level.counts[f as usize] as usize;
        for k in 0..n {
            let previous = topology.corner_edge[start + (k + n - 1) % n];
            let next = topology.corner_edge[start + k];
            indices.extend([level.indices[start + k], edge_vertex(next), nv + f, edge_vertex(previous)]);
            counts.push(4);
            children.push(f);
        }
    }
    let vertices = (nv + nf) as usize + topology.edges.len();
    let mut corner: Vec<f64> = level.corner.iter().map(|&c| worn(c)).collect();
    corner.resize(vertices, 0.0);
    let crease = child_creases(topology, level, edge_vertex);
    (Level { counts, indices, vertices, crease, corner }, stencils, children)
}

/// One Loop step: vertex points keep their indices, then one point per
/// edge; a triangle becomes its three corner triangles and the middle one.
fn split_triangles(level: &Level, topology: &Topology, scheme: Scheme) -> (Level, Stencils, Vec<u32>) {
    let nv = level.vertices as u32;
    let mut stencils = Stencils::default();
    vertex_and_edge_rows(level, topology, scheme, &mut stencils, false);
    let edge_vertex = |e: u32| nv + e;
    let mut counts = Vec::new();
    let mut indices = Vec::new();
    let mut children = Vec::new();
    for f in 0..level.counts.len() {
        let start = topology.starts[f];
        let [v0, v1, v2] = [0, 1, 2].map(|k| level.indices[start + k]);
        let [e0, e1, e2] = [0, 1, 2].map(|k| edge_vertex(topology.corner_edge[start + k]));
        for triangle in [[v0, e0, e2], [v1, e1, e0], [v2, e2, e1], [e0, e1, e2]] {
            indices.extend(triangle);
            counts.push(3);
            children.push(f as u32);
        }
    }
    let vertices = nv as usize + topology.edges.len();
    let mut corner: Vec<f64> = level.corner.iter().map(|&c| worn(c)).collect();
    corner.resize(vertices, 0.0);
    let crease = child_creases(topology, level, edge_vertex);
    (Level { counts, indices, vertices, crease, corner }, stencils, children)
}

/// The limit positions of a refined level's vertices: a corner stays, a
/// crease vertex takes the cubic B-spline's (a + 4v + b)/6, a smooth vertex
/// of valence n on a quad mesh (n^2 v + 4 sum e_i + sum d_i) / (n (n + 5))
/// (Halstead et al. 1993, e_i its edge neighbours and d_i the far corners
/// of its quads), and on a Loop mesh (1 - n chi) v + chi sum e_i with
/// chi = 1 / (3 / (8 beta) + n).
fn limit_stencils(level: &Level, topology: &Topology, scheme: Scheme) -> Stencils {
    let mut stencils = Stencils::default();
    let mut row = Vec::new();
    for v in 0..level.vertices as u32 {
        row.clear();
        let rule = rule(topology, v, level.corner[v as usize], 0.0);
        let edges = topology.vertex_edges.get(v as usize);
        match (rule, scheme) {
            (_, Scheme::Bilinear | Scheme::LoopLinear) | (Rule::Corner, _) => row.push((v, 1.0)),
            _ if edges.is_empty() => row.push((v, 1.0)),
            (Rule::Crease([a, b]), _) => row.extend([(a, 1.0 / 6.0), (v, 4.0 / 6.0), (b, 1.0 / 6.0)]),
            (Rule::Smooth, Scheme::Loop) => {
                let n = edges.len() as f64;
                let chi = 1.0 / (3.0 / (8.0 * loop_beta(edges.len())) + n);
                row.push((v, 1.0 - n * chi));
                row.extend(edges.iter().map(|&e| (topology.other_end(e, v), chi)));
            }
            (Rule::Smooth, _) => {
                let n = edges.len() as f64;
                row.push((v, n * n));
                row.extend(edges.iter().map(|&e| (topology.other_end(e, v), 4.0)));
                for &c in topology.vertex_corners.get(v as usize) {
                    let face = topology.corner_face[c as usize];
                    let k = c as usize - topology.starts[face as usize];
                    let corners = topology.face(level, face);
                    row.push((corners[(k + corners.len() / 2) % corners.len()], 1.0));
                }
                let total: f64 = row.iter().map(|&(_, w)| w).sum();
                for entry in &mut row {
                    entry.1 /= total;
                }
            }
        }
        stencils.row(row.iter().copied());
    }
    stencils
}

/// How many steps a cage of `faces` faces takes: as many as keep it under
/// about 2^14 faces, at least one (the limit rules need a refined mesh)
/// and at most four (a quad then holds 256). Each step makes four faces of
/// one (of a quad or triangle; an n-gon makes n). Production cages are
/// dense, so most take one step: the limit positions and normals make them
/// smooth, and a scene of a thousand instanced teapots stays in memory.
#[must_use]
pub fn levels_for(faces: usize) -> u32 {
    let budget = 1usize << 14;
    let mut levels = 1;
    let mut refined = faces.saturating_mul(4);
    while levels < 4 && refined.saturating_mul(4) <= budget {
        levels += 1;
        refined = refined.saturating_mul(4);
    }
    levels
}

#[cfg(test)]
mod tests;
