//! What `isotrack show` prints: the resolved file (every key resolution wrote, as a run's
//! `scenario.toml` records it) with every value in force that the file does not carry, each
//! marked as derived with a TOML comment.
//!
//! A default that follows another key (`sensor.rate_hz = 1/sim.dt_s`, the clamp's
//! `integral_limit_radps`, the tolerance 1 % of the level, ...) is written into the resolved
//! file; when its value is the formula's, its line gets `# derived: FORMULA` (by value, not by
//! who wrote it, so that showing `show`'s output gives the same text). A value resolution
//! leaves out of the file because it must follow a key a sweep or `--set` may change (the fixed
//! wing's turn-rate limit `g*tan(40 deg)/V`, the convergence dwell, the track-loss band, the
//! search geometry, the `[sitl]` home) is printed as a commented-out key at the end of its
//! section, `# KEY = VALUE  # derived: FORMULA`. So are the field's values in force that the
//! resolved file leaves out: an analytic field's drift (`[0.0, 0.0]` unless given), a NetCDF
//! time series' frame times (its own time axis). Comments only: `show`'s output, run again, is
//! the same scenario and gives the same run, byte for byte (and uncommenting a derived line pins
//! the value it had).

use super::field::{FieldKindSpec, FrameTimes};
use super::TurnRateLimit;
use crate::field::FieldModel;
use crate::Scenario;
use isotrack_core::control::{AntiWindup, SearchPattern};

/// A TOML value of `x`, as the `toml` crate writes an `f64` (so a printed value reads back as
/// the same number).
fn num(x: f64) -> String {
    toml::Value::Float(x).to_string()
}

/// `resolved_toml` (the scenario's resolved file as TOML) with the derived values marked and
/// the values in force it does not hold added, as comments.
pub fn with_derived(s: &Scenario, resolved_toml: &str) -> String {
    let spec = s.spec();
    let file = s.file();
    // Keys on their own line: (section, key, formula) for a key the user did not give.
    let mut inline: Vec<(&str, &str, String)> = Vec::new();
    // Lines added at the end of a section: (section, line).
    let mut extra: Vec<(&str, String)> = Vec::new();
    if spec.sensor.rate_hz == super::sensor::default_rate_hz(spec.sim.dt_s) {
        inline.push(("sensor", "rate_hz", "1/sim.dt_s (one sample a step)".into()));
    }
    let tol = spec.metrics.convergence_tolerance;
    if tol == super::controller::one_percent_of_level(spec.controller.level) {
        inline.push((
            "metrics",
            "convergence_tolerance",
            "1 % of |controller.level| (0.01 for level 0)".into(),
        ));
    }
    controller_inline(s, &mut inline);
    controller_in_force(s, &mut extra);
    field_in_force(s, &mut extra);
    metrics_in_force(s, &mut extra);
    team_in_force(s, &mut extra);
    let mut out = annotate(resolved_toml, &inline, &extra);
    if file.sitl.is_unset() {
        let h = &spec.sitl;
        out += &format!(
            "\n# [sitl]  (isotrack sitl only; the defaults: PX4's SITL home)\n# home_lat_deg = {}\n# home_lon_deg = {}\n# home_alt_m = {}\n",
            num(h.home_lat_deg),
            num(h.home_lon_deg),
            num(h.home_alt_m)
        );
    }
    out
}

/// The `[controller]` keys resolution wrote by a formula, marked inline when their value is
/// the formula's: the PI-like law's clamp (`max_turn_rate_radps`, else `kp*c1`) or band (`c2`),
/// `pid_crossing`'s turn rate.
fn controller_inline(s: &Scenario, inline: &mut Vec<(&str, &str, String)>) {
    let spec = s.spec();
    let ct = &s.file().controller;
    if let Some(p) = spec.controller.pi_isoline() {
        match (p.anti_windup, ct.max_turn_rate_radps) {
            (AntiWindup::Clamp { limit_radps }, Some(w)) if limit_radps == w => inline.push((
                "controller",
                "integral_limit_radps",
                "max_turn_rate_radps".into(),
            )),
            (AntiWindup::Clamp { limit_radps }, None) if limit_radps == p.kp * p.c1 => {
                inline.push((
                    "controller",
                    "integral_limit_radps",
                    "kp*c1, the proportional term's reach".into(),
                ))
            }
            (AntiWindup::Conditional { band }, _) if band == p.c2 => {
                inline.push(("controller", "integral_band", "c2".into()))
            }
            _ => {}
        }
    }
    if let super::LawSpec::PidCrossing(p) = &spec.controller.law {
        let default = ct
            .max_turn_rate_radps
            .unwrap_or(super::controller::CROSSING_TURN_RATE_RADPS);
        if p.turn_rate_radps == default {
            inline.push((
                "controller",
                "crossing_turn_rate_radps",
                "max_turn_rate_radps, or 0.5 without one".into(),
            ));
        }
    }
}

/// The `[controller]` values in force the resolved file leaves out: the fixed wing's turn-rate
/// limit and the search geometry (spacing, leg, handover) where not given.
fn controller_in_force(s: &Scenario, extra: &mut Vec<(&str, String)>) {
    let spec = s.spec();
    let ct = &s.file().controller;
    if let TurnRateLimit::Airframe(w) = spec.controller.turn_rate_limit {
        extra.push((
            "controller",
            format!(
                "# max_turn_rate_radps = {}  # derived: g*tan(40 deg)/V, the airframe's turn rate at the autopilot's bank limit (follows vehicle.airspeed_mps)",
                num(w)
            ),
        ));
    }
    if let Some(sp) = spec.controller.search {
        let (spacing, leg) = match sp.pattern {
            SearchPattern::Spiral { spacing_m, .. } => (spacing_m, None),
            SearchPattern::Lawnmower {
                spacing_m, leg_m, ..
            } => (spacing_m, Some(leg_m)),
        };
        if ct.search_spacing_m.is_none() {
            extra.push((
                "controller",
                format!(
                    "# search_spacing_m = {}  # derived: 2*v/omega_max, the turning diameter (omega_max the turn-rate limit, 1 rad/s without one)",
                    num(spacing)
                ),
            ));
        }
        if let (Some(leg), None) = (leg, ct.search_leg_m) {
            extra.push((
                "controller",
                format!(
                    "# search_leg_m = {}  # derived: 10 x search_spacing_m",
                    num(leg)
                ),
            ));
        }
        if ct.search_handover.is_none() {
            extra.push((
                "controller",
                format!(
                    "# search_handover = {}  # derived: 1 % of |level| (0.01 for level 0)",
                    num(sp.handover_delta)
                ),
            ));
        }
    }
}

/// The `[metrics]` values in force the resolved file leaves out: the convergence dwell and the
/// track-loss band where not given.
fn metrics_in_force(s: &Scenario, extra: &mut Vec<(&str, String)>) {
    let (spec, file) = (s.spec(), s.file());
    let m = &spec.metrics;
    if file.metrics.convergence_min_dwell_s.is_none() {
        extra.push((
            "metrics",
            format!(
                "# convergence_min_dwell_s = {}  # derived: 10 % of sim.duration_s",
                num(m.convergence_min_dwell_s)
            ),
        ));
    }
    if file.metrics.track_loss_band.is_none() {
        extra.push((
            "metrics",
            format!(
                "# track_loss_band = {}  # derived: 5 x convergence_tolerance",
                num(m.track_loss_band)
            ),
        ));
    }
}

/// The `[team]` values in force the resolved file leaves out (nu-18): the law, its gain, the
/// speed envelope and the ring where not given; a line spread's first pose (`[initial]`'s) and
/// direction (`heading_rad`), an arc spread's centre, first angle, step and sense; the
/// ranging's keys not given (a `[team.ranging]` the file does not have is shown as a comment,
/// its header too, so that `show`'s output reads back as the same scenario).
fn team_in_force(s: &Scenario, extra: &mut Vec<(&'static str, String)>) {
    let (Some(t), Some(spec)) = (s.file().team.as_ref(), s.spec().team.as_ref()) else {
        return;
    };
    team_keys_in_force(t, spec, extra);
    if let (Some(sp), None, Some(first)) = (&t.spread, &t.starts, spec.starts.first()) {
        spread_in_force(sp, first, spec.count(), extra);
    }
    ranging_in_force(t, spec, extra);
}

/// A value in force the file leaves out, as `show` prints it: `# KEY = VALUE  # WHY`.
fn line(key: &str, value: String, why: &str) -> String {
    format!("# {key} = {value}  # {why}")
}

/// `[team]`'s own keys in force the file `t` leaves out: the count, the law, its gain, the
/// speed envelope and the ring.
fn team_keys_in_force(
    t: &crate::schema::TeamSection,
    spec: &super::team::TeamSpec,
    extra: &mut Vec<(&'static str, String)>,
) {
    use crate::schema::{RingName, SpacingName};
    if t.count.is_none() {
        extra.push((
            "team",
            line(
                "count",
                spec.count().to_string(),
                "derived: the length of team.starts",
            ),
        ));
    }
    if t.spacing.is_none() {
        let name = match super::team::SPACING {
            SpacingName::None => "none",
            SpacingName::RangeBalance => "range_balance",
            SpacingName::ArcReference => "arc_reference",
        };
        extra.push(("team", line("spacing", format!("\"{name}\""), "default")));
    }
    if t.k_v.is_none() {
        extra.push(("team", line("k_v", num(super::team::K_V_PER_S), "default")));
    }
    let airframe = "the nominal speed (vehicle.speed_mps, a fixed wing's vehicle.airspeed_mps), within a fixed wing's safe commanded airspeeds";
    if t.v_min_mps.is_none() {
        extra.push((
            "team",
            line(
                "v_min_mps",
                num(spec.v_min_mps),
                &format!("derived: half {airframe}"),
            ),
        ));
    }
    if t.v_max_mps.is_none() {
        extra.push((
            "team",
            line(
                "v_max_mps",
                num(spec.v_max_mps),
                &format!("derived: twice {airframe}"),
            ),
        ));
    }
    if t.ring.is_none() {
        let name = match super::team::RING {
            RingName::Listed => "listed",
            RingName::Discovered => "discovered",
        };
        extra.push((
            "team",
            line(
                "ring",
                format!("\"{name}\""),
                "default: the listed order is the order of travel",
            ),
        ));
    }
}

/// A spread's values in force the file's `[team.spread]` `sp` leaves out (the team's `count`
/// starts from `first`): a line's first pose and direction, an arc's centre, first angle,
/// step and sense.
fn spread_in_force(
    sp: &crate::schema::TeamSpread,
    first: &super::sim::Start,
    count: usize,
    extra: &mut Vec<(&'static str, String)>,
) {
    use crate::schema::SpreadAlong;
    let mut spread = |key: &str, value: String, why: &str| {
        extra.push(("team.spread", line(key, value, why)));
    };
    match sp.along {
        Some(SpreadAlong::Line) => {
            if sp.x_m.is_none() {
                spread("x_m", num(first.x_m), "derived: initial.x_m");
            }
            if sp.y_m.is_none() {
                spread("y_m", num(first.y_m), "derived: initial.y_m");
            }
            if sp.heading_rad.is_none() {
                spread(
                    "heading_rad",
                    num(first.heading_rad),
                    "derived: initial.heading_rad",
                );
            }
            if sp.direction_rad.is_none() {
                spread(
                    "direction_rad",
                    num(first.heading_rad),
                    "derived: heading_rad (the line ahead of the first start)",
                );
            }
        }
        Some(SpreadAlong::Arc) => {
            if sp.center_m.is_none() {
                spread("center_m", nums(&super::team::SPREAD_CENTER_M), "default");
            }
            if sp.start_rad.is_none() {
                spread("start_rad", num(super::team::SPREAD_START_RAD), "default");
            }
            if sp.step_rad.is_none() {
                spread(
                    "step_rad",
                    num(std::f64::consts::TAU / count as f64),
                    "derived: 2 pi/count",
                );
            }
            if sp.clockwise.is_none() {
                spread(
                    "clockwise",
                    super::team::SPREAD_CLOCKWISE.to_string(),
                    "default",
                );
            }
        }
        None => {}
    }
}
/// The ranging's keys in force the file `t` leaves out (a `[team.ranging]` the file does not
/// have is shown as a comment, its header too, so that `show`'s output reads back as the same
/// scenario).
fn ranging_in_force(
    t: &crate::schema::TeamSection,
    spec: &super::team::TeamSpec,
    extra: &mut Vec<(&'static str, String)>,
) {
    let r = t.ranging.clone().unwrap_or_default();
    let g = &spec.ranging;
    let mut ranging = Vec::new();
    let mut key = |given: bool, k: &str, v: f64, why: &str| {
        if !given {
            ranging.push(line(k, num(v), why));
        }
    };
    key(r.rate_hz.is_some(), "rate_hz", g.rate_hz, "default");
    key(
        r.noise_std_m.is_some(),
        "noise_std_m",
        g.noise_std_m,
        "default",
    );
    key(
        r.max_range_m.is_some(),
        "max_range_m",
        g.max_range_m,
        "default: no limit",
    );
    key(
        r.dropout_probability.is_some(),
        "dropout_probability",
        g.dropout_probability,
        "default",
    );
    key(r.delay_s.is_some(), "delay_s", g.delay_s, "default");
    if t.ranging.is_some() {
        extra.extend(ranging.into_iter().map(|l| ("team.ranging", l)));
    } else {
        extra.push((
            "team",
            "# [team.ranging]  (not in the file: every key its default)".to_string(),
        ));
        extra.extend(ranging.into_iter().map(|l| ("team", l)));
    }
}

/// A TOML array of `xs`, each as [`num`] writes it.
fn nums(xs: &[f64]) -> String {
    toml::Value::Array(xs.iter().map(|&x| toml::Value::Float(x)).collect()).to_string()
}

/// The `[field]` values in force that the resolved file does not hold (its files' own
/// spacing, origin and units are recorded into it once the field is built): an analytic
/// field's drift when none is given, and a time series' frame times read from its file.
fn field_in_force(s: &Scenario, extra: &mut Vec<(&str, String)>) {
    match &s.spec().field.kind {
        FieldKindSpec::Analytic(a) if s.file().field.drift_mps.is_none() => extra.push((
            "field",
            format!(
                "# drift_mps = {}  # default: a steady field (not written into the resolved file)",
                nums(&[a.drift_mps.x, a.drift_mps.y])
            ),
        )),
        FieldKindSpec::Grid(g) if g.frame_times == FrameTimes::FromFile => {
            if let FieldModel::Series(series) = s.field() {
                extra.push((
                    "field",
                    format!(
                        "# frame_times_s = {}  # derived: the file's time axis, s after its first frame",
                        nums(series.times_s())
                    ),
                ));
            }
        }
        _ => {}
    }
}

/// Appends `  # derived: F` to each `inline` key's line of its section, and each `extra` line
/// after the last line of its section (a section that is missing is added at the end).
///
/// A line counts as a section header or a key only where the text before it is complete TOML:
/// a `[controller]` line inside a multi-line string (a `description`) is text, not a header.
/// Only the few candidate lines are parsed (each parse reads the text before them once).
fn annotate(text: &str, inline: &[(&str, &str, String)], extra: &[(&str, String)]) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let complete = |i: usize| toml::from_str::<toml::Table>(&lines[..i].join("\n")).is_ok();
    let is_header = |i: usize| lines[i].trim_start().starts_with('[') && complete(i);
    // The line range of section `sec`'s own keys: after its header, up to the next header.
    let range = |sec: &str| -> Option<(usize, usize)> {
        let head = format!("[{sec}]");
        let start = (0..lines.len()).find(|&i| lines[i].trim() == head && complete(i))?;
        let end = (start + 1..lines.len())
            .find(|&i| is_header(i))
            .unwrap_or(lines.len());
        Some((start, end))
    };
    let mut suffix: Vec<String> = vec![String::new(); lines.len()];
    let mut after: Vec<Vec<String>> = vec![Vec::new(); lines.len() + 1];
    // Sections the text does not have, in the order first named, each with its lines: one
    // header per section (nu36-13: a `[team]` given by `starts` alone, written as
    // `[[team.starts]]` tables only, once got a `[team]` header per line, invalid TOML).
    let mut missing: Vec<(&str, Vec<String>)> = Vec::new();
    for (sec, key, formula) in inline {
        let Some((start, end)) = range(sec) else {
            continue;
        };
        let is_key = |j: usize| {
            lines[j]
                .split_once('=')
                .is_some_and(|(k, _)| k.trim() == *key)
        };
        if let Some(j) = (start + 1..end).find(|&j| is_key(j) && complete(j)) {
            suffix[j] = format!("  # derived: {formula}");
        }
    }
    for (sec, added) in extra {
        match range(sec) {
            Some((start, end)) => {
                // After the section's last non-blank line.
                let last = (start + 1..end)
                    .rev()
                    .find(|&j| !lines[j].trim().is_empty())
                    .unwrap_or(start);
                after[last + 1].push(added.clone());
            }
            None => match missing.iter_mut().find(|(m, _)| m == sec) {
                Some((_, added_lines)) => added_lines.push(added.clone()),
                None => missing.push((sec, vec![added.clone()])),
            },
        }
    }
    let mut out = String::new();
    for (i, line) in lines.iter().enumerate() {
        for a in &after[i] {
            out += a;
            out.push('\n');
        }
        out += line;
        out += &suffix[i];
        out.push('\n');
    }
    for a in &after[lines.len()] {
        out += a;
        out.push('\n');
    }
    for (sec, added_lines) in &missing {
        out += &format!("\n[{sec}]\n");
        for a in added_lines {
            out += a;
            out.push('\n');
        }
    }
    out
}
