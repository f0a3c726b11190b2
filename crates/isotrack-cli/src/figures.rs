//! `isotrack plot`, `isotrack run --plot` and `isotrack figures`.

use crate::cli::{FigureOptions, FiguresArgs, ImageFormat, PlotArgs};
use crate::exit;
use crate::output::{run_to_trace, scenario_toml, write_summary};
use crate::run::Failure;
use isotrack_core::numtext::Echo;
use isotrack_plot::{
    field_map, timeseries_figure, trajectory_figure, Colormap, Format, Panels, PlotError, RunData,
    Style,
};
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

/// Plots run directories into `out`; returns the files written.
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
    st.colormap = Colormap::from_name(&o.colormap).ok_or_else(|| {
        usage(format!(
            "--colormap {}: expected viridis, gray, bone or copper",
            o.colormap
        ))
    })?;
    st.title = o.title.clone();
    Ok(st)
}

/// Plots run directories into `out` (`trajectory.*`, `timeseries.*`).
pub fn plot_dirs(runs: &[PathBuf], st: &Style, out: &Path) -> Result<Vec<String>, Failure> {
    let format = st.format;
    let data: Vec<RunData> = runs
        .iter()
        .map(|d| RunData::load(d))
        .collect::<Result<_, _>>()
        .map_err(failure)?;
    std::fs::create_dir_all(out).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot create {}: {e}", out.display()),
    })?;
    let title = if data.len() == 1 {
        data[0]
            .scenario
            .file()
            .name
            .clone()
            .unwrap_or_else(|| data[0].name.clone())
    } else {
        format!("{} runs", data.len())
    };
    let ext = format.extension();
    let traj = out.join(format!("trajectory.{ext}"));
    let ts = out.join(format!("timeseries.{ext}"));
    trajectory_figure(&data, &traj, st, &title).map_err(failure)?;
    timeseries_figure(&data, &ts, st, &title, Panels::default()).map_err(failure)?;
    Ok(vec![traj.display().to_string(), ts.display().to_string()])
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
    }
    if a.runs.len() == 1 && results.exists() {
        // A sweep: a metric against a swept parameter.
        let x = match &a.x {
            Some(x) => x.clone(),
            None => {
                let f = isotrack_fields::io::open_limited(&results, isotrack_plot::MAX_INPUT_BYTES)
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
        std::fs::create_dir_all(&out).map_err(|e| Failure {
            code: exit::CANTCREAT,
            message: format!("cannot create {}: {e}", out.display()),
        })?;
        let safe = |k: &str| k.replace(['.', '[', ']'], "_");
        let file = out.join(format!(
            "sweep_{}_vs_{}{}.{}",
            a.metric,
            safe(&x),
            a.group
                .as_deref()
                .map(|g| format!("_by_{}", safe(g)))
                .unwrap_or_default(),
            format.extension()
        ));
        isotrack_plot::sweep_figure(&results, &x, &a.metric, a.group.as_deref(), &file, &st)
            .map_err(failure)?;
        outln!("wrote {}", file.display());
        return Ok(());
    }
    let mut written = plot_dirs(&a.runs, &st, &out)?;
    if a.animate {
        let run = RunData::load(&a.runs[0]).map_err(failure)?;
        let gif = out.join("animation.gif");
        let title = run
            .scenario
            .file()
            .name
            .clone()
            .unwrap_or_else(|| run.name.clone());
        isotrack_plot::animation_gif(&run, &gif, &st, &title, 48, 120).map_err(failure)?;
        written.push(gif.display().to_string());
    }
    outln!("wrote {}", written.join(", "));
    Ok(())
}

/// Runs `scenario` into `dir` (trace, summary, resolved scenario) and loads it back for plotting.
fn run_into(scenario: &Scenario, dir: &Path, name: &str) -> Result<RunData, Failure> {
    let cant = |e: std::io::Error| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", dir.display()),
    };
    std::fs::create_dir_all(dir).map_err(cant)?;
    let r = run_to_trace(scenario, &dir.join("trace.csv")).map_err(cant)?;
    write_summary(
        &dir.join("summary.json"),
        scenario,
        None,
        &r,
        &isotrack_scenario::check::warnings(scenario),
    )
    .map_err(cant)?;
    std::fs::write(dir.join("scenario.toml"), scenario_toml(scenario)).map_err(cant)?;
    let mut d = RunData::load(dir).map_err(failure)?;
    d.name = name.to_string();
    Ok(d)
}

/// A bundled scenario of `--scenarios DIR`: 66 when it cannot be read (missing, a FIFO), 65
/// when what it holds is invalid, as for every other command ([`crate::run::invalid`]).
fn load(path: &Path, sets: &[String]) -> Result<Scenario, Failure> {
    load_scenario(Some(path), sets).map_err(crate::run::invalid)
}

/// `isotrack figures`: the paper's figures from this project's own runs.
pub fn figures(a: &FiguresArgs) -> Result<(), Failure> {
    let runs_dir = a.runs.clone();
    std::fs::create_dir_all(&a.out).map_err(|e| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot create {}: {e}", a.out.display()),
    })?;
    let formats: Vec<Format> = if a.svg {
        vec![Format::Png, Format::Svg]
    } else {
        vec![Format::Png]
    };
    let styles: Vec<Style> = formats
        .iter()
        .map(|&f| style(&a.look, f))
        .collect::<Result<_, _>>()?;
    let sc = |n: &str| a.scenarios.join(n);
    let set = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let mut written = vec![];
    let file = |stem: &str, f: Format| a.out.join(format!("{stem}.{}", f.extension()));

    // Fig. 2(a): the Dubins robot on the real concentration map; Fig. 1(a): that map.
    let fig2a = load(&sc("paper-fig2a-field.toml"), &[])?;
    let run2a = run_into(
        &fig2a,
        &runs_dir.join("fig2a"),
        "Dubins robot, kp = 10, ki = 0",
    )?;
    let g = match fig2a.field() {
        isotrack_scenario::field::FieldModel::Grid(g) => g.grid().extent_m(),
        isotrack_scenario::field::FieldModel::Series(g) => g.extent_m(),
        isotrack_scenario::field::FieldModel::Puff(_) => [-25.0, 25.0, -25.0, 25.0],
        isotrack_scenario::field::FieldModel::Analytic(_) => [-25.0, 25.0, -25.0, 25.0],
    };
    for st in &styles {
        let f = st.format;
        field_map(
            &fig2a,
            g,
            &file("fig1a", f),
            st,
            "Fig. 1(a): NO2 map (kriged from 74 stations), level 10 bold",
        )
        .map_err(failure)?;
        trajectory_figure(
            std::slice::from_ref(&run2a),
            &file("fig2a", f),
            st,
            "Fig. 2(a): Dubins robot on the real map",
        )
        .map_err(failure)?;
        written.extend(["fig1a", "fig2a"].map(|n| file(n, f).display().to_string()));
    }

    // Fig. 2(b): several initial states on the circular field.
    let base = sc("paper-fig2b-circular.toml");
    let starts = [
        (10.0, 0.0, -1.5),
        (0.0, 14.0, 0.0),
        (-12.0, -6.0, 1.2),
        (3.0, -2.0, 2.5),
        (-4.0, 9.0, -2.0),
    ];
    let mut runs2b = vec![];
    for (k, (x, y, h)) in starts.iter().enumerate() {
        let s = load(
            &base,
            &set(&[
                &format!("initial.x_m={x}"),
                &format!("initial.y_m={y}"),
                &format!("initial.heading_rad={h}"),
                "sim.duration_s=200",
            ]),
        )?;
        runs2b.push(run_into(
            &s,
            &runs_dir.join(format!("fig2b_{k}")),
            &format!("start ({x}, {y}, {h})"),
        )?);
    }
    // Fig. 2(c): tracking errors for several (kp, ki).
    let mut runs2c = vec![];
    for (kp, ki) in [(5.0, 0.0), (10.0, 0.0), (20.0, 0.0), (10.0, 1.0)] {
        let s = load(
            &base,
            &set(&[
                &format!("controller.kp={kp}"),
                &format!("controller.ki={ki}"),
                "sim.duration_s=200",
            ]),
        )?;
        runs2c.push(run_into(
            &s,
            &runs_dir.join(format!("fig2c_kp{kp}_ki{ki}")),
            &format!("kp = {kp}, ki = {ki}"),
        )?);
    }
    // Fig. 3: the fixed-wing UAV.
    let fig3 = load(&sc("paper-fig3-uav.toml"), &[])?;
    let run3 = run_into(
        &fig3,
        &runs_dir.join("fig3"),
        "fixed-wing UAV, 30 m/s, 1 Hz",
    )?;
    for st in &styles {
        let f = st.format;
        trajectory_figure(
            &runs2b,
            &file("fig2b", f),
            st,
            "Fig. 2(b): circular field, several initial states",
        )
        .map_err(failure)?;
        timeseries_figure(
            &runs2c,
            &file("fig2c", f),
            st,
            "Fig. 2(c): tracking error for several (kp, ki)",
            Panels {
                error: true,
                measurement: false,
                measurement_rate: false,
                omega: false,
            },
        )
        .map_err(failure)?;
        trajectory_figure(
            std::slice::from_ref(&run3),
            &file("fig3b", f),
            st,
            "Fig. 3(b): fixed-wing UAV on the pollution map",
        )
        .map_err(failure)?;
        timeseries_figure(
            std::slice::from_ref(&run3),
            &file("fig3c", f),
            st,
            "Fig. 3(c): UAV tracking error and measurement rate",
            Panels {
                error: true,
                measurement: false,
                measurement_rate: true,
                omega: false,
            },
        )
        .map_err(failure)?;
        written
            .extend(["fig2b", "fig2c", "fig3b", "fig3c"].map(|n| file(n, f).display().to_string()));
    }
    outln!("wrote {}", written.join("\n      "));
    Ok(())
}
