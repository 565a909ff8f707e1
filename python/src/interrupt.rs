//! Long calls without the GIL that Ctrl-C can still stop: the work runs on a thread of its own
//! while the calling thread waits for it, asking Python between waits whether a signal came.

use std::sync::mpsc;
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// How often a waiting call lets Python look at its signals.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` without the GIL. On a signal whose Python handler raises (KeyboardInterrupt),
/// `stop` is called, `work` is still awaited (it should end soon after `stop`), and the handler's
/// exception is returned instead of its result.
pub fn interruptible<R: Send>(
    py: Python<'_>,
    stop: impl Fn() + Sync,
    work: impl FnOnce() -> R + Send,
) -> PyResult<R> {
    py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = mpsc::channel::<()>();
            let handle = s.spawn(move || {
                let result = work();
                let _ = done.send(());
                result
            });
            let mut interrupted = None;
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Ok(()) | Err(mpsc::RecvTimeoutError::Disconnected) => break,
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                }
                if interrupted.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    stop();
                    interrupted = Some(e);
                }
            }
            let result = handle
                .join()
                .map_err(|_| PyRuntimeError::new_err("internal error: an Amorph thread panicked"));
            match interrupted {
                Some(e) => Err(e),
                None => result,
            }
        })
    })
}
