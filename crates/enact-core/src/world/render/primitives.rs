//! Painting on a square canvas that records, for every pixel, which object painted it last:
//! spans, convex polygons, ellipses, thick lines and outlined shapes, and the per-object pixel
//! counts and bounding boxes read back from that owner buffer.

use std::collections::BTreeMap;

use image::{Rgb, RgbImage};

use crate::world::things::ThingId;

/// Owner ids in the owner buffer: 0 nothing, 1 the robot, 2 + thing id.
pub(super) const ROBOT_OWNER: u16 = 1;

pub(super) fn owner_of(thing: ThingId) -> u16 {
    thing as u16 + 2
}

/// An image and, per pixel, the owner id of what was painted there.
pub(super) struct Canvas {
    pub(super) image: RgbImage,
    owners: Vec<u16>,
    pub(super) size: u32,
}

/// `c` darkened (factor below 1) or lightened.
pub(super) fn shade(c: [u8; 3], factor: f32) -> [u8; 3] {
    c.map(|v| (v as f32 * factor).clamp(0.0, 255.0) as u8)
}

impl Canvas {
    pub(super) fn new(size: u32, background: [u8; 3]) -> Canvas {
        Canvas {
            image: RgbImage::from_pixel(size, size, Rgb(background)),
            owners: vec![0; (size * size) as usize],
            size,
        }
    }

    /// Paints pixels `x0..=x1` of row `y` (already clipped to the canvas).
    fn span(&mut self, y: u32, x0: u32, x1: u32, colour: [u8; 3], owner: u16) {
        let row = (y * self.size) as usize;
        let pixels: &mut [u8] = &mut self.image;
        for x in x0 as usize..=x1 as usize {
            pixels[(row + x) * 3..(row + x) * 3 + 3].copy_from_slice(&colour);
        }
        self.owners[row + x0 as usize..=row + x1 as usize].fill(owner);
    }

    /// Paints the pixels of row `y` whose centres lie in `[left, right]`.
    fn fill_row(&mut self, y: u32, left: f32, right: f32, colour: [u8; 3], owner: u16) {
        let max = self.size as f32 - 1.0;
        let first = (left - 0.5).ceil().max(0.0);
        let last = (right - 0.5).floor().min(max);
        if first <= last {
            self.span(y, first as u32, last as u32, colour, owner);
        }
    }

    /// Pixel rows a shape spanning `y0..y1` may touch.
    fn rows(&self, y0: f32, y1: f32) -> Option<(u32, u32)> {
        if !(y0.is_finite() && y1.is_finite()) {
            return None;
        }
        let max = self.size as f32 - 1.0;
        let (a, b) = (y0.floor().max(0.0), y1.ceil().min(max));
        (a <= b).then_some((a as u32, b as u32))
    }

    /// Fills a convex polygon, row by row, sampling pixel centres.
    pub(super) fn polygon(&mut self, pts: &[(f32, f32)], colour: [u8; 3], owner: u16) {
        if pts.len() < 3 || pts.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
            return;
        }
        let y0 = pts.iter().map(|p| p.1).fold(f32::MAX, f32::min);
        let y1 = pts.iter().map(|p| p.1).fold(f32::MIN, f32::max);
        let Some((first, last)) = self.rows(y0, y1) else {
            return;
        };
        for y in first..=last {
            let py = y as f32 + 0.5;
            let (mut left, mut right) = (f32::MAX, f32::MIN);
            for i in 0..pts.len() {
                let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
                if !((p.1 <= py && py <= q.1) || (q.1 <= py && py <= p.1)) {
                    continue;
                }
                if (q.1 - p.1).abs() < 1e-6 {
                    left = left.min(p.0.min(q.0));
                    right = right.max(p.0.max(q.0));
                } else {
                    let x = p.0 + (py - p.1) / (q.1 - p.1) * (q.0 - p.0);
                    left = left.min(x);
                    right = right.max(x);
                }
            }
            if left <= right {
                self.fill_row(y, left, right, colour, owner);
            }
        }
    }

    pub(super) fn rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, colour: [u8; 3], owner: u16) {
        self.polygon(&[(x0, y0), (x1, y0), (x1, y1), (x0, y1)], colour, owner);
    }

    /// Fills an axis-aligned ellipse.
    pub(super) fn ellipse(
        &mut self,
        cx: f32,
        cy: f32,
        rx: f32,
        ry: f32,
        colour: [u8; 3],
        owner: u16,
    ) {
        if !(rx > 0.0 && ry > 0.0 && cx.is_finite()) {
            return;
        }
        let Some((first, last)) = self.rows(cy - ry, cy + ry) else {
            return;
        };
        for y in first..=last {
            let dy = (y as f32 + 0.5 - cy) / ry;
            if dy.abs() <= 1.0 {
                let half = rx * (1.0 - dy * dy).sqrt();
                self.fill_row(y, cx - half, cx + half, colour, owner);
            }
        }
    }

    /// The lower half of an ellipse (a bowl's body).
    pub(super) fn lower_half_ellipse(
        &mut self,
        cx: f32,
        cy: f32,
        rx: f32,
        ry: f32,
        c: [u8; 3],
        o: u16,
    ) {
        let pts: Vec<(f32, f32)> = (0..=16)
            .map(|i| {
                let t = std::f32::consts::PI * i as f32 / 16.0;
                (cx + rx * t.cos(), cy + ry * t.sin())
            })
            .collect();
        self.polygon(&pts, c, o);
    }

    /// A thick line as a quadrilateral.
    pub(super) fn line(
        &mut self,
        a: (f32, f32),
        b: (f32, f32),
        width: f32,
        colour: [u8; 3],
        owner: u16,
    ) {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = (dx * dx + dy * dy).sqrt().max(1e-3);
        let (nx, ny) = (-dy / len * width / 2.0, dx / len * width / 2.0);
        self.polygon(
            &[
                (a.0 + nx, a.1 + ny),
                (b.0 + nx, b.1 + ny),
                (b.0 - nx, b.1 - ny),
                (a.0 - nx, a.1 - ny),
            ],
            colour,
            owner,
        );
    }

    /// Fills `pts` with a darker rim 1.5 px wide, so small things stand out from what is behind.
    pub(super) fn outline(&mut self, pts: &[(f32, f32)], fill: [u8; 3], owner: u16) {
        let cx = pts.iter().map(|p| p.0).sum::<f32>() / pts.len() as f32;
        let cy = pts.iter().map(|p| p.1).sum::<f32>() / pts.len() as f32;
        let grown: Vec<(f32, f32)> = pts
            .iter()
            .map(|&(x, y)| {
                let (dx, dy) = (x - cx, y - cy);
                let n = (dx * dx + dy * dy).sqrt().max(1e-3);
                (x + dx / n * 1.5, y + dy / n * 1.5)
            })
            .collect();
        self.polygon(&grown, shade(fill, 0.45), owner);
        self.polygon(pts, fill, owner);
    }

    /// Per owner id: pixel count and bounding box `[count, x0, y0, x1, y1]`.
    pub(super) fn visibility(&self) -> BTreeMap<u16, [u32; 5]> {
        let mut seen: BTreeMap<u16, [u32; 5]> = BTreeMap::new();
        for (i, &owner) in self.owners.iter().enumerate() {
            if owner == 0 {
                continue;
            }
            let (x, y) = (i as u32 % self.size, i as u32 / self.size);
            let e = seen.entry(owner).or_insert([0, x, y, x, y]);
            e[0] += 1;
            e[1] = e[1].min(x);
            e[2] = e[2].min(y);
            e[3] = e[3].max(x);
            e[4] = e[4].max(y);
        }
        seen
    }
}
