//! Flat-colour shape filling for the demo frames. Shapes are drawn at twice the output size and
//! box-filtered down, which gives smooth edges without a drawing-library dependency.

use image::RgbImage;

/// An RGB colour.
pub(crate) type Colour = [u8; 3];

/// Supersampling factor per axis (`into_image` averages 2×2 blocks).
const SS: u32 = 2;

/// A square drawing surface addressed in output-pixel coordinates (floats, y down).
#[derive(Clone)]
pub(crate) struct Canvas {
    size: u32,
    /// The samples, `SS` per output pixel along each axis.
    samples: RgbImage,
}

/// Sets every pixel of a packed RGB run to `colour`. Copying ever larger blocks keeps this a few
/// `memmove`s even in unoptimised builds, where the frames would otherwise be slow to draw.
fn fill_run(run: &mut [u8], colour: Colour) {
    if run.len() < 3 {
        return;
    }
    run[..3].copy_from_slice(&colour);
    let mut done = 3;
    while done < run.len() {
        let n = done.min(run.len() - done);
        run.copy_within(0..n, done);
        done += n;
    }
}

impl Canvas {
    pub(crate) fn new(size: u32, background: Colour) -> Canvas {
        let side = size * SS;
        let mut samples = RgbImage::new(side, side);
        fill_run(&mut samples, background);
        Canvas { size, samples }
    }

    /// Paints `colour` at `opacity` (0..=1) over the samples of each sample row whose centres
    /// fall in the half-open x-intervals that `spans(y, out)` pushes for that row's centre `y`.
    /// Shapes compute their spans per row, so no per-sample inside test is needed.
    fn fill_rows(
        &mut self,
        y0: f32,
        y1: f32,
        colour: Colour,
        opacity: f32,
        spans: impl Fn(f32, &mut Vec<(f32, f32)>),
    ) {
        let side = (self.size * SS) as usize;
        let scale = SS as f32;
        // Index of the first sample whose centre is at or after `v` (clamped to the canvas).
        let first_at = |v: f32| (v * scale - 0.5).ceil().clamp(0.0, side as f32) as usize;
        let (row0, row1) = (first_at(y0), first_at(y1 + 1.0 / scale));
        let keep = 1.0 - opacity;
        let mut found = Vec::new();
        for sy in row0..row1 {
            found.clear();
            spans((sy as f32 + 0.5) / scale, &mut found);
            let buffer: &mut [u8] = &mut self.samples;
            let row = &mut buffer[sy * side * 3..(sy + 1) * side * 3];
            for (a, b) in &found {
                let (sx0, sx1) = (first_at(*a), first_at(*b));
                if sx0 >= sx1 {
                    continue;
                }
                let run = &mut row[sx0 * 3..sx1 * 3];
                if opacity >= 1.0 {
                    fill_run(run, colour);
                } else {
                    for (i, value) in run.iter_mut().enumerate() {
                        let paint = colour[i % 3] as f32 * opacity;
                        *value = (*value as f32 * keep + paint).round() as u8;
                    }
                }
            }
        }
    }

    pub(crate) fn rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, colour: Colour) {
        self.fill_rows(y0, y1, colour, 1.0, |y, out| {
            if y >= y0 && y < y1 {
                out.push((x0, x1));
            }
        });
    }

    pub(crate) fn round_rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, r: f32, c: Colour) {
        self.fill_rows(y0, y1, c, 1.0, |y, out| {
            if y < y0 || y >= y1 {
                return;
            }
            let dy = (y0 + r - y).max(y - (y1 - r)).max(0.0);
            if dy <= r {
                let inset = r - (r * r - dy * dy).sqrt();
                out.push((x0 + inset, x1 - inset));
            }
        });
    }

    pub(crate) fn ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, colour: Colour) {
        self.ellipse_alpha(cx, cy, rx, ry, colour, 1.0);
    }

    pub(crate) fn ellipse_alpha(
        &mut self,
        cx: f32,
        cy: f32,
        rx: f32,
        ry: f32,
        colour: Colour,
        opacity: f32,
    ) {
        self.fill_rows(cy - ry, cy + ry, colour, opacity, |y, out| {
            let v = (y - cy) / ry;
            if v.abs() <= 1.0 {
                let half = rx * (1.0 - v * v).sqrt();
                out.push((cx - half, cx + half));
            }
        });
    }

    pub(crate) fn circle(&mut self, cx: f32, cy: f32, r: f32, colour: Colour) {
        self.ellipse(cx, cy, r, r, colour);
    }

    /// The lower half of an ellipse (a bowl or a cut fruit seen from the side).
    pub(crate) fn lower_half_ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, c: Colour) {
        self.fill_rows(cy, cy + ry, c, 1.0, |y, out| {
            let v = (y - cy) / ry;
            if y >= cy && v <= 1.0 {
                let half = rx * (1.0 - v * v).sqrt();
                out.push((cx - half, cx + half));
            }
        });
    }

    /// A filled polygon (even-odd rule).
    pub(crate) fn polygon(&mut self, points: &[(f32, f32)], colour: Colour) {
        self.polygon_alpha(points, colour, 1.0);
    }

    pub(crate) fn polygon_alpha(&mut self, points: &[(f32, f32)], colour: Colour, opacity: f32) {
        if points.len() < 3 {
            return;
        }
        let y0 = points.iter().map(|p| p.1).fold(f32::MAX, f32::min);
        let y1 = points.iter().map(|p| p.1).fold(f32::MIN, f32::max);
        self.fill_rows(y0, y1, colour, opacity, |y, out| {
            let mut crossings: Vec<f32> = Vec::with_capacity(points.len());
            let mut j = points.len() - 1;
            for i in 0..points.len() {
                let (xi, yi) = points[i];
                let (xj, yj) = points[j];
                if (yi > y) != (yj > y) {
                    crossings.push(xi + (y - yi) * (xj - xi) / (yj - yi));
                }
                j = i;
            }
            crossings.sort_by(f32::total_cmp);
            for pair in crossings.chunks_exact(2) {
                out.push((pair[0], pair[1]));
            }
        });
    }

    /// A straight stroke of the given width with round ends.
    pub(crate) fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, colour: Colour) {
        let half = width / 2.0;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let length = (dx * dx + dy * dy).sqrt();
        if length > f32::EPSILON {
            let (nx, ny) = (-dy / length * half, dx / length * half);
            self.polygon(
                &[
                    (a.0 + nx, a.1 + ny),
                    (b.0 + nx, b.1 + ny),
                    (b.0 - nx, b.1 - ny),
                    (a.0 - nx, a.1 - ny),
                ],
                colour,
            );
        }
        self.circle(a.0, a.1, half, colour);
        self.circle(b.0, b.1, half, colour);
    }

    /// The finished frame at output size: each output pixel is the mean of its 2×2 samples.
    pub(crate) fn into_image(self) -> RgbImage {
        let size = self.size as usize;
        let stride = size * SS as usize * 3;
        let samples: &[u8] = &self.samples;
        let mut raw = Vec::with_capacity(size * size * 3);
        for pair in samples.chunks_exact(2 * stride) {
            let (upper, lower) = pair.split_at(stride);
            for x in 0..size {
                for c in 0..3 {
                    let i = x * 6 + c;
                    let sum = upper[i] as u16
                        + upper[i + 3] as u16
                        + lower[i] as u16
                        + lower[i + 3] as u16;
                    raw.push(((sum + 2) / 4) as u8);
                }
            }
        }
        // `raw` holds exactly size × size RGB pixels, so the fallback is never taken.
        RgbImage::from_raw(self.size, self.size, raw)
            .unwrap_or_else(|| RgbImage::new(self.size, self.size))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rectangle_covers_exactly_its_pixels() {
        let mut canvas = Canvas::new(8, [0, 0, 0]);
        canvas.rect(2.0, 2.0, 4.0, 5.0, [255, 0, 0]);
        let image = canvas.into_image();
        assert_eq!(image.get_pixel(2, 2).0, [255, 0, 0]);
        assert_eq!(image.get_pixel(3, 4).0, [255, 0, 0]);
        assert_eq!(image.get_pixel(4, 4).0, [0, 0, 0]);
        assert_eq!(image.get_pixel(1, 2).0, [0, 0, 0]);
    }

    #[test]
    fn shapes_fill_their_centres_and_blend_at_their_edges() {
        let mut canvas = Canvas::new(32, [0, 0, 0]);
        canvas.circle(16.0, 16.0, 6.0, [0, 0, 200]);
        canvas.polygon(&[(0.0, 0.0), (8.0, 0.0), (0.0, 8.0)], [200, 0, 0]);
        canvas.line((20.0, 28.0), (30.0, 28.0), 2.0, [0, 200, 0]);
        canvas.ellipse_alpha(16.0, 16.0, 2.0, 2.0, [200, 200, 200], 0.5);
        let image = canvas.into_image();
        assert_eq!(image.get_pixel(16, 12).0, [0, 0, 200]);
        assert_eq!(image.get_pixel(16, 16).0, [100, 100, 200]);
        assert_eq!(image.get_pixel(1, 1).0, [200, 0, 0]);
        assert_eq!(image.get_pixel(25, 27).0[1], 200);
        assert_eq!(image.get_pixel(25, 20).0, [0, 0, 0]);
        // Three of the four samples of this pixel are inside the circle.
        assert_eq!(image.get_pixel(19, 20).0, [0, 0, 150]);
    }
}
