//! The 12-state rigid-body model with the Aerosonde forces and moments (Beard & McLain 2012,
//! chapters 3-4; docs/FIXED-WING.md section 2).
//!
//! State `x = [pn, pe, pd, u, v, w, phi, theta, psi, p, q, r]` (NED position; `u, v, w` the
//! ground velocity in body axes; Euler angles; body rates). Inputs `[de, da, dr, dt]`: surfaces in
//! rad, throttle in [0, 1].

use super::params::Aerosonde;

/// The state vector.
pub type State12 = [f64; 12];

/// Actuator inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deltas {
    /// Elevator, rad.
    pub elevator_rad: f64,
    /// Aileron, rad.
    pub aileron_rad: f64,
    /// Rudder, rad.
    pub rudder_rad: f64,
    /// Throttle, 0..1.
    pub throttle: f64,
}

/// Wind: steady part in NED plus gusts in body axes, m/s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindSample {
    /// Steady wind `[w_n, w_e, w_d]`, m/s.
    pub steady_ned_mps: [f64; 3],
    /// Gusts `[u_wg, v_wg, w_wg]` in body axes, m/s.
    pub gust_body_mps: [f64; 3],
}

/// Air data of a state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AirData {
    /// Airspeed, m/s.
    pub va_mps: f64,
    /// Angle of attack `atan(w_r/u_r)`, rad.
    pub alpha_rad: f64,
    /// Sideslip `asin(v_r/Va)`, rad.
    pub beta_rad: f64,
}

/// Rotation body -> vehicle (NED) of Euler angles, row-major.
#[inline(always)]
pub fn r_body_to_ned(phi: f64, theta: f64, psi: f64) -> [[f64; 3]; 3] {
    let (s, c) = isotrack_core::lanes::sin_cos_lanes([phi, theta, psi, 0.0]);
    r_from_sincos((s[0], c[0]), (s[1], c[1]), (s[2], c[2]))
}

/// The sines and cosines of a state's Euler angles `(phi, theta, psi)`, computed once in lanes
/// and shared by what needs them at that state (the rotation, gravity, the kinematics).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EulerSinCos {
    /// The angles they are of, rad.
    pub angles: [f64; 3],
    sin: [f64; 4],
    cos: [f64; 4],
}

impl EulerSinCos {
    /// Of the angles `x[6..9]` of state `x`.
    #[inline(always)]
    pub fn of(x: &State12) -> Self {
        let (sin, cos) = isotrack_core::lanes::sin_cos_lanes([x[6], x[7], x[8], 0.0]);
        Self {
            angles: [x[6], x[7], x[8]],
            sin,
            cos,
        }
    }

    /// `(sin, cos)` of angle `k` (0 phi, 1 theta, 2 psi).
    #[inline(always)]
    pub fn sin_cos(&self, k: usize) -> (f64, f64) {
        (self.sin[k], self.cos[k])
    }

    /// Lane `i` of `e`, the sines and cosines of the angles `x[6..9]` of state `x`: what
    /// [`of`](Self::of) gives for `x` (the fourth lane, unused, that of angle 0).
    #[inline(always)]
    pub fn from_lane<const N: usize>(e: &EulerLanes<N>, x: &State12, i: usize) -> Self {
        let (s0, c0) = isotrack_core::lanes::sin_cos(0.0);
        Self {
            angles: [x[6], x[7], x[8]],
            sin: [e.sin[0][i], e.sin[1][i], e.sin[2][i], s0],
            cos: [e.cos[0][i], e.cos[1][i], e.cos[2][i], c0],
        }
    }

    /// Rotation body -> NED ([`r_body_to_ned`]).
    #[inline(always)]
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (s, c) = (self.sin, self.cos);
        r_from_sincos((s[0], c[0]), (s[1], c[1]), (s[2], c[2]))
    }
}

/// [`r_body_to_ned`] from `(sin, cos)` of the three angles.
#[inline(always)]
fn r_from_sincos(
    (sf, cf): (f64, f64),
    (st, ct): (f64, f64),
    (sp, cp): (f64, f64),
) -> [[f64; 3]; 3] {
    [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

/// Constants derived from the parameters once, for the force model's hot path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Derived {
    /// `Gamma, Gamma_1..Gamma_8`.
    pub gammas: [f64; 9],
    /// `e^{M alpha0}`.
    pub stall_k: f64,
    /// `pi e AR`.
    pub pi_e_ar: f64,
}

impl Derived {
    /// Computes the constants.
    pub fn new(p: &Aerosonde) -> Self {
        Self {
            gammas: p.gammas(),
            stall_k: (p.stall_m * p.alpha0).exp(),
            pi_e_ar: std::f64::consts::PI * p.e * p.aspect_ratio(),
        }
    }
}

/// Stall blending function `sigma(alpha)` (book eq. 4.10):
/// `(1 + e^{-M(a - a0)} + e^{M(a + a0)}) / ((1 + e^{-M(a - a0)})(1 + e^{M(a + a0)}))`,
/// computed with one exponential: `e^{-M(a - a0)} = K/E`, `e^{M(a + a0)} = K E`,
/// `E = e^{M a}`, `K = e^{M a0}`.
#[inline]
pub fn stall_blend(p: &Aerosonde, alpha: f64) -> f64 {
    stall_blend_k(p, (p.stall_m * p.alpha0).exp(), alpha)
}

#[inline(always)]
fn stall_blend_k(p: &Aerosonde, k: f64, alpha: f64) -> f64 {
    let e = (p.stall_m * alpha).exp();
    let (a, b) = (k / e, k * e);
    (1.0 + a + b) / ((1.0 + a) * (1.0 + b))
}

/// Lift coefficient with stall blending: `(1 - s)(C_L0 + C_La a) + s*2 sign(a) sin^2(a) cos(a)`
/// (`sign(0) = 0`).
#[inline]
pub fn lift_coefficient(p: &Aerosonde, alpha: f64) -> f64 {
    let (sa, ca) = alpha.sin_cos();
    lift_coefficient_sc(p, (p.stall_m * p.alpha0).exp(), alpha, sa, ca)
}

/// [`lift_coefficient`] with `e^{M alpha0}`, `sin(alpha)`, `cos(alpha)` already known.
#[inline(always)]
fn lift_coefficient_sc(p: &Aerosonde, k: f64, alpha: f64, sa: f64, ca: f64) -> f64 {
    let s = stall_blend_k(p, k, alpha);
    let sign = if alpha > 0.0 {
        1.0
    } else if alpha < 0.0 {
        -1.0
    } else {
        0.0
    };
    (1.0 - s) * (p.c_l0 + p.c_l_alpha * alpha) + s * 2.0 * sign * sa * sa * ca
}

/// The airspeed `|v_body - wind_body|` of state `x` in `wind`, m/s: [`air_data`]'s `va_mps`
/// without the angles (the autopilot needs only the airspeed).
#[inline(always)]
pub fn airspeed_mps(x: &State12, wind: &WindSample, r: &[[f64; 3]; 3]) -> f64 {
    let [va] = airspeed_lanes(
        &x.map(|v| [v]),
        &WindLanes::of(wind),
        &r.map(|row| row.map(|v| [v])),
    );
    va
}

/// [`airspeed_mps`] of `N` states in lanes (`x[k][i]`: component `k` of state `i`), the one
/// body of both.
#[inline(always)]
pub(crate) fn airspeed_lanes<const N: usize>(
    x: &[[f64; N]; 12],
    wind: &WindLanes<N>,
    r: &[[[f64; N]; 3]; 3],
) -> [f64; N] {
    let [ur, vr, wr] = air_relative_lanes(&[x[3], x[4], x[5]], wind, r);
    let mut va = [0.0; N];
    for i in 0..N {
        va[i] = (ur[i] * ur[i] + vr[i] * vr[i] + wr[i] * wr[i]).sqrt();
    }
    va
}

/// The air-relative velocity in body axes `(u_r, v_r, w_r)`: the body velocity less the wind
/// (steady wind rotated by `R_ned->body = R^T`, plus the body-axis gusts), m/s.
#[inline(always)]
fn air_relative_body(x: &State12, wind: &WindSample, r: &[[f64; 3]; 3]) -> (f64, f64, f64) {
    let [[ur], [vr], [wr]] = air_relative_lanes(
        &[[x[3]], [x[4]], [x[5]]],
        &WindLanes::of(wind),
        &r.map(|row| row.map(|v| [v])),
    );
    (ur, vr, wr)
}

/// [`air_relative_body`] of `N` states in lanes: the one body of both.
#[inline(always)]
fn air_relative_lanes<const N: usize>(
    uvw: &[[f64; N]; 3],
    wind: &WindLanes<N>,
    r: &[[[f64; N]; 3]; 3],
) -> [[f64; N]; 3] {
    let [wn, we, wd] = &wind.steady_ned_mps;
    let g = &wind.gust_body_mps;
    let mut out = [[0.0; N]; 3];
    for (k, o) in out.iter_mut().enumerate() {
        for i in 0..N {
            let wb = r[0][k][i] * wn[i] + r[1][k][i] * we[i] + r[2][k][i] * wd[i] + g[k][i];
            o[i] = uvw[k][i] - wb;
        }
    }
    out
}

/// Air data of state `x` in `wind`.
#[inline]
pub fn air_data(x: &State12, wind: &WindSample, r: &[[f64; 3]; 3]) -> AirData {
    air_data_sc(x, wind, r).0
}

/// [`air_data`] with `(sin(alpha), cos(alpha))` from the air-relative velocities: for
/// `alpha = atan(w_r/u_r)`, `cos(alpha) = |u_r|/sqrt(u_r^2 + w_r^2)` and
/// `sin(alpha) = (w_r/u_r) cos(alpha)` (no trigonometric call).
#[inline(always)]
fn air_data_sc(x: &State12, wind: &WindSample, r: &[[f64; 3]; 3]) -> (AirData, f64, f64) {
    let (ur, vr, wr) = air_relative_body(x, wind, r);
    let va = (ur * ur + vr * vr + wr * wr).sqrt();
    let beta = if va > 0.0 {
        (vr / va).clamp(-1.0, 1.0).asin()
    } else {
        0.0
    };
    let (alpha, sa, ca) = if ur != 0.0 {
        let ca = ur.abs() / (ur * ur + wr * wr).sqrt();
        ((wr / ur).atan(), wr / ur * ca, ca)
    } else {
        let a = wr.atan2(ur);
        let (sa, ca) = a.sin_cos();
        (a, sa, ca)
    };
    (
        AirData {
            va_mps: va,
            alpha_rad: alpha,
            beta_rad: beta,
        },
        sa,
        ca,
    )
}

/// The state derivative `f(x, delta, wind)`; forces and moments evaluated at `x`.
pub fn derivatives(
    p: &Aerosonde,
    dv: &Derived,
    x: &State12,
    d: &Deltas,
    wind: &WindSample,
) -> State12 {
    derivatives_inline(p, dv, x, d, wind)
}

/// [`derivatives`], always inlined: the closed-loop step is compiled for several instruction
/// sets (`FixedWing::step_with_commands`), and its callees must be inlined to be compiled with it.
#[inline(always)]
fn derivatives_inline(
    p: &Aerosonde,
    dv: &Derived,
    x: &State12,
    d: &Deltas,
    wind: &WindSample,
) -> State12 {
    // The three Euler angles' sines and cosines in one lane-wise call (isotrack_core::lanes:
    // vectorised, and no libm call on the RK4's four evaluations per step).
    derivatives_with(p, dv, x, d, wind, &EulerSinCos::of(x))
}

/// [`derivatives`] with the sines and cosines of `x`'s Euler angles already known: the lane
/// body ([`derivatives_lanes`]) with one lane, so a state stepped alone and the same state
/// stepped in lanes get the same numbers by construction.
#[inline(always)]
fn derivatives_with(
    p: &Aerosonde,
    dv: &Derived,
    x: &State12,
    d: &Deltas,
    wind: &WindSample,
    euler: &EulerSinCos,
) -> State12 {
    let e = EulerLanes {
        sin: [[euler.sin[0]], [euler.sin[1]], [euler.sin[2]]],
        cos: [[euler.cos[0]], [euler.cos[1]], [euler.cos[2]]],
    };
    derivatives_lanes(
        p,
        dv,
        &x.map(|v| [v]),
        &DeltasLanes::of(d),
        &WindLanes::of(wind),
        &e,
    )
    .map(|[v]| v)
}

/// The deflections of `N` aircraft, one lane each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DeltasLanes<const N: usize> {
    /// Elevator, rad.
    pub elevator_rad: [f64; N],
    /// Aileron, rad.
    pub aileron_rad: [f64; N],
    /// Rudder, rad.
    pub rudder_rad: [f64; N],
    /// Throttle, 0..1.
    pub throttle: [f64; N],
}

impl DeltasLanes<1> {
    /// One aircraft's deflections as one lane.
    #[inline(always)]
    pub fn of(d: &Deltas) -> Self {
        Self {
            elevator_rad: [d.elevator_rad],
            aileron_rad: [d.aileron_rad],
            rudder_rad: [d.rudder_rad],
            throttle: [d.throttle],
        }
    }
}

/// The wind of `N` aircraft, one lane each (see [`WindSample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WindLanes<const N: usize> {
    /// Steady wind `[w_n, w_e, w_d]`, m/s.
    pub steady_ned_mps: [[f64; N]; 3],
    /// Gusts `[u_wg, v_wg, w_wg]` in body axes, m/s.
    pub gust_body_mps: [[f64; N]; 3],
}

impl WindLanes<1> {
    /// One aircraft's wind as one lane.
    #[inline(always)]
    pub fn of(w: &WindSample) -> Self {
        Self {
            steady_ned_mps: w.steady_ned_mps.map(|v| [v]),
            gust_body_mps: w.gust_body_mps.map(|v| [v]),
        }
    }
}

/// The sines and cosines of `N` states' Euler angles `(phi, theta, psi)`, one lane each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EulerLanes<const N: usize> {
    /// `sin` of phi, theta, psi.
    pub sin: [[f64; N]; 3],
    /// `cos` of phi, theta, psi.
    pub cos: [[f64; N]; 3],
}

impl<const N: usize> EulerLanes<N> {
    /// Of the angles `x[6..9]` of the states `x` (three `sin_cos` in lanes: each lane the
    /// value [`EulerSinCos::of`] gives, the functions being lane-wise).
    #[inline(always)]
    pub fn of(x: &[[f64; N]; 12]) -> Self {
        let (s0, c0) = isotrack_core::lanes::sin_cos_lanes(x[6]);
        let (s1, c1) = isotrack_core::lanes::sin_cos_lanes(x[7]);
        let (s2, c2) = isotrack_core::lanes::sin_cos_lanes(x[8]);
        Self {
            sin: [s0, s1, s2],
            cos: [c0, c1, c2],
        }
    }

    /// Rotation body -> NED of each lane ([`r_body_to_ned`]'s formula).
    #[inline(always)]
    pub fn rotation(&self) -> [[[f64; N]; 3]; 3] {
        let [sf, st, sp] = &self.sin;
        let [cf, ct, cp] = &self.cos;
        // `r_from_sincos`'s entries, each one lane-wise loop.
        [
            [
                lanewise(|i| ct[i] * cp[i]),
                lanewise(|i| sf[i] * st[i] * cp[i] - cf[i] * sp[i]),
                lanewise(|i| cf[i] * st[i] * cp[i] + sf[i] * sp[i]),
            ],
            [
                lanewise(|i| ct[i] * sp[i]),
                lanewise(|i| sf[i] * st[i] * sp[i] + cf[i] * cp[i]),
                lanewise(|i| cf[i] * st[i] * sp[i] - sf[i] * cp[i]),
            ],
            [
                lanewise(|i| -st[i]),
                lanewise(|i| sf[i] * ct[i]),
                lanewise(|i| cf[i] * ct[i]),
            ],
        ]
    }
}

/// `[f64; N]` of `f(i)` for each lane `i`.
#[inline(always)]
fn lanewise<const N: usize>(f: impl Fn(usize) -> f64) -> [f64; N] {
    let mut o = [0.0; N];
    for (i, o) in o.iter_mut().enumerate() {
        *o = f(i);
    }
    o
}

/// `[f64; N]` from a lane-wise expression in lane index `$i`.
macro_rules! lanes {
    ($n:expr, $i:ident => $e:expr) => {{
        let mut o = [0.0f64; $n];
        for $i in 0..$n {
            o[$i] = $e;
        }
        o
    }};
}

/// The state derivative of `N` states in lanes (structure of arrays: `x[k][i]` is component `k`
/// of state `i`): the one body of the scalar [`derivatives`] (with one lane) and of the lane
/// step. Written branch-free (both sides computed, the answer selected per lane) so that its
/// arithmetic vectorises; the transcendentals without a lane form (`asin` of the sideslip,
/// `atan` of the angle of attack, the stall blend's `exp`) are the platform's, lane by lane.
/// Each lane's numbers are those of the same operations on that lane alone.
#[inline(always)]
pub(crate) fn derivatives_lanes<const N: usize>(
    p: &Aerosonde,
    dv: &Derived,
    x: &[[f64; N]; 12],
    d: &DeltasLanes<N>,
    wind: &WindLanes<N>,
    euler: &EulerLanes<N>,
) -> [[f64; N]; 12] {
    let gm = &dv.gammas;
    let [u, v, w] = [&x[3], &x[4], &x[5]];
    let [pr, qr, rr] = [&x[9], &x[10], &x[11]];
    let [sf, st, _] = &euler.sin;
    let [cf, ct, _] = &euler.cos;
    let r = euler.rotation();
    let air = AirLanes::of(p, &air_relative_lanes(&[*u, *v, *w], wind, &r));
    let m = p.mass_kg;
    let mut out = [[0.0; N]; 12];
    for i in 0..N {
        let (u, v, w) = (u[i], v[i], w[i]);
        let (pr, qr, rr) = (pr[i], qr[i], rr[i]);
        let (sf, cf, st, ct) = (sf[i], cf[i], st[i], ct[i]);
        let deltas = [
            d.elevator_rad[i],
            d.aileron_rad[i],
            d.rudder_rad[i],
            d.throttle[i],
        ];
        let ([fx, fy, fz], [ell, mm, nn]) =
            forces_moments(p, dv, &air.lane(i), [sf, cf, st, ct], [pr, qr, rr], deltas);
        let tt = st / ct;
        let f = [
            r[0][0][i] * u + r[0][1][i] * v + r[0][2][i] * w,
            r[1][0][i] * u + r[1][1][i] * v + r[1][2][i] * w,
            r[2][0][i] * u + r[2][1][i] * v + r[2][2][i] * w,
            rr * v - qr * w + fx / m,
            pr * w - rr * u + fy / m,
            qr * u - pr * v + fz / m,
            pr + qr * sf * tt + rr * cf * tt,
            qr * cf - rr * sf,
            (qr * sf + rr * cf) / ct,
            gm[1] * pr * qr - gm[2] * qr * rr + gm[3] * ell + gm[4] * nn,
            gm[5] * pr * rr - gm[6] * (pr * pr - rr * rr) + mm / p.jy,
            gm[7] * pr * qr - gm[1] * qr * rr + gm[4] * ell + gm[8] * nn,
        ];
        for (o, fk) in out.iter_mut().zip(f) {
            o[i] = fk;
        }
    }
    out
}

/// The air data of `N` states in lanes (`air_data_sc`'s formulas) from their air-relative
/// body velocities `[ur, vr, wr]`: the airspeed `Va`, the sideslip `beta = asin(vr / Va)` (0 at
/// `Va = 0`), the angle of attack `alpha = atan(wr / ur)` with its sine and cosine (from the
/// tangent; by `atan2` where `ur = 0`), and the stall blend's `exp(M alpha)`.
struct AirLanes<const N: usize> {
    /// Airspeed `Va`, m/s.
    va: [f64; N],
    /// Angle of attack, rad.
    alpha: [f64; N],
    /// Sideslip, rad.
    beta: [f64; N],
    /// `sin(alpha)`.
    sa: [f64; N],
    /// `cos(alpha)`.
    ca: [f64; N],
    /// `exp(M alpha)` (`M`: [`Aerosonde::stall_m`]).
    e: [f64; N],
}

/// One lane of [`AirLanes`].
#[derive(Clone, Copy)]
struct AirLane {
    va: f64,
    alpha: f64,
    beta: f64,
    sa: f64,
    ca: f64,
    e: f64,
}

impl<const N: usize> AirLanes<N> {
    /// Of the air-relative body velocities `[ur, vr, wr]` (the square roots and divisions in
    /// lanes; the `asin`, `atan` and `exp`, which have no lane form, lane by lane).
    #[inline(always)]
    fn of(p: &Aerosonde, [ur, vr, wr]: &[[f64; N]; 3]) -> Self {
        let va = lanes!(N, i => (ur[i] * ur[i] + vr[i] * vr[i] + wr[i] * wr[i]).sqrt());
        let ratio = lanes!(N, i => (vr[i] / va[i]).clamp(-1.0, 1.0));
        let ca0 = lanes!(N, i => ur[i].abs() / (ur[i] * ur[i] + wr[i] * wr[i]).sqrt());
        let tan_a = lanes!(N, i => wr[i] / ur[i]);
        let mut beta = [0.0; N];
        let mut alpha = [0.0; N];
        let mut sa = [0.0; N];
        let mut ca = [0.0; N];
        let mut e = [0.0; N];
        for i in 0..N {
            beta[i] = if va[i] > 0.0 { ratio[i].asin() } else { 0.0 };
            (alpha[i], sa[i], ca[i]) = if ur[i] != 0.0 {
                (tan_a[i].atan(), tan_a[i] * ca0[i], ca0[i])
            } else {
                let a = wr[i].atan2(ur[i]);
                let (s, c) = a.sin_cos();
                (a, s, c)
            };
            e[i] = (p.stall_m * alpha[i]).exp();
        }
        Self {
            va,
            alpha,
            beta,
            sa,
            ca,
            e,
        }
    }

    /// Lane `i`.
    #[inline(always)]
    fn lane(&self, i: usize) -> AirLane {
        AirLane {
            va: self.va[i],
            alpha: self.alpha[i],
            beta: self.beta[i],
            sa: self.sa[i],
            ca: self.ca[i],
            e: self.e[i],
        }
    }
}

/// One aircraft's body forces `[fx, fy, fz]` (N) and moments `[l, m, n]` (N m) (Beard &
/// McLain, 2012, ch. 4): gravity, from the attitude `[sin phi, cos phi, sin theta, cos theta]`;
/// the aerodynamics ([`aerodynamics`]), with air motion only (at `Va = 0` their terms are not
/// finite and left out, selected branch-free); the propeller's thrust and torque from the
/// throttle (the 2012 model). `rates`: `[p, q, r]`, rad/s; `deltas`: elevator, aileron,
/// rudder (rad) and throttle.
#[inline(always)]
fn forces_moments(
    p: &Aerosonde,
    dv: &Derived,
    air: &AirLane,
    [sf, cf, st, ct]: [f64; 4],
    rates: [f64; 3],
    deltas: [f64; 4],
) -> ([f64; 3], [f64; 3]) {
    let m = p.mass_kg;
    let va = air.va;
    let dt = deltas[3];
    // Gravity.
    let gravity = [-m * p.g * st, m * p.g * ct * sf, m * p.g * ct * cf];
    let [afx, afy, afz, aell, amm, ann] = aerodynamics(p, dv, air, gravity, rates, deltas);
    let moving = va > 0.0;
    let pick = |a: f64, b: f64| if moving { a } else { b };
    let mut fx = pick(afx, gravity[0]);
    let fy = pick(afy, gravity[1]);
    let fz = pick(afz, gravity[2]);
    let mut ell = pick(aell, 0.0);
    let mm = pick(amm, 0.0);
    let nn = pick(ann, 0.0);
    // Propulsion (2012 model).
    let km = p.k_motor * dt;
    fx += 0.5 * p.rho * p.s_prop * p.c_prop * (km * km - va * va);
    let ko = p.k_omega * dt;
    ell -= p.k_tp * ko * ko;
    ([fx, fy, fz], [ell, mm, nn])
}

/// The forces `gravity` plus the aerodynamic forces, and the aerodynamic moments, of one
/// aircraft in moving air (Beard & McLain, 2012, ch. 4): the stall blend and lift coefficient
/// (`stall_blend_k`, `lift_coefficient_sc`), the drag polar, the body-axis coefficients rotated
/// by the angle of attack, the rate and control derivatives. Not finite at `Va = 0`.
#[inline(always)]
fn aerodynamics(
    p: &Aerosonde,
    dv: &Derived,
    air: &AirLane,
    [fx, fy, fz]: [f64; 3],
    [pr, qr, rr]: [f64; 3],
    [de, da, dr, _]: [f64; 4],
) -> [f64; 6] {
    let AirLane {
        va,
        alpha,
        beta,
        sa,
        ca,
        e,
    } = *air;
    let k = dv.stall_k;
    let qbar = 0.5 * p.rho * va * va;
    // The stall blend and lift coefficient (`stall_blend_k`, `lift_coefficient_sc`).
    let (a, b) = (k / e, k * e);
    let s = (1.0 + a + b) / ((1.0 + a) * (1.0 + b));
    let sign = if alpha > 0.0 {
        1.0
    } else if alpha < 0.0 {
        -1.0
    } else {
        0.0
    };
    let cl = (1.0 - s) * (p.c_l0 + p.c_l_alpha * alpha) + s * 2.0 * sign * sa * sa * ca;
    let lin = p.c_l0 + p.c_l_alpha * alpha;
    let cd = p.c_d_p + lin * lin / dv.pi_e_ar;
    let cx = -cd * ca + cl * sa;
    let cxq = -p.c_d_q * ca + p.c_l_q * sa;
    let cxde = -p.c_d_de * ca + p.c_l_de * sa;
    let cz = -cd * sa - cl * ca;
    let czq = -p.c_d_q * sa - p.c_l_q * ca;
    let czde = -p.c_d_de * sa - p.c_l_de * ca;
    let cq = p.c * qr / (2.0 * va);
    let bp = p.b * pr / (2.0 * va);
    let br = p.b * rr / (2.0 * va);
    let afx = fx + qbar * p.s * (cx + cxq * cq + cxde * de);
    let afy = fy
        + qbar
            * p.s
            * (p.c_y0
                + p.c_y_beta * beta
                + p.c_y_p * bp
                + p.c_y_r * br
                + p.c_y_da * da
                + p.c_y_dr * dr);
    let afz = fz + qbar * p.s * (cz + czq * cq + czde * de);
    let aell = qbar
        * p.s
        * p.b
        * (p.c_ell0
            + p.c_ell_beta * beta
            + p.c_ell_p * bp
            + p.c_ell_r * br
            + p.c_ell_da * da
            + p.c_ell_dr * dr);
    let amm = qbar * p.s * p.c * (p.c_m0 + p.c_m_alpha * alpha + p.c_m_q * cq + p.c_m_de * de);
    let ann = qbar
        * p.s
        * p.b
        * (p.c_n0
            + p.c_n_beta * beta
            + p.c_n_p * bp
            + p.c_n_r * br
            + p.c_n_da * da
            + p.c_n_dr * dr);
    [afx, afy, afz, aell, amm, ann]
}

/// One RK4 step of `N` states in lanes ([`rk4_step_inline`]'s formulas), deflections and wind
/// held per lane, `euler` of `x`.
#[inline(always)]
pub(crate) fn rk4_lanes<const N: usize>(
    p: &Aerosonde,
    gm: &Derived,
    x: &mut [[f64; N]; 12],
    d: &DeltasLanes<N>,
    wind: &WindLanes<N>,
    dt_s: f64,
    euler: &EulerLanes<N>,
) {
    // Element-wise over the 12 N numbers as one flat run (which vectorises plainly).
    let add = |a: &[[f64; N]; 12], k: &[[f64; N]; 12], h: f64| {
        let mut o = *a;
        for (o, k) in o.as_flattened_mut().iter_mut().zip(k.as_flattened()) {
            *o += h * k;
        }
        o
    };
    let stage = |x: &[[f64; N]; 12]| derivatives_lanes(p, gm, x, d, wind, &EulerLanes::of(x));
    let k1 = derivatives_lanes(p, gm, x, d, wind, euler);
    let k2 = stage(&add(x, &k1, 0.5 * dt_s));
    let k3 = stage(&add(x, &k2, 0.5 * dt_s));
    let k4 = stage(&add(x, &k3, dt_s));
    let k = k1
        .as_flattened()
        .iter()
        .zip(k2.as_flattened())
        .zip(k3.as_flattened())
        .zip(k4.as_flattened());
    for (x, (((k1, k2), k3), k4)) in x.as_flattened_mut().iter_mut().zip(k) {
        *x += dt_s / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
}

/// One classical RK4 step of `dt_s` with inputs and wind held, forces re-evaluated at every
/// stage.
pub fn rk4_step(
    p: &Aerosonde,
    gm: &Derived,
    x: &mut State12,
    d: &Deltas,
    wind: &WindSample,
    dt_s: f64,
) {
    rk4_step_inline(p, gm, x, d, wind, dt_s, &EulerSinCos::of(x));
}

/// [`rk4_step`], always inlined (see [`derivatives_inline`]), with the sines and cosines of
/// `x`'s Euler angles given (`euler`, of `x`).
#[inline(always)]
pub(crate) fn rk4_step_inline(
    p: &Aerosonde,
    gm: &Derived,
    x: &mut State12,
    d: &Deltas,
    wind: &WindSample,
    dt_s: f64,
    euler: &EulerSinCos,
) {
    let add = |a: &State12, k: &State12, h: f64| {
        let mut o = *a;
        for i in 0..12 {
            o[i] += h * k[i];
        }
        o
    };
    // The first stage is at `x` itself, whose angles' sines and cosines the caller has.
    let k1 = derivatives_with(p, gm, x, d, wind, euler);
    let k2 = derivatives_inline(p, gm, &add(x, &k1, 0.5 * dt_s), d, wind);
    let k3 = derivatives_inline(p, gm, &add(x, &k2, 0.5 * dt_s), d, wind);
    let k4 = derivatives_inline(p, gm, &add(x, &k3, dt_s), d, wind);
    for i in 0..12 {
        x[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stall blend by Beard & McLain's eq. (4.10) written out, on both sides of the
    /// origin (below `-alpha0` the second exponential is small and the blend's form matters).
    #[test]
    fn stall_blend_by_its_formula_for_negative_and_positive_alpha() {
        let p = Aerosonde::beard_mclain_2012();
        for alpha in [-0.7, -0.6, -0.5, -0.47, -0.3, 0.0, 0.3, 0.5, 0.6, 0.7] {
            let a: f64 = (-p.stall_m * (alpha - p.alpha0)).exp();
            let b: f64 = (p.stall_m * (alpha + p.alpha0)).exp();
            let want = (1.0 + a + b) / ((1.0 + a) * (1.0 + b));
            let got = stall_blend(&p, alpha);
            assert!(
                (got - want).abs() <= 1e-12 * want.max(1e-300),
                "{alpha}: {got} vs {want}"
            );
            let lin = p.c_l0 + p.c_l_alpha * alpha;
            let flat = 2.0 * f64::signum(alpha) * alpha.sin().powi(2) * alpha.cos();
            let cl = (1.0 - want) * lin + want * if alpha == 0.0 { 0.0 } else { flat };
            assert!(
                (lift_coefficient(&p, alpha) - cl).abs() < 1e-12,
                "C_L at {alpha}"
            );
        }
    }

    /// Air data at the edges: no air motion gives Va = 0 with alpha = beta = 0 (and finite
    /// derivatives: only gravity and the propeller act); flying backwards through the air
    /// (u_r < 0) keeps Beard's alpha = atan(w_r/u_r), with cos(alpha) = |u_r|/sqrt(u_r^2 + w_r^2).
    #[test]
    fn air_data_without_air_motion_and_backwards() {
        let p = Aerosonde::beard_mclain_2012();
        let dv = Derived::new(&p);
        let wind = WindSample {
            steady_ned_mps: [3.0, -2.0, 0.0],
            gust_body_mps: [0.0; 3],
        };
        // Level, heading north: body axes = NED, so body velocity = wind is still air.
        let mut x = [0.0; 12];
        x[2] = -100.0;
        x[3..6].copy_from_slice(&[3.0, -2.0, 0.0]);
        let r = r_body_to_ned(0.0, 0.0, 0.0);
        let air = air_data(&x, &wind, &r);
        assert_eq!((air.va_mps, air.alpha_rad, air.beta_rad), (0.0, 0.0, 0.0));
        let d = Deltas {
            throttle: 0.5,
            ..Deltas::default()
        };
        let f = derivatives(&p, &dv, &x, &d, &wind);
        assert!(f.iter().all(|v| v.is_finite()), "{f:?}");
        let thrust = 0.5 * p.rho * p.s_prop * p.c_prop * (p.k_motor * 0.5).powi(2);
        assert!((f[3] - thrust / p.mass_kg).abs() < 1e-12, "{}", f[3]);
        assert!(
            (f[5] - p.g).abs() < 1e-12,
            "free fall in still air: {}",
            f[5]
        );
        // Backwards: u_r = -10, w_r = 2.
        x[3..6].copy_from_slice(&[3.0 - 10.0, -2.0, 2.0]);
        let air = air_data(&x, &wind, &r);
        assert!((air.alpha_rad - (2.0f64 / -10.0).atan()).abs() < 1e-15);
        assert!((air.va_mps - 104f64.sqrt()).abs() < 1e-12);
    }

    /// `airspeed_mps` is `air_data`'s `va_mps` (and `|v_body - wind_body|` by nalgebra) for
    /// states with sideslip, climb, wind and gusts.
    #[test]
    fn airspeed_alone_equals_the_air_datas() {
        use nalgebra::{Rotation3, Vector3};
        let wind = WindSample {
            steady_ned_mps: [4.0, -3.0, 1.0],
            gust_body_mps: [0.5, -1.5, 0.7],
        };
        for (i, att) in [[0.1, 0.05, 1.0], [-0.4, 0.2, -2.0], [0.0, -0.1, 3.0]]
            .iter()
            .enumerate()
        {
            let mut x = [0.0; 12];
            x[3..6].copy_from_slice(&[28.0 - i as f64, 3.0 + i as f64, -2.0]);
            x[6..9].copy_from_slice(att);
            let r = r_body_to_ned(att[0], att[1], att[2]);
            let va = airspeed_mps(&x, &wind, &r);
            assert_eq!(va, air_data(&x, &wind, &r).va_mps);
            let rot = Rotation3::from_euler_angles(att[0], att[1], att[2]);
            let wb = rot.inverse() * Vector3::from(wind.steady_ned_mps)
                + Vector3::from(wind.gust_body_mps);
            let want = (Vector3::new(x[3], x[4], x[5]) - wb).norm();
            assert!((va - want).abs() < 1e-12, "{va} vs {want}");
        }
    }

    #[test]
    fn stall_blend_reference_values() {
        let p = Aerosonde::beard_mclain_2012();
        assert!((stall_blend(&p, p.alpha0) - 0.5).abs() < 1e-12);
        assert!((lift_coefficient(&p, 0.4712) - 1.136439).abs() < 1e-6);
        assert!((lift_coefficient(&p, 0.6) - 0.529176).abs() < 1e-6);
        // Inactive in level flight: C_L = C_L0 + C_La a to 1e-9.
        let a = 0.033;
        assert!((lift_coefficient(&p, a) - (0.28 + 3.45 * a)).abs() < 1e-9);
        assert_eq!(
            lift_coefficient(&p, 0.0),
            (1.0 - stall_blend(&p, 0.0)) * 0.28
        );
    }

    #[test]
    fn rotation_is_orthonormal() {
        let r = r_body_to_ned(0.3, -0.2, 1.1);
        for i in 0..3 {
            for j in 0..3 {
                let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                assert!((dot - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
    }

    /// The state derivative against a second, independent formulation of Beard & McLain's
    /// model (Small Unmanned Aircraft, 2012, ch. 3-4) written with nalgebra: the rotation from
    /// `Rotation3::from_euler_angles` (not the hand-expanded matrix), lift and drag in the
    /// stability frame rotated by `alpha`, gravity as `R^T [0, 0, m g]`, the stall blend from
    /// its two exponentials, and the rotational dynamics as `J^-1 (M - w x J w)` with the
    /// inertia matrix inverted numerically (not the Gamma constants). States spread over
    /// attitudes, rates, winds, gusts and all four controls; agreement to 1e-9 relative.
    /// RK4 is fourth order: over one interval from a manoeuvring state (rolling, pitching,
    /// yawing, in wind and gusts, all four controls away from trim), halving the step divides
    /// the error (against 512 steps) by about 2^4 = 16; a method of order q divides it by 2^q.
    #[test]
    fn rk4_steps_are_fourth_order() {
        let p = Aerosonde::beard_mclain_2012();
        let dv = Derived::new(&p);
        let x0: State12 = [
            0.0, 0.0, -100.0, 28.0, 1.5, 2.0, 0.3, 0.1, 0.5, 0.4, -0.2, 0.3,
        ];
        let d = Deltas {
            elevator_rad: -0.2,
            aileron_rad: 0.1,
            rudder_rad: -0.05,
            throttle: 0.8,
        };
        let wind = WindSample {
            steady_ned_mps: [3.0, -2.0, 0.5],
            gust_body_mps: [1.0, -0.5, 0.8],
        };
        let span = 0.02;
        let fly = |n: usize| {
            let mut x = x0;
            for _ in 0..n {
                rk4_step(&p, &dv, &mut x, &d, &wind, span / n as f64);
            }
            x
        };
        let reference = fly(512);
        let error = |x: State12| {
            (0..12)
                .map(|k| (x[k] - reference[k]).abs())
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (error(fly(1)), error(fly(2)));
        let ratio = e1 / e2;
        assert!(
            (10.0..24.0).contains(&ratio),
            "errors {e1}, {e2}: ratio {ratio}"
        );
    }

    #[test]
    fn derivatives_match_an_independent_newton_euler_formulation() {
        // The 2012 airframe, and the same with the coefficients it sets to 0 given values (the
        // book's C_L_q = 7.95 among them; the others are made up, of the size of their neighbours):
        // the model must hold for any parameters, and a zero coefficient would hide a wrong sign or
        // product in its term.
        let other = Aerosonde {
            c_l_q: 7.95,
            c_d_q: 0.1,
            c_d_de: 0.0135,
            c_y0: 0.01,
            c_y_p: 0.02,
            c_y_r: 0.03,
            c_y_da: -0.015,
            c_ell0: 0.004,
            c_n0: -0.003,
            // Propeller torque (the book's K_Tp, K_Omega; 0 in the 2012 code): about 0.9 N m
            // at full throttle, the order of the aileron's roll moment.
            k_tp: 1.0e-3,
            k_omega: 30.0,
            c_prop: 0.9,
            ..Aerosonde::beard_mclain_2012()
        };
        for p in [Aerosonde::beard_mclain_2012(), other] {
            newton_euler_check(p);
        }
    }

    fn newton_euler_check(p: Aerosonde) {
        use nalgebra::{Matrix3, Rotation3, Vector3};
        let dv = Derived::new(&p);
        let oracle = |x: &State12, d: &Deltas, wind: &WindSample| -> State12 {
            let rot = Rotation3::from_euler_angles(x[6], x[7], x[8]);
            let vb = Vector3::new(x[3], x[4], x[5]);
            let om = Vector3::new(x[9], x[10], x[11]);
            let wb = rot.inverse() * Vector3::from(wind.steady_ned_mps)
                + Vector3::from(wind.gust_body_mps);
            let vr = vb - wb;
            let va = vr.norm();
            let alpha = vr.z.atan2(vr.x);
            let beta = (vr.y / va).asin();
            let qbar = 0.5 * p.rho * va * va;
            let m = p.mass_kg;
            let sigma = {
                let a = (-p.stall_m * (alpha - p.alpha0)).exp();
                let b = (p.stall_m * (alpha + p.alpha0)).exp();
                (1.0 + a + b) / ((1.0 + a) * (1.0 + b))
            };
            let lin = p.c_l0 + p.c_l_alpha * alpha;
            let flat = 2.0 * alpha.signum() * alpha.sin().powi(2) * alpha.cos();
            let cl = (1.0 - sigma) * lin + sigma * flat;
            let cd = p.c_d_p + lin * lin / (std::f64::consts::PI * p.e * p.b * p.b / p.s);
            let (cq, bp, br) = (
                p.c * x[10] / (2.0 * va),
                p.b * x[9] / (2.0 * va),
                p.b * x[11] / (2.0 * va),
            );
            let lift = qbar * p.s * (cl + p.c_l_q * cq + p.c_l_de * d.elevator_rad);
            let drag = qbar * p.s * (cd + p.c_d_q * cq + p.c_d_de * d.elevator_rad);
            let (sa, ca) = alpha.sin_cos();
            let side = qbar
                * p.s
                * (p.c_y0
                    + p.c_y_beta * beta
                    + p.c_y_p * bp
                    + p.c_y_r * br
                    + p.c_y_da * d.aileron_rad
                    + p.c_y_dr * d.rudder_rad);
            let prop =
                0.5 * p.rho * p.s_prop * p.c_prop * ((p.k_motor * d.throttle).powi(2) - va * va);
            let gravity = rot.inverse() * Vector3::new(0.0, 0.0, m * p.g);
            let force = Vector3::new(
                ca * -drag - sa * -lift + prop,
                side,
                sa * -drag + ca * -lift,
            ) + gravity;
            let ell = qbar
                * p.s
                * p.b
                * (p.c_ell0
                    + p.c_ell_beta * beta
                    + p.c_ell_p * bp
                    + p.c_ell_r * br
                    + p.c_ell_da * d.aileron_rad
                    + p.c_ell_dr * d.rudder_rad)
                - p.k_tp * (p.k_omega * d.throttle).powi(2);
            let mm = qbar
                * p.s
                * p.c
                * (p.c_m0 + p.c_m_alpha * alpha + p.c_m_q * cq + p.c_m_de * d.elevator_rad);
            let nn = qbar
                * p.s
                * p.b
                * (p.c_n0
                    + p.c_n_beta * beta
                    + p.c_n_p * bp
                    + p.c_n_r * br
                    + p.c_n_da * d.aileron_rad
                    + p.c_n_dr * d.rudder_rad);
            let j = Matrix3::new(p.jx, 0.0, -p.jxz, 0.0, p.jy, 0.0, -p.jxz, 0.0, p.jz);
            let om_dot =
                j.try_inverse().unwrap() * (Vector3::new(ell, mm, nn) - om.cross(&(j * om)));
            let v_dot = force / m - om.cross(&vb);
            let pos_dot = rot * vb;
            let (sf, cf) = x[6].sin_cos();
            let (tt, ct) = (x[7].tan(), x[7].cos());
            let eul = Matrix3::new(1.0, sf * tt, cf * tt, 0.0, cf, -sf, 0.0, sf / ct, cf / ct) * om;
            [
                pos_dot.x, pos_dot.y, pos_dot.z, v_dot.x, v_dot.y, v_dot.z, eul.x, eul.y, eul.z,
                om_dot.x, om_dot.y, om_dot.z,
            ]
        };
        let mut seed: u64 = 0x2545_F491_4F6C_DD1D;
        let mut rnd = |lo: f64, hi: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (hi - lo) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
        };
        for _ in 0..200 {
            let x: State12 = [
                rnd(-100.0, 100.0),
                rnd(-100.0, 100.0),
                rnd(-120.0, -80.0),
                rnd(20.0, 35.0),
                rnd(-3.0, 3.0),
                rnd(-4.0, 6.0),
                rnd(-0.8, 0.8),
                rnd(-0.4, 0.4),
                rnd(-3.0, 3.0),
                rnd(-1.0, 1.0),
                rnd(-0.5, 0.5),
                rnd(-0.5, 0.5),
            ];
            let d = Deltas {
                elevator_rad: rnd(-0.3, 0.3),
                aileron_rad: rnd(-0.3, 0.3),
                rudder_rad: rnd(-0.3, 0.3),
                throttle: rnd(0.0, 1.0),
            };
            let wind = WindSample {
                steady_ned_mps: [rnd(-5.0, 5.0), rnd(-5.0, 5.0), rnd(-1.0, 1.0)],
                gust_body_mps: [rnd(-2.0, 2.0), rnd(-2.0, 2.0), rnd(-2.0, 2.0)],
            };
            let got = derivatives(&p, &dv, &x, &d, &wind);
            let want = oracle(&x, &d, &wind);
            for k in 0..12 {
                let tol = 1e-9 * (1.0 + want[k].abs());
                assert!(
                    (got[k] - want[k]).abs() < tol,
                    "component {k}: {} vs {}",
                    got[k],
                    want[k]
                );
            }
        }
    }
}
