//! Every contact law's and sub-model's parameters, declared once: add a parameter here
//! (`param!`) and list it in its law's row of [`LAWS`] or [`DISSIPATIONS`].

use super::{Fallback, Kind, Law, Param, Rule};
use crate::model::{AdhesionMode, K2Rule, Pulloff, TsujiStiffness};

use Fallback::{Derived, Number, Required, Word};
use Kind::{Choice, NumberOrInf};
const NUM: Kind = Kind::Number;

// The hysteretic adhesive elasto-plastic law (paper 000 eqs. 5-15).
param!(
    K1,
    "k1",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the hysteretic loading stiffness k1"
);
param!(
    KP,
    "kp",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the hysteretic limit stiffness kp (>= k1)"
);
param!(
    KC,
    "kc",
    NUM,
    "N/m",
    Required,
    Rule::NonNegative,
    "the hysteretic tensile-branch slope kc"
);
param!(
    PHI_F,
    "phi_f",
    NUM,
    "",
    Required,
    Rule::LeftOpen(0.0, 1.0),
    "the hysteretic plasticity depth phi_f (paper 000 eq. 10)"
);
param!(
    FA,
    "fa",
    NUM,
    "N",
    Number(0.0),
    Rule::NonNegative,
    "the non-contact adhesive force fa (paper 000 eq. 14)"
);
param!(
    KCA,
    "kca",
    NumberOrInf,
    "N/m",
    Derived("kc, or inf when kc = 0"),
    Rule::PositiveOrInf,
    "the non-contact adhesive stiffness kc_a, inf = zero range (paper 000 eq. 14)"
);
param!(
    ADHESION,
    "adhesion",
    Choice(AdhesionMode::WORDS),
    "",
    Word(AdhesionMode::JumpIn.word()),
    Rule::None,
    "the non-contact adhesion on first approach (paper 000 eqs. 14-15)"
);
param!(
    K2_RULE,
    "k2_rule",
    Choice(K2Rule::WORDS),
    "",
    Word(K2Rule::Linear.word()),
    Rule::None,
    "the k2(delta_max) interpolation (paper 000 eq. 9 or D.1)"
);
param!(
    GAMMA0,
    "gamma0",
    NUM,
    "kg/s",
    Number(0.0),
    Rule::NonNegative,
    "the viscous damping gamma0 (paper 000 eq. 2)"
);
// The linear spring-dashpot (paper 000 eq. 2).
param!(
    K,
    "k",
    NUM,
    "N/m",
    Required,
    Rule::Positive,
    "the LSD spring stiffness k"
);
// The JKR family (papers 001, 002).
param!(
    YOUNGS,
    "youngs",
    NUM,
    "Pa",
    Required,
    Rule::Positive,
    "Young's modulus E of the material"
);
param!(
    POISSON,
    "poisson",
    NUM,
    "",
    Required,
    Rule::Open(-1.0, 0.5),
    "the Poisson ratio"
);
param!(
    SURFACE_ENERGY,
    "surface_energy",
    NUM,
    "J/m^2",
    Required,
    Rule::NonNegative,
    "the surface energy gamma per surface (Fc = 3 pi gamma R*)"
);
param!(PULLOFF, "pulloff", Choice(Pulloff::WORDS), "", Word(Pulloff::Displacement.word()), Rule::None, "where a stretched JKR contact breaks: at the turning point, at -Fc, at zero overlap (paper 002), or where the Krijt crack law closes the contact radius (crack; krijt and stress only)");
param!(
    STIFFNESS_SCALE,
    "stiffness_scale",
    NUM,
    "",
    Number(1.0),
    Rule::Positive,
    "the reduced stiffness S: E -> S E, gamma -> gamma S^(2/5) (paper 002 eq. 24)"
);
param!(
    FRICTION,
    "friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the (static) sliding friction coefficient mu_s, 0 = frictionless (jkr, hertz: paper 002 eqs. 14-17; hysteretic, lsd: Luding 2008)"
);
param!(ROLLING_HYSTERESIS, "rolling_hysteresis", NUM, "", Number(0.0), Rule::NonNegative, "the rolling resistance as adhesion hysteresis delta gamma / gamma, 0 = none (paper 002 eq. 18)");
// Luding's sliding, rolling and twisting friction (Luding 2008, docs/luding2008_laws.md;
// `model::friction`): hysteretic and lsd take all of them, jkr and hertz the twisting trio.
// Rolling and twisting act through the lever a12 = 2R* (2r against a wall).
param!(
    FRICTION_DYNAMIC,
    "friction_dynamic",
    NUM,
    "",
    Derived("friction (mu_d = mu_s)"),
    Rule::Positive,
    "the dynamic sliding friction coefficient mu_d <= mu_s, the force while slipping, which lasts until the test force falls to mu_d f_N* (Luding 2008)"
);
param!(
    KT,
    "kt",
    NUM,
    "N/m",
    Derived("2/7 k1 (hysteretic) or 2/7 k (lsd): the normal period"),
    Rule::Positive,
    "the tangential spring stiffness k_t (Luding 2008)"
);
param!(
    GAMMA_T,
    "gamma_t",
    NUM,
    "kg/s",
    Derived("2/7 gamma0"),
    Rule::NonNegative,
    "the tangential damping gamma_t (Luding 2008)"
);
param!(
    ROLLING_FRICTION,
    "rolling_friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the rolling friction coefficient mu_r, torque <= mu_r a12 f_N*; 0 = none (Luding 2008)"
);
param!(
    KR,
    "kr",
    NUM,
    "N/m",
    Derived("2/5 k1 (hysteretic) or 2/5 k (lsd)"),
    Rule::Positive,
    "the rolling spring stiffness k_r, torque stiffness k_r a12^2 per rad (Luding 2008)"
);
param!(
    GAMMA_R,
    "gamma_r",
    NUM,
    "kg/s",
    Derived("2/5 gamma0"),
    Rule::NonNegative,
    "the rolling damping gamma_r (Luding 2008)"
);
param!(
    TWISTING_FRICTION,
    "twisting_friction",
    NUM,
    "",
    Number(0.0),
    Rule::NonNegative,
    "the twisting friction coefficient mu_o, torque <= mu_o a12 f_N*; 0 = none (Luding 2008)"
);
param!(
    KO,
    "ko",
    NUM,
    "N/m",
    Derived("2/5 k1 (hysteretic), 2/5 k (lsd), 2/5 * 8 G* a at the current contact radius a (jkr, hertz)"),
    Rule::Positive,
    "the twisting spring stiffness k_o, torque stiffness k_o a12^2 per rad (Luding 2008)"
);
param!(
    GAMMA_O,
    "gamma_o",
    NUM,
    "kg/s",
    Derived("2/5 gamma0 (hysteretic, lsd), 0 (jkr, hertz)"),
    Rule::NonNegative,
    "the twisting damping gamma_o (Luding 2008)"
);
// Normal dissipation of the JKR family, one sub-model at a time.
param!(
    DISSIPATION,
    "dissipation",
    Choice(&["none", "tsuji", "powerlaw", "krijt", "stress"]),
    "",
    Derived("tsuji when restitution is given, otherwise none"),
    Rule::None,
    "the normal dissipation model"
);
param!(
    RESTITUTION,
    "restitution",
    NUM,
    "",
    Required,
    Rule::LeftOpen(0.0, 1.0),
    "the target restitution e of dissipation = \"tsuji\" (paper 002 eq. 12)"
);
param!(TSUJI_STIFFNESS, "tsuji_stiffness", Choice(TsujiStiffness::WORDS), "", Word(TsujiStiffness::ContactRadius.word()), Rule::None, "the stiffness of the Tsuji dashpots: \"contact-radius\" Sn = 2E* a, St = 8G* a (a the JKR contact radius, also at negative overlap) or \"hertz\" Sn = 2E* sqrt(R* delta), St = 8G* sqrt(R* delta), 0 at delta <= 0 (paper 002 eqs. 13-16)");
param!(
    POWER_D,
    "D",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the power-law dissipation coefficient D (paper 001 eq. 19)"
);
param!(
    POWER_ALPHA,
    "alpha",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the power-law velocity exponent alpha (paper 001 eq. 19)"
);
param!(
    POWER_BETA,
    "beta",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the power-law contact-radius exponent beta (paper 001 eq. 19; it fits 1 < beta < 1.5, and a^beta with beta < 0 diverges as a contact opens)"
);
param!(
    TVIS,
    "tvis",
    NUM,
    "s",
    Required,
    Rule::NonNegative,
    "the relaxation time T_vis of dissipation = \"krijt\" (paper 001 eq. 12)"
);
param!(SIGMA0, "sigma0", NUM, "Pa", Number(0.0), Rule::NonNegative, "the crack stress sigma0 ~ gamma / atomic spacing, 0 = a follows the JKR curve (paper 001 eq. B2)");
param!(
    TVIS0_PER_RADIUS,
    "tvis0_per_radius",
    NUM,
    "s/m",
    Required,
    Rule::NonNegative,
    "C of T_vis,0 = C*R of dissipation = \"stress\" (paper 001 eq. 18)"
);
param!(
    STRESS_B,
    "B",
    NUM,
    "",
    Required,
    Rule::NonNegative,
    "the pressure coefficient B of dissipation = \"stress\" (paper 001 eq. 17)"
);
param!(
    STRESS_ZETA,
    "zeta",
    NUM,
    "",
    Required,
    Rule::Positive,
    "the pressure exponent zeta of dissipation = \"stress\" (paper 001 eq. 17)"
);

/// The normal contact laws, with the parameters each takes.
pub const LAWS: &[Law] = &[
    Law {
        name: "hysteretic",
        doc: "the hysteretic adhesive elasto-plastic model (paper 000 eqs. 5-15)",
        params: &[
            &K1,
            &KP,
            &KC,
            &PHI_F,
            &FA,
            &KCA,
            &ADHESION,
            &GAMMA0,
            &K2_RULE,
            &FRICTION,
            &FRICTION_DYNAMIC,
            &KT,
            &GAMMA_T,
            &ROLLING_FRICTION,
            &KR,
            &GAMMA_R,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: false,
    },
    Law {
        name: "lsd",
        doc: "the linear spring-dashpot (paper 000 eq. 2)",
        params: &[
            &K,
            &GAMMA0,
            &FRICTION,
            &FRICTION_DYNAMIC,
            &KT,
            &GAMMA_T,
            &ROLLING_FRICTION,
            &KR,
            &GAMMA_R,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: false,
    },
    Law {
        name: "jkr",
        doc: "JKR with damping, friction and rolling resistance (papers 001, 002)",
        params: &[
            &YOUNGS,
            &POISSON,
            &SURFACE_ENERGY,
            &DISSIPATION,
            &FRICTION,
            &ROLLING_HYSTERESIS,
            &PULLOFF,
            &STIFFNESS_SCALE,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: true,
    },
    Law {
        name: "hertz",
        doc: "Hertz (JKR without adhesion) with damping and friction",
        params: &[
            &YOUNGS,
            &POISSON,
            &DISSIPATION,
            &FRICTION,
            &STIFFNESS_SCALE,
            &TWISTING_FRICTION,
            &KO,
            &GAMMA_O,
        ],
        dissipation: true,
    },
];

/// The normal dissipations of the JKR family, selected by `dissipation`.
pub const DISSIPATIONS: &[Law] = &[
    Law {
        name: "none",
        doc: "no dissipation beyond the JKR hysteresis",
        params: &[],
        dissipation: false,
    },
    Law {
        name: "tsuji",
        doc: "Tsuji damping calibrated by the restitution (paper 002 eqs. 11-13, 16)",
        params: &[&RESTITUTION, &TSUJI_STIFFNESS],
        dissipation: false,
    },
    Law {
        name: "powerlaw",
        doc: "power-law dissipation D E* |v|^alpha a^beta (paper 001 eq. 19)",
        params: &[&POWER_D, &POWER_ALPHA, &POWER_BETA],
        dissipation: false,
    },
    Law {
        name: "krijt",
        doc: "the Krijt viscoelastic contact radius (paper 001 eqs. 10-12, B1-B2); jkr only, with surface_energy > 0",
        params: &[&TVIS, &SIGMA0],
        dissipation: false,
    },
    Law {
        name: "stress",
        doc: "the stress-dependent Krijt model (paper 001 eqs. 17-18); jkr only, with surface_energy > 0",
        params: &[&TVIS0_PER_RADIUS, &STRESS_B, &STRESS_ZETA, &SIGMA0],
        dissipation: false,
    },
];
