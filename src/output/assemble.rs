//! Assembling a frame from tiles rendered by separate processes (a farm's
//! array job): the tiles must come from the same render (scene files,
//! mode, samples, seed, renderer), cover the frame exactly once, and are
//! written as one EXR whose pixels equal a one-process render's bit for bit
//! (pixels do not depend on the window they were rendered in).

use std::path::{Path, PathBuf};

use super::exr::{write_exr, ExrMetadata};
use super::read::{read_exr, ExrImage};
use super::OutputError;
use crate::render::{Film, FilmChannel, PixelBounds};

/// Header attributes every tile must share with the first.
pub const MUST_AGREE: [&str; 5] =
    ["lightcuts:sceneHash", "lightcuts:renderMode", "lightcuts:samplesPerPixel", "lightcuts:seed", "software"];

/// What was assembled.
#[derive(Debug, Clone)]
pub struct Assembled {
    pub width: u32,
    pub height: u32,
    pub tiles: usize,
    /// Sum of the tiles' render times, seconds.
    pub render_seconds: f64,
}

/// Checks `tiles` and writes the frame they make to `output` (atomically).
/// A tile file that does not exist (a farm task that never ran) counts as
/// absent: its pixels are reported as a gap, with the missing files named.
pub fn assemble(output: &Path, tiles: &[PathBuf]) -> Result<Assembled, OutputError> {
    let (present, absent): (Vec<&PathBuf>, Vec<&PathBuf>) = tiles.iter().partition(|t| t.exists());
    if present.is_empty() {
        let names: Vec<String> = absent.iter().map(|p| p.display().to_string()).collect();
        return Err(OutputError::NoTiles { path: output.to_path_buf(), missing: names.join(", ") });
    }
    let tiles: Vec<PathBuf> = present.iter().map(|p| (*p).clone()).collect();
    let images: Vec<ExrImage> = tiles.iter().map(|t| read_exr(t)).collect::<Result<_, _>>()?;
    let first = &images[0];
    let (width, height) = (first.display_width, first.display_height);
    check_same_render(&images, &tiles)?;
    let owner = coverage(output, &images, &tiles, &absent)?;
    // Each frame pixel's tile and its index in that tile's window.
    let sources: Vec<(&ExrImage, usize)> = (0..width * height)
        .map(|i| {
            let image = &images[owner[i].expect("every pixel is covered")];
            let (x, y) = (i % width, i / width);
            // Inside the frame (coverage checked it): x0, y0 >= 0.
            (image, (y - image.y0 as usize) * image.width + (x - image.x0 as usize))
        })
        .collect();
    // Every channel, from the tile that covers each pixel; and Cryptomatte's header.
    let channels = first
        .channels
        .keys()
        .map(|name| FilmChannel {
            name: name.clone(),
            values: sources.iter().map(|&(image, at)| image.channels[name][at]).collect(),
            // Read back from files the renderer wrote: finite already.
            non_finite: 0,
        })
        .collect();
    let attributes = first
        .attributes
        .iter()
        .filter(|(key, _)| key.starts_with("cryptomatte/"))
        .map(|(key, value)| (key.clone(), value.clone()))
        .collect();
    let film = Film {
        full_width: width as u32,
        full_height: height as u32,
        bounds: PixelBounds::full(width as u32, height as u32),
        channels,
        attributes,
    };
    let attribute = |key: &str| first.attributes.get(key).cloned().unwrap_or_default();
    let render_seconds =
        images.iter().filter_map(|i| i.attributes.get("lightcuts:renderTimeSeconds")?.parse::<f64>().ok()).sum();
    let meta = ExrMetadata {
        scene_file: PathBuf::from(attribute("lightcuts:sceneFile")),
        render_mode: attribute("lightcuts:renderMode"),
        render_seconds,
        lights: attribute("lightcuts:lights").parse().unwrap_or(0),
        spp: attribute("lightcuts:samplesPerPixel").parse().unwrap_or(0),
        seed: attribute("lightcuts:seed").parse().unwrap_or(0),
        scene_hash: attribute("lightcuts:sceneHash"),
        world_to_camera: first.world_to_camera,
        world_to_ndc: first.world_to_ndc,
    };
    write_exr(output, &film, first.half.contains("R"), &meta)?;
    Ok(Assembled { width: width as u32, height: height as u32, tiles: tiles.len(), render_seconds })
}

/// Every tile against the first: the same frame size, channels, render
/// (MUST_AGREE) and camera.
fn check_same_render(images: &[ExrImage], tiles: &[PathBuf]) -> Result<(), OutputError> {
    let (first, first_path) = (&images[0], &tiles[0]);
    let (width, height) = (first.display_width, first.display_height);
    for (image, path) in images.iter().zip(tiles).skip(1) {
        let mismatch = |what: &str, found: String, expected: String| OutputError::TileMismatch {
            path: path.clone(),
            reference: first_path.clone(),
            what: what.to_string(),
            found,
            expected,
        };
        if (image.display_width, image.display_height) != (width, height) {
            let size = |i: &ExrImage| format!("{}x{}", i.display_width, i.display_height);
            return Err(mismatch("the display window", size(image), size(first)));
        }
        let names = |i: &ExrImage| i.channels.keys().cloned().collect::<Vec<_>>().join(",");
        if names(image) != names(first) || image.half != first.half {
            return Err(mismatch("the channel list", names(image), names(first)));
        }
        for key in MUST_AGREE {
            let value = |i: &ExrImage| i.attributes.get(key).cloned().unwrap_or_else(|| "(absent)".into());
            if value(image) != value(first) {
                return Err(mismatch(key, value(image), value(first)));
            }
        }
        // The camera too (a glTF scene's --camera is not in the scene hash).
        let show = |m: Option<[f32; 16]>| m.map_or_else(|| "(absent)".to_string(), |m| format!("{m:?}"));
        if image.world_to_camera != first.world_to_camera {
            return Err(mismatch("worldToCamera", show(image.world_to_camera), show(first.world_to_camera)));
        }
        if image.world_to_ndc != first.world_to_ndc {
            return Err(mismatch("worldToNDC", show(image.world_to_ndc), show(first.world_to_ndc)));
        }
    }
    Ok(())
}

/// Which tile covers each pixel of the frame: overlaps are errors, and so
/// are gaps, listed by range (with the tile files that do not exist).
fn coverage(
    output: &Path,
    images: &[ExrImage],
    tiles: &[PathBuf],
    absent: &[&PathBuf],
) -> Result<Vec<Option<usize>>, OutputError> {
    let (width, height) = (images[0].display_width, images[0].display_height);
    let mut owner: Vec<Option<usize>> = vec![None; width * height];
    for (t, image) in images.iter().enumerate() {
        if (image.display_x0, image.display_y0) != (0, 0) {
            let (x, y) = (image.display_x0, image.display_y0);
            return Err(OutputError::DisplayWindowOrigin { path: tiles[t].clone(), x, y });
        }
        // The tile's data window must lie inside the frame (its display
        // window, the same for every tile: check_same_render).
        let (x0, y0) = (i64::from(image.x0), i64::from(image.y0));
        let (x1, y1) = (x0 + image.width as i64, y0 + image.height as i64);
        if x0 < 0 || y0 < 0 || x1 > width as i64 || y1 > height as i64 {
            return Err(OutputError::TileOutsideFrame {
                path: tiles[t].clone(),
                window: [x0, x1, y0, y1],
                display: [0, width as i64, 0, height as i64],
            });
        }
        let (x0, y0) = (x0 as usize, y0 as usize);
        for y in y0..y0 + image.height {
            for x in x0..x0 + image.width {
                if let Some(other) = owner[y * width + x].replace(t) {
                    let window = |i: &ExrImage| {
                        [i.x0 as u32, i.x0 as u32 + i.width as u32, i.y0 as u32, i.y0 as u32 + i.height as u32]
                    };
                    let (a, b) = (window(image), window(&images[other]));
                    return Err(OutputError::TileOverlap {
                        path: tiles[t].clone(),
                        other: tiles[other].clone(),
                        window: [a[0].max(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].min(b[3])],
                    });
                }
            }
        }
    }
    let gaps = uncovered(&owner, width, height);
    if !gaps.is_empty() {
        let pixels = gaps.iter().map(|r| u64::from(r[1] - r[0]) * u64::from(r[3] - r[2])).sum();
        let shown: Vec<String> =
            gaps.iter().take(8).map(|r| format!("x {}..{}, y {}..{}", r[0], r[1], r[2], r[3])).collect();
        let more = if gaps.len() > 8 { format!(" and {} more ranges", gaps.len() - 8) } else { String::new() };
        let files = if absent.is_empty() {
            String::new()
        } else {
            let names: Vec<String> = absent.iter().map(|p| p.display().to_string()).collect();
            format!(" (tile files that do not exist: {})", names.join(", "))
        };
        return Err(OutputError::TileGaps {
            path: output.to_path_buf(),
            pixels,
            missing: shown.join("; ") + &more + &files,
        });
    }
    Ok(owner)
}

/// The uncovered pixels as rectangles [x0, x1, y0, y1): runs of each row,
/// merged down while the next row has the same runs.
fn uncovered(owner: &[Option<usize>], width: usize, height: usize) -> Vec<[u32; 4]> {
    let runs = |y: usize| -> Vec<(u32, u32)> {
        let mut runs = Vec::new();
        let mut x = 0;
        while x < width {
            if owner[y * width + x].is_none() {
                let start = x;
                while x < width && owner[y * width + x].is_none() {
                    x += 1;
                }
                runs.push((start as u32, x as u32));
            } else {
                x += 1;
            }
        }
        runs
    };
    let mut rectangles: Vec<[u32; 4]> = Vec::new();
    let mut open: Vec<(u32, u32, u32)> = Vec::new(); // (x0, x1, y0) of the previous row's runs
    for y in 0..=height {
        let row = if y < height { runs(y) } else { Vec::new() };
        let previous: Vec<(u32, u32)> = open.iter().map(|&(a, b, _)| (a, b)).collect();
        if row != previous {
            rectangles.extend(open.drain(..).map(|(x0, x1, y0)| [x0, x1, y0, y as u32]));
            open = row.into_iter().map(|(a, b)| (a, b, y as u32)).collect();
        }
    }
    rectangles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_are_merged_into_rectangles() {
        let (w, h) = (6, 5);
        let mut owner = vec![Some(0); w * h];
        // Rows 1..3 missing entirely, and x 2..4 of row 4.
        for y in 1..3 {
            for x in 0..w {
                owner[y * w + x] = None;
            }
        }
        owner[4 * w + 2] = None;
        owner[4 * w + 3] = None;
        assert_eq!(uncovered(&owner, w, h), vec![[0, 6, 1, 3], [2, 4, 4, 5]]);
        assert!(uncovered(&vec![Some(0); w * h], w, h).is_empty());
    }
}
