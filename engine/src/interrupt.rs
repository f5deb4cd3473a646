//! Ctrl-C as a request to stop, for long runs that should end with a valid
//! result (`inlay train` writes the field it has): after
//! [`catch_interrupts`], the first SIGINT only raises a flag that
//! [`interrupted`] reads; a second ends the process at once (exit status
//! 130, as the shell's default would), for a run that does not stop.

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_interrupt(_signal: libc::c_int) {
    // Only async-signal-safe work here: an atomic store, or _exit.
    if INTERRUPTED.swap(true, Ordering::SeqCst) {
        // SAFETY: _exit is async-signal-safe and ends the process.
        unsafe { libc::_exit(130) };
    }
}

/// Installs the SIGINT handler (once per process; a no-op off Unix).
pub fn catch_interrupts() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        // SAFETY: a zeroed sigaction is a valid start; the handler is an
        // extern "C" fn that only touches an atomic or calls _exit.
        let ok = unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_interrupt as extern "C" fn(libc::c_int) as usize;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut()) == 0
        };
        if !ok {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// Whether Ctrl-C was pressed since [`catch_interrupts`].
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// A SIGINT sent to the process raises the flag instead of ending it.
    #[test]
    fn an_interrupt_raises_the_flag() {
        catch_interrupts().unwrap();
        assert!(!interrupted());
        // SAFETY: raising a signal whose handler was just installed.
        unsafe { libc::raise(libc::SIGINT) };
        assert!(interrupted());
    }
}
