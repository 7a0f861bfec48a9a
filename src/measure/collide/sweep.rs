//! Sweeps over impact velocities: the velocity list a user gives, and one collision each.

use super::*;

/// The most collisions a sweep runs.
pub const MAX_SWEEP: usize = 1_000_000;

/// Velocities of a sweep `FROM:TO:N`, linear or logarithmic.
pub fn sweep_velocities(text: &str, log: bool) -> Result<Vec<f64>, PowderError> {
    let bad = |why: &str| {
        PowderError::Param(crate::error::ParamError::new(
            "sweep-velocity",
            format!("`{text}` {why}; expected FROM:TO:N, e.g. 0.01:1:20"),
        ))
    };
    let parts: Vec<&str> = text.split(':').collect();
    if parts.len() != 3 {
        return Err(bad("does not have three fields"));
    }
    let from: f64 = parts[0]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable FROM"))?;
    let to: f64 = parts[1]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable TO"))?;
    let n: usize = parts[2]
        .trim()
        .parse()
        .map_err(|_| bad("has an unreadable N"))?;
    if !(from > 0.0 && to > 0.0 && from.is_finite() && to.is_finite()) {
        return Err(bad("needs positive finite velocities"));
    }
    if n == 0 {
        return Err(bad("needs N >= 1"));
    }
    if n > MAX_SWEEP {
        return Err(bad(&format!(
            "asks for {n} collisions, more than the {MAX_SWEEP} a sweep runs"
        )));
    }
    if n == 1 {
        return Ok(vec![from]);
    }
    Ok((0..n)
        .map(|k| {
            let t = k as f64 / (n - 1) as f64;
            if log {
                from * (to / from).powf(t)
            } else {
                from + (to - from) * t
            }
        })
        .collect())
}

/// Runs one collision per velocity on `backend`; results in input order. The CPU
/// backend spreads them over the cores; the GPU runs them one after another.
pub fn sweep_on(
    spec: &CollideSpec,
    velocities: &[f64],
    backend: Backend,
) -> Result<Vec<CollideResult>, PowderError> {
    if backend == Backend::Gpu {
        return velocities
            .iter()
            .map(|&velocity| {
                collide_on(
                    &CollideSpec {
                        velocity,
                        ..spec.clone()
                    },
                    backend,
                )
            })
            .collect();
    }
    sweep(spec, velocities)
}

/// Runs one collision per velocity, spread over the available cores; results in input order.
pub fn sweep(spec: &CollideSpec, velocities: &[f64]) -> Result<Vec<CollideResult>, PowderError> {
    if velocities.is_empty() {
        return Ok(Vec::new());
    }
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(velocities.len().max(1));
    let mut slots: Vec<Option<Result<CollideResult, PowderError>>> =
        (0..velocities.len()).map(|_| None).collect();
    std::thread::scope(|s| {
        for (t, chunk) in slots
            .chunks_mut(velocities.len().div_ceil(threads))
            .enumerate()
        {
            let base = t * velocities.len().div_ceil(threads);
            s.spawn(move || {
                for (k, slot) in chunk.iter_mut().enumerate() {
                    let one = CollideSpec {
                        velocity: velocities[base + k],
                        ..spec.clone()
                    };
                    *slot = Some(collide(&one));
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|r| r.expect("every slot is filled"))
        .collect()
}
