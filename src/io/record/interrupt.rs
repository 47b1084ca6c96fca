//! Ctrl-C handling: the first SIGINT, SIGTERM or SIGHUP (Ctrl-C, `timeout`, a batch scheduler's
//! cancellation, a closed terminal) sets a flag that drivers poll at step boundaries
//! ([`interrupted`]): the run stops there, writes its summary and finishes its logs, and exits
//! with status 130. A second signal exits at once with status 130.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static SIGNALS: AtomicUsize = AtomicUsize::new(0);

/// Whether an interrupt was requested (Ctrl-C or [`request_interrupt`]).
#[inline]
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// Request an interrupt (as Ctrl-C does); for tests and embedding applications.
pub fn request_interrupt() {
    INTERRUPTED.store(true, Ordering::Relaxed);
}

/// Clear the flag (for tests that run several drivers in one process).
pub fn clear_interrupt() {
    INTERRUPTED.store(false, Ordering::Relaxed);
}

/// Install the Ctrl-C handler (once per process; later calls do nothing).
pub fn install_interrupt_handler() {
    static INSTALLED: AtomicBool = AtomicBool::new(false);
    if INSTALLED.swap(true, Ordering::SeqCst) {
        return;
    }
    let r = ctrlc::set_handler(|| {
        if SIGNALS.fetch_add(1, Ordering::SeqCst) >= 1 {
            eprintln!("\ntread: interrupted again: exiting without finishing the logs");
            std::process::exit(130);
        }
        eprintln!(
            "\ntread: interrupt (SIGINT/SIGTERM): stopping at the next step boundary (again to abort)"
        );
        request_interrupt();
    });
    if let Err(e) = r {
        eprintln!("tread: warning: cannot install the Ctrl-C handler: {e}");
    }
}
