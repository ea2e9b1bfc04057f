//! The rendered window: beauty and AOVs per pixel, in scanline order.

/// The depth (`Z`) of a pixel where no camera sample hit a surface: far
/// away, as Cycles writes it (1e10), so that depth-based compositing
/// (defocus, fog, depth mattes) puts the background behind everything. 0
/// would read as the nearest possible depth.
pub const BACKGROUND_DEPTH: f32 = 1e10;

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

/// What one pixel holds: the averages over its samples. Every value is finite
/// (the integrator sanitises before storing).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pixel {
    /// Radiance, W/(m^2 sr) per channel.
    pub rgb: [f32; 3],
    /// Coverage: the fraction of samples that hit geometry or, unless the
    /// film is transparent, saw the environment.
    pub alpha: f32,
    pub albedo: [f32; 3],
    /// Shading normal (world space, facing the camera), averaged over hits.
    pub normal: [f32; 3],
    /// Distance from the eye to the nearest hit, metres; [`BACKGROUND_DEPTH`]
    /// where no sample hit a surface.
    pub z: f32,
    /// Nodes in the lightcut, averaged over the pixel's shading points.
    pub cut_size: f32,
    /// Shadow rays cast for this pixel.
    pub shadow_rays: f32,
}

/// A rendered window of the full frame.
#[derive(Debug, Clone)]
pub struct Film {
    /// Full-frame size in pixels.
    pub full_width: u32,
    pub full_height: u32,
    pub bounds: PixelBounds,
    /// bounds.area() pixels, row by row from (x0, y0).
    pub pixels: Vec<Pixel>,
    /// Channels beside the beauty and the fixed AOVs, each with one value
    /// per pixel in the order of `pixels`: the light groups'
    /// `Combined_<group>.R/G/B`, Cryptomatte's `CryptoObject00.R`...
    pub channels: Vec<FilmChannel>,
    /// Header attributes those channels need (Cryptomatte's metadata).
    pub attributes: Vec<(String, String)>,
}

/// One named channel of a film.
#[derive(Debug, Clone, PartialEq)]
pub struct FilmChannel {
    pub name: String,
    pub values: Vec<f32>,
}
