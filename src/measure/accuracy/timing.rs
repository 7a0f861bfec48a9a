//! Timing a case: short runs repeated until their mean is above the clock's noise.

use super::*;

/// A run shorter than this is repeated (up to [`MAX_REPEATS`] times) and its mean wall time
/// reported, so that millisecond runs are not timer and scheduler noise, s.
pub const MIN_TIMING: f64 = 0.2;

/// Most repetitions of one short run.
pub const MAX_REPEATS: u32 = 50;

/// Runs `f` once, then again until [`MIN_TIMING`] has passed (at most [`MAX_REPEATS`]
/// times); the result of the first run and the mean wall time per run.
pub(super) fn timed<T>(
    mut f: impl FnMut() -> Result<T, PowderError>,
) -> Result<(T, f64), PowderError> {
    let t0 = Instant::now();
    let first = f()?;
    let mut runs = 1;
    while t0.elapsed().as_secs_f64() < MIN_TIMING && runs < MAX_REPEATS {
        f()?;
        runs += 1;
    }
    Ok((first, t0.elapsed().as_secs_f64() / runs as f64))
}

/// Builds an engine with `make` and steps it with `step`; while less than [`MIN_TIMING`]
/// of stepping has passed, does it again with a fresh engine (at most [`MAX_REPEATS`]
/// times). Returns the first engine, the set-up time of the first and the mean stepping time.
pub(super) fn repeat_stepping<E>(
    mut make: impl FnMut() -> Result<E, PowderError>,
    mut step: impl FnMut(&mut E) -> Result<(), PowderError>,
) -> Result<(E, f64, f64), PowderError> {
    let t0 = Instant::now();
    let mut first = make()?;
    let setup = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    step(&mut first)?;
    let mut stepping = t1.elapsed().as_secs_f64();
    let mut runs = 1;
    while stepping < MIN_TIMING && runs < MAX_REPEATS {
        let mut again = make()?;
        let t1 = Instant::now();
        step(&mut again)?;
        stepping += t1.elapsed().as_secs_f64();
        runs += 1;
    }
    Ok((first, setup, stepping / runs as f64))
}
