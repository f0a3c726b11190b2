//! `isotrack plot`, `isotrack run --plot` and `isotrack figures`.

use crate::cli::{FigureOptions, FiguresArgs, ImageFormat, PlotArgs};
use crate::exit;
use crate::output::{scenario_toml, RunDir, Summary};
use isotrack_core::numtext::Echo;
use isotrack_plot::{
    field_map, timeseries_figure, trajectory_figure, Colormap, Format, Panels, PlotError, RunData,
    Style,
};
use isotrack_runs::Failure;
use isotrack_scenario::{load_scenario, Scenario};
use std::path::{Path, PathBuf};

fn failure(e: PlotError) -> Failure {
    match e {
        PlotError::Input(m) => Failure {
            code: exit::NOINPUT,
            message: m,
        },
        PlotError::Data(m) => Failure {
            code: exit::DATAERR,
            message: m,
        },
        PlotError::Draw { .. } => Failure {
            code: exit::CANTCREAT,
            message: e.to_string(),
        },
    }
}

/// The most pixels of one output image (about 150 MB of RGB): `--size` x (`--dpi`/100)^2.
pub const MAX_OUTPUT_PIXELS: f64 = 5e7;

/// The largest default figure size, px at 100 dpi (a map in PNG; `Style::pixel_size`).
const DEFAULT_LARGEST_SIZE_PX: (u32, u32) = (1100, 900);

/// The figure style from the options, every value checked (a usage error names the flag).
pub fn style(o: &FigureOptions, format: Format) -> Result<Style, Failure> {
    let usage = |m: String| Failure {
        code: exit::USAGE,
        message: m,
    };
    let mut st = Style::new(format);
    if let Some(sz) = &o.size {
        let parsed = sz
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)))
            .filter(|(w, h)| (200..=10_000).contains(w) && (150..=10_000).contains(h));
        st.size_px = Some(parsed.ok_or_else(|| {
            usage(format!(
                "--size {sz}: expected WxH in pixels, 200..10000 x 150..10000 (e.g. 800x600)"
            ))
        })?);
    }
    if let Some(f) = o.font_size {
        if !(f.is_finite() && (4.0..=200.0).contains(&f)) {
            return Err(usage(format!(
                "--font-size must be 4..200 px, got {}",
                Echo(f)
            )));
        }
        st.font_px = Some(f);
    }
    if !(o.dpi.is_finite() && (25.0..=1200.0).contains(&o.dpi)) {
        return Err(usage(format!(
            "--dpi must be 25..1200, got {}",
            Echo(o.dpi)
        )));
    }
    st.dpi = o.dpi;
    // Each bounded alone, size and dpi multiply: a PNG's pixel count is bounded too (a hostile
    // review: 10000x10000 at 600 dpi overflowed the drawing library's index, 300 dpi took 8 GB).
    let (w, h) = st.size_px.unwrap_or(DEFAULT_LARGEST_SIZE_PX);
    let scale = st.scale();
    let pixels = f64::from(w) * scale * f64::from(h) * scale;
    if pixels > MAX_OUTPUT_PIXELS {
        return Err(usage(format!(
            "--size {w}x{h} at --dpi {} makes a {:.0} x {:.0} px image ({:.1e} pixels): at most {MAX_OUTPUT_PIXELS:.0e}; lower --dpi or --size",
            Echo(o.dpi),
            f64::from(w) * scale,
            f64::from(h) * scale,
            pixels
        )));
    }
    let name = o.colormap.as_deref().unwrap_or("viridis");
    st.colormap = Colormap::from_name(name).ok_or_else(|| {
        usage(format!(
            "--colormap {}: expected viridis, gray, bone or copper",
            isotrack_scenario::load::clip(name)
        ))
    })?;
    // Bounded and escaped as every echoed text (a hostile review: a 100 000-character title
    // with control characters went into the figures as given).
    st.title = o.title.as_deref().map(isotrack_scenario::load::clip);
    Ok(st)
}

/// Refuses (73) when one of `names` in `out` is a file isotrack did not write (no isotrack
/// mark: the user's own `trajectory.png` in a folder that never held a run, att38-9), before
/// any figure is drawn.
pub fn refuse_foreign_figures(out: &Path, names: &[String]) -> Result<(), Failure> {
    for n in names {
        isotrack_plot::refuse_foreign_figure(&out.join(n)).map_err(|message| Failure {
            code: exit::CANTCREAT,
            message,
        })?;
    }
    Ok(())
}

/// The run figures `plot_dirs` writes in `format` for `team` (a team's run drawn alone adds
/// `team.*`).
pub fn run_figure_names(format: Format, team: bool) -> Vec<String> {
    let ext = format.extension();
    let mut names = vec![format!("trajectory.{ext}"), format!("timeseries.{ext}")];
    if team {
        names.push(format!("team.{ext}"));
    }
    names
}

/// A run directory's name as a figure's title when its scenario has no `name` (as
/// [`RunData`] names a single run): a team's run is titled by its directory too, not by its
/// first vehicle's label `vehicle 0` (nu36-11).
fn dir_label(dir: &Path) -> String {
    dir.file_name().map_or_else(
        || dir.display().to_string(),
        |n| isotrack_core::numtext::Escaped(&n.to_string_lossy()).to_string(),
    )
}

/// Registers the line said when the drawing of `runs` into `out` is interrupted (att51-2: `run
/// --out NEW --plot` stopped while drawing said nothing of the figures): which of `names` were
/// drawn (put in place since this call: another file there than before) and which not, and the
/// `plot` command that draws them; nothing once all are drawn.
fn say_figures_on_interrupt(
    runs: &[PathBuf],
    out: &Path,
    format: Format,
    names: Vec<String>,
) -> isotrack_runs::cleanup::OnInterrupt {
    use isotrack_runs::files::identity;
    use isotrack_runs::owned::shell_quoted;
    let was: Vec<_> = names.iter().map(|n| identity(&out.join(n))).collect();
    let mut cmd = format!(
        "isotrack plot {}",
        runs.iter()
            .map(|r| shell_quoted(r))
            .collect::<Vec<_>>()
            .join(" ")
    );
    if !(runs.len() == 1 && same_dir(out, &runs[0])) {
        cmd += &format!(" --out {}", shell_quoted(out));
    }
    if format == Format::Svg {
        cmd += " --format svg";
    }
    let out = out.to_path_buf();
    isotrack_runs::cleanup::on_interrupt(move || {
        let (drawn, not): (Vec<_>, Vec<_>) = names.iter().zip(&was).partition(|(n, before)| {
            let now = identity(&out.join(n));
            now.is_some() && now != **before
        });
        let list = |v: Vec<(&String, _)>| {
            v.into_iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if drawn.is_empty() {
            errln!("interrupted before the figures were drawn: `{cmd}` draws them");
        } else if !not.is_empty() {
            errln!(
                "interrupted while drawing the figures: {} drawn, {} not: `{cmd}` draws them all",
                list(drawn),
                list(not)
            );
        }
    })
}

/// The team figure (`team.*`) of one team's run directory plotted alone, its path; else the
/// note saying why none is drawn (the run's own reason, or several directories together).
fn team_figure_or_note(
    runs: &[PathBuf],
    data: &[RunData],
    out: &Path,
    st: &Style,
    title: &str,
) -> Result<Option<String>, Failure> {
    let ext = st.format.extension();
    if runs.len() == 1 && RunData::is_team(&runs[0]) {
        if isotrack_plot::TeamTracks::new(data).is_some() {
            let team = out.join(format!("team.{ext}"));
            isotrack_plot::team_figure(data, &team, st, title).map_err(failure)?;
            return Ok(Some(team.display().to_string()));
        } else {
            // nu36-10: the run's own reason (summary.json's team.metrics_note), not an
            // either/or whose first clause may be false.
            let why = data[0]
                .summary
                .team()
                .and_then(|t| t.metrics_note.clone())
                .map(|n| n.trim_start_matches("no team metrics: ").to_string())
                .unwrap_or_else(|| "the run recorded no team metrics".to_string());
            errln!(
                "note: no team figure (gaps, revisit time): {}",
                isotrack_scenario::load::clip(&why)
            );
        }
    } else if runs.len() > 1 {
        // nu36-16: several run directories, a team's among them: its team figure is drawn
        // from it alone, said rather than dropped without a word.
        let teams: Vec<String> = runs
            .iter()
            .filter(|d| RunData::is_team(d))
            .map(|d| d.display().to_string())
            .collect();
        if !teams.is_empty() {
            errln!(
                "note: no team figure (gaps, revisit time): team.{ext} is drawn for one team's run directory plotted alone (`isotrack plot {}`), not for {} directories together",
                teams[0],
                runs.len()
            );
        }
    }
    Ok(None)
}

/// Plots run directories into `out` (`trajectory.*`, `timeseries.*`).
pub fn plot_dirs(runs: &[PathBuf], st: &Style, out: &Path) -> Result<Vec<String>, Failure> {
    let format = st.format;
    // Said from the start, while the runs are still being read (att53o-5: `run --plot`
    // interrupted while its 3e6-sample trace was read back said nothing of the figures); the
    // team figure's name is known once they are read, and the note is registered again then.
    let early = say_figures_on_interrupt(runs, out, format, run_figure_names(format, false));
    // A team's run is its vehicles, each drawn as a run (issue 32).
    let data: Vec<RunData> = runs
        .iter()
        .map(|d| RunData::load_team_named(d, runs.len() > 1))
        .collect::<Result<Vec<_>, _>>()
        .map_err(failure)?
        .into_iter()
        .flatten()
        .collect();
    // Runs over different fields, or a data file changed after a run: 65 naming it (before any
    // figure is written).
    isotrack_plot::same_field(&data).map_err(failure)?;
    if let Some(n) = isotrack_plot::unrecorded_data_files_note(&data) {
        errln!("warning: {n}");
    }
    refuse_foreign_figures(
        out,
        &run_figure_names(format, runs.len() == 1 && RunData::is_team(&runs[0])),
    )?;
    // Each directory this creates is removed again (when empty) if the command is
    // interrupted (att48-5); held to the end.
    let _created = isotrack_runs::cleanup::create_dir_all(out).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot create {}: {e}", out.display()),
    })?;
    let team_drawn = runs.len() == 1
        && RunData::is_team(&runs[0])
        && isotrack_plot::TeamTracks::new(&data).is_some();
    // The early note gives way (an interrupt already under way keeps it, and says it alone).
    let _said = (!isotrack_runs::cleanup::exiting())
        .then(|| say_figures_on_interrupt(runs, out, format, run_figure_names(format, team_drawn)));
    drop(early);
    // One run directory (a team's too: its vehicles are drawn as runs) is titled by its
    // scenario.
    let title = if runs.len() == 1 {
        data[0]
            .scenario
            .file()
            .name
            .clone()
            .unwrap_or_else(|| dir_label(&runs[0]))
    } else {
        format!("{} runs", data.len())
    };
    let ext = format.extension();
    let traj = out.join(format!("trajectory.{ext}"));
    let ts = out.join(format!("timeseries.{ext}"));
    trajectory_figure(&data, &traj, st, &title).map_err(failure)?;
    timeseries_figure(&data, &ts, st, &title, Panels::default()).map_err(failure)?;
    let mut written = vec![traj.display().to_string(), ts.display().to_string()];
    written.extend(team_figure_or_note(runs, &data, out, st, &title)?);
    Ok(written)
}

/// `isotrack plot`.
pub fn plot(a: &PlotArgs) -> Result<(), Failure> {
    let format = match a.format {
        ImageFormat::Png => Format::Png,
        ImageFormat::Svg => Format::Svg,
    };
    let st = style(&a.look, format)?;
    let out = a.out.clone().unwrap_or_else(|| a.runs[0].clone());
    let results = a.runs[0].join("results.csv");
    for d in &a.runs {
        if let Err(e) = refuse_neither_run_nor_sweep(d) {
            // A run directory being replaced (`run --out` between removing the old summary
            // and renaming the new one in) reads as neither: the holder of its lock is named
            // (73) rather than a run directory called none (att38-2); a free lock is let go
            // at once. Only where a writer's lock file is (att39-9: a folder plot only reads
            // had a lock file created in it, and a read-only one was refused "cannot lock"
            // instead of this 66); a failure to look at it keeps the 66.
            if d.join(isotrack_runs::sweep::lock::LOCK_FILE).is_file() {
                if let Err(f) = lock_to_draw(d) {
                    if f.message.contains("is writing this directory") {
                        return Err(f);
                    }
                }
            }
            return Err(e);
        }
    }
    if a.runs.len() == 1 && results.exists() {
        // att38-8: a sweep directory is locked as a run directory is (below), before its
        // results are read and until the figure is in place: while `sweep --resume` or
        // `sweep --force` (or a merge) writes it, plot is refused 73 naming the holder, not
        // drawn from the rows so far into the directory whose results.csv then grows. An
        // output directory of its own (`--out`) that exists is locked too.
        let _lock = lock_sweep_to_read(&a.runs[0], &out)?;
        let _out_lock = (out.is_dir() && !same_dir(&out, &a.runs[0]))
            .then(|| lock_to_draw(&out))
            .transpose()?;
        return plot_sweep(a, &results, &out, &st);
    }
    // att36-2: an existing output directory (a run directory drawn into itself, by default) is
    // locked as `run --out` locks it, before a run is read and until the figures are in place:
    // a `run --out` replacing it meanwhile is refused (73), as is this plot while a run (or
    // any other writer) holds it (73, naming the holder), so figures never land beside another
    // run's summary than the one drawn.
    let _lock = out.is_dir().then(|| lock_to_draw(&out)).transpose()?;
    if a.animate {
        refuse_foreign_figures(&out, &["animation.gif".to_string()])?;
    }
    let mut written = plot_dirs(&a.runs, &st, &out)?;
    if a.animate {
        let runs = RunData::load_team(&a.runs[0]).map_err(failure)?;
        let gif = out.join("animation.gif");
        let title = runs[0]
            .scenario
            .file()
            .name
            .clone()
            .unwrap_or_else(|| dir_label(&a.runs[0]));
        isotrack_plot::animation_gif_team(&runs, &gif, &st, &title, 48, 120).map_err(failure)?;
        written.push(gif.display().to_string());
    }
    outln!("wrote {}", written.join(", "));
    Ok(())
}

/// The lock of directory `dir` for `plot` ([`isotrack_runs::sweep::lock::lock_output_dir`]):
/// 73 naming the holder while another command writes it. A lock file that cannot be created (a
/// directory this user cannot write) is said as what it is for plot: no figure can be written
/// there (att38-10: "cannot lock RO/.isotrack.lock: Permission denied" named a file the user
/// never asked for).
fn lock_to_draw(dir: &Path) -> Result<isotrack_runs::sweep::lock::DirLock, Failure> {
    isotrack_runs::sweep::lock::lock_output_dir(dir, "plot").map_err(|mut f| {
        let lock = dir.join(isotrack_runs::sweep::lock::LOCK_FILE);
        if let Some(why) = f
            .message
            .strip_prefix(&format!("cannot lock {}: ", lock.display()))
        {
            f.message = format!(
                "cannot write figures into {}: {why} (creating its lock file {}); give --out a directory you can write",
                dir.display(),
                isotrack_runs::sweep::lock::LOCK_FILE
            );
        }
        f
    })
}

/// The lock of sweep directory `sweep` drawn into `out` ([`lock_to_draw`]), or none when
/// `out` is elsewhere and `sweep` is one this user cannot write (a colleague's sweep, a
/// read-only mount) with no lock file in it: no writer holds it (a writer's lock file is there
/// while it writes, removed as it lets go), and plot only reads it (att40-23: such a sweep was
/// refused 73, "give --out a directory you can write", with --out given). A writer starting
/// after this look is not seen (its owner can still write there).
fn lock_sweep_to_read(
    sweep: &Path,
    out: &Path,
) -> Result<Option<isotrack_runs::sweep::lock::DirLock>, Failure> {
    match lock_to_draw(sweep) {
        Ok(l) => Ok(Some(l)),
        Err(f)
            if !same_dir(out, sweep)
                && std::fs::symlink_metadata(sweep.join(isotrack_runs::sweep::lock::LOCK_FILE))
                    .is_err()
                && f.message.starts_with("cannot write figures into ") =>
        {
            Ok(None)
        }
        Err(f) => Err(f),
    }
}

/// Whether `a` and `b` name one directory (both resolved; the same path when either cannot
/// be): a directory's lock is taken once by one command.
fn same_dir(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// A directory given to `isotrack plot` that is neither a run directory nor a sweep directory:
/// 66 naming what each holds.
fn refuse_neither_run_nor_sweep(d: &Path) -> Result<(), Failure> {
    let is_run = d.join("summary.json").is_file();
    let is_sweep = d.join("results.csv").is_file();
    if !is_run && !is_sweep {
        return Err(Failure {
            code: exit::NOINPUT,
            message: format!(
                "{} is neither a run directory (summary.json, trace.csv, scenario.toml, from `isotrack run --out`) nor a sweep directory (results.csv, from `isotrack sweep --out`)",
                d.display()
            ),
        });
    }
    Ok(())
}

/// `isotrack plot` of a sweep directory: `--metric` against `--x` (by default the first
/// parameter column of `results`), one line per `--group` value, into
/// `sweep_METRIC_vs_X[_by_GROUP].EXT` in `out`, which replaces a file of that name only if it
/// is a figure isotrack wrote ([`refuse_foreign_figures`]).
fn plot_sweep(a: &PlotArgs, results: &Path, out: &Path, st: &Style) -> Result<(), Failure> {
    let x = match &a.x {
        Some(x) => x.clone(),
        None => {
            let f = isotrack_fields::io::open_limited(results, isotrack_plot::MAX_INPUT_BYTES)
                .map_err(|e| Failure {
                    code: exit::NOINPUT,
                    message: format!("{}: {e}", results.display()),
                })?;
            let mut r = csv::Reader::from_reader(f);
            r.headers()
                .ok()
                .and_then(|h| h.get(1).map(str::to_string))
                .unwrap_or_default()
        }
    };
    // A file name from column names: ASCII letters, digits, `_` and `-` only (`.`, `[`,
    // `]`, a `/`, an escape character or a bidi control each become `_`), at most 100
    // characters of each.
    let safe = |k: &str| -> String {
        k.chars()
            .take(100)
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    let name = format!(
        "sweep_{}_vs_{}{}.{}",
        safe(&a.metric),
        safe(&x),
        a.group
            .as_deref()
            .map(|g| format!("_by_{}", safe(g)))
            .unwrap_or_default(),
        st.format.extension()
    );
    // att41-10: the user's own file of the figure's name (no isotrack mark) is refused (73)
    // before anything is drawn, as for a run's figures.
    refuse_foreign_figures(out, std::slice::from_ref(&name))?;
    // Each directory this creates is removed again (when empty) if the command is
    // interrupted (att48-5); held to the end.
    let _created = isotrack_runs::cleanup::create_dir_all(out).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot create {}: {e}", out.display()),
    })?;
    let file = out.join(name);
    isotrack_plot::sweep_figure(results, &x, &a.metric, a.group.as_deref(), &file, st)
        .map_err(failure)?;
    outln!("wrote {}", file.display());
    Ok(())
}

/// Runs `scenario` into `dir` (trace, summary, resolved scenario) and loads it back for plotting.
fn run_into(scenario: &Scenario, dir: &Path, name: &str) -> Result<RunData, Failure> {
    // Locked while written, as `compare` locks each law's directory (att36-9).
    let out = RunDir::open(dir, &[], &[], Some("figures"))?;
    let mut trace = out.trace(scenario.is_flying())?;
    let r = scenario.run(trace.writer());
    let warnings = isotrack_scenario::check::warnings(scenario);
    let summary = Summary::of_run(scenario, None, &r, &warnings);
    out.finish(trace, &scenario_toml(scenario), &summary)?;
    let mut d = RunData::load(dir).map_err(failure)?;
    d.name = name.to_string();
    Ok(d)
}

/// A bundled scenario of `--scenarios DIR`: 66 when it cannot be read (missing, a FIFO), 65
/// when what it holds is invalid, as for every other command ([`crate::load::invalid`]).
fn load(path: &Path, sets: &[String]) -> Result<Scenario, Failure> {
    load_scenario(Some(path), sets).map_err(crate::load::invalid)
}

/// A run behind a paper figure: a bundled scenario with `--set` overrides, its run directory
/// (under `--runs`) and its legend label.
struct PaperRun {
    dir: &'static str,
    scenario: &'static str,
    sets: &'static [&'static str],
    label: &'static str,
}

/// What a paper figure draws.
enum PaperPlot {
    /// The field alone (the first run's field, its extent), target isoline bold.
    FieldMap,
    /// The runs' paths over the field.
    Trajectories,
    /// The runs' time series, these panels.
    TimeSeries(Panels),
}

/// One figure of the paper: the file stem, its title, what it draws and from which runs.
struct PaperFigure {
    stem: &'static str,
    title: &'static str,
    plot: PaperPlot,
    runs: &'static [PaperRun],
}

const FIG2A_RUN: PaperRun = PaperRun {
    dir: "fig2a",
    scenario: "paper-fig2a-field.toml",
    sets: &[],
    label: "Dubins robot, kp = 10, ki = 0",
};
const FIG3_RUN: PaperRun = PaperRun {
    dir: "fig3",
    scenario: "paper-fig3-uav.toml",
    sets: &[],
    label: "fixed-wing UAV, 30 m/s, 1 Hz",
};
/// Fig. 2(b)'s initial states `(x, y, heading)` on the circular field, 200 s each.
const FIG2B_RUNS: &[PaperRun] = &[
    fig2b_run(
        "fig2b_0",
        &[
            "initial.x_m=10",
            "initial.y_m=0",
            "initial.heading_rad=-1.5",
            "sim.duration_s=200",
        ],
        "start (10, 0, -1.5)",
    ),
    fig2b_run(
        "fig2b_1",
        &[
            "initial.x_m=0",
            "initial.y_m=14",
            "initial.heading_rad=0",
            "sim.duration_s=200",
        ],
        "start (0, 14, 0)",
    ),
    fig2b_run(
        "fig2b_2",
        &[
            "initial.x_m=-12",
            "initial.y_m=-6",
            "initial.heading_rad=1.2",
            "sim.duration_s=200",
        ],
        "start (-12, -6, 1.2)",
    ),
    fig2b_run(
        "fig2b_3",
        &[
            "initial.x_m=3",
            "initial.y_m=-2",
            "initial.heading_rad=2.5",
            "sim.duration_s=200",
        ],
        "start (3, -2, 2.5)",
    ),
    fig2b_run(
        "fig2b_4",
        &[
            "initial.x_m=-4",
            "initial.y_m=9",
            "initial.heading_rad=-2",
            "sim.duration_s=200",
        ],
        "start (-4, 9, -2)",
    ),
];
/// Fig. 2(c)'s gains `(kp, ki)` on the circular field, 200 s each.
const FIG2C_RUNS: &[PaperRun] = &[
    fig2b_run(
        "fig2c_kp5_ki0",
        &["controller.kp=5", "controller.ki=0", "sim.duration_s=200"],
        "kp = 5, ki = 0",
    ),
    fig2b_run(
        "fig2c_kp10_ki0",
        &["controller.kp=10", "controller.ki=0", "sim.duration_s=200"],
        "kp = 10, ki = 0",
    ),
    fig2b_run(
        "fig2c_kp20_ki0",
        &["controller.kp=20", "controller.ki=0", "sim.duration_s=200"],
        "kp = 20, ki = 0",
    ),
    fig2b_run(
        "fig2c_kp10_ki1",
        &["controller.kp=10", "controller.ki=1", "sim.duration_s=200"],
        "kp = 10, ki = 1",
    ),
];

const fn fig2b_run(
    dir: &'static str,
    sets: &'static [&'static str],
    label: &'static str,
) -> PaperRun {
    PaperRun {
        dir,
        scenario: "paper-fig2b-circular.toml",
        sets,
        label,
    }
}

/// The paper's figures (Dong & You), in groups: a group's runs are run, then its figures drawn
/// in every format, then the next group.
const PAPER_FIGURES: &[&[PaperFigure]] = &[
    &[
        PaperFigure {
            stem: "fig1a",
            title: "Fig. 1(a): NO2 map (kriged from 74 stations), level 10 bold",
            plot: PaperPlot::FieldMap,
            runs: &[FIG2A_RUN],
        },
        PaperFigure {
            stem: "fig2a",
            title: "Fig. 2(a): Dubins robot on the real map",
            plot: PaperPlot::Trajectories,
            runs: &[FIG2A_RUN],
        },
    ],
    &[
        PaperFigure {
            stem: "fig2b",
            title: "Fig. 2(b): circular field, several initial states",
            plot: PaperPlot::Trajectories,
            runs: FIG2B_RUNS,
        },
        PaperFigure {
            stem: "fig2c",
            title: "Fig. 2(c): tracking error for several (kp, ki)",
            plot: PaperPlot::TimeSeries(Panels {
                error: true,
                measurement: false,
                measurement_rate: false,
                omega: false,
            }),
            runs: FIG2C_RUNS,
        },
        PaperFigure {
            stem: "fig3b",
            title: "Fig. 3(b): fixed-wing UAV on the pollution map",
            plot: PaperPlot::Trajectories,
            runs: &[FIG3_RUN],
        },
        PaperFigure {
            stem: "fig3c",
            title: "Fig. 3(c): UAV tracking error and measurement rate",
            plot: PaperPlot::TimeSeries(Panels {
                error: true,
                measurement: false,
                measurement_rate: true,
                omega: false,
            }),
            runs: &[FIG3_RUN],
        },
    ],
];

/// The extent a field map shows: a grid's own, else the paper's 50 m square.
fn map_extent(s: &Scenario) -> [f64; 4] {
    use isotrack_scenario::field::FieldModel;
    match s.field() {
        FieldModel::Grid(g) => g.grid().extent_m(),
        FieldModel::Series(g) => g.extent_m(),
        FieldModel::Puff(_) | FieldModel::Analytic(_) => [-25.0, 25.0, -25.0, 25.0],
    }
}

/// `isotrack figures`: the paper's figures ([`PAPER_FIGURES`]) from this project's own runs;
/// each run is made once (in the order first needed) and shared by the figures that use it.
pub fn figures(a: &FiguresArgs) -> Result<(), Failure> {
    let formats: Vec<Format> = if a.svg {
        vec![Format::Png, Format::Svg]
    } else {
        vec![Format::Png]
    };
    let styles: Vec<Style> = formats
        .iter()
        .map(|&f| style(&a.look, f))
        .collect::<Result<_, _>>()?;
    // att41-12: a file of a paper figure's name in `--out` that isotrack did not write (the
    // user's own edited `fig2b.png`, no isotrack mark) is refused (73, naming it) before any
    // run, as `plot` refuses a run's figure.
    let names: Vec<String> = formats
        .iter()
        .flat_map(|f| {
            PAPER_FIGURES
                .iter()
                .flat_map(|g| g.iter())
                .map(move |fig| format!("{}.{}", fig.stem, f.extension()))
        })
        .collect();
    refuse_foreign_figures(&a.out, &names)?;
    // Each directory this creates is removed again (when empty) if the command is
    // interrupted (att48-5); held to the end.
    let _created = isotrack_runs::cleanup::create_dir_all(&a.out).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot create {}: {e}", a.out.display()),
    })?;
    let mut done = PaperRuns::default();
    let mut written = vec![];
    for group in PAPER_FIGURES {
        for run in group.iter().flat_map(|f| f.runs) {
            if done.index(run.dir).is_none() {
                let sets: Vec<String> = run.sets.iter().map(|s| s.to_string()).collect();
                let s = load(&a.scenarios.join(run.scenario), &sets)?;
                let d = run_into(&s, &a.runs.join(run.dir), run.label)?;
                done.dirs.push(run.dir);
                done.scenarios.push(s);
                done.data.push(d);
            }
        }
        for st in &styles {
            for fig in group.iter() {
                let path = a
                    .out
                    .join(format!("{}.{}", fig.stem, st.format.extension()));
                draw_paper_figure(fig, &done, &path, st)?;
                written.push(path.display().to_string());
            }
        }
    }
    outln!("wrote {}", written.join("\n      "));
    Ok(())
}

/// The runs made so far for the paper's figures, in the order first needed (so that a
/// figure's runs, listed together, are one slice).
#[derive(Default)]
struct PaperRuns {
    dirs: Vec<&'static str>,
    scenarios: Vec<Scenario>,
    data: Vec<RunData>,
}

impl PaperRuns {
    fn index(&self, dir: &str) -> Option<usize> {
        self.dirs.iter().position(|d| *d == dir)
    }
}

/// Draws `fig` from its runs (already made) into `path`.
fn draw_paper_figure(
    fig: &PaperFigure,
    done: &PaperRuns,
    path: &Path,
    st: &Style,
) -> Result<(), Failure> {
    // The table lists each figure's runs together and they are made in that order, so they
    // are consecutive.
    let first = fig
        .runs
        .first()
        .and_then(|r| done.index(r.dir))
        .unwrap_or(0);
    let data = &done.data[first..(first + fig.runs.len()).min(done.data.len())];
    match &fig.plot {
        PaperPlot::FieldMap => {
            let s = &done.scenarios[first];
            field_map(s, map_extent(s), path, st, fig.title)
        }
        PaperPlot::Trajectories => trajectory_figure(data, path, st, fig.title),
        PaperPlot::TimeSeries(panels) => timeseries_figure(data, path, st, fig.title, *panels),
    }
    .map_err(failure)
}
