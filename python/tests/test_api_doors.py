"""Issue 30, the last open doors of the Python API: a float given for an integer key echoed as
written, `plot` and `report` answering Ctrl-C without leaving a half-written file, and the
sweep-row re-run shown able to fail."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


# --- lossy numbers across the boundary (ROBUSTNESS.md class 9) --------------------------------


def test_a_float_for_an_integer_key_is_echoed_as_written_with_the_range():
    """`Scenario.set("sim.seed", 2.0**64)` once said `floating point `18446744073709552000.0``:
    digits the user never wrote (serde's rendering), and no word of the integers allowed."""
    sc = isotrack.Scenario.default()
    with pytest.raises(isotrack.ScenarioError) as e:
        sc.set("sim.seed", 2.0**64)
    msg = str(e.value)
    assert "18446744073709552000" not in msg, msg
    assert repr(2.0**64) in msg, msg  # 1.8446744073709552e+19, as Python shows it
    assert "0 ..= 9223372036854775807" in msg, msg
    assert "sim.seed" in msg, msg
    with pytest.raises(isotrack.ScenarioError) as e:
        sc.set("sim.seed", np.float64(5.0))
    assert repr(np.float64(5.0)) + " is a float" in str(e.value), str(e.value)
    assert "written without a decimal point" in str(e.value)
    # An integer beyond TOML's: echoed exactly, with the range.
    with pytest.raises(isotrack.ScenarioError) as e:
        sc.set("sim.seed", 2**64)
    assert "18446744073709551616" in str(e.value) and "2**63-1" in str(e.value)
    # Floats where floats belong are untouched.
    assert "kp = 2.5" in sc.set("controller.kp", 2.5).to_toml()


# --- the re-run of a sweep row can fail (issue 30 "Done when") -------------------------------


def test_a_rounded_seed_is_another_run(tmp_path):
    """`test_api.py::test_every_row_of_a_random_sweep_reruns_exactly` re-runs every row of a
    random puff-plume sweep from its columns. That test could not catch seeds rounded through
    float64 if the seeds were small or the plume ignored them: here a row's seed is above 2**53
    and the same row flown with the seed rounded as float64 rounds it gives other metrics."""
    sw = tmp_path / "s.toml"
    sw.write_text(
        f'scenario = "{ROOT}/scenarios/puff-plume-edge.toml"\n'
        "[base]\nsim.duration_s = 20.0\n"
        "[random]\nruns = 4\nseed = 5\n"
        "initial.x_m = { uniform = [8.0, 12.0] }\n"
    )
    cols = isotrack.sweep(str(sw))
    big = [i for i, s in enumerate(cols["sim.seed"]) if int(s) > 2**53 and int(float(s)) != int(s)]
    assert big, list(cols["sim.seed"])
    i = big[0]
    base = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "puff-plume-edge.toml")).set(
        "sim.duration_s", 20.0
    ).set("initial.x_m", cols["initial.x_m"][i].item())
    exact = base.set("sim.seed", cols["sim.seed"][i].item()).run(record_rate_hz=0.0).summary
    rounded = base.set("sim.seed", int(float(cols["sim.seed"][i]))).run(record_rate_hz=0.0).summary
    m = "steady_state_rms_error"
    assert exact[m] == cols[m][i].item()
    assert rounded[m] != exact[m]


# --- Ctrl-C in plot and report (ROBUSTNESS.md class 4) ----------------------------------------

CHILD = textwrap.dedent(
    """
    import os, sys, time
    import isotrack
    what, run_dir, out = sys.argv[1:4]
    print("ready", flush=True)
    t0 = time.monotonic()
    try:
        if what == "plot":
            isotrack.plot([run_dir], out=out, animate=True)
        else:
            isotrack.report([run_dir] * 100, out)
        print("finished", time.monotonic() - t0, flush=True)
    except KeyboardInterrupt:
        print("interrupted", time.monotonic() - t0, flush=True)
    # The abandoned render goes on in its thread; its staging directory goes when it ends.
    d = out if what == "plot" else os.path.dirname(out)
    end = time.monotonic() + 300
    while time.monotonic() < end and any(n.startswith(".isotrack-partial") for n in os.listdir(d)):
        time.sleep(0.05)
    print("left", sorted(os.listdir(d)), flush=True)
    """
)


@pytest.fixture(scope="module")
def heavy_run(tmp_path_factory):
    """A puff-plume run long enough that its figures and report take seconds to draw."""
    d = tmp_path_factory.mktemp("heavy") / "run"
    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "puff-plume-edge.toml"))
    sc.set("sim.duration_s", 600.0).run(record_rate_hz=100.0).save(str(d))
    return d


@pytest.mark.parametrize("what", ["plot", "report"])
def test_ctrl_c_stops_plot_and_report_leaving_no_half_written_file(tmp_path, heavy_run, what):
    out = tmp_path / "fig" if what == "plot" else tmp_path / "page" / "report.html"
    p = subprocess.Popen(
        [sys.executable, "-c", CHILD, what, str(heavy_run), str(out)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(0.5)
        t_sig = time.monotonic()
        p.send_signal(signal.SIGINT)
        line = p.stdout.readline().split()
        answered = time.monotonic() - t_sig
        assert line[0] == "interrupted", line
        assert answered < 2.0, answered
        left = p.stdout.readline()
        assert p.wait(timeout=300) == 0
    finally:
        p.kill()
    assert left.startswith("left"), left
    # Nothing under the names asked for, and no staging directory left behind.
    assert left.strip() == "left []", left
