//! What the receiving thread and the engine share: the pairing state, a condition
//! variable signalled when a pair is ready, and the stop request (SIGINT, SIGTERM).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use signal_hook::consts::{SIGINT, SIGTERM};

use crate::intake::Intake;

/// The shared state.
#[derive(Debug, Default)]
pub struct Shared {
    intake: Mutex<Intake>,
    ready: Condvar,
    signal: Arc<AtomicUsize>,
    closing: AtomicBool,
}

impl Shared {
    /// With SIGINT and SIGTERM registered as a stop request (if they cannot be, their
    /// default action stays).
    #[must_use]
    pub fn with_signals() -> Arc<Self> {
        let s = Self::default();
        for sig in [SIGINT, SIGTERM] {
            let _ = signal_hook::flag::register_usize(sig, Arc::clone(&s.signal), sig as usize);
        }
        Arc::new(s)
    }

    /// The pairing state (a poisoned lock is taken over: the state is plain counts and
    /// queues).
    pub fn intake(&self) -> MutexGuard<'_, Intake> {
        self.intake
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Wakes the engine: a pair is ready, or the node stops.
    pub fn notify(&self) {
        self.ready.notify_all();
    }

    /// Waits at most `timeout` for [`Shared::notify`] with the state locked by `guard`.
    pub fn wait<'a>(
        &self,
        guard: MutexGuard<'a, Intake>,
        timeout: Duration,
    ) -> MutexGuard<'a, Intake> {
        match self.ready.wait_timeout(guard, timeout) {
            Ok((g, _)) => g,
            Err(p) => p.into_inner().0,
        }
    }

    /// The name of the signal that asked the node to stop, if one did.
    #[must_use]
    pub fn stopped_by(&self) -> Option<&'static str> {
        match self.signal.load(Ordering::Relaxed) {
            0 => None,
            s if s == SIGINT as usize => Some("SIGINT"),
            _ => Some("SIGTERM"),
        }
    }

    /// Tells the receiving thread to end (the engine has stopped).
    pub fn stop_receiving(&self) {
        self.closing.store(true, Ordering::Relaxed);
    }

    /// Whether the receiving thread goes on: no signal, and the engine has not stopped.
    #[must_use]
    pub fn receiving(&self) -> bool {
        self.stopped_by().is_none() && !self.closing.load(Ordering::Relaxed)
    }
}
