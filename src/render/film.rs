//! The rendered window: named channels (OpenEXR's names), one value per
//! pixel each, in scanline order. The beauty and every AOV are channels of
//! the same kind; which AOVs a pass fills is its [`Aovs`].

/// The depth (`Z`) of a pixel where no camera sample hit a surface: far
/// away, as Cycles writes it (1e10), so that depth-based compositing
/// (defocus, fog, depth mattes) puts the background behind everything. 0
/// would read as the nearest possible depth.
pub const BACKGROUND_DEPTH: f32 = 1e10;

/// The beauty's channels: radiance (W/(m^2 sr) per channel) and coverage
/// (the fraction of samples that hit geometry or, unless the film is
/// transparent, saw the environment).
pub const BEAUTY: [&str; 4] = ["R", "G", "B", "A"];

/// Half-open pixel window [x0, x1) x [y0, y1) in pixels of the full frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelBounds {
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
}

impl PixelBounds {
    #[must_use]
    pub fn full(width: u32, height: u32) -> Self {
        Self { x0: 0, x1: width, y0: 0, y1: height }
    }

    #[must_use]
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    #[must_use]
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    #[must_use]
    pub fn area(&self) -> usize {
        self.width() as usize * self.height() as usize
    }
}

/// The AOV layers a pass writes beside the beauty (`render --aovs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Aovs {
    /// `albedo.R/G/B`: the diffuse albedo of the first hit.
    pub albedo: bool,
    /// `N.X/Y/Z`: the shading normal (world space, facing the camera).
    pub normal: bool,
    /// `Z`: the distance from the eye to the nearest hit, metres
    /// ([`BACKGROUND_DEPTH`] where nothing was hit).
    pub depth: bool,
    /// `lightcuts.cut_size` (nodes per shading point, averaged over the
    /// pixel's) and `lightcuts.shadow_rays` (the pixel's): cut modes only.
    pub lightcuts: bool,
    /// `Combined_<group>.R/G/B` per light group (scenes with groups only).
    pub groups: bool,
    /// Cryptomatte's object and material mattes.
    pub cryptomatte: bool,
}

impl Aovs {
    /// The default layers of a render in a mode with (`cut`) or without a
    /// cut: every one but Cryptomatte's (`--cryptomatte` adds it).
    #[must_use]
    pub fn all(cut: bool) -> Self {
        Self { albedo: true, normal: true, depth: true, lightcuts: cut, groups: true, cryptomatte: false }
    }

    /// None of them: the beauty alone.
    #[must_use]
    pub fn none() -> Self {
        Self { albedo: false, normal: false, depth: false, lightcuts: false, groups: false, cryptomatte: false }
    }

    /// The layers named in `list` (`albedo`, `N`, `Z`, `lightcuts`,
    /// `groups`, `cryptomatte`, comma separated; `none` for the beauty alone).
    pub fn parse(list: &str) -> Result<Self, String> {
        let mut aovs = Self::none();
        if list.trim() == "none" {
            return Ok(aovs);
        }
        for name in list.split(',').map(str::trim) {
            match name {
                "albedo" => aovs.albedo = true,
                "N" => aovs.normal = true,
                "Z" => aovs.depth = true,
                "lightcuts" => aovs.lightcuts = true,
                "groups" => aovs.groups = true,
                "cryptomatte" => aovs.cryptomatte = true,
                other => {
                    return Err(format!(
                        "unknown AOV '{other}': expected albedo, N, Z, lightcuts, groups, cryptomatte or none"
                    ))
                }
            }
        }
        Ok(aovs)
    }
}

/// A rendered window of the full frame.
#[derive(Debug, Clone)]
pub struct Film {
    /// Full-frame size in pixels.
    pub full_width: u32,
    pub full_height: u32,
    pub bounds: PixelBounds,
    /// The beauty ([`BEAUTY`]) first, then the AOVs the pass filled: the
    /// fixed ones, each light group's `Combined_<group>.R/G/B` (Cycles'
    /// names for light-group passes), Cryptomatte's `CryptoObject00.R`...
    /// Every value is finite ([`film_value`] sanitises what the integrator
    /// summed, and counts what it had to turn from NaN or infinite).
    pub channels: Vec<FilmChannel>,
    /// Header attributes the channels need (Cryptomatte's metadata).
    pub attributes: Vec<(String, String)>,
}

/// One named channel of a film: `bounds.area()` values, row by row from
/// (x0, y0).
#[derive(Debug, Clone, PartialEq)]
pub struct FilmChannel {
    pub name: String,
    pub values: Vec<f32>,
    /// How many of the values were NaN or infinite when the renderer
    /// stored them (each stored as [`film_value`] says). Every one is a
    /// defect: the render reports them, and the tests assert there are none.
    pub non_finite: u64,
}

/// A finite f32 for the film: NaN becomes 0 and magnitudes beyond f32's
/// range are clamped to the largest finite value, so no NaN or Inf ever
/// reaches a pixel; a NaN or an infinity is counted in `non_finite` (a
/// finite value beyond f32's range, such as 1e39 W/(m^2 sr) from a 1e30
/// W/sr light, is not: it is the true value, clamped to what f32 holds).
#[must_use]
#[inline]
pub fn film_value(x: f64, non_finite: &mut u64) -> f32 {
    if !x.is_finite() {
        *non_finite += 1;
    }
    if x.is_nan() {
        0.0
    } else {
        x.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32
    }
}

impl Film {
    /// Each channel with NaN or infinite values the renderer had to turn
    /// into finite ones, and how many ([`FilmChannel::non_finite`]).
    #[must_use]
    pub fn non_finite(&self) -> Vec<(&str, u64)> {
        self.channels.iter().filter(|c| c.non_finite > 0).map(|c| (c.name.as_str(), c.non_finite)).collect()
    }

    /// The named channel's values, if the film has it.
    #[must_use]
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels.iter().find(|c| c.name == name).map(|c| c.values.as_slice())
    }

    /// The beauty's radiance, pixel by pixel.
    #[must_use]
    pub fn rgb(&self) -> Vec<[f32; 3]> {
        let [r, g, b] = ["R", "G", "B"].map(|c| self.channel(c).expect("every film has the beauty"));
        (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()
    }
}
