"""The Python peers of BENCHMARKS.md compute the same run as isotrack: the speed comparison is
between equal computations. The plain-Python loop (`benches/python/dubins_peer.py`) and the
numpy batch (`benches/python/dubins_numpy_batch.py`, the same model as the numba peer) against
isotrack's default scenario, at several durations and starts."""

import importlib.util
import math
from pathlib import Path

import numpy as np

import isotrack

PEERS = Path(__file__).resolve().parents[2] / "benches" / "python"


def peer(name):
    spec = importlib.util.spec_from_file_location(name, PEERS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_plain_python_peer_ends_at_isotracks_error():
    """Final error of the pure-Python loop and of isotrack, from (10, 0, -pi/2): equal to
    rounding while the error is still large (5 s, 30 s) and both at the isoline after 600 s."""
    run = peer("dubins_peer").run
    for duration in (5.0, 30.0, 600.0):
        _, eps_peer = run(duration_s=duration)
        r = isotrack.Scenario.default().set("sim.duration_s", duration).run()
        eps = r.trace["error"][-1]
        assert abs(eps - eps_peer) <= 1e-9 * max(abs(eps), 1e-5), (duration, eps, eps_peer)
    assert abs(eps_peer) < 1e-12 and abs(eps) < 1e-12


def test_numpy_batch_peer_gives_isotracks_steady_error_per_start():
    """The numpy peer's per-run max |eps| over the last 20 % (its metric) equals isotrack's
    steady_state_max_abs_error for the same starts (30 s runs: the error still transient)."""
    sweep = peer("dubins_numpy_batch").sweep
    starts = [(10.0, 0.0, -math.pi / 2), (-12.0, 5.0, 0.3), (4.0, -14.0, 2.0)]
    xs, ys, ths = (np.array(c) for c in zip(*starts))
    worst = sweep(xs, ys, ths, 3000)
    for (x, y, th), w in zip(starts, worst):
        sc = (
            isotrack.Scenario.default()
            .set("sim.duration_s", 30.0)
            .set("initial.x_m", x)
            .set("initial.y_m", y)
            .set("initial.heading_rad", th)
        )
        got = sc.run().summary["steady_state_max_abs_error"]
        assert w > 1e-6, "a transient, not rounding"
        assert abs(got - w) <= 1e-9 * w, ((x, y, th), got, w)
