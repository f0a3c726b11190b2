//! The scenario layer's integration tests, one module per subject, in one test binary: one
//! build and link per change instead of fifteen (mutation testing rebuilds it for every mutant),
//! and cargo runs all of them in parallel.

mod baselines;
mod batch;
mod check;
mod derive;
mod episode;
mod fixed_wing;
mod isoline;
mod keys;
mod map;
mod properties;
mod readme;
mod sampled;
mod search;
mod series;
mod stations;
mod team_check;
mod team_check_bounds;
mod team_check_equilibrium;
mod team_check_linearised;
mod team_check_start;
mod team_open;
mod team_vehicles;
mod theory;
mod validation;
mod verdict;
