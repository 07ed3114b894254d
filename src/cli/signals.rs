//! SIGINT, SIGTERM and SIGHUP end a run cleanly: the signal is only noted, and the run
//! stops at the end of the step under way, saves a checkpoint, flushes its outputs and
//! exits with 128 + the signal's number (130, 143, 129), saying that `dda resume`
//! continues it. Batch schedulers send SIGTERM some time before they kill. A second
//! signal while the first is being handled ends the process at once, with the same
//! code; the checkpoint of the run's last `--checkpoint-every` remains.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The signals that end a run cleanly.
#[cfg(unix)]
const SIGNALS: [i32; 3] = [
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGTERM,
    signal_hook::consts::SIGHUP,
];
#[cfg(not(unix))]
const SIGNALS: [i32; 2] = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];

/// Noted signals (none for the default, which watches none).
#[derive(Clone, Debug, Default)]
pub struct Signals {
    caught: Arc<AtomicUsize>,
}

impl Signals {
    /// Installs the handlers. If they cannot be installed the run goes on without them
    /// (the signals then end it at once, as before), and says so.
    pub fn install() -> Signals {
        let caught = Arc::new(AtomicUsize::new(0));
        let armed = Arc::new(AtomicBool::new(false));
        for sig in SIGNALS {
            // The order matters: the shutdown runs only when an earlier signal armed it.
            let installed = signal_hook::flag::register_conditional_shutdown(
                sig,
                128 + sig,
                Arc::clone(&armed),
            )
            .and_then(|_| signal_hook::flag::register(sig, Arc::clone(&armed)))
            .and_then(|_| {
                signal_hook::flag::register_usize(sig, Arc::clone(&caught), sig as usize)
            });
            if let Err(e) = installed {
                eprintln!("warning: cannot handle signal {sig} ({e}); it will end the run at once");
            }
        }
        Signals { caught }
    }

    /// The signal received so far, if any.
    pub fn caught(&self) -> Option<i32> {
        match self.caught.load(Ordering::SeqCst) {
            0 => None,
            s => Some(s as i32),
        }
    }
}

/// The name of signal `sig`, for messages.
pub fn name(sig: i32) -> &'static str {
    match sig {
        signal_hook::consts::SIGINT => "SIGINT",
        signal_hook::consts::SIGTERM => "SIGTERM",
        #[cfg(unix)]
        signal_hook::consts::SIGHUP => "SIGHUP",
        _ => "a signal",
    }
}
