//! `isotrack check --map --out DIR [--verify N]`: the stability chart and its verification
//! runs (docs/SAMPLED.md, "The stability chart").

use crate::cli::CheckArgs;
use crate::exit;
use crate::output::num;
use isotrack_core::numtext::{Echo, Num};
use isotrack_runs::Failure;
use isotrack_scenario::check::map::{
    agreement, steps_per_run, verify_point, verify_points, Agreement, LoopFamily, MapGrid,
    StabilityMap, VerifyPoint, MAX_VERIFY_RUNS, MAX_VERIFY_STEPS, NEAR_BOUNDARY_E_FOLDS,
};
use isotrack_scenario::load::clip;
use isotrack_scenario::Scenario;
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The columns of `stability_map.csv`.
pub const MAP_COLUMNS: [&str; 9] = [
    "kp",
    "sensor_rate_hz",
    "sensor_period_s",
    "spectral_radius",
    "stable",
    "status",
    "slope_min",
    "slope_max",
    "note",
];

/// The columns of `verify.csv`.
pub const VERIFY_COLUMNS: [&str; 11] = [
    "run",
    "kp",
    "sensor_rate_hz",
    "spectral_radius",
    "predicted",
    "outcome",
    "agrees",
    "near_boundary",
    "error_range",
    "mean_abs_turn_radps",
    "detail",
];

fn usage(message: String) -> Failure {
    Failure {
        code: exit::USAGE,
        message,
    }
}

/// `LO:HI` as two numbers.
fn parse_range(flag: &str, text: &str) -> Result<[f64; 2], Failure> {
    let bad = || {
        usage(format!(
            "{flag} {}: expected LO:HI, two numbers with 0 < LO < HI",
            clip(text)
        ))
    };
    let (a, b) = text.split_once(':').ok_or_else(bad)?;
    let lo: f64 = a.trim().parse().map_err(|_| bad())?;
    let hi: f64 = b.trim().parse().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi) {
        return Err(bad());
    }
    // A subnormal end (below 2.2e-308) has lost its precision: its logarithmic spacing is
    // not the number written (a hostile review's 1e-310).
    if !lo.is_normal() {
        return Err(usage(format!(
            "{flag} {}: LO = {} is subnormal (below {:e}): give a normal positive number",
            clip(text),
            Echo(lo),
            f64::MIN_POSITIVE
        )));
    }
    Ok([lo, hi])
}

/// The chart's options as given on the command line (each `None` when not given).
#[derive(Clone, Copy, Debug, Default)]
pub struct MapOptions {
    /// `--kp-range`.
    pub kp_range: Option<[f64; 2]>,
    /// `--rate-range`, Hz.
    pub rate_range_hz: Option<[f64; 2]>,
    /// `--map-size` (points along kp, along the rate).
    pub size: Option<(usize, usize)>,
}

/// The map options checked before the scenario is loaded: `--map` needs `--out`, the options
/// of the chart need `--map`, the values parse.
pub fn precheck(args: &CheckArgs) -> Result<MapOptions, Failure> {
    if args.threads == Some(0) {
        return Err(usage(
            "--threads 0: at least 1 worker thread (leave --threads out for all cores)".into(),
        ));
    }
    if !args.map {
        refuse_map_options(args)?;
        return Ok(MapOptions::default());
    }
    if args.out.is_none() {
        return Err(usage("--map needs --out DIR".into()));
    }
    // Issue 29: `--colormap gray` and `copper` drew byte-identical charts. The chart's palette
    // is diverging round the boundary at radius 1 (blue stable, red unstable), which no
    // sequential heat-map colour map shows: the option is refused, not ignored.
    if args.look.colormap.is_some() {
        return Err(usage(
            "--colormap is not an option of check --map: the stability chart has its own diverging palette (blue where the spectral radius is below 1, red above, the boundary drawn at 1)".into(),
        ));
    }
    let kp = args
        .kp_range
        .as_deref()
        .map(|t| parse_range("--kp-range", t))
        .transpose()?;
    let rate = args
        .rate_range
        .as_deref()
        .map(|t| parse_range("--rate-range", t))
        .transpose()?;
    let size = args.map_size.as_deref().map(parse_map_size).transpose()?;
    if let Some(n) = args.verify {
        if !(1..=MAX_VERIFY_RUNS).contains(&n) {
            return Err(usage(format!("--verify {n}: 1 to {MAX_VERIFY_RUNS} runs")));
        }
    }
    Ok(MapOptions {
        kp_range: kp,
        rate_range_hz: rate,
        size,
    })
}

/// Without `--map`: every option of the chart refused, naming it.
fn refuse_map_options(args: &CheckArgs) -> Result<(), Failure> {
    for (given, flag) in [
        (args.out.is_some(), "--out"),
        (args.kp_range.is_some(), "--kp-range"),
        (args.rate_range.is_some(), "--rate-range"),
        (args.map_size.is_some(), "--map-size"),
        (args.verify.is_some(), "--verify"),
        (args.threads.is_some(), "--threads"),
        // The chart's look (a hostile review: `check --dpi 0` exited 0, the option unused;
        // --dpi is caught when it differs from its default).
        (args.look.size.is_some(), "--size"),
        (args.look.font_size.is_some(), "--font-size"),
        (args.look.title.is_some(), "--title"),
        (args.look.colormap.is_some(), "--colormap"),
        (args.look.dpi.to_bits() != 100.0f64.to_bits(), "--dpi"),
    ] {
        if given {
            return Err(usage(format!(
                "{flag} is an option of --map (check --map --out DIR)"
            )));
        }
    }
    Ok(())
}

/// `--map-size NxM`: points along kp x along the rate.
fn parse_map_size(t: &str) -> Result<(usize, usize), Failure> {
    let bad = || {
        usage(format!(
            "--map-size {}: expected NxM (points along kp x along the rate), e.g. 61x41",
            clip(t)
        ))
    };
    // Exactly NxM: decimal digits, a lower-case `x`, decimal digits (no sign, space or
    // `X`: a hostile review's `3X4` and `+3x4` were accepted silently).
    let (a, b) = t.split_once('x').ok_or_else(bad)?;
    // No leading zero either (`04x3`), as `--shard` and the counts elsewhere.
    let digits = |x: &str| {
        !x.is_empty() && x.bytes().all(|c| c.is_ascii_digit()) && (x == "0" || !x.starts_with('0'))
    };
    if !(digits(a) && digits(b)) {
        return Err(bad());
    }
    let n: usize = a.parse().map_err(|_| bad())?;
    let m: usize = b.parse().map_err(|_| bad())?;
    Ok((n, m))
}

/// What `check --map` wrote (named in `check --json`'s `map`).
#[derive(Debug, Serialize)]
pub struct MapReport {
    /// The files written.
    pub files: Vec<String>,
    /// The grid.
    pub grid: MapGrid,
    /// Which slopes the chart uses.
    pub slope_basis: &'static str,
    /// Cells by status.
    pub cells_stable: usize,
    /// See `cells_stable`.
    pub cells_unstable: usize,
    /// See `cells_stable` (no equilibrium counts as unstable too; listed for clarity).
    pub cells_no_equilibrium: usize,
    /// See `cells_stable`.
    pub cells_not_computed: usize,
    /// `--verify`'s agreement (null without `--verify`): over the runs that finished.
    pub verify: Option<Agreement>,
    /// `--verify`'s runs: requested, finished, and whether Ctrl-C cut them short (null without
    /// `--verify`).
    pub verify_runs: Option<VerifyRuns>,
    /// The runs that disagree with the chart away from its boundary (the cell's mode changes
    /// by more than `e^NEAR_BOUNDARY_E_FOLDS` over the run), each named.
    pub disagreements_far: Vec<FarDisagreement>,
}

/// How many `--verify` runs were asked for and finished.
#[derive(Debug, Serialize)]
pub struct VerifyRuns {
    /// `--verify N`.
    pub requested: usize,
    /// The runs that finished (all of them unless interrupted).
    pub finished: usize,
    /// Ctrl-C (or SIGTERM) stopped the runs: the agreement is over the finished ones only.
    pub partial: bool,
}

/// A `--verify` run that disagrees with the chart away from its boundary.
#[derive(Debug, Serialize)]
pub struct FarDisagreement {
    /// The run's row in `verify.csv`.
    pub run: usize,
    /// `kp`.
    pub kp: f64,
    /// Sensor rate, Hz.
    pub sensor_rate_hz: f64,
    /// The chart's radius there (null when infinite).
    pub spectral_radius: Option<f64>,
    /// What the run did.
    pub outcome: &'static str,
}

/// The output paths in `dir`; refuses a path that exists and is not a regular file (a FIFO
/// would block the write) and one that is one of the inputs: the scenario file or a data file
/// it names (`field.path`, `field.paths`; absolute once the scenario is built).
fn output_path(dir: &Path, name: &str, inputs: &[PathBuf]) -> Result<PathBuf, Failure> {
    let p = dir.join(name);
    if let Some(message) = crate::output::input_clash(inputs, &p) {
        return Err(usage(message));
    }
    // Read with lstat: a symbolic link is refused, never written through (a hostile review:
    // the chart's files followed a link planted in DIR).
    isotrack_runs::files::refuse_non_regular(&p).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", p.display()),
    })?;
    Ok(p)
}

/// A figure drawn into its temporary file beside `path` ([`draw_temp`]), put in place by
/// [`Drawn::put_in_place`] (a rename) inside the step that replaces the chart's table
/// ([`replace_chart`]); dropped before that, the temporary is removed.
struct Drawn {
    /// The temporary file holding the figure.
    tmp: PathBuf,
    /// Where it goes.
    path: PathBuf,
    /// Removes `tmp` if the command is interrupted before it is renamed (att43-14).
    _pending: isotrack_runs::cleanup::Pending,
    /// Whether `tmp` was renamed to `path`.
    placed: bool,
}

impl Drawn {
    /// Renames the figure over its path (a link there is replaced, never followed).
    fn put_in_place(mut self) -> Result<(), Failure> {
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Failure {
            code: exit::CANTCREAT,
            message: format!("cannot write {}: {e}", self.path.display()),
        })?;
        self.placed = true;
        Ok(())
    }
}

impl Drop for Drawn {
    fn drop(&mut self) {
        if !self.placed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Draws a figure into a temporary file beside `path` (as `isotrack_runs::files::write_atomic`),
/// nothing replaced yet: the chart's table and both figures are then put in place in one step
/// an interrupt never cuts (att48-1: each figure was renamed as it was drawn, after the new
/// table, so Ctrl-C while drawing left the new table beside the earlier chart's figures). An
/// interrupt while drawing removes the temporary and ends the process (exit 130): a drawing that
/// fails then is waited out, never reported (att48-1: "cannot draw ...tmp.png: No such file").
fn draw_temp(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), isotrack_plot::PlotError>,
) -> Result<Drawn, String> {
    isotrack_runs::files::refuse_non_regular(path).map_err(|e| e.to_string())?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The drawing library picks nothing from the name, but keep the extension anyway.
    let tmp = isotrack_runs::files::temp_beside(path).with_extension(format!("tmp.{ext}"));
    // An old temporary (or a link planted there) goes first; then the file is created here,
    // without following a link, before the library opens it.
    let _ = std::fs::remove_file(&tmp);
    let drawn = Drawn {
        _pending: isotrack_runs::cleanup::register(&tmp),
        tmp,
        path: path.to_path_buf(),
        placed: false,
    };
    let result = isotrack_runs::files::create_output(&drawn.tmp)
        .map_err(|e| e.to_string())
        .and_then(|_| draw(&drawn.tmp).map_err(|e| e.to_string()));
    if result.is_err() && isotrack_runs::cleanup::exiting() {
        // The interrupt removed the temporary under the drawing: it ends the process.
        isotrack_runs::cleanup::wait_for_exit();
    }
    result.map(|()| drawn)
}

fn cell_row(map: &StabilityMap, idx: usize) -> Vec<String> {
    let nk = map.kps.len();
    let (kp, rate) = (map.kps[idx % nk], map.rates_hz[idx / nk]);
    let c = &map.cells[idx];
    vec![
        num(kp),
        num(rate),
        num(1.0 / rate),
        c.spectral_radius.map(num).unwrap_or_default(),
        c.status.stable().map(|b| b.to_string()).unwrap_or_default(),
        c.status.as_str().to_string(),
        num(c.slope_range[0]),
        num(c.slope_range[1]),
        c.note.unwrap_or_default().to_string(),
    ]
}

fn verify_row(k: usize, p: &VerifyPoint) -> Vec<String> {
    vec![
        k.to_string(),
        num(p.kp),
        num(p.rate_hz),
        p.cell.spectral_radius.map(num).unwrap_or_default(),
        p.cell.status.as_str().to_string(),
        p.behaviour.as_str().to_string(),
        p.agrees.map(|b| b.to_string()).unwrap_or_default(),
        p.near_boundary.to_string(),
        p.error_range.map(num).unwrap_or_default(),
        p.mean_abs_turn_radps.map(num).unwrap_or_default(),
        p.detail.clone(),
    ]
}

fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl Iterator<Item = Vec<String>>,
) -> Result<(), Failure> {
    let cant = |e: String| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", path.display()),
    };
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    w.write_record(header).map_err(|e| cant(e.to_string()))?;
    for r in rows {
        w.write_record(&r).map_err(|e| cant(e.to_string()))?;
    }
    let bytes = w.into_inner().map_err(|e| cant(e.to_string()))?;
    // Replaced by rename and recorded as written (att42-8): a later `check --map` tells it
    // from the user's edit.
    isotrack_runs::owned::write_table(path, &bytes).map_err(|e| cant(e.to_string()))
}

/// Writes the chart's table `stability_map.csv` and puts its figures (drawn into their
/// temporaries) in place, removing an earlier `verify.csv`, all in one step an interrupt never
/// cuts ([`isotrack_runs::cleanup::whole`]): after Ctrl-C the directory holds the earlier chart
/// whole or the new one (att46-12: verify.csv was removed up front; att48-1: the figures were
/// renamed after the table, one by one, so Ctrl-C left the new table beside the earlier
/// figures).
/// `placed` is set in that step once the new chart is in place.
fn replace_chart(
    out: &ChartFiles,
    map: &StabilityMap,
    figures: Vec<Drawn>,
    placed: &std::sync::atomic::AtomicBool,
) -> Result<(), Failure> {
    let removed = isotrack_runs::cleanup::whole(|| {
        let removed = isotrack_runs::owned::remove_table(&out.verify_csv).map_err(|e| Failure {
            code: exit::CANTCREAT,
            message: format!("cannot remove {}: {e}", out.verify_csv.display()),
        })?;
        write_csv(
            &out.csv,
            &MAP_COLUMNS,
            (0..map.cells.len()).map(|i| cell_row(map, i)),
        )?;
        for f in figures {
            f.put_in_place()?;
        }
        placed.store(true, std::sync::atomic::Ordering::SeqCst);
        Ok::<bool, Failure>(removed)
    })?;
    if removed {
        errln!(
            "note: removed {} from an earlier check --map (it described another chart)",
            out.verify_csv.display()
        );
    }
    Ok(())
}

/// Registers the line `check --map --verify n` says when interrupted after its new chart is in
/// place (`placed`) and before the verify runs answer the signal themselves
/// ([`verify_runs_of`]'s flag; from then on the command reports the runs that finished): none
/// of the `n` runs finished (att51-1: it exited 130 without a word on the verify).
fn say_no_run_on_interrupt(
    n: usize,
    placed: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> isotrack_runs::cleanup::OnInterrupt {
    isotrack_runs::cleanup::on_interrupt(move || {
        if placed.load(std::sync::atomic::Ordering::SeqCst) {
            errln!(
                "interrupted during --verify: 0 of {n} runs finished; the chart holds what was done (no verify.csv: no run finished)"
            );
        }
    })
}

/// Computes and writes the chart (and `--verify`), returns what was written.
pub fn write_map(
    args: &CheckArgs,
    scenario: &Scenario,
    parsed: MapOptions,
) -> Result<MapReport, Failure> {
    let dir = args
        .out
        .as_deref()
        .ok_or_else(|| usage("--map needs --out DIR".into()))?;
    let family = LoopFamily::new(scenario, args.tube_halfwidth).map_err(|note| Failure {
        code: exit::DATAERR,
        message: format!("no stability chart: {note}"),
    })?;
    let grid = map_grid(args, scenario, &family, parsed)?;
    let png_style = crate::figures::style(&args.look, isotrack_plot::Format::Png)?;
    let svg_style = crate::figures::style(&args.look, isotrack_plot::Format::Svg)?;
    // Held to the end.
    let (_lock, [csv, png, svg, verify_csv]) = open_map_dir(args, scenario, dir)?;
    let out = ChartFiles {
        csv,
        png,
        svg,
        verify_csv,
        png_style,
        svg_style,
    };
    let pool = crate::sweep::worker_pool(args.threads)?;
    // Each cell is a pure function of its point: the same bits on any thread count.
    let points = StabilityMap::points(&grid);
    let cells = pool.install(|| {
        points
            .par_iter()
            .map(|&(k, r)| family.cell(k, r))
            .collect::<Vec<_>>()
    });
    let map = StabilityMap::from_cells(&family, grid, cells);
    // The chart is written before any verification run starts: an interrupted --verify keeps
    // it (the figure without the runs' marks).
    let figures = out.draw(&map, &[])?;
    let mut files = vec![out.csv.display().to_string()];
    files.extend(figures.iter().map(|f| f.path.display().to_string()));
    let placed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let _said = args
        .verify
        .map(|n| say_no_run_on_interrupt(n, placed.clone()));
    replace_chart(&out, &map, figures, &placed)?;
    let (verify, verify_runs, far) = match args.verify {
        Some(n) => {
            let (agreement, runs, far) =
                verify_chart(n, scenario, &grid, family, pool, &map, &out)?;
            files.push(out.verify_csv.display().to_string());
            (Some(agreement), Some(runs), far)
        }
        None => (None, None, vec![]),
    };
    let count = |st: isotrack_scenario::check::map::CellStatus| {
        map.cells.iter().filter(|c| c.status == st).count()
    };
    use isotrack_scenario::check::map::CellStatus as S;
    Ok(MapReport {
        files,
        grid,
        slope_basis: map.slope_basis,
        cells_stable: count(S::Stable),
        cells_unstable: count(S::Unstable),
        cells_no_equilibrium: count(S::NoEquilibrium),
        cells_not_computed: count(S::NotComputed),
        verify,
        verify_runs,
        disagreements_far: far,
    })
}

/// The chart's files (as [`open_map_dir`] named them) and the styles of its figures.
struct ChartFiles {
    /// `stability_map.csv`.
    csv: PathBuf,
    /// `stability_map.png`.
    png: PathBuf,
    /// `stability_map.svg`.
    svg: PathBuf,
    /// `verify.csv`.
    verify_csv: PathBuf,
    /// The PNG's style.
    png_style: isotrack_plot::Style,
    /// The SVG's style.
    svg_style: isotrack_plot::Style,
}

impl ChartFiles {
    /// Draws the chart with the `verified` runs' marks as PNG and SVG into their temporaries
    /// ([`draw_temp`]), for the caller to put in place with the table they go with.
    fn draw(&self, map: &StabilityMap, verified: &[VerifyPoint]) -> Result<Vec<Drawn>, Failure> {
        let mut figures = vec![];
        for (path, style) in [(&self.png, &self.png_style), (&self.svg, &self.svg_style)] {
            let drawn = draw_temp(path, |tmp| {
                isotrack_plot::stability_map_figure(map, verified, tmp, style)
            })
            .map_err(|e| Failure {
                code: exit::CANTCREAT,
                message: format!("cannot write {}: {e}", path.display()),
            })?;
            figures.push(drawn);
        }
        Ok(figures)
    }
}

/// `--verify n`: the runs at points of the chart, `verify.csv` written, and the chart redrawn
/// (the same files) with their marks when all finished (an interrupted check keeps the plain
/// chart: it answers Ctrl-C without drawing again). Returns the agreement over the runs
/// that finished, how many did, and those that disagree away from the boundary.
fn verify_chart(
    n: usize,
    scenario: &Scenario,
    grid: &MapGrid,
    family: LoopFamily,
    pool: rayon::ThreadPool,
    map: &StabilityMap,
    out: &ChartFiles,
) -> Result<(Agreement, VerifyRuns, Vec<FarDisagreement>), Failure> {
    let seed = scenario.spec().sim.seed;
    let at = verify_points(grid, family.dt_s(), n, seed);
    let (verified, partial) = verify_runs_of(family, pool, at, n);
    let points: Vec<VerifyPoint> = verified.iter().map(|(_, p)| p.clone()).collect();
    // The figures with the runs' marks go in place with verify.csv, in one step (att48-1).
    let figures = if partial {
        vec![]
    } else {
        out.draw(map, &points)?
    };
    isotrack_runs::cleanup::whole(|| {
        for f in figures {
            f.put_in_place()?;
        }
        write_csv(
            &out.verify_csv,
            &VERIFY_COLUMNS,
            verified.iter().map(|(k, v)| verify_row(*k, v)),
        )
    })?;
    let runs = VerifyRuns {
        requested: n,
        finished: verified.len(),
        partial,
    };
    Ok((agreement(&points), runs, far_disagreements(&verified)))
}

/// The chart's grid: the scenario's default ranges, replaced by `--kp-range`, `--rate-range`
/// and `--map-size`, checked (and with `--verify`, checked to hold a whole-step rate and a
/// bounded number of steps).
fn map_grid(
    args: &CheckArgs,
    scenario: &Scenario,
    family: &LoopFamily,
    parsed: MapOptions,
) -> Result<MapGrid, Failure> {
    let mut grid = MapGrid::default_for(family);
    let MapOptions {
        kp_range: kp,
        rate_range_hz: rate,
        size,
    } = parsed;
    match kp {
        Some(r) => grid.kp_range = r,
        // The default range is the scenario's kp / 100 .. 100 kp: the key is named when it
        // cannot make one (a hostile review's controller.kp = 1e-310, a subnormal number).
        None if !(grid.kp_range[0].is_normal() && grid.kp_range[1].is_finite()) => {
            return Err(usage(format!(
                "controller.kp = {}: the chart's default kp range kp/100 .. 100*kp = {} .. {} is not a range of normal positive numbers (subnormal below {:e}); give --kp-range LO:HI",
                Echo(family.kp()),
                Echo(grid.kp_range[0]),
                Echo(grid.kp_range[1]),
                f64::MIN_POSITIVE
            )));
        }
        None => {}
    }
    if let Some(r) = rate {
        grid.rate_range_hz = r;
    }
    if let Some((n, m)) = size {
        grid.kp_points = n;
        grid.rate_points = m;
    }
    grid.validate(family.dt_s()).map_err(usage)?;
    if let Some(n) = args.verify {
        // A run samples at 1/(k dt) only: a chart with no such rate cannot be verified (its
        // runs would fall outside it: a hostile review's silent clamp).
        let [lo, hi] = isotrack_scenario::check::map::whole_step_periods(&grid, family.dt_s());
        if lo > hi {
            return Err(usage(format!(
                "--verify: no sensor rate in --rate-range {}:{} Hz is a whole number of sim.dt_s = {} s steps (rates 1/(k dt)): widen the range",
                Echo(grid.rate_range_hz[0]),
                Echo(grid.rate_range_hz[1]),
                Echo(family.dt_s())
            )));
        }
        let steps = n as f64 * steps_per_run(scenario);
        if steps > MAX_VERIFY_STEPS {
            return Err(usage(format!(
                "--verify {n}: {n} runs of {} steps each is {steps:.3e} simulation steps; at most {MAX_VERIFY_STEPS:e} (fewer runs or a shorter sim.duration_s)",
                steps_per_run(scenario)
            )));
        }
    }
    Ok(grid)
}

/// Refuses (73) a `stability_map.csv` or a `verify.csv` that isotrack did not write, or that
/// was edited since ([`isotrack_runs::owned::refuse_foreign_csv`]: its size and SHA-256 are not
/// those the directory's record holds, or no record there holds it).
fn refuse_foreign_tables(csv: &Path, verify: &Path) -> Result<(), Failure> {
    isotrack_runs::owned::refuse_foreign_csv(csv, "an isotrack stability chart's table")?;
    isotrack_runs::owned::refuse_foreign_csv(verify, "an isotrack verification table")
}

/// The chart directory's lock, with the directories [`open_map_dir`] created, registered for
/// removal on an interrupt while empty; both held to the end.
type MapDirLock = (crate::sweep::DirLock, Vec<isotrack_runs::cleanup::Pending>);

/// `dir` created and locked, and the chart's files in it (`stability_map.csv`, `.png`, `.svg`,
/// `verify.csv`), none of them an input nor a file of the user's (a table or figure isotrack
/// did not write: [`refuse_foreign_tables`], the figures' mark). Nothing in it is changed.
fn open_map_dir(
    args: &CheckArgs,
    scenario: &Scenario,
    dir: &Path,
) -> Result<(MapDirLock, [PathBuf; 4]), Failure> {
    let cant = |what: &Path, e: String| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", what.display()),
    };
    // Each directory this creates is removed again (when empty) if the command is interrupted
    // (att48-5), as `run --out`'s; held with the lock.
    let created =
        isotrack_runs::cleanup::create_dir_all(dir).map_err(|e| cant(dir, e.to_string()))?;
    // One writer per directory, as `sweep`, `merge` and `benchmark`: a second `check --map`
    // on DIR exits 73 instead of interleaving its files with this one's.
    let lock = (crate::sweep::lock_output_dir(dir, "check --map")?, created);
    let input = crate::output::input_files(args.scenario.scenario.as_deref(), scenario);
    let csv_path = output_path(dir, "stability_map.csv", &input)?;
    let png_path = output_path(dir, "stability_map.png", &input)?;
    let svg_path = output_path(dir, "stability_map.svg", &input)?;
    // `verify.csv` belongs to the chart it was made with: an earlier run's is removed as the
    // new chart's table replaces the earlier one ([`write_map`]; without --verify it would sit
    // beside a chart it does not describe; with --verify and an interruption, beside a chart
    // it was not made for).
    let verify_path = output_path(dir, "verify.csv", &input)?;
    // att41-11: whose files are these, before anything is computed or removed? A table no
    // record shows isotrack wrote as it is, or a figure without isotrack's mark (or edited
    // since it was drawn), is the user's: refused (73, naming it), every file as it was (the
    // lock removed as it drops). att44-11: an unmarked figure is never isotrack's, whatever
    // table is beside it (att42-2 took one beside an unrecorded chart table for an older
    // isotrack's, and a copy made without the record passed for that).
    refuse_foreign_tables(&csv_path, &verify_path)?;
    for name in ["stability_map.png", "stability_map.svg"] {
        isotrack_plot::refuse_foreign_figure(&dir.join(name)).map_err(|message| Failure {
            code: exit::CANTCREAT,
            message,
        })?;
    }
    Ok((lock, [csv_path, png_path, svg_path, verify_path]))
}

/// The `n` `--verify` runs at `at`, on `pool`, in a thread of their own (each sent back as it
/// finishes): each with its index (its row in `verify.csv`), and whether Ctrl-C (or SIGTERM,
/// SIGHUP) stopped them before all finished.
fn verify_runs_of(
    family: LoopFamily,
    pool: rayon::ThreadPool,
    at: Vec<(f64, f64)>,
    n: usize,
) -> (Vec<(usize, VerifyPoint)>, bool) {
    // Ctrl-C (or SIGTERM, SIGHUP) from here on stops the runs not yet started; the runs
    // that finished are reported (marked partial) and written, and the command exits
    // 128 + the signal.
    let stop = isotrack_runs::signals::interrupt_flag();
    let stopped = || stop.load(std::sync::atomic::Ordering::SeqCst);
    // The runs go on a thread of their own, each sent back as it finishes, and this
    // one answers Ctrl-C at once: a run in progress (it may take minutes) is abandoned,
    // never awaited (a hostile review: 18 s to answer, a second Ctrl-C ignored);
    // returning ends the process.
    let family = std::sync::Arc::new(family);
    let (tx, rx) = std::sync::mpsc::channel::<(usize, VerifyPoint)>();
    {
        let (family, stop) = (family.clone(), stop.clone());
        std::thread::spawn(move || {
            let stopped = || stop.load(std::sync::atomic::Ordering::SeqCst);
            pool.install(|| {
                at.par_iter()
                    .enumerate()
                    .for_each_with(tx, |tx, (i, &(k, r))| {
                        if !stopped() {
                            let _ = tx.send((i, verify_point(&family, k, r)));
                        }
                    });
            });
        });
    }
    let mut slots: Vec<Option<VerifyPoint>> = vec![None; n];
    let mut left = n;
    while left > 0 {
        match rx.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok((i, p)) => {
                if slots[i].replace(p).is_none() {
                    left -= 1;
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) if !stopped() => {}
            Err(_) => break,
        }
    }
    let partial = left > 0 || stopped();
    // Each run keeps its index (its row in verify.csv): the same numbers on any
    // thread count, and a partial file names which runs it holds.
    let verified: Vec<(usize, VerifyPoint)> = slots
        .into_iter()
        .enumerate()
        .filter_map(|(i, p)| p.map(|p| (i, p)))
        .collect();
    (verified, partial)
}

/// The runs that disagree with the chart away from its stability boundary.
fn far_disagreements(v: &[(usize, VerifyPoint)]) -> Vec<FarDisagreement> {
    v.iter()
        .filter(|(_, p)| p.agrees == Some(false) && !p.near_boundary)
        .map(|(k, p)| FarDisagreement {
            run: *k,
            kp: p.kp,
            sensor_rate_hz: p.rate_hz,
            spectral_radius: p.cell.spectral_radius,
            outcome: p.behaviour.as_str(),
        })
        .collect()
}

/// The lines `check --map` prints after the report (the user's numbers echoed as written:
/// [`Echo`], never a 309-digit expansion of `1e308`).
pub fn print_report(m: &MapReport) {
    let g = &m.grid;
    outln!(
        "Stability chart: {} x {} points, kp {} .. {}, sensor rate {} .. {} Hz, radius on {}: {} stable, {} unstable, {} without equilibrium, {} not computed",
        g.kp_points,
        g.rate_points,
        Echo(g.kp_range[0]),
        Echo(g.kp_range[1]),
        Echo(g.rate_range_hz[0]),
        Echo(g.rate_range_hz[1]),
        m.slope_basis,
        m.cells_stable,
        m.cells_unstable,
        m.cells_no_equilibrium,
        m.cells_not_computed
    );
    if let (Some(a), Some(runs)) = (&m.verify, &m.verify_runs) {
        let finished = if runs.partial {
            format!(
                "PARTIAL (interrupted): {} of {} runs finished; ",
                runs.finished, runs.requested
            )
        } else {
            String::new()
        };
        let runs_word = |n: usize| {
            if n == 1 {
                "1 run".to_string()
            } else {
                format!("{n} runs")
            }
        };
        outln!(
            "  verify: {finished}{} compared, {} agree{} (predicted stable: {}; predicted unstable: {}); disagreements near the boundary (the mode changes by less than e^{} over the run): {}, further: {}; not compared: {} in all ({} left the field, {} saturated the turn-rate limit, which the linear chart leaves out, {} too short to judge against the loop's time scale, {} in cells not computed, {} invalid)",
            runs_word(a.compared),
            a.agree,
            a.percent.map_or_else(String::new, |p| format!(" ({p:.1} %)")),
            side_text(a.predicted_stable),
            side_text(a.predicted_unstable),
            NEAR_BOUNDARY_E_FOLDS,
            a.disagreements_near_boundary,
            a.disagreements_far,
            a.not_compared,
            a.left_field,
            a.saturated,
            a.undetermined,
            a.not_computed,
            a.invalid
        );
        for d in &m.disagreements_far {
            outln!(
                "    far from the boundary: run {} at kp {}, {} Hz, {}: {}",
                d.run,
                Num(d.kp),
                Num(d.sensor_rate_hz),
                d.spectral_radius.map_or_else(
                    || "no equilibrium".to_string(),
                    |r| format!("spectral radius {}", Num(r))
                ),
                d.outcome
            );
        }
    }
    outln!("  wrote {}", m.files.join(", "));
}

/// One prediction's agreement as text: `A of N agree (P %)`, or `none compared`.
fn side_text(a: isotrack_scenario::check::map::SideAgreement) -> String {
    match a.percent {
        Some(p) => format!("{} of {} agree ({p:.1} %)", a.agree, a.compared),
        None => "none compared".to_string(),
    }
}
