//! # isotrack-runs
//!
//! isotrack's run files and sweeps, below the command-line tool and above the scenario and
//! simulation crates (ARCHITECTURE.md):
//!
//! * the run directory format: [`trace`] (`trace.csv`, its columns defined once for the writer
//!   and for `isotrack-plot`'s reader), [`summary`] (`summary.json`'s one type, the resolved
//!   `scenario.toml`), and [`rundir`], the one writer of a run directory;
//! * the sweep engine, [`sweep`]: the results rows, plan execution, the manifest (`sweep.json`),
//!   the resume index, merge and the output-directory lock;
//! * [`results`]: a run's record (outcome and metrics) and the one results-row builder;
//! * [`files`]: which paths name one file;
//! * [`owned`]: whether a file a command would replace is isotrack's own;
//! * [`signals`]: the process's answer to Ctrl-C, SIGTERM and SIGHUP (files [`cleanup`] removed,
//!   or a flag for the commands that stop cleanly).
//!
//! Failures carry the process exit code the command-line tool exits with ([`exit`]).
#![deny(missing_docs)]

pub mod cleanup;
pub mod failure;
pub mod files;
pub mod owned;
pub mod results;
pub mod rundir;
pub mod signals;
pub mod summary;
pub mod sweep;
pub mod trace;

pub use failure::{exit, Failure};
