//! `UsdGeomBasisCurves` and `UsdGeomPoints` as Embree's own curves and
//! spheres (docs/design.md §4.3): each curve's control points laid out so
//! that every segment reads consecutive points (`wrap = periodic` closes a
//! curve by repeating its first points, `pinned` adds the phantom end
//! points USD's schema defines), and `widths` and the colour primvar read
//! with their interpolation onto the points.

use glam::{DVec3, Vec3};

use super::geometry::Located;
use super::stage::{Failure, Stage};
use crate::scene::mesh::{CurveBasis, Mesh, StrandKind, Strands};

/// The width of a curve or point whose prim authors no `widths` (stage
/// units): Hydra's Storm draws such prims one unit wide.
const DEFAULT_WIDTH: f64 = 1.0;

/// How a curve primvar's values map onto the points (UsdGeomBasisCurves'
/// "Primvar Interpolation": `varying` is one value a segment end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Interpolation {
    Constant,
    Uniform,
    Vertex,
    Varying,
}

/// How a prim's curves are laid out: the basis, the wrap, and the
/// points of each curve.
struct Layout {
    basis: CurveBasis,
    wrap: Wrap,
    counts: Vec<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wrap {
    Open,
    Periodic,
    Pinned,
}

impl Layout {
    /// The number of segments of a curve of `count` points (UsdGeomBasisCurves'
    /// "Segment Indexing"); `None` when the count does not make whole segments.
    fn segments(&self, count: usize) -> Option<usize> {
        let (order, step) = match self.basis {
            CurveBasis::Linear => (2, 1),
            CurveBasis::Bezier => (4, 3),
            CurveBasis::BSpline | CurveBasis::CatmullRom => (4, 1),
        };
        match (self.wrap, self.basis) {
            (Wrap::Periodic, CurveBasis::Bezier) => (count >= 3 && count % 3 == 0).then_some(count / 3),
            (Wrap::Periodic, _) => (count >= order - 1).then_some(count),
            (Wrap::Pinned, CurveBasis::BSpline | CurveBasis::CatmullRom) => (count >= 2).then_some(count - 1),
            _ => (count >= order && (count - order) % step == 0).then(|| (count - order) / step + 1),
        }
    }

    /// The values a `varying` primvar of curve `count` points holds: one a
    /// segment end (one a segment on a periodic curve).
    fn varying(&self, count: usize) -> usize {
        let segments = self.segments(count).unwrap_or(0);
        if self.wrap == Wrap::Periodic {
            segments
        } else {
            segments + 1
        }
    }

    /// The varying value point `j` of a curve of `count` points takes: the
    /// segment end nearest to it.
    fn varying_of(&self, j: usize, count: usize) -> usize {
        let last = self.varying(count).saturating_sub(1);
        let k = match (self.basis, self.wrap) {
            (CurveBasis::Linear, _) | (_, Wrap::Pinned) => j,
            (CurveBasis::Bezier, _) => (j + 1) / 3,
            (_, Wrap::Periodic) => j,
            _ => j.saturating_sub(1),
        };
        k.min(last)
    }
}

/// A curves or points prim as a mesh of strands in the prim's space, with
/// per-point colours read from `colour` (a primvar name and the value
/// where the prim lacks it), or `primvars:displayColor`.
pub(super) fn strands(
    stage: &Stage,
    prim: &str,
    type_name: &str,
    time: f64,
    colour: Option<(&str, DVec3)>,
) -> Result<Mesh, Located> {
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let points = stage.vec3s(prim, "points", time).map_err(|e| (at("points"), e))?.unwrap_or_default();
    super::geometry::check_points(prim, &points)?;
    let layout = if type_name == "Points" { None } else { Some(curve_layout(stage, prim, time, points.len())?) };
    let (layout, count) = (layout.as_ref(), points.len());
    // Without metadata `widths` is per vertex (UsdGeomCurves), a primvar constant.
    let widths = read_primvar(stage, prim, "widths", time, (layout, count), Interpolation::Vertex, Stage::numbers)?;
    let widths = widths.unwrap_or_else(|| vec![DEFAULT_WIDTH; points.len()]);
    if let Some(w) = widths.iter().find(|w| !w.is_finite() || **w < 0.0) {
        return Err((at("widths"), format!("a width must be finite and >= 0, got {w}")));
    }
    let colour_name = colour.map_or_else(|| "primvars:displayColor".to_string(), |(n, _)| format!("primvars:{n}"));
    let colours =
        read_primvar(stage, prim, &colour_name, time, (layout, count), Interpolation::Constant, Stage::colours)?
            .or_else(|| colour.map(|(_, fallback)| vec![fallback; points.len()]));
    if colours.as_ref().is_some_and(|c| c.iter().any(|c| !c.is_finite())) {
        return Err((at(&colour_name), "holds a value that is not finite".into()));
    }
    let radii: Vec<f32> = widths.iter().map(|w| (0.5 * w) as f32).collect();
    let positions: Vec<Vec3> = points.iter().map(|p| p.as_vec3()).collect();
    let colors = colours.map(|c| c.iter().map(|c| c.as_vec3().max(Vec3::ZERO)).collect::<Vec<_>>());
    let Some(layout) = layout else {
        let strands = Strands { radii, kind: StrandKind::Spheres };
        return Ok(Mesh { positions, colors, strands: Some(strands), ..Mesh::default() });
    };
    // Flat ribbons where normals are authored (they face the ray: Embree's
    // normal-oriented ribbons are not used, docs/design.md §4.3), tubes otherwise.
    let ribbon = stage.has_value(prim, "normals", time).map_err(|e| (at("normals"), e))?;
    Ok(lay_out(layout, &positions, &radii, colors.as_deref(), ribbon))
}

/// The `type`, `basis`, `wrap` and `curveVertexCounts` of a curves prim,
/// checked against its `points_count` points.
fn curve_layout(stage: &Stage, prim: &str, time: f64, points_count: usize) -> Result<Layout, Located> {
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let token = |name: &str, fallback: &str| -> Result<String, Located> {
        Ok(stage.token(prim, name, time).map_err(|e| (at(name), e))?.unwrap_or_else(|| fallback.to_string()))
    };
    let basis = match (token("type", "cubic")?.as_str(), token("basis", "bezier")?.as_str()) {
        ("linear", _) => CurveBasis::Linear,
        ("cubic", "bezier") => CurveBasis::Bezier,
        ("cubic", "bspline") => CurveBasis::BSpline,
        ("cubic", "catmullRom") => CurveBasis::CatmullRom,
        ("cubic", other) => {
            return Err((at("basis"), format!("must be bezier, bspline or catmullRom, got '{other}'")));
        }
        (other, _) => return Err((at("type"), format!("must be linear or cubic, got '{other}'"))),
    };
    let wrap = match token("wrap", "nonperiodic")?.as_str() {
        "nonperiodic" => Wrap::Open,
        "periodic" => Wrap::Periodic,
        "pinned" => Wrap::Pinned,
        other => return Err((at("wrap"), format!("must be nonperiodic, periodic or pinned, got '{other}'"))),
    };
    let counts =
        stage.ints(prim, "curveVertexCounts", time).map_err(|e| (at("curveVertexCounts"), e))?.unwrap_or_default();
    let layout = Layout { basis, wrap, counts: counts.iter().map(|&c| c.max(0) as usize).collect() };
    if let Some((curve, &count)) =
        counts.iter().enumerate().find(|(_, &c)| c < 0 || layout.segments(c as usize).is_none())
    {
        return Err((
            at("curveVertexCounts"),
            format!("curve {curve} has {count} points, which make no whole {basis:?} segments ({wrap:?})"),
        ));
    }
    let total: usize = layout.counts.iter().sum();
    if total != points_count {
        return Err((
            at("curveVertexCounts"),
            format!("the counts add up to {total}, but there are {points_count} points"),
        ));
    }
    Ok(layout)
}

/// Primvar `name` (with its `:indices` and `interpolation`, `fallback`
/// where none is authored) as one value for each of the `points`; the
/// layout is `None` for a points prim, whose `uniform` is one value for the
/// prim and `varying` one a point.
fn read_primvar<T: Copy>(
    stage: &Stage,
    prim: &str,
    name: &str,
    time: f64,
    (layout, points): (Option<&Layout>, usize),
    fallback: Interpolation,
    read: impl Fn(&Stage, &str, &str, f64) -> Result<Option<Vec<T>>, Failure>,
) -> Result<Option<Vec<T>>, Located> {
    let at = |attribute: &str| format!("{prim}.{attribute}");
    let Some(values) = read(stage, prim, name, time).map_err(|e| (at(name), e))? else { return Ok(None) };
    if values.is_empty() {
        return Ok(None);
    }
    let interpolation = match stage.interpolation(prim, name).map_err(|e| (at(name), e))?.as_deref() {
        None => fallback,
        Some("vertex") => Interpolation::Vertex,
        Some("constant") => Interpolation::Constant,
        Some("uniform") => Interpolation::Uniform,
        Some("varying") => Interpolation::Varying,
        Some(other) => return Err((at(name), format!("interpolation '{other}' is not one for curves or points"))),
    };
    let indices_name = format!("{name}:indices");
    let indices = stage.ints(prim, &indices_name, time).map_err(|e| (at(&indices_name), e))?;
    if let Some(bad) = indices.iter().flatten().find(|&&i| i < 0 || i as usize >= values.len()) {
        return Err((at(&indices_name), format!("index {bad} is outside the {} values", values.len())));
    }
    // Element k's value.
    let element = |k: usize| -> Option<T> {
        let i = match &indices {
            Some(indices) => *indices.get(k)? as usize,
            None => k,
        };
        values.get(i).copied()
    };
    // The element each point reads.
    let mut of_point = Vec::with_capacity(points);
    match (interpolation, layout) {
        (Interpolation::Constant, _) | (Interpolation::Uniform, None) => of_point.resize(points, 0),
        (Interpolation::Vertex | Interpolation::Varying, None) | (Interpolation::Vertex, Some(_)) => {
            of_point.extend(0..points);
        }
        (Interpolation::Uniform, Some(layout)) => {
            for (curve, &count) in layout.counts.iter().enumerate() {
                of_point.extend(std::iter::repeat_n(curve, count));
            }
        }
        (Interpolation::Varying, Some(layout)) => {
            let mut first = 0;
            for &count in &layout.counts {
                of_point.extend((0..count).map(|j| first + layout.varying_of(j, count)));
                first += layout.varying(count);
            }
        }
    }
    let needed = of_point.iter().max().map_or(0, |m| m + 1);
    let expanded: Option<Vec<T>> = of_point.iter().map(|&k| element(k)).collect();
    match expanded {
        Some(v) => Ok(Some(v)),
        None => Err((
            at(name),
            format!(
                "has {} values{}; its {interpolation:?} interpolation needs {needed}",
                values.len(),
                indices.as_ref().map_or(String::new(), |i| format!(" and {} indices", i.len()))
            ),
        )),
    }
}

/// The curves as Embree reads them: each curve's points copied so that a
/// periodic curve closes (its first points repeated after its last) and a
/// pinned one reaches its ends (phantom points 2 P0 - P1 before and
/// 2 Pn - Pn-1 after, as UsdGeomBasisCurves defines them), and the first
/// point of every segment.
fn lay_out(layout: &Layout, points: &[Vec3], radii: &[f32], colours: Option<&[Vec3]>, ribbon: bool) -> Mesh {
    let mut positions = Vec::with_capacity(points.len());
    let mut out_radii = Vec::with_capacity(points.len());
    let mut out_colours = colours.map(|_| Vec::with_capacity(points.len()));
    let mut segments = Vec::new();
    let step = if layout.basis == CurveBasis::Bezier { 3 } else { 1 };
    let mut first = 0;
    for &count in &layout.counts {
        let range = first..first + count;
        first += count;
        // The curve's points by index into `points`, with a phantom point as
        // (from, away): 2 points[from] - points[away].
        let mut order: Vec<(usize, Option<usize>)> = range.clone().map(|i| (i, None)).collect();
        match (layout.wrap, layout.basis) {
            (Wrap::Periodic, basis) => {
                let repeat = if basis == CurveBasis::Bezier { 1 } else { basis.order() - 1 };
                order.extend((0..repeat).map(|k| (range.start + k % count, None)));
            }
            (Wrap::Pinned, CurveBasis::BSpline | CurveBasis::CatmullRom) => {
                let (a, z) = (range.start, range.end - 1);
                order.insert(0, (a, Some(a + 1)));
                order.push((z, Some(z - 1)));
            }
            _ => {}
        }
        let base = positions.len() as u32;
        let segment_count = layout.segments(count).unwrap_or(0);
        segments.extend((0..segment_count).map(|s| base + (s * step) as u32));
        for (i, phantom) in order {
            let p = match phantom {
                Some(away) => 2.0 * points[i] - points[away],
                None => points[i],
            };
            positions.push(p);
            out_radii.push(radii[i]);
            if let (Some(out), Some(colours)) = (&mut out_colours, colours) {
                out.push(colours[i]);
            }
        }
    }
    let kind = StrandKind::Curves { basis: layout.basis, ribbon, segments };
    Mesh { positions, colors: out_colours, strands: Some(Strands { radii: out_radii, kind }), ..Mesh::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout(basis: CurveBasis, wrap: Wrap, counts: &[usize]) -> Layout {
        Layout { basis, wrap, counts: counts.to_vec() }
    }

    #[test]
    fn segments_follow_the_schemas_segment_indexing() {
        let open = |basis, count| layout(basis, Wrap::Open, &[]).segments(count);
        assert_eq!(open(CurveBasis::Linear, 5), Some(4));
        assert_eq!(open(CurveBasis::Bezier, 10), Some(3));
        assert_eq!(open(CurveBasis::Bezier, 9), None, "a Bezier curve is 3 n + 1 points");
        assert_eq!(open(CurveBasis::BSpline, 6), Some(3));
        assert_eq!(open(CurveBasis::CatmullRom, 3), None);
        let periodic = |basis, count| layout(basis, Wrap::Periodic, &[]).segments(count);
        assert_eq!(periodic(CurveBasis::BSpline, 6), Some(6));
        assert_eq!(periodic(CurveBasis::Bezier, 9), Some(3));
        assert_eq!(periodic(CurveBasis::Linear, 4), Some(4));
        assert_eq!(layout(CurveBasis::BSpline, Wrap::Pinned, &[]).segments(4), Some(3));
    }

    #[test]
    fn laid_out_curves_close_and_pin_as_the_schema_says() {
        let square = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let radii = [0.1, 0.2, 0.3, 0.4];
        let mesh = lay_out(&layout(CurveBasis::BSpline, Wrap::Periodic, &[4]), &square, &radii, None, false);
        assert_eq!(mesh.positions.len(), 7, "3 points repeated");
        assert_eq!(&mesh.positions[4..], &square[..3]);
        let StrandKind::Curves { segments, .. } = &mesh.strands.as_ref().unwrap().kind else { panic!() };
        assert_eq!(segments, &[0, 1, 2, 3]);
        let pinned = lay_out(&layout(CurveBasis::CatmullRom, Wrap::Pinned, &[4]), &square, &radii, None, false);
        assert_eq!(pinned.positions[0], -Vec3::X, "2 P0 - P1");
        assert_eq!(pinned.positions[5], Vec3::new(-1.0, 1.0, 0.0), "2 P3 - P2");
        let strands = pinned.strands.unwrap();
        assert_eq!(strands.radii, vec![0.1, 0.1, 0.2, 0.3, 0.4, 0.4]);
        let StrandKind::Curves { segments, .. } = &strands.kind else { panic!() };
        assert_eq!(segments, &[0, 1, 2]);
        let bezier =
            lay_out(&layout(CurveBasis::Bezier, Wrap::Open, &[4, 7]), &[Vec3::ZERO; 11], &[1.0; 11], None, true);
        let StrandKind::Curves { segments, ribbon, .. } = &bezier.strands.as_ref().unwrap().kind else { panic!() };
        assert_eq!((segments.as_slice(), *ribbon), (&[0, 4, 7][..], true));
    }

    #[test]
    fn colours_are_interpolated_between_the_points_a_segment_passes_nearest() {
        let values = [0.0f32, 1.0, 2.0, 3.0, 4.0];
        let curves = |basis| Strands {
            radii: vec![0.1; 5],
            kind: StrandKind::Curves { basis, ribbon: false, segments: vec![0, 1] },
        };
        // A B-spline segment from its second point's neighbourhood to its third's.
        assert_eq!(curves(CurveBasis::BSpline).interpolate(&values, 1, 0.25), 2.25);
        assert_eq!(curves(CurveBasis::CatmullRom).interpolate(&values, 0, 1.0), 2.0);
        // Linear and Bezier segments run between their first and last points.
        assert_eq!(curves(CurveBasis::Linear).interpolate(&values, 1, 0.5), 1.5);
        assert_eq!(curves(CurveBasis::Bezier).interpolate(&values, 0, 0.5), 1.5);
        let spheres = Strands { radii: vec![0.1; 5], kind: StrandKind::Spheres };
        assert_eq!(spheres.interpolate(&values, 3, 0.7), 3.0);
    }

    #[test]
    fn varying_values_sit_at_segment_ends() {
        // A Bezier curve of 7 points has 2 segments and 3 varying values,
        // at points 0, 3 and 6; the handles take the nearer end's.
        let bezier = layout(CurveBasis::Bezier, Wrap::Open, &[7]);
        assert_eq!(bezier.varying(7), 3);
        let of: Vec<usize> = (0..7).map(|j| bezier.varying_of(j, 7)).collect();
        assert_eq!(of, [0, 0, 1, 1, 1, 2, 2]);
        // A B-spline of 6 points: 3 segments, 4 values; point j's is j - 1.
        let bspline = layout(CurveBasis::BSpline, Wrap::Open, &[6]);
        assert_eq!(bspline.varying(6), 4);
        let of: Vec<usize> = (0..6).map(|j| bspline.varying_of(j, 6)).collect();
        assert_eq!(of, [0, 0, 1, 2, 3, 3]);
    }
}
