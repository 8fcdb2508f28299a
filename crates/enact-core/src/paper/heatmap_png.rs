//! A [`Heatmap`] (the study heat map and the agreement report's) painted into a PNG with the
//! paper's [`Canvas`], from the same geometry `templates/heatmap.svg` draws, scaled up so its
//! 11 px text stays legible when the picture is shown 1280 px wide.

use super::canvas::{Canvas, rgb};
use super::figure::FigureError;
use crate::heatmap::Heatmap;

/// The scale a heat map is painted at: twice its SVG size, or more to reach 1280 px wide.
pub fn heatmap_scale(heatmap: &Heatmap) -> f64 {
    (1280.0 / heatmap.width).clamp(2.0, 4.0)
}

/// `heatmap` as a PNG at [`heatmap_scale`]: a white background, the cells in their fill
/// with their lines of text, headings, row labels, the legend and the note.
pub fn heatmap_png(heatmap: &Heatmap) -> Result<Vec<u8>, FigureError> {
    let k = heatmap_scale(heatmap);
    let (width, height) = (
        (heatmap.width * k).ceil() as u32,
        (heatmap.height * k).ceil() as u32,
    );
    let mut canvas = Canvas::new(width, height).map_err(|e| FigureError::Font(e.to_string()))?;
    let black = [0, 0, 0];
    let text = |canvas: &mut Canvas, t: &str, x: f64, y: f64, anchor: &str, size: f64| {
        canvas.text(t, (x * k, y * k), anchor, size * k, black);
    };
    if let Some(title) = &heatmap.title {
        text(&mut canvas, title, 12.0, 18.0, "start", 12.0);
    }
    for p in &heatmap.panels {
        text(
            &mut canvas,
            &p.title.label,
            p.title.x,
            heatmap.panel_title_y,
            "middle",
            12.0,
        );
        for c in &p.columns {
            text(
                &mut canvas,
                &c.label,
                c.x,
                heatmap.column_label_y,
                "middle",
                11.0,
            );
        }
        for c in &p.cells {
            canvas.rect(
                (c.x * k, c.y * k),
                (c.width * k, heatmap.cell_height * k),
                rgb(c.fill),
            );
            // The SVG's white stroke between cells.
            let (x0, y0, x1, y1) = (
                c.x * k,
                c.y * k,
                (c.x + c.width) * k,
                (c.y + heatmap.cell_height) * k,
            );
            canvas.polyline(
                &[(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
                [255, 255, 255],
                k,
                "",
            );
            for l in &c.lines {
                canvas.text(
                    &l.text,
                    ((c.x + c.width / 2.0) * k, (c.y + l.dy) * k),
                    "middle",
                    11.0 * k,
                    rgb(c.text_fill),
                );
            }
        }
    }
    for r in &heatmap.rows {
        text(&mut canvas, &r.label, heatmap.label_right, r.y, "end", 11.0);
    }
    for l in &heatmap.legend {
        canvas.rect(
            (l.x * k, heatmap.legend_y * k),
            (14.0 * k, 14.0 * k),
            rgb(l.fill),
        );
        text(
            &mut canvas,
            l.label,
            l.x + 20.0,
            heatmap.legend_y + 11.0,
            "start",
            11.0,
        );
    }
    if let Some(note) = &heatmap.note {
        text(
            &mut canvas,
            note,
            heatmap.label_right,
            heatmap.legend_y + 11.0,
            "end",
            11.0,
        );
    }
    canvas.png().map_err(|e| FigureError::Png(e.to_string()))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::dataset::Direction;
    use crate::study::figure::study_heatmap;

    /// A study with one variant, reported for one row (also the paper folder's test study).
    pub(crate) fn camera_study() -> crate::study::report::StudyReport {
        use crate::study::report::build_study_report;
        use crate::study::report::fixtures::{inputs, row};
        let (f, i) = (Direction::Forward, Direction::Inverse);
        let baseline = row(1, &[("a", f, 3, 1.0), ("b", f, 3, 0.5), ("c", i, 4, 0.0)]);
        let variant = row(2, &[("a", f, 3, 0.5), ("b", f, 3, 0.5), ("c", i, 4, 1.0)]);
        build_study_report(&inputs(baseline, Ok(variant))).unwrap()
    }

    #[test]
    fn the_png_paints_the_svgs_cells_at_twice_the_size_or_more() {
        let heatmap = study_heatmap(&camera_study());
        let k = heatmap_scale(&heatmap);
        assert!(k >= 2.0);
        let png = heatmap_png(&heatmap).unwrap();
        let image = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
            .unwrap()
            .to_rgb8();
        assert_eq!(f64::from(image.width()), (heatmap.width * k).ceil());
        assert_eq!(f64::from(image.height()), (heatmap.height * k).ceil());
        // A cell's corner, inside its white border: its fill.
        let cell = &heatmap.panels[0].cells[0];
        let (x, y) = ((cell.x + 2.0) * k, (cell.y + 2.0) * k);
        assert_eq!(image.get_pixel(x as u32, y as u32).0, rgb(cell.fill));
        // Text is painted in the cell.
        let inked = (0..(heatmap.cell_height * k) as u32)
            .flat_map(|dy| {
                let y = (cell.y * k) as u32 + dy;
                (0..(cell.width * k) as u32).map(move |dx| ((cell.x * k) as u32 + dx, y))
            })
            .filter(|(x, y)| image.get_pixel(*x, *y).0 != rgb(cell.fill))
            .count();
        assert!(inked > 50, "{inked}");
    }
}
