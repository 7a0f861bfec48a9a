//! The pair table's rows, one block a contact law or sub-model (`gpu::composition` lays
//! them out; their WGSL twins are the `PairRow` fields the generated code declares).

use super::{wgsl_consts, wgsl_struct};
use bytemuck::{Pod, Zeroable};

/// `x` in f32, or NaN where a non-zero `x` has no normal f32 (it would round to 0 or lose
/// its digits as a subnormal): `check_f32_range` refuses the row by member, as it does a
/// value beyond f32's largest.
fn narrow(x: f64) -> f32 {
    let y = x as f32;
    if x != 0.0 && (y == 0.0 || y.is_subnormal()) {
        f32::NAN
    } else {
        y
    }
}

wgsl_struct! {
/// The hysteretic law's block of the pair table (`shaders/model/hysteretic.wgsl`).
/// LSD is the special case k1 = kp = k with the LSD flag.
#[wgsl("HystereticPair")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HystereticPair {
    /// Initial (plastic) loading stiffness k1, N/m (paper 000 eq. 5).
    pub k1: f32,
    /// Largest (limit-branch) un-/re-loading stiffness kp, N/m (paper 000 eqs. 9–11).
    pub kp: f32,
    /// Slope of the irreversible tensile (adhesive) branch kc, N/m (paper 000 eq. 5).
    pub kc: f32,
    /// kp/(kp − k1)·φf (a huge finite number when kp = k1: WGSL may assume no infinities).
    pub dmaxp_per_a12: f32,
    /// Plasticity depth φf: δ0 on the limit branch over a12 (paper 000 eqs. 10–11).
    pub phi_f: f32,
    /// Non-contact adhesion force fa, N (paper 000 eq. 14).
    pub fa: f32,
    /// Non-contact stiffness; 0 encodes zero range (kca = ∞).
    pub kca: f32,
    /// Viscous damping coefficient γ0, kg/s (paper 000 eq. 2).
    pub gamma0: f32,
    /// [`HYST_JUMP_IN`], [`HYST_SQRT_RULE`] and [`HYST_LSD`], or-ed.
    pub flags: u32,
    /// 1/`dmaxp_per_a12` (the kernel multiplies where the f64 reference divides).
    pub inv_dmaxp_per_a12: f32,
    /// (k1 + kc)/(kp − k1), 0 when kp <= k1: the tensile branch's history
    /// (`HystereticParams::delta_max_on_tensile_branch`, linear rule) is
    /// 0.5·δ + √(0.25·δ² + tensile_c·δ·δmax^p).
    pub tensile_c: f32,
    /// kp·φf/(kp + kc): where the limit line meets the tensile branch, over a12.
    pub tensile_limit_per_a12: f32,
}
}

wgsl_consts! {
    /// Flags of [`HystereticPair`].
    pub HYST_FLAGS: u32 = {
        /// Jump-in adhesion (else reversible).
        HYST_JUMP_IN = 1,
        /// The k2 rule is the √ interpolation (paper 000 appendix D), not the linear eq. 9.
        HYST_SQRT_RULE = 2,
        /// The row is a linear spring-dashpot (LSD): f = k·δ + γ0·δ̇ with k = k1 = kp, no
        /// history.
        HYST_LSD = 4,
    }
}

impl HystereticPair {
    /// The row of a hysteretic pair, rounded to f32 (kca = ∞ encoded as 0).
    pub fn hysteretic(p: &crate::model::HystereticParams) -> Self {
        use crate::model::{AdhesionMode, K2Rule};
        // (∞ without plasticity: 1e30 stays finite in f32)
        let dmaxp = p.delta_max_p(1.0).min(1e30);
        let mut flags = 0;
        if p.adhesion == AdhesionMode::JumpIn {
            flags |= HYST_JUMP_IN;
        }
        if p.k2_rule == K2Rule::Sqrt {
            flags |= HYST_SQRT_RULE;
        }
        Self {
            k1: narrow(p.k1),
            kp: narrow(p.kp),
            kc: narrow(p.kc),
            dmaxp_per_a12: narrow(dmaxp),
            phi_f: narrow(p.phi_f),
            fa: narrow(p.fa),
            kca: if p.kca.is_finite() {
                narrow(p.kca)
            } else {
                0.0
            },
            gamma0: narrow(p.gamma0),
            flags,
            inv_dmaxp_per_a12: narrow(1.0 / dmaxp),
            tensile_c: narrow(p.tensile_coefficient()),
            tensile_limit_per_a12: narrow(p.tensile_limit(1.0)),
        }
    }

    /// The row of an LSD pair: k1 = kp = k, the [`HYST_LSD`] flag.
    pub fn lsd(p: &crate::model::LsdParams) -> Self {
        Self {
            k1: narrow(p.k),
            kp: narrow(p.k),
            dmaxp_per_a12: 1e30,
            inv_dmaxp_per_a12: 1e-30,
            gamma0: narrow(p.gamma0),
            flags: HYST_LSD,
            ..Default::default()
        }
    }
}

wgsl_struct! {
/// The JKR law's block of the pair table (`shaders/model/jkr.wgsl`): the JKR
/// family's parameters, derived in f64 from [`JkrParams`](crate::model::JkrParams) and
/// rounded once. Per-contact quantities that depend on R* (a0, δ0, Fc, ξcrit) are formed in
/// the kernel from the coefficients here, since R* varies with the particles' radii.
#[wgsl("JkrPair")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct JkrPair {
    /// E* = S·E/(2(1 − ν²)) (scaled), Pa.
    pub e_star: f32,
    /// G* = G/(2(2 − ν)), G = S·E/(2(1 + ν)) (scaled), Pa.
    pub g_star: f32,
    /// Surface energy after scaling, γ·S^(2/5), J/m²; 0 = Hertz.
    pub gamma: f32,
    /// (9πγ/E*)^(1/3) (scaled): a0 = a0_coef·R*^(2/3).
    pub a0_coef: f32,
    /// δ/δ0 at which a touching contact breaks ([`Pulloff`](crate::model::Pulloff)).
    pub break_ratio: f32,
    /// Sliding friction coefficient μs; 0 = no tangential force.
    pub friction: f32,
    /// Δγ/γ of the rolling resistance; 0 = none.
    pub rolling_hysteresis: f32,
    /// Unscaled 3πγ: the rolling model's Fc = this·R*.
    pub fc_unscaled_per_r: f32,
    /// Unscaled (9πγ/E*)^(1/3): the rolling model's a0 = this·R*^(2/3).
    pub a0_unscaled_coef: f32,
    /// [`JKR_DISSIPATION_NONE`], [`JKR_DISSIPATION_TSUJI`], [`JKR_DISSIPATION_POWER`],
    /// [`JKR_DISSIPATION_KRIJT`] or [`JKR_DISSIPATION_STRESS`].
    pub dissipation: u32,
    /// Tsuji: −2√(5/6)·β(e) ≥ 0.
    pub tsuji: f32,
    /// Power law: D, α, β.
    pub power_d: f32,
    /// Power law: exponent α of |v| (paper 001 eqs. 19–20).
    pub power_alpha: f32,
    /// Power law: exponent β of the contact radius a (paper 001 eqs. 19–20).
    pub power_beta: f32,
    /// P(x_break) of [`potential_shape`](crate::model::jkr::potential_shape): the stored
    /// energy of a contact is Fc·δ0·(P(x) − P(x_break)) (energy ledger).
    pub p_break: f32,
    /// Krijt and stress (`shaders/model/krijt.wgsl`): 2E*/ν² of the viscous force (eq. 12).
    pub visc: f32,
    /// T_vis (krijt) or C of T_vis,0 = C·R (stress, eq. 18).
    pub tvis: f32,
    /// 2E*·γ/σ0² of the crack speed (eq. B2), m; 0 for σ0 = 0 (no delay of a).
    pub crack: f32,
    /// B of eq. 17 (stress).
    pub stress_b: f32,
    /// ζ of eq. 17 (stress).
    pub stress_zeta: f32,
    /// Tsuji: 1 when the dashpots use paper 002's Hertz stiffness, ρ = √(R*·max(δ, 0)) in
    /// Sn = 2E*·ρ and St = 8G*·ρ; 0 for the contact radius a
    /// ([`TsujiStiffness`](crate::model::TsujiStiffness)).
    pub tsuji_hertz: u32,
    /// 1 where a contact ends as the Krijt crack closes its delayed radius
    /// ([`JkrParams::pulloff_rule`](crate::model::JkrParams::pulloff_rule) `crack`); 0 at
    /// `break_ratio`.
    pub crack_break: u32,
}
}

wgsl_consts! {
    /// Dissipation kinds of [`JkrPair`].
    pub JKR_DISSIPATIONS: u32 = {
        /// None beyond the JKR hysteresis.
        JKR_DISSIPATION_NONE = 0,
        /// Tsuji-type viscous damping from a restitution coefficient (paper 002 eqs.
        /// 11–13).
        JKR_DISSIPATION_TSUJI = 1,
        /// Power-law dissipation F = sgn(v)·D·E*·|v|^α·a^β (paper 001 eqs. 19–20).
        JKR_DISSIPATION_POWER = 2,
        /// Krijt viscoelastic dissipation with a delayed contact radius, constant T_vis
        /// (paper 001 eqs. 10–12, B1–B2; the contact radius is state,
        /// `model/krijt.wgsl`).
        JKR_DISSIPATION_KRIJT = 3,
        /// Krijt dissipation with the stress-dependent T_vis of paper 001 eqs. 17–18.
        JKR_DISSIPATION_STRESS = 4,
    }
}

impl JkrPair {
    /// The row of a JKR/Hertz pair, derived in f64 and rounded once to f32.
    pub fn new(p: &crate::model::JkrParams) -> Self {
        use crate::model::jkr::tsuji_beta;
        use crate::model::Dissipation;
        // the coefficients of R*: the law's scales at R* = 1 m
        let rule = p.pulloff_rule();
        let mut row = Self {
            e_star: narrow(p.e_star()),
            g_star: narrow(p.g_star()),
            gamma: narrow(p.gamma()),
            a0_coef: narrow(p.a0(1.0)),
            break_ratio: narrow(rule.break_overlap_ratio()),
            friction: narrow(p.friction),
            rolling_hysteresis: narrow(p.rolling_hysteresis),
            fc_unscaled_per_r: narrow(p.fc_unscaled(1.0)),
            a0_unscaled_coef: narrow(p.a0_unscaled(1.0)),
            p_break: narrow(crate::model::jkr::potential_shape(
                rule.break_radius_ratio(),
            )),
            crack_break: u32::from(rule == crate::model::Pulloff::Crack),
            ..Default::default()
        };
        match p.dissipation {
            Dissipation::None => {}
            Dissipation::Tsuji {
                restitution,
                stiffness,
            } => {
                row.dissipation = JKR_DISSIPATION_TSUJI;
                row.tsuji = narrow(-crate::model::jkr::TSUJI_PREFACTOR * tsuji_beta(restitution));
                row.tsuji_hertz = u32::from(stiffness == crate::model::TsujiStiffness::Hertz);
            }
            Dissipation::PowerLaw { d, alpha, beta } => {
                row.dissipation = JKR_DISSIPATION_POWER;
                row.power_d = narrow(d);
                row.power_alpha = narrow(alpha);
                row.power_beta = narrow(beta);
            }
            Dissipation::Krijt { tvis, sigma0 } => {
                row.dissipation = JKR_DISSIPATION_KRIJT;
                row.tvis = narrow(tvis);
                row.set_krijt(p, sigma0);
            }
            Dissipation::Stress {
                tvis0_per_radius,
                b,
                zeta,
                sigma0,
            } => {
                row.dissipation = JKR_DISSIPATION_STRESS;
                row.tvis = narrow(tvis0_per_radius);
                row.stress_b = narrow(b);
                row.stress_zeta = narrow(zeta);
                row.set_krijt(p, sigma0);
            }
        }
        row
    }

    /// The material coefficients of the Krijt law (E* and γ after the stiffness scale, as
    /// `JkrParams::krijt_material`): 2E*/ν² and 2E*γ/σ0² (capped at f32::MAX: a step of
    /// the crack that long is no delay at all).
    fn set_krijt(&mut self, p: &crate::model::JkrParams, sigma0: f64) {
        let m = p.krijt_material();
        self.visc = narrow(2.0 * m.e_star / (m.poisson * m.poisson));
        self.crack = if sigma0 > 0.0 {
            narrow((2.0 * m.e_star * m.gamma / (sigma0 * sigma0)).min(f32::MAX as f64))
        } else {
            0.0
        };
    }
}

wgsl_struct! {
/// One Luding spring's block of the pair table (`shaders/model/friction/coulomb.wgsl`):
/// [`CoulombSpring`](crate::model::CoulombSpring) rounded to f32; all zero (μs = 0) is off.
#[wgsl("CoulombSpring")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CoulombSpringRow {
    /// Static coefficient μs; 0 = off.
    pub mu_s: f32,
    /// Dynamic coefficient μd.
    pub mu_d: f32,
    /// Stiffness k, N/m.
    pub k: f32,
    /// Dashpot γ, kg/s.
    pub gamma: f32,
}
}

impl CoulombSpringRow {
    /// The block of a spring.
    pub fn new(s: &crate::model::CoulombSpring) -> Self {
        Self {
            mu_s: narrow(s.mu_s),
            mu_d: narrow(s.mu_d),
            k: narrow(s.k),
            gamma: narrow(s.gamma),
        }
    }
}

wgsl_struct! {
/// The twisting block of the pair table (`shaders/model/friction/twisting.wgsl`): the
/// spring, and for the JKR family without a given k_o the stiffness per contact radius
/// (k_o = k + k_per_a·a).
#[wgsl("TwistingRow")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwistingRow {
    /// The spring (its `k` is 0 where the stiffness follows the contact radius).
    pub spring: CoulombSpringRow,
    /// dk_o/da, N/m²: 2/5·8G* for the JKR family's default, else 0.
    pub k_per_a: f32,
}
}

impl TwistingRow {
    /// The block of a pair's model, `None` where it has no twisting friction.
    pub fn new(m: &crate::model::ContactModel) -> Option<Self> {
        use crate::model::ContactModel;
        let (spring, k_per_a) = match m {
            ContactModel::Hysteretic(p) => (p.luding.twisting, 0.0),
            ContactModel::Lsd(p) => (p.luding.twisting, 0.0),
            // the stiffness of `JkrParams::twisting_stiffness` at a: k_o, or 2/5·8G*·a
            ContactModel::Jkr(p) if p.luding.twisting.k > 0.0 => (p.luding.twisting, 0.0),
            ContactModel::Jkr(p) => (p.luding.twisting, p.twisting_stiffness(1.0)),
        };
        spring.is_on().then(|| Self {
            spring: CoulombSpringRow::new(&spring),
            k_per_a: narrow(k_per_a),
        })
    }
}
