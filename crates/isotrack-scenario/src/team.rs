//! Running a scenario's `[team]` ([`crate::spec::TeamSpec`]) through
//! [`isotrack_sim::simulate_team`]: every vehicle the scenario's field, tracking law and sensor
//! (its own seeded streams), a Dubins robot whose speed the spacing law sets within
//! `[team.v_min_mps, team.v_max_mps]` (docs/TEAMS.md).

use crate::field::{FieldModel, IsolineOracle};
use crate::spec::TeamSpec;
use crate::Scenario;
use isotrack_core::math::Vec2;
use isotrack_core::{FieldDerivatives, ScalarField};
use isotrack_sim::team::arc::{ArcProjection, CircleArc};
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::spacing::SpacingConfig;
use isotrack_sim::TraceSink;
use isotrack_sim::{simulate_team, Oracles, TeamConfig, TeamError, TeamMember, TeamResult};
use isotrack_vehicles::{DubinsState, DubinsVariableSpeed};

impl Scenario {
    /// The true isoline as an arc-length projection for the team metrics and the
    /// `arc_reference` law: the circle of a radial field that does not drift (`None` otherwise:
    /// the team metrics are then left out, and `arc_reference` is refused).
    pub fn team_arc(&self) -> Option<CircleArc> {
        match self.isoline() {
            IsolineOracle::Circle {
                center_m,
                drift_mps,
                radius_m,
            } if drift_mps.x == 0.0 && drift_mps.y == 0.0 => Some(CircleArc {
                center_m: *center_m,
                radius_m: *radius_m,
            }),
            _ => None,
        }
    }

    /// Runs the scenario's team (`None` without a `[team]` section), vehicle `i` recording its
    /// trace into `sinks[i]` (`sinks` empty: no trace).
    pub fn run_team<S: TraceSink>(&self, sinks: &mut [S]) -> Option<Result<TeamResult, TeamError>> {
        let team = self.spec().team.as_ref()?;
        Some(match self.field() {
            FieldModel::Analytic(f) => self.run_team_on(f, team, sinks),
            FieldModel::Grid(f) => self.run_team_on(f, team, sinks),
            FieldModel::Puff(f) => self.run_team_on(&**f, team, sinks),
            FieldModel::Series(f) => self.run_team_on(&**f, team, sinks),
        })
    }

    fn run_team_on<F: ScalarField + FieldDerivatives + Sync, S: TraceSink>(
        &self,
        field: &F,
        team: &TeamSpec,
        sinks: &mut [S],
    ) -> Result<TeamResult, TeamError> {
        let iso = self.isoline();
        let dist = |t: f64, p: Vec2| iso.distance(t, p);
        let grad = |t: f64, p: Vec2| Some((field.gradient(t, p)?, field.hessian(t, p)?));
        let oracles = Oracles {
            isoline_distance: Some(&dist),
            gradient: Some(&grad),
        };
        let vehicle = DubinsVariableSpeed {
            min_speed_mps: team.v_min_mps,
            max_speed_mps: team.v_max_mps,
        };
        let seed = self.spec().sim.seed;
        let members = team
            .starts
            .iter()
            .enumerate()
            .map(|(i, s)| TeamMember {
                x0: vehicle.state(
                    DubinsState {
                        position_m: Vec2::new(s.x_m, s.y_m),
                        heading_rad: s.heading_rad,
                    },
                    team.nominal_speed_mps,
                ),
                controller: self.tracker(),
                sensor: self.sensor_seeded(TeamSpec::sensor_seed(seed, i)),
                ranging_seed: TeamSpec::ranging_seed(seed, i),
            })
            .collect();
        let cfg = TeamConfig {
            ranging: team.ranging,
            spacing: SpacingConfig {
                law: team.law,
                nominal_speed_mps: team.nominal_speed_mps,
                ring: team.ring,
            },
            metrics: TeamMetricsConfig::default(),
        };
        let arc = self.team_arc();
        let r = simulate_team(
            field,
            &vehicle,
            &self.plan(),
            cfg,
            members,
            arc.as_ref().map(|a| a as &dyn ArcProjection),
            &oracles,
            sinks,
        )?;
        Ok(TeamResult {
            runs: r.runs.into_iter().map(|x| self.explain_end(x)).collect(),
            ..r
        })
    }
}
