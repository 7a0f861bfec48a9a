//! What one memory access costs on the GPU adapter (`docs/design_log.md`'s numbers for
//! lavapipe): 65 536 invocations each make 32 accesses at pseudo-random indices into 1 MiB
//! of vec4s, per access kind, and the probe prints nanoseconds per access (wall time of 20
//! dispatches in one submission, over invocations × 32), plus the time of a 1 MiB copy from
//! a buffer into a texture.
//!
//!     NODEVICE_SELECT=1 cargo run --release --example lavapipe_probe
//!
//! On a software adapter, compare the storage-buffer loads (a loop over the SIMD lanes per
//! access) with the read-only storage-texture load (one gather). On a real GPU all of them
//! are memory-bound and close.

use powder::gpu::GpuContext;
use std::time::Instant;

const SOURCE: &str = r#"
@group(0) @binding(0) var<storage, read_write> rw_vec4: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> ro_vec4: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> rw_u32: array<u32>;
@group(0) @binding(3) var sampled: texture_2d<f32>;
@group(0) @binding(4) var ro_texture: texture_storage_2d<rgba32float, read>;
@group(0) @binding(5) var wo_texture: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var<storage, read_write> out: array<vec4<f32>>;
const N: u32 = 65536u;
const L: u32 = 32u;
fn pick(k: u32, l: u32) -> u32 { return (k * 2654435761u + l * 40503u) % N; }
fn texel(j: u32) -> vec2<u32> { return vec2<u32>(j & 4095u, j >> 12u); }
@compute @workgroup_size(64)
fn none(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = vec4<f32>(0.0);
  for (var l = 0u; l < L; l++) { s += vec4<f32>(f32(pick(g.x, l))); }
  out[g.x] = s;
}
@compute @workgroup_size(64)
fn storage_vec4_load(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = vec4<f32>(0.0);
  for (var l = 0u; l < L; l++) { s += rw_vec4[pick(g.x, l)]; }
  out[g.x] = s;
}
@compute @workgroup_size(64)
fn read_only_storage_vec4_load(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = vec4<f32>(0.0);
  for (var l = 0u; l < L; l++) { s += ro_vec4[pick(g.x, l)]; }
  out[g.x] = s;
}
@compute @workgroup_size(64)
fn storage_u32_load(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = 0u;
  for (var l = 0u; l < L; l++) { s += rw_u32[pick(g.x, l)]; }
  out[g.x] = vec4<f32>(f32(s));
}
@compute @workgroup_size(64)
fn sampled_texture_load(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = vec4<f32>(0.0);
  for (var l = 0u; l < L; l++) { s += textureLoad(sampled, texel(pick(g.x, l)), 0); }
  out[g.x] = s;
}
@compute @workgroup_size(64)
fn read_only_storage_texture_load(@builtin(global_invocation_id) g: vec3<u32>) {
  var s = vec4<f32>(0.0);
  for (var l = 0u; l < L; l++) { s += textureLoad(ro_texture, texel(pick(g.x, l))); }
  out[g.x] = s;
}
@compute @workgroup_size(64)
fn storage_vec4_store(@builtin(global_invocation_id) g: vec3<u32>) {
  for (var l = 0u; l < L; l++) { rw_vec4[pick(g.x, l)] = vec4<f32>(f32(l)); }
}
@compute @workgroup_size(64)
fn storage_u32_store(@builtin(global_invocation_id) g: vec3<u32>) {
  for (var l = 0u; l < L; l++) { rw_u32[pick(g.x, l)] = l; }
}
@compute @workgroup_size(64)
fn storage_texture_store(@builtin(global_invocation_id) g: vec3<u32>) {
  for (var l = 0u; l < L; l++) { textureStore(wo_texture, texel(pick(g.x, l)), vec4<f32>(f32(l))); }
}
"#;

const N: u32 = 65_536;
const ACCESSES: f64 = 32.0;

fn main() -> Result<(), powder::PowderError> {
    let ctx = GpuContext::new()?;
    let dev = &ctx.device;
    let buffer = |label| {
        dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: N as u64 * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    };
    let (rw_vec4, ro_vec4, rw_u32, out) = (buffer("a"), buffer("b"), buffer("c"), buffer("d"));
    let texture = |usage| {
        dev.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: 4096,
                height: N / 4096,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: usage | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    };
    let sampled = texture(wgpu::TextureUsages::TEXTURE_BINDING);
    let storage = texture(wgpu::TextureUsages::STORAGE_BINDING);
    let (sampled_view, storage_view) = (
        sampled.create_view(&Default::default()),
        storage.create_view(&Default::default()),
    );
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("lavapipe probe"),
        source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
    });
    let submit = |record: &dyn Fn(&mut wgpu::CommandEncoder)| {
        let mut encoder = dev.create_command_encoder(&Default::default());
        record(&mut encoder);
        let t = Instant::now();
        ctx.queue.submit([encoder.finish()]);
        let _ = dev.poll(wgpu::PollType::wait_indefinitely());
        t.elapsed().as_secs_f64()
    };
    println!("adapter: {}", ctx.summary.name);
    let mut baseline = 0.0;
    for entry in [
        "none",
        "storage_vec4_load",
        "read_only_storage_vec4_load",
        "storage_u32_load",
        "sampled_texture_load",
        "read_only_storage_texture_load",
        "storage_vec4_store",
        "storage_u32_store",
        "storage_texture_store",
    ] {
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let layout = pipeline.get_bind_group_layout(0);
        let resource = |binding: u32| match binding {
            0 => rw_vec4.as_entire_binding(),
            1 => ro_vec4.as_entire_binding(),
            2 => rw_u32.as_entire_binding(),
            3 => wgpu::BindingResource::TextureView(&sampled_view),
            4 | 5 => wgpu::BindingResource::TextureView(&storage_view),
            _ => out.as_entire_binding(),
        };
        // the bindings each entry point uses (automatic layouts hold only those)
        let used: &[u32] = match entry {
            "none" => &[6],
            "storage_vec4_load" => &[0, 6],
            "read_only_storage_vec4_load" => &[1, 6],
            "storage_u32_load" => &[2, 6],
            "sampled_texture_load" => &[3, 6],
            "read_only_storage_texture_load" => &[4, 6],
            "storage_vec4_store" => &[0],
            "storage_u32_store" => &[2],
            _ => &[5],
        };
        let entries: Vec<wgpu::BindGroupEntry> = used
            .iter()
            .map(|&binding| wgpu::BindGroupEntry {
                binding,
                resource: resource(binding),
            })
            .collect();
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &entries,
        });
        let run = |reps: u32| {
            submit(&|encoder| {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &group, &[]);
                for _ in 0..reps {
                    pass.dispatch_workgroups(N / 64, 1, 1);
                }
            })
        };
        run(2);
        let per_dispatch = run(20) / 20.0;
        if entry == "none" {
            baseline = per_dispatch;
            println!(
                "{entry:<32} {:8.3} ms a dispatch (the loop alone)",
                per_dispatch * 1e3
            );
        } else {
            let ns = (per_dispatch - baseline).max(0.0) * 1e9 / (N as f64 * ACCESSES);
            println!("{entry:<32} {ns:8.2} ns an access");
        }
    }
    let copy = |reps: u32| {
        submit(&|encoder| {
            for _ in 0..reps {
                encoder.copy_buffer_to_texture(
                    wgpu::TexelCopyBufferInfo {
                        buffer: &rw_vec4,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(4096 * 16),
                            rows_per_image: None,
                        },
                    },
                    storage.as_image_copy(),
                    storage.size(),
                );
            }
        })
    };
    copy(2);
    println!(
        "{:<32} {:8.1} µs a MiB",
        "buffer -> texture copy",
        copy(50) / 50.0 * 1e6
    );
    Ok(())
}
