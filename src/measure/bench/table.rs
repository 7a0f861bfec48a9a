//! The table `powder bench` prints.

use super::BenchRow;

fn opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map_or_else(|| "-".into(), f)
}

/// The table `powder bench` prints (one header, then [`table_line`] per row).
pub fn table_header() -> String {
    format!(
        "{:<11} {:<6} {:>9} {:>6} {:>8} {:>9} {:>10} {:>12} {:>7} {:>9} {:>9} {:>8} {:>6}  note",
        "case",
        "back",
        "particles",
        "steps",
        "setup s",
        "wall s",
        "s/step",
        "p-steps/s",
        "speedup",
        "GPU B/p",
        "B/p-step",
        "rebuilds",
        "Z"
    )
}

/// One row of the table.
pub fn table_line(r: &BenchRow) -> String {
    format!(
        "{:<11} {:<6} {:>9} {:>6} {:>8} {:>9} {:>10} {:>12} {:>7} {:>9} {:>9} {:>8} {:>6}  {}",
        r.case,
        match r.threads {
            Some(t) => format!("{}×{t}", r.backend),
            None => r.backend.to_string(),
        },
        r.particles,
        r.steps,
        opt(r.setup_seconds, |v| format!("{v:.2}")),
        opt(r.wall_seconds, |v| format!("{v:.3}")),
        opt(r.seconds_per_step, |v| format!("{v:.3e}")),
        opt(r.particle_steps_per_second, |v| format!("{v:.3e}")),
        opt(r.speedup, |v| format!("{v:.2}×")),
        opt(r.gpu_bytes_per_particle, |v| format!("{v:.0}")),
        opt(
            r.traffic.as_ref().map(|t| t.bytes_per_particle_step),
            |v| format!("{v:.0}")
        ),
        r.rebuilds.map_or_else(|| "-".into(), |v| v.to_string()),
        opt(r.contacts_per_particle, |v| format!("{v:.2}")),
        match (r.note.as_deref(), r.quiet_batches) {
            (Some(n), _) => n.to_string(),
            (None, Some((kept, back))) if kept + back > 0 =>
                format!("quiet batches {kept} kept, {back} rolled back"),
            _ => String::new(),
        }
    ) + &r
        .passes
        .as_ref()
        .map_or(String::new(), |p| format!("\n    {}", p.summary()))
}
