//! `isotrack run` and `isotrack show`.

use crate::cli::{CheckArgs, RunArgs, ScenarioArgs};
use crate::exit;
use crate::output::{run_to_trace, scenario_toml, write_summary};
use isotrack_core::numtext::{Echo, Num};
use isotrack_scenario::{load_scenario, Scenario, ScenarioError};
use isotrack_sim::{NoTrace, RunResult};

/// A command's failure: the message and the exit code (see [`crate::exit`]).
pub use isotrack_runs::Failure;

/// A scenario error as a failure: 66 when the file, or a file it names (`field.path`), cannot
/// be read (missing, a FIFO, a directory, a device, too big), 65 when what it holds is invalid.
pub fn invalid(e: ScenarioError) -> Failure {
    Failure {
        code: if e.is_unreadable_input() {
            exit::NOINPUT
        } else {
            exit::DATAERR
        },
        message: e.to_string(),
    }
}

/// Loads the scenario named by the arguments.
pub fn load(args: &ScenarioArgs) -> Result<Scenario, Failure> {
    load_scenario(args.scenario.as_deref(), &args.set).map_err(invalid)
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.4e}"))
}

/// A few lines a person reads after a run.
pub fn human_summary(name: &str, s: &Scenario, r: &RunResult) -> String {
    let m = &r.metrics;
    let f = s.file();
    let mut out = String::new();
    out += &format!("scenario    {name}\n");
    out += &format!(
        "outcome     {} at t = {:.2} s ({} steps, {} samples){}\n",
        r.outcome.as_str(),
        r.t_end_s,
        r.steps,
        r.samples,
        r.outcome_detail
            .as_ref()
            .map(|d| format!(": {d}"))
            .unwrap_or_default()
    );
    out += &format!(
        "steady state (last {:.0} %)  max|eps| {}  rms {}  mean {}\n",
        100.0 * f.metrics.steady_state_fraction.unwrap_or(0.2),
        fmt_opt(m.steady_state_max_abs_error),
        fmt_opt(m.steady_state_rms_error),
        fmt_opt(m.steady_state_mean_error),
    );
    out += &format!(
        "convergence {} (|eps| < {})\n",
        m.convergence_time_s
            .map_or_else(|| "never".to_string(), |t| format!("{t:.2} s")),
        Echo(f.metrics.convergence_tolerance.unwrap_or_default())
    );
    // Non-finite values print as in summary.json (null there, n/a here), never as `inf`.
    let fixed = |x: f64, digits: usize| {
        if x.is_finite() {
            format!("{x:.digits$}")
        } else {
            "n/a".to_string()
        }
    };
    out += &format!(
        "path {} m   control effort {} rad^2/s   chattering {} rad/s^2\n",
        fixed(m.path_length_m, 1),
        fixed(m.control_effort, 4),
        fmt_opt(m.chattering_radps2)
    );
    out
}

/// `isotrack run`.
pub fn run(args: &RunArgs) -> Result<(), Failure> {
    let scenario = load(&args.scenario)?;
    let warnings = isotrack_scenario::check::warnings(&scenario);
    for w in &warnings {
        errln!("warning: {w}");
    }
    let name = args.scenario.scenario.as_ref().map_or_else(
        || "<built-in default: paper Fig. 2(b)>".to_string(),
        |p| p.display().to_string(),
    );
    let result = if let Some(dir) = &args.out {
        let cant = |what: &str, e: std::io::Error| Failure {
            code: exit::CANTCREAT,
            message: format!("cannot write {what}: {e}"),
        };
        // An output that is one of the inputs (the scenario file, the field's data) is refused
        // before anything is written: a run directory never replaces what it was made from.
        let inputs = crate::output::input_files(args.scenario.scenario.as_deref(), &scenario);
        for name in ["trace.csv", "summary.json", "scenario.toml"] {
            if let Some(message) = crate::output::input_clash(&inputs, &dir.join(name)) {
                return Err(Failure {
                    code: exit::USAGE,
                    message,
                });
            }
        }
        std::fs::create_dir_all(dir).map_err(|e| cant(&dir.display().to_string(), e))?;
        let trace = dir.join("trace.csv");
        let result =
            run_to_trace(&scenario, &trace).map_err(|e| cant(&trace.display().to_string(), e))?;
        let summary = dir.join("summary.json");
        write_summary(
            &summary,
            &scenario,
            args.scenario.scenario.as_deref(),
            &result,
            &warnings,
        )
        .map_err(|e| cant(&summary.display().to_string(), e))?;
        let resolved = dir.join("scenario.toml");
        std::fs::write(&resolved, scenario_toml(&scenario))
            .map_err(|e| cant(&resolved.display().to_string(), e))?;
        if !args.quiet {
            out!("{}", human_summary(&name, &scenario, &result));
            outln!(
                "wrote       {}, {}, {}",
                trace.display(),
                summary.display(),
                resolved.display()
            );
        }
        if args.plot {
            let st = crate::figures::style(&args.look, isotrack_plot::Format::Png)?;
            let written = crate::figures::plot_dirs(std::slice::from_ref(dir), &st, dir)?;
            if !args.quiet {
                outln!("plotted     {}", written.join(", "));
            }
        }
        result
    } else {
        let result = scenario.run(&mut NoTrace);
        if !args.quiet {
            out!("{}", human_summary(&name, &scenario, &result));
        }
        result
    };
    let _ = result;
    Ok(())
}

/// `isotrack show`.
pub fn show(args: &ScenarioArgs) -> Result<(), Failure> {
    let scenario = load(args)?;
    out_data!("{}", scenario_toml(&scenario));
    Ok(())
}

fn yes_no(b: Option<bool>) -> &'static str {
    match b {
        Some(true) => "yes",
        Some(false) => "NO",
        None => "n/a",
    }
}

/// `isotrack check`.
pub fn check(args: &CheckArgs) -> Result<(), Failure> {
    if let Some(h) = args.tube_halfwidth {
        if !(h.is_finite() && h > 0.0) {
            return Err(Failure {
                code: exit::USAGE,
                message: format!("--tube-halfwidth must be > 0, got {}", Echo(h)),
            });
        }
    }
    let parsed = crate::checkmap::precheck(args)?;
    let scenario = load(&args.scenario)?;
    let r = isotrack_scenario::check::check(&scenario, args.tube_halfwidth);
    let map = if args.map {
        Some(crate::checkmap::write_map(args, &scenario, parsed)?)
    } else {
        None
    };
    if args.json {
        let text = match &map {
            // Without --map the JSON is the report alone, unchanged; with it, a `map` key names
            // the files written and the chart's counts.
            Some(m) => {
                #[derive(serde::Serialize)]
                struct WithMap<'a> {
                    #[serde(flatten)]
                    report: &'a isotrack_scenario::check::CheckReport,
                    map: &'a crate::checkmap::MapReport,
                }
                serde_json::to_string_pretty(&WithMap { report: &r, map: m }).unwrap_or_default()
            }
            None => serde_json::to_string_pretty(&r).unwrap_or_default(),
        };
        out_data!("{text}\n");
        return Ok(());
    }
    outln!("verdict: {} ({})", r.verdict.as_str(), r.verdict_reason);
    for w in &r.warnings {
        outln!("warning: {w}");
    }
    let m = &r.moving;
    if m.time_varying {
        let f = |x: Option<f64>| x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.4}"));
        outln!(
            "moving isoline: speed max {} m/s, 95th percentile {} m/s; vehicle {} m/s: {}",
            f(m.isoline_speed_max_mps),
            f(m.isoline_speed_p95_mps),
            Echo(m.vehicle_speed_mps),
            match m.trackable {
                Some(true) => "trackable (the vehicle is faster everywhere sampled)",
                Some(false) =>
                    "NOT trackable everywhere (the isoline outruns the vehicle somewhere)",
                None => "no sample in the tube",
            }
        );
    }
    let p1 = &r.prop1;
    outln!("Prop. 1 (circular field, local exponential stability)");
    if p1.applicable {
        outln!(
            "  alpha = {:.6}  r_d = {:.4} m",
            p1.alpha.unwrap_or(f64::NAN),
            p1.r_d_m.unwrap_or(f64::NAN)
        );
        outln!(
            "  paper's sufficient conditions kp(kp-2)v*alpha > ki, v*alpha > c1: {}",
            yes_no(p1.paper_conditions_hold)
        );
        outln!(
            "  exact Routh-Hurwitz condition:                               {}",
            yes_no(p1.exact_local_condition_holds)
        );
    } else {
        outln!("  not applicable: {}", p1.note);
    }
    let p2 = &r.prop2;
    let f = |x: Option<f64>| x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.6}"));
    outln!("Prop. 2 (smooth field, ki = 0: gain conditions and error bound)");
    if let Some([lo, hi]) = p2.region_levels {
        outln!(
            "  start to tube, {lo:.4} <= F <= {hi:.4} ({} samples): gamma1 = {}  gamma2 = {}  gamma3 = {}",
            p2.samples_in_region,
            f(p2.gamma1),
            f(p2.gamma2),
            f(p2.gamma3)
        );
    }
    outln!(
        "  tube |F - s_d| <= {} ({} samples): gamma1 = {}  gamma2 = {}  gamma3 = {}",
        Echo(p2.tube_halfwidth),
        p2.samples_in_tube,
        f(p2.tube_gamma1),
        f(p2.tube_gamma2),
        f(p2.tube_gamma3)
    );
    // A withheld bound is no claim: say so, and print no number that reads as one.
    let withheld = !p2.bound_withheld.is_empty();
    let bound = match p2.error_bound {
        Some(b) if p2.bound_applies => format!("predicted limsup|eps| <= {b:.6}"),
        Some(b) => format!("limsup|eps| <= {b:.6} only from a start in the sector (see note)"),
        None if withheld => "NO bound on limsup|eps| is claimed (withheld, below)".to_string(),
        None => "no bound (the conditions do not hold)".to_string(),
    };
    outln!(
        "  conditions hold: {}   bound applies: {}   {bound}   smallest kp: {}",
        if p2.conditions_hold { "yes" } else { "NO" },
        if p2.bound_applies { "yes" } else { "NO" },
        f(p2.min_kp)
    );
    outln!(
        "  paper's printed form: smallest kp {}, bound {}",
        f(p2.paper_min_kp),
        if withheld {
            "not claimed".to_string()
        } else {
            f(p2.paper_error_bound)
        }
    );
    for w in &p2.bound_withheld {
        outln!("  withheld: {w}");
    }
    if let Some(phi0) = p2.initial_phi_rad {
        outln!(
            "  initial phi(t0) = {phi0:.4} rad; in the assumed sector: {}",
            yes_no(p2.initial_heading_in_sector)
        );
    }
    if !p2.note.is_empty() {
        outln!("  note: {}", p2.note);
    }
    let sm = &r.sampled;
    outln!(
        "Sampled loop (linearised at the sensor's period T = {} s, delay {} s)",
        Num(sm.period_s),
        Num(sm.delay_s)
    );
    if sm.applicable {
        print_sampled(sm);
    }
    if !sm.note.is_empty() {
        outln!("  note: {}", sm.note);
    }
    if let Some(m) = &map {
        crate::checkmap::print_report(m);
    }
    Ok(())
}

/// The sampled loop's lines of `isotrack check`: the radius at the isoline's slopes and over the
/// tube, the stable `kp` set, the rate, and the discrete loop's margins.
fn print_sampled(sm: &isotrack_scenario::check::SampledReport) {
    let f = |x: Option<f64>| {
        x.map_or_else(
            || "n/a".to_string(),
            |v| {
                if v.abs() < 1e4 {
                    format!("{v:.6}")
                } else {
                    format!("{v:.6e}")
                }
            },
        )
    };
    let range = |r: Option<[f64; 2]>| {
        r.map_or_else(|| "n/a".to_string(), |[a, b]| format!("{a:.4} .. {b:.4}"))
    };
    let state = |stable: Option<bool>| match stable {
        Some(true) => "stable",
        Some(false) => "UNSTABLE",
        None => "not computed",
    };
    outln!(
        "  model {}, on the isoline (slopes |grad F| {}{}): spectral radius {} -> {}",
        sm.vehicle_model.unwrap_or("n/a"),
        range(sm.slope_range),
        if sm.slope_exact == Some(true) {
            ", exact"
        } else {
            ""
        },
        f(sm.spectral_radius),
        state(sm.stable)
    );
    outln!(
        "  over the whole tube (slopes {}): spectral radius {} -> {}",
        range(sm.tube_slope_range),
        f(sm.tube_spectral_radius),
        state(sm.stable_over_tube)
    );
    if let Some(set) = &sm.kp_intervals {
        outln!(
            "  stable kp: {}   nearest stable kp {}   longest stable sensor period {} s",
            isotrack_scenario::check::kp_intervals_text(set),
            sm.nearest_stable_kp.map_or_else(
                || "n/a".to_string(),
                |k| isotrack_scenario::check::nearest_kp_text(k, set)
            ),
            f(sm.max_period_s)
        );
    }
    if sm.stable.is_some() {
        outln!("  {}", sensor_rate_line(sm));
    }
    if let Some(c) = &sm.course_loop {
        outln!(
            "  course loop: steady bank b* = {:.4} deg, sec^2(b*) = {:.6}, G = (g/Va) sec^2(b*) = {:.6} 1/s (g/Va = {:.6}); roll loop omega {:.4} rad/s, zeta {:.4}; course PI kp_chi {:.4}, ki_chi {:.4}",
            c.steady_bank_rad.to_degrees(),
            c.sec2_steady_bank,
            c.course_rate_per_bank_per_s,
            c.g_over_airspeed_per_s,
            c.roll_natural_frequency_radps,
            c.roll_damping_ratio,
            c.kp_chi,
            c.ki_chi
        );
    }
    if let Some(d) = &sm.discrete_loop {
        outln!(
            "  discrete loop at slope {:.4}: gain margin {} ({} dB at {} rad/s), phase margin {} deg (at {} rad/s)",
            d.slope,
            f(d.gain_margin),
            f(d.gain_margin_db),
            f(d.phase_crossover_radps),
            f(d.phase_margin_deg),
            f(d.gain_crossover_radps)
        );
        if d.conditionally_stable == Some(true) {
            let db = |g: Option<f64>| {
                g.map_or_else(|| "n/a".to_string(), |g| format!("{:.2}", 20.0 * g.log10()))
            };
            outln!(
                "  conditionally stable: stable for loop-gain factors from {} ({} dB) to {} ({} dB); it goes unstable if the gain is REDUCED by the factor {} (lower gain margin) or raised by {} (upper)",
                f(d.gain_margin_lower),
                db(d.gain_margin_lower),
                f(d.gain_margin_upper),
                db(d.gain_margin_upper),
                f(d.gain_margin_lower),
                f(d.gain_margin_upper)
            );
        }
    }
}

/// One line: is the sensor rate the limit?
fn sensor_rate_line(sm: &isotrack_scenario::check::SampledReport) -> String {
    let rate = 1.0 / sm.period_s;
    match (sm.rate_is_the_limit, sm.max_period_s) {
        (Some(true), Some(t)) => format!(
            "sensor rate: the limit: {} Hz is too slow for these gains; {:.4} Hz or faster is stable",
            Num(rate),
            1.0 / t
        ),
        (_, Some(t)) if sm.stable == Some(true) => format!(
            "sensor rate: not the limit: stable at {} Hz and down to {:.4} Hz",
            Num(rate),
            1.0 / t
        ),
        _ => "sensor rate: not the limit: the loop is unstable at any rate (change the gains)".to_string(),
    }
}
