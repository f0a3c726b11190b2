//! Suite files: the tasks of a benchmark, their seeds and the tuned gains.
//!
//! ```toml
//! name = "standard"
//! version = 1
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

use isotrack_scenario::sweep::Dist;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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
    /// The file's text (for the results' digest).
    #[serde(skip)]
    pub text: String,
}

/// 1-based line and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

impl Suite {
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
        let mut suite: Suite = toml::from_str(text).map_err(|e| SuiteError {
            path: name.to_string(),
            location: e.span().map(|s| line_col(text, s.start)),
            message: e.message().trim().to_string(),
        })?;
        suite.dir = dir.to_path_buf();
        suite.text = text.to_string();
        suite.check().map_err(|message| SuiteError {
            path: name.to_string(),
            location: None,
            message,
        })?;
        Ok(suite)
    }

    fn check(&self) -> Result<(), String> {
        if self.tasks.is_empty() {
            return Err("the suite has no [[task]]".into());
        }
        if self.scoring_seeds.is_empty() {
            return Err("scoring_seeds is empty".into());
        }
        if let Some(s) = self
            .tuning_seeds
            .iter()
            .find(|s| self.scoring_seeds.contains(s))
        {
            return Err(format!(
                "seed {s} is both a tuning and a scoring seed: the two sets must be disjoint, or the scores measure the tuning"
            ));
        }
        let mut ids = std::collections::BTreeSet::new();
        for t in &self.tasks {
            let ok = !t.id.is_empty()
                && t.id.len() <= 64
                && t.id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !ok {
                return Err(format!(
                    "task id {:?}: use 1-64 letters, digits, '-' or '_'",
                    clip(&t.id)
                ));
            }
            if !ids.insert(t.id.as_str()) {
                return Err(format!("task id {:?} appears twice", t.id));
            }
            if !(t.length_m.is_finite() && t.length_m > 0.0) {
                return Err(format!(
                    "task {}: length_m must be finite and > 0, got {}",
                    t.id, t.length_m
                ));
            }
            for (k, d) in &t.vary {
                let [a, b] = match d {
                    DistSpec::Uniform(v) | DistSpec::Normal(v) => *v,
                };
                let bad = match d {
                    DistSpec::Uniform(_) => !(a.is_finite() && b.is_finite() && a <= b),
                    DistSpec::Normal(_) => !(a.is_finite() && b.is_finite() && b >= 0.0),
                };
                if bad {
                    return Err(format!("task {}: vary {k}: bad distribution {d:?}", t.id));
                }
            }
            for (c, gains) in &t.tuned {
                if let Some((k, v)) = gains.iter().find(|(_, v)| !v.is_finite()) {
                    return Err(format!("task {}: tuned {c}.{k} = {v} is not finite", t.id));
                }
            }
        }
        Ok(())
    }

    /// The scenario file of a task.
    pub fn scenario_path(&self, task: &Task) -> PathBuf {
        self.dir.join(&task.scenario)
    }

    /// The suite as TOML (the tuned gains included), under a header comment.
    pub fn to_toml(&self, header: &str) -> String {
        let body = toml::to_string(self).unwrap_or_default();
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

/// The overrides a seed draws for a task's `vary` keys (sorted keys, one ChaCha8 stream per
/// seed), then `sim.seed = seed`.
pub fn seed_overrides(task: &Task, seed: u64) -> Vec<String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut o: Vec<String> = task
        .vary
        .iter()
        .map(|(k, d)| {
            let v = match d.dist() {
                Dist::Uniform(a, b) => {
                    let u: f64 = rand::RngExt::random(&mut rng);
                    a + (b - a) * u
                }
                Dist::Normal(m, s) => {
                    let n: f64 = StandardNormal.sample(&mut rng);
                    m + s * n
                }
            };
            format!("{k}={v:?}")
        })
        .collect();
    o.push(format!("sim.seed={seed}"));
    o
}

/// Text clipped for messages.
pub(crate) fn clip(s: &str) -> String {
    if s.chars().count() > 80 {
        s.chars().take(80).collect::<String>() + "..."
    } else {
        s.to_string()
    }
}
