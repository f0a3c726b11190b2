//! The text of `isotrack check` (issue 31: the report rendered apart from its maths): one
//! function per section of [`isotrack_scenario::check::CheckReport`], each returning its lines.
//!
//! Computed values are printed with significant digits ([`Num`]: six, exact zero as `0`),
//! never with fixed decimals that turn a small value into a misleading `0.000000`; spectral
//! radii, whose distance to 1 is the point, keep six decimals. Values the user wrote are echoed
//! as written ([`Echo`]).

use isotrack_core::numtext::{Echo, Num};
use isotrack_scenario::check::moving::MovingReport;
use isotrack_scenario::check::{
    kp_intervals_text_scanned, nearest_kp_text, rate_advice_text, CheckReport, Prop1Report,
    Prop2Report, SampledReport,
};

/// The whole text report, line by line (each line without its newline).
pub fn render(r: &CheckReport) -> Vec<String> {
    let mut out = verdict_lines(r);
    out.extend(moving_lines(&r.moving));
    out.extend(prop1_lines(&r.prop1));
    out.extend(prop2_lines(&r.prop2));
    out.extend(sampled_lines(&r.sampled, r.moving.time_varying));
    out.extend(r.team.iter().flat_map(|t| t.lines()));
    out
}

/// A computed value, or `n/a`.
fn num(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| Num(v).to_string())
}

/// A spectral radius: six decimals (whether it is below 1 is what matters), scientific from
/// 1e4 up (an unstable loop's radius can be astronomically large).
fn radius(x: Option<f64>) -> String {
    x.map_or_else(
        || "none".to_string(),
        |v| {
            if v.abs() < 1e4 {
                format!("{v:.6}")
            } else {
                format!("{v:.6e}")
            }
        },
    )
}

/// A spectral radius and what it means: `spectral radius R -> stable`, `no equilibrium ->
/// UNSTABLE` (infinite), `not computed`.
fn radius_state(r: Option<f64>, stable: Option<bool>) -> String {
    match (r, stable) {
        (_, None) => "not computed".to_string(),
        (None, Some(false)) => "no equilibrium -> UNSTABLE".to_string(),
        (r, Some(st)) => format!(
            "spectral radius {} -> {}",
            radius(r),
            if st { "stable" } else { "UNSTABLE" }
        ),
    }
}

fn yes_no(b: Option<bool>) -> &'static str {
    match b {
        Some(true) => "yes",
        Some(false) => "NO",
        None => "n/a",
    }
}

/// The verdict with its reason, then the warnings.
pub fn verdict_lines(r: &CheckReport) -> Vec<String> {
    let mut out = vec![format!(
        "verdict: {} ({})",
        r.verdict.as_str(),
        r.verdict_reason
    )];
    out.extend(r.warnings.iter().map(|w| format!("warning: {w}")));
    out
}

/// The moving isoline's speed against the vehicle's (time-varying fields only).
pub fn moving_lines(m: &MovingReport) -> Vec<String> {
    if !m.time_varying {
        return vec![];
    }
    vec![format!(
        "moving isoline: speed max {} m/s, 95th percentile {} m/s; vehicle {} m/s: {}",
        num(m.isoline_speed_max_mps),
        num(m.isoline_speed_p95_mps),
        Echo(m.vehicle_speed_mps),
        match m.trackable {
            Some(true) => "trackable (the vehicle is faster everywhere sampled)",
            Some(false) => "NOT trackable everywhere (the isoline outruns the vehicle somewhere)",
            None => "no sample in the tube",
        }
    )]
}

/// Prop. 1: the slope and radius, the paper's conditions and the exact one.
pub fn prop1_lines(p1: &Prop1Report) -> Vec<String> {
    let mut out = vec!["Prop. 1 (circular field, local exponential stability)".to_string()];
    if !p1.applicable {
        out.push(format!("  not applicable: {}", p1.note));
        return out;
    }
    out.push(format!(
        "  alpha = {}  r_d = {} m",
        num(p1.alpha),
        num(p1.r_d_m)
    ));
    out.push(format!(
        "  paper's sufficient conditions kp(kp-2)v*alpha > ki, v*alpha > c1: {}",
        yes_no(p1.paper_conditions_hold)
    ));
    out.push(format!(
        "  exact Routh-Hurwitz condition:                               {}",
        yes_no(p1.exact_local_condition_holds)
    ));
    out
}

/// The level band of Prop. 2's region as printed: `region_levels` clipped to the values the
/// field was sampled to take there, with the unclipped band named when it reaches past them
/// (a band widened by the tube's half-width below zero on a concentration is no level the
/// robot crosses).
fn region_band(p2: &Prop2Report) -> Option<String> {
    let [lo, hi] = p2.region_levels?;
    let Some([vmin, vmax]) = p2.region_sampled_levels.filter(|v| v[0] <= v[1]) else {
        return Some(format!("{} <= F <= {}", Num(lo), Num(hi)));
    };
    let (a, b) = (lo.max(vmin), hi.min(vmax));
    if a == lo && b == hi {
        return Some(format!("{} <= F <= {}", Num(lo), Num(hi)));
    }
    Some(format!(
        "{} <= F <= {} (the values sampled there; the band [min(s0, s_d) - H, max(s0, s_d) + H] = [{}, {}] reaches past them)",
        Num(a),
        Num(b),
        Num(lo),
        Num(hi)
    ))
}

/// Prop. 2: the gammas over the region and the tube, the conditions and the bound, the
/// withheld reasons, the start's heading and the notes.
pub fn prop2_lines(p2: &Prop2Report) -> Vec<String> {
    let mut out =
        vec!["Prop. 2 (smooth field, ki = 0: gain conditions and error bound)".to_string()];
    if let Some(a) = &p2.analysed_start {
        out.push(format!("  start analysed: {a}"));
    }
    if let Some(band) = region_band(p2) {
        out.push(format!(
            "  start to tube, {band} ({} samples): gamma1 = {}  gamma2 = {}  gamma3 = {}",
            p2.samples_in_region,
            num(p2.gamma1),
            num(p2.gamma2),
            num(p2.gamma3)
        ));
    }
    out.push(format!(
        "  tube |F - s_d| <= {} ({} samples): gamma1 = {}  gamma2 = {}  gamma3 = {}",
        Echo(p2.tube_halfwidth),
        p2.samples_in_tube,
        num(p2.tube_gamma1),
        num(p2.tube_gamma2),
        num(p2.tube_gamma3)
    ));
    out.push(prop2_conditions_line(p2));
    let withheld = !p2.bound_withheld.is_empty();
    out.push(format!(
        "  paper's printed form: smallest kp {}, bound {}",
        num(p2.paper_min_kp),
        if withheld {
            "not claimed".to_string()
        } else {
            num(p2.paper_error_bound)
        }
    ));
    out.extend(p2.bound_withheld.iter().map(|w| format!("  withheld: {w}")));
    if let Some(phi0) = p2.initial_phi_rad {
        out.push(format!(
            "  initial phi(t0) = {} rad; in the assumed sector: {}",
            Num(phi0),
            yes_no(p2.initial_heading_in_sector)
        ));
    }
    if !p2.note.is_empty() {
        out.push(format!("  note: {}", p2.note));
    }
    out
}

/// Whether the conditions hold and the bound applies. A withheld bound is no claim: no number
/// that reads as one. A start without field data leaves the conditions unevaluated: no
/// yes/no for them.
fn prop2_conditions_line(p2: &Prop2Report) -> String {
    if p2.ki_nonzero {
        // Prop. 2 is stated for the P law: its conditions say nothing about a law with an
        // integral term, so no yes/no (issue 29: "conditions hold: NO" read as a failure).
        return format!(
            "  conditions: not applicable (ki != 0: Prop. 2 is for ki = 0)   smallest kp of the P part alone: {}",
            num(p2.min_kp)
        );
    }
    if p2.start_without_data && p2.gamma1.is_none() {
        return "  conditions: not evaluated (the start has no field value: the field has no data there)".to_string();
    }
    let withheld = !p2.bound_withheld.is_empty();
    let bound = match p2.error_bound {
        Some(b) if p2.bound_applies => format!("predicted limsup|eps| <= {}", Num(b)),
        Some(b) => format!(
            "limsup|eps| <= {} only from a start in the sector (see note)",
            Num(b)
        ),
        None if withheld => "NO bound on limsup|eps| is claimed (withheld, below)".to_string(),
        None => "no bound (the conditions do not hold)".to_string(),
    };
    format!(
        "  conditions hold: {}   bound applies: {}   {bound}   smallest kp: {}",
        if p2.conditions_hold { "yes" } else { "NO" },
        if p2.bound_applies { "yes" } else { "NO" },
        num(p2.min_kp)
    )
}

/// The sampled loop: its heading line, then (when it applies) the stability lines, the
/// autopilot's course loop and the discrete loop's margins, then the note.
///
/// `field_moves`: the field changes with time, and the loop is linearised on it frozen at
/// `t = 0` (the lattice's time; issue 29: the radius of a moving plume read as the run's).
pub fn sampled_lines(sm: &SampledReport, field_moves: bool) -> Vec<String> {
    let mut out = vec![format!(
        "Sampled loop (linearised at the sensor's period T = {} s, delay {} s{})",
        Num(sm.period_s),
        Num(sm.delay_s),
        if field_moves {
            "; the field frozen at t = 0 s: it moves, and the radius is that frozen field's"
        } else {
            ""
        }
    )];
    if sm.applicable {
        out.extend(sampled_stability_lines(sm, field_moves));
        out.extend(course_loop_line(sm));
        out.extend(discrete_loop_lines(sm));
    }
    if !sm.note.is_empty() {
        out.push(format!("  note: {}", sm.note));
    }
    out
}

/// The radius at the isoline's slopes and over the tube, the stable `kp` set, the rate.
fn sampled_stability_lines(sm: &SampledReport, field_moves: bool) -> Vec<String> {
    let range = |r: Option<[f64; 2]>| {
        r.map_or_else(
            || "n/a".to_string(),
            |[a, b]| format!("{} .. {}", Num(a), Num(b)),
        )
    };
    let mut out = vec![
        format!(
            "  model {}, on the {} (slopes |grad F| {}{}){}: {}",
            sm.vehicle_model.unwrap_or("n/a"),
            if sm.p_law_orbit_error.is_some() {
                "orbit"
            } else {
                "isoline"
            },
            range(sm.slope_range),
            if sm.slope_exact == Some(true) {
                ", exact"
            } else {
                ""
            },
            if field_moves {
                " of the field frozen at t = 0 s"
            } else {
                ""
            },
            radius_state(sm.spectral_radius, sm.stable)
        ),
        format!(
            "  over the whole tube (slopes {}): {}",
            range(sm.tube_slope_range),
            radius_state(sm.tube_spectral_radius, sm.stable_over_tube)
        ),
    ];
    if let Some(tau) = sm.slowest_time_constant_s {
        // On a lattice isoline the worst slope's mode is that slope's frozen; the run's
        // settling follows the loop at the mean slope (issue 29: 180.7 s against 8 s).
        let mean = match (sm.isoline_time_constant_s, sm.isoline_mean_slope) {
            (Some(t), Some(a)) if (t - tau).abs() > 0.1 * tau => format!(
                " with the worst slope frozen; {} s at the isoline's mean slope {} (what the run's settling follows)",
                Num(t),
                Num(a)
            ),
            _ => String::new(),
        };
        out.push(format!(
            "  slowest mode: time constant -T/ln(rho) = {} s{mean}",
            Num(tau)
        ));
    }
    if let Some(set) = &sm.kp_intervals {
        let nearest = match sm.nearest_stable_kp {
            None => "none".to_string(),
            Some(_) if sm.stable == Some(true) => "the scenario's own".to_string(),
            Some(k) => nearest_kp_text(k, set),
        };
        let period = sm.max_period_s.map_or_else(
            || "none (unstable at the shortest period examined)".to_string(),
            |t| format!("{} s", Num(t)),
        );
        out.push(format!(
            "  stable kp: {}   nearest stable kp: {nearest}   longest stable sensor period: {period}",
            kp_intervals_text_scanned(set, sm.kp_scanned_from),
        ));
    }
    if sm.stable.is_some() {
        out.push(format!("  {}", sensor_rate_line(sm)));
    }
    out
}

/// One line: is the sensor rate the limit? Each branch says only what the report shows.
fn sensor_rate_line(sm: &SampledReport) -> String {
    let rate = 1.0 / sm.period_s;
    match (sm.stable, sm.rate_is_the_limit, sm.max_period_s) {
        (_, Some(true), Some(t)) => format!(
            "sensor rate: the limit: {} Hz is too slow for these gains; {}",
            Num(rate),
            rate_advice_text(t, sm.sim_dt_s, sm.period_scanned_from_s)
        ),
        (Some(true), _, Some(t)) => format!(
            "sensor rate: not the limit: stable at {} Hz and down to {} Hz",
            Num(rate),
            Num(1.0 / t)
        ),
        (Some(true), _, None) => format!(
            "sensor rate: not the limit: stable at {} Hz (slower rates not computed)",
            Num(rate)
        ),
        // The lag, when it is what makes the loop unstable, is named here as in the advice
        // (issue 29: this line said only "change the gains").
        _ if sm.lag_is_the_cause => "sensor rate: not the limit: the loop is unstable at any rate with this sensor lag (without it the loop is stable: reduce sensor.time_constant_s, or change the gains)"
            .to_string(),
        _ => "sensor rate: not the limit: the loop is unstable at any rate (change the gains)"
            .to_string(),
    }
}

/// The fixed-wing UAV's course-loop model (nothing for the Dubins robot).
fn course_loop_line(sm: &SampledReport) -> Option<String> {
    let c = sm.course_loop.as_ref()?;
    Some(format!(
        "  course loop: steady bank b* = {} deg, sec^2(b*) = {}, G = (g/Va) sec^2(b*) = {} 1/s (g/Va = {}); roll loop omega {} rad/s, zeta {}; course PI kp_chi {}, ki_chi {}",
        Num(c.steady_bank_rad.to_degrees()),
        Num(c.sec2_steady_bank),
        Num(c.course_rate_per_bank_per_s),
        Num(c.g_over_airspeed_per_s),
        Num(c.roll_natural_frequency_radps),
        Num(c.roll_damping_ratio),
        Num(c.kp_chi),
        Num(c.ki_chi)
    ))
}

/// The discrete loop's gain and phase margins, and the lower gain margin of a conditionally
/// stable loop.
fn discrete_loop_lines(sm: &SampledReport) -> Vec<String> {
    let Some(d) = &sm.discrete_loop else {
        return vec![];
    };
    let gain = match (d.gain_margin, d.gain_margin_db, d.phase_crossover_radps) {
        (Some(g), Some(db), Some(w)) => format!(
            "gain margin {} ({} dB at {} rad/s)",
            Num(g),
            decibels(db),
            Num(w)
        ),
        _ => "no gain margin (no phase crossover up to pi/T)".to_string(),
    };
    let phase = match (d.phase_margin_deg, d.gain_crossover_radps) {
        (Some(p), Some(w)) => format!("phase margin {} deg (at {} rad/s)", Num(p), Num(w)),
        _ => "no phase margin (no gain crossover up to pi/T)".to_string(),
    };
    let mut out = vec![format!(
        "  discrete loop at slope {}: {gain}, {phase}",
        Num(d.slope)
    )];
    if let (Some(true), Some(lo)) = (d.conditionally_stable, d.gain_margin_lower) {
        let upper = d.gain_margin_upper.map_or_else(
            || "any factor above 1 (no upper gain margin found)".to_string(),
            |g| format!("{} ({} dB)", Num(g), decibels(20.0 * g.log10())),
        );
        let raised = d
            .gain_margin_upper
            .map_or_else(String::new, |g| format!(" or raised by {} (upper)", Num(g)));
        out.push(format!(
            "  conditionally stable: stable for loop-gain factors (a factor scales kp and ki together) from {} ({} dB) to {upper}; it goes unstable if the gain is REDUCED by the factor {} (lower gain margin){raised}",
            Num(lo),
            decibels(20.0 * lo.log10()),
            Num(lo),
        ));
    }
    out
}

/// Decibels with two decimals, never `-0.00` (a margin that rounds to zero is `0.00`).
fn decibels(db: f64) -> String {
    let text = format!("{db:.2}");
    if text == "-0.00" {
        "0.00".to_string()
    } else {
        text
    }
}
