//! Windows: the particles cut into ranges of `len` (a power of two) in sorted order,
//! every per-particle array and every record array blocked by window, so one window's
//! data (and its neighbours') is one contiguous range of each buffer — what a binding
//! over part of a buffer needs (`docs/gpu_rebuild.md`, *Windows*). A record index carries
//! its window in the high bits (`(w << rec_shift) | local`), so a list entry is found
//! without a division. One window (the default wherever the arrays fit one binding) is the
//! plain layout: each array one block.

use crate::error::PowderError;
use crate::gpu::kernel::{storage_buffer, uniform_buffer, Kernel, Part};
use crate::gpu::pages::Pages;
use crate::gpu::state::{particle_stride, STRIDE_ALIGN};

crate::gpu::layout::wgsl_struct! {
/// A dispatch's window (the uniform `win`).
#[wgsl("WindowParams")]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WindowParams {
    /// Its first particle.
    pub first: u32,
    /// The first window its bindings of blocked arrays start at ([`Windows::bound`]).
    pub bound: u32,
    /// The window.
    pub index: u32,
    /// The first window of the lists' entries' binding ([`Pages::params`]).
    pub rec_base: u32,
    /// The end of the windows that binding holds.
    pub rec_end: u32,
    /// The first window of the other page's binding (`entries_x`; several pages only).
    pub rec_other: u32,
    /// The particle state's [`Pages::params`] likewise (`state`, `motion`; `state_x`).
    pub st_base: u32,
    /// The end of the windows the state's binding holds.
    pub st_end: u32,
    /// The first window of `state_x`'s binding.
    pub st_other: u32,
    _pad: crate::gpu::layout::Pad<3>,
}
}

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

/// Whether `len` particles can be a window (a power of two from [`MIN_WINDOW`] to 2^30),
/// else why not.
pub fn valid_len(len: u64) -> Result<(), String> {
    if !len.is_power_of_two() || !(MIN_WINDOW..=1 << 30).contains(&len) {
        return Err(format!(
            "a window holds a power of two of particles from {MIN_WINDOW} to 2^30, not {len}"
        ));
    }
    Ok(())
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
        valid_len(len).map_err(PowderError::Run)?;
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

    /// The windows for `n` particles whose blocked arrays take at most `per_particle`
    /// bytes a particle each: one where they all fit `limit` bytes whole (a binding),
    /// else the largest whose parts (a window and its two neighbours) fit, at least
    /// [`MIN_WINDOW`] (where even those do not fit, the buffers are refused by name).
    pub fn choose(n: u64, per_particle: u64, limit: u64) -> Self {
        if n * per_particle <= limit {
            return Self::one(n);
        }
        let most = limit / (3 * per_particle.max(1));
        let len = match most {
            0 => MIN_WINDOW,
            m => (1u64 << (63 - m.leading_zeros())).clamp(MIN_WINDOW, 1 << 30),
        };
        Self::of(n, len).unwrap_or_else(|_| Self::one(n))
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

    /// The first window the bindings of window w's dispatches start at: they cover it
    /// and the next two (or all windows where there are fewer), so w and its neighbours.
    pub fn bound(&self, w: u64) -> u64 {
        w.saturating_sub(1).min(self.count.saturating_sub(3))
    }

    /// Windows a binding covers.
    pub fn covered(&self) -> u64 {
        self.count.min(3)
    }

    /// (offset, size) in bytes of the part of a blocked buffer with `block` bytes a window
    /// that window w's dispatches bind.
    pub fn part(&self, block: u64, w: u64) -> (u64, u64) {
        (self.bound(w) * block, self.covered() * block)
    }

    /// The uniform of window w's dispatches (`win` in common.wgsl), the lists' entries
    /// and the particle state in `pages`.
    pub fn window_params(&self, w: u64, pages: &Pages, state_pages: &Pages) -> WindowParams {
        let [rec_base, rec_end, rec_other] = pages.params(w, self.bound(w), self.count);
        let [st_base, st_end, st_other] = state_pages.params(w, self.bound(w), self.count);
        WindowParams {
            first: (w * self.len) as u32,
            bound: self.bound(w) as u32,
            index: w as u32,
            rec_base,
            rec_end,
            rec_other,
            st_base,
            st_end,
            st_other,
            _pad: crate::gpu::layout::Pad::ZERO,
        }
    }

    /// The WGSL `vec4<u32>` of `GridParams::window`: shift, len, rec_shift and the
    /// `state` buffer's fields (for the grid sort's reads of the cells).
    pub fn params(&self, state_fields: u32) -> [u32; 4] {
        [self.shift, self.len as u32, self.rec_shift, state_fields]
    }
}

/// The blocked buffers' bytes a window, by the name the kernels bind them by.
pub type Blocks<'a> = [(&'a str, u64)];

/// A buffer bound page by page (`gpu::pages`): each window's dispatches bind its page
/// whole under `name`, and the other page ([`Pages::other`]) under `other` where the
/// kernel declares it. With one page the buffer is bound as any other (`other`: a spare).
pub struct Paged<'a> {
    /// The name the kernels bind it by.
    pub name: &'a str,
    /// Its pages (one buffer with one page).
    pub pages: &'a [wgpu::Buffer],
    /// How it is cut.
    pub layout: Pages,
    /// The binding of the other page, where the kernels read it.
    pub other: Option<&'a str>,
}

/// What binds kernels window by window: the windows and one `win` uniform each.
pub struct WindowBindings {
    /// The windows.
    pub windows: Windows,
    /// The pages of the lists' entries.
    pub pages: Pages,
    /// The pages of the particle state (`state`, `motion`).
    pub state_pages: Pages,
    /// Window w's [`WindowParams`].
    pub uniforms: Vec<wgpu::Buffer>,
    /// Bound as the other page of a buffer in one page (never read).
    spare: wgpu::Buffer,
}

impl WindowBindings {
    /// The uniforms of `windows`, the lists' entries in `pages` and the state in
    /// `state_pages`.
    pub fn new(device: &wgpu::Device, windows: Windows, pages: Pages, state_pages: Pages) -> Self {
        let uniforms = (0..windows.count)
            .map(|w| {
                let params = windows.window_params(w, &pages, &state_pages);
                uniform_buffer(device, "window", bytemuck::bytes_of(&params))
            })
            .collect();
        Self {
            windows,
            pages,
            state_pages,
            uniforms,
            spare: storage_buffer(device, "spare page", 16),
        }
    }

    /// What window w's dispatches bind of a blocked `buffer` of `block` bytes a window:
    /// the window and its neighbours, or the whole buffer with one window.
    pub fn part<'a>(&self, buffer: &'a wgpu::Buffer, block: u64, w: u64) -> Part<'a> {
        if self.windows.count == 1 {
            return Part::whole(buffer);
        }
        let (offset, size) = self.windows.part(block, w);
        Part {
            buffer,
            offset,
            size: Some(size),
        }
    }

    /// The bind groups of `kernel`: one a window where it binds `win` (each blocked
    /// buffer, named in `blocks` with its bytes a window, bound over the window and its
    /// neighbours; with one window, whole), else one binding everything whole. The
    /// buffers in `paged` are bound page by page where they are in several ([`Paged`]).
    pub fn groups(
        &self,
        device: &wgpu::Device,
        kernel: &Kernel,
        (buffers, blocks): (&[(&str, &wgpu::Buffer)], &Blocks),
        textures: &[(&str, &wgpu::TextureView)],
        paged: &[Paged],
    ) -> Result<Vec<wgpu::BindGroup>, PowderError> {
        let in_pages: Vec<&Paged> = paged
            .iter()
            .filter(|p| p.layout.paged() && kernel.uses(p.name))
            .collect();
        if !kernel.uses("win") {
            if let Some(p) = in_pages.first() {
                return Err(PowderError::Run(format!(
                    "kernel `{}` binds `{}` whole, which is in {} pages",
                    kernel.name, p.name, p.layout.count
                )));
            }
            return Ok(vec![kernel.bind_with_textures(device, buffers, textures)?]);
        }
        (0..self.windows.count)
            .map(|w| {
                let mut parts: Vec<(&str, Part)> = buffers
                    .iter()
                    .map(|&(name, buffer)| {
                        let part = match blocks.iter().find(|(n, _)| *n == name) {
                            Some(&(_, block)) => self.part(buffer, block, w),
                            None => Part::whole(buffer),
                        };
                        (name, part)
                    })
                    .collect();
                for p in paged {
                    let other = p.other.filter(|&x| kernel.uses(x));
                    if !p.layout.paged() {
                        parts.extend(other.map(|x| (x, Part::whole(&self.spare))));
                        continue;
                    }
                    let page = |i: u64| Part::whole(&p.pages[i as usize]);
                    parts.retain(|(name, _)| *name != p.name);
                    parts.push((p.name, page(p.layout.page_of(w))));
                    parts.extend(other.map(|x| (x, page(p.layout.other(w)))));
                }
                parts.push(("win", Part::whole(&self.uniforms[w as usize])));
                kernel.bind_parts(device, &parts, textures)
            })
            .collect()
    }

    /// Writes the windows' uniforms again for the lists' entries in `pages` (the lists
    /// grew).
    pub fn set_pages(&mut self, queue: &wgpu::Queue, pages: Pages) {
        self.pages = pages;
        for (w, uniform) in self.uniforms.iter().enumerate() {
            let params = self
                .windows
                .window_params(w as u64, &pages, &self.state_pages);
            queue.write_buffer(uniform, 0, bytemuck::bytes_of(&params));
        }
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
        assert!(Windows::of(1000, 48).is_err());
        assert!(Windows::of(1000, 32).is_err());
        // 2^k windows need k bits
        assert_eq!(Windows::of(1024, 64).unwrap().rec_shift, 28);
        assert_eq!(Windows::of(1025, 64).unwrap().rec_shift, 27);
        // each window's bindings cover it and its neighbours, three windows wide
        for i in 0..w.count {
            let b = w.bound(i);
            assert!(b + 3 <= w.count && b <= i.saturating_sub(1));
            assert!(i + 1 < b + 3 || i + 1 == w.count);
            assert_eq!(w.part(256, i), (b * 256, 3 * 256));
        }
        // chosen: one window where the arrays fit a binding, else parts that fit
        assert_eq!(Windows::choose(1000, 100, 100_000), Windows::one(1000));
        let c = Windows::choose(1000, 100, 99_999);
        assert_eq!((c.len, c.count), (256, 4));
        assert!(3 * c.len * 100 <= 99_999);
        assert_eq!(Windows::choose(1000, 100, 1000).len, MIN_WINDOW);
        let two = Windows::of(100, 64).unwrap();
        assert_eq!((two.count, two.bound(1), two.part(8, 1)), (2, 0, (0, 16)));
    }
}
