"""The Python package against the CLI and against closed forms (issue 12, first part)."""

import csv
import json
import math
import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


def cli() -> str:
    """The isotrack binary: $ISOTRACK_BIN, or the workspace's release build."""
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe} (build with cargo build --release)")
    return exe


def test_default_run_equals_the_cli():
    """The default run's summary and trace equal the CLI's summary.json and trace.csv: numbers
    equal, not close (the trace at the CLI's default 10 Hz)."""
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([cli(), "run", "--out", d, "-q"], check=True)
        want = json.loads(Path(d, "summary.json").read_text())
        with open(Path(d, "trace.csv")) as f:
            rows = list(csv.DictReader(f))
    run = isotrack.Scenario.default().run()
    got = run.summary
    assert set(got) == set(want)
    for k in want:
        if k in ("scenario_path",):
            continue
        assert got[k] == want[k], k
    assert len(run.trace["t_s"]) == len(rows)
    for col in ("t_s", "x_m", "y_m", "heading_rad", "s", "error", "omega_radps"):
        assert np.array_equal(run.trace[col], np.array([float(r[col]) for r in rows])), col


def test_a_python_p_law_reproduces_the_closed_form():
    """The paper's law with ki = 0, written in Python (backward difference of the samples),
    settles on the circular field's orbit with |eps*| = c2*atanh(v/(kp*c1*d*)) (docs/BASELINES.md
    section 0), d* from F(d*) - s_d = eps*: within 1 %."""
    kp, c1, c2, v, level = 10.0, 0.2, 1.0, 0.5, 10.0

    class PLaw:
        def reset(self):
            self.prev = None

        def update(self, t_s, value):
            eps = value - level
            d = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
            self.prev = (t_s, eps)
            return kp * (d + c1 * math.tanh(eps / c2))

    sc = isotrack.Scenario.default().set("sensor.rate_hz", 10.0)
    run = sc.run(controller=PLaw())
    assert run.summary["outcome"] == "completed"
    got = run.summary["steady_state_mean_error"]

    # Closed form: g(d) = c1*tanh((F(d) - s_d)/c2) + v/(kp*d) = 0 outside r_d, F = 20 exp(-0.1 d).
    def g(d):
        return c1 * math.tanh((20 * math.exp(-0.1 * d) - level) / c2) + v / (kp * d)

    lo, hi = math.log(2.0) / 0.1, 60.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) > 0 else (lo, mid)
    eps = 20 * math.exp(-0.1 * lo) - level
    assert abs(eps - (-c2 * math.atanh(v / (kp * c1 * lo)))) < 1e-9
    assert abs(got - eps) < 0.01 * abs(eps), (got, eps)


def test_scenario_errors_carry_line_and_column():
    with pytest.raises(isotrack.ScenarioError) as e:
        isotrack.Scenario.from_toml("[controller]\nkp = -1\n")
    assert "<toml>:2:6: `controller.kp`: must be > 0, got -1" in str(e.value)
    with pytest.raises(isotrack.ScenarioError) as e:
        isotrack.Scenario.default().set("controller.kpp", 1.0)
    assert "unknown field `kpp`" in str(e.value)


def test_check_equals_the_cli_json():
    out = subprocess.run([cli(), "check", "--json"], check=True, capture_output=True, text=True)
    assert isotrack.check(isotrack.Scenario.default()) == json.loads(out.stdout)


def test_a_controller_that_raises_gives_its_traceback():
    class Broken:
        def update(self, t_s, value):
            if t_s > 1.0:
                raise RuntimeError("my law broke")
            return 0.0

    with pytest.raises(RuntimeError, match="my law broke") as e:
        isotrack.Scenario.default().run(controller=Broken())
    assert "update" in "".join(e.traceback[-1].source.lines) or e.traceback


def test_field_values_are_vectorised_with_nan_off_the_field():
    sc = isotrack.Scenario.default().set("field.domain_m", [-10.0, 10.0, -10.0, 10.0])
    x, y = np.meshgrid(np.array([0.0, 5.0, 50.0]), np.array([0.0, 1.0]))
    v = sc.field_values(x, y)
    assert v.shape == (2, 3)
    assert v[0, 0] == 20.0
    assert abs(v[0, 1] - 20 * math.exp(-0.5)) < 1e-12
    assert math.isnan(v[0, 2])


def test_set_and_to_toml_round_trip():
    sc = isotrack.Scenario.default().set("controller.kind", "sliding_mode")
    again = isotrack.Scenario.from_toml(sc.to_toml())
    assert again.run().summary == sc.run().summary


def test_sweep_equals_results_csv():
    """``isotrack.sweep`` gives the cells of the CLI's results.csv, column by column."""
    with tempfile.TemporaryDirectory() as d:
        Path(d, "sc.toml").write_text("sim.duration_s = 10.0\n")
        sw = Path(d, "s.toml")
        sw.write_text(
            'scenario = "sc.toml"\n[grid]\ncontroller.kind = ["pi_isoline", "sliding_mode"]\n'
            "controller.kp = [5.0, 10.0, -1.0]\n[random]\nruns = 2\ninitial.x_m = { uniform = [5.0, 12.0] }\n"
        )
        out = Path(d, "out")
        subprocess.run([cli(), "sweep", str(sw), "--out", str(out)], capture_output=True)
        with open(out / "results.csv") as f:
            rows = list(csv.DictReader(f))
        got = isotrack.sweep(str(sw), threads=2)
        # One thread, with the progress bar: the same cells (deterministic on any thread count).
        again = isotrack.sweep(str(sw), threads=1, progress=True)
    assert all(np.array_equal(got[c], again[c], equal_nan=True) if got[c].dtype == np.float64 else list(got[c]) == list(again[c]) for c in got)
    assert list(got) == list(rows[0].keys())
    assert len(got["run_id"]) == len(rows) == 12
    for col in got:
        want = [r[col] for r in rows]
        if got[col].dtype == np.float64:
            exp = np.array([float(c) if c != "" else np.nan for c in want])
            assert np.array_equal(got[col], exp, equal_nan=True), col
        elif got[col].dtype == np.int64:
            # Integers exactly; a masked cell is an empty one (`samples` of an invalid run).
            cells = np.ma.getmaskarray(got[col])
            assert [("" if m else str(v)) for v, m in zip(got[col].data, cells)] == want, col
        else:
            assert list(got[col]) == want, col
    assert "invalid_scenario" in list(got["outcome"])
