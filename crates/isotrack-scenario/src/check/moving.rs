//! `isotrack check` for fields that move (issue 11): how fast the isoline moves, from the field,
//! against the vehicle's speed.
//!
//! The isoline `F(t, p) = s_d` moves along its normal at `|dF/dt| / |grad F|` (differentiate
//! `F(t, p(t)) = s_d` along the normal). Sampled on a lattice over the check's region, at the
//! points within the tube `|F - s_d| <= tube`, at 48 times spread over the run; `dF/dt` by a
//! central difference of 1 s (the field is smooth in time: linear between frames, or a drift).
//! The vehicle can keep up when the isoline is slower than it everywhere sampled (`trackable`).

use super::speed_mps;
use crate::Scenario;
use isotrack_core::{FieldDerivatives, ScalarField, Vec2};
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

/// Lattice side and sample times of the check.
const SIDE: usize = 101;
const TIMES: usize = 48;

/// The moving-isoline report of a scenario, with the tube half-width `tube` (field units).
pub fn moving_report(s: &Scenario, tube: f64, region: [f64; 4]) -> MovingReport {
    let field = s.field();
    let v = speed_mps(s);
    let time_varying = s.is_time_varying();
    if !time_varying {
        return MovingReport {
            time_varying,
            isoline_speed_max_mps: None,
            isoline_speed_p95_mps: None,
            vehicle_speed_mps: v,
            trackable: None,
            samples: 0,
            note: "the field does not change with time".into(),
        };
    }
    let duration = s.file().sim.duration_s.unwrap_or(600.0);
    let level = s.level();
    let h = 1.0_f64.min(0.25 * duration);
    let mut speeds = vec![];
    for k in 0..TIMES {
        let t = duration * (k as f64 + 0.5) / TIMES as f64;
        for j in 0..SIDE {
            for i in 0..SIDE {
                let p = Vec2::new(
                    region[0] + (region[1] - region[0]) * i as f64 / (SIDE - 1) as f64,
                    region[2] + (region[3] - region[2]) * j as f64 / (SIDE - 1) as f64,
                );
                let (Some(f), Some(g)) = (field.value(t, p), field.gradient(t, p)) else {
                    continue;
                };
                if (f - level).abs() > tube || g.norm() == 0.0 {
                    continue;
                }
                let (Some(a), Some(b)) = (field.value(t + h, p), field.value(t - h, p)) else {
                    continue;
                };
                speeds.push(((a - b) / (2.0 * h)).abs() / g.norm());
            }
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
            "|dF/dt|/|grad F| at {SIDE} x {SIDE} lattice points in the tube |F - s_d| <= {tube}, at {TIMES} times over the {duration} s run (dF/dt by a central difference of {h} s)"
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

    /// The frame times and cubic offsets `o = t^3` of [`cubic_speed`]'s series.
    const CUBIC_FRAMES_S: [f64; 7] = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0];

    /// The isoline speed of the cubic series at the k-th of the 48 times, recomputed by hand:
    /// `|o(t + h) - o(t - h)| / 2h` with `h = min(1 s, duration/4) = 0.5 s` for the 2 s run, the
    /// offset linear between frames and the first frame held before t = 0.
    fn cubic_speed(k: usize) -> f64 {
        let o = |t: f64| {
            let t = t.max(0.0);
            let i = ((t / 0.5).floor() as usize).min(5);
            let (t0, t1) = (CUBIC_FRAMES_S[i], CUBIC_FRAMES_S[i + 1]);
            let w = (t - t0) / (t1 - t0);
            (1.0 - w) * t0.powi(3) + w * t1.powi(3)
        };
        let h = 0.5;
        let t = 2.0 * (k as f64 + 0.5) / 48.0;
        (o(t + h) - o(t - h)) / (2.0 * h)
    }

    /// The documented sampling, recomputed here: the cubic series' isolines move at
    /// [`cubic_speed`] at the 48 times `2 (k + 1/2)/48`. The largest is at the last time, the
    /// 95th percentile (nearest rank `round(0.95 (n - 1))`) at the 46th (every lattice point of
    /// a time has its speed).
    #[test]
    fn a_series_isoline_speed_is_the_central_difference_at_the_48_times() {
        let d = tempfile::tempdir().unwrap();
        let offsets = CUBIC_FRAMES_S.map(|t| t * t * t);
        let s = ramp_series(d.path(), &offsets);
        let r = super::moving_report(&s, 1e9, [0.0, 4.0, 0.0, 4.0]);
        let max = r.isoline_speed_max_mps.unwrap();
        assert!(
            (max - cubic_speed(47)).abs() < 1e-9,
            "{max} vs {}",
            cubic_speed(47)
        );
        let p95 = r.isoline_speed_p95_mps.unwrap();
        assert!(
            (p95 - cubic_speed(45)).abs() < 1e-9,
            "{p95} vs {}",
            cubic_speed(45)
        );
        assert_eq!(r.samples, 48 * 101 * 101);
        assert!(r.note.contains("central difference of 0.5 s"), "{}", r.note);
    }

    /// The lattice runs from the region's low corner to its high one: on [-100, 0] m x
    /// [-100, 0] m only its last point, the data's corner (0, 0), has a value, so each time
    /// gives one speed (n = 48, the 95th percentile at rank round(0.95 x 47) = 45); a region off
    /// the data gives no samples and no verdict.
    #[test]
    fn the_lattice_spans_the_region_corner_to_corner() {
        let d = tempfile::tempdir().unwrap();
        let s = ramp_series(d.path(), &CUBIC_FRAMES_S.map(|t| t * t * t));
        let r = super::moving_report(&s, 1e9, [-100.0, 0.0, -100.0, 0.0]);
        assert_eq!(r.samples, 48);
        let max = r.isoline_speed_max_mps.unwrap();
        assert!((max - cubic_speed(47)).abs() < 1e-9, "{max}");
        let p95 = r.isoline_speed_p95_mps.unwrap();
        assert!(
            (p95 - cubic_speed(45)).abs() < 1e-9,
            "{p95} vs {}",
            cubic_speed(45)
        );
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
