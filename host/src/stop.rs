//! The one SIGTERM/SIGINT stop flag of the bench processes (ECU, sensor feeds, actuator
//! stubs). Every process stops the same way: a signal sets a flag, the process's own loop
//! polls it at its next tick, finishes the tick and writes its report. Stopping from the
//! loop, not from the handler, is what lets a `kill` still produce a complete report.

use core::sync::atomic::{AtomicBool, Ordering};

use nix::sys::signal::{sigaction, SaFlags, SigAction, SigHandler, SigSet, Signal};

/// Set by the handler, polled by the process loop. One per process (a static), because
/// a signal handler receives no context pointer to reach anything else.
static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_stop_signal(_: nix::libc::c_int) {
    // Async-signal-safe: a single lock-free atomic store, nothing else (no allocation,
    // no locks, no I/O — any of those could deadlock or corrupt state if the signal
    // interrupted the same operation on the main thread).
    STOP.store(true, Ordering::Relaxed);
}

/// Installs SIGINT and SIGTERM handlers that only set the returned flag, and returns it.
///
/// The handler is async-signal-safe (one atomic store), so the signal may arrive at any
/// point of the process loop. `SA_RESTART` is deliberately not set: a blocking
/// `clock_nanosleep` is interrupted (EINTR) so the loop sees the flag promptly instead of
/// after its full sleep. Calling this again re-installs the same handlers and returns the
/// same flag. `Err` only when the kernel refuses `sigaction`.
pub fn install_stop_signals() -> Result<&'static AtomicBool, nix::Error> {
    let action = SigAction::new(
        SigHandler::Handler(on_stop_signal),
        SaFlags::empty(),
        SigSet::empty(),
    );
    for sig in [Signal::SIGINT, Signal::SIGTERM] {
        // SAFETY: the handler only performs an atomic store (async-signal-safe).
        unsafe { sigaction(sig, &action) }?;
    }
    Ok(&STOP)
}

/// SIGPIPE back to its default for a command-line tool: a closed pipe (`lut inspect … | head`)
/// ends the process quietly, as it does any Unix tool, instead of a panic in `println!`
/// (Rust ignores SIGPIPE, so a write to the closed pipe fails and `println!` panics). Not for
/// the bench processes: an ECU whose log reader went away must keep running.
pub fn default_sigpipe() {
    // SAFETY: installs the default disposition, no handler code runs.
    let _ = unsafe { nix::sys::signal::signal(Signal::SIGPIPE, SigHandler::SigDfl) };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A raised SIGTERM must set the flag and must not kill the process (which it would
    /// with the default disposition, failing the test run).
    #[test]
    fn sigterm_sets_the_flag_instead_of_terminating() {
        let stop = install_stop_signals().expect("sigaction");
        assert!(core::ptr::eq(stop, &STOP));
        nix::sys::signal::raise(Signal::SIGTERM).expect("raise");
        // raise() returns after the handler ran on this thread.
        assert!(stop.load(Ordering::Relaxed));
        // Re-installing hands back the same flag.
        assert!(core::ptr::eq(install_stop_signals().expect("again"), stop));
    }
}
