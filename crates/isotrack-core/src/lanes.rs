//! Elementary functions written once, branch-free, for one value and for `N` lanes at a time.
//!
//! The simulation loop spends most of its time in `exp` (the field), `tanh` (the PI-like law)
//! and `sin_cos` (the Dubins step). The platform's libm computes them with branches and table
//! look-ups a compiler cannot vectorise, and a batched sweep steps several runs at once in
//! SIMD lanes. So each function here is one straight-line body (both sides of every case
//! computed, the answer selected), which the compiler turns into scalar code for one value and
//! into vector code for `[f64; N]` (AVX2 / AVX-512 where the caller is compiled for them). The
//! scalar and the lane forms are the same arithmetic, so a run stepped alone and the same run
//! stepped in a batch agree bit for bit. Only IEEE `+ - * /` and exact bit manipulation are
//! used (no fused multiply-add, whose presence differs between machines), so the results are
//! also the same on every x86-64 and ARM machine.
//!
//! Why by hand: the SIMD math crates checked (`wide`'s `exp`/`sin_cos`, `sleef`) either need
//! nightly Rust, give a different answer from their scalar counterpart, or vectorise only to
//! the instruction set fixed at compile time; none gives one function for a scalar and N lanes.
//!
//! Algorithms: `exp` as in ARM's optimized-routines (Szabolcs Nagy): Cody-Waite reduction
//! `x = k ln2/128 + r`, a 128-entry table of `2^(j/128)` with its rounding error, and the
//! Taylor polynomial of degree 5 on `|r| <= ln2/256` (no division). The rest as in FreeBSD's
//! msun (Sun's fdlibm, K. C. Ng et al.): `sin_cos` by Cody-Waite reduction modulo `pi/2`
//! (three 33-bit parts of `pi/2`) and the `__kernel_sin` / `__kernel_cos` polynomials
//! (`sin_cos_small_angle`, for a step's turn angle, by the Taylor series below `2^-5`); `tanh` by its Taylor
//! series to `x^5` below `|x| = 2^-10`, Cephes' rational approximation below `|x| = 0.625`
//! (S. L. Moshier, Cephes Math Library, `tanh.c`) and `1 - 2/(exp(2|x|) + 1)` above. The
//! polynomials on the simulation step's critical path (`exp`'s, the sine and cosine kernels')
//! are evaluated by Estrin's scheme (pairs, then pairs of pairs): the same terms as Horner's,
//! a shorter chain of dependent operations.
//!
//! Accuracy, measured against the platform's libm by `tests` over the stated ranges (dense
//! and random arguments): `exp` within 1 ulp on `[-745, 709.78]`; `tanh` within 2 ulp on
//! `[-40, 40]`; `sin_cos` within 1 ulp on `|x| <= 2^19 pi/2` (about 8.2e5 rad); beyond that
//! `sin_cos` falls back to the libm crate's full reduction (not vectorised, never met by a
//! heading or a turn angle of a physical run). Special values: `exp(NaN) = NaN`,
//! `exp(+inf) = inf`, `exp(-inf) = 0`; `tanh(+-inf) = +-1`; `sin_cos` of a non-finite angle is
//! `(NaN, NaN)`.

// The constants are fdlibm's and Cephes' as printed (their digits name the same doubles).
#![allow(clippy::excessive_precision)]

mod exp2_table;
use exp2_table::{EXP2_J, EXP2_J_TAIL};

/// Rounds to the nearest integer (ties to even) by the 1.5 * 2^52 shift, returning the rounded
/// value and its integer; valid for `|x| < 2^51`.
#[inline(always)]
fn round_shift(x: f64) -> (f64, i64) {
    const SHIFT: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    let t = x + SHIFT;
    let k = (t.to_bits() as i64).wrapping_sub(SHIFT.to_bits() as i64);
    (t - SHIFT, k)
}

/// Rounds to the nearest integer, ties to even (`libm::round` rounds ties away from zero; beyond
/// `2^51` it is used, where every double is within 0.5 of an integer anyway), without a call:
/// the platform's `round` is a library call on baseline x86-64.
#[inline(always)]
pub fn round(x: f64) -> f64 {
    if x.abs() < 2_251_799_813_685_248.0 {
        round_shift(x).0
    } else {
        libm::round(x)
    }
}

/// `2^k` for `-1022 <= k <= 1023`, exact, from the exponent bits.
#[inline(always)]
fn pow2i(k: i64) -> f64 {
    f64::from_bits((k.wrapping_add(1023) as u64) << 52)
}

/// `e^x`. Within 1 ulp of the true value on the whole range (about 0.51 ulp where the result
/// is normal); `e^x` overflows to `inf` above 709.78 and underflows through the subnormals to
/// 0 below -745.13.
///
/// Table-driven (ARM's optimized-routines construction): `x = (128 m + j) ln2/128 + r`
/// (Cody-Waite with a 34-bit high part of `ln2/128`, so `|r| <= ln2/256`), then
/// `e^x = 2^m 2^(j/128) e^r` with `2^(j/128)` from a 128-entry table carrying its own rounding
/// error (`exp2_table`), and `e^r - 1` by its Taylor polynomial of degree 5 (truncation below
/// `6e-19` relative on `|r| <= ln2/256`) in Estrin's scheme. The loop's critical path runs
/// through this function: the table makes the polynomial short (degree 5 instead of 13 on
/// `|r| <= ln2/2`) and the scale factor is formed beside it, not after it.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    let (p, j, m) = exp_reduced(x);
    // Where the result and `scale * p` are normal (|m| <= 900, checked in `tests`), scaling by
    // 2^m before the sum gives the same double as after it (exact either way), one multiply
    // sooner: the loop's critical path runs through here. [`exp_lanes`] takes the other form
    // everywhere, the same numbers.
    let y = if (-900..=900).contains(&m) {
        let scale = EXP2_J[j] * pow2i(m);
        scale + scale * p
    } else {
        exp_scaled(p, j, m)
    };
    exp_special(x, y)
}

/// The reduction of [`exp`]: `x = (128 m + j) ln2/128 + r` (Cody-Waite with a 34-bit high part
/// of `ln2/128`, so `|r| <= ln2/256`), and `p = e^r - 1 + tail_j` (the table's rounding
/// error carried). Returns `(p, j, m)`; `e^x = 2^m EXP2_J[j] (1 + p)`.
#[inline(always)]
fn exp_reduced(x: f64) -> (f64, usize, i64) {
    // Clamped so that the reduction and the scaling stay finite; the true over/underflow is
    // selected at the end.
    let xc = x.clamp(EXP_UNDER - 1.0, EXP_OVER);
    const N_INV_LN2: f64 = 184.664_965_233_787_3; // 128 / ln2
    const LN2_N_HI: f64 = 0.005_415_212_347_998_022; // ln2/128 to 34 bits: 0x1.62e42fef8p-8
    const LN2_N_LO: f64 = 1.265_508_608_332_543_8e-13; // ln2/128 - LN2_N_HI
    const C2: f64 = 1.0 / 2.0;
    const C3: f64 = 1.0 / 6.0;
    const C4: f64 = 1.0 / 24.0;
    const C5: f64 = 1.0 / 120.0;
    let (kf, k) = round_shift(xc * N_INV_LN2);
    // Exact: |k| < 2^18, so kf * LN2_N_HI has at most 52 bits, and it is within a factor 2 of xc.
    let r = (xc - kf * LN2_N_HI) - kf * LN2_N_LO;
    let j = (k & 127) as usize;
    let r2 = r * r;
    // e^r - 1 + tail, Estrin: (tail + r) + r^2 (C2 + C3 r) + r^4 (C4 + C5 r).
    let p = (EXP2_J_TAIL[j] + r) + (r2 * (C2 + C3 * r) + (r2 * r2) * (C4 + C5 * r));
    (p, j, k >> 7) // m = floor(k / 128)
}

/// `2^m EXP2_J[j] (1 + p)` for any `m` of [`exp_reduced`]: `2^m` in two halves, so that a
/// subnormal result is rounded once, at the last product.
#[inline(always)]
fn exp_scaled(p: f64, j: usize, m: i64) -> f64 {
    let m1 = m >> 1;
    let scale = EXP2_J[j] * pow2i(m1);
    (scale + scale * p) * pow2i(m - m1)
}

/// [`exp`] without its shortcut's branch (the same numbers): what a vectorised loop of lanes
/// computes.
#[inline(always)]
fn exp_branch_free(x: f64) -> f64 {
    let (p, j, m) = exp_reduced(x);
    exp_special(x, exp_scaled(p, j, m))
}

/// Above this [`exp`] overflows to `inf`.
const EXP_OVER: f64 = 7.097_827_128_933_839_730_96e2;
/// Below this [`exp`] underflows to 0.
const EXP_UNDER: f64 = -7.451_332_191_019_412_076_24e2;

/// The special cases of [`exp`] selected over its value `y` for `x`: overflow, underflow, NaN.
#[inline(always)]
fn exp_special(x: f64, y: f64) -> f64 {
    let y = if x > EXP_OVER { f64::INFINITY } else { y };
    let y = if x < EXP_UNDER { 0.0 } else { y };
    if x.is_nan() {
        x
    } else {
        y
    }
}

/// `tanh(x)`, within 2 ulp; `tanh(+-inf) = +-1`, `tanh(NaN) = NaN`.
///
/// One value takes one of the two forms by a branch (the loop's critical path runs through
/// here); [`tanh_lanes`] computes both and selects. The same numbers either way.
#[inline(always)]
pub fn tanh(x: f64) -> f64 {
    let a = x.abs();
    if a < TANH_TINY {
        tanh_tiny(x)
    } else if a < 0.625 || x.is_nan() {
        tanh_small(x)
    } else {
        tanh_big(x)
    }
}

/// Below this `|x|` [`tanh`] is its Taylor series to `x^5`: the next term, `17 x^7 / 315`, is
/// below `2^-64 |x|`, far under half an ulp. A tracking run spends most of its steps here
/// (its error tiny), and the series has no division: a shorter critical path than Cephes'
/// rational form.
const TANH_TINY: f64 = 1.0 / 1024.0;

/// `tanh(x) = x - x^3/3 + 2 x^5/15` for `|x| < TANH_TINY`.
#[inline(always)]
fn tanh_tiny(x: f64) -> f64 {
    const T1: f64 = -1.0 / 3.0;
    const T2: f64 = 2.0 / 15.0;
    let z = x * x;
    x + x * z * (T1 + z * T2)
}

/// Cephes tanh.c: `tanh(x) = x + x^3 P(x^2)/Q(x^2)` for `|x| < 0.625`.
#[inline(always)]
fn tanh_small(x: f64) -> f64 {
    const P0: f64 = -9.643_991_794_250_522_386_28e-1;
    const P1: f64 = -9.928_772_310_019_185_865_64e1;
    const P2: f64 = -1.614_687_684_417_084_479_52e3;
    const Q0: f64 = 1.128_116_784_916_329_314_02e2;
    const Q1: f64 = 2.235_488_390_601_004_485_83e3;
    const Q2: f64 = 4.844_063_053_251_254_860_48e3;
    let z = x * x;
    x + x * z * ((P0 * z + P1) * z + P2) / (((z + Q0) * z + Q1) * z + Q2)
}

/// `sign(x) (1 - 2/(e^(2|x|) + 1))` for `|x| >= 0.625`.
#[inline(always)]
fn tanh_big(x: f64) -> f64 {
    // Above 22, 2/(e^(2a) + 1) < 2^-63: the answer is 1 (and e^(2a) may overflow).
    // Branch-free: `tanh_lanes` computes this form in every lane.
    let e = exp_branch_free(2.0 * x.abs().min(22.0));
    let big = 1.0 - 2.0 / (e + 1.0);
    if x < 0.0 {
        -big
    } else {
        big
    }
}

/// The largest `|x|` reduced here modulo `pi/2` (beyond it [`sin_cos`] uses libm).
const SINCOS_MAX: f64 = 8.234_496e5; // 2^19 * pi/2

/// `(sin x, cos x)`, each within 1 ulp for `|x| <= 8.2e5` (and by libm's full reduction
/// beyond); `(NaN, NaN)` for a non-finite `x`.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let a = x.abs();
    if a <= core::f64::consts::FRAC_PI_4 {
        // No reduction (k = 0, no low part): the numbers of the reduced path, sooner.
        sin_cos_kernels(x, 0.0)
    } else if a > SINCOS_MAX {
        libm::sincos(x)
    } else {
        sin_cos_reduced(x)
    }
}

/// [`sin_cos`] for `|x| <= SINCOS_MAX` (or non-finite), branch-free.
#[inline(always)]
fn sin_cos_reduced(x: f64) -> (f64, f64) {
    const INV_PIO2: f64 = core::f64::consts::FRAC_2_PI;
    const PIO2_1: f64 = 1.570_796_326_734_125_614_17; // first 33 bits of pi/2
    const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11; // next 33 bits
    const PIO2_3: f64 = 2.022_266_248_711_166_455_80e-21; // next 33 bits
    const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32; // pi/2 - the three above
                                                           // A non-finite x becomes NaN here and stays NaN (its k is garbage but harmless).
    let xr = if x.is_finite() { x } else { f64::NAN };
    let (kf, k) = round_shift(xr * INV_PIO2);
    // r = x - k pi/2 as a double-double r + y: each kf * PIO2_i is exact (kf < 2^20, 33-bit
    // constants), and the low part keeps the kernels within an ulp near multiples of pi/2,
    // where the leading digits cancel.
    let r0 = xr - kf * PIO2_1;
    let w = kf * PIO2_2;
    let r1 = r0 - w;
    let tail = ((r0 - r1) - w) - kf * PIO2_3 - kf * PIO2_3T;
    let r = r1 + tail;
    let y = tail - (r - r1);
    let (sin_r, cos_r) = sin_cos_kernels(r, y);
    // Quadrant k mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
    let swap = k & 1 != 0;
    let (s, c) = if swap { (cos_r, sin_r) } else { (sin_r, cos_r) };
    let s = if k & 2 != 0 { -s } else { s };
    let c = if k.wrapping_add(1) & 2 != 0 { -c } else { c };
    (s, c)
}

/// `(sin x, cos x)` for an angle that is nearly always below `2^-5` in magnitude, such as a
/// step's turn angle `omega dt / 2`: there by `sin_cos_small` (a third of the operations and
/// half the chain of dependent ones), elsewhere [`sin_cos`]. Each within 1 ulp, as `sin_cos`.
#[inline(always)]
pub fn sin_cos_small_angle(x: f64) -> (f64, f64) {
    if x.abs() < SINCOS_SMALL {
        sin_cos_small(x)
    } else {
        sin_cos(x)
    }
}

/// Below this `|x|`, [`sin_cos_small_angle`] is [`sin_cos_small`].
const SINCOS_SMALL: f64 = 1.0 / 32.0;

/// `(sin x, cos x)` for `|x| < 2^-5` by their Taylor series, `sin x = x + x^3 (-1/6 + x^2/120 -
/// x^4/5040)` and `cos x = 1 - x^2/2 + x^4 (1/24 - x^2/720 + x^4/40320)`: the next terms are
/// below `2.5e-18 |x|` and `2.5e-22`, so each result is within half an ulp and a few
/// hundredths; a third of the operations of the kernels below, which cover `|x| <= pi/4`.
/// `cos` keeps fdlibm's correction of `1 - x^2/2` (`w + ((1 - w) - x^2/2)`).
#[inline(always)]
fn sin_cos_small(x: f64) -> (f64, f64) {
    const S1: f64 = -1.0 / 6.0;
    const S2: f64 = 1.0 / 120.0;
    const S3: f64 = -1.0 / 5040.0;
    const C1: f64 = 1.0 / 24.0;
    const C2: f64 = -1.0 / 720.0;
    const C3: f64 = 1.0 / 40320.0;
    let z = x * x;
    let z2 = z * z;
    let series = x + (x * z) * ((S1 + z * S2) + z2 * S3);
    // At x = -0 the series' correction is +0 and the sum +0: sin(-0) is -0.
    let sin_x = if x == 0.0 { x } else { series };
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cos_x = w + (((1.0 - w) - hz) + z2 * ((C1 + z * C2) + z2 * C3));
    (sin_x, cos_x)
}

/// fdlibm's `__kernel_sin(r, y)` and `__kernel_cos(r, y)`: `sin` and `cos` of `r + y` for
/// `|r| <= pi/4`, `|y| <= ulp(r)/2`.
#[inline(always)]
fn sin_cos_kernels(r: f64, y: f64) -> (f64, f64) {
    const S1: f64 = -1.666_666_666_666_663_243_48e-1;
    const S2: f64 = 8.333_333_333_322_489_461_24e-3;
    const S3: f64 = -1.984_126_982_985_794_931_34e-4;
    const S4: f64 = 2.755_731_370_707_006_767_89e-6;
    const S5: f64 = -2.505_076_025_340_686_341_95e-8;
    const S6: f64 = 1.589_690_995_211_550_102_21e-10;
    const C1: f64 = 4.166_666_666_666_660_190_37e-2;
    const C2: f64 = -1.388_888_888_887_410_957_49e-3;
    const C3: f64 = 2.480_158_728_947_672_941_78e-5;
    const C4: f64 = -2.755_731_435_139_066_330_35e-7;
    const C5: f64 = 2.087_572_321_298_174_827_90e-9;
    const C6: f64 = -1.135_964_755_778_819_482_65e-11;
    let z = r * r;
    let z2 = z * z;
    // __kernel_sin(r, y) and __kernel_cos(r, y), their polynomials in z = r^2 evaluated by
    // Estrin's scheme (pairs, then pairs of pairs) rather than Horner's: the same terms, a
    // shorter dependency chain (the Dubins step's turn angle is on the loop's critical path).
    let v = z * r;
    let ps = (S2 + z * S3) + z2 * ((S4 + z * S5) + z2 * S6);
    let sin_r = r - ((z * (0.5 * y - v * ps) - y) - v * S1);
    let pc = z * ((C1 + z * C2) + z2 * ((C3 + z * C4) + z2 * (C5 + z * C6)));
    let hz = 0.5 * z;
    let wc = 1.0 - hz;
    let cos_r = wc + (((1.0 - wc) - hz) + (z * pc - r * y));
    (sin_r, cos_r)
}

/// [`exp`] of each lane.
#[inline(always)]
pub fn exp_lanes<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = exp_branch_free(x[i]);
    }
    out
}

/// [`tanh`] of each lane.
#[inline(always)]
pub fn tanh_lanes<const N: usize>(x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        let (tiny, small, big) = (tanh_tiny(x[i]), tanh_small(x[i]), tanh_big(x[i]));
        let a = x[i].abs();
        out[i] = if a < TANH_TINY {
            tiny
        } else if a < 0.625 || x[i].is_nan() {
            small
        } else {
            big
        };
    }
    out
}

/// [`sin_cos`] of each lane: `(sines, cosines)`.
#[inline(always)]
pub fn sin_cos_lanes<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for i in 0..N {
        (s[i], c[i]) = sin_cos_reduced(x[i]);
    }
    // The rare lane beyond the Cody-Waite range: libm's full reduction, outside the vector loop.
    if x.iter().any(|v| v.abs() > SINCOS_MAX) {
        for i in 0..N {
            if x[i].abs() > SINCOS_MAX {
                (s[i], c[i]) = libm::sincos(x[i]);
            }
        }
    }
    (s, c)
}

/// [`sin_cos_small_angle`] of each lane: when every lane is below `2^-5` (a batch of turn
/// angles, nearly always) the short series alone, else each lane's own form.
#[inline(always)]
pub fn sin_cos_small_angle_lanes<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    if x.iter().all(|v| v.abs() < SINCOS_SMALL) {
        for i in 0..N {
            (s[i], c[i]) = sin_cos_small(x[i]);
        }
        return (s, c);
    }
    let (sr, cr) = sin_cos_lanes(x);
    for i in 0..N {
        (s[i], c[i]) = if x[i].abs() < SINCOS_SMALL {
            sin_cos_small(x[i])
        } else {
            (sr[i], cr[i])
        };
    }
    (s, c)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// Distance in units in the last place between two finite doubles of the same sign (or
    /// both zero); `u64::MAX` when one is NaN and the other not.
    fn ulps(a: f64, b: f64) -> u64 {
        if a.is_nan() || b.is_nan() {
            return if a.is_nan() && b.is_nan() {
                0
            } else {
                u64::MAX
            };
        }
        if a == b {
            return 0;
        }
        let key = |v: f64| {
            let i = v.to_bits() as i64;
            if i < 0 {
                i64::MIN - i
            } else {
                i
            }
        };
        key(a).abs_diff(key(b))
    }

    /// Dense, evenly spaced points of `[lo, hi]` and as many pseudo-random ones (a fixed
    /// xorshift stream), plus the ends.
    fn points(lo: f64, hi: f64, n: usize) -> Vec<f64> {
        let mut v: Vec<f64> = (0..=n)
            .map(|i| lo + (hi - lo) * i as f64 / n as f64)
            .collect();
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..n {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            v.push(lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64));
        }
        v
    }

    fn worst(f: impl Fn(f64) -> f64, g: impl Fn(f64) -> f64, xs: &[f64]) -> (u64, f64) {
        xs.iter()
            .map(|&x| (ulps(f(x), g(x)), x))
            .max_by_key(|p| p.0)
            .unwrap()
    }

    #[test]
    fn exp_within_one_ulp_of_libm() {
        for (lo, hi) in [
            (-745.1, 709.78),
            (-1.0, 1.0),
            (-1e-6, 1e-6),
            (-745.13, -700.0),
        ] {
            let (u, x) = worst(exp, libm::exp, &points(lo, hi, 200_000));
            assert!(u <= 1, "exp({x}): {u} ulp");
        }
        assert_eq!(exp(0.0), 1.0);
        assert!(ulps(exp(1.0), core::f64::consts::E) <= 1);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp(-746.0), 0.0);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert!(exp(f64::NAN).is_nan());
        // The smallest subnormal, 2^-1074, is e^-744.44.
        assert_eq!(exp(-744.44), libm::exp(-744.44));
    }

    /// Dekker's exact product `a b = p + e` (Veltkamp's split; no fused multiply-add needed).
    fn two_product(a: f64, b: f64) -> (f64, f64) {
        let split = |v: f64| {
            let c = 134_217_729.0 * v; // 2^27 + 1
            let hi = c - (c - v);
            (hi, v - hi)
        };
        let p = a * b;
        let ((ah, al), (bh, bl)) = (split(a), split(b));
        (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
    }

    #[test]
    fn exp_table_holds_2_to_the_j_over_128_with_its_rounding_error() {
        use exp2_table::{EXP2_J, EXP2_J_TAIL};
        assert_eq!(EXP2_J[0], 1.0);
        assert_eq!(EXP2_J_TAIL[0], 0.0);
        assert_eq!(EXP2_J[64], core::f64::consts::SQRT_2);
        for j in 0..128 {
            assert!(
                ulps(EXP2_J[j], libm::exp2(j as f64 / 128.0)) <= 1,
                "2^({j}/128)"
            );
            // The nearest double: its relative error is at most half an ulp.
            assert!(EXP2_J_TAIL[j].abs() <= f64::EPSILON / 2.0, "tail {j}");
        }
        // 2^(j/128) 2^((128-j)/128) = 2 to about 2^-104, the pair carried as double-doubles:
        // (H_j + H_j t_j) (H_k + H_k t_k) - 2 = (p - 2) + e + p (t_j + t_k) + O(2^-106).
        for j in 1..128 {
            let k = 128 - j;
            let (p, e) = two_product(EXP2_J[j], EXP2_J[k]);
            let d = (p - 2.0) + e + p * (EXP2_J_TAIL[j] + EXP2_J_TAIL[k]);
            assert!(d.abs() < 1e-30, "2^({j}/128) 2^({k}/128) - 2 = {d:e}");
        }
    }

    #[test]
    fn exp_is_mostly_correctly_rounded() {
        // At 0.51 ulp (the table's rounding error carried, one rounding at the end) all but a
        // few arguments round to the same double as the platform's exp (glibc's: 0.502 ulp,
        // the same design). Measured here: under 1 % differ; with the tails left out, 26 %.
        // (The libm crate's fdlibm `exp`, within 1 ulp only, differs from both at 10 %.)
        let xs = points(-700.0, 700.0, 100_000);
        let differ = xs.iter().filter(|&&x| exp(x) != x.exp()).count();
        assert!(differ * 100 < xs.len(), "{differ} of {} differ", xs.len());
    }

    #[test]
    fn tanh_within_two_ulp_of_libm() {
        for (lo, hi) in [(-40.0, 40.0), (-0.7, 0.7), (-1e-3, 1e-3), (0.6, 0.65)] {
            let (u, x) = worst(tanh, libm::tanh, &points(lo, hi, 200_000));
            assert!(u <= 2, "tanh({x}): {u} ulp");
        }
        // Below TANH_TINY the series is what both forms compute (the short chain is the point).
        for x in points(-0.999 * TANH_TINY, 0.999 * TANH_TINY, 10_000) {
            assert_eq!(tanh(x).to_bits(), tanh_tiny(x).to_bits(), "{x}");
            assert_eq!(
                tanh_lanes([x; 4])[0].to_bits(),
                tanh_tiny(x).to_bits(),
                "{x}"
            );
        }
        // The series below TANH_TINY (a tracking run's usual error), on both sides of the switch.
        for (lo, hi) in [(1e-12, 1e-6), (0.99 * TANH_TINY, 1.01 * TANH_TINY)] {
            let (u, x) = worst(tanh, libm::tanh, &points(lo, hi, 100_000));
            assert!(u <= 1, "tanh({x}): {u} ulp");
        }
        assert_eq!(tanh(0.0), 0.0);
        assert_eq!(tanh(f64::INFINITY), 1.0);
        assert_eq!(tanh(f64::NEG_INFINITY), -1.0);
        assert_eq!(tanh(30.0), 1.0);
        assert!(tanh(f64::NAN).is_nan());
        // Odd: exactly.
        for x in points(-5.0, 5.0, 1000) {
            assert_eq!(tanh(-x), -tanh(x));
        }
    }

    #[test]
    fn sin_cos_within_one_ulp_of_libm() {
        let sin = |x: f64| sin_cos(x).0;
        let cos = |x: f64| sin_cos(x).1;
        for (lo, hi, max_ulp) in [
            (-10.0, 10.0, 1),
            (-1e-5, 1e-5, 1),
            (-0.04, 0.04, 1),
            (-8.2e5, 8.2e5, 1),
            (1e6, 1e7, 0),
        ] {
            let xs = points(lo, hi, 200_000);
            let (u, x) = worst(sin, libm::sin, &xs);
            assert!(u <= max_ulp, "sin({x}): {u} ulp");
            let (u, x) = worst(cos, libm::cos, &xs);
            assert!(u <= max_ulp, "cos({x}): {u} ulp");
        }
        // Next to multiples of pi/2, where the reduction cancels most digits.
        let near: Vec<f64> = (1..2000)
            .flat_map(|k| {
                let m = k as f64 * core::f64::consts::FRAC_PI_2;
                [
                    m,
                    f64::from_bits(m.to_bits() + 1),
                    f64::from_bits(m.to_bits() - 1),
                ]
            })
            .collect();
        assert!(worst(sin, libm::sin, &near).0 <= 1);
        assert!(worst(cos, libm::cos, &near).0 <= 1);
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan());
        }
    }

    #[test]
    fn small_angles_round_like_the_full_kernels() {
        // Both forms are within about half an ulp below 2^-5, so they name the same double at
        // nearly every argument (and the platform's sin and cos, correctly rounded in nearly
        // all cases, agree with the series as often).
        let xs = points(-SINCOS_SMALL, SINCOS_SMALL, 100_000);
        let (mut ds, mut dc) = (0, 0);
        for &x in &xs {
            let (s, c) = sin_cos_small(x);
            let (sk, ck) = sin_cos_kernels(x, 0.0);
            assert!(ulps(s, sk) <= 1 && ulps(c, ck) <= 1, "{x}");
            ds += usize::from(s != x.sin());
            dc += usize::from(c != x.cos());
        }
        assert!(
            ds * 200 < xs.len() && dc * 200 < xs.len(),
            "{ds} sin, {dc} cos differ"
        );
        assert_eq!(sin_cos_small_angle(-0.0).0.to_bits(), (-0.0f64).to_bits());
        assert_eq!(sin_cos_small_angle(0.0), (0.0, 1.0));
        // Above 2^-5, the general form.
        assert_eq!(sin_cos_small_angle(0.04), sin_cos(0.04));
        assert_eq!(sin_cos_small_angle(-3.0), sin_cos(-3.0));
        // Within 1 ulp of libm on and around its range.
        let sin = |x: f64| sin_cos_small_angle(x).0;
        let cos = |x: f64| sin_cos_small_angle(x).1;
        let xs = points(-0.04, 0.04, 200_000);
        assert!(worst(sin, libm::sin, &xs).0 <= 1);
        assert!(worst(cos, libm::cos, &xs).0 <= 1);
    }

    #[test]
    fn round_to_nearest_even() {
        for (x, r) in [
            (0.5, 0.0),
            (1.5, 2.0),
            (2.5, 2.0),
            (-0.5, -0.0),
            (-1.5, -2.0),
            (1.4999999999999998, 1.0),
            (-7.6, -8.0),
            (2e15 + 0.5, 2e15),
            (3e15 + 0.5, 3e15 + 1.0),
            (1e300, 1e300),
        ] {
            assert_eq!(round(x), r, "round({x})");
        }
        assert!(round(f64::NAN).is_nan());
        assert_eq!(round(f64::INFINITY), f64::INFINITY);
    }

    #[test]
    fn exp_scales_alike_on_both_sides_of_its_shortcut() {
        // The scalar exp scales before the sum for |m| <= 900 (|x| up to about 624), the lanes
        // after it: the same doubles over the whole range, the edges of the shortcut included.
        let edge = 900.0 * core::f64::consts::LN_2;
        let mut xs = points(-745.2, 709.8, 100_000);
        xs.extend(points(-edge - 0.01, -edge + 0.01, 2000));
        xs.extend(points(edge - 0.01, edge + 0.01, 2000));
        for x in xs {
            assert_eq!(exp(x).to_bits(), exp_branch_free(x).to_bits(), "{x}");
            assert_eq!(exp(x).to_bits(), exp_lanes([x])[0].to_bits(), "{x}");
        }
    }

    #[test]
    fn lanes_equal_the_scalar_functions_bit_for_bit() {
        let xs = points(-30.0, 30.0, 4096);
        let mut xs8 = [0.0; 8];
        for chunk in xs.chunks_exact(8) {
            xs8.copy_from_slice(chunk);
            let e = exp_lanes(xs8);
            let t = tanh_lanes(xs8);
            let (s, c) = sin_cos_lanes(xs8);
            for i in 0..8 {
                assert_eq!(e[i].to_bits(), exp(xs8[i]).to_bits());
                assert_eq!(t[i].to_bits(), tanh(xs8[i]).to_bits());
                let (si, ci) = sin_cos(xs8[i]);
                assert_eq!(
                    (s[i].to_bits(), c[i].to_bits()),
                    (si.to_bits(), ci.to_bits())
                );
            }
        }
        // Small angles in lanes: all below 2^-5, and mixed with larger ones.
        let all_small = [0.01, -0.02, 1e-9, -0.0, 0.0312, 0.0, -0.031, 3e-4];
        let mixed = [0.01, 0.5, -0.02, 3.0, 1e-9, -0.0, 0.0312, 0.0313];
        for xs8 in [all_small, mixed] {
            let (s, c) = sin_cos_small_angle_lanes(xs8);
            for i in 0..8 {
                let (si, ci) = sin_cos_small_angle(xs8[i]);
                assert_eq!(
                    (s[i].to_bits(), c[i].to_bits()),
                    (si.to_bits(), ci.to_bits())
                );
            }
        }
        // The scalar shortcut (no reduction below pi/4) is the reduced path's arithmetic.
        for x in points(
            -core::f64::consts::FRAC_PI_4,
            core::f64::consts::FRAC_PI_4,
            10_000,
        ) {
            let (a, b) = (sin_cos(x), sin_cos_reduced(x));
            assert_eq!(
                (a.0.to_bits(), a.1.to_bits()),
                (b.0.to_bits(), b.1.to_bits()),
                "{x}"
            );
        }
        // A lane beyond the reduction range takes libm's path; the others are unchanged: lane 0
        // is an angle where the Cody-Waite path and libm differ in the last bit, so it shows
        // which path it took; 1e15 is far past the range, where Cody-Waite's products are inexact.
        let differs = points(0.5, 10.0, 100_000)
            .into_iter()
            .find(|&x| sin_cos(x) != libm::sincos(x))
            .expect("an angle where the two paths round differently");
        let x = [differs, 1e15, -2.0, f64::NAN];
        let (s, c) = sin_cos_lanes(x);
        assert_eq!((s[1], c[1]), libm::sincos(1e15));
        assert_eq!((s[0], c[0]), sin_cos(differs));
        assert_ne!((s[0], c[0]), libm::sincos(differs));
        assert!(s[3].is_nan() && c[3].is_nan());
        // Every lane beyond the range: all from libm.
        let huge = [1e15, -3e16, 1e9, 2e20];
        let (s, c) = sin_cos_lanes(huge);
        for i in 0..4 {
            assert_eq!((s[i], c[i]), libm::sincos(huge[i]), "{}", huge[i]);
        }
    }
}
