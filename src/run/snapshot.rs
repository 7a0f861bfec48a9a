//! The state of a run at an output instant, and its two renderings: the `series.csv`
//! row and the progress line.

use super::*;

/// The state of a run at one output instant.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Snapshot {
    /// Steps taken.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Energies, J (without the ledger: kinetic, gravitational and inserted only).
    pub energies: ObservedEnergies,
    /// Contact statistics; absent without the ledger.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contacts: Option<ContactStats>,
}

pub(super) fn snapshot(engine: &impl Simulation, obs: &Observation) -> Snapshot {
    Snapshot {
        step: engine.steps(),
        time: engine.time(),
        energies: obs.energies,
        contacts: obs.contacts,
    }
}

/// Header of `series.csv`: per wall the force of the particles on it and, for a moving
/// wall, where its plane passes (the scene point moved with the wall).
pub fn csv_header(walls: &[crate::scene::Wall]) -> String {
    let mut h = String::from(
        "step,time,kinetic,elastic,gravitational,dissipated,wall_work,inserted,total,contacts,wall_contacts,non_contact,coordination,max_overlap,max_overlap_ratio,mean_overlap_ratio",
    );
    for (w, wall) in walls.iter().enumerate() {
        h.push_str(&format!(",wall{w}_fx,wall{w}_fy,wall{w}_fz"));
        if wall.motion.moves() {
            h.push_str(&format!(",wall{w}_x,wall{w}_y,wall{w}_z"));
        }
    }
    h
}

/// A CSV cell: empty when the value is unknown (no ledger), so the header stays the same
/// and readers see a missing value, not a zero.
pub(super) fn cell<T: std::fmt::LowerExp>(v: Option<T>) -> String {
    v.map(|v| format!("{v:e}")).unwrap_or_default()
}

/// A CSV cell of a count: empty when unknown.
pub(super) fn count_cell(v: Option<usize>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

pub(super) fn csv_row(s: &Snapshot, obs: &Observation, walls: &[crate::scene::Wall]) -> String {
    let e = &s.energies;
    let c = s.contacts.as_ref();
    let mut row = format!(
        "{},{:e},{:e},{},{:e},{},{},{:e},{},{},{},{},{},{},{},{}",
        s.step,
        s.time,
        e.kinetic,
        cell(e.elastic),
        e.gravitational,
        cell(e.dissipated),
        cell(e.wall_work),
        e.inserted,
        cell(e.total()),
        count_cell(c.map(|c| c.contacts)),
        count_cell(c.map(|c| c.wall_contacts)),
        count_cell(c.map(|c| c.non_contact)),
        cell(c.map(|c| c.coordination)),
        cell(c.map(|c| c.max_overlap)),
        cell(c.map(|c| c.max_overlap_ratio)),
        cell(c.map(|c| c.mean_overlap_ratio))
    );
    for (w, wall) in walls.iter().enumerate() {
        match obs.wall_forces.as_ref().map(|f| f[w]) {
            Some(f) => row.push_str(&format!(",{:e},{:e},{:e}", f.x, f.y, f.z)),
            None => row.push_str(",,,"),
        }
        if wall.motion.moves() {
            let p = obs.wall_points[w];
            row.push_str(&format!(",{:e},{:e},{:e}", p.x, p.y, p.z));
        }
    }
    row
}

/// A value for people: "n/a" when unknown (no ledger).
pub(super) fn shown(v: Option<f64>, format: impl Fn(f64) -> String) -> String {
    v.map(format).unwrap_or_else(|| "n/a".into())
}

impl Snapshot {
    /// One human-readable progress line ("n/a" for what a run without the ledger does not
    /// know).
    pub fn line(&self) -> String {
        let e = &self.energies;
        let c = self.contacts.as_ref();
        format!(
            "step {:>9}  t = {:.4e} s  E_kin {:.4e}  E_el {}  E_diss {}  E_tot {} J  Z = {}  max δ/a12 = {}",
            self.step,
            self.time,
            e.kinetic,
            shown(e.elastic, |v| format!("{v:.4e}")),
            shown(e.dissipated, |v| format!("{v:.4e}")),
            shown(e.total(), |v| format!("{v:.6e}")),
            shown(c.map(|c| c.coordination), |v| format!("{v:.3}")),
            shown(c.map(|c| c.max_overlap_ratio), |v| format!("{v:.3e}"))
        )
    }
}
