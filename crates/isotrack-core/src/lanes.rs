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
//! Algorithms and constants are those of FreeBSD's msun (Sun's fdlibm, K. C. Ng et al.):
//! `exp` by Cody-Waite reduction `x = k ln2 + r` and its Taylor polynomial of degree 13 on
//! `|r| <= ln2/2` (no division); `sin_cos` by Cody-Waite reduction modulo `pi/2` (three 33-bit
//! parts of `pi/2`) and the `__kernel_sin` / `__kernel_cos` polynomials; `tanh` by its Taylor
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

/// `e^x`. Within 1 ulp of the true value on the whole range; `e^x` overflows to `inf` above
/// 709.78 and underflows through the subnormals to 0 below -745.13.
///
/// `x = k ln2 + r` (Cody-Waite, `|r| <= ln2/2`), `e^r` by its Taylor polynomial of degree 13
/// (truncation below `4.3e-18` relative) evaluated in Estrin's scheme (short dependency chains,
/// no division: the loop's critical path runs through this function), then `2^k` by the
/// exponent bits.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;
    const INV_LN2: f64 = core::f64::consts::LOG2_E;
    const OVER: f64 = 7.097_827_128_933_839_730_96e2;
    const UNDER: f64 = -7.451_332_191_019_412_076_24e2;
    // 1/n! for n = 2..13.
    const C2: f64 = 1.0 / 2.0;
    const C3: f64 = 1.0 / 6.0;
    const C4: f64 = 1.0 / 24.0;
    const C5: f64 = 1.0 / 120.0;
    const C6: f64 = 1.0 / 720.0;
    const C7: f64 = 1.0 / 5040.0;
    const C8: f64 = 1.0 / 40320.0;
    const C9: f64 = 1.0 / 362_880.0;
    const C10: f64 = 1.0 / 3_628_800.0;
    const C11: f64 = 1.0 / 39_916_800.0;
    const C12: f64 = 1.0 / 479_001_600.0;
    const C13: f64 = 1.0 / 6_227_020_800.0;
    // Clamped so that the reduction and the scaling stay finite; the true over/underflow is
    // selected at the end.
    let xc = x.clamp(UNDER - 1.0, OVER);
    let (kf, k) = round_shift(xc * INV_LN2);
    let hi = xc - kf * LN2_HI; // exact: kf * LN2_HI has at most 53 bits
    let lo = kf * LN2_LO;
    let r = hi - lo;
    let r2 = r * r;
    let r4 = r2 * r2;
    // The terms of degree >= 2, Estrin: pairs, then quadruples, then the rest.
    let q23 = C2 + C3 * r;
    let q45 = C4 + C5 * r;
    let q67 = C6 + C7 * r;
    let q89 = C8 + C9 * r;
    let q1011 = C10 + C11 * r;
    let q1213 = C12 + C13 * r;
    let q2_5 = q23 + q45 * r2;
    let q6_9 = q67 + q89 * r2;
    let q10_13 = q1011 + q1213 * r2;
    let q2_13 = q2_5 + (q6_9 + q10_13 * r4) * r4;
    // e^r = 1 + (hi - lo) + r^2 q: the low part of r added last keeps the error within an ulp.
    let y = 1.0 + (hi + (r2 * q2_13 - lo));
    // 2^k in two halves, so that a subnormal result is rounded once, at the last product.
    let k1 = k >> 1;
    let y = y * pow2i(k1) * pow2i(k.wrapping_sub(k1));
    let y = if x > OVER { f64::INFINITY } else { y };
    let y = if x < UNDER { 0.0 } else { y };
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
    let e = exp(2.0 * x.abs().min(22.0));
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
        out[i] = exp(x[i]);
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
