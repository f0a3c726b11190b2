"""One install, whole toolkit (issue 30, item 6): the `isotrack` command from the package, run
directories written from Python that the command's `plot` and `report` take, `compare`, and a
sweep flown by a Python controller."""

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


def cli() -> str:
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe} (build with cargo build --release)")
    return exe


def packaged(*args, **kw):
    """The package's `isotrack` command (its console entry), as pip installs it."""
    return subprocess.run(
        [sys.executable, "-c", "from isotrack._cli import main; main()", *args], **kw
    )


def test_the_packaged_command_is_the_binary():
    """Same stdout and exit codes as the Rust binary, for output, usage errors and bad input."""
    for args in (["check", "--json"], ["show", "--set", "controller.kp=20"], ["--version"]):
        want = subprocess.run([cli(), *args], capture_output=True, text=True)
        got = packaged(*args, capture_output=True, text=True)
        assert (got.returncode, got.stdout) == (want.returncode, want.stdout), args
    for args, code in ((["run", "--nope"], 64), (["run", "--set", "controller.kp=-1"], 65), (["run", "no.toml"], 66)):
        got = packaged(*args, capture_output=True, text=True)
        assert got.returncode == code, (args, got.stderr)
        assert "error" in got.stderr
    script = Path(sys.executable).parent / "isotrack"
    if script.exists():  # installed by pip / maturin as a console script
        r = subprocess.run([str(script), "--version"], capture_output=True, text=True)
        assert r.returncode == 0 and r.stdout.strip().endswith(isotrack.__version__)


def test_the_packaged_command_stops_on_ctrl_c(tmp_path):
    p = subprocess.Popen(
        [sys.executable, "-c", "from isotrack._cli import main; main()", "run", "--set", "sim.duration_s=1e7",
         "--set", "output.record_rate_hz=0", "-q"],
    )
    time.sleep(1.0)
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    rc = p.wait(timeout=10)
    assert time.monotonic() - t0 < 2.0
    assert rc == -signal.SIGINT


def test_run_save_writes_what_isotrack_run_writes(tmp_path):
    """Run.save of the default run: trace.csv, summary.json and scenario.toml equal, byte for
    byte, the files `isotrack run --out` writes for the same scenario."""
    subprocess.run([cli(), "run", "--out", str(tmp_path / "cli"), "-q"], check=True)
    run = isotrack.Scenario.default().run()
    assert run.save(tmp_path / "py") == str(tmp_path / "py")
    for f in ("trace.csv", "summary.json", "scenario.toml"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f


def test_a_saved_fixed_wing_run_keeps_its_telemetry(tmp_path):
    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "paper-fig3-uav.toml")).set("sim.duration_s", 5.0)
    out = tmp_path / "uav"
    subprocess.run(
        [cli(), "run", str(ROOT / "scenarios" / "paper-fig3-uav.toml"), "--set", "sim.duration_s=5.0", "--out", str(out), "-q"],
        check=True,
    )
    sc.run().save(tmp_path / "py")
    assert (tmp_path / "py" / "trace.csv").read_bytes() == (out / "trace.csv").read_bytes()


def test_plot_and_report_take_runs_and_directories(tmp_path):
    a = isotrack.Scenario.default().set("sim.duration_s", 60.0).run()
    b = isotrack.Scenario.default().set("sim.duration_s", 60.0).set("controller.kp", 5.0).run()
    d = a.save(tmp_path / "a")
    # The command takes the saved directory.
    subprocess.run([cli(), "plot", d, "--out", str(tmp_path / "cmd")], check=True, capture_output=True)
    assert (tmp_path / "cmd" / "trajectory.png").stat().st_size > 10_000
    # The Python functions take directories and Run objects.
    assert isotrack.plot(d) == d
    assert (Path(d) / "trajectory.png").stat().st_size > 10_000
    assert (Path(d) / "timeseries.png").stat().st_size > 10_000
    out = isotrack.plot([a, b], out=tmp_path / "both", format="svg")
    assert (Path(out) / "trajectory.svg").read_text().startswith("<svg")
    page = isotrack.report([d, b], tmp_path / "r.html")
    html = Path(page).read_text()
    assert html.startswith("<!DOCTYPE html>") or html.lower().startswith("<!doctype html>")
    assert len(html) > 10_000
    with pytest.raises(FileNotFoundError):
        isotrack.report([tmp_path / "nope"], tmp_path / "x.html")
    with pytest.raises(ValueError, match="format"):
        isotrack.plot(d, format="jpg")


def test_compare_flies_each_law_as_the_command_does(tmp_path):
    """compare(): the runs `isotrack compare --out` makes, metric for metric."""
    sc_file = ROOT / "scenarios" / "paper-fig2b-circular.toml"
    laws = ["pi_isoline", "sliding_mode", "pid"]
    subprocess.run(
        [cli(), "compare", str(sc_file), "--controllers", ",".join(laws), "--set", "sim.duration_s=60.0",
         "--gain", "sliding_mode.gamma=0.3", "--out", str(tmp_path / "cli")],
        check=True, capture_output=True,
    )
    import json

    runs = isotrack.compare(
        isotrack.Scenario.from_file(str(sc_file)).set("sim.duration_s", 60.0),
        controllers=laws,
        gains=["sliding_mode.gamma=0.3"],
        out=tmp_path / "py",
    )
    assert list(runs) == laws
    for law in laws:
        want = json.loads((tmp_path / "cli" / law / "summary.json").read_text())
        got = runs[law].summary
        for k in want:
            if k != "scenario_path":
                assert got[k] == want[k], (law, k)
        assert (tmp_path / "py" / law / "trace.csv").read_bytes() == (tmp_path / "cli" / law / "trace.csv").read_bytes()
    assert list(isotrack.compare(isotrack.Scenario.default().set("sim.duration_s", 1.0))) == [
        "pi_isoline", "sliding_mode", "sliding_mode_smooth", "suboptimal_sosm", "pid", "pid_crossing",
        "gradient_reference",
    ]
    with pytest.raises(ValueError, match="unknown controller"):
        isotrack.compare(isotrack.Scenario.default(), controllers=["nope"])
    with pytest.raises(ValueError, match="KIND.KEY=VALUE"):
        isotrack.compare(isotrack.Scenario.default(), gains=["gamma=0.3"])


def test_a_sweep_flown_by_a_python_p_law_gives_the_closed_form_offsets(tmp_path):
    """A sweep over kp with a Python P law (ki = 0): each row's steady mean error is the
    closed-form offset c2*atanh(v/(kp*c1*d*)) of docs/BASELINES.md section 0, within 1 %;
    the factory sees each run's own scenario."""
    c1, c2, v, level = 0.2, 1.0, 0.5, 10.0
    seen = []

    class PLaw:
        def __init__(self, kp):
            self.kp = kp

        def reset(self):
            self.prev = None

        def update(self, t_s, value):
            eps = value - level
            d = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
            self.prev = (t_s, eps)
            return self.kp * (d + c1 * math.tanh(eps / c2))

    def factory(sc):
        kp = float(sc.to_toml().split("kp = ")[1].split("\n")[0])
        seen.append(kp)
        return PLaw(kp)

    sw = tmp_path / "s.toml"
    sw.write_text(
        f'scenario = "{ROOT}/scenarios/paper-fig2b-circular.toml"\n'
        "[base]\nsensor.rate_hz = 10.0\n[grid]\ncontroller.kp = [10.0, 20.0]\n"
    )
    cols = isotrack.sweep(str(sw), controller_factory=factory)
    assert seen == [10.0, 20.0]
    assert list(cols["outcome"]) == ["completed", "completed"]

    def offset(kp):
        def g(d):
            return c1 * math.tanh((20 * math.exp(-0.1 * d) - level) / c2) + v / (kp * d)

        lo, hi = math.log(2.0) / 0.1, 60.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if g(mid) > 0 else (lo, mid)
        return 20 * math.exp(-0.1 * lo) - level

    for i, kp in enumerate([10.0, 20.0]):
        want = offset(kp)
        assert abs(cols["steady_state_mean_error"][i] - want) < 0.01 * abs(want), (kp, want)

    class Broken:
        def update(self, t_s, value):
            raise ZeroDivisionError("inside my law")

    with pytest.raises(ZeroDivisionError, match="inside my law"):
        isotrack.sweep(str(sw), controller_factory=lambda sc: Broken())
