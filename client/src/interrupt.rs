//! Ctrl-C during a wait: the flag the wait polls, and the process's handler that sets it.
//!
//! A client that just exits on Ctrl-C leaves the arm moving. `armgate move`, `ik-move`, `jmove`
//! and `run` install the handler while they wait; the wait then ends with
//! [`ClientError::Interrupted`] and the command sends `ST` (unless `--no-stop-on-interrupt`).
//!
//! [`ClientError::Interrupted`]: crate::ClientError::Interrupted

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// A flag set from outside (a signal handler, another thread) that ends a wait.
#[derive(Clone, Debug, Default)]
pub struct Interrupt(Arc<AtomicBool>);

impl Interrupt {
    /// A flag that is not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the flag.
    pub fn set(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the flag is set.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

impl PartialEq for Interrupt {
    /// The same flag.
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The flag that this process's Ctrl-C handler sets. The handler is installed on the first
/// call (a process can have only one); it fails only if another handler is installed.
pub fn ctrl_c() -> Result<Interrupt, String> {
    static FLAG: OnceLock<Result<Interrupt, String>> = OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Interrupt::new();
        let handler = flag.clone();
        ctrlc::set_handler(move || handler.set())
            .map(|()| flag)
            .map_err(|e| format!("Ctrl-C handler: {e}"))
    })
    .clone()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_are_shared_by_their_clones_only() {
        let a = Interrupt::new();
        let b = a.clone();
        assert!(!b.is_set());
        a.set();
        assert!(b.is_set());
        assert_eq!(a, b);
        assert_ne!(a, Interrupt::new());
    }
}
