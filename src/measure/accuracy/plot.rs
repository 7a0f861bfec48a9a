//! The work–precision diagram: error against run time, a series per case and backend.

use super::*;

/// The work–precision diagram: error against wall time, log-log, one line per case and
/// backend (the packing's kinetic-energy error dashed).
pub fn work_precision_plot(report: &AccuracyReport) -> Plot {
    let mut series = Vec::new();
    let adapter = report.adapter.as_ref().map_or_else(
        || "GPU f32".to_string(),
        |a| format!("GPU f32, {}", a.name.split(" (").next().unwrap_or(&a.name)),
    );
    for (case, label) in [
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
    ] {
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
            series.push(Series {
                label: format!("{label} ({who})"),
                points: pts.iter().map(|p| (p.wall_seconds, p.error)).collect(),
                style: Style::Line,
            });
            if case == "packing" {
                series.push(Series {
                    label: format!("packing, |dE_kin|/E_kin ({who})"),
                    points: pts
                        .iter()
                        .filter_map(|p| p.kinetic_error.map(|k| (p.wall_seconds, k)))
                        .collect(),
                    style: Style::DashedLine,
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
        series,
        // a band below the data for the legend
        y_range: lowest_error(report).map(|lo| (lo * 3e-3, highest_error(report) * 3.0)),
        legend: Legend::LowerRight,
    }
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
