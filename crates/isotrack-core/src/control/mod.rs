//! Coordinate-free isoline controllers.
//!
//! A controller implements [`IsolineController`]: at every sensor sample it receives a
//! [`Measurement`] (the sample's time stamp and the measured field value: no position, no heading,
//! no gradient) and returns the turn-rate command `omega` (rad/s, positive = left), which the
//! simulation holds until the next sample.
//!
//! Every controller shares the output stage [`OutputStage`]: the turning direction (which side the
//! higher field values lie on) and the optional turn-rate limit `|omega| <= omega_max`.

mod baselines;
mod pi_isoline;
mod search;

pub use baselines::{
    GradientReference, GradientReferenceParams, Pid, PidCrossing, PidCrossingParams, PidParams,
    SlidingMode, SlidingModeParams, SuboptimalSosm, SuboptimalSosmParams,
};
pub use pi_isoline::{AntiWindup, PiIsoline, PiIsolineParams};
pub use search::{Search, SearchParams, SearchPattern};

/// One sensor sample: all a coordinate-free controller ever sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Time the sample was taken at, seconds.
    pub t_s: f64,
    /// Measured field value `s(t)` (field units; noise and delay included).
    pub value: f64,
}

/// What a **reference** controller may know beyond the measurement: the true pose and field
/// gradient. Coordinate-free controllers never receive it (the simulation passes it only to a
/// controller whose [`IsolineController::needs_ground_truth`] is true).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundTruth {
    /// True pose.
    pub pose: crate::math::Pose2,
    /// True ground speed, m/s.
    pub speed_mps: f64,
    /// True field value at the pose (noise-free).
    pub value: f64,
    /// True gradient and Hessian at the pose, if the field has them there.
    pub derivatives: Option<(crate::math::Vec2, crate::math::Mat2)>,
}

/// An isoline-tracking controller. Coordinate-free controllers implement only
/// [`update`](Self::update).
pub trait IsolineController {
    /// Processes one sample and returns the turn-rate command in rad/s (positive turns left),
    /// held until the next sample. The result is finite for finite input.
    fn update(&mut self, m: &Measurement) -> f64;
    /// Returns the controller to its initial state (integrators, estimators).
    fn reset(&mut self);
    /// Whether the controller needs [`GroundTruth`] (reference controllers only; not
    /// coordinate-free).
    fn needs_ground_truth(&self) -> bool {
        false
    }
    /// [`update`](Self::update) with ground truth, called instead of it when
    /// [`needs_ground_truth`](Self::needs_ground_truth) is true.
    fn update_with_truth(&mut self, m: &Measurement, _truth: &GroundTruth) -> f64 {
        self.update(m)
    }
    /// [`update`](Self::update) of up to `N` controllers at once, one measurement each (the
    /// lanes holding `None` are skipped and answer 0): what a batched sweep does at a sample
    /// step. The default updates each in turn; a law whose arithmetic vectorises (the PI-like
    /// law's `tanh`) overrides it, with each answer and state equal, bit for bit, to what
    /// `update` gives.
    #[inline]
    fn update_lanes<const N: usize>(
        ctrls: &mut [Option<&mut Self>; N],
        ms: &[Measurement; N],
    ) -> [f64; N]
    where
        Self: Sized,
    {
        update_each(ctrls, ms)
    }
}

/// [`IsolineController::update_lanes`]'s default: each controller in turn, `None` lanes
/// answering 0. For laws that forward to a lane form only when every lane allows it.
#[inline]
pub fn update_each<C: IsolineController, const N: usize>(
    ctrls: &mut [Option<&mut C>; N],
    ms: &[Measurement; N],
) -> [f64; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        if let Some(c) = ctrls[i].as_deref_mut() {
            out[i] = c.update(&ms[i]);
        }
    }
    out
}

/// Which side of the vehicle the higher field values lie on once it tracks the isoline.
///
/// Dong & You's law as printed settles with the source of a circular field on the right
/// (clockwise around a maximum; their equilibrium `phi = -pi/2`), which is [`HigherSide::Right`].
/// [`HigherSide::Left`] mirrors the law (`omega -> -omega`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum HigherSide {
    /// Higher values on the right: clockwise around a maximum (the paper's convention).
    #[default]
    Right,
    /// Higher values on the left: counter-clockwise around a maximum.
    Left,
}

impl HigherSide {
    /// The factor applied to a law written for [`HigherSide::Right`]: `+1` or `-1`.
    pub fn sign(self) -> f64 {
        match self {
            HigherSide::Right => 1.0,
            HigherSide::Left => -1.0,
        }
    }
}

/// The output stage every controller shares: `omega = sat(direction * u, omega_max)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutputStage {
    /// Turning direction.
    pub higher_side: HigherSide,
    /// Optional turn-rate limit `omega_max` in rad/s (> 0).
    pub max_turn_rate_radps: Option<f64>,
}

impl OutputStage {
    /// Applies the direction and the limit to the law's raw output `u` (written for
    /// [`HigherSide::Right`]).
    #[inline]
    pub fn apply(&self, u: f64) -> f64 {
        // `sign * u` as a choice between `u` and `-u` (the same number): no multiply on the
        // loop's chain of dependent operations.
        let directed = match self.higher_side {
            HigherSide::Right => u,
            HigherSide::Left => -u,
        };
        crate::math::saturate(directed, self.max_turn_rate_radps)
    }
}
