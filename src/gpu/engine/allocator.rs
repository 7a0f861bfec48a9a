//! Creating the run's storage buffers within the adapter's limits (bound whole, by window
//! or in pages), with their names and sizes for the memory report.

use super::*;

/// Creates storage buffers and records their names and sizes (for [`GpuEngine::buffers`]).
/// A buffer that does not fit (bound whole: over the storage binding limit; bound a
/// window's part at a time: a part over it, or the buffer over the largest buffer) is not
/// created: a 4-byte stand-in takes its place and [`Allocator::check`] refuses.
pub(super) struct Allocator<'a> {
    pub(super) device: &'a wgpu::Device,
    pub(super) list: Vec<(String, u64)>,
    /// The largest binding a buffer may be, bytes.
    pub(super) limit: u64,
    /// The largest buffer, bytes.
    pub(super) max_buffer: u64,
    /// What does not fit, said for the user.
    pub(super) refused: Vec<String>,
}

impl<'a> Allocator<'a> {
    pub(super) fn new(device: &'a wgpu::Device, limit: u64) -> Self {
        Self {
            device,
            list: Vec::new(),
            limit: limit.min(4 * u32::MAX as u64),
            max_buffer: device.limits().max_buffer_size,
            refused: Vec::new(),
        }
    }

    /// A buffer bound whole.
    pub(super) fn buffer(&mut self, name: &str, bytes: u64) -> wgpu::Buffer {
        let fits = bytes <= self.limit;
        if !fits {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        }
        self.create(name, bytes, fits)
    }

    /// A buffer blocked by window, `part` bytes of it bound at a time (`gpu::window`).
    pub(super) fn blocked(&mut self, name: &str, bytes: u64, part: u64) -> wgpu::Buffer {
        if part > self.limit {
            self.refused.push(format!(
                "{part} bytes of `{name}` bound at a time (a window and its neighbours), over the adapter's storage binding limit of {} bytes",
                self.limit
            ));
        } else if bytes > self.max_buffer {
            self.refused.push(format!(
                "{bytes} bytes of `{name}`, over the adapter's largest buffer of {} bytes",
                self.max_buffer
            ));
        }
        let fits = part <= self.limit && bytes <= self.max_buffer;
        self.create(name, bytes, fits)
    }

    pub(super) fn create(&mut self, name: &str, bytes: u64, fits: bool) -> wgpu::Buffer {
        let b = storage_buffer(self.device, name, if fits { bytes } else { 4 });
        self.list
            .push((name.to_string(), if fits { b.size() } else { bytes }));
        b
    }

    /// An error naming the first buffer that does not fit, for `particles` particles.
    /// Call it before anything writes or binds the buffers.
    pub(super) fn check(&self, particles: usize) -> Result<(), PowderError> {
        match self.refused.first() {
            Some(what) => Err(PowderError::Run(format!(
                "{particles} particles need {what}"
            ))),
            None => Ok(()),
        }
    }
}

/// Writes `bytes` into `pages` one after the other (the bytes of the one buffer they
/// stand for).
pub(super) fn write_pages(queue: &wgpu::Queue, pages: &[wgpu::Buffer], bytes: &[u8]) {
    let mut at = 0;
    for page in pages {
        let end = (at + page.size() as usize).min(bytes.len());
        queue.write_buffer(page, 0, &bytes[at..end]);
        at = end;
    }
}

/// A storage buffer of `bytes` blocked by window, `block` bytes a window: bound whole with
/// one window, else a window and its neighbours at a time.
pub(super) fn blocked_buffer(
    alloc: &mut Allocator,
    windows: &Windows,
    (name, bytes): (&str, u64),
    block: u64,
) -> wgpu::Buffer {
    if windows.count == 1 {
        alloc.buffer(name, bytes)
    } else {
        alloc.blocked(name, bytes, windows.covered() * block)
    }
}

/// The buffers of `entries` list entries a window of `layout`: one blocked by window, or
/// one a page (bound whole).
pub(super) fn entry_buffers(
    alloc: &mut Allocator,
    (windows, pages): (&Windows, &Pages),
    layout: &RecordLayout,
    entries: u64,
) -> Vec<wgpu::Buffer> {
    let block = layout.block_bytes(entries);
    if !pages.paged() {
        let bytes = layout.windowed_bytes(entries, windows);
        return vec![blocked_buffer(alloc, windows, ("A.entries", bytes), block)];
    }
    (0..pages.count)
        .map(|p| {
            let (_, len) = pages.range(p, windows.count);
            alloc.buffer(&format!("A.entries[{p}]"), len * block)
        })
        .collect()
}
