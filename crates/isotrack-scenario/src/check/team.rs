//! The `team` section of `isotrack check` (docs/TEAMS.md, "Theory"): for a scenario with
//! `[team]`,
//!
//! * the **spacing loop** sampled at the ranging period `T = 1/team.ranging.rate_hz` with its
//!   delay `d = team.ranging.delay_s = (q + f) T`: every mode `m` of the ring Laplacian
//!   (`lambda_m = 2 - 2 cos(2 pi m/N)`, Gray 2006 sec. 3.1) has the gain per period
//!   `g_m = k_v c lambda_m T` and the characteristic polynomial
//!   `z^{q+2} - z^{q+1} + g (1 - f) z + g f`, Schur-stable or not
//!   ([`isotrack_core::spacing::spacing_mode_stable`]); the largest stable gain
//!   `k_v* = g*(q, f)/(T c lambda_max)` ([`isotrack_core::spacing::max_stable_spacing_gain`]) and
//!   the slowest mode's time constant (sampled: `-T/ln rho` of the mode with the largest radius,
//!   with a delay not always `m = 1`; continuous: `1/(k_v c lambda_1)`).
//!   The range slope `c = dr/dg`: `cos(pi/N)` for `range_balance` on an isoline known to be a
//!   circle (a chord `2R sin(g/(2R))` at the even gap `2 pi R/N`), 1 for `arc_reference` (arc
//!   gaps) and, conservatively, 1 for `range_balance` elsewhere (`|dr/dg| <= 1` on any curve,
//!   so `k_v*` is not overstated). Where the team does not settle at even spacing of a free ring
//!   (a shifted equilibrium of unequal speeds, each gap with its own chord slope; vehicles with
//!   no speed room, fixed in the frame moving at their speed) the modes are the eigenvalues of
//!   that linearisation ([`linearised::loop_spectrum`]), `k_v* = g*/(T mu_max)`;
//! * the **tracking loop**'s sampled check ([`super::sampled`]) at every speed of a grid over
//!   the range the spacing law may command, `[team.v_min_mps, team.v_max_mps]` (both ends and
//!   `v0` included; the `none` law commands `v0` only): the paper's theory assumes a constant
//!   speed, and the verdict holds only if the loop is stable at every speed of the range.

mod equilibrium;
mod linearised;
mod start;

pub use equilibrium::ShiftedEquilibrium;

use super::regions::Regions;
use super::sampled;
use super::setup::{not_computed, Law, LoopSetup};
use super::team_ring::{
    common_speed, deployed_gaps_ahead, flown_circle_radius_m, start_angle, travel_direction,
};
pub use super::team_ring::{disjoint_envelopes, DisjointEnvelopes};
use super::verdict::Verdict;
use crate::spec::TeamSpec;
use crate::team::TeamIsolineModel;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::spacing::{
    max_stable_gain_per_period, spacing_mode_spectral_radius, spacing_mode_stable, split_delay,
};
use isotrack_core::Vec2;
use isotrack_sim::team::arc::{ArcProjection, CircleArc, PolylineArc};
use isotrack_sim::team::metrics::{TeamMetricsConfig, CLOSE_APPROACH_M};
use isotrack_sim::team::spacing::{RingMode, SpacingLaw};
use serde::Serialize;

/// Speeds of the tracking check's grid over `[v_min, v_max]` (both ends included; `v0` is
/// added when it is not on the grid).
pub const TRACKING_SPEED_GRID: usize = 9;

/// Up to this many distinct nonzero eigenvalues (`floor(N/2)`, a ring of up to 33 vehicles)
/// the report lists every mode; beyond, the slowest (`m = 1`) and the fastest
/// (`m = floor(N/2)`) only. Stability is decided over every mode either way.
pub const MAX_LISTED_MODES: usize = 16;

/// One mode of the ring Laplacian in the spacing loop.
#[derive(Clone, Debug, Serialize)]
pub struct SpacingMode {
    /// The mode's index `m` (`1..=floor(N/2)`; `m` and `N - m` share the eigenvalue); linearised
    /// elsewhere ([`SpacingLoopReport::linearised_about`]), the rank of its distinct eigenvalue,
    /// ascending from 1.
    pub m: usize,
    /// `lambda_m = 2 - 2 cos(2 pi m/N)`; linearised elsewhere, `mu/c` of its eigenvalue `mu`.
    pub lambda: f64,
    /// The gain per ranging period `g_m = k_v c lambda_m T`.
    pub gain_per_period: f64,
    /// The largest root magnitude of the mode's polynomial (< 1: the mode decays).
    pub spectral_radius: Option<f64>,
    /// Whether the mode is Schur-stable.
    pub stable: bool,
}

/// The spacing loop, sampled and delayed.
#[derive(Clone, Debug, Serialize)]
pub struct SpacingLoopReport {
    /// Whether there is a spacing loop to check (`range_balance` or `arc_reference` with at
    /// least three vehicles, or two with `arc_reference`).
    pub applicable: bool,
    /// The scenario's `team.k_v`, 1/s (null for `none`).
    pub k_v_per_s: Option<f64>,
    /// The ranging period `T = 1/team.ranging.rate_hz`, s.
    pub period_s: f64,
    /// `team.ranging.delay_s`, s; 0 for `arc_reference` (att53t-7: the engine reads its true
    /// arc gaps at the ranging steps themselves, without the ranging unit's delay, noise or
    /// losses).
    pub delay_s: f64,
    /// The delay's whole periods `q` (`d = (q + f) T`; null when past the polynomial's degree
    /// cap).
    pub delay_whole_periods: Option<usize>,
    /// The delay's fraction of a period `f`.
    pub delay_fraction: Option<f64>,
    /// The range slope `c = dr/dg` near even spacing.
    pub range_slope: Option<f64>,
    /// Where `c` comes from: `circle_chord` (`cos(pi/N)`, the isoline is a known circle),
    /// `arc_gaps` (`arc_reference`: 1, exact) or `conservative` (1, the isoline's shape is not
    /// known; `|dr/dg| <= 1` on any curve).
    pub range_slope_source: Option<&'static str>,
    /// The ring Laplacian's distinct nonzero eigenvalues with each mode's gain and stability:
    /// every one up to [`MAX_LISTED_MODES`], else the slowest and the fastest.
    pub modes: Vec<SpacingMode>,
    /// Whether `modes` lists every distinct mode.
    pub all_modes_listed: bool,
    /// `lambda_1` (the smallest nonzero eigenvalue, the slowest mode).
    pub lambda_min: Option<f64>,
    /// `lambda_max` (4 for even `N`, `2 + 2 cos(pi/N)` for odd `N`).
    pub lambda_max: Option<f64>,
    /// The largest stable gain per period `g*(q, f)` (2 without delay; Levin & May's
    /// `2 cos(q pi/(2q + 1))` for a whole number of periods).
    pub max_gain_per_period: Option<f64>,
    /// The largest stable `k_v`, 1/s: `k_v* = g*/(T c lambda_max)`.
    pub max_stable_k_v_per_s: Option<f64>,
    /// Whether every mode at the scenario's `k_v` is stable.
    pub stable: Option<bool>,
    /// The slowest sampled mode: the `m` with the largest spectral radius (with a ranging delay
    /// not always `m = 1`: `isotrack_core::spacing::slowest_sampled_mode`).
    pub slowest_mode_m: Option<usize>,
    /// The slowest mode's time constant sampled, `-T/ln(rho)` with that mode's radius, s (null:
    /// it does not decay).
    pub slowest_time_constant_s: Option<f64>,
    /// The same in continuous time, `1/(k_v c lambda_1)`, s.
    pub slowest_time_constant_continuous_s: Option<f64>,
    /// Whether `modes` are bounds, not eigenvalues (past
    /// [`linearised::MAX_DENSE_VEHICLES`] free vehicles with unequal slopes or pins: the first
    /// a lower bound of the smallest, the second an upper bound of the largest; att50-13).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub eigenvalue_bounds: bool,
    /// How the two time constants above read (absent: the linear loop's values):
    /// `lower_bound` (the conservative slope `c = 1` off a known circle makes every `mu` its
    /// largest, so the loop decays no faster, att50-6; the sampled one only without a delay and
    /// with every gain per period at most 1, else null, att53t-6), `upper_bound` (the continuous one from
    /// the lower bound of the smallest `mu`, the sampled one not computed, att50-13),
    /// `one_sided` (every vehicle on the same envelope bound at the equilibrium, att51-7: the
    /// one-sided law's slowest piece, one vehicle cut, `mu = c (2 - 2 cos(pi/N))`) or
    /// `not_applicable` (some vehicles on a bound otherwise, or bounds of the spectrum with the
    /// conservative slope; both null).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_constants: Option<&'static str>,
    /// att51-7: the vehicles free in the linearisation whose equilibrium command sits on an
    /// envelope bound (`team.v_max_mps = v0`, say): each can move one way only, so the law is
    /// one-sided and `time_constants` says what is left of the linear loop's (absent when none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub one_sided_vehicles: Vec<usize>,
    /// att53t-4: whether `modes`, `k_v*` and `stable` are the one-sided law's pieces, not the
    /// free ring's: every vehicle ON the same envelope bound at the equilibrium, one slope
    /// (`time_constants = "one_sided"`). A correction that asks a vehicle past the bound is
    /// cut, so only patterns whose free vehicles all move one way survive: the slowest piece is
    /// the one-pin path's first mode (`lambda = 2 - 2 cos(pi/N)`), the fastest a lone free
    /// vehicle between two cut ones (`mu = c_{i-1} + c_i = 2c`, `lambda = 2`), so
    /// `k_v* = g*/(T 2c)`: the ring's alternating mode (`lambda = 4`) needs half the vehicles
    /// to move the cut way and cannot grow.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub one_sided_stability: bool,
    /// att53t-10: the vehicles of `one_sided_vehicles` are near their bound, not on it: the
    /// least room from the equilibrium's command to that bound, m/s (absent when on it). It is
    /// under the largest correction the deployment asks (`k_v` times the largest deviation of a
    /// vehicle's range difference from the equilibrium's), so the decay from the deployment is
    /// one-sided until every correction fits in the room, i.e. a range difference within
    /// `room/k_v` of the equilibrium's, and the linear loop's below that.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub one_sided_room_mps: Option<f64>,
    /// Past `k_v*` (the linear loop unstable; null otherwise): how far the speed saturation lets
    /// a gap swing about the even spacing, m. The unstable mode grows until the commanded
    /// speeds saturate; then each vehicle runs at `team.v_min_mps` or `team.v_max_mps`, so a
    /// gap (`g_i' = v_{i+1} - v_i`) moves at most `(v_max - v_min) T` per ranging period, and
    /// the fastest mode (`m = floor(N/2)`, neighbours at opposite speeds, the first to go
    /// unstable) reverses `q + 1` periods after a gap crosses the even spacing (the range it
    /// acts on is `d = (q + f) T` old): a bounded oscillation of amplitude up to
    /// `(v_max - v_min)(T + d)` (for `d = 0`, the relay map `a' = a - (v_max - v_min) T sgn a`
    /// flips every period within `(v_max - v_min) T` of even). The team stays spread, the
    /// speeds switch between the bounds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub saturated_gap_amplitude_m: Option<f64>,
    /// The same as a gap CV bound, `saturated_gap_amplitude_m N/L`, when the isoline's length
    /// `L` is known (a circle; null otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub saturated_gap_cv_max: Option<f64>,
    /// Where the ranges fall silent (`team.ranging.max_range_m`): the halt and the largest gap
    /// CV it can leave (absent when no halt exists or the law does not range).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range_halt: Option<RangeHaltReport>,
    /// att44-3: a `max_range_m` above the even spacing's range `e` on a known circle (and short
    /// of its diameter): how fast a gap still out of range closes when its vehicles' other
    /// neighbours sit at `e`, `2 k_v (max_range_m - e)`, m/s. The excess of a silent gap over
    /// the range does not push (the law sees `max_range_m`), so a clustered team spreads at
    /// this pace until every neighbour is in range; the time constants are the linear loop's,
    /// with every neighbour heard (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub silent_gap_closing_mps: Option<f64>,
    /// `range_balance` or `arc_reference` (att50-2) with unequal nominal speeds on a known circle
    /// (att44-6, -7): the equilibrium the loop converges to, solved for its ranges (arc gaps),
    /// or why there is none (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shifted_equilibrium: Option<ShiftedEquilibrium>,
    /// Where the loop is linearised when not at even spacing of a free ring (absent there):
    /// `shifted_equilibrium` (the chord slopes of its gaps, att46-1, -16) or `pinned` (vehicles
    /// with no speed room, or saturated at an envelope bound at the equilibrium (att50-1), fixed
    /// in the frame moving at their speed, att46-9). The modes are then
    /// the eigenvalues `mu` of `K = D^T C D` over the free vehicles (docs/TEAMS.md, "Theory"),
    /// each listed with `lambda = mu/c`, and `k_v* = g*/(T mu_max)`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linearised_about: Option<&'static str>,
    /// att50-11: which range slopes that linearisation uses (absent with `linearised_about`):
    /// `shifted_equilibrium` (each gap's own chord slope `cos(g_i/(2R'))` at the solved shifted
    /// equilibrium), `pinned_best_arcs` (the chords of the arcs the vehicles between two of no
    /// speed room share evenly) or `range_slope` (`c` for every gap).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linearised_slopes: Option<&'static str>,
    /// The slope of each gap (listed order, vehicle `i` to the one ahead) in that linearisation
    /// (empty without `linearised_about`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gap_slopes: Vec<f64>,
    /// The vehicles fixed in the linearisation for having no speed room (`v_min_i = v_max_i`),
    /// listed order (empty unless `linearised_about = "pinned"`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pinned_vehicles: Vec<usize>,
    /// The vehicles fixed in the linearisation for being saturated at an envelope bound at the
    /// equilibrium (att50-1: their command there past their own envelope), listed order (empty
    /// unless `linearised_about = "pinned"`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub saturated_vehicles: Vec<usize>,
    /// What the linear loop leaves out (noise, dropouts, range limit, speed saturation, the
    /// discovery phase), each with its key.
    pub not_modelled: Vec<String>,
    /// Remarks (why not applicable).
    pub note: String,
}

/// The tracking loop's sampled check over the speeds the spacing law may command.
#[derive(Clone, Debug, Serialize)]
pub struct TeamTrackingReport {
    /// Whether the sampled check applies (the PI-like law).
    pub applicable: bool,
    /// `[v_min, v_max]` the law may command (`[v0, v0]` for `none`), m/s.
    pub speed_range_mps: [f64; 2],
    /// The speeds checked, m/s (ascending).
    pub speeds_mps: Vec<f64>,
    /// The worst spectral radius over the isoline's slopes at each speed (null: not computed).
    pub spectral_radii: Vec<Option<f64>>,
    /// The largest of `spectral_radii`.
    pub worst_spectral_radius: Option<f64>,
    /// The speed where it occurs, m/s.
    pub worst_speed_mps: Option<f64>,
    /// Whether the loop is stable at every speed checked (null: some speed not computed).
    pub stable_over_range: Option<bool>,
    /// The vehicles' distinct sensor rates, Hz, when they differ (`team.vehicles`): each
    /// speed's radius is then the worst over them (absent with one rate).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sensor_rates_hz: Vec<f64>,
    /// Remarks.
    pub note: String,
}

/// The `team` section.
#[derive(Clone, Debug, Serialize)]
pub struct TeamCheckReport {
    /// `team.count`.
    pub count: usize,
    /// `team.spacing`.
    pub spacing_law: &'static str,
    /// Whether the law is coordinate-free (`arc_reference` is not: a reference).
    pub coordinate_free: bool,
    /// `holds` (both loops stable, or the spacing loop absent and the tracking loop stable over
    /// the range), `fails` (either unstable), `not_applicable` otherwise.
    pub verdict: Verdict,
    /// One sentence on why.
    pub verdict_reason: String,
    /// The spacing loop.
    pub spacing: SpacingLoopReport,
    /// The tracking loop over the commanded speeds.
    pub tracking: TeamTrackingReport,
}

/// The range slope `c` and its source for the scenario's law.
fn range_slope(s: &Scenario, law: &SpacingLaw, n: usize) -> (f64, &'static str) {
    match law {
        SpacingLaw::ArcReference { .. } => (1.0, "arc_gaps"),
        _ if s.team_arc().is_some() => ((std::f64::consts::PI / n as f64).cos(), "circle_chord"),
        _ => (1.0, "conservative"),
    }
}

/// The spacing loop of `team` in scenario `s` flown by law `l` ([`SpacingLoopReport`]): why
/// there is none, or its modes' stability at the law's gain.
fn spacing_report(s: &Scenario, l: &Law, team: &TeamSpec) -> SpacingLoopReport {
    let n = team.count();
    let mut rep = spacing_report_unchecked(s, l, team);
    let k_v = match team.law {
        SpacingLaw::None => {
            rep.note = "team.spacing = \"none\": every vehicle at v0, no spacing loop (the spacing stays as deployed)".into();
            return rep;
        }
        SpacingLaw::RangeBalance { gain_per_s } | SpacingLaw::ArcReference { gain_per_s } => {
            gain_per_s
        }
    };
    rep.k_v_per_s = Some(k_v);
    if let Some(why) = no_spacing_loop(s, team, k_v) {
        rep.note = why;
        return rep;
    }
    if let Some(why) = no_free_vehicle(team) {
        rep.note = why;
        return rep;
    }
    let (c, source) = range_slope(s, &team.law, n);
    rep.range_slope = Some(c);
    rep.range_slope_source = Some(source);
    rep.applicable = true;
    let (slopes, slopes_from) = loop_slopes(s, l, team, &rep, c);
    let (pinned, saturated) = fixed_vehicles(team, &rep);
    let mut pins = vec![false; n];
    pinned
        .iter()
        .chain(&saturated)
        .for_each(|&i| pins[i] = true);
    let pinned_some = pins.iter().any(|&p| p) && !pins.iter().all(|&p| p);
    let spectrum = linearised::loop_spectrum(c, &slopes, &pins)
        .filter(|_| pinned_some)
        .or_else(|| linearised::loop_spectrum(c, &slopes, &vec![false; n]));
    let Some(spectrum) = spectrum else {
        rep.applicable = false;
        rep.note = "not computed: the range slopes at the equilibrium are not in (0, 1]".into();
        return rep;
    };
    record_linearisation(
        &mut rep,
        pinned_some,
        slopes_from,
        &slopes,
        (pinned, saturated),
    );
    let lambdas = &spectrum.lambdas;
    rep.lambda_min = Some(lambdas[0]);
    rep.lambda_max = Some(lambdas[lambdas.len() - 1]);
    let (period_s, delay_s) = (rep.period_s, rep.delay_s);
    let Some(g_star) = max_stable_gain_per_period(period_s, delay_s) else {
        rep.note = format!(
            "not computed: a delay of {} periods is past the {} the check's polynomial holds",
            Num(delay_s / period_s),
            isotrack_core::spacing::MAX_DEGREE - 2
        );
        return rep;
    };
    rep.max_gain_per_period = Some(g_star);
    rep.max_stable_k_v_per_s = rep
        .lambda_max
        .map(|lmax| g_star / (period_s * c * lmax))
        .filter(|k| k.is_finite());
    check_spacing_modes(&mut rep, k_v, c, &spectrum);
    let reach = deployed_correction_mps(s, l, team, &rep);
    time_constant_caveats(&mut rep, team, &pins, &slopes, &spectrum, reach);
    if rep.stable == Some(false) {
        note_saturated_gaps(&mut rep, s, team);
    }
    rep.not_modelled = spacing_not_modelled(team, n, &rep);
    rep
}

/// att53t-9: the note when no vehicle has speed room (every one pinned at `v0`): no mode to
/// list and no time constant; `None` when one is free.
fn no_free_vehicle(team: &TeamSpec) -> Option<String> {
    let stuck = equilibrium::pinned(team);
    (stuck.len() == team.count()).then(|| {
        format!(
            "no free vehicle: {} (no speed room), so {} has no speed to command but v0 and there is no loop to linearise: no modes, k_v* or time constants; the gaps stay as deployed (the verdict judges the deployment)",
            equilibrium::pinned_keys(team, &stuck),
            team.law.name()
        )
    })
}

/// What the linearisation of [`spacing_report`] was taken about (att50-11): the pinned
/// vehicles' frame, the shifted equilibrium, or (`None`) the even ring; its slopes and the
/// fixed vehicles `(pinned, saturated)` when some but not all are fixed.
fn record_linearisation(
    rep: &mut SpacingLoopReport,
    pinned_some: bool,
    slopes_from: &'static str,
    slopes: &[f64],
    (pinned, saturated): (Vec<usize>, Vec<usize>),
) {
    rep.linearised_about = match (pinned_some, slopes_from) {
        (true, _) => Some("pinned"),
        (false, "shifted_equilibrium") => Some("shifted_equilibrium"),
        (false, _) => None,
    };
    if rep.linearised_about.is_some() {
        rep.linearised_slopes = Some(slopes_from);
        rep.gap_slopes = slopes.to_vec();
    }
    if pinned_some {
        (rep.pinned_vehicles, rep.saturated_vehicles) = (pinned, saturated);
    }
}

/// The vehicles the linearisation fixes in the frame moving at the team's speed: those with no
/// speed room ([`equilibrium::pinned`]) and, att50-1, those saturated at an envelope bound at
/// the solved equilibrium ([`equilibrium::saturated`]), each listed order.
fn fixed_vehicles(team: &TeamSpec, rep: &SpacingLoopReport) -> (Vec<usize>, Vec<usize>) {
    let saturated = rep
        .shifted_equilibrium
        .as_ref()
        .map_or(vec![], |eq| equilibrium::saturated(team, eq));
    (equilibrium::pinned(team), saturated)
}

/// The spacing loop's report before its law is checked: the ranging's period and delay, the
/// range halt; nothing applicable yet.
fn spacing_report_unchecked(s: &Scenario, l: &Law, team: &TeamSpec) -> SpacingLoopReport {
    let period_s = 1.0 / team.ranging.rate_hz;
    let delay_s = match team.law {
        SpacingLaw::ArcReference { .. } => 0.0,
        _ => team.ranging.delay_s,
    };
    let split = split_delay(period_s, delay_s);
    SpacingLoopReport {
        applicable: false,
        k_v_per_s: None,
        period_s,
        delay_s,
        delay_whole_periods: split.map(|x| x.0),
        delay_fraction: split.map(|x| x.1),
        range_slope: None,
        range_slope_source: None,
        modes: vec![],
        all_modes_listed: false,
        lambda_min: None,
        lambda_max: None,
        max_gain_per_period: None,
        max_stable_k_v_per_s: None,
        stable: None,
        slowest_mode_m: None,
        slowest_time_constant_s: None,
        slowest_time_constant_continuous_s: None,
        eigenvalue_bounds: false,
        time_constants: None,
        one_sided_vehicles: vec![],
        one_sided_stability: false,
        one_sided_room_mps: None,
        saturated_gap_amplitude_m: None,
        saturated_gap_cv_max: None,
        range_halt: range_halt(s, l, team),
        silent_gap_closing_mps: silent_gap_closing_mps(s, l, team),
        shifted_equilibrium: s.team_arc().and_then(|c| {
            equilibrium::shifted_equilibrium(s, l, team, c, |v| flown_radius_at(s, l, c, v))
        }),
        linearised_about: None,
        linearised_slopes: None,
        gap_slopes: vec![],
        pinned_vehicles: vec![],
        saturated_vehicles: vec![],
        not_modelled: vec![],
        note: String::new(),
    }
}

/// Why a team whose law has gain `k_v` has no spacing loop to check (the report's note), or
/// `None` when it has one.
fn no_spacing_loop(s: &Scenario, team: &TeamSpec, k_v: f64) -> Option<String> {
    let n = team.count();
    if let Some(why) = s.team_refusal() {
        // att32g-3: `run` refuses it (65); no loop of a run that never starts holds.
        return Some(format!(
            "not applicable: `isotrack run` refuses this scenario: {why}"
        ));
    }
    if k_v == 0.0 {
        // att32d-9: at g = 0 every mode's roots sit at z = 1 (marginal): the law commands v0
        // whatever the ranges, as `none` does; no loop to be past k_v*, no saturation.
        return Some(format!(
            "team.k_v = 0: {} commands v0 whatever the gaps, as team.spacing = \"none\": no spacing loop, the gaps stay as deployed and do not converge",
            team.law.name()
        ));
    }
    if n < 2 {
        return Some("a team of one: no spacing loop".into());
    }
    if n == 2 && matches!(team.law, SpacingLaw::RangeBalance { .. }) {
        return Some("with two vehicles the neighbour ahead is the neighbour behind: range_balance sees the same range twice and does nothing (use arc_reference or more vehicles)".into());
    }
    None
}

/// The range slope of each gap (listed order) at the equilibrium the loop is linearised
/// about, and where they come from ([`SpacingLoopReport::linearised_slopes`]:
/// `shifted_equilibrium`, `pinned_best_arcs`, `range_slope`): on a known circle the chord
/// slopes `cos(g_i/(2R'))` of the solved equilibrium's gaps (unequal nominal speeds) or of the
/// best case vehicles with no speed room leave ([`equilibrium::pinned_best_arcs`]); else `c`
/// for every gap.
fn loop_slopes(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    rep: &SpacingLoopReport,
    c: f64,
) -> (Vec<f64>, &'static str) {
    let n = team.count();
    if rep.range_slope_source != Some("circle_chord") {
        return (vec![c; n], "range_slope");
    }
    let solved = rep.shifted_equilibrium.as_ref().filter(|e| e.exists());
    if let (Some(eq), Some(circle)) = (solved, s.team_arc()) {
        let d = 2.0 * flown_radius_at(s, l, circle, eq.speed_mps);
        let slopes = eq
            .ranges_m
            .iter()
            .map(|r| (1.0 - (r / d).powi(2)).max(0.0).sqrt())
            .collect();
        return (slopes, "shifted_equilibrium");
    }
    match equilibrium::pinned_best_arcs(s, l, team) {
        Some(arcs) => (
            arcs.iter().map(|a| (a / 2.0).cos()).collect(),
            "pinned_best_arcs",
        ),
        None => (vec![c; n], "range_slope"),
    }
}

/// The spacing loop's modes at gain `k_v` (the report's period and delay), one per distinct
/// eigenvalue `mu` of the linearised loop (`spectrum`, [`linearised::loop_spectrum`]; at even
/// spacing `mu = c lambda_m`): whether every mode is stable, the modes listed (each with its
/// `mu/c` as `lambda`), the slowest.
fn check_spacing_modes(
    rep: &mut SpacingLoopReport,
    k_v: f64,
    c: f64,
    spectrum: &linearised::LoopSpectrum,
) {
    let (period_s, delay_s) = (rep.period_s, rep.delay_s);
    let mu = &spectrum.lambdas;
    let gain = |k: usize| k_v * c * mu[k] * period_s;
    // Every mode decides (not only the scan's g*): one Schur test each.
    rep.stable = Some((0..mu.len()).all(|k| spacing_mode_stable(gain(k), period_s, delay_s)));
    rep.all_modes_listed = spectrum.exact && mu.len() <= MAX_LISTED_MODES;
    let listed: Vec<usize> = if rep.all_modes_listed {
        (0..mu.len()).collect()
    } else {
        vec![0, mu.len() - 1]
    };
    let radius = |k: usize| spacing_mode_spectral_radius(gain(k), period_s, delay_s);
    rep.modes = listed
        .into_iter()
        .map(|k| SpacingMode {
            m: k + 1,
            lambda: mu[k],
            gain_per_period: gain(k),
            spectral_radius: radius(k),
            stable: spacing_mode_stable(gain(k), period_s, delay_s),
        })
        .collect();
    // The slowest sampled mode: the largest radius (ties keep the smaller mu).
    let slowest = (0..mu.len())
        .map(|k| (k, radius(k)))
        .try_fold(None::<(usize, f64)>, |best, (k, r)| {
            let r = r?;
            Some(Some(match best {
                Some(b) if b.1 >= r => b,
                _ => (k, r),
            }))
        })
        .flatten()
        .filter(|_| spectrum.exact);
    rep.slowest_mode_m = slowest.map(|(k, _)| k + 1);
    rep.slowest_time_constant_s = slowest
        .map(|(_, rho)| {
            if rho >= 1.0 {
                f64::INFINITY
            } else {
                -period_s / rho.ln()
            }
        })
        .filter(|t| t.is_finite());
    rep.slowest_time_constant_continuous_s =
        Some(1.0 / (k_v * c * mu[0])).filter(|t| t.is_finite());
}

/// How far the linear time constants of `rep` describe the decay ([`SpacingLoopReport::
/// time_constants`]): vehicles on an envelope bound at the equilibrium (not `pins`) make them
/// one-sided (att51-7: [`one_sided_time_constants`]), bounds of the spectrum leave an upper
/// bound of the continuous one (att50-13) and the conservative slope a lower bound of both
/// (att50-6).
fn time_constant_caveats(
    rep: &mut SpacingLoopReport,
    team: &TeamSpec,
    pins: &[bool],
    slopes: &[f64],
    spectrum: &linearised::LoopSpectrum,
    reach_mps: Option<f64>,
) {
    let speed = match rep.shifted_equilibrium.as_ref() {
        Some(eq) => eq.speed_mps,
        None => equilibrium::equilibrium_speed(team),
    };
    rep.one_sided_vehicles = equilibrium::on_bound(team, speed, pins, 0.0);
    // att53t-10: near a bound (its room under the deployment's largest correction) the decay
    // from the deployment is one-sided too, until the corrections fit in the room. Only without
    // vehicles fixed in the linearisation: then the corrections sum to zero round the ring, so
    // a large one each way meets both sides; with pins they need not, and the deployment's
    // largest correction does not say which bound the transient meets.
    let mut reach = 0.0;
    let free = pins.iter().all(|&p| !p);
    if let (true, true, Some(r)) = (free, rep.one_sided_vehicles.is_empty(), reach_mps) {
        rep.one_sided_vehicles = equilibrium::on_bound(team, speed, pins, r);
        reach = r;
        rep.one_sided_room_mps = (!rep.one_sided_vehicles.is_empty()).then(|| {
            rep.one_sided_vehicles
                .iter()
                .map(|&i| {
                    let e = team.speeds(i);
                    (e.max_mps - speed).min(speed - e.min_mps)
                })
                .fold(f64::INFINITY, f64::min)
        });
    }
    rep.eigenvalue_bounds = !spectrum.exact;
    let conservative = rep.range_slope_source == Some("conservative");
    rep.time_constants = if !rep.one_sided_vehicles.is_empty() {
        one_sided_time_constants(rep, team, speed, slopes, reach)
    } else if conservative && !spectrum.exact {
        Some("not_applicable")
    } else if !spectrum.exact {
        Some("upper_bound")
    } else if conservative {
        Some("lower_bound")
    } else {
        None
    };
    if rep.time_constants == Some("not_applicable") {
        rep.slowest_mode_m = None;
        rep.slowest_time_constant_s = None;
        rep.slowest_time_constant_continuous_s = None;
    }
    // att53t-6: c = 1 makes every gain its largest; a sampled mode's radius falls with its gain
    // only while it does not overshoot (no delay, g <= 1: rho = 1 - g), so only then is the
    // sampled time constant at c = 1 a lower bound too. Otherwise it is none: not given.
    let fastest = rep.k_v_per_s.unwrap_or(0.0) * rep.lambda_max.unwrap_or(0.0) * rep.period_s;
    if rep.time_constants == Some("lower_bound") && (rep.delay_s > 0.0 || fastest > 1.0) {
        rep.slowest_mode_m = None;
        rep.slowest_time_constant_s = None;
    }
}

/// att51-7: every vehicle free and on the same envelope bound at the equilibrium, every gap with
/// one slope `c` (`team.v_max_mps = v0` at even spacing): each correction that asks a vehicle
/// past the bound is cut, so the law is one-sided, linear in pieces. The corrections sum to zero,
/// so some vehicle is always cut; the slowest piece has exactly one cut (flying `V`: a pin) and
/// every other vehicle moving the other way, which the one-pin path's first mode is (its
/// eigenvector has one sign, so the pattern keeps itself): `mu = c (2 - 2 cos(pi/N))`, time
/// constant `1/(k_v mu)` (pieces with more cut vehicles decay faster). Sets `rep`'s time
/// constants to it and gives `one_sided`; `not_applicable` in any other case.
fn one_sided_time_constants(
    rep: &mut SpacingLoopReport,
    team: &TeamSpec,
    speed: f64,
    slopes: &[f64],
    reach_mps: f64,
) -> Option<&'static str> {
    let n = team.count();
    let same = equilibrium::on_one_bound(team, speed, &rep.one_sided_vehicles, reach_mps);
    let (Some(k_v), Some(c)) = (rep.k_v_per_s, rep.range_slope) else {
        return Some("not_applicable");
    };
    let conservative = rep.range_slope_source == Some("conservative");
    if rep.one_sided_vehicles.len() != n
        || !same
        || conservative
        || slopes.iter().any(|&x| x != slopes[0])
    {
        return Some("not_applicable");
    }
    let one_pin: Vec<bool> = (0..n).map(|i| i == 0).collect();
    let Some(mu) = linearised::loop_spectrum(c, slopes, &one_pin)
        .filter(|s| s.exact)
        .map(|s| s.lambdas[0])
    else {
        return Some("not_applicable");
    };
    let (period_s, delay_s) = (rep.period_s, rep.delay_s);
    let rho = spacing_mode_spectral_radius(k_v * c * mu * period_s, period_s, delay_s);
    rep.slowest_mode_m = None;
    rep.slowest_time_constant_s = rho.filter(|r| *r < 1.0).map(|r| -period_s / r.ln());
    rep.slowest_time_constant_continuous_s = Some(1.0 / (k_v * c * mu)).filter(|t| t.is_finite());
    if rep.one_sided_room_mps.is_none() {
        // ON the bound (not near it): no linear tail, the pieces decide the stability too.
        one_sided_stability(rep, k_v, c, [mu, 2.0 * slopes[0] / c]);
    }
    Some("one_sided")
}

/// att53t-4: the one-sided law's stability from its pieces ([`SpacingLoopReport::
/// one_sided_stability`]): `lambdas` the slowest piece's (the one-pin path's first mode) and
/// the fastest's (a lone free vehicle between two cut ones), over `c`. Replaces the free ring's
/// modes, `k_v*` and `stable` in `rep`.
fn one_sided_stability(rep: &mut SpacingLoopReport, k_v: f64, c: f64, lambdas: [f64; 2]) {
    let (period_s, delay_s) = (rep.period_s, rep.delay_s);
    let gain = |lambda: f64| k_v * c * lambda * period_s;
    rep.modes = lambdas
        .iter()
        .enumerate()
        .map(|(k, &lambda)| SpacingMode {
            m: k + 1,
            lambda,
            gain_per_period: gain(lambda),
            spectral_radius: spacing_mode_spectral_radius(gain(lambda), period_s, delay_s),
            stable: spacing_mode_stable(gain(lambda), period_s, delay_s),
        })
        .collect();
    rep.all_modes_listed = false;
    rep.lambda_min = Some(lambdas[0]);
    rep.lambda_max = Some(lambdas[1]);
    rep.max_stable_k_v_per_s = rep
        .max_gain_per_period
        .map(|g| g / (period_s * c * lambdas[1]))
        .filter(|k| k.is_finite());
    rep.stable = Some(rep.modes.iter().all(|m| m.stable));
    rep.one_sided_stability = true;
}

/// An unstable spacing loop: the gaps' swing once the speeds saturate (its amplitude, and its
/// gap CV bound about L/N when every vehicle has one nominal speed).
fn note_saturated_gaps(rep: &mut SpacingLoopReport, s: &Scenario, team: &TeamSpec) {
    let n = team.count();
    // The widest swing of any vehicle's speed: the union of the envelopes (att32d-15:
    // the team's [v_min, v_max] alone understated it with per-vehicle envelopes).
    let (lo, hi) = team.speed_envelope_mps();
    let amplitude = (hi - lo) * (rep.period_s + rep.delay_s);
    rep.saturated_gap_amplitude_m = Some(amplitude);
    // About L/N only when every vehicle has one nominal speed (else the oscillation is
    // about the shifted equilibrium of the not-modelled note: no CV bound).
    rep.saturated_gap_cv_max = s
        .team_arc()
        .filter(|_| team.nominal_speeds_mps().len() == 1)
        .map(|a| amplitude * n as f64 / (std::f64::consts::TAU * a.radius_m))
        .filter(|x| x.is_finite());
}

/// The effects the linear spacing loop leaves out, each naming its key.
fn spacing_not_modelled(team: &TeamSpec, n: usize, rep: &SpacingLoopReport) -> Vec<String> {
    let r = &team.ranging;
    let mut out = vec![saturation_note(team, rep)];
    out.extend(unequal_speeds_note(team, rep));
    if let SpacingLaw::ArcReference { .. } = team.law {
        // att53t-7: the engine's arc_reference reads the true arc gaps at the ranging steps.
        let lossy = r.noise_std_m > 0.0 || r.dropout_probability > 0.0;
        if r.delay_s > 0.0 || lossy || r.max_range_m.is_finite() {
            out.push(format!(
                "team.ranging.delay_s = {}, noise_std_m = {}, dropout_probability = {}, max_range_m = {}: arc_reference reads the true arc gaps at the ranging steps, without the ranging unit's delay, noise, losses or range limit, so the loop above is the delay-free one and none of them acts",
                Echo(r.delay_s),
                Echo(r.noise_std_m),
                Echo(r.dropout_probability),
                Echo(r.max_range_m)
            ));
        }
    } else {
        ranging_notes(team, rep, &mut out);
    }
    if let RingMode::Discover(d) = team.ring {
        out.push(format!(
            "team.ring = \"discovered\": the law starts after the discovery ({} s of settling and {} probe slots of {} s){}",
            Num(d.settle_s),
            n,
            Num(d.probe_s),
            equilibrium::probe_cut_note(team).map_or(String::new(), |w| format!("; {w}"))
        ));
    }
    out
}

/// [`spacing_not_modelled`]'s lines on the ranging unit (not `arc_reference`, which reads true
/// arc gaps): noise, dropouts and a finite `max_range_m`, each naming its key.
fn ranging_notes(team: &TeamSpec, rep: &SpacingLoopReport, out: &mut Vec<String>) {
    let r = &team.ranging;
    let halt = rep.range_halt.as_ref();
    if r.noise_std_m > 0.0 {
        out.push(format!(
            "team.ranging.noise_std_m = {} (noise moves the speeds about the loop's equilibrium; it does not change its stability)",
            Echo(r.noise_std_m)
        ));
    }
    out.extend(start::dropout_note(team));
    if r.max_range_m.is_finite() {
        match halt {
            Some(h) => out.push(h.text()),
            None => out.push(format!(
                "team.ranging.max_range_m = {} (beyond it the law sees max_range_m)",
                Echo(r.max_range_m)
            )),
        }
        if let Some(v) = rep.silent_gap_closing_mps {
            out.push(format!(
                "the time constants are the linear loop's, once every neighbour is in range: while a gap's range exceeds team.ranging.max_range_m = {} its excess does not push (the law sees max_range_m), a vehicle with both neighbours silent commands v0, and a silent gap whose vehicles' other neighbours are at the even spacing's range closes at only 2 k_v (max_range_m - even range) = {} m/s, so a clustered team spreads more slowly than the time constants say (the closer max_range_m to the even range, the slower)",
                Echo(r.max_range_m),
                Num(v)
            ));
        }
    }
}

/// "vehicle 3" or "vehicles 0, 2" (listed order).
fn vehicles_text(ids: &[usize]) -> String {
    format!(
        "vehicle{} {}",
        if ids.len() > 1 { "s" } else { "" },
        ids.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// The not-modelled line on speed saturation: the envelope each vehicle's command must stay in
/// for the unsaturated loop to hold, the team's `[team.v_min_mps, team.v_max_mps]` or, with
/// per-vehicle envelopes (`team.vehicles`, att50-11), each vehicle's own, and the vehicles the
/// linearisation fixes at the team's speed.
fn saturation_note(team: &TeamSpec, rep: &SpacingLoopReport) -> String {
    let team_env = format!(
        "[team.v_min_mps, team.v_max_mps] = [{}, {}] m/s",
        Echo(team.v_min_mps),
        Echo(team.v_max_mps)
    );
    let n = team.count();
    let own: Vec<String> = (0..n)
        .filter_map(|i| {
            let e = team.speeds(i);
            (e.min_mps != team.v_min_mps || e.max_mps != team.v_max_mps)
                .then(|| format!("vehicle {i} [{}, {}]", Echo(e.min_mps), Echo(e.max_mps)))
        })
        .collect();
    if own.is_empty() {
        return format!("speed saturation: the loop is the unsaturated law (it holds while v0 + k_v (r_ahead - r_behind) stays in {team_env})");
    }
    let others = if own.len() < n {
        format!(", the others the team's {team_env}")
    } else {
        " m/s".into()
    };
    let fixed: Vec<usize> = rep
        .pinned_vehicles
        .iter()
        .chain(&rep.saturated_vehicles)
        .copied()
        .collect();
    let fixed = if fixed.is_empty() {
        String::new()
    } else {
        format!(
            "; {} fixed in the linearisation fly the team's speed V whatever is commanded",
            vehicles_text(&fixed)
        )
    };
    format!(
        "speed saturation: the loop is the unsaturated law (it holds while each free vehicle's v0_i + k_v (r_ahead - r_behind) stays in its own envelope: {} (team.vehicles){others}{fixed})",
        own.join(", ")
    )
}

/// The not-modelled line on unequal nominal speeds (`None` with one): the common speed `V` and
/// what sets it (the mean, the one speed of vehicles with no speed room, or the bound a vehicle
/// saturates at), the equilibrium's range differences, and what `holds` claims there (att50-10:
/// the loop converges to that equilibrium, not to even spacing).
fn unequal_speeds_note(team: &TeamSpec, rep: &SpacingLoopReport) -> Option<String> {
    let nominal = team.nominal_speeds_mps();
    if nominal.len() < 2 {
        return None;
    }
    let mean = team.ideal_speed_mps();
    let pinned = equilibrium::pinned(team);
    let speed = match common_speed(team, mean) {
        // att50-11: a vehicle with no speed room sets V by its one speed; it is not saturated.
        Some(_) if !pinned.is_empty() => format!(
            "the team moves at V = {} m/s, the one speed of {} (v_min_i = v_max_i: no speed room, pinned, not saturated; the reachable ideal revisit time is L/(N V), not L/sum v0_i)",
            Num(equilibrium::equilibrium_speed(team)),
            vehicles_text(&pinned)
        ),
        Some((v, i, bound)) => format!(
            "the team moves at V = clamp(mean v0 = {}, max v_min_i, min v_max_i) = {} m/s, vehicle {i}'s {bound} (saturated there; the reachable ideal revisit time is L/(N V), not L/sum v0_i)",
            Num(mean),
            Num(v)
        ),
        None => format!("the team moves at the mean v0 = {} m/s", Num(mean)),
    };
    let solved = rep.shifted_equilibrium.as_ref().is_some_and(|e| e.exists());
    Some(format!(
        "team.vehicles: unequal nominal speeds ({} to {} m/s) move the loop's equilibrium: {speed} and vehicle i's range ahead exceeds its range behind by (V - v0_i)/k_v, for every vehicle whose command stays within its own envelope (one pinned, or saturated at the bound that sets V, flies V and takes up the rest); where that equilibrium is solved (a known circle) the modes are linearised there, with each gap's own chord slope; `holds` then claims that the loop converges to that equilibrium ({}), not that the gaps even out, with any number of vehicles of no speed room (att50-10: one rule)",
        Echo(nominal[0]),
        Echo(nominal[nominal.len() - 1]),
        if solved {
            "its gap CV is on the shifted equilibrium line"
        } else {
            "not solved here"
        }
    ))
}

/// Samples of a closed extracted isoline's arc coordinate at which [`min_silent_gap_m`] looks
/// ahead for the first silent neighbour (each crossing then refined by bisection).
pub const SILENT_GAP_SAMPLES: usize = 2048;

/// Where `range_balance`'s ranges fall silent (nu39-7, att41-5/-6/-19): past
/// `team.ranging.max_range_m` the law sees `max_range_m` for a neighbour, so a vehicle whose
/// two neighbours are both out of range commands `v0`. With equal nominal speeds the team
/// halts there: every vehicle at `v0`, the gaps frozen. Every equilibrium of the law has all
/// its neighbours in range with equal ranges, or all out of range (one silent neighbour and one
/// heard give unequal ranges, and the silence passes round the ring); on a circle equal ranges
/// are equal gaps, so with even spacing out of range every equilibrium is a halt. A halt has
/// every arc gap at least `g_min` (the shortest arc whose chord reaches `max_range_m`), and the
/// gaps sum to the isoline's length `L`: the largest gap CV such a halt can leave (the
/// population CV the run reports) is that of `N - 1` gaps of `g_min` and one of
/// `g_min + slack`, `slack = L - N g_min`: `slack sqrt(N - 1)/L` (0 when even spacing is just
/// in range, rising continuously as the range shortens).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RangeHaltReport {
    /// `team.ranging.max_range_m`, m.
    pub max_range_m: f64,
    /// The isoline's length `L`, m (the circle's, or the extracted closed loop's).
    pub isoline_length_m: f64,
    /// `g_min`: the shortest arc between two points of the isoline whose chord reaches
    /// `max_range_m` (`2 R asin(max_range/(2 R))` on a circle; on an extracted loop the least
    /// over [`SILENT_GAP_SAMPLES`] starting points), m.
    pub min_silent_gap_m: f64,
    /// The range between neighbours at even spacing on a known circle, `2 R sin(pi/N)`, m
    /// (absent on an extracted loop, where it varies along it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub even_range_m: Option<f64>,
    /// The largest gap CV a halt can leave, `(L - N g_min) sqrt(N - 1)/L`.
    pub worst_gap_cv: f64,
    /// The gap CV at or below which a team counts as even (`time_to_even_s`'s).
    pub even_gap_cv: f64,
    /// The radius of the circle the team flies when it is not the isoline's (att43-6: the P
    /// law, `ki = 0`, settles on an orbit off it, [`super::setup::p_law_orbit`]), m: the ranges
    /// are chords of that circle, so the bound is computed on it (absent: the isoline's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flown_radius_m: Option<f64>,
    /// On a known circle, the gap CV of the team's starts (the arc gaps between them in angular
    /// order about its centre, a CV the same whichever way the team travels), absent elsewhere.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deployed_gap_cv: Option<f64>,
    /// Whether every neighbour is out of range at the start (att43-3): every arc gap of the
    /// starts at least `g_min` and every chord between neighbouring starts at least
    /// `max_range_m`. The team is then halted from the start and keeps its deployment, so the
    /// halt's CV is `deployed_gap_cv`, not the worst over deployments.
    pub deployed_all_silent: bool,
}

impl RangeHaltReport {
    /// Whether a halt can leave the team uneven (`worst_gap_cv > even_gap_cv`): the spacing
    /// law's claim (the gaps converge to even) does not hold.
    pub fn fails(&self) -> bool {
        self.halt_gap_cv() > self.even_gap_cv
    }

    /// The gap CV the verdict judges: the deployment's when the team is halted from the start
    /// ([`Self::deployed_all_silent`]), else the worst a halt can leave.
    pub fn halt_gap_cv(&self) -> f64 {
        match (self.deployed_all_silent, self.deployed_gap_cv) {
            (true, Some(cv)) => cv,
            _ => self.worst_gap_cv,
        }
    }

    /// What the halt is, in words (the `fails` verdict's reason and `not_modelled`'s line).
    pub fn text(&self) -> String {
        let even = match self.even_range_m {
            Some(d) => format!(
                "the even spacing's range is {} m (the chord 2 r sin(pi/N) of the team's circle)",
                Num(d)
            ),
            None => "the isoline is an extracted loop".into(),
        };
        let flown = self.flown_radius_m.map_or(String::new(), |r| {
            format!(
                " (the circle the team flies, radius {} m: with ki = 0 the P law's orbit is off the isoline, and the ranges are its chords)",
                Num(r)
            )
        });
        let halt = match (self.deployed_all_silent, self.deployed_gap_cv) {
            (true, Some(cv)) => format!(
                "every neighbour is out of range at the start, so the team halts as deployed, with the starts' gap CV {}",
                Num(cv)
            ),
            _ => format!(
                "a halt on this isoline (L = {} m{flown}) can leave a gap CV up to {} (the worst over deployments{})",
                Num(self.isoline_length_m),
                Num(self.worst_gap_cv),
                self.deployed_gap_cv
                    .map_or(String::new(), |cv| format!("; the starts' is {}", Num(cv)))
            ),
        };
        format!(
            "team.ranging.max_range_m = {}: where both neighbours are beyond it range_balance sees max_range_m for both, commands v0 and the team halts; {even}, every arc gap of at least {} m is out of range, so {halt} (even: {})",
            Echo(self.max_range_m),
            Num(self.min_silent_gap_m),
            Num(self.even_gap_cv)
        )
    }
}

/// [`RangeHaltReport`] for a scenario whose team runs `range_balance` (`k_v > 0`) with at
/// least three vehicles at one nominal speed and a finite `max_range_m`, on a known circle or an
/// extracted closed loop; `None` otherwise, or when no halt exists (`N g_min >= L`: at even
/// spacing every neighbour is heard). Two vehicles have no spacing loop whatever the range
/// (each sees its one neighbour twice, att41-19); unequal speeds do not halt (the slower are
/// lapped: the spacing loop's `team.vehicles` note).
pub(super) fn range_halt(s: &Scenario, l: &Law, team: &TeamSpec) -> Option<RangeHaltReport> {
    let SpacingLaw::RangeBalance { gain_per_s } = team.law else {
        return None;
    };
    let r = team.ranging.max_range_m;
    let n = team.count();
    if gain_per_s == 0.0 || !r.is_finite() || n < 3 || team.nominal_speeds_mps().len() != 1 {
        return None;
    }
    let mut flown_radius_m = None;
    let mut deployed = None;
    let (length_m, g_min, even_range_m) = match s.team_isoline() {
        TeamIsolineModel::Circle(c) => {
            // The ranges are chords of the circle flown: the P law's orbit when it has one
            // (att43-6), else the isoline. Gaps are measured along the isoline (the metrics
            // project onto it), the same fractions of a turn as along the orbit.
            let flown = flown_circle_radius_m(s, l, c);
            flown_radius_m = (flown != c.radius_m).then_some(flown);
            let d = 2.0 * flown;
            if r >= d {
                return None;
            }
            let theta_min = 2.0 * (r / d).asin();
            deployed = deployed_on_circle(team, c, theta_min, r);
            let even = d * (std::f64::consts::PI / n as f64).sin();
            (c.length_m(), theta_min * c.radius_m, Some(even))
        }
        TeamIsolineModel::Polyline(p) if p.is_closed() => {
            let l = p.length_m();
            (l, min_silent_gap_m(&p, r, l / n as f64)?, None)
        }
        _ => return None,
    };
    let slack = length_m - n as f64 * g_min;
    (slack > 0.0 && length_m > 0.0).then(|| RangeHaltReport {
        max_range_m: r,
        isoline_length_m: length_m,
        min_silent_gap_m: g_min,
        even_range_m,
        worst_gap_cv: slack * ((n - 1) as f64).sqrt() / length_m,
        even_gap_cv: TeamMetricsConfig::default().even_gap_cv,
        flown_radius_m,
        deployed_gap_cv: deployed.map(|d| d.gap_cv),
        deployed_all_silent: deployed.is_some_and(|d| d.all_silent),
    })
}

/// [`flown_circle_radius_m`] of a vehicle flying `speed_mps` (att50-12: at a shifted
/// equilibrium every vehicle flies the common speed `V`, and the P law's orbit moves with it).
fn flown_radius_at(s: &Scenario, l: &Law, c: CircleArc, speed_mps: f64) -> f64 {
    flown_circle_radius_m(s, &Law { v: speed_mps, ..*l }, c)
}

/// [`SpacingLoopReport::silent_gap_closing_mps`]: `2 k_v (max_range_m - e)` for
/// `range_balance` on a known circle with `e < max_range_m < 2 R'` (`e = 2 R' sin(pi/N)`, the
/// even spacing's range on the circle flown), `None` otherwise.
fn silent_gap_closing_mps(s: &Scenario, l: &Law, team: &TeamSpec) -> Option<f64> {
    let SpacingLaw::RangeBalance { gain_per_s } = team.law else {
        return None;
    };
    let m = team.ranging.max_range_m;
    let n = team.count();
    if gain_per_s <= 0.0 || n < 3 || !m.is_finite() {
        return None;
    }
    let d = 2.0 * flown_circle_radius_m(s, l, s.team_arc()?);
    let even = d * (std::f64::consts::PI / n as f64).sin();
    (m > even && m < d).then_some(2.0 * gain_per_s * (m - even))
}

/// The team's starts on a known circle ([`deployed_on_circle`]).
#[derive(Clone, Copy, Debug)]
struct Deployment {
    /// The gap CV of the starts (population CV of the arc gaps in angular order).
    gap_cv: f64,
    /// Every angular gap at least `theta_min` and every chord between neighbouring starts at
    /// least the range: every neighbour out of range at the start.
    all_silent: bool,
    /// The longest chord between neighbouring starts, m, and the pair (listed indices).
    widest_chord: (f64, [usize; 2]),
    /// The least `cos(theta/2)` over the arcs `theta` between neighbouring starts under half
    /// the circle: how much of a probe's speed change a neighbour's range shows (att50-3), 1
    /// when none is.
    probe_slope: f64,
}

/// The starts of `team` on `circle`, in angular order about its centre (the same set of gaps
/// whichever way the team travels): their gap CV, whether every neighbour is out of `range_m`
/// (angular gap at least `theta_min` rad and chord at least `range_m`), and the widest chord
/// between neighbours. `None` for fewer than two starts or one off the circle
/// ([`start_angle`]).
fn deployed_on_circle(
    team: &TeamSpec,
    circle: CircleArc,
    theta_min: f64,
    range_m: f64,
) -> Option<Deployment> {
    let mut at: Vec<(f64, usize)> = (0..team.count())
        .map(|i| start_angle(team, circle, i).map(|a| (a, i)))
        .collect::<Option<_>>()?;
    if at.len() < 2 {
        return None;
    }
    at.sort_by(|a, b| a.0.total_cmp(&b.0));
    let start = |i: usize| Vec2::new(team.starts[i].x_m, team.starts[i].y_m);
    let n = at.len();
    let mut gaps = Vec::with_capacity(n);
    let mut all_silent = true;
    let mut widest = (0.0, [0, 0]);
    let mut probe_slope: f64 = 1.0;
    for k in 0..n {
        let (a, b) = (at[k], at[(k + 1) % n]);
        let gap = if k + 1 < n {
            b.0 - a.0
        } else {
            std::f64::consts::TAU - (a.0 - b.0)
        };
        let chord = (start(b.1) - start(a.1)).norm();
        all_silent &= gap >= theta_min && chord >= range_m;
        if chord > widest.0 {
            widest = (chord, [a.1, b.1]);
        }
        if gap < std::f64::consts::PI {
            probe_slope = probe_slope.min((gap / 2.0).cos());
        }
        gaps.push(gap);
    }
    let mean = std::f64::consts::TAU / n as f64;
    let var = gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n as f64;
    Some(Deployment {
        gap_cv: var.sqrt() / mean,
        all_silent,
        widest_chord: widest,
        probe_slope,
    })
}

/// The shortest arc `g <= cap_m` from any of [`SILENT_GAP_SAMPLES`] points of the closed
/// isoline `p` to the first point ahead whose chord reaches `range_m` (`cap_m` when none does
/// within it; `None` for a degenerate loop). Written here: a scan of chords along an arc, no
/// library's. The crossing is bracketed on the sampling grid and bisected, keeping the lower
/// end (a shorter `g_min`: the CV bound errs high, never low).
fn min_silent_gap_m(p: &PolylineArc, range_m: f64, cap_m: f64) -> Option<f64> {
    let l = p.length_m();
    let step = l / SILENT_GAP_SAMPLES as f64;
    if !(step > 0.0 && cap_m > 0.0) {
        return None;
    }
    let chord = |a: Vec2, s: f64| p.point_at(s).map_or(0.0, |b| (b - a).norm());
    let mut best = cap_m;
    for k in 0..SILENT_GAP_SAMPLES {
        let s0 = k as f64 * step;
        let a = p.point_at(s0)?;
        let mut g = step;
        while g < best && chord(a, s0 + g) < range_m {
            g += step;
        }
        if g >= best {
            continue;
        }
        let (mut lo, mut hi) = (g - step, g);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if chord(a, s0 + mid) < range_m {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        best = best.min(lo);
    }
    Some(best)
}

/// A team whose every range is dropped (`team.ranging.dropout_probability = 1`): no vehicle
/// ever ranges a neighbour, so a law that needs ranges does nothing. Warned, not refused: the
/// run is well defined (`range_balance` holds every vehicle at `v0`, the `none` law, since a
/// neighbour that never answers counts as at the range limit on both sides, or as no range at
/// all; a discovered ring finds no neighbour), and a sweep of the dropout up to 1 keeps its
/// last cell as that control. `None` when some range gets through or no law uses them.
pub fn ranging_warning(s: &Scenario) -> Option<String> {
    let team = s.spec().team.as_ref()?;
    let ranges = matches!(team.law, SpacingLaw::RangeBalance { .. });
    let discovered = matches!(team.ring, RingMode::Discover(_));
    if team.ranging.dropout_probability < 1.0 || team.count() < 2 || !(ranges || discovered) {
        return None;
    }
    let mut what = vec![];
    if ranges {
        what.push("range_balance holds every vehicle at v0 (as team.spacing = \"none\": the spacing stays as deployed)");
    }
    if discovered {
        what.push("team.ring = \"discovered\" finds no neighbour");
    }
    Some(format!(
        "team.ranging.dropout_probability = {}: every range is dropped, so no vehicle ever ranges a neighbour: {}",
        Echo(team.ranging.dropout_probability),
        what.join("; ")
    ))
}

/// The speeds the tracking check covers: `v0` for `none`, else a grid over `[v_min, v_max]`
/// with both ends and `v0`.
///
/// With per-vehicle speeds (`team.vehicles`) the grid spans the union of the vehicles' envelopes
/// and holds every vehicle's `v0_i` (`none`: the `v0_i` only), conservative for each vehicle.
fn tracking_speeds(team: &TeamSpec) -> ([f64; 2], Vec<f64>) {
    let nominal = team.nominal_speeds_mps();
    let no_loop = match team.law {
        SpacingLaw::None => true,
        SpacingLaw::RangeBalance { gain_per_s } | SpacingLaw::ArcReference { gain_per_s } => {
            gain_per_s == 0.0
        }
    };
    if no_loop || team.count() < 2 {
        let (lo, hi) = (nominal[0], nominal[nominal.len() - 1]);
        return ([lo, hi], nominal);
    }
    let (lo, hi) = team.speed_envelope_mps();
    let k = TRACKING_SPEED_GRID - 1;
    let mut v: Vec<f64> = (0..=k)
        .map(|i| {
            if i == k {
                hi
            } else {
                lo + (hi - lo) * i as f64 / k as f64
            }
        })
        .collect();
    // A nominal speed replaces a grid point within rounding of it (att32d-16: `0.3` and the
    // grid's `0.1 + 0.8 * 2/8 = 0.30000000000000004` were both listed).
    let near = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    for v0 in nominal {
        match v.iter_mut().find(|g| near(**g, v0)) {
            Some(g) => *g = v0,
            None => v.push(v0),
        }
    }
    v.sort_by(f64::total_cmp);
    v.dedup();
    ([lo, hi], v)
}

fn tracking_report(s: &Scenario, l: &Law, r: &Regions, team: &TeamSpec) -> TeamTrackingReport {
    let (range, speeds) = tracking_speeds(team);
    let mut rep = TeamTrackingReport {
        applicable: false,
        speed_range_mps: range,
        speeds_mps: speeds.clone(),
        spectral_radii: vec![],
        worst_spectral_radius: None,
        worst_speed_mps: None,
        stable_over_range: None,
        sensor_rates_hz: vec![],
        note: String::new(),
    };
    // Every vehicle's sensor period (per-vehicle rates, `team.vehicles`): each speed's
    // radius is the worst over them.
    let rates = team.sensor_rates_hz(s.spec().sensor.rate_hz);
    if rates.len() > 1 {
        rep.sensor_rates_hz = rates.clone();
    }
    let mut notes = vec![];
    for &v in &speeds {
        let lv = Law { v, ..*l };
        let setup = match LoopSetup::new(s, &lv, r) {
            Ok(x) => x,
            Err(note) => {
                rep.note = note;
                rep.spectral_radii.clear();
                return rep;
            }
        };
        let mut worst: Option<f64> = Some(f64::NEG_INFINITY);
        for &rate in &rates {
            let (base, slopes, orbit) = setup.at(s, &lv, 1.0 / rate);
            if let Some(why) = not_computed(&base, orbit.as_ref()) {
                notes.push(format!("at {} m/s not computed: {}", Num(v), why.reason()));
                worst = None;
                break;
            }
            let rho = sampled::worst_spectral_radius(&base, &slopes);
            worst = worst.map(|w| if rho.total_cmp(&w).is_gt() { rho } else { w });
        }
        rep.spectral_radii.push(worst);
    }
    rep.applicable = true;
    let worst = speeds
        .iter()
        .zip(&rep.spectral_radii)
        .filter_map(|(&v, r)| r.map(|r| (v, r)))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((v, rho)) = worst {
        rep.worst_speed_mps = Some(v);
        rep.worst_spectral_radius = rho.is_finite().then_some(rho);
        let all_computed = rep.spectral_radii.iter().all(Option::is_some);
        rep.stable_over_range = if rho >= 1.0 {
            Some(false)
        } else if all_computed {
            Some(true)
        } else {
            None
        };
    }
    if speeds.len() > 1 {
        notes.push(format!(
            "each speed's loop is the constant-speed linearisation (the speed changes slowly next to the tracking loop when the spacing loop is slow); the grid has {} speeds",
            speeds.len()
        ));
    }
    rep.note = notes.join("; ");
    rep
}

/// The `team` section of a scenario with `[team]` (`None` without).
pub(super) fn team_report(s: &Scenario, l: &Law, r: &Regions) -> Option<TeamCheckReport> {
    let team = s.spec().team.as_ref()?;
    let spacing = spacing_report(s, l, team);
    let tracking = tracking_report(s, l, r, team);
    let (verdict, verdict_reason) = match s.team_refusal() {
        Some(why) => (
            Verdict::NotApplicable,
            format!("`isotrack run` refuses this scenario (exit 65): {why}"),
        ),
        None => match range_balance_out_of_range(&spacing) {
            Some(why) => (Verdict::Fails, why),
            None => match (
                team_verdict(team, &spacing, &tracking),
                spacing_claim(s, l, team, &spacing),
            ) {
                // A loop that fails fails whatever the gaps do; otherwise what range_balance
                // can do with the gaps decides (att43-1, -2, -8, -13).
                (base, Some(claim)) if base.0 != Verdict::Fails => claim,
                (base, _) => base,
            },
        },
    };
    Some(TeamCheckReport {
        count: team.count(),
        spacing_law: team.law.name(),
        coordinate_free: team.law.is_coordinate_free(),
        verdict,
        verdict_reason,
        spacing,
        tracking,
    })
}

/// Whether `range_balance` can even the gaps at all, beyond its loop's stability: `None` when
/// nothing stands in its way (or for another law, or `k_v = 0`, the user's `none`), else the
/// verdict and its reason:
///
/// * the law cannot move the gaps (att43-8, att43-13, att41-19): every range lost
///   (`dropout_probability = 1`), no speed to command but `v0` (every envelope of zero width),
///   or two vehicles (each sees its one neighbour as ahead and behind). The gaps stay as
///   deployed: `holds` only when the starts are even on a known circle, else `fails`;
///   Two or more vehicles with no speed room among others keep the arcs between them
///   ([`equilibrium::pinned_arcs_claim`], att44-8): `fails` when the best spacing left is not
///   even;
/// * unequal nominal speeds on a known circle ([`equilibrium::shifted_claim`], att44-6, -7):
///   `fails` when no equilibrium exists (the ranges it needs span more than any range can),
///   `not_applicable` when its ranges reach past `max_range_m`; elsewhere, with a range limit
///   short of even spacing (att43-2): `not_applicable` (neither the halt bound of one speed nor
///   the linear loop describes it);
/// * a discovered ring whose probe cannot change the speed (`team.v_max_mps <= v0`, att44-10):
///   `fails`; whose probe slots do not hold the ranges of a fitted rate (att51-5,
///   [`start::probe_slots_claim`]): `fails` or `not_applicable`; whose starts leave neighbours
///   beyond the range (att43-1): the probes may not find the ring, and without it the law is
///   off: `not_applicable`;
/// * the start rule ([`start::start_claim`], att50-5, att53t, att54t): when the start matters,
///   a start model whose gap passes through zero `fails`; one whose least gap less its margin
///   is under the close approach, or a start the rule cannot model, `not_applicable` (unless a
///   later rule `fails`);
///
/// and, for either spacing law, a listed ring out of the order of travel
/// ([`listed_ring_out_of_order`]): `fails`.
fn spacing_claim(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    sp: &SpacingLoopReport,
) -> Option<(Verdict, String)> {
    if let Some(wrong) = listed_ring_out_of_order(s, l, team) {
        return Some((Verdict::Fails, wrong));
    }
    let (gain_per_s, ranges) = match team.law {
        SpacingLaw::RangeBalance { gain_per_s } => (gain_per_s, true),
        SpacingLaw::ArcReference { gain_per_s } => (gain_per_s, false),
        SpacingLaw::None => return None,
    };
    if gain_per_s == 0.0 || team.count() < 2 {
        return None;
    }
    if let Some(claim) = frozen_gaps_claim(s, team, ranges) {
        return Some(claim);
    }
    if let Some(claim) = equilibrium::pinned_arcs_claim(s, l, team) {
        return Some(claim);
    }
    if let Some(claim) = discovery_probe_claim(s, team) {
        return Some(claim);
    }
    let tau_s = sp
        .slowest_time_constant_s
        .or(sp.slowest_time_constant_continuous_s);
    let start = start::start_claim(s, l, team, tau_s);
    let later = 'later: {
        // att50-2: arc_reference's equilibrium too (its arc gaps for the ranges).
        let solved = sp.shifted_equilibrium.as_ref();
        if let Some(claim) = solved.and_then(|eq| equilibrium::shifted_claim(team, eq)) {
            break 'later Some(claim);
        }
        if let Some(why) = first_sample_overshoot(s, l, team, sp) {
            break 'later Some((Verdict::NotApplicable, why));
        }
        if let Some(claim) = s
            .team_arc()
            .is_none()
            .then(|| equilibrium::extracted_claim(s, team))
            .flatten()
        {
            break 'later Some(claim);
        }
        range_limit_claim(s, team, sp, ranges)
    };
    // The start rule's claim, unless a later rule fails (no equilibrium: the cause); none of
    // them says `holds`.
    match (start, later) {
        (_, Some(claim)) if claim.0 == Verdict::Fails => Some(claim),
        (Some(claim), _) => Some(claim),
        (None, claim) => claim,
    }
}

/// [`deployed_on_circle`] of `team`'s starts on the scenario's known circle (no arc bound),
/// against `range_m`; `None` off a known circle.
fn deployed(s: &Scenario, team: &TeamSpec, range_m: f64) -> Option<Deployment> {
    s.team_arc()
        .and_then(|c| deployed_on_circle(team, c, f64::INFINITY, range_m))
}

/// [`spacing_claim`]'s first case: the law cannot move the gaps (`ranges`: a law that ranges,
/// `range_balance`). Two vehicles of `range_balance`, every range lost, or every envelope of
/// zero width: the gaps stay as deployed, `holds` only when the starts are even on a known
/// circle with one nominal speed, else `fails`. `None` when the law can move them.
fn frozen_gaps_claim(s: &Scenario, team: &TeamSpec, ranges: bool) -> Option<(Verdict, String)> {
    let n = team.count();
    let even = TeamMetricsConfig::default().even_gap_cv;
    let why = if n == 2 && ranges {
        "with two vehicles the neighbour ahead is the neighbour behind: range_balance sees the same range twice and commands v0".to_string()
    } else if ranges && team.ranging.dropout_probability >= 1.0 {
        "team.ranging.dropout_probability = 1: every range is lost and range_balance commands v0"
            .to_string()
    } else if equilibrium::pinned(team).len() == n {
        // att44-9: arc_reference too; att44-8: the keys in force, overrides or the team's.
        format!(
            "{}: {} has no speed to command but v0",
            equilibrium::pinned_keys(team, &equilibrium::pinned(team)),
            team.law.name()
        )
    } else {
        return None;
    };
    let one_speed = team.nominal_speeds_mps().len() == 1;
    Some(match deployed(s, team, f64::INFINITY).filter(|_| one_speed) {
        Some(d) if d.gap_cv <= even => (
            Verdict::Holds,
            format!(
                "{why}, so the team keeps its deployment, which is even (the starts' gap CV {} <= {})",
                Num(d.gap_cv),
                Num(even)
            ),
        ),
        Some(d) => (
            Verdict::Fails,
            format!(
                "{why}, so the gaps stay as deployed: the starts' gap CV {} > {} (even spacing is not reached)",
                Num(d.gap_cv),
                Num(even)
            ),
        ),
        None => (
            Verdict::Fails,
            format!("{why}, so the gaps stay as deployed (or drift with unequal speeds): even spacing is not reached"),
        ),
    })
}

/// [`spacing_claim`]'s discovered-ring probe cases (att44-10, att51-5, att50-3): a probe that
/// cannot change the speed (`fails`), probe slots that do not hold the ranges of a fitted rate
/// ([`start::probe_slots_claim`]), a probe's range change under the ranging noise
/// (`not_applicable`). `None` otherwise.
fn discovery_probe_claim(s: &Scenario, team: &TeamSpec) -> Option<(Verdict, String)> {
    if let Some(why) = equilibrium::probe_cannot_fly(team) {
        return Some((Verdict::Fails, why));
    }
    if let Some(claim) = start::probe_slots_claim(s, team) {
        return Some(claim);
    }
    let slope = deployed(s, team, f64::INFINITY).map_or(1.0, |d| d.probe_slope);
    equilibrium::probe_below_noise(team, slope).map(|why| (Verdict::NotApplicable, why))
}

/// [`spacing_claim`]'s last cases, of `range_balance` (`ranges`) with a finite
/// `team.ranging.max_range_m`: unequal nominal speeds without a solved equilibrium and a range
/// short of the even spacing's (att43-2), or a discovered ring whose starts leave neighbours
/// beyond the range (att43-1): `not_applicable`. `None` otherwise.
fn range_limit_claim(
    s: &Scenario,
    team: &TeamSpec,
    sp: &SpacingLoopReport,
    ranges: bool,
) -> Option<(Verdict, String)> {
    let r = team.ranging.max_range_m;
    if !ranges || !r.is_finite() {
        return None;
    }
    let n = team.count();
    if team.nominal_speeds_mps().len() > 1 && sp.shifted_equilibrium.is_none() {
        let even_range = s
            .team_arc()
            .map(|c| 2.0 * c.radius_m * (std::f64::consts::PI / n as f64).sin());
        if even_range.is_none_or(|d| d > r) {
            return Some((
                Verdict::NotApplicable,
                format!(
                    "unequal nominal speeds (team.vehicles) with team.ranging.max_range_m = {}{}: where neighbours fall silent range_balance commands each vehicle its own v0, so neither the halt of one speed nor the linear loop (every neighbour heard) describes the team; run it to see whether it spreads",
                    Echo(r),
                    even_range.map_or(String::new(), |d| format!(
                        " short of the even spacing's range {} m",
                        Num(d)
                    ))
                ),
            ));
        }
    }
    let RingMode::Discover(_) = team.ring else {
        return None;
    };
    let d = deployed(s, team, r).filter(|d| d.widest_chord.0 > r)?;
    let [a, b] = d.widest_chord.1;
    Some((
        Verdict::NotApplicable,
        format!(
            "team.ring = \"discovered\" with team.ranging.max_range_m = {}: vehicles {a} and {b}, neighbours at the start, are {} m apart, beyond the range, so the probes may not find the ring, and without it the spacing law is off for the whole run (the run warns it); list the ring or lengthen the range",
            Echo(r),
            Num(d.widest_chord.0)
        ),
    ))
}

/// How many turns the listed ring makes round `circle`'s centre in the direction of
/// travel `dir`: from each start to the next listed one (the last to the first), the angle
/// ahead in `[0, 2 pi)`, summed over the ring, in turns. 1 when the listed order is the order
/// along the travel; a reversed list gives `N - 1`, a permuted one another count. `None` when a
/// start is off the circle ([`start_angle`]) or two share an angle.
fn listed_ring_turns(team: &TeamSpec, circle: CircleArc, dir: f64) -> Option<usize> {
    let tau = std::f64::consts::TAU;
    let angle = |i: usize| start_angle(team, circle, i);
    let n = team.count();
    let mut sum = 0.0;
    for i in 0..n {
        let step = (dir * (angle((i + 1) % n)? - angle(i)?)).rem_euclid(tau);
        if step == 0.0 {
            return None;
        }
        sum += step;
    }
    Some((sum / tau).round() as usize)
}

/// att43-10, att43-11: a listed ring (`ahead(i) = i + 1`) of a spacing law on a known circle
/// whose starts are not in the order of travel ([`listed_ring_turns`] other than 1): each
/// vehicle's "ahead" is not the neighbour ahead, so the law pushes neighbours together (the
/// runs seen collided within 6 s). The reason, `None` when in order or not known.
fn listed_ring_out_of_order(s: &Scenario, l: &Law, team: &TeamSpec) -> Option<String> {
    if team.law == SpacingLaw::None || team.count() < 3 || !matches!(team.ring, RingMode::Listed) {
        return None;
    }
    let c = s.team_arc()?;
    let dir = travel_direction(s, l)?;
    let side = s.spec().controller.pi_isoline()?.output.higher_side.sign();
    let turns = listed_ring_turns(team, c, dir)?;
    (turns != 1).then(|| {
        let way = if dir < 0.0 { "clockwise" } else { "counter-clockwise" };
        format!(
            "the listed ring is not the order of travel: the law travels this circle {way} (kp c1 {} 0, controller.higher_side = \"{}\"), and from each start to the next listed one, {way}, the ring winds {turns} times round the centre, not once, so a vehicle's neighbour \"ahead\" (the next listed) is not the one ahead and {} drives neighbours together; list the starts in the order of travel (team.spread.clockwise = {}), or use team.ring = \"discovered\"",
            if (dir < 0.0) == (side > 0.0) { ">" } else { "<" },
            if side > 0.0 { "right" } else { "left" },
            team.law.name(),
            dir < 0.0
        )
    })
}

/// The arc gaps (m, listed order, each vehicle's ahead) of the equilibrium the loop settles at
/// and of the deployment, on the circle the law measures (the isoline's for `arc_reference`,
/// else the circle flown, whose chords are the ranges; its radius first): even spacing with one
/// nominal speed, else the solved shifted equilibrium. `None` off a known circle, where the
/// equilibrium is not known (not solved, or vehicles with no speed room) or a start is off it.
fn settled_and_deployed_gaps(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    sp: &SpacingLoopReport,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    if !equilibrium::pinned(team).is_empty() {
        return None;
    }
    let circle = s.team_arc()?;
    let n = team.count();
    let radius = match team.law {
        SpacingLaw::ArcReference { .. } => circle.radius_m,
        _ => flown_circle_radius_m(s, l, circle),
    };
    let tau = std::f64::consts::TAU;
    let settled: Vec<f64> = match &sp.shifted_equilibrium {
        Some(eq) if eq.exists() => match team.law {
            SpacingLaw::ArcReference { .. } => eq.ranges_m.clone(),
            _ => eq
                .ranges_m
                .iter()
                .map(|r| 2.0 * radius * (r / (2.0 * radius)).clamp(-1.0, 1.0).asin())
                .collect(),
        },
        Some(_) => return None,
        None if team.nominal_speeds_mps().len() == 1 => vec![tau * radius / n as f64; n],
        None => return None,
    };
    let deployed = deployed_gaps_ahead(s, l, team, circle, radius)?;
    Some((radius, settled, deployed))
}

/// att53t-10: the largest correction the deployment asks of a vehicle against the equilibrium's
/// command, `k_v max_i |(r_i - r_{i-1}) - (r_i - r_{i-1})_eq|` (ranges the chords of the
/// [`settled_and_deployed_gaps`], arc gaps for `arc_reference`), m/s; `None` where those are not
/// known.
fn deployed_correction_mps(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    sp: &SpacingLoopReport,
) -> Option<f64> {
    let k_v = sp.k_v_per_s?;
    let (radius, settled, deployed) = settled_and_deployed_gaps(s, l, team, sp)?;
    let measure = |g: f64| match team.law {
        SpacingLaw::ArcReference { .. } => g,
        _ => 2.0 * radius * (g / (2.0 * radius)).sin(),
    };
    let n = settled.len();
    let diff = |g: &[f64], i: usize| measure(g[i]) - measure(g[(i + n - 1) % n]);
    (0..n)
        .map(|i| k_v * (diff(&deployed, i) - diff(&settled, i)).abs())
        .reduce(f64::max)
}

/// att50-4: the close approach on the way to the equilibrium, not only at it. Past a gain per
/// ranging period `g = k_v mu_max T` of 1 (the fastest mode's) each held sample overshoots the
/// equilibrium by `g - 1` of the remaining error (`x_{j+1} = (1 - g) x_j`), so the first
/// sample can carry a gap `(g - 1) max_i |deployed gap_i - equilibrium gap_i|` past its
/// equilibrium, at most `(v_max - v_min)(T + d)` (the speeds saturate: how far a gap moves in
/// the sample that crosses). When that reaches from the closest equilibrium gap to under
/// [`CLOSE_APPROACH_M`] the reason (`not_applicable`: two robots may meet before the loop
/// settles); `None` otherwise, off a known circle, or where the equilibrium is not known (a
/// shifted one not solved, vehicles with no speed room).
fn first_sample_overshoot(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    sp: &SpacingLoopReport,
) -> Option<String> {
    let g = sp
        .modes
        .iter()
        .map(|m| m.gain_per_period)
        .fold(f64::NEG_INFINITY, f64::max);
    if g.is_nan() || g <= 1.0 {
        return None;
    }
    let (_, settled, deployed) = settled_and_deployed_gaps(s, l, team, sp)?;
    let error = deployed
        .iter()
        .zip(&settled)
        .map(|(g, eq_gap)| (g - eq_gap).abs())
        .fold(0.0, f64::max);
    // The speeds saturate: a gap moves at most (v_max - v_min)(T + d) past where it crossed.
    let (lo, hi) = team.speed_envelope_mps();
    let cap = (hi - lo) * (sp.period_s + sp.delay_s);
    let overshoot = ((g - 1.0) * error).min(cap);
    let (i, closest) = settled
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    (closest - overshoot < CLOSE_APPROACH_M).then(|| {
        format!(
            "the spacing loop's fastest mode has a gain per ranging period k_v mu_max T = {} > 1, so each held sample overshoots the equilibrium by {} of the remaining error: from the deployment (a gap {} m from its equilibrium at most) the first sample can carry a gap {} m past its equilibrium ((g - 1) times that, at most the envelopes' (v_max - v_min)(T + d) = {} m), and vehicle {i}'s gap ahead settles at {} m: it may pass under the run's close-approach distance {} m (or through zero: robots pass through each other) before the loop settles; lower team.k_v under {} (a gain per period of 1) or deploy nearer the equilibrium",
            Num(g),
            Num(g - 1.0),
            Num(error),
            Num(overshoot),
            Num(cap),
            Num(closest),
            Num(CLOSE_APPROACH_M),
            Num(sp.k_v_per_s.unwrap_or(0.0) / g)
        )
    })
}

/// nu39-7, att41-5: the text of the `fails` verdict when a halt out of range can leave the team
/// uneven ([`RangeHaltReport::fails`]), `None` otherwise.
fn range_balance_out_of_range(sp: &SpacingLoopReport) -> Option<String> {
    let h = sp.range_halt.filter(RangeHaltReport::fails)?;
    let advice = match h.even_range_m {
        Some(d) => format!("set team.ranging.max_range_m above {} m", Num(d)),
        None => "set team.ranging.max_range_m longer".into(),
    };
    Some(format!(
        "{}: even spacing is not where the gaps converge ({advice})",
        h.text()
    ))
}

/// The `fails` text of an unstable spacing loop: the bound it is past, and how the speed
/// saturation bounds the gaps' oscillation (`(v_max - v_min)(T + d)`).
fn unstable_spacing_text(team: &TeamSpec, sp: &SpacingLoopReport) -> String {
    format!(
        "the spacing loop is unstable: team.k_v = {} is past the largest stable k_v* = {} 1/s at {} Hz ranging with {} s delay, so the gaps do not converge; the speed saturation bounds them: the speeds switch between the vehicles' envelopes [min v_min_i, max v_max_i] = [{}, {}] m/s and the gaps oscillate about {} by up to (v_max - v_min)(T + d) = {} m{}",
        Echo(sp.k_v_per_s.unwrap_or(0.0)),
        sp.max_stable_k_v_per_s.map_or("n/a".into(), |k| Num(k).to_string()),
        Echo(team.ranging.rate_hz),
        Num(sp.delay_s),
        Echo(team.speed_envelope_mps().0),
        Echo(team.speed_envelope_mps().1),
        if team.nominal_speeds_mps().len() == 1 {
            "the even spacing"
        } else {
            "the equilibrium of the unequal nominal speeds"
        },
        Num(sp.saturated_gap_amplitude_m.unwrap_or(f64::NAN)),
        sp.saturated_gap_cv_max
            .map_or(String::new(), |c| format!(" (a gap CV up to {})", Num(c)))
    )
}

/// The team section's verdict: disjoint envelopes, an unstable spacing or tracking loop fail;
/// both stable hold; no spacing loop holds only with one nominal speed (att54t-12).
fn team_verdict(
    team: &TeamSpec,
    sp: &SpacingLoopReport,
    tr: &TeamTrackingReport,
) -> (Verdict, String) {
    let speed_text = || match (tr.worst_speed_mps, tr.worst_spectral_radius) {
        (Some(v), Some(r)) => format!("spectral radius {r:.6} at {} m/s", Num(v)),
        (Some(v), None) => format!("no equilibrium at {} m/s", Num(v)),
        _ => String::new(),
    };
    let range_text = format!(
        "[{}, {}] m/s",
        Num(tr.speed_range_mps[0]),
        Num(tr.speed_range_mps[1])
    );
    if let Some(d) = disjoint_envelopes(team) {
        return (Verdict::Fails, d.reason());
    }
    if sp.stable == Some(false) {
        return (Verdict::Fails, unstable_spacing_text(team, sp));
    }
    if tr.stable_over_range == Some(false) {
        return (
            Verdict::Fails,
            format!(
                "the tracking loop is unstable at a speed the spacing law may command in {range_text} ({})",
                speed_text()
            ),
        );
    }
    match (sp.applicable, sp.stable, tr.stable_over_range) {
        (true, Some(true), Some(true)) => (
            Verdict::Holds,
            format!(
                "the spacing loop is stable (k_v = {} < k_v* = {} 1/s) and the tracking loop is stable at every speed checked in {range_text}",
                Echo(sp.k_v_per_s.unwrap_or(0.0)),
                sp.max_stable_k_v_per_s.map_or("n/a".into(), |k| Num(k).to_string())
            ),
        ),
        // att54t-12: with no spacing loop each vehicle flies its own v0; with unequal nominal
        // speeds the faster ones lap the slower, passing through their neighbours.
        (false, _, Some(true)) if team.nominal_speeds_mps().len() > 1 => (
            Verdict::Fails,
            format!(
                "no spacing loop ({}), and the nominal speeds differ ({} m/s): each vehicle keeps its own v0, so the faster ones lap the slower, passing through their neighbours, and the gaps do not stay as deployed",
                sp.note,
                team.nominal_speeds_mps()
                    .iter()
                    .map(|v| Num(*v).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ),
        (false, _, Some(true)) => (
            Verdict::Holds,
            format!(
                "no spacing loop ({}); the tracking loop is stable at every speed checked in {range_text}",
                sp.note
            ),
        ),
        _ => (
            Verdict::NotApplicable,
            if tr.applicable {
                "the loops could not all be computed (see the notes)".into()
            } else {
                format!("the tracking loop's sampled check does not apply: {}", tr.note)
            },
        ),
    }
}

impl TeamCheckReport {
    /// The text of `isotrack check`'s team section, line by line.
    pub fn lines(&self) -> Vec<String> {
        let sp = &self.spacing;
        let tr = &self.tracking;
        let mut out = vec![format!(
            "Team ({} vehicles, team.spacing = {}{}; docs/TEAMS.md)",
            self.count,
            self.spacing_law,
            if self.coordinate_free {
                ""
            } else {
                ", a reference: not coordinate-free"
            }
        )];
        out.push(format!(
            "  team verdict: {} ({})",
            self.verdict.as_str(),
            self.verdict_reason
        ));
        if !sp.applicable {
            out.push(format!("  spacing loop: {}", sp.note));
        } else {
            spacing_lines(sp, &mut out);
        }
        if !tr.applicable {
            out.push(format!(
                "  tracking loop over the commanded speeds: not applicable: {}",
                tr.note
            ));
            return out;
        }
        let state = match tr.stable_over_range {
            Some(true) => "stable at every speed",
            Some(false) => "UNSTABLE",
            None => "not computed at every speed",
        };
        out.push(format!(
            "  tracking loop over the commanded speeds [{}, {}] m/s ({} speeds): worst spectral radius {} at {} m/s -> {}",
            Num(tr.speed_range_mps[0]),
            Num(tr.speed_range_mps[1]),
            tr.speeds_mps.len(),
            tr.worst_spectral_radius
                .map_or("none (no equilibrium)".into(), |r| format!("{r:.6}")),
            tr.worst_speed_mps.map_or("n/a".into(), |v| Num(v).to_string()),
            state
        ));
        if !tr.note.is_empty() {
            out.push(format!("  note: {}", tr.note));
        }
        out
    }
}

/// The line on the slowest mode's time constants, with how far they describe the decay
/// ([`SpacingLoopReport::time_constants`]).
fn slowest_line(sp: &SpacingLoopReport) -> String {
    let vehicles = || {
        format!(
            "vehicle{} {}",
            if sp.one_sided_vehicles.len() > 1 {
                "s"
            } else {
                ""
            },
            sp.one_sided_vehicles
                .iter()
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let num = |x: Option<f64>, none: &str| x.map_or(none.to_string(), |v| format!("{} s", Num(v)));
    if sp.time_constants == Some("one_sided") {
        let near = sp.one_sided_room_mps.map_or(String::new(), |room| {
            format!(
                "; they are near the bound, not on it: the room {} m/s is under the largest correction the deployment asks, so the decay from the deployment is one-sided until every range difference is within room/k_v = {} m of the equilibrium's, and the linear loop's (the modes above) below that",
                Num(room),
                Num(room / sp.k_v_per_s.unwrap_or(f64::NAN))
            )
        });
        return format!(
            "  slowest mode (one-sided): time constant {} sampled, {} continuous (1/(k_v c (2 - 2 cos(pi/N)))): {} fly at the same envelope bound at the equilibrium, so each can move one way only and a correction asking it past the bound is cut: the slowest pattern has one vehicle cut (flying the team's speed, a pin) and the rest moving, the one-pin path's first mode, not the ring's m = 1{near}",
            num(sp.slowest_time_constant_s, "none (does not decay)"),
            num(sp.slowest_time_constant_continuous_s, "none (does not decay)"),
            vehicles()
        );
    }
    if sp.time_constants == Some("not_applicable") {
        return if sp.one_sided_vehicles.is_empty() {
            "  slowest mode: time constant not computed: the slope c = 1 only bounds the eigenvalues from above, and past the dense limit the smallest is bounded from below: the two bounds leave the time constant unbounded either way".into()
        } else {
            format!(
                "  slowest mode: time constant not applicable: {} fly at an envelope bound at the equilibrium (their command there is the bound), so each can move one way only: a correction asking it past the bound is cut, only part of the linear law acts, and the linear loop's time constants do not describe the decay; run it to see how fast",
                vehicles()
            )
        };
    }
    let (sampled, word) = match sp.time_constants {
        Some("upper_bound") => ("not computed past the dense limit".to_string(), "at most "),
        Some("lower_bound") => (
            sp.slowest_time_constant_s.map_or(
                "not bounded by c = 1 (with a delay, or a gain per period past 1, a sampled mode overshoots and a smaller gain can decay slower or faster)".to_string(),
                |t| format!("at least {} s", Num(t)),
            ),
            "at least ",
        ),
        _ => (num(sp.slowest_time_constant_s, "none (does not decay)"), ""),
    };
    let bound = match sp.time_constants {
        Some("lower_bound") => " (bounds: the slope c = 1 is the largest a range can have, so the loop decays no faster)",
        Some("upper_bound") => " (a bound: from the lower bound of the smallest eigenvalue)",
        _ => "",
    };
    format!(
        "  slowest mode{}: time constant {sampled} sampled (-T/ln rho), {word}{} continuous (m = 1: 1/(k_v c lambda_1)){bound}",
        sp.slowest_mode_m
            .map_or(String::new(), |m| format!(" (m = {m})")),
        num(sp.slowest_time_constant_continuous_s, "none (does not decay)")
    )
}

/// The lines of `isotrack check`'s team section on an applicable spacing loop: its sampling,
/// range slope, ring modes, largest stable gain, slowest mode and what it leaves out.
fn spacing_lines(sp: &SpacingLoopReport, out: &mut Vec<String>) {
    out.push(format!(
            "  spacing loop sampled at the ranging period T = {} s, delay {} s = (q + f) T with q = {}, f = {}",
            Num(sp.period_s),
            Num(sp.delay_s),
            sp.delay_whole_periods.map_or("n/a".into(), |q| q.to_string()),
            sp.delay_fraction.map_or("n/a".into(), |f| Num(f).to_string())
        ));
    out.push(range_slope_line(sp));
    out.extend(shifted_equilibrium_line(sp));
    out.push(modes_heading(sp));
    out.extend(sp.modes.iter().map(|m| format!("    {}", mode_line(sp, m))));
    out.extend(k_v_star_line(sp));
    if !sp.note.is_empty() {
        out.push(format!("  note: {}", sp.note));
    }
    out.push(slowest_line(sp));
    for w in &sp.not_modelled {
        out.push(format!("  not modelled: {w}"));
    }
}

/// The line on the range slope `c` and where it comes from; when the linearisation uses each
/// gap's own chord slope instead (att50-11), that `c` is only what the eigenvalues are listed
/// against.
fn range_slope_line(sp: &SpacingLoopReport) -> String {
    let own = match sp.linearised_slopes {
        Some("shifted_equilibrium" | "pinned_best_arcs") => "; the linearisation below uses each gap's own chord slope instead, and lists its eigenvalues against this c",
        _ => "",
    };
    format!(
        "  range slope c = dr/dg = {} ({}{own})",
        Num(sp.range_slope.unwrap_or(1.0)),
        match sp.range_slope_source {
            Some("circle_chord") => "chord of the circular isoline at even spacing, cos(pi/N)",
            Some("arc_gaps") => "arc_reference uses the arc gaps themselves",
            _ => "conservative: the isoline is not known to be a circle, |dr/dg| <= 1",
        }
    )
}

/// att50-10: the line on a solved shifted equilibrium (unequal nominal speeds): its common
/// speed, ranges and gap CV, and that `holds` claims convergence to it, not even spacing
/// (`None` without one that exists).
fn shifted_equilibrium_line(sp: &SpacingLoopReport) -> Option<String> {
    let eq = sp.shifted_equilibrium.as_ref().filter(|e| e.exists())?;
    let ranges = eq
        .ranges_m
        .iter()
        .map(|r| Num(*r).to_string())
        .collect::<Vec<_>>()
        .join(", ");
    Some(format!(
        "  shifted equilibrium (unequal nominal speeds): every vehicle at V = {} m/s, {} ahead {ranges} m, gap CV {}: the loop below converges here (what `holds` claims), not to even spacing",
        Num(eq.speed_mps),
        if sp.range_slope_source == Some("arc_gaps") {
            "arc gaps"
        } else {
            "ranges"
        },
        eq.gap_cv.map_or("n/a".into(), |cv| Num(cv).to_string())
    ))
}

/// The heading of the modes' list: the ring Laplacian's at even spacing of a free ring, else
/// the linearisation's ([`SpacingLoopReport::linearised_about`]), and which modes are listed.
fn modes_heading(sp: &SpacingLoopReport) -> String {
    let which = if sp.all_modes_listed {
        "every distinct one"
    } else if sp.eigenvalue_bounds {
        "bounds of the smallest and the largest: past the dense limit"
    } else {
        "the smallest and the largest of many"
    };
    if sp.one_sided_stability {
        return "  one-sided law's pieces (every vehicle on the same envelope bound: a correction asking a vehicle past it is cut, so only patterns whose free vehicles all move one way survive; the ring's alternating modes cannot grow): the slowest has one vehicle cut (the one-pin path's first mode, lambda = 2 - 2 cos(pi/N)), the fastest a lone free vehicle between two cut ones (mu = c_{i-1} + c_i, lambda = 2; k_v* = g*/(T c 2)):".into();
    }
    match sp.linearised_about {
        None => format!(
            "  ring Laplacian eigenvalues ({which}; m = 0, the sum of the gaps, is conserved):"
        ),
        Some(_) => format!(
            "  linearised about the {}{}, {}: eigenvalues mu of K = D^T C D over the free vehicles, listed as lambda = mu/c ({which}; k_v* = g*/(T mu_max)):",
            match sp.linearised_slopes {
                Some("shifted_equilibrium") => "shifted equilibrium",
                Some("pinned_best_arcs") => "best case the vehicles of no speed room leave (those between sharing each arc they keep evenly)",
                _ => "equilibrium",
            },
            fixed_vehicles_text(sp),
            slopes_text(sp)
        ),
    }
}

/// att50-11: " with vehicle 0 (no speed room, ...) fixed ..." for the vehicles the
/// linearisation fixes, pinned and saturated named apart; empty when none.
fn fixed_vehicles_text(sp: &SpacingLoopReport) -> String {
    let mut parts = vec![];
    if !sp.pinned_vehicles.is_empty() {
        parts.push(format!(
            "{} (no speed room: v_min_i = v_max_i, pinned)",
            vehicles_text(&sp.pinned_vehicles)
        ));
    }
    if !sp.saturated_vehicles.is_empty() {
        parts.push(format!(
            "{} (saturated: the command there is past the vehicle's own envelope bound)",
            vehicles_text(&sp.saturated_vehicles)
        ));
    }
    if parts.is_empty() {
        return String::new();
    }
    format!(
        " with {} fixed in the frame moving at the team's speed V",
        parts.join(" and ")
    )
}

/// att50-11: which slopes the linearisation uses, with their values.
fn slopes_text(sp: &SpacingLoopReport) -> String {
    let g = &sp.gap_slopes;
    let list = if g.len() > MAX_LISTED_MODES {
        format!(
            "{} to {}",
            Num(g.iter().copied().fold(f64::INFINITY, f64::min)),
            Num(g.iter().copied().fold(f64::NEG_INFINITY, f64::max))
        )
    } else {
        g.iter()
            .map(|c| Num(*c).to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match sp.linearised_slopes {
        Some("shifted_equilibrium" | "pinned_best_arcs") => {
            format!("each gap with its own chord slope cos(g_i/(2R')) = {list}")
        }
        _ => format!(
            "every gap with the slope c = {}",
            Num(sp.range_slope.unwrap_or(1.0))
        ),
    }
}

/// One listed mode (or bound of the spectrum): its `lambda`, gain per period, radius, stability.
fn mode_line(sp: &SpacingLoopReport, m: &SpacingMode) -> String {
    format!(
        "{}: lambda {}, g = k_v c lambda T = {}, radius {} {}",
        match (sp.eigenvalue_bounds, m.m) {
            _ if sp.one_sided_stability => {
                let piece = if m.m == 1 { "slowest" } else { "fastest" };
                format!("{piece} piece")
            }
            (false, k) => format!("m = {k}"),
            (true, 1) => "lower bound of the smallest".into(),
            (true, _) => "upper bound of the largest".into(),
        },
        Num(m.lambda),
        Num(m.gain_per_period),
        m.spectral_radius
            .map_or("n/a".into(), |r| format!("{r:.6}")),
        if m.stable { "stable" } else { "UNSTABLE" }
    )
}

/// The line on the largest stable `k_v*` and the scenario's `k_v` against it (`None` when not
/// computed).
fn k_v_star_line(sp: &SpacingLoopReport) -> Option<String> {
    let (g, k, lmax) = (
        sp.max_gain_per_period?,
        sp.max_stable_k_v_per_s?,
        sp.lambda_max?,
    );
    Some(format!(
        "  largest stable k_v* = g*/(T c lambda_max) = {}/({} * {} * {}) = {} 1/s{}; team.k_v = {} -> {}",
        Num(g),
        Num(sp.period_s),
        Num(sp.range_slope.unwrap_or(1.0)),
        Num(lmax),
        Num(k),
        if sp.one_sided_stability {
            " (the one-sided law's fastest piece, not the free ring's lambda_max)"
        } else {
            ""
        },
        Echo(sp.k_v_per_s.unwrap_or(0.0)),
        match sp.stable {
            Some(true) => "stable",
            Some(false) => "UNSTABLE",
            None => "not computed",
        }
    ))
}
