//! Checkpoints: the complete evolving state of a run (CPU: [`CpuState`]; GPU: the device
//! buffers of [`GpuSavedState`]), so a run resumes bitwise identically on the same backend
//! (and, for the GPU, the same adapter). A checkpoint names the powder version, the
//! backend and a digest of the scene, and is refused for another version, backend or
//! scene; it ends with a CRC-32 of the bytes before it, so a damaged or cut file is refused
//! too (a flip in the header's format or version reads as another version's checkpoint).
//! Written atomically.

use crate::cpu::{CpuEngine, CpuState};
use crate::error::PowderError;
use crate::gpu::GpuSavedState;
use crate::output::atomic::write_atomic;
use crate::scene::Scene;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

const MAGIC: &str = "powder-checkpoint";
/// Raw bytes that open every checkpoint, checked before anything is decoded.
const PREFIX: &[u8; 8] = b"POWDERCK";

/// bincode with fixed-width integers and a size limit, so a corrupt length can never ask
/// for more memory than the file holds.
fn codec(limit: u64) -> impl bincode::Options {
    use bincode::Options;
    bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .allow_trailing_bytes()
        .with_limit(limit)
}
/// Bumped whenever the state layout changes, or the GPU step's arithmetic does (a resume
/// continues bitwise only with the same arithmetic; 6: the hysteretic model's divisions
/// became multiplications by host-derived constants; 7: the contact history holds Luding's
/// twisting spring and the models their friction parameters; 8: the CPU's JKR contact-radius
/// solve stops once converged; 9: the CPU's JKR solve starts from a table, its force and
/// energy come from √(a/a0), the history rotation takes one square root; the scene has
/// `jump_impulses`; 10: the CPU places force jumps inside the step by default; 11: the GPU
/// places them too (each list entry's `prior` and the jumps' fields), the JKR zone rule
/// stops at the adhesion speed, the hysteretic edges and touch jumps changed; 12: the GPU's
/// arrays are blocked by windows (the wall contacts by window; the state uploaded in the
/// grid's order) and a prior without the ledger is three words; 13: the GPU's wall contacts
/// are list entries of the particles near a wall; 14: the entries' per-step fields last;
/// 15: a CPU contact keeps its friction and couple powers instead of their vectors; 16: a
/// CRC-32 of the file's bytes ends it).
const FORMAT: u32 = 16;

#[derive(Serialize, Deserialize)]
struct Header {
    magic: String,
    format: u32,
    version: String,
    backend: String,
    scene: String,
    scene_digest: u64,
    steps: u64,
    time: f64,
}

/// FNV-1a over the scene's full description (every value, exactly): two scenes share a
/// digest only if they describe the same run.
pub fn scene_digest(scene: &Scene) -> u64 {
    let text = format!("{scene:?}");
    let mut h: u64 = 0xcbf29ce484222325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

/// Writes the CPU engine's state to `path` (atomically).
pub fn save(path: &Path, scene: &Scene, engine: &CpuEngine) -> Result<(), PowderError> {
    let state = engine.state();
    save_state(path, scene, "cpu", state.steps, state.time, &state)
}

/// Reads a CPU checkpoint of `scene` from `path`.
pub fn load(path: &Path, scene: &Scene) -> Result<CpuState, PowderError> {
    load_state(path, scene, "cpu")
}

/// Writes a saved GPU state to `path` (atomically).
pub fn save_gpu(path: &Path, scene: &Scene, state: &GpuSavedState) -> Result<(), PowderError> {
    save_state(path, scene, "gpu", state.steps, state.time, state)
}

/// Reads a GPU checkpoint of `scene` from `path`.
pub fn load_gpu(path: &Path, scene: &Scene) -> Result<GpuSavedState, PowderError> {
    load_state(path, scene, "gpu")
}

fn save_state<T: Serialize>(
    path: &Path,
    scene: &Scene,
    backend: &str,
    steps: u64,
    time: f64,
    state: &T,
) -> Result<(), PowderError> {
    let header = Header {
        magic: MAGIC.into(),
        format: FORMAT,
        version: env!("CARGO_PKG_VERSION").into(),
        backend: backend.into(),
        scene: scene.name.clone(),
        scene_digest: scene_digest(scene),
        steps,
        time,
    };
    use bincode::Options;
    let encode = |e: bincode::Error| PowderError::Run(format!("cannot encode the checkpoint: {e}"));
    let mut bytes = PREFIX.to_vec();
    bytes.extend(codec(u64::MAX).serialize(&header).map_err(encode)?);
    bytes.extend(codec(u64::MAX).serialize(state).map_err(encode)?);
    let crc = crc32fast::hash(&bytes);
    bytes.extend(crc.to_le_bytes());
    write_atomic(path, &bytes)
}

fn not_a_checkpoint(path: &Path) -> PowderError {
    PowderError::Run(format!(
        "`{}` is not a powder checkpoint (or is truncated)",
        path.display()
    ))
}

fn damaged(path: &Path) -> PowderError {
    PowderError::Run(format!(
        "checkpoint `{}` is damaged or truncated: its checksum does not match its contents",
        path.display()
    ))
}

/// The header of a checkpoint's bytes, and a cursor on the state after it.
fn read_header<'a>(
    bytes: &'a [u8],
    path: &Path,
) -> Result<(Header, std::io::Cursor<&'a [u8]>), PowderError> {
    use bincode::Options;
    if !bytes.starts_with(PREFIX) {
        return Err(not_a_checkpoint(path));
    }
    let mut cursor = std::io::Cursor::new(&bytes[PREFIX.len()..]);
    let header: Header = codec(bytes.len() as u64)
        .deserialize_from(&mut cursor)
        .map_err(|_| not_a_checkpoint(path))?;
    if header.magic != MAGIC {
        return Err(not_a_checkpoint(path));
    }
    Ok((header, cursor))
}

/// The backend (`"cpu"` or `"gpu"`) that wrote the checkpoint at `path`.
pub fn backend_of(path: &Path) -> Result<String, PowderError> {
    let bytes = std::fs::read(path)
        .map_err(|e| PowderError::io(format!("cannot read checkpoint `{}`", path.display()), e))?;
    Ok(read_header(&bytes, path)?.0.backend)
}

fn load_state<T: DeserializeOwned>(
    path: &Path,
    scene: &Scene,
    backend: &str,
) -> Result<T, PowderError> {
    let bytes = std::fs::read(path)
        .map_err(|e| PowderError::io(format!("cannot read checkpoint `{}`", path.display()), e))?;
    let (header, cursor) = read_header(&bytes, path)?;
    let not_ours = || not_a_checkpoint(path);
    let limit = bytes.len() as u64;
    use bincode::Options;
    if header.format != FORMAT || header.version != env!("CARGO_PKG_VERSION") {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` was written by powder {} (format {}); this is powder {} (format {FORMAT}): rerun the scene from the start",
            path.display(),
            header.version,
            header.format,
            env!("CARGO_PKG_VERSION")
        )));
    }
    // the CRC-32 of everything before it, last: a flipped bit or a cut is refused here
    let state_start = PREFIX.len() + cursor.position() as usize;
    let body = match bytes.len().checked_sub(4) {
        Some(end) if end >= state_start => &bytes[..end],
        _ => return Err(damaged(path)),
    };
    let crc = u32::from_le_bytes(bytes[body.len()..].try_into().map_err(|_| damaged(path))?);
    if crc32fast::hash(body) != crc {
        return Err(damaged(path));
    }
    let mut cursor = std::io::Cursor::new(&body[state_start..]);
    if header.backend != backend {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` comes from the {} backend; resume it with --backend {}",
            path.display(),
            header.backend,
            header.backend
        )));
    }
    if header.scene_digest != scene_digest(scene) {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` belongs to scene `{}` (digest {:016x}), not to this scene `{}` (digest {:016x}): a resumed run must use the very scene it started with",
            path.display(),
            header.scene,
            header.scene_digest,
            scene.name,
            scene_digest(scene)
        )));
    }
    codec(limit)
        .deserialize_from(&mut cursor)
        .map_err(|_| not_ours())
}
