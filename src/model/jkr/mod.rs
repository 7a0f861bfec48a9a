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

pub mod mindlin;
mod pair;
mod radius;
pub mod rolling;
mod twisting;

use crate::model::friction::LudingFriction;
use crate::model::history::{HistoryField, HostField, Mirror, Shape};
use crate::model::krijt::{self, KrijtLaw, Relaxation};
use crate::model::{ContactHistory, NormalForce, PairGeometry};
pub use mindlin::Tangential;
pub use pair::JkrPair;
pub use radius::contact_radius_f32;
use radius::solve_t_f64;
pub use rolling::Rolling;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;

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
/// Newton iterations of the f32 contact-radius solver (the WGSL kernel's count).
pub const NEWTON_ITERATIONS_F32: usize = 3;

/// 2·√(5/6), the prefactor of the Tsuji damping (paper 002 eqs. 11 and 16).
const TSUJI_PREFACTOR: f64 = 1.8257418583505538;

/// Normal (and tangential) dissipation of the JKR family.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Dissipation {
    /// No dissipation: the only loss is the JKR contact hysteresis.
    #[default]
    None,
    /// Tsuji-type damping calibrated from a target restitution e ∈ (0, 1]
    /// (paper 002 eqs. 11–13 normal and 16 tangential). For Hertz (γ = 0) the restitution
    /// of a head-on collision equals the target, independent of the impact velocity, up to
    /// the integration error (`tests::tsuji_damping_calibration`, `docs/models.md`). With
    /// adhesion the JKR loss comes on top.
    Tsuji {
        /// Target coefficient of restitution e ∈ (0, 1].
        restitution: f64,
        /// The stiffness of the dashpots: the JKR contact radius (default) or paper 002's
        /// Hertz form.
        #[serde(default)]
        stiffness: TsujiStiffness,
    },
    /// Power-law dissipation F_dis = sgn(δ̇)·D·E*·|δ̇|^α·a^β (paper 001 eq. 19), in any
    /// consistent unit system (D carries the units). Normal direction only.
    PowerLaw {
        /// Prefactor D, m^(2−α−β)·s^α in SI (so that F_dis is in N).
        #[serde(rename = "D", alias = "d")]
        d: f64,
        /// Exponent α of the approach speed |δ̇|.
        alpha: f64,
        /// Exponent β of the contact radius a.
        beta: f64,
    },
    /// The Krijt viscoelastic JKR contact (paper 001 §II C, eqs. 10–12 and appendix B; see
    /// [`crate::model::krijt`]): the contact radius is its own state variable, driven by
    /// the crack speed of eq. B2, and a viscous force (2·T_vis·E*/ν²)·a·δ̇ acts. Normal
    /// direction only. Needs γ > 0 and ν ≠ 0.
    Krijt {
        /// Relaxation time T_vis ≥ 0, s.
        tvis: f64,
        /// σ0 ≈ γ/(atomic spacing) ≥ 0, Pa, of the crack speed (eq. B2); 0 (default) = the
        /// contact radius follows the JKR curve instantly.
        #[serde(default)]
        sigma0: f64,
    },
    /// The stress-dependent Krijt model of paper 001 §V A (eqs. 17–18):
    /// T_vis = C·R·exp[(B·p_c/E*)^ζ] for p_c > 0 (C·R otherwise), p_c the JKR centre
    /// pressure (eq. 9), R = 2R* (the particle radius for equal spheres).
    Stress {
        /// C ≥ 0, s/m: T_vis,0 = C·R (eq. 18).
        tvis0_per_radius: f64,
        /// B ≥ 0 (eq. 17).
        #[serde(rename = "B", alias = "b")]
        b: f64,
        /// ζ > 0 (eq. 17).
        zeta: f64,
        /// σ0 ≥ 0, Pa, as for `krijt`.
        #[serde(default)]
        sigma0: f64,
    },
}

/// The stiffness in the Tsuji dashpots, Sn = 2E*·ρ (normal, paper 002 eqs. 11–13) and
/// St = 8G*·ρ (tangential, eq. 16), with ρ a contact radius.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TsujiStiffness {
    /// ρ = a, the JKR contact radius: it exists (and the dashpots act) also at negative
    /// overlap while a JKR contact holds, and exceeds √(R*δ) at positive overlap.
    #[default]
    ContactRadius,
    /// ρ = √(R*·δ), zero at δ ≤ 0: paper 002's Hertz forms Sn = 2E*√(R*δ) (eq. 13) and
    /// St = 8G*√(R*δ) (below eq. 14), for which Tsuji's β(e) calibration was derived. The
    /// same as `ContactRadius` for Hertz (γ = 0), where a = √(R*δ).
    Hertz,
}

impl TsujiStiffness {
    /// ρ of Sn = 2E*·ρ and St = 8G*·ρ for contact radius `a` at overlap `delta`.
    pub fn radius(self, a: f64, delta: f64, r_eff: f64) -> f64 {
        match self {
            Self::ContactRadius => a,
            Self::Hertz => (r_eff * delta.max(0.0)).sqrt(),
        }
    }

    /// The name used in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::ContactRadius => "contact-radius",
            Self::Hertz => "hertz",
        }
    }
}

impl Dissipation {
    /// Tsuji damping with target restitution `restitution` and the default stiffness
    /// ([`TsujiStiffness::ContactRadius`]).
    pub fn tsuji(restitution: f64) -> Self {
        Self::Tsuji {
            restitution,
            stiffness: TsujiStiffness::ContactRadius,
        }
    }

    /// The Krijt law of the `krijt` and `stress` dissipations.
    pub fn krijt_law(&self) -> Option<KrijtLaw> {
        match *self {
            Self::Krijt { tvis, sigma0 } => Some(KrijtLaw {
                relaxation: Relaxation::Constant { tvis },
                sigma0,
            }),
            Self::Stress {
                tvis0_per_radius,
                b,
                zeta,
                sigma0,
            } => Some(KrijtLaw {
                relaxation: Relaxation::Stress {
                    c: tvis0_per_radius,
                    b,
                    zeta,
                },
                sigma0,
            }),
            _ => None,
        }
    }

    /// The name used in scenes and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Tsuji { .. } => "tsuji",
            Self::PowerLaw { .. } => "powerlaw",
            Self::Krijt { .. } => "krijt",
            Self::Stress { .. } => "stress",
        }
    }
}

/// Where a JKR contact breaks on separation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Pulloff {
    /// Displacement control (paper 001): the contact persists down to the turning point
    /// δc = −(3/4)^(2/3)·δ0, where F = −5/9·Fc.
    #[default]
    Displacement,
    /// Force control (LAMMPS's choice): the contact breaks where F reaches −Fc, at
    /// δ = −2^(−4/3)·δ0 ≈ −0.397·δ0.
    Force,
    /// Paper 002's rule: the contact breaks as soon as the overlap turns negative on
    /// separation, where F = −8/9·Fc as at the touch, so the JKR curve itself loses nothing.
    Zero,
}

impl Pulloff {
    /// δ/δ0 at which the contact breaks.
    pub fn break_overlap_ratio(self) -> f64 {
        match self {
            Self::Displacement => D_PULLOFF_DISPLACEMENT,
            Self::Force => D_PULLOFF_FORCE,
            Self::Zero => 0.0,
        }
    }

    /// a/a0 at which the contact breaks.
    pub fn break_radius_ratio(self) -> f64 {
        match self {
            Self::Displacement => X_PULLOFF_DISPLACEMENT,
            Self::Force => X_PULLOFF_FORCE,
            Self::Zero => X_TOUCH,
        }
    }

    /// [`potential_shape`] at the break radius ratio (tested against it).
    pub fn break_potential_shape(self) -> f64 {
        match self {
            Self::Displacement => P_PULLOFF_DISPLACEMENT,
            Self::Force => P_PULLOFF_FORCE,
            Self::Zero => P_TOUCH,
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

/// What a reduced stiffness S ≠ 1 changes (paper 002 §3, §6.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StiffnessScaling {
    /// S = Emod/E.
    pub scale: f64,
    /// γmod/γ = S^(2/5) (paper 002 eq. 24); also the factor on the pull-off force Fc.
    pub surface_energy_factor: f64,
    /// Δtcol,mod/Δtcol = (E/Emod)^(2/5) = S^(−2/5) (paper 002 §6.2).
    pub collision_time_factor: f64,
    /// How much larger the time step may be at a fixed number of steps per collision
    /// (the same factor as the collision time).
    pub dt_gain: f64,
    /// Fc,mod/Fc = S^(2/5): the force needed to separate two particles drops.
    pub pulloff_force_factor: f64,
}

impl fmt::Display for StiffnessScaling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stiffness_scale S = {:.4e}: E -> S*E and surface_energy -> surface_energy*S^(2/5) = {:.4}*surface_energy (paper 002 eq. 24); \
             collisions last S^(-2/5) = {:.4} times longer, so dt can grow by the same factor {:.4} (paper 002 sec. 6.2). \
             Warning: the pull-off force Fc = 3*pi*gamma*R* drops by S^(2/5) = {:.4}; keep external separating forces \
             (drag, shear) well below Fc,mod (paper 002 sec. 6.2)",
            self.scale,
            self.surface_energy_factor,
            self.collision_time_factor,
            self.dt_gain,
            self.pulloff_force_factor
        )?;
        if self.scale < 1e-3 {
            write!(
                f,
                ". S < 1e-3 may change the behaviour of dense agglomerates (paper 002 sec. 6.2)"
            )?;
        }
        Ok(())
    }
}

/// The Tsuji damping ratio β = ln e/√(ln²e + π²) (paper 002 eq. 12), ≤ 0.
pub fn tsuji_beta(restitution: f64) -> f64 {
    // the last value, per thread: asked for once per pair shape, with the same restitution
    thread_local!(static LAST: std::cell::Cell<(u64, f64)> = const { std::cell::Cell::new((u64::MAX, 0.0)) });
    LAST.with(|last| {
        let (bits, beta) = last.get();
        if bits == restitution.to_bits() {
            return beta;
        }
        let l = restitution.ln();
        let beta = l / (l * l + PI * PI).sqrt();
        last.set((restitution.to_bits(), beta));
        beta
    })
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

    /// The (negative) overlap at which a touching contact breaks, per [`Pulloff`]; 0 for
    /// Hertz.
    pub fn pulloff_overlap(&self, r_eff: f64) -> f64 {
        if self.gamma() == 0.0 {
            0.0
        } else {
            self.pulloff.break_overlap_ratio() * self.delta0(r_eff)
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
    /// In f64: a cubic Hermite start from a table over √(δ/δ0 − δc/δ0) and one Newton step,
    /// within 4 ulp of the guarded Newton run to convergence (which it uses past
    /// δ/δ0 ≈ 1023); δ(a(δ)) round-trips to 1e-12 over δ/δ0 ∈ [δc/δ0, 10⁸]. The f32 twin
    /// [`contact_radius_f32`], guarded Newton,
    /// 3 iterations (the initial guess is within 8.5 %; 2 iterations give 7.7e-7, 3 reach the
    /// f32 rounding floor): f32 relative error ≤ 4.4e-7 over δ/δ0 ∈ [−0.8255, 1000]
    /// against the f64 solve of the same rounded δ/δ0, including at the pull-off point.
    /// Against the f64 solve of the same f32 inputs δ, δ0 the error also contains the
    /// f32 rounding of δ/δ0 (≈ 5e-8), which the infinite slope da/dδ at δc amplifies
    /// (≈ 4e-8/√(δ/δ0 − δc/δ0)): ≤ 4.4e-7 for δ/δ0 − δc/δ0 ≥ 1e-2, ≤ 3.5e-6 for ≥ 1e-4,
    /// ≤ 2.9e-5 for ≥ 1e-6 and ≤ 1.1e-4 at the pull-off point itself (there the force is
    /// still accurate to ≈ 7e-5·Fc since dF/da is finite). This is conditioning, not the
    /// solver; f32 positions give far larger errors in δ anyway. Measured by
    /// `tests::f32_solver_accuracy`.
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

    /// A bound on the viscous coefficient c = 2·T_vis·E*·a/ν² of the `krijt`/`stress`
    /// dissipations in a collision at impact speed `v` (a at the larger of δ0 and the
    /// Hertz δmax of paper 001 eq. 15, T_vis at that radius), kg/s; 0 otherwise.
    pub fn viscous_coefficient_estimate(&self, geom: &PairGeometry, v: f64) -> f64 {
        let Some(law) = self.dissipation.krijt_law() else {
            return 0.0;
        };
        if self.gamma() == 0.0 {
            return 0.0;
        }
        let r = geom.r_eff();
        let dmax = crate::model::analytic::hertz_delta_max(geom.reduced_mass, r, self.e_star(), v)
            .max(self.delta0(r));
        let a = self.contact_radius(dmax, r);
        let m = self.krijt_material();
        let tvis = law.relaxation_time_at(a, r, &m);
        krijt::viscous_force(tvis, a, 1.0, &m)
    }

    /// The dissipative normal force for contact radius `a` at overlap `delta` and approach
    /// speed `delta_dot`, repulsive positive (it opposes δ̇).
    fn normal_dissipation(
        &self,
        a: f64,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        pair: &JkrPair,
    ) -> f64 {
        let (m, es) = (geom.reduced_mass, pair.es);
        match self.dissipation {
            Dissipation::None => 0.0,
            Dissipation::Tsuji { stiffness, .. } => {
                // Sn = 2E*·a by default (paper 002 eq. 13 writes 2E*√(Rδ), which is 2E*·a
                // for Hertz; the contact radius also exists at negative overlap in JKR), or
                // paper 002's 2E*·√(R*δ) (zero at δ ≤ 0)
                let sn = 2.0 * es * stiffness.radius(a, delta, geom.r_eff());
                -TSUJI_PREFACTOR * pair.beta * (sn * m).sqrt() * delta_dot
            }
            Dissipation::PowerLaw { d, alpha, beta } => {
                if delta_dot == 0.0 {
                    0.0
                } else {
                    delta_dot.signum() * d * es * delta_dot.abs().powf(alpha) * a.powf(beta)
                }
            }
            Dissipation::Krijt { .. } | Dissipation::Stress { .. } => {
                let Some(law) = self.dissipation.krijt_law() else {
                    return 0.0;
                };
                let mat = self.krijt_material();
                let tvis = law.relaxation_time_at(a, geom.r_eff(), &mat);
                krijt::viscous_force(tvis, a, delta_dot, &mat)
            }
        }
    }

    /// The normal force just inside the contact's two edges, where it jumps: at the touch
    /// (δ = 0, ≈ −8/9·Fc for JKR) and at the break (δ = pull-off overlap, −5/9·Fc or −Fc),
    /// each with the dissipative force at that contact radius. The energy ledger integrates
    /// the work of a step that crosses an edge from there rather than from zero.
    pub fn edge_forces(&self, geom: &PairGeometry, delta_dot: f64) -> [(f64, f64); 2] {
        let r = 0.5 * geom.a12;
        let pair = self.pair(r);
        let at = |delta: f64| {
            let a = self.contact_radius(delta, r);
            self.elastic_force(a, r) + self.normal_dissipation(a, delta, delta_dot, geom, &pair)
        };
        let exit = self.pulloff_overlap(r);
        [(0.0, at(0.0)), (exit, at(exit))]
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
    /// the same overlap as JKR ([`Pulloff`]). The other dissipations ignore dt.
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
        (touched || delta > 0.0) && delta > self.pulloff.break_overlap_ratio() * pair.scales.d0
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
                let a = law.step_radius(a_old, a_eq, delta, dt, r, &mat);
                history.contact_radius = a;
                let es = mat.e_star;
                let reference = krijt::stored_energy(
                    self.pulloff.break_radius_ratio() * a0,
                    self.pulloff.break_overlap_ratio() * d0,
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

    /// What the stiffness scale changes; `None` when S = 1.
    pub fn stiffness_scaling(&self) -> Option<StiffnessScaling> {
        if self.stiffness_scale == 1.0 {
            return None;
        }
        let g = self.stiffness_scale.powf(0.4);
        Some(StiffnessScaling {
            scale: self.stiffness_scale,
            surface_energy_factor: g,
            collision_time_factor: 1.0 / g,
            dt_gain: 1.0 / g,
            pulloff_force_factor: g,
        })
    }

    /// Human-readable report of [`Self::stiffness_scaling`] (with the pull-off warning of
    /// paper 002 §6.2); `None` when S = 1.
    pub fn stiffness_scaling_report(&self) -> Option<String> {
        self.stiffness_scaling().map(|s| s.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Kinematics;
    use approx::assert_relative_eq;
    use glam::DVec3;

    // Silica-like micro-spheres: r = 1 µm each, E = 70 GPa, ν = 0.17, γ = 0.05 J/m².
    const R1: f64 = 1e-6;

    fn params() -> JkrParams {
        JkrParams::jkr(70e9, 0.17, 0.05)
    }

    fn geom() -> PairGeometry {
        let m = 2200.0 * 4.0 / 3.0 * PI * R1.powi(3);
        PairGeometry::spheres(R1, R1, m, m)
    }

    fn reff() -> f64 {
        0.5 * geom().a12
    }

    /// The kinematics the tangential force reads: normal, tangential velocity, overlap.
    fn kin(n: DVec3, v_t: DVec3, delta: f64) -> Kinematics {
        Kinematics {
            n,
            v_t,
            delta,
            ..Default::default()
        }
    }

    /// Force with a fresh, touched history (the stable branch).
    fn touched_force(p: &JkrParams, delta: f64) -> NormalForce {
        let mut h = ContactHistory {
            touched: true,
            ..Default::default()
        };
        p.normal_force(delta, 0.0, &geom(), &mut h)
    }

    /// A force loop solves a root ahead exactly where the normal force solves one, and the
    /// force given it is the force that solves it: same force, same history, bit for bit.
    #[test]
    fn roots_are_solved_ahead_where_the_force_needs_them() {
        let g = geom();
        let r = reff();
        let base = params();
        let tsuji = JkrParams {
            dissipation: Dissipation::Tsuji {
                restitution: 0.5,
                stiffness: TsujiStiffness::default(),
            },
            ..base
        };
        let krijt = JkrParams {
            dissipation: Dissipation::Krijt {
                tvis: 1e-9,
                sigma0: 0.0,
            },
            ..base
        };
        let mut ahead = 0;
        for p0 in [base, tsuji, krijt] {
            for pulloff in [Pulloff::Displacement, Pulloff::Force, Pulloff::Zero] {
                let p = JkrParams { pulloff, ..p0 };
                let pair = p.pair(r);
                let d0 = p.delta0(r);
                for step in -300..=600 {
                    let delta = step as f64 * 0.01 * d0;
                    for touched in [false, true] {
                        let h0 = ContactHistory {
                            touched,
                            contact_radius: if touched { 0.9 * p.a0(r) } else { 0.0 },
                            ..Default::default()
                        };
                        let (mut h1, mut h2) = (h0, h0);
                        let kin = (delta, -0.01);
                        let solved = p.normal_force_of_pair(&pair, kin, &g, 1e-9, &mut h1);
                        let root = p.root_ahead(&pair, delta, touched);
                        let given = p.normal_force_rooted(&pair, kin, root, &g, 1e-9, &mut h2);
                        assert_eq!(
                            solved, given,
                            "{pulloff:?} δ = {delta:e}, touched {touched}"
                        );
                        assert_eq!(h1, h2);
                        // every solve is done ahead (else the force loop gains nothing)
                        assert_eq!(root.is_some(), solved.in_contact, "δ = {delta:e}");
                        ahead += usize::from(root.is_some());
                    }
                }
            }
        }
        assert!(ahead > 1000, "{ahead}");
    }

    #[test]
    fn landmarks_of_the_normalised_curve() {
        assert_relative_eq!(S_MIN, 6f64.powf(-1.0 / 3.0), max_relative = 1e-15);
        assert_relative_eq!(
            D_PULLOFF_DISPLACEMENT,
            -(0.75f64).powf(2.0 / 3.0),
            max_relative = 1e-15
        );
        assert_relative_eq!(D_PULLOFF_DISPLACEMENT, -1.5 * S_MIN, max_relative = 1e-15);
        assert_relative_eq!(
            D_PULLOFF_FORCE,
            -(2f64).powf(-4.0 / 3.0),
            max_relative = 1e-15
        );
        assert_relative_eq!(X_PULLOFF_DISPLACEMENT, S_MIN * S_MIN, max_relative = 1e-15);
        assert_relative_eq!(
            X_PULLOFF_FORCE,
            0.5f64.powf(2.0 / 3.0),
            max_relative = 1e-15
        );
        assert_relative_eq!(
            X_TOUCH,
            (2.0f64 / 3.0).powf(2.0 / 3.0),
            max_relative = 1e-15
        );
        // d(x) = 3x² − 2√x at the landmarks
        let d = |x: f64| 3.0 * x * x - 2.0 * x.sqrt();
        assert!(d(X_TOUCH).abs() < 1e-15);
        assert_relative_eq!(d(X_PULLOFF_FORCE), D_PULLOFF_FORCE, max_relative = 1e-14);
        assert_relative_eq!(
            d(X_PULLOFF_DISPLACEMENT),
            D_PULLOFF_DISPLACEMENT,
            max_relative = 1e-14
        );
    }

    #[test]
    fn break_potential_shapes_are_the_potential_at_the_break() {
        for rule in [Pulloff::Displacement, Pulloff::Force, Pulloff::Zero] {
            assert_eq!(
                rule.break_potential_shape(),
                potential_shape(rule.break_radius_ratio()),
                "{rule:?}"
            );
        }
    }

    #[test]
    fn contact_radius_round_trips() {
        let p = params();
        let r = reff();
        let (a0, d0) = (p.a0(r), p.delta0(r));
        // δ → a → δ: well conditioned everywhere, including the pull-off point
        let mut worst: f64 = 0.0;
        let mut ds: Vec<f64> = (0..=2000)
            .map(|i| D_PULLOFF_DISPLACEMENT + 1e-14 * 10f64.powf(i as f64 * 0.0075))
            .collect();
        ds.extend((0..=4000).map(|i| -0.9 + i as f64 * 1e-3));
        ds.extend((0..=600).map(|i| 10f64.powf(-3.0 + i as f64 * 0.02)));
        for &d in &ds {
            let delta = d * d0;
            let a = p.contact_radius(delta, r);
            let back = p.overlap_for_radius(a, r);
            let expect = delta.max(D_PULLOFF_DISPLACEMENT * d0);
            let err = (back - expect).abs() / (d0 * d.abs().max(1.0));
            worst = worst.max(err);
        }
        assert!(worst < 1e-12, "δ(a(δ)) worst relative error {worst:e}");
        // a → δ → a: ill-conditioned only right at the pull-off point (da/dδ = ∞ there)
        for i in 0..=1000 {
            let x = X_PULLOFF_DISPLACEMENT * (1.0 + 1e-3) + i as f64 * 0.01;
            let a = x * a0;
            let back = p.contact_radius(p.overlap_for_radius(a, r), r);
            assert_relative_eq!(back, a, max_relative = 1e-12);
        }
        let a = X_PULLOFF_DISPLACEMENT * a0;
        assert_relative_eq!(
            p.contact_radius(D_PULLOFF_DISPLACEMENT * d0, r),
            a,
            max_relative = 1e-7
        );
        // below the pull-off overlap the radius is clamped to the pull-off radius
        assert_relative_eq!(p.contact_radius(-2.0 * d0, r), a, max_relative = 1e-14);
        // equilibrium
        assert_relative_eq!(p.contact_radius(d0, r), a0, max_relative = 1e-14);
    }

    #[test]
    fn f64_solver_converges_far_out() {
        // very large δ/δ0 (nearly Hertz): the solver still converges in its fixed count
        let p = params();
        let r = reff();
        let d0 = p.delta0(r);
        for d in [1e3, 1e5, 1e8] {
            let a = p.contact_radius(d * d0, r);
            assert_relative_eq!(p.overlap_for_radius(a, r), d * d0, max_relative = 1e-13);
        }
    }

    #[test]
    fn force_landmarks() {
        let p = params();
        let r = reff();
        let (fc, d0) = (p.fc(r), p.delta0(r));
        let f = |d: f64| p.elastic_force(p.contact_radius(d * d0, r), r);
        assert_relative_eq!(f(0.0), -8.0 / 9.0 * fc, max_relative = 1e-12);
        assert_relative_eq!(f(D_PULLOFF_FORCE), -fc, max_relative = 1e-12);
        assert_relative_eq!(
            f(D_PULLOFF_DISPLACEMENT),
            -5.0 / 9.0 * fc,
            max_relative = 1e-7
        );
        assert!(f(1.0).abs() < 1e-12 * fc);
        // −Fc is the minimum along the branch
        for i in 0..200 {
            let d = D_PULLOFF_DISPLACEMENT + i as f64 * 0.01;
            assert!(f(d) >= -fc * (1.0 + 1e-12));
        }
        // pull-off overlaps
        assert_relative_eq!(
            p.pulloff_overlap(r),
            -(0.75f64).powf(2.0 / 3.0) * d0,
            max_relative = 1e-14
        );
        let q = JkrParams {
            pulloff: Pulloff::Force,
            ..p
        };
        assert_relative_eq!(
            q.pulloff_overlap(r),
            -0.3968502629920499 * d0,
            max_relative = 1e-14
        );
        assert_eq!(JkrParams::hertz(1e9, 0.3).pulloff_overlap(r), 0.0);
        // the paper-001 numbers: Fc = 3πγR*, δ0 = a0²/(3R*)
        assert_relative_eq!(fc, 3.0 * PI * 0.05 * r, max_relative = 1e-15);
        let es = 70e9 / (2.0 * (1.0 - 0.17 * 0.17));
        assert_relative_eq!(p.e_star(), es, max_relative = 1e-15);
        assert_relative_eq!(
            p.a0(r),
            (9.0 * PI * 0.05 * r * r / es).cbrt(),
            max_relative = 1e-15
        );
    }

    #[test]
    fn hertz_limit() {
        let r = reff();
        let h = JkrParams::hertz(70e9, 0.17);
        let es = h.e_star();
        for delta in [1e-10, 1e-9, 1e-8] {
            let f = touched_force(&h, delta);
            let expect = 4.0 / 3.0 * es * r.sqrt() * delta.powf(1.5);
            assert_relative_eq!(f.conservative, expect, max_relative = 1e-14);
            assert_relative_eq!(
                f.potential,
                8.0 / 15.0 * es * r.sqrt() * delta.powf(2.5),
                max_relative = 1e-14
            );
            // JKR with a vanishing surface energy tends to Hertz
            let j = JkrParams::jkr(70e9, 0.17, 1e-12);
            let fj = touched_force(&j, delta);
            assert_relative_eq!(fj.conservative, expect, max_relative = 1e-3);
            let jj = JkrParams::jkr(70e9, 0.17, 1e-16);
            let fjj = touched_force(&jj, delta);
            assert_relative_eq!(fjj.conservative, expect, max_relative = 3e-5);
            assert!((fjj.conservative - expect).abs() < (fj.conservative - expect).abs());
        }
        // Hertz: no contact at δ ≤ 0, even after touching
        let mut hist = ContactHistory::default();
        assert!(h.normal_force(1e-9, 0.0, &geom(), &mut hist).in_contact);
        let f = h.normal_force(-1e-12, 0.0, &geom(), &mut hist);
        assert!(!f.in_contact && f.force == 0.0 && !hist.touched);
    }

    #[test]
    fn potential_is_the_integral_of_the_force() {
        let p = params();
        let r = reff();
        let (fc, d0) = (p.fc(r), p.delta0(r));
        for d in [-0.8, -0.5, -0.2, 0.0, 0.3, 1.0, 2.0, 10.0] {
            let h = 1e-5 * d0;
            let up = touched_force(&p, d * d0 + h).potential;
            let down = touched_force(&p, d * d0 - h).potential;
            let f = touched_force(&p, d * d0).conservative;
            assert!(
                ((up - down) / (2.0 * h) - f).abs() < 1e-7 * fc,
                "dU/dδ at d = {d}: {} vs {f}",
                (up - down) / (2.0 * h)
            );
        }
        // Hertz
        let hz = JkrParams::hertz(70e9, 0.17);
        let delta = 1e-9;
        let h = 1e-14;
        let du = (touched_force(&hz, delta + h).potential
            - touched_force(&hz, delta - h).potential)
            / (2.0 * h);
        assert_relative_eq!(
            du,
            touched_force(&hz, delta).conservative,
            max_relative = 1e-7
        );
        // P(x) is the antiderivative: P'(x) = F/Fc·dδ/dx /δ0
        for x in [0.3, 0.5, 0.9, 1.5] {
            let h = 1e-6;
            let dp = (potential_shape(x + h) - potential_shape(x - h)) / (2.0 * h);
            let integrand = (4.0 * x.powi(3) - 4.0 * x.powf(1.5)) * (6.0 * x - x.powf(-0.5));
            assert_relative_eq!(dp, integrand, max_relative = 1e-8);
        }
        // the potential vanishes at the break point
        let at_break = touched_force(&p, D_PULLOFF_DISPLACEMENT * d0 * (1.0 - 1e-12)).potential;
        assert!(at_break.abs() < 1e-6 * fc * d0);
        equilibrium_stiffness_fd(&p);
    }

    /// dF/dδ at δ0 by finite differences equals 1.2·Fc/δ0.
    fn equilibrium_stiffness_fd(p: &JkrParams) {
        let r = reff();
        let d0 = p.delta0(r);
        let h = 1e-6 * d0;
        let k = (touched_force(p, d0 + h).conservative - touched_force(p, d0 - h).conservative)
            / (2.0 * h);
        assert_relative_eq!(k, p.equilibrium_stiffness(r), max_relative = 1e-8);
        assert_relative_eq!(
            p.equilibrium_stiffness(r),
            1.2 * p.fc(r) / d0,
            max_relative = 1e-15
        );
    }

    #[test]
    fn cycle_loss_from_the_potential() {
        let p = params();
        let r = reff();
        let (fc, d0) = (p.fc(r), p.delta0(r));
        // the potential just after the touch is −(energy lost over the cycle): the
        // bookkeeping drops by W at the touch and is continuous at the break
        let w = -touched_force(&p, 1e-13 * d0).potential;
        assert_relative_eq!(w / (fc * d0), 0.7722, max_relative = 1e-4);
        assert_relative_eq!(w / (fc * d0), 0.7722405328755862, max_relative = 1e-9);
        let q = JkrParams {
            pulloff: Pulloff::Force,
            ..p
        };
        let wq = -touched_force(&q, 1e-13 * d0).potential;
        assert_relative_eq!(wq / (fc * d0), 0.3813841613953991, max_relative = 1e-9);
    }

    /// Head-on pair integrated with velocity Verlet (the engine's scheme), δ from the
    /// separation. Returns (approach speed at the end (negative: separating), stuck, contact
    /// time).
    fn collide(p: &JkrParams, v: f64, steps_per_d0: f64) -> (f64, bool, f64) {
        let g = geom();
        let r = reff();
        let m = g.reduced_mass;
        let scale = if p.gamma() > 0.0 {
            p.delta0(r)
        } else {
            // Hertz: the largest overlap
            (15.0 * m * v * v / (16.0 * p.e_star() * r.sqrt())).powf(0.4)
        };
        let dt = scale / steps_per_d0 / v;
        let mut hist = ContactHistory::default();
        let mut delta = -1e-3 * scale;
        let mut vel = v;
        let mut f = p.normal_force(delta, vel, &g, &mut hist).force;
        let mut t_contact = 0.0;
        let mut was_in = false;
        for _ in 0..200_000_000u64 {
            let vh = vel - 0.5 * dt * f / m;
            delta += vh * dt;
            // velocity-dependent force: evaluate with the half-step velocity predictor
            let nf = p.normal_force(delta, vh - 0.5 * dt * f / m, &g, &mut hist);
            f = nf.force;
            vel = vh - 0.5 * dt * f / m;
            if nf.in_contact {
                t_contact += dt;
                was_in = true;
            } else if was_in {
                return (vel, false, t_contact);
            }
            if t_contact > 0.0 && delta < -2.0 * scale {
                return (vel, false, t_contact);
            }
        }
        (vel, true, t_contact)
    }

    #[test]
    fn undamped_jkr_collision_loses_the_cycle_energy() {
        let p = params();
        let r = reff();
        let m = geom().reduced_mass;
        let w = p.fc(r) * p.delta0(r) * 0.7722405328755862;
        let v_stick = (2.0 * w / m).sqrt();
        for factor in [1.5, 3.0] {
            let v = factor * v_stick;
            let (vout, stuck, _) = collide(&p, v, 2e5);
            assert!(!stuck);
            let lost = 0.5 * m * (v * v - vout * vout);
            assert_relative_eq!(lost, w, max_relative = 1e-4);
            let e = -vout / v;
            assert_relative_eq!(e, (1.0 - w / (0.5 * m * v * v)).sqrt(), max_relative = 1e-4);
        }
    }

    #[test]
    fn hysteresis_of_touch_and_pulloff() {
        let p = params();
        let r = reff();
        let g = geom();
        let d0 = p.delta0(r);
        let mut h = ContactHistory::default();
        // approaching from δ < 0: nothing
        for d in [-0.9, -0.5, -0.1, 0.0] {
            let f = p.normal_force(d * d0, 1.0, &g, &mut h);
            assert_eq!(f, NormalForce::default());
            assert!(!h.touched);
        }
        // touch
        let f = p.normal_force(1e-9 * d0, 1.0, &g, &mut h);
        assert!(h.touched && f.in_contact);
        assert_relative_eq!(f.conservative, -8.0 / 9.0 * p.fc(r), max_relative = 1e-6);
        h.tangential = DVec3::new(1e-9, 0.0, 0.0);
        h.rolling = DVec3::new(0.0, 1e-9, 0.0);
        // separating into negative overlap: still in contact, attractive
        let f = p.normal_force(-0.1 * d0, -1.0, &g, &mut h);
        assert!(f.in_contact && f.force < 0.0 && f.contact_radius > 0.0);
        let f = p.normal_force(-0.8254 * d0, -1.0, &g, &mut h);
        assert!(f.in_contact);
        assert_relative_eq!(f.conservative, -5.0 / 9.0 * p.fc(r), max_relative = 5e-2);
        // past δc: broken, history reset
        let f = p.normal_force(-0.826 * d0, -1.0, &g, &mut h);
        assert_eq!(f, NormalForce::default());
        assert_eq!(h, ContactHistory::default());
        // and no force on the way back in until δ > 0
        let f = p.normal_force(-0.1 * d0, 1.0, &g, &mut h);
        assert_eq!(f, NormalForce::default());
        // force-controlled pull-off breaks at −0.397·δ0
        let q = JkrParams {
            pulloff: Pulloff::Force,
            ..p
        };
        let mut h = ContactHistory::default();
        q.normal_force(0.5 * d0, 0.0, &g, &mut h);
        assert!(q.normal_force(-0.39 * d0, 0.0, &g, &mut h).in_contact);
        assert!(!q.normal_force(-0.40 * d0, 0.0, &g, &mut h).in_contact);
    }

    #[test]
    fn f32_solver_accuracy() {
        let p = params();
        let r = reff();
        let (a0, d0) = (p.a0(r) as f32, p.delta0(r) as f32);
        let mut ds: Vec<f64> = vec![-0.8255, D_PULLOFF_DISPLACEMENT];
        // near the pull-off point, logarithmically in the distance d − dc
        ds.extend(
            (0..=3000).map(|i| D_PULLOFF_DISPLACEMENT + 10f64.powf(-12.0 + i as f64 * 0.004)),
        );
        // the whole attractive range and around 0
        ds.extend((0..=200_000).map(|i| -0.8255 + i as f64 * 1e-5));
        ds.extend((0..=2000).map(|i| -1e-3 + i as f64 * 1e-6));
        // logarithmically up to 1000
        ds.extend((0..=20_000).map(|i| 10f64.powf(-8.0 + i as f64 * 5.5e-4)));
        // worst error per band of e = d − dc: [< 1e-6, < 1e-4, < 1e-2, ≥ 1e-2], against the
        // f64 solve of the same f32 inputs (total), and against the f64 solve of the same
        // f32-rounded d (the solver's own error)
        let mut total = [0.0f64; 4];
        let mut own = 0.0f64;
        for &d in &ds {
            let delta = (d * d0 as f64) as f32;
            let a32 = contact_radius_f32(delta, r as f32, a0, d0) as f64;
            let exact_d = delta as f64 / d0 as f64;
            let s = S_MIN + solve_t_f64(exact_d - D_PULLOFF_DISPLACEMENT);
            let a64 = a0 as f64 * s * s;
            let e = exact_d - D_PULLOFF_DISPLACEMENT;
            let band = match e {
                e if e < 1e-6 => 0,
                e if e < 1e-4 => 1,
                e if e < 1e-2 => 2,
                _ => 3,
            };
            total[band] = total[band].max((a32 - a64).abs() / a64);
            let rounded_d = (delta / d0) as f64;
            let s = S_MIN + solve_t_f64(rounded_d - (D_PULLOFF_DISPLACEMENT as f32) as f64);
            let a64 = a0 as f64 * s * s;
            own = own.max((a32 - a64).abs() / a64);
        }
        eprintln!(
            "f32 contact radius ({NEWTON_ITERATIONS_F32} iterations): relative error by \
             d - dc in [<1e-6, <1e-4, <1e-2, >=1e-2]: {:.3e} {:.3e} {:.3e} {:.3e}; \
             solver's own (same rounded d): {own:.3e}",
            total[0], total[1], total[2], total[3]
        );
        assert!(own < 6e-7, "solver error {own:e}");
        assert!(total[3] < 6e-7, "{total:?}");
        assert!(total[2] < 5e-6, "{total:?}");
        assert!(total[1] < 5e-5, "{total:?}");
        assert!(total[0] < 2e-4, "{total:?}");
        // equilibrium
        assert_relative_eq!(
            contact_radius_f32(d0, r as f32, a0, d0) as f64,
            a0 as f64,
            max_relative = 3e-7
        );
        // Hertz fallback
        let a = contact_radius_f32(1e-9, 1e-6, 0.0, 0.0);
        assert_relative_eq!(a as f64, (1e-15f64).sqrt(), max_relative = 1e-6);
        assert_eq!(contact_radius_f32(-1e-9, 1e-6, 0.0, 0.0), 0.0);
    }

    /// RK4 integration of a head-on Hertz + Tsuji collision: (restitution, contact time).
    fn tsuji_collision(p: &JkrParams, v: f64) -> (f64, f64) {
        let g = geom();
        let m = g.reduced_mass;
        let tc = p.hertz_contact_time(reff(), m, v);
        let dt = tc / 200_000.0;
        let acc = |d: f64, dd: f64| -> f64 {
            let mut h = ContactHistory::default();
            -p.normal_force(d, dd, &g, &mut h).force / m
        };
        let (mut d, mut dd, mut t) = (0.0f64, v, 0.0f64);
        for _ in 0..100_000_000u64 {
            let (k1x, k1v) = (dd, acc(d, dd));
            let (k2x, k2v) = (
                dd + 0.5 * dt * k1v,
                acc(d + 0.5 * dt * k1x, dd + 0.5 * dt * k1v),
            );
            let (k3x, k3v) = (
                dd + 0.5 * dt * k2v,
                acc(d + 0.5 * dt * k2x, dd + 0.5 * dt * k2v),
            );
            let (k4x, k4v) = (dd + dt * k3v, acc(d + dt * k3x, dd + dt * k3v));
            let nd = d + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            let ndd = dd + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            if nd <= 0.0 && t > 0.0 {
                // linear interpolation to δ = 0
                let frac = d / (d - nd);
                return (-(dd + frac * (ndd - dd)) / v, t + frac * dt);
            }
            d = nd;
            dd = ndd;
            t += dt;
        }
        panic!("the pair did not separate (e_target too small?)");
    }

    #[test]
    fn tsuji_damping_calibration() {
        let hz = JkrParams::hertz(70e9, 0.17);
        // undamped: e = 1 and the Hertz contact time 2.87·(m²/(R E² v))^(1/5)
        let (e, t) = tsuji_collision(&hz, 0.1);
        assert_relative_eq!(e, 1.0, max_relative = 1e-9);
        assert_relative_eq!(
            t,
            hz.hertz_contact_time(reff(), geom().reduced_mass, 0.1),
            max_relative = 2e-3
        );
        let mut report = String::new();
        for target in [0.95, 0.9, 0.7, 0.5, 0.3, 0.1] {
            let p = JkrParams {
                dissipation: Dissipation::tsuji(target),
                ..hz
            };
            // paper 002's Hertz stiffness rule: for Hertz a = √(R*δ), so bitwise the same
            let q = JkrParams {
                dissipation: Dissipation::Tsuji {
                    restitution: target,
                    stiffness: TsujiStiffness::Hertz,
                },
                ..hz
            };
            let mut es = Vec::new();
            for v in [1e-3, 0.1, 10.0] {
                let (e, _) = tsuji_collision(&p, v);
                assert_eq!(e.to_bits(), tsuji_collision(&q, v).0.to_bits());
                es.push(e);
            }
            // velocity-independent (the damping ∝ δ^(1/4)·δ̇ keeps Hertz self-similar)
            for e in &es {
                assert_relative_eq!(*e, es[0], max_relative = 1e-12);
            }
            let rel = es[0] / target - 1.0;
            report.push_str(&format!(
                "e_target {target}: e = {:.9} ({rel:+.2e})\n",
                es[0]
            ));
            // measured: the calibration is exact for Hertz up to the integration error
            // (+2.5e-7 at dt = tc/2e5, +1.6e-8 at tc/1e6, shrinking with dt)
            assert!(rel.abs() < 1e-6, "target {target}: e = {}", es[0]);
        }
        eprintln!("{report}");
    }

    #[test]
    fn power_law_dissipation() {
        let p = JkrParams {
            dissipation: Dissipation::PowerLaw {
                d: 118.0,
                alpha: 3.0,
                beta: 1.5,
            },
            ..params()
        };
        let r = reff();
        let g = geom();
        let d0 = p.delta0(r);
        let mut h = ContactHistory::default();
        let f = p.normal_force(0.5 * d0, 0.2, &g, &mut h);
        let expect = 118.0 * p.e_star() * 0.2f64.powi(3) * f.contact_radius.powf(1.5);
        assert_relative_eq!(f.force - f.conservative, expect, max_relative = 1e-12);
        // opposes the motion on the way out, zero at rest
        let f = p.normal_force(0.5 * d0, -0.2, &g, &mut h);
        assert_relative_eq!(f.force - f.conservative, -expect, max_relative = 1e-12);
        let f = p.normal_force(0.5 * d0, 0.0, &g, &mut h);
        assert_eq!(f.force, f.conservative);
        // Tsuji acts at negative overlap too (a > 0 there)
        let t = JkrParams {
            dissipation: Dissipation::tsuji(0.5),
            ..params()
        };
        let f = t.normal_force(-0.5 * d0, -0.1, &g, &mut h);
        assert!(f.in_contact && f.force < f.conservative);
    }

    /// Paper 002's stiffness rule for the Tsuji dashpots: Sn = 2E*·√(R*δ) and
    /// St = 8G*·√(R*δ), zero at δ ≤ 0, where the default uses the JKR contact radius a
    /// (larger than √(R*δ) at δ > 0, and positive at δ ≤ 0 while the contact holds).
    #[test]
    fn tsuji_hertz_stiffness_rule() {
        let hertz_rule = |p: JkrParams| JkrParams {
            dissipation: Dissipation::Tsuji {
                restitution: 0.5,
                stiffness: TsujiStiffness::Hertz,
            },
            ..p
        };
        let (p, q) = (
            JkrParams {
                friction: 0.3,
                dissipation: Dissipation::tsuji(0.5),
                ..params()
            },
            hertz_rule(JkrParams {
                friction: 0.3,
                ..params()
            }),
        );
        let (r, g) = (reff(), geom());
        let (d0, m) = (p.delta0(r), g.reduced_mass);
        let c = -TSUJI_PREFACTOR * tsuji_beta(0.5);
        let touched = || ContactHistory {
            touched: true,
            ..Default::default()
        };
        for d in [0.3, 1.0, 5.0] {
            let delta = d * d0;
            let (fp, fq) = (
                p.normal_force(delta, 0.2, &g, &mut touched()),
                q.normal_force(delta, 0.2, &g, &mut touched()),
            );
            // the same elastic force, the damping from √(R*δ) instead of a
            assert_eq!(fp.conservative, fq.conservative);
            let rho = (r * delta).sqrt();
            assert!(rho < fp.contact_radius);
            assert_relative_eq!(
                fq.force - fq.conservative,
                c * (2.0 * q.e_star() * rho * m).sqrt() * 0.2,
                max_relative = 1e-12
            );
            assert_relative_eq!(
                fp.force - fp.conservative,
                c * (2.0 * p.e_star() * fp.contact_radius * m).sqrt() * 0.2,
                max_relative = 1e-12
            );
            // tangential: the spring keeps 8G*·a, the dashpot takes 8G*·√(R*δ)
            let v = DVec3::new(0.0, 1e-3, 0.0);
            let (mut sp, mut sq) = (DVec3::ZERO, DVec3::ZERO);
            let tp = p.tangential_force(&kin(DVec3::X, v, delta), &fp, &g, 1e-12, &mut sp);
            let tq = q.tangential_force(&kin(DVec3::X, v, delta), &fq, &g, 1e-12, &mut sq);
            assert_eq!(tp.stiffness, tq.stiffness);
            assert_eq!(sp, sq);
            let st = 8.0 * q.g_star() * fq.contact_radius;
            let ct = c * (8.0 * q.g_star() * rho * m).sqrt();
            assert!(!tq.sliding);
            assert!((tq.force - (-st * sq - ct * v)).length() < 1e-12 * tq.force.length());
            assert!(tq.force.length() < tp.force.length());
        }
        // negative overlap: the contact holds and attracts, the Hertz-rule dashpots are off
        let delta = -0.5 * d0;
        let (fp, fq) = (
            p.normal_force(delta, -0.2, &g, &mut touched()),
            q.normal_force(delta, -0.2, &g, &mut touched()),
        );
        assert!(fq.in_contact && fq.contact_radius > 0.0);
        assert_eq!(fq.force, fq.conservative);
        assert!(fp.force < fp.conservative);
        let v = DVec3::new(0.0, 1e-3, 0.0);
        let mut sq = DVec3::ZERO;
        let tq = q.tangential_force(&kin(DVec3::X, v, delta), &fq, &g, 1e-12, &mut sq);
        assert!((tq.force + tq.stiffness * sq).length() <= 1e-15 * tq.force.length());
        // no damping at the contact's edges (δ = 0 and the pull-off overlap)
        for (delta, f) in q.edge_forces(&g, 1.0) {
            let a = q.contact_radius(delta, r);
            assert_eq!(f, q.elastic_force(a, r), "edge at {delta}");
        }
        // validation and serde: the default is the contact radius; "hertz" round-trips
        assert!(q.validate().is_ok());
        let json = serde_json::to_string(&q).unwrap();
        assert!(json.contains("\"stiffness\":\"hertz\""), "{json}");
        assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), q);
        assert_eq!(TsujiStiffness::default(), TsujiStiffness::ContactRadius);
        assert_eq!(TsujiStiffness::Hertz.name(), "hertz");
    }

    #[test]
    fn tangential_spring_and_coulomb_limit() {
        let p = JkrParams {
            friction: 0.3,
            dissipation: Dissipation::tsuji(0.5),
            ..params()
        };
        let r = reff();
        let g = geom();
        let d0 = p.delta0(r);
        let mut h = ContactHistory::default();
        let normal = p.normal_force(d0, 0.0, &g, &mut h);
        let n = DVec3::X;
        let st = 8.0 * p.g_star() * normal.contact_radius;
        let ct = -TSUJI_PREFACTOR * tsuji_beta(0.5) * (st * g.reduced_mass).sqrt();
        assert!(ct > 0.0);
        let limit = 0.3 * (normal.conservative + 2.0 * p.fc(r)).abs();
        // below the limit: F = −St·s − c·v_t
        let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
        let v = DVec3::new(0.0, 0.0, 1e-6);
        let dt = 1e-9;
        let t = p.tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
        let s_expect = DVec3::new(0.0, 1e-3 * d0, 1e-15);
        assert!((s - s_expect).length() < 1e-12 * s_expect.length());
        let f_expect = -st * s_expect - ct * v;
        assert!(!t.sliding && (t.force - f_expect).length() < 1e-12 * f_expect.length());
        assert!(f_expect.length() < limit);
        assert_relative_eq!(t.stiffness, st, max_relative = 1e-15);
        // above the limit: |F| = μs·|F_N + 2Fc| exactly, spring consistent with the force
        let mut s = DVec3::new(0.0, 10.0 * d0, 0.0);
        let t = p.tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
        assert!(t.sliding);
        assert_relative_eq!(t.force.length(), limit, max_relative = 1e-14);
        assert!((-st * s - ct * v - t.force).length() < 1e-12 * limit);
        assert!(t.force.y < 0.0);
        // a new tangent plane: the spring is rotated, keeping its length
        let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
        let n2 = DVec3::new(0.6, 0.8, 0.0);
        let t2 = p.tangential_force(&kin(n2, DVec3::ZERO, d0), &normal, &g, dt, &mut s);
        assert!(s.dot(n2).abs() < 1e-15 * s.length());
        assert_relative_eq!(s.length(), 1e-3 * d0, max_relative = 1e-14);
        assert_relative_eq!(t2.force.length(), st * 1e-3 * d0, max_relative = 1e-14);
        // no friction, or no contact: spring zeroed, no force
        let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
        let t = params().tangential_force(&kin(n, v, d0), &normal, &g, dt, &mut s);
        assert_eq!((t, s), (Tangential::default(), DVec3::ZERO));
        let mut s = DVec3::new(0.0, 1e-3 * d0, 0.0);
        let t = p.tangential_force(&kin(n, v, d0), &NormalForce::default(), &g, dt, &mut s);
        assert_eq!((t, s), (Tangential::default(), DVec3::ZERO));
        // Hertz: the limit is μs·F_N
        let hz = JkrParams {
            friction: 0.3,
            ..JkrParams::hertz(70e9, 0.17)
        };
        let nh = hz.normal_force(1e-9, 0.0, &g, &mut ContactHistory::default());
        let mut s = DVec3::new(0.0, 1e-6, 0.0);
        let t = hz.tangential_force(&kin(n, DVec3::ZERO, 1e-9), &nh, &g, dt, &mut s);
        assert_relative_eq!(
            t.force.length(),
            0.3 * nh.conservative,
            max_relative = 1e-14
        );
    }

    #[test]
    fn rolling_resistance() {
        let p = JkrParams {
            rolling_hysteresis: 0.5,
            ..params()
        };
        let r = reff();
        let g = geom();
        let d0 = p.delta0(r);
        let mut h = ContactHistory::default();
        let normal = p.normal_force(d0, 0.0, &g, &mut h);
        let n = DVec3::X;
        // particle i spins about +y, j at rest: v_roll = R*·(ω_i − ω_j) × n
        let omega_i = DVec3::new(0.0, 2.0, 0.0);
        let v_roll = r * omega_i.cross(n);
        let xi_crit = p.a0_unscaled(r) / 12.0 * 0.5;
        let mut xi = DVec3::ZERO;
        let dt = 1e-3 * xi_crit / v_roll.length();
        let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
        assert!(!m.yielding);
        assert!(m.torque.dot(omega_i) < 0.0, "opposes ω_i − ω_j");
        assert!(m.torque.normalize().dot(-omega_i.normalize()) > 1.0 - 1e-12);
        // kr = 4Fc at equilibrium (a = a0)
        assert_relative_eq!(m.stiffness, 4.0 * p.fc(r), max_relative = 1e-12);
        assert_relative_eq!(
            m.torque.length(),
            m.stiffness * xi.length(),
            max_relative = 1e-14
        );
        // keep rolling: |ξ| never exceeds ξcrit, and yields
        let mut yielded = false;
        for _ in 0..5000 {
            let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
            assert!(xi.length() <= xi_crit * (1.0 + 1e-14));
            yielded |= m.yielding;
        }
        assert!(yielded);
        assert_relative_eq!(xi.length(), xi_crit, max_relative = 1e-14);
        // the largest torque is the Krijt yield torque 4Fc·ξcrit at a = a0
        let m = p.rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
        assert_relative_eq!(
            m.torque.length(),
            4.0 * p.fc(r) * xi_crit,
            max_relative = 1e-12
        );
        // rotated into a new tangent plane with its length kept
        let n2 = DVec3::new(0.8, 0.0, 0.6);
        p.rolling_torque(n2, DVec3::ZERO, &normal, &g, dt, &mut xi);
        assert!(xi.dot(n2).abs() < 1e-14 * xi.length());
        assert_relative_eq!(xi.length(), xi_crit, max_relative = 1e-14);
        // off without hysteresis or out of contact
        let m = params().rolling_torque(n, v_roll, &normal, &g, dt, &mut xi);
        assert_eq!((m, xi), (Rolling::default(), DVec3::ZERO));
        xi = DVec3::Y;
        let m = p.rolling_torque(n, v_roll, &NormalForce::default(), &g, dt, &mut xi);
        assert_eq!((m, xi), (Rolling::default(), DVec3::ZERO));
    }

    #[test]
    fn stiffness_scaling_keeps_the_cycle_energy() {
        let p = params();
        let s = 0.01;
        let q = JkrParams {
            stiffness_scale: s,
            rolling_hysteresis: 0.5,
            ..p
        };
        let r = reff();
        assert_relative_eq!(q.e_star(), s * p.e_star(), max_relative = 1e-15);
        assert_relative_eq!(q.g_star(), s * p.g_star(), max_relative = 1e-15);
        assert_relative_eq!(q.gamma(), 0.05 * s.powf(0.4), max_relative = 1e-15);
        // paper 002 eqs. 23–24: Fc·δ0 (hence the cycle loss 0.7722·Fc·δ0) is unchanged
        let w = |p: &JkrParams| p.fc(r) * p.delta0(r) * 0.7722405328755862;
        assert_relative_eq!(w(&q), w(&p), max_relative = 1e-12);
        // and so is the work from touch to equilibrium (eq. 23) and the sticking velocity
        let work = |p: &JkrParams| {
            touched_force(p, 1e-13 * p.delta0(r)).potential
                - touched_force(p, p.delta0(r)).potential
        };
        assert_relative_eq!(work(&q), work(&p), max_relative = 1e-9);
        let m = geom().reduced_mass;
        let v = 2.0 * (2.0 * w(&p) / m).sqrt();
        let (vp, _, tp) = collide(&p, v, 2e4);
        let (vq, _, tq) = collide(&q, v, 2e4);
        // the undamped JKR dynamics are self-similar in δ0 and sqrt(m*·δ0/Fc) ∝ S^(−2/5):
        // same outcome, collisions last S^(−2/5) times longer (paper 002 §6.2)
        assert_relative_eq!(vp, vq, max_relative = 1e-9);
        let factor = q.stiffness_scaling().unwrap().collision_time_factor;
        assert_relative_eq!(factor, s.powf(-0.4), max_relative = 1e-15);
        assert_relative_eq!(tq / tp, factor, max_relative = 1e-6);
        // the pull-off force drops by S^(2/5)
        assert_relative_eq!(q.fc(r) / p.fc(r), s.powf(0.4), max_relative = 1e-14);
        // rolling: at equilibrium kr = 4·Fc (unscaled) and ξcrit with the unscaled a0
        let mut h = ContactHistory::default();
        let nq = q.normal_force(q.delta0(r), 0.0, &geom(), &mut h);
        let mut xi = DVec3::ZERO;
        let m = q.rolling_torque(DVec3::X, DVec3::Y, &nq, &geom(), 1.0, &mut xi);
        assert_relative_eq!(m.stiffness, 4.0 * p.fc(r), max_relative = 1e-12);
        assert_relative_eq!(xi.length(), p.a0(r) / 12.0 * 0.5, max_relative = 1e-12);
        // report only when S ≠ 1
        assert!(p.stiffness_scaling_report().is_none());
        let text = q.stiffness_scaling_report().unwrap();
        assert!(
            text.contains("pull-off") && text.contains("6.3096"),
            "{text}"
        );
    }

    #[test]
    fn hertz_contact_time_matches_the_closed_form() {
        let p = JkrParams::hertz(1e9, 0.3);
        let (r, m, v) = (1e-3, 1e-5, 0.5);
        let es = p.e_star();
        assert_relative_eq!(
            p.hertz_contact_time(r, m, v),
            2.87 * (m * m / (r * es * es * v)).powf(0.2),
            max_relative = 1e-15
        );
        assert_eq!(p.equilibrium_stiffness(r), 0.0);
    }

    /// The time step crosses the adhesive zone in 50 steps at the impact velocity, but
    /// never at more than the adhesion speed: faster impacts get the same dt (until the
    /// Hertz time binds), and the sticking speeds of both pull-off rules are below it.
    #[test]
    fn zone_rule_stops_at_the_adhesion_speed() {
        let p = JkrParams::jkr(1e9, 0.3, 0.05);
        let m = 2000.0 * 4.0 / 3.0 * PI * R1.powi(3);
        let g = PairGeometry::spheres(R1, R1, m, m);
        let (r, m) = (g.r_eff(), g.reduced_mass);
        let va = p.adhesion_speed(r, m);
        let slow = crate::model::ContactModel::Jkr(p).time_step(&g, 0.5 * va);
        assert_relative_eq!(
            slow.contact_time,
            2.0 * p.delta0(r) / va,
            max_relative = 1e-12
        );
        let at = |v: f64| format!("at {v:.4e} m/s");
        assert!(slow.reason.contains(&at(0.5 * va)), "{}", slow.reason);
        for f in [1.0, 3.0, 10.0] {
            let fast = crate::model::ContactModel::Jkr(p).time_step(&g, f * va);
            assert_relative_eq!(fast.contact_time, p.delta0(r) / va, max_relative = 1e-12);
            assert!(fast.reason.contains(&at(va)), "{}", fast.reason);
        }
        for pulloff in [Pulloff::Displacement, Pulloff::Force] {
            let w = crate::model::analytic::jkr_loss(pulloff) * p.fc(r) * p.delta0(r);
            let v_stick = crate::model::analytic::jkr_sticking_velocity(w, m);
            assert!(v_stick < va, "{pulloff:?}");
        }
    }

    #[test]
    fn krijt_state_force_and_potential() {
        let krijt = |tvis, sigma0| JkrParams {
            dissipation: Dissipation::Krijt { tvis, sigma0 },
            ..params()
        };
        let p = krijt(1e-9, 1e3);
        let (r, g) = (reff(), geom());
        let (a0, d0) = (p.a0(r), p.delta0(r));
        let mut h = ContactHistory::default();
        // nothing before the touch; at the touch a starts at a_JKR(0) = (2/3)^(2/3)·a0
        assert_eq!(
            p.normal_force_step(-0.1 * d0, 1.0, &g, 1e-9, &mut h),
            NormalForce::default()
        );
        let f = p.normal_force_step(1e-12 * d0, 0.0, &g, 0.0, &mut h);
        assert_relative_eq!(f.contact_radius, X_TOUCH * a0, max_relative = 1e-12);
        assert_relative_eq!(h.contact_radius, X_TOUCH * a0, max_relative = 1e-12);
        assert_relative_eq!(f.conservative, -8.0 / 9.0 * p.fc(r), max_relative = 1e-6);
        // at equilibrium a the force and the stored energy are the JKR ones
        for d in [-0.5, 0.3, 1.0, 4.0] {
            let mut h = ContactHistory {
                touched: true,
                contact_radius: p.contact_radius(d * d0, r),
                ..Default::default()
            };
            let f = p.normal_force_step(d * d0, 0.0, &g, 1.0, &mut h);
            let j = touched_force(&params(), d * d0);
            assert_relative_eq!(f.conservative, j.conservative, epsilon = 1e-9 * p.fc(r));
            assert_relative_eq!(f.potential, j.potential, epsilon = 1e-9 * p.fc(r) * d0);
        }
        // with a delay, a lags: loading from the touch radius it stays below a_JKR(δ)
        let q = krijt(1e-3, 1e6);
        let mut h = ContactHistory::default();
        q.normal_force_step(1e-12 * d0, 0.0, &g, 0.0, &mut h);
        let f = q.normal_force_step(2.0 * d0, 0.0, &g, 1e-9, &mut h);
        assert!(
            f.contact_radius > X_TOUCH * a0 && f.contact_radius < p.contact_radius(2.0 * d0, r)
        );
        // then F_E(a, δ) is above the JKR force (a smaller punch), and the viscous force
        // is 2·T_vis·E*/ν²·a·δ̇
        assert!(f.conservative > touched_force(&params(), 2.0 * d0).conservative);
        let moving = q.normal_force_step(2.0 * d0, 0.5, &g, 0.0, &mut h);
        let visc = 2.0 * 1e-3 * q.e_star() / (0.17f64 * 0.17) * moving.contact_radius * 0.5;
        assert_relative_eq!(
            moving.force - moving.conservative,
            visc,
            max_relative = 1e-12
        );
        // breaking resets the state
        q.normal_force_step(-0.9 * d0, -1.0, &g, 1e-9, &mut h);
        assert_eq!(h, ContactHistory::default());
        // validation: the rule and the parameter are named
        let bad = |d: Dissipation| {
            JkrParams {
                dissipation: d,
                ..params()
            }
            .validate()
            .unwrap_err()
        };
        assert_eq!(
            bad(Dissipation::Krijt {
                tvis: -1.0,
                sigma0: 0.0
            })
            .param,
            "tvis"
        );
        assert_eq!(
            bad(Dissipation::Krijt {
                tvis: 1.0,
                sigma0: -1.0
            })
            .param,
            "sigma0"
        );
        let st = |c, b, zeta| Dissipation::Stress {
            tvis0_per_radius: c,
            b,
            zeta,
            sigma0: 0.0,
        };
        assert_eq!(bad(st(-1.0, 6.2, 4.0)).param, "tvis0_per_radius");
        assert_eq!(bad(st(2e-4, f64::NAN, 4.0)).param, "B");
        assert_eq!(bad(st(2e-4, 6.2, 0.0)).param, "zeta");
        let e = JkrParams {
            dissipation: st(2e-4, 6.2, 4.0),
            ..JkrParams::hertz(1e9, 0.3)
        }
        .validate()
        .unwrap_err();
        assert!(
            e.param == "dissipation" && e.message.contains("surface_energy"),
            "{e}"
        );
        let e = JkrParams {
            dissipation: Dissipation::Krijt {
                tvis: 1.0,
                sigma0: 0.0,
            },
            ..JkrParams::jkr(1e9, 0.0, 0.1)
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.param, "poisson");
        // serde names: kind = "krijt" / "stress", B
        let s = JkrParams {
            dissipation: st(2.1e-4, 6.2, 4.0),
            ..params()
        };
        let json = serde_json::to_string(&s).unwrap();
        assert!(
            json.contains("\"kind\":\"stress\"") && json.contains("\"B\":6.2"),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), s);
    }

    #[test]
    fn validation_names_parameter_and_rule() {
        let bad = |f: fn(&mut JkrParams)| {
            let mut p = params();
            f(&mut p);
            p.validate().unwrap_err()
        };
        assert_eq!(bad(|p| p.youngs = 0.0).param, "youngs");
        assert_eq!(bad(|p| p.youngs = f64::NAN).param, "youngs");
        let e = bad(|p| p.poisson = 0.5);
        assert_eq!(e.param, "poisson");
        assert!(e.message.contains("0.5"));
        assert_eq!(bad(|p| p.poisson = -1.0).param, "poisson");
        assert_eq!(bad(|p| p.surface_energy = -1.0).param, "surface_energy");
        assert_eq!(
            bad(|p| p.dissipation = Dissipation::tsuji(0.0)).param,
            "restitution"
        );
        assert_eq!(
            bad(|p| p.dissipation = Dissipation::tsuji(1.1)).param,
            "restitution"
        );
        let pl = |d, alpha, beta| Dissipation::PowerLaw { d, alpha, beta };
        let mut q = params();
        q.dissipation = pl(-1.0, 3.0, 1.5);
        assert_eq!(q.validate().unwrap_err().param, "D");
        q.dissipation = pl(1.0, -3.0, 1.5);
        assert_eq!(q.validate().unwrap_err().param, "alpha");
        q.dissipation = pl(1.0, 3.0, f64::INFINITY);
        assert_eq!(q.validate().unwrap_err().param, "beta");
        assert_eq!(bad(|p| p.friction = -0.1).param, "friction");
        assert_eq!(
            bad(|p| p.rolling_hysteresis = -0.1).param,
            "rolling_hysteresis"
        );
        let e = bad(|p| {
            p.rolling_hysteresis = 0.3;
            p.surface_energy = 0.0
        });
        assert_eq!(e.param, "rolling_hysteresis");
        assert!(e.message.contains("surface_energy"));
        assert_eq!(bad(|p| p.stiffness_scale = 0.0).param, "stiffness_scale");
        assert!(params().validate().is_ok());
        assert!(JkrParams::hertz(1e9, 0.3).validate().is_ok());
        let e = bad(|p| p.youngs = -1.0);
        assert!(e.to_string().contains("`youngs`"), "{e}");
    }

    #[test]
    fn serde_names() {
        let p = JkrParams {
            dissipation: Dissipation::PowerLaw {
                d: 118.0,
                alpha: 3.0,
                beta: 1.5,
            },
            ..params()
        };
        let json = serde_json::to_string(&p).unwrap();
        assert!(
            json.contains("\"kind\":\"power-law\"") && json.contains("\"D\":118"),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<JkrParams>(&json).unwrap(), p);
        // optional fields default
        let q: JkrParams = serde_json::from_str(
            r#"{"youngs": 1e9, "poisson": 0.3, "surface_energy": 0.1,
                "dissipation": {"kind": "tsuji", "restitution": 0.5}, "pulloff": "force"}"#,
        )
        .unwrap();
        assert_eq!(q.stiffness_scale, 1.0);
        assert_eq!(q.pulloff, Pulloff::Force);
        assert_eq!(q.dissipation, Dissipation::tsuji(0.5));
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
