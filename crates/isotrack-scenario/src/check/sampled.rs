//! The sampled-data check: the PI-like law's loop linearised about the tracked isoline *at the
//! sensor's period*, with the command held between samples, the derivative estimator, the
//! sensor delay and (for the UAV) the course and roll loops. The derivation, with the matrices,
//! is docs/SAMPLED.md; in short:
//!
//! * Plant (continuous, linear about the isoline of slope `alpha = |grad F|` and curvature
//!   `kappa`): `z1` is the offset from the isoline towards lower values (m), `z2` the heading
//!   error (rad), `eps = -alpha z1`, and
//!   `z1' = v z2`, `z2' = dw - v kappa^2 z1` (Dubins: `dw` is the turn-rate command's deviation
//!   from the isoline's `v kappa`), or for the UAV `z2' = (g/Va) sec^2(b*) b - v kappa^2 z1` with
//!   the bank deviation `b` from the closed roll loop about the steady bank `b*`, the course
//!   loop's PI on the course command `h_c` relative to the isoline's tangent and
//!   `h_c' = dw - v kappa^2 z1` (course-rate guidance).
//! * Sensor lag (optional): the reading `y` follows `eps` as the simulator steps it, at every
//!   simulation step `h`: `y += (1 - exp(-h/tau)) (eps - y)` ([`SensorLag`]).
//! * Sampling: the plant is discretised exactly with the command held (zero-order hold) over the
//!   sensor period `T` (with a lag, as `T/h` sub-steps of plant then lag); a delay
//!   `tau_d = m T + r` (`0 <= r < T`) becomes `m` samples of buffer plus the fractional part `r`
//!   through `Phi(T - r)`, `Gamma(T - r)` (the modified z-transform).
//! * Law at each sample, exactly as [`isotrack_core::control::PiIsoline`] runs it:
//!   `eps'_k` from the estimator, `e_k = eps'_k + (c1/c2) g eps_k`,
//!   `sigma_k = sigma_{k-1} + T e_k`, `u_k = kp e_k + ki sigma_k`, where `g` is the slope of
//!   `tanh` at the equilibrium (1 when `ki > 0`; `1 - (v kappa/(kp c1))^2` for the P law's
//!   offset orbit).
//!
//! The loop is stable when the spectral radius of the one-period map is below 1. Written with
//! nalgebra's matrix exponential and Schur eigenvalues; the closed-loop matrix is assembled by
//! applying the (linear) one-period update to the unit vectors, so the code that builds it reads
//! like the controller it models.

use isotrack_vehicles::fixed_wing::gains::CourseLoopModel;
use nalgebra::{DMatrix, DVector};

/// What lies between the turn-rate command and the heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HeadingDynamics {
    /// Dubins robot: `heading' = omega` (paper eq. (5)).
    Dubins,
    /// Fixed-wing UAV: `omega` integrated into the course command, then the closed course and
    /// roll loops of the autopilot.
    CourseLoop(CourseLoopModel),
}

/// The derivative estimator as the linear model sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimatorModel {
    /// `(eps_k - eps_{k-1}) / T`.
    BackwardDifference,
    /// The backward difference through `y_k = a y_{k-1} + (1 - a) d_k`, `a = exp(-T/tau_s)`.
    FilteredDifference {
        /// Filter time constant, s.
        tau_s: f64,
    },
}

/// One operating point of the sampled loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledLoop {
    /// Vehicle speed `v`, m/s.
    pub speed_mps: f64,
    /// Field slope across the isoline `alpha = |grad F|`, field units per metre.
    pub slope: f64,
    /// Isoline curvature `kappa`, 1/m (0: straight).
    pub curvature_per_m: f64,
    /// Proportional gain.
    pub kp: f64,
    /// Integral gain.
    pub ki: f64,
    /// `c1`, field units per second.
    pub c1: f64,
    /// `c2`, field units.
    pub c2: f64,
    /// Sensor period `T`, s.
    pub period_s: f64,
    /// Sensor delay, s.
    pub delay_s: f64,
    /// Derivative estimator.
    pub estimator: EstimatorModel,
    /// Vehicle heading dynamics.
    pub heading: HeadingDynamics,
    /// The sensing element's first-order lag (`None`: instantaneous).
    pub sensor_lag: Option<SensorLag>,
}

/// The sensing element's first-order lag as the simulator runs it (`isotrack_sim::Sensor`): at
/// every simulation step `h`, once the vehicle has moved, `y += (1 - exp(-h/tau)) (x - y)` with
/// `x` the true value at the new position (the exact update of `y' = (x - y)/tau` for `x` held
/// over the step at its new value); the samples and the delay line carry `y`, not `x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorLag {
    /// Time constant `tau`, s (> 0).
    pub time_constant_s: f64,
    /// The simulation step `h` the lag is updated at, s (> 0). A period that is not a whole
    /// number of steps is split into `round(T/h)` (at least 1) equal steps.
    pub step_s: f64,
}

/// The plant as the sampler sees it with the command held: the continuous plant and, with a
/// lagged sensor, the lag stepped as the simulator steps it. The state is `x` (the plant's) or
/// `[x, y]` (`y` the lagged reading); [`output`](Self::output) reads what is sampled.
struct HeldPlant {
    a: DMatrix<f64>,
    b: DVector<f64>,
    c: DVector<f64>,
    /// With a lag: the sub-step `h` (a whole fraction of the period) and `1 - exp(-h/tau)`.
    lag: Option<(f64, f64)>,
}

impl HeldPlant {
    /// `None` when the lag's parameters are not positive finite numbers.
    fn new(l: &SampledLoop) -> Option<Self> {
        let (a, b, c) = plant(l);
        let lag = match l.sensor_lag {
            None => None,
            Some(SensorLag {
                time_constant_s: tau,
                step_s,
            }) => {
                let ok = |x: f64| x > 0.0 && x.is_finite();
                if !(ok(tau) && ok(step_s)) {
                    return None;
                }
                let steps = (l.period_s / step_s).round().max(1.0);
                let h = l.period_s / steps;
                Some((h, -(-h / tau).exp_m1()))
            }
        };
        Some(Self { a, b, c, lag })
    }

    /// The state's dimension.
    fn dim(&self) -> usize {
        self.a.nrows() + usize::from(self.lag.is_some())
    }

    /// The row that gives the sampled value: `C` (`eps = -alpha z1`), or the lagged `y`.
    fn output(&self) -> DVector<f64> {
        match self.lag {
            None => self.c.clone(),
            Some(_) => {
                let mut out = DVector::zeros(self.dim());
                out[self.a.nrows()] = 1.0;
                out
            }
        }
    }

    /// `(Phi, Gamma)` over `duration_s` with the command held. Without a lag, the zero-order
    /// hold; with one, `round(duration/h)` sub-steps of the simulator's order (plant over `h`,
    /// then `y += g (C x - y)`): one sub-step is
    /// `[[Phi_h, 0], [g C Phi_h, 1 - g]]`, `[Gamma_h, g C Gamma_h]`, raised to the power by
    /// squaring.
    fn over(&self, duration_s: f64) -> (DMatrix<f64>, DVector<f64>) {
        let Some((h, g)) = self.lag else {
            return zoh(&self.a, &self.b, duration_s);
        };
        let n = self.a.nrows();
        let (phi_h, gamma_h) = zoh(&self.a, &self.b, h);
        let mut step_a = DMatrix::zeros(n + 1, n + 1);
        step_a.view_mut((0, 0), (n, n)).copy_from(&phi_h);
        let c_phi = self.c.transpose() * &phi_h * g;
        step_a.view_mut((n, 0), (1, n)).copy_from(&c_phi);
        step_a[(n, n)] = 1.0 - g;
        let mut step_b = DVector::zeros(n + 1);
        step_b.rows_mut(0, n).copy_from(&gamma_h);
        step_b[n] = g * self.c.dot(&gamma_h);
        affine_power(step_a, step_b, (duration_s / h).round() as u64)
    }
}

/// The map `x -> A x + B u` applied `k` times (`u` held): `(A^k, (A^(k-1) + .. + 1) B)`, by
/// squaring (powers of one map commute, so the order of composition does not matter).
fn affine_power(
    mut a: DMatrix<f64>,
    mut b: DVector<f64>,
    mut k: u64,
) -> (DMatrix<f64>, DVector<f64>) {
    let n = a.nrows();
    let mut acc_a = DMatrix::identity(n, n);
    let mut acc_b = DVector::zeros(n);
    while k > 0 {
        if k & 1 == 1 {
            acc_b = &a * acc_b + &b;
            acc_a = &a * acc_a;
        }
        b = &a * &b + &b;
        a = &a * &a;
        k >>= 1;
    }
    (acc_a, acc_b)
}

/// Continuous plant `x' = A x + B u`, `eps = C x`.
fn plant(l: &SampledLoop) -> (DMatrix<f64>, DVector<f64>, DVector<f64>) {
    let v = l.speed_mps;
    let k2 = l.curvature_per_m * l.curvature_per_m;
    match l.heading {
        HeadingDynamics::Dubins => {
            // x = [z1, z2]
            let a = DMatrix::from_row_slice(2, 2, &[0.0, v, -v * k2, 0.0]);
            let b = DVector::from_vec(vec![0.0, 1.0]);
            let c = DVector::from_vec(vec![-l.slope, 0.0]);
            (a, b, c)
        }
        HeadingDynamics::CourseLoop(m) => {
            // x = [z1, z2, b, b', xi, h_c]; h_c = chi_c - (the isoline's tangent) turns with
            // the tangent as z2 does, so it carries the same curvature term.
            let w = m.roll_natural_frequency_radps;
            let (w2, zw2) = (w * w, 2.0 * m.roll_damping_ratio * w);
            let gv = course_rate_per_bank(&m, v * l.curvature_per_m);
            #[rustfmt::skip]
            let a = DMatrix::from_row_slice(6, 6, &[
                0.0,     v,                  0.0, 0.0,  0.0,               0.0,
                -v * k2, 0.0,                gv,  0.0,  0.0,               0.0,
                0.0,     0.0,                0.0, 1.0,  0.0,               0.0,
                0.0,     -w2 * m.kp_chi,     -w2, -zw2, w2 * m.ki_chi,     w2 * m.kp_chi,
                0.0,     -1.0,               0.0, 0.0,  0.0,               1.0,
                -v * k2, 0.0,                0.0, 0.0,  0.0,               0.0,
            ]);
            let mut b = DVector::zeros(6);
            b[5] = 1.0;
            let mut c = DVector::zeros(6);
            c[0] = -l.slope;
            (a, b, c)
        }
    }
}

/// The course rate per radian of bank about a steady turn of rate `turn_radps`: the coordinated
/// turn `chi' = (g/Va) tan(b)` linearised at the steady bank `tan(b*) = turn/(g/Va)` is
/// `(g/Va) sec^2(b*) = (g/Va) (1 + tan^2(b*))` (Beard & McLain 2012, eq. (9.14) with `Vg = Va`).
fn course_rate_per_bank(m: &CourseLoopModel, turn_radps: f64) -> f64 {
    let gv = m.g_over_airspeed_per_s;
    let tan_bank = turn_radps / gv;
    gv * (1.0 + tan_bank * tan_bank)
}

/// The course-loop model's numbers at an operating point (the fixed-wing UAV), as the check
/// used them: the steady bank of the turn that holds the isoline's curvature, its `sec^2`
/// factor, the effective course rate per radian of bank, and the autopilot's roll and course
/// loops (docs/SAMPLED.md).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CourseLoopNumbers {
    /// The steady bank `b*` of the turn at `v kappa`: `tan(b*) = v kappa / (g/Va)`, rad.
    pub steady_bank_rad: f64,
    /// `sec^2(b*) = 1 + tan^2(b*)`, the factor the steady bank puts on the course rate per bank.
    pub sec2_steady_bank: f64,
    /// `g/Va`, 1/s.
    pub g_over_airspeed_per_s: f64,
    /// The effective gain `G = (g/Va) sec^2(b*)`: course rate per radian of bank deviation,
    /// 1/s (Beard & McLain 2012, eq. (9.14) linearised, `Vg = Va`).
    pub course_rate_per_bank_per_s: f64,
    /// The closed roll loop's natural frequency `w_phi`, rad/s.
    pub roll_natural_frequency_radps: f64,
    /// The closed roll loop's damping ratio `zeta_phi`.
    pub roll_damping_ratio: f64,
    /// The course loop's proportional gain `kp_chi`, rad of bank per rad of course error.
    pub kp_chi: f64,
    /// The course loop's integral gain `ki_chi`, rad of bank per rad*s of course error.
    pub ki_chi: f64,
}

impl SampledLoop {
    /// The course-loop numbers the model uses at this operating point; `None` for the Dubins
    /// robot.
    pub fn course_loop_numbers(&self) -> Option<CourseLoopNumbers> {
        let HeadingDynamics::CourseLoop(m) = self.heading else {
            return None;
        };
        let gv = m.g_over_airspeed_per_s;
        let tan_bank = self.speed_mps * self.curvature_per_m / gv;
        Some(CourseLoopNumbers {
            steady_bank_rad: tan_bank.atan(),
            sec2_steady_bank: 1.0 + tan_bank * tan_bank,
            g_over_airspeed_per_s: gv,
            course_rate_per_bank_per_s: course_rate_per_bank(
                &m,
                self.speed_mps * self.curvature_per_m,
            ),
            roll_natural_frequency_radps: m.roll_natural_frequency_radps,
            roll_damping_ratio: m.roll_damping_ratio,
            kp_chi: m.kp_chi,
            ki_chi: m.ki_chi,
        })
    }
}

/// Zero-order-hold discretisation over `tau`: `(Phi, Gamma)` from
/// `exp([[A, B], [0, 0]] tau) = [[Phi, Gamma], [0, 1]]`.
fn zoh(a: &DMatrix<f64>, b: &DVector<f64>, tau: f64) -> (DMatrix<f64>, DVector<f64>) {
    let n = a.nrows();
    let mut m = DMatrix::zeros(n + 1, n + 1);
    m.view_mut((0, 0), (n, n)).copy_from(&(a * tau));
    m.view_mut((0, n), (n, 1)).copy_from(&(b * tau));
    let e = m.exp();
    (
        e.view((0, 0), (n, n)).into_owned(),
        e.view((0, n), (n, 1)).column(0).into_owned(),
    )
}

impl SampledLoop {
    /// The slope of `c1*tanh(eps/c2)` at the equilibrium, relative to `c1/c2`: 1 with an
    /// integral term (`eps* = 0`); with `ki = 0` on a curved isoline the P law settles where
    /// `kp c1 tanh(eps*/c2) = v kappa`, so `1 - (v kappa / (kp c1))^2`; `None` when no such
    /// orbit exists.
    pub fn tanh_slope(&self) -> Option<f64> {
        if self.ki != 0.0 || self.curvature_per_m == 0.0 {
            return Some(1.0);
        }
        let q = self.speed_mps * self.curvature_per_m / (self.kp * self.c1);
        (q.abs() < 1.0).then_some(1.0 - q * q)
    }

    /// The one-period closed-loop matrix `M` (`X_{k+1} = M X_k`), state
    /// `[x (plant), w_k .. w_{k-m} (delay line), eps_{k-1}, (y_{k-1} filter), (sigma_{k-1})]`;
    /// `None` when the P law has no equilibrium orbit or a parameter is not finite.
    pub fn closed_loop_matrix(&self) -> Option<DMatrix<f64>> {
        let t = self.period_s;
        if !(t > 0.0 && t.is_finite() && self.delay_s >= 0.0 && self.delay_s.is_finite()) {
            return None;
        }
        let g = self.tanh_slope()?;
        let held = HeldPlant::new(self)?;
        let n = held.dim();
        let (phi, gamma) = held.over(t);
        // Delay tau = m T + r; a remainder within 1e-9 T of a whole period is rounded away.
        let ratio = self.delay_s / t;
        let mut m = ratio.floor();
        let mut r = self.delay_s - m * t;
        if r > t * (1.0 - 1e-9) {
            m += 1.0;
            r = 0.0;
        } else if r < t * 1e-9 {
            r = 0.0;
        }
        if m > 10_000.0 {
            return None;
        }
        let m = m as usize;
        let frac = (r > 0.0).then(|| held.over(t - r));
        let filtered = matches!(self.estimator, EstimatorModel::FilteredDifference { .. });
        let integral = self.ki != 0.0;
        let i_buf = n;
        let i_prev = i_buf + m + 1;
        let i_filt = i_prev + 1;
        let i_sigma = i_filt + usize::from(filtered);
        let dim = i_sigma + usize::from(integral);
        let c_row = held.output().transpose();
        let (c1c2, kp, ki) = (self.c1 / self.c2 * g, self.kp, self.ki);
        let step = |xk: &DVector<f64>| -> DVector<f64> {
            let x = xk.rows(0, n).into_owned();
            let eps = xk[i_buf + m];
            let d = (eps - xk[i_prev]) / t;
            let eps_dot = match self.estimator {
                EstimatorModel::BackwardDifference => d,
                EstimatorModel::FilteredDifference { tau_s } => {
                    let a = (-t / tau_s).exp();
                    a * xk[i_filt] + (1.0 - a) * d
                }
            };
            let e = eps_dot + c1c2 * eps;
            let sigma = if integral { xk[i_sigma] + t * e } else { 0.0 };
            let u = kp * e + ki * sigma;
            let x_next = &phi * &x + &gamma * u;
            let w_next = match &frac {
                None => (&c_row * &x_next)[0],
                Some((phi_r, gamma_r)) => (&c_row * (phi_r * &x + gamma_r * u))[0],
            };
            let mut out = DVector::zeros(dim);
            out.rows_mut(0, n).copy_from(&x_next);
            out[i_buf] = w_next;
            for j in 1..=m {
                out[i_buf + j] = xk[i_buf + j - 1];
            }
            out[i_prev] = eps;
            if filtered {
                out[i_filt] = eps_dot;
            }
            if integral {
                out[i_sigma] = sigma;
            }
            out
        };
        let mut mat = DMatrix::zeros(dim, dim);
        for j in 0..dim {
            let mut unit = DVector::zeros(dim);
            unit[j] = 1.0;
            mat.set_column(j, &step(&unit));
        }
        mat.iter().all(|x| x.is_finite()).then_some(mat)
    }

    /// Spectral radius of the one-period map (`+inf` when there is no equilibrium).
    pub fn spectral_radius(&self) -> f64 {
        self.closed_loop_matrix().map_or(f64::INFINITY, |m| {
            m.complex_eigenvalues()
                .iter()
                .map(|z| z.norm())
                .fold(0.0, f64::max)
        })
    }
}

/// The most multiply-adds [`SampledLoop::late_response_fraction`] spends (the state's
/// dimension squared, times the periods simulated, times its two starts): about 0.1 s. Past it the response is not computed (`None`).
pub const MAX_RESPONSE_FLOPS: f64 = 2e8;

impl SampledLoop {
    /// How much of its transient the linear closed loop still has late in a run (issue 29: a
    /// slow mode that the law's zero nearly cancels, as at kp = 350 on the paper's circle, has
    /// a time constant of 350 s but almost no share in the response, which settles in about
    /// 20 s).
    ///
    /// The one-period map `X_{k+1} = M X_k` ([`closed_loop_matrix`](Self::closed_loop_matrix))
    /// is iterated from the state a run starts in, as deviations from the equilibrium: the
    /// offset `z1 = offset_m` (`-eps0/alpha`; 1 m when that and everything below are zero),
    /// heading along the isoline, the sensor reading, the delay line and the previous sample
    /// all at the starting error, the filter at rest; and what the turn on a curved isoline
    /// needs but a run starts without: the integral (it starts at 0 where the equilibrium holds
    /// `ki sigma* = v kappa`, so `sigma = v kappa / ki` short) and for the UAV the steady bank
    /// `b*` and the course integrator holding it (`b* / ki_chi`). Those deficits drift the
    /// vehicle to the curve's outside; their sign relative to the offset is taken both ways
    /// and the worse kept. With the true error `eps_k = C x_k` the result is
    /// `max_{k0 <= k <= k_end} |eps_k| / max_{0 <= k <= k_end} |eps_k|`
    /// (`k0 = from_s/T`, `k_end = to_s/T`, rounded down). `None` when the loop has no model
    /// or the work passes [`MAX_RESPONSE_FLOPS`].
    pub fn late_response_fraction(&self, from_s: f64, to_s: f64, offset_m: f64) -> Option<f64> {
        let t = self.period_s;
        if !(from_s >= 0.0 && to_s >= from_s && to_s.is_finite() && offset_m.is_finite()) {
            return None;
        }
        let held = HeldPlant::new(self)?;
        let np = held.a.nrows();
        let n = held.dim();
        let k_end = (to_s / t).floor();
        let m = self.closed_loop_matrix()?;
        let dim = m.nrows();
        if (2 * dim * dim) as f64 * k_end > MAX_RESPONSE_FLOPS {
            return None;
        }
        let (k_end, k0) = (k_end as usize, (from_s / t).floor() as usize);
        // Layout as in `closed_loop_matrix`: [x, (y), w_0 .. w_m, eps_prev, (filter), (sigma)].
        let filtered = matches!(self.estimator, EstimatorModel::FilteredDifference { .. });
        let integral = self.ki != 0.0;
        let i_prev = dim - 1 - usize::from(filtered) - usize::from(integral);
        // The deficits of a run's start on a curved isoline (zero on a straight one).
        let mut deficit = DVector::zeros(dim);
        let turn = self.speed_mps * self.curvature_per_m;
        if integral {
            deficit[dim - 1] = turn / self.ki;
        }
        if let (HeadingDynamics::CourseLoop(c), Some(nums)) =
            (self.heading, self.course_loop_numbers())
        {
            deficit[2] = nums.steady_bank_rad;
            if c.ki_chi != 0.0 {
                deficit[4] = nums.steady_bank_rad / c.ki_chi;
            }
        }
        let offset = if offset_m == 0.0 && deficit.iter().all(|&x| x == 0.0) {
            1.0
        } else {
            offset_m
        };
        let c = held.c.clone();
        let eps0 = c[0] * offset;
        let mut start = DVector::zeros(dim);
        start[0] = offset;
        if n > np {
            start[np] = eps0;
        }
        for i in n..=i_prev {
            start[i] = eps0;
        }
        let mut worst: f64 = 0.0;
        for sign in [1.0, -1.0] {
            let mut x = &start + &deficit * sign;
            let (mut peak, mut late) = (eps0.abs(), if k0 == 0 { eps0.abs() } else { 0.0 });
            for k in 1..=k_end {
                x = &m * x;
                let e = c.dot(&x.rows(0, np)).abs();
                peak = peak.max(e);
                if k >= k0 {
                    late = late.max(e);
                }
            }
            if !(peak.is_finite() && late.is_finite()) {
                return None;
            }
            if peak > 0.0 {
                worst = worst.max(late / peak);
            }
        }
        Some(worst)
    }
}

/// The worst (largest) spectral radius over the slopes `slopes`.
pub fn worst_spectral_radius(l: &SampledLoop, slopes: &[f64]) -> f64 {
    slopes
        .iter()
        .map(|&alpha| SampledLoop { slope: alpha, ..*l }.spectral_radius())
        .fold(0.0, |acc: f64, r| {
            if r.is_nan() {
                f64::INFINITY
            } else {
                acc.max(r)
            }
        })
}

fn stable(l: &SampledLoop, slopes: &[f64]) -> bool {
    worst_spectral_radius(l, slopes) < 1.0
}

/// Bisection on a boundary between `lo` (stable) and `hi` (unstable), geometric midpoints;
/// `lo` may lie on either side of `hi` (the bottom of a stable interval is refined from above).
fn refine(mut lo: f64, mut hi: f64, is_stable: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..50 {
        let mid = (lo * hi).sqrt();
        if is_stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi.max(lo) / hi.min(lo) < 1.0 + 1e-6 {
            break;
        }
    }
    lo
}

/// The largest `kp` (other gains fixed) for which the loop is stable at every slope: the top of
/// the stable set on a logarithmic scan of `1e-3 .. 1e6`, refined by bisection to 1e-6
/// relative. `None` when no scanned `kp` is stable.
pub fn max_kp(l: &SampledLoop, slopes: &[f64]) -> Option<f64> {
    let at = |kp: f64| stable(&SampledLoop { kp, ..*l }, slopes);
    let grid: Vec<f64> = (0..=180)
        .map(|j| 10f64.powf(-3.0 + j as f64 / 20.0))
        .collect();
    let top = grid.iter().rposition(|&kp| at(kp))?;
    Some(match grid.get(top + 1) {
        Some(&hi) => refine(grid[top], hi, at),
        None => grid[top],
    })
}

/// The longest sensor period for which the loop is stable at every slope, with every shorter
/// period stable too: the end of the stable interval that starts at `1e-4` s on a logarithmic
/// scan up to `1e3` s, refined by bisection. `None` when even `1e-4` s is unstable (the
/// continuous-time loop is).
pub fn max_period_s(l: &SampledLoop, slopes: &[f64]) -> Option<f64> {
    let at = |period_s: f64| stable(&SampledLoop { period_s, ..*l }, slopes);
    let grid: Vec<f64> = (0..=140)
        .map(|j| 10f64.powf(-4.0 + j as f64 / 20.0))
        .collect();
    if !at(grid[0]) {
        return None;
    }
    match grid.iter().position(|&t| !at(t)) {
        Some(first_bad) => Some(refine(grid[first_bad - 1], grid[first_bad], at)),
        None => grid.last().copied(),
    }
}

/// The most whole periods of delay line a model is built with. A sensor delay of `m` periods
/// adds `m` states and the eigenproblem costs `O(dim^3)`; past this many (a delay longer than
/// 32 sensor periods) the radius is reported as not computed rather than paid for (issue 29:
/// `max_period_s` once built thousands of states per scanned period). 32 keeps the worst
/// case of `run`'s warning (an unstable loop, whose advice scans `kp` and the period: about 200
/// eigenproblems per slope, 4 slopes) at a few tenths of a second.
pub const MAX_DELAY_STATES: f64 = 32.0;

impl SampledLoop {
    /// The spectral radius, or `None` (not computed) when the delay spans more than
    /// [`MAX_DELAY_STATES`] sensor periods; `+inf` as [`SampledLoop::spectral_radius`].
    pub fn radius(&self) -> Option<f64> {
        if self.delay_s / self.period_s > MAX_DELAY_STATES {
            return None;
        }
        Some(self.spectral_radius())
    }
}

/// [`worst_spectral_radius`] with the delay-line cap: `None` when the model is not computed
/// (the cap depends on the period and the delay only, so it is all slopes or none).
pub fn worst_radius(l: &SampledLoop, slopes: &[f64]) -> Option<f64> {
    l.radius()?;
    Some(worst_spectral_radius(l, slopes))
}

/// The `kp` scan: `10^(-3 + j/20)`, `j = 0..=180` (`1e-3 .. 1e6`, 20 points a decade).
fn kp_grid() -> Vec<f64> {
    (0..=180)
        .map(|j| 10f64.powf(-3.0 + j as f64 / 20.0))
        .collect()
}

/// The stable set of `kp` (other gains fixed), as disjoint intervals `[lo, hi]` in increasing
/// order: the runs of stable points of the scan `1e-3 .. 1e6` (20 a decade), each end refined by
/// bisection to 1e-6 relative (an end at the scan's limit is that limit: stable beyond it is not
/// examined). A stable window narrower than one scan step (12 %) can be missed. `None` when the
/// model is not computed ([`MAX_DELAY_STATES`]).
pub fn kp_intervals(l: &SampledLoop, slopes: &[f64]) -> Option<Vec<[f64; 2]>> {
    l.radius()?;
    let at = |kp: f64| stable(&SampledLoop { kp, ..*l }, slopes);
    Some(kp_intervals_over(&kp_grid(), at))
}

/// The `kp` scan's points from `from` up: `10^(-3 + j/20)` (`1e-3 .. 1e6`), those below `from`
/// left out (the scan then starts at the first point at or above it).
pub fn kp_grid_from(from: f64) -> Vec<f64> {
    kp_grid().into_iter().filter(|&kp| kp >= from).collect()
}

/// The stable set over the scan `grid` (increasing) for any stability test `at`: the runs of
/// stable points, each inner end refined by bisection to 1e-6 relative ([`kp_intervals`]; an
/// end at the grid's first or last point is the scan's limit). Used with an operating point
/// that moves with `kp` (the P law's orbit, recomputed at every `kp` examined).
pub fn kp_intervals_over(grid: &[f64], at: impl Fn(f64) -> bool) -> Vec<[f64; 2]> {
    let ok: Vec<bool> = grid.iter().map(|&kp| at(kp)).collect();
    let mut out = vec![];
    let mut j = 0;
    while j < grid.len() {
        if !ok[j] {
            j += 1;
            continue;
        }
        let first = j;
        while j + 1 < grid.len() && ok[j + 1] {
            j += 1;
        }
        let lo = match first {
            0 => grid[0],
            _ => refine(grid[first], grid[first - 1], &at),
        };
        let hi = match grid.get(j + 1) {
            Some(&bad) => refine(grid[j], bad, &at),
            None => grid[j],
        };
        out.push([lo, hi]);
        j += 1;
    }
    out
}

/// The stable `kp` nearest `kp` (by ratio, `|ln(x/kp)|`: gains are compared by factors), from
/// `intervals`; `kp` itself when it lies in one, `None` when there is none.
pub fn nearest_stable_kp(kp: f64, intervals: &[[f64; 2]]) -> Option<f64> {
    intervals
        .iter()
        .map(|&[lo, hi]| kp.clamp(lo, hi))
        .min_by(|a, b| (a / kp).ln().abs().total_cmp(&(b / kp).ln().abs()))
}

/// [`period_limit`]'s answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodLimit {
    /// The longest stable period with every computed shorter one stable, s (`None`: the
    /// shortest computed period is unstable already).
    pub max_period_s: Option<f64>,
    /// The shortest period examined, s: `1e-4`, or `delay / MAX_DELAY_STATES` when that is
    /// longer (shorter periods would need more delay-line states and are not computed).
    pub scanned_from_s: f64,
}

/// The longest sensor period for which the loop is stable at every slope, with every shorter
/// period stable too, over the periods that can be computed: a logarithmic scan from
/// `max(1e-4, delay/MAX_DELAY_STATES)` s up to `1e3` s (20 a decade), the first unstable one
/// refined by bisection. Holding the delay fixed, a short period means a long delay line; the
/// cap keeps every eigenproblem at most `MAX_DELAY_STATES` states larger than without delay.
pub fn period_limit(l: &SampledLoop, slopes: &[f64]) -> PeriodLimit {
    let from = (l.delay_s / MAX_DELAY_STATES).max(1e-4);
    let at = |period_s: f64| stable(&SampledLoop { period_s, ..*l }, slopes);
    let grid: Vec<f64> = std::iter::once(from)
        .chain(
            (0..=140)
                .map(|j| 10f64.powf(-4.0 + j as f64 / 20.0))
                .filter(|&t| t > from),
        )
        .collect();
    let max_period_s = if at(grid[0]) {
        match grid.iter().position(|&t| !at(t)) {
            Some(first_bad) => Some(refine(grid[first_bad - 1], grid[first_bad], at)),
            None => grid.last().copied(),
        }
    } else {
        None
    };
    PeriodLimit {
        max_period_s,
        scanned_from_s: from,
    }
}

/// The discrete loop the check analysed, as control toolboxes describe it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LoopAnalysis {
    /// The slope `|grad F|` the loop was built at.
    pub slope: f64,
    /// The plant held over one period: `x_{k+1} = phi x_k + gamma u_k` (row-major rows). With
    /// a sensor lag `x` ends with the lagged reading `y`, stepped as the simulator steps it.
    pub phi: Vec<Vec<f64>>,
    /// See `phi`.
    pub gamma: Vec<f64>,
    /// The sampled output `c x`: `eps`, or with a lag the lagged reading `y`.
    pub c: Vec<f64>,
    /// The one-period closed-loop map `X_{k+1} = M X_k` (rows; state as
    /// [`SampledLoop::closed_loop_matrix`]).
    pub closed_loop: Vec<Vec<f64>>,
    /// `det(z I - M)`, coefficients from `z^n` down to `z^0`.
    pub characteristic_polynomial: Vec<f64>,
    /// The gain margin: the factor on the loop gain `L(z)` (broken at the turn-rate command,
    /// `1 + L = 0` on the closed loop) that puts a pole on the unit circle, at the phase
    /// crossover (`arg L = -180 deg`) whose margin is nearest 1 (as `margin` does); `None`
    /// without a phase crossover in `(0, pi/T]`.
    pub gain_margin: Option<f64>,
    /// `20 log10(gain_margin)`, dB.
    pub gain_margin_db: Option<f64>,
    /// The phase crossover's frequency, rad/s.
    pub phase_crossover_radps: Option<f64>,
    /// For a stable loop, the stable range of factors on the loop gain round 1, as control
    /// toolboxes report a conditionally stable loop's two margins: the lower gain margin is the
    /// largest `1/|L|` below 1 over the phase crossovers (reduce the gain by that factor and a
    /// pole reaches the unit circle), null when there is none (the loop stays stable down to
    /// zero gain at these frequencies). A loop with a lower margin is *conditionally stable*.
    /// Null for an unstable loop.
    pub gain_margin_lower: Option<f64>,
    /// The upper gain margin: the smallest `1/|L|` above 1 over the phase crossovers (raise the
    /// gain by that factor and a pole reaches the unit circle); null when there is none, or for
    /// an unstable loop.
    pub gain_margin_upper: Option<f64>,
    /// Whether the stable loop is conditionally stable (it has a lower gain margin: it goes
    /// unstable if its gain is *reduced* by `gain_margin_lower`); null for an unstable loop.
    pub conditionally_stable: Option<bool>,
    /// The phase margin `180 + arg L` (deg, in `(-180, 180]`) at the gain crossover
    /// (`|L| = 1`) with the smallest margin; `None` without a gain crossover in `(0, pi/T]`.
    pub phase_margin_deg: Option<f64>,
    /// The gain crossover's frequency, rad/s.
    pub gain_crossover_radps: Option<f64>,
}

/// Real coefficients (highest power first) of `prod (z - r_i)` over `roots`.
fn poly_from_roots(roots: &[nalgebra::Complex<f64>]) -> Vec<f64> {
    let mut c = vec![nalgebra::Complex::new(1.0, 0.0)];
    for r in roots {
        let mut next = c.clone();
        next.push(nalgebra::Complex::new(0.0, 0.0));
        for (i, ci) in c.iter().enumerate() {
            next[i + 1] -= ci * r;
        }
        c = next;
    }
    c.iter().map(|z| z.re).collect()
}

/// Horner's rule at complex `z`.
fn poly_at(p: &[f64], z: nalgebra::Complex<f64>) -> nalgebra::Complex<f64> {
    p.iter()
        .fold(nalgebra::Complex::new(0.0, 0.0), |acc, &c| acc * z + c)
}

/// `L(z) = N(z)/D(z)` on the unit circle at `z = exp(j w T)`.
fn loop_gain_at(n: &[f64], d: &[f64], w: f64, t: f64) -> nalgebra::Complex<f64> {
    let z = nalgebra::Complex::from_polar(1.0, w * t);
    poly_at(n, z) / poly_at(d, z)
}

/// Crossings of `f` (sign change) along `ws`, each refined by 60 bisections.
fn crossings(ws: &[f64], f: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut out = vec![];
    for pair in ws.windows(2) {
        let (mut a, mut b) = (pair[0], pair[1]);
        let (fa, fb) = (f(a), f(b));
        if !(fa.is_finite() && fb.is_finite()) || fa.signum() == fb.signum() {
            continue;
        }
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if f(m).signum() == fa.signum() {
                a = m;
            } else {
                b = m;
            }
        }
        out.push(0.5 * (a + b));
    }
    out
}

/// The margins read off a sampled loop gain.
struct Margins {
    /// The gain margin nearest 1 in ratio (`1/|L|` at a phase crossover) and its frequency,
    /// rad/s.
    gain: Option<(f64, f64)>,
    /// The nearest factor below 1 at which a stable loop turns unstable.
    lower: Option<f64>,
    /// The nearest factor above 1 at which a stable loop turns unstable.
    upper: Option<f64>,
    /// The phase margin nearest 0 (deg) and its gain crossover, rad/s.
    phase: Option<(f64, f64)>,
}

/// The margins of the loop gain `L = N/D` (coefficients `n`, `d`) sampled at period `t` (s),
/// read off `L(exp(j w T))` on 4000 logarithmically spaced frequencies in `[1e-5, 1] pi/T`,
/// each crossing refined by bisection; crossings where `|L|` is unbounded (the open loop's
/// poles on the unit circle) are left out. `stable_now`: the closed loop is stable as it is
/// (the lower and upper factors are `None` otherwise).
fn margins(n: &[f64], d: &[f64], t: f64, stable_now: bool) -> Margins {
    let nyquist = std::f64::consts::PI / t;
    let ws: Vec<f64> = (0..4000)
        .map(|k| nyquist * 10f64.powf(-5.0 + 5.0 * k as f64 / 3999.0))
        .collect();
    let l = |w: f64| loop_gain_at(n, d, w, t);
    let bounded = |w: f64| l(w).norm() < 1e8;
    // Phase crossovers: L real and negative. At pi/T, L is real (z = -1).
    // A crossover where |L| is rounding noise (below 1e-8, a "gain margin" above 1e8, e.g.
    // at pi/T on a lagged loop) is no margin: left out (the review saw 2e14 reported).
    let significant = |w: f64| bounded(w) && l(w).norm() > 1e-8;
    let mut phase_x: Vec<f64> = crossings(&ws, |w| l(w).im)
        .into_iter()
        .filter(|&w| l(w).re < 0.0 && significant(w))
        .collect();
    if l(nyquist).re < 0.0 && significant(nyquist) {
        phase_x.push(nyquist);
    }
    let gm = phase_x
        .iter()
        .map(|&w| (1.0 / l(w).norm(), w))
        .min_by(|a, b| a.0.ln().abs().total_cmp(&b.0.ln().abs()));
    // A pole crosses the unit circle exactly where `1 + lambda L(exp(j w T)) = 0`, i.e. at
    // a phase crossover with `lambda = 1/|L|`; so a stable loop stays stable for the
    // factors between the nearest such `lambda` below 1 and the nearest above.
    let factors: Vec<f64> = phase_x.iter().map(|&w| 1.0 / l(w).norm()).collect();
    let gm_lower = factors
        .iter()
        .copied()
        .filter(|&g| g < 1.0)
        .max_by(f64::total_cmp)
        .filter(|_| stable_now);
    let gm_upper = factors
        .iter()
        .copied()
        .filter(|&g| g > 1.0)
        .min_by(f64::total_cmp)
        .filter(|_| stable_now);
    let pm = crossings(&ws, |w| l(w).norm().ln())
        .into_iter()
        .filter(|&w| bounded(w))
        .map(|w| {
            let z = l(w);
            let mut pm = 180.0 + z.im.atan2(z.re).to_degrees();
            if pm > 180.0 {
                pm -= 360.0;
            }
            (pm, w)
        })
        .min_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    Margins {
        gain: gm,
        lower: gm_lower,
        upper: gm_upper,
        phase: pm,
    }
}

impl SampledLoop {
    /// The discrete loop and its margins; `None` without a model.
    ///
    /// The loop gain: the slope `alpha` scales the plant's output, and nothing else in the
    /// loop depends on it, so `det(zI - M(lambda alpha)) = D(z) + lambda N(z)` (the feedback
    /// is rank one; the open loop's own modes do not depend on `alpha`), and
    /// `1 + L = det(zI - M)/D` gives `L = N/D` with `N = p_2 - p_1`, `D = 2 p_1 - p_2` from the
    /// characteristic polynomials at `alpha` and `2 alpha`. The margins are read off
    /// `L(exp(j w T))` on 4000 logarithmically spaced frequencies in `[1e-5, 1] pi/T`, each
    /// crossing refined by bisection; crossings at the open loop's poles on the unit circle
    /// (`|L|` unbounded) are not margins and are left out.
    pub fn analysis(&self) -> Option<LoopAnalysis> {
        let m = self.closed_loop_matrix()?;
        let m2 = SampledLoop {
            slope: 2.0 * self.slope,
            ..*self
        }
        .closed_loop_matrix()?;
        let p1 = poly_from_roots(m.complex_eigenvalues().as_slice());
        let p2 = poly_from_roots(m2.complex_eigenvalues().as_slice());
        let n: Vec<f64> = p2.iter().zip(&p1).map(|(b, a)| b - a).collect();
        let d: Vec<f64> = p2.iter().zip(&p1).map(|(b, a)| 2.0 * a - b).collect();
        let t = self.period_s;
        let stable_now = m.complex_eigenvalues().iter().all(|z| z.norm() < 1.0);
        let Margins {
            gain: gm,
            lower: gm_lower,
            upper: gm_upper,
            phase: pm,
        } = margins(&n, &d, t, stable_now);
        // With a sensor lag the plant held over a period carries the lagged reading `y` as its
        // last state, and `c` reads it (issue 29: `phi` was the 2 x 2 vehicle alone while
        // `closed_loop` had the lag).
        let held = HeldPlant::new(self)?;
        let (phi, gamma) = held.over(t);
        let c = held.output();
        let rows = |x: &DMatrix<f64>| -> Vec<Vec<f64>> {
            x.row_iter().map(|r| r.iter().copied().collect()).collect()
        };
        Some(LoopAnalysis {
            slope: self.slope,
            phi: rows(&phi),
            gamma: gamma.iter().copied().collect(),
            c: c.iter().copied().collect(),
            closed_loop: rows(&m),
            characteristic_polynomial: p1,
            gain_margin: gm.map(|g| g.0),
            gain_margin_db: gm.map(|g| 20.0 * g.0.log10()),
            phase_crossover_radps: gm.map(|g| g.1),
            gain_margin_lower: gm_lower,
            gain_margin_upper: gm_upper,
            conditionally_stable: stable_now.then_some(gm_lower.is_some()),
            phase_margin_deg: pm.map(|p| p.0),
            gain_crossover_radps: pm.map(|p| p.1),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tanh's slope at the equilibrium: 1 with an integral or on a straight isoline; with
    /// the P law on a curve `1 - q^2`, `q = v kappa/(kp c1)` (0.5 * 0.1/(1 * 0.2) = 0.25 gives
    /// 0.9375); no orbit from `q = 1` on (0.5 * 0.4 = 1 * 0.2 exactly).
    #[test]
    fn tanh_slope_at_the_p_laws_orbit() {
        let p = |curvature_per_m: f64, ki: f64| SampledLoop {
            curvature_per_m,
            ..dubins(1.0, ki, 0.01)
        };
        assert_eq!(p(0.1, 0.0).tanh_slope(), Some(0.9375));
        assert_eq!(p(0.1, 1.0).tanh_slope(), Some(1.0));
        assert_eq!(p(0.0, 0.0).tanh_slope(), Some(1.0));
        assert_eq!(p(0.4, 0.0).tanh_slope(), None);
        assert_eq!(p(-0.1, 0.0).tanh_slope(), Some(0.9375));
    }

    fn dubins(kp: f64, ki: f64, period_s: f64) -> SampledLoop {
        SampledLoop {
            speed_mps: 0.5,
            slope: 1.0,
            curvature_per_m: 0.0,
            kp,
            ki,
            c1: 0.2,
            c2: 1.0,
            period_s,
            delay_s: 0.0,
            estimator: EstimatorModel::BackwardDifference,
            heading: HeadingDynamics::Dubins,
            sensor_lag: None,
        }
    }

    /// The worst spectral radius over slopes is the largest of the radii at each slope, whatever
    /// slope the loop was built with.
    #[test]
    fn the_worst_radius_is_over_the_slopes_given() {
        let l = dubins(10.0, 1.0, 0.1);
        let at = |alpha: f64| SampledLoop { slope: alpha, ..l }.spectral_radius();
        let (r_low, r_high) = (at(0.2), at(3.0));
        assert!(r_low != r_high, "{r_low} {r_high}");
        let worst = worst_spectral_radius(&l, &[0.2, 3.0]);
        assert_eq!(worst, r_low.max(r_high));
        assert_eq!(worst_spectral_radius(&l, &[0.2]), r_low);
        assert_eq!(worst_spectral_radius(&l, &[3.0]), r_high);
        assert_eq!(worst_spectral_radius(&l, &[]), 0.0);
    }

    /// The UAV's continuous plant against its transfer function derived by hand in the ground
    /// frame (docs/SAMPLED.md; Laplace, zero initial state), not from the model's states: the
    /// course loop is a servo from the course command to the course, `chi' = G b` with the roll
    /// loop `b = R(s) b_c`, `R = w^2/(s^2 + 2 zeta w s + w^2)`, and the course PI
    /// `b_c = P(s)(chi_c - chi)`, `P = kp_chi + ki_chi/s`, so `chi = T(s) chi_c` with
    /// `T = G R P/(s + G R P)`; guidance integrates the turn-rate command into `chi_c`, so the
    /// UAV turns at `T(s)` times the commanded rate, and the turn rate drives the offset as it
    /// drives the Dubins robot's: `eps/u = -alpha v T(s)/(s^2 + v^2 kappa^2)`. `G` is the
    /// coordinated turn's `(g/Va) sec^2(b*)` at the steady bank, `tan(b*) = v kappa/(g/Va)`
    /// (`30 * 0.004 / 0.327`, `sec^2 = 1.1346`). At real `s` away from the poles,
    /// `C (sI - A)^-1 B` equals it.
    #[test]
    fn the_uav_plant_is_its_block_diagram() {
        let m = CourseLoopModel {
            roll_natural_frequency_radps: 7.0,
            roll_damping_ratio: 0.8,
            kp_chi: 2.5,
            ki_chi: 0.3,
            g_over_airspeed_per_s: 9.81 / 30.0,
        };
        let l = SampledLoop {
            speed_mps: 30.0,
            slope: 0.2,
            curvature_per_m: 0.004,
            heading: HeadingDynamics::CourseLoop(m),
            ..dubins(8.0, 0.5, 1.0)
        };
        let (a, b, c) = plant(&l);
        let tan_bank: f64 = 30.0 * 0.004 / (9.81 / 30.0);
        let sec2 = 1.0 / tan_bank.atan().cos().powi(2);
        assert!((sec2 - 1.1346).abs() < 1e-4, "{sec2}");
        for s in [0.37, 1.3, 4.1] {
            let resolvent = (DMatrix::identity(6, 6) * s - &a).try_inverse().unwrap();
            let got = c.dot(&(resolvent * &b));
            let (w, z) = (7.0, 0.8);
            let roll = w * w / (s * s + 2.0 * z * w * s + w * w);
            let open = (9.81 / 30.0) * sec2 * roll * (2.5 + 0.3 / s);
            let servo = open / (s + open);
            let want = -0.2 * 30.0 * servo / (s * s + 30.0f64.powi(2) * 0.004f64.powi(2));
            assert!(
                (got - want).abs() <= 1e-12 * want.abs(),
                "s = {s}: {got} vs {want}"
            );
        }
        // The Dubins plant likewise: eps/u = -alpha v / (s^2 + v^2 kappa^2).
        let l = SampledLoop {
            curvature_per_m: 0.3,
            ..dubins(1.0, 0.0, 0.1)
        };
        let (a, b, c) = plant(&l);
        for s in [0.37, 1.3] {
            let resolvent = (DMatrix::identity(2, 2) * s - &a).try_inverse().unwrap();
            let got = c.dot(&(resolvent * &b));
            // alpha = 1, v = 0.5, kappa = 0.3.
            let want = -0.5 / (s * s + 0.25 * 0.09);
            assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} vs {want}");
        }
    }

    /// Asserts that the closed-loop matrix of `l` has `count` eigenvalues of modulus above
    /// `zero_below` (the rest are the zeros of redundant states) and that each is a root of the
    /// hand-derived polynomial `p`, to `tol`.
    fn assert_nonzero_eigenvalues_are_roots(
        l: &SampledLoop,
        zero_below: f64,
        count: usize,
        tol: f64,
        p: impl Fn(nalgebra::Complex<f64>) -> nalgebra::Complex<f64>,
        label: &str,
    ) {
        let eig = l.closed_loop_matrix().unwrap().complex_eigenvalues();
        let nonzero: Vec<_> = eig.iter().filter(|z| z.norm() > zero_below).collect();
        assert_eq!(nonzero.len(), count, "{label}: {eig:?}");
        for z in nonzero {
            assert!(p(*z).norm() < tol, "{label}: p({z}) = {}", p(*z));
        }
    }

    /// The characteristic polynomial of the straight-isoline Dubins loop with the P law and a
    /// backward difference, derived by hand from transfer functions (docs/SAMPLED.md):
    /// `G(z) = -alpha v T^2 (z + 1) / (2 (z - 1)^2)`, `K(z) = kp((1 + cT) z - 1)/(T z)`,
    /// `c = c1/c2`, so `1 - G K = 0` is
    /// `2 z (z - 1)^2 + alpha v T kp (z + 1)((1 + cT) z - 1) = 0`.
    #[test]
    fn eigenvalues_are_the_roots_of_the_hand_derived_polynomial() {
        for (kp, t) in [(10.0, 0.01), (10.0, 1.0), (2.0, 0.3), (50.0, 0.05)] {
            let l = dubins(kp, 0.0, t);
            let (av, c) = (l.slope * l.speed_mps, l.c1 / l.c2);
            let p = |z: nalgebra::Complex<f64>| {
                let one = nalgebra::Complex::new(1.0, 0.0);
                (z - one) * (z - one) * z * 2.0
                    + (z + one) * (z * (1.0 + c * t) - one) * (av * t * kp)
            };
            // The nonzero eigenvalues (the redundant delay-line state adds a zero) are the
            // polynomial's three roots.
            let label = format!("kp {kp} T {t}");
            assert_nonzero_eigenvalues_are_roots(&l, 1e-9, 3, 1e-9 * (1.0 + kp), p, &label);
        }
    }

    /// A delay of `m` whole periods multiplies the loop gain by `z^-m`: the polynomial above
    /// becomes `2 z^(1+m) (z - 1)^2 + alpha v T kp (z + 1)((1 + cT) z - 1)`, whose `3 + m`
    /// roots are the matrix's nonzero eigenvalues. A delay within `1e-9 T` of a whole period
    /// (either side) is that whole period.
    #[test]
    fn whole_periods_of_delay_multiply_the_loop_by_z_to_the_minus_m() {
        let (kp, t) = (3.0, 0.1);
        for m in [1usize, 2] {
            for delay in [
                m as f64 * t,
                m as f64 * t * (1.0 - 1e-12),
                m as f64 * t + 1e-13,
            ] {
                let l = SampledLoop {
                    delay_s: delay,
                    ..dubins(kp, 0.0, t)
                };
                let (av, c) = (l.slope * l.speed_mps, l.c1 / l.c2);
                let p = |z: nalgebra::Complex<f64>| {
                    let one = nalgebra::Complex::new(1.0, 0.0);
                    (z - one) * (z - one) * z.powu(1 + m as u32) * 2.0
                        + (z + one) * (z * (1.0 + c * t) - one) * (av * t * kp)
                };
                let label = format!("m {m}, delay {delay}");
                assert_nonzero_eigenvalues_are_roots(&l, 1e-6, 3 + m, 1e-9, p, &label);
            }
        }
        // Rounded, not approximated: the same matrix as the whole period, to the bit.
        for m in [1.0, 2.0] {
            let at = |delay_s: f64| {
                SampledLoop {
                    delay_s,
                    ..dubins(kp, 0.0, t)
                }
                .closed_loop_matrix()
                .unwrap()
            };
            let exact = at(m * t);
            assert_eq!(at(m * t * (1.0 - 1e-12)), exact, "{m} T from below");
            assert_eq!(at(m * t + 1e-13), exact, "{m} T from above");
        }
        let none = dubins(kp, 0.0, t).closed_loop_matrix().unwrap();
        assert_eq!(
            SampledLoop {
                delay_s: 1e-13,
                ..dubins(kp, 0.0, t)
            }
            .closed_loop_matrix()
            .unwrap(),
            none,
            "a hair of delay is none"
        );
        // A delay far beyond the delay line's capacity has no model.
        let l = SampledLoop {
            delay_s: 1e4 * 0.1 + 0.1,
            ..dubins(kp, 0.0, t)
        };
        assert!(l.closed_loop_matrix().is_none());
    }

    /// As `T -> 0` the sampled loop's stability agrees with the continuous-time Routh-Hurwitz
    /// condition of Prop. 1 on the circular field (slope alpha, radius r_d).
    #[test]
    fn fast_sampling_agrees_with_the_continuous_time_condition() {
        let r_d = 10.0 * std::f64::consts::LN_2;
        for (kp, ki) in [
            (10.0, 1.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (0.5, 0.05),
            (10.0, 0.0),
        ] {
            let l = SampledLoop {
                curvature_per_m: 1.0 / r_d,
                ..dubins(kp, ki, 1e-3)
            };
            let continuous =
                isotrack_core::theory::prop1_exact_local_condition(1.0, 0.5, r_d, kp, ki, 0.2, 1.0);
            assert_eq!(l.spectral_radius() < 1.0, continuous, "kp {kp} ki {ki}");
        }
    }

    #[test]
    fn the_papers_gains_fail_at_one_hertz_and_hold_at_a_hundred() {
        // Issue 10: kp = 10, ki = 1, c1 = 0.2, c2 = 1 on the circular field never settles at
        // 1 Hz and tracks at 100 Hz.
        let r_d = 10.0 * std::f64::consts::LN_2;
        let at = |t| SampledLoop {
            curvature_per_m: 1.0 / r_d,
            ..dubins(10.0, 1.0, t)
        };
        assert!(at(1.0).spectral_radius() > 1.0);
        assert!(at(0.01).spectral_radius() < 1.0);
        let t_max = max_period_s(&at(0.01), &[1.0]).unwrap();
        assert!(t_max > 0.01 && t_max < 1.0, "{t_max}");
        assert!(at(t_max * 0.999).spectral_radius() < 1.0);
        assert!(at(t_max * 1.001).spectral_radius() > 1.0);
        // With ki = 1 no kp is stable at 1 Hz (the integral needs kp large, the sampling kp
        // small); the P law has a window, whose top sits where the spectral radius crosses 1
        // and below the small-cT estimate alpha v T kp = 2 (kp = 4).
        assert_eq!(max_kp(&at(1.0), &[1.0]), None);
        let p_law = SampledLoop { ki: 0.0, ..at(1.0) };
        let kp_max = max_kp(&p_law, &[1.0]).unwrap();
        assert!(kp_max > 1.0 && kp_max < 4.0, "{kp_max}");
        let rho = SampledLoop {
            kp: kp_max,
            ..p_law
        }
        .spectral_radius();
        assert!((rho - 1.0).abs() < 1e-4, "{rho}");
    }

    #[test]
    fn a_whole_sample_of_delay_equals_a_longer_delay_line() {
        // A delay of exactly 2 T and one of 2 T minus a hair give (nearly) the same spectrum;
        // both are less stable than no delay.
        let base = dubins(3.0, 0.0, 0.1);
        let r0 = base.spectral_radius();
        let r2 = SampledLoop {
            delay_s: 0.2,
            ..base
        }
        .spectral_radius();
        let r2m = SampledLoop {
            delay_s: 0.2 - 1e-7,
            ..base
        }
        .spectral_radius();
        assert!(r2 > r0, "{r0} {r2}");
        assert!((r2 - r2m).abs() < 1e-4, "{r2} {r2m}");
    }

    /// No model for a period or delay that is not a finite number in range.
    #[test]
    fn parameters_out_of_range_have_no_model() {
        for t in [0.0, -0.1, f64::INFINITY, f64::NAN] {
            assert!(
                dubins(3.0, 0.0, t).closed_loop_matrix().is_none(),
                "T = {t}"
            );
        }
        for delay_s in [-0.1, f64::INFINITY, f64::NAN] {
            let l = SampledLoop {
                delay_s,
                ..dubins(3.0, 0.0, 0.1)
            };
            assert!(l.closed_loop_matrix().is_none(), "delay {delay_s}");
        }
        assert!(dubins(3.0, 0.0, 0.1).closed_loop_matrix().is_some());
    }

    /// The P law on a curved isoline, by hand: the plant `z1'' = -w^2 z1 + v dw` (`w = v kappa`)
    /// held over `T` is `G(z) = -alpha v (1 - cos wT)(z + 1) / (w^2 (z^2 - 2 z cos wT + 1))`
    /// (the ZOH transform of `-alpha v / (s^2 + w^2)`, which is the straight case's
    /// `-alpha v T^2 (z + 1)/(2 (z - 1)^2)` as `w -> 0`); the law's gain on `eps` is
    /// `c = (c1/c2)(1 - q^2)`, `q = v kappa/(kp c1)`. So `1 - G K = 0` is
    /// `w^2 T z (z^2 - 2 z cos wT + 1) + alpha v kp (1 - cos wT)(z + 1)((1 + cT) z - 1) = 0`.
    /// With c2 = 0.5 and q = 0.25 (`c = 0.4 * 0.9375`) neither factor is 1.
    #[test]
    fn the_p_law_on_a_curve_has_the_hand_derived_polynomial() {
        for (kp, t) in [(1.0, 0.1), (1.0, 1.0), (2.0, 0.5), (5.0, 0.05)] {
            let l = SampledLoop {
                curvature_per_m: 0.1 * kp,
                c2: 0.5,
                ..dubins(kp, 0.0, t)
            };
            let q = l.speed_mps * l.curvature_per_m / (kp * l.c1);
            assert!((q - 0.25).abs() < 1e-15);
            let c = l.c1 / l.c2 * (1.0 - q * q);
            let (av, w) = (l.slope * l.speed_mps, l.speed_mps * l.curvature_per_m);
            let cos = (w * t).cos();
            let p = |z: nalgebra::Complex<f64>| {
                let one = nalgebra::Complex::new(1.0, 0.0);
                z * (z * z - z * (2.0 * cos) + one) * (w * w * t)
                    + (z + one) * (z * (1.0 + c * t) - one) * (av * kp * (1.0 - cos))
            };
            let label = format!("kp {kp} T {t}");
            assert_nonzero_eigenvalues_are_roots(&l, 1e-9, 3, 1e-12 * (1.0 + kp), p, &label);
        }
    }

    /// The filtered difference by hand on the straight isoline: the estimator
    /// `D(z) = (1 - a)(z - 1) / (T (z - a))`, `a = exp(-T/tau)`, so the law is
    /// `K(z) = kp ((1 - a)(z - 1) + cT (z - a)) / (T (z - a))` and `1 - G K = 0` is
    /// `2 (z - 1)^2 (z - a) + alpha v T kp (z + 1)((1 - a)(z - 1) + cT (z - a)) = 0`, a cubic
    /// (the other two eigenvalues are zero); filter time constants on both sides of the period.
    #[test]
    fn the_filtered_difference_has_the_hand_derived_polynomial() {
        for (kp, t, tau_s) in [(3.0, 0.1, 0.05), (3.0, 0.1, 0.3), (1.0, 1.0, 0.25)] {
            let l = SampledLoop {
                estimator: EstimatorModel::FilteredDifference { tau_s },
                ..dubins(kp, 0.0, t)
            };
            let (av, c, a) = (l.slope * l.speed_mps, l.c1 / l.c2, (-t / tau_s).exp());
            let p = |z: nalgebra::Complex<f64>| {
                let one = nalgebra::Complex::new(1.0, 0.0);
                let za = z - one * a;
                (z - one) * (z - one) * za * 2.0
                    + (z + one) * ((z - one) * (1.0 - a) + za * (c * t)) * (av * t * kp)
            };
            // The two zero eigenvalues form a Jordan block that rounding splits into a pair of
            // about 1e-8.
            let label = format!("kp {kp} T {t} tau {tau_s}");
            assert_nonzero_eigenvalues_are_roots(&l, 1e-6, 3, 1e-10 * (1.0 + kp), p, &label);
        }
    }

    /// The bisection stops once `hi/lo < 1 + 1e-6`: from a scan step of `10^(1/20)` that is
    /// `ceil(log2(ln(10^(1/20)) / ln(1 + 1e-6))) = 17` halvings of the log-interval (each an
    /// eigenvalue problem per slope), and it returns the stable end within 1e-6 of the boundary.
    #[test]
    fn refine_stops_at_a_millionth() {
        let want = (0.05 * std::f64::consts::LN_10 / 1e-6f64.ln_1p())
            .log2()
            .ceil();
        assert_eq!(want, 17.0);
        let boundary = 1.05;
        let calls = std::cell::Cell::new(0);
        let got = refine(1.0, 10f64.powf(0.05), |x| {
            calls.set(calls.get() + 1);
            x < boundary
        });
        assert_eq!(calls.get() as f64, want);
        assert!(got < boundary && boundary / got < 1.0 + 1e-6, "{got}");
    }

    /// A fractional delay against the double integrator in closed form: on the straight
    /// isoline `z1' = v z2`, `z2' = u`, so `u` held for `tau` moves `z2` by `u tau` and `z1` by
    /// `v z2 tau + v u tau^2/2`. The sample taken `r` before each period's end is
    /// `eps_{k+1} = -alpha z1((k + 1)T - r)`, reached from `kT` over `T - r`; the law is
    /// `u_k = kp ((eps_k - eps_{k-1})/T + c eps_k)`. Twenty periods from one state, by hand and
    /// by the matrix, with `r` a quarter and three quarters of the period.
    #[test]
    fn a_fractional_delay_matches_the_double_integrator_by_hand() {
        let (kp, t) = (3.0, 0.2);
        for r in [0.25 * t, 0.75 * t] {
            let l = SampledLoop {
                delay_s: t + r,
                ..dubins(kp, 0.0, t)
            };
            let (v, alpha, c) = (l.speed_mps, l.slope, l.c1 / l.c2);
            let m = l.closed_loop_matrix().unwrap();
            // [z1, z2, w_k, w_{k-1}, eps_{k-1}]: one whole period of delay line.
            assert_eq!(m.nrows(), 5);
            let x0 = DVector::from_vec(vec![0.7, -0.2, -0.5, -0.6, -0.65]);
            let (mut z1, mut z2, mut w0, mut w1, mut prev) = (x0[0], x0[1], x0[2], x0[3], x0[4]);
            let mut x = x0;
            for k in 0..20 {
                let eps = w1;
                let u = kp * ((eps - prev) / t + c * eps);
                let tau = t - r;
                let w_next = -alpha * (z1 + v * z2 * tau + v * u * tau * tau / 2.0);
                (z1, z2) = (z1 + v * z2 * t + v * u * t * t / 2.0, z2 + u * t);
                (w0, w1, prev) = (w_next, w0, eps);
                x = &m * x;
                let hand = [z1, z2, w0, w1, prev];
                for (i, h) in hand.iter().enumerate() {
                    assert!(
                        (x[i] - h).abs() < 1e-12 * (1.0 + h.abs()),
                        "r {r}, step {k}, state {i}: {} vs {h}",
                        x[i]
                    );
                }
            }
        }
    }

    /// A lagged sensor stepped once per period (`h = T`) on the straight isoline, by hand: the
    /// reading `y_k = a y_{k-1} + (1 - a) eps_k` (`a = exp(-T/tau)`, updated after the move, so
    /// with `eps_k`) is `Y = (1 - a) z/(z - a) E`; with `G` and `K` of the worked case,
    /// `1 - G L K = 0` is
    /// `2 (z - 1)^2 (z - a) + alpha v T kp (1 - a)(z + 1)((1 + cT) z - 1) = 0`, a cubic.
    #[test]
    fn a_lag_stepped_once_per_period_has_the_hand_derived_polynomial() {
        for (kp, t, tau) in [(3.0, 0.1, 0.05), (3.0, 0.1, 0.4), (1.0, 1.0, 2.5)] {
            let l = SampledLoop {
                sensor_lag: Some(SensorLag {
                    time_constant_s: tau,
                    step_s: t,
                }),
                ..dubins(kp, 0.0, t)
            };
            let (av, c, a) = (l.slope * l.speed_mps, l.c1 / l.c2, (-t / tau).exp());
            let p = |z: nalgebra::Complex<f64>| {
                let one = nalgebra::Complex::new(1.0, 0.0);
                (z - one) * (z - one) * (z - one * a) * 2.0
                    + (z + one) * (z * (1.0 + c * t) - one) * (av * t * kp * (1.0 - a))
            };
            let label = format!("kp {kp} T {t} tau {tau}");
            assert_nonzero_eigenvalues_are_roots(&l, 1e-6, 3, 1e-10 * (1.0 + kp), p, &label);
        }
    }

    /// A lagged sensor stepped four times per period, behind a delay of one period and two
    /// steps, against the simulator's order written out by hand on the double integrator
    /// (straight isoline): at each step `h` the robot moves (`z1 += v z2 h + v u h^2/2`,
    /// `z2 += u h`) and then the reading follows, `y += (1 - exp(-h/tau)) (-alpha z1 - y)`; the
    /// value delivered at the next sample is the reading two steps before it, `r = 2 h`, and the
    /// law uses the one a period older still. Twenty periods from one state, by hand and by
    /// the matrix.
    #[test]
    fn a_lag_between_samples_matches_the_simulators_order_by_hand() {
        let (kp, t, h, tau) = (2.0, 0.2, 0.05, 0.3);
        let l = SampledLoop {
            delay_s: t + 2.0 * h,
            sensor_lag: Some(SensorLag {
                time_constant_s: tau,
                step_s: h,
            }),
            ..dubins(kp, 0.0, t)
        };
        let (v, alpha, c) = (l.speed_mps, l.slope, l.c1 / l.c2);
        let g = 1.0 - (-h / tau).exp();
        let m = l.closed_loop_matrix().unwrap();
        // [z1, z2, y, w_k, w_{k-1}, eps_{k-1}]
        assert_eq!(m.nrows(), 6);
        let x0 = DVector::from_vec(vec![0.7, -0.2, -0.6, -0.5, -0.65, -0.62]);
        let (mut z1, mut z2, mut y) = (x0[0], x0[1], x0[2]);
        let (mut w0, mut w1, mut prev) = (x0[3], x0[4], x0[5]);
        let mut x = x0;
        for k in 0..20 {
            let eps = w1;
            let u = kp * ((eps - prev) / t + c * eps);
            let mut w_next = f64::NAN;
            for j in 1..=4 {
                (z1, z2) = (z1 + v * z2 * h + v * u * h * h / 2.0, z2 + u * h);
                y += g * (-alpha * z1 - y);
                if j == 2 {
                    w_next = y;
                }
            }
            (w0, w1, prev) = (w_next, w0, eps);
            x = &m * x;
            let hand = [z1, z2, y, w0, w1, prev];
            for (i, want) in hand.iter().enumerate() {
                assert!(
                    (x[i] - want).abs() < 1e-12 * (1.0 + want.abs()),
                    "step {k}, state {i}: {} vs {want}",
                    x[i]
                );
            }
        }
    }

    /// A lag leaves the loop without a model when its time constant or step is not a positive
    /// finite number; a period that is not a whole number of steps is split into
    /// `round(T/h)` equal ones (0.1 s at steps of 0.03 s: three of 1/30 s).
    #[test]
    fn a_lag_needs_a_positive_time_constant_and_step() {
        let lagged = |time_constant_s: f64, step_s: f64| SampledLoop {
            sensor_lag: Some(SensorLag {
                time_constant_s,
                step_s,
            }),
            ..dubins(3.0, 0.0, 0.1)
        };
        for (tau, h) in [(0.0, 0.01), (-1.0, 0.01), (f64::NAN, 0.01), (1.0, 0.0)] {
            assert!(lagged(tau, h).closed_loop_matrix().is_none(), "{tau} {h}");
        }
        assert!(lagged(1.0, f64::INFINITY).closed_loop_matrix().is_none());
        assert_eq!(
            lagged(1.0, 0.03).closed_loop_matrix(),
            lagged(1.0, 0.1 / 3.0).closed_loop_matrix()
        );
    }
}
