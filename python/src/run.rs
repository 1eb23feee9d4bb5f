//! Running a render from Python: the render goes on a thread of its own with the GIL released,
//! while the calling thread wakes every [`POLL`] to take the GIL for a moment, run Python's
//! signal handlers (so Ctrl-C raises `KeyboardInterrupt`, which sets the render's cancel flag:
//! the flag the command line's Ctrl-C sets) and call the progress callback.

use caustic::render::Meter;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::Duration;

/// How often the waiting thread looks at signals and progress.
const POLL: Duration = Duration::from_millis(50);

/// Runs `work` (which watches `cancel` and counts its work on `meter`) without the GIL. Signals
/// are checked, and `progress(done, total)` called, every `POLL` until it ends; an exception
/// from either cancels the work, waits for it to stop and is raised.
pub fn run<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    meter: &Meter,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    std::thread::scope(|scope| {
        let (done_tx, done_rx) = channel::<()>();
        // Behind a lock only to be shared with the closures that wait without the GIL.
        let done_rx = Mutex::new(done_rx);
        let worker = std::thread::Builder::new()
            .name("caustic render".into())
            .spawn_scoped(scope, move || {
                let result = work();
                let _ = done_tx.send(());
                result
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start the render thread: {e}")))?;
        let stop = |e: PyErr| {
            cancel.store(true, Ordering::SeqCst);
            // The render stops after the work in flight (tiles, a photon chunk).
            py.detach(|| worker_join(&done_rx));
            Err(e)
        };
        loop {
            let finished = py.detach(|| match done_rx.lock().unwrap_or_else(|e| e.into_inner()).recv_timeout(POLL) {
                Ok(()) | Err(RecvTimeoutError::Disconnected) => true,
                Err(RecvTimeoutError::Timeout) => false,
            });
            if finished {
                break;
            }
            if let Err(e) = py.check_signals() {
                return stop(e);
            }
            if let Some(callback) = progress
                && let Err(e) = callback.call1(meter.read())
            {
                return stop(e);
            }
        }
        let result = worker.join().map_err(|_| PyRuntimeError::new_err("the render failed with a panic"))?;
        if let Some(callback) = progress {
            callback.call1(meter.read())?;
        }
        Ok(result)
    })
}

/// Waits until the worker has said it is done (or has gone).
fn worker_join(done: &Mutex<Receiver<()>>) {
    let _ = done.lock().unwrap_or_else(|e| e.into_inner()).recv();
}
