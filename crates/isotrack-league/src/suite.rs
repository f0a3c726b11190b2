//! Suite files: the tasks of a benchmark, their seeds and the tuned gains.
//!
//! ```toml
//! name = "standard"
//! version = 2
//! scoring = 2                                    # the score formula (docs/BENCHMARK.md)
//! controllers = ["pi_isoline", "sliding_mode"]   # the built-in laws it scores
//! tuning_seeds = [9001, 9002, 9003]              # gains are tuned on these ...
//! scoring_seeds = [1, 2, 3, 4, 5]                # ... and scored on these (disjoint)
//!
//! [[task]]
//! id = "circular-100hz"
//! title = "The paper's circular field, 100 Hz"
//! scenario = "../scenarios/paper-fig2b-circular.toml"   # relative to the suite file
//! set = ["sim.duration_s=300"]                          # overrides, as --set
//! length_m = 6.93                                       # the task's length scale
//! vary = { "initial.heading_rad" = { uniform = [-3.14159, 3.14159] } }
//!
//! [task.tuned.pi_isoline]        # written by `isotrack benchmark --tune`
//! kp = 10.0
//! ```
//!
//! Run `seed` of a task: the scenario with the task's `set`, the controller and its tuned gains,
//! each `vary` key drawn from a ChaCha8 stream seeded by `seed` (keys in sorted order), and
//! `sim.seed = seed` (sensor noise, gusts, dropouts).
//!
//! A suite is checked as a whole before anything runs: [`Suite::parse`] refuses what the file
//! alone shows (no or duplicate controllers, unknown laws, duplicate seeds, task ids that differ
//! only in case, a `vary` or `set` of `sim.seed`, gains for a law that is not built in), and
//! [`run_benchmark`](crate::run_benchmark) refuses every run its scenarios cannot make (invalid or
//! misspelt gains, `vary` keys that are not scenario keys or draw invalid values) before the
//! first run starts. Each error names the suite file, line and column of the key.

use crate::score::Scoring;
use isotrack_scenario::schema::ControllerKind;
use isotrack_scenario::sweep::Dist;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};

/// Suite files larger than this are refused (a suite is a page of text).
pub const MAX_SUITE_FILE_BYTES: u64 = 1 << 20;

/// A problem with a suite file, located where possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}{}: {message}", location.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct SuiteError {
    /// The suite file.
    pub path: String,
    /// Line and column (1-based), if known.
    pub location: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

/// A distribution for a `vary` key: `{ uniform = [a, b] }` or `{ normal = [mean, std] }`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum DistSpec {
    /// Uniform on `[a, b)`.
    Uniform([f64; 2]),
    /// Normal with mean and standard deviation.
    Normal([f64; 2]),
}

impl DistSpec {
    fn dist(self) -> Dist {
        match self {
            DistSpec::Uniform([a, b]) => Dist::Uniform(a, b),
            DistSpec::Normal([m, s]) => Dist::Normal(m, s),
        }
    }
}

/// One task of a suite, as written in the file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// Short identifier (letters, digits, `-`, `_`): file and column names.
    pub id: String,
    /// One line for people.
    pub title: String,
    /// The scenario file, relative to the suite file.
    pub scenario: String,
    /// The task's length scale, m: the steady RMS distance to the isoline is scored relative to
    /// it, and `speed / length_m` is the reference turn rate of the effort score.
    pub length_m: f64,
    /// Overrides of the scenario, `KEY=VALUE` as `--set`.
    #[serde(default)]
    pub set: Vec<String>,
    /// Keys drawn per seed.
    #[serde(default)]
    pub vary: BTreeMap<String, DistSpec>,
    /// Tuned gains per controller: `controller.KEY = value` for each key.
    #[serde(default)]
    pub tuned: BTreeMap<String, BTreeMap<String, f64>>,
}

/// A suite file.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    /// The suite's name.
    pub name: String,
    /// Its version: results of different versions do not compare.
    pub version: u32,
    /// The score formula ([`Scoring`]): `1` the original one, `2` (the default) the one that
    /// gives nothing for holding an isoline that was never captured.
    #[serde(default)]
    pub scoring: Scoring,
    /// What it measures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The built-in controllers it scores (the `controller.kind` names).
    pub controllers: Vec<String>,
    /// Seeds the tuning runs on.
    pub tuning_seeds: Vec<u64>,
    /// Seeds the scores come from (disjoint from `tuning_seeds`).
    pub scoring_seeds: Vec<u64>,
    /// The tasks.
    #[serde(rename = "task")]
    pub tasks: Vec<Task>,
    /// The directory the suite file is in (scenario paths are relative to it).
    #[serde(skip)]
    pub dir: PathBuf,
    /// The file's text (for the results' digest, and to locate errors).
    #[serde(skip)]
    pub text: String,
    /// The suite file as named in errors.
    #[serde(skip)]
    pub origin: String,
}

/// One step of the path to a key of a suite file: a key, or an index into an array (of values
/// or of `[[task]]` tables).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Seg {
    /// A key.
    Key(String),
    /// An array index.
    Index(usize),
}

/// The path `task[i].rest...`.
pub(crate) fn task_path(i: usize, rest: &[&str]) -> Vec<Seg> {
    let mut p = vec![Seg::Key("task".into()), Seg::Index(i)];
    p.extend(rest.iter().map(|k| Seg::Key(k.to_string())));
    p
}

/// 1-based line and column of the key at `path` in TOML `text` (of its deepest part found: a
/// table's header when the key itself is missing), `None` if the text does not parse.
pub(crate) fn locate_in(text: &str, path: &[Seg]) -> Option<(usize, usize)> {
    let doc = DeTable::parse(text).ok()?;
    let mut table: &DeTable<'_> = doc.get_ref();
    let mut value: Option<&toml::Spanned<DeValue<'_>>> = None;
    let mut found: Option<std::ops::Range<usize>> = None;
    for seg in path {
        let next = match (seg, value.map(|v| v.get_ref())) {
            (Seg::Key(k), None | Some(DeValue::Table(_))) => {
                if let Some(DeValue::Table(t)) = value.map(|v| v.get_ref()) {
                    table = t;
                }
                table
                    .iter()
                    .find(|(key, _)| key.get_ref().as_ref() == k.as_str())
                    .map(|(key, v)| (key.span(), v))
            }
            (Seg::Index(i), Some(DeValue::Array(a))) => a.get(*i).map(|v| (v.span(), v)),
            _ => None,
        };
        let Some((span, v)) = next else { break };
        // An element of an array of tables spans nothing useful: keep its first key's place.
        if !(matches!(v.get_ref(), DeValue::Table(_)) && matches!(seg, Seg::Index(_))) {
            found = Some(span);
        }
        value = Some(v);
    }
    found.map(|s| line_col(text, s.start))
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

impl Suite {
    /// A [`SuiteError`] at the key `path` of this suite's file.
    pub fn error_at(&self, path: &[Seg], message: String) -> SuiteError {
        SuiteError {
            path: self.origin.clone(),
            location: locate_in(&self.text, path),
            message,
        }
    }

    /// Reads and checks a suite file.
    pub fn load(path: &Path) -> Result<Self, SuiteError> {
        let err = |message: String| SuiteError {
            path: path.display().to_string(),
            location: None,
            message,
        };
        let text = Self::read(path).map_err(|e| err(e.to_string()))?;
        Self::from_text(path, &text)
    }

    /// The text of a suite file: a regular file (never waiting on a FIFO) of at most
    /// [`MAX_SUITE_FILE_BYTES`]. An error here is the file's, not its contents'.
    pub fn read(path: &Path) -> std::io::Result<String> {
        isotrack_fields::io::read_text_limited(path, MAX_SUITE_FILE_BYTES)
    }

    /// Parses and checks the text of the suite file `path` (its directory anchors the
    /// scenarios).
    pub fn from_text(path: &Path, text: &str) -> Result<Self, SuiteError> {
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        Self::parse(text, &path.display().to_string(), &dir)
    }

    /// Parses and checks suite text; `name` names it in errors, `dir` anchors its scenarios.
    pub fn parse(text: &str, name: &str, dir: &Path) -> Result<Self, SuiteError> {
        let mut suite: Suite = toml::from_str(text).map_err(|e| {
            let mut message = e.message().trim().to_string();
            // The only u64 values are seeds: say their range, echo what was written (serde's
            // `invalid type: string "9223372036854775808", expected u64` says neither).
            if message.ends_with("expected u64") {
                let typed = e.span().and_then(|s| text.get(s)).unwrap_or("").trim();
                message = format!(
                    "seeds are integers from 0 to {} (sim.seed is a TOML integer), got {}",
                    i64::MAX,
                    isotrack_scenario::load::clip(typed)
                );
            }
            SuiteError {
                path: name.to_string(),
                location: e.span().map(|s| line_col(text, s.start)),
                message,
            }
        })?;
        suite.dir = dir.to_path_buf();
        suite.text = text.to_string();
        suite.origin = name.to_string();
        suite
            .check()
            .map_err(|(path, message)| suite.error_at(&path, message))?;
        Ok(suite)
    }

    /// What the file alone shows to be wrong: the message and the path of the key.
    fn check(&self) -> Result<(), (Vec<Seg>, String)> {
        if self.tasks.is_empty() {
            return Err((vec![], "the suite has no [[task]]".into()));
        }
        self.check_name()?;
        self.check_controllers()?;
        self.check_seeds()?;
        // Task ids by their lower case, to the first task with it.
        let mut ids: BTreeMap<String, usize> = BTreeMap::new();
        for (i, t) in self.tasks.iter().enumerate() {
            let earlier = ids.get(&t.id.to_ascii_lowercase()).map(|&j| &self.tasks[j]);
            check_task(i, t, earlier, &self.controllers)?;
            ids.insert(t.id.to_ascii_lowercase(), i);
        }
        Ok(())
    }

    /// The suite's name: visible, since it heads the leaderboard and its pages.
    fn check_name(&self) -> Result<(), (Vec<Seg>, String)> {
        let top = |k: &str| vec![Seg::Key(k.into())];
        // The name heads the leaderboard and its pages: no name that prints as another.
        let shown = |c: char| !isotrack_core::numtext::is_not_plain(c);
        if self.name.trim().is_empty() || !self.name.chars().all(shown) {
            return Err((
                top("name"),
                format!(
                    "name `{}`: give the suite a visible name, without control or invisible (zero-width) characters",
                    clip(&self.name)
                ),
            ));
        }
        Ok(())
    }

    /// `controllers`: not empty, each a built-in law, none twice.
    fn check_controllers(&self) -> Result<(), (Vec<Seg>, String)> {
        let top = |k: &str| vec![Seg::Key(k.into())];
        let at = |k: &str, i: usize| vec![Seg::Key(k.into()), Seg::Index(i)];
        if self.controllers.is_empty() {
            return Err((
                top("controllers"),
                "controllers is empty: name the built-in laws the suite scores".into(),
            ));
        }
        // Sets, not pairwise scans: a 1 MiB file can hold 10^5 seeds.
        let mut seen = std::collections::BTreeSet::new();
        for (i, c) in self.controllers.iter().enumerate() {
            if ControllerKind::from_name(c).is_none() {
                return Err((
                    at("controllers", i),
                    format!(
                        "controllers: `{}` is not a built-in law ({})",
                        clip(c),
                        builtin_names()
                    ),
                ));
            }
            if !seen.insert(c.as_str()) {
                return Err((
                    at("controllers", i),
                    format!("controllers: `{}` appears twice", clip(c)),
                ));
            }
        }
        Ok(())
    }

    /// `tuning_seeds` and `scoring_seeds`: TOML integers, none twice, the two sets disjoint,
    /// some scoring seeds.
    fn check_seeds(&self) -> Result<(), (Vec<Seg>, String)> {
        let top = |k: &str| vec![Seg::Key(k.into())];
        let at = |k: &str, i: usize| vec![Seg::Key(k.into()), Seg::Index(i)];
        if self.scoring_seeds.is_empty() {
            return Err((top("scoring_seeds"), "scoring_seeds is empty".into()));
        }
        for key in ["tuning_seeds", "scoring_seeds"] {
            let seeds = if key == "tuning_seeds" {
                &self.tuning_seeds
            } else {
                &self.scoring_seeds
            };
            // Each seed becomes `sim.seed`, a TOML integer (64-bit signed).
            if let Some(i) = (0..seeds.len()).find(|&i| seeds[i] > i64::MAX as u64) {
                return Err((
                    at(key, i),
                    format!(
                        "{key}: seeds are integers from 0 to {} (sim.seed is a TOML integer), got {}",
                        i64::MAX,
                        seeds[i]
                    ),
                ));
            }
            let mut seen = std::collections::BTreeSet::new();
            if let Some(i) = (0..seeds.len()).find(|&i| !seen.insert(seeds[i])) {
                return Err((
                    at(key, i),
                    format!(
                        "{key}: seed {} appears twice (a repeated seed is the same run counted again)",
                        seeds[i]
                    ),
                ));
            }
        }
        let tuning: std::collections::BTreeSet<u64> = self.tuning_seeds.iter().copied().collect();
        if let Some(i) =
            (0..self.scoring_seeds.len()).find(|&i| tuning.contains(&self.scoring_seeds[i]))
        {
            return Err((
                at("scoring_seeds", i),
                format!(
                    "seed {} is both a tuning and a scoring seed: the two sets must be disjoint, or the scores measure the tuning",
                    self.scoring_seeds[i]
                ),
            ));
        }
        Ok(())
    }

    /// The scenario file of a task.
    pub fn scenario_path(&self, task: &Task) -> PathBuf {
        self.dir.join(&task.scenario)
    }

    /// The suite as TOML (the tuned gains included), under a header comment.
    pub fn to_toml(&self, header: &str) -> String {
        let body = isotrack_scenario::tomltext::to_toml(self).unwrap_or_default();
        let mut out = String::new();
        for line in header.lines() {
            out.push_str("# ");
            out.push_str(line);
            out.push('\n');
        }
        out.push('\n');
        out.push_str(&body);
        out
    }
}

/// The built-in law names, for messages.
fn builtin_names() -> String {
    ControllerKind::ALL
        .iter()
        .map(|k| k.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The checks of task `i` that need no scenario; `earlier` is a task before it whose id is the
/// same ignoring case, if any.
fn check_task(
    i: usize,
    t: &Task,
    earlier: Option<&Task>,
    controllers: &[String],
) -> Result<(), (Vec<Seg>, String)> {
    check_task_id(i, t, earlier)?;
    check_task_title_and_length(i, t)?;
    check_task_set(i, t)?;
    check_task_rest(i, t, controllers)
}

/// Task `i`'s id: 1-64 letters, digits, '-' or '_', and no earlier task's id ignoring case
/// (`earlier`).
fn check_task_id(i: usize, t: &Task, earlier: Option<&Task>) -> Result<(), (Vec<Seg>, String)> {
    let ok = !t.id.is_empty()
        && t.id.len() <= 64
        && t.id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !ok {
        return Err((
            task_path(i, &["id"]),
            format!(
                "task id {:?}: use 1-64 letters, digits, '-' or '_'",
                clip(&t.id)
            ),
        ));
    }
    // Ids name directories (`tasks/ID`): on a case-insensitive file system two ids that
    // differ only in case would share one.
    if let Some(o) = earlier {
        let what = if o.id == t.id {
            format!("task id {:?} appears twice", t.id)
        } else {
            format!(
                "task id {:?} differs from task id {:?} only in case: ids name directories, which a case-insensitive file system would merge",
                t.id, o.id
            )
        };
        return Err((task_path(i, &["id"]), what));
    }
    Ok(())
}

/// Task `i`'s title (visible, at most [`MAX_TITLE_CHARS`]) and `length_m` (finite, > 0).
fn check_task_title_and_length(i: usize, t: &Task) -> Result<(), (Vec<Seg>, String)> {
    // The title heads the task's row of the leaderboard and its page: visible characters
    // only, at most MAX_TITLE_CHARS.
    let shown = |c: char| !isotrack_core::numtext::is_not_plain(c);
    if t.title.chars().count() > MAX_TITLE_CHARS || !t.title.chars().all(shown) {
        return Err((
            task_path(i, &["title"]),
            format!(
                "task {}: title `{}`: give at most {MAX_TITLE_CHARS} visible characters, without control or invisible (bidi, zero-width) characters",
                t.id,
                clip(&t.title)
            ),
        ));
    }
    if !(t.length_m.is_finite() && t.length_m > 0.0) {
        return Err((
            task_path(i, &["length_m"]),
            format!(
                "task {}: length_m must be finite and > 0, got {}",
                t.id,
                isotrack_core::numtext::Echo(t.length_m)
            ),
        ));
    }
    Ok(())
}

/// Task `i`'s `set`: no `sim.seed`, each key once, and no gain both set and tuned.
fn check_task_set(i: usize, t: &Task) -> Result<(), (Vec<Seg>, String)> {
    let seed_note = "every run's sim.seed is its seed (tuning_seeds, scoring_seeds)";
    if let Some(j) = t
        .set
        .iter()
        .position(|a| assigned_keys(a).iter().any(|k| k == "sim.seed"))
    {
        return Err((
            vec![
                Seg::Key("task".into()),
                Seg::Index(i),
                Seg::Key("set".into()),
                Seg::Index(j),
            ],
            format!("task {}: set sim.seed has no effect: {seed_note}", t.id),
        ));
    }
    // One value per key: a key set twice (the last would win unseen), or both set and drawn
    // (the draw would replace the set value unseen).
    // Keys compared as TOML reads them: `sim . duration_s = 3` and `sim = { duration_s = 3 }`
    // both set `sim.duration_s`.
    let mut set_keys: BTreeMap<String, usize> = BTreeMap::new();
    for (j, a) in t.set.iter().enumerate() {
        let at = vec![
            Seg::Key("task".into()),
            Seg::Index(i),
            Seg::Key("set".into()),
            Seg::Index(j),
        ];
        for k in assigned_keys(a) {
            check_set_key(t, &set_keys, &k, j, at.clone())?;
            set_keys.insert(k, j);
        }
    }
    for (c, gains) in &t.tuned {
        if let Some((gain, j)) = gains
            .keys()
            .find_map(|g| set_keys.get(&format!("controller.{g}")).map(|j| (g, *j)))
        {
            return Err((
                task_path(i, &["tuned", c, gain]),
                format!(
                    "task {}: set[{j}] assigns controller.{gain} and [task.tuned.{c}] gives {gain}: one value per gain (the tuned one would win unseen)",
                    t.id
                ),
            ));
        }
    }
    Ok(())
}

/// The longest task title, characters.
pub const MAX_TITLE_CHARS: usize = 200;

/// The leaf keys an assignment `KEY = VALUE` sets, dotted, as TOML reads it (`a . b = 1` and
/// `a = { b = 1 }` both set `a.b`); the text before `=`, trimmed, when it is no TOML.
fn assigned_keys(a: &str) -> Vec<String> {
    fn leaves(prefix: &str, v: &toml::Value, out: &mut Vec<String>) {
        match v {
            toml::Value::Table(t) if !t.is_empty() => {
                for (k, v) in t {
                    leaves(&format!("{prefix}.{k}"), v, out);
                }
            }
            _ => out.push(prefix.to_string()),
        }
    }
    match a.parse::<toml::Table>() {
        Ok(t) => {
            let mut out = vec![];
            for (k, v) in &t {
                leaves(k, v, &mut out);
            }
            out
        }
        Err(_) => a
            .split_once('=')
            .map(|(k, _)| vec![k.trim().to_string()])
            .unwrap_or_default(),
    }
}

/// One set key `k` (from `set[j]`) against the keys set before it and the drawn ones.
fn check_set_key(
    t: &Task,
    set_keys: &BTreeMap<String, usize>,
    k: &str,
    j: usize,
    at: Vec<Seg>,
) -> Result<(), (Vec<Seg>, String)> {
    {
        if let Some(first) = set_keys.get(k) {
            return Err((
                at,
                format!(
                    "task {}: set assigns {} twice (set[{first}] and set[{j}]): one value per key",
                    t.id,
                    clip(k)
                ),
            ));
        }
        if t.vary.keys().any(|v| v.trim() == k) {
            return Err((
                at,
                format!(
                    "task {}: {} is both set and in vary: every run would draw it, replacing the set value",
                    t.id,
                    clip(k)
                ),
            ));
        }
    }
    Ok(())
}

/// The rest of [`check_task`]: the drawn keys and the tuned gains.
fn check_task_rest(i: usize, t: &Task, controllers: &[String]) -> Result<(), (Vec<Seg>, String)> {
    let seed_note = "every run's sim.seed is its seed (tuning_seeds, scoring_seeds)";
    for (k, d) in &t.vary {
        if k.trim() == "sim.seed" {
            return Err((
                task_path(i, &["vary", k]),
                format!("task {}: vary sim.seed: {seed_note}", t.id),
            ));
        }
        let [a, b] = match d {
            DistSpec::Uniform(v) | DistSpec::Normal(v) => *v,
        };
        let bad = match d {
            DistSpec::Uniform(_) => !(a.is_finite() && b.is_finite() && a <= b),
            DistSpec::Normal(_) => !(a.is_finite() && b.is_finite() && b >= 0.0),
        };
        if bad {
            return Err((
                task_path(i, &["vary", k]),
                format!("task {}: vary {}: bad distribution {d:?}", t.id, clip(k)),
            ));
        }
        // The sweep's `[random]` rule: no draw overflows to `inf` (a uniform's width `b - a`, a
        // normal's `mean +- 40 std`), the one check of both (`Dist::check_draws_finite`).
        if let Err(why) = d.dist().check_draws_finite() {
            return Err((
                task_path(i, &["vary", k]),
                format!("task {}: vary {}: {why}", t.id, clip(k)),
            ));
        }
    }
    for (c, gains) in &t.tuned {
        if ControllerKind::from_name(c).is_none() {
            return Err((
                task_path(i, &["tuned", c]),
                format!(
                    "task {}: tuned gains for `{}`, which is not a built-in law ({}): only the built-in laws run with recorded gains",
                    t.id,
                    clip(c),
                    builtin_names()
                ),
            ));
        }
        if !controllers.contains(c) {
            return Err((
                task_path(i, &["tuned", c]),
                format!(
                    "task {}: tuned gains for {c}, which the suite does not score (controllers = [{}]): add it to controllers or remove [task.tuned.{c}]",
                    t.id,
                    controllers.join(", ")
                ),
            ));
        }
        if let Some((k, v)) = gains.iter().find(|(_, v)| !v.is_finite()) {
            return Err((
                task_path(i, &["tuned", c, k]),
                format!("task {}: tuned {c}.{} = {v} is not finite", t.id, clip(k)),
            ));
        }
    }
    Ok(())
}

/// The overrides a seed draws for a task's `vary` keys (sorted keys, one ChaCha8 stream per
/// seed), then `sim.seed = seed`.
pub fn seed_overrides(task: &Task, seed: u64) -> Vec<String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut o: Vec<String> = task
        .vary
        .iter()
        .map(|(k, d)| {
            let v = d.dist().sample(&mut rng);
            format!("{k}={v:?}")
        })
        .collect();
    o.push(format!("sim.seed={seed}"));
    o
}

/// Text from the suite file for messages: escaped, then cut after 80 characters of what is
/// shown ([`isotrack_core::numtext::Clipped`]; a line feed in a TOML key was printed raw).
pub(crate) fn clip(s: &str) -> String {
    isotrack_core::numtext::Clipped::with_limit(s, 80).to_string()
}
