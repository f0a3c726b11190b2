//! A plume of puffs in wind, after the filament/puff model of Farrell, Murlis, Long, Li & Carde,
//! "Filament-based atmospheric dispersion model to achieve short time-scale structure of odor
//! plumes", Environmental Fluid Mechanics 2 (2002), simplified to 2-D.
//!
//! What it leaves out of that model (and of its implementations such as pompy):
//!
//! * **Centre-relative dispersion.** There each puff also takes its own random walk about the
//!   plume's centre line (pompy's `centre_rel_diff_scale`), which tears the plume into the
//!   patchy filaments a real odour plume shows. Here a puff moves only with the wind, so puffs
//!   stay in release order along one meandering ribbon, widening only by their Fickian growth.
//! * **A spatially varying wind.** There the wind is a field over the domain (with its own
//!   noise), so different parts of the plume move differently. Here one wind `u(t)`, uniform in
//!   space, moves every puff at once: the whole plume sways together.
//!
//! Its long-run mean without meander is still the Gaussian plume of its own parameters (below,
//! tested), but its intermittency and small-scale structure are weaker than in a real plume or
//! in Farrell et al.'s: a tracker that copes here may still be defeated by real filaments.
//!
//! Puffs leave the source at `release_rate_hz`, each a Gaussian of mass `puff_mass` and width
//! `sigma(a)^2 = sigma0^2 + 2 K a` at age `a` (Fickian growth, diffusivity `K`). All puffs are
//! carried by the same wind `u(t) = U + u'(t)`: the mean wind `U` plus a meander `u'`, a
//! stationary Gaussian process with exponential correlation `sigma_u^2 exp(-|tau|/T)` per
//! component (Ornstein-Uhlenbeck statistics), synthesised as a sum of `J = 64` random cosines
//! with frequencies drawn from its Cauchy spectrum (random Fourier features) so that its
//! integral is closed-form: a puff released at `t_i` is at `p_s + W(t) - W(t_i)`,
//! `W(t) = U t + integral_0^t u'`. The field is then a pure function of `(t, p)`: no state,
//! deterministic for a seed, any query order, shared by threads.
//!
//! `C(t, p) = background + sum_i m / (2 pi sigma_i^2) exp(-|p - p_i|^2 / (2 sigma_i^2))`.
//! Its long-run mean without meander is the 2-D Gaussian plume of a continuous source
//! `q = m * release_rate` in a wind `U` along `x`:
//! `C_mean(x, y) = q / (U sqrt(2 pi) sigma_y(x)) exp(-y^2 / (2 sigma_y(x)^2))`,
//! `sigma_y^2 = sigma0^2 + 2 K x / U` (tested).
//!
//! Cost per query: a spatial index over the puffs. A puff's offset from the query point is
//! `q + W(t_i)` with `q` common to all, so the bounding box of `W(t_i)` over a block of 32
//! consecutive releases, computed once, bounds that block at every time; a block farther than
//! 6 sigma (of its oldest puff) is skipped after one box test. `O(live puffs / 32 + puffs near
//! the query)`: the bundled scenario (240 live puffs) runs 60 000 steps in 0.20 s, under 3.5 us a
//! step (BENCHMARKS.md).

use isotrack_core::math::{Mat2, Vec2};
use isotrack_core::{FieldDerivatives, ScalarField};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Puff-plume parameters (SI units; concentration in field units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PuffPlumeParams {
    /// Source position, m.
    pub source_m: Vec2,
    /// Puffs released per second.
    pub release_rate_hz: f64,
    /// Mass of a puff: its concentration integrates to this over the plane (field units x m^2).
    pub puff_mass: f64,
    /// Initial puff width `sigma0`, m.
    pub puff_sigma0_m: f64,
    /// Diffusivity `K`, m^2/s.
    pub diffusivity_m2ps: f64,
    /// Mean wind `[east, north]`, m/s.
    pub wind_mps: Vec2,
    /// Meander standard deviation per component `sigma_u`, m/s.
    pub meander_std_mps: f64,
    /// Meander correlation time `T`, s.
    pub meander_correlation_s: f64,
    /// A puff older than this is dropped, s.
    pub max_age_s: f64,
    /// Background concentration.
    pub background: f64,
    /// Seed of the meander.
    pub seed: u64,
    /// `[x_min, x_max, y_min, y_max]`, m: outside it the field has no value.
    pub domain_m: Option<[f64; 4]>,
}

/// The random Fourier components of one meander component: `(omega, phase)`.
const COMPONENTS: usize = 64;

/// Release times per cached chunk of `W(t_i)`.
const CHUNK: usize = 4096;
/// Puffs per block of the spatial index.
const BLOCK: usize = 32;

/// A cached chunk: `W(t_i)` of its releases, and per block of [`BLOCK`] consecutive releases
/// the bounding box `[x_min, x_max, y_min, y_max]` of those `W(t_i)`. A puff's offset from a
/// query point is `q + W(t_i)` with `q = p - source - W(t)` common to all, so a block's box,
/// fixed once computed, bounds its puffs at every time: the spatial index of the plume.
#[derive(Debug)]
struct Chunk {
    w: Box<[Vec2]>,
    boxes: Box<[[f64; 4]]>,
}
/// Chunks cached (4 Mi releases: 24 days at 2 Hz); later releases are computed each time.
const MAX_CHUNKS: usize = 1024;

/// The puff plume (see the module docs).
#[derive(Debug)]
pub struct PuffPlume {
    p: PuffPlumeParams,
    /// Per axis: frequencies (rad/s) and phases.
    modes: [[(f64, f64); COMPONENTS]; 2],
    amp: f64,
    /// `W(t_i)` at the release times, computed a chunk at a time on first use (each costs 128
    /// sines; a query visits hundreds of puffs): a pure cache, the values are those of
    /// `displacement`.
    released: Vec<std::sync::OnceLock<Chunk>>,
    /// `sin(phase)` of each mode, per axis (the `W(0)` term of every displacement).
    sin_phase: [[f64; COMPONENTS]; 2],
    /// This plume's identity for the per-thread cache of `W(t)` ([`LAST_W`]).
    id: u64,
}

/// Identities of plumes (a clone is a new plume: its own cache key).
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

std::thread_local! {
    /// The last `(plume id, t bits, W(t))` this thread computed: a query at the same time as the
    /// previous one (a lattice or a moving isoline sampled at one time, thousands of points)
    /// reuses its 256 sines. A pure cache: the values are `displacement`'s.
    static LAST_W: std::cell::Cell<Option<(u64, u64, Vec2)>> = const { std::cell::Cell::new(None) };
    /// `W(t_i)` of consecutive releases beyond the cached chunks, for the plume of the last
    /// query past them ([`PuffPlume::far_window`]). A pure cache, like [`LAST_W`].
    static FAR_W: std::cell::Cell<FarWindow> = const {
        std::cell::Cell::new(FarWindow { id: None, start: 0, w: Vec::new() })
    };
}

/// Releases `start..start + w.len()` of plume `id`: their `W(t_i)`.
#[derive(Debug, Default)]
struct FarWindow {
    id: Option<u64>,
    start: i64,
    w: Vec<Vec2>,
}

/// The longest window of releases [`PuffPlume::far_window`] keeps, releases (2 MiB of `W(t_i)`;
/// a scenario allows at most 100 000 puffs alive at once).
const MAX_FAR_WINDOW: i64 = 1 << 17;

#[cfg(test)]
std::thread_local! {
    /// `W(t)` evaluations (128 sines each) made on this thread: the cost the tests bound.
    static DISPLACEMENTS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

impl Clone for PuffPlume {
    fn clone(&self) -> Self {
        Self::new(self.p)
    }
}

impl PartialEq for PuffPlume {
    fn eq(&self, other: &Self) -> bool {
        self.p == other.p
    }
}

impl PuffPlume {
    /// The plume for `p`.
    pub fn new(p: PuffPlumeParams) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
        rng.set_stream(7);
        let mut modes = [[(0.0, 0.0); COMPONENTS]; 2];
        let scale = 1.0 / p.meander_correlation_s.max(1e-9);
        for axis in modes.iter_mut() {
            for m in axis.iter_mut() {
                let u: f64 = rand::RngExt::random(&mut rng);
                let v: f64 = rand::RngExt::random(&mut rng);
                // |Cauchy(0, 1/T)| by inversion; kept away from 0 (a mode that never moves).
                let omega = (scale * (std::f64::consts::PI * (u - 0.5)).tan())
                    .abs()
                    .max(1e-9);
                *m = (omega, 2.0 * std::f64::consts::PI * v);
            }
        }
        let mut sin_phase = [[0.0; COMPONENTS]; 2];
        for (axis, sines) in modes.iter().zip(sin_phase.iter_mut()) {
            for ((_, ph), s) in axis.iter().zip(sines.iter_mut()) {
                *s = ph.sin();
            }
        }
        Self {
            amp: p.meander_std_mps * (2.0 / COMPONENTS as f64).sqrt(),
            p,
            modes,
            sin_phase,
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            released: (0..MAX_CHUNKS)
                .map(|_| std::sync::OnceLock::new())
                .collect(),
        }
    }

    /// `W(t_i)` of release `i` (cached by chunk).
    fn chunk(&self, c: usize) -> Option<&Chunk> {
        let interval = 1.0 / self.p.release_rate_hz;
        let cell = self.released.get(c)?;
        Some(cell.get_or_init(|| {
            let w: Box<[Vec2]> = (0..CHUNK)
                .map(|k| self.displacement(((c * CHUNK + k) as f64) * interval))
                .collect();
            let boxes = w
                .chunks(BLOCK)
                .map(|b| {
                    b.iter().fold(
                        [
                            f64::INFINITY,
                            f64::NEG_INFINITY,
                            f64::INFINITY,
                            f64::NEG_INFINITY,
                        ],
                        |r, v| [r[0].min(v.x), r[1].max(v.x), r[2].min(v.y), r[3].max(v.y)],
                    )
                })
                .collect();
            Chunk { w, boxes }
        }))
    }

    /// The parameters.
    pub fn params(&self) -> &PuffPlumeParams {
        &self.p
    }

    /// The meander velocity `u'(t)`, m/s.
    pub fn meander_mps(&self, t_s: f64) -> Vec2 {
        let c = |axis: &[(f64, f64); COMPONENTS]| {
            axis.iter().map(|(w, ph)| (w * t_s + ph).cos()).sum::<f64>()
        };
        Vec2::new(self.amp * c(&self.modes[0]), self.amp * c(&self.modes[1]))
    }

    /// `W(t) = U t + integral_0^t u'`, m.
    fn displacement(&self, t_s: f64) -> Vec2 {
        #[cfg(test)]
        DISPLACEMENTS.with(|n| n.set(n.get() + 1));
        let c = |axis: usize| {
            self.modes[axis]
                .iter()
                .zip(&self.sin_phase[axis])
                .map(|((w, ph), sin_ph)| ((w * t_s + ph).sin() - sin_ph) / w)
                .sum::<f64>()
        };
        self.p.wind_mps * t_s + Vec2::new(self.amp * c(0), self.amp * c(1))
    }

    /// [`displacement`](Self::displacement) at the query time, through this thread's cache of
    /// the last one.
    fn displacement_now(&self, t_s: f64) -> Vec2 {
        LAST_W.with(|last| match last.get() {
            Some((id, bits, w)) if id == self.id && bits == t_s.to_bits() => w,
            _ => {
                let w = self.displacement(t_s);
                last.set(Some((self.id, t_s.to_bits(), w)));
                w
            }
        })
    }

    /// Calls `f(i, W(t_i))` for the releases `i` in `from..=to`, all beyond the cached chunks,
    /// their `W(t_i)` from this thread's [`FAR_W`] window: a lattice of queries at one time
    /// computes the live puffs' displacements once (not once per query: 240 puffs of 128
    /// sines each made `check` of a run past the cache, 24 days at 2 Hz, take minutes), and a
    /// run stepping forward computes each release's once. A range longer than
    /// [`MAX_FAR_WINDOW`] is computed puff by puff.
    fn far_window(&self, from: i64, to: i64, f: &mut impl FnMut(i64, Vec2)) {
        let interval = 1.0 / self.p.release_rate_hz;
        if to < from {
            return;
        }
        if to - from >= MAX_FAR_WINDOW {
            for i in from..=to {
                f(i, self.displacement(i as f64 * interval));
            }
            return;
        }
        // Taken out of the cell while `f` runs (it never queries a plume, but nothing here
        // relies on that), and put back after.
        let mut win = FAR_W.with(|c| c.take());
        if win.id != Some(self.id) || from < win.start || from > win.start + win.w.len() as i64 {
            win.id = Some(self.id);
            win.start = from;
            win.w.clear();
        } else {
            win.w.drain(..(from - win.start) as usize);
            win.start = from;
        }
        while win.start + (win.w.len() as i64) <= to {
            let i = win.start + win.w.len() as i64;
            win.w.push(self.displacement(i as f64 * interval));
        }
        for i in from..=to {
            f(i, win.w[(i - from) as usize]);
        }
        FAR_W.with(|c| c.set(win));
    }

    /// Runs `f(mass/(2 pi s^2) exp(..), offset d = p - p_i, s^2)` over the live puffs at `t`.
    fn each_puff(&self, t_s: f64, p: Vec2, mut f: impl FnMut(f64, Vec2, f64)) {
        if t_s < 0.0 || t_s.is_nan() || self.p.release_rate_hz <= 0.0 {
            return;
        }
        let interval = 1.0 / self.p.release_rate_hz;
        let w_now = self.displacement_now(t_s);
        // Puffs released at t_i = i * interval, 0 <= t_i <= t, age <= max_age.
        let last = (t_s / interval).floor() as i64;
        let first = ((t_s - self.p.max_age_s) / interval).ceil().max(0.0) as i64;
        let q = p - self.p.source_m - w_now;
        let sigma2 = |age: f64| self.p.puff_sigma0_m.powi(2) + 2.0 * self.p.diffusivity_m2ps * age;
        let mut puff = |i: i64, wi: Vec2| {
            let age = t_s - i as f64 * interval;
            let s2 = sigma2(age);
            let d = q + wi;
            let r2 = d.dot(d);
            if r2 <= 36.0 * s2 {
                let g =
                    self.p.puff_mass / (2.0 * std::f64::consts::PI * s2) * (-0.5 * r2 / s2).exp();
                f(g, d, s2);
            }
        };
        let mut i = first;
        while i <= last {
            let (c, j) = (i as usize / CHUNK, i as usize % CHUNK);
            let Some(chunk) = self.chunk(c) else {
                // Beyond the cache (so are all later releases): this thread's window of
                // `W(t_i)`, shared by every query at this time and slid along by later ones.
                self.far_window(i, last, &mut puff);
                break;
            };
            // One block: skipped whole when the query is more than 6 sigma (of its oldest
            // puff, the widest) from its box.
            let b = j / BLOCK;
            let block_end = ((c * CHUNK + (b + 1) * BLOCK) as i64 - 1).min(last);
            let [x0, x1, y0, y1] = chunk.boxes[b];
            let (nx, ny) = (-q.x, -q.y);
            let dx = (x0 - nx).max(0.0).max(nx - x1);
            let dy = (y0 - ny).max(0.0).max(ny - y1);
            let s2_max = sigma2(t_s - i as f64 * interval);
            if dx * dx + dy * dy <= 36.0 * s2_max {
                for k in i..=block_end {
                    puff(k, chunk.w[k as usize % CHUNK]);
                }
            }
            i = block_end + 1;
        }
    }

    /// The long-run mean without meander, the 2-D Gaussian plume (module docs), for a wind along
    /// `+x` from the source; `None` upwind of it.
    pub fn gaussian_plume_mean(&self, p: Vec2) -> Option<f64> {
        let u = self.p.wind_mps.norm();
        let e = self.p.wind_mps * (1.0 / u);
        let d = p - self.p.source_m;
        let (x, y) = (d.dot(e), e.x * d.y - e.y * d.x);
        if x <= 0.0 || u <= 0.0 {
            return None;
        }
        let q = self.p.puff_mass * self.p.release_rate_hz;
        let s2 = self.p.puff_sigma0_m.powi(2) + 2.0 * self.p.diffusivity_m2ps * x / u;
        Some(
            self.p.background
                + q / (u * (2.0 * std::f64::consts::PI * s2).sqrt()) * (-0.5 * y * y / s2).exp(),
        )
    }
}

impl PuffPlume {
    /// Inside the domain (everywhere when none is set); never at a non-finite point (no puff
    /// is near NaN or infinity: the field is undefined there, as every other field).
    fn inside(&self, p: Vec2) -> bool {
        p.x.is_finite()
            && p.y.is_finite()
            && self
                .p
                .domain_m
                .is_none_or(|d| (d[0]..=d[1]).contains(&p.x) && (d[2]..=d[3]).contains(&p.y))
    }
}

impl ScalarField for PuffPlume {
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64> {
        if !self.inside(p) {
            return None;
        }
        let mut c = self.p.background;
        self.each_puff(t_s, p, |g, _, _| c += g);
        Some(c)
    }
}

impl FieldDerivatives for PuffPlume {
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2> {
        if !self.inside(p) {
            return None;
        }
        let mut gr = Vec2::new(0.0, 0.0);
        self.each_puff(t_s, p, |g, d, s2| gr = gr - d * (g / s2));
        Some(gr)
    }
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2> {
        if !self.inside(p) {
            return None;
        }
        let mut h = [[0.0; 2]; 2];
        self.each_puff(t_s, p, |g, d, s2| {
            // d2/dx_i dx_j of g = g (d_i d_j / s2^2 - delta_ij / s2).
            let dd = [d.x, d.y];
            for (i, row) in h.iter_mut().enumerate() {
                for (j, hij) in row.iter_mut().enumerate() {
                    let delta = if i == j { 1.0 } else { 0.0 };
                    *hij += g * (dd[i] * dd[j] / (s2 * s2) - delta / s2);
                }
            }
        });
        Some(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> PuffPlumeParams {
        PuffPlumeParams {
            source_m: Vec2::new(0.0, 0.0),
            release_rate_hz: 2.0,
            puff_mass: 10.0,
            puff_sigma0_m: 0.5,
            diffusivity_m2ps: 0.05,
            wind_mps: Vec2::new(1.0, 0.0),
            meander_std_mps: 0.0,
            meander_correlation_s: 10.0,
            max_age_s: 200.0,
            background: 0.0,
            seed: 3,
            domain_m: None,
        }
    }

    /// The field is undefined at a non-finite point, as every other field (a hostile review:
    /// NaN and infinite coordinates read the background, 0).
    #[test]
    fn no_value_at_non_finite_points() {
        let f = PuffPlume::new(params());
        for p in [
            Vec2::new(f64::NAN, 0.0),
            Vec2::new(0.0, f64::NAN),
            Vec2::new(f64::INFINITY, 0.0),
            Vec2::new(0.0, f64::NEG_INFINITY),
        ] {
            assert_eq!(f.value(100.0, p), None, "{p:?}");
            assert!(f.gradient(100.0, p).is_none(), "{p:?}");
        }
        assert!(f.value(100.0, Vec2::new(10.0, 0.0)).is_some());
    }

    /// Without meander, the time average over 200 s at points 10-40 m downwind equals the
    /// Gaussian-plume formula within 2 % (on the axis and one plume width off it).
    #[test]
    fn long_run_mean_is_the_gaussian_plume() {
        let f = PuffPlume::new(params());
        for (x, k) in [(10.0f64, 0.0f64), (20.0, 0.0), (40.0, 0.0), (20.0, 1.0)] {
            let sy = (0.25 + 2.0 * 0.05 * x).sqrt();
            let p = Vec2::new(x, k * sy);
            let n = 20_000;
            let mean = (0..n)
                .map(|j| f.value(200.0 + 200.0 * j as f64 / n as f64, p).unwrap())
                .sum::<f64>()
                / n as f64;
            let want = f.gaussian_plume_mean(p).unwrap();
            assert!(
                (mean - want).abs() < 0.02 * want,
                "({x}, {k} sy): {mean} vs {want}"
            );
        }
    }

    /// The meander has the stated spread, and the field is a pure function of (t, p): the same
    /// seed gives the same values in any query order, another seed others.
    #[test]
    fn meander_statistics_and_determinism() {
        let mut p = params();
        p.meander_std_mps = 0.4;
        let f = PuffPlume::new(p);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|k| f.meander_mps(k as f64 * 5.0).x).collect();
        let var = xs.iter().map(|v| v * v).sum::<f64>() / n as f64;
        assert!((var.sqrt() - 0.4).abs() < 0.06, "std {}", var.sqrt());
        let q = Vec2::new(15.0, 1.0);
        let a: Vec<f64> = (0..50).map(|k| f.value(k as f64, q).unwrap()).collect();
        let b: Vec<f64> = (0..50)
            .rev()
            .map(|k| f.value(k as f64, q).unwrap())
            .collect();
        assert_eq!(a, b.into_iter().rev().collect::<Vec<_>>());
        let g = PuffPlume::new(PuffPlumeParams { seed: 4, ..p });
        assert_ne!(a[40], g.value(40.0, q).unwrap());
    }

    /// The block index changes nothing: every value equals the brute-force sum over all live
    /// puffs, at times spanning several cache chunks and blocks.
    #[test]
    fn the_index_equals_brute_force() {
        let mut p = params();
        p.meander_std_mps = 0.3;
        p.release_rate_hz = 40.0;
        p.max_age_s = 150.0;
        let f = PuffPlume::new(p);
        let brute = |t: f64, q: Vec2| {
            let mut c = 0.0;
            let interval = 1.0 / p.release_rate_hz;
            let last = (t / interval).floor() as i64;
            let first = ((t - p.max_age_s) / interval).ceil().max(0.0) as i64;
            for i in first..=last {
                let ti = i as f64 * interval;
                let s2 = p.puff_sigma0_m.powi(2) + 2.0 * p.diffusivity_m2ps * (t - ti);
                let centre = p.source_m + (f.displacement(t) - f.displacement(ti));
                let d = q - centre;
                let r2 = d.dot(d);
                if r2 <= 36.0 * s2 {
                    c += p.puff_mass / (2.0 * std::f64::consts::PI * s2) * (-0.5 * r2 / s2).exp();
                }
            }
            c
        };
        for (t, x, y) in [
            (10.0, 3.0, 0.2),
            (130.0, 50.0, -3.0),
            (260.0, 20.0, 5.0),
            (260.0, 140.0, 1.0),
        ] {
            let q = Vec2::new(x, y);
            let (a, b) = (f.value(t, q).unwrap(), brute(t, q));
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
                "t {t}: {a} vs {b}"
            );
        }
    }

    /// Issue 30: `isotrack check` of a puff plume took 2 s at `sim.duration_s = 2e6` and more
    /// than 190 s at 4e6, because past the cached chunks (2^22 releases, 24 days at 2 Hz) each
    /// query computed every live puff's `W(t_i)` (128 sines) itself. Now a lattice of queries at
    /// one time computes them once: 800 queries (value and gradient at 400 points) at a time
    /// past the cache cost at most the live puffs' `W(t_i)` and `W(t)`, and a query 10 s later
    /// only the 20 new releases'; the values equal the brute-force sum.
    #[test]
    fn queries_past_the_cache_compute_each_live_puff_once() {
        let mut p = params();
        p.meander_std_mps = 0.3;
        let f = PuffPlume::new(p);
        let interval = 1.0 / p.release_rate_hz;
        let t = (MAX_CHUNKS * CHUNK) as f64 * interval + 1000.0;
        let live = (p.max_age_s * p.release_rate_hz) as u64 + 1;
        // Points at the centres of puffs of every age (computed before counting).
        let centre =
            |t: f64, i: i64| p.source_m + (f.displacement(t) - f.displacement(i as f64 * interval));
        let last = (t / interval).floor() as i64;
        let points: Vec<Vec2> = (0..400)
            .map(|k| centre(t, last - k) + Vec2::new(0.1, -0.2))
            .collect();
        let brute = |t: f64, q: Vec2| {
            let first = ((t - p.max_age_s) / interval).ceil() as i64;
            (first..=(t / interval).floor() as i64)
                .map(|i| {
                    let s2 = p.puff_sigma0_m.powi(2)
                        + 2.0 * p.diffusivity_m2ps * (t - i as f64 * interval);
                    // As the plume sums: q - source - W(t), then + W(t_i) (at t ~ 2e6 s,
                    // W is ~2e6 m and another order of the terms rounds otherwise).
                    let d =
                        (q - p.source_m - f.displacement(t)) + f.displacement(i as f64 * interval);
                    let r2 = d.dot(d);
                    if r2 <= 36.0 * s2 {
                        p.puff_mass / (2.0 * std::f64::consts::PI * s2) * (-0.5 * r2 / s2).exp()
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
        };
        let count = || DISPLACEMENTS.with(|n| n.get());
        for (t, bound) in [(t, live + 1), (t + 10.0, 20 + 1), (t, live + 1)] {
            let before = count();
            let values: Vec<f64> = points.iter().map(|&q| f.value(t, q).unwrap()).collect();
            for &q in &points {
                f.gradient(t, q).unwrap();
            }
            let spent = count() - before;
            assert!(
                spent <= bound,
                "t {t}: {spent} W(t) evaluations, at most {bound}"
            );
            for (q, v) in points.iter().zip(&values).step_by(37) {
                let b = brute(t, *q);
                assert_eq!(*v, b, "t {t} at {q:?}");
            }
        }
        assert!(values_positive(&f, t, &points));
    }

    fn values_positive(f: &PuffPlume, t: f64, points: &[Vec2]) -> bool {
        points.iter().all(|&q| f.value(t, q).unwrap() > 0.0)
    }

    /// Gradient and Hessian against central differences.
    #[test]
    fn derivatives_match_differences() {
        let mut p = params();
        p.meander_std_mps = 0.3;
        let f = PuffPlume::new(p);
        let (t, x) = (30.0, Vec2::new(12.0, 0.7));
        let h = 1e-4;
        let v = |q: Vec2| f.value(t, q).unwrap();
        let g = f.gradient(t, x).unwrap();
        let gx = (v(x + Vec2::new(h, 0.0)) - v(x - Vec2::new(h, 0.0))) / (2.0 * h);
        let gy = (v(x + Vec2::new(0.0, h)) - v(x - Vec2::new(0.0, h))) / (2.0 * h);
        assert!((g.x - gx).abs() < 1e-6 * gx.abs().max(1.0), "{} {gx}", g.x);
        assert!((g.y - gy).abs() < 1e-6 * gy.abs().max(1.0), "{} {gy}", g.y);
        let hm = f.hessian(t, x).unwrap();
        let gr = |q: Vec2| f.gradient(t, q).unwrap();
        let hxy = (gr(x + Vec2::new(0.0, h)).x - gr(x - Vec2::new(0.0, h)).x) / (2.0 * h);
        assert!(
            (hm[0][1] - hxy).abs() < 1e-5 * hxy.abs().max(1.0),
            "{} {hxy}",
            hm[0][1]
        );
    }

    /// Without meander every puff is where the wind put it: `c(t, p) = b + sum over puffs
    /// released at t_i = i/rate, 0 <= t - t_i <= max_age, of m/(2 pi s^2) exp(-|p - src -
    /// U (t - t_i)|^2 / (2 s^2))`, `s^2 = s0^2 + 2 D (t - t_i)`: summed here by hand over every
    /// puff (the field keeps only those within 6 sigma, a relative difference below 1e-7).
    #[test]
    fn values_by_the_puff_sum_by_hand() {
        let mut pp = params();
        pp.background = 0.3;
        pp.max_age_s = 30.0;
        pp.source_m = Vec2::new(2.0, -1.0);
        pp.wind_mps = Vec2::new(0.8, 0.3);
        let f = PuffPlume::new(pp);
        for (t, x, y) in [
            (12.3, 5.0, 0.0),
            (45.0, 20.0, 4.0),
            (45.0, 10.0, 3.5),
            (0.0, 2.0, -1.0),
        ] {
            let mut want = pp.background;
            let mut i = 0;
            while i as f64 / pp.release_rate_hz <= t {
                let age = t - i as f64 / pp.release_rate_hz;
                if age <= pp.max_age_s {
                    let s2 = pp.puff_sigma0_m.powi(2) + 2.0 * pp.diffusivity_m2ps * age;
                    let c = pp.source_m + pp.wind_mps * age;
                    let r2 = (x - c.x).powi(2) + (y - c.y).powi(2);
                    want +=
                        pp.puff_mass / (2.0 * std::f64::consts::PI * s2) * (-0.5 * r2 / s2).exp();
                }
                i += 1;
            }
            let got = f.value(t, Vec2::new(x, y)).unwrap();
            assert!(
                (got - want).abs() <= 1e-7 * want.abs(),
                "t {t} ({x}, {y}): {got} vs {want}"
            );
        }
        // Before the first release, only the background; and a source that releases nothing
        // leaves only the background at any time.
        assert_eq!(f.value(-1.0, Vec2::new(2.0, -1.0)), Some(0.3));
        pp.release_rate_hz = 0.0;
        let none = PuffPlume::new(pp);
        assert_eq!(none.value(10.0, Vec2::new(2.0, -1.0)), Some(0.3));
        assert_eq!(none.value(0.0, Vec2::new(2.0, -1.0)), Some(0.3));
    }

    /// The meander's displacement is the integral of its velocity: `W(t) = U t + int_0^t u'`,
    /// checked against Simpson's rule on `meander_mps` (computed apart, from the cosines).
    #[test]
    fn displacement_integrates_the_meander() {
        let mut pp = params();
        pp.meander_std_mps = 0.4;
        pp.meander_correlation_s = 5.0;
        let f = PuffPlume::new(pp);
        for t in [0.0, 3.7, 20.0, 61.0] {
            let n = 4000;
            let h = t / n as f64;
            let mut acc = Vec2::new(0.0, 0.0);
            for k in 0..=n {
                let w = if k == 0 || k == n {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                acc = acc + f.meander_mps(k as f64 * h) * (w * h / 3.0);
            }
            let want = pp.wind_mps * t + acc;
            let got = f.displacement(t);
            // Simpson's error here is below 1e-7 m.
            assert!((got - want).norm() < 1e-6, "t {t}: {got:?} vs {want:?}");
        }
    }

    /// Two plumes are equal when their parameters are, whatever else they cache.
    #[test]
    fn equality_is_by_parameters() {
        let a = PuffPlume::new(params());
        assert!(a == a.clone());
        let mut p2 = params();
        p2.seed = 4;
        assert!(a != PuffPlume::new(p2));
    }

    /// The per-thread cache of `W(t)` is invisible: queries interleaved over two plumes (two
    /// seeds) and repeated times give what each plume gives without a cache
    /// (`displacement`, and a fresh plume for every value), on this thread and another.
    #[test]
    fn the_displacement_cache_changes_no_value() {
        let pa = PuffPlumeParams {
            meander_std_mps: 0.3,
            ..params()
        };
        let p2 = PuffPlumeParams { seed: 4, ..pa };
        let (a, b) = (PuffPlume::new(pa), PuffPlume::new(p2));
        let queries = [
            (0, 30.0),
            (0, 30.0),
            (1, 30.0),
            (0, 30.0),
            (1, 45.5),
            (0, 45.5),
            (0, 30.0),
        ];
        let check = |a: &PuffPlume, b: &PuffPlume| {
            for (k, &(which, t)) in queries.iter().enumerate() {
                let (plume, fresh_params) = if which == 0 { (a, pa) } else { (b, p2) };
                assert_eq!(
                    plume.displacement_now(t),
                    plume.displacement(t),
                    "query {k}"
                );
                let p = Vec2::new(1.5, 0.1);
                let fresh = PuffPlume::new(fresh_params).value(t, p);
                assert!(fresh.unwrap() > 0.1, "query {k}: {fresh:?}");
                assert_eq!(plume.value(t, p), fresh, "query {k}");
            }
        };
        check(&a, &b);
        std::thread::scope(|s| {
            s.spawn(|| check(&a, &b));
        });
        // The two plumes do move differently.
        assert_ne!(a.displacement(30.0), b.displacement(30.0));
    }

    /// The mean plume by the formula, in the wind's frame worked out by hand: wind (0.6, 0.8)
    /// (speed 1), source (2, -1); the point (5.4, 4.4) is 6.36 m downwind and 0.52 m to the left.
    /// `C = b + q / (u sqrt(2 pi s^2)) exp(-y^2 / (2 s^2))`, `s^2 = s0^2 + 2 D x / u`; upwind
    /// and in still air there is none. The domain bounds the field, edges included.
    #[test]
    fn gaussian_plume_mean_by_hand() {
        let mut pp = params();
        pp.wind_mps = Vec2::new(0.6, 0.8);
        pp.source_m = Vec2::new(2.0, -1.0);
        pp.background = 0.2;
        let f = PuffPlume::new(pp);
        // d = (3.4, 5.4): along = 0.6*3.4 + 0.8*5.4 = 6.36; across = 0.6*5.4 - 0.8*3.4 = 0.52.
        let (x, y) = (6.36f64, 0.52f64);
        let s2 = 0.25 + 2.0 * 0.05 * x;
        let want =
            0.2 + 10.0 * 2.0 / (2.0 * std::f64::consts::PI * s2).sqrt() * (-0.5 * y * y / s2).exp();
        let got = f.gaussian_plume_mean(Vec2::new(5.4, 4.4)).unwrap();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        assert_eq!(f.gaussian_plume_mean(Vec2::new(1.0, -2.0)), None, "upwind");
        pp.wind_mps = Vec2::new(0.0, 0.0);
        assert_eq!(
            PuffPlume::new(pp).gaussian_plume_mean(Vec2::new(5.0, 5.0)),
            None
        );
        let mut pd = params();
        pd.domain_m = Some([0.0, 10.0, -2.0, 2.0]);
        let g = PuffPlume::new(pd);
        assert!(g.value(5.0, Vec2::new(10.0, 2.0)).is_some());
        assert!(g.value(5.0, Vec2::new(10.01, 0.0)).is_none());
        assert!(g.value(5.0, Vec2::new(3.0, -2.01)).is_none());
        assert!(g.gradient(5.0, Vec2::new(3.0, -2.01)).is_none());
        assert!(g.hessian(5.0, Vec2::new(-0.01, 0.0)).is_none());
    }
}
