//! The contact network at a snapshot: one line per engaged contact (between the two centres,
//! or from a centre to its contact point on a wall) with its forces, overlap, history and
//! whether it slides, as VTK PolyData (`contacts/<scene>_<step>.vtp`, collected in
//! `<scene>_contacts.pvd`) for force-chain pictures in ParaView.

use crate::cpu::engine::minimum_image;
use crate::cpu::Partner;
use crate::model::history::{HistoryField, HostField};
use crate::model::ContactHistory;
use crate::output::appended::AppendedVtp;
use glam::DVec3;

/// One engaged contact (touching, or exerting a force, or storing energy) after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactLine {
    /// The particle whose side the values are given from (of a pair, the lower id).
    pub i: usize,
    /// The other particle (higher id) or the wall.
    pub partner: Partner,
    /// Normal force on i along n (from the partner to i), repulsive positive, N.
    pub normal_force: f64,
    /// The whole contact force on i (normal and tangential), N.
    pub force: DVec3,
    /// Overlap δ, m (negative: apart, in the adhesive range).
    pub overlap: f64,
    /// The contact's history, seen from i.
    pub history: ContactHistory,
    /// Whether the tangential force slid at the Coulomb limit in the step (sticking
    /// otherwise, or no friction).
    pub sliding: bool,
}

/// The engaged contacts of a snapshot and the history fields their laws keep.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactNetwork {
    /// Pairs by (i, j), then wall contacts by (wall, particle).
    pub lines: Vec<ContactLine>,
    /// The history fields of the scene's laws (`gpu::Composition::history`).
    pub fields: Vec<&'static HistoryField>,
}

/// Where a snapshot's lines end: the particle centres now and the geometry the ends need.
pub struct Ends<'a> {
    /// Particle centres, m.
    pub positions: &'a [DVec3],
    /// Particle radii, m.
    pub radii: &'a [f64],
    /// Each wall's unit normal (pointing into the domain).
    pub wall_normals: &'a [DVec3],
    /// Periodic axes and the domain box: a pair across a periodic boundary is drawn to the
    /// partner's nearest image.
    pub periodic: [bool; 3],
    /// The domain box (min, max), m.
    pub domain: (DVec3, DVec3),
}

impl Ends<'_> {
    /// The line's two ends: i's centre and the partner's (nearest image), or the contact
    /// point on the wall (i's centre moved r_i − δ against the wall's normal).
    fn of(&self, c: &ContactLine) -> (DVec3, DVec3) {
        let x = self.positions[c.i];
        let to = match c.partner {
            Partner::Particle(j) => {
                x - minimum_image(x - self.positions[j], self.periodic, self.domain)
            }
            Partner::Wall(w) => x - self.wall_normals[w] * (self.radii[c.i] - c.overlap),
        };
        (x, to)
    }
}

/// The history values output per contact: the scene's fields, each output name once, the
/// touched flag (which every law keeps) left to its own array and the slipping flag to
/// `sliding` (the step's, which it stores).
fn history_outputs(fields: &[&'static HistoryField]) -> Vec<HostField> {
    let mut out: Vec<HostField> = Vec::new();
    for f in fields {
        let name = f.host.output().0;
        let own_array = matches!(f.host, HostField::Touched | HostField::Slipping);
        if !own_array && !out.iter().any(|h| h.output().0 == name) {
            out.push(f.host);
        }
    }
    out
}

/// The `.vtp` document of a contact network: two points and one line per contact, the
/// values as cell data (binary, [`AppendedVtp`]).
pub fn vtp(net: &ContactNetwork, ends: &Ends) -> Vec<u8> {
    let lines = &net.lines;
    let n = lines.len();
    let mut d = AppendedVtp::new(2 * n, 0, n);
    d.open("Points", "");
    let points: Vec<DVec3> = lines
        .iter()
        .flat_map(|c| {
            let (a, b) = ends.of(c);
            [a, b]
        })
        .collect();
    d.vectors("position", &points);
    d.close("Points");
    d.open("CellData", r#" Scalars="normal_force" Vectors="force""#);
    let values = |f: fn(&ContactLine) -> f64| lines.iter().map(f).collect::<Vec<f64>>();
    let flags =
        |f: fn(&ContactLine) -> bool| lines.iter().map(|c| u8::from(f(c))).collect::<Vec<u8>>();
    d.array("normal_force", 1, &values(|c| c.normal_force));
    d.vectors("force", &lines.iter().map(|c| c.force).collect::<Vec<_>>());
    d.array("overlap", 1, &values(|c| c.overlap));
    d.array("sliding", 1, &flags(|c| c.sliding));
    d.array("touched", 1, &flags(|c| c.history.touched));
    d.array(
        "i",
        1,
        &lines.iter().map(|c| c.i as i64).collect::<Vec<_>>(),
    );
    // the other particle's id, or −1 − w for wall w
    let partner: Vec<i64> = lines
        .iter()
        .map(|c| match c.partner {
            Partner::Particle(j) => j as i64,
            Partner::Wall(w) => -1 - w as i64,
        })
        .collect();
    d.array("partner", 1, &partner);
    for h in history_outputs(&net.fields) {
        let (name, components) = h.output();
        let flat: Vec<f64> = lines
            .iter()
            .flat_map(|c| h.value(&c.history)[..components].to_vec())
            .collect();
        d.array(name, components, &flat);
    }
    d.close("CellData");
    d.open("Lines", "");
    d.array("connectivity", 1, &(0..2 * n as i64).collect::<Vec<_>>());
    d.array(
        "offsets",
        1,
        &(1..=n as i64).map(|k| 2 * k).collect::<Vec<_>>(),
    );
    d.close("Lines");
    d.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::history::TANGENTIAL_SPRING;
    use crate::output::appended::read_array;

    fn line(i: usize, partner: Partner, overlap: f64) -> ContactLine {
        ContactLine {
            i,
            partner,
            normal_force: 2.0,
            force: DVec3::new(2.0, 0.5, 0.0),
            overlap,
            history: ContactHistory {
                touched: true,
                tangential: DVec3::new(0.0, 1e-6, 0.0),
                ..Default::default()
            },
            sliding: true,
        }
    }

    #[test]
    fn lines_run_between_centres_and_to_the_wall_contact_point() {
        let pos = [DVec3::new(0.1, 0.5, 0.5), DVec3::new(0.9, 0.5, 0.5)];
        let net = ContactNetwork {
            lines: vec![
                line(0, Partner::Particle(1), 1e-3),
                line(1, Partner::Wall(0), 0.01),
            ],
            fields: vec![&TANGENTIAL_SPRING],
        };
        let ends = Ends {
            positions: &pos,
            radii: &[0.1, 0.1],
            wall_normals: &[DVec3::NEG_X],
            periodic: [true, false, false],
            domain: (DVec3::ZERO, DVec3::ONE),
        };
        // across the periodic boundary: particle 1's image at x = −0.1
        let (a, b) = ends.of(&net.lines[0]);
        assert!((a - pos[0]).length() < 1e-15 && (b - DVec3::new(-0.1, 0.5, 0.5)).length() < 1e-12);
        // the wall x = 1 with the normal −x: the contact point 0.09 beyond the centre
        let (_, c) = ends.of(&net.lines[1]);
        assert!((c - DVec3::new(0.99, 0.5, 0.5)).length() < 1e-12, "{c}");
        let doc = vtp(&net, &ends);
        let text = String::from_utf8_lossy(&doc);
        assert!(text.contains(r#"NumberOfPoints="4""#) && text.contains(r#"NumberOfLines="2""#));
        for name in ["normal_force", "overlap", "sliding", "touched", "i"] {
            assert_eq!(read_array(&doc, name).map(|v| v.len()), Some(2), "{name}");
        }
        for name in ["force", "tangential_spring"] {
            assert_eq!(read_array(&doc, name).map(|v| v.len()), Some(6), "{name}");
        }
        assert_eq!(read_array(&doc, "partner"), Some(vec![1.0, -1.0]));
        assert_eq!(read_array(&doc, "offsets"), Some(vec![2.0, 4.0]));
        assert_eq!(read_array(&doc, "delta_max"), None);
    }
}
