//! Transforms: a prim's `xformOpOrder` composed into its local matrix, and
//! its world matrix as its ancestors' (UsdGeomXformable: the first op in the
//! order is the outermost, so the local matrix is op_0 op_1 ... op_n-1 on
//! column vectors; `!invert!` ops invert, `!resetXformStack!` drops the
//! parents'). Matrices are f64 until they reach the scene, as USD's are.

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::stage::{Failure, Stage};

/// The local matrix of `prim` at `time`: identity when it has no ops.
/// Returns whether it resets its parents' transforms too.
pub(super) fn local(stage: &Stage, prim: &str, time: f64) -> Result<(DMat4, bool), (String, Failure)> {
    let wrong = |attribute: &str, message: String| (format!("{prim}.{attribute}"), message);
    let Some(order) = stage.tokens(prim, "xformOpOrder", time).map_err(|e| wrong("xformOpOrder", e))? else {
        return Ok((DMat4::IDENTITY, false));
    };
    let mut matrix = DMat4::IDENTITY;
    let mut resets = false;
    for op in &order {
        if op == "!resetXformStack!" {
            // Everything before it (and the parents) is dropped.
            matrix = DMat4::IDENTITY;
            resets = true;
            continue;
        }
        let (inverted, name) = match op.strip_prefix("!invert!") {
            Some(name) => (true, name),
            None => (false, op.as_str()),
        };
        let m = op_matrix(stage, prim, name, time).map_err(|e| wrong(name, e))?;
        let m = if inverted {
            if m.determinant().abs() < 1e-300 {
                return Err(wrong(name, "an inverted op that cannot be inverted (determinant 0)".into()));
            }
            m.inverse()
        } else {
            m
        };
        matrix *= m;
    }
    if !matrix.is_finite() {
        return Err(wrong("xformOpOrder", "the ops compose to a matrix that is not finite".into()));
    }
    Ok((matrix, resets))
}

/// The attributes a prim's transform reads (to find which vary in time).
pub(super) fn op_names(stage: &Stage, prim: &str, time: f64) -> Result<Vec<String>, (String, Failure)> {
    let order = stage.tokens(prim, "xformOpOrder", time).map_err(|e| (format!("{prim}.xformOpOrder"), e))?;
    Ok(order
        .unwrap_or_default()
        .into_iter()
        .filter(|op| op != "!resetXformStack!")
        .map(|op| op.strip_prefix("!invert!").map_or(op.clone(), str::to_string))
        .collect())
}

/// One op's matrix. Its name is `xformOp:KIND` or `xformOp:KIND:SUFFIX`.
fn op_matrix(stage: &Stage, prim: &str, name: &str, time: f64) -> Result<DMat4, Failure> {
    let kind = name
        .strip_prefix("xformOp:")
        .ok_or_else(|| format!("'{name}' in xformOpOrder is not an xformOp"))?
        .split(':')
        .next()
        .unwrap_or_default();
    let absent = || format!("{name} is named in xformOpOrder but has no value");
    let vector = || stage.vec3(prim, name, time)?.ok_or_else(absent);
    let angle = || stage.number(prim, name, time)?.ok_or_else(absent);
    Ok(match kind {
        "translate" => DMat4::from_translation(vector()?),
        "scale" => DMat4::from_scale(vector()?),
        "rotateX" => DMat4::from_rotation_x(angle()?.to_radians()),
        "rotateY" => DMat4::from_rotation_y(angle()?.to_radians()),
        "rotateZ" => DMat4::from_rotation_z(angle()?.to_radians()),
        "rotateXYZ" => euler([0, 1, 2], vector()?),
        "rotateXZY" => euler([0, 2, 1], vector()?),
        "rotateYXZ" => euler([1, 0, 2], vector()?),
        "rotateYZX" => euler([1, 2, 0], vector()?),
        "rotateZXY" => euler([2, 0, 1], vector()?),
        "rotateZYX" => euler([2, 1, 0], vector()?),
        "orient" => {
            let q: DQuat = stage.quat(prim, name, time)?.ok_or_else(absent)?;
            let length = q.length();
            if !(length.is_finite() && length > 0.0) {
                return Err(format!("{name} must be a non-zero finite quaternion"));
            }
            DMat4::from_quat(q / length)
        }
        "transform" => stage.matrix(prim, name, time)?.ok_or_else(absent)?,
        other => return Err(format!("'{other}' is not an xformOp this renderer knows")),
    })
}

/// A three-axis rotation op: `rotateXYZ` (axes [0, 1, 2]) turns about X
/// first, then Y, then Z, so on column vectors it is Rz Ry Rx; `degrees`
/// holds each axis's angle at that axis's index.
fn euler(axes: [usize; 3], degrees: DVec3) -> DMat4 {
    let about = |axis: usize| {
        let r = degrees[axis].to_radians();
        DMat4::from_mat3(match axis {
            0 => DMat3::from_rotation_x(r),
            1 => DMat3::from_rotation_y(r),
            _ => DMat3::from_rotation_z(r),
        })
    };
    let [first, second, third] = axes;
    about(third) * about(second) * about(first)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotate_xyz_turns_about_x_first() {
        // (0, 1, 0) turned 90 degrees about X is (0, 0, 1), which 90 about
        // Z leaves; turned about Z first it would be (-1, 0, 0).
        let p = euler([0, 1, 2], DVec3::new(90.0, 0.0, 90.0)).transform_point3(DVec3::Y);
        assert!((p - DVec3::Z).length() < 1e-12, "{p}");
        // rotateZYX: Z first, (0, 1, 0) -> (-1, 0, 0), then X leaves it.
        let p = euler([2, 1, 0], DVec3::new(90.0, 0.0, 90.0)).transform_point3(DVec3::Y);
        assert!((p - DVec3::NEG_X).length() < 1e-12, "{p}");
    }
}
