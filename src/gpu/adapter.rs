//! Which adapter the GPU engine opens, and a summary of what an adapter offers (`powder
//! info`).
//!
//! Adapter choice (environment variable `POWDER_ADAPTER`):
//!
//! * `auto` (default, also when unset or empty): a real GPU when one is present —
//!   discrete, then integrated, then virtual, then unknown — and the software adapter
//!   (device type `Cpu`: Mesa lavapipe on Vulkan, llvmpipe on GL) otherwise;
//! * `software`: only adapters of device type `Cpu`;
//! * `hardware`: only adapters that are not of device type `Cpu`;
//! * anything else: adapters whose name contains the string, or whose backend it names
//!   (`vulkan`, `gl`, `metal`, `dx12`), ignoring case.
//!
//! Among equally ranked adapters, Vulkan is preferred over Metal, DX12 and GL (the same
//! device usually shows up both on Vulkan and on GL). Adapters without compute shaders are
//! never chosen.

use crate::gpu::section::Section;
use crate::PowderError;
use serde::Serialize;
use std::fmt;

/// Backends searched for adapters.
pub const BACKENDS: wgpu::Backends = wgpu::Backends::VULKAN
    .union(wgpu::Backends::METAL)
    .union(wgpu::Backends::DX12)
    .union(wgpu::Backends::GL);

/// The environment variable that overrides the adapter choice.
pub const ADAPTER_ENV: &str = "POWDER_ADAPTER";

/// What to install when no adapter exists at all.
pub const INSTALL_HINT: &str = "on Debian/Ubuntu install the software Vulkan driver: \
     apt-get install -y mesa-vulkan-drivers libvulkan1";

/// The limits the GPU engine cares about (a subset of [`wgpu::Limits`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct LimitsSummary {
    /// Largest storage-buffer binding, bytes.
    pub max_storage_buffer_binding_size: u64,
    /// Largest buffer, bytes.
    pub max_buffer_size: u64,
    /// Largest workgroup size along x, invocations.
    pub max_compute_workgroup_size_x: u32,
    /// Most invocations in one workgroup.
    pub max_compute_invocations_per_workgroup: u32,
    /// Most workgroups along one dispatch dimension.
    pub max_compute_workgroups_per_dimension: u32,
    /// Most storage buffers one shader stage may bind.
    pub max_storage_buffers_per_shader_stage: u32,
    /// Most bind groups one pipeline may use.
    pub max_bind_groups: u32,
}

impl From<&wgpu::Limits> for LimitsSummary {
    fn from(l: &wgpu::Limits) -> Self {
        Self {
            max_storage_buffer_binding_size: l.max_storage_buffer_binding_size,
            max_buffer_size: l.max_buffer_size,
            max_compute_workgroup_size_x: l.max_compute_workgroup_size_x,
            max_compute_invocations_per_workgroup: l.max_compute_invocations_per_workgroup,
            max_compute_workgroups_per_dimension: l.max_compute_workgroups_per_dimension,
            max_storage_buffers_per_shader_stage: l.max_storage_buffers_per_shader_stage,
            max_bind_groups: l.max_bind_groups,
        }
    }
}

/// What an adapter is and offers, for people (`Display`) and scripts (`Serialize`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct AdapterSummary {
    /// Adapter name as the driver reports it (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub name: String,
    /// `vulkan`, `metal`, `dx12` or `gl`.
    pub backend: String,
    /// `DiscreteGpu`, `IntegratedGpu`, `VirtualGpu`, `Cpu` or `Other`.
    pub device_type: String,
    /// Driver name (may be empty).
    pub driver: String,
    /// Driver version and details (may be empty).
    pub driver_info: String,
    /// Optional wgpu features the adapter offers (none is requested but, for a pass
    /// profile, the timestamps of `gpu::timestamps`).
    pub features: Vec<String>,
    /// The limits the GPU engine cares about.
    pub limits: LimitsSummary,
}

impl AdapterSummary {
    /// Summarises `adapter`: its info, optional features and limits.
    pub fn of(adapter: &wgpu::Adapter) -> Self {
        let info = adapter.get_info();
        Self {
            name: info.name,
            backend: info.backend.to_str().to_string(),
            device_type: format!("{:?}", info.device_type),
            driver: info.driver,
            driver_info: info.driver_info,
            features: adapter
                .features()
                .iter_names()
                .map(|(name, _)| name.to_string())
                .collect(),
            limits: LimitsSummary::from(&adapter.limits()),
        }
    }
}

fn mib(bytes: u64) -> String {
    if bytes >= 1 << 20 {
        format!("{bytes} ({} MiB)", bytes >> 20)
    } else {
        bytes.to_string()
    }
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let l = &self.limits;
        writeln!(f, "adapter          {}", self.name)?;
        writeln!(f, "backend          {}", self.backend)?;
        writeln!(f, "device type      {}", self.device_type)?;
        let driver = match (self.driver.is_empty(), self.driver_info.is_empty()) {
            (true, true) => "-".to_string(),
            (false, true) => self.driver.clone(),
            (true, false) => self.driver_info.clone(),
            (false, false) => format!("{} ({})", self.driver, self.driver_info),
        };
        writeln!(f, "driver           {driver}")?;
        writeln!(f, "limits")?;
        writeln!(
            f,
            "  max_storage_buffer_binding_size        {}",
            mib(l.max_storage_buffer_binding_size)
        )?;
        writeln!(
            f,
            "  max_buffer_size                        {}",
            mib(l.max_buffer_size)
        )?;
        writeln!(
            f,
            "  max_compute_workgroup_size_x           {}",
            l.max_compute_workgroup_size_x
        )?;
        writeln!(
            f,
            "  max_compute_invocations_per_workgroup  {}",
            l.max_compute_invocations_per_workgroup
        )?;
        writeln!(
            f,
            "  max_compute_workgroups_per_dimension   {}",
            l.max_compute_workgroups_per_dimension
        )?;
        writeln!(
            f,
            "  max_storage_buffers_per_shader_stage   {}",
            l.max_storage_buffers_per_shader_stage
        )?;
        writeln!(
            f,
            "  max_bind_groups                        {}",
            l.max_bind_groups
        )?;
        if self.features.is_empty() {
            write!(f, "features         (none)")
        } else {
            write!(f, "features         {}", self.features.join(", "))
        }
    }
}

/// How `POWDER_ADAPTER` restricts the choice.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AdapterPreference {
    /// Best real GPU, else software.
    Auto,
    /// Device type `Cpu` only.
    Software,
    /// Anything but device type `Cpu`.
    Hardware,
    /// Case-insensitive substring of the adapter name.
    Name(String),
}

impl AdapterPreference {
    /// Parses a `POWDER_ADAPTER` value (`None` or empty = auto).
    pub fn parse(value: Option<&str>) -> Self {
        match value.map(str::trim) {
            None | Some("") => Self::Auto,
            Some(v) => match v.to_ascii_lowercase().as_str() {
                "auto" => Self::Auto,
                "software" => Self::Software,
                "hardware" => Self::Hardware,
                _ => Self::Name(v.to_string()),
            },
        }
    }

    /// Reads `POWDER_ADAPTER`.
    pub fn from_env() -> Self {
        Self::parse(std::env::var(ADAPTER_ENV).ok().as_deref())
    }

    /// Whether an adapter with this info may be chosen.
    pub fn accepts(&self, info: &wgpu::AdapterInfo) -> bool {
        match self {
            Self::Auto => true,
            Self::Software => info.device_type == wgpu::DeviceType::Cpu,
            Self::Hardware => info.device_type != wgpu::DeviceType::Cpu,
            // part of the adapter's name, or its backend ("vulkan", "gl", "metal", "dx12")
            Self::Name(s) => {
                let s = s.to_lowercase();
                info.name.to_lowercase().contains(&s)
                    || format!("{:?}", info.backend).to_lowercase() == s
            }
        }
    }
}

/// Sort key of an adapter: lower is better.
pub fn adapter_rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Metal => 1,
        wgpu::Backend::Dx12 => 2,
        wgpu::Backend::Gl => 3,
        _ => 4,
    };
    (device, backend)
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({}, {:?})",
        info.name,
        info.backend.to_str(),
        info.device_type
    )
}

/// Every adapter wgpu finds on [`BACKENDS`] (dropping the last of them destroys their
/// instance outside the section that keeps threads apart: [`adapter_infos`] where the
/// descriptions suffice).
pub fn enumerate_adapters() -> Vec<wgpu::Adapter> {
    let _section = Section::begin();
    enumerate_in_section()
}

/// What [`enumerate_adapters`] finds, the adapters (and their instance) dropped inside the
/// section.
pub fn adapter_infos() -> Vec<wgpu::AdapterInfo> {
    let _section = Section::begin();
    let adapters = enumerate_in_section();
    let infos = adapters.iter().map(|a| a.get_info()).collect();
    drop(adapters);
    infos
}

pub(crate) fn enumerate_in_section() -> Vec<wgpu::Adapter> {
    let instance = new_instance();
    pollster::block_on(instance.enumerate_adapters(BACKENDS))
}

fn new_instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = BACKENDS;
    // wgpu validates every indirect dispatch with an extra dispatch; ours only ever replay
    // sizes the host computed within the device limits, or zeros (the skipped rebuild), so
    // the check only costs (measured: docs/architecture.md, on the Verlet skin).
    desc.flags
        .remove(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
    wgpu::Instance::new(desc)
}

/// Picks the best adapter allowed by `pref`; the error names what exists.
pub fn choose_adapter(
    adapters: Vec<wgpu::Adapter>,
    pref: &AdapterPreference,
) -> Result<wgpu::Adapter, PowderError> {
    let found: Vec<(wgpu::AdapterInfo, bool)> = adapters
        .iter()
        .map(|a| {
            let info = a.get_info();
            let compute = a
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
                && gl_runs_compute(&info);
            (info, compute)
        })
        .collect();
    let i = pick_adapter(&found, pref)?;
    Ok(adapters.into_iter().nth(i).expect("an index of the list"))
}

/// Whether a GL adapter's context runs compute shaders: OpenGL 4.3 or OpenGL ES 3.1, read
/// from its version string (`driver_info`). wgpu reports compute on a 3.3 context that has
/// the ARB extension (NVIDIA's through EGL), but naga writes GLSL 3.30 for it, which has
/// none. Other backends, and versions it cannot read, pass.
pub fn gl_runs_compute(info: &wgpu::AdapterInfo) -> bool {
    if info.backend != wgpu::Backend::Gl {
        return true;
    }
    let text = info.driver_info.trim();
    let (es, rest) = match text.strip_prefix("OpenGL ES") {
        Some(rest) => (true, rest.trim_start()),
        None => (false, text),
    };
    let mut parts = rest
        .split(|c: char| !c.is_ascii_digit())
        .map(|p| p.parse::<u32>());
    match (parts.next(), parts.next()) {
        (Some(Ok(major)), Some(Ok(minor))) => (major, minor) >= if es { (3, 1) } else { (4, 3) },
        _ => true,
    }
}

/// The index of the best adapter allowed by `pref` among `(info, has compute shaders)`;
/// adapters without compute shaders (a desktop GL context below 4.3, as NVIDIA's EGL
/// gives wgpu) are never chosen, and the error says so when only they match.
pub fn pick_adapter(
    found: &[(wgpu::AdapterInfo, bool)],
    pref: &AdapterPreference,
) -> Result<usize, PowderError> {
    let tried = "Vulkan, Metal, DX12, GL";
    if found.is_empty() {
        return Err(PowderError::Run(format!(
            "no GPU adapter found (tried {tried}); {INSTALL_HINT}"
        )));
    }
    let all: Vec<String> = found.iter().map(|(info, _)| describe(info)).collect();
    let matching: Vec<usize> = (0..found.len())
        .filter(|&i| pref.accepts(&found[i].0))
        .collect();
    // Stable sort: enumeration order breaks ties.
    let mut usable: Vec<usize> = matching.iter().copied().filter(|&i| found[i].1).collect();
    usable.sort_by_key(|&i| adapter_rank(&found[i].0));
    if let Some(&i) = usable.first() {
        return Ok(i);
    }
    let wanted = match pref {
        AdapterPreference::Name(s) => s.clone(),
        other => format!("{other:?}").to_lowercase(),
    };
    if let Some(&i) = matching.first() {
        let info = &found[i].0;
        return Err(PowderError::Run(format!(
            "the adapter {ADAPTER_ENV}={wanted} matches, {} (driver {}), has no compute \
             shaders (wgpu needs OpenGL 4.3 or OpenGL ES 3.1 on GL); adapters found: {}; \
             choose another with {ADAPTER_ENV}",
            describe(info),
            info.driver_info,
            all.join("; ")
        )));
    }
    Err(PowderError::Run(format!(
        "no GPU adapter matches {ADAPTER_ENV}={wanted} (tried {tried}); adapters found: {}; \
         set {ADAPTER_ENV} to auto, software, hardware or part of one of these names",
        all.join("; ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(
        name: &str,
        backend: wgpu::Backend,
        device_type: wgpu::DeviceType,
    ) -> wgpu::AdapterInfo {
        wgpu::AdapterInfo {
            name: name.into(),
            ..wgpu::AdapterInfo::new(device_type, backend)
        }
    }

    /// An adapter without compute shaders (NVIDIA's GL through EGL: a GL 3.3 context) is
    /// passed over where another matches, and refused by name where it alone does.
    #[test]
    fn adapters_without_compute_shaders_are_never_chosen() {
        let gl = wgpu::AdapterInfo {
            driver_info: "3.3.0 NVIDIA 580.159.04".into(),
            ..info(
                "NVIDIA H200/PCIe/SSE2",
                wgpu::Backend::Gl,
                wgpu::DeviceType::Other,
            )
        };
        let vk = info(
            "NVIDIA H200",
            wgpu::Backend::Vulkan,
            wgpu::DeviceType::DiscreteGpu,
        );
        let lavapipe = info("llvmpipe", wgpu::Backend::Vulkan, wgpu::DeviceType::Cpu);
        let found = [(gl.clone(), false), (lavapipe, true), (vk, true)];
        assert_eq!(pick_adapter(&found, &AdapterPreference::Auto).unwrap(), 2);
        assert_eq!(
            pick_adapter(&found, &AdapterPreference::Software).unwrap(),
            1
        );
        let err = pick_adapter(&found, &AdapterPreference::parse(Some("gl")))
            .unwrap_err()
            .to_string();
        assert!(err.contains("no compute shaders"), "{err}");
        assert!(err.contains("3.3.0 NVIDIA"), "{err}");
        // alone: even auto does not take it
        let err = pick_adapter(&[(gl, false)], &AdapterPreference::Auto)
            .unwrap_err()
            .to_string();
        assert!(err.contains("no compute shaders"), "{err}");
        assert!(pick_adapter(&[], &AdapterPreference::Auto).is_err());
    }

    #[test]
    fn gl_versions_with_compute_shaders() {
        let gl = |v: &str| wgpu::AdapterInfo {
            driver_info: v.into(),
            ..info("x", wgpu::Backend::Gl, wgpu::DeviceType::Other)
        };
        assert!(gl_runs_compute(&gl("4.5 (Core Profile) Mesa 22.3.6")));
        assert!(gl_runs_compute(&gl("4.3.0 NVIDIA 580.159.04")));
        assert!(!gl_runs_compute(&gl("3.3.0 NVIDIA 580.159.04")));
        assert!(!gl_runs_compute(&gl("4.1 Metal - 88")));
        assert!(gl_runs_compute(&gl("OpenGL ES 3.2 NVIDIA 580.159.04")));
        assert!(!gl_runs_compute(&gl("OpenGL ES 3.0 Mesa 22.3.6")));
        assert!(gl_runs_compute(&gl("")));
        let vk = info("x", wgpu::Backend::Vulkan, wgpu::DeviceType::Cpu);
        assert!(gl_runs_compute(&wgpu::AdapterInfo {
            driver_info: "3.3".into(),
            ..vk
        }));
    }

    #[test]
    fn gpu_preference_parsing() {
        assert_eq!(AdapterPreference::parse(None), AdapterPreference::Auto);
        assert_eq!(AdapterPreference::parse(Some("")), AdapterPreference::Auto);
        assert_eq!(
            AdapterPreference::parse(Some("AUTO")),
            AdapterPreference::Auto
        );
        assert_eq!(
            AdapterPreference::parse(Some("software")),
            AdapterPreference::Software
        );
        assert_eq!(
            AdapterPreference::parse(Some("Hardware")),
            AdapterPreference::Hardware
        );
        assert_eq!(
            AdapterPreference::parse(Some("RTX")),
            AdapterPreference::Name("RTX".into())
        );
    }

    #[test]
    fn gpu_adapter_ranking_and_filters() {
        use wgpu::{Backend as B, DeviceType as D};
        let lavapipe = info("llvmpipe (LLVM 15.0.6, 256 bits)", B::Vulkan, D::Cpu);
        let gl = info("llvmpipe (LLVM 15.0.6, 256 bits)", B::Gl, D::Cpu);
        let igpu = info("Intel(R) UHD Graphics", B::Vulkan, D::IntegratedGpu);
        let dgpu = info("NVIDIA GeForce RTX 4090", B::Vulkan, D::DiscreteGpu);
        let dgpu_gl = info("NVIDIA GeForce RTX 4090", B::Gl, D::DiscreteGpu);
        let mut all = [&gl, &lavapipe, &igpu, &dgpu_gl, &dgpu];
        all.sort_by_key(|i| adapter_rank(i));
        assert_eq!(all[0], &dgpu);
        assert_eq!(all[1], &dgpu_gl);
        assert_eq!(all[2], &igpu);
        assert_eq!(all[3], &lavapipe);
        assert_eq!(all[4], &gl);
        assert!(AdapterPreference::Software.accepts(&lavapipe));
        assert!(!AdapterPreference::Software.accepts(&igpu));
        assert!(AdapterPreference::Hardware.accepts(&igpu));
        assert!(!AdapterPreference::Hardware.accepts(&gl));
        assert!(AdapterPreference::Name("rtx".into()).accepts(&dgpu));
        assert!(!AdapterPreference::Name("rtx".into()).accepts(&lavapipe));
        // a backend's name picks that backend's adapters
        assert!(AdapterPreference::Name("gl".into()).accepts(&gl));
        assert!(!AdapterPreference::Name("gl".into()).accepts(&lavapipe));
        assert!(AdapterPreference::Name("Vulkan".into()).accepts(&lavapipe));
    }

    #[test]
    fn gpu_no_adapter_error_names_the_fix() {
        let e = choose_adapter(Vec::new(), &AdapterPreference::Auto).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("no GPU adapter found"), "{text}");
        assert!(text.contains("apt-get install -y mesa-vulkan-drivers libvulkan1"));
    }
}
