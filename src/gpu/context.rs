//! The wgpu device the GPU engine runs on, opened on the adapter `POWDER_ADAPTER` chooses
//! ([`crate::gpu::adapter`]). The device is created with the adapter's own limits, not
//! wgpu's downlevel defaults, so storage buffers can be as large as the adapter allows; no
//! optional feature is requested (but a profile's timestamps), so the kernels stay
//! portable (core WGSL only).

use crate::gpu::adapter::{
    choose_adapter, enumerate_in_section, AdapterPreference, AdapterSummary,
};
use crate::gpu::section::{Section, SectionEnd};
use crate::PowderError;

/// An open wgpu device, its queue, and the adapter it came from (a clone shares them).
#[derive(Clone)]
pub struct GpuContext {
    /// The logical device, created with the adapter's own limits.
    pub device: wgpu::Device,
    /// The device's command queue.
    pub queue: wgpu::Queue,
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// What the adapter is and offers (for `powder info` and reports).
    pub summary: AdapterSummary,
    /// Last: the handles above drop inside the section [`Drop`] opens, then this ends it.
    section: SectionEnd,
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        // (the device idle first: a hung GPU must not hold up other threads' contexts)
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        self.section.0 = Some(Section::begin());
    }
}

/// The limits a device is opened with.
enum Limits {
    /// The adapter's own.
    Adapter,
    /// The adapter's, with the storage binding size capped (bytes).
    BindingCapped(u64),
    /// wgpu's defaults (WebGPU's).
    WebGpuDefault,
}

impl GpuContext {
    /// Whether the adapter is a software rasteriser (lavapipe, llvmpipe): the one switch
    /// for the paths that pay off only there.
    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// Opens the adapter chosen by `POWDER_ADAPTER` ([`crate::gpu::adapter`]).
    pub fn new() -> Result<Self, PowderError> {
        Self::with_preference(&AdapterPreference::from_env())
    }

    /// Opens the best adapter allowed by `pref`.
    pub fn with_preference(pref: &AdapterPreference) -> Result<Self, PowderError> {
        Self::open(pref, Limits::Adapter, false)
    }

    /// Opens the adapter chosen by `POWDER_ADAPTER` with the pass profile's timestamp
    /// features where it offers them (`gpu::timestamps`); other runs open without them.
    pub fn with_timestamps() -> Result<Self, PowderError> {
        Self::open(&AdapterPreference::from_env(), Limits::Adapter, true)
    }

    /// Opens the adapter chosen by `POWDER_ADAPTER` with its storage binding limit lowered
    /// to at most `bytes`: what a scene needs and does on a smaller GPU, tried on this one
    /// (the engine splits or refuses per-slot buffers against this limit).
    pub fn with_storage_binding_limit(bytes: u64) -> Result<Self, PowderError> {
        Self::open(
            &AdapterPreference::from_env(),
            Limits::BindingCapped(bytes),
            false,
        )
    }

    /// Opens the adapter chosen by `POWDER_ADAPTER` with wgpu's default limits (WebGPU's:
    /// 8 storage buffers a stage, 128 MiB a binding, 256 MiB a buffer), what a browser or
    /// the most modest backend gives.
    pub fn with_default_limits() -> Result<Self, PowderError> {
        Self::open(&AdapterPreference::from_env(), Limits::WebGpuDefault, false)
    }

    fn open(
        pref: &AdapterPreference,
        choice: Limits,
        timestamps: bool,
    ) -> Result<Self, PowderError> {
        let section = Section::begin();
        let adapter = choose_adapter(enumerate_in_section(), pref)?;
        let summary = AdapterSummary::of(&adapter);
        let mut limits = adapter.limits();
        match choice {
            Limits::Adapter => {}
            Limits::BindingCapped(b) => {
                limits.max_storage_buffer_binding_size =
                    limits.max_storage_buffer_binding_size.min(b);
            }
            Limits::WebGpuDefault => limits = wgpu::Limits::default(),
        }
        // only a profile asks for the timestamps: plain runs open devices without features
        // (why: docs/gpu_rebuild.md, *The second hardware run*)
        let features = match timestamps {
            true => adapter.features() & crate::gpu::timestamps::FEATURES,
            false => wgpu::Features::empty(),
        };
        let desc = wgpu::DeviceDescriptor {
            label: Some("powder"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| {
            PowderError::Run(format!(
                "cannot open a device on adapter {} ({}): {e}",
                summary.name, summary.backend
            ))
        })?;
        drop(section);
        Ok(Self {
            device,
            queue,
            adapter,
            summary,
            section: SectionEnd::default(),
        })
    }

    /// The limits the device was created with (the adapter's own).
    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// Largest storage binding, capped by the largest buffer.
    pub fn max_storage_binding(&self) -> u64 {
        let l = self.device.limits();
        l.max_storage_buffer_binding_size.min(l.max_buffer_size)
    }

    /// An error naming `what` where `count` items of `per_item` bytes exceed one storage
    /// binding, with how many would fit.
    pub fn check_binding(
        &self,
        what: &str,
        count: u64,
        per_item: u64,
        unit: &str,
    ) -> Result<(), PowderError> {
        let limit = self.max_storage_binding();
        let bytes = count * per_item;
        if bytes > limit {
            return Err(PowderError::Run(format!(
                "{what}: {count} {unit} need {bytes} bytes ({per_item} bytes each), over the \
                 adapter's storage binding limit of {limit} bytes ({} MiB, {}); at most {} {unit} \
                 fit",
                limit >> 20,
                self.summary.name,
                limit / per_item
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Contexts opened, cloned and dropped on several threads at once (where an adapter
    /// exists): each open and each drop takes the section, none deadlocks.
    #[test]
    fn contexts_open_and_drop_on_several_threads() {
        let threads: Vec<_> = (0..3)
            .map(|_| {
                std::thread::spawn(|| {
                    for _ in 0..2 {
                        let Ok(ctx) = GpuContext::new() else { return };
                        let clone = ctx.clone();
                        drop(ctx);
                        assert!(clone.limits().max_buffer_size > 0);
                    }
                })
            })
            .collect();
        for t in threads {
            t.join().unwrap();
        }
    }
}
