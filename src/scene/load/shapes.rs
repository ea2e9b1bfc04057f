//! The `[[shapes]]`: quads, boxes, spheres and OBJ meshes, each with its
//! material and an optional name (Cryptomatte's object name).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::{within_limits, Validator, MAX_COORDINATE};
use glam::Vec3;

use crate::scene::file::{self, BoxSpec, MeshSpec, MotionSpec, QuadSpec, SceneFile, ShapeSpec, SphereSpec};
use crate::scene::object::Motion;
use crate::scene::{Mesh, SceneError};

/// The shapes' meshes, in file order, each with its motion over the shutter.
pub(super) fn shapes(
    v: &Validator<'_>,
    base: &Path,
    spec: &SceneFile,
    material_index: &HashMap<String, usize>,
    inputs: &mut Vec<PathBuf>,
) -> Result<Vec<(Mesh, Option<Motion>)>, SceneError> {
    let mut meshes = Vec::new();
    for (i, raw) in spec.shapes.iter().enumerate() {
        let field = |f: &str| format!("shapes[{i}].{f}");
        let entry_error = |e: file::SpecError| v.error(&format!("shapes[{i}]{}", e.field()), &e.to_string());
        let mut raw = raw.clone();
        let name = file::take_string(&mut raw, "name", ".name").map_err(entry_error)?;
        let motion = file::take_motion(&mut raw).map_err(entry_error)?;
        let shape = ShapeSpec::parse(&raw).map_err(entry_error)?;
        let material_of = |name: &String| {
            material_index
                .get(name)
                .copied()
                .ok_or_else(|| v.error(&field("material"), &format!("no material named '{name}' in [materials]")))
        };
        let mesh = match &shape {
            ShapeSpec::Quad(QuadSpec { corner, u, v: edge_v, material }) => {
                let m = material_of(material)?;
                let (c, u, w) =
                    (v.point(*corner, &field("corner"))?, v.point(*u, &field("u"))?, v.point(*edge_v, &field("v"))?);
                v.check(u.cross(w).length() > 0.0, &field("v"), || {
                    "the quad has zero area (u and v are parallel)".into()
                })?;
                Mesh::quad(c, u, w, m)
            }
            ShapeSpec::Box(BoxSpec { min, max, material }) => {
                let m = material_of(material)?;
                let (lo, hi) = (v.point(*min, &field("min"))?, v.point(*max, &field("max"))?);
                v.check(lo.cmplt(hi).all(), &field("max"), || {
                    format!("must exceed min in x, y and z, got {max:?} vs {min:?}")
                })?;
                Mesh::cuboid(lo, hi, m)
            }
            ShapeSpec::Sphere(SphereSpec { center, radius, material, segments }) => {
                let m = material_of(material)?;
                let c = v.point(*center, &field("center"))?;
                v.check(radius.is_finite() && *radius > 0.0, &field("radius"), || {
                    format!("must be finite and > 0, got {radius}")
                })?;
                v.check((3..=4096).contains(segments), &field("segments"), || {
                    format!("must be between 3 and 4096, got {segments}")
                })?;
                Mesh::sphere(c, *radius, *segments, m)
            }
            ShapeSpec::Mesh(MeshSpec { file, material, scale, translate }) => {
                let m = material_of(material)?;
                v.check(scale.is_finite() && *scale > 0.0, &field("scale"), || {
                    format!("must be finite and > 0, got {scale}")
                })?;
                let t = v.point(*translate, &field("translate"))?;
                let mesh_path = base.join(file);
                inputs.push(mesh_path.clone());
                if !mesh_path.is_file() {
                    return Err(v.error(&field("file"), &format!("mesh file '{}' not found", mesh_path.display())));
                }
                Mesh::load_obj(&mesh_path, *scale, t, m)?
            }
        };
        if let Some(bad) = mesh.positions.iter().position(|p| !within_limits(*p)) {
            return Err(v.error(
                &format!("shapes[{i}]"),
                &format!(
                    "vertex {bad} is {}: coordinates must be finite and within +/-{MAX_COORDINATE:e} m",
                    mesh.positions[bad]
                ),
            ));
        }
        let (lo, hi) = mesh.bounds();
        let motion = motion.map(|m| motion_of(v, &m, 0.5 * (lo + hi), &field("motion"))).transpose()?;
        meshes.push((Mesh { name: name.unwrap_or_else(|| format!("shapes[{i}]")), ..mesh }, motion));
    }
    Ok(meshes)
}

/// A shape's `motion`, about `centre` (its box's centre at the shutter's
/// open); `field` names it.
fn motion_of(v: &Validator<'_>, spec: &MotionSpec, centre: Vec3, field: &str) -> Result<Motion, SceneError> {
    let translate = v.point(spec.translate, &format!("{field}.translate"))?;
    let degrees = spec.rotate_degrees;
    v.check(degrees.is_finite() && degrees.abs() <= 360.0, &format!("{field}.rotate_degrees"), || {
        format!("must be between -360 and 360 degrees, got {degrees}")
    })?;
    let axis = match spec.rotate_axis {
        Some(axis) => v.point(axis, &format!("{field}.rotate_axis"))?,
        None => Vec3::ZERO,
    };
    v.check(degrees == 0.0 || axis.length() > 0.0, &format!("{field}.rotate_axis"), || {
        "must be given, and not zero, when rotate_degrees is".into()
    })?;
    let motion = Motion::rigid(centre, translate, axis, degrees);
    v.check(motion.steps.iter().all(|s| s.is_finite()), field, || "the motion's placements are not finite".into())?;
    Ok(motion)
}
