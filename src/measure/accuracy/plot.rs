//! The work–precision diagram: error against run time, a series per case and backend.

use super::*;

/// The work–precision diagram: error against wall time, log-log, one colour per measure,
/// the CPU's lines solid and the GPU's dashed; the legend in a band below the data.
pub fn work_precision_plot(report: &AccuracyReport) -> Plot {
    let mut series = Vec::new();
    let adapter = report.adapter.as_ref().map_or_else(
        || "GPU f32".to_string(),
        |a| format!("GPU f32, {}", a.name.split(" (").next().unwrap_or(&a.name)),
    );
    for (measure, (case, label)) in [
        ("pair", "pair, max |e - e_closed| over chi"),
        (
            "jkr-displacement",
            "JKR displacement pull-off, max |e - e_closed|",
        ),
        (
            "jkr-displacement-verlet",
            "JKR displacement pull-off, jumps left to Verlet",
        ),
        ("jkr-force", "JKR force pull-off, max |e - e_closed|"),
        (
            "jkr-force-verlet",
            "JKR force pull-off, jumps left to Verlet",
        ),
        ("packing", "packing, RMS |x - x_ref|/r"),
    ]
    .into_iter()
    .enumerate()
    {
        for backend in ["cpu", "gpu"] {
            let pts: Vec<&AccuracyPoint> = report
                .points
                .iter()
                .filter(|p| p.case == case && p.backend == backend)
                .collect();
            if pts.is_empty() {
                continue;
            }
            let who = if backend == "cpu" {
                "CPU f64".to_string()
            } else {
                adapter.clone()
            };
            let style = match backend {
                "cpu" => Style::Line,
                _ => Style::DashedLine,
            };
            series.push(Series {
                label: format!("{label} ({who})"),
                points: pts.iter().map(|p| (p.wall_seconds, p.error)).collect(),
                style,
                colour: Some(measure),
            });
            if case == "packing" {
                series.push(Series {
                    label: format!("packing, |dE_kin|/E_kin ({who})"),
                    points: pts
                        .iter()
                        .filter_map(|p| p.kinetic_error.map(|k| (p.wall_seconds, k)))
                        .collect(),
                    style,
                    colour: Some(measure + 1),
                });
            }
        }
    }
    let divisors: Vec<String> = {
        let mut d: Vec<f64> = report.points.iter().map(|p| p.divisor).collect();
        d.sort_by(f64::total_cmp);
        d.dedup();
        d.iter().map(|x| format!("{x}")).collect()
    };
    Plot {
        title: format!("Work-precision, dt = tc/({})", divisors.join(", ")),
        x_label: "wall time (s)".into(),
        y_label: "error".into(),
        log_x: true,
        log_y: true,
        y_range: lowest_error(report)
            .map(|lo| legend_band(lo, highest_error(report), series.len())),
        series,
        legend: Legend::LowerRight,
    }
}

/// The y range: the data (`lo` … `hi`, with a margin above) over a band below it as tall
/// as a legend of `entries` lines (about 20 px each of the plot's ~480), so the legend in
/// the lower corner covers no point.
fn legend_band(lo: f64, hi: f64, entries: usize) -> (f64, f64) {
    let top = hi * 3.0;
    let data = (top / lo).log10().max(1.0);
    let share = ((entries as f64 * 20.0 + 24.0) / 480.0).min(0.8);
    let band = data * share / (1.0 - share) + 0.15;
    (lo / 10f64.powf(band), top)
}

pub(super) fn errors(report: &AccuracyReport) -> impl Iterator<Item = f64> + '_ {
    report
        .points
        .iter()
        .flat_map(|p| [Some(p.error), p.kinetic_error])
        .flatten()
        .filter(|e| e.is_finite() && *e > 0.0)
}

pub(super) fn lowest_error(report: &AccuracyReport) -> Option<f64> {
    errors(report).reduce(f64::min)
}

pub(super) fn highest_error(report: &AccuracyReport) -> f64 {
    errors(report).fold(0.0, f64::max)
}
