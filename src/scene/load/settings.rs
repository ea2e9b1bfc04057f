//! The scene's settings: film, camera (the TOML's or the glTF file's),
//! environment and indirect light.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::lights::MAX_EMISSION;
use super::Validator;
use crate::scene::file::ImportedCamera;
use crate::scene::file::{self, SceneFile};
use crate::scene::{
    check_resolution, Environment, EnvironmentMap, Film, Indirect, PathSettings, SceneError, VplSettings,
    DEFAULT_GLTF_WIDTH, DEFAULT_MAX_DEPTH, MAX_SPP, MAX_VPL_PATHS, MOST_PATH_DEPTH,
};

/// The film and the camera when the TOML gives them; a scene without a
/// glTF import must give both.
pub(super) fn check_film_and_camera(v: &Validator<'_>, spec: &SceneFile) -> Result<(), SceneError> {
    let path = v.file;
    if spec.gltf.is_none() && spec.usd.is_none() {
        v.check(spec.film.is_some(), "film", || {
            "missing: give [film] (or import a glTF file with [gltf] or a USD stage with [usd])".into()
        })?;
        v.check(spec.camera.is_some(), "camera", || {
            "missing: give [camera] (or import a glTF file or USD stage with a camera, with [gltf] or [usd])".into()
        })?;
    }
    if let Some(f) = &spec.film {
        v.check(f.width >= 1, "film.width", || "must be at least 1".into())?;
        v.check(f.height >= 1, "film.height", || "must be at least 1".into())?;
        v.check((1..=MAX_SPP).contains(&f.spp), "film.spp", || {
            format!("must be from 1 to {}, got {}", MAX_SPP, f.spp)
        })?;
        check_resolution(path, "film", f.width, f.height)?;
    }
    if let Some(cam) = &spec.camera {
        check_camera(v, cam, "camera")?;
    }
    Ok(())
}

/// Checks a camera (`field` names it in messages).
fn check_camera(v: &Validator<'_>, cam: &file::CameraSpec, field: &str) -> Result<(), SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let eye = v.point(cam.eye, &f("eye"))?;
    let look_at = v.point(cam.look_at, &f("look_at"))?;
    let up = v.point(cam.up, &f("up"))?;
    v.check(cam.fov_y.is_finite() && cam.fov_y > 0.0 && cam.fov_y < 180.0, &f("fov_y"), || {
        format!("must be between 0 and 180 degrees (exclusive), got {}", cam.fov_y)
    })?;
    let forward = look_at - eye;
    v.check(forward.length() > 0.0, &f("look_at"), || "must differ from the eye".into())?;
    v.check(forward.normalize().cross(up).length() > 1e-6, &f("up"), || {
        "must not be parallel to the viewing direction".into()
    })?;
    v.check(cam.lens_radius.is_finite() && cam.lens_radius >= 0.0, &f("lens_radius"), || {
        format!("must be finite and at least 0 (0: a pinhole), got {}", cam.lens_radius)
    })?;
    if let Some(d) = cam.focus_distance {
        v.check(d.is_finite() && d > 0.0, &f("focus_distance"), || format!("must be finite and above 0, got {d}"))?;
    }
    let [open, close] = cam.shutter;
    v.check(open.is_finite() && close.is_finite() && open <= close, &f("shutter"), || {
        format!("must be [open, close] in seconds with open <= close, got {:?}", cam.shutter)
    })?;
    let eye_end = cam.eye_end.map(|e| v.point(e, &f("eye_end"))).transpose()?.unwrap_or(eye);
    let look_at_end = cam.look_at_end.map(|l| v.point(l, &f("look_at_end"))).transpose()?.unwrap_or(look_at);
    // The view must stay defined all the way: checked at 65 times, the
    // ends included.
    for k in 1..=64 {
        let t = k as f32 / 64.0;
        let forward = look_at.lerp(look_at_end, t) - eye.lerp(eye_end, t);
        let field = if cam.look_at_end.is_some() { f("look_at_end") } else { f("eye_end") };
        v.check(forward.length() > 0.0 && forward.normalize().cross(up).length() > 1e-6, &field, || {
            format!("the camera's view direction vanishes or turns along up at {t} of the shutter")
        })?;
    }
    Ok(())
}

/// The vertical field of view of the camera made for a glTF file that has
/// none, degrees.
pub const FRAMING_FOV_Y: f32 = 45.0;

/// The camera (the TOML's, else the glTF file's, else one framing the
/// objects' `bounds`, with a note in `warnings`) and the film (the TOML's, else 640
/// pixels wide at the glTF camera's aspect ratio, 640 x 480 for a framing
/// camera), the camera opening the shutter `--shutter` gives unless the
/// TOML has its own.
pub(super) fn camera_and_film(
    v: &Validator<'_>,
    spec: &SceneFile,
    imported_camera: Option<ImportedCamera>,
    bounds: (Vec3, Vec3),
    incomplete: &[String],
    warnings: &mut Vec<String>,
) -> Result<(file::CameraSpec, Film), SceneError> {
    let (camera_spec, aspect_ratio) = match (&spec.camera, imported_camera) {
        (Some(c), _) => (c.clone(), None),
        (None, Some(c)) => {
            let field = match (&spec.gltf, &spec.usd) {
                (Some(g), _) => format!("gltf.file ({}) camera", g.file),
                (None, Some(u)) => format!("usd.file ({}) camera", u.file),
                (None, None) => "camera".to_string(),
            };
            check_camera(v, &c.spec, &field)?;
            (c.spec, c.aspect_ratio)
        }
        (None, None) => {
            let Some(camera) = framing_camera(bounds) else {
                let file = match (&spec.gltf, &spec.usd) {
                    (Some(_), _) => "the glTF file has",
                    (None, Some(_)) => "the USD stage has",
                    (None, None) => "the scene has",
                };
                // What was left out is why there is nothing to frame (a
                // stage of curves only): said here, as the warnings that
                // would say it are not printed for a failed load.
                // Each line is "file: what"; the error names the file.
                let left_out: Vec<&str> = incomplete
                    .iter()
                    .map(|line| line.split_once(": ").map_or(line.as_str(), |(_, what)| what))
                    .collect();
                let left_out =
                    if left_out.is_empty() { String::new() } else { format!(" (left out: {})", left_out.join("; ")) };
                return Err(v.error(
                    "camera",
                    &format!("missing: {file} no camera and no geometry to frame{left_out}, and no [camera] is given"),
                ));
            };
            warnings.push(format!(
                "{}: no camera in the file: one frames the scene's bounds from the front (+Z, 14 degrees above the \
                 centre), {FRAMING_FOV_Y} degrees vertical field of view (--camera or a TOML's [camera] picks another)",
                v.file.display()
            ));
            (camera, None)
        }
    };
    let film = match &spec.film {
        Some(f) => Film { width: f.width, height: f.height, spp: f.spp },
        // The glTF camera's aspect ratio at 640 pixels wide.
        None => {
            let height = aspect_ratio.map_or(480.0, |a| (DEFAULT_GLTF_WIDTH as f32 / a).round().clamp(1.0, 16384.0));
            Film { width: DEFAULT_GLTF_WIDTH, height: height as u32, spp: 1 }
        }
    };
    // A glTF file's or stage's (or the framing) camera opens the shutter
    // --shutter gives.
    let mut camera_spec = camera_spec;
    if spec.camera.is_none() {
        let given = spec.gltf.as_ref().and_then(|g| g.shutter).or_else(|| spec.usd.as_ref().and_then(|u| u.shutter));
        camera_spec.shutter = given.unwrap_or(camera_spec.shutter);
    }
    Ok((camera_spec, film))
}

/// A camera that sees the whole of the bounds' (the objects') bounding sphere, from the
/// front (+Z) and a little above (the direction (0, 0.25, 1)), as glTF
/// viewers show a file without a camera; None without geometry.
fn framing_camera((lo, hi): (Vec3, Vec3)) -> Option<file::CameraSpec> {
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    // The sphere fits the vertical field of view (the narrower at 4:3),
    // with a 5% margin.
    let distance = 1.05 * radius / (0.5 * FRAMING_FOV_Y).to_radians().sin();
    let eye = centre + distance * Vec3::new(0.0, 0.25, 1.0).normalize();
    Some(file::CameraSpec::pinhole(eye.to_array(), centre.to_array(), [0.0, 1.0, 0.0], FRAMING_FOV_Y))
}

/// The `[environment]`: a constant radiance or a lat-long EXR.
pub(super) fn environment(
    v: &Validator<'_>,
    base: &Path,
    spec: &SceneFile,
    inputs: &mut Vec<PathBuf>,
) -> Result<Option<Environment>, SceneError> {
    let environment = match &spec.environment {
        None => None,
        Some(env) => {
            let field = |f: &str| format!("environment.{f}");
            v.sample_count(env.samples, &field("samples"))?;
            v.check(env.scale.is_finite() && env.scale >= 0.0, &field("scale"), || {
                format!("must be finite and >= 0, got {}", env.scale)
            })?;
            let map = match (&env.radiance, &env.file) {
                (Some(_), Some(_)) => return Err(v.error(&field("file"), "give either radiance or file, not both")),
                (None, None) => return Err(v.error(&field("radiance"), "missing: give radiance or file")),
                (Some(r), None) => EnvironmentMap::Constant(v.emission(*r, &field("radiance"))?),
                (None, Some(f)) => {
                    let exr = base.join(f);
                    inputs.push(exr.clone());
                    let map = EnvironmentMap::load_exr(&exr, env.scale).map_err(|e| {
                        SceneError::new(&exr, field("file"), format!("cannot use as an environment: {e}"))
                    })?;
                    // Each texel is within the limit (the reader checked): the scale took it past.
                    let brightest = map.brightest();
                    v.check(brightest <= MAX_EMISSION, &field("scale"), || {
                        format!(
                            "{} times {} makes its brightest texel {brightest:e} W/(m^2 sr): at most {MAX_EMISSION:e}",
                            exr.display(),
                            env.scale
                        )
                    })?;
                    map
                }
            };
            Some(Environment { map, samples: env.samples })
        }
    };
    Ok(environment)
}

/// The `[indirect]` light's settings.
pub(super) fn indirect(v: &Validator<'_>, spec: &SceneFile) -> Result<Option<Indirect>, SceneError> {
    let Some(ind) = &spec.indirect else { return Ok(None) };
    let method = ind.method.as_deref().unwrap_or(if ind.paths.is_some() { "vpl" } else { "path" });
    let refused = |field: &str, method: &str| {
        v.error(&format!("indirect.{field}"), &format!("is a setting of method = \"{method}\", not of this one"))
    };
    match method {
        "vpl" => {
            if ind.max_depth.is_some() {
                return Err(refused("max_depth", "path"));
            }
            let paths = ind.paths.ok_or_else(|| v.error("indirect.paths", "method = \"vpl\" needs it"))?;
            v.check(paths <= MAX_VPL_PATHS, "indirect.paths", || {
                format!("must be at most {MAX_VPL_PATHS}, got {paths}")
            })?;
            let bounces = ind.bounces.unwrap_or(1);
            v.check((1..=16).contains(&bounces), "indirect.bounces", || {
                format!("must be between 1 and 16, got {bounces}")
            })?;
            Ok(Some(Indirect::Vpl(VplSettings { paths: paths as usize, bounces })))
        }
        "path" => {
            for (field, given) in [("paths", ind.paths.is_some()), ("bounces", ind.bounces.is_some())] {
                if given {
                    return Err(refused(field, "vpl"));
                }
            }
            let max_depth = ind.max_depth.unwrap_or(DEFAULT_MAX_DEPTH);
            v.check((1..=MOST_PATH_DEPTH).contains(&max_depth), "indirect.max_depth", || {
                format!("must be between 1 and {MOST_PATH_DEPTH}, got {max_depth}")
            })?;
            Ok(Some(Indirect::Path(PathSettings { max_depth })))
        }
        other => Err(v.error("indirect.method", &format!("must be \"path\" or \"vpl\", got \"{other}\""))),
    }
}
