//! Checkpoints: the complete evolving state of a run (CPU: [`CpuState`]; GPU: the device
//! buffers of [`GpuSavedState`]), so a run resumes bitwise identically on the same backend
//! (and, for the GPU, the same adapter).
//!
//! A checkpoint is a NumPy `.npz` archive ([`npz`]): a JSON header `powder.json` (format,
//! powder version, backend, scene and its digest, step and time), then the state as named
//! little-endian arrays ([`cpu`], [`gpu`]). `numpy.load` reads it as it is
//! (`tools/read_checkpoint.py`). It is refused for another format, version, backend or
//! scene; each member's zip CRC-32 is checked, so a damaged or cut file is refused too.
//! Written atomically.

pub mod cpu;
pub mod gpu;
pub mod npz;

use crate::cpu::{CpuEngine, CpuState};
use crate::error::PowderError;
use crate::gpu::GpuSavedState;
use crate::output::atomic::write_atomic;
use crate::output::series_csv::SeriesMark;
use crate::run::MonitorReference;
use crate::scene::{ParticleInit, Scene};
use npz::{Archive, Array, Member, NpzError};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

const MAGIC: &str = "powder-checkpoint";
/// The header's member, first in the archive.
const HEADER: &str = "powder.json";
/// What checkpoints of formats up to 16 (bincode) open with.
const BINCODE_PREFIX: &[u8; 8] = b"POWDERCK";
/// Bumped whenever the state's arrays change, or the GPU step's arithmetic does (a resume
/// continues bitwise only with the same arithmetic). The history of earlier formats is in
/// `docs/checkpoints.md`; 17: a `.npz` archive of named arrays (16 and before: bincode); 18:
/// the digest covers the run up to the checkpoint ([`run_digest`]); 19: the GPU books the
/// work of a wall sliding along its face, and the header names the scene's parts; 20: the
/// particles' digest is of their bits, not their text; 21: a contact's history keeps
/// whether Luding's sliding law slipped (`slipping`).
pub const FORMAT: u32 = 21;

/// The checkpoint's header (`powder.json`).
#[derive(Debug, Serialize, Deserialize)]
pub struct Header {
    /// `powder-checkpoint`.
    pub magic: String,
    /// [`FORMAT`] of the powder that wrote it.
    pub format: u32,
    /// The powder version that wrote it.
    pub version: String,
    /// `cpu` or `gpu`.
    pub backend: String,
    /// The scene's name.
    pub scene: String,
    /// [`run_digest`] of the scene it ran, at its time.
    pub scene_digest: u64,
    /// The digests of its parts ([`run_digests`]), to name what another scene changed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub scene_parts: Vec<(String, u64)>,
    /// Steps taken and simulated time, s (also in the state's arrays, bitwise).
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
    /// What the run keeps beside its state.
    #[serde(default)]
    pub run: RunMarks,
}

/// What a run keeps beside its state in a checkpoint's header (`run`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunMarks {
    /// The series' rows the run had written up to the checkpoint (`series.csv`; none
    /// without one), so a resume keeps only that run's rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series: Option<SeriesMark>,
    /// What the run monitor measures against, so a resumed run checks as the straight run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monitor: Option<MonitorReference>,
}

/// Why a checkpoint's state arrays could not be taken (a member missing or not the array
/// it should be): the checkpoint is damaged.
#[derive(Clone, Debug)]
pub struct StateError(pub String);

/// FNV-1a over what decides a run of `scene` up to time `t` (every value, exactly): the
/// scene but its name, duration and output cadences, and without the wall phases that
/// start at `t` or later. Two scenes share it only if their runs agree up to `t`, so a
/// checkpoint taken at `t` resumes under either: the same run continued or extended, or a
/// branch that changes what the walls do from `t` on (e.g. tests of one prepared sample).
pub fn run_digest(scene: &Scene, t: f64) -> u64 {
    run_digests(scene, t).0
}

/// [`run_digest`] and the digest of each part of the scene it covers, named as in the
/// scene file (`simulation.gravity`, `material 1`, `interactions`, `wall 0` with its phases
/// before `t`, `particles`, ...): a resume under another scene names the parts that differ.
pub fn run_digests(scene: &Scene, t: f64) -> (u64, Vec<(String, u64)>) {
    // every field named: a new one must be placed here (hashed, or left out on purpose)
    let Scene {
        name: _,
        domain,
        gravity,
        dt,
        force_dt,
        jump_impulses,
        duration: _,
        output_every: _,
        impact_velocity,
        checkpoint_every: _,
        contact_output,
        materials,
        interactions,
        walls,
        particles,
    } = scene;
    let past: Vec<_> = walls
        .iter()
        .map(|w| {
            let mut w = w.clone();
            w.motion.phases.retain(|(from, _)| *from < t);
            w
        })
        .collect();
    let mut h = Fnv::new();
    let mut parts = Vec::new();
    let mut part = |what: String, text: &str| {
        let mut p = Fnv::new();
        let _ = p.write_str(text);
        parts.push((what, p.0));
    };
    // (the whole run's digest streams the text as it always has, so earlier checkpoints
    // keep theirs)
    let settings = [
        ("domain", format!("{domain:?}")),
        ("simulation.gravity", format!("{gravity:?}")),
        ("simulation.dt", format!("{dt:?}")),
        ("simulation.force_dt", format!("{force_dt:?}")),
        ("simulation.jump_impulses", format!("{jump_impulses:?}")),
        ("simulation.impact_velocity", format!("{impact_velocity:?}")),
        ("simulation.contact_output", format!("{contact_output:?}")),
    ];
    for (what, text) in &settings {
        let _ = h.write_str(text);
        part(what.to_string(), text);
    }
    let _ = write!(h, "{materials:?}{interactions:?}{past:?}");
    for (i, m) in materials.iter().enumerate() {
        part(format!("material {i}"), &format!("{m:?}"));
    }
    part("interactions".into(), &format!("{interactions:?}"));
    for (i, w) in past.iter().enumerate() {
        part(format!("wall {i}"), &format!("{w:?}"));
    }
    let all = particles_digest(particles);
    let _ = write!(h, "{all:016x}");
    parts.push(("particles".into(), all));
    (h.0, parts)
}

/// A digest of the particles' bits, word by word (formatting each as text took half a
/// large run's time: the digest is taken at every checkpoint).
fn particles_digest(particles: &[ParticleInit]) -> u64 {
    // splitmix64's finaliser: every bit of a word reaches every bit of the digest
    let mix = |mut w: u64| {
        w = (w ^ (w >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        w = (w ^ (w >> 27)).wrapping_mul(0x94d049bb133111eb);
        w ^ (w >> 31)
    };
    let mut h = Fnv::new().0;
    for p in particles {
        // every field named: a new one must be hashed here
        let ParticleInit {
            position,
            velocity,
            angular_velocity,
            radius,
            material,
            insert_at,
        } = p;
        let floats =
            (position.iter().chain(velocity).chain(angular_velocity)).chain([radius, insert_at]);
        for w in floats.map(|f| f.to_bits()).chain([*material as u64]) {
            h = (h ^ mix(w)).wrapping_mul(0x100000001b3);
        }
    }
    h
}

/// What differs between the scene parts a checkpoint recorded and this scene's, as a
/// clause of the refusal (empty for a checkpoint that recorded none).
fn differing_parts(theirs: &[(String, u64)], ours: &[(String, u64)]) -> String {
    if theirs.is_empty() {
        return String::new();
    }
    let find =
        |list: &[(String, u64)], name: &str| list.iter().find(|(n, _)| n == name).map(|&(_, d)| d);
    let mut named: Vec<String> = Vec::new();
    for (name, d) in ours {
        match find(theirs, name) {
            Some(t) if t == *d => {}
            Some(_) => named.push(name.clone()),
            None => named.push(format!("{name} (not in the checkpoint's scene)")),
        }
    }
    for (name, _) in theirs {
        if find(ours, name).is_none() {
            named.push(format!("{name} (only in the checkpoint's scene)"));
        }
    }
    match named.is_empty() {
        true => String::new(),
        false => format!("; they differ in {}", named.join(", ")),
    }
}

/// FNV-1a, fed as text.
pub(crate) struct Fnv(pub(crate) u64);

impl Fnv {
    /// The hash of nothing yet.
    pub(crate) fn new() -> Self {
        Self(0xcbf29ce484222325)
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for b in s.bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x100000001b3);
        }
        Ok(())
    }
}

/// Writes the CPU engine's state to `path` (atomically), with what the run keeps beside it.
pub fn save(
    path: &Path,
    scene: &Scene,
    engine: &CpuEngine,
    run: &RunMarks,
) -> Result<(), PowderError> {
    crate::run::engine_fits(scene, engine)?;
    let state = engine.state();
    save_state(
        path,
        scene,
        "cpu",
        (state.steps, state.time),
        run,
        cpu::arrays(&state),
    )
}

/// Reads a CPU checkpoint of `scene` from `path`: the state and what its run kept beside it.
pub fn load(path: &Path, scene: &Scene) -> Result<(CpuState, RunMarks), PowderError> {
    let bytes = read(path)?;
    let (header, archive) = open(&bytes, path, scene, "cpu")?;
    let state = cpu::state(&|name| array(&archive, name)).map_err(|e| damaged(path, &e.0))?;
    same_clock(path, &header, state.steps, state.time)?;
    Ok((state, header.run))
}

/// The header's step and time against the state's (bitwise: both are written from one
/// value); the scene's digest was taken at the header's time.
fn same_clock(path: &Path, header: &Header, steps: u64, time: f64) -> Result<(), PowderError> {
    if header.steps != steps || header.time.to_bits() != time.to_bits() {
        return Err(damaged(
            path,
            &format!(
                "its header says step {} at t = {:e} s, its state step {steps} at t = {time:e} s",
                header.steps, header.time
            ),
        ));
    }
    Ok(())
}

/// Writes a saved GPU state to `path` (atomically), with what the run keeps beside it.
pub fn save_gpu(
    path: &Path,
    scene: &Scene,
    state: &GpuSavedState,
    run: &RunMarks,
) -> Result<(), PowderError> {
    if state.active.len() != scene.particles.len() || state.wall_points.len() != scene.walls.len() {
        return Err(PowderError::Run(format!(
            "the GPU state was not taken from scene `{}`: it has {} particles and {} walls, the scene {} and {}",
            scene.name,
            state.active.len(),
            state.wall_points.len(),
            scene.particles.len(),
            scene.walls.len()
        )));
    }
    let arrays = gpu::arrays(state)
        .map_err(|e| PowderError::Run(format!("cannot encode the checkpoint: {}", e.0)))?;
    save_state(path, scene, "gpu", (state.steps, state.time), run, arrays)
}

/// Reads a GPU checkpoint of `scene` from `path`: the state and what its run kept beside it.
pub fn load_gpu(path: &Path, scene: &Scene) -> Result<(GpuSavedState, RunMarks), PowderError> {
    let bytes = read(path)?;
    let (header, archive) = open(&bytes, path, scene, "gpu")?;
    let about = archive
        .raw("gpu.json")
        .ok_or_else(|| damaged(path, "`gpu.json` is missing"))?;
    let state =
        gpu::state(about, &|name| array(&archive, name)).map_err(|e| damaged(path, &e.0))?;
    same_clock(path, &header, state.steps, state.time)?;
    Ok((state, header.run))
}

/// The steps the run of the checkpoint at `path` had taken.
pub fn steps_of(path: &Path) -> Result<u64, PowderError> {
    Ok(peek_header(path)?.steps)
}

/// The name of the scene whose run wrote the checkpoint at `path`.
pub fn scene_of(path: &Path) -> Result<String, PowderError> {
    Ok(peek_header(path)?.scene)
}

/// Whether the checkpoint at `path` is intact and of `scene`'s run up to its time (what a
/// resume of it asks of the scene; the backend aside).
pub fn is_of(path: &Path, scene: &Scene) -> bool {
    read(path)
        .ok()
        .and_then(|bytes| header(&bytes, path).ok().map(|(h, _)| h))
        .is_some_and(|h| h.scene_digest == run_digest(scene, h.time))
}

/// The backend (`"cpu"` or `"gpu"`) that wrote the checkpoint at `path`.
pub fn backend_of(path: &Path) -> Result<String, PowderError> {
    Ok(peek_header(path)?.backend)
}

fn save_state(
    path: &Path,
    scene: &Scene,
    backend: &str,
    (steps, time): (u64, f64),
    run: &RunMarks,
    arrays: Vec<(String, Member)>,
) -> Result<(), PowderError> {
    let (scene_digest, scene_parts) = run_digests(scene, time);
    let header = Header {
        magic: MAGIC.into(),
        format: FORMAT,
        version: env!("CARGO_PKG_VERSION").into(),
        backend: backend.into(),
        scene: scene.name.clone(),
        scene_digest,
        scene_parts,
        steps,
        time,
        run: *run,
    };
    let json = serde_json::to_vec_pretty(&header)
        .map_err(|e| PowderError::Run(format!("cannot encode the checkpoint: {e}")))?;
    let mut members = vec![(HEADER.to_string(), Member::Raw(json))];
    members.extend(arrays);
    write_atomic(path, &npz::write(&members))
}

fn read(path: &Path) -> Result<Vec<u8>, PowderError> {
    let cannot = |e| PowderError::io(format!("cannot read checkpoint `{}`", path.display()), e);
    // (a device such as /dev/zero would be read until memory runs out)
    if !std::fs::metadata(path).map_err(cannot)?.is_file() {
        return Err(PowderError::Run(format!(
            "`{}` is not a file: a checkpoint is the checkpoint.bin a run wrote",
            path.display()
        )));
    }
    std::fs::read(path).map_err(cannot)
}

fn not_a_checkpoint(path: &Path) -> PowderError {
    PowderError::Run(format!(
        "`{}` is not a powder checkpoint (or is truncated)",
        path.display()
    ))
}

fn other_format(path: &Path, version: &str, format: Option<u64>) -> PowderError {
    let format = format.map_or("an unknown format".to_string(), |f| format!("format {f}"));
    PowderError::Run(format!(
        "checkpoint `{}` was written by powder {version} ({format}); this is powder {} (format {FORMAT}): rerun the scene from the start",
        path.display(),
        env!("CARGO_PKG_VERSION")
    ))
}

fn damaged(path: &Path, what: &str) -> PowderError {
    PowderError::Run(format!(
        "checkpoint `{}` is damaged or truncated ({what}): resume from an earlier copy or rerun the scene",
        path.display()
    ))
}

/// Whether `bytes` open as a powder checkpoint archive: a zip whose first member is the
/// header (so a cut or damaged one is told apart from another file).
fn opens_as_ours(bytes: &[u8]) -> bool {
    let name = HEADER.as_bytes();
    bytes.starts_with(b"PK\x03\x04") && bytes.get(30..30 + name.len()) == Some(name)
}

/// The archive of `bytes` and its header.
fn header<'a>(bytes: &'a [u8], path: &Path) -> Result<(Header, Archive<'a>), PowderError> {
    if bytes.starts_with(BINCODE_PREFIX) {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` was written by an older powder (format 16 or earlier, bincode); this is powder {} (format {FORMAT}): rerun the scene from the start",
            path.display(),
            env!("CARGO_PKG_VERSION")
        )));
    }
    let archive = match Archive::read(bytes) {
        Ok(a) => a,
        Err(NpzError::Damaged(member)) => {
            return Err(damaged(
                path,
                &format!("`{member}` does not match its checksum"),
            ))
        }
        Err(_) if opens_as_ours(bytes) => {
            return Err(damaged(path, "its zip directory is missing or broken"))
        }
        Err(_) => return Err(not_a_checkpoint(path)),
    };
    let raw = archive.raw(HEADER).ok_or_else(|| not_a_checkpoint(path))?;
    Ok((parse_header(raw, path)?, archive))
}

/// The header member `raw` of the checkpoint at `path`, refused unless it is this format
/// and version's.
fn parse_header(raw: &[u8], path: &Path) -> Result<Header, PowderError> {
    // magic, format and version first, leniently: a later format's header may differ
    let json: serde_json::Value =
        serde_json::from_slice(raw).map_err(|_| not_a_checkpoint(path))?;
    if json["magic"] != MAGIC {
        return Err(not_a_checkpoint(path));
    }
    let (format, version) = (json["format"].as_u64(), json["version"].as_str());
    if format != Some(FORMAT as u64) || version != Some(env!("CARGO_PKG_VERSION")) {
        return Err(other_format(path, version.unwrap_or("?"), format));
    }
    serde_json::from_value(json).map_err(|_| not_a_checkpoint(path))
}

/// The header of the checkpoint at `path`, read alone (its first member) where it can be:
/// a large checkpoint is not read whole to learn its step, scene or backend. Otherwise the
/// whole file is read, for the error that says what is wrong with it.
fn peek_header(path: &Path) -> Result<Header, PowderError> {
    let first = std::fs::metadata(path)
        .ok()
        .filter(|m| m.is_file())
        .and_then(|_| std::fs::File::open(path).ok())
        .and_then(|f| npz::first_member(std::io::BufReader::new(f), 1 << 26));
    match first {
        Some((name, raw)) if name == HEADER => parse_header(&raw, path),
        _ => Ok(header(&read(path)?, path)?.0),
    }
}

/// The archive of `bytes`, refused unless it is this format and version's checkpoint of
/// `scene` from `backend`.
fn open<'a>(
    bytes: &'a [u8],
    path: &Path,
    scene: &Scene,
    backend: &str,
) -> Result<(Header, Archive<'a>), PowderError> {
    let (header, archive) = header(bytes, path)?;
    if header.backend != backend {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` comes from the {} backend; resume it with --backend {}",
            path.display(),
            header.backend,
            header.backend
        )));
    }
    let (digest, parts) = run_digests(scene, header.time);
    if header.scene_digest != digest {
        return Err(PowderError::Run(format!(
            "checkpoint `{}` belongs to scene `{}` (digest {:016x}), not to this scene `{}` (digest {:016x} up to t = {:e} s){}: a resumed run must use the very scene it started with, but for its duration, its output cadences and the wall phases from the checkpoint's time on",
            path.display(),
            header.scene,
            header.scene_digest,
            scene.name,
            digest,
            header.time,
            differing_parts(&header.scene_parts, &parts)
        )));
    }
    Ok((header, archive))
}

/// The array `name` of a checkpoint (missing or malformed: a [`StateError`]).
fn array(archive: &Archive, name: &str) -> Result<Array, StateError> {
    match archive.array(name) {
        Ok(Some(a)) => Ok(a),
        Ok(None) => Err(StateError(format!("the array `{name}` is missing"))),
        Err(_) => Err(StateError(format!("`{name}` is not an array"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device or a folder given as a checkpoint is refused at once (`/dev/zero` was read
    /// until memory ran out).
    #[test]
    fn a_checkpoint_that_is_not_a_file_is_refused() {
        for path in ["/dev/zero", "/tmp"] {
            let path = Path::new(path);
            if path.exists() {
                let e = read(path).unwrap_err().to_string();
                assert!(e.contains("is not a file"), "{e}");
            }
        }
        let e = read(Path::new("/no/such/checkpoint.bin"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read checkpoint"), "{e}");
    }

    /// Every field of every particle, and their order, decides the digest and its
    /// `particles` part; the other parts stay.
    #[test]
    fn every_particle_field_changes_the_digest() {
        let text = include_str!("../../examples/cohesive_cluster.toml");
        let scene = Scene::from_toml_str(text, "cluster").unwrap();
        let (digest, parts) = run_digests(&scene, 0.0);
        let edits: [&dyn Fn(&mut ParticleInit); 6] = [
            &|p| p.position[2] = f64::from_bits(p.position[2].to_bits() + 1),
            &|p| p.velocity[0] = -p.velocity[0] - 0.0,
            &|p| p.angular_velocity[1] += 1e-300,
            &|p| p.radius *= 1.0 + f64::EPSILON,
            &|p| p.material += 1,
            &|p| p.insert_at += 1e-9,
        ];
        let n = scene.particles.len();
        for (k, edit) in edits.iter().enumerate() {
            let mut changed = scene.clone();
            edit(&mut changed.particles[n - 1]);
            let (d, p) = run_digests(&changed, 0.0);
            let differ: Vec<&str> = (parts.iter().zip(&p))
                .filter(|(a, b)| a != b)
                .map(|(a, _)| a.0.as_str())
                .collect();
            assert!(
                d != digest && differ == ["particles"],
                "edit {k}: {differ:?}"
            );
        }
        let mut swapped = scene.clone();
        swapped.particles.swap(0, 1);
        assert_ne!(run_digest(&swapped, 0.0), digest);
    }
}
