//! The impulse velocity Verlet misplaces when a contact's normal force jumps inside a step
//! (JKR at the touch and at pull-off, jump-in adhesion), and the correction that places it.
//!
//! Verlet counts a jump F_e at θ·dt as ½·F_e·dt where the force delivers (1 − θ)·F_e·dt
//! (switching on; θ·F_e·dt off), an O(dt) error per crossing. The difference to the
//! trapezoid over the part of the step inside the contact (θ linear in time) is added as a
//! velocity impulse at the step's end, leaving O(dt²) and matching what the energy ledger
//! books. Laws without a jump (F_e = 0: Hertz) are left as Verlet has them. Why and what
//! it gains: `docs/force_jumps.md`.

/// Where a contact crossed an edge of its force law within the step: the overlap at the
/// start and at the end of the step, the edge (δ, force just inside) and the force at the
/// end inside the contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// The contact started: the force jumped from 0 to the edge force.
    Entry {
        /// Overlap at the start of the step, m.
        before: f64,
        /// Overlap at the end, m.
        after: f64,
        /// (δ, F) just inside the entry edge, m and N.
        edge: (f64, f64),
        /// Normal force at the end of the step, N.
        force_after: f64,
    },
    /// The contact ended: the force jumped from the edge force to 0.
    Exit {
        /// Overlap at the start of the step, m.
        before: f64,
        /// Overlap at the end, m.
        after: f64,
        /// Normal force at the start of the step, N.
        force_before: f64,
        /// (δ, F) just inside the exit edge, m and N.
        edge: (f64, f64),
    },
}

/// The fraction of the step before the overlap reached `edge`, linear in time, in [0, 1].
fn fraction(before: f64, after: f64, edge: f64) -> f64 {
    let span = after - before;
    if span == 0.0 {
        return 0.5;
    }
    ((edge - before) / span).clamp(0.0, 1.0)
}

/// Whether the overlap passed `edge` between `before` and `after` (in either direction):
/// a contact that appears already inside (an inserted particle) or whose start overlap is
/// only estimated on the wrong side crossed nothing and gets no impulse.
fn passed(before: f64, after: f64, edge: f64) -> bool {
    (before <= edge && edge <= after) || (after <= edge && edge <= before)
}

impl Crossing {
    /// The normal impulse (repulsive positive, on the first particle along n) to add at the
    /// end of a step of length `dt`: what the force delivered minus what velocity Verlet
    /// gave, both trapezoidal over the part of the step inside the contact; 0 without a
    /// jump.
    pub fn impulse(&self, dt: f64) -> f64 {
        match *self {
            Self::Entry {
                before,
                after,
                edge,
                force_after,
            } if edge.1 != 0.0 && passed(before, after, edge.0) => {
                let inside = 1.0 - fraction(before, after, edge.0);
                (inside * 0.5 * (edge.1 + force_after) - 0.5 * force_after) * dt
            }
            Self::Exit {
                before,
                after,
                force_before,
                edge,
            } if edge.1 != 0.0 && passed(before, after, edge.0) => {
                let inside = fraction(before, after, edge.0);
                (inside * 0.5 * (force_before + edge.1) - 0.5 * force_before) * dt
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_force_switched_on_or_off_inside_the_step() {
        let dt = 1e-3;
        // switched on at 30 % of the step (δ from −3 to 7 through 0): F·0.7·dt delivered,
        // Verlet gave F·dt/2
        let entry = Crossing::Entry {
            before: -3.0,
            after: 7.0,
            edge: (0.0, -2.0),
            force_after: -2.0,
        };
        assert!((entry.impulse(dt) - (-2.0 * 0.7 * dt + 2.0 * 0.5 * dt)).abs() < 1e-15);
        // switched off at 30 % (δ from 3 to −7 through 0): F·0.3·dt delivered
        let exit = Crossing::Exit {
            before: 3.0,
            after: -7.0,
            force_before: -2.0,
            edge: (0.0, -2.0),
        };
        assert!((exit.impulse(dt) - (-2.0 * 0.3 * dt + 2.0 * 0.5 * dt)).abs() < 1e-15);
        // at mid-step nothing is misplaced
        let mid = Crossing::Entry {
            before: -1.0,
            after: 1.0,
            edge: (0.0, 5.0),
            force_after: 5.0,
        };
        assert_eq!(mid.impulse(dt), 0.0);
    }

    #[test]
    fn a_force_linear_in_time_is_integrated_exactly_and_no_jump_left_alone() {
        // F = 1 + 4τ/dt on [θ·dt, dt] with δ linear in time: the trapezoid is exact
        let (dt, theta) = (0.5, 0.25);
        let entry = Crossing::Entry {
            before: -1.0,
            after: 3.0,
            edge: (0.0, 1.0 + 4.0 * theta),
            force_after: 5.0,
        };
        let delivered = (1.0 - theta) * dt * (1.0 + 4.0 * theta + 5.0) / 2.0;
        assert!((entry.impulse(dt) - (delivered - 0.5 * 5.0 * dt)).abs() < 1e-15);
        // an edge outside the step's overlaps was not crossed: nothing to place (a particle
        // inserted inside a contact, a start overlap estimated past the edge)
        let outside = Crossing::Exit {
            before: 1.0,
            after: 2.0,
            force_before: 3.0,
            edge: (5.0, 3.0),
        };
        assert_eq!(outside.impulse(dt), 0.0);
        let inserted = Crossing::Entry {
            before: 0.5,
            after: 0.6,
            edge: (0.0, -2.0),
            force_after: -2.0,
        };
        assert_eq!(inserted.impulse(dt), 0.0);
        // no jump (Hertz): velocity Verlet as it is
        let hertz = Crossing::Exit {
            before: 1.0,
            after: -3.0,
            force_before: 7.0,
            edge: (0.0, 0.0),
        };
        assert_eq!(hertz.impulse(dt), 0.0);
    }
}
