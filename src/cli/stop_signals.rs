//! The signals that stop `powder run` gracefully: Ctrl-C, and SIGTERM and SIGHUP, which
//! batch schedulers, `timeout`, `docker stop` and a closed terminal send. The run writes a
//! last checkpoint and exits with 128 + the signal's number, as shells report it.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering::Relaxed};
use std::sync::{Arc, OnceLock};

/// The run loop's stop flag, set by the handler.
static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
/// The first stop signal received (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// SIGINT's number where the platform has no others: the status a stopped run exits with.
const SIGINT: i32 = 2;

#[cfg(unix)]
extern "C" fn on_signal(sig: libc::c_int) {
    // (atomics only: async-signal-safe; a second signal while the checkpoint is written
    // changes nothing)
    let _ = SIGNAL.compare_exchange(0, sig, Relaxed, Relaxed);
    if let Some(flag) = FLAG.get() {
        flag.store(true, Relaxed);
    }
}

/// Routes the stop signals to `flag`, which the run loop reads after each chunk.
pub(crate) fn install(flag: Arc<AtomicBool>) {
    if FLAG.set(flag).is_err() {
        return;
    }
    #[cfg(unix)]
    for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        // SAFETY: the handler touches atomics only.
        unsafe {
            libc::signal(sig, on_signal as *const () as libc::sighandler_t);
        }
    }
    #[cfg(not(unix))]
    if let Some(flag) = FLAG.get().cloned() {
        let _ = ctrlc::set_handler(move || {
            let _ = SIGNAL.compare_exchange(0, SIGINT, Relaxed, Relaxed);
            flag.store(true, Relaxed);
        });
    }
}

/// The exit status of a run a signal stopped: 128 + its number (130 for Ctrl-C).
pub(crate) fn exit_status() -> u8 {
    let sig = match SIGNAL.load(Relaxed) {
        0 => SIGINT,
        s => s,
    };
    u8::try_from(128 + sig).unwrap_or(128 + SIGINT as u8)
}
