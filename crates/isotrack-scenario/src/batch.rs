//! Running many scenarios at once: those that share their field, vehicle and plan (the runs
//! of a sweep that vary starts, seeds, gains or sensors) are stepped together in SIMD lanes
//! ([`isotrack_sim::simulate_batch`]); each result is the one [`Scenario::run`] gives.

use crate::field::FieldModel;
use crate::vehicle::VehicleModel;
use crate::Scenario;
use isotrack_core::math::Vec2;
use isotrack_core::{FieldDerivatives, ScalarField};
use isotrack_sim::{simulate_batch, BatchRun, Oracles, RunResult, LANES};
use isotrack_vehicles::{DubinsState, FixedWingConfig};
use std::sync::Arc;

impl Scenario {
    /// Runs every scenario of `runs` (no trace) and returns their results in order, each
    /// bit-identical to `run(&mut NoTrace)` of that scenario. Consecutive scenarios that share
    /// their field and vehicle (the same built objects, as [`Scenario::derive`] variants do
    /// when neither changes) and their step plan are stepped [`LANES`] at a time.
    pub fn run_batch(runs: &[Scenario]) -> Vec<RunResult> {
        let mut out = Vec::with_capacity(runs.len());
        let mut rest = runs;
        while let Some(first) = rest.first() {
            let n = rest
                .iter()
                .take(LANES)
                .take_while(|s| s.batches_with(first))
                .count();
            let (group, tail) = rest.split_at(n);
            out.extend(first.run_group(group));
            rest = tail;
        }
        out
    }

    /// Whether `self` can be stepped in the same lanes as `other`.
    fn batches_with(&self, other: &Scenario) -> bool {
        let same_vehicle = match (&*self.vehicle, &*other.vehicle) {
            // A Dubins robot is its speed (derive rebuilds it when sim.seed changes, which only
            // a UAV's gusts depend on).
            (VehicleModel::Dubins(a), VehicleModel::Dubins(b)) => a == b,
            // A UAV is its configuration (trim and gains follow from it); derive rebuilds it
            // when sim.seed changes, which only its gusts' seed depends on, and each lane
            // starts with its own scenario's gust seed (`run_on`).
            (VehicleModel::FixedWing(a), VehicleModel::FixedWing(b)) => {
                let unseeded = |c: &FixedWingConfig| FixedWingConfig { seed: 0, ..*c };
                unseeded(a.config()) == unseeded(b.config())
            }
            _ => Arc::ptr_eq(&self.vehicle, &other.vehicle),
        };
        Arc::ptr_eq(&self.field, &other.field) && same_vehicle && self.plan() == other.plan()
    }

    /// One group of [`batches_with`](Self::batches_with) scenarios (`self` the first), each
    /// with its own start, controller, sensor and isoline oracle.
    fn run_group(&self, group: &[Scenario]) -> Vec<RunResult> {
        let results = match self.field() {
            FieldModel::Analytic(f) => run_on(f, group),
            FieldModel::Grid(f) => run_on(f, group),
            FieldModel::Puff(f) => run_on(&**f, group),
            FieldModel::Series(f) => run_on(&**f, group),
        };
        group
            .iter()
            .zip(results)
            .map(|(s, r)| s.explain_end(r))
            .collect()
    }
}

/// The group on its (shared) field, dispatched once on the vehicle.
fn run_on<F: ScalarField + FieldDerivatives + Sync>(
    field: &F,
    group: &[Scenario],
) -> Vec<RunResult> {
    let first = &group[0];
    let plan = first.plan();
    let dists: Vec<_> = group
        .iter()
        .map(|s| {
            let iso = s.isoline();
            move |t: f64, p: Vec2| iso.distance(t, p)
        })
        .collect();
    let grad = |t: f64, p: Vec2| Some((field.gradient(t, p)?, field.hessian(t, p)?));
    let oracles = |i: usize| Oracles {
        isoline_distance: Some(&dists[i]),
        gradient: Some(&grad),
    };
    match &*first.vehicle {
        VehicleModel::Dubins(vehicle) => {
            let x0 = |s: &Scenario| {
                let st = s.start();
                DubinsState {
                    position_m: Vec2::new(st.x_m, st.y_m),
                    heading_rad: st.heading_rad,
                }
            };
            simulate_batch(field, vehicle, &plan, batch_runs(group, oracles, x0))
        }
        VehicleModel::FixedWing(vehicle) => {
            // Each run's own gust seed (the airframes of a group differ in nothing else).
            let x0 = |s: &Scenario| {
                let st = s.start();
                let seed = match &*s.vehicle {
                    VehicleModel::FixedWing(own) => own.config().seed,
                    VehicleModel::Dubins(_) => vehicle.config().seed,
                };
                vehicle.initial_state_seeded(st.x_m, st.y_m, st.heading_rad, seed)
            };
            simulate_batch(field, &**vehicle, &plan, batch_runs(group, oracles, x0))
        }
    }
}

/// Each run of `group` with `x0(scenario)` as its initial state, its own controller and sensor,
/// and `oracles(i)`.
fn batch_runs<'a, X>(
    group: &[Scenario],
    oracles: impl Fn(usize) -> Oracles<'a>,
    x0: impl Fn(&Scenario) -> X,
) -> Vec<BatchRun<'a, X, crate::build::Tracker>> {
    group
        .iter()
        .enumerate()
        .map(|(i, s)| BatchRun {
            x0: x0(s),
            controller: s.tracker(),
            sensor: s.sensor(),
            oracles: oracles(i),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::parse_scenario;

    /// Derived runs that differ in seed, start or gains share their lanes (a Dubins robot is
    /// its speed: rebuilt for a new seed, still the same robot); a new speed, field or plan
    /// does not.
    #[test]
    fn runs_batch_when_field_vehicle_and_plan_agree() {
        let base = parse_scenario("", "<test>", &["sim.duration_s=5".into()]).unwrap();
        let d = |set: &str| base.derive(&[set.to_string()], "<test>").unwrap();
        for set in ["sim.seed=4", "initial.x_m=9", "controller.kp=3"] {
            assert!(d(set).batches_with(&base), "{set}");
        }
        for set in ["vehicle.speed_mps=1", "field.i0=30", "sim.duration_s=6"] {
            assert!(!d(set).batches_with(&base), "{set}");
        }
    }

    /// UAV runs that differ in seed (and so in gust seed), start or gains share their lanes;
    /// a new airspeed, wind or gust switch does not.
    #[test]
    fn uav_runs_batch_across_seeds() {
        let base = parse_scenario(
            "[vehicle]\nkind = \"fixed_wing\"\ngusts = true\n",
            "<test>",
            &["sim.duration_s=5".into()],
        )
        .unwrap();
        let d = |set: &str| base.derive(&[set.to_string()], "<test>").unwrap();
        for set in ["sim.seed=4", "initial.x_m=9", "controller.kp=3"] {
            assert!(d(set).batches_with(&base), "{set}");
        }
        for set in [
            "vehicle.airspeed_mps=25",
            "vehicle.wind_mps=[1.0, 0.0]",
            "vehicle.gusts=false",
        ] {
            assert!(!d(set).batches_with(&base), "{set}");
        }
    }
}
