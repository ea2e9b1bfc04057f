//! Upper bounds of a cluster's error at a shading point ([LC05];
//! docs/design.md §8): M_ub * G_ub * I_C, compared on luminance, for both
//! children of a node at once (f32x4 lanes 0 and 1).
//!
//! Everything here is f32 and free of inverse trigonometric functions: the
//! widened cone uses cos(theta - beta) = cos theta cos beta + sin theta
//! sin beta with the cosine and sine of beta stored per node (pbrt-v4's
//! `cosSubClamped`). Intensities are normalised (multiplied by 1 / the
//! trees' total luminance) so that products stay in f32's range. Every
//! rounding is covered by a slack that makes the bound larger, never smaller;
//! each bound is tested to be >= the true maximum over the cluster's lights
//! at 20,000 random configurations per light kind.

use std::f32::consts::PI;

use glam::Vec3;
use wide::{f32x4, CmpEq, CmpGe, CmpGt};

use crate::light::LightKind;
use crate::light_tree::layout::{Block, Cones};
use crate::scene::material::phong_normalisation;
use crate::shading::pbr::{distribution, schlick_weight, visibility_cos, PbrLanes};
use crate::shading::{Lobes, SurfacePoint};
use crate::util::simd::{dot3, pow_upper, splat3, V3};

/// Slack of every cosine bound, relative and absolute: a bound takes a few
/// f32 roundings (dot products, sqrt, divide), each within 2^-24 relative;
/// 1e-5 covers them with a wide margin and changes cut sizes by nothing
/// measurable.
const COS_SLACK: f32 = 1e-5;

/// Relative slack of the final product (five multiplies and a divide, each
/// within 2^-24, and the normalisation's own rounding).
const PRODUCT_SLACK: f32 = 1.0 + 1.0 / 1_048_576.0;

/// Rec. 709 luminance weights (util::color::luminance), for the weighted
/// sums below.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Per lane: a cone's axis with its frame (tangent, bitangent), cos and
/// sin of its half-angle, and for spots the cutoff (see
/// `PointBounds::emission`).
struct ConeLanes {
    frame: Frame,
    cos_beta: f32x4,
    sin_beta: f32x4,
    cutoff: Option<f32x4>,
}

/// Lanes 0 and 1 from a slot pair (lanes 2 and 3 are 0).
#[inline(always)]
fn lanes(pair: [f32; 2]) -> f32x4 {
    f32x4::new([pair[0], pair[1], 0.0, 0.0])
}

#[inline(always)]
fn abs3(a: &V3) -> V3 {
    [a[0].abs(), a[1].abs(), a[2].abs()]
}

#[inline(always)]
fn sub3(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// An orthonormal frame (tangent, bitangent, axis) per lane, with the
/// absolute values the box projection needs.
#[derive(Clone, Copy)]
struct Frame {
    tangent: V3,
    bitangent: V3,
    axis: V3,
    abs_tangent: V3,
    abs_bitangent: V3,
    abs_axis: V3,
}

impl Frame {
    /// The frame of unit `axis` in every lane (per shading point).
    fn splat(axis: Vec3) -> Self {
        let (t, b) = axis.any_orthonormal_pair();
        Self::of(splat3(t), splat3(b), splat3(axis))
    }

    fn of(tangent: V3, bitangent: V3, axis: V3) -> Self {
        Self {
            tangent,
            bitangent,
            axis,
            abs_tangent: abs3(&tangent),
            abs_bitangent: abs3(&bitangent),
            abs_axis: abs3(&axis),
        }
    }

    /// Upper bound of cos(angle between the axis and v) over v in the box of
    /// centre `c` and half-extent `h` (docs/design.md §8.2): along a unit
    /// axis e the box spans e.c -/+ |e|.h, which gives the box of the
    /// rotated box; then w / sqrt(u^2 + v^2 + w^2) at the largest w and the
    /// smallest |u|, |v|. 0 where the whole box is behind the plane.
    #[inline(always)]
    fn cos_bound(&self, c: &V3, h: &V3) -> f32x4 {
        let z1 = dot3(&self.axis, c) + dot3(&self.abs_axis, h);
        let zero = f32x4::ZERO;
        let mx = (dot3(&self.tangent, c).abs() - dot3(&self.abs_tangent, h)).fast_max(zero);
        let my = (dot3(&self.bitangent, c).abs() - dot3(&self.abs_bitangent, h)).fast_max(zero);
        let ratio = z1 / (mx * mx + my * my + z1 * z1).sqrt();
        let bound = (ratio * f32x4::splat(1.0 + COS_SLACK) + f32x4::splat(COS_SLACK)).fast_min(f32x4::ONE);
        z1.cmp_gt(zero).blend(bound, zero)
    }
}

/// Relative slack of the GGX lobe's bound: D and V take a dozen roundings
/// each (2^-24 relative apiece) on top of their bounding cosines.
const GGX_SLACK: f32 = 1e-4;

/// What the metallic-roughness bound needs of a shading point.
struct GgxBounds {
    lanes: PbrLanes,
    /// Frames around the mirror direction and around -wo.
    mirror: Frame,
    back: Frame,
    /// 1 - max(f0): the diffuse part's largest weight (F >= f0).
    diffuse_fresnel: f32x4,
    /// A rough clear coat's frames around its normal and its mirror
    /// direction (docs/design.md §5.10), where its lobe is bounded.
    coat: Option<(Frame, Frame)>,
}

/// What a gather cluster's bounds know of its points' materials
/// ([MDLC06]; docs/design.md §13.3), instead of one point's lobe.
struct ClusterMaterial {
    /// cos and sin of the normal cone's half-angle about `normal`'s axis.
    cos_cone: f32x4,
    sin_cone: f32x4,
    /// Luminance weights x summed strength x the largest f_r cos theta
    /// over every direction, of the cluster's glossy points (Phong or
    /// metallic-roughness): a bound that ignores where the light is.
    glossy: V3,
}

/// A gather cluster ([MDLC06]) as its bounds see it: the box of its
/// points, their normals' cone, the summed strength of its points, the
/// largest diffuse coefficient k_d / pi of its diffuse points and the
/// largest f_r cos theta of its glossy points (per channel, luminance
/// weights not applied), and the smallest distance clamp.
#[derive(Debug, Clone, Copy)]
pub struct GatherBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    pub axis: Vec3,
    pub cos_cone: f32,
    pub strength: Vec3,
    pub diffuse: Vec3,
    pub glossy: Vec3,
    pub min_distance_squared: f32,
}

/// Relative slack of a gather cluster's sums and maxima (each a few f32
/// roundings).
const GATHER_SLACK: f32 = 1.0 + 1e-5;

/// What the bounds need of one shading point, prepared once per point, or
/// of a gather cluster (`PointBounds::gather_cluster`).
pub struct PointBounds {
    p: V3,
    /// Half-extent of a gather cluster's box about `p` (0 for a point):
    /// the vectors from the cluster to a light box of half-extent h lie in
    /// a box of half-extent h + extent, so every bound below holds for the
    /// pair of boxes by bounding over that box.
    extent: V3,
    /// A gather cluster's material bound (None: one point's, below).
    cluster: Option<ClusterMaterial>,
    normal: Frame,
    /// The Phong lobe's frame around the mirror direction, and its exponent.
    phong: Option<(Frame, f32)>,
    /// A metallic-roughness material's lobe (instead of diffuse + Phong).
    ggx: Option<GgxBounds>,
    /// A fibre's largest f cos over every direction (instead of any
    /// surface's lobes; docs/design.md §5.7): per channel, and
    /// luminance-weighted.
    fibre: Option<(Vec3, V3)>,
    /// Luminance weights times the diffuse BRDF k_d / pi, and times the
    /// Phong lobe's peak k_s (n + 2) / (2 pi): M's luminance against an
    /// intensity I is diffuse.I + cos_r^n lobe.I, times cos theta.
    diffuse: V3,
    lobe: V3,
    luminance: V3,
    /// The distance clamp squared (f32, rounded down: 0 if it underflows,
    /// which makes G's bound infinite, still an upper bound).
    min_distance_squared: f32x4,
    /// The lobes the stand-ins of continuous emitters (area lights'
    /// points, the environment's directions) light the point with
    /// (`SurfacePoint::emitter_lobes`; every lobe for a gather cluster).
    emitter_lobes: Lobes,
    /// 1 / the trees' total luminance: normalises intensities.
    scale: f32x4,
}

impl PointBounds {
    /// `scale` normalises intensities (see [`crate::light_tree::LightTrees::scale`]).
    #[must_use]
    #[inline(always)]
    pub fn new(sp: &SurfacePoint<'_>, scale: f32) -> Self {
        let m = sp.material;
        let lobe = if m.has_specular() { m.specular * phong_normalisation(m.exponent) } else { Vec3::ZERO };
        let clamp32 = min_distance_squared_f32(sp);
        Self {
            p: splat3(sp.p),
            extent: splat3(Vec3::ZERO),
            cluster: None,
            normal: Frame::splat(sp.n),
            phong: m.has_specular().then(|| (Frame::splat(sp.r), m.exponent)),
            ggx: sp.pbr.map(|pbr| {
                let lanes = PbrLanes::new(&pbr, sp.n.dot(sp.wo), sp.coat_n, sp.coat_cos_view());
                GgxBounds {
                    lanes,
                    mirror: Frame::splat(sp.r),
                    back: Frame::splat(-sp.wo),
                    diffuse_fresnel: f32x4::splat(1.0 - pbr.f0.max_element()),
                    coat: lanes.coat.map(|_| {
                        (Frame::splat(sp.coat_n), Frame::splat(crate::scene::material::reflect(sp.wo, sp.coat_n)))
                    }),
                }
            }),
            fibre: sp.fibre.map(|f| {
                let peak = f.peak();
                (peak, splat3(LUMINANCE * peak))
            }),
            diffuse: splat3(LUMINANCE * sp.kd * (1.0 / PI)),
            lobe: splat3(LUMINANCE * lobe),
            luminance: splat3(LUMINANCE),
            min_distance_squared: f32x4::splat(clamp32),
            emitter_lobes: sp.emitter_lobes,
            scale: f32x4::splat(scale),
        }
    }

    /// The bounds of a gather cluster ([MDLC06]): for every pair of one of
    /// its points and one light of a slot, a bound of S M G I (S the
    /// point's strength), which also bounds the representative pair's
    /// estimate S_sum M_rep G_rep I (docs/design.md §13.3).
    #[must_use]
    pub fn gather_cluster(g: &GatherBounds, scale: f32) -> Self {
        let (centre, half) = crate::light_tree::layout::centre_half(g.lo, g.hi);
        let cos_cone = g.cos_cone.clamp(-1.0, 1.0);
        let sin_cone = (1.0 - cos_cone * cos_cone).max(0.0).sqrt();
        let weights = LUMINANCE * g.strength * GATHER_SLACK * GATHER_SLACK;
        Self {
            p: splat3(centre),
            extent: splat3(half),
            cluster: Some(ClusterMaterial {
                cos_cone: f32x4::splat(cos_cone),
                sin_cone: f32x4::splat(sin_cone * GATHER_SLACK),
                glossy: splat3(weights * g.glossy),
            }),
            normal: Frame::splat(g.axis),
            phong: None,
            ggx: None,
            fibre: None,
            diffuse: splat3(weights * g.diffuse),
            lobe: splat3(Vec3::ZERO),
            luminance: splat3(LUMINANCE),
            min_distance_squared: f32x4::splat(g.min_distance_squared),
            emitter_lobes: Lobes::ALL,
            scale: f32x4::splat(scale),
        }
    }

    /// One point's terms for a gather cluster ([`GatherBounds`]): (k_d /
    /// pi, 0) for a diffuse material; (0, the largest f_r cos theta over
    /// every direction) for a glossy one, which is this point's own bound
    /// over a box holding every unit vector.
    #[must_use]
    pub fn gather_terms(&self, kd: Vec3) -> (Vec3, Vec3) {
        if let Some((peak, _)) = self.fibre {
            return (Vec3::ZERO, peak);
        }
        if self.phong.is_none() && self.ggx.is_none() {
            return (kd * (1.0 / PI), Vec3::ZERO);
        }
        let (c, h) = (splat3(Vec3::ZERO), splat3(Vec3::ONE));
        let peak = |axis: Vec3| {
            let (cos_theta, weighted) = self.material(&c, &h, &splat3(axis), Lobes::ALL);
            (cos_theta * weighted).to_array()[0]
        };
        let luminance_weighted = Vec3::new(peak(Vec3::X), peak(Vec3::Y), peak(Vec3::Z));
        (Vec3::ZERO, luminance_weighted / LUMINANCE)
    }

    /// M's bound against the slots' intensities, luminance-weighted:
    /// cos_theta * (diffuse.I + cos_r^n lobe.I), for directions in the boxes
    /// (c, h) (vectors from the shading point; any length), of the
    /// material's `lobes` (a gather cluster's bound covers every lobe).
    #[inline(always)]
    fn material(&self, c: &V3, h: &V3, intensity: &V3, lobes: Lobes) -> (f32x4, f32x4) {
        if let Some(cluster) = &self.cluster {
            // cos(n, v) <= cos(max(0, theta_min - beta)) for n in the cone.
            let cos_theta =
                widen(self.normal.cos_bound(c, h), cluster.cos_cone, cluster.sin_cone).fast_max(f32x4::ZERO);
            let weighted = cos_theta * dot3(&self.diffuse, intensity) + dot3(&cluster.glossy, intensity);
            return (weighted.cmp_gt(f32x4::ZERO).blend(f32x4::ONE, f32x4::ZERO), weighted);
        }
        if let Some((_, peak)) = &self.fibre {
            // Lit from every side: no cosine, the peak towards any box.
            return (f32x4::ONE, dot3(peak, intensity));
        }
        if let Some(ggx) = &self.ggx {
            return self.ggx(ggx, c, h, intensity, lobes);
        }
        let cos_theta = self.normal.cos_bound(c, h);
        let mut weighted = if lobes.diffuse { dot3(&self.diffuse, intensity) } else { f32x4::ZERO };
        if let Some((frame, exponent)) = self.phong.as_ref().filter(|_| lobes.glossy) {
            // cos^n is increasing in cos: the bound of cos_r, raised to n, bounds it.
            let lobe = pow_upper(frame.cos_bound(c, h), *exponent);
            weighted += dot3(&self.lobe, intensity) * lobe;
        }
        (cos_theta, weighted)
    }

    /// A metallic-roughness material's bound (docs/design.md §8.3): every
    /// factor of f_r cos theta is monotonic in one cosine, each bounded
    /// over the box: n.l by the normal's cosine bound; n.h <= cos(half the
    /// smallest angle between the mirror direction r and the box) (a
    /// half-vector h tilted by delta from n reflects wo to within 2 delta
    /// of r), so n.h <= sqrt((1 + cos_ub(r)) / 2); v.h = sqrt((1 + wo.wi) /
    /// 2) >= sqrt((1 - cos_ub(-wo)) / 2), which bounds Schlick's weight.
    /// Returns (1 where the box is above the surface's plane, else 0; the
    /// luminance-weighted bound, cosine included).
    #[inline(always)]
    fn ggx(&self, ggx: &GgxBounds, c: &V3, h: &V3, intensity: &V3, lobes: Lobes) -> (f32x4, f32x4) {
        let (zero, one) = (f32x4::ZERO, f32x4::ONE);
        let slack = |x: f32x4| (x * f32x4::splat(1.0 + COS_SLACK) + f32x4::splat(COS_SLACK)).fast_min(one);
        let cos_theta = self.normal.cos_bound(c, h);
        let n_dot_h = slack((f32x4::splat(0.5) * (one + ggx.mirror.cos_bound(c, h))).sqrt());
        let v_dot_h = (f32x4::splat(0.5) * (one - ggx.back.cos_bound(c, h)).fast_max(zero)).sqrt();
        let v_dot_h = (v_dot_h * f32x4::splat(1.0 - COS_SLACK) - f32x4::splat(COS_SLACK)).fast_max(zero);
        let lanes = &ggx.lanes;
        let specular = distribution(n_dot_h, lanes.alpha2)
            * visibility_cos(cos_theta, lanes.n_dot_v, lanes.alpha2)
            * f32x4::splat(1.0 + GGX_SLACK);
        let specular = if lobes.glossy && lanes.glossy { specular } else { zero };
        let diffuse_fresnel = if lobes.diffuse { ggx.diffuse_fresnel } else { zero };
        let m = lanes.combine(cos_theta, specular, schlick_weight(v_dot_h), diffuse_fresnel);
        let m = if lanes.is_layered() {
            // The coat's cosines about its own normal, as the base's.
            let coat = ggx.coat.as_ref().map_or((zero, zero), |(normal, mirror)| {
                (normal.cos_bound(c, h), slack((f32x4::splat(0.5) * (one + mirror.cos_bound(c, h))).sqrt()))
            });
            lanes.layers_bound(m, cos_theta, coat, lobes)
        } else {
            m
        };
        let weighted = dot3(&[m[0] * self.luminance[0], m[1] * self.luminance[1], m[2] * self.luminance[2]], intensity);
        (cos_theta.cmp_gt(zero).blend(one, zero), weighted)
    }

    /// G's bound for point lights in the boxes: 1 / max(d_min^2, clamp^2),
    /// with d_min the distance from the point to the box (0 inside it). The
    /// clamp is the one the exact evaluation applies, so the bound stays
    /// finite inside a box.
    #[inline(always)]
    fn geometric(&self, c: &V3, h: &V3, estimate: bool) -> f32x4 {
        if estimate {
            // The stochastic walk's importance: 1 / the squared distance to
            // the box's centre, no closer than the box's half-diagonal or
            // the clamp (pbrt-v4's LightBounds::Importance does the like).
            // Not a bound, only a weight: it is never 0.
            let d = sub3(c, &self.p);
            return f32x4::ONE / dot3(&d, &d).fast_max(dot3(h, h)).fast_max(self.min_distance_squared);
        }
        let zero = f32x4::ZERO;
        let d = [
            ((c[0] - self.p[0]).abs() - h[0]).fast_max(zero),
            ((c[1] - self.p[1]).abs() - h[1]).fast_max(zero),
            ((c[2] - self.p[2]).abs() - h[2]).fast_max(zero),
        ];
        // Rounded down a little: the squared distance's roundings must not
        // make G's bound smaller.
        let d2 = dot3(&d, &d) * f32x4::splat(1.0 - 1.0 / 1_048_576.0);
        f32x4::ONE / d2.fast_max(self.min_distance_squared)
    }

    /// The normalised error bounds of a block's two slots: luminance of
    /// M_ub * G_ub * I_C times the normalisation. 0 for an exact slot (a
    /// leaf, or coincident lights) and for a cluster that cannot reach the
    /// point; never NaN.
    #[must_use]
    #[inline(always)]
    pub fn pair(&self, kind: LightKind, block: &Block, cones: Option<Cones<'_>>) -> [f32; 2] {
        let [b0, b1] = self.importance(kind, block, cones);
        let exact = |k: usize| block.child[k].is_exact();
        [if exact(0) { 0.0 } else { b0 }, if exact(1) { 0.0 } else { b1 }]
    }

    /// The same bound of both slots, exact ones included: an upper bound of
    /// each slot's unoccluded contribution (normalised), 0 only where no
    /// light of the slot can reach the point. The stochastic cut's
    /// importance.
    #[must_use]
    #[inline(always)]
    pub fn importance(&self, kind: LightKind, block: &Block, cones: Option<Cones<'_>>) -> [f32; 2] {
        let gather = |pairs: &[[f32; 2]; 3]| -> V3 { [lanes(pairs[0]), lanes(pairs[1]), lanes(pairs[2])] };
        let cone = cones.map(|Cones { cone: c, spot }| ConeLanes {
            frame: Frame::of(gather(&c.tangent), gather(&c.bitangent), gather(&c.axis)),
            cos_beta: lanes(c.cos_half_angle),
            sin_beta: lanes(c.sin_half_angle),
            cutoff: spot.map(|s| lanes(s.min_cos_outer)),
        });
        let [b0, b1, ..] = self
            .lanes(kind, &gather(&block.centre), &gather(&block.half), &gather(&block.intensity), cone.as_ref(), false)
            .to_array();
        [b0, b1]
    }

    /// The bounds of the slots of two blocks of one tree at once, in the
    /// order (first's 0, first's 1, second's 0, second's 1).
    #[must_use]
    #[inline(always)]
    pub fn quad(&self, kind: LightKind, blocks: [&Block; 2], cones: Option<[Cones<'_>; 2]>) -> [f32; 4] {
        let [b0, b1, b2, b3] = self.quad_lanes(kind, blocks, cones, false);
        let [[c0, c1], [c2, c3]] = [blocks[0].child, blocks[1].child];
        let exact = |c: crate::light_tree::layout::Child, b: f32| if c.is_exact() { 0.0 } else { b };
        [exact(c0, b0), exact(c1, b1), exact(c2, b2), exact(c3, b3)]
    }

    /// The stochastic walk's weights of the slots of two blocks of one
    /// tree, in the order (first's 0, first's 1, second's 0, second's 1):
    /// like [`PointBounds::importance`], but with G estimated at the box's
    /// centre (an estimate of the slot's contribution, not a bound). 0
    /// exactly where the bound is 0: where no light of the slot can reach
    /// the point.
    #[must_use]
    #[inline(always)]
    pub fn importance_quad(&self, kind: LightKind, blocks: [&Block; 2], cones: Option<[Cones<'_>; 2]>) -> [f32; 4] {
        self.quad_lanes(kind, blocks, cones, true)
    }

    #[inline(always)]
    fn quad_lanes(
        &self,
        kind: LightKind,
        blocks: [&Block; 2],
        cones: Option<[Cones<'_>; 2]>,
        estimate: bool,
    ) -> [f32; 4] {
        let two = |a: [f32; 2], b: [f32; 2]| f32x4::new([a[0], a[1], b[0], b[1]]);
        let gather = |field: fn(&Block) -> &[[f32; 2]; 3]| -> V3 {
            let (a, b) = (field(blocks[0]), field(blocks[1]));
            [two(a[0], b[0]), two(a[1], b[1]), two(a[2], b[2])]
        };
        let cone = cones.map(|[a, b]| {
            let cutoff = a.spot.zip(b.spot).map(|(x, y)| two(x.min_cos_outer, y.min_cos_outer));
            let (a, b) = (a.cone, b.cone);
            let pairs = |x: &[[f32; 2]; 3], y: &[[f32; 2]; 3]| [two(x[0], y[0]), two(x[1], y[1]), two(x[2], y[2])];
            ConeLanes {
                frame: Frame::of(
                    pairs(&a.tangent, &b.tangent),
                    pairs(&a.bitangent, &b.bitangent),
                    pairs(&a.axis, &b.axis),
                ),
                cos_beta: two(a.cos_half_angle, b.cos_half_angle),
                sin_beta: two(a.sin_half_angle, b.sin_half_angle),
                cutoff,
            }
        });
        self.lanes(
            kind,
            &gather(|b| &b.centre),
            &gather(|b| &b.half),
            &gather(|b| &b.intensity),
            cone.as_ref(),
            estimate,
        )
        .to_array()
    }

    /// The bounds of up to four clusters, one per lane: boxes (centre `c`,
    /// half-extent `h`), summed intensities, and for oriented lights the
    /// cones (axis, cos and sin of the half-angle).
    #[inline(always)]
    /// `estimate`: G is the walk's estimate instead of its bound (see
    /// [`PointBounds::importance_quad`]).
    #[allow(clippy::too_many_arguments)]
    fn lanes(
        &self,
        kind: LightKind,
        c: &V3,
        h: &V3,
        intensity: &V3,
        cone: Option<&ConeLanes>,
        estimate: bool,
    ) -> f32x4 {
        let (cos_theta, weighted, geometric) = match kind {
            LightKind::Directional | LightKind::Environment => {
                let lobes = if kind == LightKind::Environment { self.emitter_lobes } else { Lobes::ALL };
                let (cos_theta, weighted) = self.material(c, h, intensity, lobes);
                (cos_theta, weighted, f32x4::ONE)
            }
            LightKind::Omni | LightKind::Area | LightKind::Oriented | LightKind::Spot => {
                // (A point's extent is 0: h + 0 is h, bit for bit.)
                let h = &add3(h, &self.extent);
                let to_box = sub3(c, &self.p);
                let lobes = if kind == LightKind::Area { self.emitter_lobes } else { Lobes::ALL };
                let (cos_theta, weighted) = self.material(&to_box, h, intensity, lobes);
                let mut geometric = self.geometric(c, h, estimate);
                if let Some(cone) = cone {
                    geometric *= self.emission(c, h, cone);
                }
                (cos_theta, weighted, geometric)
            }
        };
        let zero = f32x4::ZERO;
        let bound = cos_theta * (weighted * self.scale) * geometric;
        let bound = bound * f32x4::splat(PRODUCT_SLACK) + f32x4::splat(f32::MIN_POSITIVE);
        // inf * 0 (an unreachable box inside the clamp) is NaN: count it as
        // infinite, the bound that is always safe.
        let bound = bound.cmp_eq(bound).blend(bound, f32x4::splat(f32::INFINITY));
        let reaches = cos_theta.cmp_gt(zero) & weighted.cmp_gt(zero) & geometric.cmp_gt(zero);
        reaches.blend(bound, zero)
    }

    /// Oriented lights: the bound of max(0, cos phi) over the cluster,
    /// phi between a light's normal and the direction to the point.
    /// theta_min, the smallest angle between the cone's axis and x - y over
    /// the box, has an upper-bounded cosine; with the cone's half-angle beta,
    /// cos phi <= cos(max(theta_min - beta, 0)) = 1 when theta_min <= beta,
    /// else cos theta cos beta + sin theta sin beta.
    #[inline(always)]
    /// Spots (`cutoff`: the smallest cosine of an outer angle in the
    /// cluster): no light shines at the point when theta_min - beta is
    /// beyond the widest outer angle; otherwise the falloff is at most 1.
    fn emission(&self, c: &V3, h: &V3, cone: &ConeLanes) -> f32x4 {
        let ConeLanes { frame, cos_beta, sin_beta, cutoff } = *cone;
        let from_box = sub3(&self.p, c);
        let widened = widen(frame.cos_bound(&from_box, h), cos_beta, sin_beta);
        match cutoff {
            Some(cutoff) => widened.cmp_gt(cutoff).blend(f32x4::ONE, f32x4::ZERO),
            None => widened.fast_max(f32x4::ZERO),
        }
    }
}

/// The point's distance clamp squared in f32, rounded down (0 if it
/// underflows, which makes G's bound infinite, still an upper bound).
#[must_use]
pub fn min_distance_squared_f32(sp: &SurfacePoint<'_>) -> f32 {
    let clamp = sp.min_distance_squared();
    let clamp32 = clamp as f32;
    if f64::from(clamp32) > clamp {
        f32::from_bits(clamp32.to_bits() - 1)
    } else {
        clamp32
    }
}

/// cos(max(theta - beta, 0)) from theta's cosine bound and beta's cosine
/// and sine: 1 when theta <= beta, else cos theta cos beta + sin theta sin
/// beta, with the cosine slack.
#[inline(always)]
fn widen(cos_theta: f32x4, cos_beta: f32x4, sin_beta: f32x4) -> f32x4 {
    let sin_theta = (f32x4::ONE - cos_theta * cos_theta).fast_max(f32x4::ZERO).sqrt();
    let widened = cos_theta * cos_beta + sin_theta * sin_beta;
    let widened = (widened * f32x4::splat(1.0 + COS_SLACK) + f32x4::splat(COS_SLACK)).fast_min(f32x4::ONE);
    cos_theta.cmp_ge(cos_beta).blend(f32x4::ONE, widened)
}

#[inline(always)]
fn add3(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Upper bound of cos(angle between unit `axis` and v) over v in the box
/// [lo, hi], by the same code as the cut's (for tests and one-off use).
#[must_use]
pub fn cos_bound(axis: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    Frame::splat(axis).cos_bound(&splat3(c), &splat3(h)).to_array()[0]
}

#[cfg(test)]
mod tests;
