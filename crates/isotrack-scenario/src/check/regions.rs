//! What the check's lattice gives it over a scenario's field: the region sampled ([`region`]),
//! the start-to-tube region's and the tube's bounds and the isoline's slopes ([`regions`]).
//! Shared by `check`, the stability chart ([`super::map`]), the baselines' check
//! ([`super::baselines`]) and the team check; a leaf of `check` (it uses only
//! [`super::lattice`]).

use super::lattice::{self, Lattice};
use crate::field::FieldModel;
use crate::spec::Start;
use crate::Scenario;
use isotrack_core::math::Vec2;
use isotrack_core::theory::radial_exp_isoline_radius_m;
use isotrack_core::ScalarField;
use isotrack_fields::grid::Interpolation;
use isotrack_fields::AnalyticKind;

/// Lattice points per side for `isotrack check`.
pub(super) const CHECK_LATTICE: usize = 601;

/// An empty box `[x0, x1, y0, y1]`, m: growing it round a point gives the square round it.
const EMPTY: [f64; 4] = [
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
];

/// The box `r` grown to hold the square of half-side `m` round `p`.
fn grow(mut r: [f64; 4], p: Vec2, m: f64) -> [f64; 4] {
    r[0] = r[0].min(p.x - m);
    r[1] = r[1].max(p.x + m);
    r[2] = r[2].min(p.y - m);
    r[3] = r[3].max(p.y + m);
    r
}

/// The box `r` grown to hold every vehicle's start (nu36-4: a team's, not `[initial]`'s),
/// each grown by `m` as the one start was.
fn with_starts(r: [f64; 4], all: &[Start], m: f64) -> [f64; 4] {
    let b = all
        .iter()
        .fold(EMPTY, |r, st| grow(r, Vec2::new(st.x_m, st.y_m), m));
    [
        r[0].min(b[0]),
        r[1].max(b[1]),
        r[2].min(b[2]),
        r[3].max(b[3]),
    ]
}

/// The region over which the field is sampled: the grid, the domain, or a box round the
/// analytic field's features and the start.
pub(super) fn region(s: &Scenario) -> [f64; 4] {
    let all = starts(s);
    match s.field() {
        FieldModel::Grid(g) => g.grid().extent_m(),
        FieldModel::Series(g) => g.extent_m(),
        FieldModel::Puff(pf) => puff_region(pf, s.spec().field.domain_m(), all),
        FieldModel::Analytic(a) => {
            if let Some(d) = a.domain_m {
                return d;
            }
            match &a.kind {
                AnalyticKind::RadialExp(r) => {
                    let rd =
                        radial_exp_isoline_radius_m(r.i0, r.decay_per_m, s.level()).unwrap_or(10.0);
                    with_starts(grow(EMPTY, r.center_m, 3.0 * rd), all, 1.0)
                }
                AnalyticKind::GaussianPlumes(p) => {
                    p.plumes.iter().fold(with_starts(EMPTY, all, 1.0), |r, pl| {
                        grow(r, pl.center_m, 4.0 * pl.sigma_m[0].max(pl.sigma_m[1]))
                    })
                }
                AnalyticKind::LinearRamp(_) => with_starts(EMPTY, all, 100.0),
            }
        }
    }
}

/// A puff plume's region: the plume's reach over its puffs' lifetime downwind, and the
/// starts; within the `domain` when there is one (att36-12: the domain alone, 2 km or 200 km
/// wide, spread the fixed lattice over it, 333 m a step for a plume tens of metres wide, and
/// the verdict changed with it: the domain says where the field is defined, the plume is the
/// same).
fn puff_region(
    pf: &isotrack_fields::puff::PuffPlume,
    domain: Option<[f64; 4]>,
    all: &[Start],
) -> [f64; 4] {
    let pp = pf.params();
    let reach = pp.wind_mps.norm() * pp.max_age_s + 4.0 * pp.puff_sigma0_m + 10.0;
    let b = with_starts(grow(EMPTY, pp.source_m, reach), all, 10.0);
    match domain {
        Some(d) => {
            let cut = [
                b[0].max(d[0]),
                b[1].min(d[1]),
                b[2].max(d[2]),
                b[3].min(d[3]),
            ];
            if cut[0] < cut[1] && cut[2] < cut[3] {
                cut
            } else {
                d
            }
        }
        None => b,
    }
}

/// The slope range the sampled check covers: the 5th percentile .. maximum of `slopes` (the
/// lowest slopes sit at saddles, where the isoline branches and no linearisation holds; a loop
/// with a tiny slope is slow, not unstable).
pub(super) fn slope_range(mut slopes: Vec<f64>) -> Option<[f64; 2]> {
    slopes.retain(|g| g.is_finite() && *g > 0.0);
    if slopes.is_empty() {
        return None;
    }
    // The order statistics a full sort would give, without the sort (`O(n)`): the 5th
    // percentile's place, and the largest.
    let hi = slopes.iter().copied().max_by(f64::total_cmp)?;
    let at = (slopes.len() - 1) * 5 / 100;
    let (_, &mut lo, _) = slopes.select_nth_unstable_by(at, f64::total_cmp);
    Some([lo, hi])
}

/// The isoline's own slopes where the field gives them exactly: `k*s_d` on a circular field
/// (`F = i0 exp(-k d)`, so `|dF/dd| = k F`); `None` elsewhere (read off the lattice).
pub(super) fn exact_isoline_slope(s: &Scenario) -> Option<f64> {
    match s.field() {
        FieldModel::Analytic(a) => match &a.kind {
            AnalyticKind::RadialExp(r) => {
                radial_exp_isoline_radius_m(r.i0, r.decay_per_m, s.level())
                    .map(|_| r.decay_per_m * s.level())
            }
            _ => None,
        },
        _ => None,
    }
}

/// The start: position and level (the pose [`analysed_start`] gives).
pub(super) fn start(s: &Scenario) -> Vec2 {
    let (_, st) = analysed_start(s);
    Vec2::new(st.x_m, st.y_m)
}

/// Every start a vehicle flies from: `[initial]` for one vehicle, the team's starts for a team
/// (whose `[initial]` no vehicle flies from, nu36-4).
pub(super) fn starts(s: &Scenario) -> &[Start] {
    match s.spec().team.as_ref() {
        Some(t) if !t.starts.is_empty() => &t.starts,
        _ => std::slice::from_ref(&s.spec().start),
    }
}

/// The pose the start-dependent checks analyse (the start-to-tube region, the heading sector,
/// the reach and settling warnings), with its vehicle's index for a team: `[initial]` for one
/// vehicle; for a team (nu36-4: `[initial]` is no vehicle's start there) the team's start
/// farthest from the level, `|F(0, p) - s_d|` largest at `t = 0`, a start without a field
/// value before any (the first such in the listed order on a tie): the region from it to the
/// tube holds the levels of every start on its side of the isoline.
pub(super) fn analysed_start(s: &Scenario) -> (Option<usize>, Start) {
    let Some(t) = s.spec().team.as_ref().filter(|t| !t.starts.is_empty()) else {
        return (None, s.spec().start);
    };
    let level = s.level();
    let distance = |st: &Start| {
        s.field()
            .value(0.0, Vec2::new(st.x_m, st.y_m))
            .filter(|f| f.is_finite())
            .map_or(f64::INFINITY, |f| (f - level).abs())
    };
    let mut best = (0, distance(&t.starts[0]));
    for (i, st) in t.starts.iter().enumerate().skip(1) {
        let d = distance(st);
        if d > best.1 {
            best = (i, d);
        }
    }
    (Some(best.0), t.starts[best.0])
}

/// What the lattice gives the checks: bounds over the start-to-tube region and the tube, the
/// tube's slopes and the isoline's own.
pub(super) struct Regions {
    /// The isoline's slopes at its lattice crossings in the tube (empty where the slope is
    /// exact).
    pub(super) isoline_slopes: Vec<f64>,
    pub(super) levels: Option<[f64; 2]>,
    pub(super) region: Option<lattice::Bounds>,
    pub(super) tube: Option<lattice::Bounds>,
    pub(super) slope_range: Option<[f64; 2]>,
    pub(super) isoline_slope_range: Option<[f64; 2]>,
    /// The field has no value at the start.
    pub(super) start_without_data: bool,
}

impl Regions {
    /// The regions of a field whose isoline slope `alpha` is exact ([`exact_isoline_slope`]),
    /// without a lattice: the isoline's slope range `[alpha, alpha]` (as [`regions`] gives it
    /// there) and nothing read off a lattice (no tube slopes, no bounds). Enough for the
    /// warnings of `run`, which read only the isoline's slopes ([`super::warnings`]).
    pub(super) fn of_exact_slope(alpha: f64) -> Self {
        Self {
            isoline_slopes: vec![],
            levels: None,
            region: None,
            tube: None,
            slope_range: None,
            isoline_slope_range: Some([alpha, alpha]),
            start_without_data: false,
        }
    }
}

pub(super) fn regions(s: &Scenario, tube: f64, n: usize, with_bounds: bool) -> Regions {
    let field = s.field();
    let level = s.level();
    let p0 = start(s);
    let lat = Lattice::new(field, region(s), n);
    let has_hessian = !matches!(field, FieldModel::Grid(g) if g.interpolation() == Interpolation::Bilinear)
        && !matches!(field, FieldModel::Series(g) if g.interpolation() == Interpolation::Bilinear);
    let (lo, hi) = (level - tube, level + tube);
    let tube_cells = lat
        .nearest_band_cell(p0, lo, hi)
        .map(|seed| lat.component(seed, lo, hi));
    let slope_range = tube_cells.as_ref().and_then(|c| slope_range(lat.slopes(c)));
    let isoline_slopes: Vec<f64> = match exact_isoline_slope(s) {
        Some(_) => vec![],
        None => tube_cells
            .as_ref()
            .map(|c| lat.isoline_slopes(c, level))
            .unwrap_or_default()
            .into_iter()
            .filter(|g| g.is_finite() && *g > 0.0)
            .collect(),
    };
    let isoline_slope_range = match exact_isoline_slope(s) {
        Some(alpha) => Some([alpha, alpha]),
        None => self::slope_range(isoline_slopes.clone()),
    };
    if !with_bounds {
        return Regions {
            isoline_slopes,
            levels: None,
            region: None,
            tube: None,
            slope_range,
            isoline_slope_range,
            start_without_data: false,
        };
    }
    let tube_bounds = tube_cells.as_ref().and_then(|c| lat.bounds(c, has_hessian));
    let (levels, region_bounds) = match (field.value(0.0, p0), lat.cell_of(p0)) {
        (Some(s0), Some(cell)) => {
            // The levels from the start's, widened by the tube's half-width H on its far side,
            // to the tube's far edge: [min(s0, s_d) - H, max(s0, s_d) + H]. Prop. 2 (Dong & You)
            // assumes its bounds over the whole plane, and its proof uses them wherever the robot
            // goes. From the sector `phi(t0) in [-pi + phi, -phi]` the robot can first move away
            // from the isoline (`s' = -v |grad F| cos phi` takes either sign there) before it
            // turns in, so the band stops not at the start's level but H beyond it; past the
            // isoline, `|e|` is non-increasing outside `rho` and the error stays within the
            // bound, which the note compares with the tube. A margin, not a proof: the levels
            // the transient reaches are not bounded by the check.
            //
            // A team (nu36-4): the band holds every vehicle's start level with data (the
            // analysed start, farthest from the level, holds those on its side).
            let (s_lo, s_hi) = starts(s)
                .iter()
                .filter_map(|st| field.value(0.0, Vec2::new(st.x_m, st.y_m)))
                .filter(|f| f.is_finite())
                .fold((s0, s0), |(a, b), f| (a.min(f), b.max(f)));
            let levels = [(s_lo - tube).min(lo), (s_hi + tube).max(hi)];
            let cells = lat.component(cell, levels[0], levels[1]);
            (Some(levels), lat.bounds(&cells, has_hessian))
        }
        _ => (None, None),
    };
    Regions {
        isoline_slopes,
        levels,
        region: region_bounds,
        tube: tube_bounds,
        slope_range,
        isoline_slope_range,
        start_without_data: !field.value(0.0, p0).is_some_and(f64::is_finite),
    }
}
