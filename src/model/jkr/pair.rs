//! A JKR pair's constants (E*, G*, γ, Fc, a0, δ0, the Tsuji β), derived once per material
//! and effective radius where a force loop meets the same pair contact after contact
//! ([`crate::model::PairConstants`]); bitwise what the parameters' methods give.

use super::{tsuji_beta, Dissipation, JkrParams, Scales};

/// The constants of one pair of a JKR material and effective radius R*.
#[derive(Clone, Copy, Debug)]
pub struct JkrPair {
    /// E*, G* and γ after the stiffness scale.
    pub(super) es: f64,
    pub(super) gs: f64,
    pub(super) gamma: f64,
    /// Pull-off force 3πγR*.
    pub(super) fc: f64,
    /// a0 and δ0.
    pub(super) scales: Scales,
    /// The Tsuji damping ratio β (0 without Tsuji damping).
    pub(super) beta: f64,
}

impl JkrParams {
    /// The constants of a pair of effective radius `r_eff`.
    pub fn pair(&self, r_eff: f64) -> JkrPair {
        let (es, gamma) = (self.e_star(), self.gamma());
        JkrPair {
            es,
            gs: self.g_star(),
            gamma,
            fc: self.fc(r_eff),
            scales: Scales::new(r_eff, es, gamma),
            beta: match self.dissipation {
                Dissipation::Tsuji { restitution, .. } => tsuji_beta(restitution),
                _ => 0.0,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pair_constants_are_the_methods_bits() {
        let mut p = JkrParams::jkr(1e8, 0.3, 0.01);
        p.dissipation = Dissipation::tsuji(0.5);
        for (scale, r) in [(1.0, 2.5e-6), (0.01, 2.5e-6), (0.01, 4e-6)] {
            p.stiffness_scale = scale;
            let c = p.pair(r);
            assert_eq!(c.es.to_bits(), p.e_star().to_bits());
            assert_eq!(c.gs.to_bits(), p.g_star().to_bits());
            assert_eq!(c.gamma.to_bits(), p.gamma().to_bits());
            assert_eq!(c.fc.to_bits(), p.fc(r).to_bits());
            assert_eq!(c.scales.a0.to_bits(), p.a0(r).to_bits());
            assert_eq!(c.scales.d0.to_bits(), p.delta0(r).to_bits());
            assert_eq!(c.beta.to_bits(), tsuji_beta(0.5).to_bits());
        }
        assert_eq!(JkrParams::jkr(1e8, 0.3, 0.01).pair(1e-6).beta, 0.0);
    }
}
