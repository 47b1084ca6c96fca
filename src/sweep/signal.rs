//! Signals for the sweep processes: SIGTERM (what Slurm sends at a time limit or on `scancel`),
//! SIGINT (Ctrl-C) and SIGHUP only set flags here; the sweep loops poll them and end cleanly.
//! (`tread run` has its own Ctrl-C handling; the sweep never installs both in one process.)

use std::sync::atomic::{AtomicI32, AtomicUsize, Ordering};

static FIRST: AtomicI32 = AtomicI32::new(0);
static COUNT: AtomicUsize = AtomicUsize::new(0);

extern "C" fn on_signal(sig: libc::c_int) {
    // Only atomics: async-signal-safe.
    let _ = FIRST.compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst);
    COUNT.fetch_add(1, Ordering::SeqCst);
}

/// Catch SIGTERM, SIGINT and SIGHUP from now on.
pub fn install() {
    let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    for sig in [libc::SIGTERM, libc::SIGINT, libc::SIGHUP] {
        // SAFETY: the handler only touches atomics; `signal` with a valid handler is sound.
        unsafe {
            libc::signal(sig, handler);
        }
    }
}

/// The first signal received, if any.
pub fn received() -> Option<i32> {
    match FIRST.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// How many signals were received.
pub fn count() -> usize {
    COUNT.load(Ordering::SeqCst)
}

/// Send `sig` to process `pid` (errors, e.g. an exited process, are ignored).
pub fn send(pid: u32, sig: i32) {
    // SAFETY: kill(2) with a positive pid has no memory-safety preconditions.
    unsafe {
        libc::kill(pid as libc::pid_t, sig);
    }
}

/// Send `sig` to process group `pgid`.
pub fn send_group(pgid: u32, sig: i32) {
    // SAFETY: as `send`; a negative pid addresses the process group.
    unsafe {
        libc::kill(-(pgid as libc::pid_t), sig);
    }
}

pub fn name(sig: i32) -> String {
    match sig {
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGINT => "SIGINT".into(),
        libc::SIGHUP => "SIGHUP".into(),
        libc::SIGKILL => "SIGKILL".into(),
        libc::SIGSEGV => "SIGSEGV".into(),
        libc::SIGABRT => "SIGABRT".into(),
        libc::SIGUSR1 => "SIGUSR1".into(),
        libc::SIGUSR2 => "SIGUSR2".into(),
        s => format!("signal {s}"),
    }
}

pub use libc::{SIGINT, SIGKILL, SIGTERM};
