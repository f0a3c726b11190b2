//! Ctrl-C and panics at the door to Python.
//!
//! Python's SIGINT handler only sets a flag; `KeyboardInterrupt` is raised when the main thread
//! next checks it (`Python::check_signals`). Engine code runs with the GIL released, so it checks
//! itself: [`SignalWatch`] for work on the calling thread (a run, field values), [`interruptible`]
//! for work on a thread pool (a sweep, a benchmark), whose threads cannot receive signals.
//! [`no_panic`] turns a panic (a bug) into a `RuntimeError` that says so, never a
//! `PanicException` (a `BaseException` that `except Exception` does not catch).

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

/// How often engine code asks Python for pending signals: well under the "fraction of a
/// second" a Ctrl-C may take, well over the cost of taking the GIL (about a microsecond).
const SIGNAL_PERIOD: Duration = Duration::from_millis(20);

/// Polls Python's signal handlers from engine code on the calling thread, at most every
/// [`SIGNAL_PERIOD`]; keeps the first exception (`KeyboardInterrupt`) they raise.
pub(crate) struct SignalWatch {
    last: Instant,
    calls: u32,
    stride: u32,
    /// The exception a signal handler raised.
    pub(crate) error: Option<PyErr>,
}

impl SignalWatch {
    /// A watch for calls a few microseconds apart (a run's samples): the clock is read every
    /// 64 calls.
    pub(crate) fn new() -> Self {
        Self::reading_the_clock_every(64)
    }

    /// A watch that reads the clock every `stride` calls (1 for calls a millisecond apart).
    pub(crate) fn reading_the_clock_every(stride: u32) -> Self {
        Self {
            last: Instant::now(),
            calls: 0,
            stride: stride.max(1),
            error: None,
        }
    }

    /// Whether to go on: `false` once a signal handler raised (the exception is kept). Cheap:
    /// the clock is read every `stride` calls, the GIL taken every [`SIGNAL_PERIOD`].
    pub(crate) fn keep_going(&mut self) -> bool {
        if self.error.is_some() {
            return false;
        }
        self.calls = self.calls.wrapping_add(1);
        if !self.calls.is_multiple_of(self.stride) || self.last.elapsed() < SIGNAL_PERIOD {
            return true;
        }
        self.last = Instant::now();
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(e);
                false
            }
        }
    }
}

/// Runs `work` on a helper thread, the GIL released, while this thread answers signals every
/// [`SIGNAL_PERIOD`]: on `KeyboardInterrupt` (or any exception a handler raises) it sets
/// `cancel`, waits for `work` to notice and return, and raises the exception. A panic in `work`
/// is a `RuntimeError`.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    interruptible_ticking(py, cancel, work, &mut |_| Ok(()))
}

/// [`interruptible`], calling `tick` on this thread (the GIL held) every [`SIGNAL_PERIOD`] while
/// `work` runs and once when it has returned (a progress display); an exception `tick` raises
/// stops `work` as a `KeyboardInterrupt` does, and is raised.
pub(crate) fn interruptible_ticking<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
    tick: &mut dyn FnMut(Python<'_>) -> PyResult<()>,
) -> PyResult<T> {
    let mut interrupted: Option<PyErr> = None;
    // `done` is set (and the condition variable notified) when `work` has returned.
    let done = (Mutex::new(false), Condvar::new());
    let outcome = std::thread::scope(|scope| {
        let handle = scope.spawn(|| {
            let r = catch_unwind(AssertUnwindSafe(work));
            let (flag, cv) = &done;
            *flag.lock().unwrap_or_else(|p| p.into_inner()) = true;
            cv.notify_all();
            r
        });
        loop {
            let finished = py.detach(|| {
                let (flag, cv) = &done;
                let guard = flag.lock().unwrap_or_else(|p| p.into_inner());
                let (guard, _) = cv
                    .wait_timeout_while(guard, SIGNAL_PERIOD, |finished| !*finished)
                    .unwrap_or_else(|p| p.into_inner());
                *guard
            });
            if interrupted.is_none() {
                if let Err(e) = py.check_signals().and_then(|()| tick(py)) {
                    cancel.store(true, Ordering::Relaxed);
                    interrupted = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        py.detach(|| handle.join())
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    match outcome {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(panic)) | Err(panic) => Err(panic_error(panic.as_ref())),
    }
}

/// Runs `f`, a panic in it becoming a `RuntimeError` (with the panic's message).
pub(crate) fn no_panic<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| Err(panic_error(p.as_ref())))
}

fn panic_error(payload: &(dyn std::any::Any + Send)) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    PyRuntimeError::new_err(format!(
        "internal error in isotrack (a bug: please report it with the call that caused it): {what}"
    ))
}

/// Runs `work` on a thread of its own, the GIL released, while this thread answers signals
/// every [`SIGNAL_PERIOD`]. For pure computations that cannot be cancelled (`check`): on
/// `KeyboardInterrupt` the caller gets the exception at once and the thread finishes alone, its
/// answer dropped (it writes nothing). A panic in `work` is a `RuntimeError`.
pub(crate) fn detached<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    detached_then(py, work, || ())
}

/// [`detached`] for work that writes (`plot`, `report` into a staging directory): on
/// `KeyboardInterrupt` (or any exception a signal handler raises) `abandon` is called at once on
/// this thread, and again on the work's thread when the work ends, so that what it wrote after
/// the first call goes too. A lock orders the two: work that ends before the interrupt is
/// cleaned up by the first call, work that ends after it by the second.
pub(crate) fn detached_then<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send + 'static,
    abandon: impl Fn() + Send + Sync + 'static,
) -> PyResult<T> {
    use std::sync::mpsc::{channel, RecvTimeoutError};
    use std::sync::Arc;
    let (tx, rx) = channel();
    let abandon = Arc::new(abandon);
    let abandoned = Arc::new(Mutex::new(false));
    let (their_abandon, their_flag) = (abandon.clone(), abandoned.clone());
    std::thread::Builder::new()
        .name("isotrack-detached".into())
        .spawn(move || {
            let r = catch_unwind(AssertUnwindSafe(work));
            let gone = their_flag.lock().unwrap_or_else(|p| p.into_inner());
            if *gone {
                their_abandon();
            } else {
                let _ = tx.send(r);
            }
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
    let interrupted = |e: PyErr| {
        *abandoned.lock().unwrap_or_else(|p| p.into_inner()) = true;
        abandon();
        e
    };
    let mut rx = rx;
    loop {
        // The receiver goes to the GIL-free side and back (it is `Send`, not `Sync`).
        let (answer, back) = py.detach(move || (rx.recv_timeout(SIGNAL_PERIOD), rx));
        rx = back;
        match answer {
            Ok(Ok(v)) => return Ok(v),
            Ok(Err(panic)) => return Err(panic_error(panic.as_ref())),
            Err(RecvTimeoutError::Timeout) => py.check_signals().map_err(interrupted)?,
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "internal error in isotrack: a worker thread ended without an answer",
                ))
            }
        }
    }
}
