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
