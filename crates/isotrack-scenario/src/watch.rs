//! Runs that a caller can stop: a library front end (the Python package) asks at every sample
//! whether to go on, so that Ctrl-C stops a long run within a sample period instead of at its
//! end.

use crate::Scenario;
use isotrack_core::control::GroundTruth;
use isotrack_core::{IsolineController, Measurement};
use isotrack_sim::{RunResult, TraceSink};

/// A controller that asks `keep_going` before each of its samples. Once it answers `false` the
/// command is NaN, the loop's own way of ending a run (as `diverged`), and the run is reported
/// as stopped. Until then every call is forwarded: the run is the controller's own, bit for bit.
struct Watched<'a, C: ?Sized> {
    inner: &'a mut C,
    keep_going: &'a mut dyn FnMut() -> bool,
    stopped: bool,
}

impl<C: IsolineController + ?Sized> Watched<'_, C> {
    fn go_on(&mut self) -> bool {
        if !self.stopped && !(self.keep_going)() {
            self.stopped = true;
        }
        !self.stopped
    }
}

impl<C: IsolineController + ?Sized> IsolineController for Watched<'_, C> {
    fn update(&mut self, m: &Measurement) -> f64 {
        if self.go_on() {
            self.inner.update(m)
        } else {
            f64::NAN
        }
    }
    fn reset(&mut self) {
        self.inner.reset();
    }
    fn needs_ground_truth(&self) -> bool {
        self.inner.needs_ground_truth()
    }
    fn update_with_truth(&mut self, m: &Measurement, truth: &GroundTruth) -> f64 {
        if self.go_on() {
            self.inner.update_with_truth(m, truth)
        } else {
            f64::NAN
        }
    }
}

impl Scenario {
    /// [`Scenario::run`], asking `keep_going()` before each sensor sample: `None` when it
    /// answered `false` (the run stopped there), else the run's result, equal bit for bit to
    /// [`Scenario::run`]'s.
    pub fn run_watched<S: TraceSink + ?Sized>(
        &self,
        sink: &mut S,
        keep_going: &mut dyn FnMut() -> bool,
    ) -> Option<RunResult> {
        let mut controller = self.tracker();
        self.run_with_watched(&mut controller, sink, keep_going)
    }

    /// [`Scenario::run_with`] another controller, asking `keep_going()` before each sample as
    /// [`Scenario::run_watched`] does.
    pub fn run_with_watched<C: IsolineController + ?Sized, S: TraceSink + ?Sized>(
        &self,
        controller: &mut C,
        sink: &mut S,
        keep_going: &mut dyn FnMut() -> bool,
    ) -> Option<RunResult> {
        let mut watched = Watched {
            inner: controller,
            keep_going,
            stopped: false,
        };
        let r = self.run_with(&mut watched, sink);
        (!watched.stopped).then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isotrack_sim::NoTrace;

    #[test]
    fn a_watched_run_is_the_run_and_stops_when_asked() {
        let s = Scenario::default_paper_fig2b()
            .derive(&["sim.duration_s=20.0".into()], "test")
            .unwrap();
        let want = s.run(&mut NoTrace);
        let mut asked = 0u64;
        let got = s.run_watched(&mut NoTrace, &mut || {
            asked += 1;
            true
        });
        assert_eq!(got, Some(want.clone()));
        // 20 s at the default 100 Hz sensor: asked once per sample.
        assert_eq!(asked, want.samples);
        let mut left = 10;
        let stopped = s.run_watched(&mut NoTrace, &mut || {
            left -= 1;
            left > 0
        });
        assert_eq!(stopped, None);
        assert_eq!(left, 0, "not asked again once stopped");
    }
}
