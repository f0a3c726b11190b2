//! Limits shared by the figures and the checks of the data they draw (a leaf: the drawing and
//! the run readers both use it).

/// The largest `|value|` an axis may reach. Beyond it widths and pads overflow to infinity and
/// plotters' tick search never ends (a trace at 1e308 once hung `isotrack plot`); the error
/// names the quantity instead.
pub const MAX_AXIS_ABS: f64 = 1.0e100;
