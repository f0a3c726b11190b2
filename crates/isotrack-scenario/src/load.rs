//! Reading scenario files and `--set` overrides, with errors that say where: text to a
//! [`Scenario`]. The errors are [`crate::error`]'s, the overrides [`crate::assign`]'s.

use crate::assign::{
    apply_one, controller_kind, did_you_mean, key_covers, kinds_of, locate_derived,
    number_out_of_range, Assignment,
};
use crate::error::{ErrorLocation, LocatedIssue, ScenarioError};
use crate::resolve::{drop_inapplicable_keys, Issue, KINDED_SECTIONS};
use crate::schema::ScenarioFile;
use crate::Scenario;
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};

/// The largest scenario (or sweep) file read, bytes (1 MiB: the longest bundled one is 2 kB).
pub const MAX_SCENARIO_FILE_BYTES: u64 = 1 << 20;

// Kept at the paths the other crates name them by (`isotrack_scenario::load::clip`, ...).
pub use crate::assign::{closest_names, MAX_KEY_PARTS};
pub use crate::error::{clip, MAX_ECHO_CHARS};

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
        located_in(text, origin, span, key, message)
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
    let set_keys = apply_overrides(&mut table, overrides)?;
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

/// An error in `text` (read from `origin`) at the byte `span` (its line and column; none without
/// a span), on `key` if known.
fn located_in(
    text: &str,
    origin: &str,
    span: Option<Range<usize>>,
    key: Option<String>,
    message: String,
) -> ScenarioError {
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
}

/// Applies the `--set` overrides to `table` one at a time, so that an error names its argument.
/// Returns the keys set with the argument that set each (for locating later problems); a
/// `--set` that switches a section's kind drops the file's keys for the old kind, and the
/// earlier overrides into that section with them.
fn apply_overrides(
    table: &mut toml::Table,
    overrides: &[String],
) -> Result<Vec<(String, String)>, ScenarioError> {
    let mut set_keys: Vec<(String, String)> = Vec::new();
    for arg in overrides {
        let at = ErrorLocation::Override { arg: arg.clone() };
        let before = kinds_of(table);
        let key = apply_one(table, arg, at)?;
        let after = kinds_of(table);
        for (section, _) in KINDED_SECTIONS
            .iter()
            .zip(before.iter().zip(&after))
            .filter(|(_, (b, a))| b != a)
        {
            // `--set controller.kind=...` switches controllers (and so for fields and
            // vehicles): the file's keys for the old kind go; later overrides are checked
            // against the new kind.
            drop_inapplicable_keys(table, section);
            set_keys.retain(|(k, _)| !k.starts_with(&format!("{section}.")));
        }
        set_keys.push((key, arg.clone()));
    }
    Ok(set_keys)
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
    use crate::assign::looks_like_a_number;
    use crate::error::clip_quoted;

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
        let applied = crate::apply_assignments(
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
