//! Every bound is >= the true maximum over the cluster's lights, at
//! thousands of random shading points, normals, view directions, materials
//! and clusters (seeded).
use glam::DVec3;

use super::*;
use crate::light::TreeLight;
use crate::light_tree::layout::{centre_half, Child, ConeBlock, SpotBlock};
use crate::light_tree::Cone;
use crate::scene::material::{reflect, Albedo, Material};
use crate::shading::light_term;
use crate::util::sampling::Rng;

/// The bound of one cluster (box [lo, hi], cone of normals, summed
/// intensity) at `sp`, by the cut's own code: the cluster in slot `slot` of
/// a block whose other slot is a leaf, with no normalisation (scale 1).
#[allow(clippy::too_many_arguments)]
fn cluster_bound(
    kind: LightKind,
    sp: &SurfacePoint<'_>,
    lo: Vec3,
    hi: Vec3,
    cone: Cone,
    min_cos_outer: f32,
    intensity: Vec3,
    slot: usize,
) -> f32 {
    let (centre, half) = centre_half(lo, hi);
    let mut block = Block::default();
    let mut cones = ConeBlock::default();
    block.child = [Child::leaf(0), Child::leaf(1)];
    block.child[slot] = Child::internal(1, false);
    let (sin, cos) = cone.half_angle.sin_cos();
    for axis in 0..3 {
        block.centre[axis][slot] = centre[axis];
        block.half[axis][slot] = half[axis];
        block.intensity[axis][slot] = intensity[axis];
        cones.axis[axis][slot] = cone.axis[axis];
    }
    cones.cos_half_angle[slot] = if cone.half_angle == 0.0 { 1.0 } else { cos };
    cones.sin_half_angle[slot] = if cone.half_angle == 0.0 { 0.0 } else { sin };
    let mut spots = SpotBlock::default();
    spots.min_cos_outer[slot] = min_cos_outer;
    let spot = (kind == LightKind::Spot).then_some(&spots);
    let cones = kind.has_cone().then_some(Cones { cone: &cones, spot });
    PointBounds::new(sp, 1.0).pair(kind, &block, cones)[slot]
}

/// M * G per unit intensity of a light of `kind` at `point` (a direction
/// for a directional light) with `normal` (oriented lights; a spot's
/// direction) and `spread` (a spot's inner and outer cosines).
fn term(kind: LightKind, sp: &SurfacePoint<'_>, point: Vec3, normal: Vec3, spread: [f32; 2]) -> DVec3 {
    light_term(&TreeLight { spread, ..TreeLight::at(point, normal, Vec3::ONE) }.light(kind), sp)
}

fn unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
        if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

fn material(rng: &mut Rng) -> Material {
    if rng.next_f32() < 0.4 {
        return pbr_material(rng);
    }
    let exponents = [0.0, 1.0, 7.5, 40.0, 500.0, 10_000.0];
    let albedo = Albedo::Constant(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()));
    Material {
        specular: if rng.next_f32() < 0.3 {
            Vec3::ZERO
        } else {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
        },
        exponent: exponents[rng.below(exponents.len() as u64) as usize],
        ..Material::diffuse("m", albedo)
    }
}

/// 0, `top` or a value between, each a third of the time.
fn edge(rng: &mut Rng, top: f32) -> f32 {
    [0.0, top, top * rng.next_f32()][rng.below(3) as usize]
}

/// A metallic-roughness material over every value the importers accept:
/// metallic 0, 1 or between, roughness from 0 (clamped to the lobe's
/// smallest alpha) through 0.02 to 1, a base colour with channels at 0, at
/// 1 or between, KHR_materials_specular's factor (0 to 1, its ends too) and
/// colour (unbounded: 0.04 x colour reaches 1 from 25 on) sometimes.
fn pbr_material(rng: &mut Rng) -> Material {
    let roughness = [0.0, 0.02, 0.05, 0.2, 0.5, 1.0, rng.next_f32()][rng.below(7) as usize];
    let metallic = [0.0, 1.0, rng.next_f32()][rng.below(3) as usize];
    let (specular, specular_colour) = if rng.next_f32() < 0.6 {
        (1.0, Vec3::ONE)
    } else {
        let factor = edge(rng, 1.0);
        let top = [1.0, 3.0, 100.0][rng.below(3) as usize];
        (factor, Vec3::new(edge(rng, top), edge(rng, top), edge(rng, top)))
    };
    let albedo = Albedo::Constant(Vec3::new(edge(rng, 1.0), edge(rng, 1.0), edge(rng, 1.0)));
    let (clearcoat, sheen) = layers(roughness, metallic);
    Material {
        pbr: Some(crate::scene::material::PbrMaterial {
            specular,
            specular_colour,
            clearcoat,
            sheen,
            ..crate::scene::material::PbrMaterial::untextured(metallic, roughness)
        }),
        ..Material::diffuse("pbr", albedo)
    }
}

/// A clear coat (smooth or rough, docs/design.md §5.10) on about half the
/// materials and a sheen on about half, drawn from their own stream (seeded
/// by the base's draws) so that the other draws stay as they were.
fn layers(
    roughness: f32,
    metallic: f32,
) -> (Option<crate::scene::material::Clearcoat>, Option<crate::scene::material::Sheen>) {
    let mut rng = Rng::seeded(u64::from(roughness.to_bits()) << 32 | u64::from(metallic.to_bits()));
    let clearcoat = (rng.next_f32() < 0.5).then(|| crate::scene::material::Clearcoat {
        factor: edge(&mut rng, 1.0).max(0.01),
        texture: None,
        roughness: [0.0, 0.05, 0.3, 1.0, rng.next_f32()][rng.below(5) as usize],
        roughness_texture: None,
        normal_map: None,
    });
    let sheen = (rng.next_f32() < 0.5).then(|| crate::scene::material::Sheen {
        colour: Vec3::new(edge(&mut rng, 1.0), edge(&mut rng, 1.0), edge(&mut rng, 1.0)).max(Vec3::splat(0.01)),
        colour_texture: None,
        roughness: [0.0, 0.3, 1.0, rng.next_f32()][rng.below(4) as usize],
        roughness_texture: None,
    });
    (clearcoat, sheen)
}

fn surface<'m>(rng: &mut Rng, material: &'m Material) -> SurfacePoint<'m> {
    let n = unit(rng);
    let mut wo = unit(rng);
    if wo.dot(n) < 0.0 {
        wo = -wo;
    }
    // Geometric normal: usually the shading normal, sometimes tilted from it.
    let ng = if rng.next_f32() < 0.5 { n } else { (n + 0.3 * unit(rng)).normalize() };
    let ng = if ng.dot(wo) < 0.0 { -ng } else { ng };
    let n = if n.dot(ng) < 0.0 { -n } else { n };
    let base = match material.albedo {
        Albedo::Constant(c) => c,
        Albedo::Texture(_) => unreachable!(),
    };
    let pbr = material
        .pbr
        .as_ref()
        .map(|m| crate::shading::pbr::Pbr::of(m, base, &crate::scene::material::TexCoords::default(), &[]));
    // Drawn in this order, as the random stream always has.
    let p = Vec3::new(rng.range_f32(-3.0, 3.0), rng.range_f32(-3.0, 3.0), rng.range_f32(-3.0, 3.0));
    // Half the time the environment's lights see the diffuse lobe alone
    // (a glossy lobe too sharp for them), which the bounds must follow.
    let emitter_lobes = if rng.next_f32() < 0.5 { crate::shading::Lobes::DIFFUSE } else { crate::shading::Lobes::ALL };
    let kd = pbr.map_or(base, |p| p.diffuse_albedo());
    // A clear coat's own normal, tilted from n half the time (its own
    // stream, so that the other draws stay as they were).
    let mut coat_rng = Rng::seeded(u64::from(p.x.to_bits()) << 32 | u64::from(p.y.to_bits()));
    let tilted = (n + 0.4 * unit(&mut coat_rng)).normalize();
    let coat_n = if coat_rng.next_f32() < 0.5 && tilted.dot(wo) > 0.05 { tilted } else { n };
    SurfacePoint { ng, pbr, emitter_lobes, coat_n, ..SurfacePoint::bare(material, p, n, wo, kd) }
}

#[test]
fn cos_bound_is_above_every_vector_in_the_box() {
    let mut rng = Rng::seeded(1);
    for _ in 0..5000 {
        let axis = unit(&mut rng);
        let c = Vec3::new(rng.range_f32(-2.0, 2.0), rng.range_f32(-2.0, 2.0), rng.range_f32(-2.0, 2.0));
        let e = Vec3::new(rng.range_f32(0.0, 1.5), rng.range_f32(0.0, 1.5), rng.range_f32(0.0, 1.5));
        let (lo, hi) = (c - e, c + e);
        let bound = cos_bound(axis, lo, hi);
        assert!((0.0..=1.0).contains(&bound));
        // Corners, face centres and random interior points.
        for _ in 0..64 {
            let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let v = lo + (hi - lo) * t;
            if v.length_squared() > 0.0 {
                assert!(axis.dot(v.normalize()) <= bound, "cos {} > bound {bound}", axis.dot(v.normalize()));
            }
        }
        for k in 0..8 {
            let v = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            if v.length_squared() > 0.0 {
                assert!(axis.dot(v.normalize()) <= bound);
            }
        }
    }
}

#[test]
fn cos_bound_is_tight_for_a_single_direction() {
    let mut rng = Rng::seeded(2);
    for _ in 0..1000 {
        let (axis, v) = (unit(&mut rng), unit(&mut rng) * 3.0);
        let bound = cos_bound(axis, v, v);
        let exact = axis.dot(v.normalize()).max(0.0);
        assert!(bound >= exact && bound <= exact + 1e-4, "{bound} vs {exact}");
    }
}

/// A random cluster of lights of one kind near (sometimes around) `sp`:
/// each light's position (a direction for directional lights), normal (a
/// spot's direction) and spread (a spot's inner and outer cosines), with
/// the cluster's box, cone of normals and widest outer cosine.
struct RandomCluster {
    lights: Vec<(Vec3, Vec3, [f32; 2])>,
    lo: Vec3,
    hi: Vec3,
    cone: Cone,
    min_cos_outer: f32,
}

impl RandomCluster {
    fn new(rng: &mut Rng, kind: LightKind, sp: &SurfacePoint<'_>) -> Self {
        let count = 1 + rng.below(8) as usize;
        // Lights near a random centre, sometimes around the shading point itself.
        let centre = if rng.next_f32() < 0.2 {
            sp.p
        } else {
            Vec3::new(rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0))
        };
        let spread = [0.0, 0.01, 0.5, 3.0][rng.below(4) as usize];
        let base_normal = unit(rng);
        let lights: Vec<(Vec3, Vec3, [f32; 2])> = (0..count)
            .map(|_| {
                let position = match kind {
                    LightKind::Directional | LightKind::Environment => {
                        (base_normal + spread * unit(rng)).normalize_or(base_normal)
                    }
                    _ => {
                        centre
                            + spread
                                * Vec3::new(
                                    rng.range_f32(-1.0, 1.0),
                                    rng.range_f32(-1.0, 1.0),
                                    rng.range_f32(-1.0, 1.0),
                                )
                    }
                };
                let normal = if rng.next_f32() < 0.5 { (base_normal + 0.4 * unit(rng)).normalize() } else { unit(rng) };
                // Spots: outer half-angles from 1 to 90 degrees, inner below them.
                let outer = rng.range_f32(1.0, 90.0).to_radians();
                let spread = [(outer * rng.next_f32()).cos(), outer.cos()];
                (position, normal, spread)
            })
            .collect();
        let (lo, hi) =
            lights.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), l| (lo.min(l.0), hi.max(l.0)));
        let cone = lights.iter().skip(1).fold(Cone::of_direction(lights[0].1), |c, l| c.union(Cone::of_direction(l.1)));
        let min_cos_outer = lights.iter().map(|l| l.2[1]).fold(1.0f32, f32::min);
        Self { lights, lo, hi, cone, min_cos_outer }
    }

    /// The largest M * G of the cluster's lights in channel `c`, times that
    /// channel's luminance weight: what the luminance bound against a unit
    /// intensity in channel c must be at least.
    fn largest(&self, kind: LightKind, sp: &SurfacePoint<'_>, c: usize) -> f64 {
        let weight = [0.2126, 0.7152, 0.0722][c];
        self.lights.iter().map(|(p, n, spread)| weight * term(kind, sp, *p, *n, *spread)[c]).fold(0.0, f64::max)
    }

    /// Writes the cluster into slot `slot` of a block (as an internal node,
    /// its intensity a unit in channel `c`) and of its cone and spot blocks.
    fn write(&self, slot: usize, c: usize, block: &mut Block, cones: &mut ConeBlock, spots: &mut SpotBlock) {
        let (centre, half) = centre_half(self.lo, self.hi);
        block.child[slot] = Child::internal(1, false);
        let (sin, cos) = self.cone.half_angle.sin_cos();
        for axis in 0..3 {
            block.centre[axis][slot] = centre[axis];
            block.half[axis][slot] = half[axis];
            block.intensity[axis][slot] = if axis == c { 1.0 } else { 0.0 };
            cones.axis[axis][slot] = self.cone.axis[axis];
        }
        cones.cos_half_angle[slot] = if self.cone.half_angle == 0.0 { 1.0 } else { cos };
        cones.sin_half_angle[slot] = if self.cone.half_angle == 0.0 { 0.0 } else { sin };
        spots.min_cos_outer[slot] = self.min_cos_outer;
    }
}

/// The blocks of `clusters` (two per block), as the cut lays them out, for
/// channel `c`.
fn blocks_of(clusters: &[RandomCluster], c: usize) -> Vec<(Block, ConeBlock, SpotBlock)> {
    clusters
        .chunks(2)
        .map(|pair| {
            let (mut block, mut cones, mut spots) = (Block::default(), ConeBlock::default(), SpotBlock::default());
            block.child = [Child::leaf(0), Child::leaf(1)];
            for (slot, cluster) in pair.iter().enumerate() {
                cluster.write(slot, c, &mut block, &mut cones, &mut spots);
            }
            (block, cones, spots)
        })
        .collect()
}

fn cones_of<'a>(kind: LightKind, b: &'a (Block, ConeBlock, SpotBlock)) -> Option<Cones<'a>> {
    kind.has_cone().then_some(Cones { cone: &b.1, spot: (kind == LightKind::Spot).then_some(&b.2) })
}

/// The kernel of the property test: one random cluster of one kind.
fn check_random_cluster(rng: &mut Rng, kind: LightKind) {
    let m = material(rng);
    let sp = surface(rng, &m);
    check_cluster_at(rng, kind, &sp);
}

/// One random cluster of one kind against the bounds at `sp`.
fn check_cluster_at(rng: &mut Rng, kind: LightKind, sp: &SurfacePoint<'_>) {
    let sp = sp.clone();
    let cluster = RandomCluster::new(rng, kind, &sp);
    let slot = rng.below(2) as usize;
    // Channel by channel: the luminance bound against a unit intensity in
    // channel c bounds that channel's M * G, weighted by its luminance weight.
    for c in 0..3 {
        let mut intensity = Vec3::ZERO;
        intensity[c] = 1.0;
        let bound =
            cluster_bound(kind, &sp, cluster.lo, cluster.hi, cluster.cone, cluster.min_cos_outer, intensity, slot);
        assert!(bound.is_finite(), "bound {bound} not finite");
        let value = cluster.largest(kind, &sp, c);
        assert!(
            value <= f64::from(bound) * (1.0 + 1e-6),
            "{kind:?}: channel {c}'s light term {value} exceeds bound {bound} at p={} n={} lights={:?}",
            sp.p,
            sp.n,
            cluster.lights
        );
    }
}

/// The kernel of the property test of the four-lane forms the cut and the
/// walk use when two nodes of one tree are refined or walked together:
/// four random clusters in two blocks. `quad` bounds every slot (and equals
/// `pair` of each block, bit for bit: the lanes are independent);
/// `importance_quad`, the walk's weight, is 0 exactly where the bound is
/// (a child of weight 0 must contribute nothing) and finite or infinite,
/// never NaN.
fn check_random_quad(rng: &mut Rng, kind: LightKind) {
    let m = material(rng);
    let sp = surface(rng, &m);
    let clusters: Vec<RandomCluster> = (0..4).map(|_| RandomCluster::new(rng, kind, &sp)).collect();
    let bounds = PointBounds::new(&sp, 1.0);
    for c in 0..3 {
        let blocks = blocks_of(&clusters, c);
        let quad_cones = cones_of(kind, &blocks[0]).zip(cones_of(kind, &blocks[1])).map(|(a, b)| [a, b]);
        let quad = bounds.quad(kind, [&blocks[0].0, &blocks[1].0], quad_cones);
        let importance = bounds.importance_quad(kind, [&blocks[0].0, &blocks[1].0], quad_cones);
        for (k, cluster) in clusters.iter().enumerate() {
            let pair = bounds.pair(kind, &blocks[k / 2].0, cones_of(kind, &blocks[k / 2]))[k % 2];
            assert_eq!(quad[k].to_bits(), pair.to_bits(), "{kind:?}: slot {k}'s quad bound {} vs pair {pair}", quad[k]);
            let value = cluster.largest(kind, &sp, c);
            assert!(
                value <= f64::from(quad[k]) * (1.0 + 1e-6),
                "{kind:?}: slot {k}, channel {c}: light term {value} exceeds the quad bound {} at p={} lights={:?}",
                quad[k],
                sp.p,
                cluster.lights
            );
            assert!(!importance[k].is_nan() && importance[k] >= 0.0, "{kind:?}: weight {}", importance[k]);
            assert_eq!(
                importance[k] == 0.0,
                quad[k] == 0.0,
                "{kind:?}: slot {k}, channel {c}: weight {} where the bound is {} (light term {value})",
                importance[k],
                quad[k]
            );
        }
    }
}

#[test]
fn quad_bounds_and_walk_weights_hold_at_random_points() {
    for (seed, kind) in LightKind::ALL.into_iter().enumerate() {
        let mut rng = Rng::seeded(20 + seed as u64);
        for _ in 0..5_000 {
            check_random_quad(&mut rng, kind);
        }
    }
}

/// A fibre is lit from every side: its bound (the peak of its f cos)
/// holds for lights behind it as well as in front, for every kind of light
/// and every roughness and colour.
#[test]
fn fibre_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(31);
    for kind in LightKind::ALL {
        for _ in 0..3_000 {
            let m = material(&mut rng);
            let mut sp = surface(&mut rng, &m);
            let tangent = unit(&mut rng).cross(sp.ng).normalize_or(Vec3::X);
            let colour = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let roughness = rng.range_f32(0.0, 1.0);
            sp.fibre = crate::shading::fibre::Fibre::new(tangent, sp.ng, sp.wo, colour, roughness);
            sp.pbr = None;
            assert!(sp.fibre.is_some());
            check_cluster_at(&mut rng, kind, &sp);
        }
    }
}

#[test]
fn omni_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(10);
    for _ in 0..20_000 {
        check_random_cluster(&mut rng, LightKind::Omni);
    }
}

#[test]
fn oriented_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(11);
    for _ in 0..20_000 {
        check_random_cluster(&mut rng, LightKind::Oriented);
    }
}

#[test]
fn spot_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(13);
    for _ in 0..20_000 {
        check_random_cluster(&mut rng, LightKind::Spot);
    }
}

#[test]
fn directional_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(12);
    for _ in 0..20_000 {
        check_random_cluster(&mut rng, LightKind::Directional);
    }
}

#[test]
fn environment_bounds_hold_at_random_points() {
    let mut rng = Rng::seeded(13);
    for _ in 0..20_000 {
        check_random_cluster(&mut rng, LightKind::Environment);
    }
}

#[test]
fn a_point_inside_the_box_gets_a_finite_bound_above_every_light() {
    let m = Material::diffuse("m", Albedo::Constant(Vec3::ONE));
    let mut rng = Rng::seeded(3);
    let sp = surface(&mut rng, &m);
    let (lo, hi) = (sp.p - Vec3::ONE, sp.p + Vec3::ONE);
    let b = cluster_bound(LightKind::Omni, &sp, lo, hi, Cone::of_direction(Vec3::Y), 0.0, Vec3::ONE, 0);
    assert!(b.is_finite() && b > 0.0);
    // A light on top of the point along the normal, at the clamp distance.
    let near = term(LightKind::Omni, &sp, sp.p + sp.n * 1e-9, Vec3::ZERO, [0.0; 2]);
    let luminance = 0.2126 * near.x + 0.7152 * near.y + 0.0722 * near.z;
    assert!(luminance <= f64::from(b) && near.is_finite());
}

/// [MDLC06]'s pairs: every node of a gather tree (the shipping tree
/// builder's, over points spread in position and normal, of diffuse, Phong
/// and metallic-roughness materials, with strengths) against a light
/// cluster bounds S_sum * M * G * I for every (gather point, light) pair
/// below both: the cluster's true sum and its representative pair's
/// estimate are both at most that.
#[test]
fn gather_cluster_bounds_hold_for_every_pair_below() {
    use crate::light_tree::layout::CutTree;
    use crate::lightcut::multidimensional::{build_gather_tree, GatherPoint, GatherScratch};
    let mut rng = Rng::seeded(2006);
    // Six random materials, and two diffuse ones that whole clusters share
    // (where the normal cone, not a glossy peak, bounds M); of different
    // albedos, so that a cluster's diffuse term must be its largest.
    let mut materials: Vec<Material> = (0..6).map(|_| material(&mut rng)).collect();
    materials.push(Material::diffuse("matte", Albedo::Constant(Vec3::new(0.8, 0.5, 0.3))));
    materials.push(Material::diffuse("dark matte", Albedo::Constant(Vec3::new(0.2, 0.1, 0.05))));
    let mut scratch = GatherScratch::default();
    let (mut checked, mut reached) = (0, 0);
    for _ in 0..600 {
        let centre = Vec3::new(rng.range_f32(-3.0, 3.0), rng.range_f32(-3.0, 3.0), rng.range_f32(-3.0, 3.0));
        let extent = [0.0, 0.003, 0.05, 0.5][rng.below(4) as usize];
        let spread = [0.0, 0.05, 0.6, 3.0][rng.below(4) as usize];
        let axis = unit(&mut rng);
        let uniform = rng.next_f32() < 0.5;
        let matte = rng.next_f32() < 0.4;
        let points: Vec<GatherPoint<'_>> = (0..1 + rng.below(20))
            .map(|_| {
                let m = if matte { 6 + rng.below(2) as usize } else { rng.below(6) as usize };
                let mut sp = surface(&mut rng, &materials[m]);
                let cube = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
                sp.p = centre + extent * cube;
                let n = (axis + spread * unit(&mut rng)).normalize_or(axis);
                (sp.n, sp.ng) = (n, n);
                if sp.wo.dot(n) <= 0.0 {
                    sp.wo = -sp.wo;
                }
                sp.r = reflect(sp.wo, n);
                let strength = if uniform {
                    DVec3::splat(1.0 / 16.0)
                } else {
                    DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0
                };
                GatherPoint { sp, strength }
            })
            .collect();
        build_gather_tree(&points, 1.0, &mut scratch);
        let kind = LightKind::ALL[rng.below(4) as usize];
        let cluster = RandomCluster::new(&mut rng, kind, &points[0].sp);
        let c = rng.below(3) as usize;
        let (mut block, mut cones, mut spots) = (Block::default(), ConeBlock::default(), SpotBlock::default());
        block.child = [Child::EMPTY, Child::EMPTY];
        cluster.write(0, c, &mut block, &mut cones, &mut spots);
        let mut tree = CutTree::exhaustive(kind, Vec::new());
        tree.blocks = vec![block];
        if kind.has_cone() {
            tree.cones = vec![cones];
        }
        if kind == LightKind::Spot {
            tree.spots = vec![spots];
        }
        for g in 0..scratch.node_count() as u32 {
            let bound = f64::from(scratch.pair_bounds(g, &tree, 0)[0]);
            let (below, strength) = scratch.points_below(g);
            let weight = [0.2126, 0.7152, 0.0722][c] * strength[c];
            let largest = below
                .iter()
                .flat_map(|&i| cluster.lights.iter().map(move |l| (i, l)))
                .map(|(i, (p, n, s))| weight * term(kind, &points[i as usize].sp, *p, *n, *s)[c])
                .fold(0.0, f64::max);
            assert!(
                bound >= largest * (1.0 - 1e-5),
                "{kind:?} node {g} of {} ({} points): bound {bound} < {largest}",
                scratch.node_count(),
                below.len()
            );
            checked += 1;
            reached += usize::from(largest > 0.0);
        }
    }
    assert!(reached > checked / 3, "{reached} of {checked} pairs reach their gather points");
}
