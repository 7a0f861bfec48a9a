//! Windows: the particles cut into ranges of `len` (a power of two) in sorted order,
//! every per-particle array and every record array blocked by window, so one window's
//! data (and its neighbours') is one contiguous range of each buffer — what a binding
//! over part of a buffer needs (issue 15, increment 5c; docs/gpu_rebuild.md). A record
//! index carries its window in the high bits (`(w << rec_shift) | local`), so a list
//! entry or wall contact is found without a division. One window (the default wherever
//! the arrays fit one binding) lays everything out as before windows existed.

use crate::error::PowderError;
use crate::gpu::state::{particle_stride, STRIDE_ALIGN};

/// The fewest particles a window holds: every window's block of any array (4-byte records
/// included) is then a multiple of 256 bytes, as binding offsets want.
pub const MIN_WINDOW: u64 = 64;

/// How a run's particles are blocked into windows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Windows {
    /// Particles a window holds (elements from one field's block to the next).
    pub len: u64,
    /// Windows.
    pub count: u64,
    /// `k >> shift` is particle k's window (31 with one window: always 0).
    pub shift: u32,
    /// A record index's window is `r >> rec_shift` (31 with one window).
    pub rec_shift: u32,
}

impl Windows {
    /// One window holding all `n` particles: the unwindowed layout.
    pub fn one(n: u64) -> Self {
        Self {
            len: particle_stride(n).max(STRIDE_ALIGN),
            count: 1,
            shift: 31,
            rec_shift: 31,
        }
    }

    /// Windows of `len` particles (a power of two from [`MIN_WINDOW`] to 2^30) for `n`
    /// particles; one window where `len` holds them all.
    pub fn of(n: u64, len: u64) -> Result<Self, PowderError> {
        if !len.is_power_of_two() || !(MIN_WINDOW..=1 << 30).contains(&len) {
            return Err(PowderError::Run(format!(
                "a window holds a power of two of particles from {MIN_WINDOW} to 2^30, not {len}"
            )));
        }
        if len >= particle_stride(n) {
            return Ok(Self::one(n));
        }
        let count = n.div_ceil(len);
        // the bits a window index needs, above the record's local index
        let bits = 64 - (count - 1).leading_zeros();
        Ok(Self {
            len,
            count,
            shift: len.trailing_zeros(),
            rec_shift: 32 - bits,
        })
    }

    /// `(1 << shift) − 1`: a particle's index within its window.
    pub fn mask(&self) -> u64 {
        (1u64 << self.shift) - 1
    }

    /// The largest number of records one window's region may hold.
    pub fn max_records(&self) -> u64 {
        1u64 << self.rec_shift
    }

    /// Particle k's window and its index within.
    pub fn split(&self, k: u64) -> (u64, u64) {
        (k >> self.shift, k & self.mask())
    }

    /// Element of particle k in a blocked array of `fields` per-particle regions: region
    /// `f` of window w at `(w·fields + f)·len`.
    pub fn element(&self, fields: u64, f: u64, k: u64) -> u64 {
        let (w, i) = self.split(k);
        (w * fields + f) * self.len + i
    }

    /// The record index of local record `i` of window `w`.
    pub fn record(&self, w: u64, i: u64) -> u64 {
        (w << self.rec_shift) | i
    }

    /// A record index's window and local index.
    pub fn split_record(&self, r: u64) -> (u64, u64) {
        (r >> self.rec_shift, r & (self.max_records() - 1))
    }

    /// The record of particle k's contact with wall `wall` (per window wall-major: the
    /// window's particles for wall 0, then wall 1, ...; `wall_slot` in step.wgsl).
    pub fn wall_record(&self, k: u64, wall: u64) -> u64 {
        let (w, i) = self.split(k);
        self.record(w, wall * self.len + i)
    }

    /// The WGSL `vec4<u32>` of `GridParams::window`: shift, len, rec_shift and the
    /// `state` buffer's fields (for the grid sort's reads of the cells).
    pub fn params(&self, state_fields: u32) -> [u32; 4] {
        [self.shift, self.len as u32, self.rec_shift, state_fields]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_window_is_the_unwindowed_layout() {
        let w = Windows::one(1000);
        assert_eq!((w.len, w.count), (1008, 1));
        for k in [0, 1, 999] {
            assert_eq!(w.element(5, 3, k), 3 * 1008 + k);
            assert_eq!(w.wall_record(k, 2), 2 * 1008 + k);
        }
        assert_eq!(Windows::of(1000, 1024).unwrap(), w);
    }

    #[test]
    fn windows_block_every_array_and_encode_records() {
        let w = Windows::of(1000, 64).unwrap();
        assert_eq!((w.count, w.shift, w.rec_shift), (16, 6, 28));
        assert_eq!(w.split(130), (2, 2));
        // field 1 of particle 130 in a 3-field array: window 2's block, field 1
        assert_eq!(w.element(3, 1, 130), (2 * 3 + 1) * 64 + 2);
        assert_eq!(w.split_record(w.record(15, 77)), (15, 77));
        assert_eq!(w.wall_record(130, 1), (2 << 28) | 66);
        assert!(Windows::of(1000, 48).is_err());
        assert!(Windows::of(1000, 32).is_err());
        // 2^k windows need k bits
        assert_eq!(Windows::of(1024, 64).unwrap().rec_shift, 28);
        assert_eq!(Windows::of(1025, 64).unwrap().rec_shift, 27);
    }
}
