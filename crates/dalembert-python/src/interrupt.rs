//! Work run without the GIL on a helper thread while the calling thread watches for Ctrl-C, so
//! that a long run or sweep stops within one step (the rows computed so far are kept).

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Runs `work(cancel)` and returns its result with the `KeyboardInterrupt` (or other signal
/// error) raised meanwhile, if any; `cancel` is set when one is.
pub fn run<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> T + Send) -> (T, Option<PyErr>) {
    let cancel = AtomicBool::new(false);
    std::thread::scope(|s| {
        let handle = s.spawn(|| work(&cancel));
        let mut raised = None;
        let mut wait = Duration::from_micros(50);
        while !handle.is_finished() {
            py.detach(|| std::thread::sleep(wait));
            wait = (wait * 2).min(Duration::from_millis(20));
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        }
        let value = match handle.join() {
            Ok(v) => v,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        (value, raised)
    })
}
