//! An estimate of the device memory a GPU step moves, from the resources each of its passes
//! binds ([`crate::gpu::GpuEngine::traffic`]; `powder bench` and `powder info SCENE` report
//! it): each pass is counted as touching each distinct buffer or texture it binds once,
//! whole — an upper bound for passes that read each element at most once, blind to caches.
//! Per step: the every-step passes plus the rebuild's times the rebuilds per step; the
//! passes that open and close a batch (`kick_drift`, the last `collect` and `kick`) stand
//! in for a `collect_kick_drift` each and are left out. More: `docs/performance.md`,
//! *`powder bench`*.

use serde::Serialize;

/// When a pass runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum When {
    /// Every step.
    Step,
    /// Only on a step that rebuilds the neighbour lists.
    Rebuild,
}

/// One pass of the step and what it binds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassTraffic {
    /// The kernel's entry point (`grid.*` for the cell sort's), or `mirror copies`.
    pub pass: String,
    /// Every step, or only on a rebuild.
    pub when: When,
    /// Sum of `bound`, bytes.
    pub bytes: u64,
    /// (WGSL global name, bytes) of every distinct resource the pass binds.
    pub bound: Vec<(String, u64)>,
}

impl PassTraffic {
    /// A pass with its bound resources; `bytes` is their sum.
    pub fn new(pass: impl Into<String>, when: When, bound: Vec<(String, u64)>) -> Self {
        Self {
            pass: pass.into(),
            when,
            bytes: bound.iter().map(|(_, b)| b).sum(),
            bound,
        }
    }
}

/// (global name, bytes) of the resources `bindings` names, in binding order, each distinct
/// resource once: `resources` are (global name, identity, bytes), the first of a name is
/// the one bound (as [`crate::gpu::kernel::Kernel::bind`] picks it), and a name bound to a
/// resource already counted (an alias) is skipped; names not in `resources` are ignored.
pub fn distinct_bound<K: PartialEq>(
    bindings: &[(String, u32)],
    resources: &[(&str, K, u64)],
) -> Vec<(String, u64)> {
    let mut seen: Vec<&K> = Vec::new();
    let mut out = Vec::new();
    for (name, _) in bindings {
        if let Some((_, id, bytes)) = resources.iter().find(|(n, _, _)| n == name) {
            if !seen.contains(&id) {
                seen.push(id);
                out.push((name.clone(), *bytes));
            }
        }
    }
    out
}

/// The estimate for a measured run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrafficEstimate {
    /// Bytes bound by the passes of every step, per particle.
    pub step_bytes_per_particle: f64,
    /// Bytes bound by the passes of a rebuild, per particle (on top of a step's).
    pub rebuild_bytes_per_particle: f64,
    /// Neighbour-list rebuilds per step in the measured steps.
    pub rebuilds_per_step: f64,
    /// `step_bytes_per_particle + rebuilds_per_step · rebuild_bytes_per_particle`: the
    /// estimate of bytes moved per particle-step (an upper bound; see the module).
    pub bytes_per_particle_step: f64,
    /// Every pass, in recording order.
    pub passes: Vec<PassTraffic>,
}

impl TrafficEstimate {
    /// The estimate for `particles` particles from the passes, with `rebuilds` rebuilds in
    /// `steps` steps.
    pub fn new(passes: Vec<PassTraffic>, particles: usize, rebuilds: u64, steps: u64) -> Self {
        let n = particles.max(1) as f64;
        let sum = |when: When| {
            passes
                .iter()
                .filter(|p| p.when == when)
                .map(|p| p.bytes)
                .sum::<u64>() as f64
                / n
        };
        let (step, rebuild) = (sum(When::Step), sum(When::Rebuild));
        let rebuilds_per_step = if steps == 0 {
            0.0
        } else {
            rebuilds as f64 / steps as f64
        };
        Self {
            step_bytes_per_particle: step,
            rebuild_bytes_per_particle: rebuild,
            rebuilds_per_step,
            bytes_per_particle_step: step + rebuilds_per_step * rebuild,
            passes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bindings(names: &[&str]) -> Vec<(String, u32)> {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.to_string(), i as u32))
            .collect()
    }

    #[test]
    fn aliases_count_once_and_unbound_names_are_ignored() {
        // identities: 1 = the counts (bound as plain and atomic), 2 = keys, 3 = unused
        let res = [
            ("cell_count", 1, 400),
            ("cell_count_atomic", 1, 400),
            ("keys", 2, 40),
            ("unused", 3, 1_000_000),
            ("keys", 9, 7), // a later entry of the same name is not the one bound
        ];
        let got = distinct_bound(
            &bindings(&["keys", "cell_count_atomic", "cell_count"]),
            &res,
        );
        assert_eq!(
            got,
            vec![
                ("keys".to_string(), 40),
                ("cell_count_atomic".to_string(), 400)
            ]
        );
        assert!(distinct_bound(&bindings(&["missing"]), &res).is_empty());
    }

    #[test]
    fn estimate_adds_rebuilds_per_step() {
        let pass = |name: &str, when, bytes| {
            PassTraffic::new(name, when, vec![("a".into(), bytes), ("b".into(), 100)])
        };
        let passes = vec![
            pass("force", When::Step, 900),
            pass("decide", When::Step, 0),
            pass("neighbours", When::Rebuild, 1900),
        ];
        assert_eq!(passes[0].bytes, 1000);
        // 10 particles: 1100 bytes a step, 2000 more on a rebuild; 1 rebuild in 4 steps
        let e = TrafficEstimate::new(passes.clone(), 10, 1, 4);
        assert_eq!(e.step_bytes_per_particle, 110.0);
        assert_eq!(e.rebuild_bytes_per_particle, 200.0);
        assert_eq!(e.rebuilds_per_step, 0.25);
        assert_eq!(e.bytes_per_particle_step, 160.0);
        assert_eq!(e.passes, passes);
        // no steps: no rebuild share (and no division by zero)
        let e = TrafficEstimate::new(passes, 10, 3, 0);
        assert_eq!(e.bytes_per_particle_step, 110.0);
    }
}
