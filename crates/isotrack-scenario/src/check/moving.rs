//! `isotrack check` for fields that move (issue 11): how fast the isoline moves, from the field,
//! against the vehicle's speed.
//!
//! The isoline `F(t, p) = s_d` moves along its normal at `|dF/dt| / |grad F|` (differentiate
//! `F(t, p(t)) = s_d` along the normal). Sampled on a lattice over the check's region, at the
//! points within the tube `|F - s_d| <= tube`, at 48 times spread over the run. `dF/dt` is a
//! difference on the field's own time step ([`Rule`], issue 30 item 16: a fixed 1 s difference
//! aliased frames 0.1 s apart, reporting an isoline moving at 25 m/s as 0.31 m/s):
//!
//! * a grid time series interpolated linearly or to the nearest frame: the difference of the two
//!   frames around the sample time over their spacing in run time (`dtau / time_scale`). Linear
//!   in time, the field's `dF/dt` is exactly that within the interval; nearest, the isoline jumps
//!   once per interval and this is the jump per interval. Before the first frame and after the
//!   last (held) the field stands still;
//! * a grid time series interpolated cubically (C1 in time): a central difference over an eighth
//!   of the smallest frame spacing in run time;
//! * a drifting analytic field `F0(p - d t)`: a central difference over the time the pattern
//!   takes to move an eighth of the lattice's step (`step / (8 |d|)`);
//! * a puff plume: likewise with the puffs' speed `|wind| + 3 meander_std`, and at most an
//!   eighth of the release interval.
//!
//! The vehicle can keep up when the isoline is slower than it everywhere sampled (`trackable`).
//!
//! Its budget is fixed, whatever the run's duration: [`TIMES`] times of [`SIDE`] x [`SIDE`]
//! points, each with at most three values and a gradient. A puff plume's value at a late time
//! costs no more than at an early one (issue 30: past its cached releases, 24 days at 2 Hz,
//! `check --set sim.duration_s=4e6` once took minutes; `isotrack_fields::puff` now shares the
//! live puffs' displacements across a lattice at one time).

use super::setup::speed_mps;
use crate::field::FieldModel;
use crate::spec::FieldKindSpec;
use crate::Scenario;
use isotrack_core::{FieldDerivatives, ScalarField, Vec2};
use isotrack_fields::grid::TimeInterpolation;
use serde::Serialize;

/// The moving-isoline check.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MovingReport {
    /// Whether the field changes with time (a grid time series, or a drifting analytic field).
    pub time_varying: bool,
    /// Largest isoline speed sampled in the tube over the run, m/s.
    pub isoline_speed_max_mps: Option<f64>,
    /// 95th percentile of the sampled isoline speeds, m/s.
    pub isoline_speed_p95_mps: Option<f64>,
    /// The vehicle's speed (the Dubins robot's, or the UAV's airspeed), m/s.
    pub vehicle_speed_mps: f64,
    /// Whether the vehicle is faster than the isoline everywhere sampled (`null` for a field
    /// that does not move, or when no point of the tube was sampled).
    pub trackable: Option<bool>,
    /// Samples behind the statistics (lattice points in the tube, over all times).
    pub samples: usize,
    /// What was sampled, and how.
    pub note: String,
}

/// Lattice side of the check, points.
pub const SIDE: usize = 101;
/// Sample times of the check, spread over the run.
pub const TIMES: usize = 48;

/// How `dF/dt` is estimated for the scenario's field (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    /// `(F(t + h) - F(t - h)) / 2h` with this `h`, s of run time: fields smooth in time.
    Central(f64),
    /// `(F(r_k+1) - F(r_k)) / (r_k+1 - r_k)` over the run times `r_k` of the frames around `t`:
    /// a series linear in time (exact) or stepping to the nearest frame (the jump per interval).
    Frames,
}

/// The rule for `dF/dt` of the scenario's field, from the field's own time scale, with a phrase
/// saying what it is; `None` for a field that does not move. `lattice_step_m` is the check
/// lattice's spacing.
pub fn difference_rule(s: &Scenario, lattice_step_m: f64) -> Option<(Rule, String)> {
    let eighth = |x: f64| x / 8.0;
    let central = |h: f64, why: String| {
        (h > 0.0 && h.is_finite()).then(|| {
            (
                Rule::Central(h),
                format!("a central difference over {} s, {why}", short(h)),
            )
        })
    };
    match s.field() {
        FieldModel::Series(g) => {
            let dtau = g
                .times_s()
                .windows(2)
                .map(|w| w[1] - w[0])
                .fold(f64::INFINITY, f64::min);
            let dt = dtau / g.field_time_scale();
            let frames = format!(
                "the frames are at least {} s of run time apart ({} s of field time / time_scale {})",
                short(dt),
                short(dtau),
                short(g.field_time_scale())
            );
            let cubic = matches!(
                &s.spec().field.kind,
                FieldKindSpec::Grid(gs) if gs.time_interpolation == TimeInterpolation::Cubic
            );
            match cubic {
                true => central(
                    eighth(dt),
                    format!("an eighth of the smallest frame spacing ({frames})"),
                ),
                false => Some((
                    Rule::Frames,
                    format!("the difference of the two frames around each time over their spacing ({frames})"),
                )),
            }
        }
        FieldModel::Analytic(a) => {
            let d = a.drift_mps.norm();
            central(
                eighth(lattice_step_m / d),
                format!(
                    "the time the pattern drifting at {} m/s takes to move an eighth of the lattice step {} m",
                    short(d),
                    short(lattice_step_m)
                ),
            )
        }
        FieldModel::Puff(pf) => {
            let p = pf.params();
            let u = p.wind_mps.norm() + 3.0 * p.meander_std_mps;
            central(
                eighth((lattice_step_m / u).min(1.0 / p.release_rate_hz)),
                format!(
                    "an eighth of the smaller of the time the puffs (at up to {} m/s) take to cross the lattice step {} m and the release interval",
                    short(u),
                    short(lattice_step_m)
                ),
            )
        }
        FieldModel::Grid(_) => None,
    }
}

/// The run times `(r_k, r_k+1)` of the frames around run time `t` of a series, `None` before
/// the first frame or after the last (the field stands still there).
fn frames_around(s: &Scenario, t: f64) -> Option<(f64, f64)> {
    let FieldModel::Series(g) = s.field() else {
        return None;
    };
    let times = g.times_s();
    let tau = g.field_time_s(t);
    let n = times.len();
    if n < 2 || tau < times[0] || tau > times[n - 1] {
        return None;
    }
    let k = (times.partition_point(|&x| x <= tau) - 1).min(n - 2);
    // Run time of field time x: (x - time_origin_s) / time_scale, as field_time_s inverts.
    let origin = g.field_time_s(0.0);
    let run = |x: f64| (x - origin) / g.field_time_scale();
    Some((run(times[k]), run(times[k + 1])))
}

/// A number for the note, to four significant digits.
fn short(x: f64) -> String {
    format!("{}", isotrack_core::numtext::Num(x))
}

/// The moving-isoline report of a scenario, with the tube half-width `tube` (field units).
pub fn moving_report(s: &Scenario, tube: f64, region: [f64; 4]) -> MovingReport {
    let field = s.field();
    let v = speed_mps(s);
    let time_varying = s.is_time_varying();
    let lattice_step_m = ((region[1] - region[0]).max(region[3] - region[2]) / (SIDE - 1) as f64)
        .max(f64::MIN_POSITIVE);
    let Some((rule, how)) = difference_rule(s, lattice_step_m).filter(|_| time_varying) else {
        return MovingReport {
            time_varying,
            isoline_speed_max_mps: None,
            isoline_speed_p95_mps: None,
            vehicle_speed_mps: v,
            trackable: None,
            samples: 0,
            note: "the field does not change with time".into(),
        };
    };
    let duration = s.spec().sim.duration_s;
    let level = s.level();
    let points: Vec<Vec2> = (0..SIDE * SIDE)
        .map(|n| {
            let (i, j) = (n % SIDE, n / SIDE);
            Vec2::new(
                region[0] + (region[1] - region[0]) * i as f64 / (SIDE - 1) as f64,
                region[2] + (region[3] - region[2]) * j as f64 / (SIDE - 1) as f64,
            )
        })
        .collect();
    // One time over the whole lattice at a time: a puff plume reuses its meander per time.
    let at = |t: f64| -> Vec<Option<f64>> { points.iter().map(|&p| field.value(t, p)).collect() };
    let mut speeds = vec![];
    for k in 0..TIMES {
        let t = duration * (k as f64 + 0.5) / TIMES as f64;
        let now = at(t);
        // (values at the later time, at the earlier, their distance in run time); None where
        // the field stands still at t.
        let diff = match rule {
            Rule::Central(h) => Some((at(t + h), at(t - h), 2.0 * h)),
            Rule::Frames => frames_around(s, t).map(|(a, b)| (at(b), at(a), b - a)),
        };
        for (n, &p) in points.iter().enumerate() {
            if !now[n].is_some_and(|f| (f - level).abs() <= tube) {
                continue;
            }
            let Some(g) = field.gradient(t, p).filter(|g| g.norm() != 0.0) else {
                continue;
            };
            let rate = match &diff {
                None => 0.0,
                Some((later, earlier, span)) => {
                    let (Some(a), Some(b)) = (later[n], earlier[n]) else {
                        continue;
                    };
                    ((a - b) / span).abs()
                }
            };
            speeds.push(rate / g.norm());
        }
    }
    speeds.retain(|x| x.is_finite());
    speeds.sort_by(f64::total_cmp);
    let n = speeds.len();
    let max = speeds.last().copied();
    // Nearest rank: 0.95 (n - 1) <= n - 1 rounds to at most n - 1, a valid index.
    let p95 = (n > 0).then(|| speeds[(0.95 * (n - 1) as f64).round() as usize]);
    MovingReport {
        time_varying,
        isoline_speed_max_mps: max,
        isoline_speed_p95_mps: p95,
        vehicle_speed_mps: v,
        trackable: max.map(|m| m < v),
        samples: n,
        note: format!(
            "|dF/dt|/|grad F| at {SIDE} x {SIDE} lattice points in the tube |F - s_d| <= {}, at {TIMES} times over the {} s run; dF/dt by {how}",
            short(tube),
            short(duration)
        ),
    }
}

#[cfg(test)]
mod tests {
    use crate::parse_scenario;

    /// A linear ramp drifting at 0.3 m/s across its gradient moves its isolines at exactly
    /// 0.3 m/s (the drift's component along the gradient): trackable by a 0.5 m/s robot, not by
    /// a 0.2 m/s one.
    #[test]
    fn a_drifting_ramp_moves_at_the_drift_speed() {
        let s = |v: f64| {
            parse_scenario(
                "[field]\nkind = \"linear_ramp\"\ngradient_per_m = [0.0, 1.0]\ndrift_mps = [0.4, 0.3]\ndomain_m = [-50.0, 50.0, -50.0, 50.0]\n[initial]\nx_m = 0.0\ny_m = 0.0\n[controller]\nlevel = 0.0\n",
                "<test>",
                &[format!("vehicle.speed_mps={v}")],
            )
            .unwrap()
        };
        let r = super::moving_report(&s(0.5), 1.0, [-50.0, 50.0, -50.0, 50.0]);
        assert!(r.time_varying);
        assert!(
            (r.isoline_speed_max_mps.unwrap() - 0.3).abs() < 1e-9,
            "{r:?}"
        );
        assert!((r.isoline_speed_p95_mps.unwrap() - 0.3).abs() < 1e-9);
        assert_eq!(r.trackable, Some(true));
        let r = super::moving_report(&s(0.2), 1.0, [-50.0, 50.0, -50.0, 50.0]);
        assert_eq!(r.trackable, Some(false));
        let still = parse_scenario("", "<test>", &[]).unwrap();
        let r = super::moving_report(&still, 1.0, [-20.0, 20.0, -20.0, 20.0]);
        assert!(!r.time_varying && r.trackable.is_none());
    }

    /// A grid time series `F = y + o_i` on a 5 x 5 grid (1 m cells from the origin, so the data
    /// cover [0, 4] m x [0, 4] m), frames every 0.5 s with offsets `o_i`, bilinear, s_d = 2, a
    /// 2 s run.
    fn ramp_series(d: &std::path::Path, offsets: &[f64]) -> crate::Scenario {
        let mut names = vec![];
        for (i, o) in offsets.iter().enumerate() {
            let rows: Vec<String> = (0..5)
                .map(|j| vec![format!("{}", j as f64 + o); 5].join(","))
                .collect();
            let name = format!("f{i}.csv");
            std::fs::write(d.join(&name), rows.join("\n") + "\n").unwrap();
            names.push(format!("\"{name}\""));
        }
        let times: Vec<String> = (0..offsets.len())
            .map(|i| format!("{:?}", 0.5 * i as f64))
            .collect();
        let text = format!(
            "[field]\nkind = \"grid\"\npaths = [{}]\nframe_times_s = [{}]\ninterpolation = \"bilinear\"\n[initial]\nx_m = 2.0\ny_m = 2.0\n[controller]\nlevel = 2.0\n[sim]\nduration_s = 2.0\n",
            names.join(", "),
            times.join(", ")
        );
        crate::parse_scenario_in(&text, "s.toml", &[], d).unwrap()
    }

    /// The frame times and cubic offsets `o = t^3` of the series of [`LAST_INTERVAL_SPEED`].
    const CUBIC_FRAMES_S: [f64; 7] = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0];

    /// The isolines `y = 2 - o(t)` of the cubic series move, between frames 1.5 s and 2 s
    /// (linear in time there), at `(2^3 - 1.5^3) / 0.5 = 9.25` m/s: the speed at every one of
    /// the 48 times `2 (k + 1/2)/48` from k = 36 (t = 1.52 s) to the last (1.98 s): the
    /// difference of the frames at 1.5 s and 2 s.
    const LAST_INTERVAL_SPEED: f64 = (8.0 - 3.375) / 0.5;

    /// The sampled speeds are the speeds of the frame intervals: the largest and the 95th
    /// percentile (nearest rank `round(0.95 (n - 1))` of `n = 48 x 101 x 101`, among the 24
    /// times in the last interval) are its 9.25 m/s; every lattice point of a time has its speed.
    #[test]
    fn a_series_isoline_speed_is_the_speed_of_its_frame_interval() {
        let d = tempfile::tempdir().unwrap();
        let offsets = CUBIC_FRAMES_S.map(|t| t * t * t);
        let s = ramp_series(d.path(), &offsets);
        let r = super::moving_report(&s, 1e9, [0.0, 4.0, 0.0, 4.0]);
        let max = r.isoline_speed_max_mps.unwrap();
        assert!((max - LAST_INTERVAL_SPEED).abs() < 1e-9, "{max}");
        let p95 = r.isoline_speed_p95_mps.unwrap();
        assert!((p95 - LAST_INTERVAL_SPEED).abs() < 1e-9, "{p95}");
        assert_eq!(r.samples, 48 * 101 * 101);
        assert!(
            r.note.contains("the two frames around each time"),
            "{}",
            r.note
        );
    }

    /// Issue 30 item 16: a ramp `F = y + o_i` (8 rows, s_d = 4) whose offset zig-zags between 0
    /// and 2.5 from frame to frame, frames 0.1 s of run time apart (given so, or 1 s apart in
    /// field time played at time_scale 10): the isoline `y = 4 - o(t)` moves 2.5 m per 0.1 s,
    /// 25 m/s, all the time (linear between frames). A fixed 1 s difference spans 5 periods of
    /// the zig-zag and saw almost nothing; the frame-spacing difference sees 25 m/s, and a
    /// 0.5 m/s robot cannot keep up.
    #[test]
    fn frames_a_tenth_of_a_second_apart_do_not_alias() {
        let d = tempfile::tempdir().unwrap();
        let rows = |o: f64| -> String {
            (0..8)
                .map(|j| vec![format!("{}", j as f64 + o); 5].join(","))
                .collect::<Vec<_>>()
                .join("\n")
                + "\n"
        };
        std::fs::write(d.path().join("a.csv"), rows(0.0)).unwrap();
        std::fs::write(d.path().join("b.csv"), rows(2.5)).unwrap();
        let n = 41; // frames over 4 s of run time
        let paths: Vec<&str> = (0..n)
            .map(|i| if i % 2 == 0 { "\"a.csv\"" } else { "\"b.csv\"" })
            .collect();
        for (spacing, scale) in [(0.1, 1.0), (1.0, 10.0)] {
            let times: Vec<String> = (0..n)
                .map(|i| format!("{:?}", i as f64 * spacing))
                .collect();
            let text = format!(
                "[field]\nkind = \"grid\"\npaths = [{}]\nframe_times_s = [{}]\ntime_scale = {scale:?}\ninterpolation = \"bilinear\"\n[initial]\nx_m = 2.0\ny_m = 3.0\n[controller]\nlevel = 4.0\n[sim]\nduration_s = 3.0\n",
                paths.join(", "),
                times.join(", ")
            );
            let s = crate::parse_scenario_in(&text, "s.toml", &[], d.path()).unwrap();
            let r = super::moving_report(&s, 1.0, [0.0, 4.0, 0.0, 7.0]);
            let max = r.isoline_speed_max_mps.unwrap();
            assert!(
                (max - 25.0).abs() < 1e-9,
                "spacing {spacing}, scale {scale}: {r:?}"
            );
            let p95 = r.isoline_speed_p95_mps.unwrap();
            assert!((p95 - 25.0).abs() < 1e-9, "{r:?}");
            assert_eq!(r.trackable, Some(false));
        }
    }

    /// A circular Gaussian plume (sigma 2 m) drifting at 50 m/s along x: its isoline moves at
    /// `|d . n|`, 50 m/s where the normal is along x (the lattice's middle row passes through
    /// the centre; over the 4 s run the plume crosses the 20 m region in its first 0.2 s, the
    /// first few of the 48 times). A 1 s difference saw the plume 25 sigma away at both ends
    /// (speed ~0); the step of an eighth of the lattice step over the drift speed finds 50 m/s
    /// (central difference: relative error `(h d)^2 F'''/(6 F')`, below 1e-4 here).
    #[test]
    fn a_fast_drifting_plume_is_differenced_on_its_own_time_scale() {
        let s = parse_scenario(
            "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 10.0, sigma_m = [2.0, 2.0], rotation_rad = 0.0 }]\ndrift_mps = [50.0, 0.0]\n[initial]\nx_m = 2.0\ny_m = 0.0\n[controller]\nlevel = 5.0\n[sim]\nduration_s = 4.0\n",
            "<test>",
            &["vehicle.speed_mps=60".to_string()],
        )
        .unwrap();
        let r = super::moving_report(&s, 0.5, [-10.0, 10.0, -10.0, 10.0]);
        let max = r.isoline_speed_max_mps.unwrap();
        assert!((max - 50.0).abs() < 1e-3 * 50.0, "{r:?}");
        assert_eq!(r.trackable, Some(true));
    }

    /// The lattice runs from the region's low corner to its high one: on [-100, 0] m x
    /// [-100, 0] m only its last point, the data's corner (0, 0), has a value, so each time
    /// gives one speed (n = 48, the 95th percentile at rank round(0.95 x 47) = 45, both in the
    /// last frame interval, see [`LAST_INTERVAL_SPEED`]); a region off
    /// the data gives no samples and no verdict.
    #[test]
    fn the_lattice_spans_the_region_corner_to_corner() {
        let d = tempfile::tempdir().unwrap();
        let s = ramp_series(d.path(), &CUBIC_FRAMES_S.map(|t| t * t * t));
        let r = super::moving_report(&s, 1e9, [-100.0, 0.0, -100.0, 0.0]);
        assert_eq!(r.samples, 48);
        let max = r.isoline_speed_max_mps.unwrap();
        assert!((max - LAST_INTERVAL_SPEED).abs() < 1e-9, "{max}");
        let p95 = r.isoline_speed_p95_mps.unwrap();
        assert!((p95 - LAST_INTERVAL_SPEED).abs() < 1e-9, "{p95}");
        let r = super::moving_report(&s, 1e9, [10.0, 20.0, 10.0, 20.0]);
        assert!(r.time_varying);
        assert_eq!(r.samples, 0);
        assert_eq!(r.isoline_speed_max_mps, None);
        assert_eq!(r.isoline_speed_p95_mps, None);
        assert_eq!(r.trackable, None);
    }

    /// A ramp `F = y` drifting at 0.5 m/s along y (`F(t, p) = y - 0.5 t`), s_d = 0, a 48 s run,
    /// the robot at `v` m/s. Sampled on whole-metre points at the times k + 1/2 with h = 1 s,
    /// every step is exact in binary.
    fn drifting_ramp(v: f64) -> crate::Scenario {
        parse_scenario(
            "[field]\nkind = \"linear_ramp\"\ngradient_per_m = [0.0, 1.0]\ndrift_mps = [0.0, 0.5]\n[initial]\nx_m = 0.0\ny_m = 0.0\n[controller]\nlevel = 0.0\n[sim]\nduration_s = 48.0\n",
            "<test>",
            &[format!("vehicle.speed_mps={v}")],
        )
        .unwrap()
    }

    /// The tube is closed, `|F - s_d| <= tube`: on the drifting ramp at t = k + 1/2 and tube
    /// 1/4, `|y - k/2 - 1/4| <= 1/4` holds on whole metres only at one row (y = k/2 for even k,
    /// (k + 1)/2 for odd), exactly on the tube's edge: 101 points at each of the 48 times.
    #[test]
    fn the_tube_includes_its_edges() {
        let r = super::moving_report(&drifting_ramp(1.0), 0.25, [-50.0, 50.0, -50.0, 50.0]);
        assert_eq!(r.samples, 48 * 101);
        assert_eq!(r.isoline_speed_max_mps, Some(0.5));
    }

    /// Trackable means strictly faster: the drifting ramp's isolines move at exactly 0.5 m/s,
    /// which a 0.5 m/s robot cannot outrun.
    #[test]
    fn an_isoline_as_fast_as_the_vehicle_is_not_trackable() {
        let region = [-50.0, 50.0, -50.0, 50.0];
        let r = super::moving_report(&drifting_ramp(0.5), 1e9, region);
        assert_eq!(r.isoline_speed_max_mps, Some(0.5));
        assert_eq!(r.trackable, Some(false));
        let r = super::moving_report(&drifting_ramp(0.5 + 1e-12), 1e9, region);
        assert_eq!(r.trackable, Some(true));
    }
}
