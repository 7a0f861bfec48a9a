//! The signals that stop `powder run` gracefully: Ctrl-C, and SIGTERM and SIGHUP, which
//! batch schedulers, `timeout`, `docker stop` and a closed terminal send. The run writes a
//! last checkpoint and exits with 128 + the signal's number, as shells report it.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering::Relaxed};
use std::sync::{Arc, OnceLock};

/// The run loop's stop flag, set by the thread that takes the signals.
static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
/// The first stop signal received (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);
/// Whether the run has begun (its set-up done): before, a stop signal ends the process at
/// once, as it would without powder's handling (nothing has run that a checkpoint keeps;
/// folders the run created stay, empty, and one arriving just as the run begins may still
/// end it before its first step).
static RUNNING: AtomicBool = AtomicBool::new(false);

/// SIGINT's number where the platform has no others: the status a stopped run exits with.
const SIGINT: i32 = 2;

/// Routes the stop signals to `flag`, which the run loop reads after each chunk, once the
/// run has begun ([`running`]); before, a signal takes its default action. Called before
/// any other thread exists: the signals are blocked in every thread (the pools' and the GPU
/// driver's inherit the mask), so none is interrupted in a system call, and one thread
/// takes them with `sigwait`. A signal the process was started ignoring (SIGHUP under
/// `nohup`, SIGINT in a background job of a script) stays ignored.
pub(crate) fn install(flag: Arc<AtomicBool>) {
    if FLAG.set(flag).is_err() {
        return;
    }
    #[cfg(unix)]
    // SAFETY: sigaction, sigset and pthread_sigmask calls with valid pointers.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            let mut old: libc::sigaction = std::mem::zeroed();
            if libc::sigaction(sig, std::ptr::null(), &mut old) == 0
                && old.sa_sigaction != libc::SIG_IGN
            {
                libc::sigaddset(&mut set, sig);
            }
        }
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        let taker = std::thread::Builder::new().name("stop-signals".into());
        let taken = taker.spawn(move || loop {
            let mut sig: libc::c_int = 0;
            // (a second signal while the checkpoint is written changes nothing)
            if libc::sigwait(&set, &mut sig) == 0 {
                if !RUNNING.load(Relaxed) {
                    end_by(sig);
                }
                let _ = SIGNAL.compare_exchange(0, sig, Relaxed, Relaxed);
                if let Some(flag) = FLAG.get() {
                    flag.store(true, Relaxed);
                }
            }
        });
        if taken.is_err() {
            // (no thread to take them: the signals keep their default action)
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
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

/// Marks the run begun: from now on a stop signal stops it after the current chunk.
pub(crate) fn running() {
    RUNNING.store(true, Relaxed);
}

/// Ends the process by `sig`'s default action, from the thread that takes the signals.
#[cfg(unix)]
fn end_by(sig: libc::c_int) {
    // SAFETY: signal, sigset and pthread_sigmask calls with valid pointers; raise on this
    // thread, where the signal is then unblocked.
    unsafe {
        libc::signal(sig, libc::SIG_DFL);
        let mut one: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut one);
        libc::sigaddset(&mut one, sig);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &one, std::ptr::null_mut());
        libc::raise(sig);
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
