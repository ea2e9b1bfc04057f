use glam::{DVec2, DVec3};

use super::*;

/// The cube [-1, 1]^3 as six outward-facing quads.
fn cube() -> (Vec<DVec3>, Cage) {
    let points = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let faces: [[u32; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let cage = Cage {
        counts: vec![4; 6],
        indices: faces.concat(),
        vertices: 8,
        creases: Vec::new(),
        corners: Vec::new(),
        boundary: Boundary::EdgeAndCorner,
        scheme: Scheme::CatmullClark,
    };
    (points, cage)
}

fn cube_edges(cage: &Cage) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> =
        cage.indices.chunks(4).flat_map(|q| (0..4).map(move |k| sorted(q[k], q[(k + 1) % 4]))).collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

#[test]
fn catmull_clark_limit_of_a_cube_corner_is_its_limit_mask() {
    // Halstead et al.'s mask on the cage itself, for a corner of valence 3:
    // (9 v + 4 sum of its edge neighbours + sum of its quads' far corners) / 24,
    // which for (1, 1, 1) is (9 + 4 - 1) / 24 = 1/2 of the corner. Every
    // refinement depth must reach the same limit point.
    let (points, cage) = cube();
    for levels in 1..=4 {
        let refined = refine(&cage, levels);
        let limit = refined.limit(&points);
        for (i, p) in points.iter().enumerate() {
            assert!((limit[i] - 0.5 * *p).length() < 1e-12, "level {levels}: corner {i} at {}", limit[i]);
        }
        assert_eq!(refined.counts.len(), 6 * 4usize.pow(levels));
        assert!(refined.parents.iter().enumerate().all(|(f, &p)| p as usize == f / 4usize.pow(levels)));
    }
}

#[test]
fn catmull_clark_limit_surface_of_a_cube_is_round() {
    // Every limit point lies between the inscribed sphere's radius (the face
    // centres' limit) and the corners' limit, and on no flat face.
    let (points, cage) = cube();
    let limit = refine(&cage, 3).limit(&points);
    let radii: Vec<f64> = limit.iter().map(|p| p.length()).collect();
    let (low, high) = radii.iter().fold((f64::MAX, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
    assert!(low > 0.6 && high <= 0.5 * 3f64.sqrt() + 1e-12, "radii {low}..{high}");
}

#[test]
fn an_infinitely_sharp_crease_keeps_its_edge() {
    // Every edge of the cube infinitely sharp: the limit surface is the cube.
    let (points, mut cage) = cube();
    cage.creases = cube_edges(&cage).into_iter().map(|e| (e, INFINITELY_SHARP)).collect();
    let refined = refine(&cage, 3);
    let limit = refined.limit(&points);
    for p in &limit {
        assert!((p.abs().max_element() - 1.0).abs() < 1e-12, "{p} is off the cube");
    }
    for (i, p) in points.iter().enumerate() {
        assert!((limit[i] - *p).length() < 1e-12, "corner {i} moved to {}", limit[i]);
    }
    // The normals stay flat on each face: split across the creases.
    let (normals, corners) = refined.corner_normals(&limit);
    assert_eq!(normals.len(), 6 * 9 * 9, "one normal per face and vertex of the 8 x 8 grid on each face");
    assert_eq!(corners.len(), refined.indices.len());
    for n in normals {
        assert!((n.abs().max_element() - 1.0).abs() < 1e-9, "normal {n} is not a face's");
    }
}

#[test]
fn semi_sharp_creases_lie_between_smooth_and_sharp() {
    let (points, mut cage) = cube();
    let edges = cube_edges(&cage);
    let mut last = 0.0;
    for sharpness in [0.0, 0.5, 1.0, 2.0, 3.0, INFINITELY_SHARP] {
        cage.creases = edges.iter().map(|&e| (e, sharpness)).collect();
        let corner = refine(&cage, 4).limit(&points)[7].x;
        assert!(corner > last, "sharpness {sharpness}: corner at {corner}, below {last}");
        last = corner;
    }
    assert!((last - 1.0).abs() < 1e-12);
}

#[test]
fn a_corner_sharpness_pins_a_vertex() {
    let (points, mut cage) = cube();
    cage.corners = vec![(7, INFINITELY_SHARP)];
    let limit = refine(&cage, 3).limit(&points);
    assert_eq!(limit[7], points[7]);
    assert!((limit[0] - 0.5 * points[0]).length() < 1e-12);
}

/// A flat 3 x 3 grid of quads in z = 0 (16 points, 9 faces).
fn grid(boundary: Boundary) -> (Vec<DVec3>, Cage) {
    let points = (0..16).map(|i| DVec3::new(f64::from(i % 4), f64::from(i / 4), 0.0)).collect();
    let mut indices = Vec::new();
    for y in 0..3u32 {
        for x in 0..3u32 {
            let v = y * 4 + x;
            indices.extend([v, v + 1, v + 5, v + 4]);
        }
    }
    let cage = Cage {
        counts: vec![4; 9],
        indices,
        vertices: 16,
        creases: Vec::new(),
        corners: Vec::new(),
        boundary,
        scheme: Scheme::CatmullClark,
    };
    (points, cage)
}

#[test]
fn boundaries_follow_interpolate_boundary() {
    let (points, cage) = grid(Boundary::EdgeAndCorner);
    let limit = refine(&cage, 2).limit(&points);
    assert!(limit.iter().all(|p| p.z == 0.0), "a flat cage stays flat");
    // edgeAndCorner: the grid's corners stay; a boundary vertex moves along
    // the boundary's B-spline, (a + 4 v + b) / 6, which on a straight line is v.
    for i in [0, 3, 12, 15, 1, 2, 4, 8] {
        assert!((limit[i] - points[i]).length() < 1e-12, "point {i} moved to {}", limit[i]);
    }
    // edgeOnly: a corner is a crease vertex: (a + 4 v + b) / 6 pulls it in.
    let (points, cage) = grid(Boundary::EdgeOnly);
    let limit = refine(&cage, 2).limit(&points);
    assert!((limit[0] - DVec3::new(1.0 / 6.0, 1.0 / 6.0, 0.0)).length() < 1e-12, "{}", limit[0]);
    // The interior vertex (1, 1) of a flat regular grid stays put.
    assert!((limit[5] - points[5]).length() < 1e-12);
}

#[test]
fn bilinear_keeps_face_varying_values_linear() {
    let (_, mut cage) = grid(Boundary::EdgeAndCorner);
    cage.scheme = Scheme::Bilinear;
    let uv: Vec<DVec2> = (0..16).map(|i| DVec2::new(f64::from(i % 4) / 3.0, f64::from(i / 4) / 3.0)).collect();
    let refined = refine(&cage, 2);
    let values = refined.limit(&uv);
    // Linear in a linear field: every refined value is where a bilinear
    // split puts it, a multiple of 1/12 on each axis.
    for v in &values {
        let scaled = *v * 12.0;
        assert!((scaled - scaled.round()).length() < 1e-9, "{v}");
    }
    assert_eq!(values.len(), 13 * 13);
}

#[test]
fn loop_limit_of_an_octahedron_vertex_is_its_limit_mask() {
    // A Loop vertex of valence 4 goes to (1 - 4 chi) v + chi sum of its
    // neighbours, chi = 1 / (3 / (8 beta) + 4), beta = (5/8 - (3/8 + cos(pi/2)/4)^2) / 4.
    let points: Vec<DVec3> = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
    let triangles: [[u32; 3]; 8] =
        [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    let cage = Cage {
        counts: vec![3; 8],
        indices: triangles.concat(),
        vertices: 6,
        creases: Vec::new(),
        corners: Vec::new(),
        boundary: Boundary::EdgeAndCorner,
        scheme: Scheme::Loop,
    };
    let beta: f64 = (0.625 - 0.375f64.powi(2)) / 4.0;
    let chi = 1.0 / (3.0 / (8.0 * beta) + 4.0);
    // Vertex 0 = +x: neighbours +-y, +-z sum to zero.
    let expected = (1.0 - 4.0 * chi) * DVec3::X;
    for levels in 1..=3 {
        let refined = refine(&cage, levels);
        let limit = refined.limit(&points);
        assert!((limit[0] - expected).length() < 1e-12, "level {levels}: {}", limit[0]);
        assert_eq!(refined.counts.len(), 8 * 4usize.pow(levels));
        assert!(refined.counts.iter().all(|&c| c == 3));
    }
}

#[test]
fn smooth_normals_point_out_of_a_closed_surface() {
    let (points, cage) = cube();
    let refined = refine(&cage, 3);
    let limit = refined.limit(&points);
    let (normals, corners) = refined.corner_normals(&limit);
    assert_eq!(normals.len(), limit.len(), "a smooth surface: one normal per vertex");
    for (corner, &n) in corners.iter().enumerate() {
        let p = limit[refined.indices[corner] as usize];
        let n = normals[n as usize];
        assert!(n.dot(p.normalize()) > 0.8, "normal {n} at {p}");
    }
}

#[test]
fn levels_stay_within_the_budget() {
    assert_eq!(levels_for(6), 4);
    assert_eq!(levels_for(1_000), 2);
    assert_eq!(levels_for(2_500), 1);
    assert_eq!(levels_for(1_000_000), 1);
}
