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
    /// Apply the paper's theory to a scenario: Prop. 1 (circular fields) and Prop. 2 (gain
    /// conditions and steady-state error bound from the field's own gradient and Hessian).
    Check(CheckArgs),
    /// Run one scenario with each controller (the paper's law and the baselines) on the same
    /// field, start, sensor and turn-rate limit, and tabulate the metrics.
    Compare(CompareArgs),
    /// Draw the trajectory over the field and the time series of one or more run directories
    /// (several are overlaid with a legend).
    Plot(PlotArgs),
    /// Regenerate the paper's figures (Fig. 1(a), 2(a)-(c), 3(b)-(c)) from this project's runs.
    Figures(FiguresArgs),
    /// Run a sweep file: the grid product x random draws of one scenario, in parallel,
    /// resumable, shardable; one row per run in `DIR/results.csv`.
    Sweep(SweepArgs),
    /// Combine the outputs of sweep shards; refuses missing or duplicate runs.
    Merge(MergeArgs),
    /// Trim the fixed-wing UAV (wings level, zero flight-path angle) and print the trim state,
    /// inputs and autopilot gains.
    Trim(TrimArgs),
    /// Apply recorded actuator inputs to the fixed-wing UAV from trim and write the state
    /// trajectory.
    Replay(ReplayArgs),
    /// Interpolate scattered station values onto a grid (IDW or ordinary kriging) and write it
    /// as a CSV grid with a JSON sidecar.
    Interpolate(InterpolateArgs),
    /// Run a benchmark suite (default: the bundled `suites/standard-v2.toml`): every controller
    /// on every task and scoring seed; writes `leaderboard.csv`, `leaderboard.md`, `index.html`
    /// and per-task results into DIR.
    Benchmark(BenchmarkArgs),
    /// Make one self-contained HTML page of run directories: the field, the paths with a time
    /// slider, and the error, measurement and turn-rate plots on the same cursor.
    Report(ReportArgs),
    /// Play a scenario's vehicle, field and sensor as a MAVLink 2 vehicle (a simulated
    /// autopilot for `isotrack fly`, a ground station or an SDK); docs/FLYING.md.
    Sitl(SitlArgs),
    /// Fly a scenario's law as a MAVLink 2 companion computer: measurements in, attitude or
    /// yaw-rate setpoints out, with failsafes; docs/FLYING.md.
    Fly(FlyArgs),
}

/// `isotrack sitl`.
#[derive(Debug, Args)]
pub struct SitlArgs {
    /// The scenario.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// The link: `udpin:HOST:PORT` (listen; answer whoever writes), `udpout:HOST:PORT`,
    /// `tcpin:HOST:PORT` (listen), `tcpout:HOST:PORT` or `serial:DEVICE:BAUD`.
    #[arg(long, value_name = "URL")]
    pub mavlink: String,
    /// Simulated seconds per wall-clock second (default 1: real time).
    #[arg(long, value_name = "X", conflicts_with = "lockstep")]
    pub speedup: Option<f64>,
    /// Advance one sensor period only when the companion has answered the last sample (tests).
    #[arg(long)]
    pub lockstep: bool,
    /// Send HEARTBEAT only at this fixed rate of the wall clock, Hz, as PX4 does (1): a mode
    /// or arming change shows only in the next beat, never at once (default: once a simulated
    /// second and after every change). On the wall clock, also with --speedup; not with
    /// --lockstep.
    #[arg(long, value_name = "HZ", conflicts_with = "lockstep")]
    pub heartbeat_hz: Option<f64>,
    /// The vehicle's MAVLink system id (1 to 254; 255 is the ground stations').
    #[arg(long, value_name = "ID", default_value_t = 1)]
    pub system_id: u8,
    /// `--lockstep`: end the run when nothing came from the companion (or anyone) for S
    /// seconds of wall time. Also: a peer of `udpin:`/`tcpin:` silent this long is dropped.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub timeout_s: f64,
    /// Write the simulation's own `trace.csv`, `summary.json` and `scenario.toml` into DIR.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
}

/// The mode `isotrack fly` switches the vehicle to when a failsafe trips.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FailsafeArg {
    /// Hold (PX4 AUTO.LOITER; ArduCopter/ArduPlane LOITER, ArduRover HOLD).
    Hold,
    /// Return home (PX4 AUTO.RTL; ArduPilot RTL).
    Return,
    /// Loiter (PX4 AUTO.LOITER; ArduPilot LOITER).
    Loiter,
}

/// `isotrack fly`.
#[derive(Debug, Args)]
pub struct FlyArgs {
    /// The scenario (its controller is the law flown).
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// The link to the autopilot: `udpin:HOST:PORT`, `udpout:HOST:PORT`, `tcpin:HOST:PORT`,
    /// `tcpout:HOST:PORT` or `serial:DEVICE:BAUD`.
    #[arg(long, value_name = "URL")]
    pub mavlink: String,
    /// The measurement: a NAMED_VALUE_FLOAT name (`ISO_S`, or `mavlink:NAME`), or
    /// `udp:HOST:PORT` for text lines `t_s,value` from a sensor not wired to the autopilot.
    #[arg(long, value_name = "SOURCE", default_value = "ISO_S")]
    pub sensor: String,
    /// Switch the vehicle to OFFBOARD (else wait for the pilot to); a disarmed one only with
    /// --arm.
    #[arg(long)]
    pub take_control: bool,
    /// With --take-control, also arm a disarmed vehicle (for simulators such as `isotrack
    /// sitl`); without it a disarmed vehicle is refused (exit 79, nothing commanded).
    #[arg(long)]
    pub arm: bool,
    /// With --take-control, also arm and take a vehicle announcing MAV_TYPE_GENERIC (which
    /// says nothing of its airframe; MAVSDK's autopilot server announces it): refused
    /// otherwise (exit 65, vehicle_mismatch).
    #[arg(long)]
    pub allow_generic: bool,
    /// Write `trace.csv` (received positions, measurements, commands), `summary.json`,
    /// `scenario.toml` and the raw MAVLink log `mavlink.tlog` into DIR.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
    /// End the flight (commanding the --failsafe mode) after this long since the companion has
    /// control, s: on the vehicle's clock from the first measurement answered in control, on
    /// its own clock from when the vehicle was first heard armed and in OFFBOARD, whichever
    /// ends first.
    #[arg(long, value_name = "S")]
    pub max_duration_s: Option<f64>,
    /// Fail safe after this long without a message from the vehicle or a measurement, s (0.1
    /// to 86400).
    #[arg(long, value_name = "S", default_value_t = 3.0)]
    pub timeout_s: f64,
    /// Fail safe farther than this from the position where fly got control (armed and in
    /// OFFBOARD), m; not enforced before.
    #[arg(long, value_name = "M")]
    pub fence_m: Option<f64>,
    /// The mode a failsafe switches to.
    #[arg(long, value_enum, default_value_t = FailsafeArg::Hold)]
    pub failsafe: FailsafeArg,
    /// Setpoints per second between answers (PX4's offboard mode needs >= 2).
    #[arg(long, value_name = "HZ", default_value_t = 10.0)]
    pub setpoint_rate_hz: f64,
    /// This companion's MAVLink system id (component 191, an onboard computer; 1 to 254).
    #[arg(long, value_name = "ID", default_value_t = 1)]
    pub system_id: u8,
    /// The vehicle's MAVLink system id (default: the first autopilot heard; a second one
    /// heard before control, or within 2 s of it, ends the flight, exit 69).
    #[arg(long, value_name = "ID")]
    pub target_system: Option<u8>,
}

/// `isotrack benchmark`.
#[derive(Debug, Args)]
pub struct BenchmarkArgs {
    /// The suite file (default: `suites/standard-v2.toml` of this repository).
    pub suite: Option<PathBuf>,
    /// Output directory.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: PathBuf,
    /// Comma-separated controllers (default: the suite's).
    #[arg(long, value_delimiter = ',', value_name = "NAME,...")]
    pub controllers: Vec<String>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Reuse the task results already in DIR whose suite, controllers and gains are unchanged.
    #[arg(long)]
    pub resume: bool,
    /// Rerun the tuning of the built-in laws on the suite's tuning seeds (else the gains the
    /// suite records); `DIR/suite.toml` records the new gains.
    #[arg(long)]
    pub tune: bool,
}

/// `isotrack report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Run directories (from `run --out`, `compare --out`, ...); several are overlaid.
    #[arg(required = true, value_name = "RUN_DIR")]
    pub runs: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Every `--out DIR`: the directory as the command creates, cleans up on an interrupt and names
/// it, settled once as the arguments are read, before anything is created
/// ([`isotrack_runs::cleanup::settled_dir`]: `u/b/../c` with no `u/b` is `u/c`; att53o-2).
fn out_dir() -> impl clap::builder::TypedValueParser<Value = PathBuf> {
    use clap::builder::TypedValueParser;
    clap::builder::PathBufValueParser::new().map(|p| isotrack_runs::cleanup::settled_dir(&p))
}

/// A count written canonically: decimal digits, no sign, space or leading zero (`+5` and `05`
/// are refused, as `--map-size` and `--shard` refuse them).
fn canonical_count(text: &str) -> Result<usize, String> {
    let ok = !text.is_empty()
        && text.bytes().all(|b| b.is_ascii_digit())
        && (text == "0" || !text.starts_with('0'));
    if !ok {
        return Err(
            "expected a count in plain decimal digits (no sign, space or leading zero)".into(),
        );
    }
    text.parse()
        .map_err(|_| "expected a count that fits the machine's word".to_string())
}

/// `isotrack check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The scenario.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Half-width of the tube |F - s_d| <= H over which gamma1..3 are taken (default: c2).
    #[arg(long, value_name = "H")]
    pub tube_halfwidth: Option<f64>,
    /// Write the stability chart into `--out DIR`: the sampled loop's spectral radius over kp x
    /// sensor rate (`stability_map.csv`, `.png`, `.svg`).
    #[arg(long)]
    pub map: bool,
    /// Output directory of `--map` (created if missing, as `run --out`).
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
    /// The chart's kp range `LO:HI` (default: 1/100 to 100 times the scenario's kp).
    #[arg(long, value_name = "LO:HI", allow_hyphen_values = true)]
    pub kp_range: Option<String>,
    /// The chart's sensor-rate range in Hz, `LO:HI` (default: 1/10 to 10 times the
    /// scenario's rate, at most 1/sim.dt_s).
    #[arg(long, value_name = "LO:HI", allow_hyphen_values = true)]
    pub rate_range: Option<String>,
    /// The chart's points, `NxM`: N along kp, M along the rate (default 61x41; 2..400 each, at
    /// most 40000 cells).
    #[arg(long, value_name = "NxM")]
    pub map_size: Option<String>,
    /// Simulate N points spread over the chart, classify each run (converged, limit cycle,
    /// diverged) against the chart, write `verify.csv` and mark them on the chart (1..1000).
    #[arg(long, value_name = "N", value_parser = canonical_count)]
    pub verify: Option<usize>,
    /// Worker threads for the chart and `--verify` (default: all cores). Results do not depend
    /// on it.
    #[arg(long, value_name = "N", value_parser = canonical_count)]
    pub threads: Option<usize>,
    /// How the chart looks.
    #[command(flatten)]
    pub look: FigureOptions,
}

/// `isotrack compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Comma-separated controller kinds (default: all): pi_isoline, sliding_mode,
    /// sliding_mode_smooth, suboptimal_sosm, pid, pid_crossing, gradient_reference.
    #[arg(long, value_delimiter = ',', value_name = "KIND,...")]
    pub controllers: Vec<String>,
    /// Override a scenario key for every run, e.g. `--set sensor.noise_std=0.05`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Set one controller's own key, e.g. `--gain sliding_mode.gamma=0.3`. Repeatable.
    #[arg(long = "gain", value_name = "KIND.KEY=VALUE")]
    pub gain: Vec<String>,
    /// Write `comparison.csv` and one run directory per controller (`trace.csv`,
    /// `summary.json`, `scenario.toml`) into DIR.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
}

/// Figure format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ImageFormat {
    /// PNG.
    Png,
    /// SVG.
    Svg,
}

/// `isotrack plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// Run directories written by `isotrack run --out` or `isotrack compare --out`.
    #[arg(required = true, value_name = "RUN_DIR")]
    pub runs: Vec<PathBuf>,
    /// Image format.
    #[arg(long, value_enum, default_value_t = ImageFormat::Png)]
    pub format: ImageFormat,
    /// Where to write `trajectory.*` and `timeseries.*` (default: the first run directory).
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
    /// For a sweep directory (one with `results.csv`): the swept key on the x axis (default: the
    /// first varied key). A vector key (`vehicle.wind_mps`) is plotted by its norm, or one
    /// component by `vehicle.wind_mps[0]`.
    #[arg(long, value_name = "KEY")]
    pub x: Option<String>,
    /// Also write `animation.gif` of the (first) run: the field, its isoline and the vehicle
    /// over time (48 frames).
    #[arg(long)]
    pub animate: bool,
    /// For a sweep directory: one line per value of this column (e.g. `controller.kind`).
    #[arg(long, value_name = "KEY")]
    pub group: Option<String>,
    /// For a sweep directory: the metric on the y axis.
    #[arg(
        long,
        value_name = "COLUMN",
        default_value = "steady_state_max_abs_error"
    )]
    pub metric: String,
    /// Figure options.
    #[command(flatten)]
    pub look: FigureOptions,
}

/// How figures look (`plot`, `run --plot`, `figures`).
#[derive(Debug, Clone, Args)]
pub struct FigureOptions {
    /// Figure size in pixels at 100 dpi, `WxH` (default: 1100x900 for maps in PNG, about half
    /// in SVG, sized for a single journal column).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// Base font size, pixels at 100 dpi (default 16 in PNG, 13 in SVG).
    #[arg(long, value_name = "PX")]
    pub font_size: Option<f64>,
    /// The figure title, replacing the default (`--title ""` for none: a caption says it).
    #[arg(long, value_name = "TEXT")]
    pub title: Option<String>,
    /// Heat-map colour map: viridis (the default), gray, bone or copper. Not for `check --map`,
    /// whose stability chart has its own diverging palette (blue where the spectral radius is
    /// below 1, red above): refused there.
    #[arg(long, value_name = "NAME")]
    pub colormap: Option<String>,
    /// PNG resolution in dots per inch: scales every pixel dimension (300 for print).
    #[arg(long, value_name = "DPI", default_value_t = 100.0)]
    pub dpi: f64,
}

/// `isotrack figures`.
#[derive(Debug, Args)]
pub struct FiguresArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "docs/figures", value_parser = out_dir())]
    pub out: PathBuf,
    /// Also write SVG versions.
    #[arg(long)]
    pub svg: bool,
    /// The scenarios directory.
    #[arg(long, value_name = "DIR", default_value = "scenarios")]
    pub scenarios: PathBuf,
    /// Where the runs behind the figures go (trace, summary, scenario per run).
    #[arg(long, value_name = "DIR", default_value = "target/figure-runs")]
    pub runs: PathBuf,
    /// Figure options (`--title` replaces every figure's title).
    #[command(flatten)]
    pub look: FigureOptions,
}

/// `isotrack sweep`.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The sweep file (TOML).
    pub sweep: PathBuf,
    /// Output directory.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: PathBuf,
    /// Continue an interrupted sweep in DIR: keep the complete rows, run the rest.
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Start over in a DIR that already holds a sweep (its results are replaced).
    #[arg(long)]
    pub force: bool,
    /// Override a key of the base scenario before the sweep's own keys (repeatable); part of
    /// the sweep's digest.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Run only the K-th of N disjoint shards (runs with id % N == K - 1), e.g. `--shard 2/8`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// `isotrack merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard output directories.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Merged output directory.
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: PathBuf,
    /// Replace the `results.csv` of an existing sweep in `--out`.
    #[arg(long)]
    pub force: bool,
}

/// `isotrack trim`.
#[derive(Debug, Args)]
pub struct TrimArgs {
    /// Airspeed, m/s.
    #[arg(long, value_name = "V")]
    pub airspeed_mps: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Use the 2012 code's airspeed-gain formula (`C_L,delta_e` in `a_V1`).
    #[arg(long)]
    pub ecen674_gains: bool,
}

/// `isotrack replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// Input CSV with a header: `t_s, delta_e_rad, delta_a_rad, delta_r_rad, delta_t`; each row
    /// is held until the next.
    #[arg(long, value_name = "FILE.csv")]
    pub inputs: PathBuf,
    /// Output CSV: the state at the input file's time stamps.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
    /// Initial (trim) airspeed, m/s.
    #[arg(long, value_name = "V", default_value_t = 30.0)]
    pub airspeed_mps: f64,
    /// Initial altitude, m.
    #[arg(long, value_name = "H", default_value_t = 100.0)]
    pub altitude_m: f64,
}

/// Station interpolation methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Ordinary kriging with a fitted variogram.
    Kriging,
    /// Inverse-distance weighting.
    Idw,
}

/// `isotrack interpolate`.
#[derive(Debug, Args)]
pub struct InterpolateArgs {
    /// Station CSV with a header: `x_m, y_m` or `lon_deg, lat_deg` columns and a value column.
    pub stations: PathBuf,
    /// The value column.
    #[arg(long, value_name = "NAME")]
    pub value_column: String,
    /// Interpolation method.
    #[arg(long, value_enum, default_value_t = Method::Kriging)]
    pub method: Method,
    /// Grid spacing, m (default: 1/100 of the longer side of the stations' bounding box).
    #[arg(long, value_name = "M")]
    pub spacing_m: Option<f64>,
    /// IDW power.
    #[arg(long, default_value_t = 2.0)]
    pub idw_power: f64,
    /// Output grid CSV (the sidecar gets the same name with `.json`).
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
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
    #[arg(long, value_name = "DIR", value_parser = out_dir())]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
    /// After the run, draw `trajectory.png` and `timeseries.png` into the output directory
    /// (needs `--out`).
    #[arg(long, requires = "out")]
    pub plot: bool,
    /// Figure options for `--plot`.
    #[command(flatten)]
    pub look: FigureOptions,
    /// Worker threads for a team (`[team]`; default: all cores; a team of fewer than 512
    /// vehicles steps on one). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}
