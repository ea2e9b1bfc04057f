//! Error-against-time plots for `lightcuts sweep`: log-log axes, one series
//! per statistic, each point labelled with its setting. Drawn once with
//! plotters, into SVG and into a PNG bitmap.
//!
//! The text is drawn with a TrueType font read at run time (DejaVu Sans from
//! Debian's fonts-dejavu-core, or `$LIGHTCUTS_FONT`), so no font is compiled
//! in and nothing links to fontconfig.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::preview::write_rgb_png;
use super::{write_atomically, OutputError};

/// One series of (x, y, label) points, drawn in `colour`.
pub struct Series {
    pub name: String,
    pub colour: [u8; 3],
    /// Drawn dashed (e.g. a second statistic of the same setting).
    pub dashed: bool,
    pub points: Vec<(f64, f64, String)>,
}

pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

const WIDTH: u32 = 900;
const HEIGHT: u32 = 620;
/// The family name plotters knows our font by.
const FONT: &str = "sans-serif";

/// Fonts tried in order when `$LIGHTCUTS_FONT` is not set.
const FONT_FILES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
];

/// Registers the first readable font with plotters, once per process.
/// Returns the files tried when none is usable.
fn register_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let candidates: Vec<PathBuf> = match std::env::var_os("LIGHTCUTS_FONT") {
                Some(font) => vec![PathBuf::from(font)],
                None => FONT_FILES.iter().map(PathBuf::from).collect(),
            };
            for file in &candidates {
                if let Ok(bytes) = std::fs::read(file) {
                    // plotters keeps fonts for the whole process: leak the bytes once.
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    if plotters::style::register_font(FONT, FontStyle::Normal, bytes).is_ok() {
                        return Ok(());
                    }
                }
            }
            Err(candidates.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))
        })
        .clone()
}

/// Log-scale axis range covering the positive finite values, widened to
/// whole decades.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| *v > 0.0 && v.is_finite()).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    let (lo, hi) = (10f64.powf(lo.log10().floor()), 10f64.powf(hi.log10().ceil()));
    if hi <= lo {
        (lo, lo * 10.0)
    } else {
        (lo, hi)
    }
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

impl Plot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        root.fill(&WHITE)?;
        let points = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = decades(points().map(|p| p.0));
        let (y0, y1) = decades(points().map(|p| p.1));
        // Values at or below 0 (an exact result) sit on the lower axis.
        let clamp = |x: f64, y: f64| (x.clamp(x0, x1), y.clamp(y0, y1));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, (FONT, 22))
            .margin(18)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .x_label_formatter(&|v| format!("{v}"))
            .y_label_formatter(&|v| format!("{v}"))
            .draw()?;
        for s in &self.series {
            let colour = RGBColor(s.colour[0], s.colour[1], s.colour[2]);
            let line = s.points.iter().map(|p| clamp(p.0, p.1));
            let style = colour.stroke_width(2);
            let drawn = if s.dashed {
                chart.draw_series(DashedLineSeries::new(line, 8, 5, style))?
            } else {
                chart.draw_series(LineSeries::new(line, style))?
            };
            drawn
                .label(&s.name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2)));
            chart.draw_series(s.points.iter().map(|p| {
                let at = clamp(p.0, p.1);
                EmptyElement::at(at)
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(p.2.clone(), (6, -16), (FONT, 13).into_font().color(&colour))
            }))?;
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()?;
        root.present()
    }

    fn drawing_error(path: &Path, error: impl std::error::Error + Send + Sync + 'static) -> OutputError {
        OutputError::Plot { path: path.to_path_buf(), source: Box::new(error) }
    }

    fn font(path: &Path) -> Result<(), OutputError> {
        register_font().map_err(|tried| OutputError::NoFont { path: path.to_path_buf(), tried })
    }

    /// The plot as an SVG document.
    pub fn to_svg(&self, path: &Path) -> Result<String, OutputError> {
        Self::font(path)?;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
            self.draw(&root).map_err(|e| Self::drawing_error(path, e))?;
        }
        Ok(svg)
    }

    /// The plot as 8-bit RGB pixels, `WIDTH` x `HEIGHT`.
    pub fn to_rgb(&self, path: &Path) -> Result<Vec<u8>, OutputError> {
        Self::font(path)?;
        let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
            self.draw(&root).map_err(|e| Self::drawing_error(path, e))?;
        }
        Ok(rgb)
    }

    pub fn write_svg(&self, path: &Path) -> Result<(), OutputError> {
        let svg = self.to_svg(path)?;
        write_atomically(path, |file| file.write_all(svg.as_bytes()).map_err(OutputError::io(path, "write")))
    }

    pub fn write_png(&self, path: &Path) -> Result<(), OutputError> {
        write_rgb_png(path, WIDTH, HEIGHT, &self.to_rgb(path)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot() -> Plot {
        Plot {
            title: "A Title".into(),
            x_label: "time (s)".into(),
            y_label: "error (%)".into(),
            series: vec![Series {
                name: "mean".into(),
                colour: [200, 40, 40],
                dashed: false,
                points: vec![(0.5, 2.0, "2%".into()), (2.0, 0.5, "0.5%".into()), (8.0, 0.0, "0%".into())],
            }],
        }
    }

    #[test]
    fn axes_cover_whole_decades_of_the_positive_values() {
        assert_eq!(decades([0.5, 2.0, 8.0].into_iter()), (0.1, 10.0));
        assert_eq!(decades([0.0, -1.0].into_iter()), (0.1, 10.0));
        assert_eq!(decades([3.0].into_iter()), (1.0, 10.0));
    }

    #[test]
    fn svg_and_bitmap_hold_the_plot() {
        let svg = plot().to_svg(Path::new("p.svg")).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("A Title") && svg.contains("0.5%"), "{svg}");
        let rgb = plot().to_rgb(Path::new("p.png")).unwrap();
        let red = rgb.chunks(3).filter(|p| p == &[200, 40, 40]).count();
        let dark = rgb.chunks(3).filter(|p| p.iter().all(|&c| c < 60)).count();
        assert!(red > 100, "the series is drawn: {red} pixels");
        assert!(dark > 500, "axes and text are drawn: {dark} pixels");
    }
}
