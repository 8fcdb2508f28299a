//! A small anti-aliased raster painter, enough to paint the paper's figure into a PNG without
//! an SVG renderer: lines (solid or dashed, any width), filled discs and text in the bundled
//! DejaVu Sans Bold (the only font the core carries).

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use image::{ImageFormat, RgbImage};

use crate::pipeline::label::FONT_BYTES;

/// `#rrggbb` as RGB; black for anything else.
pub(crate) fn rgb(hex: &str) -> [u8; 3] {
    let channel = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            .unwrap_or(0)
    };
    if hex.len() == 7 && hex.starts_with('#') {
        [channel(1), channel(3), channel(5)]
    } else {
        [0, 0, 0]
    }
}

pub(crate) struct Canvas {
    image: RgbImage,
    font: FontRef<'static>,
}

impl Canvas {
    /// A white canvas.
    pub(crate) fn new(width: u32, height: u32) -> Result<Canvas, ab_glyph::InvalidFont> {
        Ok(Canvas {
            image: RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255])),
            font: FontRef::try_from_slice(FONT_BYTES)?,
        })
    }

    fn blend(&mut self, x: i64, y: i64, colour: [u8; 3], alpha: f64) {
        if alpha <= 0.0 || x < 0 || y < 0 {
            return;
        }
        let (Ok(x), Ok(y)) = (u32::try_from(x), u32::try_from(y)) else {
            return;
        };
        if x >= self.image.width() || y >= self.image.height() {
            return;
        }
        let a = alpha.min(1.0);
        let pixel = self.image.get_pixel_mut(x, y);
        for (p, c) in pixel.0.iter_mut().zip(colour) {
            *p = (f64::from(*p) * (1.0 - a) + f64::from(c) * a).round() as u8;
        }
    }

    /// Pixels within `reach` of the box (x0, y0)–(x1, y1), each with its centre.
    fn around(
        &self,
        (x0, y0, x1, y1): (f64, f64, f64, f64),
        reach: f64,
    ) -> Vec<(i64, i64, f64, f64)> {
        let left = (x0.min(x1) - reach).floor().max(0.0) as i64;
        let right = (x0.max(x1) + reach)
            .ceil()
            .min(f64::from(self.image.width())) as i64;
        let top = (y0.min(y1) - reach).floor().max(0.0) as i64;
        let bottom = (y0.max(y1) + reach)
            .ceil()
            .min(f64::from(self.image.height())) as i64;
        (top..bottom)
            .flat_map(|y| (left..right).map(move |x| (x, y, x as f64 + 0.5, y as f64 + 0.5)))
            .collect()
    }

    /// A straight segment of `width` with round ends.
    fn segment(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), colour: [u8; 3], width: f64) {
        let half = width / 2.0;
        let (dx, dy) = (x1 - x0, y1 - y0);
        let length2 = dx * dx + dy * dy;
        for (x, y, cx, cy) in self.around((x0, y0, x1, y1), half + 1.0) {
            let t = if length2 > 0.0 {
                (((cx - x0) * dx + (cy - y0) * dy) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let distance = ((cx - x0 - t * dx).powi(2) + (cy - y0 - t * dy).powi(2)).sqrt();
            self.blend(x, y, colour, (half + 0.5 - distance).clamp(0.0, 1.0));
        }
    }

    /// A polyline, dashed by `dash` (SVG `stroke-dasharray`, empty: solid), the pattern
    /// running on across its corners as SVG's does.
    pub(crate) fn polyline(
        &mut self,
        points: &[(f64, f64)],
        colour: [u8; 3],
        width: f64,
        dash: &str,
    ) {
        let mut pattern: Vec<f64> = dash
            .split_whitespace()
            .filter_map(|d| d.parse().ok())
            .filter(|d: &f64| *d > 0.0)
            .collect();
        // SVG repeats a pattern of odd length twice, so that dashes and gaps alternate.
        if pattern.len() % 2 == 1 {
            pattern.extend(pattern.clone());
        }
        let mut index = 0;
        let mut left = pattern.first().copied().unwrap_or(f64::INFINITY);
        for pair in points.windows(2) {
            let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
            let length = ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
            let at = |t: f64| {
                if length > 0.0 {
                    (x0 + (x1 - x0) * t / length, y0 + (y1 - y0) * t / length)
                } else {
                    (x0, y0)
                }
            };
            let mut t = 0.0;
            while t < length {
                let step = left.min(length - t);
                if index % 2 == 0 {
                    self.segment(at(t), at(t + step), colour, width);
                }
                t += step;
                left -= step;
                if left <= 1e-9 && !pattern.is_empty() {
                    index = (index + 1) % pattern.len();
                    left = pattern[index];
                }
            }
        }
    }

    /// A filled disc.
    pub(crate) fn disc(&mut self, (x, y): (f64, f64), radius: f64, colour: [u8; 3]) {
        for (px, py, cx, cy) in self.around((x, y, x, y), radius + 1.0) {
            let distance = ((cx - x).powi(2) + (cy - y).powi(2)).sqrt();
            self.blend(px, py, colour, (radius + 0.5 - distance).clamp(0.0, 1.0));
        }
    }

    /// A filled axis-aligned rectangle, its edges anti-aliased by how much of each pixel
    /// they cover.
    pub(crate) fn rect(
        &mut self,
        (x, y): (f64, f64),
        (width, height): (f64, f64),
        colour: [u8; 3],
    ) {
        let (x1, y1) = (x + width, y + height);
        for py in y.floor() as i64..y1.ceil() as i64 {
            let cover_y = (y1.min(py as f64 + 1.0) - y.max(py as f64)).clamp(0.0, 1.0);
            for px in x.floor() as i64..x1.ceil() as i64 {
                let cover_x = (x1.min(px as f64 + 1.0) - x.max(px as f64)).clamp(0.0, 1.0);
                self.blend(px, py, colour, cover_x * cover_y);
            }
        }
    }

    /// The advance width of `text` at `size` px per em.
    pub(crate) fn text_width(&self, text: &str, size: f64) -> f64 {
        let scaled = self.font.as_scaled(self.scale(size));
        let mut width = 0.0;
        let mut previous = None;
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(prev) = previous {
                width += scaled.kern(prev, id);
            }
            width += scaled.h_advance(id);
            previous = Some(id);
        }
        f64::from(width)
    }

    fn scale(&self, size: f64) -> PxScale {
        // SVG's font-size is pixels per em; ab_glyph scales by the font's height.
        let units_per_em = self.font.units_per_em().unwrap_or(2048.0);
        PxScale::from(size as f32 * self.font.height_unscaled() / units_per_em)
    }

    /// `text` with its baseline at `y`, starting at, centred on or ending at `x` as `anchor`
    /// is SVG's `start`, `middle` or `end`.
    pub(crate) fn text(
        &mut self,
        text: &str,
        (x, y): (f64, f64),
        anchor: &str,
        size: f64,
        colour: [u8; 3],
    ) {
        let width = self.text_width(text, size);
        let start = match anchor {
            "middle" => x - width / 2.0,
            "end" => x - width,
            _ => x,
        };
        let scale = self.scale(size);
        let scaled = self.font.as_scaled(scale);
        let mut caret = start as f32;
        let mut previous = None;
        let mut outlines = Vec::new();
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(prev) = previous {
                caret += scaled.kern(prev, id);
            }
            let glyph = id.with_scale_and_position(scale, point(caret, y as f32));
            caret += scaled.h_advance(id);
            previous = Some(id);
            outlines.extend(self.font.outline_glyph(glyph));
        }
        for outline in outlines {
            let bounds = outline.px_bounds();
            let (left, top) = (bounds.min.x.floor() as i64, bounds.min.y.floor() as i64);
            let mut coverage = Vec::new();
            outline.draw(|u, v, c| coverage.push((i64::from(u), i64::from(v), f64::from(c))));
            for (u, v, c) in coverage {
                self.blend(left + u, top + v, colour, c);
            }
        }
    }

    pub(crate) fn png(&self) -> Result<Vec<u8>, image::ImageError> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        self.image.write_to(&mut bytes, ImageFormat::Png)?;
        Ok(bytes.into_inner())
    }

    #[cfg(test)]
    pub(crate) fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        self.image.get_pixel(x, y).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_read_from_hex() {
        assert_eq!(rgb("#0072b2"), [0x00, 0x72, 0xb2]);
        assert_eq!(rgb("red"), [0, 0, 0]);
    }

    #[test]
    fn a_line_covers_its_pixels_and_leaves_the_rest_white() {
        let mut canvas = Canvas::new(40, 20).unwrap();
        canvas.polyline(&[(2.0, 10.0), (38.0, 10.0)], [0, 0, 0], 3.0, "");
        assert_eq!(canvas.pixel(20, 10), [0, 0, 0]);
        assert_eq!(canvas.pixel(20, 2), [255, 255, 255]);
    }

    #[test]
    fn a_dash_leaves_gaps() {
        let mut canvas = Canvas::new(40, 20).unwrap();
        // 8 on, 4 off: x in 1..9 drawn, 9..13 blank, 13..21 drawn.
        canvas.polyline(&[(1.0, 10.0), (39.0, 10.0)], [0, 0, 0], 2.0, "8 4");
        assert_eq!(canvas.pixel(5, 10), [0, 0, 0]);
        assert_eq!(canvas.pixel(11, 10), [255, 255, 255]);
        assert_eq!(canvas.pixel(17, 10), [0, 0, 0]);
    }

    #[test]
    fn text_is_painted_where_its_anchor_puts_it() {
        let mut canvas = Canvas::new(200, 40).unwrap();
        let width = canvas.text_width("Hello", 16.0);
        assert!(width > 30.0 && width < 60.0, "{width}");
        canvas.text("Hello", (190.0, 30.0), "end", 16.0, [0, 0, 0]);
        let inked = |canvas: &Canvas, xs: std::ops::Range<u32>| {
            xs.flat_map(|x| (0..40).map(move |y| (x, y)))
                .filter(|(x, y)| canvas.pixel(*x, *y) != [255, 255, 255])
                .count()
        };
        assert!(inked(&canvas, 130..192) > 50);
        assert_eq!(inked(&canvas, 0..120), 0);
        assert!(!canvas.png().unwrap().is_empty());
    }
}
