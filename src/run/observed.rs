//! The energies a run observes: the parts every run knows from the state (kinetic,
//! gravitational, what inserted particles brought) and the parts only an energy ledger
//! knows (stored, dissipated, the work of moving walls). A GPU run without the ledger
//! (`powder run --no-ledger`) leaves the latter absent, never zero: a zero would read as a
//! measured value.

use crate::cpu::Energies;
use serde::{Deserialize, Serialize};

/// Energies of the whole system at one instant, J; `None` where the run keeps no ledger.
/// Serialised like [`Energies`], with the absent parts left out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ObservedEnergies {
    /// Translational plus rotational kinetic energy (from the velocities).
    pub kinetic: f64,
    /// Stored in contacts (recoverable elastic energy plus the adhesion potential).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elastic: Option<f64>,
    /// −Σ m·g·x (from the positions).
    pub gravitational: f64,
    /// Dissipated so far (plastic, adhesive hysteresis, viscous).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dissipated: Option<f64>,
    /// Work done on the particles by moving walls so far.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_work: Option<f64>,
    /// Kinetic + gravitational energy brought in by particles inserted so far (pouring).
    pub inserted: f64,
}

impl ObservedEnergies {
    /// The first term that is not finite (NaN or beyond f64's range), by name, with its value.
    pub fn non_finite(&self) -> Option<(&'static str, f64)> {
        [
            ("kinetic", Some(self.kinetic)),
            ("stored elastic", self.elastic),
            ("gravitational", Some(self.gravitational)),
            ("dissipated", self.dissipated),
            ("wall work", self.wall_work),
            ("inserted", Some(self.inserted)),
        ]
        .into_iter()
        .find_map(|(name, v)| v.filter(|v| !v.is_finite()).map(|v| (name, v)))
    }

    /// The sum of the terms' magnitudes, J: what the total's rounding scales with.
    pub fn magnitude(&self) -> f64 {
        self.kinetic.abs()
            + self.elastic.unwrap_or(0.0).abs()
            + self.gravitational.abs()
            + self.dissipated.unwrap_or(0.0).abs()
            + self.wall_work.unwrap_or(0.0).abs()
            + self.inserted.abs()
    }

    /// The complete ledger, when every part is known.
    pub fn ledger(&self) -> Option<Energies> {
        Some(Energies {
            kinetic: self.kinetic,
            elastic: self.elastic?,
            gravitational: self.gravitational,
            dissipated: self.dissipated?,
            wall_work: self.wall_work?,
            inserted: self.inserted,
        })
    }

    /// The conserved sum ([`Energies::total`]); `None` without the ledger.
    pub fn total(&self) -> Option<f64> {
        self.ledger().map(|e| e.total())
    }
}

impl From<Energies> for ObservedEnergies {
    fn from(e: Energies) -> Self {
        Self {
            kinetic: e.kinetic,
            elastic: Some(e.elastic),
            gravitational: e.gravitational,
            dissipated: Some(e.dissipated),
            wall_work: Some(e.wall_work),
            inserted: e.inserted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_ledger_round_trips_and_totals() {
        let e = Energies {
            kinetic: 1.0,
            elastic: 2.0,
            gravitational: 3.0,
            dissipated: 4.0,
            wall_work: 0.5,
            inserted: 0.25,
        };
        let o = ObservedEnergies::from(e);
        assert_eq!(o.ledger(), Some(e));
        assert_eq!(o.total(), Some(e.total()));
        assert_eq!(
            serde_json::to_value(o).unwrap(),
            serde_json::to_value(e).unwrap(),
            "the same JSON as the ledger's"
        );
    }

    #[test]
    fn without_the_ledger_the_unknown_parts_are_absent() {
        let o = ObservedEnergies {
            kinetic: 1.0,
            gravitational: -2.0,
            ..Default::default()
        };
        assert_eq!(o.total(), None);
        let v = serde_json::to_value(o).unwrap();
        for key in ["elastic", "dissipated", "wall_work"] {
            assert!(v.get(key).is_none(), "{key} in {v}");
        }
        assert_eq!(v["kinetic"], 1.0);
        assert_eq!(v["gravitational"], -2.0);
    }
}
