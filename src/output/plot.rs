//! Error-against-time plots for `lightcuts sweep`: log-log axes, one series
//! per error statistic, each point labelled with its threshold. Written as
//! SVG, and as PNG by a small rasteriser with a built-in 5x7 font (no
//! external tools).

use std::fmt::Write as _;
use std::path::Path;

use super::preview::write_rgb_png;
use super::{write_atomically, OutputError};

/// One series of (x, y, label) points, drawn in `colour`.
pub struct Series {
    pub name: String,
    pub colour: [u8; 3],
    pub points: Vec<(f64, f64, String)>,
}

pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

const WIDTH: u32 = 800;
const HEIGHT: u32 = 560;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 30.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 70.0;

/// Log-scale axis range covering the values, widened to whole decades.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| *v > 0.0 && v.is_finite()).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let (lo, hi) = (lo.log10().floor(), hi.log10().ceil());
    if hi <= lo {
        (lo, lo + 1.0)
    } else {
        (lo, hi)
    }
}

impl Plot {
    fn frame(&self) -> ((f64, f64), (f64, f64)) {
        let xs = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
        let ys = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
        (decades(xs), decades(ys))
    }

    /// Maps (x, y) to pixel coordinates; values <= 0 sit on the axis.
    fn to_pixels(&self, x: f64, y: f64) -> (f64, f64) {
        let ((x0, x1), (y0, y1)) = self.frame();
        let lx = x.max(1e-300).log10().clamp(x0, x1);
        let ly = y.max(1e-300).log10().clamp(y0, y1);
        let px = LEFT + (lx - x0) / (x1 - x0) * (f64::from(WIDTH) - LEFT - RIGHT);
        let py = f64::from(HEIGHT) - BOTTOM - (ly - y0) / (y1 - y0) * (f64::from(HEIGHT) - TOP - BOTTOM);
        (px, py)
    }

    #[must_use]
    pub fn to_svg(&self) -> String {
        let ((x0, x1), (y0, y1)) = self.frame();
        let (w, h) = (f64::from(WIDTH), f64::from(HEIGHT));
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" font-family="sans-serif" font-size="13">"#
        );
        let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="28" text-anchor="middle" font-size="16">{}</text>"#,
            w / 2.0,
            escape(&self.title)
        );
        for d in x0 as i32..=x1 as i32 {
            let (px, _) = self.to_pixels(10f64.powi(d), 10f64.powf(y0));
            let _ = writeln!(svg, r##"<line x1="{px}" y1="{TOP}" x2="{px}" y2="{}" stroke="#ddd"/>"##, h - BOTTOM);
            let _ = writeln!(
                svg,
                r#"<text x="{px}" y="{}" text-anchor="middle">{}</text>"#,
                h - BOTTOM + 18.0,
                decade_label(d)
            );
        }
        for d in y0 as i32..=y1 as i32 {
            let (_, py) = self.to_pixels(10f64.powf(x0), 10f64.powi(d));
            let _ = writeln!(svg, r##"<line x1="{LEFT}" y1="{py}" x2="{}" y2="{py}" stroke="#ddd"/>"##, w - RIGHT);
            let _ = writeln!(
                svg,
                r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
                LEFT - 6.0,
                py + 4.0,
                decade_label(d)
            );
        }
        let _ = writeln!(
            svg,
            r#"<rect x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="black"/>"#,
            w - LEFT - RIGHT,
            h - TOP - BOTTOM
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            (LEFT + w - RIGHT) / 2.0,
            h - 20.0,
            escape(&self.x_label)
        );
        let _ = writeln!(
            svg,
            r#"<text x="20" y="{}" text-anchor="middle" transform="rotate(-90 20 {})">{}</text>"#,
            (TOP + h - BOTTOM) / 2.0,
            (TOP + h - BOTTOM) / 2.0,
            escape(&self.y_label)
        );
        for (k, s) in self.series.iter().enumerate() {
            let colour = format!("rgb({},{},{})", s.colour[0], s.colour[1], s.colour[2]);
            let path: Vec<String> =
                s.points.iter().map(|p| self.to_pixels(p.0, p.1)).map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
                path.join(" ")
            );
            for (x, y, label) in &s.points {
                let (px, py) = self.to_pixels(*x, *y);
                let _ = writeln!(svg, r#"<circle cx="{px:.1}" cy="{py:.1}" r="4" fill="{colour}"/>"#);
                let _ = writeln!(
                    svg,
                    r#"<text x="{:.1}" y="{:.1}" fill="{colour}">{}</text>"#,
                    px + 6.0,
                    py - 6.0,
                    escape(label)
                );
            }
            let _ = writeln!(
                svg,
                r#"<text x="{}" y="{}" fill="{colour}">{}</text>"#,
                w - RIGHT - 150.0,
                TOP + 20.0 + 18.0 * k as f64,
                escape(&s.name)
            );
        }
        svg.push_str("</svg>\n");
        svg
    }

    /// The same plot as 8-bit RGB pixels.
    #[must_use]
    pub fn to_rgb(&self) -> Vec<u8> {
        let ((x0, x1), (y0, y1)) = self.frame();
        let mut canvas = Canvas::new(WIDTH, HEIGHT);
        let (w, h) = (f64::from(WIDTH), f64::from(HEIGHT));
        canvas.text(&self.title, w / 2.0, 20.0, [0, 0, 0], Align::Centre);
        for d in x0 as i32..=x1 as i32 {
            let (px, _) = self.to_pixels(10f64.powi(d), 10f64.powf(y0));
            canvas.line((px, TOP), (px, h - BOTTOM), [221, 221, 221]);
            canvas.text(&decade_label(d), px, h - BOTTOM + 8.0, [0, 0, 0], Align::Centre);
        }
        for d in y0 as i32..=y1 as i32 {
            let (_, py) = self.to_pixels(10f64.powf(x0), 10f64.powi(d));
            canvas.line((LEFT, py), (w - RIGHT, py), [221, 221, 221]);
            canvas.text(&decade_label(d), LEFT - 8.0, py - 3.0, [0, 0, 0], Align::Right);
        }
        for (a, b) in [
            ((LEFT, TOP), (w - RIGHT, TOP)),
            ((w - RIGHT, TOP), (w - RIGHT, h - BOTTOM)),
            ((LEFT, h - BOTTOM), (w - RIGHT, h - BOTTOM)),
            ((LEFT, TOP), (LEFT, h - BOTTOM)),
        ] {
            canvas.line(a, b, [0, 0, 0]);
        }
        canvas.text(&self.x_label, (LEFT + w - RIGHT) / 2.0, h - 30.0, [0, 0, 0], Align::Centre);
        canvas.text(&self.y_label, LEFT, TOP - 16.0, [0, 0, 0], Align::Left);
        for (k, s) in self.series.iter().enumerate() {
            let pixels: Vec<(f64, f64)> = s.points.iter().map(|p| self.to_pixels(p.0, p.1)).collect();
            for pair in pixels.windows(2) {
                canvas.line(pair[0], pair[1], s.colour);
            }
            for ((px, py), (_, _, label)) in pixels.iter().zip(&s.points) {
                canvas.disc(*px, *py, 4.0, s.colour);
                canvas.text(label, px + 6.0, py - 12.0, s.colour, Align::Left);
            }
            canvas.text(&s.name, w - RIGHT - 150.0, TOP + 10.0 + 14.0 * k as f64, s.colour, Align::Left);
        }
        canvas.pixels
    }

    pub fn write_svg(&self, path: &Path) -> Result<(), OutputError> {
        let svg = self.to_svg();
        write_atomically(path, |t| std::fs::write(t, svg.as_bytes()).map_err(|e| e.to_string()))
    }

    pub fn write_png(&self, path: &Path) -> Result<(), OutputError> {
        write_rgb_png(path, WIDTH, HEIGHT, &self.to_rgb())
    }
}

fn decade_label(d: i32) -> String {
    let v = 10f64.powi(d);
    if (-3..=3).contains(&d) {
        format!("{v}")
    } else {
        format!("1e{d}")
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[derive(Clone, Copy)]
enum Align {
    Left,
    Centre,
    Right,
}

struct Canvas {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Canvas {
    fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![255; (width * height * 3) as usize] }
    }

    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.pixels[i..i + 3].copy_from_slice(&c);
        }
    }

    fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), c: [u8; 3]) {
        let steps = (x1 - x0).abs().max((y1 - y0).abs()).ceil().max(1.0) as i64;
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            self.set((x0 + (x1 - x0) * t).round() as i64, (y0 + (y1 - y0) * t).round() as i64, c);
        }
    }

    fn disc(&mut self, cx: f64, cy: f64, r: f64, c: [u8; 3]) {
        let ri = r.ceil() as i64;
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                if (dx * dx + dy * dy) as f64 <= r * r {
                    self.set(cx.round() as i64 + dx, cy.round() as i64 + dy, c);
                }
            }
        }
    }

    /// Text in the 5x7 font at twice its size is too big for labels; one
    /// pixel per font dot keeps labels readable at 800 x 560.
    fn text(&mut self, s: &str, x: f64, y: f64, c: [u8; 3], align: Align) {
        let width = 6.0 * s.chars().count() as f64;
        let x = match align {
            Align::Left => x,
            Align::Centre => x - width / 2.0,
            Align::Right => x - width,
        };
        for (k, ch) in s.chars().enumerate() {
            let glyph = glyph(ch);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        self.set((x + 6.0 * k as f64) as i64 + col, y as i64 + row as i64, c);
                    }
                }
            }
        }
    }
}

/// 5x7 bitmaps (top row first, bit 4 = leftmost column) for the characters
/// labels use; others draw as a box.
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_lowercase() {
        '0' => [0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e],
        '1' => [0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e],
        '2' => [0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f],
        '3' => [0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e],
        '4' => [0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02],
        '5' => [0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e],
        '6' => [0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e],
        '7' => [0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e],
        '9' => [0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c],
        '.' => [0, 0, 0, 0, 0, 0x0c, 0x0c],
        ',' => [0, 0, 0, 0, 0x0c, 0x04, 0x08],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '-' => [0, 0, 0, 0x1f, 0, 0, 0],
        '+' => [0, 0x04, 0x04, 0x1f, 0x04, 0x04, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        ':' => [0, 0x0c, 0x0c, 0, 0x0c, 0x0c, 0],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '=' => [0, 0, 0x1f, 0, 0x1f, 0, 0],
        ' ' => [0; 7],
        'a' => [0, 0, 0x0e, 0x01, 0x0f, 0x11, 0x0f],
        'b' => [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1e],
        'c' => [0, 0, 0x0e, 0x10, 0x10, 0x11, 0x0e],
        'd' => [0x01, 0x01, 0x0d, 0x13, 0x11, 0x11, 0x0f],
        'e' => [0, 0, 0x0e, 0x11, 0x1f, 0x10, 0x0e],
        'f' => [0x06, 0x09, 0x08, 0x1c, 0x08, 0x08, 0x08],
        'g' => [0, 0x0f, 0x11, 0x11, 0x0f, 0x01, 0x0e],
        'h' => [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11],
        'i' => [0x04, 0, 0x0c, 0x04, 0x04, 0x04, 0x0e],
        'k' => [0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12],
        'l' => [0x0c, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e],
        'm' => [0, 0, 0x1a, 0x15, 0x15, 0x11, 0x11],
        'n' => [0, 0, 0x16, 0x19, 0x11, 0x11, 0x11],
        'o' => [0, 0, 0x0e, 0x11, 0x11, 0x11, 0x0e],
        'p' => [0, 0, 0x1e, 0x11, 0x1e, 0x10, 0x10],
        'r' => [0, 0, 0x16, 0x19, 0x10, 0x10, 0x10],
        's' => [0, 0, 0x0e, 0x10, 0x0e, 0x01, 0x1e],
        't' => [0x08, 0x08, 0x1c, 0x08, 0x08, 0x09, 0x06],
        'u' => [0, 0, 0x11, 0x11, 0x11, 0x13, 0x0d],
        'v' => [0, 0, 0x11, 0x11, 0x11, 0x0a, 0x04],
        'w' => [0, 0, 0x11, 0x11, 0x15, 0x15, 0x0a],
        'x' => [0, 0, 0x11, 0x0a, 0x04, 0x0a, 0x11],
        'y' => [0, 0, 0x11, 0x11, 0x0f, 0x01, 0x0e],
        'z' => [0, 0, 0x1f, 0x02, 0x04, 0x08, 0x1f],
        'j' => [0x02, 0, 0x06, 0x02, 0x02, 0x12, 0x0c],
        'q' => [0, 0, 0x0d, 0x13, 0x0f, 0x01, 0x01],
        _ => [0x1f, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1f],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_cover_the_values_and_points_land_inside_the_frame() {
        assert_eq!(decades([0.03, 7.0].into_iter()), (-2.0, 1.0));
        let plot = Plot {
            title: "t".into(),
            x_label: "time (s)".into(),
            y_label: "error (%)".into(),
            series: vec![Series {
                name: "mean".into(),
                colour: [200, 0, 0],
                points: vec![(0.5, 0.01, "2%".into()), (5.0, 0.1, "0.1%".into())],
            }],
        };
        for (x, y) in [(0.5, 0.01), (5.0, 0.1)] {
            let (px, py) = plot.to_pixels(x, y);
            assert!(
                (LEFT..=f64::from(WIDTH) - RIGHT).contains(&px) && (TOP..=f64::from(HEIGHT) - BOTTOM).contains(&py)
            );
        }
        assert!(plot.to_svg().contains("<polyline"));
        let rgb = plot.to_rgb();
        assert_eq!(rgb.len(), (WIDTH * HEIGHT * 3) as usize);
        assert!(rgb.chunks(3).any(|p| p == [200, 0, 0]), "the series is drawn");
    }
}
