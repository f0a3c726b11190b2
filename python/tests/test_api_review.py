"""The hostile review's leftovers of issue 30 ("a Python API that never lies"): a run that cannot
be edited into a lying run directory, sweep columns whose dtype the sweep file fixes, wrong
types named, compare() that refuses to compare nothing, exact seeds, invalid actions that raise,
progress where there is no terminal, frames from the vector environment."""

import io
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


def short(sc=None, seconds=2.0):
    return (sc or isotrack.Scenario.default()).set("sim.duration_s", seconds)


# --- 1. A run cannot be edited into a lying run directory -------------------------------------


def test_trace_is_read_only_and_save_writes_what_was_simulated(tmp_path):
    run = short().run()
    err = run.trace["error"]
    with pytest.raises(ValueError, match="read-only"):
        err[0] = 123.0
    with pytest.raises(ValueError):
        err.flags.writeable = True
    with pytest.raises(TypeError):
        run.trace["error"] = np.zeros_like(err)
    with pytest.raises(AttributeError):
        run.scenario = isotrack.Scenario.default().set("name", "not flown")
    # The summary handed out is a copy: editing it edits nothing.
    s = run.summary
    s["outcome"] = "diverged"
    assert run.summary["outcome"] == "completed"
    # np.asarray / views / copies: a copy is free to edit and does not reach the run.
    mine = err.copy()
    mine[0] = 123.0
    assert run.trace["error"][0] != 123.0
    run.save(tmp_path / "a")
    # The same scenario flown again and saved untouched: the same bytes, file by file.
    short().run().save(tmp_path / "b")
    for f in ("trace.csv", "summary.json", "scenario.toml"):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
    # Row 0 of the trace is the start at the default scenario's x = 10 m ... and its error is
    # the field's value there minus the level, which no edit above changed.
    first = (tmp_path / "a" / "trace.csv").read_text().splitlines()[1].split(",")
    header = (tmp_path / "a" / "trace.csv").read_text().splitlines()[0].split(",")
    assert float(first[header.index("error")]) == float(run.trace["error"][0])


def test_a_run_pickles_and_stays_read_only(tmp_path):
    import pickle

    run = short(seconds=1.0).run()
    back = pickle.loads(pickle.dumps(run))
    assert back.summary == run.summary and back.scenario == run.scenario
    assert all(np.array_equal(back.trace[k], run.trace[k], equal_nan=True) for k in run.trace)
    with pytest.raises(ValueError, match="read-only"):
        back.trace["x_m"][0] = 0.0
    back.save(tmp_path / "a")
    run.save(tmp_path / "b")
    assert (tmp_path / "a" / "trace.csv").read_bytes() == (tmp_path / "b" / "trace.csv").read_bytes()


def test_a_run_made_from_your_arrays_leaves_them_yours(tmp_path):
    """Run(summary, trace) copies: the caller's arrays stay writeable, the run's are not."""
    a = np.arange(3.0)
    run = isotrack.Run({"outcome": "completed", "t_end_s": 1.0}, {"t_s": a})
    a[0] = 5.0  # still writeable
    assert run.trace["t_s"][0] == 0.0


# --- 2. Sweep columns: dtypes from the sweep file, never guessed from the cells ---------------


def sweep_file(tmp_path, grid):
    sw = tmp_path / "s.toml"
    sw.write_text(
        f'scenario = "{ROOT}/scenarios/paper-fig2b-circular.toml"\n'
        "[base]\nsim.duration_s = 2.0\n[grid]\n" + grid
    )
    return str(sw)


METRIC_FLOATS = [
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_mean_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
]


def test_sweep_column_dtypes_are_fixed_by_the_sweep_file(tmp_path):
    # Every run completes: no run has a detail.
    ok = isotrack.sweep(sweep_file(tmp_path, 'controller.kp = [5.0, 10.0]\nname = ["1", "2"]\n'))
    assert list(ok["outcome"]) == ["completed"] * 4
    # `samples` is a masked array whether or not a run was invalid (nothing masked here).
    assert isinstance(ok["samples"], np.ma.MaskedArray) and not ok["samples"].mask.any()
    assert ok["outcome_detail"].dtype.kind == "U" and list(ok["outcome_detail"]) == [""] * 4
    # A swept string key stays text even when its values look like integers.
    assert ok["name"].dtype.kind == "U" and list(ok["name"]) == ["1", "2", "1", "2"]
    # One run is an invalid scenario: the detail says why, the column is still str.
    bad = isotrack.sweep(sweep_file(tmp_path, "controller.kp = [5.0, -1.0]\n"))
    assert bad["outcome_detail"].dtype.kind == "U"
    assert bad["outcome_detail"][0] == "" and "controller.kp" in bad["outcome_detail"][1]
    for cols in (ok, bad):
        assert cols["run_id"].dtype == np.int64
        assert cols["samples"].dtype == np.int64
        assert cols["outcome"].dtype.kind == "U"
        assert cols["controller.kp"].dtype == np.float64
        for m in METRIC_FLOATS:
            assert cols[m].dtype == np.float64, m
    # An invalid run's metrics are NaN (empty cells), its samples masked.
    assert math.isnan(bad["path_length_m"][1]) and bad["samples"].mask.tolist() == [False, True]
    # Integers swept stay int64; booleans bool.
    ints = isotrack.sweep(sweep_file(tmp_path, "sim.seed = [1, 2]\nfield.value_log10 = [false, true]\n"))
    # (grid keys in sorted order, the last varying fastest)
    assert ints["sim.seed"].dtype == np.int64 and ints["sim.seed"].tolist() == [1, 2, 1, 2]
    assert ints["field.value_log10"].dtype == np.bool_
    assert ints["field.value_log10"].tolist() == [False, False, True, True]


# --- 3. Wrong types and missing paths: a clear error naming the argument ----------------------


def test_wrong_types_and_missing_paths_name_the_argument(tmp_path):
    sc = isotrack.Scenario.default()
    run = short(seconds=1.0).run()
    run_dir = run.save(tmp_path / "run")
    missing = str(tmp_path / "missing")
    cases = [
        (lambda: isotrack.check("x"), TypeError, "scenario"),
        (lambda: isotrack.check(sc, tube_halfwidth="1"), TypeError, "tube_halfwidth"),
        (lambda: isotrack.Scenario("x"), TypeError, "Scenario"),
        (lambda: isotrack.Scenario.from_file(5), TypeError, "path"),
        (lambda: isotrack.Scenario.from_file(missing), FileNotFoundError, "missing"),
        (lambda: isotrack.Scenario.from_toml(b"x = 1"), TypeError, "text"),
        (lambda: sc.set(5, 1.0), TypeError, "key"),
        (lambda: sc.run(record_rate_hz="10"), TypeError, "record_rate_hz"),
        (lambda: sc.run(record_rate_hz=10**400), ValueError, "record_rate_hz"),
        (lambda: sc.run(controller=5), TypeError, "controller"),
        (lambda: sc.run(controller=lambda t, v: 0.0), TypeError, "controller"),
        (lambda: sc.field_values("a", "b"), TypeError, "x"),
        (lambda: sc.field_values([0.0], [0.0], t=None), TypeError, "t"),
        (lambda: sc.field_values([0.0], [0.0], t="1"), TypeError, "t"),
        (lambda: run.save(5), TypeError, "directory"),
        (lambda: isotrack.sweep(5), TypeError, "path_or_toml_text"),
        (lambda: isotrack.sweep(missing), FileNotFoundError, "missing"),
        (lambda: isotrack.sweep(missing, threads="2"), TypeError, "threads"),
        (lambda: isotrack.sweep(missing, threads=0), ValueError, "threads"),
        (lambda: isotrack.sweep(missing, progress="yes"), TypeError, "progress"),
        (lambda: isotrack.sweep(missing, controller_factory=5), TypeError, "controller_factory"),
        (lambda: isotrack.benchmark(5), TypeError, "controller_factory"),
        (lambda: isotrack.benchmark(lambda s: None, suite=missing), FileNotFoundError, "missing"),
        (lambda: isotrack.benchmark(lambda s: None, suite=5), TypeError, "suite"),
        (lambda: isotrack.benchmark(lambda s: None, name=5), TypeError, "name"),
        (lambda: isotrack.benchmark(lambda s: None, controllers="pi_isoline"), TypeError, "controllers"),
        (lambda: isotrack.benchmark(lambda s: None, tune="no"), TypeError, "tune"),
        (lambda: isotrack.compare("x"), TypeError, "scenario"),
        (lambda: isotrack.compare(sc, controllers="pi_isoline"), TypeError, "controllers"),
        (lambda: isotrack.compare(sc, controllers=[1]), TypeError, "controllers"),
        (lambda: isotrack.compare(sc, gains="a=1"), TypeError, "gains"),
        (lambda: isotrack.compare(sc, record_rate_hz="1"), TypeError, "record_rate_hz"),
        (lambda: isotrack.compare(sc, out=5), TypeError, "out"),
        (lambda: isotrack.report(5, str(tmp_path / "r.html")), TypeError, "runs"),
        (lambda: isotrack.report([run_dir], 5), TypeError, "out"),
        (lambda: isotrack.report([missing], str(tmp_path / "r.html")), FileNotFoundError, "missing"),
        (lambda: isotrack.report([], str(tmp_path / "r.html")), ValueError, "runs"),
        (lambda: isotrack.plot(5), TypeError, "runs"),
        (lambda: isotrack.plot([run_dir], out=5), TypeError, "out"),
        (lambda: isotrack.plot([missing]), FileNotFoundError, "missing"),
        (lambda: isotrack.plot([run_dir], animate="yes"), TypeError, "animate"),
        (lambda: isotrack.plot([run_dir], x=5), TypeError, "x"),
        (lambda: isotrack.plot([run_dir], format=5), ValueError, "format"),
    ]
    for call, kind, word in cases:
        with pytest.raises(kind) as e:
            call()
        assert word in str(e.value), (word, kind, e.value)
        assert len(str(e.value)) < 1000


def test_wrong_types_for_the_environments_name_the_argument():
    gym = pytest.importorskip("isotrack.gym")
    for kwargs, kind, word in [
        ({"scenario": "x"}, TypeError, "scenario"),
        ({"start_radius_m": "1"}, TypeError, "start_radius_m"),
        ({"random_heading": "yes"}, TypeError, "random_heading"),
        ({"max_turn_rate_radps": "1"}, TypeError, "max_turn_rate_radps"),
        ({"effort_weight": None}, TypeError, "effort_weight"),
        ({"render_mode": 5}, ValueError, "render_mode"),
        ({"render_mode": "rgb_array", "render_half_width_m": "5"}, TypeError, "render_half_width_m"),
    ]:
        for make in (gym.IsolineEnv, lambda **k: gym.IsolineVectorEnv(num_envs=2, **k)):
            with pytest.raises(kind) as e:
                make(**kwargs)
            assert word in str(e.value), (kwargs, e.value)
    for env in (gym.IsolineEnv(), gym.IsolineVectorEnv(num_envs=2)):
        with pytest.raises(TypeError, match="options"):
            env.reset(options=5)
        with pytest.raises(TypeError, match="seed"):
            env.reset(seed="1")


# --- 4. compare() refuses to compare nothing, or a law twice ----------------------------------


def test_compare_refuses_empty_and_duplicate_controllers():
    sc = short(seconds=1.0)
    with pytest.raises(ValueError, match="controllers is empty"):
        isotrack.compare(sc, controllers=[])
    with pytest.raises(ValueError, match="'pi_isoline' twice"):
        isotrack.compare(sc, controllers=["pi_isoline", "sliding_mode", "pi_isoline"])
    with pytest.raises(ValueError, match="not exactly a built-in law"):  # not a second pi_isoline
        isotrack.compare(sc, controllers=["pi_isoline", " pi_isoline"])
    assert list(isotrack.compare(sc, controllers=["sliding_mode", "pi_isoline"])) == ["sliding_mode", "pi_isoline"]


# --- 5. Seeds are integers, exactly -----------------------------------------------------------


def test_seeds_are_exact_integers_numpy_ones_too():
    sc = short(seconds=0.5)
    top = 2**63 - 1  # the largest seed: TOML's integers are signed 64-bit
    for seed in (top, np.int64(top), np.uint64(top)):
        assert sc.set("sim.seed", seed).run().summary["scenario"]["sim"]["seed"] == top
    for seed in (np.uint64(2**63 + 5), np.uint64(2**64 - 1), 2**63):
        with pytest.raises(isotrack.ScenarioError, match=r"does not fit in a 64-bit integer \(-2\*\*63 \.\.= 2\*\*63-1"):
            sc.set("sim.seed", seed)
    # A numpy integer is never taken through a float, for any key.
    with pytest.raises(isotrack.ScenarioError, match="does not fit"):
        sc.set("controller.kp", np.uint64(2**63 + 5))
    assert sc.set("sim.seed", np.uint32(7)) == sc.set("sim.seed", 7)
    # Not integers: refused, never rounded or read as 0/1.
    for seed in (5.0, np.float64(5.0), 5.5, True, np.bool_(True), "5", -1, np.int64(-1)):
        with pytest.raises(isotrack.ScenarioError, match="sim.seed"):
            sc.set("sim.seed", seed)


def test_environment_seeds_are_exact():
    gym = pytest.importorskip("isotrack.gym")
    big = 2**63 + 5
    a, b = gym.IsolineEnv(), gym.IsolineEnv()
    assert np.array_equal(a.reset(seed=np.uint64(big))[0], b.reset(seed=big)[0])
    assert a.reset(seed=np.uint64(big))[1]["start"] == b.reset(seed=big)[1]["start"]
    assert a.reset(seed=np.uint64(big))[1]["start"] != b.reset(seed=big + 1)[1]["start"]
    for bad in (1.0, np.float64(1.0), True, "1"):
        with pytest.raises(TypeError, match="seed"):
            a.reset(seed=bad)
    with pytest.raises(ValueError, match="seed"):
        a.reset(seed=-1)


# --- 6. Invalid actions raise, and step nothing ----------------------------------------------


def test_invalid_actions_raise_and_step_nothing():
    gym = pytest.importorskip("isotrack.gym")
    env, twin = gym.IsolineEnv(), gym.IsolineEnv()
    env.reset(seed=3)
    twin.reset(seed=3)
    for bad in (float("nan"), float("inf"), -float("inf")):
        with pytest.raises(ValueError, match="finite"):
            env.step([bad])
    # Nothing was stepped: the next step is the twin's first.
    got, want = env.step([0.2]), twin.step([0.2])
    assert np.array_equal(got[0], want[0]) and got[1:4] == want[1:4]
    vec, vtwin = gym.IsolineVectorEnv(num_envs=3), gym.IsolineVectorEnv(num_envs=3)
    vec.reset(seed=4)
    vtwin.reset(seed=4)
    a = np.full((3, 1), 0.1)
    a[2, 0] = np.nan
    with pytest.raises(ValueError, match=r"sub-environments \[2\]"):
        vec.step(a)
    a[2, 0] = 0.1
    o1, r1, *_ = vec.step(a)
    o2, r2, *_ = vtwin.step(a)
    assert np.array_equal(o1, o2) and np.array_equal(r1, r2)


# --- 7. Progress without a terminal -----------------------------------------------------------


LINE = re.compile(r"^sweep: (\d+)/(\d+) runs \(\d+ %\), \d+\.\d s$")


def progress_lines(text):
    assert "\r" not in text  # whole lines, never redrawn in place
    lines = text.splitlines()
    assert lines and all(LINE.match(x) for x in lines), lines
    return [tuple(int(v) for v in LINE.match(x).groups()) for x in lines]


def test_sweep_progress_is_shown_without_a_terminal(tmp_path, capsys):
    sw = sweep_file(tmp_path, "controller.kp = [5.0, 10.0, 20.0]\n")
    isotrack.sweep(sw, progress=True)
    shown = progress_lines(capsys.readouterr().err)
    assert shown[-1] == (3, 3)
    assert [d for d, _ in shown] == sorted(d for d, _ in shown)

    class Zero:
        def update(self, t_s, value):
            return 0.0

    isotrack.sweep(sw, progress=True, controller_factory=lambda s: Zero())
    shown = progress_lines(capsys.readouterr().err)
    assert shown[0] == (0, 3) and shown[-1] == (3, 3)
    # Without progress=True: nothing.
    isotrack.sweep(sw)
    assert capsys.readouterr().err == ""


def test_progress_lines_are_rate_bounded():
    """Not a terminal: a line at most every LINE_PERIOD_S (here made huge), plus the last."""
    out = io.StringIO()
    p = isotrack._Progress(out)
    p.LINE_PERIOD_S = 1e9
    for d in range(0, 1001):
        p(d, 1000)
    assert [x.split(" runs")[0] for x in out.getvalue().splitlines()] == ["sweep: 0/1000", "sweep: 1000/1000"]

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    tty = Terminal()
    p = isotrack._Progress(tty)
    p(0, 4)
    p(4, 4)
    # On a terminal: one line redrawn in place, ended once.
    assert tty.getvalue().startswith("\rsweep: 0/4 runs") and tty.getvalue().count("\n") == 1
    assert tty.getvalue().endswith("\n") and "\rsweep: 4/4 runs (100 %)" in tty.getvalue()


# --- 8. The vector environment renders ---------------------------------------------------------


def test_vector_env_renders_one_frame_per_sub_environment():
    gym = pytest.importorskip("isotrack.gym")
    n = 3
    vec = gym.IsolineVectorEnv(num_envs=n, render_mode="rgb_array")
    assert vec.metadata["render_modes"] == ["rgb_array"]
    singles = [gym.IsolineEnv(render_mode="rgb_array") for _ in range(n)]
    vec.reset(seed=10)
    for i, e in enumerate(singles):
        e.reset(seed=10 + i)
    for step in range(5):
        frames = vec.render()
        assert isinstance(frames, tuple) and len(frames) == n
        assert np.stack(frames).shape == (n, 256, 256, 3) and np.stack(frames).dtype == np.uint8
        for i, e in enumerate(singles):
            # Sub-environment i is the single environment seeded s + i: the same picture.
            assert np.array_equal(frames[i], e.render()), (step, i)
        actions = np.array([[0.3], [-0.3], [0.0]])
        vec.step(actions)
        for i, e in enumerate(singles):
            e.step(actions[i])
    with pytest.raises(ValueError, match="render_mode"):
        gym.IsolineVectorEnv(num_envs=2, render_mode="human")
    with pytest.warns(UserWarning, match="render_mode"):
        assert gym.IsolineVectorEnv(num_envs=2).render() is None


# --- ROBUSTNESS.md class 1: outputs that are not regular files ---------------------------------


def test_outputs_that_are_fifos_are_refused_without_blocking(tmp_path):
    """A FIFO where a run directory's file, a report or a figure goes would block the write
    until someone reads it (it once hung `Run.save` and `report` for good): refused at once."""
    import time

    run = short(seconds=1.0).run()
    (tmp_path / "run").mkdir()
    os.mkfifo(tmp_path / "run" / "trace.csv")
    os.mkfifo(tmp_path / "page.html")
    good = run.save(tmp_path / "good")
    (tmp_path / "fig").mkdir()
    os.mkfifo(tmp_path / "fig" / "trajectory.png")
    t0 = time.monotonic()
    with pytest.raises(OSError, match="trace.csv: not a regular file"):
        run.save(tmp_path / "run")
    with pytest.raises(OSError, match="page.html: not a regular file"):
        isotrack.report([good], str(tmp_path / "page.html"))
    with pytest.raises(OSError, match="trajectory.png: not a regular file"):
        isotrack.plot([good], out=str(tmp_path / "fig"))
    assert time.monotonic() - t0 < 5.0


# --- ROBUSTNESS.md class 4: Ctrl-C in check() -------------------------------------------------


def test_ctrl_c_answers_a_long_check():
    """A puff plume's check over 2.5e6 s takes minutes (2 s at 2e6 s, more than 25 s at
    2.5e6 s on a 2-core machine): a SIGINT at 0.3 s is answered within 2 s. (The computation
    goes on, dropped, on its own thread until it ends or the interpreter exits.)"""
    import signal
    import threading
    import time

    sc = (
        isotrack.Scenario.from_file(str(ROOT / "scenarios" / "puff-plume-edge.toml"))
        .set("output.record_rate_hz", 0.0)
        .set("sim.duration_s", 2.5e6)
    )
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            isotrack.check(sc)
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 2.0
    # The module still answers.
    assert isotrack.check(isotrack.Scenario.default())["verdict"]


# --- ROBUSTNESS.md class 2: sizes -------------------------------------------------------------


def test_toml_text_is_bounded_like_files():
    """Scenario and sweep text from Python are held to the CLI's 1 MiB file limit (a 50 MB
    scenario name was once accepted)."""
    big = 'name = "' + "a" * (2 << 20) + '"\n'
    with pytest.raises(ValueError, match="larger than 1048576 bytes"):
        isotrack.Scenario.from_toml(big)
    with pytest.raises(ValueError, match="larger than 1048576 bytes"):
        isotrack.sweep('scenario = "x.toml"\n' + big)
    # Multi-byte characters count as their bytes.
    with pytest.raises(ValueError, match="larger than"):
        isotrack.Scenario.from_toml('name = "' + "\u00e9" * (600 << 10) + '"\n')
    assert isotrack.Scenario.from_toml('name = "' + "a" * 1000 + '"\n').to_toml()


def test_saving_twice_keeps_the_users_figures(tmp_path):
    """att39-6 (att38-1 through Python): the second ``Run.save(DIR)`` into a folder holding the
    user's own trajectory.png and team.svg deleted them (the first save's summary made the
    folder read as an earlier run, and every figure there as that run's). isotrack never
    removes a file it may not have written: both survive any number of saves, byte for byte."""
    d = tmp_path / "mine"
    d.mkdir()
    (d / "trajectory.png").write_bytes(b"MY PICTURE")
    (d / "team.svg").write_text("<svg>mine</svg>")
    run = short(seconds=1.0).run()
    for _ in range(3):
        run.save(d)
        assert (d / "trajectory.png").read_bytes() == b"MY PICTURE"
        assert (d / "team.svg").read_text() == "<svg>mine</svg>"
    assert (d / "summary.json").is_file() and (d / "trace.csv").is_file()
