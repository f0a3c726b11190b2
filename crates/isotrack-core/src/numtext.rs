//! Numbers and user text in messages (issue 30, items 19 and the hostile review's leftovers):
//! the one formatting every error, warning and note uses for a number it echoes or computes,
//! and for a string the user wrote.
//!
//! Two kinds of number, two rules:
//!
//! * A value the **user wrote** ([`Echo`]) is echoed exactly: the shortest decimal that reads
//!   back to the same `f64` (Rust's `{}`), in exponent form (`{:e}`) when its magnitude is
//!   outside `[1e-5, 1e16)`, so `1.0000001` is never shown as `1` and `1e-300` is never 300
//!   digits. At most 24 characters (17 significant digits, a sign, a point and `e-308`).
//! * A value the **program computed** ([`Num`], [`NumUp`], [`NumDown`]) is rounded to
//!   [`SIGNIFICANT_DIGITS`] significant digits, trailing zeros dropped, plain decimals for
//!   magnitudes in `[1e-6, 1e9)` and scientific (`1e300`, `-2.5e-7`) outside: at most 14
//!   characters. `f64`'s own `Display` prints a computed bound as `0.0024500000000000004` and
//!   `1e300` as 301 digits. A bound the user is told to respect is rounded away from the
//!   forbidden side: [`NumUp`] for "at least" (rounded towards `+inf`, so the printed value
//!   itself is allowed), [`NumDown`] for "at most".
//!
//! User text (file names, keys, values, task names, units and names read from files) goes
//! through [`Escaped`] (or [`Clipped`](struct@Clipped), which also bounds its length): control characters that
//! a terminal obeys (C0 but tab, DEL, C1, and the Unicode bidi controls that reorder what
//! follows) and line feeds are written as escapes (`\x1b`, `\x0a`, `\u{202e}`), so a message
//! shows what was typed instead of acting on the terminal or forging a line of its own.

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

/// A value the user wrote, for a message: the shortest decimal that reads back to the same
/// `f64`, in exponent form when its magnitude is outside `[1e-5, 1e16)` (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Echo(pub f64);

impl fmt::Display for Echo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() || x == 0.0 || (1e-5..1e16).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A number written into a file that is read back (a TOML value, a CSV cell): the shortest
/// decimal that reads back to the same `f64` bit for bit, in exponent form (`{:e}`: `1e-300`,
/// `2.5e17`) when its magnitude is outside `[1e-5, 1e16)` (the rule of the `ryu` crate and of
/// [`Echo`]: there the exponent form is the shorter one), else positional with at least one
/// digit after the point (`0.5`, `600.0`), so it stays a float in TOML. Rust's `{}` alone writes
/// `1e-300` as 300 digits and `1e300` as 301. Non-finite values as Rust writes them (`NaN`,
/// `inf`; TOML's `nan`/`inf` are the caller's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TomlFloat(pub f64);

impl fmt::Display for TomlFloat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() {
            write!(f, "{x}")
        } else if x == 0.0 || (1e-5..1e16).contains(&x.abs()) {
            if x % 1.0 == 0.0 {
                write!(f, "{x}.0")
            } else {
                write!(f, "{x}")
            }
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// A list of values the user wrote (`[1, 2.5]`), each as [`Echo`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EchoList<'a>(pub &'a [f64]);

impl fmt::Display for EchoList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (i, x) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{}", Echo(*x))?;
        }
        f.write_str("]")
    }
}

/// Whether a terminal would act on `c` rather than show it: C0 controls but tab and newline,
/// DEL, C1 controls, and the Unicode bidirectional controls that reorder what follows (ALM
/// U+061C, LRM and RLM U+200E-U+200F, the embeddings and overrides U+202A-U+202E, the isolates
/// U+2066-U+2069). Joiners (U+200C, U+200D), which some scripts and emoji need, pass.
pub fn is_terminal_control(c: char) -> bool {
    matches!(c,
        '\u{0}'..='\u{8}' | '\u{b}'..='\u{1f}' | '\u{7f}'..='\u{9f}'
        | '\u{61c}' | '\u{200e}'..='\u{200f}' | '\u{202a}'..='\u{202e}'
        | '\u{2066}'..='\u{2069}')
}

/// Whether `c` is invisible: a Unicode default-ignorable code point (the zero-width space
/// U+200B, joiners U+200C-U+200D, marks U+200E-U+200F, the bidi controls, the word joiner and
/// invisible operators U+2060-U+206F, the byte-order mark U+FEFF, the soft hyphen U+00AD,
/// variation selectors, tags, Hangul fillers, ...). A name holding one looks like another
/// name (`pi_isoline` and `pi_isoline` + U+200B print alike), so names refuse them.
pub fn is_invisible(c: char) -> bool {
    matches!(c,
        '\u{ad}' | '\u{34f}' | '\u{61c}' | '\u{115f}' | '\u{1160}' | '\u{17b4}' | '\u{17b5}'
        | '\u{180b}'..='\u{180f}' | '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}'
        | '\u{2060}'..='\u{206f}' | '\u{3164}' | '\u{fe00}'..='\u{fe0f}' | '\u{feff}'
        | '\u{ffa0}' | '\u{fff0}'..='\u{fff8}' | '\u{1bca0}'..='\u{1bca3}'
        | '\u{1d173}'..='\u{1d17a}' | '\u{e0000}'..='\u{e0fff}')
}

/// Whether `c` is no character of plain text a user names or labels something with: a
/// character of the Unicode general categories Cc (controls: C0 with tab and line feed, DEL,
/// C1), Cf (format characters: the bidi controls, zero-width characters, the soft hyphen, the
/// byte-order mark, the interlinear annotation marks U+FFF9-U+FFFB, the Egyptian hieroglyph
/// format controls U+13430-..., the Arabic number signs U+0600-U+0605, ...), Zl (U+2028) or Zp
/// (U+2029), or an [`is_invisible`] one (default-ignorable code points of other categories:
/// variation selectors, Hangul fillers, unassigned ones). Categories from the Unicode
/// Character Database (UAX #44, `UnicodeData.txt`) through the `unicode-general-category`
/// crate's tables. The one rule for the strings isotrack shows from any source: a scenario's
/// `name`, `field.units`, ..., a NetCDF attribute, a suite's name and titles, a results file's
/// text cells, a registered controller's name, a run directory's name in a page.
pub fn is_not_plain(c: char) -> bool {
    use unicode_general_category::{get_general_category, GeneralCategory as G};
    c.is_control()
        || is_invisible(c)
        || matches!(
            get_general_category(c),
            G::Control | G::Format | G::LineSeparator | G::ParagraphSeparator
        )
}

/// Whether user text shows `c` as an escape ([`Escaped`]): a [`is_terminal_control`]
/// character, a line feed, or any other [`is_not_plain`] character but the tab. A line feed
/// (or U+2028) in a file name, a unit or a CSV header would start a new console line that the
/// text's author writes (`x\nerror: ...`), so inside user text it is shown as `\x0a`; the
/// lines of a message itself are the program's. An invisible character is shown as
/// `\u{200b}` so that a message refusing it shows where it is; the joiners U+200C and U+200D
/// (needed by some scripts and emoji, and reordering nothing) are shown as they are.
pub fn is_escaped(c: char) -> bool {
    // The joiners (U+200C, U+200D), which some scripts and emoji need, are shown as they are.
    c == '\n'
        || is_terminal_control(c)
        || (!matches!(c, '\t' | '\u{200c}' | '\u{200d}') && is_not_plain(c))
}

/// How `c` is shown in user text: itself, `\x1b` (C0, line feed, DEL) or `\u{202e}` (above).
fn write_shown(f: &mut fmt::Formatter<'_>, c: char) -> fmt::Result {
    if !is_escaped(c) {
        use fmt::Write;
        f.write_char(c)
    } else if (c as u32) < 0x80 {
        write!(f, "\\x{:02x}", c as u32)
    } else {
        write!(f, "\\u{{{:x}}}", c as u32)
    }
}

/// How many characters `c` takes once shown ([`write_shown`]): 1, 4 for `\x1b`, 6 for `\u{85}`,
/// 8 for `\u{202e}`.
fn shown_len(c: char) -> usize {
    if !is_escaped(c) {
        1
    } else if (c as u32) < 0x80 {
        4
    } else {
        // `\u{` + hex digits + `}`.
        let digits = (32 - (c as u32).leading_zeros()).div_ceil(4) as usize;
        4 + digits
    }
}

/// User text for a message, with every [`is_escaped`] character (terminal controls and line
/// feeds) escaped: `\x1b` for C0, line feed and DEL, `\u{85}` / `\u{202e}` above.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Escaped<'a>(pub &'a str);

impl fmt::Display for Escaped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0;
        let mut start = 0;
        for (i, c) in s.char_indices() {
            if is_escaped(c) {
                f.write_str(&s[start..i])?;
                write_shown(f, c)?;
                start = i + c.len_utf8();
            }
        }
        f.write_str(&s[start..])
    }
}

/// How many characters of one string the user wrote a message echoes ([`Clipped`](struct@Clipped)).
pub const ECHO_CHARS: usize = 200;

/// User text for a message: [`Escaped`] first, then cut so that at most [`ECHO_CHARS`]
/// characters (or `limit`) of the escaped text are shown, followed by `... (N more
/// characters)`, N counted on the escaped text too. The cut falls between two characters of
/// the text, never inside an escape (`\x1b` is shown whole or not at all), so what is shown
/// is at most `limit` characters plus the note: a 900 000-character path, a 40 000-character
/// `--set` value or 200 escapes (`\u{202e}`, 8 characters each) are echoed as their start and
/// their length. The one clipping of user text in the project (the scenario's `load::clip`
/// and the console's line bound are this).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clipped<'a> {
    text: &'a str,
    limit: usize,
}

#[allow(non_snake_case)]
/// [`Clipped`](struct@Clipped) at [`ECHO_CHARS`] characters.
pub fn Clipped(text: &str) -> Clipped<'_> {
    Clipped::with_limit(text, ECHO_CHARS)
}

impl<'a> Clipped<'a> {
    /// `text` escaped, then cut after `limit` characters of what is shown.
    pub fn with_limit(text: &'a str, limit: usize) -> Self {
        Self { text, limit }
    }
}

impl fmt::Display for Clipped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let total: usize = self.text.chars().map(shown_len).sum();
        if total <= self.limit {
            return write!(f, "{}", Escaped(self.text));
        }
        let mut shown = 0;
        for c in self.text.chars() {
            let n = shown_len(c);
            if shown + n > self.limit {
                break;
            }
            write_shown(f, c)?;
            shown += n;
        }
        write!(f, "... ({} more characters)", total - shown)
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
    let Some((m, e)) = decompose(x.abs()) else {
        return write!(f, "{x}");
    };
    let (m, e) = towards_bound(m, e, x, rounding);
    if neg {
        f.write_str("-")?;
    }
    let (digits, len) = significant_digits(m);
    let ds = core::str::from_utf8(&digits[..len]).unwrap_or("0");
    if (-6..9).contains(&e) {
        write_positional(f, ds, e)
    } else {
        write_scientific(f, ds, e)
    }
}

/// The decimal `(m, e)` of `|x|` (see [`decompose`]) moved one step of its last digit away from
/// the forbidden side: for "at least" the printed value must not be below `x`, for "at most" not
/// above; unchanged when the nearest already keeps the bound (or for [`Rounding::Nearest`]).
fn towards_bound(mut m: u64, mut e: i32, x: f64, rounding: Rounding) -> (u64, i32) {
    let neg = x < 0.0;
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
    (m, e)
}

/// The [`SIGNIFICANT_DIGITS`] ASCII digits of `m` and how many of them are kept once trailing
/// zeros are dropped (at least one).
fn significant_digits(m: u64) -> ([u8; SIGNIFICANT_DIGITS as usize], usize) {
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
    (digits, len)
}

/// The digits `ds` (first digit of decimal exponent `e`, `-6 <= e < 9`) as a plain decimal:
/// `0.000ds`, `ds000` or `d.ddd`.
fn write_positional(f: &mut fmt::Formatter<'_>, ds: &str, e: i32) -> fmt::Result {
    if e < 0 {
        f.write_str("0.")?;
        for _ in 0..(-e - 1) {
            f.write_str("0")?;
        }
        return f.write_str(ds);
    }
    let int_len = e as usize + 1;
    let len = ds.len();
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

/// The digits `ds` with decimal exponent `e` as `d.ddde<e>` (`de<e>` for a single digit).
fn write_scientific(f: &mut fmt::Formatter<'_>, ds: &str, e: i32) -> fmt::Result {
    f.write_str(&ds[..1])?;
    if ds.len() > 1 {
        f.write_str(".")?;
        f.write_str(&ds[1..])?;
    }
    write!(f, "e{e}")
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// A long echo is cut after its first 200 characters with the count of the rest; a short
    /// one is only escaped.
    #[test]
    fn clipped_echoes() {
        let long = "x".repeat(1000);
        let shown = format!("{}", Clipped(&long));
        assert_eq!(shown, "x".repeat(200) + "... (800 more characters)");
        assert_eq!(format!("{}", Clipped("a\u{1b}b")), "a\\x1bb");
        let cut = format!("{}", Clipped::with_limit("ééééé", 2));
        assert_eq!(cut, "éé... (3 more characters)");
    }

    /// Issue 30: the bound is on what is shown, escapes counted as they are shown and never
    /// cut: 300 ESC characters were echoed as 200 escapes (800 characters); now at most 200
    /// characters, whole escapes, and the rest counted as shown.
    #[test]
    fn clipped_escapes_first_then_cuts_on_what_is_shown() {
        let escs = "\u{1b}".repeat(300);
        let shown = format!("{}", Clipped(&escs));
        assert_eq!(shown, "\\x1b".repeat(50) + "... (1000 more characters)");
        // An escape that would cross the bound is left out whole: `ab` + `\x1b` > 5.
        assert_eq!(
            format!("{}", Clipped::with_limit("abc\u{1b}def", 5)),
            "abc... (7 more characters)"
        );
        // `\u{202e}` is 8 characters shown; exactly at the bound it passes uncut.
        assert_eq!(
            format!("{}", Clipped::with_limit("\u{202e}", 8)),
            "\\u{202e}"
        );
        assert_eq!(
            format!("{}", Clipped::with_limit("\u{202e}x", 8)),
            "\\u{202e}... (1 more characters)"
        );
        // Line feeds in user text are escaped, so an echo is one line.
        assert_eq!(format!("{}", Clipped("a\nb")), "a\\x0ab");
        for c in ['\u{1b}', '\n', '\u{85}', '\u{202e}', '\u{10ffff}', 'é', 'x'] {
            let mut one = [0u8; 4];
            let one = c.encode_utf8(&mut one);
            assert_eq!(
                format!("{}", Escaped(one)).chars().count(),
                shown_len(c),
                "{c:?}"
            );
        }
    }

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

    /// A value the user wrote is echoed as written (shortest round trip), never rounded to
    /// six digits (`1.0000001` once read "got 1"), and never as hundreds of digits
    /// (`1e-300` once printed as a 300-digit decimal); at most 24 characters.
    #[test]
    fn echoes_keep_the_users_value_exactly_and_short() {
        for (x, shown) in [
            (1.0000001, "1.0000001"),
            (0.1, "0.1"),
            (-2.5, "-2.5"),
            (1.0, "1"),
            (0.0, "0"),
            (1e-300, "1e-300"),
            (1e300, "1e300"),
            (1.2345678901234568e-300, "1.2345678901234568e-300"),
            (0.00001, "0.00001"),
            (0.000001, "1e-6"),
            (9e15, "9000000000000000"),
            (1e16, "1e16"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            let text = format!("{}", Echo(x));
            assert_eq!(text, shown, "{x:e}");
            if x.is_finite() {
                assert_eq!(text.parse::<f64>().unwrap(), x, "round trip of {text}");
            }
        }
        for x in [
            -1.2345678901234567e-300,
            -9.999999999999998e15,
            -0.000012345678901234567,
            f64::MIN_POSITIVE,
            -f64::MAX,
        ] {
            let text = format!("{}", Echo(x));
            assert!(text.len() <= 24, "{text}");
            assert_eq!(text.parse::<f64>().unwrap(), x, "round trip of {text}");
        }
        assert_eq!(
            format!("{}", EchoList(&[1.0000001, 1e-300])),
            "[1.0000001, 1e-300]"
        );
    }

    /// Computed values stay short: 14 characters at most, whatever the magnitude.
    #[test]
    fn computed_values_are_short() {
        for x in [
            1.0 / 1e-300,
            1e-300,
            -1.0 / 3.0e-7,
            123456789.123,
            -0.00000123456789,
        ] {
            let text = format!("{}", Num(x));
            assert!(text.len() <= 14, "{text}");
        }
        assert_eq!(format!("{}", Num(1.0 / 1e-300)), "1e300");
    }

    /// Control characters a terminal would obey and line feeds are shown as escapes; other
    /// text, tabs and non-ASCII letters pass as they are.
    #[test]
    fn terminal_controls_are_escaped() {
        for (raw, shown) in [
            ("a\x1b[31mred", "a\\x1b[31mred"),
            ("bell\x07", "bell\\x07"),
            ("over\rwrite", "over\\x0dwrite"),
            ("del\x7f", "del\\x7f"),
            ("c1\u{9b}31m", "c1\\u{9b}31m"),
            ("evil\u{202e}txt.csv", "evil\\u{202e}txt.csv"),
            ("iso\u{2066}late", "iso\\u{2066}late"),
            ("tab\tand é ü 中", "tab\tand é ü 中"),
            // Issue 30: a line feed in user text would start a console line of its own.
            ("new\nline", "new\\x0aline"),
            ("می\u{200c}خواهم", "می\u{200c}خواهم"),
            ("rlm\u{200f}", "rlm\\u{200f}"),
            ("", ""),
        ] {
            assert_eq!(format!("{}", Escaped(raw)), shown);
        }
    }

    /// Numbers written back into files: the exponent form outside [1e-5, 1e16) (`1e-300`, not
    /// 300 digits), positional with a point inside; each reads back bit for bit, and is at most
    /// 24 characters (17 significant digits, a sign, a point, `e-308`).
    #[test]
    fn toml_floats_are_short_and_round_trip() {
        for (x, shown) in [
            (1e-300, "1e-300"),
            (-1e-300, "-1e-300"),
            (1e300, "1e300"),
            (5e-324, "5e-324"),
            (f64::MAX, "1.7976931348623157e308"),
            (0.1, "0.1"),
            (600.0, "600.0"),
            (0.0, "0.0"),
            (-0.0, "-0.0"),
            (1e-5, "0.00001"),
            (9.99e-6, "9.99e-6"),
            (1e16, "1e16"),
            (9999999999999998.0, "9999999999999998.0"),
            (1e-310, "1e-310"),
            (1.0000001, "1.0000001"),
        ] {
            let t = format!("{}", TomlFloat(x));
            assert_eq!(t, shown);
            assert!(t.len() <= 24, "{t}");
            let back: f64 = t.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{t}");
        }
        // Every binade, both signs: bit for bit, at most 24 characters, a point or an exponent.
        for exponent in 0..0x7ffu64 {
            for mantissa in [
                0u64,
                1,
                0x8_0000_0000_0001,
                0xf_ffff_ffff_ffff,
                0x1_2345_6789_abcd,
            ] {
                let x = f64::from_bits((exponent << 52) | mantissa);
                for x in [x, -x] {
                    let t = format!("{}", TomlFloat(x));
                    assert_eq!(t.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{t}");
                    assert!(t.len() <= 24 && (t.contains('.') || t.contains('e')), "{t}");
                }
            }
        }
    }

    /// Zero-width and other invisible characters are invisible; letters, spaces, emoji and
    /// visible punctuation are not.
    #[test]
    fn invisible_characters() {
        for c in [
            '\u{200b}',
            '\u{200c}',
            '\u{200d}',
            '\u{2060}',
            '\u{feff}',
            '\u{ad}',
            '\u{202e}',
            '\u{e0041}',
            '\u{fe0f}',
        ] {
            assert!(is_invisible(c), "{c:?}");
        }
        for c in ['a', ' ', '_', '|', 'é', '中', '\u{1f600}', '\u{2028}'] {
            assert!(!is_invisible(c), "{c:?}");
        }
    }

    /// Issue 30 (att30b item 3): the line and paragraph separators (Zl, Zp) and every format
    /// character (Cf) are not plain text, the ones that are not default-ignorable included:
    /// the interlinear annotation marks U+FFF9-U+FFFB, the Egyptian hieroglyph format controls
    /// U+13430-U+13438, the Arabic number signs U+0600-U+0605, U+06DD, U+070F, U+0890-U+0891,
    /// U+08E2, U+110BD, U+110CD (the code points Python's `unicodedata.category` gives as Cf,
    /// Zl, Zp that the old rule passed). Letters, spaces, marks and emoji are plain.
    #[test]
    fn every_format_and_separator_character_is_not_plain() {
        let refused = [
            '\u{2028}',
            '\u{2029}',
            '\u{fff9}',
            '\u{fffa}',
            '\u{fffb}',
            '\u{13430}',
            '\u{13438}',
            '\u{600}',
            '\u{605}',
            '\u{6dd}',
            '\u{70f}',
            '\u{890}',
            '\u{891}',
            '\u{8e2}',
            '\u{110bd}',
            '\u{110cd}',
            '\u{200b}',
            '\u{feff}',
            '\u{ad}',
            '\u{202e}',
            '\u{85}',
            '\u{1b}',
            '\u{e0001}',
        ];
        for c in refused {
            assert!(is_not_plain(c), "U+{:04X}", c as u32);
            // Shown escaped in a message, so a refusal shows where it is.
            let shown = format!("{}", Escaped(&format!("a{c}b")));
            assert!(
                shown.starts_with("a\\") && shown.ends_with('b'),
                "{shown:?}"
            );
            assert!(!shown.contains(c), "{shown:?}");
        }
        assert_eq!(format!("{}", Escaped("a\u{200b}b")), "a\\u{200b}b");
        assert_eq!(format!("{}", Escaped("a\u{2028}b")), "a\\u{2028}b");
        for c in [
            'a',
            ' ',
            '\u{a0}',
            '_',
            'é',
            '中',
            '\u{301}',
            '\u{1f600}',
            '\u{3000}',
        ] {
            assert!(!is_not_plain(c), "U+{:04X}", c as u32);
        }
        // A tab is a control character, but shown as itself (descriptions hold tabs).
        assert!(is_not_plain('\t'));
        assert_eq!(format!("{}", Escaped("a\tb")), "a\tb");
    }
}
