//! powder as a library: build a scene in code, run it on the GPU, read back the state and
//! the energy ledger, and compare with the f64 CPU reference.
//!
//!     cargo run --release --example library
//!
//! A small cohesive heap: 125 hysteretic spheres on a jittered lattice fall onto a floor.
//! Without a GPU adapter (`apt-get install -y mesa-vulkan-drivers` gives the software one)
//! only the CPU part runs.

use powder::cpu::CpuEngine;
use powder::gpu::{GpuContext, GpuEngine};
use powder::model::{ContactModel, HystereticParams};
use powder::scene::{Domain, DtSetting, Material, ParticleInit, Scene, Wall, WallMotion};
use powder::PowderError;

fn scene() -> Scene {
    let r = 1.1e-3;
    let mut particles = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..5 {
                // a lattice 2.4 r apart, jittered by a fixed pattern
                let jitter = 0.1 * r * ((i * 7 + j * 3 + k) % 5) as f64 / 5.0;
                particles.push(ParticleInit {
                    position: [
                        2e-3 + 2.4 * r * i as f64 + jitter,
                        2e-3 + 2.4 * r * j as f64 - jitter,
                        2e-3 + 2.4 * r * k as f64,
                    ],
                    velocity: [0.0; 3],
                    angular_velocity: [0.0; 3],
                    radius: r,
                    material: 0,
                    insert_at: 0.0,
                });
            }
        }
    }
    Scene {
        name: "library_heap".into(),
        domain: Domain {
            min: [0.0; 3],
            max: [0.02, 0.02, 0.03],
            periodic: [false; 3],
        },
        gravity: [0.0, 0.0, -9.81],
        dt: DtSetting::Auto,
        force_dt: false,
        jump_impulses: None,
        duration: 0.05,
        output_every: 1000,
        impact_velocity: 1.0,
        checkpoint_every: 10_000,
        contact_output: None,
        materials: vec![Material {
            name: "powder".into(),
            density: 2000.0,
            // paper 003's figure parameters (kc = 100 N/m) and a little viscosity
            model: ContactModel::Hysteretic(HystereticParams {
                gamma0: 1e-3,
                ..HystereticParams::paper_figure()
            }),
        }],
        interactions: vec![],
        walls: vec![Wall {
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            motion: WallMotion::fixed(),
            material: 0,
        }],
        particles,
    }
}

fn main() -> Result<(), PowderError> {
    let scene = scene();
    let mut cpu = CpuEngine::new(&scene)?;
    let steps = (scene.duration / cpu.dt()).ceil() as u64;
    println!(
        "{} particles, dt = {:.3e} s ({}), {steps} steps",
        cpu.len(),
        cpu.dt(),
        cpu.time_step().reason
    );
    cpu.run_steps(steps)?;
    let ec = cpu.energies();
    println!(
        "cpu: kinetic {:.4e} J, stored {:.4e} J, dissipated {:.4e} J, {} contacts",
        ec.kinetic,
        ec.elastic,
        ec.dissipated,
        cpu.contact_stats().contacts
    );
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("no GPU run: {e}");
            return Ok(());
        }
    };
    let mut gpu = GpuEngine::new(&scene, ctx)?;
    gpu.run_steps(steps)?;
    let state = gpu.state()?;
    let eg = gpu.energies(&state)?;
    println!(
        "gpu ({}): kinetic {:.4e} J, stored {:.4e} J, dissipated {:.4e} J, {} contacts",
        gpu.adapter(),
        eg.kinetic,
        eg.elastic,
        eg.dissipated,
        gpu.contact_stats()?.contacts
    );
    let worst = cpu
        .positions()
        .iter()
        .zip(&state.positions)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    println!(
        "largest position difference {:.3e} radii; dissipated energy differs by {:.2e} of the CPU's",
        worst / 1.1e-3,
        (eg.dissipated - ec.dissipated).abs() / ec.dissipated.max(1e-300)
    );
    Ok(())
}
