//! Readiness: `Starting` until the hands and models are loaded and both listeners are bound,
//! `Ready` while serving, `Draining` from the shutdown signal on. `/readyz` and the gRPC health
//! service follow it; `/healthz` (liveness) does not.

use std::sync::Arc;
use tokio::sync::watch;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadyState {
    Starting,
    Ready,
    Draining,
}

impl ReadyState {
    pub fn name(self) -> &'static str {
        match self {
            ReadyState::Starting => "starting",
            ReadyState::Ready => "ready",
            ReadyState::Draining => "draining",
        }
    }
}

/// The shared readiness flag; cheap to clone.
#[derive(Debug, Clone)]
pub struct Readiness(Arc<watch::Sender<ReadyState>>);

impl Default for Readiness {
    fn default() -> Self {
        Self::new()
    }
}

impl Readiness {
    pub fn new() -> Self {
        Self(Arc::new(watch::Sender::new(ReadyState::Starting)))
    }

    pub fn set(&self, state: ReadyState) {
        self.0.send_replace(state);
    }

    pub fn state(&self) -> ReadyState {
        *self.0.borrow()
    }

    pub fn is_ready(&self) -> bool {
        self.state() == ReadyState::Ready
    }

    /// Follows the changes (the gRPC health service mirrors them).
    pub fn subscribe(&self) -> watch::Receiver<ReadyState> {
        self.0.subscribe()
    }
}
