//! The Embree wrapper against a brute-force ray-triangle intersector.
use super::*;
use crate::util::sampling::Rng;

/// Möller–Trumbore in f64: the reference answer.
fn brute_force(vertices: &[Vec3], triangles: &[[u32; 3]], ray: &Ray) -> Option<(f64, usize)> {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let mut best: Option<(f64, usize)> = None;
    for (i, tri) in triangles.iter().enumerate() {
        let p0 = vertices[tri[0] as usize].as_dvec3();
        let e1 = vertices[tri[1] as usize].as_dvec3() - p0;
        let e2 = vertices[tri[2] as usize].as_dvec3() - p0;
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-14 {
            continue;
        }
        let tv = o - p0;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = d.dot(qv) / det;
        let t = e2.dot(qv) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            continue;
        }
        if t >= f64::from(ray.t_near) && t <= f64::from(ray.t_far) && best.is_none_or(|b| t < b.0) {
            best = Some((t, i));
        }
    }
    best
}

fn random_mesh(rng: &mut Rng, triangles: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut vertices = Vec::new();
    let mut tris = Vec::new();
    for t in 0..triangles {
        let c = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
        for _ in 0..3 {
            vertices.push(
                c + 0.3 * Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0)),
            );
        }
        let b = 3 * t as u32;
        tris.push([b, b + 1, b + 2]);
    }
    (vertices, tris)
}

fn random_ray(rng: &mut Rng) -> Ray {
    let origin = Vec3::new(rng.range_f32(-2.0, 2.0), rng.range_f32(-2.0, 2.0), rng.range_f32(-2.0, 2.0));
    let target = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
    Ray { origin, direction: target - origin, t_near: 0.0, t_far: rng.range_f32(0.2, 3.0), time: 0.0 }
}

/// Whether a ray passes within `tolerance` (in t) of an edge-case decision
/// where f32 Embree and f64 reference may legitimately disagree.
fn near_ambiguous(vertices: &[Vec3], triangles: &[[u32; 3]], ray: &Ray) -> bool {
    // Perturb the ray slightly: if the reference answer changes, the case is ambiguous.
    let base = brute_force(vertices, triangles, ray).map(|h| h.1);
    let eps = 1e-4;
    [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z].iter().any(|&e| {
        let mut r = *ray;
        r.origin += e * eps;
        let mut far = r;
        far.t_far *= 1.0 + eps;
        let mut near = r;
        near.t_far *= 1.0 - eps;
        brute_force(vertices, triangles, &r).map(|h| h.1) != base
            || brute_force(vertices, triangles, &far).map(|h| h.1) != base
            || brute_force(vertices, triangles, &near).map(|h| h.1) != base
    })
}

#[test]
fn padding_leaves_room_for_a_16_byte_load_past_the_last_vertex() {
    for n in 1..50usize {
        let floats = padded_vertex_floats(n);
        let last_start_bytes = (n - 1) * 12;
        assert!(floats * 4 >= last_start_bytes + 16, "n={n}");
        assert!(floats >= 3 * n);
        // and no more than one float of waste
        assert!(floats <= 3 * n + 1);
    }
    assert!(padded_vertex_floats(0) * 4 >= 16);
}

#[test]
fn closest_hit_and_occlusion_match_brute_force_on_random_meshes() {
    let device = Device::try_new().expect("Embree device");
    let mut rng = Rng::seeded(42);
    let mut checked = 0;
    let mut hits = 0;
    for _mesh in 0..8 {
        let (vertices, tris) = random_mesh(&mut rng, 40);
        let mut builder = device.try_new_scene().unwrap();
        let id = builder.attach_triangles(&vertices, &tris).unwrap();
        let scene = builder.commit().unwrap();
        let rays: Vec<Ray> = (0..500).map(|_| random_ray(&mut rng)).collect();
        let shadow_rays: Vec<ShadowRay> = rays.iter().map(|r| ShadowRay::new(*r)).collect();
        let mut batch = Vec::new();
        scene.occluded_batch(&shadow_rays, &mut batch);
        // Packets of every width, on a count that leaves a partial packet.
        for width in [PacketWidth::Four, PacketWidth::Eight, PacketWidth::Sixteen] {
            let mut packets = Vec::new();
            scene.occluded_packets(&shadow_rays[..499], &mut packets, width);
            assert_eq!(packets, batch[..499], "packets of {width:?} agree with single rays");
        }
        let mut batch_hits = Vec::new();
        scene.intersect_batch(&rays, &mut batch_hits);
        for (i, ray) in rays.iter().enumerate() {
            let single_hit = scene.intersect(ray);
            let single_occluded = scene.occluded(ray);
            // batch = single, always, bit for bit
            assert_eq!(batch[i], single_occluded);
            assert_eq!(batch_hits[i], single_hit);
            if near_ambiguous(&vertices, &tris, ray) {
                continue;
            }
            checked += 1;
            let reference = brute_force(&vertices, &tris, ray);
            assert_eq!(single_occluded, reference.is_some(), "ray {ray:?}");
            match (single_hit, reference) {
                (None, None) => {}
                (Some(h), Some((t, prim))) => {
                    hits += 1;
                    assert_eq!(h.geometry, id);
                    assert_eq!(h.primitive as usize, prim, "ray {ray:?}");
                    assert!((f64::from(h.t) - t).abs() <= 1e-4 * t.max(1.0), "t {} vs {t}", h.t);
                    let tri = tris[prim];
                    let p = ray.origin + ray.direction * h.t;
                    let [p0, p1, p2] = tri.map(|k| vertices[k as usize]);
                    let q = (1.0 - h.u - h.v) * p0 + h.u * p1 + h.v * p2;
                    assert!((p - q).length() < 1e-3, "barycentrics disagree");
                    let ng = (p1 - p0).cross(p2 - p0);
                    assert!((h.ng - ng).length() <= 1e-4 * ng.length().max(1.0));
                }
                (a, b) => panic!("Embree {a:?} vs reference {b:?} for {ray:?}"),
            }
        }
    }
    assert!(checked > 3500, "too many ambiguous rays: {checked}");
    assert!(hits > 500 && hits < checked, "test should see both hits and misses: {hits}/{checked}");
}

#[test]
fn rays_respect_their_interval() {
    let device = Device::try_new().unwrap();
    let mut builder = device.try_new_scene().unwrap();
    // One big triangle in the plane z = 1.
    let v = [Vec3::new(-10.0, -10.0, 1.0), Vec3::new(10.0, -10.0, 1.0), Vec3::new(0.0, 10.0, 1.0)];
    builder.attach_triangles(&v, &[[0, 1, 2]]).unwrap();
    let scene = builder.commit().unwrap();
    let ray = |t_near, t_far| Ray { origin: Vec3::ZERO, direction: Vec3::Z, t_near, t_far, time: 0.0 };
    assert!(scene.occluded(&ray(0.0, 2.0)));
    assert!(!scene.occluded(&ray(0.0, 0.99)));
    assert!(!scene.occluded(&ray(1.01, 2.0)));
    assert_eq!(scene.intersect(&ray(0.0, f32::INFINITY)).map(|h| h.t), Some(1.0));
    assert!(scene.intersect(&ray(0.0, 0.5)).is_none());
}

#[test]
fn several_meshes_report_their_own_ids_and_an_empty_scene_hits_nothing() {
    let device = Device::try_new().unwrap();
    let empty = device.try_new_scene().unwrap().commit().unwrap();
    let ray = Ray { origin: Vec3::ZERO, direction: Vec3::Z, t_near: 0.0, t_far: f32::INFINITY, time: 0.0 };
    assert!(empty.intersect(&ray).is_none());
    assert!(!empty.occluded(&ray));
    let mut builder = device.try_new_scene().unwrap();
    let tri = |z: f32| [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(0.0, 1.0, z)];
    let a = builder.attach_triangles(&tri(2.0), &[[0, 1, 2]]).unwrap();
    let b = builder.attach_triangles(&tri(1.0), &[[0, 1, 2]]).unwrap();
    assert_ne!(a, b);
    let scene = builder.commit().unwrap();
    assert_eq!(scene.intersect(&ray).unwrap().geometry, b);
}

#[test]
fn bad_meshes_are_rejected_before_embree_sees_them() {
    let device = Device::try_new().unwrap();
    let mut builder = device.try_new_scene().unwrap();
    let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!(matches!(
        builder.attach_triangles(&v, &[[0, 1, 3]]),
        Err(MeshError::IndexOutOfRange { triangle: 0, index: 3, vertex_count: 3 })
    ));
    let bad = [Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y];
    assert!(matches!(builder.attach_triangles(&bad, &[[0, 1, 2]]), Err(MeshError::NonFiniteVertex { vertex: 1 })));
}

#[test]
fn flush_denormals_is_per_thread() {
    std::thread::spawn(|| {
        assert!(!flush_denormals_enabled());
        set_flush_denormals();
        assert!(flush_denormals_enabled());
    })
    .join()
    .unwrap();
}

#[test]
fn version_is_the_major_build_rs_found() {
    let (major, _, _) = version();
    assert_eq!(major.to_string(), env!("LIGHTCUTS_EMBREE_MAJOR"));
    // ci/embree4.sh sets this so a silent fall-back to Embree 3 fails.
    if let Ok(expected) = std::env::var("LIGHTCUTS_EXPECT_EMBREE_MAJOR") {
        assert_eq!(major.to_string(), expected);
    }
}

#[test]
fn packet_structures_are_aligned_as_embree_requires() {
    for width in [PacketWidth::Four, PacketWidth::Eight, PacketWidth::Sixteen] {
        let (valid_mask, packet, required) = packet_alignment(width);
        assert_eq!(required, 4 * width as u32, "{width:?}: rtcOccluded{} needs {required} bytes", width as u32);
        assert!(valid_mask >= required, "{width:?}: the valid mask is aligned to {valid_mask} bytes of {required}");
        assert!(packet >= required, "{width:?}: the ray packet is aligned to {packet} bytes of {required}");
    }
}

/// A triangle in the plane z = 1, and a ray towards it from the origin.
fn wall() -> (Scene, Ray) {
    let device = Device::try_new().unwrap();
    let mut builder = device.try_new_scene().unwrap();
    let v = [Vec3::new(-10.0, -10.0, 1.0), Vec3::new(10.0, -10.0, 1.0), Vec3::new(0.0, 10.0, 1.0)];
    builder.attach_triangles(&v, &[[0, 1, 2]]).unwrap();
    (builder.commit().unwrap(), Ray { origin: Vec3::ZERO, direction: Vec3::Z, t_near: 0.0, t_far: 0.5, time: 0.0 })
}

#[test]
fn rays_embree_must_not_see_are_refused_in_every_build_and_block_their_light() {
    let (scene, clear) = wall();
    assert!(!scene.occluded(&clear), "the ray stops short of the wall");
    let bad = [
        Ray { origin: Vec3::new(f32::NAN, 0.0, 0.0), ..clear },
        Ray { direction: Vec3::new(0.0, f32::INFINITY, 1.0), ..clear },
        Ray { origin: Vec3::splat(1e19), ..clear },
        Ray { t_far: f32::NAN, ..clear },
        Ray { t_near: -1.0, ..clear },
        Ray { time: 1.5, ..clear },
        Ray { time: f32::NAN, ..clear },
    ];
    let before = refused_rays();
    for ray in &bad {
        assert!(!ray.is_valid(), "{ray:?}");
        assert!(scene.intersect(ray).is_none(), "{ray:?}: no hit");
        assert!(scene.occluded(ray), "{ray:?}: a refused shadow ray blocks its light");
    }
    assert_eq!(refused_rays() - before, 2 * bad.len() as u64);
    // In batches and packets, among valid rays: only the refused ones read
    // as blocked, the others are traced.
    let mut rays: Vec<ShadowRay> = bad.iter().map(|r| ShadowRay::new(*r)).collect();
    rays.insert(2, ShadowRay::new(clear));
    let mut occluded = Vec::new();
    scene.occluded_batch(&rays, &mut occluded);
    let expected = [true, true, false, true, true, true, true, true];
    assert_eq!(occluded, expected);
    for width in [PacketWidth::Four, PacketWidth::Eight, PacketWidth::Sixteen] {
        scene.occluded_packets(&rays, &mut occluded, width);
        assert_eq!(occluded, expected, "{width:?}");
    }
    let mut hits = Vec::new();
    scene.intersect_batch(&[bad[0], Ray { t_far: 2.0, ..clear }], &mut hits);
    assert!(hits[0].is_none() && hits[1].is_some_and(|h| h.t == 1.0));
}

#[test]
fn an_error_embree_reports_is_taken_once_and_names_what_was_being_done() {
    let (scene, _) = wall();
    assert_eq!(scene.take_error("tracing"), Ok(()));
    scene.device().provoke_error_for_tests();
    let error = scene.take_error("tracing a tile's rays").unwrap_err();
    assert!(error.to_string().contains("while tracing a tile's rays"), "{error}");
    assert_ne!(error.code, 0);
    assert_eq!(scene.take_error("tracing"), Ok(()), "the error is taken, not reported again");
}

#[test]
fn a_moving_instance_is_where_it_is_at_each_ray_time_on_every_query() {
    let device = Device::try_new().unwrap();
    let mut child = device.try_new_scene().unwrap();
    // A unit square in the plane z = 1, around x = 0.
    let square =
        [Vec3::new(-0.5, -0.5, 1.0), Vec3::new(0.5, -0.5, 1.0), Vec3::new(0.5, 0.5, 1.0), Vec3::new(-0.5, 0.5, 1.0)];
    child.attach_triangles(&square, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    let child = Arc::new(child.commit().unwrap());
    let mut builder = device.try_new_scene().unwrap();
    // Over the shutter it slides 4 units along x (two steps), and a second
    // copy turns a quarter about z in three steps.
    let slide = [Affine3A::IDENTITY, Affine3A::from_translation(Vec3::new(4.0, 0.0, 0.0))];
    let sliding = builder.attach_moving_instance(&child, &slide).unwrap();
    let far = Affine3A::from_translation(Vec3::new(0.0, 10.0, 0.0));
    let turn: Vec<Affine3A> =
        (0..3).map(|k| far * Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_4 * k as f32)).collect();
    let turning = builder.attach_moving_instance(&child, &turn).unwrap();
    let scene = builder.commit().unwrap();
    // A ray along +z at x: it meets the square while |x - 4 time| < 0.5.
    let ray = |x: f32, y: f32, time: f32| Ray {
        origin: Vec3::new(x, y, 0.0),
        direction: Vec3::Z,
        t_near: 0.0,
        t_far: f32::INFINITY,
        time,
    };
    for (x, time, hits) in [(0.0, 0.0, true), (0.0, 0.2, false), (2.0, 0.5, true), (2.0, 0.0, false), (3.8, 1.0, true)]
    {
        let r = ray(x, 0.0, time);
        assert_eq!(scene.intersect(&r).map(|h| h.geometry), hits.then_some(sliding), "x {x} at {time}");
        assert_eq!(scene.occluded(&r), hits, "x {x} at {time}");
        let mut packets = Vec::new();
        scene.occluded_packets(&[ShadowRay::new(r); 5], &mut packets, PacketWidth::Eight);
        assert_eq!(packets, vec![hits; 5], "packets at x {x}, time {time}");
        let mut batch = Vec::new();
        scene.occluded_batch(&[ShadowRay::new(r)], &mut batch);
        assert_eq!(batch, vec![hits]);
    }
    // The turning square's corner (0.5, 0.5) reaches the y axis at 45
    // degrees (time 0.5, 0.707 above its centre) and stays below 0.5
    // elsewhere on that line at the open.
    assert_eq!(scene.intersect(&ray(0.0, 10.68, 0.5)).map(|h| h.geometry), Some(turning));
    assert!(!scene.occluded(&ray(0.0, 10.68, 0.0)));
    // Steps Embree would refuse are refused first.
    let mut builder = device.try_new_scene().unwrap();
    assert!(matches!(builder.attach_moving_instance(&child, &[]), Err(MeshError::BadInstance)));
    let too_many = vec![Affine3A::IDENTITY; MAX_TIME_STEPS + 1];
    assert!(matches!(builder.attach_moving_instance(&child, &too_many), Err(MeshError::BadInstance)));
    let singular = [Affine3A::IDENTITY, Affine3A::from_scale(Vec3::ZERO)];
    assert!(matches!(builder.attach_moving_instance(&child, &singular), Err(MeshError::BadInstance)));
}

/// The nearest t at which `ray` meets a sphere (f64), the reference answer.
fn ray_sphere(ray: &Ray, centre: Vec3, radius: f32) -> Option<f64> {
    let (o, d) = (ray.origin.as_dvec3() - centre.as_dvec3(), ray.direction.as_dvec3());
    let (a, b, c) = (d.dot(d), 2.0 * o.dot(d), o.dot(o) - f64::from(radius).powi(2));
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    [(-b - disc.sqrt()) / (2.0 * a), (-b + disc.sqrt()) / (2.0 * a)]
        .into_iter()
        .find(|&t| t >= f64::from(ray.t_near) && t <= f64::from(ray.t_far))
}

#[test]
fn spheres_are_hit_where_the_ray_meets_them_with_their_outward_normal() {
    let device = Device::try_new().unwrap();
    let mut builder = device.try_new_scene().unwrap();
    let spheres = [Vec4::new(0.0, 0.0, 0.0, 0.5), Vec4::new(1.2, 0.3, -0.4, 0.25), Vec4::new(-0.9, -0.6, 0.5, 0.4)];
    let id = builder.attach_spheres(&spheres).unwrap();
    let scene = builder.commit().unwrap();
    let mut rng = Rng::seeded(7);
    let (mut hits, mut checked) = (0, 0);
    for _ in 0..4000 {
        let ray = random_ray(&mut rng);
        let reference = spheres
            .iter()
            .enumerate()
            .filter_map(|(i, s)| ray_sphere(&ray, s.truncate(), s.w).map(|t| (t, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let hit = scene.intersect(&ray);
        // Rays grazing a sphere or ending at its surface may go either way in f32.
        let grazing = reference.is_some_and(|(t, _)| (t - f64::from(ray.t_far)).abs() < 1e-3);
        match (reference, hit) {
            (Some((t, i)), Some(h)) => {
                assert_eq!((h.geometry, h.primitive), (id, i as u32));
                assert!((f64::from(h.t) - t).abs() < 1e-4 * t.max(1.0), "t {} against {t}", h.t);
                let p = ray.origin + h.t * ray.direction;
                let outward = (p - spheres[i].truncate()).normalize();
                assert!(h.ng.normalize().dot(outward) > 0.999, "normal {} against {outward}", h.ng);
                hits += 1;
            }
            (None, None) => {}
            _ => assert!(grazing, "Embree and the reference disagree on {ray:?}"),
        }
        checked += 1;
    }
    assert!(hits > 200 && checked == 4000, "{hits} hits");
}

/// A curve along x from -0.5 to 0.5 in every basis, radius 0.1: control
/// points placed so that each basis's segment spans exactly that stretch.
fn straight_curve(basis: CurveBasis) -> Vec<Vec4> {
    let xs: &[f32] = match basis {
        CurveBasis::Linear => &[-0.5, 0.5],
        CurveBasis::Bezier => &[-0.5, -1.0 / 6.0, 1.0 / 6.0, 0.5],
        // A uniform B-spline segment runs from (P0 + 4 P1 + P2) / 6 to (P1 + 4 P2 + P3) / 6.
        CurveBasis::BSpline => &[-1.5, -0.5, 0.5, 1.5],
        // A Catmull-Rom segment runs from P1 to P2.
        CurveBasis::CatmullRom => &[-1.5, -0.5, 0.5, 1.5],
    };
    xs.iter().map(|&x| Vec4::new(x, 0.0, 0.0, 0.1)).collect()
}

#[test]
fn curves_of_every_basis_are_tubes_and_ribbons_between_their_ends() {
    let device = Device::try_new().unwrap();
    let down =
        |x: f32| Ray { origin: Vec3::new(x, 0.0, 5.0), direction: -Vec3::Z, t_near: 0.0, t_far: 10.0, time: 0.0 };
    let grazing = Ray { origin: Vec3::new(0.0, 5.0, 0.0), direction: -Vec3::Y, t_near: 0.0, t_far: 10.0, time: 0.0 };
    for basis in [CurveBasis::Linear, CurveBasis::Bezier, CurveBasis::BSpline, CurveBasis::CatmullRom] {
        let points = straight_curve(basis);
        for shape in [CurveShape::Round, CurveShape::Flat] {
            let mut builder = device.try_new_scene().unwrap();
            builder.attach_curves(basis, shape, &points, &[0]).unwrap();
            let scene = builder.commit().unwrap();
            let what = format!("{basis:?} {shape:?}");
            let hit = scene.intersect(&down(0.2)).unwrap_or_else(|| panic!("{what}: the ray at x = 0.2 misses"));
            // A tube's top is its radius above the axis; a ribbon lies on it.
            let expected = if shape == CurveShape::Round { 4.9 } else { 5.0 };
            assert!((hit.t - expected).abs() < 2e-3, "{what}: t {}", hit.t);
            // A tube's normal faces out of it; a ribbon's `ng` is the curve's tangent.
            let expected = if shape == CurveShape::Round { Vec3::Z } else { Vec3::X };
            assert!(hit.ng.normalize().dot(expected) > 0.99, "{what}: ng {}", hit.ng);
            // The parameter along the segment: x = 0.2 is u = 0.7 on every basis placed so.
            assert!((hit.u - 0.7).abs() < 0.02, "{what}: u {}", hit.u);
            assert!(scene.intersect(&down(0.75)).is_none(), "{what}: the curve ends at x = 0.5");
            // A tube is round and a ribbon turns to face every ray: both are
            // met from the side too.
            assert!(scene.occluded(&grazing), "{what}: missed from the side");
        }
    }
}

#[test]
fn bad_curves_and_spheres_are_rejected_before_embree_sees_them() {
    let device = Device::try_new().unwrap();
    let mut builder = device.try_new_scene().unwrap();
    let points = straight_curve(CurveBasis::BSpline);
    assert!(matches!(
        builder.attach_curves(CurveBasis::BSpline, CurveShape::Round, &points, &[1]),
        Err(MeshError::SegmentOutOfRange { segment: 0, order: 4, vertex_count: 4 })
    ));
    let line = straight_curve(CurveBasis::Linear);
    assert!(matches!(
        builder.attach_curves(CurveBasis::Linear, CurveShape::Flat, &line, &[0, 1]),
        Err(MeshError::SegmentOutOfRange { segment: 1, order: 2, vertex_count: 2 })
    ));
    let negative = [Vec4::new(0.0, 0.0, 0.0, -1.0)];
    assert!(matches!(builder.attach_spheres(&negative), Err(MeshError::NonFiniteVertex { vertex: 0 })));
    let nan = [Vec4::new(f32::NAN, 0.0, 0.0, 1.0)];
    assert!(matches!(builder.attach_spheres(&nan), Err(MeshError::NonFiniteVertex { vertex: 0 })));
}
