//! SVG line and marker plots (plotters' SVG backend; text is left to the SVG viewer, so no
//! system fonts are needed).

use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::PowderError;
use crate::output::atomic::write_atomic;

/// Width and height of every plot, in pixels.
pub const SIZE: (u32, u32) = (800, 600);

/// Fraction of the data span added on each side of an automatic axis range.
const MARGIN: f64 = 0.05;

/// Series colours (the "tab10" palette), cycled when there are more series.
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Solid line through the points.
    Line,
    /// A marker at each point, no line.
    Markers,
    /// Dashed line through the points.
    DashedLine,
}

/// One labelled data series. An empty label keeps the series out of the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text; empty = not in the legend.
    pub label: String,
    /// (x, y) data points, in axis units.
    pub points: Vec<(f64, f64)>,
    /// How the series is drawn.
    pub style: Style,
    /// Index into the palette; `None`: the series' own index (several series may share a
    /// colour, told apart by their style).
    pub colour: Option<usize>,
}

/// A 2-D plot of one or more series.
///
/// Points with a non-finite coordinate, or with a coordinate <= 0 on a logarithmic axis, are
/// skipped. Axis ranges come from the remaining points plus a small margin, except the y axis
/// when `y_range` is given (lines are then clipped to it, markers outside it are dropped).
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// Caption above the plot.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Logarithmic x axis (points with x <= 0 are skipped).
    pub log_x: bool,
    /// Logarithmic y axis (points with y <= 0 are skipped).
    pub log_y: bool,
    /// The data, drawn in order, each with its own colour.
    pub series: Vec<Series>,
    /// Fixed y range (lo, hi) instead of the automatic one.
    pub y_range: Option<(f64, f64)>,
    /// Where the legend goes (pick the emptiest corner of the data).
    pub legend: Legend,
}

/// Legend placement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    #[default]
    /// Top right corner.
    UpperRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom left corner.
    LowerLeft,
    /// Bottom right corner.
    LowerRight,
}

/// One axis: its range and whether it is logarithmic.
#[derive(Debug, Clone, Copy)]
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Axis {
    /// The coordinate in which the axis is linear.
    fn fwd(&self, v: f64) -> f64 {
        if self.log {
            v.log10()
        } else {
            v
        }
    }

    fn inv(&self, t: f64) -> f64 {
        if self.log {
            10f64.powf(t)
        } else {
            t
        }
    }

    fn contains(&self, v: f64) -> bool {
        v >= self.lo && v <= self.hi
    }
}

/// Whether a value can be placed on an axis.
fn usable(v: f64, log: bool) -> bool {
    v.is_finite() && (!log || v > 0.0)
}

impl Plot {
    /// Renders the plot as an SVG document.
    pub fn to_svg_string(&self) -> Result<String, PowderError> {
        let points: Vec<Vec<(f64, f64)>> = self
            .series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .copied()
                    .filter(|&(x, y)| usable(x, self.log_x) && usable(y, self.log_y))
                    .collect()
            })
            .collect();
        let xs: Vec<f64> = points.iter().flatten().map(|p| p.0).collect();
        if xs.is_empty() {
            let axes = match (self.log_x, self.log_y) {
                (false, false) => "",
                (true, false) => " (x axis is logarithmic: x must be > 0)",
                (false, true) => " (y axis is logarithmic: y must be > 0)",
                (true, true) => " (both axes are logarithmic: x and y must be > 0)",
            };
            return Err(PowderError::Run(format!(
                "cannot plot `{}`: no finite data point{axes}",
                self.title
            )));
        }
        let x_axis = auto_axis(&xs, self.log_x)
            .ok_or_else(|| self.err("the x data span too wide a range to plot"))?;
        let y_axis = match self.y_range {
            Some((lo, hi)) => {
                if !(usable(lo, self.log_y) && usable(hi, self.log_y) && lo < hi) {
                    let need = if self.log_y { "0 < lo < hi" } else { "lo < hi" };
                    return Err(
                        self.err(&format!("invalid y_range ({lo}, {hi}): need finite {need}"))
                    );
                }
                Axis {
                    lo,
                    hi,
                    log: self.log_y,
                }
            }
            None => {
                let ys: Vec<f64> = points.iter().flatten().map(|p| p.1).collect();
                auto_axis(&ys, self.log_y)
                    .ok_or_else(|| self.err("the y data span too wide a range to plot"))?
            }
        };

        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
            let (x, y) = ((x_axis.lo..x_axis.hi), (y_axis.lo..y_axis.hi));
            let res = match (self.log_x, self.log_y) {
                (false, false) => self.draw(&root, x, y, x_axis, y_axis, &points),
                (true, false) => self.draw(&root, x.log_scale(), y, x_axis, y_axis, &points),
                (false, true) => self.draw(&root, x, y.log_scale(), x_axis, y_axis, &points),
                (true, true) => {
                    self.draw(&root, x.log_scale(), y.log_scale(), x_axis, y_axis, &points)
                }
            };
            res.and_then(|()| root.present().map_err(|e| e.to_string()))
                .map_err(|e| self.err(&e))?;
        }
        Ok(svg)
    }

    /// Renders the plot and writes it to `path` atomically.
    pub fn write_svg(&self, path: &Path) -> Result<(), PowderError> {
        let svg = self.to_svg_string()?;
        write_atomic(path, svg.as_bytes())
    }

    fn err(&self, what: &str) -> PowderError {
        PowderError::Run(format!("cannot plot `{}`: {what}", self.title))
    }

    /// Draws the chart on `root`; `x` and `y` are the (linear or log) coordinate specs matching
    /// `x_axis` and `y_axis`, and `points` the usable points of each series.
    fn draw<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend<'_>, Shift>,
        x: X,
        y: Y,
        x_axis: Axis,
        y_axis: Axis,
        points: &[Vec<(f64, f64)>],
    ) -> Result<(), String>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let e = |e: DrawingAreaErrorKind<std::io::Error>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(75)
            .build_cartesian_2d(x, y)
            .map_err(e)?;

        let x_fmt = tick_formatter(x_axis);
        let y_fmt = tick_formatter(y_axis);
        chart
            .configure_mesh()
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .axis_desc_style(("sans-serif", 16))
            .label_style(("sans-serif", 13))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(e)?;

        let mut any_label = false;
        for (i, (series, pts)) in self.series.iter().zip(points).enumerate() {
            let colour = COLOURS[series.colour.unwrap_or(i) % COLOURS.len()];
            let line = colour.stroke_width(2);
            let marker = colour.filled();

            // Legend entry (drawn from an empty series so that clipped pieces share it).
            if !series.label.is_empty() {
                any_label = true;
                let anno = chart
                    .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                    .map_err(e)?
                    .label(series.label.as_str());
                match series.style {
                    Style::Line => {
                        anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line))
                    }
                    Style::DashedLine => anno.legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (6, 0)], line)
                            + PathElement::new(vec![(10, 0), (16, 0)], line)
                            + PathElement::new(vec![(20, 0), (22, 0)], line)
                    }),
                    Style::Markers => {
                        anno.legend(move |(x, y)| Circle::new((x + 10, y), 3, marker))
                    }
                };
            }

            let draw_markers = series.style == Style::Markers || pts.len() == 1;
            if draw_markers {
                let visible = pts
                    .iter()
                    .copied()
                    .filter(|&(px, py)| x_axis.contains(px) && y_axis.contains(py));
                chart
                    .draw_series(visible.map(|p| Circle::new(p, 3, marker)))
                    .map_err(e)?;
            }
            if series.style == Style::Markers {
                continue;
            }
            for piece in clip_polyline(pts, x_axis, y_axis) {
                match series.style {
                    Style::Line => chart.draw_series(LineSeries::new(piece, line)),
                    _ => chart.draw_series(DashedLineSeries::new(piece, 8, 5, line)),
                }
                .map_err(e)?;
            }
        }

        if any_label {
            chart
                .configure_series_labels()
                .position(match self.legend {
                    Legend::UpperRight => SeriesLabelPosition::UpperRight,
                    Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
                    Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
                    Legend::LowerRight => SeriesLabelPosition::LowerRight,
                })
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()
                .map_err(e)?;
        }
        Ok(())
    }
}

/// The range of `values` (all usable, at least one) plus a margin. Log axes get the margin in
/// log space and always contain a power of ten, so that they carry at least one tick label.
/// `None` when the range overflows.
fn auto_axis(values: &[f64], log: bool) -> Option<Axis> {
    let tf = |v: f64| if log { v.log10() } else { v };
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in values {
        lo = lo.min(tf(v));
        hi = hi.max(tf(v));
    }
    let span = hi - lo;
    let (mut lo, mut hi) = if span == 0.0 || span < lo.abs().max(hi.abs()) * 1e-12 {
        // A single value (or indistinguishable ones): a default range around it.
        let half = if log {
            0.5
        } else if lo != 0.0 {
            0.1 * lo.abs()
        } else {
            1.0
        };
        (lo - half, hi + half)
    } else {
        let m = MARGIN * hi - MARGIN * lo;
        (lo - m, hi + m)
    };
    if log {
        if lo.ceil() > hi {
            lo = lo.floor();
        }
        lo = 10f64.powf(lo);
        hi = 10f64.powf(hi);
        if lo <= 0.0 || !hi.is_finite() {
            // Clamp to what f64 can hold rather than give up.
            lo = lo.max(f64::MIN_POSITIVE);
            hi = hi.min(f64::MAX);
        }
    }
    (lo.is_finite() && hi.is_finite() && (hi - lo).is_finite() && lo < hi).then_some(Axis {
        lo,
        hi,
        log,
    })
}

/// Tick labels: as few digits as the axis needs, scientific notation for very large or small
/// magnitudes.
fn tick_formatter(axis: Axis) -> impl Fn(&f64) -> String {
    move |&v: &f64| {
        if v == 0.0 {
            return "0".to_string();
        }
        if axis.log {
            // Ticks are 1..9 times a power of ten: three significant digits suffice.
            return format_sig(v, 3);
        }
        let step = (axis.hi - axis.lo) / 10.0;
        let mag = axis.lo.abs().max(axis.hi.abs());
        if !(1e-3..1e5).contains(&mag) {
            // Enough significant digits to tell neighbouring ticks apart.
            let sig = ((mag / step).log10().ceil() as i32 + 1).clamp(2, 12);
            format_sci(v, sig as usize - 1)
        } else {
            let decimals = (1 - step.log10().floor() as i32).clamp(0, 12) as usize;
            trim_zeros(format!("{v:.decimals$}"))
        }
    }
}

/// `v` with `sig` significant digits, in positional notation for moderate magnitudes.
fn format_sig(v: f64, sig: usize) -> String {
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (sig as i32 - 1 - a.log10().floor() as i32).clamp(0, 12) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        format_sci(v, sig.saturating_sub(1))
    }
}

/// Scientific notation with at most `decimals` mantissa decimals, trailing zeros removed.
fn format_sci(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$e}");
    match s.split_once('e') {
        Some((mantissa, exp)) => format!("{}e{exp}", trim_zeros(mantissa.to_string())),
        None => s,
    }
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Splits a polyline into the pieces inside the axes' rectangle (clipping in the coordinates
/// where the axes are linear). Unclipped points keep their exact values.
fn clip_polyline(points: &[(f64, f64)], x: Axis, y: Axis) -> Vec<Vec<(f64, f64)>> {
    let rect = (x.fwd(x.lo), x.fwd(x.hi), y.fwd(y.lo), y.fwd(y.hi));
    let mut pieces = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut flush = |cur: &mut Vec<(f64, f64)>| {
        if cur.len() >= 2 {
            pieces.push(std::mem::take(cur));
        } else {
            cur.clear();
        }
    };
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        let pt = (x.fwd(p.0), y.fwd(p.1));
        let qt = (x.fwd(q.0), y.fwd(q.1));
        match clip_segment(pt, qt, rect) {
            None => flush(&mut cur),
            Some((t0, t1)) => {
                let at = |t: f64| {
                    (
                        x.inv(pt.0 + t * (qt.0 - pt.0)),
                        y.inv(pt.1 + t * (qt.1 - pt.1)),
                    )
                };
                if t0 > 0.0 || cur.is_empty() {
                    flush(&mut cur);
                    cur.push(if t0 > 0.0 { at(t0) } else { p });
                }
                if t1 < 1.0 {
                    cur.push(at(t1));
                    flush(&mut cur);
                } else {
                    cur.push(q);
                }
            }
        }
    }
    flush(&mut cur);
    pieces
}

/// Liang–Barsky clipping of the segment p→q to the rectangle (x0, x1, y0, y1): the parameter
/// interval [t0, t1] ⊂ [0, 1] that lies inside, or `None`.
fn clip_segment(
    p: (f64, f64),
    q: (f64, f64),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) -> Option<(f64, f64)> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let mut t0 = 0.0f64;
    let mut t1 = 1.0f64;
    for (den, num) in [
        (-dx, p.0 - x0),
        (dx, x1 - p.0),
        (-dy, p.1 - y0),
        (dy, y1 - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(label: &str, points: Vec<(f64, f64)>, style: Style) -> Series {
        Series {
            label: label.to_string(),
            points,
            style,
            colour: None,
        }
    }

    fn plot(series: Vec<Series>) -> Plot {
        Plot {
            title: "Restitution vs impact speed".to_string(),
            x_label: "v (m/s)".to_string(),
            y_label: "e".to_string(),
            log_x: false,
            log_y: false,
            series,
            y_range: None,
            legend: Legend::default(),
        }
    }

    fn demo() -> Plot {
        let xs: Vec<f64> = (1..=20).map(|i| i as f64 * 0.1).collect();
        plot(vec![
            series(
                "simulation",
                xs.iter().map(|&x| (x, 0.9 - 0.1 * x)).collect(),
                Style::Markers,
            ),
            series(
                "theory",
                xs.iter().map(|&x| (x, 0.9 - 0.1 * x)).collect(),
                Style::Line,
            ),
            series(
                "bound",
                xs.iter().map(|&x| (x, 0.95 - 0.1 * x)).collect(),
                Style::DashedLine,
            ),
        ])
    }

    #[test]
    fn svg_has_title_and_legend() {
        let svg = demo().to_svg_string().unwrap();
        assert!(svg.contains("<svg"), "{svg}");
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("Restitution vs impact speed"));
        for label in ["simulation", "theory", "bound", "v (m/s)"] {
            assert!(svg.contains(label), "missing {label}");
        }
        assert!(svg.contains("width=\"800\"") && svg.contains("height=\"600\""));
        // Distinct colours for the three series.
        for c in &COLOURS[..3] {
            let hex = format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
            assert!(svg.to_uppercase().contains(&hex), "missing colour {hex}");
        }
    }

    #[test]
    fn title_is_escaped() {
        let mut p = demo();
        p.title = "a < b & c".to_string();
        let svg = p.to_svg_string().unwrap();
        assert!(svg.contains("a &lt; b &amp; c"));
    }

    #[test]
    fn log_x_with_zero_and_non_finite_points_does_not_panic() {
        let mut p = plot(vec![series(
            "data",
            vec![
                (0.0, 1.0),
                (1e-3, 2.0),
                (f64::NAN, 3.0),
                (1.0, f64::INFINITY),
                (1e2, 4.0),
                (-5.0, 1.0),
            ],
            Style::Line,
        )]);
        p.log_x = true;
        let svg = p.to_svg_string().unwrap();
        assert!(svg.contains("<svg") && svg.contains("data"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        p.log_y = true;
        p.to_svg_string().unwrap();
    }

    #[test]
    fn single_point_and_empty_series_render() {
        for (log_x, log_y) in [(false, false), (true, true)] {
            let mut p = plot(vec![
                series("empty", vec![], Style::Line),
                series("one", vec![(2.0, 3.0)], Style::DashedLine),
            ]);
            p.log_x = log_x;
            p.log_y = log_y;
            let svg = p.to_svg_string().unwrap();
            assert!(svg.contains("empty") && svg.contains("one"));
            assert!(svg.contains("<circle"), "a lone point is shown as a marker");
        }
        // A single point at zero on linear axes.
        plot(vec![series("z", vec![(0.0, 0.0)], Style::Markers)])
            .to_svg_string()
            .unwrap();
    }

    #[test]
    fn narrow_log_range_has_tick_labels() {
        let mut p = plot(vec![series("d", vec![(2.0, 3.0), (3.0, 4.0)], Style::Line)]);
        p.log_x = true;
        p.log_y = true;
        let svg = p.to_svg_string().unwrap();
        // Text content sits on its own line in plotters' SVG.
        assert!(svg.contains("\n1\n</text>"), "{svg}");
    }

    #[test]
    fn empty_plot_errors_naming_the_title() {
        let err = plot(vec![]).to_svg_string().unwrap_err();
        assert!(matches!(err, PowderError::Run(_)));
        assert!(
            err.to_string().contains("Restitution vs impact speed"),
            "{err}"
        );

        let mut p = plot(vec![series(
            "neg",
            vec![(-1.0, 1.0), (0.0, f64::NAN)],
            Style::Line,
        )]);
        p.log_x = true;
        let err = p.to_svg_string().unwrap_err();
        assert!(
            err.to_string().contains("Restitution vs impact speed"),
            "{err}"
        );
    }

    #[test]
    fn y_range_is_used_and_validated() {
        let mut p = demo();
        p.y_range = Some((0.8, 0.85));
        let svg = p.to_svg_string().unwrap();
        assert!(svg.contains("<svg"));
        p.y_range = Some((1.0, 1.0));
        let err = p.to_svg_string().unwrap_err();
        assert!(err.to_string().contains("y_range"), "{err}");
        p.log_y = true;
        p.y_range = Some((0.0, 1.0));
        assert!(p.to_svg_string().is_err());
    }

    #[test]
    fn tiny_and_huge_values_render() {
        let p = plot(vec![series(
            "small",
            vec![(1e-9, 1e-12), (2e-9, 3e-12), (3e-9, 2e-12)],
            Style::Line,
        )]);
        let svg = p.to_svg_string().unwrap();
        assert!(svg.contains("e-9") && svg.contains("e-12"), "{svg}");
        let p = plot(vec![series(
            "huge",
            vec![(-1.7e308, 0.0), (1.7e308, 1.0)],
            Style::Line,
        )]);
        // Either a plot or an error naming the title, never a panic.
        if let Err(err) = p.to_svg_string() {
            assert!(err.to_string().contains("Restitution"), "{err}");
        }
    }

    #[test]
    fn clipping_splits_lines_at_the_range() {
        let x = Axis {
            lo: 0.0,
            hi: 10.0,
            log: false,
        };
        let y = Axis {
            lo: 0.0,
            hi: 1.0,
            log: false,
        };
        let pts = [
            (0.0, 0.5),
            (2.0, 0.5),
            (4.0, 2.0),
            (6.0, 2.0),
            (8.0, 0.5),
            (10.0, 0.5),
        ];
        let pieces = clip_polyline(&pts, x, y);
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0][0], (0.0, 0.5));
        assert_eq!(pieces[0].len(), 3);
        assert!((pieces[0][2].1 - 1.0).abs() < 1e-12);
        assert_eq!(*pieces[1].last().unwrap(), (10.0, 0.5));
        // Fully inside: unchanged.
        let inside = [(1.0, 0.1), (2.0, 0.2), (3.0, 0.3)];
        assert_eq!(clip_polyline(&inside, x, y), vec![inside.to_vec()]);
    }

    #[test]
    fn tick_labels_are_compact() {
        let lin = Axis {
            lo: 0.0,
            hi: 2.0,
            log: false,
        };
        let f = tick_formatter(lin);
        assert_eq!(f(&0.2), "0.2");
        assert_eq!(f(&1.0), "1");
        assert_eq!(f(&0.30000000000000004), "0.3");
        let log = Axis {
            lo: 1e-3,
            hi: 10.0,
            log: true,
        };
        let f = tick_formatter(log);
        assert_eq!(f(&0.30000000000000004), "0.3");
        assert_eq!(f(&1e-7), "1e-7");
        let small = Axis {
            lo: 1e-9,
            hi: 3e-9,
            log: false,
        };
        assert_eq!(tick_formatter(small)(&1.5e-9), "1.5e-9");
    }

    #[test]
    fn write_svg_writes_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.svg");
        std::fs::write(&path, "old").unwrap();
        demo().write_svg(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<svg") && text.contains("theory"));
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file is left behind");

        let err = demo()
            .write_svg(&dir.path().join("missing").join("p.svg"))
            .unwrap_err();
        assert!(err.to_string().contains("p.svg"), "{err}");
    }
}
