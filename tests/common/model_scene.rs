//! Scenes built as `Scene` values (not parsed): one material of a given model, spheres of
//! radius 1 mm and a floor, for tests that set a law's fields directly.

#![allow(dead_code)]

use powder::model::ContactModel;
use powder::scene::{Domain, DtSetting, Material, ParticleInit, Scene, Wall};

/// A 2 cm box around the origin with one material (`model`, 2000 kg/m³), `walls`,
/// `particles` and gravity `gravity` along z.
pub fn scene(
    model: ContactModel,
    particles: Vec<ParticleInit>,
    walls: Vec<Wall>,
    gravity: f64,
) -> Scene {
    Scene {
        name: "test".into(),
        domain: Domain {
            min: [-0.01; 3],
            max: [0.01; 3],
            periodic: [false; 3],
        },
        gravity: [0.0, 0.0, gravity],
        dt: DtSetting::Auto,
        force_dt: false,
        jump_impulses: None,
        duration: 1.0,
        output_every: 1000,
        contact_output: None,
        impact_velocity: 1.0,
        checkpoint_every: 10_000,
        materials: vec![Material {
            name: "m".into(),
            density: 2000.0,
            model,
        }],
        interactions: vec![],
        walls,
        particles,
    }
}

/// A sphere of radius 1 mm of the material at `position` with `velocity`.
pub fn particle(position: [f64; 3], velocity: [f64; 3]) -> ParticleInit {
    ParticleInit {
        position,
        velocity,
        angular_velocity: [0.0; 3],
        radius: 1e-3,
        material: 0,
        insert_at: 0.0,
    }
}

/// The floor z = 0 of the material.
pub fn floor() -> Wall {
    Wall {
        point: [0.0, 0.0, 0.0],
        normal: [0.0, 0.0, 1.0],
        motion: Default::default(),
        material: 0,
    }
}
