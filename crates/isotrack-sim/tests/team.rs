//! Teams on the paper's circular field (`F = 20 exp(-0.1 |p|)`, the level-10 isoline a circle of
//! radius `R = 10 ln 2` m, tracked clockwise by the Fig. 2(b) PI-like law): the spacing laws
//! against what the geometry and the theory (`isotrack_core::spacing`) say.
use isotrack_core::control::{PiIsoline, PiIsolineParams};
use isotrack_core::math::Vec2;
use isotrack_core::spacing::{max_stable_spacing_gain, ring_laplacian_eigenvalue};
use isotrack_fields::{AnalyticField, AnalyticKind, RadialExp};
use isotrack_sim::team::arc::CircleArc;
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::ranging::RangingConfig;
use isotrack_sim::team::spacing::{DiscoveryConfig, RingMode, SpacingConfig, SpacingLaw};
use isotrack_sim::{
    simulate, simulate_team, NoTrace, Oracles, Sensor, SensorConfig, StepPlan, TeamConfig,
    TeamMember, TeamResult,
};
use isotrack_vehicles::{Dubins, DubinsState, DubinsVariableSpeed};
use std::f64::consts::{FRAC_PI_2, PI};

const V0: f64 = 0.5;
const DT: f64 = 0.01;

fn radius() -> f64 {
    10.0 * std::f64::consts::LN_2
}

fn field() -> AnalyticField {
    AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()))
}

fn arc() -> CircleArc {
    CircleArc {
        center_m: Vec2::new(0.0, 0.0),
        radius_m: radius(),
    }
}

/// On the isoline at angle `th` (rad, counter-clockwise from +x), heading clockwise along it.
fn on_circle(th: f64) -> DubinsState {
    let r = radius();
    DubinsState {
        position_m: Vec2::new(r * th.cos(), r * th.sin()),
        heading_rad: th - FRAC_PI_2,
    }
}

fn vehicle(v_min: f64, v_max: f64) -> DubinsVariableSpeed {
    DubinsVariableSpeed {
        min_speed_mps: v_min,
        max_speed_mps: v_max,
    }
}

fn members(
    v: &DubinsVariableSpeed,
    angles: &[f64],
    rate_hz: f64,
) -> Vec<TeamMember<isotrack_vehicles::DubinsSpeedState, PiIsoline>> {
    angles
        .iter()
        .enumerate()
        .map(|(i, &th)| TeamMember {
            x0: v.state(on_circle(th), V0),
            controller: PiIsoline::new(PiIsolineParams::paper_fig2b(10.0)),
            sensor: Sensor::new(
                SensorConfig {
                    rate_hz,
                    ..SensorConfig::default()
                },
                DT,
                100 + i as u64,
            )
            .unwrap(),
            ranging_seed: 1000 + i as u64,
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn run(
    angles: &[f64],
    law: SpacingLaw,
    ring: RingMode,
    ranging: RangingConfig,
    duration_s: f64,
    envelope: (f64, f64),
) -> TeamResult {
    let v = vehicle(envelope.0, envelope.1);
    let plan = StepPlan::new(DT, duration_s, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        ranging,
        spacing: SpacingConfig {
            law,
            nominal_speed_mps: V0,
            ring,
        },
        metrics: TeamMetricsConfig::default(),
    };
    let a = arc();
    simulate_team(
        &field(),
        &v,
        &plan,
        cfg,
        members(&v, angles, 100.0),
        Some(&a),
        &Oracles::default(),
        &mut [] as &mut [NoTrace],
    )
    .unwrap()
}

/// The CV of the gaps of points at `angles` on a circle (independent of the sim's metric).
fn cv_of(angles: &[f64]) -> f64 {
    let mut a: Vec<f64> = angles.iter().map(|t| t.rem_euclid(2.0 * PI)).collect();
    a.sort_by(f64::total_cmp);
    let n = a.len();
    let gaps: Vec<f64> = (0..n)
        .map(|i| {
            if i + 1 == n {
                a[0] + 2.0 * PI - a[i]
            } else {
                a[i + 1] - a[i]
            }
        })
        .collect();
    let mean = 2.0 * PI / n as f64;
    (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n as f64).sqrt() / mean
}

/// A cluster: four robots 0.3 rad (2.1 m) apart on the isoline, listed in the order of travel
/// (clockwise: each next one ahead).
fn cluster() -> Vec<f64> {
    (0..4).map(|i| -0.3 * i as f64).collect()
}

fn ideal_ranging(rate_hz: f64) -> RangingConfig {
    RangingConfig {
        rate_hz,
        ..RangingConfig::default()
    }
}

/// `range_balance` from the cluster (gap CV 0.92) reaches gap_cv < 0.05 in the steady window,
/// revisits every point within 10 % of the ideal `L/(N v0)`, keeps the order, and its speeds
/// reach the envelope's edge without leaving it; `arc_reference` spreads the team too.
#[test]
fn range_balance_spreads_a_cluster() {
    let r = run(
        &cluster(),
        SpacingLaw::RangeBalance { gain_per_s: 0.1 },
        RingMode::Listed,
        ideal_ranging(10.0),
        300.0,
        (0.25, 0.75),
    );
    let t = r.team.unwrap();
    let cv0 = cv_of(&cluster());
    assert!(cv0 > 0.9, "{cv0}");
    assert!(t.gap_cv.unwrap() < 0.05, "{t:?}");
    assert!(t.time_to_even_s.is_some());
    let ideal = 2.0 * PI * radius() / (4.0 * V0);
    assert!((t.revisit_time_ideal_s - ideal).abs() < 1e-9);
    let mx = t.revisit_time_max_s.unwrap();
    assert!(mx < 1.1 * ideal, "{mx} vs {ideal}");
    assert!(t.order_preserved);
    let [lo, hi] = t.speed_range_mps.unwrap();
    assert!(lo >= 0.25 && hi <= 0.75, "{lo} {hi}");
    assert!(
        hi == 0.75 || lo == 0.25,
        "the cluster saturates a speed: {lo} {hi}"
    );
    for run in &r.runs {
        assert_eq!(run.outcome, isotrack_sim::Outcome::Completed);
    }
    let a = run(
        &cluster(),
        SpacingLaw::ArcReference { gain_per_s: 0.1 },
        RingMode::Listed,
        ideal_ranging(10.0),
        300.0,
        (0.25, 0.75),
    );
    assert!(a.team.unwrap().gap_cv.unwrap() < 0.05);
}

/// `none`: every robot at v0; the field is symmetric under rotation about its source, so the
/// team turns rigidly and the gap CV stays the deployment's (computed from the angles); the
/// longest unvisited time is the largest gap over v0 (74.6 s, inside the 100 s window).
#[test]
fn none_keeps_the_spacing() {
    let r = run(
        &cluster(),
        SpacingLaw::None,
        RingMode::Listed,
        ideal_ranging(10.0),
        500.0,
        (0.25, 0.75),
    );
    let t = r.team.unwrap();
    let cv0 = cv_of(&cluster());
    assert!(
        (t.gap_cv_final.unwrap() - cv0).abs() < 1e-3,
        "{t:?} vs {cv0}"
    );
    assert!((t.gap_cv.unwrap() - cv0).abs() < 1e-3);
    assert_eq!(t.speed_range_mps, Some([V0, V0]));
    let big_gap = (2.0 * PI - 0.9) * radius();
    let mx = t.revisit_time_max_s.unwrap();
    assert!((mx - big_gap / V0).abs() < 0.05 * big_gap / V0, "{mx}");
}

/// One robot with the `none` law moves as `simulate` moves a constant-speed Dubins robot, bit
/// for bit (the team drives the same step kernel).
#[test]
fn a_team_of_one_is_simulate() {
    let v = vehicle(0.1, 1.0);
    let plan = StepPlan::new(DT, 60.0, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        ranging: ideal_ranging(10.0),
        spacing: SpacingConfig {
            law: SpacingLaw::None,
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig::default(),
    };
    let start = DubinsState {
        position_m: Vec2::new(10.0, 0.0),
        heading_rad: -FRAC_PI_2,
    };
    let sensor = || {
        Sensor::new(
            SensorConfig {
                rate_hz: 100.0,
                noise_std: 0.01,
                ..SensorConfig::default()
            },
            DT,
            5,
        )
        .unwrap()
    };
    let team = simulate_team(
        &field(),
        &v,
        &plan,
        cfg,
        vec![TeamMember {
            x0: v.state(start, V0),
            controller: PiIsoline::new(PiIsolineParams::paper_fig2b(10.0)),
            sensor: sensor(),
            ranging_seed: 0,
        }],
        None,
        &Oracles::default(),
        &mut [] as &mut [NoTrace],
    )
    .unwrap();
    let alone = simulate(
        &field(),
        &Dubins { speed_mps: V0 },
        start,
        &mut PiIsoline::new(PiIsolineParams::paper_fig2b(10.0)),
        sensor(),
        &plan,
        &Oracles::default(),
        &mut NoTrace,
    );
    assert_eq!(format!("{:?}", team.runs[0]), format!("{alone:?}"));
}

/// Listed in an order that is not the order of travel: 0, 2, 1, 3 clockwise. The ring found
/// from ranges and range rates is the true one (0 -> 2 -> 1 -> 3 -> 0), and `range_balance` on
/// it spreads the team without robots meeting; on the listed ring they pass through each other.
#[test]
fn ring_found_from_range_rates() {
    // Vehicle i at angles[i]: clockwise order 0, 2, 1, 3.
    let angles = [0.0, -0.6, -0.3, -0.9];
    let discover = RingMode::Discover(DiscoveryConfig {
        settle_s: 10.0,
        probe_s: 4.0,
        probe_speed_delta_mps: 0.2,
    });
    let ranging = RangingConfig {
        rate_hz: 10.0,
        noise_std_m: 0.05,
        ..RangingConfig::default()
    };
    let law = SpacingLaw::RangeBalance { gain_per_s: 0.1 };
    let r = run(&angles, law, discover, ranging, 300.0, (0.25, 0.75));
    // [ahead, behind] of each vehicle along the clockwise travel.
    let truth = [Some([2, 3]), Some([3, 2]), Some([1, 0]), Some([0, 1])];
    assert_eq!(r.ring, truth);
    let t = r.team.unwrap();
    assert!(t.gap_cv.unwrap() < 0.05, "{t:?}");
    assert!(t.order_preserved);
    // The robots start 2.1 m apart and never come closer than 1 m.
    assert!(t.min_separation_m.unwrap() > 1.0, "{t:?}");
    // On the listed ring the team spreads too, but in the listed order: robots pass through
    // each other to get there (a collision for real robots).
    let listed = run(&angles, law, RingMode::Listed, ranging, 300.0, (0.25, 0.75));
    let tl = listed.team.unwrap();
    assert!(tl.min_separation_m.unwrap() < 0.5, "{tl:?}");
}

/// Same team, seeds, noise, losses and delay: bit-identical results, run twice and on two
/// threads at once.
#[test]
fn deterministic() {
    let ranging = RangingConfig {
        rate_hz: 5.0,
        noise_std_m: 0.1,
        max_range_m: 12.0,
        dropout_probability: 0.2,
        delay_s: 0.3,
    };
    let go = move || {
        format!(
            "{:?}",
            run(
                &cluster(),
                SpacingLaw::RangeBalance { gain_per_s: 0.1 },
                RingMode::Listed,
                ranging,
                60.0,
                (0.25, 0.75),
            )
        )
    };
    let a = go();
    let b = go();
    assert_eq!(a, b);
    let h1 = std::thread::spawn(go);
    let h2 = std::thread::spawn(go);
    assert_eq!(h1.join().unwrap(), a);
    assert_eq!(h2.join().unwrap(), a);
}

/// The sampled, delayed spacing loop: theory's largest stable `k_v`
/// (`max_stable_spacing_gain`, range slope `cos(pi/4)` for chords at even spacing) against the
/// driver on a grid of ranging rates and delays, at 0.5, 0.8, 1.25 and 2 times that gain. The
/// team starts evenly spread but for one robot 0.01 rad off; the simulated verdict: the steady
/// window's mean gap CV is below half its start (decayed) or not.
#[test]
fn theory_verdict_matches_simulation() {
    let n = 4;
    let c = (PI / n as f64).cos();
    let mut angles: Vec<f64> = (0..n).map(|i| -2.0 * PI * i as f64 / n as f64).collect();
    angles[1] += 0.01;
    let cv0 = cv_of(&angles);
    let mut table = vec![];
    let mut disagree = 0;
    for rate_hz in [1.0, 2.0, 5.0] {
        let t_s = 1.0 / rate_hz;
        for delay_periods in [0.0, 0.5, 1.0, 2.0] {
            let d = delay_periods * t_s;
            let k_star = max_stable_spacing_gain(n, t_s, d, c).unwrap();
            for factor in [0.5, 0.8, 1.25, 2.0] {
                let k = factor * k_star;
                // The slowest mode's time constant sets the duration (at least 40 of them).
                let tau = 1.0 / (k * c * ring_laplacian_eigenvalue(n, 1));
                let duration = (40.0 * tau + 20.0 * (t_s + d)).ceil().max(60.0);
                let r = run(
                    &angles,
                    SpacingLaw::RangeBalance { gain_per_s: k },
                    RingMode::Listed,
                    RangingConfig {
                        rate_hz,
                        delay_s: d,
                        ..RangingConfig::default()
                    },
                    duration,
                    (0.05, 0.95),
                );
                let cv_end = r.team.unwrap().gap_cv.unwrap();
                let sim_stable = cv_end < 0.5 * cv0;
                let theory_stable = factor < 1.0;
                table.push(format!(
                    "rate {rate_hz} Hz, delay {d:.2} s, k* {k_star:.4}, k {k:.4}: cv {cv0:.5} -> {cv_end:.5}, sim {sim_stable}, theory {theory_stable}"
                ));
                if sim_stable != theory_stable {
                    disagree += 1;
                }
            }
        }
    }
    eprintln!("{}", table.join("\n"));
    assert_eq!(disagree, 0, "{}", table.join("\n"));
}

/// The team metrics on the isoline extracted from the field sampled every 0.2 m (marching
/// squares, stitched into a closed polyline) agree with the analytic circle's.
#[test]
fn polyline_isoline_gives_the_circle_metrics() {
    use isotrack_fields::isoline::IsolineSegments;
    use isotrack_sim::team::arc::{ArcProjection, PolylineArc};
    let f = field();
    let segs = IsolineSegments::from_samples(Vec2::new(-10.0, -10.0), 0.2, 101, 101, 10.0, |p| {
        isotrack_core::ScalarField::value(&f, 0.0, p)
    });
    let mut loops = segs.closed_loops(1e-6);
    assert_eq!(loops.len(), 1);
    let poly = PolylineArc::new(loops.remove(0)).unwrap();
    let circle = arc();
    assert!((poly.length_m() / circle.length_m() - 1.0).abs() < 2e-3);
    let v = vehicle(0.25, 0.75);
    let plan = StepPlan::new(DT, 200.0, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        ranging: ideal_ranging(10.0),
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig {
            every_steps: 10,
            ..TeamMetricsConfig::default()
        },
    };
    let go = |a: &dyn ArcProjection| {
        simulate_team(
            &f,
            &v,
            &plan,
            cfg,
            members(&v, &cluster(), 100.0),
            Some(a),
            &Oracles::default(),
            &mut [] as &mut [NoTrace],
        )
        .unwrap()
        .team
        .unwrap()
    };
    let (tp, tc) = (go(&poly), go(&circle));
    assert!(
        (tp.gap_cv.unwrap() - tc.gap_cv.unwrap()).abs() < 0.01,
        "{tp:?} {tc:?}"
    );
    let (mp, mc) = (
        tp.revisit_time_max_s.unwrap(),
        tc.revisit_time_max_s.unwrap(),
    );
    assert!((mp - mc).abs() < 0.02 * mc, "{mp} {mc}");
    assert_eq!(tp.order_preserved, tc.order_preserved);
}

/// The thread's CPU time (user + system), s, from `/proc/thread-self/stat` (clock ticks of
/// 1/100 s): throughput measured on a loaded machine without counting the time other processes
/// took (`None` off Linux).
fn thread_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // Fields 14 and 15 of stat (utime, stime) are the 12th and 13th after the command.
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// The process's CPU time (user + system, every thread's, those ended included), s, from
/// `/proc/self/stat` (`None` off Linux).
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Throughput of the 1000-robot ring (as benches/team.rs, 60 s at 100 Hz, range_balance on
/// 10 Hz ranging, no team metrics) on 1 and 2 threads (`THREADS=1,2,3` to choose; `DURATION_S`
/// for another duration), in
/// vehicle-steps per second of wall time and of CPU time (this thread's on one thread; the
/// process's, every thread's, on several: rayon's idle workers spin a little, which counts).
/// Run by hand: `cargo test --workspace --release --locked --all-features --test team --
/// --ignored --nocapture throughput`.
#[test]
#[ignore]
fn throughput_1000_ring() {
    use isotrack_sim::{Group, TeamThreads};
    let n = 1000;
    let r = 10.0 * 20f64.ln();
    let v = vehicle(0.25, 0.75);
    let members = || -> Vec<_> {
        (0..n)
            .map(|i| {
                let th = -2.0 * PI * (i as f64 + 0.1 * (i % 3) as f64) / n as f64;
                let x0 = DubinsState {
                    position_m: Vec2::new(r * th.cos(), r * th.sin()),
                    heading_rad: th - FRAC_PI_2,
                };
                TeamMember {
                    x0: v.state(x0, V0),
                    controller: PiIsoline::new(PiIsolineParams::paper_fig2b(1.0)),
                    sensor: Sensor::new(
                        SensorConfig {
                            rate_hz: 100.0,
                            ..SensorConfig::default()
                        },
                        DT,
                        i as u64,
                    )
                    .unwrap(),
                    ranging_seed: i as u64,
                }
            })
            .collect()
    };
    // `DURATION_S=600` for the 600 s (the peak memory does not grow with it).
    let duration_s: f64 = std::env::var("DURATION_S").map_or(60.0, |d| d.parse().unwrap());
    let plan = StepPlan::new(DT, duration_s, 0.0, 0.2, 0.1, 10.0, 1.0).unwrap();
    let cfg = TeamConfig {
        ranging: ideal_ranging(10.0),
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig::default(),
    };
    let threads: Vec<usize> = std::env::var("THREADS")
        .unwrap_or_else(|_| "1,2".into())
        .split(',')
        .map(|t| t.trim().parse().unwrap())
        .collect();
    let mut first: Option<String> = None;
    for t in threads {
        let m = members();
        let (c0, p0, w0) = (thread_cpu_s(), process_cpu_s(), std::time::Instant::now());
        let mut g = Group::new(&v, &plan, cfg, m, None).unwrap();
        g.drive_threads(
            &field(),
            &v,
            &Oracles::default(),
            &mut [] as &mut [NoTrace],
            TeamThreads::new(t),
        );
        let res = g.finish(&mut [] as &mut [NoTrace]);
        let wall = w0.elapsed().as_secs_f64();
        let steps: u64 = res.runs.iter().map(|r| r.steps).sum();
        let cpu = c0.zip(thread_cpu_s()).map(|(a, b)| b - a);
        let pcpu = p0.zip(process_cpu_s()).map(|(a, b)| b - a);
        eprintln!(
            "{t} thread(s): {steps} vehicle-steps: wall {wall:.3} s ({:.2} M/s), this thread's CPU {cpu:?} s, the process's CPU {pcpu:?} s ({:?} M/s of CPU time)",
            steps as f64 / wall / 1e6,
            pcpu.map(|c| steps as f64 / c / 1e6)
        );
        // The same run on any number of threads.
        let text = format!("{res:?}");
        assert_eq!(first.get_or_insert_with(|| text.clone()), &text);
    }
}

/// The circle of radius `R`, as a moving isoline whose every version is the inscribed
/// `m`-gon started at a vertex that jumps with the version, clockwise on odd versions: what
/// marching squares of a field re-extracted per frame gives (a loop started anywhere, either
/// way round).
struct JumpingCircle {
    m: usize,
}

impl isotrack_sim::team::arc::MovingArc for JumpingCircle {
    fn version(&self, t_s: f64) -> Option<i64> {
        Some((t_s / 1.0).floor() as i64)
    }
    fn loops(&self, version: i64) -> Vec<Vec<Vec2>> {
        let r = radius();
        let shift = (version * 37).rem_euclid(self.m as i64) as usize;
        let mut l: Vec<Vec2> = (0..self.m)
            .map(|i| {
                let th = 2.0 * PI * ((i + shift) % self.m) as f64 / self.m as f64;
                Vec2::new(r * th.cos(), r * th.sin())
            })
            .collect();
        if version % 2 != 0 {
            l.reverse();
        }
        // A small second loop far off, which no robot is near: never picked.
        let far = (0..8)
            .map(|i| {
                let th = 2.0 * PI * i as f64 / 8.0;
                Vec2::new(100.0 + th.cos(), th.sin())
            })
            .collect();
        vec![far, l]
    }
}

/// The team metrics along a moving isoline (extracted again every second, started anywhere,
/// either way round) equal the circle's (`CircleArc`, exact) to the polygon's discretisation:
/// the arc coordinates are carried across extractions, not reset.
#[test]
fn a_moving_isoline_gives_the_circle_metrics() {
    use isotrack_sim::team::TeamIsoline;
    use isotrack_sim::Group;
    let f = field();
    let v = vehicle(0.25, 0.75);
    let plan = StepPlan::new(DT, 200.0, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        ranging: ideal_ranging(10.0),
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig {
            every_steps: 10,
            ..TeamMetricsConfig::default()
        },
    };
    let jumping = JumpingCircle { m: 720 };
    let circle = arc();
    let go = |iso: TeamIsoline<'_>| {
        let mut g =
            Group::with_isoline(&v, &plan, cfg, members(&v, &cluster(), 100.0), Some(iso)).unwrap();
        g.drive(&f, &v, &Oracles::default(), &mut [] as &mut [NoTrace]);
        g.finish(&mut [] as &mut [NoTrace]).team.unwrap()
    };
    let (tm, tc) = (
        go(TeamIsoline::Moving(&jumping)),
        go(TeamIsoline::Fixed(&circle)),
    );
    let per = 2.0 * 720.0 * radius() * (PI / 720.0).sin();
    assert!((tm.isoline_length_m - per).abs() < 1e-9, "{tm:?}");
    let stats = tm.moving_isoline.clone().unwrap();
    // One extraction per second of the 200 s run, t = 0 and t = 200 s included.
    assert_eq!(stats.extractions, 201);
    assert_eq!(stats.samples_without_isoline, 0);
    assert!(
        (tm.gap_cv.unwrap() - tc.gap_cv.unwrap()).abs() < 0.005,
        "{tm:?} {tc:?}"
    );
    let (mm, mc) = (
        tm.revisit_time_max_s.unwrap(),
        tc.revisit_time_max_s.unwrap(),
    );
    assert!((mm - mc).abs() < 0.02 * mc, "{mm} {mc}");
    let (am, ac) = (
        tm.revisit_time_mean_s.unwrap(),
        tc.revisit_time_mean_s.unwrap(),
    );
    assert!((am - ac).abs() < 0.02 * ac, "{am} {ac}");
    assert_eq!(tm.order_preserved, tc.order_preserved);
    assert!(tc.moving_isoline.is_none());
}

/// One vehicle's sink into a team's one log (a trace file's order: every row with its vehicle).
struct LogSink<'a> {
    log: &'a std::cell::RefCell<Vec<(usize, isotrack_sim::TraceRow)>>,
    vehicle: usize,
}

impl isotrack_sim::TraceSink for LogSink<'_> {
    fn record(&mut self, row: &isotrack_sim::TraceRow) {
        self.log.borrow_mut().push((self.vehicle, *row));
    }
}

/// A team of 60 robots (seven full chunks of eight lanes and a partial one) on the circle,
/// every row traced (`record_rate_hz` 100) into one log, the team metrics every step: its
/// result and log as text (`{:?}` prints each `f64` exactly, the shortest text that reads back
/// to the same bits), driven on up to `threads` threads, each stepping at least eight
/// vehicles (one chunk).
fn threaded_team(law: SpacingLaw, ring: RingMode, threads: usize, duration_s: f64) -> String {
    use isotrack_sim::{Group, TeamThreads};
    let n = 60;
    let angles: Vec<f64> = (0..n)
        .map(|i| -2.0 * PI * (i as f64 + 0.3 * (i % 4) as f64) / n as f64)
        .collect();
    let v = vehicle(0.25, 0.75);
    let plan = StepPlan::new(DT, duration_s, 100.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        // Noisy, lossy, delayed ranging, its range limit (0.9 m) within the spread of the
        // gaps (0.73 m on average, 0.22 m to 0.95 m at the start).
        ranging: RangingConfig {
            rate_hz: 5.0,
            noise_std_m: 0.05,
            max_range_m: 0.9,
            dropout_probability: 0.2,
            delay_s: 0.3,
        },
        spacing: SpacingConfig {
            law,
            nominal_speed_mps: V0,
            ring,
        },
        metrics: TeamMetricsConfig::default(),
    };
    let mut members = members(&v, &angles, 100.0);
    for (i, m) in members.iter_mut().enumerate() {
        // Noisy sensors too.
        m.sensor = Sensor::new(
            SensorConfig {
                rate_hz: 50.0,
                noise_std: 0.01,
                ..SensorConfig::default()
            },
            DT,
            7 + i as u64,
        )
        .unwrap();
    }
    let a = arc();
    let log = std::cell::RefCell::new(Vec::new());
    let mut sinks: Vec<LogSink<'_>> = (0..n)
        .map(|vehicle| LogSink { log: &log, vehicle })
        .collect();
    let mut g = Group::new(&v, &plan, cfg, members, Some(&a)).unwrap();
    let split = TeamThreads {
        threads,
        min_vehicles_per_thread: 8,
    };
    assert_eq!(split.parts(n), threads);
    g.drive_threads(&field(), &v, &Oracles::default(), &mut sinks, split);
    let r = g.finish(&mut sinks);
    drop(sinks);
    let log = log.into_inner();
    // The listed ring is known; a discovered one, with this ranging, is not every neighbour:
    // the table found is not one ring, so it is not flown (att32f-5: every vehicle at `v0`,
    // a warning) and the runs must still agree bit for bit. Every vehicle's every step is
    // traced.
    let known = r.ring.iter().filter(|x| x.is_some()).count();
    match ring {
        RingMode::Listed => assert!(known > n / 2, "{:?}", r.ring),
        RingMode::Discover(_) => {
            assert_eq!(known, 0, "{:?}", r.ring);
            assert!(r.warnings[0].contains("not one ring"), "{:?}", r.warnings);
        }
    }
    assert!(
        log.len() > n * (duration_s / DT) as usize / 2,
        "{}",
        log.len()
    );
    format!("{r:?}\n{log:?}")
}

/// 1, 2, 3 and 7 threads give the same team run bit for bit: every result, metric and trace
/// row, the rows in the same order; for `range_balance` on noisy, lossy, delayed ranging,
/// `arc_reference` and `none`, and with the ring found first (discovery steps on one thread,
/// the rest on several).
#[test]
fn threads_give_bit_identical_runs() {
    let discover = RingMode::Discover(DiscoveryConfig {
        settle_s: 1.0,
        probe_s: 1.0,
        probe_speed_delta_mps: 0.1,
    });
    let cases = [
        (
            SpacingLaw::RangeBalance { gain_per_s: 0.2 },
            RingMode::Listed,
            30.0,
        ),
        (
            SpacingLaw::ArcReference { gain_per_s: 0.2 },
            RingMode::Listed,
            20.0,
        ),
        (SpacingLaw::None, RingMode::Listed, 10.0),
        (SpacingLaw::RangeBalance { gain_per_s: 0.2 }, discover, 70.0),
    ];
    for (law, ring, duration_s) in cases {
        let one = threaded_team(law, ring, 1, duration_s);
        for threads in [2, 3, 7] {
            let many = threaded_team(law, ring, threads, duration_s);
            assert!(
                one == many,
                "{law:?} {ring:?}: {threads} threads differ from one"
            );
        }
    }
}

/// The PI-like law, answering NaN from `end_s` on: its vehicle's run ends there (`diverged`),
/// as a vehicle's run ends early for any reason (completed, its command, the field, a
/// non-finite measurement).
struct EndsAt {
    inner: PiIsoline,
    end_s: f64,
}

impl isotrack_core::IsolineController for EndsAt {
    fn update(&mut self, m: &isotrack_core::Measurement) -> f64 {
        if m.t_s >= self.end_s {
            f64::NAN
        } else {
            self.inner.update(m)
        }
    }

    fn reset(&mut self) {
        self.inner.reset();
    }
}

/// Four robots evenly spread (`L/4` apart) under `range_balance` on the listed ring, ideal
/// ranging at 10 Hz up to `max_range_m`, `k_v = 0.1` 1/s; vehicle `gone` ends at `end_s`.
fn one_ends_early(gone: usize, end_s: f64, duration_s: f64, max_range_m: f64) -> TeamResult {
    let v = vehicle(0.25, 0.75);
    let plan = StepPlan::new(DT, duration_s, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap();
    let cfg = TeamConfig {
        ranging: RangingConfig {
            max_range_m,
            ..ideal_ranging(10.0)
        },
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig::default(),
    };
    let angles: Vec<f64> = (0..4).map(|i| -FRAC_PI_2 * i as f64).collect();
    let members = members(&v, &angles, 100.0)
        .into_iter()
        .enumerate()
        .map(|(i, m)| TeamMember {
            x0: m.x0,
            controller: EndsAt {
                inner: m.controller,
                end_s: if i == gone { end_s } else { f64::INFINITY },
            },
            sensor: m.sensor,
            ranging_seed: m.ranging_seed,
        })
        .collect();
    let a = arc();
    simulate_team(
        &field(),
        &v,
        &plan,
        cfg,
        members,
        Some(&a),
        &Oracles::default(),
        &mut [] as &mut [NoTrace],
    )
    .unwrap()
}

/// att32e-3: one of four robots ends at 30 s. The listed ring closes around it (its
/// behind-neighbour's "ahead" becomes its "ahead", and the mirror), and the three others
/// re-space to `L/3` on the ring Laplacian of three: `lambda_1 = 3`, chords at `L/3` with slope
/// `c = cos(pi/3)`, so the slowest mode's time constant is `1/(k_v c lambda_1) = 6.67 s`.
/// From the gaps `L/2, L/4, L/4` (CV 0.354) the linear loop reaches CV 0.05 in
/// `tau ln(0.354/0.05) = 13 s`; the test allows ten time constants (the chord's slope at the
/// `L/2` gap is near 0 and the speeds saturate at first). At the end the gap CV of the three
/// (computed here from their end positions) is below 0.005, and no two come closer than the
/// chord of `L/4` less a tenth of the radius; the same with a range limit of 20 m (the
/// isoline's diameter is 13.9 m). Before the fix the gone vehicle stayed in its neighbours'
/// ring: without a range limit they held its last range for ever, and the three kept the
/// gaps `L/2, L/4, L/4` (end gap CV 0.353); with the limit its range read 20 m after a second,
/// so the vehicle behind it flew its top speed and the one ahead of it its slowest, and they
/// met.
#[test]
fn the_listed_ring_closes_around_a_vehicle_that_ends_early() {
    let (end_s, duration_s) = (30.0, 300.0);
    for (gone, max_range_m) in [(2usize, 20.0), (1, f64::INFINITY), (0, f64::INFINITY)] {
        let r = one_ends_early(gone, end_s, duration_s, max_range_m);
        for (i, run) in r.runs.iter().enumerate() {
            if i == gone {
                assert_eq!(run.outcome, isotrack_sim::Outcome::Diverged);
                assert!((run.t_end_s - end_s).abs() < 0.011, "{}", run.t_end_s);
            } else {
                assert_eq!(run.outcome, isotrack_sim::Outcome::Completed, "{i}");
            }
        }
        let live: Vec<u32> = (0..4u32).filter(|&i| i as usize != gone).collect();
        let angles: Vec<f64> = live
            .iter()
            .map(|&i| {
                let p = r.runs[i as usize].end_position_m;
                p[1].atan2(p[0])
            })
            .collect();
        let cv_end = cv_of(&angles);
        assert!(cv_end < 0.005, "gone {gone}: end gap CV {cv_end}");
        let t = r.team.unwrap();
        let tau = 1.0 / (0.1 * (PI / 3.0).cos() * ring_laplacian_eigenvalue(3, 1));
        assert!((tau - 20.0 / 3.0).abs() < 1e-9);
        let even = t.time_to_even_s.expect("evenly spread at the end");
        assert!(
            even > end_s && even < end_s + 10.0 * tau,
            "gone {gone}: {t:?}"
        );
        // Item 2: the ideal revisit time of the three live vehicles over the window (240 s
        // to the end), `L/(3 v0)`; the measured mean revisit time is that of three evenly
        // spread robots (within 1 %), while the team's `L/(4 v0)` stays reported beside it.
        let l = 2.0 * PI * radius();
        let active = t
            .revisit_time_ideal_active_s
            .expect("a vehicle gone in the window");
        assert!((active - l / (3.0 * V0)).abs() < 1e-9, "{active}");
        assert!((t.revisit_time_ideal_s - l / (4.0 * V0)).abs() < 1e-9);
        let mean = t.revisit_time_mean_s.unwrap();
        assert!((mean / active - 1.0).abs() < 0.01, "{mean} vs {active}");
        let chord = 2.0 * radius() * (PI / 4.0).sin();
        let sep = t.min_separation_m.unwrap();
        assert!(
            sep > chord - 0.1 * radius(),
            "gone {gone}: {sep} vs {chord}"
        );
        // The ring of the three: `ahead(i) = i + 1` skipping the gone vehicle.
        for (k, &i) in live.iter().enumerate() {
            let want = [live[(k + 1) % 3], live[(k + 2) % 3]];
            assert_eq!(r.ring[i as usize], Some(want), "gone {gone}");
        }
        assert_eq!(r.ring[gone], None);
    }
}

/// att32f-9: a vehicle whose run ends (here `diverged`) at the run's last step leaves the ring
/// as one ending earlier does, while the vehicles that completed keep theirs: the ring at the
/// end (`summary.json`'s `team.neighbours`) is the listed ring `ahead(i) = i + 1` of the three
/// others. Before the fix the ring was not closed once no run went on, and the gone vehicle
/// stayed vehicle 1's "ahead" and vehicle 3's "behind" (`[[1,3],[2,0],[3,1],[0,2]]`).
#[test]
fn a_vehicle_that_ends_at_the_last_step_leaves_the_ring() {
    let duration_s = 2.0;
    // Its controller answers NaN at the sample at `duration_s` (the last step) only.
    let r = one_ends_early(2, duration_s - 0.5 * DT, duration_s, f64::INFINITY);
    for (i, run) in r.runs.iter().enumerate() {
        let want = if i == 2 {
            isotrack_sim::Outcome::Diverged
        } else {
            isotrack_sim::Outcome::Completed
        };
        assert_eq!(run.outcome, want, "{i}");
    }
    // It ended at the last step: its last valid state is the step before.
    assert!(
        (r.runs[2].t_end_s - (duration_s - DT)).abs() < 1e-9,
        "{}",
        r.runs[2].t_end_s
    );
    assert_eq!(
        r.ring,
        vec![Some([1, 3]), Some([3, 0]), None, Some([0, 1])],
        "the ring of 0 -> 1 -> 3 -> 0"
    );
    // Nobody ends: the whole listed ring stays.
    let all = one_ends_early(2, f64::INFINITY, duration_s, f64::INFINITY);
    assert_eq!(
        all.ring,
        vec![Some([1, 3]), Some([2, 0]), Some([3, 1]), Some([0, 2])]
    );
}
