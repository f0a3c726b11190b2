//! A Python object flying in place of the built-in controller.

use crate::values::shown;
use isotrack_core::{IsolineController, Measurement};
use pyo3::prelude::*;

/// A Python object as a coordinate-free controller: `update(t_s, value) -> omega`, clipped to
/// the scenario's turn-rate limit as every built-in law's output is. The first exception is kept
/// (and raised when the run returns); the run then ends as `diverged` (the command is NaN), the
/// loop's own way of stopping.
pub(crate) struct PyController {
    pub(crate) obj: Py<PyAny>,
    pub(crate) error: Option<PyErr>,
    pub(crate) max_turn_rate_radps: Option<f64>,
}

impl PyController {
    /// `obj` as a controller clipped to `max_turn_rate_radps`, `reset()` first when it has the
    /// method ([`reset_if_any`]).
    pub(crate) fn started(
        py: Python<'_>,
        obj: Py<PyAny>,
        max_turn_rate_radps: Option<f64>,
    ) -> PyResult<Self> {
        reset_if_any(py, &obj)?;
        Ok(Self {
            obj,
            error: None,
            max_turn_rate_radps,
        })
    }
}

/// Calls `obj.reset()` when `obj` has the method (a controller's reset before its run is
/// optional).
pub(crate) fn reset_if_any(py: Python<'_>, obj: &Py<PyAny>) -> PyResult<()> {
    if obj.bind(py).hasattr("reset")? {
        obj.call_method0(py, "reset")?;
    }
    Ok(())
}

impl IsolineController for PyController {
    fn update(&mut self, m: &Measurement) -> f64 {
        if self.error.is_some() {
            return f64::NAN;
        }
        Python::attach(|py| {
            match self
                .obj
                .call_method1(py, "update", (m.t_s, m.value))
                .and_then(|r| command_value(r.bind(py)))
            {
                Ok(w) => match self.max_turn_rate_radps {
                    // NaN passes (and ends the run as `diverged`).
                    Some(m) => w.clamp(-m, m),
                    None => w,
                },
                Err(e) => {
                    self.error = Some(e);
                    f64::NAN
                }
            }
        })
    }
    fn reset(&mut self) {}
}

/// A controller's `update` answer as a turn rate (rad/s): a real number, never a bool (`True`
/// would fly 1 rad/s; every numeric argument of the package refuses bools too).
pub(crate) fn command_value(r: &Bound<'_, PyAny>) -> PyResult<f64> {
    let is_bool = r.is_instance_of::<pyo3::types::PyBool>()
        || r.get_type()
            .fully_qualified_name()
            .is_ok_and(|n| n == "numpy.bool" || n == "numpy.bool_");
    if is_bool {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "controller.update() must return a turn rate (a number, rad/s), got {} (a bool)",
            shown(r)
        )));
    }
    r.extract::<f64>()
}

/// The objects a `controller_factory` has returned so far in one sweep or benchmark, each with
/// the run (and vehicle) it flies: an object returned again for another run would carry its
/// state (an integral, a last time) from run to run, so that a row depends on the runs before
/// it and cannot be run again alone. Held by weak reference where the object allows one (a dead
/// object cannot come back, and its address may then be reused), else by strong reference (so
/// that its address is not reused while the sweep runs).
#[derive(Default)]
pub(crate) struct Returned {
    seen: std::collections::HashMap<usize, (Py<PyAny>, bool, String)>,
}

impl Returned {
    /// Records `obj` as flying `label`; `Some(earlier label)` when the factory already returned
    /// this very object (still alive) for `earlier`.
    pub(crate) fn check(
        &mut self,
        py: Python<'_>,
        obj: &Py<PyAny>,
        label: String,
    ) -> PyResult<Option<String>> {
        use pyo3::types::{PyWeakrefMethods, PyWeakrefReference};
        let key = obj.as_ptr() as usize;
        if let Some((held, weak, earlier)) = self.seen.get(&key) {
            let alive = if *weak {
                held.bind(py)
                    .cast::<PyWeakrefReference>()
                    .ok()
                    .and_then(|w| w.upgrade())
                    .is_some_and(|o| o.is(obj.bind(py)))
            } else {
                held.is(obj)
            };
            if alive {
                return Ok(Some(earlier.clone()));
            }
        }
        let held = match PyWeakrefReference::new(obj.bind(py)) {
            Ok(w) => (w.into_any().unbind(), true),
            Err(_) => (obj.clone_ref(py), false),
        };
        self.seen.insert(key, (held.0, held.1, label));
        Ok(None)
    }
}

/// The refusal of one object returned for two runs (`earlier` and `now` name them).
pub(crate) fn shared_across_runs(earlier: &str, now: &str) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(format!(
        "controller_factory returned the same object for {now} as for {earlier}: its state \
         (an integral, a last time) would carry from run to run, so that a result depends on \
         the runs before it and cannot be run again alone; return a new controller at every call"
    ))
}
