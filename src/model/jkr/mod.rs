//! The JKR family of contact laws in f64 (papers 001 and 002): Hertz (γ = 0) and JKR
//! elastic normal force with contact hysteresis, Tsuji or power-law normal damping,
//! Mindlin-type tangential spring with the adhesive Coulomb limit, and the
//! Dominik–Tielens/Krijt rolling resistance; optionally with a reduced particle stiffness
//! (paper 002 §3).
//!
//! Sign conventions: δ > 0 is overlap, δ̇ = dδ/dt is the approach speed, a positive normal
//! force is repulsive. The unit normal n points from particle j to particle i.
//!
//! Material: both bodies share E and ν, so E* = E/(2(1−ν²)) (paper 002 eq. 2) and
//! G* = G/(2(2−ν)), G = E/(2(1+ν)) (eq. 15). γ is the surface energy *per surface* (work
//! of adhesion 2γ), so Fc = 3πγR*, a0 = (9πγR*²/E*)^(1/3), δ0 = a0²/(3R*) (paper 001
//! eq. 8, paper 002 eq. 7).
//!
//! Dimensionless JKR, x = a/a0 and d = δ/δ0: d = 3x² − 2√x (paper 001 eq. 5),
//! F/Fc = 4x³ − 4x^(3/2) (eq. 6), ∫F dδ = Fc·δ0·P(x) + const ([`potential_shape`]). The
//! touch and pull-off points are the constants [`X_TOUCH`], [`S_MIN`],
//! [`D_PULLOFF_DISPLACEMENT`], [`D_PULLOFF_FORCE`]; the whole law: `docs/models.md`,
//! *The JKR family*.

use crate::error::ParamError;

mod dissipation;
pub mod mindlin;
mod pair;
pub(crate) mod radius;
pub mod rolling;
mod scaling;
mod twisting;
mod viscous_step;

use crate::model::friction::LudingFriction;
use crate::model::history::{HistoryField, HostField, Mirror, Shape};
use crate::model::krijt;
use crate::model::params::word_enum;
use crate::model::{ContactHistory, NormalForce, PairGeometry};
pub(crate) use dissipation::TSUJI_PREFACTOR;
pub use dissipation::{tsuji_beta, Dissipation, TsujiStiffness};
pub use mindlin::Tangential;
pub use pair::JkrPair;
pub use radius::contact_radius_f32;
use radius::solve_t_f64;
pub use rolling::Rolling;
pub use scaling::StiffnessScaling;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
pub use viscous_step::{PowerLawEstimate, ViscousEstimate};

/// The per-contact history of the JKR normal law: touched since the pair last broke.
pub const HISTORY: &[HistoryField] = &[HistoryField {
    name: "touched",
    shape: Shape::Flag,
    mirror: Mirror::Same,
    host: HostField::Touched,
    doc: "touched since the pair last broke",
}];

/// s_min = 6^(−1/3): √(a/a0) at the displacement-controlled pull-off (turning point of
/// d(s) = 3s⁴ − 2s).
pub const S_MIN: f64 = 0.5503212081491045;
/// δ/δ0 at the displacement-controlled pull-off: −(3/4)^(2/3) = −1.5·6^(−1/3).
pub const D_PULLOFF_DISPLACEMENT: f64 = -0.8254818122236567;
/// δ/δ0 where the JKR force reaches −Fc (force-controlled pull-off): −2^(−4/3).
pub const D_PULLOFF_FORCE: f64 = -0.3968502629920499;
/// δ/δ0 beyond which no contact radius holds against the crack law of paper 001 eq. B2:
/// min over a of G_eff/γ = (4/3)·|δ/δ0|^(3/2) reaches [`krijt::BETA_MAX`], where the crack
/// runs at infinite speed, at −(0.75·50)^(2/3). The farthest a `crack` contact reaches.
pub const D_PULLOFF_CRACK: f64 = -11.20351186639291;
/// a/a0 at the displacement-controlled pull-off, 6^(−2/3).
pub const X_PULLOFF_DISPLACEMENT: f64 = 0.30285343213869;
/// a/a0 at the force-controlled pull-off, 2^(−2/3).
pub const X_PULLOFF_FORCE: f64 = 0.6299605249474366;
/// a/a0 at the first touch (δ = 0), (2/3)^(2/3).
pub const X_TOUCH: f64 = 0.7631428283688879;
/// [`potential_shape`] at [`X_PULLOFF_DISPLACEMENT`], [`X_PULLOFF_FORCE`] and [`X_TOUCH`].
const P_PULLOFF_DISPLACEMENT: f64 = 0.07337616108654725;
const P_PULLOFF_FORCE: f64 = -0.31748021039364027;
const P_TOUCH: f64 = -0.6988643717890397;

/// Newton iterations of the iterative f64 contact-radius solve at most (converged to
/// rounding everywhere); it stops after a step below 1e-8 of the root (then at rounding).
pub const NEWTON_ITERATIONS_F64: usize = 5;
/// The least JKR adhesion 3πγ/(E*·R*) a contact carries in f64
/// ([`JkrParams::check_adhesion_scale`]).
pub const MIN_ADHESION_SCALE: f64 = 1e-100;
/// Newton iterations of the f32 contact-radius solver (the WGSL kernel's count).
pub const NEWTON_ITERATIONS_F32: usize = 3;

word_enum! {
/// Where a JKR contact breaks on separation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Pulloff {
    /// Displacement control (paper 001): the contact persists down to the turning point
    /// δc = −(3/4)^(2/3)·δ0, where F = −5/9·Fc.
    #[default]
    Displacement = "displacement",
    /// Force control (LAMMPS's choice): the contact breaks where F reaches −Fc, at
    /// δ = −2^(−4/3)·δ0 ≈ −0.397·δ0.
    Force = "force",
    /// Paper 002's rule: the contact breaks as soon as the overlap turns negative on
    /// separation, where F = −8/9·Fc as at the touch, so the JKR curve itself loses nothing.
    Zero = "zero",
    /// The Krijt dissipations only: the contact lasts until the crack law (paper 001
    /// eq. B2) has shrunk its contact radius to 0, where F and U reach 0 continuously;
    /// beyond the turning point the neck recedes at the crack speed. With σ0 = 0 it
    /// breaks at the turning point, as `displacement`.
    Crack = "crack",
}
}

impl Pulloff {
    /// δ/δ0 at which the contact breaks (`crack`: at the latest, [`D_PULLOFF_CRACK`]).
    pub fn break_overlap_ratio(self) -> f64 {
        match self {
            Self::Displacement => D_PULLOFF_DISPLACEMENT,
            Self::Force => D_PULLOFF_FORCE,
            Self::Zero => 0.0,
            Self::Crack => D_PULLOFF_CRACK,
        }
    }

    /// a/a0 at which the contact breaks.
    pub fn break_radius_ratio(self) -> f64 {
        match self {
            Self::Displacement => X_PULLOFF_DISPLACEMENT,
            Self::Force => X_PULLOFF_FORCE,
            Self::Zero => X_TOUCH,
            Self::Crack => 0.0,
        }
    }

    /// [`potential_shape`] at the break radius ratio (tested against it).
    pub fn break_potential_shape(self) -> f64 {
        match self {
            Self::Displacement => P_PULLOFF_DISPLACEMENT,
            Self::Force => P_PULLOFF_FORCE,
            Self::Zero => P_TOUCH,
            Self::Crack => 0.0,
        }
    }
}

fn default_stiffness_scale() -> f64 {
    1.0
}

/// Parameters of the JKR family (SI units). Both bodies are of the same material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JkrParams {
    /// Young's modulus E of both bodies, Pa (before the stiffness scale).
    pub youngs: f64,
    /// Poisson's ratio ν ∈ (−1, 0.5).
    pub poisson: f64,
    /// Surface energy γ per surface, J/m² (work of adhesion 2γ); 0 gives Hertz.
    pub surface_energy: f64,
    #[serde(default)]
    /// Normal (and tangential) dissipation on top of the JKR hysteresis; default none.
    pub dissipation: Dissipation,
    /// Sliding friction coefficient μs ≥ 0; 0 = no tangential force.
    #[serde(default)]
    pub friction: f64,
    /// Adhesion hysteresis Δγ/γ ≥ 0 of the rolling resistance (paper 002 eq. 18);
    /// 0 = no rolling resistance. Needs γ > 0.
    #[serde(default)]
    pub rolling_hysteresis: f64,
    #[serde(default)]
    /// Where a stretched contact breaks: displacement (paper 001) or force control.
    pub pulloff: Pulloff,
    /// Stiffness scale S > 0 (typically ≤ 1): E → S·E and γ → γ·S^(2/5) (paper 002 eq. 24).
    #[serde(default = "default_stiffness_scale")]
    pub stiffness_scale: f64,
    /// Luding's twisting resistance ([`crate::model::friction::twisting`]; only `twisting`
    /// is used: the family has its own sliding and rolling laws). Its stiffness 0 means the
    /// Mindlin-derived k_o = 2/5·8G*·a at the current contact radius
    /// ([`Self::twisting_stiffness`]).
    #[serde(default)]
    pub luding: LudingFriction,
}

/// The length scales a0 and δ0 of a pair (scaled γ and E*).
#[derive(Clone, Copy, Debug)]
struct Scales {
    a0: f64,
    d0: f64,
}

impl Scales {
    /// a0 = (9πγR*²/E*)^(1/3) and δ0 = a0²/(3R*).
    fn new(r_eff: f64, es: f64, gamma: f64) -> Self {
        let a0 = memo_cbrt(9.0 * PI * gamma * r_eff * r_eff / es);
        Self {
            a0,
            d0: a0 * a0 / (3.0 * r_eff),
        }
    }

    /// Contact radius a(δ) on the stable JKR branch (γ > 0), see
    /// [`JkrParams::contact_radius`].
    fn contact_radius(&self, delta: f64) -> f64 {
        let s = self.root(delta);
        self.a0 * s * s
    }

    /// s = √(a/a0) on the stable branch at overlap `delta`.
    fn root(&self, delta: f64) -> f64 {
        S_MIN + solve_t_f64(delta / self.d0 - D_PULLOFF_DISPLACEMENT)
    }
}

/// Elastic JKR force 4E*a³/(3R*) − 4√(πγE*a³), see [`JkrParams::elastic_force`].
fn elastic_force(a: f64, r_eff: f64, es: f64, gamma: f64) -> f64 {
    let a3 = a * a * a;
    4.0 * es * a3 / (3.0 * r_eff) - 4.0 * (PI * gamma * es * a3).sqrt()
}

/// P(x) = (24/5)x⁵ − 8x^(7/2) + 2x², x = a/a0: ∫F dδ = Fc·δ0·P(x) + const along the
/// stable JKR branch (dδ = δ0·(6x − x^(−1/2))·dx and F = Fc·(4x³ − 4x^(3/2)) give the
/// integrand Fc·δ0·(24x⁴ − 28x^(5/2) + 4x)).
pub fn potential_shape(x: f64) -> f64 {
    potential_shape_of_root(x.sqrt())
}

/// [`potential_shape`] of x = s²: s⁴·(4.8·s⁶ − 8·s³ + 2).
fn potential_shape_of_root(s: f64) -> f64 {
    let s3 = s * s * s;
    let s4 = s3 * s;
    s4 * (4.8 * s3 * s3 - 8.0 * s3 + 2.0)
}

impl JkrParams {
    /// Hertz contact (γ = 0) without dissipation, friction or rolling resistance.
    pub fn hertz(youngs: f64, poisson: f64) -> Self {
        Self::jkr(youngs, poisson, 0.0)
    }

    /// JKR contact without dissipation, friction or rolling resistance; displacement
    /// pull-off, S = 1.
    pub fn jkr(youngs: f64, poisson: f64, surface_energy: f64) -> Self {
        Self {
            youngs,
            poisson,
            surface_energy,
            dissipation: Dissipation::None,
            friction: 0.0,
            rolling_hysteresis: 0.0,
            pulloff: Pulloff::Displacement,
            stiffness_scale: 1.0,
            luding: LudingFriction::default(),
        }
    }

    /// Checks every rule of the model; the error names the parameter and the rule.
    pub fn validate(&self) -> Result<(), ParamError> {
        use crate::model::params as p;
        let mut checks = vec![
            (&p::YOUNGS, self.youngs),
            (&p::POISSON, self.poisson),
            (&p::SURFACE_ENERGY, self.surface_energy),
            (&p::FRICTION, self.friction),
            (&p::ROLLING_HYSTERESIS, self.rolling_hysteresis),
            (&p::STIFFNESS_SCALE, self.stiffness_scale),
        ];
        match self.dissipation {
            Dissipation::None => {}
            Dissipation::Tsuji { restitution, .. } => checks.push((&p::RESTITUTION, restitution)),
            Dissipation::PowerLaw { d, alpha, beta } => checks.extend([
                (&p::POWER_D, d),
                (&p::POWER_ALPHA, alpha),
                (&p::POWER_BETA, beta),
            ]),
            Dissipation::Krijt { tvis, sigma0 } => {
                checks.extend([(&p::TVIS, tvis), (&p::SIGMA0, sigma0)])
            }
            Dissipation::Stress {
                tvis0_per_radius,
                b,
                zeta,
                sigma0,
            } => checks.extend([
                (&p::TVIS0_PER_RADIUS, tvis0_per_radius),
                (&p::STRESS_B, b),
                (&p::STRESS_ZETA, zeta),
                (&p::SIGMA0, sigma0),
            ]),
        }
        for (param, x) in checks {
            param.check(x)?;
        }
        if self.stiffness_scale != 1.0
            && !matches!(
                self.dissipation,
                Dissipation::None | Dissipation::Tsuji { .. }
            )
        {
            return Err(ParamError::new(
                "stiffness_scale",
                format!(
                    "stiffness_scale = {} does not keep the restitution with dissipation = \"{}\": paper 002 derives the reduced-stiffness rule (eq. 24) for JKR with Tsuji damping only (the Krijt pair of paper 001 moves from e = 0.889 to 0.948 at S = 0.01); use dissipation = \"tsuji\" or \"none\", or leave stiffness_scale at 1",
                    self.stiffness_scale,
                    self.dissipation.name()
                ),
            ));
        }
        if self.pulloff == Pulloff::Crack && self.dissipation.krijt_law().is_none() {
            return Err(ParamError::new(
                "pulloff",
                format!(
                    "pulloff = \"crack\" ends a contact where the Krijt crack law (paper 001 eq. B2) closes its contact radius: it needs dissipation = \"krijt\" or \"stress\", not \"{}\"; use pulloff = \"displacement\", \"force\" or \"zero\"",
                    self.dissipation.name()
                ),
            ));
        }
        if self.dissipation.krijt_law().is_some() {
            if self.surface_energy <= 0.0 {
                return Err(ParamError::new(
                    "dissipation",
                    format!(
                        "dissipation = \"{}\" needs surface_energy > 0: the crack speed of paper 001 eq. B2 is a function of G_eff/gamma",
                        self.dissipation.name()
                    ),
                ));
            }
            if self.poisson == 0.0 {
                return Err(ParamError::new(
                    "poisson",
                    format!(
                        "dissipation = \"{}\" needs poisson != 0: the viscous force 2*T_vis*E*/nu^2*a*v of paper 001 eq. 12 divides by nu^2",
                        self.dissipation.name()
                    ),
                ));
            }
        }
        let twisting = &self.luding.twisting;
        p::TWISTING_FRICTION.check(twisting.mu_s)?;
        p::GAMMA_O.check(twisting.gamma)?;
        if twisting.k != 0.0 {
            p::KO.check(twisting.k)?;
        }
        if self.luding.sliding.is_on()
            || self.luding.rolling.is_on()
            || twisting.mu_d != twisting.mu_s
        {
            return Err(ParamError::new(
                "twisting_friction",
                "the JKR family takes Luding's twisting only: its sliding friction is `friction` (Mindlin, paper 002 eqs. 14-17) and its rolling resistance `rolling_hysteresis` (paper 002 eqs. 18-22)",
            ));
        }
        if self.rolling_hysteresis > 0.0 && self.surface_energy <= 0.0 {
            return Err(ParamError::new(
                "rolling_hysteresis",
                format!(
                    "rolling resistance (rolling_hysteresis = {}) needs surface_energy > 0: the rolling stiffness is 4*Fc*(a/a0)^(3/2) (paper 002 eqs. 18-21)",
                    self.rolling_hysteresis
                ),
            ));
        }
        Ok(())
    }

    /// Unscaled E* = E/(2(1−ν²)).
    pub fn e_star_unscaled(&self) -> f64 {
        self.youngs / (2.0 * (1.0 - self.poisson * self.poisson))
    }

    /// Effective modulus after scaling, S·E/(2(1−ν²)), Pa.
    pub fn e_star(&self) -> f64 {
        self.stiffness_scale * self.e_star_unscaled()
    }

    /// Effective shear modulus after scaling, G* = G/(2(2−ν)) with G = S·E/(2(1+ν)), Pa.
    pub fn g_star(&self) -> f64 {
        self.stiffness_scale * self.youngs / (4.0 * (1.0 + self.poisson) * (2.0 - self.poisson))
    }

    /// Surface energy after scaling, γ·S^(2/5) (paper 002 eq. 24), J/m².
    pub fn gamma(&self) -> f64 {
        if self.stiffness_scale == 1.0 {
            self.surface_energy
        } else {
            self.surface_energy * self.stiffness_scale.powf(0.4)
        }
    }

    /// Refuses an adhesion too weak against the elastic scale at `r_eff` for f64 to carry:
    /// below 3πγ/(E*·R*) = [`MIN_ADHESION_SCALE`] the contact radius over a0 overflows its
    /// powers (NaN energies), while the adhesive force is far below the elastic force's
    /// rounding, so Hertz (surface_energy = 0) is the same law.
    pub fn check_adhesion_scale(&self, r_eff: f64) -> Result<(), String> {
        let scale = 3.0 * std::f64::consts::PI * self.gamma() / (self.e_star() * r_eff);
        if self.surface_energy > 0.0 && (scale.is_nan() || scale < MIN_ADHESION_SCALE) {
            return Err(format!(
                "surface_energy = {:e} J/m^2 gives an adhesion 3πγ/(E*·R*) of {scale:.3e} at R* = {r_eff:e} m, below {MIN_ADHESION_SCALE:e}: far below the elastic force's rounding, and beyond what f64 carries through the JKR curve; set surface_energy = 0 (Hertz, the same law at that scale)",
                self.surface_energy
            ));
        }
        Ok(())
    }

    /// Pull-off force Fc = 3πγR* (scaled γ), N.
    pub fn fc(&self, r_eff: f64) -> f64 {
        3.0 * PI * self.gamma() * r_eff
    }

    /// Equilibrium contact radius a0 = (9πγR*²/E*)^(1/3) (scaled γ, E*), m.
    pub fn a0(&self, r_eff: f64) -> f64 {
        self.scales(r_eff).a0
    }

    /// The length scales of a pair of effective radius `r_eff`.
    fn scales(&self, r_eff: f64) -> Scales {
        Scales::new(r_eff, self.e_star(), self.gamma())
    }

    /// Equilibrium overlap δ0 = a0²/(3R*) (scaled), m.
    pub fn delta0(&self, r_eff: f64) -> f64 {
        self.scales(r_eff).d0
    }

    /// Unscaled Fc = 3πγR* (the rolling model keeps it, paper 002 §3.2), N.
    pub fn fc_unscaled(&self, r_eff: f64) -> f64 {
        3.0 * PI * self.surface_energy * r_eff
    }

    /// Unscaled a0 = (9πγR*²/E*)^(1/3) (the rolling model's ξcrit keeps it), m.
    pub fn a0_unscaled(&self, r_eff: f64) -> f64 {
        memo_cbrt(9.0 * PI * self.surface_energy * r_eff * r_eff / self.e_star_unscaled())
    }

    /// The pull-off rule in effect: `crack` without a delayed contact radius (σ0 = 0, or
    /// T_vis = 0) closes at the turning point, which is `displacement`.
    pub fn pulloff_rule(&self) -> Pulloff {
        match (self.pulloff, self.dissipation.krijt_law()) {
            (Pulloff::Crack, Some(law)) if law.delays_radius() => Pulloff::Crack,
            (Pulloff::Crack, _) => Pulloff::Displacement,
            (rule, _) => rule,
        }
    }

    /// The (negative) overlap at which a touching contact breaks (at the latest, with a
    /// delayed `crack`), per [`Self::pulloff_rule`]; 0 for Hertz.
    pub fn pulloff_overlap(&self, r_eff: f64) -> f64 {
        if self.gamma() == 0.0 {
            0.0
        } else {
            self.pulloff_rule().break_overlap_ratio() * self.delta0(r_eff)
        }
    }

    /// Contact radius a(δ) on the stable JKR branch: the root of δ = a²/R − 2√(πγa/E*)
    /// (paper 001 eq. 5) with a ≥ a(δc); for δ below the displacement-controlled pull-off
    /// δc = −(3/4)^(2/3)·δ0 it returns a(δc). Hertz (γ = 0): a = √(R·max(δ, 0)).
    ///
    /// Normalised, s = √(a/a0) solves g(s) = 3s⁴ − 2s − δ/δ0 = 0 for s ≥ s_min = 6^(−1/3).
    /// g has a double root at the pull-off point, where plain Newton is only linear; the
    /// solver therefore runs Newton on the deflated form √3·t·√((t + 2s_min)² + 2s_min²)
    /// = √(δ/δ0 − δc/δ0) with t = s − s_min (exact, no series truncation), which is
    /// increasing and convex with a non-zero slope at t = 0, started to the right of the
    /// root (guarded Newton, monotone, quadratic everywhere).
    ///
    /// In f64 a cubic Hermite start from a table and one Newton step (within 4 ulp of the
    /// converged solve); the f32 twin [`contact_radius_f32`] runs 3 guarded Newton
    /// iterations. Their accuracy, and the conditioning at the pull-off point:
    /// `docs/models.md`, *The JKR family* (checked by `tests::f32_solver_accuracy`).
    pub fn contact_radius(&self, delta: f64, r_eff: f64) -> f64 {
        if self.gamma() == 0.0 {
            return (r_eff * delta.max(0.0)).sqrt();
        }
        self.scales(r_eff).contact_radius(delta)
    }

    /// Overlap δ(a) = a²/R − 2√(πγa/E*) (paper 001 eq. 5), the inverse of
    /// [`Self::contact_radius`] on the stable branch.
    pub fn overlap_for_radius(&self, a: f64, r_eff: f64) -> f64 {
        a * a / r_eff - 2.0 * (PI * self.gamma() * a / self.e_star()).sqrt()
    }

    /// Elastic JKR force F = 4E*a³/(3R*) − 4√(πγE*a³) (paper 001 eq. 6, paper 002 eqs. 8–9),
    /// repulsive positive.
    pub fn elastic_force(&self, a: f64, r_eff: f64) -> f64 {
        elastic_force(a, r_eff, self.e_star(), self.gamma())
    }

    /// The material constants of the Krijt law (after the stiffness scale).
    pub fn krijt_material(&self) -> krijt::Material {
        krijt::Material {
            e_star: self.e_star(),
            gamma: self.gamma(),
            poisson: self.poisson,
        }
    }

    /// The normal force just inside the contact's two edges, where it jumps: at the touch
    /// (δ = 0, ≈ −8/9·Fc for JKR) and at the break (δ = pull-off overlap, −5/9·Fc or −Fc),
    /// each with the dissipative force at that contact radius. The energy ledger integrates
    /// the work of a step that crosses an edge from there rather than from zero. A `crack`
    /// contact ([`Self::pulloff_rule`]) ends with a = 0 and no force at `delta`, the end of
    /// the step, unless the step placed its break ([`NormalForce::broke_within`],
    /// `docs/models.md`, *Krijt*).
    pub fn edge_forces(&self, geom: &PairGeometry, delta: f64, delta_dot: f64) -> [(f64, f64); 2] {
        let r = 0.5 * geom.a12;
        let pair = self.pair(r);
        let at = |delta: f64| {
            let a = self.contact_radius(delta, r);
            self.elastic_force(a, r) + self.normal_dissipation(a, delta, delta_dot, geom, &pair)
        };
        let entry = (0.0, at(0.0));
        if self.pulloff_rule() == Pulloff::Crack {
            return [entry, (delta, 0.0)];
        }
        let exit = self.pulloff_overlap(r);
        [entry, (exit, at(exit))]
    }

    /// Normal force for overlap `delta` and approach speed `delta_dot`, with the JKR
    /// contact hysteresis kept in `history.touched`:
    /// * no force before the first touch (δ ≤ 0, not touched);
    /// * the contact starts at δ > 0 (the force jumps to ≈ −8/9·Fc just past δ = 0);
    /// * a touching contact persists for δ > [`Self::pulloff_overlap`] (also at δ < 0) and
    ///   breaks once δ ≤ it: touched = false, tangential and rolling history zeroed, no force.
    ///
    /// Hertz (γ = 0): contact only while δ > 0.
    ///
    /// `conservative` is the elastic force, `force` adds the dissipation (Tsuji:
    /// −2√(5/6)·β·√(Sn·m*)·δ̇ with Sn = 2E*a, paper 002 eqs. 11–13; power law:
    /// sgn(δ̇)·D·E*·|δ̇|^α·a^β with a from the equilibrium JKR relation, paper 001 eq. 19).
    /// `potential` is the stored energy relative to the break point,
    /// Fc·δ0·(P(x) − P(x_break)) (Hertz: 8/15·E*·√R*·δ^(5/2)). It is negative for a bound
    /// contact: just after the touch it is −W with W = Fc·δ0·(P(x_break) − P(x_touch)) the
    /// energy lost in an undamped touch/pull-off cycle (≈ 0.7722·Fc·δ0 with displacement
    /// pull-off, ≈ 0.3814·Fc·δ0 with force pull-off), so kinetic + potential energy drops by
    /// W at the touch and is continuous at the break.
    ///
    /// `krijt`/`stress` dissipation: see [`Self::normal_force_step`]; here with dt = 0 (the
    /// contact radius is not advanced).
    pub fn normal_force(
        &self,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        history: &mut ContactHistory,
    ) -> NormalForce {
        self.normal_force_step(delta, delta_dot, geom, 0.0, history)
    }

    /// [`Self::normal_force`] over a time step `dt`, which the `krijt` and `stress`
    /// dissipations need: their contact radius a is the state `history.contact_radius`
    /// (a_JKR(0) = (2/3)^(2/3)·a0 at the first touch), advanced by one backward-Euler step
    /// of the crack speed (paper 001 eq. B2) to the current overlap; the elastic force is
    /// F_E(a, δ) = 4E*a³/(3R*) − 2E*a(a²/R* − δ), the stored energy the JKR energy of
    /// eq. 7 at (a, δ) from its value at the break point, and the dissipative force
    /// (2·T_vis·E*/ν²)·a·δ̇ (eq. 12). See [`crate::model::krijt`]. The contact breaks at
    /// the same overlap as JKR ([`Pulloff`]), or with `crack` where the crack has closed
    /// (a = 0). The other dissipations ignore dt.
    pub fn normal_force_step(
        &self,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> NormalForce {
        let pair = self.pair(0.5 * geom.a12);
        self.normal_force_of_pair(&pair, (delta, delta_dot), geom, dt, history)
    }

    /// [`Self::normal_force_step`] with the pair's constants ([`Self::pair`] of R* = a12/2).
    pub fn normal_force_of_pair(
        &self,
        pair: &JkrPair,
        (delta, delta_dot): (f64, f64),
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> NormalForce {
        self.normal_force_rooted(pair, (delta, delta_dot), None, geom, dt, history)
    }

    /// Whether an adhesive contact is on its JKR branch at `delta`: touched before or
    /// overlapping, and short of its break (else it exerts nothing and forgets its history).
    fn bound(&self, pair: &JkrPair, delta: f64, touched: bool) -> bool {
        (touched || delta > 0.0)
            && delta > self.pulloff_rule().break_overlap_ratio() * pair.scales.d0
    }

    /// s = √(a/a0) at `delta` where [`Self::normal_force_of_pair`] solves it (an adhesive
    /// contact on its branch), else None.
    pub(crate) fn root_ahead(&self, pair: &JkrPair, delta: f64, touched: bool) -> Option<f64> {
        (pair.gamma != 0.0 && self.bound(pair, delta, touched)).then(|| pair.scales.root(delta))
    }

    /// [`Self::normal_force_of_pair`] with s = √(a/a0) solved ahead ([`Self::root_ahead`]).
    pub(crate) fn normal_force_rooted(
        &self,
        pair: &JkrPair,
        (delta, delta_dot): (f64, f64),
        root: Option<f64>,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> NormalForce {
        let r = 0.5 * geom.a12;
        let (gamma, es) = (pair.gamma, pair.es);
        let (a, conservative, potential) = if gamma == 0.0 {
            if delta <= 0.0 {
                *history = ContactHistory::default();
                return NormalForce::default();
            }
            let a = (r * delta).sqrt();
            let conservative = 4.0 * es * a * a * a / (3.0 * r);
            let potential = 8.0 / 15.0 * es * r.sqrt() * delta * delta * delta.sqrt();
            (a, conservative, potential)
        } else {
            if !self.bound(pair, delta, history.touched) {
                *history = ContactHistory::default();
                return NormalForce::default();
            }
            let sc = pair.scales;
            let (a0, d0) = (sc.a0, sc.d0);
            let s = root.unwrap_or_else(|| sc.root(delta));
            let a_eq = a0 * s * s;
            if let Some(law) = self.dissipation.krijt_law() {
                let mat = self.krijt_material();
                let a_old = if history.contact_radius > 0.0 {
                    history.contact_radius
                } else {
                    X_TOUCH * a0
                };
                let rule = self.pulloff_rule();
                let a = if rule == Pulloff::Crack && delta < 0.0 && dt > 0.0 {
                    let root = |d: f64| {
                        (d / d0 >= D_PULLOFF_DISPLACEMENT).then(|| {
                            let s = sc.root(d);
                            a0 * s * s
                        })
                    };
                    match law.step_neck(a_old, (delta, delta_dot), dt, r, &mat, root) {
                        krijt::NeckStep::Open(a) => a,
                        krijt::NeckStep::Closed {
                            fraction,
                            radius,
                            overlap,
                        } => {
                            // the neck closed within the step: the contact breaks there
                            let force = krijt::elastic_force(radius, overlap, r, mat.e_star)
                                + self.normal_dissipation(radius, overlap, delta_dot, geom, pair);
                            *history = ContactHistory::default();
                            return NormalForce {
                                broke_within: Some((fraction, force)),
                                ..NormalForce::default()
                            };
                        }
                    }
                } else if rule == Pulloff::Crack {
                    let a_eq = (delta / d0 >= D_PULLOFF_DISPLACEMENT).then_some(a_eq);
                    law.step_radius_to_zero(a_old, a_eq, delta, dt, r, &mat)
                } else {
                    law.step_radius(a_old, a_eq, delta, dt, r, &mat)
                };
                if a <= 0.0 {
                    // the crack has closed the neck: the contact breaks
                    *history = ContactHistory::default();
                    return NormalForce::default();
                }
                history.contact_radius = a;
                let es = mat.e_star;
                let reference = krijt::stored_energy(
                    rule.break_radius_ratio() * a0,
                    rule.break_overlap_ratio() * d0,
                    r,
                    es,
                    gamma,
                );
                let potential = krijt::stored_energy(a, delta, r, es, gamma) - reference;
                (a, krijt::elastic_force(a, delta, r, es), potential)
            } else {
                // in s = √(a/a0): F = Fc·4(s⁶ − s³), the stored energy Fc·δ0·(P(s²) − P_break)
                let fc = pair.fc;
                let s3 = s * s * s;
                let conservative = 4.0 * fc * s3 * (s3 - 1.0);
                let potential =
                    fc * d0 * (potential_shape_of_root(s) - self.pulloff.break_potential_shape());
                (a_eq, conservative, potential)
            }
        };
        history.touched = true;
        history.delta_max = history.delta_max.max(delta);
        NormalForce {
            force: conservative + self.normal_dissipation(a, delta, delta_dot, geom, pair),
            conservative,
            potential,
            in_contact: true,
            contact_radius: a,
            broke_within: None,
        }
    }

    /// Hertz contact time 2.87·(m*²/(R*·E*²·v))^(1/5) at impact speed `v` (scaled E*), s.
    pub fn hertz_contact_time(&self, r_eff: f64, m_eff: f64, v: f64) -> f64 {
        let es = self.e_star();
        2.87 * (m_eff * m_eff / (r_eff * es * es * v)).powf(0.2)
    }

    /// Rayleigh time π·r·√(ρ/G)/(0.1631·ν + 0.8766) of a sphere of radius `radius` and
    /// density `density` (scaled shear modulus G = S·E/(2(1 + ν))): the time a Rayleigh
    /// surface wave needs to cross it, the classic DEM bound on dt for elastic spheres, s.
    pub fn rayleigh_time(&self, radius: f64, density: f64) -> f64 {
        let g = self.stiffness_scale * self.youngs / (2.0 * (1.0 + self.poisson));
        std::f64::consts::PI * radius * (density / g).sqrt() / (0.1631 * self.poisson + 0.8766)
    }

    /// The adhesion speed √(2·Fc·δ0/m*), m/s: an impact slower than it loses a sizeable
    /// part of its kinetic energy to the adhesive zone (the undamped loss W is 0.77·Fc·δ0
    /// or less, so the sticking speed √(2W/m*) is below it).
    pub fn adhesion_speed(&self, r_eff: f64, reduced_mass: f64) -> f64 {
        (2.0 * self.fc(r_eff) * self.delta0(r_eff) / reduced_mass).sqrt()
    }

    /// Stiffness dF/dδ at the equilibrium overlap δ0: 1.2·Fc/δ0 (dF/dx = 6Fc and
    /// dδ/dx = 5δ0 at x = 1), N/m; 0 for Hertz.
    pub fn equilibrium_stiffness(&self, r_eff: f64) -> f64 {
        if self.gamma() == 0.0 {
            0.0
        } else {
            1.2 * self.fc(r_eff) / self.delta0(r_eff)
        }
    }
}

thread_local! {
    /// The last two cube roots of [`memo_cbrt`]: (argument bits, root).
    static CBRT_MEMO: std::cell::Cell<[(u64, f64); 2]> =
        const { std::cell::Cell::new([(u64::MAX, 0.0); 2]) };
}

/// `x.cbrt()`, bitwise, remembering the last two arguments: a0 and the unscaled a0 of a
/// pair are asked for several times per contact and step (δ0, the contact radius, the
/// rolling stiffness and ξcrit), with the same few radii in a packing.
fn memo_cbrt(x: f64) -> f64 {
    CBRT_MEMO.with(|m| {
        let mut c = m.get();
        let bits = x.to_bits();
        if c[0].0 == bits {
            return c[0].1;
        }
        if c[1].0 == bits {
            return c[1].1;
        }
        let y = x.cbrt();
        c[1] = c[0];
        c[0] = (bits, y);
        m.set(c);
        y
    })
}

#[cfg(test)]
mod tests;
