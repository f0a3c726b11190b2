//! # isotrack-scenario
//!
//! A scenario is a TOML file describing one run: `[field]`, `[vehicle]`, `[initial]`, `[sensor]`,
//! `[controller]`, `[sim]`, `[metrics]`, `[output]`. Every key has a default (the paper's
//! Fig. 2(b) setting), so an empty file is a valid scenario and the built-in default.
//!
//! * [`schema`]: the sections and keys (the file format, documented key by key).
//! * [`load`]: reading a file, applying `--set KEY=VALUE` overrides, and errors that name the file,
//!   line and key ([`ScenarioError`]).
//! * [`resolve`]: filling defaults and validating values, giving a [`Scenario`] whose every key is
//!   explicit (what `summary.json` records).
//! * [`build`]: turning a resolved scenario into field, vehicle, sensor and controller, and
//!   running it ([`Scenario::run`]).
#![deny(missing_docs)]

pub mod build;
pub mod load;
pub mod resolve;
pub mod schema;

pub use build::ControllerModel;
pub use load::{load_scenario, parse_scenario, ErrorLocation, ScenarioError};
pub use schema::ScenarioFile;

/// A resolved, validated scenario: every key that applies has a value.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    file: ScenarioFile,
}

impl Scenario {
    /// The resolved keys (serialise this to record the exact run; it reads back as the same
    /// scenario).
    pub fn file(&self) -> &ScenarioFile {
        &self.file
    }

    /// The built-in default: the paper's Fig. 2(b) setting (what an empty file resolves to).
    pub fn default_paper_fig2b() -> Self {
        resolve::resolve(ScenarioFile::default()).expect("the built-in default scenario is valid")
    }
}
