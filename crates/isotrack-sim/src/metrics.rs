//! Streaming run metrics: constant memory whatever the run length.

use serde::Serialize;

/// What the metrics need to know before the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricsConfig {
    /// Step, seconds.
    pub dt_s: f64,
    /// First step of the steady-state window (the window is `[t_ss, t_end]` of the planned run).
    pub steady_state_start_step: u64,
    /// Convergence tolerance on `|eps|`, field units (> 0).
    pub convergence_tolerance: f64,
    /// Minimum dwell: the error must stay within the tolerance for at least this many steps,
    /// up to the end of the run, for a convergence time to be reported. A limit cycle that
    /// happens to be inside the band at the very end is not convergence.
    pub convergence_min_dwell_steps: u64,
    /// The track-loss band on `|eps|`, field units (>= the tolerance): once the error has been
    /// within the tolerance, leaving this band is a track loss (re-acquired when back within
    /// the tolerance).
    pub track_loss_band: f64,
}

/// Accumulates the metrics of one run step by step.
#[derive(Clone, Debug)]
pub struct Metrics {
    cfg: MetricsConfig,
    ss_n: u64,
    ss_max_abs: f64,
    ss_sum: f64,
    ss_sum_sq: f64,
    ss_tv_omega: f64,
    ss_sign_changes: u64,
    ss_prev_omega: Option<f64>,
    ss_prev_sign: f64,
    last_violation: Option<u64>,
    last_step: u64,
    path_length_m: f64,
    effort: f64,
    iso_n: u64,
    iso_max: f64,
    iso_sum_sq: f64,
    ss_in_band: u64,
    /// Whether the error is tracked: within the tolerance once, and not out of the band since.
    tracking: bool,
    track_losses: u64,
    /// Whether the error ever reached the level (see [`RunMetrics::reached_level`]).
    reached: bool,
    /// The sign of the first finite error (`Some(true)`: above the level).
    first_above: Option<bool>,
    /// The largest squared distance from the start, m^2.
    far_sq: f64,
}

/// The metrics of a finished run. `None` (JSON `null`) where a metric is undefined: no step
/// reached the steady-state window, or the error never stayed within tolerance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunMetrics {
    /// `max |eps|` over the steady-state window (field units).
    pub steady_state_max_abs_error: Option<f64>,
    /// `sqrt(mean(eps^2))` over the steady-state window.
    pub steady_state_rms_error: Option<f64>,
    /// `mean(eps)` over the steady-state window (signed: the bias).
    pub steady_state_mean_error: Option<f64>,
    /// First time after which `|eps|` stays below the tolerance to the end of the run, seconds;
    /// `None` if it stays there for less than the minimum dwell (including not at all at the
    /// end), or the run did not complete.
    pub convergence_time_s: Option<f64>,
    /// Distance travelled, metres (sum of step displacements).
    pub path_length_m: f64,
    /// Control effort `integral(omega^2 dt)` over the integrated steps of the run, rad^2/s: the
    /// sum of `omega_k^2 * dt` over the commands that were held for a step (the command at the
    /// final sample of a run is never integrated and does not count).
    pub control_effort: f64,
    /// Chattering: total variation of `omega` over the steady-state window divided by the
    /// window's duration, rad/s^2.
    pub chattering_radps2: Option<f64>,
    /// Sign changes of `omega` per second over the steady-state window.
    pub sign_changes_per_s: Option<f64>,
    /// Largest distance to the true isoline over the steady-state window, m (`None` when the
    /// field gives no isoline distance).
    pub steady_state_max_isoline_distance_m: Option<f64>,
    /// RMS distance to the true isoline over the steady-state window, m.
    pub steady_state_rms_isoline_distance_m: Option<f64>,
    /// Share of the steady-state window's steps with `|eps| <= convergence tolerance` (how much
    /// of the time a moving isoline was held), in `[0, 1]`.
    pub time_in_band_fraction: Option<f64>,
    /// Times the error left the track-loss band after having been within the tolerance
    /// (`metrics.track_loss_band`, default 5 x the tolerance); re-acquired when back within
    /// the tolerance.
    pub track_losses: u64,
    /// Whether the true error ever reached the level: came within the convergence tolerance
    /// (`|eps| <= tol`) or changed sign (crossed the isoline) at some step of the run. Every
    /// step counts, whatever `output.record_rate_hz` keeps in the trace (`compare` flags the
    /// laws that never did). Not written to `summary.json`.
    #[serde(skip)]
    pub reached_level: bool,
    /// The largest distance from the start position at any step of the run, m. Not written
    /// to `summary.json`.
    #[serde(skip)]
    pub farthest_from_start_m: f64,
}

impl Metrics {
    /// Empty accumulator.
    pub fn new(cfg: MetricsConfig) -> Self {
        Self {
            cfg,
            ss_n: 0,
            ss_max_abs: 0.0,
            ss_sum: 0.0,
            ss_sum_sq: 0.0,
            ss_tv_omega: 0.0,
            ss_sign_changes: 0,
            ss_prev_omega: None,
            ss_prev_sign: 0.0,
            last_violation: None,
            last_step: 0,
            path_length_m: 0.0,
            effort: 0.0,
            iso_n: 0,
            iso_max: 0.0,
            iso_sum_sq: 0.0,
            ss_in_band: 0,
            tracking: false,
            track_losses: 0,
            reached: false,
            first_above: None,
            far_sq: 0.0,
        }
    }

    /// Observes step `k`: the true error `eps_k` and the command `omega_k` held over the step.
    #[inline]
    pub fn observe(&mut self, k: u64, eps: f64, omega: f64) {
        self.last_step = k;
        let a = eps.abs();
        let within = a < self.cfg.convergence_tolerance;
        if !within {
            self.last_violation = Some(k);
        }
        // A NaN error (no value) counts as outside the band.
        if self.tracking && (a > self.cfg.track_loss_band || a.is_nan()) {
            self.tracking = false;
            self.track_losses += 1;
        } else if !self.tracking && within {
            self.tracking = true;
        }
        if !self.reached && eps.is_finite() {
            let above = eps > 0.0;
            self.reached = a <= self.cfg.convergence_tolerance
                || *self.first_above.get_or_insert(above) != above;
        }
        if k >= self.cfg.steady_state_start_step {
            self.ss_n += 1;
            self.ss_in_band += u64::from(a <= self.cfg.convergence_tolerance);
            self.ss_max_abs = self.ss_max_abs.max(eps.abs());
            self.ss_sum += eps;
            self.ss_sum_sq += eps * eps;
            if let Some(prev) = self.ss_prev_omega {
                self.ss_tv_omega += (omega - prev).abs();
            }
            self.ss_prev_omega = Some(omega);
            let sign = if omega > 0.0 {
                1.0
            } else if omega < 0.0 {
                -1.0
            } else {
                0.0
            };
            if sign != 0.0 {
                if self.ss_prev_sign != 0.0 && sign != self.ss_prev_sign {
                    self.ss_sign_changes += 1;
                }
                self.ss_prev_sign = sign;
            }
        }
    }

    /// Whether step `k` is in the steady-state window.
    #[inline]
    pub fn in_window(&self, k: u64) -> bool {
        k >= self.cfg.steady_state_start_step
    }

    /// Observes the distance to the true isoline at a step of the steady-state window.
    #[inline]
    pub fn observe_isoline_distance(&mut self, d_m: f64) {
        self.iso_n += 1;
        self.iso_max = self.iso_max.max(d_m);
        self.iso_sum_sq += d_m * d_m;
    }

    /// Adds the command `omega` held over one integrated step to the control effort.
    #[inline]
    pub fn integrate_command(&mut self, omega: f64) {
        self.effort += omega * omega * self.cfg.dt_s;
    }

    /// Adds a step's displacement to the path length.
    #[inline]
    pub fn add_path(&mut self, ds_m: f64) {
        self.path_length_m += ds_m;
    }

    /// Observes the squared distance of a step's position from the start, m^2.
    #[inline]
    pub fn observe_offset_sq(&mut self, d_sq_m2: f64) {
        self.far_sq = self.far_sq.max(d_sq_m2);
    }

    /// The metrics; `completed` says whether the run reached its planned end.
    pub fn finish(&self, completed: bool) -> RunMetrics {
        let n = self.ss_n as f64;
        let have_ss = self.ss_n > 0;
        let window_s = (self.ss_n.saturating_sub(1)) as f64 * self.cfg.dt_s;
        let per_s = |x: f64| (have_ss && window_s > 0.0).then(|| x / window_s);
        RunMetrics {
            steady_state_max_abs_error: have_ss.then_some(self.ss_max_abs),
            steady_state_rms_error: have_ss.then(|| (self.ss_sum_sq / n).sqrt()),
            steady_state_mean_error: have_ss.then(|| self.ss_sum / n),
            convergence_time_s: if !completed {
                None
            } else {
                let dwell = self.cfg.convergence_min_dwell_steps;
                match self.last_violation {
                    None => (self.last_step >= dwell).then_some(0.0),
                    Some(k) if k == self.last_step => None,
                    // Inside from step k + 1 to the last step: last_step - k - 1 steps.
                    Some(k) => (self.last_step - k > dwell).then(|| (k + 1) as f64 * self.cfg.dt_s),
                }
            },
            path_length_m: self.path_length_m,
            control_effort: self.effort,
            chattering_radps2: per_s(self.ss_tv_omega),
            sign_changes_per_s: per_s(self.ss_sign_changes as f64),
            steady_state_max_isoline_distance_m: (self.iso_n > 0).then_some(self.iso_max),
            steady_state_rms_isoline_distance_m: (self.iso_n > 0)
                .then(|| (self.iso_sum_sq / self.iso_n as f64).sqrt()),
            time_in_band_fraction: have_ss.then(|| self.ss_in_band as f64 / n),
            track_losses: self.track_losses,
            reached_level: self.reached,
            farthest_from_start_m: self.far_sq.sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn window_statistics_and_convergence() {
        let mut m = Metrics::new(MetricsConfig {
            dt_s: 0.5,
            steady_state_start_step: 6,
            convergence_tolerance: 0.1,
            convergence_min_dwell_steps: 0,
            track_loss_band: 0.5,
        });
        // eps: 1, 0.5, 0.2, 0.05, 0.3, 0.05, 0.02, -0.04, 0.06, -0.02 (10 steps)
        let eps = [1.0, 0.5, 0.2, 0.05, 0.3, 0.05, 0.02, -0.04, 0.06, -0.02];
        let om = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0, 1.0, -1.0];
        for k in 0..10 {
            m.observe(k as u64, eps[k], om[k]);
            if k < 9 {
                m.integrate_command(om[k]);
            }
        }
        let r = m.finish(true);
        // last violation at k = 4 -> converged from k = 5, t = 2.5 s
        assert_eq!(r.convergence_time_s, Some(2.5));
        assert_relative_eq!(r.steady_state_max_abs_error.unwrap(), 0.06);
        assert_relative_eq!(
            r.steady_state_mean_error.unwrap(),
            (0.02 - 0.04 + 0.06 - 0.02) / 4.0
        );
        let rms =
            ((0.02f64.powi(2) + 0.04f64.powi(2) + 0.06f64.powi(2) + 0.02f64.powi(2)) / 4.0).sqrt();
        assert_relative_eq!(r.steady_state_rms_error.unwrap(), rms);
        // window 3 intervals of 0.5 s = 1.5 s; TV = 2+2+2 = 6; 3 sign changes
        assert_relative_eq!(r.chattering_radps2.unwrap(), 4.0);
        assert_relative_eq!(r.sign_changes_per_s.unwrap(), 2.0);
        // effort: the commands of steps 6, 7, 8 are integrated (step 9 is the last sample),
        // each omega^2 = 1 times dt 0.5
        assert_relative_eq!(r.control_effort, 1.5);
    }

    #[test]
    fn never_converged_and_early_end() {
        let mut m = Metrics::new(MetricsConfig {
            dt_s: 1.0,
            steady_state_start_step: 100,
            convergence_tolerance: 0.1,
            convergence_min_dwell_steps: 0,
            track_loss_band: 0.5,
        });
        m.observe(0, 0.0, 0.0);
        m.observe(1, 5.0, 0.0);
        let r = m.finish(true);
        assert_eq!(r.convergence_time_s, None);
        assert_eq!(r.steady_state_max_abs_error, None);
        assert_eq!(r.chattering_radps2, None);
        assert_eq!(m.finish(false).convergence_time_s, None);
    }

    /// In-band share and track losses by hand: tolerance 0.1, band 0.5.
    #[test]
    fn band_share_and_track_losses() {
        let mut m = Metrics::new(MetricsConfig {
            dt_s: 1.0,
            steady_state_start_step: 4,
            convergence_tolerance: 0.1,
            convergence_min_dwell_steps: 0,
            track_loss_band: 0.5,
        });
        // Not tracked yet at 1.0 (no loss); acquired at 0.05; 0.3 stays in the band; 0.8 is a
        // loss; 0.2 is not a re-acquisition; 0.0 is; 0.9 is a second loss.
        let eps = [1.0, 0.05, 0.3, 0.8, 0.2, 0.0, 0.9, 0.05];
        for (k, e) in eps.iter().enumerate() {
            m.observe(k as u64, *e, 0.0);
        }
        let r = m.finish(true);
        assert_eq!(r.track_losses, 2);
        // Window steps 4..=7: 0.2, 0.0, 0.9, 0.05 -> 2 of 4 within 0.1.
        assert_eq!(r.time_in_band_fraction, Some(0.5));
    }

    #[test]
    fn convergence_needs_the_minimum_dwell() {
        // Inside the band from step 5 on, the run ends at step 9: 4 steps inside (5..9).
        let run = |dwell: u64| {
            let mut m = Metrics::new(MetricsConfig {
                dt_s: 1.0,
                steady_state_start_step: 0,
                convergence_tolerance: 0.1,
                convergence_min_dwell_steps: dwell,
                track_loss_band: 0.5,
            });
            for k in 0..10u64 {
                m.observe(k, if k < 5 { 1.0 } else { 0.0 }, 0.0);
            }
            m.finish(true).convergence_time_s
        };
        assert_eq!(run(4), Some(5.0));
        assert_eq!(run(5), None, "a short visit at the end is not convergence");
    }
}
