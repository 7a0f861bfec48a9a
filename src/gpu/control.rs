//! The step's control words (`control` in `shaders/step/shared.wgsl`), named once for the
//! host and the kernels: the monitor, zeroed before each batch and read back after it,
//! then the Verlet skin state, which persists across batches.

use crate::gpu::layout::wgsl_consts;

wgsl_consts! {
    /// The control words, by index.
    pub CONTROL_WORDS: u32 = {
        /// The longest list seen (a particle's, walls included, or its `lower` list).
        CONTROL_LONGEST_LIST = 0,
        /// 1 when a rebuild found a particle's neighbours beyond its window's bindings.
        CONTROL_BEYOND_WINDOW = 1,
        /// The persistent id + 1 of a particle with a non-finite acceleration.
        CONTROL_NON_FINITE = 2,
        /// Engaged contacts a rebuild dropped (`ledger.wgsl`).
        CONTROL_DROPPED = 3,
        /// The largest overlap over a12 of any contact (f32 bits, which order as the
        /// values when non-negative: `atomicMax`).
        CONTROL_PEAK_OVERLAP = 4,
        /// The persistent id + 1 of a particle with a contact beyond
        /// `MONITOR_MAX_OVERLAP_RATIO`.
        CONTROL_OVERLAP_PARTICLE = 5,
        /// The persistent id + 1 of a particle whose centre left the domain box.
        CONTROL_ESCAPED_PARTICLE = 6,
        /// Why the batch halted: 0, or one of [`HALTS`].
        CONTROL_HALT = 7,
        /// The largest displacement since the last rebuild at the batch's end (f32 bits;
        /// `collect`), for the host's forecast of the next rebuild (`gpu::quiet`).
        CONTROL_DISPLACEMENT = 8,
        /// Steps since the batch's last rebuild (0 on a rebuild, +1 on any other step).
        CONTROL_STEPS_SINCE_REBUILD = 9,
        /// Steps begun before any halt (`decide`, `decide_lean`).
        CONTROL_STEPS_BEGUN = 10,
        /// The list entries a halted rebuild needed.
        CONTROL_ENTRIES_NEEDED = 11,
        /// 1 once some particle has moved more than skin/2 since the last rebuild (set
        /// by `kick_drift` where it happens).
        SKIN_MOVED = 12,
        /// 1 when this step rebuilds (`decide`).
        SKIN_REBUILD = 13,
        /// Rebuilds so far.
        SKIN_REBUILDS = 14,
        /// Unused: the control words end here.
        CONTROL_END = 16,
    }
}

wgsl_consts! {
    /// Why a batch halted ([`CONTROL_HALT`]).
    pub HALTS: u32 = {
        /// A rebuild's new lists did not fit (`commit`).
        HALT_GROW = 1,
        /// A rebuild is due in a step recorded without one (`decide_lean`).
        HALT_REBUILD = 2,
    }
}

wgsl_consts! {
    /// The run monitor's limits the kernels apply.
    pub MONITOR_LIMITS: f32 = {
        /// The run loop's [`MAX_OVERLAP_RATIO`](crate::run::MAX_OVERLAP_RATIO).
        MONITOR_MAX_OVERLAP_RATIO = crate::run::MAX_OVERLAP_RATIO as f32,
    }
}

/// Bytes of the monitor, the part of `control` zeroed before each batch.
pub const MONITOR_BYTES: u64 = 4 * SKIN_MOVED as u64;

/// Where the Verlet skin state follows the monitor.
pub const SKIN_OFFSET: u64 = MONITOR_BYTES;

/// Bytes of `control`.
pub const CONTROL_BYTES: u64 = 4 * CONTROL_END as u64;
