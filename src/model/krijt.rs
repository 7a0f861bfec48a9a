//! The Krijt viscoelastic JKR contact (paper 001 §II C, eqs. 10–12 and appendix B) and the
//! stress-dependent relaxation time of Yoshida, Kokubo & Tanaka (paper 001 §V A,
//! eqs. 17–18), in f64. Wired in as the `krijt` and `stress` dissipations of
//! [`crate::model::jkr`]; the conventions are those of that module (δ > 0 overlap,
//! δ̇ approach speed, repulsive force positive, γ per surface so that Fc = 3πγR*).
//!
//! The contact radius a is per-contact state
//! ([`crate::model::ContactHistory::contact_radius`], 0 = unset), not the JKR root a(δ):
//! a_JKR(δ = 0) at the first touch, then moved by the crack speed of eq. B2 with a
//! backward-Euler step ([`advance_radius`]; ȧ is stiff), which never passes the JKR
//! equilibrium, so the crack dissipation 4πa(γ − G_eff)·ȧ is ≥ 0 every step. The stored
//! energy ([`stored_energy`]) has ∂U/∂δ = F_E exactly, so the ledger books the viscous
//! work, the crack dissipation, the touch loss and the neck energy at the break. The
//! derivation and the relaxation times: `docs/models.md`, *Krijt and stress-dependent
//! dissipation*.

use crate::model::analytic;
use crate::model::history::{HistoryField, HostField, Mirror, Shape};
use std::f64::consts::PI;

/// The per-contact history of the Krijt dissipations: the contact radius as state.
pub const HISTORY: &[HistoryField] = &[HistoryField {
    name: "contact_radius",
    shape: Shape::Word,
    mirror: Mirror::Same,
    host: HostField::ContactRadius,
    doc: "the Krijt contact radius a, m (0 = unset)",
}];

/// β below which the crack speed of eq. B2 diverges (ln(0.98/(1 − β)) = 0).
pub const BETA_MIN: f64 = 0.02;
/// β above which the crack speed of eq. B2 diverges (ln(0.98/(1 − 1/β)) = 0).
pub const BETA_MAX: f64 = 50.0;
/// Sub-steps of the crack law in a step of a `crack` contact that ends at negative overlap
/// ([`KrijtLaw::step_neck`]): there the neck recedes and closes, and the first-order
/// crack step's error and the closing time are resolved to dt/16.
pub const NECK_SUBSTEPS: u32 = 16;
/// Bisection iterations of [`advance_radius`] at most (it stops earlier once the bracket
/// is below 1e-13 of a).
pub const BISECTION_ITERATIONS: usize = 64;

/// How the relaxation time T_vis is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relaxation {
    /// A constant T_vis, s.
    Constant {
        /// T_vis, s.
        tvis: f64,
    },
    /// T_vis = C·R·exp[(B·p_c/E*)^ζ] for p_c > 0, C·R otherwise (eqs. 17–18).
    Stress {
        /// C, s/m: T_vis,0 = C·R (eq. 18).
        c: f64,
        /// B, dimensionless (eq. 17).
        b: f64,
        /// ζ > 0, dimensionless (eq. 17).
        zeta: f64,
    },
}

/// The Krijt law of one material pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KrijtLaw {
    /// How T_vis is set.
    pub relaxation: Relaxation,
    /// σ0 ≈ γ/(atomic spacing), Pa; 0 = the contact radius follows the JKR curve instantly.
    pub sigma0: f64,
}

/// The material constants the law needs (after the stiffness scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Effective Young's modulus E* = E/(2(1 − ν²)) after the stiffness scale, Pa.
    pub e_star: f64,
    /// γ per surface, J/m².
    pub gamma: f64,
    /// Poisson's ratio ν (eq. 12 divides by ν²).
    pub poisson: f64,
}

impl KrijtLaw {
    /// T_vis for centre pressure `pc` and pair radius `a12` = 2R*, s.
    pub fn relaxation_time(&self, pc: f64, e_star: f64, a12: f64) -> f64 {
        match self.relaxation {
            Relaxation::Constant { tvis } => tvis,
            Relaxation::Stress { c, b, zeta } => {
                let t0 = c * a12;
                // (C = 0: no viscosity, whatever the pressure)
                if pc > 0.0 && t0 != 0.0 {
                    t0 * (b * pc / e_star).powf(zeta).exp()
                } else {
                    t0
                }
            }
        }
    }

    /// T_vis at contact radius `a` (centre pressure of eq. 9 at a).
    pub fn relaxation_time_at(&self, a: f64, r_eff: f64, m: &Material) -> f64 {
        match self.relaxation {
            Relaxation::Constant { tvis } => tvis,
            Relaxation::Stress { .. } => {
                let pc = analytic::jkr_centre_pressure(a, r_eff, m.e_star, m.gamma);
                self.relaxation_time(pc, m.e_star, 2.0 * r_eff)
            }
        }
    }

    /// v_c = 2E*γ/(σ0²·T_vis), m/s, the speed scale of eq. B2; infinite for σ0 = 0 or
    /// T_vis = 0 (no delay).
    pub fn crack_speed_scale(&self, tvis: f64, m: &Material) -> f64 {
        let den = self.sigma0 * self.sigma0 * tvis;
        if den > 0.0 {
            2.0 * m.e_star * m.gamma / den
        } else {
            f64::INFINITY
        }
    }

    /// One step of the contact radius: from `a_old` to the backward-Euler solution at
    /// overlap `delta` ([`advance_radius`]). `a_eq` is the JKR root a(δ).
    pub fn step_radius(
        &self,
        a_old: f64,
        a_eq: f64,
        delta: f64,
        dt: f64,
        r_eff: f64,
        m: &Material,
    ) -> f64 {
        let vc_dt = self.crack_travel(a_old, dt, r_eff, m);
        advance_radius(a_old, a_eq, vc_dt, |a| {
            energy_release_ratio(a, delta, r_eff, m.e_star, m.gamma)
        })
    }

    /// [`Self::step_radius`] where the crack may close the contact (`pulloff = "crack"`):
    /// `a_eq` is None beyond the JKR turning point, where no root exists. A crack that
    /// recedes with no equilibrium below `a_old` takes [`recede_radius`]'s step; 0 = the
    /// contact has broken.
    pub fn step_radius_to_zero(
        &self,
        a_old: f64,
        a_eq: Option<f64>,
        delta: f64,
        dt: f64,
        r_eff: f64,
        m: &Material,
    ) -> f64 {
        let beta = |a: f64| energy_release_ratio(a, delta, r_eff, m.e_star, m.gamma);
        match a_eq {
            Some(a_eq) if a_eq <= a_old || beta(a_old) <= 1.0 => {
                self.step_radius(a_old, a_eq, delta, dt, r_eff, m)
            }
            _ => {
                let vc_dt = self.crack_travel(a_old, dt, r_eff, m);
                recede_radius(a_old, least_release_radius(delta, r_eff), vc_dt, beta)
            }
        }
    }

    /// [`Self::step_radius_to_zero`] over a step of length `dt` that ends at overlap `delta`,
    /// in [`NECK_SUBSTEPS`] sub-steps along an overlap linear in time (from
    /// delta − delta_dot·dt); `a_eq` gives the JKR root at an overlap (None beyond the
    /// turning point). Where the neck closes, the sub-step it closes in places it.
    #[allow(clippy::too_many_arguments)]
    pub fn step_neck(
        &self,
        a_old: f64,
        (delta, delta_dot): (f64, f64),
        dt: f64,
        r_eff: f64,
        m: &Material,
        a_eq: impl Fn(f64) -> Option<f64>,
    ) -> NeckStep {
        let n = f64::from(NECK_SUBSTEPS);
        let overlap = |t: f64| delta - delta_dot * dt * (1.0 - t);
        let mut a = a_old;
        for j in 1..=NECK_SUBSTEPS {
            let d = if j == NECK_SUBSTEPS {
                delta
            } else {
                overlap(f64::from(j) / n)
            };
            let next = self.step_radius_to_zero(a, a_eq(d), d, dt / n, r_eff, m);
            if next <= 0.0 {
                // (closed somewhere in sub-step j: its middle, with the radius before it)
                let fraction = (f64::from(j) - 0.5) / n;
                return NeckStep::Closed {
                    fraction,
                    radius: a,
                    overlap: overlap(fraction),
                };
            }
            a = next;
        }
        NeckStep::Open(a)
    }

    /// Whether the contact radius lags the JKR curve at all: σ0 > 0 and a T_vis that is not
    /// 0 everywhere (else v_c is infinite).
    pub fn delays_radius(&self) -> bool {
        let tvis = match self.relaxation {
            Relaxation::Constant { tvis } => tvis,
            Relaxation::Stress { c, .. } => c,
        };
        self.sigma0 > 0.0 && tvis > 0.0
    }

    /// v_c·dt with T_vis at the start of the step (at `a_old`), m; infinite without delay
    /// (a follows the JKR curve instantly), 0 at dt = 0 with a delay (a is kept).
    fn crack_travel(&self, a_old: f64, dt: f64, r_eff: f64, m: &Material) -> f64 {
        let tvis = self.relaxation_time_at(a_old, r_eff, m);
        let vc = self.crack_speed_scale(tvis, m);
        if vc.is_infinite() {
            vc
        } else {
            dt * vc
        }
    }
}

/// How a step of a receding neck ended ([`KrijtLaw::step_neck`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NeckStep {
    /// Still open, with this contact radius at the end of the step, m.
    Open(f64),
    /// Closed within the step.
    Closed {
        /// The fraction of the step at which it closed, in (0, 1).
        fraction: f64,
        /// The contact radius just before, m.
        radius: f64,
        /// The overlap there, m.
        overlap: f64,
    },
}

/// The dimensionless crack speed f(β) = σ0²·T_vis·ȧ/(2E*γ) of eq. B2: +∞ for β ≤ 0.02,
/// −∞ for β ≥ 50, 0 at β = 1.
pub fn crack_speed_shape(beta: f64) -> f64 {
    if beta <= BETA_MIN {
        f64::INFINITY
    } else if beta <= 0.29 {
        0.15 / (beta * (0.98 / (1.0 - beta)).ln())
    } else if beta < 1.0 {
        let x = 1.0 / beta - 1.0;
        (0.1035 * x + 0.3421) * x.powf(1.1160)
    } else if beta == 1.0 {
        0.0
    } else if beta < 3.7 {
        let x = beta - 1.0;
        -(0.2112 * x + 0.3939) * x.powf(1.1403)
    } else if beta < BETA_MAX {
        -0.24 * beta / (0.98 / (1.0 - 1.0 / beta)).ln()
    } else {
        f64::NEG_INFINITY
    }
}

/// G_eff = E*(a² − δR*)²/(4πaR*²) (eq. B1), J/m².
pub fn effective_surface_energy(a: f64, delta: f64, r_eff: f64, e_star: f64) -> f64 {
    let u = a * a - delta * r_eff;
    e_star * u * u / (4.0 * PI * a * r_eff * r_eff)
}

/// The signed ratio β = sgn(a² − δR*)·G_eff/γ (negative where the contact edge is
/// compressed, a² < δR*).
pub fn energy_release_ratio(a: f64, delta: f64, r_eff: f64, e_star: f64, gamma: f64) -> f64 {
    let g = effective_surface_energy(a, delta, r_eff, e_star) / gamma;
    if a * a >= delta * r_eff {
        g
    } else {
        -g
    }
}

/// The contact radius √(−δR*/3) where G_eff is smallest at a negative overlap δ (0 for
/// δ ≥ 0): G_eff grows with a above it (the stable side) and falls with a below it.
pub fn least_release_radius(delta: f64, r_eff: f64) -> f64 {
    (-delta * r_eff / 3.0).max(0.0).sqrt()
}

/// A step of a crack that recedes with no equilibrium below `a_old` (beyond the JKR
/// turning point, or below the unstable root), 0 where it closes: the backward-Euler root
/// above `a_min` ([`least_release_radius`]) where one exists. Else the crack passes a_min
/// within the step; below a_min it speeds up as it recedes (nothing there for an implicit
/// step to damp), so it runs at the slowest speed of its path, f(β) at max(a_min, a_old),
/// a first-order explicit step. `vc_dt` infinite (σ0 = 0): 0 at once.
pub fn recede_radius(a_old: f64, a_min: f64, vc_dt: f64, beta: impl Fn(f64) -> f64) -> f64 {
    if vc_dt.is_infinite() {
        return 0.0;
    }
    if vc_dt <= 0.0 {
        return a_old;
    }
    let slowest = if a_old > a_min {
        let f = crack_speed_shape(beta(a_min));
        if a_min - a_old - vc_dt * f <= 0.0 {
            return advance_radius(a_old, a_min, vc_dt, beta);
        }
        f
    } else {
        crack_speed_shape(beta(a_old))
    };
    (a_old + vc_dt * slowest).max(0.0)
}

/// Backward-Euler step of ȧ = v_c·f(β(a)): the root of a − a_old − `vc_dt`·f(β(a)) between
/// a_old and `a_eq`, by bisection: the equilibrium (where β = 1), or any radius where the
/// residual has the sign opposite to a_old's. `vc_dt` = v_c·dt ≥ 0 (infinite: a_eq).
/// `beta` must increase with a on that interval (the stable JKR branch) for the root to be
/// unique.
pub fn advance_radius(a_old: f64, a_eq: f64, vc_dt: f64, beta: impl Fn(f64) -> f64) -> f64 {
    if vc_dt.is_infinite() || a_old == a_eq {
        return a_eq;
    }
    if vc_dt <= 0.0 {
        return a_old;
    }
    let residual = |a: f64| {
        let f = crack_speed_shape(beta(a));
        if f.is_infinite() {
            // the crack runs at the limiting speed: only the sign matters
            -f
        } else {
            a - a_old - vc_dt * f
        }
    };
    // residual(a_old) = −vc_dt·f(a_old) and residual(a_eq) = a_eq − a_old have opposite
    // signs; keep lo where it is negative
    let (mut lo, mut hi) = if a_old < a_eq {
        (a_old, a_eq)
    } else {
        (a_eq, a_old)
    };
    for _ in 0..BISECTION_ITERATIONS {
        if hi - lo <= 1e-13 * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let r = residual(mid);
        if r == 0.0 {
            return mid;
        }
        // the residual increases with a
        if r < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Elastic force for any contact radius and overlap, F_E = 4E*a³/(3R*) − 2E*a(a²/R* − δ)
/// (eq. 11 with the JKR pressure distribution), repulsive positive.
pub fn elastic_force(a: f64, delta: f64, r_eff: f64, e_star: f64) -> f64 {
    4.0 * e_star * a * a * a / (3.0 * r_eff) - 2.0 * e_star * a * (a * a / r_eff - delta)
}

/// The JKR energy of eq. 7 for any (a, δ): E*a³[(a/R*)²/5 − 2δ/(3R*) + (δ/a)²] − 2πγa²,
/// J (elastic energy plus surface energy; its δ-derivative at fixed a is
/// [`elastic_force`], its a-derivative 4πa(G_eff − γ)).
pub fn stored_energy(a: f64, delta: f64, r_eff: f64, e_star: f64, gamma: f64) -> f64 {
    if a <= 0.0 {
        return 0.0;
    }
    let x = a / r_eff;
    e_star * a * a * a * (0.2 * x * x - 2.0 * delta / (3.0 * r_eff) + (delta / a).powi(2))
        - 2.0 * PI * gamma * a * a
}

/// Dissipative force of eq. 12, (2·T_vis·E*/ν²)·a·δ̇, repulsive positive (it opposes δ̇).
pub fn viscous_force(tvis: f64, a: f64, delta_dot: f64, m: &Material) -> f64 {
    2.0 * tvis * m.e_star / (m.poisson * m.poisson) * a * delta_dot
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    // Paper 001, LJ units, R = 147 (table II): γ = 3.17, E* = 65.5, ν = 0.25.
    const GAMMA: f64 = 3.17;
    const ES: f64 = 65.5;
    const R_EFF: f64 = 73.5;

    fn mat() -> Material {
        Material {
            e_star: ES,
            gamma: GAMMA,
            poisson: 0.25,
        }
    }

    fn a0() -> f64 {
        (9.0 * PI * GAMMA * R_EFF * R_EFF / ES).cbrt()
    }

    /// δ(a) on the JKR curve (paper 001 eq. 5).
    fn jkr_delta(a: f64) -> f64 {
        a * a / R_EFF - 2.0 * (PI * GAMMA * a / ES).sqrt()
    }

    #[test]
    fn crack_speed_shape_is_continuous_and_signed() {
        // the four branches of eq. B2 meet within 1 % at β = 0.29 and 3.7, and are 0 at 1
        let below = crack_speed_shape(0.29);
        let above = crack_speed_shape(0.29 + 1e-12);
        assert_relative_eq!(below, above, max_relative = 1e-2);
        let below = crack_speed_shape(3.7 - 1e-12);
        let above = crack_speed_shape(3.7);
        assert_relative_eq!(below, above, max_relative = 1e-2);
        assert_eq!(crack_speed_shape(1.0), 0.0);
        assert!(crack_speed_shape(1.0 - 1e-9).abs() < 1e-8);
        assert!(crack_speed_shape(1.0 + 1e-9).abs() < 1e-8);
        // sign and monotone decrease over the whole range
        let mut last = f64::INFINITY;
        for i in 1..2000 {
            let b = BETA_MIN * (BETA_MAX / BETA_MIN).powf(i as f64 / 2000.0);
            let f = crack_speed_shape(b);
            assert!(f.is_finite());
            assert_eq!(f > 0.0, b < 1.0, "β = {b}");
            // the eq. B2 branches jump by < 1 % where they meet
            assert!(
                f < last * (1.0 + 1e-2) || f < 0.0,
                "β = {b}: {f} after {last}"
            );
            last = f;
        }
        assert_eq!(crack_speed_shape(0.01), f64::INFINITY);
        assert_eq!(crack_speed_shape(-1.0), f64::INFINITY);
        assert_eq!(crack_speed_shape(60.0), f64::NEG_INFINITY);
    }

    #[test]
    fn equilibrium_and_jkr_limits() {
        for x in [0.35, 0.5, 0.8, 1.0, 1.5, 3.0] {
            let a = x * a0();
            let d = jkr_delta(a);
            // eq. B1 gives γ on the JKR curve, and F_E is the JKR force
            assert_relative_eq!(
                effective_surface_energy(a, d, R_EFF, ES),
                GAMMA,
                max_relative = 1e-12
            );
            let fj =
                4.0 * ES * a.powi(3) / (3.0 * R_EFF) - 4.0 * (PI * GAMMA * ES * a.powi(3)).sqrt();
            assert_relative_eq!(
                elastic_force(a, d, R_EFF, ES),
                fj,
                max_relative = 1e-9,
                epsilon = 1e-9
            );
        }
    }

    #[test]
    fn stored_energy_derivatives() {
        // ∂U/∂δ = F_E and ∂U/∂a = 4πa(G − γ), also off the JKR curve
        for (x, d) in [(0.8, 0.3), (1.2, 2.0), (0.5, -0.5), (1.0, 1.7)] {
            let a = x * a0();
            let h = 1e-6;
            let du_dd = (stored_energy(a, d + h, R_EFF, ES, GAMMA)
                - stored_energy(a, d - h, R_EFF, ES, GAMMA))
                / (2.0 * h);
            assert_relative_eq!(du_dd, elastic_force(a, d, R_EFF, ES), max_relative = 1e-6);
            let ha = 1e-6 * a;
            let du_da = (stored_energy(a + ha, d, R_EFF, ES, GAMMA)
                - stored_energy(a - ha, d, R_EFF, ES, GAMMA))
                / (2.0 * ha);
            let g = effective_surface_energy(a, d, R_EFF, ES);
            assert_relative_eq!(
                du_da,
                4.0 * PI * a * (g - GAMMA),
                max_relative = 1e-5,
                epsilon = 1e-6
            );
        }
    }

    #[test]
    fn backward_euler_relaxes_without_overshoot() {
        let law = KrijtLaw {
            relaxation: Relaxation::Constant { tvis: 0.075 },
            sigma0: GAMMA / 1.09,
        };
        let m = mat();
        let a_eq = a0();
        let delta = jkr_delta(a_eq);
        for start in [0.5, 0.9, 1.1, 1.6] {
            let mut a = start * a_eq;
            let mut gap = (a - a_eq).abs();
            for _ in 0..200 {
                let next = law.step_radius(a, a_eq, delta, 0.01, R_EFF, &m);
                // moves toward the equilibrium, never past it
                assert!((next - a_eq).abs() <= gap * (1.0 + 1e-12));
                assert_eq!(next >= a_eq, a >= a_eq, "overshoot from {start}");
                // the backward-Euler equation holds
                let tvis = 0.075;
                let f = crack_speed_shape(energy_release_ratio(next, delta, R_EFF, ES, GAMMA));
                let vc = law.crack_speed_scale(tvis, &m);
                if f.is_finite() && next != a_eq {
                    assert_relative_eq!(
                        next - a,
                        0.01 * vc * f,
                        max_relative = 1e-6,
                        epsilon = 1e-10 * a_eq
                    );
                }
                gap = (next - a_eq).abs();
                a = next;
            }
            assert!(gap < 0.05 * a_eq, "from {start}: gap {gap}");
        }
        // huge steps: straight to a_eq; σ0 = 0: no delay at all
        let big = law.step_radius(0.5 * a_eq, a_eq, delta, 1e12, R_EFF, &m);
        assert_relative_eq!(big, a_eq, max_relative = 1e-6);
        let instant = KrijtLaw { sigma0: 0.0, ..law };
        assert_eq!(
            instant.step_radius(0.5 * a_eq, a_eq, delta, 1e-9, R_EFF, &m),
            a_eq
        );
        // dt = 0 keeps the radius
        assert_eq!(
            law.step_radius(0.5 * a_eq, a_eq, delta, 0.0, R_EFF, &m),
            0.5 * a_eq
        );
    }

    #[test]
    fn least_release_radius_is_where_g_eff_is_smallest() {
        for d in [-0.5, -0.9, -3.0] {
            let delta = d * a0() * a0() / (3.0 * R_EFF);
            let am = least_release_radius(delta, R_EFF);
            let g = |a: f64| effective_surface_energy(a, delta, R_EFF, ES);
            assert!(g(am) < g(0.99 * am) && g(am) < g(1.01 * am), "d = {d}");
            // (4/3)|d|^(3/2) in units of γ
            assert_relative_eq!(
                g(am) / GAMMA,
                4.0 / 3.0 * (-d).powf(1.5),
                max_relative = 1e-12
            );
        }
        assert_eq!(least_release_radius(0.5, R_EFF), 0.0);
    }

    #[test]
    fn a_receding_crack_closes_at_its_slowest_speed_or_the_implicit_root() {
        // beyond the turning point (δ/δ0 = −1): G_eff > γ at every radius
        let delta = -a0() * a0() / (3.0 * R_EFF);
        let beta = |a: f64| energy_release_ratio(a, delta, R_EFF, ES, GAMMA);
        let am = least_release_radius(delta, R_EFF);
        let a_old = 0.5 * a0();
        assert!(a_old > am && beta(am) > 1.0);
        // a short step: the backward-Euler root on the stable side, below a_old
        let vc_dt = 1e-3 * a0();
        let a = recede_radius(a_old, am, vc_dt, beta);
        assert!(am < a && a < a_old);
        assert_relative_eq!(
            a - a_old,
            vc_dt * crack_speed_shape(beta(a)),
            max_relative = 1e-9
        );
        // a step that passes a_min: the slowest speed of the path, f(β(a_min))
        let vc_dt = 1.35 * (a_old - am) / -crack_speed_shape(beta(am));
        let a = recede_radius(a_old, am, vc_dt, beta);
        assert_relative_eq!(
            a,
            a_old + vc_dt * crack_speed_shape(beta(am)),
            max_relative = 1e-12
        );
        assert!(0.0 < a && a < am);
        // below a_min it speeds up: explicit from a_old, and 0 once it would pass 0
        let low = 0.5 * am;
        let slow = 1e-3 * low;
        assert_relative_eq!(
            recede_radius(low, am, slow, beta),
            low + slow * crack_speed_shape(beta(low)),
            max_relative = 1e-12
        );
        assert_eq!(recede_radius(low, am, 1e3 * a0(), beta), 0.0);
        // no delay closes at once; dt = 0 keeps the radius
        assert_eq!(recede_radius(a_old, am, f64::INFINITY, beta), 0.0);
        assert_eq!(recede_radius(a_old, am, 0.0, beta), a_old);
        // far beyond the turning point β ≥ BETA_MAX everywhere: the crack runs at once
        let far = 1.01 * crate::model::jkr::D_PULLOFF_CRACK * a0() * a0() / (3.0 * R_EFF);
        let beta_far = |a: f64| energy_release_ratio(a, far, R_EFF, ES, GAMMA);
        let am_far = least_release_radius(far, R_EFF);
        assert!(beta_far(am_far) > BETA_MAX);
        assert_eq!(recede_radius(a_old, am_far, 1e-9, beta_far), 0.0);
    }

    #[test]
    fn step_radius_to_zero_recedes_only_without_an_equilibrium_below() {
        let law = KrijtLaw {
            relaxation: Relaxation::Constant { tvis: 0.075 },
            sigma0: 10.0 * GAMMA,
        };
        let m = mat();
        let a_eq = a0();
        let delta = jkr_delta(a_eq);
        // with an equilibrium: the same step as step_radius, from either side
        for start in [0.7, 1.4] {
            let a = start * a_eq;
            assert_eq!(
                law.step_radius_to_zero(a, Some(a_eq), delta, 0.1, R_EFF, &m),
                law.step_radius(a, a_eq, delta, 0.1, R_EFF, &m)
            );
        }
        // below the unstable root (G_eff > γ although a JKR root exists above): recedes
        let d = -0.5 * a0() * a0() / (3.0 * R_EFF);
        let x_eq = crate::model::jkr::JkrParams::jkr(2.0 * 0.9375 * ES, 0.25, GAMMA)
            .contact_radius(d, R_EFF);
        let tiny = 0.01 * a0();
        assert!(energy_release_ratio(tiny, d, R_EFF, ES, GAMMA) > 1.0);
        let next = law.step_radius_to_zero(tiny, Some(x_eq), d, 0.1, R_EFF, &m);
        assert!(next < tiny, "{next}");
        // without an equilibrium (beyond the turning point) it recedes; σ0 = 0 closes
        let past = -a0() * a0() / (3.0 * R_EFF);
        let next = law.step_radius_to_zero(0.5 * a0(), None, past, 0.1, R_EFF, &m);
        assert!(0.0 < next && next < 0.5 * a0());
        let instant = KrijtLaw { sigma0: 0.0, ..law };
        assert_eq!(
            instant.step_radius_to_zero(0.5 * a0(), None, past, 0.1, R_EFF, &m),
            0.0
        );
    }

    #[test]
    fn a_fast_neck_closes_in_the_sub_step_that_passes_the_turning_point() {
        let jkr = crate::model::jkr::JkrParams::jkr(2.0 * 0.9375 * ES, 0.25, GAMMA);
        let d0 = a0() * a0() / (3.0 * R_EFF);
        let a_eq = |d: f64| {
            (d / d0 >= crate::model::jkr::D_PULLOFF_DISPLACEMENT)
                .then(|| jkr.contact_radius(d, R_EFF))
        };
        // one step from −0.80·δ0 to −0.90·δ0, on the JKR curve at its start
        let (start, end, dt) = (-0.8 * d0, -0.9 * d0, 1.0);
        let crossing = (crate::model::jkr::D_PULLOFF_DISPLACEMENT * d0 - start) / (end - start);
        let step = |sigma0: f64| {
            let law = KrijtLaw {
                relaxation: Relaxation::Constant { tvis: 0.075 },
                sigma0,
            };
            let a_old = jkr.contact_radius(start, R_EFF);
            law.step_neck(a_old, (end, (end - start) / dt), dt, R_EFF, &mat(), a_eq)
        };
        // a crack fast enough to follow the JKR curve closes within a sub-step of δc
        match step(0.01) {
            NeckStep::Closed {
                fraction,
                radius,
                overlap,
            } => {
                let sub = 1.0 / f64::from(NECK_SUBSTEPS);
                assert!(
                    crossing < fraction && fraction < crossing + 1.5 * sub,
                    "{fraction} vs {crossing}"
                );
                assert_eq!(overlap, end - (end - start) * (1.0 - fraction));
                // the neck just before: near the turning point's radius (1/6)^(2/3)·a0
                assert_relative_eq!(radius, 6f64.powf(-2.0 / 3.0) * a0(), max_relative = 0.05);
            }
            open => panic!("{open:?}"),
        }
        // the paper's σ0 lingers past δc: the neck closes later, or not in this step
        match step(GAMMA / 1.091) {
            NeckStep::Closed { fraction, .. } => assert!(fraction > crossing + 0.25),
            NeckStep::Open(a) => assert!(a > 0.0),
        }
    }

    #[test]
    fn stress_relaxation_time() {
        let law = KrijtLaw {
            relaxation: Relaxation::Stress {
                c: 2.1e-4,
                b: 6.2,
                zeta: 4.0,
            },
            sigma0: 0.0,
        };
        let a12 = 147.0;
        // p_c <= 0: C·R
        assert_relative_eq!(law.relaxation_time(-1.0, ES, a12), 2.1e-4 * 147.0);
        assert_relative_eq!(law.relaxation_time(0.0, ES, a12), 2.1e-4 * 147.0);
        // C = 0: no viscosity at any pressure (not 0·exp(∞) = NaN)
        let none = KrijtLaw {
            relaxation: Relaxation::Stress {
                c: 0.0,
                b: 100.0,
                zeta: 4.0,
            },
            sigma0: 0.0,
        };
        assert_eq!(none.relaxation_time(ES, ES, a12), 0.0);
        // p_c = 0.2 E*: C·R·exp(1.24⁴)
        assert_relative_eq!(
            law.relaxation_time(0.2 * ES, ES, a12),
            2.1e-4 * 147.0 * (1.24f64.powi(4)).exp(),
            max_relative = 1e-12
        );
        // at the equilibrium a0, p_c from eq. 9
        let m = mat();
        let pc = analytic::jkr_centre_pressure(a0(), R_EFF, ES, GAMMA);
        assert_relative_eq!(
            law.relaxation_time_at(a0(), R_EFF, &m),
            law.relaxation_time(pc, ES, a12),
            max_relative = 1e-15
        );
        // viscous force of eq. 12: 2·T·E*/ν² · a · δ̇
        assert_relative_eq!(
            viscous_force(0.075, 10.0, 0.1, &m),
            2.0 * 0.075 * ES / 0.0625 * 10.0 * 0.1,
            max_relative = 1e-15
        );
    }
}
