//! The paper's error-analysis figure (its "Error Distribution" figure, there of GPT-5 alone)
//! for the hub's rows of a paper: two panels, forward and inverse world modeling, one 100 %
//! stacked bar per row splitting that row's structural errors into the five classes (polarity
//! inversion, predicate substitution, entity substitution, omission, hallucination), each
//! share printed on its segment when it fits, and a legend under the panels. Pure geometry,
//! sized to be read at 1280 px wide; `templates/paper/error_analysis.svg` draws it as SVG and
//! [`ErrorChart::png`] paints the same geometry into a PNG.

use askama::Template;
use serde::Serialize;

use super::canvas::{Canvas, rgb};
use super::figure::{FONT_SIZE, FigureError, Label, TITLE_SIZE, WIDTH};
use crate::dataset::Direction;
use crate::error_analysis::{ErrorAnalysis, ErrorFigures, StructuralClass};

/// Row names are drawn right-aligned in this column.
const LABEL_COLUMN: f64 = 250.0;
const PANEL_GAP: f64 = 40.0;
const MARGIN_RIGHT: f64 = 24.0;
/// The first bar's top.
const PLOT_TOP: f64 = 52.0;
const BAR_HEIGHT: f64 = 30.0;
const ROW_STEP: f64 = 42.0;
/// Under the last bar: tick labels, the axis name, then the legend.
const AXIS_SPACE: f64 = 64.0;
const LEGEND_ROW: f64 = 30.0;
/// A share is printed on its segment when the segment is at least this wide.
const MIN_PRINTED_WIDTH: f64 = 52.0;
/// A row name longer than this many characters is cut (the full name is in its tooltip): 22
/// characters of 16 px DejaVu Sans Bold fit the label column.
const MAX_NAME: usize = 22;

/// The classes' colours, in [`StructuralClass::ALL`] order (Okabe–Ito), and whether a share
/// printed on them is white (on the dark ones) or black.
const COLOURS: [(&str, bool); 5] = [
    ("#0072b2", true),
    ("#e69f00", false),
    ("#009e73", true),
    ("#cc79a7", false),
    ("#d55e00", true),
];
const AXIS: &str = "#000000";
const GRID: &str = "#e0e0e0";

/// One row of the figure: a hub row's name and its analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalysedRow {
    pub model: String,
    pub analysis: ErrorAnalysis,
}

/// One class's part of a bar.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Segment {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub height: f64,
    pub colour: &'static str,
    /// The share in percent, one decimal, when it is printed on the segment.
    pub printed: Option<String>,
    /// Black or white, whichever reads on `colour`.
    pub ink: &'static str,
    /// Hover text: model, class, count and share.
    pub title: String,
}

/// A row's bar in one panel; no segments (and a note) when the row made no errors there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorBar {
    pub model: String,
    pub y: f64,
    pub segments: Vec<Segment>,
    pub errors: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorPanel {
    pub title: &'static str,
    pub plot_left: f64,
    pub plot_right: f64,
    pub bars: Vec<ErrorBar>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Swatch {
    pub x: f64,
    pub y: f64,
    pub colour: &'static str,
    pub name: &'static str,
}

/// The figure's geometry, in user units (= PNG pixels).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorChart {
    pub width: f64,
    pub height: f64,
    /// Where the bars end (the axis).
    pub plot_bottom: f64,
    pub description: String,
    pub panels: Vec<ErrorPanel>,
    pub legend: Vec<Swatch>,
}

fn round1(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

/// `name`, cut to [`MAX_NAME`] characters with an ellipsis.
fn short(name: &str) -> String {
    if name.chars().count() <= MAX_NAME {
        name.to_owned()
    } else {
        let mut cut: String = name.chars().take(MAX_NAME - 1).collect();
        cut.push('…');
        cut
    }
}

fn bar(model: &str, figures: &ErrorFigures, y: f64, left: f64, right: f64) -> ErrorBar {
    let mut segments = Vec::new();
    let mut x = left;
    let mut shares = 0.0;
    for (class, (colour, dark)) in StructuralClass::ALL.iter().zip(COLOURS) {
        let n = figures.structural.get(*class);
        if figures.errors == 0 || n == 0 {
            continue;
        }
        let share = n as f64 / figures.errors as f64;
        shares += share;
        // Each edge is placed from the running total, so the bar ends exactly at `right`.
        let end = round1(left + (right - left) * shares);
        let width = round1(end - x);
        segments.push(Segment {
            x,
            y,
            width,
            height: BAR_HEIGHT,
            colour,
            printed: (width >= MIN_PRINTED_WIDTH).then(|| format!("{:.1}", share * 100.0)),
            ink: if dark { "#ffffff" } else { "#000000" },
            title: format!(
                "{model}: {} {n} of {} ({:.1}%)",
                class.label(),
                figures.errors,
                share * 100.0
            ),
        });
        x = end;
    }
    ErrorBar {
        model: model.to_owned(),
        y,
        segments,
        errors: figures.errors,
    }
}

impl ErrorChart {
    /// The structural errors of each of `rows`, in their order, per direction.
    pub fn of(rows: &[AnalysedRow]) -> ErrorChart {
        let panel_width = (WIDTH - LABEL_COLUMN - PANEL_GAP - MARGIN_RIGHT) / 2.0;
        let panel = |index: usize, direction: Direction| {
            let plot_left = LABEL_COLUMN + (panel_width + PANEL_GAP) * index as f64;
            let plot_right = plot_left + panel_width;
            ErrorPanel {
                title: match direction {
                    Direction::Forward => "Forward World Modeling",
                    Direction::Inverse => "Inverse World Modeling",
                },
                plot_left,
                plot_right,
                bars: rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        bar(
                            &r.model,
                            r.analysis.direction(direction),
                            PLOT_TOP + ROW_STEP * i as f64,
                            plot_left,
                            plot_right,
                        )
                    })
                    .collect(),
            }
        };
        let plot_bottom = PLOT_TOP + ROW_STEP * rows.len() as f64 - (ROW_STEP - BAR_HEIGHT);
        let legend_top = plot_bottom + AXIS_SPACE + 24.0;
        let column = (WIDTH - LABEL_COLUMN) / 3.0;
        let legend = StructuralClass::ALL
            .iter()
            .zip(COLOURS)
            .enumerate()
            .map(|(k, (class, (colour, _)))| Swatch {
                x: round1(LABEL_COLUMN + column * (k % 3) as f64),
                y: legend_top + LEGEND_ROW * (k / 3) as f64,
                colour,
                name: class.label(),
            })
            .collect();
        ErrorChart {
            width: WIDTH,
            height: legend_top + LEGEND_ROW * 2.0,
            plot_bottom,
            description: format!(
                "Shares of structural error classes per row, forward and inverse world \
                 modeling ({} rows)",
                rows.len()
            ),
            panels: vec![panel(0, Direction::Forward), panel(1, Direction::Inverse)],
            legend,
        }
    }

    /// Every piece of text but the shares on the segments: titles, row names, ticks, the
    /// axis name, the legend and "no errors" where a row made none.
    pub fn labels(&self) -> Vec<Label> {
        let text = |x: f64, y: f64, text: String, anchor: &'static str| Label {
            x,
            y,
            text,
            anchor,
            size: FONT_SIZE,
            bold: false,
        };
        let mut labels = Vec::new();
        for (index, p) in self.panels.iter().enumerate() {
            let middle = round1((p.plot_left + p.plot_right) / 2.0);
            labels.push(Label {
                size: TITLE_SIZE,
                bold: true,
                ..text(middle, 28.0, p.title.to_owned(), "middle")
            });
            for (k, x) in self.grid(p).into_iter().enumerate() {
                labels.push(text(
                    x,
                    self.plot_bottom + 24.0,
                    (k * 25).to_string(),
                    "middle",
                ));
            }
            labels.push(text(
                middle,
                self.plot_bottom + 50.0,
                "Share of errors (%)".to_owned(),
                "middle",
            ));
            for b in &p.bars {
                let baseline = b.y + BAR_HEIGHT / 2.0 + 6.0;
                if index == 0 {
                    labels.push(text(LABEL_COLUMN - 12.0, baseline, short(&b.model), "end"));
                }
                if b.segments.is_empty() {
                    labels.push(text(
                        p.plot_left + 8.0,
                        baseline,
                        "no errors".to_owned(),
                        "start",
                    ));
                }
            }
        }
        for s in &self.legend {
            labels.push(text(s.x + 30.0, s.y, s.name.to_owned(), "start"));
        }
        labels
    }

    /// The figure as a PNG, `width` × `height` pixels, painted from the same geometry as
    /// [`ErrorChart::svg`].
    pub fn png(&self) -> Result<Vec<u8>, FigureError> {
        let (width, height) = (self.width.ceil() as u32, self.height.ceil() as u32);
        let mut canvas =
            Canvas::new(width, height).map_err(|e| FigureError::Font(e.to_string()))?;
        for p in &self.panels {
            for x in self.grid(p) {
                canvas.polyline(
                    &[(x, self.grid_top()), (x, self.plot_bottom + 6.0)],
                    rgb(GRID),
                    1.0,
                    "",
                );
            }
            canvas.polyline(
                &[
                    (p.plot_left, self.plot_bottom + 6.0),
                    (p.plot_right, self.plot_bottom + 6.0),
                ],
                rgb(AXIS),
                1.0,
                "",
            );
            for b in &p.bars {
                for s in &b.segments {
                    canvas.rect((s.x, s.y), (s.width, s.height), rgb(s.colour));
                    if let Some(printed) = &s.printed {
                        canvas.text(
                            printed,
                            (s.x + s.width / 2.0, s.y + s.height / 2.0 + 6.0),
                            "middle",
                            FONT_SIZE,
                            rgb(s.ink),
                        );
                    }
                }
            }
        }
        for s in &self.legend {
            canvas.rect((s.x, s.y - 16.0), (20.0, 20.0), rgb(s.colour));
        }
        for l in self.labels() {
            canvas.text(&l.text, (l.x, l.y), l.anchor, l.size, [0, 0, 0]);
        }
        canvas.png().map_err(|e| FigureError::Png(e.to_string()))
    }

    /// The grid lines' x positions in a panel (0, 25, 50, 75 and 100 %).
    pub fn grid(&self, panel: &ErrorPanel) -> Vec<f64> {
        (0..=4)
            .map(|k| {
                round1(panel.plot_left + (panel.plot_right - panel.plot_left) * f64::from(k) / 4.0)
            })
            .collect()
    }

    /// Where the grid lines start (a little above the first bar).
    pub fn grid_top(&self) -> f64 {
        PLOT_TOP - 6.0
    }

    /// The figure as a standalone SVG file, `stamp` in its `<metadata>`.
    pub fn svg(&self, stamp: &str) -> Result<String, askama::Error> {
        ErrorChartSvg { chart: self, stamp }.render()
    }
}

#[derive(Template)]
#[template(path = "paper/error_analysis.svg")]
struct ErrorChartSvg<'a> {
    chart: &'a ErrorChart,
    stamp: &'a str,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An analysis whose forward errors are 1 polarity inversion, 3 omissions and 4
    /// hallucinations, and which made no inverse error.
    fn analysis() -> ErrorAnalysis {
        let mut analysis = empty();
        let forward = &mut analysis.by_direction.forward;
        forward.structural.polarity_inversion = 1;
        forward.structural.omission = 3;
        forward.structural.hallucination = 4;
        forward.errors = 8;
        analysis
    }

    fn empty() -> ErrorAnalysis {
        crate::error_analysis::analyse(std::iter::empty())
    }

    fn rows() -> Vec<AnalysedRow> {
        vec![
            AnalysedRow {
                model: "A model with a really long name indeed".to_owned(),
                analysis: analysis(),
            },
            AnalysedRow {
                model: "Human".to_owned(),
                analysis: analysis(),
            },
        ]
    }

    #[test]
    fn segments_split_each_bar_by_share_of_errors() {
        let chart = ErrorChart::of(&rows());
        assert_eq!(chart.width, 1280.0);
        let forward = &chart.panels[0];
        // (1280 - 250 - 40 - 24) / 2 = 483 px per panel.
        assert_eq!((forward.plot_left, forward.plot_right), (250.0, 733.0));
        assert_eq!(chart.panels[1].plot_left, 773.0);
        let bar = &forward.bars[0];
        assert_eq!(bar.errors, 8);
        assert_eq!(bar.y, 52.0);
        assert_eq!(forward.bars[1].y, 94.0);
        let geometry: Vec<(f64, f64, &str)> = bar
            .segments
            .iter()
            .map(|s| (s.x, s.width, s.colour))
            .collect();
        // 1/8, 3/8 and 4/8 of 483 px: 60.375, 181.125, 241.5.
        assert_eq!(
            geometry,
            [
                (250.0, 60.4, "#0072b2"),
                (310.4, 181.1, "#cc79a7"),
                (491.5, 241.5, "#d55e00"),
            ]
        );
        let printed: Vec<Option<&str>> =
            bar.segments.iter().map(|s| s.printed.as_deref()).collect();
        assert_eq!(printed, [Some("12.5"), Some("37.5"), Some("50.0")]);
        assert_eq!(
            bar.segments[1].title,
            "A model with a really long name indeed: Omission 3 of 8 (37.5%)"
        );
        // Bars: 52..82 and 94..124.
        assert_eq!(chart.plot_bottom, 124.0);
        assert_eq!(chart.legend.len(), 5);
        assert!(chart.legend.iter().all(|s| s.y < chart.height));
    }

    #[test]
    fn a_direction_without_errors_says_so_and_long_names_are_cut() {
        let chart = ErrorChart::of(&rows());
        assert!(chart.panels[1].bars.iter().all(|b| b.segments.is_empty()));
        let labels = chart.labels();
        let texts: Vec<&str> = labels.iter().map(|l| l.text.as_str()).collect();
        assert_eq!(texts.iter().filter(|t| **t == "no errors").count(), 2);
        assert!(texts.contains(&"A model with a really…"));
        assert!(texts.contains(&"Human"));
    }

    #[test]
    fn the_svg_and_the_png_draw_the_same_bars() {
        let mut rows = rows();
        rows[1].model = "<A & B>".to_owned();
        let chart = ErrorChart::of(&rows);
        let svg = chart.svg("hub 1.0").unwrap();
        assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(svg.contains("<metadata>hub 1.0</metadata>"));
        // Three segments per forward bar, and the legend's five swatches.
        assert_eq!(svg.matches("<rect").count(), 1 + 6 + 5);
        assert!(svg.contains("&#60;A &#38; B&#62;"));
        assert!(!svg.contains("<A & B>"));
        let png = chart.png().unwrap();
        let image = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
            .unwrap()
            .to_rgb8();
        assert_eq!(image.width(), 1280);
        assert_eq!(f64::from(image.height()), chart.height.ceil());
        // Just inside the hallucination segment's top-right corner: its colour.
        let s = &chart.panels[0].bars[0].segments[2];
        assert_eq!(
            image
                .get_pixel((s.x + s.width - 3.0) as u32, (s.y + 2.0) as u32)
                .0,
            rgb("#d55e00")
        );
        assert_eq!(image.get_pixel(2, 2).0, [255, 255, 255]);
    }
}
