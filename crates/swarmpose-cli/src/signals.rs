//! SIGINT and SIGTERM as a request to stop between two work items: a long run keeps what
//! it has done, writes its summary, and exits with 130 (SIGINT) or 143 (SIGTERM).

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use signal_hook::consts::{SIGINT, SIGTERM};

/// The signal received so far (0 for none).
#[derive(Debug, Clone)]
pub struct StopRequest(Arc<AtomicUsize>);

impl StopRequest {
    /// Registers SIGINT and SIGTERM; if they cannot be registered, the default action
    /// (ending the process) stays.
    #[must_use]
    pub fn install() -> Self {
        let flag = Arc::new(AtomicUsize::new(0));
        for sig in [SIGINT, SIGTERM] {
            let _ = signal_hook::flag::register_usize(sig, Arc::clone(&flag), sig as usize);
        }
        Self(flag)
    }

    /// The exit status for the signal received (128 + its number), if one was.
    #[must_use]
    pub fn exit_status(&self) -> Option<u8> {
        match self.0.load(Ordering::Relaxed) {
            0 => None,
            sig => Some(128u8.saturating_add(u8::try_from(sig).unwrap_or(127))),
        }
    }

    /// The signal's name, if one was received.
    #[must_use]
    pub fn name(&self) -> Option<&'static str> {
        match self.0.load(Ordering::Relaxed) {
            0 => None,
            s if s == SIGINT as usize => Some("SIGINT"),
            _ => Some("SIGTERM"),
        }
    }
}
