//! Luding's twisting friction on a JKR/Hertz contact: the Coulomb load, lever and stiffness
//! the family gives [`crate::model::friction::twisting`] (GPU: `shaders/model/friction/twisting.wgsl`).

use super::JkrParams;
use crate::model::friction;
use crate::model::{Kinematics, NormalForce, PairGeometry};
use glam::DVec3;

impl JkrParams {
    /// The twisting stiffness at contact radius `a`: the given k_o, or (k_o = 0, the default)
    /// 2/5 of the Mindlin tangential stiffness 8G*·a, N/m. Luding's k_o = 2/5·k scaling of the
    /// normal stiffness k, with the tangential stiffness 8G*a (= 0.82·2E*a, the Hertz normal
    /// tangent stiffness, for ν = 0.3) standing in for k: the twisting oscillator then has
    /// about the normal period for two equal spheres.
    pub fn twisting_stiffness(&self, a: f64) -> f64 {
        let k = self.luding.twisting.k;
        if k > 0.0 {
            k
        } else {
            crate::model::friction::ROTATIONAL_SHARE * 8.0 * self.g_star() * a
        }
    }

    /// Luding's twisting resistance of a JKR/Hertz contact over a step: the couple on i
    /// (−it on j) and the spring's energy ½·k_o·ξ_o². The Coulomb load is |F_el + 2Fc| as for
    /// the sliding friction (paper 002 eq. 17), the lever a12 = 2R*, the stiffness
    /// [`Self::twisting_stiffness`] at the current contact radius. Acts while the contact
    /// exists (also in a stretched neck at δ < 0, as the sliding friction); the spring is
    /// forgotten with the history at pull-off.
    pub fn twisting(
        &self,
        k: &Kinematics,
        normal: &NormalForce,
        geom: &PairGeometry,
        dt: f64,
        twist: &mut f64,
    ) -> (DVec3, f64) {
        let load = (normal.conservative + 2.0 * self.fc(geom.r_eff())).abs();
        let ko = self.twisting_stiffness(normal.contact_radius);
        if ko <= 0.0 {
            *twist = 0.0;
            return (DVec3::ZERO, 0.0);
        }
        let (couple, st) = friction::twisting::step(
            &self.luding.twisting,
            ko,
            k.n,
            k.omega_rel,
            geom.a12,
            load,
            dt,
            twist,
        );
        (couple, 0.5 * ko * st.spring * st.spring)
    }

    /// The twisting oscillator for the time step, with the stiffness at the largest contact
    /// radius: the Hertz one at impact speed `v`, or a0 if larger (JKR).
    pub fn twisting_oscillator(&self, geom: &PairGeometry, v: f64) -> Option<friction::Oscillator> {
        if !self.luding.twisting.is_on() {
            return None;
        }
        let r = geom.r_eff();
        let delta = crate::model::analytic::hertz_delta_max(geom.reduced_mass, r, self.e_star(), v);
        let hertz = (r * delta).sqrt();
        let a = if self.gamma() > 0.0 {
            hertz.max(self.a0(r))
        } else {
            hertz
        };
        Some(friction::Oscillator {
            k: self.twisting_stiffness(a),
            mass: geom.rotational_mass,
            gamma: self.luding.twisting.gamma,
            what: "twisting",
        })
    }
}
