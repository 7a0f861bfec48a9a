//! How many particles fit: a scene that asks for more than the machine's memory holds is
//! refused up front with the number that would fit, instead of failing half-way.

/// Bytes the CPU path needs per particle: the scene's particle list, the engine's state
/// and about six contacts with their history and ledger record.
pub const CPU_BYTES_PER_PARTICLE: u64 = 2048;

/// Memory available to this process now (`MemAvailable` of /proc/meminfo), bytes.
pub fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Checks that `n` particles of `per_particle` bytes fit in the available memory;
/// the error says how many would.
pub fn check_particles(n: u64, per_particle: u64, what: &str) -> Result<(), String> {
    let Some(avail) = available() else {
        return Ok(());
    };
    let need = n.saturating_mul(per_particle);
    if need > avail {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        return Err(format!(
            "{n} particles need about {:.1} GiB for {what}, but only {:.1} GiB of memory is available: at most {} particles fit",
            gib(need),
            gib(avail),
            avail / per_particle
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_counts_are_refused_with_what_fits() {
        if available().is_none() {
            return;
        }
        let err =
            check_particles(u64::MAX / 4096, CPU_BYTES_PER_PARTICLE, "the CPU engine").unwrap_err();
        assert!(
            err.contains("at most") && err.contains("particles fit"),
            "{err}"
        );
        assert!(check_particles(1000, CPU_BYTES_PER_PARTICLE, "the CPU engine").is_ok());
    }
}
