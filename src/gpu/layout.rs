//! Memory layout shared by the host and the kernels: the particle position
//! representation and the uniform blocks, as `#[repr(C)]` bytemuck structs whose WGSL
//! twins live in `shaders/common.wgsl` / `shaders/grid.wgsl` (the tests check the two
//! layouts against naga's).
//!
//! **Positions: integer cell + f32 offset.** f32 absolute positions ~1e4 diameters from
//! the origin are spaced as coarsely as the overlaps that decide the forces, so a particle
//! is an integer cell ([`CellCoord`], w = material) and an f32 offset inside it
//! ([`CellOffset`], in `[0, h)`, w = radius). Separations are formed as
//! `(cell_i - cell_j) * h + (off_i - off_j)`: the integer difference is exact, so an
//! overlap keeps f32's relative precision (`h * 2^-24`) anywhere in a domain of up to
//! `2^31` cells per axis. The cell width `h` (from the domain's min corner, fixed for a
//! run) is the neighbour grid's ([`crate::gpu::grid`]); encode with the f32 value the
//! kernels see ([`gpu_cell_width`]).

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// Integer cell of a particle: xyz = cell coordinates, w = material index (in the engine's
/// state with `gpu::state::NOT_APPEARED` added until the particle appears). WGSL: `vec4<i32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CellCoord(pub [i32; 4]);

/// Position inside the cell: xyz in `[0, h)`, w = radius. WGSL: `vec4<f32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CellOffset(pub [f32; 4]);

/// Grid parameters of a run: twin of `GridParams` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridParams {
    /// Cells per axis.
    pub dims: [u32; 3],
    /// Particles in the run.
    pub n_particles: u32,
    /// Cell width per axis (equal unless periodic axes fix it to the period over the
    /// cell count).
    pub cell_width: [f32; 3],
    /// `dims[0] * dims[1] * dims[2]`.
    pub n_cells: u32,
    /// The windows ([`crate::gpu::window::Windows::params`]).
    pub window: [u32; 4],
}

/// One level of the exclusive scan: twin of `ScanParams` in `shaders/grid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ScanParams {
    /// Elements at this level.
    pub n: u32,
    /// Workgroups doing real work: `ceil(n / SCAN_BLOCK)`.
    pub n_blocks: u32,
    /// Where the elements start in the input (elements).
    pub in_offset: u32,
    /// Where they go in the output (elements).
    pub out_offset: u32,
}

/// The f32-representable cell width nearest `h`: what the kernels will see.
pub fn gpu_cell_width(h: f64) -> f64 {
    h as f32 as f64
}

/// Splits an absolute position into its cell (relative to `origin`, width `h`) and the
/// f32 offset inside it, each component in `[0, h)`. The w components are 0; set them
/// to the material index and the radius (or use [`PackedPosition::new`]).
///
/// The offset is rounded to the nearest f32; when that rounds up to `h` itself the
/// particle moves to the next cell with offset 0, so `0 <= offset < h` always holds.
/// Cells beyond the i32 range saturate (positions there are not representable).
pub fn encode(p: DVec3, origin: DVec3, h: f64) -> ([i32; 4], [f32; 4]) {
    encode3(p, origin, DVec3::splat(h))
}

/// [`encode`] with a cell width per axis.
pub fn encode3(p: DVec3, origin: DVec3, hs: DVec3) -> ([i32; 4], [f32; 4]) {
    let mut cell = [0i32; 4];
    let mut offset = [0f32; 4];
    for axis in 0..3 {
        let h = hs[axis];
        let h32 = h as f32;
        let rel = p[axis] - origin[axis];
        let mut c = (rel / h).floor();
        // Offset taken in f64 from the cell's corner; exact up to f64 rounding of rel.
        let mut o = rel - c * h;
        // (rel / h).floor() can be off by one next to a cell face.
        if o < 0.0 {
            c -= 1.0;
            o += h;
        } else if o >= h {
            c += 1.0;
            o -= h;
        }
        let mut o32 = o as f32;
        if o32 >= h32 || (o32 as f64) >= h {
            c += 1.0;
            o32 = 0.0;
        }
        cell[axis] = c as i32;
        offset[axis] = o32.max(0.0);
    }
    (cell, offset)
}

/// Absolute position of a cell and offset (w components ignored).
pub fn decode(cell: [i32; 4], offset: [f32; 4], origin: DVec3, h: f64) -> DVec3 {
    decode3(cell, offset, origin, DVec3::splat(h))
}

/// [`decode`] with a cell width per axis.
pub fn decode3(cell: [i32; 4], offset: [f32; 4], origin: DVec3, h: DVec3) -> DVec3 {
    DVec3::new(
        origin.x + (cell[0] as f64) * h.x + offset[0] as f64,
        origin.y + (cell[1] as f64) * h.y + offset[1] as f64,
        origin.z + (cell[2] as f64) * h.z + offset[2] as f64,
    )
}

/// A particle's position with its material (cell.w) and radius (offset.w).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PackedPosition {
    /// Integer cell; w = material index (see [`CellCoord`]).
    pub cell: CellCoord,
    /// Offset inside the cell, m; w = radius, m.
    pub offset: CellOffset,
}

impl PackedPosition {
    /// Encodes position `p` (m) on the grid at `origin` with cell width `h` (see [`encode`]),
    /// with `material` in cell.w and `radius` (m, rounded to f32) in offset.w.
    pub fn new(p: DVec3, origin: DVec3, h: f64, material: u32, radius: f64) -> Self {
        let (mut cell, mut offset) = encode(p, origin, h);
        cell[3] = material as i32;
        offset[3] = radius as f32;
        Self {
            cell: CellCoord(cell),
            offset: CellOffset(offset),
        }
    }

    /// The absolute position, m, on the grid at `origin` with cell width `h` (see [`decode`]).
    pub fn position(&self, origin: DVec3, h: f64) -> DVec3 {
        decode(self.cell.0, self.offset.0, origin, h)
    }

    /// The material index (cell.w without `NOT_APPEARED`).
    pub fn material(&self) -> u32 {
        (self.cell.0[3] & !crate::gpu::state::NOT_APPEARED) as u32
    }

    /// The radius, m (offset.w).
    pub fn radius(&self) -> f32 {
        self.offset.0[3]
    }
}

/// The vector from particle j to particle i as the kernels form it, in f32:
/// `(cell_i - cell_j) * h + (off_i - off_j)`.
pub fn separation_f32(
    cell_i: [i32; 4],
    off_i: [f32; 4],
    cell_j: [i32; 4],
    off_j: [f32; 4],
    h: f32,
) -> [f32; 3] {
    let mut d = [0f32; 3];
    for axis in 0..3 {
        let dc = cell_i[axis].wrapping_sub(cell_j[axis]) as f32;
        d[axis] = dc * h + (off_i[axis] - off_j[axis]);
    }
    d
}

/// The hysteretic law's block of the pair table (`HystereticPair` of
/// `shaders/contact/hysteretic.wgsl`).
/// LSD is the special case k1 = kp = k with the LSD flag.
#[repr(C)]
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

/// Flags of [`HystereticPair`], as in the WGSL.
pub const HYST_JUMP_IN: u32 = 1;
/// The k2 rule is the √ interpolation (paper 000 appendix D) instead of the linear eq. 9.
pub const HYST_SQRT_RULE: u32 = 2;
/// The row is a linear spring-dashpot (LSD): f = k·δ + γ0·δ̇ with k = k1 = kp.
pub const HYST_LSD: u32 = 4;

impl HystereticPair {
    /// The row of a hysteretic pair, rounded to f32 (kca = ∞ encoded as 0).
    pub fn hysteretic(p: &crate::model::HystereticParams) -> Self {
        use crate::model::{AdhesionMode, K2Rule};
        let dmaxp = if p.kp > p.k1 {
            p.kp / (p.kp - p.k1) * p.phi_f
        } else {
            1e30
        };
        let mut flags = 0;
        if p.adhesion == AdhesionMode::JumpIn {
            flags |= HYST_JUMP_IN;
        }
        if p.k2_rule == K2Rule::Sqrt {
            flags |= HYST_SQRT_RULE;
        }
        let dmaxp = dmaxp.min(1e30);
        Self {
            k1: p.k1 as f32,
            kp: p.kp as f32,
            kc: p.kc as f32,
            dmaxp_per_a12: dmaxp as f32,
            phi_f: p.phi_f as f32,
            fa: p.fa as f32,
            kca: if p.kca.is_finite() { p.kca as f32 } else { 0.0 },
            gamma0: p.gamma0 as f32,
            flags,
            inv_dmaxp_per_a12: (1.0 / dmaxp) as f32,
            tensile_c: if p.kp > p.k1 {
                ((p.k1 + p.kc) / (p.kp - p.k1)) as f32
            } else {
                0.0
            },
            tensile_limit_per_a12: (p.kp * p.phi_f / (p.kp + p.kc)) as f32,
        }
    }

    /// The row of an LSD pair: k1 = kp = k, the [`HYST_LSD`] flag.
    pub fn lsd(p: &crate::model::LsdParams) -> Self {
        Self {
            k1: p.k as f32,
            kp: p.k as f32,
            dmaxp_per_a12: 1e30,
            inv_dmaxp_per_a12: 1e-30,
            gamma0: p.gamma0 as f32,
            flags: HYST_LSD,
            ..Default::default()
        }
    }
}

/// The JKR law's block of the pair table (`JkrPair` of `shaders/contact/jkr.wgsl`): the JKR
/// family's parameters, derived in f64 from [`JkrParams`](crate::model::JkrParams) and
/// rounded once. Per-contact quantities that depend on R* (a0, δ0, Fc, ξcrit) are formed in
/// the kernel from the coefficients here, since R* varies with the particles' radii.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct JkrPair {
    /// E* (scaled), Pa.
    pub e_star: f32,
    /// G* (scaled), Pa.
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
    /// Krijt and stress (`shaders/contact/krijt.wgsl`): 2E*/ν² of the viscous force (eq. 12).
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
}

/// Dissipation kinds of [`JkrPair`], as in the WGSL.
pub const JKR_DISSIPATION_NONE: u32 = 0;
/// Tsuji-type viscous damping from a restitution coefficient (paper 002 eqs. 11–13).
pub const JKR_DISSIPATION_TSUJI: u32 = 1;
/// Power-law dissipation F = sgn(v)·D·E*·|v|^α·a^β (paper 001 eqs. 19–20).
pub const JKR_DISSIPATION_POWER: u32 = 2;
/// Krijt viscoelastic dissipation with a delayed contact radius, constant T_vis (paper 001
/// eqs. 10–12, B1–B2).
pub const JKR_DISSIPATION_KRIJT: u32 = 3;
/// Krijt dissipation with the stress-dependent T_vis of paper 001 eqs. 17–18.
pub const JKR_DISSIPATION_STRESS: u32 = 4;

impl JkrPair {
    /// The row of a JKR/Hertz pair, derived in f64 and rounded once to f32. Krijt and
    /// stress-dependent dissipation are not ported and leave `dissipation` at
    /// [`JKR_DISSIPATION_NONE`].
    pub fn new(p: &crate::model::JkrParams) -> Self {
        use crate::model::jkr::tsuji_beta;
        use crate::model::Dissipation;
        use std::f64::consts::PI;
        let gamma = p.gamma();
        let a0_coef = if gamma > 0.0 {
            (9.0 * PI * gamma / p.e_star()).cbrt()
        } else {
            0.0
        };
        let a0_unscaled_coef = if p.surface_energy > 0.0 {
            (9.0 * PI * p.surface_energy / p.e_star_unscaled()).cbrt()
        } else {
            0.0
        };
        let mut row = Self {
            e_star: p.e_star() as f32,
            g_star: p.g_star() as f32,
            gamma: gamma as f32,
            a0_coef: a0_coef as f32,
            break_ratio: p.pulloff.break_overlap_ratio() as f32,
            friction: p.friction as f32,
            rolling_hysteresis: p.rolling_hysteresis as f32,
            fc_unscaled_per_r: (3.0 * PI * p.surface_energy) as f32,
            a0_unscaled_coef: a0_unscaled_coef as f32,
            p_break: crate::model::jkr::potential_shape(p.pulloff.break_radius_ratio()) as f32,
            ..Default::default()
        };
        match p.dissipation {
            Dissipation::None => {}
            Dissipation::Tsuji {
                restitution,
                stiffness,
            } => {
                row.dissipation = JKR_DISSIPATION_TSUJI;
                // 2·√(5/6)·(−β): the prefactor of paper 002 eqs. 11 and 16
                row.tsuji = (-2.0 * (5.0f64 / 6.0).sqrt() * tsuji_beta(restitution)) as f32;
                row.tsuji_hertz = u32::from(stiffness == crate::model::TsujiStiffness::Hertz);
            }
            Dissipation::PowerLaw { d, alpha, beta } => {
                row.dissipation = JKR_DISSIPATION_POWER;
                row.power_d = d as f32;
                row.power_alpha = alpha as f32;
                row.power_beta = beta as f32;
            }
            Dissipation::Krijt { tvis, sigma0 } => {
                row.dissipation = JKR_DISSIPATION_KRIJT;
                row.tvis = tvis as f32;
                row.set_krijt(p, sigma0);
            }
            Dissipation::Stress {
                tvis0_per_radius,
                b,
                zeta,
                sigma0,
            } => {
                row.dissipation = JKR_DISSIPATION_STRESS;
                row.tvis = tvis0_per_radius as f32;
                row.stress_b = b as f32;
                row.stress_zeta = zeta as f32;
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
        self.visc = (2.0 * m.e_star / (m.poisson * m.poisson)) as f32;
        self.crack = if sigma0 > 0.0 {
            (2.0 * m.e_star * m.gamma / (sigma0 * sigma0)).min(f32::MAX as f64) as f32
        } else {
            0.0
        };
    }
}

/// One Luding spring's block of the pair table (`CoulombSpring` of
/// `shaders/contact/coulomb.wgsl`): [`CoulombSpring`](crate::model::CoulombSpring) rounded to
/// f32; all zero (μs = 0) is off.
#[repr(C)]
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

impl CoulombSpringRow {
    /// The block of a spring.
    pub fn new(s: &crate::model::CoulombSpring) -> Self {
        Self {
            mu_s: s.mu_s as f32,
            mu_d: s.mu_d as f32,
            k: s.k as f32,
            gamma: s.gamma as f32,
        }
    }
}

/// The twisting block of the pair table (`TwistingRow` of
/// `shaders/contact/luding_twisting.wgsl`): the spring, and for the JKR family without a
/// given k_o the stiffness per contact radius (k_o = k + k_per_a·a).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwistingRow {
    /// The spring (its `k` is 0 where the stiffness follows the contact radius).
    pub spring: CoulombSpringRow,
    /// dk_o/da, N/m²: 2/5·8G* for the JKR family's default, else 0.
    pub k_per_a: f32,
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
            k_per_a: k_per_a as f32,
        })
    }
}

/// Per-run step parameters: twin of `StepParams` in `shaders/step.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StepParams {
    /// Time step, s.
    pub dt: f32,
    /// Entries the neighbour lists have room for (each per-entry array).
    pub list_capacity: u32,
    /// Materials in the pair-model table (n_materials × n_materials rows).
    pub n_materials: u32,
    /// Walls in the wall buffer.
    pub n_walls: u32,
    /// At offset 16, not 0: see the note on the WGSL struct (a lavapipe slowdown and leak).
    pub gravity: [f32; 3],
    /// Largest distance beyond touching at which any pair interacts (non-contact range or
    /// JKR neck), m; pairs farther apart than r_i + r_j + reach exert no force.
    pub reach: f32,
    /// The domain box's extent in cells (the run monitor's escape check).
    pub extent_cells: [f32; 3],
    /// 1 when some wall is servo-controlled.
    pub servo_walls: u32,
    /// 1 on periodic axes.
    pub periodic: [u32; 3],
    /// Always 0: the kernels read it to hide values from the shader compiler, so Kahan
    /// compensations are not folded away (see `opaque` in `shaders/step.wgsl`).
    pub zero: u32,
    /// The Verlet skin, m: a rebuild comes once a particle (or a moving wall, along its
    /// normal) has moved more than half of it.
    pub skin: f32,
    /// 1 when the force jumps of a variant that places them are placed (0 for the initial
    /// forces, whose contacts crossed nothing).
    pub jumps: u32,
    /// Pads `period_lo` to its 16-byte alignment.
    pub _pad: [u32; 2],
    /// Per periodic axis, the scene's period less the device's, L − dims·h, m (h is
    /// rounded to f32): a wrap and a separation across the seam add it (0 elsewhere).
    pub period_lo: [f32; 3],
    /// Pads the struct to WGSL's 16-byte size multiple.
    pub _pad_end: u32,
}

/// A planar wall: a point as cell + offset and the unit normal. Twin of `Wall` in
/// `shaders/step.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WallGpu {
    /// A point of the plane: integer cell (xyz), w unused.
    pub cell: [i32; 4],
    /// A point of the plane: offset inside the cell (xyz), m; w: the plane's rounding
    /// residual n·(encoded − true point), m, which the kernels' overlap subtracts (a wall the
    /// device moves books each move's rounding into it).
    pub offset: [f32; 4],
    /// Unit normal pointing into the domain (xyz); w unused.
    pub normal: [f32; 4],
    /// Velocity over the current step (xyz).
    pub velocity: [f32; 4],
    /// x: [`WALL_FIXED`], [`WALL_PRESCRIBED`] or [`WALL_SERVO`]; y, z, w: the servo's
    /// force (N), gain (m/s per N) and largest speed (m/s).
    pub motion: [f32; 4],
    /// The unit normal's f32 rounding residual (xyz, true − stored); w unused. The kernels'
    /// wall overlap adds it, so a tilted plane does not turn about its stored point.
    pub normal_lo: [f32; 4],
}

/// Wall motion kinds of [`WallGpu::motion`], as in the WGSL.
pub const WALL_FIXED: f32 = 0.0;
/// The wall moves with a prescribed velocity schedule.
pub const WALL_PRESCRIBED: f32 = 1.0;
/// The wall is servo-controlled to hold a target force.
pub const WALL_SERVO: f32 = 2.0;

impl WallGpu {
    /// A fixed wall through `point` (m) with normal `normal` (normalised here), encoded on the
    /// grid at `origin` with cell widths `h`.
    pub fn new(point: DVec3, normal: DVec3, origin: DVec3, h: DVec3) -> Self {
        let (cell, mut offset) = encode3(point, origin, h);
        let n = normal.normalize();
        let n32 = DVec3::new(n.x as f32 as f64, n.y as f32 as f64, n.z as f32 as f64);
        offset[3] = n32.dot(decode3(cell, offset, origin, h) - point) as f32;
        Self {
            cell,
            offset,
            normal: [n.x as f32, n.y as f32, n.z as f32, 0.0],
            velocity: [0.0; 4],
            motion: [WALL_FIXED, 0.0, 0.0, 0.0],
            normal_lo: [
                (n.x - n32.x) as f32,
                (n.y - n32.y) as f32,
                (n.z - n32.z) as f32,
                0.0,
            ],
        }
    }

    /// A scene wall at time 0.
    pub fn from_scene(w: &crate::scene::Wall, origin: DVec3, h: DVec3) -> Self {
        let mut g = Self::new(
            DVec3::from_array(w.point),
            DVec3::from_array(w.normal),
            origin,
            h,
        );
        g.motion = Self::motion_code(w.motion.at(0.0));
        g
    }

    /// `motion` for a wall in `phase`: (kind, servo force, gain, largest speed).
    pub fn motion_code(phase: crate::scene::WallPhase) -> [f32; 4] {
        use crate::scene::WallPhase;
        match phase {
            WallPhase::Rest => [WALL_FIXED, 0.0, 0.0, 0.0],
            WallPhase::Velocity(_) => [WALL_PRESCRIBED, 0.0, 0.0, 0.0],
            WallPhase::Servo {
                force,
                gain,
                max_speed,
            } => [WALL_SERVO, force as f32, gain as f32, max_speed as f32],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::composition::Keeps;
    use crate::gpu::shaders;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;
    use std::mem::{offset_of, size_of};

    fn norm_f32(d: [f32; 3]) -> f32 {
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    #[test]
    fn gpu_layout_round_trip_error_is_below_h_2_pow_minus_23() {
        let mut rng = Pcg64::seed_from_u64(7);
        for &h in &[2.2, 1e-4, 3.0e-6, 0.5, 17.0] {
            let origin = DVec3::new(-3.5, 12.25, -1e3) * h;
            let bound = h * 2f64.powi(-23);
            let width = 1e4 * h;
            let mut worst = 0f64;
            for k in 0..20_000 {
                let mut p = origin + DVec3::new(rng.random(), rng.random(), rng.random()) * width;
                if k % 100 == 0 {
                    // Exactly on a cell face, and just below one.
                    let c = (rng.random::<f64>() * 1e4).floor();
                    p.x = origin.x + c * h;
                    p.y = origin.y + c * h - h * 1e-12;
                }
                let (cell, off) = encode(p, origin, h);
                for o in &off[..3] {
                    assert!(
                        *o >= 0.0 && (*o as f64) < h,
                        "offset {o} outside [0, {h}) for {p}"
                    );
                }
                let q = decode(cell, off, origin, h);
                worst = worst.max((q - p).abs().max_element());
            }
            assert!(
                worst <= bound,
                "h = {h}: worst round-trip error {worst:e} > h 2^-23 = {bound:e}"
            );
        }
    }

    /// Worst relative overlap errors over random pairs of touching spheres (radius 1,
    /// overlap 1e-3) near cell 1e4 of a grid of width h = 2.2: (f32 cell/offset
    /// arithmetic vs the stored state in f64, stored state vs the true overlap, f32
    /// cell/offset vs the true overlap, naive absolute f32 vs the true overlap).
    fn overlap_errors(axis_aligned: bool) -> [f64; 4] {
        // The kernels' h is f32: encode with exactly that value (see gpu_cell_width).
        let h = gpu_cell_width(2.2);
        let h32 = h as f32;
        let origin = DVec3::ZERO;
        let (r, overlap) = (1.0f64, 1e-3f64);
        let mut rng = Pcg64::seed_from_u64(11);
        let mut worst = [0f64; 4];
        for k in 0..20_000 {
            let centre = DVec3::new(rng.random(), rng.random(), rng.random()) * 100.0 * h
                + DVec3::splat(1e4 * h);
            let dir = if axis_aligned {
                let mut v = DVec3::ZERO;
                v[k % 3] = if (k / 3) % 2 == 0 { 1.0 } else { -1.0 };
                v
            } else {
                loop {
                    let v = DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - DVec3::ONE;
                    if v.length() > 0.1 && v.length() < 1.0 {
                        break v.normalize();
                    }
                }
            };
            let pi = centre;
            let pj = centre + dir * (2.0 * r - overlap);
            let (ci, oi) = encode(pi, origin, h);
            let (cj, oj) = encode(pj, origin, h);
            assert!(ci[0] >= 10_000 && ci[0] < 10_200);
            // GPU way: cell and offset differences in f32.
            let gpu = (2.0 * r as f32 - norm_f32(separation_f32(ci, oi, cj, oj, h32))) as f64;
            // The stored state evaluated in f64.
            let stored = 2.0 * r - (decode(ci, oi, origin, h) - decode(cj, oj, origin, h)).length();
            // Naive: absolute f32 positions.
            let naive = (2.0 * r as f32 - (pi.as_vec3() - pj.as_vec3()).length()) as f64;
            let errs = [
                (gpu - stored).abs(),
                (stored - overlap).abs(),
                (gpu - overlap).abs(),
                (naive - overlap).abs(),
            ];
            for (w, e) in worst.iter_mut().zip(errs) {
                *w = w.max(e / overlap);
            }
        }
        worst
    }

    #[test]
    fn gpu_layout_far_from_origin_overlap_survives_f32() {
        let (h, overlap) = (gpu_cell_width(2.2), 1e-3);
        // Storing a position rounds each axis by at most h 2^-24 (half an f32 ulp of the
        // offset); that moves a pair's distance by at most 2 h 2^-24 along an axis and
        // 2 sqrt(3) h 2^-24 in general, i.e. 2.6e-4 / 4.5e-4 of this overlap, anywhere in
        // the domain (it is the position resolution, not a loss far from the origin).
        let storage_axis = 2.0 * h * 2f64.powi(-24) / overlap;
        let storage_any = 3f64.sqrt() * storage_axis;

        // Head-on contacts along the axes: the f32 arithmetic on cells and offsets
        // reproduces the stored state's overlap to < 1e-4.
        let [arith, stored, total, naive] = overlap_errors(true);
        eprintln!(
            "axis-aligned, overlap 1e-3 near cell 1e4: relative error of cell/offset f32 \
             {arith:.2e} vs the stored state, {total:.2e} vs the true positions \
             (storage {stored:.2e}); naive absolute f32 {naive:.2e}"
        );
        assert!(arith < 1e-4, "cell/offset f32 arithmetic error {arith:e}");
        assert!(stored <= storage_axis, "storage error {stored:e}");
        assert!(
            total < 1e-4 + storage_axis,
            "cell/offset f32 total error {total:e}"
        );
        // Absolute f32 positions near 2.2e4 are spaced 2^-9 ~ 2e-3 apart: the overlap
        // is lost entirely.
        assert!(
            naive > 0.1,
            "naive f32 unexpectedly kept the overlap: {naive:e}"
        );

        // Arbitrary directions: forming |d| ~ 2 in f32 (three components, squares, sum,
        // sqrt) costs about one f32 ulp of 2 (2.4e-7), i.e. ~2e-4 of this overlap.
        // Still three to four orders of magnitude better than absolute f32.
        let [arith, stored, total, naive] = overlap_errors(false);
        eprintln!(
            "any direction, overlap 1e-3 near cell 1e4: relative error of cell/offset f32 \
             {arith:.2e} vs the stored state, {total:.2e} vs the true positions \
             (storage {stored:.2e}); naive absolute f32 {naive:.2e}"
        );
        assert!(arith < 3e-4, "cell/offset f32 arithmetic error {arith:e}");
        assert!(stored <= storage_any, "storage error {stored:e}");
        assert!(
            total < 3e-4 + storage_any,
            "cell/offset f32 total error {total:e}"
        );
        assert!(
            naive > 0.1,
            "naive f32 unexpectedly kept the overlap: {naive:e}"
        );
    }

    #[test]
    fn gpu_layout_touching_spheres_at_cell_1e4() {
        // The worked example: radius 1, h = 2.2 (as f32), centres 1.999 apart along x
        // around cell 1e4 (x ~ 2.2e4). Particle i is stored exactly, j to 1.5e-8.
        let h = gpu_cell_width(2.2);
        let origin = DVec3::ZERO;
        let pi = DVec3::new(10_000.0 * h + 0.625, 10_000.0 * h + 1.0, 10_000.0 * h + 1.0);
        let pj = pi + DVec3::new(1.999, 0.0, 0.0);
        let (ci, oi) = encode(pi, origin, h);
        let (cj, oj) = encode(pj, origin, h);
        assert_eq!(ci[0], 10_000);
        assert_eq!(cj[0], 10_001);
        let gpu = 2.0 - norm_f32(separation_f32(cj, oj, ci, oi, h as f32)) as f64;
        assert!(
            ((gpu - 1e-3) / 1e-3).abs() < 1e-4,
            "cell/offset overlap {gpu:e}"
        );
        let naive = 2.0 - (pj.as_vec3() - pi.as_vec3()).length() as f64;
        assert!(
            ((naive - 1e-3) / 1e-3).abs() > 0.1,
            "naive overlap {naive:e}"
        );
    }

    #[test]
    fn gpu_layout_packed_position_carries_material_and_radius() {
        let p = PackedPosition::new(DVec3::new(1.0, -2.0, 3.5), DVec3::splat(-4.0), 0.75, 3, 0.3);
        assert_eq!(p.material(), 3);
        assert_eq!(p.radius(), 0.3f32);
        assert!(
            (p.position(DVec3::splat(-4.0), 0.75) - DVec3::new(1.0, -2.0, 3.5)).length() < 1e-6
        );
        assert_eq!(size_of::<PackedPosition>(), 32);
        assert_eq!(bytemuck::bytes_of(&p).len(), 32);
    }

    /// Size and member offsets of a WGSL struct as naga lays it out.
    fn wgsl_struct(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
        for (_, ty) in module.types.iter() {
            if ty.name.as_deref() == Some(name) {
                if let naga::TypeInner::Struct { members, span } = &ty.inner {
                    return (
                        *span,
                        members
                            .iter()
                            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                            .collect(),
                    );
                }
            }
        }
        panic!("struct {name} not found in the WGSL module");
    }

    #[test]
    fn gpu_layout_rust_structs_match_wgsl() {
        let grid = shaders::variant("grid").expect("grid variant");
        let (module, _) = shaders::validate(&grid.source).unwrap();
        let (size, members) = wgsl_struct(&module, "GridParams");
        assert_eq!(size as usize, size_of::<GridParams>());
        let expect = [
            ("dims", offset_of!(GridParams, dims)),
            ("n_particles", offset_of!(GridParams, n_particles)),
            ("cell_width", offset_of!(GridParams, cell_width)),
            ("n_cells", offset_of!(GridParams, n_cells)),
        ];
        for (name, off) in expect {
            let m = members.iter().find(|(n, _)| n == name).unwrap();
            assert_eq!(m.1 as usize, off, "GridParams.{name}");
        }
        let (size, members) = wgsl_struct(&module, "ScanParams");
        assert_eq!(size as usize, size_of::<ScanParams>());
        assert_eq!(
            members[0],
            ("n".to_string(), offset_of!(ScanParams, n) as u32)
        );
        assert_eq!(
            members[1],
            (
                "n_blocks".to_string(),
                offset_of!(ScanParams, n_blocks) as u32
            )
        );
        assert_eq!(size_of::<CellCoord>(), 16);
        assert_eq!(size_of::<CellOffset>(), 16);
    }

    #[test]
    fn gpu_layout_step_structs_match_wgsl() {
        let (module, _) = shaders::validate(&shaders::step_variant().source).unwrap();
        let check = |name: &str, size: usize, expect: &[(&str, usize)]| {
            let (wsize, members) = wgsl_struct(&module, name);
            assert_eq!(wsize as usize, size, "{name} size");
            for (field, off) in expect {
                let m = members
                    .iter()
                    .find(|(n, _)| n == field)
                    .unwrap_or_else(|| panic!("{name}.{field}"));
                assert_eq!(m.1 as usize, *off, "{name}.{field}");
            }
        };
        check(
            "StepParams",
            size_of::<StepParams>(),
            &[
                ("gravity", offset_of!(StepParams, gravity)),
                ("dt", offset_of!(StepParams, dt)),
                ("list_capacity", offset_of!(StepParams, list_capacity)),
                ("n_materials", offset_of!(StepParams, n_materials)),
                ("n_walls", offset_of!(StepParams, n_walls)),
                ("reach", offset_of!(StepParams, reach)),
                ("extent_cells", offset_of!(StepParams, extent_cells)),
                ("servo_walls", offset_of!(StepParams, servo_walls)),
                ("periodic", offset_of!(StepParams, periodic)),
                ("zero", offset_of!(StepParams, zero)),
                ("skin", offset_of!(StepParams, skin)),
                ("period_lo", offset_of!(StepParams, period_lo)),
            ],
        );
        check(
            "HystereticPair",
            size_of::<HystereticPair>(),
            &[
                ("k1", offset_of!(HystereticPair, k1)),
                ("kp", offset_of!(HystereticPair, kp)),
                ("kc", offset_of!(HystereticPair, kc)),
                ("dmaxp_per_a12", offset_of!(HystereticPair, dmaxp_per_a12)),
                ("phi_f", offset_of!(HystereticPair, phi_f)),
                ("fa", offset_of!(HystereticPair, fa)),
                ("kca", offset_of!(HystereticPair, kca)),
                ("gamma0", offset_of!(HystereticPair, gamma0)),
                ("flags", offset_of!(HystereticPair, flags)),
                (
                    "inv_dmaxp_per_a12",
                    offset_of!(HystereticPair, inv_dmaxp_per_a12),
                ),
                ("tensile_c", offset_of!(HystereticPair, tensile_c)),
                (
                    "tensile_limit_per_a12",
                    offset_of!(HystereticPair, tensile_limit_per_a12),
                ),
            ],
        );
        // a scene with every law: the pair row is the tag and each law's block, unpadded
        use crate::gpu::composition::Composition;
        let all = Composition::all()
            .into_iter()
            .max_by_key(|c| c.history_bytes())
            .unwrap();
        let (jkr, _) = shaders::validate(&all.variant(Keeps::ALL[3], true, false).source).unwrap();
        let (wsize, members) = wgsl_struct(&jkr, "PairRow");
        assert_eq!(wsize as usize, all.row_bytes(), "PairRow size");
        let jkr_at = 4 + size_of::<HystereticPair>() as u32;
        let sliding_at = jkr_at + size_of::<JkrPair>() as u32;
        let spring = size_of::<CoulombSpringRow>() as u32;
        assert_eq!(
            members,
            vec![
                ("law".to_string(), 0),
                ("hysteretic".to_string(), 4),
                ("jkr".to_string(), jkr_at),
                ("luding_sliding".to_string(), sliding_at),
                ("luding_rolling".to_string(), sliding_at + spring),
                ("luding_twisting".to_string(), sliding_at + 2 * spring),
            ]
        );
        let (wsize, members) = wgsl_struct(&jkr, "CoulombSpring");
        assert_eq!(wsize, spring, "CoulombSpring size");
        for (field, off) in [
            ("mu_s", offset_of!(CoulombSpringRow, mu_s)),
            ("mu_d", offset_of!(CoulombSpringRow, mu_d)),
            ("k", offset_of!(CoulombSpringRow, k)),
            ("gamma", offset_of!(CoulombSpringRow, gamma)),
        ] {
            assert!(
                members.contains(&(field.to_string(), off as u32)),
                "CoulombSpring.{field}"
            );
        }
        let (wsize, members) = wgsl_struct(&jkr, "TwistingRow");
        assert_eq!(wsize as usize, size_of::<TwistingRow>(), "TwistingRow size");
        assert_eq!(
            members,
            vec![
                ("spring".to_string(), offset_of!(TwistingRow, spring) as u32),
                (
                    "k_per_a".to_string(),
                    offset_of!(TwistingRow, k_per_a) as u32
                ),
            ]
        );
        let (wsize, members) = wgsl_struct(&jkr, "JkrPair");
        assert_eq!(wsize as usize, size_of::<JkrPair>(), "JkrPair size");
        for (field, off) in [
            ("e_star", offset_of!(JkrPair, e_star)),
            ("g_star", offset_of!(JkrPair, g_star)),
            ("gamma", offset_of!(JkrPair, gamma)),
            ("a0_coef", offset_of!(JkrPair, a0_coef)),
            ("break_ratio", offset_of!(JkrPair, break_ratio)),
            ("friction", offset_of!(JkrPair, friction)),
            (
                "rolling_hysteresis",
                offset_of!(JkrPair, rolling_hysteresis),
            ),
            ("fc_unscaled_per_r", offset_of!(JkrPair, fc_unscaled_per_r)),
            ("a0_unscaled_coef", offset_of!(JkrPair, a0_unscaled_coef)),
            ("dissipation", offset_of!(JkrPair, dissipation)),
            ("tsuji", offset_of!(JkrPair, tsuji)),
            ("power_d", offset_of!(JkrPair, power_d)),
            ("power_alpha", offset_of!(JkrPair, power_alpha)),
            ("power_beta", offset_of!(JkrPair, power_beta)),
            ("p_break", offset_of!(JkrPair, p_break)),
            ("visc", offset_of!(JkrPair, visc)),
            ("tvis", offset_of!(JkrPair, tvis)),
            ("crack", offset_of!(JkrPair, crack)),
            ("stress_b", offset_of!(JkrPair, stress_b)),
            ("stress_zeta", offset_of!(JkrPair, stress_zeta)),
            ("tsuji_hertz", offset_of!(JkrPair, tsuji_hertz)),
        ] {
            let m = members
                .iter()
                .find(|(n, _)| n == field)
                .unwrap_or_else(|| panic!("JkrPair.{field}"));
            assert_eq!(m.1 as usize, off, "JkrPair.{field}");
        }
        assert_eq!(members.len(), 21, "JkrPair members: {members:?}");
        check(
            "Wall",
            size_of::<WallGpu>(),
            &[
                ("cell", offset_of!(WallGpu, cell)),
                ("offset", offset_of!(WallGpu, offset)),
                ("normal", offset_of!(WallGpu, normal)),
                ("velocity", offset_of!(WallGpu, velocity)),
                ("motion", offset_of!(WallGpu, motion)),
                ("normal_lo", offset_of!(WallGpu, normal_lo)),
            ],
        );
    }

    /// The stored history of each composition is as large as the host allocates
    /// (`Composition::history_bytes`): `struct Hist` in naga's layout, and the history
    /// fields of the entries (pairs' and walls') and the new lists.
    #[test]
    fn gpu_layout_history_strides_match_wgsl() {
        for kind in crate::gpu::composition::Composition::all() {
            let (module, _) =
                shaders::validate(&kind.variant(Keeps::ALL[3], false, false).source).unwrap();
            let (_, hist) = module
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some("Hist"))
                .unwrap_or_else(|| panic!("{}: no Hist", kind.name()));
            assert_eq!(
                hist.inner.size(module.to_ctx()) as u64,
                kind.history_bytes(),
                "{}",
                kind.name()
            );
            let records = kind.records(Keeps::ALL[3]);
            for (r, name) in records.iter().zip(["hist", "new_hist"]) {
                let (_, words) = r.place(name).expect("a history field");
                assert_eq!(4 * words, kind.history_bytes(), "{}: {name}", kind.name());
            }
        }
    }
}
