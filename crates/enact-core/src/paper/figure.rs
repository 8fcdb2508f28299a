//! The paper's accuracy-by-step-length figure (its teaser's style) for a [`PaperTable`]: two
//! panels, forward and inverse world modeling, accuracy (%) against L = 3..10, one line per
//! row with the Human row in black on top, and a legend under the panels. Pure geometry, sized
//! to be read at 1280 px wide; `templates/paper/accuracy_by_step_length.svg` draws it as SVG and
//! [`StepChart::png`] paints the same geometry into a PNG.

use askama::Template;
use serde::Serialize;

use super::canvas::{Canvas, rgb};
use super::write::grouped;
use super::{Category, CellKey, PaperTable};
use crate::dataset::{Direction, StepLength};

/// The whole figure is this wide (user units = PNG pixels).
pub const WIDTH: f64 = 1280.0;
const PANEL_HEIGHT: f64 = 460.0;
const MARGIN_LEFT: f64 = 72.0;
const MARGIN_RIGHT: f64 = 24.0;
const MARGIN_TOP: f64 = 64.0;
const MARGIN_BOTTOM: f64 = 64.0;
/// Text sizes (px) that stay legible when the figure is shown 1280 px wide.
pub const FONT_SIZE: f64 = 16.0;
pub const TITLE_SIZE: f64 = 20.0;
const LEGEND_COLUMNS: usize = 4;
const LEGEND_ROW: f64 = 26.0;
/// Between the x axes' names and the legend's first baseline.
const LEGEND_GAP: f64 = 28.0;

/// Line colours (the Okabe–Ito palette without black, which is the humans', and three more
/// distinct ones), cycled; each pass through them uses the next dash pattern.
const PALETTE: [&str; 10] = [
    "#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#882255", "#44aa99",
    "#999933", "#999999",
];
/// SVG `stroke-dasharray`s (empty: solid).
const DASHES: [&str; 4] = ["", "8 4", "2 4", "10 4 2 4"];
const HUMAN_COLOUR: &str = "#000000";
const GRID: &str = "#e0e0e0";
const AXIS: &str = "#000000";

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tick {
    pub position: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    /// Hover text: model, L and value.
    pub label: String,
}

/// How a row's line looks, in the plot and in the legend.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineStyle {
    pub colour: &'static str,
    /// SVG `stroke-dasharray`; empty for a solid line.
    pub dash: &'static str,
    pub width: f64,
}

/// One row's line in one panel: runs of consecutive step lengths with a value.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Series {
    pub model: String,
    pub style: LineStyle,
    pub runs: Vec<Vec<Point>>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Panel {
    pub title: &'static str,
    pub plot_left: f64,
    pub plot_right: f64,
    pub plot_top: f64,
    pub plot_bottom: f64,
    pub x_ticks: Vec<Tick>,
    pub y_ticks: Vec<Tick>,
    pub series: Vec<Series>,
}

/// A piece of text; `y` is its baseline, `anchor` SVG's `text-anchor`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Label {
    pub x: f64,
    pub y: f64,
    pub text: String,
    pub anchor: &'static str,
    pub size: f64,
    pub bold: bool,
}

/// A straight line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rule {
    pub x1: f64,
    pub y1: f64,
    pub x2: f64,
    pub y2: f64,
    pub style: LineStyle,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LegendEntry {
    pub x: f64,
    pub y: f64,
    pub model: String,
    pub style: LineStyle,
}

/// The figure's geometry, in user units (= PNG pixels).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepChart {
    pub width: f64,
    pub height: f64,
    /// "Task Accuracy (%)" or "Pairwise Accuracy (%)", over each panel's y axis.
    pub y_label: String,
    /// What the figure shows, for screen readers.
    pub description: String,
    pub panels: Vec<Panel>,
    pub legend: Vec<LegendEntry>,
}

fn round1(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

fn style(index: usize, human: bool) -> LineStyle {
    if human {
        LineStyle {
            colour: HUMAN_COLOUR,
            dash: "",
            width: 4.0,
        }
    } else {
        LineStyle {
            colour: PALETTE[index % PALETTE.len()],
            dash: DASHES[(index / PALETTE.len()) % DASHES.len()],
            width: 2.5,
        }
    }
}

impl StepChart {
    /// Accuracy by step length for every row of `table`, grouped as the table prints them
    /// (the Human row last, so drawn on top).
    pub fn accuracy_by_step_length(table: &PaperTable) -> StepChart {
        let rows: Vec<(&Category, &super::PaperRow)> = grouped(table)
            .into_iter()
            .flat_map(|(c, rows)| rows.into_iter().map(move |r| (c, r)))
            .collect();
        let styles: Vec<LineStyle> = {
            let mut others = 0;
            rows.iter()
                .map(|(c, _)| {
                    let human = **c == Category::Human;
                    let s = style(others, human);
                    others += usize::from(!human);
                    s
                })
                .collect()
        };
        let panel_width = WIDTH / 2.0;
        let lengths: Vec<StepLength> = StepLength::all().collect();
        let span = (lengths.len() - 1) as f64;
        let panel = |index: usize, direction: Direction| {
            let plot_left = panel_width * index as f64 + MARGIN_LEFT;
            let plot_right = panel_width * (index + 1) as f64 - MARGIN_RIGHT;
            let plot_top = MARGIN_TOP;
            let plot_bottom = PANEL_HEIGHT - MARGIN_BOTTOM;
            let x_of = |i: usize| round1(plot_left + (plot_right - plot_left) * i as f64 / span);
            let y_of = |v: f64| {
                round1(plot_bottom - (plot_bottom - plot_top) * v.clamp(0.0, 100.0) / 100.0)
            };
            let series = rows
                .iter()
                .zip(&styles)
                .map(|((_, row), style)| {
                    let mut runs: Vec<Vec<Point>> = Vec::new();
                    let mut run: Vec<Point> = Vec::new();
                    for (i, step_length) in lengths.iter().enumerate() {
                        let key = CellKey {
                            direction,
                            step_length: *step_length,
                        };
                        match row.value(key) {
                            Some(v) => run.push(Point {
                                x: x_of(i),
                                y: y_of(v),
                                label: format!("{}: L={step_length}, {v:.2}%", row.model),
                            }),
                            None if !run.is_empty() => runs.push(std::mem::take(&mut run)),
                            None => {}
                        }
                    }
                    if !run.is_empty() {
                        runs.push(run);
                    }
                    Series {
                        model: row.model.clone(),
                        style: style.clone(),
                        runs,
                    }
                })
                .collect();
            Panel {
                title: match direction {
                    Direction::Forward => "Forward World Modeling",
                    Direction::Inverse => "Inverse World Modeling",
                },
                plot_left,
                plot_right,
                plot_top,
                plot_bottom,
                x_ticks: lengths
                    .iter()
                    .enumerate()
                    .map(|(i, l)| Tick {
                        position: x_of(i),
                        label: l.to_string(),
                    })
                    .collect(),
                y_ticks: (0..=5)
                    .map(|k| Tick {
                        position: y_of(f64::from(k) * 20.0),
                        label: (k * 20).to_string(),
                    })
                    .collect(),
                series,
            }
        };
        let column_width = (WIDTH - MARGIN_LEFT) / LEGEND_COLUMNS as f64;
        let legend: Vec<LegendEntry> = rows
            .iter()
            .zip(&styles)
            .enumerate()
            .map(|(i, ((_, row), style))| LegendEntry {
                x: round1(MARGIN_LEFT + column_width * (i % LEGEND_COLUMNS) as f64),
                y: PANEL_HEIGHT + LEGEND_GAP + LEGEND_ROW * (i / LEGEND_COLUMNS) as f64,
                model: row.model.clone(),
                style: style.clone(),
            })
            .collect();
        let legend_rows = rows.len().div_ceil(LEGEND_COLUMNS);
        StepChart {
            width: WIDTH,
            height: PANEL_HEIGHT + LEGEND_GAP + LEGEND_ROW * legend_rows as f64,
            y_label: format!("{} (%)", table.metric.title()),
            description: format!(
                "{} (%) against step length L, forward and inverse world modeling, one line \
                 per row ({} rows)",
                table.metric.title(),
                rows.len()
            ),
            panels: vec![panel(0, Direction::Forward), panel(1, Direction::Inverse)],
            legend,
        }
    }

    /// Every piece of text: panel titles, axis names, tick labels and the legend's names.
    pub fn labels(&self) -> Vec<Label> {
        let mut labels = Vec::new();
        let text = |x: f64, y: f64, text: &str, anchor: &'static str| Label {
            x,
            y,
            text: text.to_owned(),
            anchor,
            size: FONT_SIZE,
            bold: false,
        };
        for p in &self.panels {
            let middle = round1((p.plot_left + p.plot_right) / 2.0);
            labels.push(Label {
                size: TITLE_SIZE,
                bold: true,
                ..text(middle, 26.0, p.title, "middle")
            });
            labels.push(text(p.plot_left, p.plot_top - 14.0, &self.y_label, "start"));
            labels.push(text(
                middle,
                p.plot_bottom + 48.0,
                "Step length L",
                "middle",
            ));
            for t in &p.y_ticks {
                labels.push(text(p.plot_left - 8.0, t.position + 5.0, &t.label, "end"));
            }
            for t in &p.x_ticks {
                labels.push(text(t.position, p.plot_bottom + 22.0, &t.label, "middle"));
            }
        }
        for l in &self.legend {
            labels.push(text(l.x + 44.0, l.y, &l.model, "start"));
        }
        labels
    }

    /// Every straight line that is not a row's: grid lines, axes and the legend's samples.
    pub fn rules(&self) -> Vec<Rule> {
        let mut rules = Vec::new();
        let plain = |x1: f64, y1: f64, x2: f64, y2: f64, colour: &'static str| Rule {
            x1,
            y1,
            x2,
            y2,
            style: LineStyle {
                colour,
                dash: "",
                width: 1.0,
            },
        };
        for p in &self.panels {
            for t in &p.y_ticks {
                rules.push(plain(
                    p.plot_left,
                    t.position,
                    p.plot_right,
                    t.position,
                    GRID,
                ));
            }
            rules.push(plain(
                p.plot_left,
                p.plot_bottom,
                p.plot_right,
                p.plot_bottom,
                AXIS,
            ));
            rules.push(plain(
                p.plot_left,
                p.plot_top,
                p.plot_left,
                p.plot_bottom,
                AXIS,
            ));
        }
        for l in &self.legend {
            rules.push(Rule {
                style: l.style.clone(),
                ..plain(l.x, l.y - 5.0, l.x + 36.0, l.y - 5.0, AXIS)
            });
        }
        rules
    }

    /// The figure as a PNG, `width` × `height` pixels, painted from the same geometry as
    /// [`StepChart::svg`] (text in the core's bundled DejaVu Sans Bold).
    pub fn png(&self) -> Result<Vec<u8>, FigureError> {
        self.canvas()?
            .png()
            .map_err(|e| FigureError::Png(e.to_string()))
    }

    fn canvas(&self) -> Result<Canvas, FigureError> {
        // Whole pixels: the geometry is laid out in them.
        let (width, height) = (self.width.ceil() as u32, self.height.ceil() as u32);
        let mut canvas =
            Canvas::new(width, height).map_err(|e| FigureError::Font(e.to_string()))?;
        for r in self.rules() {
            canvas.polyline(
                &[(r.x1, r.y1), (r.x2, r.y2)],
                rgb(r.style.colour),
                r.style.width,
                r.style.dash,
            );
        }
        for l in self.labels() {
            canvas.text(&l.text, (l.x, l.y), l.anchor, l.size, [0, 0, 0]);
        }
        for p in &self.panels {
            for s in &p.series {
                let colour = rgb(s.style.colour);
                for run in &s.runs {
                    let points: Vec<(f64, f64)> = run.iter().map(|m| (m.x, m.y)).collect();
                    canvas.polyline(&points, colour, s.style.width, s.style.dash);
                    for point in points {
                        canvas.disc(point, s.style.width + 1.0, colour);
                    }
                }
            }
        }
        Ok(canvas)
    }

    /// The figure as a standalone SVG file, `stamp` in its `<metadata>`.
    pub fn svg(&self, stamp: &str) -> Result<String, askama::Error> {
        StepChartSvg { chart: self, stamp }.render()
    }
}

/// Why a figure could not be painted: the bundled font or PNG encoding failed (a build
/// defect, not the data's fault).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FigureError {
    #[error("the bundled font does not load: {0}")]
    Font(String),
    #[error("the PNG could not be encoded: {0}")]
    Png(String),
}

#[derive(Template)]
#[template(path = "paper/accuracy_by_step_length.svg")]
struct StepChartSvg<'a> {
    chart: &'a StepChart,
    stamp: &'a str,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{Metric, enact_paper_results, table_of};

    fn papers_chart() -> StepChart {
        StepChart::accuracy_by_step_length(&table_of(Metric::TaskAccuracy, &enact_paper_results()))
    }

    #[test]
    fn points_sit_at_their_step_length_and_value() {
        let chart = papers_chart();
        assert_eq!(chart.width, 1280.0);
        assert_eq!(chart.panels.len(), 2);
        let forward = &chart.panels[0];
        let gpt5 = &forward.series[0];
        assert_eq!(gpt5.model, "GPT-5");
        assert_eq!(gpt5.runs.len(), 1);
        let points = &gpt5.runs[0];
        assert_eq!(points.len(), 8);
        // L=3 at the left edge, L=10 at the right; 80.59% of the way up.
        assert_eq!(points[0].x, forward.plot_left);
        assert_eq!(points[7].x, forward.plot_right);
        let height = forward.plot_bottom - forward.plot_top;
        assert!((points[0].y - (forward.plot_bottom - height * 0.8059)).abs() <= 0.05);
        assert_eq!(points[0].label, "GPT-5: L=3, 80.59%");
        // The inverse panel is the right half.
        assert!(chart.panels[1].plot_left > 640.0);
        assert_eq!(
            chart.panels[1].series[0].runs[0][0].label,
            "GPT-5: L=3, 86.19%"
        );
    }

    #[test]
    fn the_humans_are_drawn_last_in_black_and_every_other_line_differs() {
        let chart = papers_chart();
        let series = &chart.panels[0].series;
        assert_eq!(series.len(), 31);
        let human = series.last().unwrap();
        assert_eq!(human.model, "Human Performance");
        assert_eq!(human.style.colour, HUMAN_COLOUR);
        let mut styles: Vec<(&str, &str)> = series
            .iter()
            .map(|s| (s.style.colour, s.style.dash))
            .collect();
        styles.sort_unstable();
        styles.dedup();
        assert_eq!(styles.len(), 31, "two rows share a line style");
        assert_eq!(chart.legend.len(), 31);
        assert!(chart.legend.iter().all(|e| e.y < chart.height));
    }

    #[test]
    fn a_missing_value_breaks_the_line() {
        let mut table = table_of(Metric::TaskAccuracy, &enact_paper_results()[..1]);
        let key = CellKey::parse("forward_5").unwrap();
        table.rows[0].cells.remove(&key);
        let chart = StepChart::accuracy_by_step_length(&table);
        let runs: Vec<usize> = chart.panels[0].series[0]
            .runs
            .iter()
            .map(Vec::len)
            .collect();
        assert_eq!(runs, [2, 5]);
        assert_eq!(chart.panels[1].series[0].runs[0].len(), 8);
    }

    #[test]
    fn the_svg_draws_every_line_and_escapes_names() {
        let mut table = table_of(Metric::PairwiseAccuracy, &enact_paper_results());
        table.rows[0].model = "<A & B>".to_owned();
        let chart = StepChart::accuracy_by_step_length(&table);
        let svg = chart.svg("hub 1.0").unwrap();
        assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(svg.contains("width=\"1280\""));
        assert!(svg.contains("<metadata>hub 1.0</metadata>"));
        assert_eq!(svg.matches("<polyline").count(), 2 * 31);
        assert!(svg.contains("Pairwise Accuracy (%)"));
        assert!(svg.contains("<title>&#60;A &#38; B&#62;</title>"));
        assert!(!svg.contains("<A & B>"));
        assert!(svg.contains("stroke-dasharray=\"8 4\""));
    }

    #[test]
    fn the_png_paints_the_same_geometry_at_1280_pixels() {
        let chart = papers_chart();
        let png = chart.png().unwrap();
        let image = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
            .unwrap()
            .to_rgb8();
        assert_eq!(image.width(), 1280);
        assert_eq!(f64::from(image.height()), chart.height.ceil());
        // The Human row's first point (black), a row's line colour, and white background.
        let human = &chart.panels[0].series[30].runs[0][0];
        assert_eq!(image.get_pixel(human.x as u32, human.y as u32).0, [0, 0, 0]);
        // The last row before the humans is drawn over every other.
        let bagel = &chart.panels[1].series[29];
        assert_eq!(bagel.model, "BAGEL");
        let point = &bagel.runs[0][0];
        assert_eq!(
            image.get_pixel(point.x as u32, point.y as u32).0,
            rgb(bagel.style.colour)
        );
        assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255]);
        // Text is painted: the panel title's middle is inked.
        let title = &chart.labels()[0];
        let inked = (0..40)
            .flat_map(|y| (title.x as u32 - 100..title.x as u32 + 100).map(move |x| (x, y)))
            .filter(|(x, y)| image.get_pixel(*x, *y).0 != [255, 255, 255])
            .count();
        assert!(inked > 200, "{inked}");
    }
}
