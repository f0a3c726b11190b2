//! Numbers in messages (issue 30, item 19): the one formatting every error, warning and note
//! uses for a number it echoes or computes.
//!
//! `f64`'s own `Display` prints the shortest string that reads back to the same bits, so a
//! computed bound comes out as `0.0024500000000000004` and `1e300` as 301 digits. [`Num`]
//! rounds to [`SIGNIFICANT_DIGITS`] significant digits, drops trailing zeros, and writes plain
//! decimals for magnitudes in `[1e-6, 1e9)`, scientific (`1e300`, `-2.5e-7`) outside. A bound
//! the user is told to respect is rounded away from the forbidden side: [`NumUp`] for "at
//! least" (rounded towards `+inf`, so the printed value itself is allowed), [`NumDown`] for
//! "at most".

use core::fmt;

/// Significant digits of a number in a message: enough to echo what a person types, few
/// enough that a computed value reads as a value.
pub const SIGNIFICANT_DIGITS: u32 = 6;

/// A number for a message, rounded to the nearest of [`SIGNIFICANT_DIGITS`] digits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f64);

/// A lower bound for a message ("at least X"): rounded towards `+inf`, so `X` itself passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NumUp(pub f64);

/// An upper bound for a message ("at most X"): rounded towards `-inf`, so `X` itself passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NumDown(pub f64);

#[derive(Clone, Copy, PartialEq)]
enum Rounding {
    Nearest,
    Up,
    Down,
}

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_number(f, self.0, Rounding::Nearest)
    }
}

impl fmt::Display for NumUp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_number(f, self.0, Rounding::Up)
    }
}

impl fmt::Display for NumDown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_number(f, self.0, Rounding::Down)
    }
}

/// A small stack buffer for `core::fmt` (no allocation: this crate is `no_std`).
struct Buf {
    bytes: [u8; 40],
    len: usize,
}

impl fmt::Write for Buf {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        if end > self.bytes.len() {
            return Err(fmt::Error);
        }
        self.bytes[self.len..end].copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

impl Buf {
    fn new() -> Self {
        Self {
            bytes: [0; 40],
            len: 0,
        }
    }
    fn as_str(&self) -> &str {
        core::str::from_utf8(&self.bytes[..self.len]).unwrap_or("")
    }
}

/// The value of the decimal `m * 10^(e - (SIGNIFICANT_DIGITS - 1))`, as `f64` parses it.
fn decimal_value(m: u64, e: i32) -> f64 {
    use fmt::Write;
    let mut b = Buf::new();
    let _ = write!(b, "{m}e{}", e - (SIGNIFICANT_DIGITS as i32 - 1));
    b.as_str().parse().unwrap_or(f64::NAN)
}

/// `|x|` (finite, non-zero) as `(m, e)`: `m` of exactly [`SIGNIFICANT_DIGITS`] digits and the
/// decimal exponent of its first digit, rounded to nearest.
fn decompose(a: f64) -> Option<(u64, i32)> {
    use fmt::Write;
    let mut b = Buf::new();
    write!(b, "{:.*e}", SIGNIFICANT_DIGITS as usize - 1, a).ok()?;
    let (mantissa, exp) = b.as_str().split_once('e')?;
    let e: i32 = exp.parse().ok()?;
    let mut m = 0u64;
    for c in mantissa.bytes().filter(u8::is_ascii_digit) {
        m = 10 * m + u64::from(c - b'0');
    }
    Some((m, e))
}

fn write_number(f: &mut fmt::Formatter<'_>, x: f64, rounding: Rounding) -> fmt::Result {
    if x == 0.0 {
        return f.write_str("0");
    }
    if !x.is_finite() {
        return write!(f, "{x}");
    }
    let neg = x < 0.0;
    let a = x.abs();
    let Some((mut m, mut e)) = decompose(a) else {
        return write!(f, "{x}");
    };
    // Away from the forbidden side: for "at least" the printed value must not be below x, for
    // "at most" not above: one step of the last digit towards the side where the bound holds.
    let r = decimal_value(m, e);
    let printed = if neg { -r } else { r };
    let smallest = 10u64.pow(SIGNIFICANT_DIGITS - 1);
    let magnitude_up = match rounding {
        Rounding::Up if printed < x => Some(!neg),
        Rounding::Down if printed > x => Some(neg),
        _ => None,
    };
    match magnitude_up {
        Some(true) => {
            m += 1;
            if m == 10 * smallest {
                m = smallest;
                e += 1;
            }
        }
        Some(false) => {
            m -= 1;
            if m < smallest {
                m = 10 * smallest - 1;
                e -= 1;
            }
        }
        None => {}
    }
    if neg {
        f.write_str("-")?;
    }
    // The significant digits without trailing zeros.
    let mut digits = [0u8; SIGNIFICANT_DIGITS as usize];
    let mut rest = m;
    for d in digits.iter_mut().rev() {
        *d = b'0' + (rest % 10) as u8;
        rest /= 10;
    }
    let mut len = digits.len();
    while len > 1 && digits[len - 1] == b'0' {
        len -= 1;
    }
    let ds = core::str::from_utf8(&digits[..len]).unwrap_or("0");
    if (-6..9).contains(&e) {
        if e < 0 {
            f.write_str("0.")?;
            for _ in 0..(-e - 1) {
                f.write_str("0")?;
            }
            f.write_str(ds)
        } else {
            let int_len = e as usize + 1;
            if len <= int_len {
                f.write_str(ds)?;
                for _ in len..int_len {
                    f.write_str("0")?;
                }
                Ok(())
            } else {
                f.write_str(&ds[..int_len])?;
                f.write_str(".")?;
                f.write_str(&ds[int_len..])
            }
        }
    } else {
        f.write_str(&ds[..1])?;
        if len > 1 {
            f.write_str(".")?;
            f.write_str(&ds[1..])?;
        }
        write!(f, "e{e}")
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// Six significant digits, plain in [1e-6, 1e9), scientific outside, no trailing zeros;
    /// the reported `0.0024500000000000004` reads `0.00245`.
    #[test]
    fn rounds_to_six_significant_digits() {
        for (x, shown) in [
            (0.0024500000000000004, "0.00245"),
            (0.0, "0"),
            (-0.5, "-0.5"),
            (600.0, "600"),
            (6.4e7, "64000000"),
            (1e9, "1e9"),
            (1e300, "1e300"),
            (-1e-7, "-1e-7"),
            (1e-6, "0.000001"),
            (2.0 / 3.0, "0.666667"),
            (123456789.0, "123457000"),
            (1.0 / 3.0 * 1e-10, "3.33333e-11"),
            (999999.6, "1000000"),
            (f64::INFINITY, "inf"),
            (f64::NAN, "NaN"),
            (5e-324, "4.94066e-324"),
        ] {
            assert_eq!(format!("{}", Num(x)), shown, "{x:e}");
        }
    }

    /// A bound is rounded towards the side where it holds: the printed "at least" value is not
    /// below the bound (so using it passes), the printed "at most" value not above.
    #[test]
    fn bounds_round_towards_the_side_where_they_hold() {
        let x = 0.0024500000000000004;
        assert_eq!(format!("{}", NumUp(x)), "0.00245001");
        assert_eq!(format!("{}", NumDown(x)), "0.00245");
        assert_eq!(format!("{}", NumUp(0.00245)), "0.00245");
        assert_eq!(format!("{}", NumUp(9.999999e5)), "1000000");
        assert_eq!(format!("{}", NumDown(1.0000001)), "1");
        assert_eq!(format!("{}", NumDown(-2.0 / 3.0)), "-0.666667");
        assert_eq!(format!("{}", NumUp(-2.0 / 3.0)), "-0.666666");
        assert_eq!(format!("{}", NumDown(1.000001e-5 * 0.99999999)), "0.00001");
        for x in [
            1.0 / 3.0,
            2.0 / 3.0,
            0.1 + 0.2,
            7.000000000001,
            1e-300 / 3.0,
            1e300 / 7.0,
        ] {
            for x in [x, -x] {
                let up: f64 = format!("{}", NumUp(x)).parse().unwrap();
                let down: f64 = format!("{}", NumDown(x)).parse().unwrap();
                assert!(down <= x && x <= up, "{down} <= {x} <= {up}");
            }
        }
    }
}
