//! The GPU engine: the time step of `shaders/step/` driven from the host, for every
//! contact law the scene composes (`gpu::composition`), with walls, gravity and pouring.
//!
//! The particle state lives in one buffer set in the order of the last neighbour-list
//! rebuild. A step drifts it and asks on the device whether a rebuild is due (some particle
//! moved more than half the Verlet skin, [`SKIN`]·r_min); if so the batch halts there and
//! the host runs that step again with the rebuild recorded (grid sort, re-sort in place,
//! new lists, history remapped by persistent id). Then the forces and the kicks. Many steps go into
//! one submission; the host reads back a small monitor per batch. Every run is bitwise
//! deterministic. How the step works and why: `docs/architecture.md`.
//!
//! The files: `build` (an engine for a scene) with `program` (what its shaders are
//! compiled from), `initial` (the first state), `bind` (bind groups), `f32_range` (scene
//! values f32 cannot hold); `allocator` (buffers within the adapter's limits), `state_set`
//! (the particle state and list entries), `buffers` (the step's other buffers, the new
//! lists), `capacity` (the lists' size and windows, growing them); `dispatch` (workgroup
//! counts); `record` (a step's passes, a batch); `stepping` (running steps, halts, quiet
//! batches); `walls` (walls, pouring); `readback`, `checkpoint`, `introspection` (sizes,
//! kernels, traffic, pass profile).

use crate::cpu::{ContactStats, Energies, Partner};
use crate::error::PowderError;
use crate::gpu::composition::{Composition, Keeps};
use crate::gpu::context::GpuContext;
use crate::gpu::control::*;
use crate::gpu::grid::GridSort;
use crate::gpu::kernel::{
    read_joined, storage_buffer, submit_and_read, u32s, uniform_buffer, whole, Kernel, Part,
    Program,
};
use crate::gpu::layout::{encode3, gpu_cell_width, HystereticPair, JkrPair, StepParams, WallGpu};
use crate::gpu::mirror::Mirrors;
use crate::gpu::pages::{Pages, MIN_PAGE_WINDOWS};
use crate::gpu::permute::{self, Field, Permutation, ROW_WORDS};
use crate::gpu::quiet::{Forecast, QuietBatches};
use crate::gpu::records::{RecordLayout, WALL_ENTRY};
use crate::gpu::scan::ExclusiveScan;
use crate::gpu::state::{Buffer, StateLayout, NOT_APPEARED};
use crate::gpu::timestamps::{PassClock, PassProfile};
use crate::gpu::traffic::{PassTraffic, When};
use crate::gpu::window::{Blocks, Paged, WindowBindings, Windows, MIN_WINDOW};
use crate::model::{ContactHistory, ContactModel, PairGeometry};
use crate::output::contacts::{ContactLine, ContactNetwork};
use crate::scene::{Scene, WallPhase};
use crate::setup::Resolved;
use glam::DVec3;

mod allocator;
mod bind;
mod buffers;
mod build;
mod capacity;
mod checkpoint;
mod dispatch;
mod f32_range;
mod initial;
mod introspection;
mod program;
mod readback;
mod record;
mod state_set;
mod stepping;
mod walls;

use allocator::*;
use bind::*;
use buffers::*;
use capacity::*;
use dispatch::Dispatches;
use f32_range::check_f32_range;
use initial::*;
use program::*;
use readback::*;
use record::*;
use state_set::*;
use stepping::*;
use walls::*;

pub use checkpoint::GpuSavedState;
pub use record::RebuildChain;

/// The Verlet skin in units of the smallest radius: lists hold the pairs within
/// r_i + r_j + reach + skin, rebuilt once some particle has moved more than skin/2.
pub const SKIN: f64 = 0.1;

/// The neighbour lists' first capacity, entries a particle (+256): the first rebuild
/// grows them to what it needs (`GpuEngine::grow_lists`).
const INITIAL_ENTRIES_PER_PARTICLE: u64 = 2;

/// Headroom of a grown capacity over what a rebuild needed (less where the entries'
/// binding limit leaves less).
const LIST_HEADROOM: f64 = 1.25;

/// Steps recorded into one submission.
pub const STEPS_PER_SUBMIT: u64 = 64;

/// Steps between rebuilds, on average, below which the steps record the rebuild's passes
/// in every step though [`RebuildChain::OnDemand`] is asked for (each halt costs a
/// submission and records the batch's rest again; bitwise the same run either way).
const MIN_LEAN_STEPS: u64 = 8;

/// List entries a particle the automatic windows leave room for (the lists hold 3.7–3.8 a
/// particle with their headroom and wall entries on the dense bench packings, `powder
/// bench`).
const WINDOW_ENTRIES_PER_PARTICLE: u64 = 6;

/// A snapshot read back from the device, in the scene's particle order.
#[derive(Clone, Debug)]
pub struct GpuState {
    /// Particle centres, m (f32 on the device, widened to f64).
    pub positions: Vec<DVec3>,
    /// Particle velocities, m/s (f32 on the device, widened to f64).
    pub velocities: Vec<DVec3>,
    /// Angular velocities; empty when the scene does not rotate (as
    /// `CpuEngine::angular_velocities`).
    pub angular_velocities: Vec<DVec3>,
}

/// One contact's history keyed by (particle, partner) persistent ids.
pub type KeyedHistory = ((u32, u32), ContactHistory);

/// Choices of a GPU run that are not part of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuOptions {
    /// Keep the energy ledger and contact statistics on the device
    /// ([`GpuEngine::energies`], [`GpuEngine::contact_stats`], [`GpuEngine::wall_forces`]):
    /// its memory a particle: `docs/gpu_rebuild.md`, *Where it stands*.
    /// Default on; `powder run --no-ledger` turns it off.
    pub ledger: bool,
    /// Quiet batches (`gpu::quiet`): batches recorded without the per-step rebuild
    /// decision where no rebuild is expected, run again with it where one was needed.
    /// Results are bitwise the same either way. Default [`QuietBatches::Auto`].
    pub quiet: QuietBatches,
    /// The neighbour lists' first capacity, entries a window (all entries with one
    /// window; default: a guess the first rebuild
    /// grows to 1.25× what it needs). Lists grow whenever a rebuild needs more — the batch
    /// halts at that rebuild and finishes after the growth, bitwise as without it — so
    /// this only saves those halts where the need is known.
    pub list_entries: Option<u64>,
    /// The software adapter's paths: the state read through texture mirrors, and quiet
    /// batches under [`QuietBatches::Auto`] (`None`: by the adapter kind,
    /// `GpuContext::is_software`). Results are bitwise the same either way.
    pub software_paths: Option<bool>,
    /// Particles a window holds (`gpu::window`: a power of two; every array blocked by
    /// window), `None` for one window holding all. Results are bitwise the same either
    /// way; more windows take more list entries (each window's block is sized for the
    /// fullest).
    pub window_particles: Option<u64>,
    /// Keep what [`GpuEngine::contact_network`] reads (each contact's prior) where neither
    /// the ledger nor the force jumps keep it: 12 bytes a list entry, and as much or more
    /// in the rebuild's new lists (about 24–32 bytes a list entry in all). Default off;
    /// `powder run` turns it on for the scene's `contact_output`.
    pub contacts: bool,
    /// The largest buffer the lists' entries take (bytes; default: the adapter's largest
    /// buffer): beyond it they are cut into pages of whole windows, each bound whole
    /// (`gpu::pages`; windows are then needed). Results are bitwise the same either way.
    pub entry_page_bytes: Option<u64>,
    /// The largest buffer each of the particle state's two takes (bytes; default: the
    /// adapter's largest buffer): beyond it both are cut into pages of whole windows
    /// likewise. Results are bitwise the same either way.
    pub state_page_bytes: Option<u64>,
    /// How the steps hold a rebuild of the neighbour lists ([`RebuildChain`]; default
    /// on demand). Results are bitwise the same either way.
    pub rebuild_chain: RebuildChain,
}

impl Default for GpuOptions {
    fn default() -> Self {
        Self {
            ledger: true,
            quiet: QuietBatches::Auto,
            list_entries: None,
            software_paths: None,
            window_particles: None,
            contacts: false,
            entry_page_bytes: None,
            state_page_bytes: None,
            rebuild_chain: RebuildChain::OnDemand,
        }
    }
}

/// The GPU simulation of one scene.
pub struct GpuEngine {
    /// Simulated time, s (kept in f64 on the host; read with `time()`).
    pub(crate) time: f64,
    /// Steps taken.
    pub(crate) steps: u64,
    dt: f64,
    /// The time-step rule dt was checked against (default, limit, reason).
    time_step: crate::model::TimeStep,
    /// The digests of the scene's parts it was built from (`checkpoint::run_digests`).
    scene_parts: Vec<(String, u64)>,
    n: u32,
    /// Entries the neighbour lists have room for (grown when a rebuild needs more).
    entries: u64,
    /// The largest buffer of entries before pages ([`entry_buffer_limit`]).
    largest_entries: u64,
    /// What the step's program is compiled from (again where the entries go into pages).
    spec: StepSpec,
    origin: DVec3,
    /// Cell width per axis (the f32 values the kernels use), m.
    h: DVec3,
    radius: Vec<f64>,
    mass: Vec<f64>,
    grid: GridSort,
    /// The grid sort's key pass bound to A's cells (made once: the buffer never changes).
    /// The grid sort's `cell_keys` bind groups, one a window.
    grid_keys: Vec<wgpu::BindGroup>,
    /// The windows and their uniforms (`gpu::window`).
    windowing: WindowBindings,
    /// The state (A).
    state: StateSet,
    /// Texture copies of A's cells, offsets and predictions for the force pass.
    mirrors: Mirrors,
    /// Quiet batches, where the scene allows them (no moving walls, no pouring).
    quiet: Option<Quiet>,
    /// The lists a rebuild builds (B; bound in the kernels, never read by the host).
    _new_lists: NewLists,
    /// A rebuild's in-place re-sort of the state.
    permutation: Permutation,
    /// The step's other buffers.
    b: StepBuffers,
    /// Where the indirect dispatches' arguments lie in `b.args`.
    dispatch: Dispatches,
    /// A halted batch's remaining steps, the first without its drift (`run_steps`).
    resume: Option<u64>,
    /// The pass profile's timestamps while it runs ([`GpuEngine::profile`]).
    clock: Option<PassClock>,
    /// Times the lists grew (each a halted batch, or the first build).
    growths: u64,
    /// How the steps hold a rebuild, and the batches halted for one (`decide_lean`).
    rebuild_chain: RebuildChain,
    lean_halts: u64,
    /// Whether the next batch's steps are recorded lean (on demand, while rebuilds are
    /// rarer than one in `MIN_LEAN_STEPS` steps), and the rebuilds the last batch ended at.
    lean: bool,
    rebuilds_seen: u64,
    program: Program,
    bound: Bound,
    max_per_dim: u32,
    kind: Composition,
    /// What the step variant keeps beyond the forces (ledger, force jumps).
    keeps: Keeps,
    n_walls: u32,
    /// (name, bytes) of every buffer allocated for the run.
    buffers: Vec<(String, u64)>,
    gravity: DVec3,
    /// Engaged contacts that left the neighbour lists within one step (`CONTROL_DROPPED`).
    dropped: u64,
    /// Deepest overlap/a12 since the run monitor last looked, and a particle with a
    /// contact beyond `run::MAX_OVERLAP_RATIO` if any (`CONTROL_PEAK_OVERLAP`, `CONTROL_OVERLAP_PARTICLE`).
    peak: Option<(f64, Option<usize>)>,
    /// A particle whose centre left the domain box (`CONTROL_ESCAPED_PARTICLE`).
    escaped: Option<usize>,
    /// A rebuild's scans of the new lists' lengths into their first entries (the pair
    /// lists', `lower`'s), dispatched indirectly from `args` at `dispatch.scans`.
    /// Two a window, in window order (`lower`'s after each window's pair lists').
    scans: Vec<ExclusiveScan>,
    /// Unit normals of the walls (into the domain).
    wall_normals: Vec<DVec3>,
    /// How each wall moves, and the walls on the device (they move: state).
    wall_motion: Vec<crate::scene::WallMotion>,
    /// The phase (`WallMotion::index_at`) each wall is in on the device.
    wall_phase: Vec<Option<usize>>,
    /// The prescribed walls' points in f64, integrated on the host (v·dt per step, as the
    /// CPU does) and written to the device at every batch, so f32 rounding of the device's
    /// per-step moves never accumulates.
    wall_points: Vec<DVec3>,
    /// Pouring: when each particle (persistent id) appears, whether it has (mirrored in
    /// the device's `active` buffer, written at the batch where that changes), the energy
    /// it brings (½mv² − m·g·x at its insertion, which it keeps until then) and the sum
    /// brought so far.
    insert_at: Vec<f64>,
    active: Vec<bool>,
    insert_energy: Vec<f64>,
    inserted: f64,
    /// Last: the buffers and pipelines above drop first, so the device goes with it (one
    /// thread at a time creates or destroys devices: `GpuContext`).
    ctx: GpuContext,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::{self, wgsl_u32_const};

    #[test]
    fn gpu_control_layout_matches_wgsl() {
        let (module, _) = shaders::validate(&shaders::step_variant().source).unwrap();
        let (_, control) = module
            .global_variables
            .iter()
            .find(|(_, g)| g.name.as_deref() == Some("control"))
            .expect("the step declares `control`");
        let bytes = module.types[control.ty].inner.size(module.to_ctx());
        assert_eq!(bytes as u64, CONTROL_BYTES);
        assert_eq!(
            wgsl_u32_const(&module, "SKIN_MOVED") as u64 * 4,
            SKIN_OFFSET
        );
    }

    /// The software adapter's context, or `None` outside CI where there is none (CI needs
    /// one: lavapipe).
    fn context() -> Option<GpuContext> {
        match GpuContext::new() {
            Ok(ctx) => Some(ctx),
            Err(e) if std::env::var_os("CI").is_none() => {
                eprintln!("skipping: {e}");
                None
            }
            Err(e) => panic!("CI needs a GPU adapter (lavapipe): {e}"),
        }
    }

    /// A state saved before the ledger's rows joined the particle state (a
    /// `particle_ledger` buffer of its own) is refused by name, before anything changes.
    #[test]
    fn gpu_a_state_with_the_old_ledger_buffer_is_refused() {
        let Some(ctx) = context() else { return };
        let scene =
            crate::measure::bench::packing(crate::measure::bench::Case::Hysteretic, 64, 1.0, 1)
                .unwrap();
        let mut engine = GpuEngine::new(&scene, ctx).unwrap();
        let mut saved = engine.save_state().unwrap();
        assert!(saved.has_ledger());
        saved.ledger = false;
        saved
            .buffers
            .push(("particle_ledger".into(), vec![0; 64 * 64]));
        assert!(saved.has_ledger());
        let err = engine.restore_state(saved).unwrap_err().to_string();
        assert!(err.contains("`particle_ledger`"), "{err}");
        let ok = engine.save_state().unwrap();
        engine.restore_state(ok).unwrap();
    }

    /// A saved state whose appeared flags do not fit the scene's pouring (an edited
    /// checkpoint), or with another number of walls, is refused before anything changes.
    #[test]
    fn gpu_a_state_whose_appearances_do_not_fit_the_pouring_is_refused() {
        let Some(ctx) = context() else { return };
        let (scene, dt) = crate::cpu::engine::tests::poured_packing();
        let mut a = GpuEngine::new(&scene, ctx.clone()).unwrap();
        a.run_steps(45).unwrap();
        let mut b = GpuEngine::new(&scene, ctx).unwrap();
        let early = (0..scene.particles.len())
            .find(|&i| scene.particles[i].insert_at > 50.0 * dt)
            .unwrap();
        let mut bad = a.save_state().unwrap();
        bad.active[early] = true;
        let err = b.restore_state(bad).unwrap_err().to_string();
        assert!(
            err.contains(&format!("particle {early} appeared after 45 steps")),
            "{err}"
        );
        let mut bad = a.save_state().unwrap();
        bad.active.iter_mut().for_each(|x| *x = false);
        let err = b.restore_state(bad).unwrap_err().to_string();
        assert!(err.contains("particle 0 not yet appeared"), "{err}");
        let mut bad = a.save_state().unwrap();
        bad.wall_points.pop();
        let err = b.restore_state(bad).unwrap_err().to_string();
        assert!(err.contains("walls but the scene has"), "{err}");
        assert_eq!(b.steps(), 0);
        b.restore_state(a.save_state().unwrap()).unwrap();
        a.run_steps(60).unwrap();
        b.run_steps(60).unwrap();
        let (sa, sb) = (a.state().unwrap(), b.state().unwrap());
        assert_eq!(sa.positions, sb.positions);
        assert_eq!(sa.velocities, sb.velocities);
    }
}
