"""The Gymnasium environments: Gymnasium's own checker, the environment against Scenario.run
(bit for bit), the vector environment against single environments, resets, ends and rewards."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")
from gymnasium.utils.env_checker import check_env  # noqa: E402

import isotrack  # noqa: E402
from isotrack.gym import IsolineEnv, IsolineVectorEnv  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
LEVEL = 10.0


class PaperLaw:
    """The paper's PI-like law on the observation: e = deps + c1*tanh(eps/c2), omega = kp*e +
    ki*sigma (sigma by the rectangle rule over the sample period), the default gains."""

    def __init__(self, period_s=0.01, kp=10.0, ki=1.0, c1=0.2, c2=1.0):
        self.period_s, self.kp, self.ki, self.c1, self.c2 = period_s, kp, ki, c1, c2
        self.sigma = 0.0

    def act(self, eps, deps):
        e = deps + self.c1 * math.tanh(eps / self.c2)
        self.sigma += e * self.period_s
        return self.kp * e + self.ki * self.sigma


class PaperController:
    """The same law as a controller for Scenario.run: it forms the observation the environment
    gives (eps = value - s_d, its backward difference) and answers with the same arithmetic."""

    def __init__(self):
        self.law = PaperLaw()
        self.prev = None

    def update(self, t_s, value):
        eps = value - LEVEL
        deps = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
        self.prev = (t_s, eps)
        return self.law.act(eps, deps)


def test_gymnasium_env_checker_passes():
    env = IsolineEnv()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # unbounded observation, non-normalised action: by design
        check_env(env)
    made = gymnasium.make("isotrack/Isoline-v0", scenario=isotrack.Scenario.default())
    assert made.spec.id == "isotrack/Isoline-v0"
    assert made.unwrapped.action_space.high[0] == 1.0  # no limit in the scenario: 1 rad/s
    vec = gymnasium.make_vec("isotrack/Isoline-v0", num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(vec.unwrapped, IsolineVectorEnv) and vec.num_envs == 3


def test_env_answered_by_the_paper_law_is_scenario_run():
    """From the scenario's own start, the environment answered by the paper's law is the run that
    Scenario.run gives with the same law in the loop: the same outcome, step count, samples
    and every metric, bit for bit; its steady error is the paper's (below 1e-9)."""
    sc = isotrack.Scenario.default()
    env = IsolineEnv(sc, max_turn_rate_radps=1e9)  # no clipping: the scenario has no limit
    obs, info = env.reset(seed=0, options={"start": "scenario"})
    assert info["start"] == (10.0, 0.0, -math.pi / 2)
    law = PaperLaw()
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step([law.act(obs[0], obs[1])])
        steps += 1
        if terminated or truncated:
            break
    assert truncated and not terminated and info["outcome"] == "completed"
    assert steps == 60_001  # one step answers each sample, t = 0 ... 600 s at 100 Hz
    want = sc.run(controller=PaperController()).summary
    for key, value in info["result"].items():
        assert want[key] == value, key
    assert want["steady_state_max_abs_error"] < 1e-9


def test_reward_is_the_documented_formula():
    """Reward = -|eps|/c2 - 0.01*(omega/omega_max)^2 with eps the true error at the new sample: on
    a noise-free sensor the true error is the observation."""
    sc = isotrack.Scenario.default().set("controller.c2", 2.0)
    env = IsolineEnv(sc, max_turn_rate_radps=0.5)
    env.reset(seed=3)
    for omega in (0.1, -0.3, 2.0):  # 2.0 clips to 0.5
        obs, reward, *_ = env.step([omega])
        applied = max(-0.5, min(0.5, omega))
        assert reward == pytest.approx(-abs(obs[0]) / 2.0 - 0.01 * (applied / 0.5) ** 2, rel=1e-12)


def test_reset_is_reproducible_and_within_the_documented_bounds():
    sc = isotrack.Scenario.default()
    env = IsolineEnv(sc, start_radius_m=2.0)
    a = [env.reset(seed=s) for s in (5, 5, 6)]
    assert np.array_equal(a[0][0], a[1][0]) and a[0][1]["start"] == a[1][1]["start"]
    assert a[0][1]["start"] != a[2][1]["start"]
    starts = np.array([env.reset(seed=s)[1]["start"] for s in range(400)])
    r = np.hypot(starts[:, 0] - 10.0, starts[:, 1])
    assert r.max() <= 2.0 and r.max() > 1.9  # the whole disc is reached
    # Uniform in the disc: the share within half the radius is 1/4 (binomial, 4 sd).
    assert abs(np.mean(r < 1.0) - 0.25) < 4 * math.sqrt(0.25 * 0.75 / 400)
    assert starts[:, 2].min() < -3.0 and starts[:, 2].max() > 3.0  # headings over [-pi, pi)
    # The first observation is the error at the start: F(d) - s_d on the circular field.
    obs, info = env.reset(seed=9)
    x, y, _ = info["start"]
    assert obs[0] == pytest.approx(20 * math.exp(-0.1 * math.hypot(x, y)) - LEVEL, abs=1e-12)
    assert obs[1] == 0.0
    fixed = env.reset(seed=1, options={"start": (3.0, 4.0, 0.0)})
    assert fixed[1]["start"] == (3.0, 4.0, 0.0)
    assert fixed[0][0] == pytest.approx(20 * math.exp(-0.5) - LEVEL, abs=1e-12)
    # The default disc: 1 % of the distance flown in the run (0.5 m/s x 600 s).
    assert IsolineEnv(sc)._starts.radius_m == pytest.approx(3.0)


def test_leaving_the_field_terminates_with_the_penalty():
    """Straight ahead (omega = 0) the volcano robot leaves the DEM: terminated, `left_field`,
    and the step pays the documented penalty (10 + 0.01 per sample left)."""
    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "volcano.toml"))
    env = IsolineEnv(sc)
    env.reset(seed=0, options={"start": "scenario"})
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step([0.0])
        steps += 1
        if terminated or truncated:
            break
    assert terminated and not truncated and info["outcome"] == "left_field"
    samples_per_run = 3000.0 * 10 + 1
    left = samples_per_run - (steps + 1)  # the reset delivered the first sample
    assert reward < -(10.0 + 0.01) * left * 0.999
    with pytest.raises(RuntimeError, match="reset"):
        env.step([0.0])


def test_non_finite_action_diverges():
    env = IsolineEnv()
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step([float("nan")])
    assert terminated and info["outcome"] == "diverged"


def test_vector_env_equals_single_envs():
    """Sub-environment i of the vector environment reset with seed s is the single environment
    reset with s + i: the same observations, rewards, flags and autoresets, step for step, with
    a noisy sensor and runs that end early (a NaN command) and at their duration."""
    sc = isotrack.Scenario.default().set("sim.duration_s", 1.0).set("sensor.noise_std", 0.01)
    n, seed, steps = 4, 123, 260
    vec = IsolineVectorEnv(sc, num_envs=n)
    singles = [IsolineEnv(sc) for _ in range(n)]
    vobs, vinfo = vec.reset(seed=seed)
    sobs = []
    for i, e in enumerate(singles):
        o, info = e.reset(seed=seed + i)
        sobs.append(o)
        assert tuple(vinfo["start"][i]) == info["start"]
    assert np.array_equal(vobs, np.array(sobs))
    laws = [PaperLaw() for _ in range(n)]
    ended = [False] * n
    seen_ends = set()
    for k in range(steps):
        actions = np.array([[laws[i].act(*vobs[i])] for i in range(n)])
        if k == 30:
            actions[2, 0] = np.nan  # env 2 diverges
        vobs, vrew, vterm, vtrunc, vinfo = vec.step(actions)
        for i, e in enumerate(singles):
            if ended[i]:  # next-step autoreset: the vector env reset it now
                o, info = e.reset()
                laws[i] = PaperLaw()
                assert np.array_equal(vobs[i], o) and vrew[i] == 0.0 and not vterm[i] and not vtrunc[i]
                assert tuple(vinfo["start"][i]) == info["start"]
                ended[i] = False
                continue
            o, r, term, trunc, info = e.step(actions[i])
            assert np.array_equal(vobs[i], o), (k, i)
            assert vrew[i] == r and vterm[i] == term and vtrunc[i] == trunc, (k, i)
            if term or trunc:
                ended[i] = True
                seen_ends.add(info["outcome"])
                assert vinfo["outcome"][i] == info["outcome"] and vinfo["_outcome"][i]
                assert vinfo["result"][i] == info["result"]
        if ended[2] and k == 30:
            laws[2] = PaperLaw()
    assert seen_ends == {"completed", "diverged"}


def test_vector_env_seeds_and_spaces():
    vec = IsolineVectorEnv(num_envs=5)
    assert vec.action_space.shape == (5, 1) and vec.observation_space.shape == (5, 2)
    a, _ = vec.reset(seed=[1, 2, 3, 4, 5])
    b, _ = vec.reset(seed=1)
    assert np.array_equal(a, b)
    assert len({tuple(o) for o in a}) == 5  # different seeds, different starts
    with pytest.raises(ValueError, match="expected 5 seeds"):
        vec.reset(seed=[1, 2])
    with pytest.raises(ValueError, match="num_envs"):
        IsolineVectorEnv(num_envs=0)
    with pytest.raises(RuntimeError, match="reset"):
        IsolineVectorEnv(num_envs=2).step(np.zeros((2, 1)))


def test_bad_arguments_raise_clearly():
    with pytest.raises(ValueError, match="start_radius_m"):
        IsolineEnv(start_radius_m=-1.0)
    with pytest.raises(ValueError, match="error_scale"):
        IsolineEnv(error_scale=0.0)
    with pytest.raises(TypeError, match="isotrack.Scenario"):
        IsolineEnv(scenario="default")
    env = IsolineEnv()
    with pytest.raises(ValueError, match="start"):
        env.reset(options={"start": "elsewhere"})


def test_scenario_pickles_for_worker_processes():
    """Gymnasium copies an environment's arguments and AsyncVectorEnv pickles them: a scenario
    survives both as the same scenario (its resolved TOML, absolute file paths)."""
    import copy
    import pickle

    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "volcano.toml")).set("sim.duration_s", 10.0)
    back = pickle.loads(pickle.dumps(sc))
    assert back == sc and copy.deepcopy(sc) is sc
    assert back.run().summary["end_position_m"] == sc.run().summary["end_position_m"]
