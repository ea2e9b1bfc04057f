//! A glTF animation's node transforms, sampled at the times of a shutter
//! (docs/design.md §13.6): each channel's keyframes interpolated as glTF
//! 2.0 defines (section 3.11 "Animations": STEP, LINEAR with spherical linear
//! interpolation of rotations, CUBICSPLINE's Hermite spline with its in-
//! and out-tangents), before the first key its first value and after the
//! last its last. Morph-target weight channels are not played.

use std::collections::HashMap;

use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::animation::{Interpolation, Property};

use super::io::Data;
use crate::scene::SceneError;

/// Which of a node's transform components a channel drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Part {
    Translation,
    Rotation,
    Scale,
}

/// One channel's keyframes: strictly increasing times (seconds) and their
/// values (x, y, z and, for rotations, w); CUBICSPLINE's values are three
/// per key: in-tangent, value, out-tangent.
#[derive(Debug, Clone)]
struct Track {
    times: Vec<f32>,
    values: Vec<Vec4>,
    interpolation: Interpolation,
}

impl Track {
    /// The value at `time`.
    fn at(&self, time: f32, part: Part) -> Vec4 {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| if cubic { self.values[3 * k + 1] } else { self.values[k] };
        let last = self.times.len() - 1;
        if time <= self.times[0] {
            return value(0);
        }
        if time >= self.times[last] {
            return value(last);
        }
        // The key k with times[k] <= time < times[k + 1].
        let k = self.times.partition_point(|&t| t <= time) - 1;
        let span = self.times[k + 1] - self.times[k];
        let s = (time - self.times[k]) / span;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if part == Part::Rotation => {
                let (a, b) = (Quat::from_vec4(value(k)).normalize(), Quat::from_vec4(value(k + 1)).normalize());
                Vec4::from(a.slerp(b, s))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let out_tangent = self.values[3 * k + 2] * span;
                let in_tangent = self.values[3 * (k + 1)] * span;
                let v = value(k) * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + out_tangent * (s3 - 2.0 * s2 + s)
                    + value(k + 1) * (-2.0 * s3 + 3.0 * s2)
                    + in_tangent * (s3 - s2);
                if part == Part::Rotation {
                    Vec4::from(Quat::from_vec4(v).normalize())
                } else {
                    v
                }
            }
        }
    }
}

/// The tracks of one animation, by (node index, part).
#[derive(Debug, Clone, Default)]
pub(super) struct Animation {
    /// Its name in the file (`#i` when it has none).
    pub(super) name: String,
    tracks: HashMap<(usize, Part), Track>,
    /// Morph-target weight channels, which are not played.
    pub(super) weight_channels: usize,
}

impl Animation {
    /// The file's animation named `name`, else its first; None when the
    /// file has none. Every channel's sampler is read and checked (times
    /// strictly increasing and finite, as many values as the
    /// interpolation needs, finite values); errors name the file and the
    /// sampler.
    pub(super) fn read(
        file: &std::path::Path,
        doc: &gltf::Document,
        data: &Data<'_>,
        name: Option<&str>,
    ) -> Result<Option<Self>, SceneError> {
        let chosen = match name {
            None => doc.animations().next(),
            Some(name) => {
                let found = doc.animations().find(|a| a.name() == Some(name));
                if found.is_none() {
                    let names: Vec<String> = doc
                        .animations()
                        .enumerate()
                        .map(|(i, a)| a.name().map_or_else(|| format!("#{i} (unnamed)"), str::to_string))
                        .collect();
                    let names = if names.is_empty() { "none".to_string() } else { names.join(", ") };
                    return Err(SceneError::new(
                        file,
                        "animations",
                        format!("no animation named '{name}' in the file (it has: {names})"),
                    ));
                }
                found
            }
        };
        let Some(animation) = chosen else { return Ok(None) };
        // The validator gltf-json runs checks neither a channel's target
        // node nor its path, and the gltf crate unwraps both: checked here.
        let json = &doc.as_json().animations[animation.index()];
        for (c, channel) in json.channels.iter().enumerate() {
            let at = format!("animations[{}].channels[{c}].target", animation.index());
            if channel.target.node.value() >= doc.nodes().len() {
                let message =
                    format!("node {} does not exist (the file has {})", channel.target.node.value(), doc.nodes().len());
                return Err(SceneError::new(file, format!("{at}.node"), message));
            }
            if !matches!(channel.target.path, gltf::json::validation::Checked::Valid(_)) {
                let message = "must be translation, rotation, scale or weights";
                return Err(SceneError::new(file, format!("{at}.path"), message));
            }
        }
        let name = animation.name().map_or_else(|| format!("#{}", animation.index()), str::to_string);
        let mut read = Self { name, ..Self::default() };
        for channel in animation.channels() {
            let sampler = channel.sampler();
            let at = format!("animations[{}].samplers[{}]", animation.index(), sampler.index());
            let part = match channel.target().property() {
                Property::Translation => Part::Translation,
                Property::Rotation => Part::Rotation,
                Property::Scale => Part::Scale,
                Property::MorphTargetWeights => {
                    read.weight_channels += 1;
                    continue;
                }
            };
            let times: Vec<f32> =
                data.read_floats::<1>(&sampler.input(), &format!("{at}.input"))?.into_iter().map(|[t]| t).collect();
            let values: Vec<Vec4> = if part == Part::Rotation {
                data.read_floats::<4>(&sampler.output(), &format!("{at}.output"))?.into_iter().map(Vec4::from).collect()
            } else {
                let v = data.read_floats::<3>(&sampler.output(), &format!("{at}.output"))?;
                v.into_iter().map(|v| Vec3::from(v).extend(0.0)).collect()
            };
            let per_key = if sampler.interpolation() == Interpolation::CubicSpline { 3 } else { 1 };
            let error = |field: &str, message: String| SceneError::new(file, format!("{at}.{field}"), message);
            if times.is_empty() || !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[0] >= w[1]) {
                return Err(error(
                    "input",
                    "the key times must be finite and strictly increasing, at least one".into(),
                ));
            }
            if values.len() != per_key * times.len() {
                return Err(error(
                    "output",
                    format!("has {} values for {} keys ({per_key} per key)", values.len(), times.len()),
                ));
            }
            if !values.iter().all(|v| v.is_finite()) {
                return Err(error("output", "the values must be finite".into()));
            }
            read.tracks.insert(
                (channel.target().node().index(), part),
                Track { times, values, interpolation: sampler.interpolation() },
            );
        }
        Ok(Some(read))
    }

    /// The first and the last of its transform channels' key times,
    /// seconds (None when it has none): outside them every channel holds
    /// its first or last key.
    pub(super) fn key_range(&self) -> Option<[f32; 2]> {
        let first = self.tracks.values().map(|t| t.times[0]).reduce(f32::min)?;
        let last = self.tracks.values().map(|t| t.times[t.times.len() - 1]).reduce(f32::max)?;
        Some([first, last])
    }

    /// Whether the animation drives node `node`'s transform.
    pub(super) fn drives(&self, node: usize) -> bool {
        [Part::Translation, Part::Rotation, Part::Scale].iter().any(|&p| self.tracks.contains_key(&(node, p)))
    }

    /// Node `node`'s local transform at `time` (seconds): its own
    /// translation, rotation and scale, each replaced by the animation's
    /// where a channel drives it.
    pub(super) fn local(&self, node: &gltf::Node<'_>, time: f32) -> Mat4 {
        let (t, r, s) = node.transform().decomposed();
        let track = |part| self.tracks.get(&(node.index(), part)).map(|track: &Track| track.at(time, part));
        let translation = track(Part::Translation).map_or(Vec3::from(t), Vec4::truncate);
        let rotation = track(Part::Rotation).map_or(Quat::from_array(r), Quat::from_vec4).normalize();
        let scale = track(Part::Scale).map_or(Vec3::from(s), Vec4::truncate);
        Mat4::from_scale_rotation_translation(scale, rotation, translation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(times: &[f32], values: &[[f32; 4]], interpolation: Interpolation) -> Track {
        Track { times: times.to_vec(), values: values.iter().map(|v| Vec4::from(*v)).collect(), interpolation }
    }

    #[test]
    fn keyframes_interpolate_as_gltf_defines() {
        let linear = track(&[1.0, 3.0], &[[0.0, 0.0, 0.0, 0.0], [4.0, 2.0, 0.0, 0.0]], Interpolation::Linear);
        assert_eq!(linear.at(0.0, Part::Translation), Vec4::ZERO, "before the first key, its value");
        assert_eq!(linear.at(2.0, Part::Translation), Vec4::new(2.0, 1.0, 0.0, 0.0));
        assert_eq!(linear.at(9.0, Part::Translation), Vec4::new(4.0, 2.0, 0.0, 0.0), "after the last, its value");
        let step = Track { interpolation: Interpolation::Step, ..linear.clone() };
        assert_eq!(step.at(2.9, Part::Translation), Vec4::ZERO);
        // Rotations: spherical, a quarter turn about y halfway is 45 degrees.
        let quarter = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let turn = track(&[0.0, 1.0], &[[0.0, 0.0, 0.0, 1.0], quarter.to_array()], Interpolation::Linear);
        let half = Quat::from_vec4(turn.at(0.5, Part::Rotation));
        assert!(half.abs_diff_eq(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4), 1e-6), "{half}");
        // A cubic spline with zero tangents eases: 0.5 at the middle, 0.104 at a quarter.
        let zero = [0.0; 4];
        let cubic =
            track(&[0.0, 2.0], &[zero, zero, zero, zero, [1.0, 0.0, 0.0, 0.0], zero], Interpolation::CubicSpline);
        assert!((cubic.at(1.0, Part::Translation).x - 0.5).abs() < 1e-6);
        assert!((cubic.at(0.5, Part::Translation).x - 0.15625).abs() < 1e-6);
        // With tangents of a straight line (slope 0.5 a second) it is that line.
        let slope = [0.5, 0.0, 0.0, 0.0];
        let line =
            track(&[0.0, 2.0], &[slope, zero, slope, slope, [1.0, 0.0, 0.0, 0.0], slope], Interpolation::CubicSpline);
        assert!((line.at(0.5, Part::Translation).x - 0.25).abs() < 1e-6);
    }
}
