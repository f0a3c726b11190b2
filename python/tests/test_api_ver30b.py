"""ver30b's Python findings (issue 30, a Python API that never lies): a controller_factory that
returns one object for two runs refused (sweep and benchmark), Run.save under Ctrl-C (the earlier
run intact, or the save completed and said so), and the error classes and messages of the
doors one step in."""

import os
from pathlib import Path

import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]
CIRCULAR = ROOT / "scenarios" / "paper-fig2b-circular.toml"


class PI:
    """A PI law on the level error with an integral: its state (the integral, the last time)
    would carry from one run to the next if one object flew two runs."""

    def __init__(self):
        self.i = 0.0
        self.last = None
        self.calls = 0

    def update(self, t, v):
        self.calls += 1
        e = v - 10.0
        dt = 0.0 if self.last is None else t - self.last
        self.last = t
        self.i += e * dt
        return 2.0 * e + 1.0 * self.i


class Slotted:
    """An object without a __weakref__ slot (held by strong reference)."""

    __slots__ = ("n",)

    def __init__(self):
        self.n = 0

    def update(self, t, v):
        self.n += 1
        return 0.1


SWEEP = f"scenario = {str(CIRCULAR)!r}\n[base]\nsim.duration_s = 2.0\n[grid]\ncontroller.kp = [1.0, 2.0, 3.0]\n"


@pytest.mark.parametrize("cls", [PI, Slotted])
def test_a_sweep_factory_returning_one_object_for_two_runs_is_refused(cls):
    """ver30b-11: the second run's object is the first run's: refused, naming both runs, before
    the second run flies (its state would be the first run's)."""
    one = cls()
    with pytest.raises(ValueError, match=r"same object for run 1 as for run 0"):
        isotrack.sweep(SWEEP, controller_factory=lambda sc: one)
    # A new object per call: every row the same (the law ignores kp), as theory says for
    # runs that share nothing.
    rows = isotrack.sweep(SWEEP, controller_factory=lambda sc: PI())
    rms = list(rows["steady_state_rms_error"])
    assert rms[0] == rms[1] == rms[2]


def test_a_sweep_factory_reusing_a_dead_objects_address_is_not_refused():
    """Objects that die after their run may have their address reused by the next: not the same
    object, so not refused (the weak reference is dead)."""
    n = []

    def factory(sc):
        n.append(1)
        return PI()

    isotrack.sweep(SWEEP, controller_factory=factory)
    assert len(n) == 3


def test_a_team_sweep_factory_returning_one_object_across_runs_is_refused():
    """ver30b-11 for a team: distinct objects inside a run, but run 1's vehicle 0 is run 0's."""
    team = ROOT / "scenarios" / "team-circular-4.toml"
    sweep = f"scenario = {str(team)!r}\n[base]\nsim.duration_s = 1.0\n[grid]\nteam.k_v = [0.1, 0.2]\n"
    pool = [PI() for _ in range(4)]
    calls = []

    def factory(sc):
        calls.append(1)
        return pool[(len(calls) - 1) % 4]

    with pytest.raises(ValueError, match=r"same object for vehicle 0 of run 1 as for vehicle 0 of run 0"):
        isotrack.sweep(sweep, controller_factory=factory)


def test_a_benchmark_factory_returning_one_object_for_two_runs_is_refused(tmp_path):
    """ver30b-11 (benchmark): seed 2's run would start from seed 1's state and its score land on
    the leaderboard: refused, and no leaderboard written."""
    suite = tmp_path / "suite.toml"
    suite.write_text(
        'name = "edge"\nversion = 1\nscoring = 2\ndescription = "edge"\ncontrollers = ["pi_isoline"]\n'
        "tuning_seeds = [9]\nscoring_seeds = [1, 2]\n\n[[task]]\n"
        f'id = "t"\ntitle = "t"\nscenario = {str(CIRCULAR)!r}\nlength_m = 6.93\n'
        'set = ["sim.duration_s=2.0", "controller.max_turn_rate_radps=1.0"]\n'
    )
    one = PI()
    out = tmp_path / "b"
    with pytest.raises(ValueError, match=r"controller_factory returned the same object for run 2 \(seed \d+\) as for run 1"):
        isotrack.benchmark(lambda sc: one, name="mine", suite=str(suite), controllers=["mine"], out=str(out))
    assert not (out / "leaderboard.csv").exists()
    r = isotrack.benchmark(lambda sc: PI(), name="mine", suite=str(suite), controllers=["mine"])
    assert [n for n, _ in r["overall"]] == ["mine"]



SAVE_CHILD = """
import json, os, shutil, signal, sys, time
import isotrack
base = isotrack.Scenario.from_file(sys.argv[1])
d, trials = sys.argv[2], int(sys.argv[3])
old = base.set("sim.duration_s", 2.0).run()
big = base.set({"sim.duration_s": 3000.0, "output.record_rate_hz": 100.0}).run()
t0 = time.monotonic(); big.save(d + "_calib"); cal = time.monotonic() - t0
for k in range(trials):
    shutil.rmtree(d, ignore_errors=True)
    old.save(d)
    print("READY %.6f" % cal, flush=True)
    sys.stdin.readline()
    said = "SAVED"
    try:
        big.save(d)
    except KeyboardInterrupt as e:
        said = "KBI " + str(e)
    # A signal that comes after the save returned is absorbed here (the parent says when it
    # sent it): a KeyboardInterrupt after the call, as for any call.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    assert sys.stdin.readline() == "sent\\n"
    signal.signal(signal.SIGINT, signal.default_int_handler)
    s = json.load(open(os.path.join(d, "summary.json")))
    print(json.dumps([said, s["t_end_s"], sorted(os.listdir(d))]), flush=True)
"""


def test_ctrl_c_during_run_save_leaves_the_earlier_run_or_says_the_new_one_is_saved(tmp_path):
    """ver30b-9: SIGINT sent to a process saving a 300 001-row run over an earlier 2 s run, at
    90 % to 102 % of the save's own time (the last rows and the final writes, where the new
    run replaces the earlier one), then at 30 % to 60 %: every outcome obeys the one rule. A bare KeyboardInterrupt
    leaves the earlier run (t_end 2 s), no temporary and no lock file; one that says "the save
    completed" leaves the new run (t_end 3000 s); or the save returns. Before the fix 3 of 13
    such late signals raised a bare KeyboardInterrupt with the new run in place."""
    import json
    import signal
    import subprocess
    import sys
    import time

    # 16 late signals (90 % to 102 % of the save's time, where the new run replaces the earlier
    # one), then 4 early ones (30 % to 60 %): under load the late ones may all land after the
    # commit, the early ones reach the earlier side whatever the machine is doing.
    late, trials = 16, 20
    d = str(tmp_path / "d")
    p = subprocess.Popen(
        [sys.executable, "-c", SAVE_CHILD, str(CIRCULAR), d, str(trials)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    seen = []
    try:
        for k in range(trials):
            line = p.stdout.readline().split()
            assert line and line[0] == "READY", line
            cal = float(line[1])
            p.stdin.write("go\n")
            p.stdin.flush()
            if k < late:
                time.sleep(cal * (0.90 + 0.12 * k / (late - 1)))
            else:
                time.sleep(cal * (0.30 + 0.30 * (k - late) / (trials - late - 1)))
            p.send_signal(signal.SIGINT)
            p.stdin.write("sent\n")
            p.stdin.flush()
            said, t_end, files = json.loads(p.stdout.readline())
            seen.append(said.split()[0] if "completed" not in said else "KBI-completed")
            if said == "SAVED":
                assert t_end == 3000.0
            elif "interrupted after the save completed" in said:
                assert t_end == 3000.0 and d in said, said
            else:
                assert said.startswith("KBI"), said
                assert t_end == 2.0, f"a bare KeyboardInterrupt, yet the new run is in place: {said!r}"
            assert files == ["scenario.toml", "summary.json", "trace.csv"], files
        assert p.wait(timeout=120) == 0
    finally:
        p.kill()
    assert "KBI" in seen, seen  # the earlier side was reached at least once


@pytest.mark.parametrize("team", [False, True])
def test_ctrl_c_delivered_as_the_save_returns_says_the_save_completed(tmp_path, monkeypatch, team):
    """CI 2026-11-27: a SIGINT that arrives after the native save's last check, while the call
    returns, is delivered by CPython right after the call, in Run.save: it raised a bare
    KeyboardInterrupt with the new run in place. Here the signal is sent as the native call
    returns (a real SIGINT, delivered at the next bytecode): the KeyboardInterrupt says the
    save completed and the directory holds the new run; one delivered before the native call
    stays a bare KeyboardInterrupt with nothing written."""
    import json
    import signal

    base = isotrack.Scenario.from_file(str(ROOT / "scenarios" / ("team-circular-4.toml" if team else "paper-fig2b-circular.toml")))
    run = base.set("sim.duration_s", 1.5).run()
    name = "write_team_run" if team else "write_run"
    real = getattr(isotrack._native, name)

    def returns_then_signal(*args):
        real(*args)
        os.kill(os.getpid(), signal.SIGINT)

    def signal_first(*args):
        os.kill(os.getpid(), signal.SIGINT)
        real(*args)

    d = tmp_path / "d"
    monkeypatch.setattr(isotrack._native, name, returns_then_signal)
    with pytest.raises(KeyboardInterrupt, match=r"^interrupted after the save completed: .*/d holds the new run, whole"):
        run.save(str(d))
    assert json.load(open(d / "summary.json"))["t_end_s"] == 1.5
    e = tmp_path / "e"
    monkeypatch.setattr(isotrack._native, name, signal_first)
    with pytest.raises(KeyboardInterrupt) as bare:
        run.save(str(e))
    assert "completed" not in str(bare.value)
    assert not e.exists()


@pytest.mark.parametrize("factory", [False, True])
def test_a_sweeps_scenario_that_is_a_fifo_or_a_directory_gets_the_top_level_class(tmp_path, factory):
    """ver30b-12: `scenario =` naming a FIFO is an OSError (not FileNotFoundError: the file
    exists), a directory an IsADirectoryError, a missing file FileNotFoundError, as the same
    path gets as sweep()'s own argument; the FIFO is never opened (this would block)."""
    fifo = tmp_path / "p.toml"
    os.mkfifo(fifo)
    (tmp_path / "dir.toml").mkdir()
    kw = {"controller_factory": lambda sc: PI()} if factory else {}
    for target, cls in [(fifo, OSError), (tmp_path / "dir.toml", IsADirectoryError), (tmp_path / "none.toml", FileNotFoundError)]:
        text = f"scenario = {str(target)!r}\n[grid]\ncontroller.kp = [1.0]\n"
        with pytest.raises(OSError) as e:
            isotrack.sweep(text, **kw)
        assert type(e.value) is cls, (target, type(e.value), e.value)
        assert str(target) in str(e.value)


@pytest.mark.parametrize(
    "pairs, named",
    [
        ({"controller": {"kp": 3.0}, "controller.kp": 4.0}, ("controller", "controller.kp")),
        ({"controller.kp": 4.0, "controller": {"kp": 3.0}}, ("controller.kp", "controller")),
        ({"sim": {"seed": 1}, "sim.seed": 2}, ("sim", "sim.seed")),
        ({"sim": {"seed": 1}, "sim.duration_s": 5.0, "sim.seed": 2}, ("sim", "sim.seed")),
        ({"controller": "pi", "controller.kp": 1.0}, ("controller", "controller.kp")),
    ],
)
def test_one_key_set_twice_in_one_set_call_is_refused(pairs, named):
    """ver30b-13 (a): one key given twice in one dict (a table holding it and the dotted key)
    was taken silently, the last one winning: refused naming both, whatever the order."""
    sc = isotrack.Scenario.from_file(str(CIRCULAR))
    with pytest.raises(isotrack.ScenarioError, match=rf"`{named[0]}` and `{named[1]}` set one key twice"):
        sc.set(pairs)


def test_a_table_and_a_key_it_does_not_hold_merge_in_one_set_call():
    """A table merges key by key: it and a dotted key it does not hold are no conflict; nor are
    separate set() calls (the last one taken, as separate --set flags)."""
    sc = isotrack.Scenario.from_file(str(CIRCULAR))
    s = sc.set({"sim": {"seed": 7}, "sim.duration_s": 5.0})
    assert "seed = 7" in s.to_toml() and "duration_s = 5.0" in s.to_toml()
    assert "seed = 9" in s.set("sim.seed", 9).to_toml()


@pytest.mark.parametrize("where", ["top", "dotted", "dict"])
def test_a_huge_key_is_refused_before_it_is_parsed(where):
    """ver30b-13 (b): a key longer than any scenario key (10 MB here) is refused naming its
    length, at the top level, as a dotted part and inside a dict."""
    n = 10_000_000
    big = "k" * n
    sc = isotrack.Scenario.from_file(str(CIRCULAR))
    with pytest.raises(isotrack.ScenarioError, match=r"a key of 100000\d\d bytes \(no scenario key is longer than 256\)"):
        if where == "top":
            sc.set(big, 1.0)
        elif where == "dotted":
            sc.set({"controller." + big: 1.0, "sim.seed": 1})
        else:
            sc.set("controller", {big: 1.0})


def test_an_error_inside_a_table_value_names_the_key_inside_it():
    """ver30b-10 (Python's set): a wrong value inside a table is said of its dotted key, as the
    dotted set says it, not of the table; a value where a table goes names no Rust type."""
    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "team-circular-4.toml"))
    with pytest.raises(isotrack.ScenarioError) as dotted:
        sc.set("controller.kp", True)
    with pytest.raises(isotrack.ScenarioError) as table:
        sc.set("controller", {"kp": True})
    assert "`controller.kp`" in str(dotted.value), str(dotted.value)
    assert str(table.value) == str(dotted.value)
    with pytest.raises(isotrack.ScenarioError) as e:
        sc.set("team", {"ranging": {"a": 1}})
    assert "team.ranging" in str(e.value), str(e.value)
    with pytest.raises(isotrack.ScenarioError) as e:
        sc.set("controller", "x")
    assert "struct" not in str(e.value) and "Section" not in str(e.value), str(e.value)
    assert "expected a table of keys" in str(e.value), str(e.value)
