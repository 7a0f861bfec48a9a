//! The constants of the WGSL solvers (model/jkr.wgsl's contact radius, model/krijt.wgsl's
//! crack speed), rounded from the f64 reference's, so the two languages solve one function.

use super::wgsl_consts;
use crate::model::jkr::{radius, NEWTON_ITERATIONS_F32, X_TOUCH};
use crate::model::krijt::{BETA_MAX, BETA_MIN};

wgsl_consts! {
    /// The f32 constants of the JKR contact radius (`jkr::contact_radius_f32`).
    pub JKR_SOLVER: f32 = {
        /// s_min = 6^(−1/3), where the displacement pull-off sits (s = √(a/a0)).
        JKR_S_MIN = crate::model::jkr::S_MIN as f32,
        /// d_min = −(3/4)^(2/3), the displacement pull-off δ/δ0.
        JKR_D_MIN = crate::model::jkr::D_PULLOFF_DISPLACEMENT as f32,
        /// c = 2·s_min, of the deflated solve.
        JKR_C = radius::C_T as f32,
        /// b = 2·s_min², of the deflated solve.
        JKR_B = radius::B_T as f32,
        /// √3.
        JKR_SQRT3 = radius::SQRT3 as f32,
        /// √18·s_min, the solve's slope at t = 0.
        JKR_SLOPE0 = radius::SLOPE0 as f32,
        /// π.
        JKR_PI = std::f64::consts::PI as f32,
    }
}

wgsl_consts! {
    /// The f32 constants of the Krijt contact radius's dynamics (`model::krijt`).
    pub KRIJT_SOLVER: f32 = {
        /// a/a0 at the first touch, a_JKR(0)/a0 = (2/3)^(2/3) (`jkr::X_TOUCH`).
        KRIJT_X_TOUCH = X_TOUCH as f32,
        /// β below which the crack speed of eq. B2 diverges (`krijt::BETA_MIN`).
        KRIJT_BETA_MIN = BETA_MIN as f32,
        /// β above which the crack speed of eq. B2 diverges (`krijt::BETA_MAX`).
        KRIJT_BETA_MAX = BETA_MAX as f32,
    }
}

wgsl_consts! {
    /// The iteration counts of the WGSL solvers.
    pub SOLVER_ITERATIONS: i32 = {
        /// Newton steps of the JKR contact radius in f32 (`jkr::NEWTON_ITERATIONS_F32`).
        JKR_NEWTON_ITERATIONS = NEWTON_ITERATIONS_F32 as i32,
        /// Bisection steps of the Krijt backward-Euler solve at most (it stops once the
        /// bracket has no f32 inside; 30 halvings take a bracket of 2^6·a to one ulp of a).
        KRIJT_BISECTION_ITERATIONS = 30,
        /// Sub-steps of the crack law in a step of a `crack` contact's neck
        /// (`krijt::NECK_SUBSTEPS`).
        KRIJT_NECK_SUBSTEPS = crate::model::krijt::NECK_SUBSTEPS as i32,
    }
}

const _: () = assert!(KRIJT_BISECTION_ITERATIONS >= 24);
