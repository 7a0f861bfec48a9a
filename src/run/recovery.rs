//! The copy of the state a failing chunk is stepped again from: taken before every chunk
//! where a copy is cheap, less often where it is not (a GPU's whole state read back), the
//! chunk's start then rebuilt by stepping on from the copy (a run's bits do not depend on
//! where its steps are cut).

use super::*;
use std::time::{Duration, Instant};

/// The largest share of the stepping time the copies may take where the run chooses how
/// often to copy (`RunOptions::copy_every` `None`).
const COPY_SHARE: f64 = 0.05;

/// The last copy of the state, and when the next one is due.
pub(super) struct RecoveryCopy<S: Simulation> {
    saved: Option<S::Saved>,
    /// The step the copy holds.
    step: u64,
    /// How long the last copy took.
    cost: Duration,
    /// The stepping since it.
    since: Duration,
    every: Option<u64>,
}

impl<S: Simulation> RecoveryCopy<S> {
    /// No copy yet: the first chunk takes one; the next ones every `every` steps (`None`:
    /// by their cost).
    pub(super) fn new(every: Option<u64>) -> Self {
        Self {
            saved: None,
            step: 0,
            cost: Duration::ZERO,
            since: Duration::ZERO,
            every,
        }
    }

    fn copy(&mut self, engine: &S) -> Result<(), PowderError> {
        // (the old copy goes first: never two of a large state at once)
        self.saved = None;
        let started = Instant::now();
        self.saved = Some(engine.save()?);
        self.cost = started.elapsed();
        self.since = Duration::ZERO;
        self.step = engine.steps();
        Ok(())
    }

    /// Before a chunk: a new copy where one is due (the first always).
    pub(super) fn refresh(&mut self, engine: &S) -> Result<(), PowderError> {
        let now = engine.steps();
        let due = match self.every {
            Some(n) => now >= self.step.saturating_add(n),
            None => self.since.as_secs_f64() * COPY_SHARE >= self.cost.as_secs_f64(),
        };
        if self.saved.is_none() || (due && now != self.step) {
            self.copy(engine)?;
        }
        Ok(())
    }

    /// Counts a chunk's stepping time towards the next copy.
    pub(super) fn stepped(&mut self, took: Duration) {
        self.since += took;
    }

    /// Returns the engine to step `at` (at or after the copy's): the copy restored and
    /// stepped on. Once: the copy goes with it (the run stops after).
    pub(super) fn restore_to(&mut self, engine: &mut S, at: u64) -> Result<(), PowderError> {
        let saved = self.saved.take().ok_or_else(|| {
            PowderError::Run("the state copy to step again from was used already".into())
        })?;
        engine.restore(saved)?;
        engine.run_steps(at.saturating_sub(self.step))
    }
}
