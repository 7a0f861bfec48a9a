//! Per-pass GPU timestamps: while a profile runs, a timestamp after every kernel of the
//! recorded steps (all windows' dispatches of it), so a real run — windowed or not, its
//! rebuilds where they fall — says on the device which pass costs what.

use std::cell::{Cell, RefCell};

use crate::error::PowderError;
use crate::gpu::context::GpuContext;

/// Timestamps one submission holds at most (wgpu's largest query set).
const CAPACITY: u32 = wgpu::QUERY_SET_MAX_QUERIES;

/// The device features the clock needs: timestamps inside compute passes and between them.
pub const FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// Timestamps written while steps are recorded, read back with each batch's report.
pub struct PassClock {
    set: wgpu::QuerySet,
    /// Where the batch's timestamps are resolved to (read back with the batch's report).
    resolved: wgpu::Buffer,
    /// Per timestamp written: the pass whose time ends there, `None` where an interval
    /// starts (a pass begins: the gap since the last timestamp is nobody's).
    marks: RefCell<Vec<Option<&'static str>>>,
    /// Nanoseconds a tick.
    period: f64,
    /// Seconds on the device per pass so far, in the order first seen.
    totals: RefCell<Vec<(&'static str, f64)>>,
    /// Whether some submission had more timestamps than the query set holds (the rest of
    /// it went untimed).
    overflowed: Cell<bool>,
}

impl PassClock {
    /// A clock on `ctx`'s device (opened by `GpuContext::with_timestamps`), or an error
    /// saying what it lacks.
    pub fn new(ctx: &GpuContext) -> Result<Self, PowderError> {
        let missing = FEATURES - ctx.device.features();
        if !missing.is_empty() {
            return Err(PowderError::Run(format!(
                "the device on adapter {} ({}) has no GPU timestamps inside and between compute passes ({missing:?} missing; the adapter lacks them, or the context was not opened by GpuContext::with_timestamps): no pass profile",
                ctx.summary.name, ctx.summary.backend
            )));
        }
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass clock"),
            ty: wgpu::QueryType::Timestamp,
            count: CAPACITY,
        });
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass clock resolved"),
            size: CAPACITY as u64 * wgpu::QUERY_SIZE as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok(Self {
            set,
            resolved,
            marks: RefCell::new(Vec::new()),
            period: ctx.queue.get_timestamp_period() as f64,
            totals: RefCell::new(Vec::new()),
            overflowed: Cell::new(false),
        })
    }

    /// The next query index for `mark`, or `None` once the set is full.
    fn next(&self, mark: Option<&'static str>) -> Option<u32> {
        let mut marks = self.marks.borrow_mut();
        if marks.len() as u32 >= CAPACITY {
            self.overflowed.set(true);
            return None;
        }
        marks.push(mark);
        Some(marks.len() as u32 - 1)
    }

    /// A pass begins: a timestamp that starts an interval.
    pub fn start(&self, pass: &mut wgpu::ComputePass<'_>) {
        if let Some(i) = self.next(None) {
            pass.write_timestamp(&self.set, i);
        }
    }

    /// `name`'s dispatches were recorded: the time since the last timestamp is its.
    pub fn mark(&self, pass: &mut wgpu::ComputePass<'_>, name: &'static str) {
        if let Some(i) = self.next(Some(name)) {
            pass.write_timestamp(&self.set, i);
        }
    }

    /// As [`Self::start`], between passes (before work that records passes of its own).
    pub fn start_between(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(i) = self.next(None) {
            encoder.write_timestamp(&self.set, i);
        }
    }

    /// As [`Self::mark`], between passes.
    pub fn mark_between(&self, encoder: &mut wgpu::CommandEncoder, name: &'static str) {
        if let Some(i) = self.next(Some(name)) {
            encoder.write_timestamp(&self.set, i);
        }
    }

    /// Before a batch is submitted: its timestamps resolved into the buffer to read back
    /// with it, and that buffer's bytes (`None` when none were written).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) -> Option<(&wgpu::Buffer, u64)> {
        let n = self.marks.borrow().len() as u32;
        if n == 0 {
            return None;
        }
        encoder.resolve_query_set(&self.set, 0..n, &self.resolved, 0);
        Some((&self.resolved, n as u64 * wgpu::QUERY_SIZE as u64))
    }

    /// The batch's timestamps read back: each interval added to its pass.
    pub fn take(&self, bytes: &[u8]) {
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(bytes);
        let marks = std::mem::take(&mut *self.marks.borrow_mut());
        attribute(&marks, &ticks, self.period, &mut self.totals.borrow_mut());
    }

    /// Seconds on the device per pass since the clock started, in recording order.
    pub fn totals(&self) -> Vec<(&'static str, f64)> {
        self.totals.borrow().clone()
    }

    /// Whether some batch recorded more timestamps than one query set holds.
    pub fn overflowed(&self) -> bool {
        self.overflowed.get()
    }
}

/// Adds each interval between consecutive timestamps (`ticks`, `period` ns a tick) to the
/// pass its closing mark names; an interval that closes on a start (`None`) is nobody's. A
/// timestamp earlier than the one before (a driver may write them out of order across
/// passes) counts as no time.
fn attribute(
    marks: &[Option<&'static str>],
    ticks: &[u64],
    period: f64,
    totals: &mut Vec<(&'static str, f64)>,
) {
    for (i, mark) in marks.iter().enumerate().skip(1) {
        let Some(name) = mark else { continue };
        let (Some(&end), Some(&begin)) = (ticks.get(i), ticks.get(i - 1)) else {
            continue;
        };
        let seconds = end.saturating_sub(begin) as f64 * period * 1e-9;
        match totals.iter_mut().find(|(n, _)| n == name) {
            Some((_, total)) => *total += seconds,
            None => totals.push((name, seconds)),
        }
    }
}

/// What a pass profile measured ([`crate::gpu::GpuEngine::profile`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassProfile {
    /// Steps profiled.
    pub steps: u64,
    /// Neighbour-list rebuilds among them (the rebuild chain's passes run with no
    /// workgroups on the other steps).
    pub rebuilds: u64,
    /// Host wall-clock seconds of the profiled steps (the timestamps included).
    pub wall_seconds: f64,
    /// (pass, seconds on the device over the profiled steps), in recording order: each
    /// the time from the timestamp before its dispatches (all windows') to the one after.
    pub passes: Vec<(String, f64)>,
}

impl PassProfile {
    /// Seconds on the device a step, summed over the passes.
    pub fn device_seconds_per_step(&self) -> f64 {
        self.passes.iter().map(|(_, s)| s).sum::<f64>() / self.steps.max(1) as f64
    }

    /// One line: µs a step of each pass, and the device's share of the wall-clock time.
    pub fn summary(&self) -> String {
        let steps = self.steps.max(1) as f64;
        let parts: Vec<String> = self
            .passes
            .iter()
            .map(|(name, s)| format!("{name} {:.1}", s / steps * 1e6))
            .collect();
        format!(
            "passes (µs a step over {} steps, {} rebuilds; device {:.1} of {:.1} µs a step): {}",
            self.steps,
            self.rebuilds,
            self.device_seconds_per_step() * 1e6,
            self.wall_seconds / steps * 1e6,
            parts.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::attribute;

    /// Each interval goes to the pass whose mark closes it, summed over repeats; gaps
    /// before a pass's start are nobody's; a reversed pair counts as zero.
    #[test]
    fn intervals_go_to_the_mark_that_closes_them() {
        let marks = [
            None,
            Some("force"),
            Some("collect"),
            None,
            Some("force"),
            Some("kick"),
        ];
        let ticks = [100, 130, 150, 1000, 1010, 1005];
        let mut totals = Vec::new();
        attribute(&marks, &ticks, 2.0, &mut totals);
        assert_eq!(
            totals,
            vec![("force", 80e-9), ("collect", 40e-9), ("kick", 0.0)]
        );
        // a later batch adds to the same passes
        attribute(&marks[..2], &ticks[..2], 2.0, &mut totals);
        assert_eq!(totals[0], ("force", 140e-9));
    }
}
