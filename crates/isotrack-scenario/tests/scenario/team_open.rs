//! Team metrics along an open isoline (issue 32, docs/TEAMS.md "Open isolines"): the straight
//! isoline of a planar field, where the arc coordinate is the distance along the line and the
//! gaps, the stretch and the revisit times of a team that keeps its deployment (`none`) are
//! worked by hand.

use isotrack_scenario::{parse_scenario, Scenario, TeamIsolineModel};
use isotrack_sim::team::arc::ArcProjection;
use isotrack_sim::team::metrics::TeamSummary;
use isotrack_sim::TraceRow;

/// Four Dubins robots on the isoline `y = 5` m of the plane `F = 0.1 y` (level 0.5), heading
/// west (the higher values on their right, as the PI-like law tracks), listed in the order of
/// travel at `x = 12, 6, 3, 0` m: gaps 6, 3 and 3 m along the line. No domain: the isoline is
/// the line through the box the team can reach in the run.
fn planar(law: &str, extra: &str) -> Scenario {
    let text = format!(
        "[field]\nkind = \"linear_ramp\"\noffset = 0.0\ngradient_per_m = [0.0, 0.1]\n\
         [vehicle]\nkind = \"dubins\"\nspeed_mps = 0.5\n\
         [controller]\nkind = \"pi_isoline\"\nlevel = 0.5\nkp = 10.0\nki = 1.0\nc1 = 0.2\nc2 = 1.0\n\
         [sensor]\nnoise_std = 0.0\n\
         [sim]\ndt_s = 0.01\nduration_s = 120.0\nseed = 0\n\
         [team]\nspacing = \"{law}\"\n{extra}\
         starts = [{{x_m = 12.0, y_m = 5.0, heading_rad = 3.141592653589793}}, \
         {{x_m = 6.0, y_m = 5.0, heading_rad = 3.141592653589793}}, \
         {{x_m = 3.0, y_m = 5.0, heading_rad = 3.141592653589793}}, \
         {{x_m = 0.0, y_m = 5.0, heading_rad = 3.141592653589793}}]\n"
    );
    parse_scenario(&text, "planar-team.toml", &[]).unwrap()
}

fn team_of(s: &Scenario) -> (TeamSummary, Vec<Vec<TraceRow>>) {
    let mut sinks: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
    let r = s.run_team(&mut sinks).unwrap().unwrap();
    (r.team.expect("team metrics along the open line"), sinks)
}

/// The population coefficient of variation of `g`.
fn cv(g: &[f64]) -> f64 {
    let n = g.len() as f64;
    let m = g.iter().sum::<f64>() / n;
    (g.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt() / m
}

/// The isoline the metrics use is the open line `y = 5` across the reach box (from
/// `x = -151` to `163` m: the starts' box widened by `1.25 v_max T + 1 = 151` m, `v_max = 2 v0
/// = 1` m/s), and a point's arc coordinate is its distance along the line.
#[test]
fn the_isoline_of_a_plane_is_the_open_line() {
    let s = planar("none", "");
    let TeamIsolineModel::Polyline(p) = s.team_isoline() else {
        panic!("an open polyline expected");
    };
    assert!(!p.is_closed());
    assert!(s.team_isoline().is_open());
    assert!((p.length_m() - 314.0).abs() < 1e-9, "{}", p.length_m());
    assert!(p.vertices().iter().all(|v| (v.y - 5.0).abs() < 1e-12));
    let at = |x: f64| p.project(isotrack_core::Vec2::new(x, 5.3)).unwrap().s_m;
    for (a, b) in [(0.0, 12.0), (-100.0, 40.0), (3.0, 6.0)] {
        assert!(((at(b) - at(a)).abs() - (b - a)).abs() < 1e-9);
    }
}

/// Under `none` every robot runs the same law on the same (translation-invariant) field at
/// the same speed, so the deployment holds: gaps 6, 3, 3 m at every sample (the gap CV of
/// those three, no wrap-around gap), the closest pair 3 m apart, the stretch 12 m, the ideal
/// revisit time the mean gap over `v0`, 4/0.5 = 8 s; a point inside the stretch waits a gap
/// over `v0` between passes, at most 6/0.5 = 12 s and on average (each point sees each gap
/// once) 8 s, within a revisit bin's crossing (an open isoline's bins are a sample's travel,
/// 0.05 m: 0.1 s) and a metrics sample (0.1 s). The order along the line holds.
#[test]
fn a_deployment_kept_on_an_open_line_by_hand() {
    let s = planar("none", "");
    let (t, rows) = team_of(&s);
    // The robots stayed on the line and kept their order and spacing (the trace).
    let last = rows.iter().map(|r| r.last().unwrap()).collect::<Vec<_>>();
    assert!(last.iter().all(|r| (r.y_m - 5.0).abs() < 1e-6));
    assert!(((last[0].x_m - last[1].x_m) - 6.0).abs() < 1e-6);
    assert!(last[3].x_m < -50.0, "travelled west: {}", last[3].x_m);
    let want = cv(&[6.0, 3.0, 3.0]);
    assert!(
        (t.gap_cv.unwrap() - want).abs() < 1e-6,
        "{:?} vs {want}",
        t.gap_cv
    );
    assert!((t.gap_cv_final.unwrap() - want).abs() < 1e-6);
    assert!((t.min_separation_m.unwrap() - 3.0).abs() < 1e-6);
    assert!(
        (t.revisit_time_ideal_s - 8.0).abs() < 1e-6,
        "{}",
        t.revisit_time_ideal_s
    );
    let tol = 0.1 + 0.1 + 1e-6;
    let mx = t.revisit_time_max_s.unwrap();
    assert!((mx - 12.0).abs() <= tol, "max {mx}");
    let mean = t.revisit_time_mean_s.unwrap();
    assert!((mean - 8.0).abs() <= tol, "mean {mean}");
    let o = t.open_isoline.clone().unwrap();
    assert!((o.stretch_length_m.unwrap() - 12.0).abs() < 1e-6);
    assert!((o.mean_gap_m.unwrap() - 4.0).abs() < 1e-6);
    assert!(t.order_preserved);
    assert!((t.isoline_length_m - 314.0).abs() < 1e-9);
    assert!(t.moving_isoline.is_none());
}

/// `arc_reference` spaces by arc gaps around a ring, which an open isoline does not have:
/// refused by the engine (its run errs, no metrics along a wrap-around that is not there).
#[test]
fn arc_reference_needs_a_closed_isoline() {
    let s = planar("arc_reference", "k_v = 0.1\n");
    let mut sinks: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
    let e = s.run_team(&mut sinks).unwrap().unwrap_err();
    assert_eq!(e, isotrack_sim::TeamError::NoIsoline);
}
