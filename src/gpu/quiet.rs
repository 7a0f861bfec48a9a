//! Quiet batches: batches of steps recorded without the per-step rebuild decision.
//!
//! A normal batch's steps ask the device whether to rebuild the neighbour lists (by default
//! `decide_lean`, one invocation a step that halts the batch where a rebuild is due; with
//! `RebuildChain::EveryStep`, `decide` and the rebuild's passes as indirect dispatches): a
//! fixed cost a step, large on a software adapter (`docs/design_log.md`, *Measurements
//! moved out of the code*). A quiet batch records only the drift, the mirror copies and the
//! forces, after copying what the steps change (the contacts' history into the lists a
//! rebuild builds, idle in a quiet batch; the rest into copies of its own). If the drift's
//! "moved more than skin/2" flag is still clear at the end, no step would have rebuilt and
//! the batch is kept, bitwise what a normal batch computes; otherwise the copies go back
//! and the batch runs again the normal way. Wrong guesses cost time, never results.
//!
//! Whether to try: [`Forecast`] extrapolates the largest displacement since the last
//! rebuild to the end of the next batch, with a margin of 1.5. The copies cost as much
//! memory as the particle state, so `Auto` uses quiet batches on software adapters only
//! ([`QuietBatches::on`]).

/// How a GPU run uses quiet batches (`GpuOptions::quiet`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuietBatches {
    /// Every batch checks each step (the rebuild decision on the device).
    Off,
    /// On a software adapter, a batch runs quiet when the forecast expects no rebuild in
    /// it; never on a GPU (the default).
    Auto,
    /// Every batch tries to run quiet (tests: every rollback path runs).
    Always,
}

impl QuietBatches {
    /// What the choice means with or without the software adapter's paths
    /// (`GpuOptions::software_paths`): `Auto` tries quiet batches only there, where they
    /// pay (above); on a GPU their copies of the state would cost memory for dispatches
    /// that launch no work.
    pub fn on(self, software: bool) -> Self {
        match self {
            Self::Auto if !software => Self::Off,
            mode => mode,
        }
    }
}

/// The margin on the linear extrapolation of the displacement (accelerating particles).
const MARGIN: f64 = 1.5;

/// Fewest steps since a rebuild that give a displacement rate.
const MIN_STEPS: u64 = 16;

/// The host's estimate of when the next rebuild comes.
#[derive(Clone, Debug)]
pub struct Forecast {
    /// Half the Verlet skin, m: a rebuild comes once some particle has moved farther.
    half_skin: f64,
    /// Steps since the last rebuild at the end of the last batch, when known.
    since: Option<u64>,
    /// The largest displacement since the last rebuild then, m.
    disp: f64,
    /// How fast that displacement grew (m a step), from the last batch that ended at least
    /// `MIN_STEPS` after its rebuild.
    rate: Option<f64>,
}

impl Forecast {
    /// A forecast for lists built with `skin` (m), just after a rebuild.
    pub fn new(skin: f64) -> Self {
        Self {
            half_skin: 0.5 * skin,
            since: Some(0),
            disp: 0.0,
            rate: None,
        }
    }

    /// Whether a batch of `batch` steps should run quiet.
    pub fn quiet(&self, batch: u64, mode: QuietBatches) -> bool {
        match mode {
            QuietBatches::Off => false,
            QuietBatches::Always => true,
            QuietBatches::Auto => match self.rate {
                Some(rate) if self.disp.is_finite() && rate.is_finite() => {
                    self.disp + MARGIN * rate * batch as f64 <= self.half_skin
                }
                _ => false,
            },
        }
    }

    /// After a batch of `batch` steps (quiet or normal) that ended `since_rebuild` steps
    /// after its last rebuild (`None`: it rebuilt nowhere) with the largest displacement
    /// `disp` (m).
    pub fn observe(&mut self, batch: u64, since_rebuild: Option<u64>, disp: f64) {
        let since = match since_rebuild {
            Some(s) => s,
            // (unknown before: at least this batch, which makes the rate an upper bound)
            None => self.since.unwrap_or(0) + batch,
        };
        self.since = Some(since);
        self.disp = disp;
        if since >= MIN_STEPS {
            self.rate = Some(disp / since as f64);
        }
    }

    /// After a restore: nothing known until a batch has run.
    pub fn forget(&mut self) {
        self.since = None;
        self.rate = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_quiet_forecast_extrapolates_the_displacement() {
        let mut f = Forecast::new(1e-4);
        // just rebuilt: no rate yet
        assert!(!f.quiet(64, QuietBatches::Auto));
        assert!(f.quiet(64, QuietBatches::Always));
        assert!(!f.quiet(64, QuietBatches::Off));
        // 1e-6 m in 64 steps: 64 more steps reach 1e-6 + 1.5·1e-6, far below 5e-5
        f.observe(64, None, 1e-6);
        assert!(f.quiet(64, QuietBatches::Auto));
        // 2e-5 m in 128 steps: 2e-5 + 1.5·1e-5 = 3.5e-5 <= 5e-5, quiet; 3.5e-5 in 192
        // steps: 3.5e-5 + 1.75e-5 > 5e-5, not
        f.observe(64, None, 2e-5);
        assert!(f.quiet(64, QuietBatches::Auto));
        f.observe(64, None, 3.5e-5);
        assert!(!f.quiet(64, QuietBatches::Auto));
        // a rebuild 40 steps before the batch's end with 4e-6 m since: 1e-7 m a step
        f.observe(64, Some(40), 4e-6);
        assert!(f.quiet(64, QuietBatches::Auto));
        assert!(!f.quiet(400, QuietBatches::Auto));
        // a rebuild at the batch's last step: the rate of before, 1e-7 m a step
        f.observe(64, Some(0), 0.0);
        assert!(f.quiet(64, QuietBatches::Auto));
        assert!(!f.quiet(400, QuietBatches::Auto));
        // a non-finite displacement (the monitor stops such a run) never runs quiet
        f.observe(64, None, f64::NAN);
        assert!(!f.quiet(1, QuietBatches::Auto));
        f.forget();
        assert!(!f.quiet(1, QuietBatches::Auto));
        // after a restore the first batch's steps bound the unknown age from below
        f.observe(64, None, 1e-6);
        assert!(f.quiet(64, QuietBatches::Auto));
    }
}
