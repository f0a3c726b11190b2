//! Python values as `Scenario.set`'s dotted keys and TOML values: checked and converted here,
//! never read as TOML text.

use crate::errors::ScenarioErrorPy;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

/// The most dotted parts of a key (`isotrack_scenario`'s limit for `--set`) and the deepest
/// nesting of lists in a value (a scenario's deepest value is a list of pairs).
const MAX_KEY_PARTS: usize = isotrack_scenario::load::MAX_KEY_PARTS;
const MAX_VALUE_DEPTH: usize = 8;
/// The longest key taken, bytes (the longest dotted scenario key is about 40).
const MAX_KEY_BYTES: usize = 256;

/// A `Scenario.set` key: dotted parts of letters, digits, `_` and `-` (TOML's bare keys), at
/// most [`MAX_KEY_PARTS`] of them. Anything else is refused here, so that no key is ever read
/// as TOML (`"sim.duration_s = 7 #"` once set the duration to 7).
pub(crate) fn check_key(key: &str) -> PyResult<()> {
    // No scenario key is longer than a few dozen characters: a longer one is refused before
    // it is split, matched or compared for "did you mean" (a 10 MB key inside a dict once
    // took 33 s to refuse, ver30b-13).
    if key.len() > MAX_KEY_BYTES {
        return Err(ScenarioErrorPy::new_err(format!(
            "`{}`: a key of {} bytes (no scenario key is longer than {MAX_KEY_BYTES})",
            isotrack_scenario::load::clip(key),
            key.len()
        )));
    }
    let shown = isotrack_scenario::load::clip(key);
    let parts: Vec<&str> = key.split('.').collect();
    if parts.len() > MAX_KEY_PARTS {
        return Err(ScenarioErrorPy::new_err(format!(
            "`{shown}`: a key has at most {MAX_KEY_PARTS} dotted parts, this one has {}",
            parts.len()
        )));
    }
    let bare = |p: &str| {
        !p.is_empty()
            && p.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    if !parts.iter().all(|p| bare(p)) {
        return Err(ScenarioErrorPy::new_err(format!(
            "`{shown}`: not a dotted key such as controller.kp (letters, digits, `_` and `-` \
             between the dots)"
        )));
    }
    Ok(())
}

/// A value as a TOML literal for `--set`, its floats in the shortest form that reads back
/// exactly (`1e300`, not the 301 digits the `toml` crate writes, which every error message
/// would echo): Rust's `{:?}` of a finite `f64`, which TOML reads (`1e300`, `0.1`, `10.0`).
/// A table is an inline table (`{ kp = 2.0, ki = 1.0 }`) whose keys [`toml_value`] has checked
/// to be dotted bare keys, written as they are (a dotted key nests, as in `--set`'s TOML).
pub(crate) fn toml_literal(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) if f.is_finite() => format!("{f:?}"),
        toml::Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(toml_literal).collect();
            format!("[{}]", parts.join(", "))
        }
        toml::Value::Table(t) if t.is_empty() => "{}".to_string(),
        toml::Value::Table(t) => {
            let parts: Vec<String> = t
                .iter()
                .map(|(k, x)| format!("{k} = {}", toml_literal(x)))
                .collect();
            format!("{{ {} }}", parts.join(", "))
        }
        other => other.to_string(),
    }
}

/// A scenario error about a float given for an integer key, as the user wrote it: serde
/// echoes the float through its own formatting (`2.0**64` as `floating point
/// `18446744073709552000.0``, digits the user never wrote), and does not say which integers
/// the key takes. The float is echoed as Python's `repr` and the range named (TOML's integers
/// are 64-bit signed, so an unsigned key takes 0 ..= 2**63-1).
pub(crate) fn as_written(message: &str, value: &Bound<'_, PyAny>) -> String {
    const FLOAT: &str = "invalid type: floating point `";
    if value.is_instance_of::<PyList>()
        || value.is_instance_of::<PyTuple>()
        || value.is_instance_of::<PyDict>()
    {
        return message.to_string();
    }
    let Some(start) = message.find(FLOAT) else {
        return message.to_string();
    };
    let rest = &message[start + FLOAT.len()..];
    let Some(close) = rest.find('`') else {
        return message.to_string();
    };
    let after = &rest[close + 1..];
    let (expected, tail) = match after.strip_prefix(", expected ") {
        Some(e) => {
            let end = e
                .find(|c: char| !c.is_ascii_alphanumeric())
                .unwrap_or(e.len());
            (&e[..end], &e[end..])
        }
        None => ("", after),
    };
    let range = match expected {
        "u8" => "an integer in 0 ..= 255",
        "u16" => "an integer in 0 ..= 65535",
        "u32" => "an integer in 0 ..= 4294967295 (2**32-1)",
        "u64" | "usize" => "an integer in 0 ..= 9223372036854775807 (2**63-1, TOML's largest)",
        "i32" => "an integer in -2147483648 ..= 2147483647",
        "i64" | "isize" => "an integer in -2**63 ..= 2**63-1",
        _ => return message.to_string(),
    };
    format!(
        "{}{} is a float; this key takes {range}, written without a decimal point{tail}",
        &message[..start],
        shown(value)
    )
}

/// A value's `repr` for a message, clipped (a million-element list once made a megabyte error),
/// or its type when it has no `repr` (an int past Python's digit limit).
pub(crate) fn shown(v: &Bound<'_, PyAny>) -> String {
    let text = v
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| format!("a {}", v.get_type()));
    isotrack_scenario::load::clip(&text)
}

/// A Python value as a TOML value for `--set`: booleans, integers (64-bit), finite floats,
/// strings, lists or tuples of them, and dicts of them (a TOML table, merged key by key into
/// the scenario's as `--set KEY={ ... }` is; its keys dotted keys as [`check_key`] takes), nested
/// at most [`MAX_VALUE_DEPTH`] deep (a list or dict that holds itself is refused, not followed).
pub(crate) fn toml_value(key: &str, v: &Bound<'_, PyAny>, depth: usize) -> PyResult<toml::Value> {
    let bad = |what: String| ScenarioErrorPy::new_err(format!("`{key}`: {what}"));
    if depth > MAX_VALUE_DEPTH {
        return Err(bad(format!(
            "lists or dicts nested more than {MAX_VALUE_DEPTH} deep (or one that holds itself)"
        )));
    }
    if let Ok(b) = v.extract::<bool>() {
        return Ok(toml::Value::Boolean(b));
    }
    if v.is_instance_of::<pyo3::types::PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(bad(format!(
                "{} does not fit in a 64-bit integer (-2**63 ..= 2**63-1, TOML's integers)",
                shown(v)
            ))),
        };
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(toml::Value::String(s));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: PyResult<Vec<toml::Value>> = v
            .try_iter()?
            .map(|item| toml_value(key, &item?, depth + 1))
            .collect();
        return Ok(toml::Value::Array(items?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let Ok(name) = k.extract::<String>() else {
                return Err(bad(format!(
                    "a dict's keys are the table's keys (str, such as \"kp\"), got {}",
                    shown(&k)
                )));
            };
            check_key(&name)
                .map_err(|e| ScenarioErrorPy::new_err(format!("`{key}`: {}", e.value(v.py()))))?;
            t.insert(name, toml_value(key, &x, depth + 1)?);
        }
        return Ok(toml::Value::Table(t));
    }
    // A numpy integer (`np.int64`, `np.uint64`, ...) is not a Python int: taken exactly through
    // `operator.index`, never through a float (which rounds past 2**53).
    // A numpy array has `__index__` but refuses it unless it is a 0-d integer array: then it is
    // no integer, and is read as a float below (or refused, naming the key).
    let exact = if !v.is_instance_of::<pyo3::types::PyFloat>() && v.hasattr("__index__")? {
        v.py().import("operator")?.call_method1("index", (v,)).ok()
    } else {
        None
    };
    if let Some(exact) = exact {
        return match exact.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(bad(format!(
                "{} does not fit in a 64-bit integer (-2**63 ..= 2**63-1, TOML's integers)",
                shown(v)
            ))),
        };
    }
    if let Ok(f) = v.extract::<f64>() {
        if !f.is_finite() {
            return Err(bad(format!("{f} is not a finite number")));
        }
        return Ok(toml::Value::Float(f));
    }
    Err(bad(format!(
        "cannot use {} as a scenario value (numbers, booleans, strings, or lists or dicts of them)",
        shown(v)
    )))
}

/// A TOML value's literal (a sweep's `"table"` cell, [`crate::sweep::literal_cells`]) as the
/// Python value `Scenario.set` takes back: a table a dict (its keys in TOML's order), an array a
/// list, a string a str, integers int, floats float, booleans bool (a date-time its TOML text).
#[pyfunction]
pub(crate) fn toml_cell(py: Python<'_>, text: &str) -> PyResult<Py<PyAny>> {
    let mut t: toml::Table = toml::from_str(&format!("v = {text}")).map_err(|e| {
        ScenarioErrorPy::new_err(format!(
            "internal error in isotrack: a sweep cell that is not a TOML value ({}): {}",
            isotrack_scenario::load::clip(text),
            e.message()
        ))
    })?;
    let v = t.remove("v").unwrap_or(toml::Value::Boolean(false));
    to_python(py, &v)
}

fn to_python(py: Python<'_>, v: &toml::Value) -> PyResult<Py<PyAny>> {
    use pyo3::IntoPyObjectExt;
    Ok(match v {
        toml::Value::String(s) => s.into_py_any(py)?,
        toml::Value::Integer(i) => i.into_py_any(py)?,
        toml::Value::Float(f) => f.into_py_any(py)?,
        toml::Value::Boolean(b) => b.into_py_any(py)?,
        toml::Value::Datetime(d) => d.to_string().into_py_any(py)?,
        toml::Value::Array(a) => {
            let items: PyResult<Vec<Py<PyAny>>> = a.iter().map(|x| to_python(py, x)).collect();
            PyList::new(py, items?)?.into_any().unbind()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, to_python(py, x)?)?;
            }
            d.into_any().unbind()
        }
    })
}

/// The dotted keys a `(key, value)` sets with their values ([`keys_set`]'s, each with its value).
pub(crate) fn leaves<'a>(key: &str, v: &'a toml::Value, out: &mut Vec<(String, &'a toml::Value)>) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                leaves(&format!("{key}.{k}"), x, out);
            }
        }
        _ => out.push((key.to_string(), v)),
    }
}

/// A message without the Rust type names serde writes (`expected struct ControllerSection`,
/// for a value where a table goes, ver30b-10): said as `expected a table of keys`.
pub(crate) fn no_type_names(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(at) = rest.find("expected struct ") {
        out.push_str(&rest[..at]);
        let after = &rest[at + "expected struct ".len()..];
        let end = after
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        out.push_str("expected a table of keys");
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The dotted keys a `(key, value)` sets: `key` itself, or for a table each of its values'
/// keys under it (a table is merged key by key, so it sets only the keys it holds; a list,
/// `team.vehicles = [{...}]` included, is one value).
pub(crate) fn keys_set(key: &str, v: &toml::Value, out: &mut Vec<String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                keys_set(&format!("{key}.{k}"), x, out);
            }
        }
        _ => out.push(key.to_string()),
    }
}

/// Refuses two `(key, value)` pairs of one `set` call that set one key (ver30b-13): the same
/// dotted key, or a key and a key under it (`{"sim": {"seed": 1}, "sim.seed": 2}`, which
/// would otherwise take whichever came last), as a sweep refuses `[base]` and `[grid]`
/// setting one key twice. `keys[i]` are the keys pair `names[i]` sets ([`keys_set`]).
pub(crate) fn check_once(names: &[&str], keys: &[Vec<String>]) -> PyResult<()> {
    let mut by_key: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, ks) in keys.iter().enumerate() {
        for k in ks {
            by_key.entry(k.as_str()).or_insert(i);
        }
    }
    for (i, ks) in keys.iter().enumerate() {
        for k in ks {
            // The key itself and every key above it (`sim` above `sim.seed`).
            let above = k.match_indices('.').map(|(at, _)| &k[..at]);
            for prefix in std::iter::once(k.as_str()).chain(above) {
                match by_key.get(prefix) {
                    Some(&j) if j != i => {
                        let (a, b) = if j < i { (j, i) } else { (i, j) };
                        return Err(ScenarioErrorPy::new_err(format!(
                            "`{}` and `{}` set one key twice in one set() call (`{prefix}`; \
                             a table holding a key and the key itself, or two spellings of \
                             it): keep one",
                            isotrack_scenario::load::clip(names[a]),
                            isotrack_scenario::load::clip(names[b])
                        )));
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}
