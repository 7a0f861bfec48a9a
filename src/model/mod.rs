//! Contact models, one module per model, in f64: the physics reference that the GPU
//! kernels are checked against.

pub mod analytic;
pub mod flags;
pub mod friction;
pub mod history;
pub mod hysteretic;
pub mod jkr;
pub mod krijt;
pub mod lsd;
pub mod params;

pub use friction::{CoulombSpring, LudingFriction};
pub use hysteretic::{AdhesionMode, HystereticParams, K2Rule};
pub use jkr::{Dissipation, JkrParams, Pulloff, TsujiStiffness};
pub use lsd::LsdParams;

use crate::error::ParamError;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Per-contact history that survives between steps (and, on the GPU, re-sorting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactHistory {
    /// Largest overlap reached on the current branch family (δmax).
    pub delta_max: f64,
    /// Whether the pair has touched since it last left the interaction range
    /// (jump-in adhesion acts only after the first touch; a JKR contact persists into
    /// negative overlap until pull-off).
    pub touched: bool,
    /// Tangential spring displacement, kept in the current tangent plane (JKR friction;
    /// Luding's sliding spring ξ_t, staggered half a step ahead, see
    /// [`friction::coulomb`]). Negated when the pair is seen from the partner.
    pub tangential: DVec3,
    /// Rolling displacement ξ, kept in the current tangent plane (JKR rolling resistance;
    /// Luding's rolling spring ξ_r, staggered). The same seen from the partner.
    pub rolling: DVec3,
    /// Contact radius a as its own state variable (the `krijt` and `stress` dissipations
    /// of JKR, see [`krijt`]), m; 0 = unset (set to a_JKR(0) at the first touch).
    #[serde(default)]
    pub contact_radius: f64,
    /// Luding's twisting spring along n as a scalar ξ_o = n·ξ_o, m (staggered, see
    /// [`friction::twisting`]): the same seen from either particle.
    #[serde(default)]
    pub twist: f64,
    /// Whether Luding's sliding spring slipped in the contact's last step: its Coulomb
    /// limit is then μd, not μs, until it sticks ([`friction::coulomb`]).
    #[serde(default)]
    pub slipping: bool,
}

/// The normal force of one contact and what the energy bookkeeping needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NormalForce {
    /// Total normal force, repulsive positive (conservative + viscous).
    pub force: f64,
    /// The rate-independent part (no viscous term).
    pub conservative: f64,
    /// Stored (recoverable) energy of the contact in its current state.
    pub potential: f64,
    /// Mechanical contact, as opposed to the non-contact range (for JKR: from the first
    /// touch until pull-off, also at negative overlap).
    pub in_contact: bool,
    /// Contact radius a, m (JKR/Hertz; 0 for the piece-wise linear models).
    pub contact_radius: f64,
    /// A contact that broke within the step at a time it resolves (a `crack` neck closing):
    /// the fraction of the step and the normal force just before, N. None: at the end.
    pub broke_within: Option<(f64, f64)>,
}

/// Pair properties the normal force laws need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairGeometry {
    /// Reduced radius a12 = 2·a1·a2/(a1 + a2) (paper 000 eq. 11); 2·a for a wall.
    pub a12: f64,
    /// Reduced mass m1·m2/(m1 + m2); m for a wall.
    pub reduced_mass: f64,
    /// Effective mass of the rolling and twisting oscillators about the lever a12 of solid
    /// spheres (I = 2/5·m·r²): 1/[a12²·(1/I1 + 1/I2)] (m/5 = 2/5·m_r for equal spheres,
    /// m/10 against a wall, where a12 = 2r).
    pub rotational_mass: f64,
}

impl PairGeometry {
    /// Effective radius R* = r1·r2/(r1 + r2) (r for a wall) = a12/2.
    pub fn r_eff(&self) -> f64 {
        0.5 * self.a12
    }

    /// Effective mass of the tangential contact-point motion of solid spheres,
    /// 1/(1/m1 + 1/m2 + r1²/I1 + r2²/I2) = 2/7·m_r.
    pub fn tangential_mass(&self) -> f64 {
        2.0 / 7.0 * self.reduced_mass
    }

    /// A sphere–sphere pair: radii `r1`, `r2` (m) and masses `m1`, `m2` (kg).
    pub fn spheres(r1: f64, r2: f64, m1: f64, m2: f64) -> Self {
        let a12 = 2.0 * r1 * r2 / (r1 + r2);
        Self {
            a12,
            reduced_mass: m1 * m2 / (m1 + m2),
            // 1/I = 5/(2·m·r²)
            rotational_mass: 0.4 / (a12 * a12 * (1.0 / (m1 * r1 * r1) + 1.0 / (m2 * r2 * r2))),
        }
    }

    /// A sphere–wall pair: sphere radius `r` (m) and mass `m` (kg); the wall has infinite
    /// radius and mass.
    pub fn wall(r: f64, m: f64) -> Self {
        Self {
            a12: 2.0 * r,
            reduced_mass: m,
            rotational_mass: 0.1 * m,
        }
    }
}

/// A normal contact model with its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum ContactModel {
    /// The hysteretic adhesive elasto-plastic model (paper 000 eqs. 5–15).
    Hysteretic(HystereticParams),
    /// The linear spring–dashpot (paper 000 eq. 2).
    Lsd(LsdParams),
    /// JKR (Hertz when the surface energy is zero), with damping, friction and rolling.
    Jkr(JkrParams),
}

/// What a model derives once per pair of materials and radii, for a force loop that meets
/// the same pair contact after contact ([`ContactModel::pair_constants`]).
#[derive(Clone, Copy, Debug)]
pub enum PairConstants {
    /// JKR's moduli, pull-off force, length scales and damping ratio.
    Jkr(jkr::JkrPair),
    /// Nothing to derive (the piece-wise linear models).
    None,
}

/// Relative motion at one contact, as the engine measures it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kinematics {
    /// Overlap δ, m.
    pub delta: f64,
    /// Approach speed δ̇, m/s.
    pub delta_dot: f64,
    /// Unit normal from particle j to particle i.
    pub n: DVec3,
    /// Tangential velocity of i relative to j at the contact point.
    pub v_t: DVec3,
    /// Rolling velocity v_L = R*·(ω_i − ω_j) × n + ½·(r_i − r_j)/(r_i + r_j)·v_t
    /// (paper 002 eq. 20).
    pub v_roll: DVec3,
    /// Relative angular velocity ω_i − ω_j (ω_i against a wall); zero without rotation.
    pub omega_rel: DVec3,
}

/// Forces and torques of one contact on particle i (particle j gets the opposite force;
/// see the engine for the torques).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Response {
    /// Normal force on i along n (repulsive positive) and its parts.
    pub normal: NormalForce,
    /// Tangential force on i.
    pub tangential: DVec3,
    /// The antisymmetric couple on i (−this on j): the rolling and twisting resistance
    /// torques (JKR rolling, Luding rolling + twisting). The torques of the tangential force
    /// are not in it: the engine applies them at the contact point.
    pub couple: DVec3,
    /// Stored energy of the contact: normal + the springs (tangential, rolling, twisting), J.
    pub potential: f64,
    /// Whether the tangential force slipped at the Coulomb limit (sticking otherwise, or no
    /// friction).
    pub sliding: bool,
}

impl ContactModel {
    /// The name of its law, as scenes and the command line write it (`params::LAWS`).
    pub fn law_name(&self) -> &'static str {
        match self {
            Self::Hysteretic(_) => "hysteretic",
            Self::Lsd(_) => "lsd",
            Self::Jkr(p) if p.surface_energy == 0.0 => "hertz",
            Self::Jkr(_) => "jkr",
        }
    }

    /// Checks the parameters against the model's rules; the error names the parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Self::Hysteretic(p) => p.validate(),
            Self::Lsd(p) => p.validate(),
            Self::Jkr(p) => p.validate(),
        }
    }

    /// Whether contacts of this model exert tangential forces or torques, so particles
    /// need angular velocity.
    pub fn needs_rotation(&self) -> bool {
        match self {
            Self::Jkr(p) => {
                p.friction > 0.0 || p.rolling_hysteresis > 0.0 || p.luding.twisting.is_on()
            }
            Self::Hysteretic(p) => p.luding.is_on(),
            Self::Lsd(p) => p.luding.is_on(),
        }
    }

    /// Forces of one contact for the given kinematics, updating the history.
    pub fn respond(
        &self,
        k: &Kinematics,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> Response {
        self.respond_with(&self.pair_constants(geom), k, geom, dt, history)
    }

    /// The constants of a pair of geometry `geom` that [`Self::respond_with`] takes.
    pub fn pair_constants(&self, geom: &PairGeometry) -> PairConstants {
        match self {
            Self::Jkr(p) => PairConstants::Jkr(p.pair(0.5 * geom.a12)),
            Self::Hysteretic(_) | Self::Lsd(_) => PairConstants::None,
        }
    }

    /// Whether [`Self::root_ahead`] ever gives a root (JKR with adhesion).
    pub(crate) fn solves_roots(&self) -> bool {
        matches!(self, Self::Jkr(p) if p.gamma() != 0.0)
    }

    /// The root a law solves from the overlap alone (JKR: s = √(a/a0)) where `respond`
    /// will need it, so that a force loop can solve the roots of several contacts side by
    /// side; None where the law needs none.
    pub(crate) fn root_ahead(
        &self,
        pair: &PairConstants,
        delta: f64,
        touched: bool,
    ) -> Option<f64> {
        match (self, pair) {
            (Self::Jkr(p), PairConstants::Jkr(c)) => p.root_ahead(c, delta, touched),
            _ => None,
        }
    }

    /// [`Self::respond`] with the pair's constants, which must be [`Self::pair_constants`]
    /// of this model and `geom` (a force loop keeps them for partners of the same shape).
    pub fn respond_with(
        &self,
        pair: &PairConstants,
        k: &Kinematics,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> Response {
        self.respond_rooted(pair, k, None, geom, dt, history)
    }

    /// [`Self::respond_with`] given the law's root at `k.delta` where the force loop solved
    /// it ahead: `root` must be [`Self::root_ahead`] of `pair`, `k.delta` and
    /// `history.touched`, or None.
    pub(crate) fn respond_rooted(
        &self,
        pair: &PairConstants,
        k: &Kinematics,
        root: Option<f64>,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> Response {
        match self {
            Self::Jkr(p) => {
                let pair = match pair {
                    PairConstants::Jkr(c) => *c,
                    PairConstants::None => p.pair(0.5 * geom.a12),
                };
                let normal =
                    p.normal_force_rooted(&pair, (k.delta, k.delta_dot), root, geom, dt, history);
                let mut r = Response {
                    normal,
                    potential: normal.potential,
                    ..Default::default()
                };
                if normal.in_contact && p.friction > 0.0 {
                    let t = p.tangential_force_of_pair(
                        &pair,
                        (k, &normal),
                        geom,
                        dt,
                        &mut history.tangential,
                    );
                    r.tangential = t.force;
                    r.sliding = t.sliding;
                    r.potential += 0.5 * t.stiffness * history.tangential.length_squared();
                }
                if normal.in_contact && p.rolling_hysteresis > 0.0 {
                    let m =
                        p.rolling_torque(k.n, k.v_roll, &normal, geom, dt, &mut history.rolling);
                    r.couple = m.torque;
                    r.potential += 0.5 * m.stiffness * history.rolling.length_squared();
                }
                if normal.in_contact && p.luding.twisting.is_on() {
                    let (couple, energy) = p.twisting(k, &normal, geom, dt, &mut history.twist);
                    r.couple += couple;
                    r.potential += energy;
                }
                r
            }
            Self::Hysteretic(p) => {
                let normal = p.force(k.delta, k.delta_dot, geom.a12, history);
                Self::with_friction(
                    &p.luding,
                    normal,
                    p.coulomb_load(&normal, k.delta),
                    k,
                    geom,
                    dt,
                    history,
                )
            }
            Self::Lsd(p) => {
                let normal = p.force(k.delta, k.delta_dot);
                Self::with_friction(
                    &p.luding,
                    normal,
                    p.coulomb_load(&normal),
                    k,
                    geom,
                    dt,
                    history,
                )
            }
        }
    }

    /// The response of a hysteretic/LSD contact: its normal force and Luding's friction with
    /// the Coulomb load `load` (in mechanical contact only, δ > 0).
    fn with_friction(
        luding: &LudingFriction,
        normal: NormalForce,
        load: f64,
        k: &Kinematics,
        geom: &PairGeometry,
        dt: f64,
        history: &mut ContactHistory,
    ) -> Response {
        let mut r = Response {
            normal,
            potential: normal.potential,
            ..Default::default()
        };
        if luding.is_on() {
            let f = luding.respond(k, geom, k.delta > 0.0, load, dt, history);
            r.tangential = f.tangential;
            r.couple = f.couple;
            r.sliding = f.sliding;
            r.potential += f.potential;
        }
        r
    }

    /// Non-contact interaction range (how far beyond touching a pair still interacts), m.
    /// For JKR this is how far into negative overlap a touching pair stays in contact.
    pub fn range(&self) -> f64 {
        match self {
            Self::Hysteretic(p) => p.range(),
            Self::Lsd(_) => 0.0,
            Self::Jkr(_) => 0.0,
        }
    }

    /// Largest separation beyond touching at which a pair of effective radius `r_eff` can
    /// still interact, m: the search cut-off needs it.
    pub fn reach(&self, r_eff: f64) -> f64 {
        match self {
            Self::Jkr(p) => -p.pulloff_overlap(r_eff),
            _ => self.range(),
        }
    }

    /// Normal force for overlap δ and approach speed δ̇, updating the history.
    pub fn force(
        &self,
        delta: f64,
        delta_dot: f64,
        geom: &PairGeometry,
        history: &mut ContactHistory,
    ) -> NormalForce {
        match self {
            Self::Hysteretic(p) => p.force(delta, delta_dot, geom.a12, history),
            Self::Lsd(p) => p.force(delta, delta_dot),
            Self::Jkr(p) => p.normal_force(delta, delta_dot, geom, history),
        }
    }

    /// Where the contact starts and ends and the force just inside those edges:
    /// `[(entry δ, entry force), (exit δ, exit force)]`. The forces can jump there (JKR at
    /// touch and pull-off, −fa of jump-in adhesion, a viscous force γ0·δ̇ at first touch).
    /// `delta` is the overlap at the end of the step (a delayed JKR `crack` contact ends
    /// there).
    pub fn edges(&self, geom: &PairGeometry, delta: f64, delta_dot: f64) -> [(f64, f64); 2] {
        match self {
            Self::Hysteretic(p) => {
                let range = p.range();
                // the first touch: the adhesion −fa and the viscous force jump on
                let touch = (0.0, -p.fa + p.gamma0 * delta_dot);
                if range == 0.0 {
                    [touch, touch]
                } else if p.adhesion == AdhesionMode::JumpIn {
                    // an untouched pair feels nothing in the range: it enters at the touch
                    // and leaves at the range's end, where the adhesion has fallen to 0
                    [touch, (-range, 0.0)]
                } else {
                    [(-range, 0.0), (-range, 0.0)]
                }
            }
            Self::Lsd(p) => {
                let f = p.gamma0 * delta_dot;
                [(0.0, f), (0.0, f)]
            }
            Self::Jkr(p) => p.edge_forces(geom, delta, delta_dot),
        }
    }

    /// Whether the normal law loses nothing in a collision (its e sits on either side of 1
    /// by the integrator's error): LSD and Hertz undamped, the hysteretic law without
    /// plasticity, damping or non-contact adhesion.
    pub fn elastic_normal(&self) -> bool {
        match self {
            Self::Lsd(p) => p.gamma0 == 0.0,
            Self::Jkr(p) => p.surface_energy == 0.0 && matches!(p.dissipation, Dissipation::None),
            Self::Hysteretic(p) => p.kp == p.k1 && p.gamma0 == 0.0 && p.fa == 0.0,
        }
    }

    /// The force that switches on at δ = 0 inside an engaged contact, where δ = 0 is not
    /// one of its [`Self::edges`]: the mechanical contact's viscous force γ0·δ̇ where a
    /// non-contact range surrounds the touch (the hysteretic contact and non-contact
    /// forces meet at −fa there); 0 where the force is continuous at δ = 0.
    pub fn touch_jump(&self, delta_dot: f64) -> f64 {
        match self {
            Self::Hysteretic(p) if p.range() > 0.0 => p.gamma0 * delta_dot,
            _ => 0.0,
        }
    }

    /// Whether the normal force can jump inside a step: at an edge of the contact (a force
    /// just inside an edge, approaching or separating: JKR with adhesion, zero-range
    /// jump-in adhesion, viscous damping at first touch) or at the touch inside it
    /// ([`Self::touch_jump`]), so a step crossing one misplaces an impulse.
    pub fn has_force_jumps(&self, geom: &PairGeometry) -> bool {
        [-1.0, 1.0].iter().any(|&v| {
            self.touch_jump(v) != 0.0 || self.edges(geom, 0.0, v).iter().any(|&(_, f)| f != 0.0)
        })
    }

    /// The friction oscillators of a pair (Luding's sliding, rolling and twisting where
    /// they act; the JKR family's twisting with the stiffness of the largest contact radius
    /// at `impact_velocity`), for the time step.
    pub fn friction_oscillators(
        &self,
        geom: &PairGeometry,
        impact_velocity: f64,
    ) -> Vec<friction::Oscillator> {
        match self {
            Self::Hysteretic(p) => p.luding.oscillators(geom),
            Self::Lsd(p) => p.luding.oscillators(geom),
            Self::Jkr(p) => p
                .twisting_oscillator(geom, impact_velocity)
                .into_iter()
                .collect(),
        }
    }

    /// The normal stiffness dF/dδ of a contact of effective radius `r_eff` carrying the
    /// normal force `load` (N): the linear laws' spring (the hysteretic model's un-/reloading
    /// kp, its stiffest under compression), Hertz's (6·E*²·r·F)^(1/3), and for JKR at least
    /// its stiffness about the equilibrium overlap (a servo's stability, `run::servo`).
    pub fn normal_stiffness(&self, r_eff: f64, load: f64) -> f64 {
        match self {
            Self::Lsd(p) => p.k,
            Self::Hysteretic(p) => p.kp,
            Self::Jkr(p) => {
                let hertz = (6.0 * p.e_star() * p.e_star() * r_eff * load).cbrt();
                hertz.max(p.equilibrium_stiffness(r_eff))
            }
        }
    }

    /// Time-step limits for a pair of geometry `geom` meeting at up to `impact_velocity`.
    ///
    /// The contact time tc is π·√(m_r/k_max) on the stiffest linear branch (the largest of
    /// kp, kc and kc_a where finite; k for LSD); for Hertz/JKR the Hertz time
    /// 2.87·(m*²/(R*·E*²·v))^(1/5) at the impact velocity, and for JKR no longer than the
    /// oscillation time π·√(m*/k_eq) about the equilibrium overlap (k_eq = dF/dδ at δ0)
    /// nor the time δ0/v to cross the adhesive zone at v = the impact velocity, at most the
    /// adhesion speed √(2·Fc·δ0/m*) (faster impacts lose too little of their energy there
    /// for its error to matter: [`JkrParams::adhesion_speed`]).
    ///
    /// Where friction acts, no longer than the half-period π·√(m/k) of each friction
    /// oscillator ([`Self::friction_oscillators`]: tangential k_t with m_t = 2/7·m_r,
    /// rolling k_r and twisting k_o with 1/[ℓ²(1/I_i + 1/I_j)]; against a wall, where
    /// ℓ = 2r, the rolling period with k_r = 2/5·k is half the normal one), and every
    /// dashpot γ within γ·dt/m ≤ [`MAX_VISCOUS_STEP`], the `krijt`/`stress` viscous
    /// coefficient at its largest in a head-on collision at `impact_velocity`
    /// ([`JkrParams::viscous_coefficient_estimate`]).
    pub fn time_step(&self, geom: &PairGeometry, impact_velocity: f64) -> TimeStep {
        let mr = geom.reduced_mass;
        let (tc, what, gamma0) = match self {
            Self::Hysteretic(p) => {
                let k = p.stiffest();
                (
                    std::f64::consts::PI * (mr / k).sqrt(),
                    format!(
                        "tc = pi*sqrt(m_r/k) on the stiffest branch k = {k:.4e} N/m, m_r = {mr:.4e} kg"
                    ),
                    p.gamma0,
                )
            }
            Self::Lsd(p) => (
                std::f64::consts::PI * (mr / p.k).sqrt(),
                format!(
                    "tc = pi*sqrt(m_r/k) with k = {:.4e} N/m, m_r = {mr:.4e} kg",
                    p.k
                ),
                p.gamma0,
            ),
            Self::Jkr(p) => {
                let r = geom.r_eff();
                let hertz = p.hertz_contact_time(r, mr, impact_velocity);
                if p.surface_energy > 0.0 {
                    let eq = std::f64::consts::PI * (mr / p.equilibrium_stiffness(r)).sqrt();
                    // the adhesive zone (depth ~δ0, force jumps at its edges) crossed in many
                    // steps: the loss W is off by O(dt²) (O(dt) with the jumps left to
                    // Verlet), which moves e by δW/(2·e·E), so only where W is a sizeable
                    // part of E: up to the adhesion speed (docs/force_jumps.md)
                    let v_zone = impact_velocity.min(p.adhesion_speed(r, mr));
                    let zone = p.delta0(r) / v_zone;
                    if zone < eq.min(hertz) {
                        (zone, format!("tc = delta0/v, the time to cross the JKR adhesive zone delta0 = {:.4e} m at {v_zone:.4e} m/s (the impact velocity {} m/s, at most the adhesion speed)", p.delta0(r), crate::error::num(impact_velocity)), 0.0)
                    } else if eq < hertz {
                        (eq, format!("tc = pi*sqrt(m*/k_eq), the JKR oscillation about the equilibrium overlap (k_eq = {:.4e} N/m)", p.equilibrium_stiffness(r)), 0.0)
                    } else {
                        (
                            hertz,
                            format!(
                                "tc = Hertz contact time at the impact velocity {} m/s",
                                crate::error::num(impact_velocity)
                            ),
                            0.0,
                        )
                    }
                } else {
                    (
                        hertz,
                        format!(
                            "tc = Hertz contact time at the impact velocity {} m/s",
                            crate::error::num(impact_velocity)
                        ),
                        0.0,
                    )
                }
            }
        };
        // the friction oscillators: each half-period pi*sqrt(m/k) counts as a contact time
        let (mut tc, mut what) = (tc, what);
        for o in self.friction_oscillators(geom, impact_velocity) {
            let t = std::f64::consts::PI * (o.mass / o.k).sqrt();
            if t < tc {
                tc = t;
                what = format!(
                    "tc = pi*sqrt(m/k) of the {} oscillator (k = {:.4e} N/m, m = {:.4e} kg)",
                    o.what, o.k, o.mass
                );
            }
        }
        let mut max = tc / MAX_DT_FRACTION;
        let mut reason = format!("dt <= tc/{MAX_DT_FRACTION} with {what}, tc = {tc:.4e} s");
        // explicit viscous forces: keep γ·dt/m small (the exact decay per step is
        // exp(−γ·dt/m); with the force at the predicted velocity the update is unstable
        // beyond γ·dt/m = 1)
        if gamma0 > 0.0 {
            let visc = MAX_VISCOUS_STEP * mr / gamma0;
            if visc < max {
                max = visc;
                reason = format!("dt <= {MAX_VISCOUS_STEP}*m_r/gamma0 = {visc:.4e} s for the viscous damping gamma0 = {gamma0:.4e} kg/s");
            }
        }
        for o in self.friction_oscillators(geom, impact_velocity) {
            if o.gamma > 0.0 {
                let visc = MAX_VISCOUS_STEP * o.mass / o.gamma;
                if visc < max {
                    max = visc;
                    reason = format!("dt <= {MAX_VISCOUS_STEP}*m/gamma = {visc:.4e} s for the {} damping {:.4e} kg/s (m = {:.4e} kg)", o.what, o.gamma, o.mass);
                }
            }
        }
        // the krijt/stress viscous force is explicit too, its coefficient growing with the
        // contact: the longest step that resolves a head-on collision at the impact velocity
        if let Self::Jkr(p) = self {
            if let Some(k) =
                p.viscous_coefficient_estimate(geom, impact_velocity, max, MAX_VISCOUS_STEP)
            {
                if k.dt < max {
                    max = k.dt;
                    reason = format!("dt <= {:.4e} s, the longest step at which a head-on collision at {impact_velocity} m/s keeps c*dt/m_r <= {MAX_VISCOUS_STEP} for the viscous coefficient c = 2*T_vis*E*/nu^2*a of dissipation = \"{}\", largest at the overlap {:.4e} m (c = {:.4e} kg/s)", k.dt, p.dissipation.name(), k.reach, k.c);
                }
            }
            if let Some(k) = p.power_law_coefficient(geom, impact_velocity) {
                let visc = MAX_VISCOUS_STEP * mr / k.c;
                if visc < max {
                    max = visc;
                    reason = format!("dt <= {MAX_VISCOUS_STEP}*m_r/c = {visc:.4e} s for the coefficient c = max(alpha,1)*D*E*v^(alpha-1)*a^beta = {:.4e} kg/s of dissipation = \"powerlaw\" at the approach speed v = {:.4e} m/s (the impact velocity {impact_velocity} m/s{}) and contact radius a = {:.4e} m", k.c, k.speed, if p.gamma() > 0.0 { " and the adhesion speed" } else { "" }, k.radius);
                }
            }
        }
        TimeStep {
            default: (tc / DEFAULT_DT_FRACTION).min(max),
            max,
            contact_time: tc,
            reason,
        }
    }
}

/// Largest accepted dt without `--force` from the Rayleigh time T_R: 0.4·T_R (the upper end
/// of the 0.2–0.4·T_R range DEM codes recommend); the default is half of it.
pub const MAX_RAYLEIGH_FRACTION: f64 = 0.4;

impl TimeStep {
    /// The Rayleigh-time rule for the smallest sphere of a JKR/Hertz material.
    pub fn rayleigh(t_r: f64, material: &str, radius: f64) -> Self {
        let max = MAX_RAYLEIGH_FRACTION * t_r;
        TimeStep {
            default: 0.5 * max,
            max,
            contact_time: t_r,
            reason: format!(
                "dt <= {MAX_RAYLEIGH_FRACTION}*T_R with the Rayleigh time T_R = pi*r*sqrt(rho/G)/(0.1631*nu + 0.8766) = {t_r:.4e} s of the smallest `{material}` sphere (r = {radius:e} m)"
            ),
        }
    }
}

/// Default dt = tc/50 (MercuryDPM, paper 002: Δtcol/δt ≈ 50).
pub const DEFAULT_DT_FRACTION: f64 = 50.0;
/// Largest accepted dt without `--force`: tc/10. Velocity Verlet is stable up to
/// tc·2/π ≈ 0.64·tc, but restitution and overlap errors grow quickly beyond tc/10.
pub const MAX_DT_FRACTION: f64 = 10.0;
/// Largest accepted γ·dt/m of an explicit dashpot (the update, with the force at the
/// predicted velocity, is unstable beyond 1).
pub const MAX_VISCOUS_STEP: f64 = 0.2;

/// The time-step rule of one pair: the default, the largest accepted value and why.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeStep {
    /// Default time step, s: tc/[`DEFAULT_DT_FRACTION`] capped at `max` (Rayleigh rule: max/2).
    pub default: f64,
    /// Largest accepted time step without `force`, s: the smaller of tc/[`MAX_DT_FRACTION`] and
    /// [`MAX_VISCOUS_STEP`]·m_r/γ0 ([`MAX_RAYLEIGH_FRACTION`]·T_R for the Rayleigh rule).
    pub max: f64,
    /// Undamped contact time on the stiffest branch.
    pub contact_time: f64,
    /// Human-readable statement of the binding limit.
    pub reason: String,
}
