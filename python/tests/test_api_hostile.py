"""Regression tests for a hostile tester's findings on the Python package (each failed before
its fix)."""

import io
import json
import math
import os
import pickle
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


def short():
    return isotrack.Scenario.default().set("sim.duration_s", 2.0)


class Const:
    def __init__(self, w):
        self.w = w

    def update(self, t_s, value):
        return self.w


# 1. A run flown by a Python controller is recorded as such.
def test_python_controller_recorded_in_saved_run(tmp_path):
    run = short().run(controller=Const(0.3))
    name = f"{Const.__module__}.Const"
    assert run.summary["controller"] == {"kind": "python", "class": name}
    assert run.summary["scenario"]["controller"]["kind"] == "python"
    d = tmp_path / "d"
    run.save(d)
    summary = json.loads((d / "summary.json").read_text())
    assert summary["controller"]["kind"] == "python"
    assert summary["scenario"]["controller"]["class"] == name
    toml = (d / "scenario.toml").read_text()
    assert toml.startswith("# This run was flown by a Python controller")
    assert name in toml.splitlines()[0]
    # Still a scenario the CLI and the package read (plot and report need it).
    isotrack.Scenario.from_file(str(d / "scenario.toml"))
    # att46-3: and plot and report draw the run (they refused every saved Python-controller
    # run: "summary.json's scenario is not a scenario (unknown field `class`)").
    isotrack.plot(str(d), out=str(tmp_path / "figs"))
    assert (tmp_path / "figs" / "trajectory.png").exists()
    isotrack.report(str(d), out=str(tmp_path / "r.html"))
    assert (tmp_path / "r.html").stat().st_size > 0
    # An edited level in scenario.toml is still not this run's.
    head, law = toml.split("[controller]", 1)
    (d / "scenario.toml").write_text(head + "[controller]" + law.replace("\nlevel = ", "\nlevel = 1", 1))
    with pytest.raises(isotrack.ScenarioError, match="controller.level"):
        isotrack.plot(str(d), out=str(tmp_path / "figs2"))
    # A run of the scenario's own law says nothing of the kind.
    own = short().run()
    assert "controller" not in own.summary
    own.save(tmp_path / "own")
    assert not (tmp_path / "own" / "scenario.toml").read_text().startswith("#")


# 2. A Run made by hand is never saved as a run directory; NaN never written as JSON.
def test_hand_made_run_not_saved(tmp_path):
    real = short().run()
    forged = isotrack.Run(real.summary, dict(real.trace), real.scenario)
    with pytest.raises(ValueError, match="not made by a simulation"):
        forged.save(tmp_path / "forged")
    assert not (tmp_path / "forged").exists()
    with pytest.raises(ValueError, match="summary"):
        isotrack.Run({"outcome": float("nan")}, {}, None)
    # A simulated run still pickles and saves after a round trip.
    back = pickle.loads(pickle.dumps(real))
    back.save(tmp_path / "back")
    assert json.loads((tmp_path / "back" / "summary.json").read_text())["outcome"] == "completed"
    with pytest.raises(ValueError, match="not made by a simulation"):
        pickle.loads(pickle.dumps(forged)).save(tmp_path / "forged2")


# 3. SB3VecEnv without stable-baselines3: no ImportError from `import *` or hasattr.
def test_gym_star_import_and_hasattr_without_sb3():
    code = (
        "import sys; sys.modules['stable_baselines3'] = None\n"
        "import isotrack.gym as g\n"
        "assert 'SB3VecEnv' not in g.__all__, g.__all__\n"
        "from isotrack.gym import *\n"
        "assert not hasattr(g, 'SB3VecEnv')\n"
        "try:\n"
        "    g.SB3VecEnv\n"
        "except AttributeError as e:\n"
        "    assert 'pip install stable-baselines3' in str(e), e\n"
        "else:\n"
        "    raise SystemExit('no AttributeError')\n"
    )
    # find_spec on a None entry raises ValueError: looked up as absent.
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


# 4. A broken stderr never loses a sweep.
def test_sweep_progress_on_broken_stderr(monkeypatch):
    text = f'scenario = "{ROOT}/scenarios/paper-fig2b-circular.toml"\n[base]\nsim.duration_s = 2.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n'
    dead = io.StringIO()
    dead.close()
    monkeypatch.setattr(sys, "stderr", dead)
    out = isotrack.sweep(text, progress=True)
    assert list(out["run_id"]) == [0, 1]


# 5. set() holds values to the scenario text limit, so that every scenario pickles.
def test_set_huge_value_refused_consistently():
    with pytest.raises(isotrack.ScenarioError, match="1048576"):
        short().set("name", "x" * 2**20)
    sc = short().set("name", "x" * 1000)
    assert pickle.loads(pickle.dumps(sc)) == sc


# 7. save("") refused, as the CLI refuses --out "".
def test_save_empty_path_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="empty"):
        short().run().save("")
    assert list(tmp_path.iterdir()) == []


# 8. A first command of NaN: the trace still holds the start.
def test_nan_first_command_keeps_start_row():
    sc = short()
    run = sc.run(controller=Const(float("nan")))
    assert run.summary["outcome"] == "diverged"
    assert len(run.trace["t_s"]) == 1
    assert run.trace["t_s"][-1] == 0.0
    # The default start: (10, 0) m (the paper's Fig. 2(b) setting), the command held before
    # the first sample (0: none yet), the error s - s_d of the circular field there.
    assert run.trace["x_m"][0] == 10.0 and run.trace["y_m"][0] == 0.0
    assert run.trace["omega_radps"][0] == 0.0
    assert run.trace["error"][0] == run.trace["s"][0] - sc.level
    assert math.isfinite(run.trace["error"][0])


# 10. compare names exactly a law; benchmark(controllers=[]) refused.
@pytest.mark.parametrize("bad", ["pi_isoline\n", " pi_isoline", "pi_isoline "])
def test_compare_refuses_names_with_blanks(bad):
    with pytest.raises(ValueError, match="not exactly a built-in law"):
        isotrack.compare(short(), controllers=[bad])


def test_benchmark_refuses_empty_controllers():
    with pytest.raises(ValueError, match="empty"):
        isotrack.benchmark(lambda s: Const(0.0), suite=str(ROOT / "suites/standard-v2.toml"), controllers=[])


# 11. 0-d numpy arrays are their scalars.
def test_set_zero_d_arrays():
    a = short().set("controller.kp", np.array(3.0))
    assert a == short().set("controller.kp", 3.0)
    b = short().set("sim.seed", np.array(5))
    assert b == short().set("sim.seed", 5)


# 12. Numbers in messages in their shortest round-trip form.
def test_messages_shortest_numbers():
    with pytest.raises(ValueError) as e:
        short().field_values(0.0, 0.0, t=1e300)
    assert "1e300" in str(e.value) and not re.search(r"\d{40}", str(e.value))
    with pytest.raises(ValueError) as e:
        short().run(record_rate_hz=1e300)
    assert "1e300" in str(e.value) and not re.search(r"\d{40}", str(e.value))


# 13. sweep paths with `=`; an empty path.
def test_sweep_missing_path_with_equals(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such sweep file"):
        isotrack.sweep(str(tmp_path / "kp=1.toml"))
    with pytest.raises(FileNotFoundError):
        isotrack.sweep("out/kp=1.toml")
    with pytest.raises(ValueError, match="empty"):
        isotrack.sweep("")


# 14. reprs.
def test_reprs():
    r = repr(isotrack.Run({}, {}, None))
    assert r.startswith("Run(")
    # A control character in a name is refused (issue 30: one plain-text rule for every string).
    with pytest.raises(isotrack.ScenarioError, match="control or invisible"):
        short().set("name", "a\nb")
    text = repr(short().set("name", 'a "b" \\ c'))
    assert "\n" not in text and text.startswith("Scenario(")


# 15. The library does not print.
def test_report_and_plot_print_nothing(tmp_path, capfd):
    run = short().run()
    d = run.save(str(tmp_path / "r"))
    isotrack.report([d], str(tmp_path / "r.html"))
    isotrack.plot([d], out=str(tmp_path / "p"), format="svg")
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert (tmp_path / "r.html").is_file()


def test_sweep_threads_cap_is_a_warning(capfd):
    text = f'scenario = "{ROOT}/scenarios/paper-fig2b-circular.toml"\n[base]\nsim.duration_s = 1.0\n[grid]\ncontroller.kp = [5.0]\n'
    with pytest.warns(UserWarning, match="capped"):
        isotrack.sweep(text, threads=1 << 20)
    out, err = capfd.readouterr()
    assert "--threads" not in out + err


# 16. Loose validation.
def test_controller_returning_bool_refused():
    with pytest.raises(TypeError, match="bool"):
        short().run(controller=Const(True))
    with pytest.raises(TypeError, match="bool"):
        short().run(controller=Const(np.bool_(True)))


def test_plot_sweep_options_on_run_dir(tmp_path):
    d = short().run().save(str(tmp_path / "r"))
    with pytest.raises(TypeError, match="x"):
        isotrack.plot([d], x="controller.kp")


gym = pytest.importorskip("isotrack.gym")


def test_vector_reset_seed_must_be_a_sequence():
    env = gym.IsolineVectorEnv(scenario=short(), num_envs=2)
    with pytest.raises(TypeError):
        env.reset(seed={0: 1, 1: 2})
    with pytest.raises(TypeError):
        env.reset(seed={1, 2})
    env.reset(seed=[1, 2])


def test_unknown_reset_options_refused():
    env = gym.IsolineEnv(scenario=short())
    with pytest.raises(ValueError, match="strat"):
        env.reset(options={"strat": "scenario"})
    venv = gym.IsolineVectorEnv(scenario=short(), num_envs=2)
    with pytest.raises(ValueError, match="strat"):
        venv.reset(options={"strat": "scenario"})


def test_tiny_turn_rate_not_blamed_on_render_width():
    with pytest.raises(ValueError) as e:
        gym.IsolineEnv(scenario=short(), max_turn_rate_radps=5e-324)
    assert "render_half_width_m must" not in str(e.value)


# 18. A pickled scenario's data files are checked when it is unpickled.
def test_pickle_detects_changed_data_file(tmp_path):
    src = ROOT / "scenarios" / "topobathy-bc.toml"
    text = src.read_text()
    data = (src.parent / "../data/topobathy_bc/topobathy_bc.csv").resolve()
    copy = tmp_path / "field.csv"
    copy.write_bytes(data.read_bytes())
    scen = tmp_path / "s.toml"
    scen.write_text(text.replace('"../data/topobathy_bc/topobathy_bc.csv"', json.dumps(str(copy))))
    sc = isotrack.Scenario.from_file(str(scen))
    blob = pickle.dumps(sc)
    assert pickle.loads(blob) == sc
    with open(copy, "ab") as f:
        f.write(b"\n")
    with pytest.raises(ValueError, match="changed"):
        pickle.loads(blob)
    copy.unlink()
    with pytest.raises(FileNotFoundError):
        pickle.loads(blob)


# Issue 30 (doors30a), item 6: one content digest, the Rust one, for pickled scenarios and for
# the data files a run records in summary.json; it is SHA-256 (checked against hashlib).
def test_one_content_digest_for_pickles_and_run_directories(tmp_path):
    import hashlib

    data = ROOT / "data/topobathy_bc/topobathy_bc.csv"
    want = hashlib.sha256(data.read_bytes()).hexdigest()
    assert isotrack._native.file_sha256(str(data)) == want
    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "topobathy-bc.toml"))
    assert list(sc._digests.values()) == [want]
    run = sc.set("sim.duration_s", 1.0).run()
    run.save(tmp_path / "r")
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert list(summary["data_files"].values()) == [want]
    with pytest.raises(OSError):
        isotrack._native.file_sha256(str(tmp_path / "missing.csv"))


def mini_suite(tmp_path, title="circular field"):
    p = tmp_path / "mini.toml"
    p.write_text(
        f"""name = "mini"
version = 1
controllers = ["pi_isoline"]
tuning_seeds = [11]
scoring_seeds = [1]

[[task]]
id = "circular"
title = {json.dumps(title)}
scenario = "{ROOT}/scenarios/paper-fig2b-circular.toml"
set = ["sim.duration_s=10.0", "controller.max_turn_rate_radps=1.0"]
length_m = 6.93
"""
    )
    return p


# 6. benchmark(out=) as `isotrack benchmark --out`: refuses an existing benchmark, locks,
# writes suite.toml.
def test_benchmark_out_like_the_cli(tmp_path):
    suite = str(mini_suite(tmp_path))
    out = tmp_path / "b"
    isotrack.benchmark(lambda s: Const(0.5), suite=suite, out=str(out))
    assert (out / "suite.toml").is_file()
    assert "tuned" in (out / "suite.toml").read_text()
    before = (out / "leaderboard.csv").read_text()
    with pytest.raises(OSError, match="already holds a benchmark") as e:
        isotrack.benchmark(lambda s: Const(-0.5), suite=suite, out=str(out))
    # att30d-15: in this function's words, not the command's flags.
    assert "resume=True" in str(e.value) and "out=" in str(e.value), str(e.value)
    assert "--resume" not in str(e.value) and "--out" not in str(e.value), str(e.value)
    assert (out / "leaderboard.csv").read_text() == before
    isotrack.benchmark(lambda s: Const(0.5), suite=suite, out=str(out), resume=True)
    # Locked while another writer holds it.
    import fcntl

    with open(out / ".isotrack.lock", "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(OSError, match="writing this directory"):
            isotrack.benchmark(lambda s: Const(0.5), suite=suite, out=str(out), resume=True)


# 9. Markdown cells escaped: `<`, `|`, newlines.
def test_leaderboard_markdown_escaped(tmp_path):
    # A line feed in a title is refused by the suite (it would end a Markdown row) ...
    lf = str(mini_suite(tmp_path, title="two\nlines | <b>"))
    with pytest.raises(isotrack.ScenarioError, match="control or invisible"):
        isotrack.benchmark(lambda s: Const(0.5), suite=lf, name="x", out=str(tmp_path / "a"))
    # ... and the markup a title may hold is escaped in leaderboard.md.
    suite = str(mini_suite(tmp_path, title="two lines | <b>"))
    out = tmp_path / "b"
    isotrack.benchmark(lambda s: Const(0.5), suite=suite, name="<!--<script>", out=str(out))
    md = (out / "leaderboard.md").read_text()
    assert "<" not in md
    assert "&lt;!--&lt;script>" in md
    row = [line for line in md.splitlines() if line.startswith("| circular |")]
    assert row == ["| circular | two lines \\| &lt;b> |"]


def test_set_echoes_floats_shortest():
    with pytest.raises(isotrack.ScenarioError) as e:
        short().set("sim.duration_s", 1e300)
    assert "sim.duration_s=1e300" in str(e.value)
    assert not re.search(r"\d{40}", str(e.value))
    # Floats still read back exactly.
    for v in (0.1, 1e16, 2.5e-7, 3.0, 10.0):
        sc = isotrack.Scenario.from_toml(short().set("controller.kp", v).to_toml())
        assert sc == short().set("controller.kp", v)


def test_set_arrays_inside_lists_name_the_key():
    # An array that is not 0-d is refused naming the key (numpy's TypeError before).
    with pytest.raises(isotrack.ScenarioError, match="controller.kp"):
        short().set("controller.kp", np.array([3.0, 4.0]))
    with pytest.raises(isotrack.ScenarioError, match="sim.seed"):
        short().set("sim.seed", [np.array([1, 2])])


@pytest.mark.parametrize("name,link", [("loop", "/g/loop -> /g"), ("up", "/g/up -> /")])
def test_netcdf_group_cycle_is_a_scenario_error_not_a_crash(tmp_path, name, link):
    # Issue 30, att30d-7: a NetCDF-4 grid whose group holds a hard link to itself or to the
    # root overflowed the stack in the reader and killed the interpreter (SIGSEGV). Run in a
    # child so that a regression fails here instead of killing pytest.
    nc = ROOT / "crates/isotrack-fields/tests/fixtures/netcdf" / f"refused_group_{name}.nc"
    sc = tmp_path / "sc.toml"
    sc.write_text(f'[field]\nkind = "grid"\npath = "{nc}"\nvariable = "v"\n')
    code = (
        "import sys, isotrack\n"
        "try:\n"
        "    isotrack.Scenario.from_file(sys.argv[1])\n"
        "except isotrack.ScenarioError as e:\n"
        "    print(e)\n"
        "else:\n"
        "    raise SystemExit('loaded')\n"
    )
    r = subprocess.run([sys.executable, "-c", code, str(sc)], capture_output=True, text=True)
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert "field.path" in r.stdout and f"refused_group_{name}.nc" in r.stdout, r.stdout
    assert link in r.stdout, r.stdout
