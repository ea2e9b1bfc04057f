//! Image comparison on luminance: relative-error statistics and a heat map,
//! the image-subtraction tool the 2010 report wanted.
//!
//! Relative error of a pixel: |L_test - L_ref| / max(L_ref, floor), with
//! floor = 1e-3 x the reference's mean luminance over the window. Pixels
//! darker than a thousandth of the image's mean are black to the eye; the
//! floor keeps their tiny absolute errors from reading as huge relative ones.

use std::path::Path;

use glam::DVec3;
use serde::Serialize;

use super::read::{read_exr, ExrImage};
use super::OutputError;
use crate::render::BACKGROUND_DEPTH;
use crate::util::color::luminance64;

/// Fraction of the reference's mean luminance used as the denominator floor.
pub const FLOOR_FRACTION: f64 = 1e-3;

#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    pub pixels: usize,
    pub floor: f64,
    pub mean_relative_error: f64,
    pub median_relative_error: f64,
    pub p95_relative_error: f64,
    pub p99_relative_error: f64,
    pub max_relative_error: f64,
    pub fraction_above_1_percent: f64,
    pub fraction_above_2_percent: f64,
    pub fraction_above_5_percent: f64,
    /// Root-mean-square luminance difference (W/(m^2 sr)).
    pub rmse: f64,
    /// Mean of (L_test - L_ref)^2 / (L_ref^2 + floor^2).
    pub relative_mse: f64,
    /// Mean luminance of the test image and of the reference, W/(m^2 sr).
    pub mean_luminance: f64,
    pub reference_mean_luminance: f64,
    /// Block averages compared (`compare --blocks`), when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blocks: Option<BlockComparison>,
    /// Each light group's layer compared with the reference's, when both
    /// images have group layers.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<GroupComparison>,
}

/// One light group's layer (`Combined_<group>.R/G/B`) against the
/// reference's: relative error on luminance, with the floor taken from the
/// group's own mean (so a dim group is held to its own light).
#[derive(Debug, Clone, Serialize)]
pub struct GroupComparison {
    pub group: String,
    pub mean_relative_error: f64,
    pub p99_relative_error: f64,
    pub mean_luminance: f64,
    pub reference_mean_luminance: f64,
}

/// Relative error of the mean luminance of `size` x `size`-pixel blocks:
/// what a comparison with a noisy reference (a path tracer's) can measure,
/// since averaging a block averages its noise away. Blocks across a
/// silhouette (neighbouring pixels more than 10% apart in depth, or a pixel
/// that sees no surface) are skipped: there the two renderers' pixel
/// filters, not their lighting, decide the values.
#[derive(Debug, Clone, Serialize)]
pub struct BlockComparison {
    pub size: usize,
    /// Blocks compared, and blocks skipped as silhouettes (or without a depth channel, none).
    pub blocks: usize,
    pub skipped: usize,
    pub mean_relative_error: f64,
    pub median_relative_error: f64,
    pub p95_relative_error: f64,
    pub max_relative_error: f64,
}

/// Whether depth `z` (the Z channel) is a surface: the background is
/// [`BACKGROUND_DEPTH`] (Cycles' value too), or 0 in files written before it.
fn is_surface(z: f32) -> bool {
    z.is_finite() && z > 0.0 && z < BACKGROUND_DEPTH
}

/// Compares the block averages of two luminance images (see
/// [`BlockComparison`]); `depth` from whichever image has a Z channel.
#[must_use]
pub fn compare_blocks(
    test: &[f64],
    reference: &[f64],
    depth: Option<&[f32]>,
    width: usize,
    height: usize,
    size: usize,
) -> BlockComparison {
    let size = size.max(1);
    let mut errors = Vec::new();
    let mut skipped = 0;
    for by in 0..height / size {
        for bx in 0..width / size {
            let pixels = || (0..size).flat_map(move |y| (0..size).map(move |x| (bx * size + x, by * size + y)));
            let silhouette = depth.is_some_and(|z| {
                let at = |x: usize, y: usize| z[y * width + x];
                pixels().any(|(x, y)| {
                    let here = at(x, y);
                    let jump = |other: f32| !is_surface(other) || (other - here).abs() > 0.1 * here.min(other);
                    !is_surface(here)
                        || (x + 1 < (bx + 1) * size && jump(at(x + 1, y)))
                        || (y + 1 < (by + 1) * size && jump(at(x, y + 1)))
                })
            });
            if silhouette {
                skipped += 1;
                continue;
            }
            let mean = |image: &[f64]| pixels().map(|(x, y)| image[y * width + x]).sum::<f64>() / (size * size) as f64;
            let (t, r) = (mean(test), mean(reference));
            errors.push((t - r).abs() / r.max(f64::MIN_POSITIVE));
        }
    }
    let mut sorted = errors.clone();
    sorted.sort_by(f64::total_cmp);
    let quantile = |q: f64| sorted.get(((q * (sorted.len() as f64 - 1.0)).round()) as usize).copied().unwrap_or(0.0);
    BlockComparison {
        size,
        blocks: errors.len(),
        skipped,
        mean_relative_error: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
        median_relative_error: quantile(0.5),
        p95_relative_error: quantile(0.95),
        max_relative_error: sorted.last().copied().unwrap_or(0.0),
    }
}

/// Per-pixel relative errors and the summary.
pub struct ComparisonResult {
    pub summary: Comparison,
    pub relative: Vec<f64>,
    pub width: usize,
    pub height: usize,
    /// Per-channel absolute difference, for the diff EXR.
    pub difference: Vec<DVec3>,
}

fn luminances(image: &ExrImage, path: &Path) -> Result<Vec<DVec3>, OutputError> {
    layer_rgb(image, path, "")
}

/// The RGB of a layer: `prefix` is "" for the beauty, `Combined_key.` for a group.
pub fn layer_rgb(image: &ExrImage, path: &Path, prefix: &str) -> Result<Vec<DVec3>, OutputError> {
    let channel = |c: &str| image.channel(path, &format!("{prefix}{c}"));
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    Ok(r.iter().zip(g).zip(b).map(|((&r, &g), &b)| DVec3::new(f64::from(r), f64::from(g), f64::from(b))).collect())
}

/// The light groups an image has layers for, in the file's channel order.
#[must_use]
pub fn group_names(image: &ExrImage) -> Vec<String> {
    image
        .channels
        .keys()
        .filter_map(|name| name.strip_prefix("Combined_")?.strip_suffix(".R"))
        .map(str::to_string)
        .collect()
}

/// Compares two EXRs' R, G and B; with `blocks`, also their block averages
/// (silhouettes found from the Z channel of the test image, else of the reference).
pub fn compare_files(test: &Path, reference: &Path, blocks: Option<usize>) -> Result<ComparisonResult, OutputError> {
    let (t, r) = (read_exr(test)?, read_exr(reference)?);
    let window = |i: &ExrImage| [i64::from(i.x0), i64::from(i.y0), i.width as i64, i.height as i64];
    if window(&t) != window(&r) {
        return Err(OutputError::WindowMismatch {
            path: test.to_path_buf(),
            reference: reference.to_path_buf(),
            window: window(&t),
            reference_window: window(&r),
        });
    }
    let mut result = compare_rgb(&luminances(&t, test)?, &luminances(&r, reference)?, t.width, t.height);
    if let Some(size) = blocks {
        let depth = t.channel(test, "Z").or_else(|_| r.channel(reference, "Z")).ok();
        let lum = |i: &ExrImage, p: &Path| -> Result<Vec<f64>, OutputError> {
            Ok(luminances(i, p)?.into_iter().map(luminance64).collect())
        };
        result.summary.blocks =
            Some(compare_blocks(&lum(&t, test)?, &lum(&r, reference)?, depth, t.width, t.height, size));
    }
    let reference_groups = group_names(&r);
    for group in group_names(&t).into_iter().filter(|g| reference_groups.contains(g)) {
        let prefix = format!("Combined_{group}.");
        let c = compare_rgb(&layer_rgb(&t, test, &prefix)?, &layer_rgb(&r, reference, &prefix)?, t.width, t.height);
        result.summary.groups.push(GroupComparison {
            group,
            mean_relative_error: c.summary.mean_relative_error,
            p99_relative_error: c.summary.p99_relative_error,
            mean_luminance: c.summary.mean_luminance,
            reference_mean_luminance: c.summary.reference_mean_luminance,
        });
    }
    Ok(result)
}

/// Compares two RGB images of the same size.
#[must_use]
pub fn compare_rgb(test: &[DVec3], reference: &[DVec3], width: usize, height: usize) -> ComparisonResult {
    let n = test.len().max(1);
    let lt: Vec<f64> = test.iter().map(|&c| luminance64(c)).collect();
    let lr: Vec<f64> = reference.iter().map(|&c| luminance64(c)).collect();
    let mean_ref = lr.iter().sum::<f64>() / n as f64;
    // The floor is positive even for a black reference, so 0/0 never happens.
    let floor = (FLOOR_FRACTION * mean_ref).max(f64::MIN_POSITIVE);
    let relative: Vec<f64> = lt.iter().zip(&lr).map(|(&a, &b)| (a - b).abs() / b.max(floor)).collect();
    let mut sorted = relative.clone();
    sorted.sort_by(f64::total_cmp);
    let quantile = |q: f64| sorted.get(((q * (sorted.len() as f64 - 1.0)).round()) as usize).copied().unwrap_or(0.0);
    let above = |x: f64| relative.iter().filter(|&&e| e > x).count() as f64 / n as f64;
    let squared: f64 = lt.iter().zip(&lr).map(|(a, b)| (a - b) * (a - b)).sum();
    let relative_mse =
        lt.iter().zip(&lr).map(|(a, b)| (a - b) * (a - b) / (b * b + floor * floor)).sum::<f64>() / n as f64;
    let summary = Comparison {
        pixels: test.len(),
        floor,
        mean_relative_error: relative.iter().sum::<f64>() / n as f64,
        median_relative_error: quantile(0.5),
        p95_relative_error: quantile(0.95),
        p99_relative_error: quantile(0.99),
        max_relative_error: sorted.last().copied().unwrap_or(0.0),
        fraction_above_1_percent: above(0.01),
        fraction_above_2_percent: above(0.02),
        fraction_above_5_percent: above(0.05),
        rmse: (squared / n as f64).sqrt(),
        relative_mse,
        mean_luminance: lt.iter().sum::<f64>() / n as f64,
        reference_mean_luminance: mean_ref,
        blocks: None,
        groups: Vec::new(),
    };
    let difference = test.iter().zip(reference).map(|(a, b)| (*a - *b).abs()).collect();
    ComparisonResult { summary, relative, width, height, difference }
}

/// Heat-map colour of a relative error: black at 0, then blue (0.5%), green
/// (1%), yellow (2%), red (5%) and white at 10% and above, interpolated on a
/// log scale between the stops.
#[must_use]
pub fn heat(e: f64) -> [u8; 3] {
    const STOPS: [(f64, [f64; 3]); 6] = [
        (0.001, [0.0, 0.0, 0.0]),
        (0.005, [0.0, 0.2, 1.0]),
        (0.01, [0.0, 0.8, 0.3]),
        (0.02, [1.0, 0.9, 0.0]),
        (0.05, [1.0, 0.1, 0.0]),
        (0.1, [1.0, 1.0, 1.0]),
    ];
    if e.is_nan() || e >= STOPS[5].0 {
        return [255; 3];
    }
    if e <= STOPS[0].0 {
        return [0; 3];
    }
    let k = STOPS.iter().position(|s| e < s.0).unwrap_or(5);
    let (a, b) = (STOPS[k - 1], STOPS[k]);
    let t = (e.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
    [0, 1, 2].map(|c| ((a.1[c] + (b.1[c] - a.1[c]) * t) * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error_and_a_known_offset_is_measured() {
        let reference: Vec<DVec3> = (0..100).map(|i| DVec3::splat(1.0 + i as f64)).collect();
        let same = compare_rgb(&reference, &reference, 10, 10).summary;
        assert_eq!(same.max_relative_error, 0.0);
        assert_eq!(same.rmse, 0.0);
        let brighter: Vec<DVec3> = reference.iter().map(|c| *c * 1.03).collect();
        let s = compare_rgb(&brighter, &reference, 10, 10).summary;
        assert!((s.mean_relative_error - 0.03).abs() < 1e-9);
        assert!((s.p99_relative_error - 0.03).abs() < 1e-9);
        assert_eq!(s.fraction_above_2_percent, 1.0);
        assert_eq!(s.fraction_above_5_percent, 0.0);
    }

    #[test]
    fn black_pixels_use_the_floor_and_never_divide_by_zero() {
        let reference = vec![DVec3::ZERO, DVec3::ONE];
        let test = vec![DVec3::splat(1e-6), DVec3::ONE];
        let s = compare_rgb(&test, &reference, 2, 1).summary;
        assert!(s.max_relative_error.is_finite());
        let black = compare_rgb(&[DVec3::ZERO], &[DVec3::ZERO], 1, 1).summary;
        assert_eq!(black.max_relative_error, 0.0);
    }

    #[test]
    fn heat_map_runs_from_black_to_white() {
        assert_eq!(heat(0.0), [0, 0, 0]);
        assert_eq!(heat(1.0), [255, 255, 255]);
        assert_eq!(heat(0.02), [255, 230, 0]);
        assert_eq!(heat(f64::NAN), [255, 255, 255]);
    }
}
