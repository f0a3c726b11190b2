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


# --- tables through Scenario.set and sweep (att30d-6, att32d-16) -----------------------------


def cli_exe():
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not os.path.exists(exe):
        pytest.skip("the isotrack binary is not built (cargo build --release -p isotrack-cli)")
    return exe


def settings(toml_text):
    """The lines that set something (`show` adds comments on defaults and derived values)."""
    lines = (line.split("  # ")[0].rstrip() for line in toml_text.splitlines())
    return [line for line in lines if line and not line.startswith("#")]


def test_set_takes_a_dict_merged_key_by_key_as_the_cli_set_does():
    """att30d-6, att32d-16: `--set 'controller={kp = 2.0}'` and `--set 'team.vehicles=[{index =
    1, speed_mps = 0.4}]'` worked, while Scenario.set refused a dict ("cannot use {...} as a
    scenario value"): per-vehicle overrides could only be given as TOML text. A dict is now a
    table, merged key by key as --set merges it: the resolved scenario is the one `isotrack
    show --set` prints, text for text."""
    fig2b = ROOT / "scenarios" / "paper-fig2b-circular.toml"
    team = ROOT / "scenarios" / "team-circular-4.toml"
    exe = cli_exe()
    cases = [
        (fig2b, "controller", {"kp": 2.0, "ki": 3.0}, "controller={kp = 2.0, ki = 3.0}"),
        (team, "team.vehicles", [{"index": 1, "speed_mps": 0.4}], "team.vehicles=[{index = 1, speed_mps = 0.4}]"),
        (team, "team.ranging", {"noise_std_m": 0.3}, "team.ranging={noise_std_m = 0.3}"),
        (team, "team", {"ranging": {"noise_std_m": 0.3}, "k_v": 0.2}, "team={ranging = {noise_std_m = 0.3}, k_v = 0.2}"),
        (team, "team", {"ranging.noise_std_m": 0.3}, "team={ranging.noise_std_m = 0.3}"),
    ]
    for path, key, value, arg in cases:
        sc = isotrack.Scenario.from_file(str(path))
        got = sc.set(key, value).to_toml()
        shown = subprocess.run([exe, "show", str(path), "--set", arg], check=True, capture_output=True, text=True)
        assert settings(got) == settings(shown.stdout), arg
        assert got != sc.to_toml(), arg
    # Merged: the file's other controller keys (c1 = 0.2, c2 = 1.0) are kept, as the dotted keys do.
    sc = isotrack.Scenario.from_file(str(fig2b))
    assert sc.set("controller", {"kp": 2.0, "ki": 3.0}) == sc.set("controller.kp", 2.0).set("controller.ki", 3.0)
    # Through set(dict) of several keys too.
    assert sc.set({"controller": {"kp": 2.0}, "sim.duration_s": 5.0}) == sc.set("controller.kp", 2.0).set(
        "sim.duration_s", 5.0
    )
    # A per-vehicle override's own checks answer as from TOML (index past the team).
    t = isotrack.Scenario.from_file(str(team))
    with pytest.raises(isotrack.ScenarioError, match="team.vehicles"):
        t.set("team.vehicles", [{"index": 9, "speed_mps": 0.4}])
    # Keys that are not keys, and a dict holding itself, are refused, never read as TOML.
    with pytest.raises(isotrack.ScenarioError, match="dict's keys"):
        sc.set("controller", {1: 2.0})
    with pytest.raises(isotrack.ScenarioError, match="not a dotted key"):
        sc.set("controller", {"kp = 1.0, ki": 2.0})
    loop = {}
    loop["a"] = loop
    with pytest.raises(isotrack.ScenarioError, match="nested more than"):
        sc.set("controller", loop)
    with pytest.raises(isotrack.ScenarioError, match="not a finite number"):
        sc.set("controller", {"kp": float("nan")})


def test_a_sweep_of_tables_returns_them_as_dicts_and_each_row_reruns(tmp_path):
    """att30d-6: a [grid] table (`controller = [{kp = 2.0, ki = 1.0}, {ki = 3.0, c1 = 0.5}]`)
    came back as the string "{ ki = 1.0, kp = 2.0 }", which Scenario.set refused, so the
    README's re-run of a row could not be done from Python. The cell is now the dict; set on the
    base (with the row's seed), it gives the row's metrics again, bit for bit. A key of arrays of
    tables (`team.vehicles`) comes back split into `team.vehicles[0]`, a dict each, and re-runs
    as the list of them."""
    fig2b = ROOT / "scenarios" / "paper-fig2b-circular.toml"
    sw = tmp_path / "s.toml"
    sw.write_text(
        f'scenario = "{fig2b}"\n[base]\nsim.duration_s = 5.0\nsensor.noise_std = 0.01\n'
        "[grid]\ncontroller = [{kp = 2.0, ki = 1.0}, {ki = 3.0, c1 = 0.5}]\n"
        "[random]\nruns = 2\nseed = 3\n"
    )
    cols = isotrack.sweep(str(sw))
    assert cols["controller"].dtype == object
    assert list(cols["controller"]) == [{"ki": 1.0, "kp": 2.0}] * 2 + [{"c1": 0.5, "ki": 3.0}] * 2
    base = isotrack.Scenario.from_file(str(fig2b)).set({"sim.duration_s": 5.0, "sensor.noise_std": 0.01})
    metrics = ["steady_state_rms_error", "steady_state_max_abs_error", "samples"]
    for i in range(4):
        run = base.set("controller", cols["controller"][i]).set("sim.seed", cols["sim.seed"][i].item()).run()
        for m in metrics:
            assert run.summary[m] == cols[m][i].item(), (i, m)
    # The two laws differ, and so do the two seeds of one law (a real re-run, not a constant).
    rms = cols["steady_state_rms_error"]
    assert len(set(rms.tolist())) == 4
    team = ROOT / "scenarios" / "team-circular-4.toml"
    sw.write_text(
        f'scenario = "{team}"\n[base]\nsim.duration_s = 30.0\n'
        "[grid]\nteam.vehicles = [[{index = 1, speed_mps = 0.4}], [{index = 2, speed_mps = 0.6}]]\n"
    )
    cols = isotrack.sweep(str(sw))
    assert list(cols["team.vehicles[0]"]) == [{"index": 1, "speed_mps": 0.4}, {"index": 2, "speed_mps": 0.6}]
    tbase = isotrack.Scenario.from_file(str(team)).set("sim.duration_s", 30.0)
    for i in range(2):
        run = tbase.set("team.vehicles", [cols["team.vehicles[0]"][i]]).run(record_rate_hz=0.0)
        assert run.team["gap_cv"] == cols["gap_cv"][i].item()
        assert run.summary["steady_state_rms_error"] == cols["steady_state_rms_error"][i].item()
    assert cols["gap_cv"][0] != cols["gap_cv"][1]


def test_a_fifo_or_a_directory_is_one_error_class_for_every_input_file(tmp_path):
    """att30d-15: the same FIFO raised ScenarioError (a ValueError) from Scenario.from_file and
    benchmark(suite=), OSError from sweep. Now every input file is checked alike before it is
    opened (never blocking on a FIFO): a FIFO an OSError that is no ValueError, a directory an
    IsADirectoryError, a missing file a FileNotFoundError, each with one message."""
    fifo = tmp_path / "p.toml"
    os.mkfifo(fifo)
    calls = {
        "scenario": lambda p: isotrack.Scenario.from_file(p),
        "sweep": lambda p: isotrack.sweep(p),
        "suite": lambda p: isotrack.benchmark(lambda sc: None, suite=p),
    }
    for what, call in calls.items():
        t0 = time.monotonic()
        with pytest.raises(OSError) as e:
            call(str(fifo))
        assert time.monotonic() - t0 < 5.0
        assert type(e.value) is OSError and not isinstance(e.value, ValueError), (what, e.value)
        assert str(e.value) == f"{fifo}: not a regular file (a FIFO, a device or a socket)", what
        with pytest.raises(IsADirectoryError, match="not a regular file"):
            call(str(tmp_path))
        with pytest.raises(FileNotFoundError, match=f"no such {what} file"):
            call(str(tmp_path / "missing.toml"))


def test_benchmark_refuses_an_old_benchmark_in_its_own_words(tmp_path):
    """att30d-15: benchmark(out=D) over a benchmark named the command's flags (`--resume`,
    `--out`); see test_api_hostile.py test_benchmark_out_like_the_cli for the run itself. Here
    only the refusal, before any run: a leaderboard.csv already in D."""
    out = tmp_path / "b"
    out.mkdir()
    (out / "leaderboard.csv").write_text("rank,controller,overall\n")
    suite = ROOT / "suites" / "standard-v2.toml"

    class Zero:
        def update(self, t, v):
            return 0.0

    with pytest.raises(OSError) as e:
        isotrack.benchmark(lambda sc: Zero(), suite=str(suite), out=str(out))
    msg = str(e.value)
    assert "already holds a benchmark" in msg and "resume=True" in msg and "out=" in msg, msg
    assert "--" not in msg, msg


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
    # The output directory did not exist: it goes with it (nothing half-written left, an empty
    # directory included, as the command's rule is).
    d = out if what == "plot" else os.path.dirname(out)
    end = time.monotonic() + 300
    while time.monotonic() < end and os.path.exists(d):
        time.sleep(0.05)
    print("left", sorted(os.listdir(d)) if os.path.exists(d) else "nothing", flush=True)
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
    # Nothing under the names asked for, no staging directory, and no empty output directory
    # (the call made it).
    assert left.strip() == "left nothing", left
