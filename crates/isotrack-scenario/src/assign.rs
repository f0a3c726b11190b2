//! `KEY=VALUE` assignments to a scenario's keys (`--set`, a sweep's `[base]`/`[grid]`/`[random]`,
//! `compare --gain`): parsing one value, inserting it, checking the schema still holds, switching
//! kinds, and locating a derived scenario's problems at the assignment that caused them.

use crate::error::{clip, ErrorLocation, LocatedIssue, ScenarioError};
use crate::resolve::{drop_inapplicable_keys, Issue, KINDED_SECTIONS};
use crate::schema::{ControllerKind, ScenarioFile};

/// The most dotted parts of a `--set` key (every scenario key has two, `controller.kp`; the
/// rest is room for a clear "unknown field" message).
pub const MAX_KEY_PARTS: usize = 8;

/// One `KEY=VALUE` assignment and the label its errors carry (where it came from: a sweep's
/// `[grid]`, a `compare --gain`, ...), so a message names its true source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    /// `KEY=VALUE`.
    pub arg: String,
    /// Where it came from, shown in messages in place of `--set KEY=VALUE`.
    pub label: String,
}

impl Assignment {
    /// An assignment labelled `{source}: {arg}`.
    pub fn new(arg: impl Into<String>, source: &str) -> Self {
        let arg = arg.into();
        Self {
            label: format!("{source}: {arg}"),
            arg,
        }
    }
}

/// Applies assignments to a (typically resolved) scenario file; errors carry the assignment's
/// label. Used to derive variants of a scenario (one per controller in `compare`, one per run
/// in a sweep).
pub fn apply_assignments(
    file: &ScenarioFile,
    assignments: &[Assignment],
) -> Result<ScenarioFile, ScenarioError> {
    let mut table = match toml::Value::try_from(file) {
        Ok(toml::Value::Table(t)) => t,
        _ => toml::Table::new(),
    };
    let mut switches = [false; KINDED_SECTIONS.len()];
    for a in assignments {
        let at = ErrorLocation::Assigned {
            label: a.label.clone(),
        };
        let key = apply_one(&mut table, &a.arg, at)?;
        for (s, section) in switches.iter_mut().zip(KINDED_SECTIONS) {
            *s |= key == format!("{section}.kind") || key == section;
        }
    }
    for (_, section) in switches.iter().zip(KINDED_SECTIONS).filter(|(s, _)| **s) {
        // A sweep across controllers (or fields, or vehicles): each run keeps only the keys
        // its kind takes (README, "Sweeps"), after all its assignments, whatever their order.
        drop_inapplicable_keys(&mut table, section);
    }
    toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| {
            ScenarioError::Invalid(vec![LocatedIssue {
                location: ErrorLocation::Default {
                    origin: "<derived>".into(),
                },
                key: None,
                message: e.message().to_string(),
                unreadable: false,
            }])
        })
}

/// Locates the issues of a derived scenario: at the assignment that set the key (or a table
/// holding it), else as inherited from the scenario it was derived from.
pub(crate) fn locate_derived(
    issues: Vec<Issue>,
    origin: &str,
    assignments: &[Assignment],
) -> ScenarioError {
    ScenarioError::Invalid(
        issues
            .into_iter()
            .map(|i| {
                let set = assignments.iter().rev().find(|a| {
                    let k = a.arg.split_once('=').map_or("", |(k, _)| k.trim());
                    key_covers(k, &i.key)
                });
                LocatedIssue {
                    location: match set {
                        Some(a) => ErrorLocation::Assigned {
                            label: a.label.clone(),
                        },
                        None => ErrorLocation::Inherited {
                            origin: origin.to_string(),
                        },
                    },
                    key: Some(i.key),
                    message: i.message,
                    unreadable: i.unreadable,
                }
            })
            .collect(),
    )
}

/// A team key assigned onto a base scenario without `[team]` (nu-19: a sweep's `[grid]
/// team.k_v`): the section the assignment creates has no `team.count` (nor `team.starts`), and
/// that problem, inherited from nowhere the user wrote, is located at the first assignment of
/// a team key, saying that the base has no `[team]` (it was "a value of the base scenario or
/// its default" asking for `team.count`). Other problems are as located.
pub(crate) fn blame_team_onto_no_team(
    e: ScenarioError,
    assignments: &[Assignment],
) -> ScenarioError {
    let ScenarioError::Invalid(issues) = e else {
        return e;
    };
    let team_key = |a: &&Assignment| {
        let k = a.arg.split_once('=').map_or("", |(k, _)| k.trim());
        key_covers("team", k)
    };
    let Some(first) = assignments.iter().find(team_key) else {
        return ScenarioError::Invalid(issues);
    };
    let key = first.arg.split_once('=').map_or("", |(k, _)| k.trim());
    ScenarioError::Invalid(
        issues
            .into_iter()
            .map(|i| {
                if i.key.as_deref() == Some("team.count")
                    && matches!(i.location, ErrorLocation::Inherited { .. })
                {
                    LocatedIssue {
                        location: ErrorLocation::Assigned {
                            label: first.label.clone(),
                        },
                        key: Some(key.to_string()),
                        message: "the base scenario has no [team] section: a team key applies to a team; give the base a [team] (team.count, or team.starts), or assign team.count too".into(),
                        unreadable: false,
                    }
                } else {
                    i
                }
            })
            .collect(),
    )
}

/// Whether an assignment to `set` is the source of a problem with `issue_key`: the same key,
/// a table holding it, or a key inside it.
pub(crate) fn key_covers(set: &str, issue_key: &str) -> bool {
    issue_key == set
        || issue_key.starts_with(&format!("{set}."))
        || issue_key.starts_with(&format!("{set}["))
        || set.starts_with(&format!("{issue_key}."))
}

/// Applies one `KEY=VALUE` to `table` and checks the schema still holds; returns the key.
/// Errors name the argument.
pub(crate) fn apply_one(
    table: &mut toml::Table,
    arg: &str,
    at: ErrorLocation,
) -> Result<String, ScenarioError> {
    let fail = |key: Option<String>, message: String| {
        ScenarioError::Invalid(vec![LocatedIssue {
            location: at.clone(),
            key,
            message,
            unreadable: false,
        }])
    };
    let (key, raw) = arg
        .split_once('=')
        .ok_or_else(|| fail(None, "expected KEY=VALUE".into()))?;
    let key = key.trim().to_string();
    // Before anything walks the key: a 60 000-part key once nested 60 000 tables and
    // overflowed the stack.
    let parts = key.split('.').count();
    if parts > MAX_KEY_PARTS {
        return Err(fail(
            None,
            format!("a key has at most {MAX_KEY_PARTS} dotted parts, this one has {parts}"),
        ));
    }
    if key.is_empty() || key.split('.').any(|p| p.trim().is_empty()) {
        return Err(fail(
            None,
            "expected a dotted key such as controller.kp".into(),
        ));
    }
    let value = parse_override_value(raw.trim()).map_err(|m| fail(Some(key.clone()), m))?;
    insert_dotted(table, &key, value).map_err(|m| fail(Some(key.clone()), m))?;
    toml::Value::Table(table.clone())
        .try_into::<ScenarioFile>()
        .map_err(|e| {
            let message = did_you_mean(e.message().trim(), Some(&key), controller_kind(table));
            fail(Some(key.clone()), message)
        })?;
    Ok(key)
}

/// The controller kind a scenario table names (`None` when it names none or an unknown one).
pub(crate) fn controller_kind(table: &toml::Table) -> Option<ControllerKind> {
    let kind = table.get("controller")?.get("kind")?.clone();
    kind.try_into().ok()
}

/// The names closest to `typed` among `candidates`: those at one edit (Damerau-Levenshtein)
/// or with a Jaro-Winkler similarity of at least 0.8 (a prefix such as `speed` for
/// `speed_mps`), the best first, at most three. `strsim`'s measures, as clap uses for
/// subcommands.
pub fn closest_names<'a>(typed: &str, candidates: &[&'a str]) -> Vec<&'a str> {
    let mut scored: Vec<(usize, f64, &str)> = candidates
        .iter()
        .map(|c| {
            (
                strsim::damerau_levenshtein(typed, c),
                strsim::jaro_winkler(typed, c),
                *c,
            )
        })
        .filter(|&(d, jw, _)| d <= 1 || jw >= 0.8)
        .collect();
    scored.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
    let Some(&(d0, jw0, _)) = scored.first() else {
        return vec![];
    };
    // The best, and those as good (a typo one edit from several names names them all).
    scored
        .iter()
        .take_while(|&&(d, jw, _)| d == d0 && (d0 <= 1 || (jw0 - jw).abs() < 1e-9))
        .take(3)
        .map(|s| s.2)
        .collect()
}

/// A schema error with a suggestion: for `unknown field `X`, expected one of `a`, `b`` (the
/// schema's own list of the section's keys, as serde writes it), the nearest of those keys;
/// in `[controller]` the list and the suggestion are the keys of the controller kind the
/// scenario names (`kind`, default `pi_isoline`), not every law's.
pub(crate) fn did_you_mean(
    message: &str,
    key: Option<&str>,
    kind: Option<ControllerKind>,
) -> String {
    if let Some(plain) = number_out_of_range(message) {
        return plain;
    }
    let Some(rest) = message.strip_prefix("unknown field `") else {
        return message.to_string();
    };
    let Some((typed, tail)) = rest.split_once('`') else {
        return message.to_string();
    };
    let listed: Vec<&str> = tail
        .split_once("expected one of ")
        .or_else(|| tail.split_once("expected "))
        .map(|(_, list)| {
            list.split(", ")
                .map(|k| k.trim().trim_matches('`'))
                .filter(|k| !k.is_empty())
                .collect()
        })
        .unwrap_or_default();
    let in_controller = key.is_some_and(|k| k.starts_with("controller."));
    let (keys, head) = if in_controller {
        let kind = kind.unwrap_or(ControllerKind::PiIsoline);
        let keys = crate::resolve::controller_keys(kind);
        let head = format!(
            "unknown field `{typed}` for controller.kind = \"{}\", expected one of {}",
            kind.name(),
            keys.iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        (keys, head)
    } else {
        (listed, message.to_string())
    };
    match closest_names(typed, &keys).as_slice() {
        [] => head,
        [one] => format!("{head}; did you mean `{one}`?"),
        [init @ .., last] => format!(
            "{head}; did you mean {} or `{last}`?",
            init.iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The `kind` of each of [`KINDED_SECTIONS`] a scenario table names (`None` when unset: the
/// default).
pub(crate) fn kinds_of(table: &toml::Table) -> [Option<String>; KINDED_SECTIONS.len()] {
    KINDED_SECTIONS.map(|section| {
        table
            .get(section)?
            .get("kind")?
            .as_str()
            .map(str::to_string)
    })
}

/// `VALUE` as one TOML value, parsed on its own (never spliced into TOML text, so a newline
/// or a `#` cannot add a key or hide the rest); a bare word that is not TOML (`dubins`) is
/// taken as a string; anything else that does not parse is refused.
fn parse_override_value(raw: &str) -> Result<toml::Value, String> {
    match raw.parse::<toml::Value>() {
        Ok(v) => Ok(v),
        // A number TOML cannot hold (`9223372036854775808`, `1e400`) is no word: taken as a
        // string it was refused as "invalid type: string ..., expected u64".
        Err(_) if looks_like_a_number(raw) => Err(if raw.contains(['.', 'e', 'E']) {
            format!("`{}` {FLOAT_RANGE}", clip(raw))
        } else {
            format!("`{}` {INTEGER_RANGE}", clip(raw))
        }),
        Err(_) if is_bare_word(raw) => Ok(toml::Value::String(raw.to_string())),
        // A number TOML cannot hold inside a list or table (`[1e400]`): the number's bound,
        // not advice to quote a string (att30c-16).
        Err(e) if number_out_of_range(e.message()).is_some() => Err(format!(
            "`{}`: {}",
            clip(&raw.escape_debug().to_string()),
            number_out_of_range(e.message()).unwrap_or_default()
        )),
        Err(e) => Err(format!(
            "`{}` is not one TOML value ({}); quote a string, e.g. \"text\"",
            clip(&raw.escape_debug().to_string()),
            e.message().trim()
        )),
    }
}

/// What is said of an integer TOML cannot hold (TOML's integers are 64-bit signed, so a
/// `u64` seed too stops at 2^63 - 1).
const INTEGER_RANGE: &str =
    "does not fit in a 64-bit integer (-9223372036854775808 ..= 9223372036854775807, TOML's integers)";

/// What is said of a float beyond the largest 64-bit float.
const FLOAT_RANGE: &str = "is beyond the largest 64-bit float (about 1.8e308)";

/// Whether `raw` is written as a decimal number (`-12`, `1_000`, `2.5e-3`): an optional sign,
/// digits (with `_` between them), an optional fraction and exponent.
pub(crate) fn looks_like_a_number(raw: &str) -> bool {
    let digits = |t: &str| {
        !t.is_empty()
            && t.starts_with(|c: char| c.is_ascii_digit())
            && t.ends_with(|c: char| c.is_ascii_digit())
            && t.chars().all(|c| c.is_ascii_digit() || c == '_')
    };
    let body = raw.strip_prefix(['+', '-']).unwrap_or(raw);
    let (mantissa, exponent) = match body.split_once(['e', 'E']) {
        Some((m, e)) => (m, Some(e.strip_prefix(['+', '-']).unwrap_or(e))),
        None => (body, None),
    };
    let mantissa_ok = match mantissa.split_once('.') {
        Some((i, f)) => digits(i) && digits(f),
        None => digits(mantissa),
    };
    mantissa_ok && exponent.is_none_or(digits)
}

/// The TOML reader's and serde's words for a number out of range (`u64 value was too large`,
/// `invalid type: integer `1e23` as i128, expected u64`, `floating-point number overflowed`)
/// in plain words, naming the range; `None` for any other message.
pub(crate) fn number_out_of_range(message: &str) -> Option<String> {
    let m = message.trim();
    if m.ends_with("value was too large") || m == "integer number overflowed" {
        return Some(format!("the number {INTEGER_RANGE}"));
    }
    if let Some(rest) = m.strip_prefix("invalid type: integer `") {
        if let Some((n, tail)) = rest.split_once('`') {
            if tail.starts_with(" as i128") {
                return Some(format!("`{}` {INTEGER_RANGE}", clip(n)));
            }
        }
    }
    if m == "floating-point number overflowed" {
        return Some(format!("the number {FLOAT_RANGE}"));
    }
    // A negative number for an unsigned key (`sim.seed = -1`): serde's "invalid value:
    // integer `-1`, expected u64" said in the same words as the other bounds (att30c-16).
    if let Some(rest) = m.strip_prefix("invalid value: integer `") {
        if let Some((n, tail)) = rest.split_once('`') {
            let max = match tail.trim() {
                ", expected u64" | ", expected usize" => Some(i64::MAX as u64),
                ", expected u32" => Some(u64::from(u32::MAX)),
                ", expected u16" => Some(u64::from(u16::MAX)),
                ", expected u8" => Some(u64::from(u8::MAX)),
                _ => None,
            };
            if let Some(max) = max {
                return Some(format!(
                    "`{}` is out of range: this key takes an integer 0 ..= {max}",
                    clip(n)
                ));
            }
        }
    }
    None
}

/// Text taken as a string when it is not a TOML value (a kind, a path, a name, with spaces;
/// other control characters are kept, and escaped wherever they are shown): one line, no
/// comment sign, not the start of an array, table or quoted string.
fn is_bare_word(raw: &str) -> bool {
    !raw.is_empty()
        && !raw.starts_with(['[', '{', '"', '\''])
        && !raw.chars().any(|c| matches!(c, '\n' | '\r' | '#'))
}

fn insert_dotted(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    let (last, parents) = parts.split_last().ok_or("empty key")?;
    let mut t = table;
    let mut walked = String::new();
    for p in parents {
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(p);
        let entry = t
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = entry
            .as_table_mut()
            .ok_or_else(|| format!("`{walked}` is not a table"))?;
    }
    match t.get_mut(*last) {
        Some(old) => merge_value(old, value),
        None => {
            t.insert(last.to_string(), value);
        }
    }
    Ok(())
}

/// Sets `old` to `new`, a table key by key: `controller = { kp = 2.0 }` over a `[controller]`
/// holding `ki` and `c1` sets `kp` and keeps them (issue 30, att30c-14: it once replaced the
/// section, so the file's keys fell back to their defaults without a word). Anything else
/// (a number, a list, a table over a non-table) replaces.
fn merge_value(old: &mut toml::Value, new: toml::Value) {
    match (old, new) {
        (toml::Value::Table(o), toml::Value::Table(n)) => {
            for (k, v) in n {
                match o.get_mut(&k) {
                    Some(slot) => merge_value(slot, v),
                    None => {
                        o.insert(k, v);
                    }
                }
            }
        }
        (old, new) => *old = new,
    }
}
