//! Where a measurement ran: the machine, the GPU adapter, the commit and the time, written
//! into every benchmark's JSON.

use crate::gpu::GpuContext;
use serde::Serialize;

/// The machine a measurement ran on.
#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    /// `model name` of /proc/cpuinfo (null where unreadable).
    pub cpu_model: Option<String>,
    /// `processor` entries of /proc/cpuinfo.
    pub logical_cpus: Option<usize>,
    /// Threads this process may use (`std::thread::available_parallelism`).
    pub available_parallelism: usize,
    /// `MemAvailable` at the start, bytes.
    pub memory_available: Option<u64>,
    /// The 1-minute load average at the start (/proc/loadavg): other work on a shared
    /// machine slows every timing down.
    pub load_average: Option<f64>,
    /// `std::env::consts::OS`.
    pub os: &'static str,
    /// `std::env::consts::ARCH`.
    pub arch: &'static str,
}

impl Machine {
    /// Reads /proc/cpuinfo and /proc/meminfo (Linux; null fields elsewhere).
    pub fn detect() -> Self {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").ok();
        let cpu_model = cpuinfo.as_deref().and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        });
        let logical_cpus = cpuinfo
            .as_deref()
            .map(|t| t.lines().filter(|l| l.starts_with("processor")).count())
            .filter(|&c| c > 0);
        Self {
            cpu_model,
            logical_cpus,
            available_parallelism: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            memory_available: crate::memory::available(),
            load_average: std::fs::read_to_string("/proc/loadavg")
                .ok()
                .and_then(|t| t.split_whitespace().next()?.parse().ok()),
            os: std::env::consts::OS,
            arch: std::env::consts::ARCH,
        }
    }
}

/// The GPU adapter a measurement ran on (from [`crate::gpu::AdapterSummary`]).
#[derive(Clone, Debug, Serialize)]
pub struct Adapter {
    /// E.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// `vulkan`, `metal`, `dx12` or `gl`.
    pub backend: String,
    /// `DiscreteGpu`, `IntegratedGpu`, `VirtualGpu`, `Cpu` (software) or `Other`.
    pub device_type: String,
    /// Driver name.
    pub driver: String,
    /// Driver version and details.
    pub driver_info: String,
    /// The limits the GPU engine cares about.
    pub limits: crate::gpu::LimitsSummary,
}

impl Adapter {
    /// The adapter of an open context.
    pub fn of(ctx: &GpuContext) -> Self {
        let s = &ctx.summary;
        Self {
            name: s.name.clone(),
            backend: s.backend.clone(),
            device_type: s.device_type.clone(),
            driver: s.driver.clone(),
            driver_info: s.driver_info.clone(),
            limits: s.limits.clone(),
        }
    }
}

/// Where a measurement comes from: powder's version, the source tree's commit, the date.
#[derive(Clone, Debug, Serialize)]
pub struct Provenance {
    /// The crate version.
    pub powder_version: &'static str,
    /// `git rev-parse HEAD` of the source tree this binary was built from, if it is still
    /// there and a git checkout (with `-dirty` when it has uncommitted changes).
    pub git_commit: Option<String>,
    /// UTC, ISO 8601.
    pub date: String,
    /// Where it ran.
    pub machine: Machine,
    /// The command line of the process that measured (its options decide the numbers).
    pub command: Vec<String>,
}

impl Provenance {
    /// Collects the version, commit, date and machine now.
    pub fn now() -> Self {
        Self {
            powder_version: env!("CARGO_PKG_VERSION"),
            git_commit: git_commit(),
            date: utc_now(),
            machine: Machine::detect(),
            command: std::env::args().collect(),
        }
    }
}

fn git_commit() -> Option<String> {
    let dir = env!("CARGO_MANIFEST_DIR");
    let run = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(dir)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let head = run(&["rev-parse", "HEAD"]).filter(|h| !h.is_empty())?;
    let dirty =
        run(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    Some(if dirty { format!("{head}-dirty") } else { head })
}

/// The current UTC time as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    utc_date(secs)
}

/// Seconds since the Unix epoch as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_date(secs: i64) -> String {
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // civil_from_days (H. Hinnant)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates_are_iso() {
        assert_eq!(utc_date(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_date(951_827_696), "2000-02-29T12:34:56Z");
        assert_eq!(utc_date(1_735_689_599), "2024-12-31T23:59:59Z");
        let d = utc_now();
        assert_eq!(d.len(), 20, "{d}");
        assert!(d.starts_with("20") && d.ends_with('Z'), "{d}");
    }
}
