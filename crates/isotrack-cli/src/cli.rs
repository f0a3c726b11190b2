//! Command-line arguments.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Coordinate-free isoline tracking: steer a vehicle onto a contour of an unknown scalar field
/// using only the field value it measures (Dong & You's PI-like law and friends).
#[derive(Debug, Parser)]
#[command(name = "isotrack", version, about, long_about = None)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run one scenario (the paper's Fig. 2(b) setting when no file is given).
    Run(RunArgs),
    /// Print the fully resolved scenario (every default filled in) as TOML.
    Show(ScenarioArgs),
}

/// A scenario and its overrides.
#[derive(Debug, Args)]
pub struct ScenarioArgs {
    /// Scenario file (TOML). Without it: the built-in default, the paper's Fig. 2(b) setting.
    pub scenario: Option<PathBuf>,
    /// Override a scenario key by its dotted path, e.g. `--set controller.kp=20`. VALUE is read
    /// as a TOML value (a bare word is a string). Repeatable; applied in order.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `isotrack run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scenario.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Write `trace.csv`, `summary.json` and the resolved `scenario.toml` into DIR (created if
    /// needed).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}
