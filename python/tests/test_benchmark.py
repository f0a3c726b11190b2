"""isotrack.benchmark: a Python controller on the benchmark's tasks and seeds, beside the
built-in laws."""

import json
import math
from pathlib import Path

import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]


def mini_suite(tmp_path):
    s = ROOT / "scenarios"
    p = tmp_path / "mini.toml"
    p.write_text(
        f"""name = "mini"
version = 1
controllers = ["pi_isoline", "sliding_mode"]
tuning_seeds = [11]
scoring_seeds = [1, 2]

[[task]]
id = "circular"
title = "circular field, 10 Hz"
scenario = "{s}/paper-fig2b-circular.toml"
set = ["sim.duration_s=60.0", "sensor.rate_hz=10.0", "controller.max_turn_rate_radps=1.0"]
length_m = 6.93
vary = {{ "initial.heading_rad" = {{ uniform = [-3.0, 3.0] }} }}
"""
    )
    return p


class PaperLaw:
    """The paper's PI-like law in Python (backward difference, rectangle-rule integral)."""

    def __init__(self, level, kp=10.0, ki=1.0, c1=0.2, c2=1.0):
        self.level, self.kp, self.ki, self.c1, self.c2 = level, kp, ki, c1, c2
        self.prev, self.sigma = None, 0.0

    def update(self, t_s, value):
        eps = value - self.level
        if self.prev is None:
            d, dt = 0.0, 0.0
        else:
            dt = t_s - self.prev[0]
            d = (eps - self.prev[1]) / dt
        self.prev = (t_s, eps)
        e = d + self.c1 * math.tanh(eps / self.c2)
        self.sigma += e * dt
        return self.kp * e + self.ki * self.sigma


def test_a_python_law_is_scored_beside_the_builtin_laws(tmp_path):
    seen = []

    def factory(sc):
        seen.append((sc.level, sc.max_turn_rate_radps))
        return PaperLaw(sc.level)

    out = tmp_path / "out"
    r = isotrack.benchmark(factory, suite=str(mini_suite(tmp_path)), name="mine", out=str(out))
    assert r["controllers"] == ["pi_isoline", "sliding_mode", "mine"]
    assert {c for c, _ in r["overall"]} == {"pi_isoline", "sliding_mode", "mine"}
    task = r["tasks"][0]
    scores = dict(task["scores"])
    # Same law, same tasks and seeds: the same score as the built-in within a point (the
    # built-in's first sample and integral differ in detail), and a good one.
    assert abs(scores["mine"] - scores["pi_isoline"]) < 1.0, scores
    assert scores["mine"] > 60.0
    assert len([run for run in task["runs"] if run["controller"] == "mine"]) == 2
    # One factory call per scored run (the picture's path is the first seed's scored run, not
    # a run of its own), each seeing the task's level and limit.
    assert len(seen) == 2 and all(s == (10.0, 1.0) for s in seen)
    trajectories = json.loads((out / "tasks" / "circular" / "task.json").read_text())["trajectories"]
    assert [t["controller"] for t in trajectories] == ["pi_isoline", "sliding_mode", "mine"]
    assert (out / "leaderboard.csv").read_text().splitlines()[0] == "rank,controller,overall,circular"
    assert "mine" in (out / "index.html").read_text()


def test_only_yours_and_errors(tmp_path):
    suite = str(mini_suite(tmp_path))
    r = isotrack.benchmark(lambda sc: PaperLaw(sc.level), suite=suite, name="mine", controllers=["mine"])
    assert r["controllers"] == ["mine"]

    class Broken:
        def update(self, t_s, value):
            raise ZeroDivisionError("inside my law")

    with pytest.raises(ZeroDivisionError, match="inside my law"):
        isotrack.benchmark(lambda sc: Broken(), suite=suite, controllers=["python"])
    with pytest.raises(FileNotFoundError):
        isotrack.benchmark(lambda sc: Broken(), suite=str(tmp_path / "none.toml"))
    with pytest.raises(isotrack.ScenarioError, match="unknown controller"):
        isotrack.benchmark(lambda sc: Broken(), suite=suite, controllers=["nope"])
