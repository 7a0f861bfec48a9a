//! What the engine built and does: sizes, kernels, buffers, the traffic estimate and the pass profile.

use super::*;

impl GpuEngine {
    /// The time step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.n as usize
    }

    /// Whether the scene has no particles.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Times the neighbour lists grew so far: each a batch that halted at a rebuild whose
    /// lists did not fit, finished after the growth (the first build included).
    pub fn list_growths(&self) -> u64 {
        self.growths
    }

    /// Entries the neighbour lists have room for now, all windows' (each pair a particle
    /// evaluates takes one, and its partner's `lower` one): grown by a rebuild that needs
    /// more.
    pub fn list_entries(&self) -> u64 {
        self.entries * self.state.layout.windows().count
    }

    /// The windows the particles are blocked into (`gpu::window`).
    pub fn windows(&self) -> Windows {
        *self.state.layout.windows()
    }

    /// The pages the lists' entries are in (`gpu::pages`; one where they fit one buffer).
    pub fn entry_pages(&self) -> Pages {
        self.state.pages
    }

    /// Batches halted for a rebuild due in a step recorded without one
    /// ([`RebuildChain::OnDemand`]).
    pub fn rebuild_halts(&self) -> u64 {
        self.lean_halts
    }

    /// The pages the particle state's two buffers are in (`gpu::pages`; one where they
    /// fit one buffer each).
    pub fn state_pages(&self) -> Pages {
        self.state.state_pages
    }

    /// Whether the engine takes the software adapter's paths (texture mirrors, quiet
    /// batches; `GpuOptions::software_paths`).
    pub fn software_paths(&self) -> bool {
        !self.mirrors.is_empty()
    }

    /// Name of the adapter the engine runs on.
    pub fn adapter(&self) -> &str {
        &self.ctx.summary.name
    }

    /// Particle radii in the scene's order, m (f64, as given).
    pub fn radii(&self) -> &[f64] {
        &self.radius
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The time-step rule dt was checked against (default, largest accepted dt, reason).
    pub fn time_step(&self) -> &crate::model::TimeStep {
        &self.time_step
    }

    /// Number of walls.
    pub fn wall_count(&self) -> usize {
        self.n_walls as usize
    }

    /// The digests of the parts of the scene it was built from, named as in the scene
    /// file (`checkpoint::run_digests`, all wall phases).
    pub fn scene_parts(&self) -> &[(String, u64)] {
        &self.scene_parts
    }

    /// Particle masses in the scene's order, kg (f64).
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Whether particles carry angular velocity (some contact model has friction or
    /// rolling resistance), as `CpuEngine::rotates`.
    pub fn rotates(&self) -> bool {
        self.kind.rotation()
    }

    /// Whether the run keeps the energy ledger and contact statistics ([`GpuOptions`]).
    pub fn has_ledger(&self) -> bool {
        self.keeps.ledger
    }

    /// Whether the run places the impulses of force jumps inside the step (the scene's
    /// `jump_impulses`).
    pub fn places_jumps(&self) -> bool {
        self.keeps.jumps
    }

    /// The name of the step's shader module (`Composition::variant_name`).
    pub fn variant_name(&self) -> String {
        self.kind
            .variant_name(self.keeps, !self.mirrors.is_empty(), self.state.far())
    }

    /// The step's kernels this engine built pipelines for (entry points of the step
    /// variant, and the re-sort's `permute`; the moving-wall kernels only where walls
    /// move), in recording order.
    pub fn kernel_names(&self) -> Vec<String> {
        let b = &self.bound;
        [
            Some(&b.kick_drift),
            Some(&b.collect_kick_drift),
            b.wall_move.as_ref(),
            Some(&b.decide),
            Some(&b.decide_lean),
            Some(&b.gather),
            Some(&b.count_neighbours),
            Some(&b.neighbours),
            Some(&b.commit),
            Some(&b.remap),
            Some(&b.copy_back_history),
            Some(&b.force),
            b.wall_servo.as_ref(),
            Some(&b.collect),
            Some(&b.kick),
        ]
        .into_iter()
        .flatten()
        .map(|p| p.kernel.name.clone())
        .flat_map(|name| {
            // the re-sort's kernel (its own module) once the new lists are known to fit
            let permute = (name == "commit").then(|| "permute".to_string());
            std::iter::once(name).chain(permute)
        })
        .collect()
    }

    /// The fields of the particle state, in buffer order (`gpu::state`).
    pub fn state_fields(&self) -> Vec<&'static str> {
        self.state.layout.names()
    }

    /// The fields of a list entry (`gpu::records`) with their bytes, in buffer order: the
    /// entries buffer (`A.entries`, or its pages `A.entries[p]`) holds this many bytes per
    /// entry of capacity.
    pub fn entry_fields(&self) -> Vec<(&'static str, u64)> {
        let l = &self.state.entry_layout;
        l.fields
            .iter()
            .map(|f| (f.name, 4 * f.kind.words()))
            .collect()
    }

    /// (kernel, storage buffers it binds) of every kernel built for the step, the most
    /// first: wgpu limits them per shader stage (WebGPU's default: 8).
    pub fn storage_bindings(&self) -> Vec<(String, u32)> {
        let mut v: Vec<(String, u32)> = self
            .program
            .kernels
            .values()
            .map(|k| (k.name.clone(), k.storage_buffers))
            .collect();
        v.sort_by_key(|(name, b)| (std::cmp::Reverse(*b), name.clone()));
        v
    }

    /// The step variant this scene runs (see [`Self::variant_name`]).
    pub fn kind(&self) -> &Composition {
        &self.kind
    }

    /// Every device buffer allocated for the run, as (name, bytes), in allocation order:
    /// the grid sort's index buffers (`grid.*`; its internal scan and large-cell scratch,
    /// a few bytes per cell / 32 particles, are not listed), the particle state (`A.*`),
    /// the lists a rebuild builds (`B.*`), the uniform step parameters, the pair table,
    /// walls, the per-step scratch, the re-sort's scratch (`permute.scratch`) and the
    /// quiet batches' copies (`quiet.*`). Angular buffers (`A.omega`, `A.alpha`,
    /// `A.wpred`) appear only when the scene rotates.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        self.buffers.clone()
    }

    /// Total bytes of [`Self::buffers`].
    pub fn buffer_bytes(&self) -> u64 {
        self.buffers.iter().map(|(_, b)| b).sum()
    }

    /// What each pass of a step binds, for the estimate of the bytes a step moves
    /// (`gpu::traffic`, where the counting is explained): the passes of every step in
    /// recording order (`collect_kick_drift`, the wall kernels where walls move, `decide`
    /// or `decide_lean` ([`RebuildChain`]), the mirror copies, `force`), then those of a
    /// rebuild (`decide` where the steps record `decide_lean`, the cell sort's as `grid.*`,
    /// `gather`, `count_neighbours`, the lists' scans as `lists.*`, `neighbours`, `commit`,
    /// the re-sort's `permute *`, `remap`, `copy_back_history`).
    pub fn traffic(&self) -> Vec<PassTraffic> {
        let b = &self.bound;
        let pass = |p: &Pass, when| PassTraffic::new(p.kernel.name.clone(), when, p.bound.clone());
        let mut out = vec![pass(&b.collect_kick_drift, When::Step)];
        out.extend(b.wall_move.as_ref().map(|p| pass(p, When::Step)));
        let on_demand = self.rebuild_chain == RebuildChain::OnDemand;
        out.push(pass(
            if on_demand { &b.decide_lean } else { &b.decide },
            When::Step,
        ));
        if !self.mirrors.is_empty() {
            out.push(PassTraffic::new(
                "mirror copies",
                When::Step,
                self.mirrors.copy_traffic(),
            ));
        }
        out.push(pass(&b.force, When::Step));
        out.extend(b.wall_servo.as_ref().map(|p| pass(p, When::Step)));
        if on_demand {
            out.push(pass(&b.decide, When::Rebuild));
        }
        for (name, mut bound) in self.grid.traffic(&self.state.state[0]) {
            // the sort reads the state's first field, the cells
            for (global, bytes) in &mut bound {
                if global == "cells" {
                    *bytes = self.state.layout.field_bytes();
                }
            }
            out.push(PassTraffic::new(
                format!("grid.{name}"),
                When::Rebuild,
                bound,
            ));
        }
        if !self.mirrors.is_empty() {
            out.push(pass(&b.gather, When::Rebuild));
        }
        out.push(pass(&b.count_neighbours, When::Rebuild));
        for scan in &self.scans {
            for (name, bound) in scan.traffic() {
                out.push(PassTraffic::new(
                    format!("lists.{name}"),
                    When::Rebuild,
                    bound,
                ));
            }
        }
        out.push(pass(&b.neighbours, When::Rebuild));
        out.push(pass(&b.commit, When::Rebuild));
        for (name, bound) in self.permutation.traffic() {
            out.push(PassTraffic::new(name, When::Rebuild, bound));
        }
        for p in [&b.remap, &b.copy_back_history] {
            out.push(pass(p, When::Rebuild));
        }
        out
    }

    /// Runs `steps` steps with a GPU timestamp after every pass (all windows'
    /// dispatches of it) and returns the device time each pass took: a real run's, its
    /// rebuilds where they fall. An error where the adapter gives no timestamps inside
    /// compute passes (`gpu::timestamps::FEATURES`). On the software adapter, quiet
    /// batches that were rolled back count too (their device time was spent).
    pub fn profile(&mut self, steps: u64) -> Result<PassProfile, PowderError> {
        if steps == 0 {
            return Err(
                crate::ParamError::new("profile-steps", "profile at least one step").into(),
            );
        }
        let before = self.rebuilds()?;
        self.clock = Some(PassClock::new(&self.ctx)?);
        let t = std::time::Instant::now();
        let ran = self.run_steps(steps);
        let wall_seconds = t.elapsed().as_secs_f64();
        let clock = self.clock.take();
        ran?;
        let clock = clock.expect("the clock runs until here");
        if clock.overflowed() {
            return Err(PowderError::Run(format!(
                "a batch of the pass profile wrote more than {} timestamps",
                wgpu::QUERY_SET_MAX_QUERIES
            )));
        }
        Ok(PassProfile {
            steps,
            rebuilds: self.rebuilds()? - before,
            wall_seconds,
            passes: clock
                .totals()
                .into_iter()
                .map(|(name, s)| (name.to_string(), s))
                .collect(),
        })
    }
}
