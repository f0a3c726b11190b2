//! Reading scenario files and `--set` overrides, with errors that say where.

use crate::resolve::{drop_inapplicable_keys, Issue, KINDED_SECTIONS};
use crate::schema::{ControllerKind, ScenarioFile};
use crate::Scenario;
use std::fmt;
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};

/// Where a scenario problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ErrorLocation {
    /// In the scenario file, at a 1-based line and column (if known).
    File {
        /// The file as given.
        path: String,
        /// 1-based line.
        line: Option<usize>,
        /// 1-based column.
        column: Option<usize>,
    },
    /// In a `--set KEY=VALUE` argument.
    Override {
        /// The argument as given.
        arg: String,
    },
    /// In a default value (a combination the defaults alone cannot satisfy).
    Default {
        /// The file as given, or `<built-in default>`.
        origin: String,
    },
    /// In an assignment that did not come from `--set`: a sweep's `[base]`, `[grid]` or
    /// `[random]` value, a `compare --gain`; the label names it (e.g.
    /// `sweep s.toml run 3, [grid] controller.kp=1.0`).
    Assigned {
        /// Where the assignment came from and what it was.
        label: String,
    },
    /// In a value a derived scenario inherited from the scenario it was derived from (its file
    /// or its defaults).
    Inherited {
        /// The derived scenario, e.g. `sweep s.toml run 3`.
        origin: String,
    },
}

impl fmt::Display for ErrorLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorLocation::File {
                path,
                line: Some(l),
                column: Some(c),
            } => write!(f, "{path}:{l}:{c}"),
            ErrorLocation::File {
                path,
                line: Some(l),
                column: None,
            } => write!(f, "{path}:{l}"),
            ErrorLocation::File { path, .. } => write!(f, "{path}"),
            ErrorLocation::Override { arg } => write!(f, "--set {arg}"),
            ErrorLocation::Default { origin } => write!(f, "{origin} (default value)"),
            ErrorLocation::Assigned { label } => write!(f, "{label}"),
            ErrorLocation::Inherited { origin } => {
                write!(f, "{origin} (a value of the base scenario or its default)")
            }
        }
    }
}

/// One located problem: where, which key, what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocatedIssue {
    /// Where.
    pub location: ErrorLocation,
    /// The dotted key, if the problem belongs to one.
    pub key: Option<String>,
    /// What is wrong.
    pub message: String,
    /// A file the key names could not be read at all (missing, not a regular file, beyond its
    /// size limit): the command exits 66, not 65 ([`ScenarioError::is_unreadable_input`]).
    pub unreadable: bool,
}

impl fmt::Display for LocatedIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // User text (keys, `--set` arguments, quoted values) is clipped: a message stays a
        // message whatever was typed.
        let at = clip(&self.location.to_string());
        let message = clip_quoted(&self.message);
        match &self.key {
            Some(k) => write!(f, "{at}: `{}`: {message}", clip(k)),
            None => write!(f, "{at}: {message}"),
        }
    }
}

/// `message` with every backtick-quoted span clipped by [`clip`], then the whole clipped to a
/// few times [`MAX_ECHO_CHARS`].
fn clip_quoted(message: &str) -> String {
    let clipped: Vec<String> = message
        .split('`')
        .enumerate()
        .map(|(i, part)| {
            if i % 2 == 1 {
                clip(part)
            } else {
                part.to_string()
            }
        })
        .collect();
    let joined = clipped.join("`");
    let max = 5 * MAX_ECHO_CHARS;
    if joined.chars().count() > max {
        let head: String = joined.chars().take(max).collect();
        format!("{head}...")
    } else {
        joined
    }
}

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario file {path}: {source}")]
    Io {
        /// The path as given.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file or an override is not valid TOML, has unknown keys, wrong types or invalid values.
    #[error("invalid scenario:\n{}", .0.iter().map(|i| format!("  {i}")).collect::<Vec<_>>().join("\n"))]
    Invalid(Vec<LocatedIssue>),
}

impl ScenarioError {
    /// Whether a file could not be read at all: the scenario file itself, or a file it names
    /// (`field.path`, `field.paths`) that is missing, a FIFO, a directory, a device or beyond
    /// its size limit. Commands exit 66 for these, 65 for what a file holds.
    pub fn is_unreadable_input(&self) -> bool {
        match self {
            ScenarioError::Io { .. } => true,
            ScenarioError::Invalid(v) => v.iter().any(|i| i.unreadable),
        }
    }

    /// The located problems (empty for I/O errors).
    pub fn issues(&self) -> &[LocatedIssue] {
        match self {
            ScenarioError::Invalid(v) => v,
            ScenarioError::Io { .. } => &[],
        }
    }
}

/// The largest scenario (or sweep) file read, bytes (1 MiB: the longest bundled one is 2 kB).
pub const MAX_SCENARIO_FILE_BYTES: u64 = 1 << 20;

/// The most dotted parts of a `--set` key (every scenario key has two, `controller.kp`; the
/// rest is room for a clear "unknown field" message).
pub const MAX_KEY_PARTS: usize = 8;

/// The most characters of user text (a key, a value, a file's line) echoed in one message: a
/// 10 MB key once made a 20 MB error. Counted on the text as shown, escapes included.
pub const MAX_ECHO_CHARS: usize = isotrack_core::numtext::ECHO_CHARS;

/// `text` as [`isotrack_core::numtext::Clipped`] shows it: terminal controls and line feeds
/// escaped (a message raised to Python or written to a file shows them as `\x1b`, as the
/// console does), then cut to [`MAX_ECHO_CHARS`] characters of what is shown, with the number
/// left out said.
pub fn clip(text: &str) -> String {
    isotrack_core::numtext::Clipped(text).to_string()
}

/// Loads a scenario file (or the built-in default when `path` is `None`), applies the `--set`
/// overrides in order, fills defaults and validates.
pub fn load_scenario(path: Option<&Path>, overrides: &[String]) -> Result<Scenario, ScenarioError> {
    match path {
        None => parse_scenario_in("", "<built-in default>", overrides, Path::new(".")),
        Some(p) => {
            let shown = p.display().to_string();
            let text = isotrack_fields::io::read_text_limited(p, MAX_SCENARIO_FILE_BYTES).map_err(
                |source| ScenarioError::Io {
                    path: shown.clone(),
                    source,
                },
            )?;
            // A file with nothing in it (whitespace and comments only) once ran the default
            // scenario silently: an empty file is more likely a mistake than a wish.
            let blank = text.lines().all(|l| {
                let l = l.trim();
                l.is_empty() || l.starts_with('#')
            });
            if blank {
                return Err(ScenarioError::Invalid(vec![LocatedIssue {
                    location: ErrorLocation::File {
                        path: shown,
                        line: None,
                        column: None,
                    },
                    key: None,
                    message: "empty scenario file; to run the default omit the argument".into(),
                    unreadable: false,
                }]));
            }
            let base = p.parent().unwrap_or(Path::new("."));
            let base = if base.as_os_str().is_empty() {
                Path::new(".")
            } else {
                base
            };
            parse_scenario_in(&text, &shown, overrides, base)
        }
    }
}

/// Parses scenario text whose origin (for messages) is `origin`, then as [`load_scenario`];
/// files it names are relative to the current directory.
pub fn parse_scenario(
    text: &str,
    origin: &str,
    overrides: &[String],
) -> Result<Scenario, ScenarioError> {
    parse_scenario_in(text, origin, overrides, Path::new("."))
}

/// As [`parse_scenario`], with files relative to `base_dir`.
pub fn parse_scenario_in(
    text: &str,
    origin: &str,
    overrides: &[String],
    base_dir: &Path,
) -> Result<Scenario, ScenarioError> {
    let located = |span: Option<Range<usize>>, key: Option<String>, message: String| {
        let (line, column) = match &span {
            Some(s) => {
                let (l, c) = line_col(text, s.start);
                (Some(l), Some(c))
            }
            None => (None, None),
        };
        ScenarioError::Invalid(vec![LocatedIssue {
            location: ErrorLocation::File {
                path: origin.to_string(),
                line,
                column,
            },
            key,
            message,
            unreadable: false,
        }])
    };

    // 1. Syntax, with spans kept for locating keys later.
    let doc = DeTable::parse(text).map_err(|e| {
        let message = e.message().trim();
        let message = number_out_of_range(message).unwrap_or_else(|| message.to_string());
        located(e.span(), None, message)
    })?;
    // 2. Schema: unknown keys and wrong types, located by the error's span.
    if let Err(e) = toml::from_str::<ScenarioFile>(text) {
        let key = e.span().and_then(|s| key_at(doc.get_ref(), &s, ""));
        let kind = toml::from_str::<toml::Table>(text)
            .ok()
            .and_then(|t| controller_kind(&t));
        let message = did_you_mean(e.message().trim(), key.as_deref(), kind);
        return Err(located(e.span(), key, message));
    }
    // 3. Overrides, one at a time so that an error names its argument.
    let mut table: toml::Table = toml::from_str(text).map_err(|e| {
        // A u64 key (`sim.seed`) takes 2^63 in the schema, a TOML table does not: said as out
        // of range, at its key.
        let key = e.span().and_then(|s| key_at(doc.get_ref(), &s, ""));
        let message = e.message().trim();
        let message = number_out_of_range(message).unwrap_or_else(|| message.to_string());
        located(e.span(), key, message)
    })?;
    let mut set_keys: Vec<(String, String)> = Vec::new();
    for arg in overrides {
        let at = ErrorLocation::Override { arg: arg.clone() };
        let before = kinds_of(&table);
        let key = apply_one(&mut table, arg, at)?;
        let after = kinds_of(&table);
        for (section, _) in KINDED_SECTIONS
            .iter()
            .zip(before.iter().zip(&after))
            .filter(|(_, (b, a))| b != a)
        {
            // `--set controller.kind=...` switches controllers (and so for fields and
            // vehicles): the file's keys for the old kind go; later overrides are checked
            // against the new kind.
            drop_inapplicable_keys(&mut table, section);
            set_keys.retain(|(k, _)| !k.starts_with(&format!("{section}.")));
        }
        set_keys.push((key, arg.clone()));
    }
    let file: ScenarioFile = toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| located(None, None, e.message().to_string()))?;
    // 4. Defaults and values.
    Scenario::from_file(file, base_dir).map_err(|issues| {
        ScenarioError::Invalid(
            issues
                .into_iter()
                .map(|i| locate_issue(i, text, origin, doc.get_ref(), &set_keys))
                .collect(),
        )
    })
}

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

/// Resolves and builds a derived scenario file (files relative to `base_dir`); problems are
/// located at the assignment that set the key, else reported against `origin`.
pub fn build_derived(
    file: ScenarioFile,
    origin: &str,
    base_dir: &Path,
    assignments: &[Assignment],
) -> Result<Scenario, ScenarioError> {
    Scenario::from_file(file, base_dir)
        .map_err(|issues| locate_derived(issues, origin, assignments))
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

/// Whether an assignment to `set` is the source of a problem with `issue_key`: the same key,
/// a table holding it, or a key inside it.
fn key_covers(set: &str, issue_key: &str) -> bool {
    issue_key == set
        || issue_key.starts_with(&format!("{set}."))
        || issue_key.starts_with(&format!("{set}["))
        || set.starts_with(&format!("{issue_key}."))
}

/// Applies one `KEY=VALUE` to `table` and checks the schema still holds; returns the key.
/// Errors name the argument.
fn apply_one(
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
fn controller_kind(table: &toml::Table) -> Option<ControllerKind> {
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
fn did_you_mean(message: &str, key: Option<&str>, kind: Option<ControllerKind>) -> String {
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
fn kinds_of(table: &toml::Table) -> [Option<String>; KINDED_SECTIONS.len()] {
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
fn looks_like_a_number(raw: &str) -> bool {
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

fn locate_issue(
    issue: Issue,
    text: &str,
    origin: &str,
    doc: &DeTable<'_>,
    set_keys: &[(String, String)],
) -> LocatedIssue {
    // The latest override that set this key (or a table containing it, or a key inside it).
    let over = set_keys
        .iter()
        .rev()
        .find(|(k, _)| key_covers(k, &issue.key));
    let location = if let Some((_, arg)) = over {
        ErrorLocation::Override { arg: arg.clone() }
    } else if let Some(span) = span_of(doc, &issue.key) {
        let (l, c) = line_col(text, span.start);
        ErrorLocation::File {
            path: origin.to_string(),
            line: Some(l),
            column: Some(c),
        }
    } else {
        ErrorLocation::Default {
            origin: origin.to_string(),
        }
    };
    LocatedIssue {
        location,
        key: Some(issue.key),
        message: issue.message,
        unreadable: issue.unreadable,
    }
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The span of the value at a dotted key such as `field.sources[1].sigma_m`.
fn span_of(doc: &DeTable<'_>, key: &str) -> Option<Range<usize>> {
    let mut table = doc;
    let mut result = None;
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (*part, None),
        };
        let (_, v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == name)?;
        let mut v = v;
        if let Some(ix) = index {
            if let DeValue::Array(a) = v.get_ref() {
                v = a.get(ix)?;
            }
        }
        result = Some(v.span());
        if i + 1 < parts.len() {
            match v.get_ref() {
                DeValue::Table(t) => table = t,
                _ => return result,
            }
        }
    }
    result
}

/// The dotted key whose key or value contains `span` (for schema errors).
fn key_at(table: &DeTable<'_>, span: &Range<usize>, prefix: &str) -> Option<String> {
    for (k, v) in table.iter() {
        let name = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        let ks = k.span();
        let vs = v.span();
        let inside = |r: &Range<usize>| r.start <= span.start && span.end <= r.end.max(r.start + 1);
        if inside(&ks) {
            return Some(name);
        }
        if inside(&vs) {
            if let DeValue::Table(t) = v.get_ref() {
                return key_at(t, span, &name).or(Some(name));
            }
            return Some(name);
        }
        if let DeValue::Table(t) = v.get_ref() {
            // `[section]` headers: the table's span may not cover its keys.
            if let Some(found) = key_at(t, span, &name) {
                return Some(found);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str, sets: &[&str]) -> Vec<LocatedIssue> {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        match parse_scenario(text, "s.toml", &sets) {
            Err(ScenarioError::Invalid(v)) => v,
            other => panic!("expected an error, got {other:?}"),
        }
    }

    fn file_line(i: &LocatedIssue) -> Option<usize> {
        match &i.location {
            ErrorLocation::File { line, .. } => *line,
            _ => None,
        }
    }

    /// Issue 30 (att30b via fix30d), item 5: a number TOML cannot hold got serde's and the
    /// TOML reader's words, which said the wrong thing: `--set sim.seed=9223372036854775808`
    /// "invalid type: string ..., expected u64" (2^63 is a u64; TOML's integers stop at
    /// 2^63 - 1), `--set controller.kp=1e400` "invalid type: string", `seed =
    /// 9223372036854775808` in a file a bare "u64 value was too large". Each says the number
    /// does not fit and the range, naming the key or the argument; a version-like word
    /// (`1.2.3`) is still a string.
    #[test]
    fn numbers_out_of_range_are_said_plainly() {
        let int = "does not fit in a 64-bit integer (-9223372036854775808 ..= 9223372036854775807, TOML's integers)";
        let float = "is beyond the largest 64-bit float (about 1.8e308)";
        for (sets, want) in [
            (
                ["sim.seed=9223372036854775808"],
                format!("`9223372036854775808` {int}"),
            ),
            (
                ["controller.kp=99_999_999_999_999_999_999_999"],
                format!("`99_999_999_999_999_999_999_999` {int}"),
            ),
            (["controller.kp=-1e400"], format!("`-1e400` {float}")),
            (["controller.kp=1.5E+309"], format!("`1.5E+309` {float}")),
        ] {
            let e = err("", &sets);
            assert_eq!(e[0].message, want, "{}", e[0]);
            assert!(matches!(&e[0].location, ErrorLocation::Override { arg } if arg == sets[0]));
        }
        for (text, want) in [
            (
                "[sim]\nseed = 9223372036854775808\n",
                format!("the number {int}"),
            ),
            (
                "[sim]\nseed = 99999999999999999999999\n",
                format!("`99999999999999999999999` {int}"),
            ),
            ("[controller]\nkp = 1e400\n", format!("the number {float}")),
        ] {
            let e = err(text, &[]);
            assert_eq!(e[0].message, want, "{text}: {}", e[0]);
            assert_eq!(file_line(&e[0]), Some(2), "{text}");
        }
        // In range, and words that only look numeric-ish, are as before.
        assert!(parse_scenario("", "s.toml", &["sim.seed=9223372036854775807".into()]).is_ok());
        assert!(looks_like_a_number("1_000.5e-3") && looks_like_a_number("-7"));
        for word in [
            "1.2.3",
            "1e",
            "_1",
            "1_",
            "e5",
            "1.",
            ".5",
            "0x10",
            "inf",
            "2020-01-01",
        ] {
            assert!(!looks_like_a_number(word), "{word}");
        }
    }

    /// Issue 30 (att30c-14): `--set 'controller={kp=2.0}'` replaced the whole section, so the
    /// file's `ki = 0.0` and `c1 = 0.5` fell back to their defaults (1.0 and 0.2) without a word.
    /// A table value merges key by key, as the dotted key does; a kind switched by a table still
    /// drops the old kind's keys.
    #[test]
    fn a_table_value_merges_key_by_key() {
        let text = "[controller]\nki = 0.0\nc1 = 0.5\n[vehicle]\nspeed_mps = 0.8\n";
        let set = |arg: &str| {
            parse_scenario(text, "s.toml", &[arg.to_string()])
                .unwrap()
                .file()
                .clone()
        };
        let table = set("controller={kp=2.0}");
        assert_eq!(table.controller.kp, Some(2.0));
        assert_eq!(table.controller.ki, Some(0.0));
        assert_eq!(table.controller.c1, Some(0.5));
        assert_eq!(table, set("controller.kp=2.0"));
        // Nested: a table holding a table merges at every level.
        assert_eq!(set("vehicle={}").vehicle.speed_mps, Some(0.8));
        // Through `apply_assignments` too (a sweep's `[grid] controller = [{kp = 2.0}]`).
        let base = parse_scenario(text, "s.toml", &[]).unwrap();
        let applied = apply_assignments(
            base.file(),
            &[Assignment::new("controller={ kp = 2.0 }", "[grid]")],
        )
        .unwrap();
        assert_eq!(applied.controller.kp, Some(2.0));
        assert_eq!(applied.controller.c1, Some(0.5));
        assert_eq!(applied.controller.ki, Some(0.0));
        // A kind switched inside a table: the PI-like law's keys go, as with controller.kind.
        let pid = set("controller={kind=\"pid\", kp=3.0}");
        assert_eq!(pid.controller.kp, Some(3.0));
        assert_eq!(pid.controller.c1, None);
    }

    /// Issue 30 (att30c-16): one wording for a number out of range, at key and column, in a
    /// list as alone, and for a negative seed (serde's "expected u64" once).
    #[test]
    fn numbers_out_of_range_have_one_wording() {
        for arg in ["initial.x_m=[1e400]", "field.center_m=[0.0, 1e400]"] {
            let e = err("", &[arg]);
            assert!(
                e[0].message
                    .contains("the number is beyond the largest 64-bit float")
                    && !e[0].message.contains("quote a string"),
                "{arg}: {}",
                e[0]
            );
        }
        let e = err("", &["sim.seed=-1"]);
        assert!(
            e[0].message.contains(
                "`-1` is out of range: this key takes an integer 0 ..= 9223372036854775807"
            ),
            "{}",
            e[0]
        );
        let e = err("[sim]\nseed = -1\n", &[]);
        assert_eq!(file_line(&e[0]), Some(2));
        assert_eq!(e[0].key.as_deref(), Some("sim.seed"));
        assert!(
            e[0].message.contains("0 ..= 9223372036854775807"),
            "{}",
            e[0]
        );
        assert!(!e[0].message.contains("expected u64"), "{}", e[0]);
    }

    #[test]
    fn syntax_error_has_line() {
        let e = err("[controller]\nkp = = 3\n", &[]);
        assert_eq!(file_line(&e[0]), Some(2));
    }

    #[test]
    fn unknown_key_is_named_with_line() {
        let e = err("[sim]\ndt_s = 0.01\n\n[controller]\nkp = 1\nkz = 2\n", &[]);
        assert_eq!(file_line(&e[0]), Some(6));
        assert!(e[0].message.contains("kz"), "{}", e[0]);
        assert_eq!(e[0].key.as_deref(), Some("controller.kz"));
    }

    /// Hostile review of issue 30: an unknown key gets the nearest valid key of its section
    /// (the schema's list), in `[controller]` of the kind the scenario names.
    #[test]
    fn unknown_keys_get_a_did_you_mean() {
        let e = err("[sim]\ndt_sec = 0.01\n", &[]);
        assert!(e[0].message.ends_with("; did you mean `dt_s`?"), "{}", e[0]);
        assert!(e[0].message.contains("expected one of `dt_s`"), "{}", e[0]);
        // [controller]: the PI-like law's keys, not every law's (kd is the PID's).
        let e = err("[controller]\nkq = 2\n", &[]);
        assert!(
            e[0].message
                .contains("for controller.kind = \"pi_isoline\""),
            "{}",
            e[0]
        );
        assert!(
            e[0].message.ends_with("did you mean `kp` or `ki`?"),
            "{}",
            e[0]
        );
        assert!(!e[0].message.contains("`kd`"), "{}", e[0]);
        let e = err("[controller]\nkind = \"sliding_mode\"\ngama = 2\n", &[]);
        assert!(e[0].message.ends_with("did you mean `gamma`?"), "{}", e[0]);
        assert!(!e[0].message.contains("`kp`"), "{}", e[0]);
        // Through --set too, with the kind set before it.
        let e = err("", &["controller.kind=pid", "controller.kdd=1"]);
        assert!(e[0].message.ends_with("did you mean `kd`?"), "{}", e[0]);
        let e = err("", &["vehicle.speed=1"]);
        assert!(
            e[0].message.ends_with("did you mean `speed_mps`?"),
            "{}",
            e[0]
        );
        // Nothing near: no suggestion.
        let e = err("[sim]\nzzzzzz = 1\n", &[]);
        assert!(!e[0].message.contains("did you mean"), "{}", e[0]);
    }

    #[test]
    fn wrong_type_names_key() {
        let e = err("[controller]\nkp = \"ten\"\n", &[]);
        assert_eq!(file_line(&e[0]), Some(2));
        assert_eq!(e[0].key.as_deref(), Some("controller.kp"));
    }

    #[test]
    fn invalid_values_are_located() {
        let e = err("[controller]\nki = 0.5\nkp = -1\n[sim]\ndt_s = nan\n", &[]);
        let kp = e
            .iter()
            .find(|i| i.key.as_deref() == Some("controller.kp"))
            .unwrap();
        assert_eq!(file_line(kp), Some(3));
        let dt = e
            .iter()
            .find(|i| i.key.as_deref() == Some("sim.dt_s"))
            .unwrap();
        assert_eq!(file_line(dt), Some(5));
    }

    #[test]
    fn override_errors_name_the_argument() {
        let e = err("", &["controller.kp=0"]);
        assert_eq!(
            e[0].location,
            ErrorLocation::Override {
                arg: "controller.kp=0".into()
            }
        );
        let e = err("", &["controller.kz=1"]);
        assert!(e[0].message.contains("kz"));
        let e = err("", &["controller.kp"]);
        assert!(e[0].message.contains("KEY=VALUE"));
        // An empty part anywhere in the dotted key is refused before the table is touched.
        for arg in ["=1", "controller..kp=1", "controller.=1", ".kp=1", " . =1"] {
            let e = err("", &[arg]);
            assert_eq!(e.len(), 1, "{arg}");
            assert!(
                e[0].message.contains("expected a dotted key"),
                "{arg}: {}",
                e[0]
            );
            assert_eq!(e[0].key, None, "{arg}");
        }
    }

    #[test]
    fn overrides_apply_in_order_and_bare_words_are_strings() {
        let s = parse_scenario(
            "[controller]\nkp = 3\n",
            "s.toml",
            &[
                "controller.kp=20".into(),
                "vehicle.kind=dubins".into(),
                "controller.kp=25".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.file().controller.kp, Some(25.0));
    }

    #[test]
    fn dotted_keys_in_file_are_located() {
        let e = err("controller.kp = -3\n", &[]);
        assert_eq!(file_line(&e[0]), Some(1));
    }

    #[test]
    fn locations_display_as_documented() {
        let file = |line, column| ErrorLocation::File {
            path: "s.toml".into(),
            line,
            column,
        };
        assert_eq!(file(Some(3), Some(6)).to_string(), "s.toml:3:6");
        assert_eq!(file(Some(3), None).to_string(), "s.toml:3");
        assert_eq!(file(None, None).to_string(), "s.toml");
        let arg = "controller.kp=0".to_string();
        assert_eq!(
            ErrorLocation::Override { arg }.to_string(),
            "--set controller.kp=0"
        );
        let origin = "s.toml".to_string();
        assert_eq!(
            ErrorLocation::Default { origin }.to_string(),
            "s.toml (default value)"
        );
        let label = "sweep s.toml run 3, [grid] controller.kp=0".to_string();
        assert_eq!(
            ErrorLocation::Assigned {
                label: label.clone()
            }
            .to_string(),
            label
        );
        let origin = "sweep s.toml run 3".to_string();
        assert_eq!(
            ErrorLocation::Inherited { origin }.to_string(),
            "sweep s.toml run 3 (a value of the base scenario or its default)"
        );
        let issue = |key: Option<&str>| LocatedIssue {
            location: file(Some(2), Some(1)),
            key: key.map(str::to_string),
            message: "must be > 0, got 0".into(),
            unreadable: false,
        };
        assert_eq!(
            issue(Some("controller.kp")).to_string(),
            "s.toml:2:1: `controller.kp`: must be > 0, got 0"
        );
        assert_eq!(issue(None).to_string(), "s.toml:2:1: must be > 0, got 0");
    }

    /// User text is echoed up to MAX_ECHO_CHARS characters; backtick-quoted spans are clipped
    /// each, and a whole message at five times that.
    #[test]
    fn echoes_are_clipped() {
        let at_limit = "é".repeat(MAX_ECHO_CHARS);
        assert_eq!(clip(&at_limit), at_limit);
        let over = "é".repeat(MAX_ECHO_CHARS + 7);
        assert_eq!(clip(&over), format!("{at_limit}... (7 more characters)"));
        let quoted = format!("unknown key `{over}` here");
        assert_eq!(
            clip_quoted(&quoted),
            format!("unknown key `{at_limit}... (7 more characters)` here")
        );
        assert_eq!(clip("a\u{1b}[2Jb\u{202e}"), "a\\x1b[2Jb\\u{202e}");
        let plain = "x".repeat(5 * MAX_ECHO_CHARS);
        assert_eq!(clip_quoted(&plain), plain);
        let long = "x".repeat(5 * MAX_ECHO_CHARS + 1);
        assert_eq!(clip_quoted(&long), format!("{plain}..."));
    }

    #[test]
    fn an_assignment_covers_its_key_its_table_and_the_keys_inside() {
        assert!(key_covers("controller.kp", "controller.kp"));
        assert!(key_covers("controller", "controller.kp"));
        assert!(key_covers("field.sources", "field.sources[1].sigma_m"));
        assert!(key_covers("controller.kp.x", "controller.kp"));
        assert!(!key_covers("controller.k", "controller.kp"));
        // A problem with a whole table is placed at an assignment inside it.
        assert!(key_covers("controller.kp", "controller"));
        assert!(!key_covers("controller.kpx", "controller.kp"));
        assert!(!key_covers("sim", "sensor.rate_hz"));
    }

    #[test]
    fn line_and_column_count_characters() {
        let text = "a = 1\n# é é\nkp = 2\n";
        assert_eq!(line_col(text, 0), (1, 1));
        let kp = text.find("kp").unwrap();
        assert_eq!(line_col(text, kp), (3, 1));
        let second = text.rfind('é').unwrap();
        // "# é " before it: 4 characters (6 bytes).
        assert_eq!(line_col(text, second), (2, 5));
        assert_eq!(line_col(text, 10_000), (4, 1));
    }

    /// A problem is placed at the `--set` that set its key (or its table), else at its line in
    /// the file, else at the defaults; a nested array element is found by its index.
    #[test]
    fn problems_are_placed_at_their_source() {
        let e = err("", &["controller={ kp = 0.0 }"]);
        assert_eq!(
            e[0].location,
            ErrorLocation::Override {
                arg: "controller={ kp = 0.0 }".into()
            }
        );
        let text = "[field]\nkind = \"gaussian_plumes\"\n\n[[field.sources]]\ncenter_m = [0.0, 0.0]\namplitude = 1.0\nsigma_m = [1.0, 1.0]\nrotation_rad = 0.0\n\n[[field.sources]]\ncenter_m = [0.0, 0.0]\namplitude = 1.0\nsigma_m = [1.0, 0.0]\nrotation_rad = 0.0\n";
        let e = err(text, &[]);
        assert_eq!(e[0].key.as_deref(), Some("field.sources[1].sigma_m"));
        assert_eq!(file_line(&e[0]), Some(13));
        // record_rate_hz's default (10 Hz) is not a whole number of 0.03 s steps: the
        // defaults are at fault.
        let e = err("[sim]\ndt_s = 0.03\n", &[]);
        assert_eq!(e[0].key.as_deref(), Some("output.record_rate_hz"));
        assert_eq!(
            e[0].location,
            ErrorLocation::Default {
                origin: "s.toml".into()
            }
        );
    }

    /// `--set controller.kind=...` switches laws: the file's keys for the old law are dropped,
    /// and later overrides are checked against the new one.
    #[test]
    fn switching_the_controller_drops_the_old_laws_keys() {
        let pid = "[controller]\nkind = \"pid\"\nkd = 5.0\n";
        let s = parse_scenario(pid, "s.toml", &["controller.kind=pi_isoline".into()]).unwrap();
        assert_eq!(s.file().controller.kd, None);
        assert_eq!(s.file().controller.kp, Some(10.0));
        let sets = [
            "controller.kp=2".into(),
            "controller.kind=sliding_mode".into(),
        ];
        let s = parse_scenario("", "s.toml", &sets).unwrap();
        assert_eq!(s.file().controller.kp, None);
        let e = err("", &["controller.kind=sliding_mode", "controller.kp=2"]);
        assert_eq!(e[0].key.as_deref(), Some("controller.kp"));
        assert_eq!(
            e[0].location,
            ErrorLocation::Override {
                arg: "controller.kp=2".into()
            }
        );
    }

    /// A sweep across kinds: each derived run drops the resolved keys of the old kind (the
    /// Dubins robot's speed, the radial field's peak) and takes the new kind's defaults.
    #[test]
    fn derived_scenarios_switch_kinds() {
        let base = parse_scenario("", "s.toml", &[]).unwrap();
        let s = base
            .derive(&["vehicle.kind=fixed_wing".into()], "run 1")
            .unwrap();
        assert_eq!(s.file().vehicle.speed_mps, None);
        assert_eq!(s.file().vehicle.airspeed_mps, Some(30.0));
        let s = base
            .derive(&["field.kind=linear_ramp".into()], "run 2")
            .unwrap();
        assert_eq!(s.file().field.i0, None);
        assert_eq!(s.file().field.gradient_per_m, Some([0.0, 1.0]));
        let s = base
            .derive(&["controller.kind=pid".into()], "run 3")
            .unwrap();
        assert_eq!(
            (s.file().controller.c1, s.file().controller.kd),
            (None, Some(10.0))
        );
        // And with `--set` on a file: the file's keys of the old kind go.
        let s = parse_scenario(
            "[vehicle]\nspeed_mps = 2.0\n",
            "s.toml",
            &["vehicle.kind=fixed_wing".into()],
        )
        .unwrap();
        assert_eq!(s.file().vehicle.speed_mps, None);
        // Keys every kind shares stay.
        let s = parse_scenario(
            "[field]\nunits = \"ppm\"\n",
            "s.toml",
            &["field.kind=linear_ramp".into()],
        )
        .unwrap();
        assert_eq!(s.file().field.units.as_deref(), Some("ppm"));
    }

    /// A derived scenario's problem is placed at the assignment that set the key, else said to
    /// be inherited.
    #[test]
    fn derived_problems_name_the_assignment_or_the_base() {
        let base = parse_scenario("[sim]\ndt_s = 0.05\n", "s.toml", &[]).unwrap();
        let e = base
            .derive(&["controller.kp=0".into()], "sweep s.toml run 3")
            .unwrap_err();
        assert_eq!(
            e.issues()[0].location.to_string(),
            "sweep s.toml run 3: controller.kp=0"
        );
        // The fixed-wing UAV needs dt <= 0.02 s: the base's 0.05 s is at fault, not the kind.
        let e = base
            .derive(&["vehicle.kind=fixed_wing".into()], "sweep s.toml run 3")
            .unwrap_err();
        assert_eq!(e.issues()[0].key.as_deref(), Some("sim.dt_s"));
        assert_eq!(
            e.issues()[0].location,
            ErrorLocation::Inherited {
                origin: "sweep s.toml run 3".into()
            }
        );
    }

    /// A 60 000-part `--set` key overflowed the stack (issue 30): refused before it is walked,
    /// in a file's overrides and in a derived scenario alike; eight parts is still a key.
    #[test]
    fn keys_with_too_many_parts_are_refused() {
        let long = format!("{}=1", vec!["a"; 60_000].join("."));
        let e = err("", &[long.as_str()]);
        assert!(
            e[0].message
                .contains("a key has at most 8 dotted parts, this one has 60000"),
            "{}",
            e[0]
        );
        let base = parse_scenario("", "s.toml", &[]).unwrap();
        let e = base.derive(&[long], "x").unwrap_err();
        assert!(e.to_string().contains("at most 8 dotted parts"), "{e}");
        let eight = format!("controller.{}=1", ["a"; 7].join("."));
        let e = err("", &[eight.as_str()]);
        assert!(e[0].message.contains("unknown field"), "{}", e[0]);
    }
}
