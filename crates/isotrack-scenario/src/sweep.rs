//! Sweep files: many runs of one scenario.
//!
//! ```toml
//! scenario = "../scenarios/paper-fig2b-circular.toml"   # relative to the sweep file
//!
//! [base]                      # fixed overrides for every run (dotted keys)
//! sim.duration_s = 300.0
//!
//! [grid]                      # the product of these lists
//! controller.kp = [5.0, 10.0, 20.0]
//! controller.ki = [0.0, 1.0]
//!
//! [random]                    # `runs` draws per grid point
//! runs = 10
//! seed = 42
//! initial.x_m = { uniform = [-15.0, 15.0] }
//! sensor.noise_std = { normal = [0.02, 0.005] }
//! ```
//!
//! Runs = grid product x random runs. Run `id = grid_index * runs + draw` (grid keys in sorted
//! order, the last key varying fastest). Draw `r` of grid point `g` takes its values from a
//! ChaCha8 stream seeded by `seed` on stream `id`: a pure function of the seed and the run's
//! index, whatever the thread count or shard.

use crate::{Assignment, ScenarioError};
use isotrack_core::numtext::{is_not_plain, Escaped, Num};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};

/// A distribution for a `[random]` key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dist {
    /// Uniform on `[a, b)`.
    Uniform(f64, f64),
    /// Normal with mean and standard deviation.
    Normal(f64, f64),
}

impl Dist {
    /// One draw from `rng`: uniform `a + (b - a) u` with `u` uniform on `[0, 1)` (one `f64`
    /// from the stream), normal `m + s n` with `n` standard normal (`rand_distr`'s ziggurat).
    /// The one sampler of sweeps' `[random]` keys and benchmark suites' `vary` keys: a value
    /// depends only on the stream and the order of the draws.
    pub fn sample(self, rng: &mut ChaCha8Rng) -> f64 {
        match self {
            Dist::Uniform(a, b) => {
                let u: f64 = rand::RngExt::random(rng);
                a + (b - a) * u
            }
            Dist::Normal(m, s) => {
                let n: f64 = StandardNormal.sample(rng);
                m + s * n
            }
        }
    }
}

impl Dist {
    /// Whether every draw is a finite number: a uniform's `a`, `b` and width `b - a` finite
    /// with `a < b` (`[-1e308, 1e308]` has a width of `inf`, so `a + (b - a) u` is `inf` for
    /// every draw), a normal's mean and std finite with std >= 0 and `mean +- 40 std` finite
    /// (the ziggurat's draws stay far inside 40 standard deviations: P(|n| > 40) < 1e-348).
    /// `Err` says what is wrong, in words.
    pub fn check(self) -> Result<(), String> {
        match self {
            Dist::Uniform(a, b) if !(a.is_finite() && b.is_finite() && a < b) => {
                Err("expected { uniform = [a, b] } with finite a < b".into())
            }
            Dist::Normal(m, s) if !(m.is_finite() && s.is_finite() && s >= 0.0) => {
                Err("expected { normal = [mean, std] } with finite mean and std >= 0".into())
            }
            _ => self.check_draws_finite(),
        }
    }

    /// The part of [`Dist::check`] that keeps every draw finite, for parameters already known
    /// finite (a benchmark suite's `vary`, whose own rule allows a uniform with `a = b`): a
    /// uniform's width `b - a` finite, a normal's `mean +- 40 std` finite. `Err` says which
    /// bound overflows, in words.
    pub fn check_draws_finite(self) -> Result<(), String> {
        match self {
            Dist::Uniform(a, b) if !(b - a).is_finite() => Err(format!(
                "{{ uniform = [{}, {}] }} is wider than the largest 64-bit float (about 1.8e308): every draw would be inf",
                Num(a),
                Num(b)
            )),
            Dist::Normal(m, s) if !((m + 40.0 * s).is_finite() && (m - 40.0 * s).is_finite()) => {
                Err(format!(
                    "{{ normal = [{}, {}] }} reaches beyond the largest 64-bit float (about 1.8e308) within 40 std: some draws would be inf",
                    Num(m),
                    Num(s)
                ))
            }
            _ => Ok(()),
        }
    }
}

/// A parsed sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPlan {
    /// The base scenario file (absolute or relative to the working directory).
    pub scenario: PathBuf,
    /// The sweep file's directory: a relative file path in `[base]`, `[grid]` or `[random]`
    /// (`field.path`, `field.paths`) is relative to it, as `scenario` is.
    pub dir: PathBuf,
    /// Fixed overrides, `KEY=VALUE`.
    pub base: Vec<String>,
    /// Grid keys and their values (TOML literals), keys sorted.
    pub grid: Vec<(String, Vec<toml::Value>)>,
    /// Draws per grid point (1 without `[random]`).
    pub draws: u64,
    /// Seed of the random draws.
    pub seed: u64,
    /// Random keys, sorted.
    pub random: Vec<(String, Dist)>,
    /// Runs: the grid product times `draws`, at most [`MAX_RUNS`].
    total: u64,
    /// Whether each run gets its own `sim.seed` (no `sim.seed` in `[base]`, `[grid]` or
    /// `[random]`), see [`derived_seed`].
    pub derives_seed: bool,
}

/// The `sim.seed` of run `id` of a sweep that does not set `sim.seed` itself:
/// SplitMix64 (Steele, Lea & Flood 2014) of the sweep's `random.seed` and the run id, kept to
/// 63 bits (TOML integers are signed). Distinct runs get distinct noise and gusts, and a run's
/// seed does not depend on the thread count or shard.
pub fn derived_seed(sweep_seed: u64, id: u64) -> u64 {
    // SplitMix64's finaliser, written out: it is a few lines, and a crate for it would add a
    // dependency for one function.
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    mix(sweep_seed.wrapping_add(mix(id.wrapping_add(0x9E37_79B9_7F4A_7C15)))) >> 1
}

/// The most runs a sweep may hold: 1e9 rows of `results.csv` are about 200 GB already.
pub const MAX_RUNS: u64 = 1_000_000_000;

/// A sweep-file problem, naming the file and key.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct SweepError {
    /// The sweep file.
    pub path: String,
    /// What is wrong.
    pub message: String,
}

fn flatten(
    prefix: &str,
    v: &toml::Value,
    stop: &dyn Fn(&toml::Value) -> bool,
    out: &mut Vec<(String, toml::Value)>,
) {
    match v {
        toml::Value::Table(t) if !stop(v) => {
            for (k, x) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, x, stop, out);
            }
        }
        _ => out.push((prefix.to_string(), v.clone())),
    }
}

/// The common length of a `[grid]` list whose values are all arrays of numbers (`None` for a
/// list of scalars).
fn array_len(list: &[toml::Value]) -> Option<usize> {
    let first = list.first()?.as_array()?.len();
    list.iter()
        .all(|v| v.as_array().is_some_and(|a| a.len() == first))
        .then_some(first)
}

/// A TOML value as a CSV cell: strings unquoted, numbers as TOML writes them.
fn cell(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => crate::tomltext::value_text(other),
    }
}

/// A TOML value as an override `VALUE` (round-trips through `--set` parsing): a string as a
/// TOML basic string on one line ([`basic_string`]), an array's strings too, anything else as
/// [`crate::tomltext::value_text`] writes it.
pub fn value_literal(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => basic_string(s),
        toml::Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(value_literal).collect();
            format!("[{}]", parts.join(", "))
        }
        other => crate::tomltext::value_text(other),
    }
}

/// `s` as a TOML basic string on one line: `"` and `\` escaped, the controls TOML refuses
/// in a basic string (U+0000-U+001F but the tab, and U+007F) escaped as `\b`, `\n`, `\f`,
/// `\r` or `\uXXXX`, the tab as `\t`; every other character as it is (TOML takes any other
/// Unicode character in a basic string). Rust's `{:?}` wrote `\u{301}` for a combining accent
/// (a macOS NFD file name `café.csv`) and `\u{200b}`, `\u{2028}`, `\u{85}`, `\u{b}`,
/// `\0` for others: no TOML escapes, so a sweep refused such a `[grid]` value with a TOML
/// error about the user's quoting (att38-6).
pub fn basic_string(s: &str) -> String {
    use std::fmt::Write;
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\t' => out.push_str("\\t"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            c if c < ' ' || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The 1-based line of sweep text `text` that sets flattened key `key` (`initial.x_m`,
/// written whole or as its last segment under a table header), if one is found.
fn line_of(text: &str, key: &str) -> Option<usize> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let sets = |line: &str, k: &str| {
        line.trim_start()
            .strip_prefix(k)
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    };
    let lines: Vec<&str> = text.lines().collect();
    lines
        .iter()
        .position(|l| sets(l, key))
        .or_else(|| lines.iter().position(|l| sets(l, last)))
        .map(|i| i + 1)
}

/// One key a sweep file sets: its section, its parts as written (a quoted part may hold a
/// dot or a space), and the 1-based line of its last part.
struct SetKey {
    section: &'static str,
    parts: Vec<String>,
    line: usize,
}

impl SetKey {
    /// The key as a scenario reads it: every part split at its dots and trimmed (what
    /// `--set` does with `controller. kp`).
    fn path(&self) -> Vec<&str> {
        self.parts
            .iter()
            .flat_map(|p| p.split('.'))
            .map(str::trim)
            .collect()
    }

    /// The key as written, quoted parts in quotes, each character a terminal would act on
    /// escaped: `"controller.kp\x0a"`.
    fn written(&self) -> String {
        let bare = |p: &str| {
            !p.is_empty()
                && p.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        };
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|p| {
                if bare(p) {
                    p.clone()
                } else {
                    format!("\"{}\"", Escaped(p))
                }
            })
            .collect();
        format!("[{}] {}", self.section, parts.join("."))
    }
}

/// Every key sweep text sets in `[base]`, `[grid]` and `[random]` (a distribution table is
/// one key; `random.runs` and `random.seed` are not keys of the scenario), from the TOML
/// reader's spans. Empty when the text does not parse (the caller reports that).
fn set_keys(text: &str) -> Vec<SetKey> {
    fn walk(
        text: &str,
        section: &'static str,
        table: &DeTable<'_>,
        parts: &mut Vec<String>,
        out: &mut Vec<SetKey>,
    ) {
        for (k, v) in table.iter() {
            let name = k.get_ref().to_string();
            if section == "random" && parts.is_empty() && (name == "runs" || name == "seed") {
                continue;
            }
            parts.push(name);
            match v.get_ref() {
                DeValue::Table(t)
                    if !(section == "random"
                        && t.iter().any(|(n, _)| {
                            n.get_ref().as_ref() == "uniform" || n.get_ref().as_ref() == "normal"
                        })) =>
                {
                    walk(text, section, t, parts, out)
                }
                _ => out.push(SetKey {
                    section,
                    parts: parts.clone(),
                    line: text[..k.span().start.min(text.len())].matches('\n').count() + 1,
                }),
            }
            parts.pop();
        }
    }
    let Ok(doc) = DeTable::parse(text) else {
        return vec![];
    };
    let mut out = vec![];
    for section in ["base", "grid", "random"] {
        let found = doc
            .get_ref()
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == section);
        if let Some((_, v)) = found {
            if let DeValue::Table(t) = v.get_ref() {
                walk(text, section, t, &mut vec![], &mut out);
            }
        }
    }
    out
}

/// Issue 30 (att30c-13): a key set twice in two spellings (`controller.kp` and
/// `"controller.kp"`, or `"controller. kp"`, are distinct TOML keys but one scenario key, and
/// the last one written ran while `results.csv` had a column for each), or in two sections
/// (`[base]` and `[grid]`), or a key and a table holding it; and a key part TOML quotes that a
/// scenario key never holds: a dot, a space, a control or invisible character (a line feed
/// in a key once made the sweep refuse its own `results.csv` after every run), or nothing.
/// Refused naming the lines, before any run.
fn check_set_keys(text: &str) -> Result<(), String> {
    let keys = set_keys(text);
    // Sorted by path, a key and any key it is a prefix of are neighbours (every path between
    // them starts with it too): n log n, not a comparison of every pair.
    let mut sorted: Vec<(Vec<&str>, usize)> = keys
        .iter()
        .enumerate()
        .map(|(i, k)| (k.path(), i))
        .collect();
    sorted.sort();
    for w in sorted.windows(2) {
        let ((pa, ia), (pb, ib)) = (&w[0], &w[1]);
        if pb.starts_with(pa) {
            let (a, b) = (&keys[*ia.min(ib)], &keys[*ia.max(ib)]);
            let how = if pa.len() == pb.len() {
                "set the same key"
            } else {
                "set one key twice (one is a table holding the other)"
            };
            return Err(format!(
                "line {}: {} and line {}: {} {how}: keep one",
                a.line,
                a.written(),
                b.line,
                b.written()
            ));
        }
    }
    for k in &keys {
        for p in &k.parts {
            let problem = if p.trim().is_empty() {
                "an empty part".to_string()
            } else if let Some(c) = p.chars().find(|&c| is_not_plain(c)) {
                format!("a control or invisible character (U+{:04X})", c as u32)
            } else if p.contains('.') {
                "a dot inside quotes".to_string()
            } else if p.chars().any(char::is_whitespace) {
                "a space".to_string()
            } else {
                continue;
            };
            return Err(format!(
                "line {}: {}: the key holds {problem}: write a scenario key plainly, as dotted parts (controller.kp)",
                k.line,
                k.written()
            ));
        }
    }
    Ok(())
}

/// The dotted key set on the line of sweep text starting at byte `start`, under its last
/// `[section]` header (`grid.controller.kp`), for a message about a value TOML cannot read
/// (the text does not parse, so no reader's spans are at hand). `None` for a line without
/// `KEY =`.
fn key_on_line(text: &str, start: usize) -> Option<String> {
    let line = text[start..].lines().next()?;
    let key = line.split_once('=')?.0.trim();
    if key.is_empty() || key.starts_with('[') {
        return None;
    }
    let section = text[..start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('[') && !l.starts_with("[["))
        .map(|l| l.trim_matches(['[', ']']).trim().to_string());
    Some(match section {
        Some(s) => format!("{s}.{key}"),
        None => key.to_string(),
    })
}

/// Sweep-file text as a TOML table; a number out of range in the TOML reader's words (`u64
/// value was too large`, with no place) is said plainly, where it is.
fn sweep_table(text: &str) -> Result<toml::Table, String> {
    toml::from_str(text).map_err(|e: toml::de::Error| {
        match crate::assign::number_out_of_range(e.message()) {
            Some(plain) => {
                // At line, column and key, as a scenario file's message (att30c-16).
                let at = e.span().map(|s| {
                    let before = &text[..s.start.min(text.len())];
                    let line = before.matches('\n').count() + 1;
                    let start = before.rfind('\n').map_or(0, |i| i + 1);
                    let column = before[start..].chars().count() + 1;
                    let key = key_on_line(text, start)
                        .map(|k| format!("`{}`: ", Escaped(&k)))
                        .unwrap_or_default();
                    format!("line {line}, column {column}: {key}")
                });
                format!("{}{plain}", at.unwrap_or_default())
            }
            None => e.to_string(),
        }
    })
}

/// The `[base]` table as `KEY=VALUE` overrides, in the table's order.
fn base_overrides(b: &toml::Value) -> Vec<String> {
    let mut flat = vec![];
    flatten("", b, &|_| false, &mut flat);
    flat.into_iter()
        .map(|(k, v)| format!("{k}={}", value_literal(&v)))
        .collect()
}

/// The `[grid]` table's keys and their lists, keys sorted: each a non-empty list, of arrays
/// only if of arrays of one length.
fn grid_lists(g: &toml::Value) -> Result<Vec<(String, Vec<toml::Value>)>, String> {
    let mut flat = vec![];
    flatten("", g, &|_| false, &mut flat);
    let mut grid = vec![];
    for (k, v) in flat {
        let list = v
            .as_array()
            .filter(|a| !a.is_empty())
            .ok_or_else(|| format!("grid.{k}: must be a non-empty list of values"))?;
        let arrays = list.iter().filter(|v| v.is_array()).count();
        if arrays > 0 && array_len(list).is_none() {
            return Err(format!(
                "grid.{k}: a list of arrays needs arrays of one length, and nothing else"
            ));
        }
        grid.push((k, list.clone()));
    }
    grid.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(grid)
}

/// The `[random]` table (of sweep text `text`, for line numbers): its `runs` (required, >= 1),
/// its `seed` (default 0) and its distributions, keys sorted.
fn random_section(r: &toml::Value, text: &str) -> Result<RandomSection, String> {
    let t = r
        .as_table()
        .ok_or_else(|| "`random` must be a table".to_string())?;
    let draws = random_integer(t, "runs", 1)?.ok_or("random.runs is required")?;
    let seed = random_integer(t, "seed", 0)?.unwrap_or(0);
    let is_dist = |v: &toml::Value| {
        v.as_table()
            .is_some_and(|t| t.contains_key("uniform") || t.contains_key("normal"))
    };
    let mut flat = vec![];
    for (k, v) in t.iter().filter(|(k, _)| *k != "runs" && *k != "seed") {
        flatten(k, v, &is_dist, &mut flat);
    }
    let mut random = vec![];
    for (k, v) in flat {
        let d = distribution(&k, &v, text)?;
        random.push((k, d));
    }
    random.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(RandomSection {
        draws,
        seed,
        random,
    })
}

/// The `[random]` table read: the draws per grid point, the seed and the distributions.
struct RandomSection {
    draws: u64,
    seed: u64,
    random: Vec<(String, Dist)>,
}

/// `random.NAME` of table `t` as an integer `>= min` (`None` when absent).
fn random_integer(t: &toml::Table, name: &str, min: i64) -> Result<Option<u64>, String> {
    t.get(name)
        .map(|v| {
            v.as_integer()
                .filter(|n| *n >= min)
                .map(|n| n as u64)
                .ok_or_else(|| format!("random.{name} must be an integer >= {min}"))
        })
        .transpose()
}

/// The distribution of `[random]` key `k` (value `v`, in sweep text `text`), checked
/// ([`Dist::check`]).
fn distribution(k: &str, v: &toml::Value, text: &str) -> Result<Dist, String> {
    // One distribution per key, and nothing beside it: `{ uniform = [1, 2], log = true }` once
    // ran a plain uniform, silently.
    let names: Vec<&str> = v
        .as_table()
        .map(|t| t.keys().map(String::as_str).collect())
        .unwrap_or_default();
    if names.len() > 1 || names.iter().any(|n| *n != "uniform" && *n != "normal") {
        return Err(format!(
            "{}random.{k}: unknown or extra keys ({}) in a distribution: expected {{ uniform = [a, b] }} or {{ normal = [mean, std] }} alone",
            line_of(text, k).map(|l| format!("line {l}: ")).unwrap_or_default(),
            names.join(", ")
        ));
    }
    let pair = |name: &str| -> Option<(f64, f64)> {
        let a = v.as_table()?.get(name)?.as_array()?;
        let num = |x: &toml::Value| x.as_float().or(x.as_integer().map(|i| i as f64));
        (a.len() == 2)
            .then(|| Some((num(&a[0])?, num(&a[1])?)))
            .flatten()
    };
    let at = line_of(text, k)
        .map(|l| format!("line {l}: "))
        .unwrap_or_default();
    let d = match (pair("uniform"), pair("normal")) {
        (Some((a, b)), None) => Dist::Uniform(a, b),
        (None, Some((m, s))) => Dist::Normal(m, s),
        _ => {
            return Err(format!(
                "{at}random.{k}: expected {{ uniform = [a, b] }} with a < b or {{ normal = [mean, std] }} with std >= 0"
            ))
        }
    };
    d.check().map_err(|m| format!("{at}random.{k}: {m}"))?;
    Ok(d)
}

/// The sweep's run count: the grid product times `draws`, at most [`MAX_RUNS`] (checked: an
/// overflowing product once wrapped to a small count and skipped runs).
fn total_runs(grid: &[(String, Vec<toml::Value>)], draws: u64) -> Result<u64, String> {
    grid.iter()
        .try_fold(draws, |acc, (_, v)| acc.checked_mul(v.len() as u64))
        .filter(|&t| t <= MAX_RUNS)
        .ok_or_else(|| {
            let sizes: Vec<String> = grid.iter().map(|(_, v)| v.len().to_string()).collect();
            format!(
                "the sweep has more than {MAX_RUNS} runs (grid lists of {} values x {draws} random runs); split it",
                if sizes.is_empty() { "no".to_string() } else { sizes.join(" x ") }
            )
        })
}

impl SweepPlan {
    /// Reads and checks a sweep file.
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        let err = |m: String| SweepError {
            path: path.display().to_string(),
            message: m,
        };
        let text = isotrack_fields::io::read_text_limited(path, crate::MAX_SCENARIO_FILE_BYTES)
            .map_err(|e| err(format!("cannot read: {e}")))?;
        Self::parse(&text, path)
    }

    /// Parses sweep-file text; `path` names it and anchors the relative scenario path.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SweepError> {
        let err = |m: String| SweepError {
            path: path.display().to_string(),
            message: m,
        };
        let doc = sweep_table(text).map_err(err)?;
        for k in doc.keys() {
            if !["scenario", "base", "grid", "random"].contains(&k.as_str()) {
                return Err(err(format!(
                    "unknown key `{k}`, expected one of `scenario`, `base`, `grid`, `random`"
                )));
            }
        }
        check_set_keys(text).map_err(err)?;
        let scenario = doc
            .get("scenario")
            .and_then(|v| v.as_str())
            .ok_or_else(|| err("`scenario = \"PATH\"` is required".into()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let scenario = if Path::new(scenario).is_absolute() {
            PathBuf::from(scenario)
        } else {
            dir.join(scenario)
        };
        let base = doc.get("base").map(base_overrides).unwrap_or_default();
        let grid = match doc.get("grid") {
            Some(g) => grid_lists(g).map_err(err)?,
            None => vec![],
        };
        let RandomSection {
            draws,
            seed,
            random,
        } = match doc.get("random") {
            Some(r) => random_section(r, text).map_err(err)?,
            None => RandomSection {
                draws: 1,
                seed: 0,
                random: vec![],
            },
        };
        for (k, _) in &grid {
            if random.iter().any(|(r, _)| r == k) {
                return Err(err(format!("`{k}` is both in [grid] and [random]")));
            }
        }
        let total = total_runs(&grid, draws).map_err(err)?;
        let sets_seed = |k: &str| k == "sim.seed" || k == "sim";
        // A `[grid] sim = [{...}, ...]` list of tables sets the seed only if one of its
        // tables holds `seed`: the tables merge key by key, as the dotted `sim.KEY` lists do,
        // so a table of other `sim` keys leaves each run its own derived seed (ver30b-7).
        let grid_sets_seed = |(k, values): &(String, Vec<toml::Value>)| {
            k == "sim.seed"
                || (k == "sim"
                    && values
                        .iter()
                        .any(|v| v.as_table().is_none_or(|t| t.contains_key("seed"))))
        };
        let derives_seed = !(base
            .iter()
            .any(|b| sets_seed(b.split_once('=').map_or("", |(k, _)| k.trim())))
            || grid.iter().any(grid_sets_seed)
            || random.iter().any(|(k, _)| sets_seed(k)));
        Ok(Self {
            scenario,
            dir: dir.to_path_buf(),
            base,
            grid,
            draws,
            seed,
            random,
            total,
            derives_seed,
        })
    }

    /// Number of runs (at most [`MAX_RUNS`]).
    pub fn total(&self) -> u64 {
        self.total
    }

    /// The varied keys, in column order (grid, then random, then `sim.seed` when it is
    /// derived per run).
    pub fn varied_keys(&self) -> Vec<String> {
        self.grid
            .iter()
            .map(|g| g.0.clone())
            .chain(self.random.iter().map(|r| r.0.clone()))
            .chain(self.derives_seed.then(|| "sim.seed".to_string()))
            .collect()
    }

    /// The `results.csv` columns of the varied keys: as [`varied_keys`](Self::varied_keys),
    /// with a `[grid]` key whose values are arrays (`vehicle.wind_mps = [[0, 0], [3, 0]]`) split
    /// into numeric columns `key[0]`, `key[1]`, ... (not one string column).
    pub fn columns(&self) -> Vec<String> {
        let mut cols = vec![];
        for (k, list) in &self.grid {
            match array_len(list) {
                Some(n) => cols.extend((0..n).map(|i| format!("{k}[{i}]"))),
                None => cols.push(k.clone()),
            }
        }
        cols.extend(self.random.iter().map(|r| r.0.clone()));
        if self.derives_seed {
            cols.push("sim.seed".into());
        }
        cols
    }

    /// The cells of run `id` under [`columns`](Self::columns) (strings unquoted, arrays split).
    pub fn run_cells(&self, id: u64) -> Vec<String> {
        let mut g = id / self.draws;
        let mut picked = vec![None; self.grid.len()];
        for (i, (_, list)) in self.grid.iter().enumerate().rev() {
            let n = list.len() as u64;
            picked[i] = Some(&list[(g % n) as usize]);
            g /= n;
        }
        let mut cells = vec![];
        for v in picked.into_iter().flatten() {
            match v {
                toml::Value::Array(a) => cells.extend(a.iter().map(cell)),
                other => cells.push(cell(other)),
            }
        }
        let n_grid = self.grid.len();
        cells.extend(self.run_values(id).into_iter().skip(n_grid));
        cells
    }

    /// Notes on runs that will come out identical: a `[grid]` list holding one value twice, or
    /// several draws per grid point with nothing random in them (a fixed `sim.seed` and no
    /// `[random]` key).
    pub fn duplicate_notes(&self) -> Vec<String> {
        /// The most duplicated values named per `[grid]` key; the rest are counted.
        const NAMED: usize = 3;
        let mut notes = vec![];
        for (k, list) in &self.grid {
            // Linear in the list's length (a hash set): 80 000 values once took 36 s.
            let mut seen = std::collections::HashSet::new();
            let mut repeated: Vec<String> = vec![];
            let mut counted = std::collections::HashSet::new();
            for a in list.iter().map(value_literal) {
                if !seen.insert(a.clone()) && counted.insert(a.clone()) {
                    repeated.push(a);
                }
            }
            for a in repeated.iter().take(NAMED) {
                notes.push(format!(
                    "[grid] {k} lists {a} more than once: those runs are duplicates"
                ));
            }
            if repeated.len() > NAMED {
                notes.push(format!(
                    "[grid] {k} lists {} more values more than once",
                    repeated.len() - NAMED
                ));
            }
        }
        // A std so small that `m + s z` rounds to `m` for every draw within 8 std (`1e-320`
        // beside a mean of 1) draws the mean every time, as a std of 0 does.
        let fixed = |m: f64, s: f64| s == 0.0 || (m + 8.0 * s == m && m - 8.0 * s == m);
        for (k, d) in &self.random {
            if let Dist::Normal(m, s) = d {
                if fixed(*m, *s) {
                    notes.push(format!(
                        "random.{k} = {{ normal = [{m:?}, {s:?}] }} draws {m:?} every time: nothing random in it"
                    ));
                }
            }
        }
        let nothing_random = self
            .random
            .iter()
            .all(|(_, d)| matches!(d, Dist::Normal(m, s) if fixed(*m, *s)));
        if self.draws > 1 && nothing_random && !self.derives_seed {
            notes.push(format!(
                "random.runs = {} with no [random] key and sim.seed set by the sweep: the {} draws of each grid point are identical",
                self.draws, self.draws
            ));
        }
        notes
    }

    /// The values of the varied keys for run `id` (as override literals), in [`varied_keys`]
    /// order.
    ///
    /// [`varied_keys`]: Self::varied_keys
    pub fn run_values(&self, id: u64) -> Vec<String> {
        let mut g = id / self.draws;
        let mut vals = vec![String::new(); self.grid.len()];
        for (i, (_, list)) in self.grid.iter().enumerate().rev() {
            let n = list.len() as u64;
            vals[i] = value_literal(&list[(g % n) as usize]);
            g /= n;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(id);
        for (_, d) in &self.random {
            let v = d.sample(&mut rng);
            vals.push(format!("{v:?}"));
        }
        if self.derives_seed {
            vals.push(derived_seed(self.seed, id).to_string());
        }
        vals
    }

    /// The overrides of run `id`: the base, then the varied keys.
    pub fn run_overrides(&self, id: u64) -> Vec<String> {
        self.run_assignments(id, "")
            .into_iter()
            .map(|a| a.arg)
            .collect()
    }

    /// The overrides of run `id`, each labelled with its section for messages:
    /// `{origin}, [grid] controller.kp=1.0`.
    pub fn run_assignments(&self, id: u64, origin: &str) -> Vec<Assignment> {
        let label = |section: &str, arg: &str| format!("{origin}, [{section}] {arg}");
        let mut o: Vec<Assignment> = self
            .base
            .iter()
            .map(|arg| Assignment {
                label: label("base", arg),
                arg: arg.clone(),
            })
            .collect();
        let n_grid = self.grid.len();
        for (i, (k, v)) in self
            .varied_keys()
            .iter()
            .zip(self.run_values(id))
            .enumerate()
        {
            let arg = format!("{k}={v}");
            let section = if i < n_grid {
                "grid"
            } else if i < n_grid + self.random.len() {
                "random"
            } else {
                "derived seed"
            };
            o.push(Assignment {
                label: label(section, &arg),
                arg,
            });
        }
        o
    }

    /// Checks every key of the sweep against the scenario schema before anything runs: each
    /// `[base]` value, every `[grid]` value, and each `[random]` key with a number. Unknown keys
    /// and wrong types are errors of the sweep file; values the schema accepts but a run's
    /// scenario rejects are recorded per run (`invalid_scenario`).
    pub fn check_keys(&self, base: &crate::Scenario, origin: &str) -> Result<(), ScenarioError> {
        let mut each: Vec<Assignment> = vec![];
        for arg in &self.base {
            each.push(Assignment {
                arg: arg.clone(),
                label: format!("{origin} [base] {arg}"),
            });
        }
        for (k, list) in &self.grid {
            for v in list {
                let arg = format!("{k}={}", value_literal(v));
                each.push(Assignment {
                    label: format!("{origin} [grid] {arg}"),
                    arg,
                });
            }
        }
        for (k, _) in &self.random {
            let arg = format!("{k}=0.5");
            each.push(Assignment {
                label: format!("{origin} [random] {k}"),
                arg,
            });
        }
        for a in each {
            crate::apply_assignments(base.file(), std::slice::from_ref(&a))?;
        }
        Ok(())
    }

    /// The data files the runs of this sweep read (`field.path`, `field.paths`; absolute, as
    /// a built field names them), distinct and sorted, for a base scenario whose own keys are
    /// `given` ([`crate::Scenario::given`], paths absolute): the base's files when no `[grid]`
    /// key chooses the field's files, else those of every combination of the values of the
    /// `[grid]` keys that do (`field`, `field.kind`, `field.path`, `field.paths`; `[random]`
    /// draws numbers only), each applied after `[base]` as a run applies it, resolved
    /// without reading a file. A combination a run cannot make (an `invalid_scenario` run)
    /// reads nothing. Beyond [`MAX_FILE_COMBINATIONS`] combinations, the base's files and
    /// every path any of those values names (a superset of the files the runs read). A sweep's `sweep.json` records their
    /// SHA-256 (ver30b-3: a sweep over two grid files recorded only the base's, so `--resume`
    /// and `merge` kept rows computed on an edited one without a word).
    pub fn data_files(&self, given: &crate::ScenarioFile) -> Vec<String> {
        let lists = self.file_choosing_values();
        let base: Vec<Assignment> = self
            .base
            .iter()
            .map(|arg| Assignment {
                label: format!("[base] {arg}"),
                arg: arg.clone(),
            })
            .collect();
        let mut files = std::collections::BTreeSet::new();
        let combinations = lists
            .iter()
            .try_fold(1u64, |acc, l| acc.checked_mul(l.len() as u64))
            .filter(|&n| n <= MAX_FILE_COMBINATIONS);
        match combinations {
            Some(n) => {
                // Mixed radix over the lists, the last varying fastest.
                for mut c in 0..n {
                    let mut args = Vec::with_capacity(lists.len());
                    for l in lists.iter().rev() {
                        let len = l.len() as u64;
                        args.push(&l[(c % len) as usize]);
                        c /= len;
                    }
                    args.reverse();
                    self.combination_files(given, &base, &args, &mut files);
                }
            }
            None => {
                // Too many to resolve: the base's files and every path any value names,
                // whatever kind the run ends up with (a superset).
                self.combination_files(given, &base, &[], &mut files);
                self.named_files(&mut files);
            }
        }
        files.into_iter().collect()
    }

    /// The distinct values (sorted, as assignments `KEY=VALUE`) of each `[grid]` key that
    /// chooses the field's files ([`chooses_files`]), in the grid's order.
    fn file_choosing_values(&self) -> Vec<Vec<String>> {
        self.grid
            .iter()
            .filter(|(k, _)| chooses_files(k))
            .map(|(k, list)| {
                let mut args: Vec<String> = list
                    .iter()
                    .map(|v| format!("{k}={}", value_literal(v)))
                    .collect();
                args.sort();
                args.dedup();
                args
            })
            .collect()
    }

    /// Adds to `files` the data files (absolute, beside the sweep file) of the run made by the
    /// `[grid]` assignments `args` applied after `[base]` (`base`) to the base's own keys
    /// `given`, resolved without reading a file; nothing for a combination a run cannot make.
    fn combination_files(
        &self,
        given: &crate::ScenarioFile,
        base: &[Assignment],
        args: &[&String],
        files: &mut std::collections::BTreeSet<String>,
    ) {
        let mut each = base.to_vec();
        each.extend(args.iter().map(|arg| Assignment {
            label: format!("[grid] {arg}"),
            arg: (*arg).clone(),
        }));
        let Ok(file) = crate::apply_assignments(given, &each) else {
            return;
        };
        let Ok(file) = crate::resolve::resolve(file) else {
            return;
        };
        // The seed moves a puff plume's meander only, never its files.
        if let Ok(field) = crate::spec::FieldSpec::new(&file.field, 0) {
            for p in field.data_files() {
                let path = crate::field::resolve_one(p, &self.dir);
                files.insert(path.display().to_string());
            }
        }
    }

    /// Adds to `files` every path (absolute, beside the sweep file) that any value of a
    /// `[grid]` key choosing the field's files names (`field.path`, `field.paths`, a `field`
    /// table's `path` or `paths`), whatever kind the run ends up with.
    fn named_files(&self, files: &mut std::collections::BTreeSet<String>) {
        for (_, _, path) in self.named_values() {
            files.insert(path);
        }
    }

    /// Every path a value of a `[grid]` key choosing the field's files names, as
    /// `(key index in the grid, value index in its list, absolute path beside the sweep
    /// file)`, in the grid's order.
    fn named_values(&self) -> Vec<(usize, usize, String)> {
        let mut out = vec![];
        for (ki, (k, list)) in self.grid.iter().enumerate() {
            if !chooses_files(k) {
                continue;
            }
            for (vi, v) in list.iter().enumerate() {
                let named = match (k.as_str(), v) {
                    ("field.path" | "field.paths", v) => vec![v],
                    ("field", toml::Value::Table(t)) => {
                        ["path", "paths"].iter().filter_map(|p| t.get(*p)).collect()
                    }
                    _ => vec![],
                };
                let strings = named.into_iter().flat_map(|v| match v {
                    toml::Value::String(p) => vec![p.as_str()],
                    toml::Value::Array(a) => a.iter().filter_map(|x| x.as_str()).collect(),
                    _ => vec![],
                });
                for p in strings {
                    let path = crate::field::resolve_one(p, &self.dir);
                    out.push((ki, vi, path.display().to_string()));
                }
            }
        }
        out
    }

    /// The `[grid]` value that names data file `path` (absolute, as [`Self::data_files`]
    /// gives it), as the sweep file writes it: `[grid] KEY value N VALUE` (N from 1, the
    /// value a TOML literal, a line break in it escaped), for messages about that file
    /// (att30n-13); `None` when no `[grid]` value names it (the base scenario's file).
    pub fn file_origin(&self, path: &str) -> Option<String> {
        let (ki, vi, _) = self.named_values().into_iter().find(|n| n.2 == path)?;
        let (k, list) = &self.grid[ki];
        Some(format!(
            "[grid] {k} value {} {}",
            vi + 1,
            value_literal(&list[vi])
        ))
    }

    /// Whether a run of this sweep reads each data file of `paths` (absolute, among
    /// [`Self::data_files`]) when its combinations of file-choosing `[grid]` values are too
    /// many for [`Self::data_files`] to resolve (a superset then): every combination that
    /// holds a value naming the file is resolved, the others cannot read it. `Some(true)` when
    /// one reads it, `Some(false)` when none does (att30n-1: a path beside a kind that reads
    /// no file), `None` when those combinations are themselves more than
    /// [`MAX_FILE_COMBINATIONS`], or when no `[grid]` value names it (the base's file).
    pub fn reads_files(&self, given: &crate::ScenarioFile, paths: &[String]) -> Vec<Option<bool>> {
        let lists = self.file_choosing_values();
        // The grid's file-choosing keys in order: the index of each among `lists`.
        let file_keys: Vec<usize> = self
            .grid
            .iter()
            .enumerate()
            .filter(|(_, (k, _))| chooses_files(k))
            .map(|(i, _)| i)
            .collect();
        let base: Vec<Assignment> = self
            .base
            .iter()
            .map(|arg| Assignment {
                label: format!("[base] {arg}"),
                arg: arg.clone(),
            })
            .collect();
        // Each path the values name: the values naming it (resolved once for all paths).
        let mut naming: std::collections::HashMap<String, Vec<(usize, usize)>> =
            std::collections::HashMap::new();
        for (ki, vi, p) in self.named_values() {
            naming.entry(p).or_default().push((ki, vi));
        }
        let reads = |path: &String| -> Option<bool> {
            let values = naming.get(path)?;
            for &(ki, vi) in values {
                let li = file_keys.iter().position(|&i| i == ki)?;
                let (k, list) = &self.grid[ki];
                let fixed = format!("{k}={}", value_literal(&list[vi]));
                let others = lists
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != li)
                    .try_fold(1u64, |acc, (_, l)| acc.checked_mul(l.len() as u64))
                    .filter(|&n| n <= MAX_FILE_COMBINATIONS)?;
                for mut c in 0..others {
                    let mut args: Vec<&String> = Vec::with_capacity(lists.len());
                    for (i, l) in lists.iter().enumerate().rev() {
                        if i == li {
                            args.push(&fixed);
                            continue;
                        }
                        let len = l.len() as u64;
                        args.push(&l[(c % len) as usize]);
                        c /= len;
                    }
                    args.reverse();
                    let mut files = std::collections::BTreeSet::new();
                    self.combination_files(given, &base, &args, &mut files);
                    if files.contains(path) {
                        return Some(true);
                    }
                }
            }
            Some(false)
        };
        paths.iter().map(reads).collect()
    }

    /// Whether [`Self::data_files`] gives a superset of the files the runs read (more than
    /// [`MAX_FILE_COMBINATIONS`] combinations of file-choosing `[grid]` values).
    pub fn data_files_are_a_superset(&self) -> bool {
        self.file_choosing_values()
            .iter()
            .try_fold(1u64, |acc, l| acc.checked_mul(l.len() as u64))
            .is_none_or(|n| n > MAX_FILE_COMBINATIONS)
    }
}

/// Whether `[grid]` key `k` chooses a field's files (`field`, `field.kind`, `field.path`,
/// `field.paths`; `[random]` draws numbers only).
fn chooses_files(k: &str) -> bool {
    matches!(k, "field" | "field.kind" | "field.path" | "field.paths")
}

/// The most combinations of the `[grid]` values that choose a field's files that
/// [`SweepPlan::data_files`] resolves one by one (each a few microseconds, no file read).
pub const MAX_FILE_COMBINATIONS: u64 = 4096;

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(text: &str) -> Result<SweepPlan, SweepError> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.toml");
        std::fs::write(&p, text).unwrap();
        SweepPlan::load(&p)
    }

    /// Issue 30 (att30b via fix30d), item 5: a sweep's seed beyond TOML's integers was
    /// refused as a bare "u64 value was too large".
    #[test]
    fn a_seed_beyond_tomls_integers_is_said_plainly() {
        let e = plan("scenario = \"x.toml\"\n[random]\nruns = 1\nseed = 18446744073709551615\n")
            .unwrap_err();
        assert!(
            e.message.contains("does not fit in a 64-bit integer (-9223372036854775808 ..= 9223372036854775807, TOML's integers)"),
            "{}",
            e.message
        );
        assert!(!e.message.contains("u64 value"), "{}", e.message);
    }

    #[test]
    fn grid_and_random_indexing() {
        let p = plan(
            "scenario = \"x.toml\"\n[base]\nsim.duration_s = 10.0\n[grid]\ncontroller.kp = [1.0, 2.0, 3.0]\ncontroller.ki = [0.0, 1.0]\n[random]\nruns = 4\nseed = 9\ninitial.x_m = { uniform = [-1.0, 1.0] }\n",
        )
        .unwrap();
        assert_eq!(p.total(), 24);
        assert_eq!(
            p.varied_keys(),
            ["controller.ki", "controller.kp", "initial.x_m", "sim.seed"]
        );
        assert_eq!(p.run_values(5)[3], derived_seed(9, 5).to_string());
        // id = grid_index * 4 + draw; grid index: ki slowest, kp fastest (sorted keys).
        let v = p.run_values(4 * 4 + 2); // grid 4 = (ki index 1, kp index 1)
        assert_eq!(&v[..2], ["1.0", "2.0"]);
        let x: f64 = v[2].parse().unwrap();
        assert!((-1.0..1.0).contains(&x));
        // Pure function of (seed, id).
        assert_eq!(p.run_values(18), p.run_values(18));
        assert_ne!(p.run_values(18)[2], p.run_values(19)[2]);
        assert_eq!(p.run_overrides(0)[0], "sim.duration_s=10.0");
    }

    /// The derived seed is SplitMix64: its published sequence from state 0 starts
    /// 0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4 (Vigna's reference `splitmix64.c`). Run 0's inner
    /// mix is the first; a sweep seed that lands the outer mix on state 2*golden gives the
    /// second, halved to 63 bits.
    #[test]
    fn derived_seeds_are_splitmix64() {
        const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
        let sweep_seed = GOLDEN.wrapping_mul(2).wrapping_sub(0xE220_A839_7B1D_CDAF);
        assert_eq!(derived_seed(sweep_seed, 0), 0x6E78_9E6A_A1B9_65F4 >> 1);
        let seeds: std::collections::BTreeSet<u64> =
            (0..10_000).map(|i| derived_seed(7, i)).collect();
        assert_eq!(seeds.len(), 10_000);
        assert!(seeds.iter().all(|s| *s <= i64::MAX as u64));
        // Set by the sweep: not derived.
        let p = plan("scenario = \"x\"\n[base]\nsim.seed = 3\n[random]\nruns = 2\n").unwrap();
        assert!(!p.derives_seed);
        assert!(p.duplicate_notes()[0].contains("identical"));
        // One draw, or draws that differ by a [random] key: nothing identical to note, even
        // with the seed fixed.
        let p =
            plan("scenario = \"x\"\n[base]\nsim.seed = 3\n[grid]\ncontroller.kp = [1.0, 2.0]\n")
                .unwrap();
        assert!(!p.derives_seed);
        assert_eq!(p.duplicate_notes(), Vec::<String>::new());
        let p = plan("scenario = \"x\"\n[base]\nsim.seed = 3\n[random]\nruns = 2\ninitial.x_m = { uniform = [-1.0, 1.0] }\n")
            .unwrap();
        assert!(!p.derives_seed);
        assert_eq!(p.duplicate_notes(), Vec::<String>::new());
        let p = plan("scenario = \"x\"\n[grid]\ncontroller.kp = [1.0, 2.0, 1.0]\n").unwrap();
        assert!(p.derives_seed);
        assert!(p.duplicate_notes()[0].contains("1.0 more than once"));
    }

    /// ver30b-7: a `[grid] sim` list of tables without `seed` is the dotted `sim.KEY` list
    /// written another way: each run keeps its own derived seed (README, "One seed per run"),
    /// the same seed run by run as the dotted spelling gives; a table that holds `seed` sets it.
    #[test]
    fn a_grid_sim_table_without_seed_keeps_the_derived_seeds() {
        let table = plan(
            "scenario = \"x\"\n[grid]\nsim = [{ duration_s = 20.0 }, { duration_s = 21.0 }]\n",
        )
        .unwrap();
        let dotted = plan("scenario = \"x\"\n[grid]\nsim.duration_s = [20.0, 21.0]\n").unwrap();
        assert!(table.derives_seed && dotted.derives_seed);
        assert_eq!(table.columns().last().map(String::as_str), Some("sim.seed"));
        for id in 0..2 {
            assert_eq!(table.run_values(id).last(), dotted.run_values(id).last());
            assert_eq!(
                table.run_values(id).last().unwrap(),
                &derived_seed(0, id).to_string()
            );
        }
        let seeded = plan(
            "scenario = \"x\"\n[grid]\nsim = [{ duration_s = 20.0 }, { duration_s = 21.0, seed = 4 }]\n",
        )
        .unwrap();
        assert!(!seeded.derives_seed);
    }

    #[test]
    fn run_count_overflow_is_an_error_not_a_wrap() {
        // 3 x 6148914691236517206 wraps to 2 in u64 arithmetic; 2^64 runs wrap to 0.
        let e = plan("scenario = \"x\"\n[grid]\ncontroller.kp = [5.0, 10.0, 20.0]\n[random]\nruns = 6148914691236517206\n")
            .unwrap_err();
        assert!(e.message.contains("more than 1000000000 runs"), "{e}");
        let keys: String = (0..64).map(|i| format!("k{i} = [1, 2]\n")).collect();
        let e = plan(&format!("scenario = \"x\"\n[grid]\n{keys}")).unwrap_err();
        assert!(e.message.contains("more than"), "{e}");
        // At the limit exactly: accepted.
        let ok =
            plan("scenario = \"x\"\n[grid]\na = [1, 2]\n[random]\nruns = 500000000\n").unwrap();
        assert_eq!(ok.total(), MAX_RUNS);
    }

    #[test]
    fn errors_name_the_key() {
        assert!(plan("scenario = \"x\"\nbogus = 1\n")
            .unwrap_err()
            .message
            .contains("bogus"));
        assert!(plan("[grid]\na = [1]\n")
            .unwrap_err()
            .message
            .contains("scenario"));
        assert!(plan("scenario = \"x\"\n[grid]\nsim.seed = 3\n")
            .unwrap_err()
            .message
            .contains("grid.sim.seed"));
        assert!(
            plan("scenario = \"x\"\n[random]\nruns = 2\nk = { uniform = [2, 1] }\n")
                .unwrap_err()
                .message
                .contains("random.k")
        );
        for dist in ["uniform = [1, 1]", "normal = [0, -1]", "uniform = [0, inf]"] {
            let e = plan(&format!(
                "scenario = \"x\"\n[random]\nruns = 2\nk = {{ {dist} }}\n"
            ))
            .unwrap_err();
            assert!(e.message.contains("random.k"), "{dist}: {e}");
        }
        assert!(plan("scenario = \"x\"\n[random]\nruns = 2\nk = { normal = [0, 0] }\n").is_ok());
        assert!(
            plan("scenario = \"x\"\n[random]\nk = { normal = [0, 1] }\n")
                .unwrap_err()
                .message
                .contains("runs")
        );
    }

    /// The `results.csv` cells: strings unquoted, numbers as TOML writes them, arrays split into
    /// one numeric column per element, random values and the derived seed after the grid.
    #[test]
    fn columns_and_cells() {
        let p = plan(
            "scenario = \"x\"\n[grid]\nvehicle.wind_mps = [[0.0, 0.0], [3.0, -1.5]]\ncontroller.kind = [\"pid\", \"sliding_mode\"]\n[random]\nruns = 2\nseed = 4\ninitial.x_m = { normal = [5.0, 0.0] }\n",
        )
        .unwrap();
        assert_eq!(p.total(), 8);
        assert_eq!(
            p.columns(),
            [
                "controller.kind",
                "vehicle.wind_mps[0]",
                "vehicle.wind_mps[1]",
                "initial.x_m",
                "sim.seed"
            ]
        );
        // Run 7: grid point 3 (kind 1, wind 1), draw 1; a normal with std 0 draws its mean.
        let seed = derived_seed(4, 7).to_string();
        assert_eq!(
            p.run_cells(7),
            ["sliding_mode", "3.0", "-1.5", "5.0", seed.as_str()]
        );
        assert_eq!(
            p.run_values(7),
            ["\"sliding_mode\"", "[3.0, -1.5]", "5.0", seed.as_str()]
        );
        assert_eq!(p.run_cells(0)[..3], ["pid", "0.0", "0.0"]);
        // Each override is labelled with its section.
        let labels: Vec<String> = p
            .run_assignments(7, "sweep s.toml run 7")
            .into_iter()
            .map(|a| a.label)
            .collect();
        assert_eq!(
            labels,
            [
                "sweep s.toml run 7, [grid] controller.kind=\"sliding_mode\"",
                "sweep s.toml run 7, [grid] vehicle.wind_mps=[3.0, -1.5]",
                "sweep s.toml run 7, [random] initial.x_m=5.0",
                format!("sweep s.toml run 7, [derived seed] sim.seed={seed}").as_str(),
            ]
        );
    }

    /// A uniform draw lies in [a, b) with mean (a + b)/2; a normal one has its mean and std.
    #[test]
    fn random_draws_follow_their_distributions() {
        let p = plan(
            "scenario = \"x\"\n[random]\nruns = 4000\nseed = 1\na = { uniform = [2.0, 6.0] }\nb = { normal = [-1.0, 0.5] }\n",
        )
        .unwrap();
        let (mut ua, mut nb, mut nb2) = (vec![], 0.0, 0.0);
        for id in 0..p.total() {
            let v = p.run_values(id);
            let a: f64 = v[0].parse().unwrap();
            let b: f64 = v[1].parse().unwrap();
            ua.push(a);
            nb += b;
            nb2 += b * b;
        }
        let n = p.total() as f64;
        assert!(ua.iter().all(|a| (2.0..6.0).contains(a)));
        let mean_a = ua.iter().sum::<f64>() / n;
        // Standard errors: 4/sqrt(12 n) = 0.018 and 0.5/sqrt(n) = 0.008; 4 of them allowed.
        assert!((mean_a - 4.0).abs() < 0.08, "{mean_a}");
        let mean_b = nb / n;
        let std_b = (nb2 / n - mean_b * mean_b).sqrt();
        assert!((mean_b + 1.0).abs() < 0.032, "{mean_b}");
        assert!((std_b - 0.5).abs() < 0.03, "{std_b}");
    }

    /// `sim.seed` (or the whole `[sim]` table) set in any section stops the derived seed.
    #[test]
    fn a_seed_set_anywhere_is_not_derived() {
        for text in [
            "scenario = \"x\"\n[base]\nsim.seed = 3\n",
            "scenario = \"x\"\n[base]\nsim = { seed = 3 }\n",
            "scenario = \"x\"\n[grid]\nsim.seed = [1, 2]\n",
            "scenario = \"x\"\n[random]\nruns = 2\nsim.seed = { uniform = [0, 9] }\n",
        ] {
            let p = plan(text).unwrap();
            assert!(!p.derives_seed, "{text}");
            let seeds = p.columns().iter().filter(|c| *c == "sim.seed").count();
            assert_eq!(seeds, usize::from(!text.contains("[base]")), "{text}");
            let labels = p.run_assignments(0, "").into_iter().map(|a| a.label);
            assert!(labels.filter(|l| l.contains("derived seed")).count() == 0);
        }
        let p = plan("scenario = \"x\"\n[grid]\nsim.dt_s = [0.01]\n").unwrap();
        assert_eq!(p.columns(), ["sim.dt_s", "sim.seed"]);
    }

    /// Every key is checked against the schema before a run, and the error names the section.
    #[test]
    fn check_keys_refuses_unknown_keys_by_section() {
        let base = crate::parse_scenario("", "<test>", &[]).unwrap();
        for (text, label) in [
            (
                "[base]\ncontroller.kz = 1.0\n",
                "s.toml [base] controller.kz=1.0",
            ),
            (
                "[grid]\ncontroller.kp = [1.0, \"x\"]\n",
                "s.toml [grid] controller.kp=\"x\"",
            ),
            (
                "[random]\nruns = 2\nvehicle.nope = { uniform = [0, 1] }\n",
                "s.toml [random] vehicle.nope",
            ),
        ] {
            let p = plan(&format!("scenario = \"x\"\n{text}")).unwrap();
            let e = p.check_keys(&base, "s.toml").unwrap_err();
            let at = e.issues()[0].location.to_string();
            assert_eq!(at, label, "{text}");
        }
        let p = plan("scenario = \"x\"\n[grid]\ncontroller.kp = [1.0, 2.0]\n[random]\nruns = 2\ninitial.x_m = { uniform = [0, 1] }\n").unwrap();
        assert!(p.check_keys(&base, "s.toml").is_ok());
    }

    /// Issue 30 (runs-guard), item 4: a distribution table holds one distribution and nothing
    /// else (the error names the line); a normal with std 0 is noted as nothing random.
    #[test]
    fn distribution_tables_refuse_unknown_keys() {
        for (dist, extra) in [
            ("uniform = [1.0, 2.0], log = true", "log"),
            ("uniform = [1.0, 2.0], extra = 3", "extra"),
            ("uniform = [1.0, 2.0], normal = 7", "normal"),
        ] {
            let text = format!("scenario = \"x\"\n[random]\nruns = 2\nx = {{ {dist} }}\n");
            let e = plan(&text).unwrap_err().to_string();
            assert!(e.contains("line 4") && e.contains(extra), "{e}");
        }
        let p = plan("scenario = \"x\"\n[base]\nsim.seed = 3\n[random]\nruns = 2\nx = { normal = [5.0, 0.0] }\n").unwrap();
        let notes = p.duplicate_notes();
        assert!(
            notes.iter().any(|n| n.contains("nothing random")),
            "{notes:?}"
        );
        // Issue 30 (fix30), item 10: a std of 1e-320 beside a mean of 1 rounds away.
        let p =
            plan("scenario = \"x\"\n[random]\nruns = 2\nx = { normal = [1.0, 1e-320] }\n").unwrap();
        assert!(
            p.duplicate_notes()
                .iter()
                .any(|n| n.contains("nothing random")),
            "{:?}",
            p.duplicate_notes()
        );
        let p =
            plan("scenario = \"x\"\n[random]\nruns = 2\nx = { normal = [1.0, 1e-3] }\n").unwrap();
        assert!(
            !p.duplicate_notes()
                .iter()
                .any(|n| n.contains("nothing random")),
            "{:?}",
            p.duplicate_notes()
        );
        assert!(notes.iter().any(|n| n.contains("identical")), "{notes:?}");
    }

    /// Issue 30 (att30c-13): one scenario key set twice in two spellings (a dotted and a
    /// quoted key, a quoted key with a space, two sections, a table and a key inside it) ran
    /// with the last and labelled rows with both; a key with a line feed ran every run, then
    /// the sweep refused its own `results.csv`. Refused before any run, naming both lines.
    #[test]
    fn a_key_set_twice_in_any_spelling_is_refused_naming_both_lines() {
        for (body, lines) in [
            (
                "[grid]\ncontroller.kp = [1.0, 2.0]\n\"controller.kp\" = [3.0, 4.0]\n",
                (3, 4),
            ),
            (
                "[grid]\n\"controller. kp\" = [1.0, 2.0]\n\"controller.kp\" = [3.0, 4.0]\n",
                (3, 4),
            ),
            (
                "[base]\ncontroller.kp = 9.0\n\"controller.kp\" = 8.0\n",
                (3, 4),
            ),
            (
                "[base]\ncontroller.kp = 9.0\n[grid]\ncontroller.kp = [1.0, 2.0]\n",
                (3, 5),
            ),
            (
                "[grid]\ncontroller = [{kp = 1.0}]\n[random]\nruns = 2\ncontroller.kp = { uniform = [1.0, 2.0] }\n",
                (3, 6),
            ),
        ] {
            let e = plan(&format!("scenario = \"x\"\n{body}")).unwrap_err().message;
            let (a, b) = lines;
            assert!(
                e.contains(&format!("line {a}:")) && e.contains(&format!("line {b}:")),
                "{body}: {e}"
            );
            assert!(e.contains("keep one"), "{e}");
        }
        for (key, what) in [
            (
                "\"controller.kp\\n\"",
                "control or invisible character (U+000A)",
            ),
            (
                "\"controller\".\"kp\\u202e\"",
                "control or invisible character (U+202E)",
            ),
            ("controller.\" kp\"", "a space"),
            ("\"controller.kp\"", "a dot inside quotes"),
            ("controller.\"\"", "an empty part"),
        ] {
            let e = plan(&format!("scenario = \"x\"\n[grid]\n{key} = [1.0]\n"))
                .unwrap_err()
                .message;
            assert!(e.contains("line 3:") && e.contains(what), "{key}: {e}");
            assert!(!e.contains('\n') && !e.contains('\u{202e}'), "{e}");
        }
        // One key per spelling that means one thing is fine, as are siblings.
        let p = plan("scenario = \"x\"\n[base]\ncontroller.ki = 0.0\n[grid.controller]\nkp = [1.0]\n[random]\nruns = 2\ncontroller.c1 = { uniform = [0.1, 0.2] }\n").unwrap();
        assert_eq!(p.varied_keys()[..2], ["controller.kp", "controller.c1"]);
    }

    /// Issue 30 (att30c-16): a number TOML cannot hold in a sweep file is said at line,
    /// column and key, as in a scenario file.
    #[test]
    fn a_number_beyond_range_is_said_at_line_column_and_key() {
        let e = plan("scenario = \"x\"\n[grid]\ncontroller.kp = [1.0, 1e400]\n")
            .unwrap_err()
            .message;
        assert!(
            e.contains("line 3, column ")
                && e.contains(
                    "`grid.controller.kp`: the number is beyond the largest 64-bit float"
                ),
            "{e}"
        );
    }

    /// Issue 30 (att30c-17): a uniform whose width `b - a` overflows drew `inf` for every run;
    /// a normal reaching past the largest float within 40 std sometimes. Refused at the line.
    #[test]
    fn distributions_whose_draws_overflow_are_refused_at_their_line() {
        for dist in [
            "uniform = [-1e308, 1e308]",
            "uniform = [-1.7976931348623157e308, 1.0e300]",
            "normal = [0.0, 1.7e308]",
            "normal = [1.7e308, 1e307]",
        ] {
            let e = plan(&format!(
                "scenario = \"x\"\n[random]\nruns = 2\nk = {{ {dist} }}\n"
            ))
            .unwrap_err()
            .message;
            assert!(
                e.contains("line 4:") && e.contains("random.k") && e.contains("64-bit float"),
                "{dist}: {e}"
            );
        }
        // Wide but finite: every draw finite (the largest width is below 1.8e308).
        for dist in ["uniform = [-8e307, 8e307]", "normal = [0.0, 4e306]"] {
            let p = plan(&format!(
                "scenario = \"x\"\n[random]\nruns = 200\nk = {{ {dist} }}\n"
            ))
            .unwrap();
            for id in 0..p.total() {
                let v: f64 = p.run_values(id)[0].parse().unwrap();
                assert!(v.is_finite(), "{dist}: run {id}: {v}");
            }
        }
    }

    /// Item 5: 5000 identical grid values give one note, not 4999; 3 named values at most plus
    /// a count of the others.
    #[test]
    fn duplicate_notes_are_few() {
        let list = vec!["1.0"; 5000].join(", ");
        let p = plan(&format!("scenario = \"x\"\n[grid]\nk = [{list}]\n")).unwrap();
        assert_eq!(p.duplicate_notes().len(), 1);
        let list: Vec<String> = (0..10)
            .flat_map(|i| [format!("{i}.0"), format!("{i}.0")])
            .collect();
        let p = plan(&format!(
            "scenario = \"x\"\n[grid]\nk = [{}]\n",
            list.join(", ")
        ))
        .unwrap();
        let notes = p.duplicate_notes();
        assert_eq!(notes.len(), 4, "{notes:?}");
        assert!(notes[3].contains("7 more values"), "{notes:?}");
    }

    /// ver30b-3: the data files a sweep's runs read are every file its `[grid]` chooses
    /// (each combination of `field`, `field.kind`, `field.path`, `field.paths`, applied after
    /// `[base]`, a relative path under the sweep file's directory), not only the base's; a
    /// combination that reads no file (an analytic kind) adds none, and a sweep whose grid
    /// chooses no file reads the base's.
    #[test]
    fn data_files_are_every_file_the_grid_chooses() {
        let dir = Path::new("/nonexistent-isotrack-sweep");
        let given = |text: &str| toml::from_str::<crate::ScenarioFile>(text).unwrap();
        let parse = |text: &str| SweepPlan::parse(text, &dir.join("sweep.toml")).unwrap();
        let base_grid = given("[field]\nkind = \"grid\"\npath = \"/data/base.csv\"\n");
        let analytic = given("[field]\nkind = \"radial_exp\"\n");
        let at = |n: &str| dir.join(n).display().to_string();
        // No file key in the grid: the base's file.
        let p = parse("scenario = \"x.toml\"\n[grid]\ncontroller.kp = [1.0, 2.0]\n");
        assert_eq!(p.data_files(&base_grid), ["/data/base.csv"]);
        assert!(p.data_files(&analytic).is_empty());
        // Two paths over the base's: those two, not the base's.
        let p = parse(
            "scenario = \"x.toml\"\n[grid]\nfield.path = [\"b.csv\", \"a.csv\", \"b.csv\"]\n",
        );
        assert_eq!(p.data_files(&base_grid), [at("a.csv"), at("b.csv")]);
        // Kinds x paths from an analytic base: the grid runs' files only.
        let p = parse(
            "scenario = \"x.toml\"\n[grid]\nfield.kind = [\"radial_exp\", \"grid\"]\nfield.path = [\"a.csv\", \"/abs/c.csv\"]\n",
        );
        assert_eq!(
            p.data_files(&analytic),
            ["/abs/c.csv".to_string(), at("a.csv")]
        );
        // A list of field tables over a base that names a file: one table's own file, an
        // analytic one (none), one that keeps the base's.
        let p = parse(
            "scenario = \"x.toml\"\n[grid]\nfield = [{ kind = \"grid\", path = \"e.csv\" }, { kind = \"radial_exp\" }, { spacing_m = [2.0, 2.0] }]\n",
        );
        assert_eq!(
            p.data_files(&base_grid),
            ["/data/base.csv".to_string(), at("e.csv")]
        );
        // Past MAX_FILE_COMBINATIONS (2 kinds x 2049 paths): every path named, unresolved.
        let many: Vec<String> = (0..2049).map(|i| format!("\"f{i}.csv\"")).collect();
        let p = parse(&format!(
            "scenario = \"x.toml\"\n[grid]\nfield.kind = [\"radial_exp\", \"grid\"]\nfield.path = [{}]\n",
            many.join(", ")
        ));
        let files = p.data_files(&analytic);
        assert_eq!(files.len(), 2049);
        assert!(files.contains(&at("f0.csv")) && files.contains(&at("f2048.csv")));
    }
}
