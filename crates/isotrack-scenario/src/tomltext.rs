//! TOML text isotrack writes (`isotrack show`, a run's `scenario.toml`, a sweep's
//! `base_scenario.toml`, a suite as run) and TOML values it writes into CSV cells: every float
//! in its shortest round-trip form ([`TomlFloat`]). The `toml` crate writes a float with Rust's
//! `{}`, which never uses an exponent: `1e-300` came out as 300 digits and `1e300` as 301.

use isotrack_core::numtext::TomlFloat;

/// `v` as TOML text (`toml::to_string`), its floats outside `[1e-5, 1e16)` in exponent form
/// ([`short_floats`]). Reads back as the same value, bit for bit.
pub fn to_toml<T: serde::Serialize + ?Sized>(v: &T) -> Result<String, toml::ser::Error> {
    toml::to_string(v).map(|t| short_floats(&t))
}

/// A TOML value as text (strings quoted, as `toml` writes them), its floats as [`TomlFloat`]:
/// what a sweep writes into `results.csv` cells and override arguments.
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) if x.is_finite() => TomlFloat(*x).to_string(),
        toml::Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(value_text).collect();
            format!("[{}]", parts.join(", "))
        }
        other => short_floats(&other.to_string()),
    }
}

/// Whether `c` may be part of a bare key or a number token.
fn is_word(c: u8) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, b'_' | b'-' | b'+' | b'.')
}

/// The index just past the string starting at `text[i]` (a `"` or `'`, single or tripled;
/// backslash escapes in basic strings).
fn skip_string(text: &[u8], i: usize) -> usize {
    let q = text[i];
    let triple = text.get(i..i + 3) == Some(&[q, q, q][..]);
    let mut j = i + if triple { 3 } else { 1 };
    while j < text.len() {
        let c = text[j];
        if c == b'\\' && q == b'"' {
            j += 2;
            continue;
        }
        if c == q {
            if !triple {
                return j + 1;
            }
            if text.get(j..j + 3) == Some(&[q, q, q][..]) {
                // Up to two more quotes may end the content (`""""" `).
                let mut k = j + 3;
                while k < text.len() && text[k] == q && k < j + 5 {
                    k += 1;
                }
                return k;
            }
        }
        if c == b'\n' && !triple {
            return j;
        }
        j += 1;
    }
    text.len()
}

/// TOML text `text` with every float value written in positional form outside `[1e-5, 1e16)`
/// rewritten in exponent form ([`TomlFloat`]): `0.000...01` (300 digits) becomes `1e-300`. Only
/// values are touched (after a `=` on their line, outside strings and comments; a time's
/// fractional seconds after `:` are not numbers), and only when the new form is shorter;
/// the number read back is the same `f64`.
pub fn short_floats(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let (mut i, mut copied, mut in_value) = (0, 0, false);
    while i < b.len() {
        let c = b[i];
        match c {
            b'\n' => {
                in_value = false;
                i += 1;
            }
            b'#' => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'=' => {
                in_value = true;
                i += 1;
            }
            b'"' | b'\'' => i = skip_string(b, i),
            _ if in_value
                && (c.is_ascii_digit() || c == b'-' || c == b'+')
                && (i == 0 || !(is_word(b[i - 1]) || b[i - 1] == b':')) =>
            {
                let start = i;
                while i < b.len() && is_word(b[i]) {
                    i += 1;
                }
                let token = &text[start..i];
                let float_like = token.contains('.') && !token.contains(['e', 'E', '_', ':']);
                if let (true, Ok(x)) = (float_like, token.parse::<f64>()) {
                    let short = TomlFloat(x).to_string();
                    if short.len() < token.len() {
                        out.push_str(&text[copied..start]);
                        out.push_str(&short);
                        copied = i;
                    }
                }
            }
            _ => i += 1,
        }
    }
    out.push_str(&text[copied..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floats outside [1e-5, 1e16) come out in exponent form and read back bit for bit; the
    /// others, strings, keys, comments and times are left as they were.
    #[test]
    fn long_floats_are_shortened_and_read_back() {
        let v: toml::Table = toml::from_str(
            "a = 1e-300\nb = 1e300\nc = 0.5\nd = [1e-310, 2.0, -4.5e20]\n[t]\ns = \"0.0000000000000000000001\"\ne = { x = 1e-20 }\n",
        )
        .unwrap();
        let text = to_toml(&v).unwrap();
        assert!(text.len() < 200, "{text}");
        assert!(text.contains("a = 1e-300\n"), "{text}");
        assert!(text.contains("b = 1e300\n"), "{text}");
        assert!(text.contains("c = 0.5\n"), "{text}");
        assert!(text.contains("[1e-310, 2.0, -4.5e20]"), "{text}");
        assert!(text.contains("\"0.0000000000000000000001\""), "{text}");
        assert!(text.contains("1e-20"), "{text}");
        let back: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(back, v);
        assert_eq!(back["a"].as_float().unwrap().to_bits(), 1e-300f64.to_bits());
        // toml's own text is 300 digits long: what this fixes.
        assert!(toml::to_string(&v).unwrap().len() > 600);
        // Comments, literal and multi-line strings, times.
        let raw = "# 0.000000000000000001\nk = '0.000000000000000001'\nm = \"\"\"\nx = 0.000000000000000001\"\"\"\nt = 07:32:00.000000001\n";
        assert_eq!(short_floats(raw), raw);
        assert_eq!(
            value_text(&toml::Value::Array(vec![
                toml::Value::Float(1e-300),
                toml::Value::Integer(3)
            ])),
            "[1e-300, 3]"
        );
    }
}
