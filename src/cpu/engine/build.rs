//! Building the CPU engine from a scene: the resolved models and time step, the cell grid
//! and skin, the first force evaluation.

use super::*;
use crate::setup::Resolved;

impl CpuEngine {
    /// [`Self::new`] on `threads` (the first force evaluation included).
    pub fn with_threads(scene: &Scene, threads: Threads) -> Result<Self, PowderError> {
        let Resolved {
            n_materials,
            models,
            wall_models,
            mass,
            dt,
            time_step,
            r_max,
            max_reach,
            rotation,
        } = threads.install_all(|| Resolved::new(scene))?;
        let n = scene.particles.len();
        let pos: Vec<DVec3> = scene
            .particles
            .iter()
            .map(|p| DVec3::from_array(p.position))
            .collect();
        let vel: Vec<DVec3> = scene
            .particles
            .iter()
            .map(|p| DVec3::from_array(p.velocity))
            .collect();
        let radius: Vec<f64> = scene.particles.iter().map(|p| p.radius).collect();
        let material: Vec<usize> = scene.particles.iter().map(|p| p.material).collect();
        let cutoff = 2.0 * r_max + max_reach;
        let domain = (
            DVec3::from_array(scene.domain.min),
            DVec3::from_array(scene.domain.max),
        );
        let periodic = scene.domain.periodic;
        let r_min = radius.iter().copied().fold(f64::INFINITY, f64::min);
        // the skin, halved until a periodic axis holds 3 cells of cut-off + skin (without
        // any skin, the list is rebuilt every step)
        let mut skin = if r_min.is_finite() { SKIN * r_min } else { 0.0 };
        let grid = loop {
            let grid = CellGrid::periodic(
                domain.0,
                domain.1,
                (cutoff + skin) * (1.0 + 1e-9),
                n,
                periodic,
            );
            match grid {
                Some(grid) => break grid,
                None if skin > 1e-3 * cutoff => skin *= 0.5,
                None if skin > 0.0 => skin = 0.0,
                None => {
                    let extent = domain.1 - domain.0;
                    let (axis, length) = (0..3)
                        .filter(|&a| periodic[a])
                        .map(|a| (["x", "y", "z"][a], extent[a]))
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .unwrap_or(("?", f64::NAN));
                    return Err(PowderError::Scene(format!(
                        "the domain is {length:.4e} m long along the periodic axis {axis}, shorter than 3 interaction cut-offs ({:.4e} m): a pair would meet two periodic images; enlarge [domain] or make the axis non-periodic",
                        3.0 * cutoff
                    )));
                }
            }
        };
        let walls = scene
            .walls
            .iter()
            .map(|w| WallPlane {
                point: DVec3::from_array(w.point),
                normal: DVec3::from_array(w.normal).normalize(),
                motion: w.motion.clone(),
                velocity: DVec3::ZERO,
            })
            .collect();
        let cutoff_pad = radius.iter().map(|r| r + max_reach).collect();
        let (omega, torque, inertia) = if rotation {
            (
                scene
                    .particles
                    .iter()
                    .map(|p| DVec3::from_array(p.angular_velocity))
                    .collect(),
                vec![DVec3::ZERO; n],
                mass.iter()
                    .zip(&radius)
                    .map(|(&m, &r)| crate::scene::sphere_inertia(m, r))
                    .collect(),
            )
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        let mut engine = Self {
            time: 0.0,
            steps: 0,
            dt,
            time_step,
            scene_parts: crate::checkpoint::run_digests(scene, f64::INFINITY).1,
            acc: vec![DVec3::ZERO; n],
            force: vec![DVec3::ZERO; n],
            omega,
            torque,
            inertia,
            pos,
            vel,
            radius,
            mass,
            material,
            n_materials,
            ranges: models.iter().map(ContactModel::range).collect(),
            wall_ranges: wall_models.iter().map(ContactModel::range).collect(),
            models,
            walls,
            wall_models,
            gravity: DVec3::from_array(scene.gravity),
            grid,
            cutoff_pad,
            skin,
            roots_ahead: true,
            pairs: PairList::empty(n),
            pos_ref: Vec::new(),
            rebuild_due: true,
            rebuilds: 0,
            threads,
            entry_force: Vec::new(),
            entry_torque: Vec::new(),
            own_force: Vec::new(),
            own_torque: Vec::new(),
            wall_contacts: WallList::default(),
            spare_walls: WallList::default(),
            jumps: Vec::new(),
            jump_impulses: scene.jump_impulses.unwrap_or(true),
            wall_start: Vec::new(),
            wall_candidates: Vec::new(),
            wall_ref: Vec::new(),
            v_pred: Vec::new(),
            w_pred: Vec::new(),
            dissipated: 0.0,
            wall_work: 0.0,
            domain,
            periodic,
            insert_at: scene.particles.iter().map(|p| p.insert_at).collect(),
            active: scene.particles.iter().map(|p| p.insert_at <= 0.0).collect(),
            next_insert: 0.0,
            inserted: 0.0,
            peak: None,
        };
        engine.next_insert = engine.earliest_pending();
        engine.v_pred.clone_from(&engine.vel);
        engine.w_pred.clone_from(&engine.omega);
        engine.compute_forces()?;
        engine.update_acceleration();
        // Contacts present at the start carry stored energy, not dissipation, and
        // crossed no edge.
        engine.dissipated = 0.0;
        engine.jumps.clear();
        Ok(engine)
    }
}
