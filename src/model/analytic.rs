//! Closed forms from the papers, the yardstick for the simulations.
//!
//! Equation numbers refer to paper 000 (Singh, Magnanimo, Luding, long version) unless
//! marked otherwise. η = (kp − k1)/k1 is the plasticity, β = kc/k1 the adhesivity and
//! χ = δmax/δmax^p the scaled impact velocity (= v/vp without fa).

use crate::model::hysteretic::{AdhesionMode, HystereticParams};
use crate::model::ContactModel;
use std::f64::consts::PI;

/// Plasticity η = (kp − k1)/k1 (eq. 27a).
pub fn plasticity(k1: f64, kp: f64) -> f64 {
    (kp - k1) / k1
}

/// Adhesivity β = kc/k1 (eq. 27b).
pub fn adhesivity(k1: f64, kc: f64) -> f64 {
    kc / k1
}

/// e_n^(1)² for χ ≤ 1 without fa (eq. 32, squared); ≤ 0 means the pair sticks.
pub fn en1_squared(eta: f64, beta: f64, chi: f64) -> f64 {
    let a = 1.0 + eta * chi;
    1.0 / a - beta * eta * eta * chi * chi / (a * (1.0 + beta + eta * chi))
}

/// e_n^(2)² for χ ≥ 1 without fa (eq. 33, squared); ≤ 0 means the pair sticks.
pub fn en2_squared(eta: f64, beta: f64, chi: f64) -> f64 {
    1.0 - (1.0 - en1_squared(eta, beta, 1.0)) / (chi * chi)
}

/// Coefficient of restitution without fa and without viscosity (eqs. 32–33), 0 when stuck.
pub fn en_no_fa(eta: f64, beta: f64, chi: f64) -> f64 {
    let sq = if chi <= 1.0 {
        en1_squared(eta, beta, chi)
    } else {
        en2_squared(eta, beta, chi)
    };
    sq.max(0.0).sqrt()
}

/// Lower end of the sticking regime χc^(b) (eq. 34).
pub fn chi_c_b(eta: f64, beta: f64) -> f64 {
    (1.0 + (1.0 + 4.0 * beta * (1.0 + beta)).sqrt()) / (2.0 * beta * eta)
}

/// Upper end of the sticking regime χc^(c) (eq. 37); meaningful for β ≥ β*.
pub fn chi_c_c(eta: f64, beta: f64) -> f64 {
    (1.0 - en1_squared(eta, beta, 1.0)).sqrt()
}

/// Minimal adhesivity for sticking β* = 1/(η − 1) (eq. 40b).
pub fn beta_star(eta: f64) -> f64 {
    1.0 / (eta - 1.0)
}

/// Sticking overlap δc/δmax^p for χc^(b) ≤ χ ≤ 1 (eq. 36) and 1 ≤ χ ≤ χc^(c) (eq. 38);
/// `None` where the pair does not stick.
pub fn sticking_overlap(eta: f64, beta: f64, chi: f64) -> Option<f64> {
    let sq = if chi <= 1.0 {
        en1_squared(eta, beta, chi)
    } else {
        en2_squared(eta, beta, chi)
    };
    if sq > 0.0 || beta <= 0.0 {
        None
    } else {
        Some(chi * (-sq / beta).sqrt())
    }
}

/// Largest sticking overlap, at χ = 1 (eq. 39).
pub fn sticking_overlap_at_limit(eta: f64, beta: f64) -> f64 {
    ((beta * eta * eta - (1.0 + eta + beta)) / (beta * (1.0 + eta) * (1.0 + eta + beta))).sqrt()
}

/// Low-velocity approximation e_n ≈ 1 − ηχ/2 (paper 000 §5.1).
pub fn en_low_velocity(eta: f64, chi: f64) -> f64 {
    1.0 - 0.5 * eta * chi
}

/// Asymptote for kc = 0 and ηχ ≫ 1: e_n ≈ (ηχ)^(−1/2) (eq. C.2).
pub fn en_asymptote_no_adhesion(eta: f64, chi: f64) -> f64 {
    (eta * chi).powf(-0.5)
}

/// Asymptote for small β and ηχ ≫ β: e_n ≈ √(1/(ηχ) − β) (eq. C.3).
pub fn en_asymptote_weak_adhesion(eta: f64, beta: f64, chi: f64) -> f64 {
    (1.0 / (eta * chi) - beta).max(0.0).sqrt()
}

/// Walton–Braun-type form for kc = 0: e_n = 1/√(1 + S·v/ω0) with S = (kp − k1)/(k1·δmax^p)
/// and ω0 = √(k1/m_r) (eq. C.1c).
pub fn en_walton_braun_plastic(s: f64, v: f64, omega0: f64) -> f64 {
    1.0 / (1.0 + s * v / omega0).sqrt()
}

/// √-rule asymptote for kc = 0 and large ηχ: e_n ≈ (η·√χ)^(−1/2) (eq. D.2).
pub fn en_asymptote_sqrt_rule(eta: f64, chi: f64) -> f64 {
    (eta * chi.sqrt()).powf(-0.5)
}

/// Walton–Braun restitution with constant unloading stiffness, e = √(k1/k2) (eq. 6).
pub fn walton_braun(k1: f64, k2: f64) -> f64 {
    (k1 / k2).sqrt()
}

/// LSD contact duration tc = π/ω, ω = √(k/m_r − η0²), η0 = γ0/(2m_r) (eq. 3);
/// `None` when the oscillator is over-damped.
pub fn lsd_contact_time(k: f64, gamma0: f64, reduced_mass: f64) -> Option<f64> {
    let eta0 = gamma0 / (2.0 * reduced_mass);
    let wsq = k / reduced_mass - eta0 * eta0;
    (wsq > 0.0).then(|| PI / wsq.sqrt())
}

/// LSD restitution e = exp(−η0·tc) (eq. 4); `None` when over-damped.
pub fn lsd_restitution(k: f64, gamma0: f64, reduced_mass: f64) -> Option<f64> {
    let eta0 = gamma0 / (2.0 * reduced_mass);
    lsd_contact_time(k, gamma0, reduced_mass).map(|tc| (-eta0 * tc).exp())
}

/// Dimensionless restitution with fa (eqs. 30–31) in terms of η, β, the non-contact
/// adhesivity α = √(Ea/Ei) and the inverse impact velocity ψ = √(Ep/Ei) (eq. 27).
/// Returns (e_n², χ) with χ = (√(1+α²) + α)/ψ (eq. 28a).
pub fn en_squared_dimensionless(eta: f64, beta: f64, alpha: f64, psi: f64) -> (f64, f64) {
    let chi = ((1.0 + alpha * alpha).sqrt() + alpha) / psi;
    let sq = if chi < 1.0 {
        let a = 1.0 + eta * chi;
        (1.0 / a - beta * eta * eta * chi * chi / (a * (1.0 + beta + eta * chi)))
            * psi
            * psi
            * chi
            * chi
            - 2.0 * alpha * psi * chi
    } else {
        1.0 - (1.0 - 1.0 / (1.0 + eta) + beta * eta * eta / ((1.0 + eta) * (1.0 + beta + eta)))
            * psi
            * psi
    };
    (sq, chi)
}

/// Dimensionless impact velocity ζ = vi/vp = 1/√(ψ² − 2αψ) (eq. 28b).
pub fn zeta(alpha: f64, psi: f64) -> f64 {
    1.0 / (psi * psi - 2.0 * alpha * psi).sqrt()
}

/// The full closed-form prediction for one head-on collision of the hysteretic model
/// (paper 000 eqs. 16–25), viscosity excluded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HystereticPrediction {
    /// Total restitution e = εo·en·εi (0 when stuck).
    pub e: f64,
    /// Contact restitution e_n (eq. 22 or 24).
    pub en: f64,
    /// Pull-in restitution εi (eq. 17b; 1 for jump-in).
    pub eps_i: f64,
    /// Pull-off restitution εo (eq. 18b).
    pub eps_o: f64,
    /// Whether the pair sticks (e = 0): the energy left after unloading is not enough to
    /// leave the contact or the non-contact adhesive well.
    pub stuck: bool,
    /// Largest overlap (eq. 20b, or on the limit branch for v ≥ vp).
    pub delta_max: f64,
    /// χ = δmax/δmax^p (eq. 28a) with δmax of the k1 branch (eq. 20b): v/vp without fa,
    /// also beyond the limit.
    pub chi: f64,
    /// Plastic limit velocity (eq. 19).
    pub v_p: f64,
    /// Energy dissipated in contact, J.
    pub dissipated: f64,
}

/// Predicts the outcome of a head-on collision with approach speed `v_inf` (from beyond
/// the interaction range), reduced radius `a12` and reduced mass `mr`.
/// Returns `None` where no closed form applies (viscous damping, γ0 > 0).
pub fn hysteretic_collision(
    p: &HystereticParams,
    a12: f64,
    mr: f64,
    v_inf: f64,
) -> Option<HystereticPrediction> {
    if p.gamma0 > 0.0 {
        return None;
    }
    let (k1, kp, kc, fa) = (p.k1, p.kp, p.kc, p.fa);
    let well = if p.kca.is_finite() {
        fa * fa / p.kca
    } else {
        0.0
    };
    let eps_i = match p.adhesion {
        AdhesionMode::Reversible => (1.0 + well / (mr * v_inf * v_inf)).sqrt(),
        AdhesionMode::JumpIn => 1.0,
    };
    let vi = eps_i * v_inf;
    let ei = 0.5 * mr * vi * vi;
    let dp = p.delta_max_p(a12);
    let vp_sq = if dp.is_finite() {
        dp * (k1 * dp - 2.0 * fa) / mr
    } else {
        f64::INFINITY
    };
    let loop_factor = |k2: f64| 1.0 - k1 / k2 + kc * (k2 - k1).powi(2) / (k1 * k2 * (k2 + kc));
    // δmax reached along k1 (eq. 20b); its ratio to δmax^p is χ (eq. 28a) in both regimes.
    let dmax_k1 = (fa + (fa * fa + k1 * mr * vi * vi).sqrt()) / k1;
    let (delta_max, dissipated) = if vi * vi < vp_sq {
        // eq. 21
        let dmax = dmax_k1;
        let k2 = p.k2(dmax, a12);
        (dmax, loop_factor(k2) * 0.5 * k1 * dmax * dmax)
    } else {
        // eq. 23: kinetic energy left at δmax^p loads the limit branch kp(δ − δ0^p) − fa.
        let ke1 = ei - 0.5 * dp * (k1 * dp - 2.0 * fa);
        let u0 = dp - p.delta0_p(a12);
        let c = 2.0 * ke1 + kp * u0 * u0 - 2.0 * fa * u0;
        let u = (fa + (fa * fa + kp * c).sqrt()) / kp;
        (p.delta0_p(a12) + u, loop_factor(kp) * 0.5 * k1 * dp * dp)
    };
    let ef = ei - dissipated;
    let chi = dmax_k1 / dp;
    let stuck_prediction = |en: f64| HystereticPrediction {
        e: 0.0,
        en,
        eps_i,
        eps_o: 0.0,
        stuck: true,
        delta_max,
        chi,
        v_p: vp_sq.sqrt(),
        dissipated,
    };
    if ef <= 0.0 {
        return Some(stuck_prediction(0.0));
    }
    let en = (ef / ei).sqrt();
    let vf = en * vi;
    let eps_o_sq = 1.0 - well / (mr * vf * vf);
    if eps_o_sq <= 0.0 {
        return Some(stuck_prediction(en));
    }
    let eps_o = eps_o_sq.sqrt();
    Some(HystereticPrediction {
        e: eps_o * en * eps_i,
        en,
        eps_i,
        eps_o,
        stuck: false,
        delta_max,
        chi,
        v_p: vp_sq.sqrt(),
        dissipated,
    })
}

/// Impact speed that reaches χ (without fa): v = χ·vp, vp = √(k1/m_r)·δmax^p (eq. 13).
pub fn velocity_for_chi(p: &HystereticParams, a12: f64, mr: f64, chi: f64) -> f64 {
    chi * (p.k1 / mr).sqrt() * p.delta_max_p(a12)
}

/// Appendix A: the limit stiffness kp′ that keeps the collisions below the old plastic
/// limit unchanged when the plasticity depth goes from φf to φf′ (eq. A.3):
/// kp′ = k1 + AB/2 + √((AB/2)² + k1·AB), A = (kp − k1)²/kp, B = φf′/φf, the root of
/// eq. A.2, (kp − k1)²/(kp·φf) = (kp′ − k1)²/(kp′·φf′).
pub fn tuned_limit_stiffness(k1: f64, kp: f64, phi_f: f64, phi_f_new: f64) -> f64 {
    let a = (kp - k1).powi(2) / kp;
    let ab2 = 0.5 * a * phi_f_new / phi_f;
    k1 + ab2 + (ab2 * ab2 + 2.0 * k1 * ab2).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn limits_are_consistent() {
        let (eta, beta) = (4.0, 1.0);
        assert_relative_eq!(
            en1_squared(eta, beta, chi_c_b(eta, beta)),
            0.0,
            epsilon = 1e-12
        );
        assert_relative_eq!(
            en2_squared(eta, beta, chi_c_c(eta, beta)),
            0.0,
            epsilon = 1e-12
        );
        // eq. 39 is eq. 36 at χ = 1; the paper's fig. 8 value for η = 4, β = 1 is √(1/3)
        assert_relative_eq!(
            sticking_overlap(eta, beta, 1.0).unwrap(),
            sticking_overlap_at_limit(eta, beta),
            epsilon = 1e-12
        );
        assert_relative_eq!(
            sticking_overlap_at_limit(eta, beta),
            (1.0f64 / 3.0).sqrt(),
            epsilon = 1e-12
        );
        // at β* the sticking regime shrinks to χ = 1
        let bs = beta_star(eta);
        assert_relative_eq!(en1_squared(eta, bs, 1.0), 0.0, epsilon = 1e-12);
        assert_relative_eq!(chi_c_b(eta, bs), 1.0, epsilon = 1e-12);
        assert_relative_eq!(chi_c_c(eta, bs), 1.0, epsilon = 1e-12);
        // continuity at χ = 1
        assert_relative_eq!(
            en1_squared(eta, 0.1, 1.0),
            en2_squared(eta, 0.1, 1.0),
            epsilon = 1e-14
        );
    }

    /// Eq. D.2 against the model's √-rule k2 (eq. D.1): without adhesion e_n = √(k1/k2)
    /// (eq. 6) at δmax = χ·δmax^p, which the asymptote approaches for ηχ ≫ 1.
    #[test]
    fn the_sqrt_rule_asymptote_approaches_the_models_restitution() {
        let eta = 500.0;
        let p = HystereticParams {
            kp: (1.0 + eta) * 100.0,
            k1: 100.0,
            kc: 0.0,
            k2_rule: crate::model::K2Rule::Sqrt,
            ..HystereticParams::paper_figure()
        };
        let a12 = 1e-3;
        for chi in [0.2, 0.5, 0.9] {
            let en = walton_braun(p.k1, p.k2(chi * p.delta_max_p(a12), a12));
            assert_relative_eq!(en, en_asymptote_sqrt_rule(eta, chi), max_relative = 3e-3);
        }
    }

    #[test]
    fn asymptotes_approach_the_full_form() {
        let eta = 500.0;
        let chi = 0.5;
        let full = en_no_fa(eta, 0.0, chi);
        assert_relative_eq!(
            full,
            en_asymptote_no_adhesion(eta, chi),
            max_relative = 3e-3
        );
        let full = en_no_fa(eta, 1e-4, chi);
        assert_relative_eq!(
            full,
            en_asymptote_weak_adhesion(eta, 1e-4, chi),
            max_relative = 1e-2
        );
        assert_relative_eq!(
            en_no_fa(4.0, 0.0, 1e-4),
            en_low_velocity(4.0, 1e-4),
            max_relative = 1e-7
        );
    }

    #[test]
    fn dimensional_prediction_matches_dimensionless_forms() {
        let a12: f64 = 1.1e-3;
        let mr = 0.5 * 2000.0 * 4.0 / 3.0 * PI * a12.powi(3);
        for fa in [0.0, 5e-7, 5e-6] {
            let p = HystereticParams {
                fa,
                ..HystereticParams::paper_figure()
            };
            for v in [1e-3, 1e-2, 3e-2, 0.1] {
                let pred = hysteretic_collision(&p, a12, mr, v).unwrap();
                let ei = 0.5 * mr * v * v;
                let alpha = (0.5 * fa * fa / p.k1 / ei).sqrt();
                let dp = p.delta_max_p(a12);
                let psi = (0.5 * p.k1 * dp * dp / ei).sqrt();
                let (sq, chi) = en_squared_dimensionless(4.0, 1.0, alpha, psi);
                assert_relative_eq!(chi, pred.chi, max_relative = 1e-9);
                if !pred.stuck {
                    assert_relative_eq!(sq.sqrt(), pred.en, max_relative = 1e-9);
                } else {
                    assert!(sq <= 1e-12);
                }
                if fa == 0.0 {
                    assert_relative_eq!(pred.e, en_no_fa(4.0, 1.0, v / pred.v_p), epsilon = 1e-12);
                }
            }
        }
    }

    #[test]
    fn appendix_a_tuned_limit_stiffness() {
        // paper 000 fig. 9: k1 = 100, kp = 500, φf = 0.05 → φf′ = 0.5. By hand: A = 400²/500
        // = 320, B = 10, AB/2 = 1600, kp′ = 100 + 1600 + √(1600² + 100·3200) = 1700 + √2.88e6
        let kp2 = tuned_limit_stiffness(100.0, 500.0, 0.05, 0.5);
        assert_relative_eq!(kp2, 3397.056274847714, max_relative = 1e-14);
        // eq. A.2: (kp − k1)²/(kp·φf) = 6400 = (kp′ − k1)²/(kp′·φf′)
        assert_relative_eq!(
            (kp2 - 100.0).powi(2) / (kp2 * 0.5),
            6400.0,
            max_relative = 1e-12
        );
        // eq. A.1: the new k2 at the old limit overlap is the old kp
        let (dp_old, dp_new) = (500.0 / 400.0 * 0.05, kp2 / (kp2 - 100.0) * 0.5);
        assert_relative_eq!(
            100.0 + (kp2 - 100.0) * dp_old / dp_new,
            500.0,
            max_relative = 1e-12
        );
        // φf′ = φf keeps kp; the method of HystereticParams gives the same
        assert_relative_eq!(tuned_limit_stiffness(100.0, 500.0, 0.05, 0.05), 500.0);
        assert_relative_eq!(
            HystereticParams::paper_figure().kp_for_phi_f(0.5).unwrap(),
            kp2,
            max_relative = 1e-14
        );
    }

    #[test]
    fn lsd_and_walton_braun() {
        let e = lsd_restitution(1000.0, 0.0, 1e-3).unwrap();
        assert_relative_eq!(e, 1.0);
        let tc = lsd_contact_time(1000.0, 0.0, 1e-3).unwrap();
        assert_relative_eq!(tc, PI * (1e-3f64 / 1000.0).sqrt());
        assert!(lsd_restitution(1.0, 10.0, 1e-3).is_none());
        assert_relative_eq!(walton_braun(100.0, 400.0), 0.5);
    }

    #[test]
    fn appendix_c_walton_braun_form_is_eq_32_for_kc_zero() {
        let p = HystereticParams {
            kc: 0.0,
            ..HystereticParams::paper_figure()
        };
        let a12 = 1e-3;
        let mr = 1e-5;
        let dp = p.delta_max_p(a12);
        let s = (p.kp - p.k1) / (p.k1 * dp);
        let w0 = (p.k1 / mr).sqrt();
        for v in [1e-3, 1e-2] {
            let chi = v / (w0 * dp);
            assert_relative_eq!(
                en_walton_braun_plastic(s, v, w0),
                en_no_fa(4.0, 0.0, chi),
                max_relative = 1e-12
            );
        }
    }
}

// ---- JKR and Hertz (papers 001, 002) ----
//
// Closed forms for the JKR family of `crate::model::jkr`. Energies in units of Fc·δ0 with
// Fc = 3πγR*, δ0 = a0²/(3R*), a0 = (9πγR*²/E*)^(1/3) (γ per surface).

use crate::model::jkr::{self, Pulloff};

/// Hertz contact time 2.87·(m*²/(R*·E*²·v))^(1/5) for impact speed `v`, s.
pub fn hertz_contact_time(m_eff: f64, r_eff: f64, e_star: f64, v: f64) -> f64 {
    2.87 * (m_eff * m_eff / (r_eff * e_star * e_star * v)).powf(0.2)
}

/// Energy lost in one undamped JKR touch/pull-off cycle, W/(Fc·δ0) = P(x_break) − P(x_touch)
/// with P(x) = (24/5)x⁵ − 8x^(7/2) + 2x², x_touch = (2/3)^(2/3):
/// ≈ 0.7722 for displacement pull-off (x_break = 6^(−2/3); paper 001 quotes ≈ 0.773) and
/// ≈ 0.3814 for force pull-off (x_break = 2^(−2/3)). `crack` without delay (σ0 = 0) breaks
/// at the turning point, as displacement pull-off.
pub fn jkr_loss(pulloff: Pulloff) -> f64 {
    let rule = match pulloff {
        Pulloff::Crack => Pulloff::Displacement,
        other => other,
    };
    jkr::potential_shape(rule.break_radius_ratio()) - jkr::potential_shape(jkr::X_TOUCH)
}

/// Restitution of an undamped JKR collision that loses `w` (J) at reduced mass `m_eff` and
/// impact speed `v`: √(1 − W/(½m*v²)); `None` when the pair sticks (W ≥ ½m*v²).
pub fn jkr_restitution(w: f64, m_eff: f64, v: f64) -> Option<f64> {
    let ke = 0.5 * m_eff * v * v;
    (w < ke).then(|| (1.0 - w / ke).sqrt())
}

/// Largest impact speed at which an undamped JKR pair sticks, √(2W/m*).
pub fn jkr_sticking_velocity(w: f64, m_eff: f64) -> f64 {
    (2.0 * w / m_eff).sqrt()
}

/// Surface energy for a reduced stiffness S = Emod/E: γ·S^(2/5) (paper 002 eq. 24).
pub fn reduced_surface_energy(gamma: f64, s: f64) -> f64 {
    gamma * s.powf(0.4)
}

/// Collision-time factor Δtcol,mod/Δtcol = (E/Emod)^(2/5) = S^(−2/5) (paper 002 §6.2).
pub fn collision_time_factor(s: f64) -> f64 {
    s.powf(-0.4)
}

/// Hertz centre pressure p_c,H = (2E*/π)·√(δ/R*) (paper 001 eq. 4), Pa; 0 for δ ≤ 0.
pub fn hertz_centre_pressure(delta: f64, r_eff: f64, e_star: f64) -> f64 {
    2.0 * e_star / PI * (delta.max(0.0) / r_eff).sqrt()
}

/// JKR centre pressure p_c,J = 2E*a/(πR*) − √(4γE*/(πa)) (paper 001 eq. 9) at contact
/// radius `a` (γ per surface), Pa; negative (tensile) for a small contact.
pub fn jkr_centre_pressure(a: f64, r_eff: f64, e_star: f64, gamma: f64) -> f64 {
    2.0 * e_star * a / (PI * r_eff) - (4.0 * gamma * e_star / (PI * a)).sqrt()
}

/// Tangential restitution e_t = u_t'/u_t of an elastic oblique impact of solid spheres with
/// Luding's sliding friction, k_t = 2/7·k (the tangential oscillator has the normal
/// period) and no damping, at normal approach speed `vn` and tangential contact-point speed
/// `ut` (docs/luding2008_laws.md §6a; sphere–sphere and sphere–wall alike): the spring's
/// ξ(t) = (u_t/ω)·sin ωt is in phase with δ(t), so f_t/f_N = (2/7)·u_t/v_n throughout, and
/// the contact **sticks throughout** iff u_t ≤ 3.5·μs·v_n, and then reverses, e_t = −1;
/// otherwise it slips from the touch, keeps μd while it slips (the `slipping` flag), and
/// **slides throughout** since u_t > 3.5·μd·v_n too: e_t = 1 − 7·μd·v_n/u_t (the rigid-body
/// 1 − 3.5·μd·(1 + e_n)·v_n/u_t with e_n = 1). With μs = μd the branches meet at −1.
pub fn luding_tangential_restitution(mu_s: f64, mu_d: f64, vn: f64, ut: f64) -> f64 {
    if ut <= 3.5 * mu_s * vn {
        -1.0
    } else {
        1.0 - 7.0 * mu_d * vn / ut
    }
}

/// (μs, μd) when [`luding_tangential_restitution`] applies to the model: an elastic
/// hysteretic (k1 = kp, kc = fa = 0, γ0 = 0) or undamped LSD pair with Luding's sliding
/// friction only, k_t = 2/7·k (to 1e-12) and γ_t = 0; `None` otherwise.
pub fn luding_elastic_sliding(model: &ContactModel) -> Option<(f64, f64)> {
    let (k, luding) = match model {
        ContactModel::Hysteretic(p)
            if p.k1 == p.kp && p.kc == 0.0 && p.fa == 0.0 && p.gamma0 == 0.0 =>
        {
            (p.k1, &p.luding)
        }
        ContactModel::Lsd(p) if p.gamma0 == 0.0 => (p.k, &p.luding),
        _ => return None,
    };
    let s = &luding.sliding;
    let kt = crate::model::friction::TANGENTIAL_SHARE * k;
    (s.is_on()
        && (s.k - kt).abs() <= 1e-12 * kt
        && s.gamma == 0.0
        && !luding.rolling.is_on()
        && !luding.twisting.is_on())
    .then_some((s.mu_s, s.mu_d))
}

/// Largest overlap of an undamped Hertz collision, δmax = (15·m*·v²/(16·E*·√R*))^(2/5):
/// ½m*v² = (8/15)E*√R*·δmax^(5/2). For two equal spheres of mass m (m* = m/2) this is
/// paper 001 eq. 15, (15/32·m·v²/(E*·√R*))^(2/5).
pub fn hertz_delta_max(m_eff: f64, r_eff: f64, e_star: f64, v: f64) -> f64 {
    (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4)
}

/// Thornton–Ning restitution of an elastic–perfectly-plastic impact (paper 001 eq. 13):
/// e_TN = (6√3/5)^(1/2)·√(1 − v_Y²/(6v²))·[1 + 2√(6v²/(5v_Y²) − 1/5)]^(−1/4) for
/// v > v_Y, and 1 for v ≤ v_Y (it is continuous there).
pub fn thornton_ning_restitution(v: f64, v_yield: f64) -> f64 {
    if v <= v_yield {
        return 1.0;
    }
    let q = (v_yield / v).powi(2);
    (6.0 * 3f64.sqrt() / 5.0).sqrt()
        * (1.0 - q / 6.0).sqrt()
        * (1.0 + 2.0 * (6.0 / (5.0 * q) - 0.2).sqrt()).powf(-0.25)
}

/// Restitution with the plastic loss added (paper 001 eq. 14):
/// e_pl = √(e² − (1 − e_TN²)); 0 when the plastic loss exceeds what is left (sticking).
pub fn plastic_restitution(e: f64, e_tn: f64) -> f64 {
    (e * e - (1.0 - e_tn * e_tn)).max(0.0).sqrt()
}

/// Yield velocity v_Y of a Hertz impact: the speed whose largest overlap (eq. 15,
/// [`hertz_delta_max`]) brings the centre pressure p_c = (2E*/π)·√(δ/R*) (eq. 4) to 1.6·Y,
/// the onset of plastic flow (paper 001 §IV A 3). Then δ_Y = R*·(0.8πY/E*)² and
/// ½m*v_Y² = (8/15)E*√R*·δ_Y^(5/2). Equal spheres: v_Y² = E*·(0.8πY/E*)⁵/(5πρ), whatever
/// the radius (paper 001: Y = 0.15E* ↔ v_Y ≈ 0.17 in its LJ units).
pub fn yield_velocity(yield_stress: f64, e_star: f64, r_eff: f64, m_eff: f64) -> f64 {
    let delta_y = r_eff * (0.8 * PI * yield_stress / e_star).powi(2);
    (16.0 * e_star * r_eff.sqrt() * delta_y.powf(2.5) / (15.0 * m_eff)).sqrt()
}

// ---- Tabor parameter (paper 002 eq. 1) ----

/// D_min of the Tabor parameter: the minimum atomic separation, "typically taken to be
/// 1.65 Å" (paper 002 below eq. 1), in m. Another unit system needs its own value.
pub const TABOR_MIN_SEPARATION: f64 = 1.65e-10;

/// The JKR range of the Tabor parameter, λT > 3 (paper 002 §1 after Johnson and
/// Greenwood: DMT for λT < 0.1, Maugis–Dugdale for 0.1 ≤ λT ≤ 3).
pub const TABOR_JKR_MIN: f64 = 3.0;

/// Upper end of the DMT range, λT < 0.1 (paper 002 §1).
pub const TABOR_DMT_MAX: f64 = 0.1;

/// Tabor parameter λT = (4R*γ²/(E*²·D_min³))^(1/3) (paper 002 eq. 1), with γ the surface
/// energy per surface (work of adhesion 2γ, so this is (R*w²/(E*²D³))^(1/3)), R* and E*
/// the effective radius and modulus of eq. 2.
pub fn tabor_parameter(r_eff: f64, surface_energy: f64, e_star: f64, d_min: f64) -> f64 {
    (4.0 * r_eff * surface_energy * surface_energy / (e_star * e_star * d_min.powi(3))).cbrt()
}

/// λT of a JKR pair from the material's own E, ν and γ: a stiffness scale S changes the
/// simulated stiffness, not which contact theory describes the material.
pub fn jkr_tabor(p: &jkr::JkrParams, r_eff: f64, d_min: f64) -> f64 {
    tabor_parameter(r_eff, p.surface_energy, p.e_star_unscaled(), d_min)
}

/// The contact theory the Tabor parameter selects (paper 002 §1): "JKR" (λT > 3),
/// "Maugis-Dugdale" (0.1 ≤ λT ≤ 3) or "DMT" (λT < 0.1).
pub fn tabor_regime(tabor: f64) -> &'static str {
    if tabor > TABOR_JKR_MIN {
        "JKR"
    } else if tabor >= TABOR_DMT_MAX {
        "Maugis-Dugdale"
    } else {
        "DMT"
    }
}

/// The warning for a JKR pair below the JKR range, naming the pair (`pair`, e.g. "the
/// pair `a`-`b`"); `None` in range.
pub fn tabor_warning(pair: &str, tabor: f64, d_min: f64) -> Option<String> {
    (tabor <= TABOR_JKR_MIN).then(|| {
        format!(
            "{pair} has Tabor parameter {} (paper 002 eq. 1, D_min = {d_min:e}), below the JKR range (> {TABOR_JKR_MIN}): the {} regime, where the JKR contact law does not hold",
            crate::error::fixed(tabor, 3),
            tabor_regime(tabor)
        )
    })
}

/// The largest equilibrium contact radius a0/R* taken without a warning: JKR, like Hertz,
/// assumes a contact small against the spheres (paper 001's LJ spheres reach 0.27).
pub const JKR_SMALL_CONTACT_MAX: f64 = 0.5;

/// The warning for a JKR pair whose equilibrium contact radius a0 (after the stiffness
/// scale, as simulated) exceeds [`JKR_SMALL_CONTACT_MAX`]·R*, naming the pair; `None`
/// below it.
pub fn small_contact_warning(pair: &str, p: &jkr::JkrParams, r_eff: f64) -> Option<String> {
    let ratio = p.a0(r_eff) / r_eff;
    (p.surface_energy > 0.0 && ratio > JKR_SMALL_CONTACT_MAX).then(|| {
        format!(
            "{pair} has a JKR equilibrium contact radius a0 = {:.4e} m, {ratio:.3}·R*, beyond {JKR_SMALL_CONTACT_MAX}·R*: JKR assumes contacts small against the spheres, so its forces are beyond the theory there (a smaller surface_energy, a stiffer material or a stiffness_scale nearer 1 shrinks a0/R* ∝ (γ/(E*·R*))^(1/3))",
            p.a0(r_eff)
        )
    })
}

#[cfg(test)]
mod jkr_tests {
    use super::*;
    use crate::model::jkr::JkrParams;
    use approx::assert_relative_eq;

    /// a0 = 1.27·R* (5 µm spheres, E = 0.1 GPa, γ = 10 J/m²) is warned, naming the pair
    /// and the ratio; paper 001's LJ spheres (a0 = 0.27·R*) and Hertz are not.
    #[test]
    fn a_contact_large_against_the_spheres_is_warned() {
        let soft = JkrParams::jkr(1e8, 0.3, 10.0);
        let r = 2.5e-6;
        let ratio = soft.a0(r) / r;
        assert!((ratio - 1.27).abs() < 0.01, "{ratio}");
        let w = small_contact_warning("the pair `a`-`b`", &soft, r).unwrap();
        assert!(w.contains("the pair `a`-`b`") && w.contains("1.27"), "{w}");
        let lj = JkrParams::jkr(122.8125, 0.25, 3.17);
        assert!((lj.a0(73.5) / 73.5 - 0.265).abs() < 0.01);
        assert!(small_contact_warning("x", &lj, 73.5).is_none());
        assert!(small_contact_warning("x", &JkrParams::hertz(1e8, 0.3), r).is_none());
    }

    #[test]
    fn jkr_loss_values() {
        assert_relative_eq!(jkr_loss(Pulloff::Displacement), 0.7722, max_relative = 1e-4);
        assert_relative_eq!(
            jkr_loss(Pulloff::Displacement),
            0.7722405328755862,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            jkr_loss(Pulloff::Force),
            0.3813841613953991,
            max_relative = 1e-12
        );
        // the same loss from the model's potential just after the touch (it is −W there)
        let p = JkrParams::jkr(1e9, 0.3, 0.1);
        let r = 1e-5;
        let mut h = crate::model::ContactHistory::default();
        let geom = crate::model::PairGeometry::spheres(2.0 * r, 2.0 * r, 1.0, 1.0);
        let f = p.normal_force(1e-13 * p.delta0(r), 0.0, &geom, &mut h);
        assert_relative_eq!(
            -f.potential / (p.fc(r) * p.delta0(r)),
            jkr_loss(Pulloff::Displacement),
            max_relative = 1e-9
        );
    }

    #[test]
    fn restitution_and_sticking() {
        let (w, m) = (2e-15, 1e-12);
        let vs = jkr_sticking_velocity(w, m);
        assert_relative_eq!(0.5 * m * vs * vs, w, max_relative = 1e-14);
        assert!(jkr_restitution(w, m, 0.99 * vs).is_none());
        assert!(jkr_restitution(w, m, vs).is_none());
        let e = jkr_restitution(w, m, 2.0 * vs).unwrap();
        assert_relative_eq!(e, 0.75f64.sqrt(), max_relative = 1e-14);
        assert!(jkr_restitution(w, m, 1e3 * vs).unwrap() > 0.999_999);
    }

    #[test]
    fn reduced_stiffness_relations() {
        let s = 0.01;
        assert_relative_eq!(reduced_surface_energy(0.1, s), 0.1 * 0.01f64.powf(0.4));
        assert_relative_eq!(
            collision_time_factor(s),
            10f64.powf(0.8),
            max_relative = 1e-14
        );
        assert_eq!(collision_time_factor(1.0), 1.0);
        // γ^(5/3)/E^(2/3) is invariant (paper 002 eq. A.11), hence Fc·δ0 and the loss W
        let (g, e) = (0.1, 1e9);
        let gm = reduced_surface_energy(g, s);
        assert_relative_eq!(
            gm.powf(5.0 / 3.0) / (s * e).powf(2.0 / 3.0),
            g.powf(5.0 / 3.0) / e.powf(2.0 / 3.0),
            max_relative = 1e-12
        );
        // Hertz contact time scales by the same factor at fixed m*, R*, v
        let (m, r, v) = (1e-9, 1e-4, 1.0);
        assert_relative_eq!(
            hertz_contact_time(m, r, s * e, v) / hertz_contact_time(m, r, e, v),
            collision_time_factor(s),
            max_relative = 1e-12
        );
        let p = JkrParams::hertz(e, 0.3);
        assert_relative_eq!(
            hertz_contact_time(m, r, p.e_star(), v),
            p.hertz_contact_time(r, m, v),
            max_relative = 1e-15
        );
    }

    #[test]
    fn tabor_parameter_of_paper_002_eq_1() {
        // E = 1 GPa, ν = 0.3, γ = 0.05 J/m², two 1 µm spheres (R* = 0.5 µm), D = 1.65 Å:
        // E* = 1e9/1.82 = 5.4945e8 Pa, λ³ = 4·5e-7·0.0025/(E*²·4.492125e-30) = 3686.8
        let p = JkrParams::jkr(1e9, 0.3, 0.05);
        let lambda = jkr_tabor(&p, 5e-7, TABOR_MIN_SEPARATION);
        assert_relative_eq!(lambda, 15.448523667638632, max_relative = 1e-12);
        assert_relative_eq!(
            lambda.powi(3),
            5e-9 / ((1e9f64 / 1.82).powi(2) * 4.492125e-30),
            max_relative = 1e-12
        );
        // the stiffness scale does not change it (the material's own E and γ)
        let scaled = JkrParams {
            stiffness_scale: 0.01,
            ..p
        };
        assert_eq!(jkr_tabor(&scaled, 5e-7, TABOR_MIN_SEPARATION), lambda);
        // λ ∝ R^(1/3) γ^(2/3) E*^(−2/3) D^(−1)
        assert_relative_eq!(
            tabor_parameter(8.0 * 5e-7, 0.05, p.e_star(), 1.65e-10),
            2.0 * lambda,
            max_relative = 1e-12
        );
        assert_eq!(tabor_regime(lambda), "JKR");
        assert!(tabor_warning("x", lambda, 1.65e-10).is_none());
        // a stiff sub-micron pair (E = 100 GPa, γ = 0.01, R* = 50 nm): λ ≈ 0.114, Maugis
        let stiff = tabor_parameter(5e-8, 0.01, 1e11 / 1.82, 1.65e-10);
        assert_relative_eq!(
            stiff,
            (2e-11 / ((1e11f64 / 1.82).powi(2) * 4.492125e-30)).cbrt(),
            max_relative = 1e-12
        );
        assert!((stiff - 0.1138).abs() < 1e-3, "{stiff}");
        assert_eq!(tabor_regime(stiff), "Maugis-Dugdale");
        assert_eq!(tabor_regime(0.05), "DMT");
        assert_eq!(tabor_regime(3.0), "Maugis-Dugdale");
        let w = tabor_warning("the pair `a`-`b`", stiff, 1.65e-10).unwrap();
        assert!(w.contains("`a`-`b`") && w.contains("0.114") && w.contains("Maugis"));
    }

    #[test]
    fn yield_velocity_of_paper_001() {
        // paper 001 §IV A 3: v_Y ≈ 0.17 corresponds to Y = 0.15E* (LJ units: E* = 65.5,
        // ρ = 1.09, equal spheres R = 147)
        let (es, rho, r) = (65.5, 1.09, 147.0f64);
        let m = rho * 4.0 / 3.0 * PI * r.powi(3);
        let vy = yield_velocity(0.15 * es, es, 0.5 * r, 0.5 * m);
        assert!((vy - 0.17).abs() < 2e-3, "{vy}");
        // by hand for equal spheres: v_Y² = E*(0.8πY/E*)⁵/(5πρ) = 0.029130
        assert_relative_eq!(vy * vy, 0.02913067, max_relative = 1e-6);
        // the Hertz centre pressure at v_Y is 1.6Y
        let pc = hertz_centre_pressure(hertz_delta_max(0.5 * m, 0.5 * r, es, vy), 0.5 * r, es);
        assert_relative_eq!(pc, 1.6 * 0.15 * es, max_relative = 1e-12);
    }

    #[test]
    fn paper_001_pressures_and_plasticity() {
        // LJ units, R = 147 (table II): E* = 65.5, γ = 3.17, ρ = 1.09, R* = 73.5
        let (es, gamma, r): (f64, f64, f64) = (65.5, 3.17, 73.5);
        let m = 1.09 * 4.0 / 3.0 * PI * 147f64.powi(3);
        // eq. 15 (particle mass m) equals the m* = m/2 form
        for v in [0.1, 0.2] {
            let eq15 = (15.0 / 32.0 * m * v * v / (es * r.sqrt())).powf(0.4);
            assert_relative_eq!(
                hertz_delta_max(0.5 * m, r, es, v),
                eq15,
                max_relative = 1e-14
            );
        }
        // paper 001 §V A: p_c,H ≈ 0.194 E* at v = 0.1 and 0.255 E* at v = 0.2 (R = 147)
        let pc = |v: f64| hertz_centre_pressure(hertz_delta_max(0.5 * m, r, es, v), r, es) / es;
        assert!((pc(0.1) - 0.194).abs() < 0.003, "{}", pc(0.1));
        assert!((pc(0.2) - 0.255).abs() < 0.003, "{}", pc(0.2));
        assert_eq!(hertz_centre_pressure(-1.0, r, es), 0.0);
        // eq. 9 reduces to eq. 4 without adhesion (a² = δR*)
        let a = 20.0;
        assert_relative_eq!(
            jkr_centre_pressure(a, r, es, 0.0),
            hertz_centre_pressure(a * a / r, r, es),
            max_relative = 1e-14
        );
        // at the JKR equilibrium a0: 2E*a0/(πR*) − √(4γE*/(πa0))
        let a0 = (9.0 * PI * gamma * r * r / es).cbrt();
        let p0 = jkr_centre_pressure(a0, r, es, gamma);
        assert_relative_eq!(
            p0,
            2.0 * es * a0 / (PI * r) - (4.0 * gamma * es / (PI * a0)).sqrt(),
            max_relative = 1e-15
        );
        assert!(p0 > 0.0 && p0 < 0.2 * es);
        // small contacts are in tension
        assert!(jkr_centre_pressure(0.3 * a0, r, es, gamma) < 0.0);
        // Thornton–Ning: 1 up to v_Y, continuous there, falling beyond
        assert_eq!(thornton_ning_restitution(0.1, 0.17), 1.0);
        assert_relative_eq!(
            thornton_ning_restitution(0.17 * (1.0 + 1e-12), 0.17),
            1.0,
            max_relative = 1e-9
        );
        let mut last = 1.0;
        for k in 1..50 {
            let e = thornton_ning_restitution(0.17 * (1.0 + 0.2 * k as f64), 0.17);
            assert!(e < last && e > 0.0);
            last = e;
        }
        // large v: e_TN → (6√3/5)^(1/2)·(2·√(6/5)·v/v_Y)^(−1/4) ∝ v^(−1/4)
        let (v, vy) = (1e4, 1.0);
        let asym = (6.0 * 3f64.sqrt() / 5.0).sqrt() * (2.0 * (1.2f64).sqrt() * v / vy).powf(-0.25);
        assert_relative_eq!(thornton_ning_restitution(v, vy), asym, max_relative = 1e-3);
        // eq. 14
        assert_relative_eq!(plastic_restitution(0.9, 1.0), 0.9);
        assert_relative_eq!(
            plastic_restitution(0.8, 0.9),
            (0.64f64 - 0.19).sqrt(),
            max_relative = 1e-15
        );
        assert_eq!(plastic_restitution(0.3, 0.5), 0.0);
    }
}
