//! The command line's flags turned into validated settings, once (as
//! ripgrep's `flags/` does): the render mode and its cut settings with their
//! defaults and conflicts, the pass (film, samples, window, seed, threads,
//! camera), and the parsers of the flags' values. `render`, `sweep` and
//! `bench` take what this module resolves and never import each other.

use std::path::{Path, PathBuf};

use clap::Args;

use super::farm::tile_rows;
use super::CliError;
use crate::lightcut::multidimensional::MULTIDIMENSIONAL_DEFAULTS;
use crate::lightcut::stochastic::{STOCHASTIC_DEFAULTS, STOCHASTIC_FROM_SPP};
use crate::lightcut::{CutSettings, GroupError};
use crate::render::session::Mode;
use crate::render::{Aovs, PassSettings, PixelBounds};
use crate::scene::{check_resolution, LoadOptions, Scene};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file: TOML (JSON by its .json extension), glTF 2.0 (.gltf,
    /// .glb) or a USD stage (.usd, .usda, .usdc, .usdz).
    pub scene: PathBuf,
    /// Output OpenEXR file.
    #[arg(short, long, value_name = "OUT.exr", help_heading = "Output")]
    pub output: PathBuf,
    /// Write the beauty (R, G, B, A) as 16-bit half floats.
    #[arg(long, help_heading = "Output")]
    pub half: bool,
    /// The AOV layers to write beside the beauty: a comma-separated list of
    /// albedo, N, Z, lightcuts (the cut's size and shadow rays; cut modes
    /// only), groups (Combined_<group>.R/G/B per light group; scenes with
    /// groups), cryptomatte, or none. Default: all but cryptomatte.
    #[arg(long, value_name = "LIST", value_parser = Aovs::parse, help_heading = "Output")]
    pub aovs: Option<Aovs>,
    /// Also write Cryptomatte's object and material ID mattes
    /// (CryptoObject00..02, CryptoMaterial00..02).
    #[arg(long, help_heading = "Output")]
    pub cryptomatte: bool,
    /// A transparent background: where a camera ray hits nothing the pixel
    /// gets RGB 0 and alpha 0 (premultiplied, ready for "over" onto a
    /// plate) instead of the environment with alpha 1. The environment
    /// still lights the scene and shows in mirrors.
    #[arg(long, help_heading = "Output")]
    pub transparent: bool,
    /// Also write a tone-mapped sRGB PNG preview.
    #[arg(long, value_name = "PREVIEW.png", help_heading = "Output")]
    pub png: Option<PathBuf>,
    /// Preview exposure in stops (the EXR is never scaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, help_heading = "Output")]
    pub exposure: f32,
    /// No progress output.
    #[arg(long, short, help_heading = "Output")]
    pub quiet: bool,
    /// The full statistics block: cut-size histogram, share of time in
    /// Embree (times every ray query), peak memory.
    #[arg(long, help_heading = "Output")]
    pub stats: bool,
    #[command(flatten)]
    pub mode: ModeArgs,
    /// Samples per pixel, overriding the scene's.
    #[arg(long, value_name = "N", help_heading = "Sampling")]
    pub spp: Option<u32>,
    #[command(flatten)]
    pub pass: PassArgs,
    /// Render tile I of N (I from 0): the horizontal band of rows
    /// floor(I H / N) to floor((I + 1) H / N), every column; the EXR's data
    /// window is the band, its display window the frame (see `assemble`).
    #[arg(long, value_name = "I/N", value_parser = parse_tile, conflicts_with = "pixel_bounds", help_heading = "Farm")]
    pub tile: Option<(u32, u32)>,
    /// Skip the render when the output exists, and claim the output
    /// atomically (OUT.exr.claim, created exclusively) before rendering, so
    /// that two processes never render the same file and a re-run renders
    /// only what is missing.
    #[arg(long, help_heading = "Farm")]
    pub no_overwrite: bool,
    #[command(flatten)]
    pub knobs: CutKnobs,
    /// How textures are read: `mip` filters them over each pixel's
    /// footprint by a MIP map (docs/design.md §5.3); `off` reads the image
    /// at each hit, which aliases where a texel is smaller than a pixel.
    #[arg(long, value_name = "FILTER", value_parser = crate::render::TextureFilter::parse, default_value = "mip", help_heading = "Advanced")]
    pub texture_filter: crate::render::TextureFilter,
}

impl RenderArgs {
    /// The pass and the mode these flags ask for on `scene`: the film, the
    /// samples, the window (`--pixel-bounds` or `--tile`), the AOVs and the
    /// background; conflicts among them are usage errors.
    pub fn resolve(&self, scene: &Scene) -> Result<(PassSettings, Mode), CliError> {
        let mut settings = self.pass.settings(scene, self.spp)?;
        if let Some((index, count)) = self.tile {
            if count > settings.height {
                return Err(CliError::Usage {
                    flag: "--tile",
                    message: format!(
                        "{count} tiles of a frame {} rows high: at most one tile per row",
                        settings.height
                    ),
                });
            }
            let (y0, y1) = tile_rows(index, count, settings.height);
            settings.bounds = PixelBounds { x0: 0, x1: settings.width, y0, y1 };
        }
        let mode = self.mode.mode(settings.spp, &self.knobs)?;
        let mut aovs = self.aovs.unwrap_or(Aovs::all(mode.cut().is_some()));
        aovs.cryptomatte |= self.cryptomatte;
        if aovs.lightcuts && mode.cut().is_none() {
            return Err(CliError::Usage {
                flag: "--aovs",
                message: "lightcuts (the cut's size and shadow rays) needs a cut method, not --method exact".into(),
            });
        }
        if !self.exposure.is_finite() {
            return Err(CliError::Usage {
                flag: "--exposure",
                message: format!("must be finite, got {}", self.exposure),
            });
        }
        settings.aovs = aovs;
        settings.transparent = self.transparent;
        settings.texture_filter = self.texture_filter;
        Ok((settings, mode))
    }
}

/// How each shading point's lights are chosen (`--method`): the closed set
/// of [`Mode`]s a user names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Every light, one shadow ray each: the reference.
    Exact,
    /// Lightcuts [LC05]: every cluster's error bounded.
    Bounded,
    /// Stochastic lightcuts [SLC19]: each cut node's light drawn per sample.
    Stochastic,
    /// Multidimensional lightcuts [MDLC06]: one cut over a pixel's samples.
    Multidimensional,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Self::Exact => "exact",
            Self::Bounded => "bounded",
            Self::Stochastic => "stochastic",
            Self::Multidimensional => "multidimensional",
        }
    }
}

/// How direct light is computed. Without `--method`, the method that gave
/// the smaller error for the time at the samples per pixel asked for (see
/// [`default_mode`]).
#[derive(Debug, Args)]
#[command(next_help_heading = "Light selection")]
pub struct ModeArgs {
    /// How each shading point's lights are chosen: `exact` (every light,
    /// one shadow ray each: the reference), `bounded` (Lightcuts [LC05]:
    /// each cluster's error bounded, its representative fixed when the tree
    /// is built), `stochastic` (stochastic lightcuts [SLC19]: each cut
    /// node's light drawn per sample, so the error falls with samples per
    /// pixel) or `multidimensional` (multidimensional lightcuts [MDLC06]:
    /// one cut per pixel through (gather cluster, light cluster) pairs over
    /// all its samples). Default: bounded below 16 samples per pixel,
    /// stochastic from 16 (docs/design.md §10.8); bounded with --reconstruct.
    #[arg(long, value_enum, value_name = "METHOD")]
    pub method: Option<Method>,
    /// Short for --method exact.
    #[arg(long, hide = true, conflicts_with_all = ["method", "bounded", "stochastic", "multidimensional"])]
    pub exact: bool,
    /// Short for --method bounded.
    #[arg(long, hide = true, conflicts_with_all = ["method", "stochastic", "multidimensional"])]
    pub bounded: bool,
    /// Short for --method stochastic.
    #[arg(long, hide = true, conflicts_with_all = ["method", "multidimensional"])]
    pub stochastic: bool,
    /// Short for --method multidimensional.
    #[arg(long, hide = true, conflicts_with = "method")]
    pub multidimensional: bool,
    /// Relative error threshold: a cluster is split while its bound exceeds
    /// this fraction of the point's total (bounded: of the estimate, default
    /// 0.02; stochastic: of the summed bounds, default 0.05; multidimensional:
    /// of the pixel's estimate, default 0.02).
    /// 0 splits every cluster, reproducing the exact method (bounded) when
    /// --max-cut allows.
    #[arg(long)]
    pub error: Option<f64>,
    /// Largest cut per shading point, in nodes (bounded default 1000; per
    /// light group with --group-error group).
    #[arg(long)]
    pub max_cut: Option<usize>,
    /// In a scene with light groups, what each cluster's error is held to:
    /// `group` (a cut per group, relative to the group's own light: every
    /// group layer as accurate as the beauty) or `pixel` (one cut through
    /// every group's trees, relative to the pixel's total: cheaper, dim
    /// groups' layers less accurate). Every method but exact.
    #[arg(long, value_name = "group|pixel", value_parser = parse_group_error)]
    pub group_error: Option<GroupError>,
    /// Bounded method: reconstruction cuts [LC05] section 6. Full cuts only
    /// at the corners of B x B pixel blocks; every camera hit between them
    /// cuts the trees again with the same bounds, but traces a shadow ray
    /// only where the corners' cuts disagree on what they saw. Implies the
    /// bounded method when none is given.
    #[arg(long, value_name = "B")]
    pub reconstruct: Option<u32>,
    /// Stochastic method: light each camera hit by the drawn lights of every
    /// camera hit of its B x B pixel block (B from 2 to 8) at the same
    /// sample, weighted by multiple importance sampling (docs/design.md
    /// §10.11; unbiased): B^2 times the shadow rays of a cut, for less noise
    /// from the same cuts.
    #[arg(long, value_name = "B", conflicts_with = "resampled_rays")]
    pub reuse: Option<u32>,
}

/// The stochastic method's research knobs, shown under "Advanced": each
/// changes how a cut's light is drawn, none is needed to render well.
#[derive(Debug, Args)]
#[command(next_help_heading = "Advanced")]
pub struct CutKnobs {
    /// Stochastic method: shadow rays per cut, resampled among the cut's
    /// drawn lights by their unoccluded contributions (resampled importance
    /// sampling; unbiased). 0 (the default) traces every cut node's light.
    #[arg(long, value_name = "N")]
    pub resampled_rays: Option<usize>,
    /// Stochastic method: choose a cut at every sample's shading point,
    /// instead of once per pixel at its first sample's camera hit, for the
    /// later samples on the same surface (the default: docs/design.md §10.9).
    #[arg(long)]
    pub cut_per_sample: bool,
    /// Stochastic method: draw M lights per shading point over the whole
    /// cut, each cut node by its importance, one shadow ray each, instead
    /// of one light from every cut node (docs/design.md §10.10; unbiased).
    /// Pays at many samples per pixel: with a finer cut (a smaller
    /// --error) for the same rays.
    #[arg(long, value_name = "M", conflicts_with = "resampled_rays")]
    pub cut_draws: Option<usize>,
}

/// Parses `--group-error`.
pub fn parse_group_error(s: &str) -> Result<GroupError, String> {
    match s {
        "group" => Ok(GroupError::Group),
        "pixel" => Ok(GroupError::Pixel),
        _ => Err(format!("expected group or pixel, got '{s}'")),
    }
}

impl ModeArgs {
    /// The method named by `--method` or by one of its short forms.
    fn named_method(&self) -> Option<Method> {
        self.method.or_else(|| {
            [
                (self.exact, Method::Exact),
                (self.bounded, Method::Bounded),
                (self.stochastic, Method::Stochastic),
                (self.multidimensional, Method::Multidimensional),
            ]
            .into_iter()
            .find_map(|(given, method)| given.then_some(method))
        })
    }

    /// The mode these flags ask for, at `spp` samples per pixel: the named
    /// method, or the default at `spp`; a flag of another method is a usage
    /// error naming the method this render uses.
    pub fn mode(&self, spp: u32, knobs: &CutKnobs) -> Result<Mode, CliError> {
        let named = self.named_method();
        let method = named.unwrap_or(if self.reconstruct.is_some() {
            Method::Bounded
        } else if matches!(default_mode(spp), Mode::Stochastic(_)) {
            Method::Stochastic
        } else {
            Method::Bounded
        });
        let chosen = match named {
            Some(_) => format!("this render's method is {}", method.name()),
            None => format!("at {spp} spp this render's method is {} by default", method.name()),
        };
        let only = |flag: &'static str, given: bool, wanted: &[Method]| {
            if given && !wanted.contains(&method) {
                let names: Vec<&str> = wanted.iter().map(|m| m.name()).collect();
                let remedy = match names[..] {
                    [only] => format!("add --method {only}"),
                    _ => "drop it or choose another --method".into(),
                };
                return Err(CliError::Usage {
                    flag,
                    message: format!("applies to the {} method only; {chosen}: {remedy}", names.join(" or ")),
                });
            }
            Ok(())
        };
        let cut_methods = [Method::Bounded, Method::Stochastic, Method::Multidimensional];
        only("--error", self.error.is_some(), &cut_methods)?;
        only("--max-cut", self.max_cut.is_some(), &cut_methods)?;
        only("--group-error", self.group_error.is_some(), &cut_methods)?;
        only("--reconstruct", self.reconstruct.is_some(), &[Method::Bounded])?;
        only("--reuse", self.reuse.is_some(), &[Method::Stochastic])?;
        only("--resampled-rays", knobs.resampled_rays.is_some(), &[Method::Stochastic])?;
        only("--cut-per-sample", knobs.cut_per_sample, &[Method::Stochastic])?;
        only("--cut-draws", knobs.cut_draws.is_some(), &[Method::Stochastic])?;
        match method {
            Method::Exact => Ok(Mode::Exact),
            Method::Multidimensional => Ok(Mode::Multidimensional(self.cut(MULTIDIMENSIONAL_DEFAULTS)?)),
            Method::Bounded => {
                let mut cut = self.cut(CutSettings::default())?;
                if let Some(block) = self.reconstruct {
                    if block == 0 {
                        return Err(CliError::Usage {
                            flag: "--reconstruct",
                            message: "the block must be at least 1 pixel".into(),
                        });
                    }
                    cut.reconstruction_block = block;
                }
                Ok(Mode::Bounded(cut))
            }
            Method::Stochastic => {
                let mut cut = self.cut(STOCHASTIC_DEFAULTS)?;
                cut.pixel_cut = !knobs.cut_per_sample;
                cut.cut_draws = knobs.cut_draws.unwrap_or(cut.cut_draws);
                cut.resampled_rays = knobs.resampled_rays.unwrap_or(cut.resampled_rays);
                if let Some(block) = self.reuse {
                    if !(2..=MAX_REUSE_BLOCK).contains(&block) {
                        return Err(CliError::Usage {
                            flag: "--reuse",
                            message: format!("the block's edge must be 2 to {MAX_REUSE_BLOCK} pixels, not {block}"),
                        });
                    }
                    cut.reuse_block = block;
                }
                Ok(Mode::Stochastic(cut))
            }
        }
    }

    /// A cut method's settings: its defaults with `--error`, `--max-cut`
    /// and `--group-error` applied.
    fn cut(&self, defaults: CutSettings) -> Result<CutSettings, CliError> {
        let mut cut = cut_settings(self.error.unwrap_or(defaults.error), self.max_cut.unwrap_or(defaults.max_cut))?;
        cut.group_error = self.group_error.unwrap_or(defaults.group_error);
        Ok(cut)
    }
}

/// The largest block of `--reuse`: a pixel's light costs about B^2 cuts'
/// shadow rays and evaluations.
const MAX_REUSE_BLOCK: u32 = 8;

/// The mode a render uses when no `--method` is given, at `spp` samples per
/// pixel, with its default settings.
#[must_use]
pub fn default_mode(spp: u32) -> Mode {
    if spp >= STOCHASTIC_FROM_SPP {
        Mode::Stochastic(STOCHASTIC_DEFAULTS)
    } else {
        Mode::Bounded(CutSettings::default())
    }
}

/// The options every rendering command shares (pbrt-style overrides).
#[derive(Debug, Args)]
pub struct PassArgs {
    /// Film size, overriding the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, help_heading = "Sampling")]
    pub resolution: Option<(u32, u32)>,
    /// Seed of every random choice (sample positions, representatives, VPLs).
    #[arg(long, default_value_t = 0, help_heading = "Sampling")]
    pub seed: u64,
    /// Worker threads (0: one per CPU; at most 1024). The image does not depend on it.
    #[arg(long, default_value_t = 0, value_parser = parse_threads, help_heading = "Sampling")]
    pub threads: usize,
    /// Render only this half-open window of the full frame, in pixels.
    #[arg(long, value_name = "x0,x1,y0,y1", value_parser = parse_pixel_bounds, help_heading = "Sampling")]
    pub pixel_bounds: Option<[u32; 4]>,
    /// Indirect light, overriding the scene's `[indirect]`: `path` (camera
    /// paths with next-event estimation at every vertex), `vpl` (virtual
    /// point lights) or `none` (direct light only). The scene's settings
    /// of the method are kept; otherwise max-depth 8, or 10,000 one-bounce
    /// VPL paths (docs/design.md §6.7).
    #[arg(long, value_name = "path|vpl|none", value_parser = ["path", "vpl", "none"], help_heading = "Indirect light")]
    pub indirect: Option<String>,
    /// The path method's most surface interactions per camera path (1:
    /// direct light only; Mitsuba 3's max_depth counts one more).
    #[arg(long, value_name = "N", help_heading = "Indirect light")]
    pub max_depth: Option<u32>,
    /// Render through the glTF camera of this name, or `#N` for the N-th
    /// camera (from 0) in the file's node order; or a USD stage's camera by
    /// its prim path (/World/Cam). The scene's first camera otherwise;
    /// overrides a TOML's [camera].
    #[arg(long, value_name = "NAME|#N|/PATH", help_heading = "Scene overrides")]
    pub camera: Option<String>,
    /// Add an environment: `R,G,B` (a constant radiance, W/(m^2 sr), e.g.
    /// 1,1,1) or a lat-long OpenEXR file; 1,024 directional lights. It
    /// replaces the scene's own environment.
    #[arg(long, value_name = "R,G,B|FILE.exr", help_heading = "Scene overrides")]
    pub environment: Option<String>,
    /// Add a sun: azimuth and elevation in degrees (azimuth from +Z towards
    /// +X, elevation above the horizon, +Y up), irradiance in W/m^2
    /// (default 3).
    #[arg(long, value_name = "AZIMUTH,ELEVATION[,IRRADIANCE]", value_parser = parse_sun, allow_hyphen_values = true, help_heading = "Scene overrides")]
    pub sun: Option<[f32; 3]>,
    /// Luminous efficacy converting a glTF file's light units (candela,
    /// lux) to W/sr and W/m^2: 683 (Blender's convention) unless given; 1
    /// matches glTF viewers, which take 1 cd as 1 W/sr.
    #[arg(long, value_name = "LM_PER_W", help_heading = "Scene overrides")]
    pub lumens_per_watt: Option<f32>,
    /// Open the shutter from OPEN to CLOSE seconds (overrides the scene's
    /// [camera] shutter): what moves blurs, and a glTF file's animation is
    /// played over it (its node transforms sampled at 33 times). OPEN =
    /// CLOSE renders the animation's pose at that instant, sharp. Times
    /// are the file's seconds: Blender's glTF exporter writes frame f at f
    /// / fps seconds, so frame 6 of a 24 fps animation is --shutter
    /// 0.25,0.25, and the shutter of frame 6 (half a frame, centred) is
    /// --shutter 0.2396,0.2604. For a USD stage OPEN and CLOSE are its time
    /// codes (frames, for Blender's exports), and what its time samples
    /// move blurs.
    #[arg(long, value_name = "OPEN,CLOSE", value_parser = parse_shutter, allow_hyphen_values = true, help_heading = "Scene overrides")]
    pub shutter: Option<[f32; 2]>,
    /// The glTF file's animation to play over the shutter, by name (its
    /// first otherwise). A name the file lacks is an error; without a
    /// shutter the animation is not played (a warning says so).
    #[arg(long, value_name = "NAME", help_heading = "Scene overrides")]
    pub animation: Option<String>,
    /// The USD stage's time code to render (its start time code
    /// otherwise): every attribute is read at it.
    #[arg(long, value_name = "T", allow_hyphen_values = true, help_heading = "Scene overrides")]
    pub time: Option<f64>,
    /// A directory where a USD stage's assets are looked for when they are
    /// not beside the layer that names them (USD's search paths, as
    /// PXR_AR_DEFAULT_SEARCH_PATH, which is read too); may be repeated.
    #[arg(long, value_name = "DIR", help_heading = "Scene overrides")]
    pub asset_path: Vec<PathBuf>,
    /// Make what the scene lacks an error: a missing layer, texture or
    /// file, a format or prim type this renderer does not read (a warning
    /// otherwise, and the render goes on without it).
    #[arg(long, help_heading = "Scene overrides")]
    pub strict: bool,
}

impl PassArgs {
    /// Loads the scene (through `--camera` when given) and prints its
    /// warnings, one line each.
    pub fn load(&self, path: &Path) -> Result<Scene, CliError> {
        let options = LoadOptions {
            camera: self.camera.as_deref(),
            lumens_per_watt: self.lumens_per_watt,
            shutter: self.shutter,
            animation: self.animation.as_deref(),
            time: self.time,
            asset_paths: &self.asset_path,
            strict: self.strict,
        };
        super::process::read_usd_in_a_child(path, &options.flags())?;
        let mut scene = Scene::load_with(path, &options)?;
        scene.add_lights(self.environment.as_deref(), self.sun)?;
        scene.set_indirect(self.indirect.as_deref(), self.max_depth)?;
        for warning in scene.warnings.iter().chain(&scene.incomplete) {
            eprintln!("warning: {warning}");
        }
        if !scene.has_light() {
            eprintln!(
                "warning: {}: the scene has no lights and renders black: add --environment 1,1,1 or --sun 30,45 \
                 (or lights in a TOML scene that imports it)",
                path.display()
            );
        }
        Ok(scene)
    }

    /// The pass these options describe for `scene`, at `spp` samples per
    /// pixel (None: the scene's).
    pub fn settings(&self, scene: &Scene, spp: Option<u32>) -> Result<PassSettings, CliError> {
        pass_settings(scene, self.resolution, spp, self.seed, self.pixel_bounds)
    }
}

/// Film size, samples and window after applying the command-line overrides.
pub fn pass_settings(
    scene: &Scene,
    resolution: Option<(u32, u32)>,
    spp: Option<u32>,
    seed: u64,
    pixel_bounds: Option<[u32; 4]>,
) -> Result<PassSettings, CliError> {
    let (width, height) = resolution.unwrap_or((scene.film.width, scene.film.height));
    check_resolution(&scene.path, "--resolution", width, height)?;
    let spp = spp.unwrap_or(scene.film.spp);
    if !(1..=crate::scene::MAX_SPP).contains(&spp) {
        return Err(CliError::Usage {
            flag: "--spp",
            message: format!("must be from 1 to {}, got {spp}", crate::scene::MAX_SPP),
        });
    }
    let bounds = match pixel_bounds {
        None => PixelBounds::full(width, height),
        Some([x0, x1, y0, y1]) => {
            if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
                return Err(CliError::Usage {
                    flag: "--pixel-bounds",
                    message: format!("{x0},{x1},{y0},{y1} is not a non-empty window inside the {width}x{height} frame"),
                });
            }
            PixelBounds { x0, x1, y0, y1 }
        }
    };
    Ok(PassSettings {
        width,
        height,
        spp,
        seed,
        bounds,
        aovs: Aovs::all(false),
        transparent: false,
        texture_filter: crate::render::TextureFilter::Mip,
    })
}

/// The cut settings of a lightcuts render, validated.
pub fn cut_settings(error: f64, max_cut: usize) -> Result<CutSettings, CliError> {
    if !(error.is_finite() && error >= 0.0) {
        return Err(CliError::Usage { flag: "--error", message: format!("must be finite and >= 0, got {error}") });
    }
    if max_cut == 0 {
        return Err(CliError::Usage { flag: "--max-cut", message: "must be at least 1".into() });
    }
    Ok(CutSettings { error, max_cut, ..CutSettings::default() })
}

/// Parses `I/N` with 0 <= I < N.
pub fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("expected I/N, got '{s}'"))?;
    let i: u32 = i.trim().parse().map_err(|_| format!("'{i}' is not a non-negative integer"))?;
    let n: u32 = n.trim().parse().map_err(|_| format!("'{n}' is not a positive integer"))?;
    if n == 0 || i >= n {
        return Err(format!("need 0 <= I < N, got {i}/{n}"));
    }
    Ok((i, n))
}

/// Parses `WxH`.
/// Parses a thread count: 0 (one per CPU) to [`MAX_THREADS`](crate::render::MAX_THREADS).
pub fn parse_threads(s: &str) -> Result<usize, String> {
    let most = crate::render::MAX_THREADS;
    match s.trim().parse::<usize>() {
        Ok(n) if n <= most => Ok(n),
        _ => Err(format!("must be a whole number from 0 (one per CPU) to {most}, got '{s}'")),
    }
}

pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("width '{w}' is not a positive integer"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("height '{h}' is not a positive integer"))?;
    if w == 0 || h == 0 {
        return Err(format!("width and height must be at least 1, got {w}x{h}"));
    }
    Ok((w, h))
}

/// Parses `x0,x1,y0,y1`.
/// `AZIMUTH,ELEVATION[,IRRADIANCE]` (degrees, degrees, W/m^2).
pub fn parse_shutter(s: &str) -> Result<[f32; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [open, close] = parts[..] else { return Err(format!("expected OPEN,CLOSE (seconds), got '{s}'")) };
    let number = |v: &str| v.trim().parse::<f32>().map_err(|e| format!("'{v}' is not a number: {e}"));
    Ok([number(open)?, number(close)?])
}

pub fn parse_sun(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(format!("expected AZIMUTH,ELEVATION[,IRRADIANCE], got '{s}'"));
    }
    let mut out = [0.0, 0.0, crate::scene::ADDED_SUN_IRRADIANCE];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p.trim().parse().map_err(|_| format!("'{p}' is not a number"))?;
    }
    Ok(out)
}

pub fn parse_pixel_bounds(s: &str) -> Result<[u32; 4], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 4 {
        return Err(format!("expected x0,x1,y0,y1, got '{s}'"));
    }
    let mut out = [0u32; 4];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p.trim().parse().map_err(|_| format!("'{p}' is not a non-negative integer"))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_and_bounds_parse_and_reject_garbage() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert!(parse_resolution("640").is_err());
        assert!(parse_resolution("0x480").is_err());
        assert!(parse_resolution("-3x4").is_err());
        assert_eq!(parse_pixel_bounds("1,2,3,4"), Ok([1, 2, 3, 4]));
        assert!(parse_pixel_bounds("1,2,3").is_err());
        assert!(parse_pixel_bounds("1,2,3,x").is_err());
    }

    /// The help states the defaults the code has, and every scene format
    /// the loader reads.
    #[test]
    fn help_states_the_defaults_and_formats_that_exist() {
        use clap::CommandFactory;
        let command = crate::cli::Cli::command();
        let render = command.find_subcommand("render").expect("a render command");
        let help = |name: &str| {
            let arg = render.get_arguments().find(|a| a.get_id() == name).unwrap_or_else(|| panic!("--{name}"));
            arg.get_long_help().or(arg.get_help()).map(ToString::to_string).unwrap_or_default()
        };
        let error = help("error");
        for (mode, default) in [
            ("bounded", CutSettings::default().error),
            ("stochastic", STOCHASTIC_DEFAULTS.error),
            ("multidimensional", MULTIDIMENSIONAL_DEFAULTS.error),
        ] {
            let stated = format!("{mode}: ");
            let at = error.find(&stated).unwrap_or_else(|| panic!("--error names no default for {mode}: {error}"));
            let said = &error[at..].split(';').next().unwrap_or_default();
            assert!(said.contains(&format!("default {default}")), "--error, {mode}: '{said}', the code's {default}");
        }
        let scene = help("scene");
        for extension in [".json", ".gltf", ".glb", ".usd", ".usda", ".usdc", ".usdz", "TOML"] {
            assert!(scene.contains(extension), "the scene's help names no {extension}: {scene}");
        }
        assert!(help("camera").contains("prim path"));
    }

    /// Every `--flag` a help string names is a flag of that command (or of
    /// one of its subcommands), so no help points at a flag that was
    /// renamed or removed.
    #[test]
    fn every_flag_a_help_names_exists() {
        use clap::CommandFactory;
        let root = crate::cli::Cli::command();
        let render = root.find_subcommand("render").expect("a render command").clone();
        fn check(command: &clap::Command, render: &clap::Command, path: &str) {
            // A help may also name a flag of `render` (`a --method exact render`).
            let longs: Vec<String> = command
                .get_arguments()
                .chain(render.get_arguments())
                .filter_map(|a| a.get_long())
                .map(String::from)
                .collect();
            let mut texts: Vec<String> = command
                .get_arguments()
                .filter_map(|a| a.get_long_help().or(a.get_help()))
                .map(ToString::to_string)
                .collect();
            texts.extend(command.get_about().map(ToString::to_string));
            for text in &texts {
                for (at, _) in text.match_indices("--") {
                    let name: String =
                        text[at + 2..].chars().take_while(|c| c.is_ascii_lowercase() || *c == '-').collect();
                    let name = name.trim_end_matches('-');
                    let known = longs.iter().any(|l| l == name)
                        || command.get_subcommands().any(|sub| sub.get_arguments().any(|a| a.get_long() == Some(name)));
                    assert!(name.is_empty() || known, "{path}: the help names --{name}, which is no flag: {text}");
                }
            }
            for sub in command.get_subcommands() {
                check(sub, render, &format!("{path} {}", sub.get_name()));
            }
        }
        check(&root, &render, "lightcuts");
    }

    /// `render --help` groups every flag under a heading a user looks for.
    #[test]
    fn render_help_groups_every_flag() {
        use clap::CommandFactory;
        let command = crate::cli::Cli::command();
        let render = command.find_subcommand("render").expect("a render command");
        let headings =
            ["Output", "Sampling", "Light selection", "Indirect light", "Scene overrides", "Farm", "Advanced"];
        for arg in render.get_arguments().filter(|a| !a.is_hide_set() && !a.is_positional()) {
            if matches!(arg.get_id().as_str(), "help" | "version") {
                continue;
            }
            let heading = arg.get_help_heading().unwrap_or_else(|| panic!("--{} has no heading", arg.get_id()));
            assert!(headings.contains(&heading), "--{}: heading {heading}", arg.get_id());
        }
        for heading in headings {
            assert!(render.get_arguments().any(|a| a.get_help_heading() == Some(heading)), "no flag under {heading}");
        }
    }

    fn render_mode(flags: &[&str], spp: u32) -> Result<Mode, String> {
        use clap::Parser;
        let argv = ["lightcuts", "render", "scene.toml", "-o", "out.exr"].iter().chain(flags);
        let cli = crate::cli::Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
        let crate::cli::Command::Render(args) = cli.command else { unreachable!("a render command") };
        args.mode.mode(spp, &args.knobs).map_err(|e| e.to_string())
    }

    /// `--method` names every mode, its short forms mean the same, the
    /// default follows the samples, and a flag of another method is refused
    /// with the method this render uses.
    #[test]
    fn method_chooses_the_mode_and_refuses_other_methods_flags() {
        use clap::ValueEnum;
        for method in Method::value_variants() {
            let name = method.name();
            let long = render_mode(&["--method", name], 1).expect(name);
            let short = render_mode(&[&format!("--{name}")], 1).expect(name);
            assert_eq!(format!("{long:?}"), format!("{short:?}"), "{name}");
            assert!(long.describe().starts_with(name) || name == "bounded", "{name}: {}", long.describe());
        }
        assert!(matches!(render_mode(&[], 1), Ok(Mode::Bounded(_))));
        assert!(matches!(render_mode(&[], STOCHASTIC_FROM_SPP), Ok(Mode::Stochastic(_))));
        assert!(
            matches!(render_mode(&["--reconstruct", "2"], STOCHASTIC_FROM_SPP), Ok(Mode::Bounded(c)) if c.reconstruction_block == 2)
        );
        assert!(
            matches!(render_mode(&["--reuse", "2"], STOCHASTIC_FROM_SPP), Ok(Mode::Stochastic(c)) if c.reuse_block == 2)
        );
        for (flags, refusal) in [
            (&["--method", "exact", "--error", "0.1"][..], "--error: applies to the bounded or stochastic or multidimensional method only; this render's method is exact"),
            (&["--method", "bounded", "--reuse", "2"][..], "--reuse: applies to the stochastic method only; this render's method is bounded"),
            (&["--reuse", "2"][..], "at 1 spp this render's method is bounded by default"),
            (&["--method", "multidimensional", "--reconstruct", "2"][..], "--reconstruct: applies to the bounded method only"),
            (&["--stochastic", "--cut-draws", "2", "--method", "bounded"][..], "cannot be used with"),
        ] {
            let error = render_mode(flags, 1).expect_err(&flags.join(" "));
            assert!(error.contains(refusal), "{flags:?}: {error}");
        }
    }
}
