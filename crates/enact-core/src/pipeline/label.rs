//! Text on item frames: ENACT's "Current State" / "Next State i" labels, rendered with the
//! bundled DejaVu Sans Bold (see assets/fonts/LICENSE-DejaVu.txt).

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};
use image::RgbImage;

/// An RGB colour.
type Colour = [u8; 3];

/// The label font, embedded so that generation reads no file at run time.
pub(crate) const FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-Bold.ttf");

/// How ENACT draws a state label onto a frame.
struct LabelStyle {
    origin: (f32, f32),
    fill: Colour,
    outline: Colour,
    /// The outline is the text redrawn at every offset within ± this many pixels.
    outline_px: i32,
}

/// ENACT quirk: PIL labels are placed at (15, 15) with font size `max(40, height / 10)` (51 for
/// a 512-pixel frame), filled (255, 20, 20) over a white outline made by redrawing the text at
/// every offset within ±3 pixels.
const ENACT_LABEL: LabelStyle = LabelStyle {
    origin: (15.0, 15.0),
    fill: [255, 20, 20],
    outline: [255, 255, 255],
    outline_px: 3,
};

impl LabelStyle {
    /// PIL font size (pixels per em) for a frame of this height.
    fn em_px(&self, frame_height: u32) -> f32 {
        (frame_height / 10).max(40) as f32
    }
}

/// Anti-aliased coverage of a piece of text, in frame pixels.
struct Coverage {
    left: i32,
    top: i32,
    width: i32,
    height: i32,
    alpha: Vec<f32>,
}

impl Coverage {
    fn at(&self, x: i32, y: i32) -> f32 {
        let (u, v) = (x - self.left, y - self.top);
        if u < 0 || v < 0 || u >= self.width || v >= self.height {
            0.0
        } else {
            self.alpha[(v * self.width + u) as usize]
        }
    }
}

/// A text overlay ready to blend: the pixels it touches, each with how much of the frame
/// shows through and the (premultiplied) colour laid over it.
pub(crate) struct Overlay {
    cells: Vec<OverlayCell>,
}

struct OverlayCell {
    x: u32,
    y: u32,
    keep: f32,
    paint: [f32; 3],
}

impl Overlay {
    /// Keeps the cells of a dense `width × height` grid at (`left`, `top`) that change a pixel.
    fn from_grid(left: i32, top: i32, width: i32, keep: &[f32], paint: &[[f32; 3]]) -> Overlay {
        let cells = keep
            .iter()
            .zip(paint)
            .enumerate()
            .filter(|(_, (k, _))| **k < 1.0)
            .filter_map(|(i, (k, p))| {
                let (x, y) = (left + i as i32 % width, top + i as i32 / width);
                (x >= 0 && y >= 0).then_some(OverlayCell {
                    x: x as u32,
                    y: y as u32,
                    keep: *k,
                    paint: *p,
                })
            })
            .collect();
        Overlay { cells }
    }

    pub(crate) fn apply(&self, image: &mut RgbImage) {
        let (width, height) = image.dimensions();
        let buffer: &mut [u8] = image;
        for cell in &self.cells {
            if cell.x >= width || cell.y >= height {
                continue;
            }
            let at = ((cell.y * width + cell.x) * 3) as usize;
            for c in 0..3 {
                let mixed = buffer[at + c] as f32 * cell.keep + cell.paint[c];
                buffer[at + c] = mixed.round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

/// The bundled font and the state labels drawn with it.
pub(crate) struct LabelFont {
    font: FontRef<'static>,
}

impl LabelFont {
    pub(crate) fn load() -> Result<LabelFont, ab_glyph::InvalidFont> {
        Ok(LabelFont {
            font: FontRef::try_from_slice(FONT_BYTES)?,
        })
    }

    /// Coverage of `text` whose pen starts at `x` and whose ascender line is at `y` (PIL's
    /// default "la" anchor), with `em_px` pixels per em (PIL's font size).
    fn coverage(&self, text: &str, x: f32, y: f32, em_px: f32) -> Coverage {
        let units_per_em = self.font.units_per_em().unwrap_or(2048.0);
        let scale = PxScale::from(em_px * self.font.height_unscaled() / units_per_em);
        let scaled = self.font.as_scaled(scale);
        let baseline = y + scaled.ascent();
        let mut caret = x;
        let mut previous = None;
        let mut outlines = Vec::new();
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(prev) = previous {
                caret += scaled.kern(prev, id);
            }
            let glyph = id.with_scale_and_position(scale, point(caret, baseline));
            caret += scaled.h_advance(id);
            previous = Some(id);
            if let Some(outline) = self.font.outline_glyph(glyph) {
                outlines.push(outline);
            }
        }
        let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
        for outline in &outlines {
            let b = outline.px_bounds();
            x0 = x0.min(b.min.x.floor() as i32);
            y0 = y0.min(b.min.y.floor() as i32);
            x1 = x1.max(b.max.x.ceil() as i32);
            y1 = y1.max(b.max.y.ceil() as i32);
        }
        if outlines.is_empty() {
            return Coverage {
                left: 0,
                top: 0,
                width: 0,
                height: 0,
                alpha: Vec::new(),
            };
        }
        let (width, height) = (x1 - x0, y1 - y0);
        let mut alpha = vec![0.0f32; (width * height) as usize];
        for outline in &outlines {
            let b = outline.px_bounds();
            let (gx, gy) = (b.min.x.floor() as i32 - x0, b.min.y.floor() as i32 - y0);
            outline.draw(|u, v, c| {
                let (px, py) = (gx + u as i32, gy + v as i32);
                if px >= 0 && py >= 0 && px < width && py < height {
                    let cell = &mut alpha[(py * width + px) as usize];
                    *cell = (*cell + c).min(1.0);
                }
            });
        }
        Coverage {
            left: x0,
            top: y0,
            width,
            height,
            alpha,
        }
    }

    /// An ENACT state label ("Current State", "Next State 3") for a frame of the given height.
    pub(crate) fn state_label(&self, text: &str, frame_height: u32) -> Overlay {
        let style = &ENACT_LABEL;
        let (x, y) = style.origin;
        let fill = self.coverage(text, x, y, style.em_px(frame_height));
        let pad = style.outline_px;
        let (left, top) = (fill.left - pad, fill.top - pad);
        let (width, height) = (fill.width + 2 * pad, fill.height + 2 * pad);
        let cells = (width * height) as usize;
        let clear: Vec<f32> = (0..cells)
            .map(|i| 1.0 - fill.at(left + i as i32 % width, top + i as i32 / width))
            .collect();
        // Each offset copy of the text is blended over the previous ones, as repeated PIL draws
        // are, so the outline lets through the product of (1 - coverage) over the 7×7 window
        // around a pixel, less the centre. The window product is separable: rows, then columns.
        let mut rows = vec![1.0f32; cells];
        for v in 0..height {
            for u in 0..width {
                let mut product = 1.0;
                for du in (u - pad).max(0)..=(u + pad).min(width - 1) {
                    product *= clear[(v * width + du) as usize];
                }
                rows[(v * width + u) as usize] = product;
            }
        }
        let mut keep = Vec::with_capacity(cells);
        let mut paint = Vec::with_capacity(cells);
        for v in 0..height {
            for u in 0..width {
                let i = (v * width + u) as usize;
                let mut window = 1.0;
                for dv in (v - pad).max(0)..=(v + pad).min(height - 1) {
                    window *= rows[(dv * width + u) as usize];
                }
                let text = 1.0 - clear[i];
                // Where the text itself is opaque the outline underneath never shows.
                let outline_keep = if clear[i] > 0.0 {
                    (window / clear[i]).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let outline = 1.0 - outline_keep;
                keep.push(outline_keep * (1.0 - text));
                paint.push(std::array::from_fn(|c| {
                    style.outline[c] as f32 * outline * (1.0 - text) + style.fill[c] as f32 * text
                }));
            }
        }
        Overlay::from_grid(left, top, width, &keep, &paint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    #[test]
    fn the_font_loads_and_labels_are_red_on_white_near_the_corner() {
        let font = LabelFont::load().unwrap();
        let overlay = font.state_label("Next State 9", 512);
        let mut image = RgbImage::from_pixel(512, 512, Rgb([0, 0, 0]));
        overlay.apply(&mut image);
        let mut red = 0;
        let mut white = 0;
        let (mut min_x, mut min_y, mut max_x, mut max_y) = (512, 512, 0, 0);
        for (x, y, p) in image.enumerate_pixels() {
            if p.0 == ENACT_LABEL.fill {
                red += 1;
            }
            if p.0 == ENACT_LABEL.outline {
                white += 1;
            }
            if p.0 != [0, 0, 0] {
                min_x = min_x.min(x);
                min_y = min_y.min(y);
                max_x = max_x.max(x);
                max_y = max_y.max(y);
            }
        }
        assert!(red > 2000, "{red} red pixels");
        assert!(white > 1000, "{white} white pixels");
        // Starts at (15, 15) less the outline, and a 51-pixel font is about 40 pixels tall in caps.
        assert!((10..=20).contains(&min_x), "{min_x}");
        assert!((12..=30).contains(&min_y), "{min_y}");
        assert!((45..=75).contains(&(max_y - min_y)), "{min_y}..{max_y}");
        assert!(max_x > 250 && max_x < 420, "{max_x}");
    }

    #[test]
    fn empty_text_draws_nothing() {
        let font = LabelFont::load().unwrap();
        let mut image = RgbImage::from_pixel(8, 8, Rgb([1, 2, 3]));
        font.state_label("", 8).apply(&mut image);
        assert!(image.pixels().all(|p| p.0 == [1, 2, 3]));
    }
}
