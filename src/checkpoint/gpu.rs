//! The GPU engine's saved state ([`GpuSavedState`]) as named arrays of a checkpoint: each
//! device buffer's bytes as `buffer.<name>`, the host's values beside them, and what the
//! bytes mean (the adapter, the contact law's layout, the buffers' order) in `gpu.json`.

use super::cpu::{f64s, u64s};
use super::npz::{Array, Member};
use super::StateError;
use crate::gpu::GpuSavedState;
use glam::DVec3;

#[derive(serde::Serialize, serde::Deserialize)]
struct Description {
    adapter: String,
    layout: String,
    buffers: Vec<String>,
    /// Whether the run kept the energy ledger (absent in checkpoints from before its rows
    /// joined the particle state: they name a `particle_ledger` buffer).
    #[serde(default)]
    ledger: bool,
}

/// The state's arrays and its description, in a fixed order.
pub fn arrays(s: &GpuSavedState) -> Result<Vec<(String, Member)>, StateError> {
    let about = Description {
        adapter: s.adapter.clone(),
        layout: s.layout.clone(),
        buffers: s.buffers.iter().map(|(n, _)| n.clone()).collect(),
        ledger: s.ledger,
    };
    let json = serde_json::to_vec_pretty(&about).map_err(|e| StateError(e.to_string()))?;
    let a = |name: &str, array: Array| (name.to_string(), Member::Array(array));
    let points: Vec<f64> = s.wall_points.iter().flat_map(|p| p.to_array()).collect();
    let mut out = vec![
        ("gpu.json".to_string(), Member::Raw(json)),
        a("time", Array::scalar_f64(s.time)),
        a("steps", Array::scalar_u64(s.steps)),
        a("dropped", Array::scalar_u64(s.dropped)),
        a(
            "wall_point",
            Array {
                descr: "<f8".into(),
                shape: vec![s.wall_points.len(), 3],
                data: bytemuck::cast_slice(&points).to_vec(),
            },
        ),
        a(
            "active",
            Array::of(
                "|b1",
                &s.active.iter().map(|&b| u8::from(b)).collect::<Vec<u8>>(),
            ),
        ),
        a("inserted", Array::scalar_f64(s.inserted)),
    ];
    for (name, bytes) in &s.buffers {
        out.push(a(&format!("buffer.{name}"), Array::of("|u1", bytes)));
    }
    Ok(out)
}

/// The state from its description and arrays (`get` gives each array by name).
pub fn state(
    about: &[u8],
    get: &dyn Fn(&str) -> Result<Array, StateError>,
) -> Result<GpuSavedState, StateError> {
    let about: Description = serde_json::from_slice(about)
        .map_err(|e| StateError(format!("`gpu.json` does not describe a GPU state: {e}")))?;
    let mut buffers = Vec::with_capacity(about.buffers.len());
    for name in about.buffers {
        let a = get(&format!("buffer.{name}"))?;
        if a.descr != "|u1" || a.shape != [a.data.len()] {
            return Err(StateError(format!("buffer `{name}` is not a byte array")));
        }
        buffers.push((name, a.data));
    }
    let points = get("wall_point")?;
    let wall_points = f64s(&points, "wall_point", 2)?
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect();
    let active = get("active")?;
    if active.descr != "|b1" || active.shape.len() != 1 || active.data.iter().any(|&b| b > 1) {
        return Err(StateError("`active` is not a list of flags".into()));
    }
    Ok(GpuSavedState {
        time: f64s(&get("time")?, "time", 0)?[0],
        steps: u64s(&get("steps")?, "steps")?,
        dropped: u64s(&get("dropped")?, "dropped")?,
        adapter: about.adapter,
        buffers,
        wall_points,
        active: active.data.iter().map(|&b| b == 1).collect(),
        inserted: f64s(&get("inserted")?, "inserted", 0)?[0],
        layout: about.layout,
        ledger: about.ledger,
    })
}
