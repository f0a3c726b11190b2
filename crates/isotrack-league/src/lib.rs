//! # isotrack-league
//!
//! A graded benchmark for isoline trackers: a suite file lists tasks (a scenario, its
//! overrides, what varies per seed), tuning seeds and scoring seeds; each built-in law is tuned
//! per task on the tuning seeds ([`tune`]) and every controller, built-in or registered
//! ([`Registry`]), is scored on the scoring seeds ([`score`]); the leaderboard is the mean score
//! per task and overall ([`leaderboard`]).
//!
//! * [`suite`]: the suite file format and the per-seed draws.
//! * [`registry`]: controllers by name, your own in one line.
//! * [`score`]: the score of a run, `[0, 100]`, and its documented formula.
//! * [`tune`]: the documented tuning procedure.
//! * [`run`]: running a suite ([`run_benchmark`]), deterministic on any thread count.
//! * [`leaderboard`]: `leaderboard.csv`, `leaderboard.md`, per-task `results.csv`.
//! * [`page`]: the benchmark's `index.html` ([`benchmark_page`], on `isotrack-html`'s shell).
#![deny(missing_docs)]

pub mod leaderboard;
mod one_run;
pub mod page;
pub mod registry;
mod results;
mod resume;
pub mod run;
pub mod score;
pub mod suite;
pub mod tune;

pub use page::benchmark_page;
pub use registry::{check_name, ControllerFactory, Entrant, NameError, Registry};
pub use run::{run_benchmark, BenchError, BenchResult, Options, TaskResult};
pub use score::{Score, ScoreContext, Scoring};
pub use suite::{Seg, Suite, SuiteError, Task};
