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

/// Routes the stop signals to `flag`, which the run loop reads after each chunk. A
/// signal the process was started ignoring (SIGHUP under `nohup`, SIGINT in a background
/// job) stays ignored.
pub(crate) fn install(flag: Arc<AtomicBool>) {
    if FLAG.set(flag).is_err() {
        return;
    }
    #[cfg(unix)]
    for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        // SAFETY: sigaction with valid pointers; the handler touches atomics only.
        unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            if libc::sigaction(sig, std::ptr::null(), &mut old) != 0
                || old.sa_sigaction == libc::SIG_IGN
            {
                continue;
            }
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as *const () as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(sig, &action, std::ptr::null_mut());
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
