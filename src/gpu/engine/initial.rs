//! A run's initial particle state in the grid's order, and the energy each particle brings
//! when it appears.

use super::*;

/// The particles (by index into `cells`) in the order of the grid sort (`grid.wgsl`):
/// by clamped linear cell key, x fastest, then by index.
pub(super) fn grid_order(cells: &[[i32; 4]], dims: [u32; 3]) -> Vec<usize> {
    let key = |c: &[i32; 4]| {
        let k: [u64; 3] = [0, 1, 2].map(|a| c[a].clamp(0, dims[a] as i32 - 1) as u64);
        k[0] + dims[0] as u64 * (k[1] + dims[1] as u64 * k[2])
    };
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by_key(|&i| (key(&cells[i]), i));
    order
}

/// A run's initial particle state as the state's fields want it, each particle's values
/// in the grid's order (the first sort keeps it: every particle starts in its window, and
/// a window's neighbours hold its partners, `gpu::window`).
pub(super) struct InitialState {
    /// Scene index of each particle, in upload order.
    order: Vec<usize>,
    cells: Vec<[i32; 4]>,
    offs: Vec<[f32; 4]>,
    vels: Vec<[f32; 4]>,
    acc0: [f32; 4],
    /// The prediction `kick_drift` writes each step, for the initial forces.
    vpred0: Vec<[f32; 4]>,
    /// The compensations (stored − true) of velocity and position, and the radius's
    /// rounding residual: the kernels' x − c is the scene's value to ~1e-16 relative.
    kahan_v: Vec<[f32; 4]>,
    kahan_o: Vec<[f32; 4]>,
    /// ω as the scene gives it, w = I = 2/5·m·r².
    omega: Vec<[f32; 4]>,
}

impl InitialState {
    /// The scene's particles in cells of width `h` from `origin` (`dims` per axis).
    pub(super) fn new(
        scene: &Scene,
        r: &Resolved,
        (origin, h, dims): (DVec3, DVec3, [u32; 3]),
        dt32: f32,
    ) -> Self {
        let n = scene.particles.len();
        let mut cells = Vec::with_capacity(n);
        let mut offs = Vec::with_capacity(n);
        let mut vels = Vec::with_capacity(n);
        let mut kahan_v: Vec<[f32; 4]> = Vec::with_capacity(n);
        let mut kahan_o: Vec<[f32; 4]> = Vec::with_capacity(n);
        for (p, m) in scene.particles.iter().zip(&r.mass) {
            let x = DVec3::from_array(p.position);
            let (mut c, mut o) = encode3(x, origin, h);
            c[3] = p.material as i32;
            if p.insert_at > 0.0 {
                c[3] |= NOT_APPEARED;
            }
            o[3] = p.radius as f32;
            let dx = crate::gpu::layout::decode3(c, o, origin, h) - x;
            let v = p.velocity;
            let v32 = v.map(|c| c as f32);
            let cv = [0, 1, 2].map(|a| (v32[a] as f64 - v[a]) as f32);
            kahan_v.push([cv[0], cv[1], cv[2], 0.0]);
            kahan_o.push([
                dx.x as f32,
                dx.y as f32,
                dx.z as f32,
                (o[3] as f64 - p.radius) as f32,
            ]);
            cells.push(c);
            offs.push(o);
            vels.push([v32[0], v32[1], v32[2], *m as f32]);
        }
        let g = scene.gravity;
        let acc0 = [g[0] as f32, g[1] as f32, g[2] as f32, 0.0];
        let vpred0: Vec<[f32; 4]> = vels
            .iter()
            .map(|v| {
                let p = |i: usize| v[i] + 0.5 * dt32 * acc0[i];
                [p(0), p(1), p(2), v[3]]
            })
            .collect();
        let omega = scene
            .particles
            .iter()
            .zip(&r.mass)
            .map(|(p, m)| {
                let [x, y, z] = p.angular_velocity.map(|c| c as f32);
                [x, y, z, crate::scene::sphere_inertia(*m, p.radius) as f32]
            })
            .collect();
        Self {
            order: grid_order(&cells, dims),
            cells,
            offs,
            vels,
            acc0,
            vpred0,
            kahan_v,
            kahan_o,
            omega,
        }
    }

    /// The state field `name`'s initial words in upload order (`None`: zero).
    pub(super) fn field(&self, name: &str) -> Option<Vec<[u32; 4]>> {
        let words = |v: &[[f32; 4]]| -> Vec<[u32; 4]> {
            self.order.iter().map(|&i| bytemuck::cast(v[i])).collect()
        };
        match name {
            "cell" => Some(
                self.order
                    .iter()
                    .map(|&i| bytemuck::cast(self.cells[i]))
                    .collect(),
            ),
            "off" => Some(words(&self.offs)),
            "vel" => Some(words(&self.vels)),
            "acc" => Some(vec![bytemuck::cast(self.acc0); self.order.len()]),
            "vpred" => Some(words(&self.vpred0)),
            "kahan_v" => Some(words(&self.kahan_v)),
            "kahan_o" => Some(words(&self.kahan_o)),
            // persistent id; the lists and wall entries come with the first rebuild
            "ids" => Some(self.order.iter().map(|&i| [i as u32, 0, 0, 0]).collect()),
            "omega" => Some(words(&self.omega)),
            // (the initial forces' spin: ω, the angular acceleration being 0 until they are in)
            "wpred" => Some(words(&self.omega)),
            _ => None,
        }
    }
}

/// The energy each particle brings when it appears (kinetic, rotational about its centre,
/// gravitational), J: the ledger books it at its insertion.
pub(super) fn insert_energies(scene: &Scene, mass: &[f64]) -> Vec<f64> {
    scene
        .particles
        .iter()
        .zip(mass)
        .map(|(p, m)| {
            let spin = 0.2 * m * p.radius * p.radius;
            0.5 * m * DVec3::from_array(p.velocity).length_squared()
                + spin * DVec3::from_array(p.angular_velocity).length_squared()
                - m * DVec3::from_array(scene.gravity).dot(DVec3::from_array(p.position))
        })
        .collect()
}
