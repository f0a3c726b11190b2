//! Reading scenario files and `--set` overrides, with errors that say where.

use crate::resolve::Issue;
use crate::schema::ScenarioFile;
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
}

impl fmt::Display for LocatedIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.key {
            Some(k) => write!(f, "{}: `{k}`: {}", self.location, self.message),
            None => write!(f, "{}: {}", self.location, self.message),
        }
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
    /// The located problems (empty for I/O errors).
    pub fn issues(&self) -> &[LocatedIssue] {
        match self {
            ScenarioError::Invalid(v) => v,
            ScenarioError::Io { .. } => &[],
        }
    }
}

/// Loads a scenario file (or the built-in default when `path` is `None`), applies the `--set`
/// overrides in order, fills defaults and validates.
pub fn load_scenario(path: Option<&Path>, overrides: &[String]) -> Result<Scenario, ScenarioError> {
    match path {
        None => parse_scenario_in("", "<built-in default>", overrides, Path::new(".")),
        Some(p) => {
            let shown = p.display().to_string();
            let text = std::fs::read_to_string(p).map_err(|source| ScenarioError::Io {
                path: shown.clone(),
                source,
            })?;
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
        }])
    };

    // 1. Syntax, with spans kept for locating keys later.
    let doc = DeTable::parse(text)
        .map_err(|e| located(e.span(), None, e.message().trim().to_string()))?;
    // 2. Schema: unknown keys and wrong types, located by the error's span.
    if let Err(e) = toml::from_str::<ScenarioFile>(text) {
        let key = e.span().and_then(|s| key_at(doc.get_ref(), &s, ""));
        return Err(located(e.span(), key, e.message().trim().to_string()));
    }
    // 3. Overrides, one at a time so that an error names its argument.
    let mut table: toml::Table =
        toml::from_str(text).map_err(|e| located(e.span(), None, e.message().to_string()))?;
    let mut set_keys: Vec<(String, String)> = Vec::new();
    for arg in overrides {
        let key = apply_one(&mut table, arg)?;
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

/// Applies `KEY=VALUE` overrides to a (typically resolved) scenario file; errors name the
/// argument. Used to derive variants of a scenario (e.g. one per controller in `compare`).
pub fn apply_overrides(
    file: &ScenarioFile,
    overrides: &[String],
) -> Result<ScenarioFile, ScenarioError> {
    let mut table = match toml::Value::try_from(file) {
        Ok(toml::Value::Table(t)) => t,
        _ => toml::Table::new(),
    };
    for arg in overrides {
        apply_one(&mut table, arg)?;
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
            }])
        })
}

/// Resolves and builds a derived scenario file (files relative to `base_dir`); problems are
/// reported against `origin`.
pub fn build_derived(
    file: ScenarioFile,
    origin: &str,
    base_dir: &Path,
) -> Result<Scenario, ScenarioError> {
    Scenario::from_file(file, base_dir).map_err(|issues| {
        ScenarioError::Invalid(
            issues
                .into_iter()
                .map(|i| LocatedIssue {
                    location: ErrorLocation::Default {
                        origin: origin.to_string(),
                    },
                    key: Some(i.key),
                    message: i.message,
                })
                .collect(),
        )
    })
}

/// Applies one `KEY=VALUE` to `table` and checks the schema still holds; returns the key.
/// Errors name the argument.
fn apply_one(table: &mut toml::Table, arg: &str) -> Result<String, ScenarioError> {
    let fail = |key: Option<String>, message: String| {
        ScenarioError::Invalid(vec![LocatedIssue {
            location: ErrorLocation::Override {
                arg: arg.to_string(),
            },
            key,
            message,
        }])
    };
    let (key, raw) = arg
        .split_once('=')
        .ok_or_else(|| fail(None, "expected KEY=VALUE".into()))?;
    let key = key.trim().to_string();
    if key.is_empty() || key.split('.').any(|p| p.trim().is_empty()) {
        return Err(fail(
            None,
            "expected a dotted key such as controller.kp".into(),
        ));
    }
    insert_dotted(table, &key, parse_override_value(raw.trim()))
        .map_err(|m| fail(Some(key.clone()), m))?;
    toml::Value::Table(table.clone())
        .try_into::<ScenarioFile>()
        .map_err(|e| fail(Some(key.clone()), e.message().trim().to_string()))?;
    Ok(key)
}

/// `VALUE` as a TOML value; a bare word that is not TOML (`dubins`) is taken as a string.
fn parse_override_value(raw: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
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
    t.insert(last.to_string(), value);
    Ok(())
}

fn locate_issue(
    issue: Issue,
    text: &str,
    origin: &str,
    doc: &DeTable<'_>,
    set_keys: &[(String, String)],
) -> LocatedIssue {
    // The latest override that set this key (or a table containing it, or a key inside it).
    let over = set_keys.iter().rev().find(|(k, _)| {
        issue.key == *k
            || issue.key.starts_with(&format!("{k}."))
            || issue.key.starts_with(&format!("{k}["))
            || k.starts_with(&format!("{}.", issue.key))
    });
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
}
