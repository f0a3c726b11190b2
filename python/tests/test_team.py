"""Teams from Python (issue 32 item 7, docs/TEAMS.md): Scenario.run() of a [team] scenario (the
trace with its `vehicle` column, run.vehicles, run.team), a Python law flying every vehicle (bit
for bit the built-in law it reproduces), sweeps of a team with the team columns (the CLI's cells),
Run.save byte for byte as `isotrack run --out`, and the PettingZoo ParallelEnv (its API test, the built-in laws fed back
reproducing Scenario.run() exactly, bad actions refused, determinism)."""

import math
import re
import shutil
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]
TEAM = ROOT / "scenarios" / "team-circular-4.toml"
#: The level-10 isoline of the circular field: R = ln(20/10)/0.1 (the scenario's header).
RADIUS_M = 10.0 * math.log(2.0)


def cli():
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not os.path.exists(exe):
        pytest.skip("the isotrack binary is not built (cargo build --release -p isotrack-cli)")
    return exe


def short_team(duration_s=20.0):
    """The bundled four-robot team, shorter, its tracking law's turn rate limited (so that the
    built-in answers lie inside the environment's action space), the sensor at 10 Hz and noisy,
    the ranging noisy, lossy and late: every path of the step is used."""
    s = isotrack.Scenario.from_file(str(TEAM))
    for k, v in [
        ("sim.duration_s", duration_s),
        ("controller.max_turn_rate_radps", 1.0),
        ("sensor.rate_hz", 10.0),
        ("sensor.noise_std", 0.01),
        ("team.ranging.noise_std_m", 0.05),
        ("team.ranging.dropout_probability", 0.2),
        ("team.ranging.delay_s", 0.2),
    ]:
        s = s.set(k, v)
    return s


def same(a, b):
    """Equal arrays, bit for bit (NaN where the other has NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if a.dtype.kind == "f":
        return bool(np.array_equal(a.view(np.uint64), b.view(np.uint64)))
    return bool(np.array_equal(a, b))


# --- Scenario.run() of a team -------------------------------------------------------------------


def test_set_with_a_dict_checks_bounding_keys_together():
    """att32: one set at a time checks each key against the scenario as it stands, so raising
    v_min above the current v0 = 0.5 m/s first is refused; a dict sets both at once (the CLI's
    several --set), in either order, as the command line does."""
    s = isotrack.Scenario.from_file(str(TEAM))
    with pytest.raises(isotrack.ScenarioError, match="team.v_min_mps"):
        s.set("team.v_min_mps", 0.6)
    for pairs in (
        {"team.v_min_mps": 0.6, "vehicle.speed_mps": 0.7},
        {"vehicle.speed_mps": 0.7, "team.v_min_mps": 0.6},
    ):
        t = s.set(pairs)
        assert "v_min_mps = 0.6" in t.to_toml() and "speed_mps = 0.7" in t.to_toml()
        assert t.to_toml() == s.set("vehicle.speed_mps", 0.7).set("team.v_min_mps", 0.6).to_toml()
    # Still refused together when the pair itself is wrong, naming the key.
    with pytest.raises(isotrack.ScenarioError, match="team.v_min_mps"):
        s.set({"team.v_min_mps": 0.8, "vehicle.speed_mps": 0.7})
    with pytest.raises(TypeError):
        s.set({"team.v_min_mps": 0.6}, 0.7)
    with pytest.raises(TypeError):
        s.set({1: 0.6})
    with pytest.raises(TypeError):
        s.set("team.v_min_mps")
    assert s.set({}).to_toml() == s.to_toml()


def test_team_run_has_every_vehicle_and_the_team_metrics():
    run = isotrack.Scenario.from_file(str(TEAM)).run()
    tr = run.trace
    assert tr["vehicle"].dtype == np.int64
    assert sorted(set(tr["vehicle"].tolist())) == [0, 1, 2, 3]
    vs = run.vehicles
    assert len(vs) == 4
    for v in vs:
        assert v["outcome"] == "completed"
    # Top-level metrics are vehicle 0's (as summary.json's).
    assert run.summary["steady_state_max_abs_error"] == vs[0]["steady_state_max_abs_error"]
    # The starts: the arc spread, start i at angle -0.3 i on the circle of radius R (clockwise),
    # heading along the travel (clockwise: angle - pi/2).
    for i in range(4):
        t = run.vehicle_trace(i)
        th = -0.3 * i
        assert t["t_s"][0] == 0.0
        assert abs(t["x_m"][0] - RADIUS_M * math.cos(th)) < 1e-12
        assert abs(t["y_m"][0] - RADIUS_M * math.sin(th)) < 1e-12
        assert abs(math.remainder(t["heading_rad"][0] - (th - math.pi / 2), 2 * math.pi)) < 1e-12
        assert "vehicle" not in t
    # Each recorded step holds vehicle 0's row, then 1's, ... (the CLI's order).
    assert tr["vehicle"][:8].tolist() == [0, 1, 2, 3, 0, 1, 2, 3]
    team = run.team
    assert team["vehicle_count"] == 4
    assert team["spacing"] == "range_balance" and team["coordinate_free"] is True
    m = team
    # range_balance spreads the cluster: the target, and the ideal revisit time
    # L / (N v0) = 2 pi R / (4 * 0.5).
    assert m["gap_cv"] < 0.05
    assert abs(m["revisit_time_ideal_s"] - 2 * math.pi * RADIUS_M / (4 * 0.5)) < 1e-9
    # The listed ring: ahead i+1, behind i-1.
    assert team["neighbours"] == [[(i + 1) % 4, (i + 3) % 4] for i in range(4)]


def test_single_vehicle_runs_are_unchanged():
    run = isotrack.Scenario.default().set("sim.duration_s", 5.0).run()
    assert "vehicle" not in run.trace
    assert run.team is None and run.vehicles is None
    with pytest.raises(ValueError, match="not a team"):
        run.vehicle_trace(0)


class PidLaw:
    """The built-in `pid` law in Python, operation for operation (backward difference,
    rectangle-rule integral, `kd eps' + kp eps + ki integral`): floats are IEEE doubles, so it
    answers what the built-in answers, bit for bit."""

    def __init__(self, level, kp, ki, kd):
        self.level, self.kp, self.ki, self.kd = level, kp, ki, kd
        self.calls = 0
        self.reset()

    def reset(self):
        self.last = None  # (t, eps) of the derivative estimator
        self.eps_dot = 0.0
        self.last_t = None
        self.integral = 0.0

    def update(self, t_s, value):
        self.calls += 1
        eps = value - self.level
        if self.last is None:
            self.last = (t_s, eps)
            self.eps_dot = 0.0
        else:
            dt = t_s - self.last[0]
            if not (math.isnan(dt) or dt <= 0.0 or not math.isfinite(eps)):
                self.eps_dot = (eps - self.last[1]) / dt
                self.last = (t_s, eps)
        dt = 0.0 if self.last_t is None else max(t_s - self.last_t, 0.0)
        self.last_t = t_s
        if math.isfinite(eps):
            self.integral += dt * eps
        return self.kd * self.eps_dot + self.kp * eps + self.ki * self.integral


PID_GAINS = {"kp": 3.0, "ki": 0.2, "kd": 10.0}


def pid_team(duration_s=20.0):
    """short_team() flown by the built-in `pid` law (the PI-like law's linearisation: kd = kp_DY,
    kp = kp_DY c1/c2 + ki_DY, ki = ki_DY c1/c2)."""
    text = TEAM.read_text()
    head, rest = text.split("[controller]", 1)
    rest = rest[rest.index("[sim]"):]
    law = "[controller]\nkind = \"pid\"\nlevel = 10.0\n" + "".join(f"{k} = {v}\n" for k, v in PID_GAINS.items())
    s = isotrack.Scenario.from_toml(head + law + "\n" + rest)
    for k, v in [
        ("sim.duration_s", duration_s),
        ("controller.max_turn_rate_radps", 1.0),
        ("sensor.rate_hz", 10.0),
        ("sensor.noise_std", 0.01),
        ("team.ranging.noise_std_m", 0.05),
        ("team.ranging.dropout_probability", 0.2),
        ("team.ranging.delay_s", 0.2),
    ]:
        s = s.set(k, v)
    return s


def test_a_python_law_flies_the_team_as_the_builtin_law_bit_for_bit():
    sc = pid_team()
    builtin = sc.run()
    # One object: every vehicle flies its own deep copy (the object itself is not flown).
    one = PidLaw(sc.level, **PID_GAINS)
    by_copy = sc.run(controller=one)
    assert one.calls == 0
    # A list: one per vehicle, as given.
    laws = [PidLaw(sc.level, **PID_GAINS) for _ in range(4)]
    by_list = sc.run(controller=laws)
    # 10 Hz for 20 s: each vehicle's law answered its own 201 samples.
    assert [c.calls for c in laws] == [201] * 4
    for run in (by_copy, by_list):
        assert set(run.trace) == set(builtin.trace)
        for k in builtin.trace:
            assert same(run.trace[k], builtin.trace[k]), k
        assert run.team == builtin.team
        assert run.vehicles == builtin.vehicles
        assert run.summary["controller"]["kind"] == "python"
        assert run.summary["controller"]["class"].endswith("PidLaw")
    # The noisy sensors make it a real test: the vehicles' measurements differ from the truth.
    tr = builtin.trace
    assert np.nanmax(np.abs(tr["s_measured"] - tr["s"])) > 0.005


def test_a_team_controller_is_checked_and_its_error_raised():
    sc = short_team(duration_s=5.0)

    class Zero:
        def update(self, t, v):
            return 0.0

    with pytest.raises(ValueError, match="3 controllers for a team of 4"):
        sc.run(controller=[Zero(), Zero(), Zero()])
    with pytest.raises(TypeError, match=r"controller\[1\]"):
        sc.run(controller=[Zero(), object(), Zero(), Zero()])

    class Boom:
        def __init__(self):
            self.n = 0

        def update(self, t, v):
            if t >= 1.0:
                raise RuntimeError("boom at one second")
            return 0.0

    with pytest.raises(RuntimeError, match="boom at one second"):
        sc.run(controller=Boom())


class Integrating:
    """A stateful law (an integral and the last sample's time): shared by two vehicles, their
    samples would interleave through one state."""

    def __init__(self):
        self.integral, self.last, self.calls = 0.0, None, 0

    def update(self, t, v):
        self.calls += 1
        dt = 0.0 if self.last is None else t - self.last
        self.last = t
        self.integral += (v - 10.0) * dt
        return 0.1 * self.integral


def test_one_controller_listed_for_two_vehicles_is_refused():
    """att32d-4: `[obj] * 4` made four vehicles share one stateful controller (their samples
    interleaved through its integral): refused, naming the first two indices of that object,
    before anything is flown; distinct objects (and one object, deep-copied) still fly."""
    sc = short_team(duration_s=2.0)
    one = Integrating()
    with pytest.raises(ValueError, match=r"controller\[0\] and controller\[1\] are the same object"):
        sc.run(controller=[one] * 4)
    a, b, c = Integrating(), Integrating(), Integrating()
    with pytest.raises(ValueError, match=r"controller\[0\] and controller\[2\] are the same object"):
        sc.run(controller=(a, b, a, c))
    assert one.calls == a.calls == b.calls == c.calls == 0
    laws = [Integrating() for _ in range(4)]
    sc.run(controller=laws)
    # 10 Hz for 2 s: each its own 21 samples.
    assert [x.calls for x in laws] == [21] * 4


def test_a_factory_returning_one_object_for_two_vehicles_is_refused():
    """att32d-4: a controller_factory that returns one object for every vehicle of a team run
    is refused, naming the vehicles and the run; nothing of the sweep is returned."""
    one = Integrating()
    sweep = (
        f"scenario = {str(TEAM)!r}\n[base]\nsim.duration_s = 2.0\n"
        "[grid]\nteam.k_v = [0.1]\n"
    )
    with pytest.raises(ValueError, match="same object for vehicles 0 and 1 of run 0"):
        isotrack.sweep(sweep, controller_factory=lambda sc: one)
    assert one.calls == 0
    made = []

    def factory(sc):
        made.append(Integrating())
        return made[-1]

    isotrack.sweep(sweep, controller_factory=factory)
    assert len(made) == 4 and all(x.calls > 0 for x in made)


def team_sweep_text(extra=""):
    return (
        f"scenario = {str(TEAM)!r}\n[base]\nsim.duration_s = 60.0\n{extra}"
        "[grid]\nteam.spacing = [\"none\", \"range_balance\"]\nteam.count = [3, 4]\n"
    )


def test_a_team_sweep_has_the_team_columns_as_the_cli_writes_them(tmp_path):
    res = isotrack.sweep(team_sweep_text(), threads=2)
    cols = list(res)
    assert cols[-7:] == [
        "gap_cv", "time_to_even_s", "revisit_time_max_s", "revisit_time_mean_s",
        "revisit_time_ideal_s", "min_separation_m", "order_preserved",
    ]
    assert res["gap_cv"].dtype == np.float64
    assert isinstance(res["order_preserved"], np.ma.MaskedArray)
    # The ideal revisit time L / (N v0) for N = 3, 4 (from the geometry, not the engine).
    l = 2 * math.pi * RADIUS_M
    for n, ideal in zip(res["team.count"], res["revisit_time_ideal_s"]):
        assert abs(ideal - l / (n * 0.5)) < 1e-9 * ideal
    # `none` keeps the deployed cluster (0.3 rad apart): its gap CV, exactly as geometry says.
    for law, n, cv in zip(res["team.spacing"], res["team.count"], res["gap_cv"]):
        if law == "none":
            gaps = [0.3] * (n - 1) + [2 * math.pi - 0.3 * (n - 1)]
            mean = 2 * math.pi / n
            want = math.sqrt(sum((g - mean) ** 2 for g in gaps) / n) / mean
            assert abs(cv - want) < 1e-3 * want, (n, cv, want)
    # The CLI's results.csv, cell for cell.
    exe = cli()
    sw = tmp_path / "team.toml"
    sw.write_text(team_sweep_text())
    out = tmp_path / "out"
    subprocess.run([exe, "sweep", str(sw), "--out", str(out)], check=True, capture_output=True)
    import csv

    with open(out / "results.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == cols
    for i, row in enumerate(rows[1:]):
        for k, cell in zip(cols, row):
            v = res[k][i]
            if k == "order_preserved":
                assert str(bool(v)).lower() == cell
            elif res[k].dtype.kind == "f":
                assert (cell == "" and np.isnan(v)) or float(cell) == v, (k, cell, v)
            else:
                assert str(v) == cell, (k, cell, v)


def test_a_team_sweep_with_a_python_law_is_the_builtin_sweep():
    text = TEAM.read_text()
    head, rest = text.split("[controller]", 1)
    rest = rest[rest.index("[sim]"):]
    law = "[controller]\nkind = \"pid\"\nlevel = 10.0\n" + "".join(f"{k} = {v}\n" for k, v in PID_GAINS.items())
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "pid-team.toml"
        p.write_text(head + law + "\n" + rest)
        sweep = (
            f"scenario = {str(p)!r}\n[base]\nsim.duration_s = 30.0\nsensor.rate_hz = 10.0\n"
            "[grid]\nteam.spacing = [\"none\", \"range_balance\"]\n"
        )
        built = isotrack.sweep(sweep, threads=1)
        made = []

        def factory(sc):
            made.append(sc.level)
            return PidLaw(sc.level, **PID_GAINS)

        mine = isotrack.sweep(sweep, controller_factory=factory)
    # One controller per vehicle of each run.
    assert len(made) == 2 * 4
    assert list(mine) == list(built)
    for k in built:
        if k == "warnings":
            continue
        a, b = built[k], mine[k]
        if a.dtype.kind == "f":
            assert same(a, b), k
        else:
            assert list(a) == list(b), k


def test_team_run_save_is_byte_identical_to_the_cli(tmp_path):
    exe = cli()
    sets = ["sim.duration_s=40", "team.ranging.noise_std_m=0.05", "team.ranging.dropout_probability=0.1"]
    cmd = [exe, "run", str(TEAM), "--quiet", "--out", str(tmp_path / "cli")]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, capture_output=True)
    sc = isotrack.Scenario.from_file(str(TEAM))
    for s in sets:
        k, v = s.split("=")
        sc = sc.set(k, float(v))
    run = sc.run()
    run.save(tmp_path / "py")
    for f in ("trace.csv", "summary.json", "scenario.toml"):
        a = (tmp_path / "cli" / f).read_bytes()
        b = (tmp_path / "py" / f).read_bytes()
        assert a == b, f
    header = (tmp_path / "py" / "trace.csv").read_text().splitlines()[0]
    assert header.endswith(",vehicle")


def test_team_run_pickles_and_saves_again(tmp_path):
    import pickle

    run = short_team(5.0).run()
    back = pickle.loads(pickle.dumps(run))
    assert same(back.trace["vehicle"], run.trace["vehicle"])
    run.save(tmp_path / "a")
    back.save(tmp_path / "b")
    assert (tmp_path / "a" / "trace.csv").read_bytes() == (tmp_path / "b" / "trace.csv").read_bytes()


# --- The PettingZoo environment -----------------------------------------------------------------

@pytest.fixture
def ipz():
    """isotrack.pettingzoo (skipped without pettingzoo; CI installs it)."""
    pytest.importorskip("pettingzoo")
    import isotrack.pettingzoo as m

    return m


def drive_builtin(env, seed=None):
    obs, infos = env.reset(seed=seed)
    steps = 0
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: infos[a]["builtin_action"] for a in env.agents})
        steps += 1
    return steps


def test_parallel_api_test_passes(ipz):
    from pettingzoo.test import parallel_api_test

    env = ipz.parallel_env(short_team(10.0))
    parallel_api_test(env, num_cycles=200)


def test_the_builtin_laws_fed_back_fly_scenario_run_exactly(ipz):
    sc = short_team(20.0)
    env = ipz.parallel_env(sc)
    # sensor 10 Hz (10 steps), ranging 10 Hz (10 steps), delay 0.2 s (20 steps): gcd 10.
    assert env.period_steps == 10
    steps = drive_builtin(env)
    # 20 s of 0.01 s steps, 10 a step: pauses at 0 (the reset's), 10, ..., 2000: 200 steps,
    # the last reaching the run's end (t = 20 s) and truncating there, as IsolineEnv's
    # floor(D*R) (nu-17: a 201st step repeated the last observation).
    assert steps == 200
    run = sc.run()
    got = env.trace()
    assert list(got) == list(run.trace)
    for k in run.trace:
        assert same(got[k], run.trace[k]), k
    summary = env.summary()
    assert summary["vehicles"] == run.summary["vehicles"]
    assert summary["team"] == run.summary["team"]


def test_a_seed_flies_as_sim_seed_does(ipz):
    sc = short_team(10.0)
    env = ipz.parallel_env(sc)
    drive_builtin(env, seed=7)
    run = sc.set("sim.seed", 7).run()
    other = sc.run()
    for k in run.trace:
        assert same(env.trace()[k], run.trace[k]), k
    # The seed matters (noise and dropouts differ): not the scenario's own run.
    assert not same(env.trace()["s_measured"], other.trace["s_measured"])


def test_unseeded_resets_draw_new_episodes_from_the_seeded_generator(ipz):
    """att32d-8: after reset(seed=7) each plain reset() replayed the scenario's sim.seed episode.
    Now, as Gymnasium's environments: a seeded reset seeds a generator, each unseeded reset flies
    the episode of the next seed it draws (episode_seed, which sim.seed replays), and the first
    reset of all without a seed is the scenario's own run, its generator seeded with sim.seed."""
    from gymnasium.utils import seeding

    sc = short_team(3.0)
    env = ipz.parallel_env(sc)
    drive_builtin(env)
    assert env.episode_seed == 0
    first = env.trace()
    own = sc.run()
    for k in own.trace:
        assert same(first[k], own.trace[k]), k
    # The generator seeded with sim.seed = 0: the next unseeded reset draws its first number.
    drive_builtin(env)
    rng = seeding.np_random(0)[0]
    assert env.episode_seed == int(rng.integers(0, 2**63 - 1, endpoint=True))
    drive_builtin(env, seed=7)
    assert env.episode_seed == 7
    rng = seeding.np_random(7)[0]
    seeds = []
    traces = []
    for _ in range(2):
        drive_builtin(env)
        seeds.append(env.episode_seed)
        traces.append(env.trace())
    assert seeds == [int(rng.integers(0, 2**63 - 1, endpoint=True)) for _ in range(2)]
    assert len({7, *seeds}) == 3
    # Each a new episode (the noisy sensors differ), and exactly sim.seed's run.
    assert not same(traces[0]["s_measured"], traces[1]["s_measured"])
    assert not same(traces[0]["s_measured"], first["s_measured"])
    for seed, tr in zip(seeds, traces):
        run = sc.set("sim.seed", seed).run()
        for k in run.trace:
            assert same(tr[k], run.trace[k]), (seed, k)
    # The same seeded sequence of resets, the same episodes (another environment).
    other = ipz.parallel_env(sc)
    drive_builtin(other, seed=7)
    drive_builtin(other)
    assert other.episode_seed == seeds[0]


def test_the_summary_records_the_episode_seed_and_seeds_stop_at_sim_seeds_range(ipz):
    """att32d-12: the episode's summary.json recorded the base scenario's sim.seed (0) after
    reset(seed=5), and seeds up to 2**64-1 were taken that no sim.seed can replay. The summary
    now records the seed flown (its scenario the one Scenario.run() replays), and a seed past
    2**63-1 (TOML's largest integer) is a ValueError saying the range."""
    sc = short_team(3.0)
    env = ipz.parallel_env(sc)
    drive_builtin(env, seed=5)
    summary = env.summary()
    run = sc.set("sim.seed", 5).run()
    assert summary["scenario"]["sim"]["seed"] == 5
    assert summary["scenario"] == run.summary["scenario"]
    assert summary["team"] == run.summary["team"]
    for bad in (2**63, 2**64 - 1, np.uint64(2**63 + 5)):
        with pytest.raises(ValueError, match=r"0 \.\.= 2\*\*63-1"):
            env.reset(seed=bad)
    with pytest.raises(ValueError, match=r">= 0|0 \.\.="):
        env.reset(seed=-1)
    top = 2**63 - 1
    drive_builtin(env, seed=top)
    assert env.episode_seed == top
    assert env.summary()["scenario"]["sim"]["seed"] == top
    assert env.summary()["team"] == sc.set("sim.seed", top).run().summary["team"]


def test_first_observation_is_the_measured_error_and_the_true_chords(ipz):
    # Ideal ranging, no sensor noise: the first ranges are the chords of the cluster on the
    # circle, 2 R sin(0.3 / 2) to each neighbour in the cluster, the end vehicles' long way round
    # 2 R sin((2 pi - 0.9) / 2) (vehicle 0's neighbour behind is 3).
    sc = isotrack.Scenario.from_file(str(TEAM)).set("sim.duration_s", 5.0).set("controller.max_turn_rate_radps", 1.0)
    env = ipz.parallel_env(sc)
    obs, infos = env.reset()
    near = 2 * RADIUS_M * math.sin(0.15)
    far = 2 * RADIUS_M * math.sin((2 * math.pi - 0.9) / 2)
    for i in range(4):
        o = obs[f"vehicle_{i}"]
        assert o.shape == (6,) and o.dtype == np.float64
        # On the isoline: s = 10 = s_d up to rounding; deps 0 at the first sample.
        assert abs(o[0]) < 1e-12 and o[1] == 0.0
        ahead = far if i == 3 else near
        behind = far if i == 0 else near
        assert abs(o[2] - ahead) < 1e-9 and o[3] == 1.0
        assert abs(o[4] - behind) < 1e-9 and o[5] == 1.0
        assert infos[f"vehicle_{i}"]["sampled"] is True


def test_out_of_range_neighbours_read_invalid(ipz):
    sc = isotrack.Scenario.from_file(str(TEAM)).set("sim.duration_s", 5.0).set("team.ranging.max_range_m", 5.0)
    env = ipz.parallel_env(sc, max_turn_rate_radps=2.0)
    obs, _ = env.reset()
    # Vehicle 0's neighbour behind (3) is 2 R sin((2 pi - 0.9) / 2) = 6.0 m away: beyond 5 m, no
    # answer; its neighbour ahead, 2 R sin(0.15) = 2.1 m, answers.
    assert obs["vehicle_0"][4] == 0.0 and obs["vehicle_0"][5] == 0.0
    assert obs["vehicle_0"][3] == 1.0


def test_bad_actions_raise_and_step_nothing(ipz):
    env = ipz.parallel_env(short_team(5.0))
    obs, infos = env.reset()
    good = {a: infos[a]["builtin_action"] for a in env.agents}
    bad_cases = [
        (np.zeros(3), ValueError),  # wrong shape
        (np.zeros((2, 1)), ValueError),  # never reshaped
        (np.array([np.nan, 0.5]), ValueError),
        (np.array([0.0, np.inf]), ValueError),
        (np.array([1.5, 0.5]), ValueError),  # turn beyond 1 rad/s
        (np.array([0.0, 0.1]), ValueError),  # speed below v_min = 0.25
        (np.array([0.0, 0.9]), ValueError),  # speed above v_max = 0.75
        (np.array([True, False]), TypeError),
        ("0.1", TypeError),
        (None, TypeError),
    ]
    for action, err in bad_cases:
        with pytest.raises(err):
            env.step({**good, "vehicle_2": action})
    # The bounds are plain numbers (att32: not numpy reprs such as np.float64(-1.0)).
    with pytest.raises(ValueError) as e:
        env.step({**good, "vehicle_2": np.array([1.5, 0.5])})
    assert str(e.value) == (
        "vehicle_2: the action [1.5, 0.5] is outside the action space [-1.0, 1.0] rad/s x [0.25, 0.75] m/s"
    ), str(e.value)
    with pytest.raises(KeyError):
        env.step({a: v for a, v in good.items() if a != "vehicle_1"})
    with pytest.raises(KeyError):
        env.step({**good, "vehicle_9": good["vehicle_0"]})
    # Nothing was stepped: the environment still flies the built-in run exactly.
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: infos[a]["builtin_action"] for a in env.agents})
    run = short_team(5.0).run()
    for k in run.trace:
        assert same(env.trace()[k], run.trace[k]), k
    # A float32 sample of the action space is always accepted (its rounded bounds included).
    env.reset()
    space = env.action_space("vehicle_0")
    env.step({a: space.high.copy() for a in env.agents})
    env.step({a: space.low.copy() for a in env.agents})


def test_deterministic_with_seeds(ipz):
    def episode():
        env = ipz.parallel_env(short_team(5.0))
        rng = np.random.default_rng(3)
        obs, _ = env.reset(seed=11)
        out = [np.stack([obs[a] for a in sorted(obs)])]
        while env.agents:
            acts = {a: np.array([rng.uniform(-0.3, 0.3), rng.uniform(0.3, 0.7)]) for a in env.agents}
            obs, rew, term, trunc, _ = env.step(acts)
            out.append(np.stack([obs[a] for a in sorted(obs)]))
            out.append(np.array([rew[a] for a in sorted(rew)]))
        return out

    a, b = episode(), episode()
    assert len(a) == len(b)
    assert all(same(x, y) for x, y in zip(a, b))


def test_speed_actions_set_the_speed(ipz):
    # Every robot commanded to v_max: each covers v_max * dt per step (the Dubins kinematics), so
    # over the run the path is v_max * duration for all, whatever the spacing law says.
    sc = isotrack.Scenario.from_file(str(TEAM)).set("sim.duration_s", 10.0).set("controller.max_turn_rate_radps", 1.0)
    env = ipz.parallel_env(sc)
    obs, infos = env.reset()
    while env.agents:
        obs, rew, term, trunc, infos = env.step(
            {a: np.array([infos[a]["builtin_action"][0], 0.75]) for a in env.agents}
        )
    # (The path sums each step's chord: shorter than the arc by a relative (omega dt)^2 / 24.)
    for v in env.summary()["vehicles"]:
        assert abs(v["path_length_m"] / (0.75 * 10.0) - 1.0) < 1e-6


def test_rewards_are_the_documented_sum(ipz):
    # Ideal sensor on the isoline, zero turn command at the first step: the reward is the
    # spacing imbalance only, ((d_a - d_b) / (d_a + d_b))^2 times the weight, plus the tracking
    # error after one step (tiny) and no effort. Vehicle 1 is in the middle of the cluster:
    # balanced (0); vehicle 0 has the far neighbour behind.
    sc = isotrack.Scenario.from_file(str(TEAM)).set("sim.duration_s", 5.0).set("controller.max_turn_rate_radps", 1.0)
    env = ipz.parallel_env(sc, spacing_weight=2.0, effort_weight=0.0)
    obs, infos = env.reset()
    obs, rew, *_ = env.step({a: np.array([0.0, 0.5]) for a in env.agents})
    assert abs(rew["vehicle_1"]) < 1e-3
    near = 2 * RADIUS_M * math.sin(0.15)
    far = 2 * RADIUS_M * math.sin((2 * math.pi - 0.9) / 2)
    expected = -2.0 * ((near - far) / (near + far)) ** 2
    assert abs(rew["vehicle_0"] - expected) < 2e-3


def test_a_scenario_without_a_team_is_refused(ipz):
    with pytest.raises(ValueError, match="team"):
        ipz.parallel_env(isotrack.Scenario.default())
    with pytest.raises(ValueError, match="discovered"):
        ipz.parallel_env(isotrack.Scenario.from_file(str(TEAM)).set("team.ring", "discovered").set("sim.duration_s", 400.0))


def test_ctrl_c_stops_a_long_team_run():
    """A SIGINT 0.3 s into a team run that takes seconds is answered within 2 s (the run
    finishes on its own thread, its answer dropped)."""
    import signal
    import threading
    import time

    sc = isotrack.Scenario.from_file(str(TEAM)).set("sim.duration_s", 30000.0).set("output.record_rate_hz", 0.0)
    t0 = time.monotonic()
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sc.run()
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 2.0


def test_an_agent_that_leaves_the_field_is_terminated_and_removed(ipz):
    # The kriged NO2 map of Fig. 2(a): a grid over x in [-24, 24] m, y in [-21, 21] m. Vehicle 0
    # starts 1 m below its top edge heading out at v_max = 2 v0 = 1 m/s: it leaves the field
    # after about 1 s; vehicle 1 starts at the centre heading +x and flies the 10 s out.
    text = (ROOT / "scenarios" / "paper-fig2a-field.toml").read_text()
    text = text.replace('path = "../data/', f'path = "{ROOT}/data/')
    text = text.replace("duration_s = 600.0", "duration_s = 10.0")
    text += (
        "\n[team]\ncount = 2\nspacing = \"none\"\n"
        "starts = [{x_m = 0.0, y_m = 20.0, heading_rad = 1.5707963267948966},"
        " {x_m = 0.0, y_m = 0.0, heading_rad = 0.0}]\n"
    )
    sc = isotrack.Scenario.from_toml(text).set("controller.max_turn_rate_radps", 1.0)
    env = ipz.parallel_env(sc)
    obs, infos = env.reset()
    ended = {}
    steps = 0
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: np.array([0.0, 1.0]) for a in env.agents})
        steps += 1
        for a in term:
            if term[a] or trunc[a]:
                ended[a] = ("terminated" if term[a] else "truncated", steps)
                assert a not in env.agents
    assert ended["vehicle_0"][0] == "terminated"
    assert ended["vehicle_1"] == ("truncated", steps)
    v = env.summary()["vehicles"]
    assert v[0]["outcome"] == "left_field" and v[1]["outcome"] == "completed"
    assert 0.9 < v[0]["t_end_s"] < 1.1, v[0]["t_end_s"]
    with pytest.raises(ValueError, match="no agent is live"):
        env.step({})


def test_reward_settings_keep_an_episode_finite(ipz):
    """att30c-15: the team environment bounds its reward settings by the Gymnasium envs' one
    rule (every agent's reward over every step of the episode stays below 1e300): the settings
    that summed to -inf or -1e302 are refused by name, a subnormal scale says so; at the bound
    an episode's rewards are finite."""
    sc = short_team(duration_s=5.0)
    for kw, match in [
        ({"error_scale": 2.3e-308}, "error_scale must be at least"),
        ({"error_scale": 1e-300}, "error_scale must be at least"),
        ({"spacing_weight": 1.7e308}, "spacing_weight must be at most"),
        ({"spacing_weight": 1e300}, "spacing_weight must be at most"),
        ({"effort_weight": 1e300}, "effort_weight must be at most"),
        ({"error_scale": 5e-324}, "not subnormal"),
        ({"spacing_weight": 5e-324}, "not subnormal"),
    ]:
        with pytest.raises(ValueError, match=match):
            ipz.parallel_env(sc, **kw)
    # 5 s at 0.01 s: 501 steps x 4 agents; the largest weight allowed is 1e300 / 2004.
    w = 1e300 / (501 * 4)
    env = ipz.parallel_env(sc, spacing_weight=w * 0.999, effort_weight=w * 0.999)
    obs, infos = env.reset(seed=1)
    total = 0.0
    while env.agents:
        actions = {a: infos[a]["builtin_action"] for a in env.agents}
        obs, rewards, term, trunc, infos = env.step(actions)
        total += sum(rewards.values())
    assert math.isfinite(total)


@pytest.mark.parametrize("count", [4, 1])
def test_the_summary_comes_when_every_vehicle_leaves_the_field(ipz, count):
    """att30n-5: an episode in which every vehicle leaves the field before sim.duration_s ends
    (no agent left) but `summary()` stayed None. The domain cuts the level-10 circle at x = 6 m
    (R = 6.93 m): every vehicle, flying the built-in laws, leaves there, the last well before
    20 s. The summary is then `Scenario.run()`'s, every vehicle `left_field`."""
    spread = {
        "along": "arc",
        "center_m": [0.0, 0.0],
        "radius_m": RADIUS_M,
        "start_rad": math.pi / 2,
        "step_rad": 0.3,
        "clockwise": True,
    }
    sc = (
        isotrack.Scenario.from_file(str(TEAM))
        .set(
            {
                "sim.duration_s": 20.0,
                "field.domain_m": [-20.0, 6.0, -20.0, 20.0],
                "initial.x_m": 0.0,
                "controller.max_turn_rate_radps": 1.0,
                "team.spread": spread,
            }
        )
        .set("team.count", count)
    )
    run = sc.run()
    assert [v["outcome"] for v in run.summary["vehicles"]] == ["left_field"] * count
    assert run.summary["t_end_s"] < 19.0
    env = ipz.parallel_env(sc)
    steps = drive_builtin(env)
    assert env.agents == []
    summary = env.summary()
    assert summary is not None
    assert summary["vehicles"] == run.summary["vehicles"]
    # att36-3: the team metrics too (the level-10 circle cut by the domain is an open
    # isoline: the environment said the field had none) and the scenario's file.
    assert summary["team"] == run.summary["team"]
    assert summary["team"].get("isoline_length_m") is not None
    got = env.trace()
    for k in run.trace:
        assert same(got[k], run.trace[k]), k
    # The episode ends at the last vehicle's end, within a step.
    step_s = env.period_steps * 0.01  # sim.dt_s = 0.01 s
    assert abs(steps * step_s - max(v["t_end_s"] for v in run.summary["vehicles"])) <= step_s + 1e-9


@pytest.mark.parametrize("duration_s", [1.05, 1.01, 1.09, 1.0])
@pytest.mark.parametrize("count", [1, 2])
def test_a_duration_off_the_step_takes_isoline_envs_count(ipz, duration_s, count):
    """att30n-6: with sim.duration_s no multiple of the environment's step (0.1 s: sensor
    10 Hz, ranging 5 Hz), the team environment took one step more than IsolineEnv's
    floor(D * R) = 10, the last repeating the observation at t = 1.0 s as `sampled`. Now 10
    steps, the last at the last sample (t = 1.0 s) truncating; the run still flies to
    sim.duration_s with the last commands held: trace and summary are `Scenario.run()`'s."""
    sc = isotrack.Scenario.from_file(str(TEAM)).set(
        {
            "sim.duration_s": duration_s,
            "sensor.rate_hz": 10.0,
            "team.ranging": {"rate_hz": 5.0},
            "controller.max_turn_rate_radps": 1.0,
            "team.count": count,
        }
    )
    env = ipz.parallel_env(sc)
    obs, infos = env.reset()
    seen = []
    while env.agents:
        obs, rew, term, trunc, infos = env.step({a: infos[a]["builtin_action"] for a in env.agents})
        seen.append((infos["vehicle_0"]["t_s"], infos["vehicle_0"]["sampled"], term["vehicle_0"], trunc["vehicle_0"]))
    assert len(seen) == math.floor(duration_s * 10.0 + 1e-9) == 10
    t_last, sampled, term, trunc = seen[-1]
    assert abs(t_last - 1.0) < 1e-9 and sampled and trunc and not term
    run = sc.run()
    got = env.trace()
    for k in run.trace:
        assert same(got[k], run.trace[k]), k
    assert env.summary()["vehicles"] == run.summary["vehicles"]
    assert env.summary()["team"] == run.summary["team"]


@pytest.mark.parametrize("duration_s", [1.05, 3.05])
def test_a_duration_off_the_step_flies_the_laws_tail(ipz, duration_s):
    """nu36-19: with sim.duration_s no multiple of the environment's step (0.1 s: sensor and
    ranging at 10 Hz) and a seeded noisy episode, the built-in actions fed back flew another
    tail than Scenario.run() (the agents' speeds of the pause before held after the last
    pause, where the spacing laws answer): vehicles 1 and 2 ended 0.1 mm off, gap_cv differed
    in the 9th digit. The tail is the laws' now: the same run bit for bit."""
    sc = isotrack.Scenario.from_file(str(TEAM)).set(
        {"sim.duration_s": duration_s, "controller.max_turn_rate_radps": 1.0, "sensor.rate_hz": 10.0}
    )
    env = ipz.parallel_env(sc)
    drive_builtin(env, seed=0)
    run = sc.set("sim.seed", 0).run()
    got = env.trace()
    for k in run.trace:
        assert same(got[k], run.trace[k]), k
    assert env.summary()["vehicles"] == run.summary["vehicles"]
    assert env.summary()["team"] == run.summary["team"]


def test_the_environment_measures_along_a_grid_isoline_as_the_run_does(ipz):
    """att36-3: the environment built its team metrics on the circle of a radial field only:
    along a grid's isoline (the kriged NO2 map, marching squares) the summary said "the field
    has no isoline", where Scenario.run() measures along it."""
    text = (ROOT / "scenarios" / "paper-fig2a-field.toml").read_text()
    text = text.replace('path = "../data/', f'path = "{ROOT}/data/')
    text = text.replace("duration_s = 600.0", "duration_s = 8.0")
    text += (
        "\n[team]\nstarts = [{x_m = 0.0, y_m = 0.0, heading_rad = 0.0},"
        " {x_m = 2.0, y_m = 1.0, heading_rad = 1.0}]\n"
    )
    sc = isotrack.Scenario.from_toml(text).set("controller.max_turn_rate_radps", 1.0)
    run = sc.run()
    assert run.summary["team"].get("gap_cv") is not None or run.summary["team"].get("isoline_length_m") is not None
    env = ipz.parallel_env(sc)
    drive_builtin(env)
    assert env.summary()["team"] == run.summary["team"]


def test_the_summary_names_the_scenario_file(ipz):
    """att36-3 (its MINOR): the environment's summary had no scenario_path where
    Scenario.from_file(F).run()'s names F."""
    sc = isotrack.Scenario.from_file(str(TEAM)).set(
        {"sim.duration_s": 1.0, "controller.max_turn_rate_radps": 1.0}
    )
    env = ipz.parallel_env(sc)
    drive_builtin(env)
    assert env.summary()["scenario_path"] == sc.run().summary["scenario_path"]
    assert env.summary()["scenario_path"] is not None


def test_leaving_the_field_never_pays(ipz):
    """nu36-5: the step that ended an agent off the field read a tracking term of 0 and no
    penalty, so an agent far from the isoline did best by leaving at once. Now the terminating
    step keeps the agent's last tracking term and pays (10 + spacing_weight + effort_weight)
    per environment step left (the single-vehicle environment's rule), or the penalty given."""
    sc = isotrack.Scenario.from_file(str(TEAM)).set(
        {
            "sim.duration_s": 30.0,
            "controller.max_turn_rate_radps": 1.0,
            "sensor.rate_hz": 10.0,
            "field.domain_m": [-10.0, 10.0, -10.0, 10.0],
        }
    )
    for given in [None, 0.0, 123.0]:
        kw = {} if given is None else {"termination_penalty": given}
        env = ipz.parallel_env(sc, **kw)
        obs, infos = env.reset(seed=0)
        rewards = {a: [] for a in env.agents}
        ended = {}
        steps = 0
        while env.agents:
            # Straight out at top speed (v_max 0.75 m/s): every vehicle leaves the 20 m box.
            obs, rew, term, trunc, infos = env.step({a: np.array([0.0, 0.75]) for a in env.agents})
            steps += 1
            for a, r in rew.items():
                rewards[a].append(r)
                if term[a]:
                    ended[a] = steps
        assert sorted(ended) == sorted(rewards), ended
        period_s = env.period_steps * 0.01
        n_pauses = round(30.0 / period_s)
        for a, rs in rewards.items():
            before, last = rs[-2], rs[-1]
            # Flying out, the tracking term grows: the last step's own terms (tracking at
            # the last true value, spacing <= 1, effort 0 for a zero turn rate) lie within
            # one step's change of the step before's.
            pauses_left = n_pauses - ended[a]
            penalty = (10.0 + 1.0 + 0.01) * pauses_left if given is None else given
            own = last + penalty
            assert before - 1.0 - 0.5 <= own <= 0.0, (a, before, last, penalty)
            assert own <= -1.0, (a, own)  # the tracking term is kept, not 0
            if given is None:
                # Never better than flying on with the worst capped step to the end.
                assert sum(rs) <= -(10.0 + 1.0 + 0.01) * pauses_left


def test_a_scenario_whose_data_file_changed_is_not_run(tmp_path):
    """att36-10: Scenario.run() after the scenario's data file changed on disk flew the field
    read when the scenario was made but named the new file's SHA-256 in summary.json: a run
    directory whose provenance was false. It raises now, as unpickling does."""
    data = ROOT / "data" / "no2_germany_kriged" / "no2_germany_kriged.csv"
    (tmp_path / "field.csv").write_bytes(data.read_bytes())
    text = (ROOT / "scenarios" / "paper-fig2a-field.toml").read_text()
    text = text.replace('path = "../data/no2_germany_kriged/no2_germany_kriged.csv"', 'path = "field.csv"')
    text = text.replace("duration_s = 600.0", "duration_s = 2.0")
    (tmp_path / "s.toml").write_text(text)
    sc = isotrack.Scenario.from_file(str(tmp_path / "s.toml"))
    first = sc.run()
    digest = first.summary["data_files"][str(tmp_path / "field.csv")]
    lines = (tmp_path / "field.csv").read_text().splitlines(keepends=True)
    (tmp_path / "field.csv").write_text("".join(lines) + "\n")
    with pytest.raises(ValueError, match="changed since the scenario was made"):
        sc.run()
    # Made again, it flies the file as it is now and names that file's digest.
    again = isotrack.Scenario.from_file(str(tmp_path / "s.toml")).run()
    assert again.summary["data_files"][str(tmp_path / "field.csv")] != digest


def test_an_edit_keeping_size_and_modification_time_is_not_run(tmp_path):
    """att40-9: the digest cache behind the check before a run was keyed on the path, the size
    and the modification time, so an edit of the same size with the modification time set back
    (``touch -r``, a tool restoring times) was taken for the file hashed before and the old
    field flew under the edited file's name. Every write sets the status-change time, which is
    in the key now."""
    import time

    data = ROOT / "data" / "no2_germany_kriged" / "no2_germany_kriged.csv"
    field = tmp_path / "field.csv"
    field.write_bytes(data.read_bytes())
    text = (ROOT / "scenarios" / "paper-fig2a-field.toml").read_text()
    text = text.replace('path = "../data/no2_germany_kriged/no2_germany_kriged.csv"', 'path = "field.csv"')
    text = text.replace("duration_s = 600.0", "duration_s = 2.0")
    (tmp_path / "s.toml").write_text(text)
    sc = isotrack.Scenario.from_file(str(tmp_path / "s.toml"))
    sc.run()  # the file hashed and cached
    before = os.stat(field)
    time.sleep(0.05)  # past the kernel's coarse timestamp tick
    raw = bytearray(field.read_bytes())
    at = max(i for i, b in enumerate(raw) if chr(b).isdigit())
    raw[at] = ord("1") if raw[at] != ord("1") else ord("2")
    field.write_bytes(bytes(raw))
    os.utime(field, ns=(before.st_atime_ns, before.st_mtime_ns))
    after = os.stat(field)
    assert (after.st_size, after.st_mtime_ns) == (before.st_size, before.st_mtime_ns)
    with pytest.raises(ValueError, match="changed since the scenario was made"):
        sc.run()


def _volcano_copy(tmp_path):
    """volcano.toml with its data file copied into tmp_path (the scenario reads the copy)."""
    shutil.copy(ROOT / "data" / "volcano" / "volcano.csv", tmp_path / "volcano.csv")
    text = (ROOT / "scenarios" / "volcano.toml").read_text()
    text = re.sub(r'path = "[^"]*volcano\.csv"', 'path = "volcano.csv"', text)
    (tmp_path / "volcano.toml").write_text(text)
    return tmp_path / "volcano.csv"


def _edit(path):
    text = path.read_text()
    path.write_text(text.replace("13", "19"))


def test_a_scenario_set_from_one_whose_data_file_changed_is_not_run(tmp_path):
    """att39-5: ``sc.set(KEY, V).run()`` (the README's idiom) after the data file changed flew
    the field ``sc`` had read (the old one) and named the new file's SHA-256: ``set`` took its
    digests from the file as it is now. A scenario set from another carries the digests of the
    field it flies; one that reads its files again takes theirs."""
    csv = _volcano_copy(tmp_path)
    sc = isotrack.Scenario.from_file(str(tmp_path / "volcano.toml")).set("sim.duration_s", 5.0)
    old = sc.run().summary["data_files"][str(csv)]
    _edit(csv)
    for derived in (sc.set("controller.kp", 5.0), sc.set({"sim.duration_s": 4.0}), sc.set("sim.seed", 3)):
        with pytest.raises(ValueError, match="changed since the scenario was made"):
            derived.run()
    # Read again (its own file): it flies the file as it is now and names that digest.
    fresh = isotrack.Scenario.from_file(str(tmp_path / "volcano.toml")).set("sim.duration_s", 5.0).run()
    assert fresh.summary["data_files"][str(csv)] != old


def test_a_time_series_whose_file_changed_is_not_run(tmp_path):
    """att39-11: the data files of a grid time series (``field.paths``, a list) were never
    checked: a run after one of them changed flew the old frames and named the new digest."""
    csv = _volcano_copy(tmp_path)
    shutil.copy(csv, tmp_path / "v2.csv")
    text = (tmp_path / "volcano.toml").read_text()
    text = text.replace('path = "volcano.csv"', 'paths = ["volcano.csv", "v2.csv"]\nframe_times_s = [0.0, 100.0]')
    (tmp_path / "ts.toml").write_text(text)
    sc = isotrack.Scenario.from_file(str(tmp_path / "ts.toml")).set("sim.duration_s", 5.0)
    assert sorted(sc._digests) == sorted([str(csv), str(tmp_path / "v2.csv")])
    sc.run()
    _edit(tmp_path / "v2.csv")
    with pytest.raises(ValueError, match="v2.csv: the scenario's data file changed"):
        sc.run()


def test_the_team_env_refuses_a_data_file_changed_since_the_scenario(tmp_path, ipz):
    """att39-5: the PettingZoo team env flew the field its scenario had read and its summary
    named the changed file's digest. reset() raises as Scenario.run() does."""
    csv = _volcano_copy(tmp_path)
    down = -math.pi / 2
    sc = isotrack.Scenario.from_file(str(tmp_path / "volcano.toml")).set(
        {
            "sim.duration_s": 4.0,
            "controller.max_turn_rate_radps": 1.0,
            "team.starts": [{"x_m": 300.0, "y_m": 700.0 - 50.0 * i, "heading_rad": down} for i in range(3)],
        }
    )
    env = ipz.parallel_env(sc)
    env.reset(seed=1)
    _edit(csv)
    with pytest.raises(ValueError, match="changed since the scenario was made"):
        env.reset(seed=1)


@pytest.mark.parametrize("error_scale", [None, 0.1])
def test_leaving_never_pays_for_an_agent_that_cannot_track(ipz, error_scale):
    """att39-10: the tracking term was uncapped (the cap of 10 error scales was in the default
    penalty only), so an agent that could not hold its error under 10 error scales (here: a
    0.5-m level circle a 2.5-m turn radius cannot fly, error_scale 0.1) scored better by flying
    straight out of the field than by flying on. With the term capped at 10 (every step's
    reward >= -(10 + spacing_weight + effort_weight)), the penalty bounds flying on."""
    base = isotrack.Scenario.from_file(str(TEAM)).set(
        {
            "controller.max_turn_rate_radps": 0.2,
            "controller.level": 19.0,
            "sim.duration_s": 60.0,
            "field.domain_m": [-7.5, 7.5, -7.5, 7.5],
        }
    )

    def episode(leave):
        env = ipz.parallel_env(base, error_scale=error_scale)
        obs, infos = env.reset(seed=0)
        total, left, worst = 0.0, False, 0.0
        while env.agents:
            acts = {a: infos[a]["builtin_action"] for a in env.agents}
            if leave and "vehicle_0" in acts:
                acts["vehicle_0"] = np.array([0.0, env.action_space("vehicle_0").high[1]], np.float32)
            obs, rw, te, tr, infos = env.step(acts)
            if "vehicle_0" in rw:
                total += rw["vehicle_0"]
                if te["vehicle_0"]:
                    left = True
                else:
                    worst = min(worst, rw["vehicle_0"])
        return total, left, worst

    stay, stay_left, worst = episode(False)
    go, go_left = episode(True)[:2]
    assert not stay_left and go_left
    assert worst >= -(10.0 + 1.0 + 0.01) - 1e-12, worst
    assert go < stay, (go, stay)
