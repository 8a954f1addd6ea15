//! What the teleop tests share: a child process reaped when dropped, and a bounded wait.

use std::process::Child;
use std::time::{Duration, Instant};

/// A child process killed when dropped (the test may fail on the way).
pub struct Reap(pub Child);

impl Drop for Reap {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits up to `within` for `done`, polling every 20 ms.
pub fn wait_for(within: Duration, mut done: impl FnMut() -> bool) -> bool {
    let started = Instant::now();
    while started.elapsed() < within {
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    done()
}
