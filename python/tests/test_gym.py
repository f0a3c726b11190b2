"""The Gymnasium environments: Gymnasium's own checker, the environment against Scenario.run
(bit for bit), the vector environment against single environments, resets, ends and rewards."""

import math
import os
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
    gives (eps = value - s_d, its backward difference) and answers with the same arithmetic. The
    run's last sample (at `last_t_s`) ends the episode before an agent can answer it, and the
    environment holds the command over that step: so does this controller."""

    def __init__(self, last_t_s):
        self.law = PaperLaw()
        self.prev = None
        self.last_t_s = last_t_s
        self.omega = None

    def update(self, t_s, value):
        if t_s == self.last_t_s:
            return self.omega
        eps = value - LEVEL
        deps = 0.0 if self.prev is None else (eps - self.prev[1]) / (t_s - self.prev[0])
        self.prev = (t_s, eps)
        self.omega = self.law.act(eps, deps)
        return self.omega


def checker_warnings(env):
    """The warnings Gymnasium's `check_env` gives for `env` (every render mode included; without
    matplotlib, which `"human"` needs, the render checks are skipped)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        skip_render_check = False
    except ImportError:
        skip_render_check = True
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=skip_render_check)
    return sorted({str(w.message) for w in caught})


def test_gymnasium_env_checker_passes():
    """`check_env` passes on the environment made through Gymnasium (so that it also renders in
    both declared modes); its only warnings are the two unbounded observation limits, and none
    at all where the sensor's range bounds the observation."""
    made = gymnasium.make("isotrack/Isoline-v0", scenario=isotrack.Scenario.default())
    assert made.spec.id == "isotrack/Isoline-v0"
    assert made.unwrapped.action_space.high[0] == 1.0  # no limit in the scenario: 1 rad/s
    assert made.unwrapped.action_space.dtype == np.float32
    assert made.unwrapped.metadata["render_fps"] == 100.0  # one step per sample at 100 Hz
    found = checker_warnings(made.unwrapped)
    assert len(found) == 2 and all("observation space" in w and "infinity" in w for w in found), found
    ranged = isotrack.Scenario.default().set("sensor.range", [5.0, 15.0])
    made = gymnasium.make("isotrack/Isoline-v0", scenario=ranged)
    assert checker_warnings(made.unwrapped) == []
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
    assert steps == 60_000  # samples at t = 0 ... 600 s at 100 Hz: the reset gives the first
    assert info["t_s"] == 600.0
    want = sc.run(controller=PaperController(last_t_s=600.0)).summary
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
    assert left > 0  # it left the field before the end
    assert reward < -(10.0 + 0.01) * left * 0.999
    with pytest.raises(RuntimeError, match="reset"):
        env.step([0.0])


def test_non_finite_action_raises():
    """Gymnasium's convention: an invalid action raises (it once ended the run as `diverged`)."""
    env = IsolineEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step([float("nan")])
    obs, reward, terminated, truncated, info = env.step([0.0])  # the run goes on
    assert not terminated and not truncated


def test_vector_env_equals_single_envs():
    """Sub-environment i of the vector environment reset with seed s is the single environment
    reset with s + i: the same observations, rewards, flags and autoresets, step for step, with
    a noisy sensor and runs that end early (leaving the field east of x = 10.2 m) and at their
    duration."""
    sc = (
        isotrack.Scenario.default()
        .set("sim.duration_s", 1.0)
        .set("sensor.noise_std", 0.01)
        .set("field.domain_m", [-50.0, 10.2, -50.0, 50.0])
    )
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
    assert seen_ends == {"completed", "left_field"}


def test_vector_env_seeds_and_spaces():
    vec = IsolineVectorEnv(num_envs=5)
    assert vec.action_space.shape == (5, 1) and vec.observation_space.shape == (5, 2)
    a, _ = vec.reset(seed=[1, 2, 3, 4, 5])
    b, _ = vec.reset(seed=1)
    assert np.array_equal(a, b)
    assert len({tuple(o) for o in a}) == 5  # different seeds, different starts
    with pytest.raises(ValueError, match="expected 5 seeds"):
        vec.reset(seed=[1, 2])
    for bad in ("abcde", 1.5, True):
        with pytest.raises(TypeError, match="seed must be"):
            vec.reset(seed=bad)
    with pytest.raises(ValueError, match=r"x_m, y_m, heading_rad"):
        vec.reset(options={"start": (1.0, 2.0)})
    with pytest.raises(ValueError, match="num_envs"):
        IsolineVectorEnv(num_envs=0)
    with pytest.raises(RuntimeError, match="reset"):
        IsolineVectorEnv(num_envs=2).step(np.zeros((2, 1)))


def test_bad_arguments_raise_clearly():
    with pytest.raises(ValueError, match="start_radius_m"):
        IsolineEnv(start_radius_m=-1.0)
    with pytest.raises(ValueError, match="error_scale"):
        IsolineEnv(error_scale=0.0)
    # Issue 30 (doors30a), item 7: a subnormal scale divides the reward into infinity; a
    # subnormal weight is no weight anyone means. Both refused, the value echoed short.
    with pytest.raises(ValueError, match=r"error_scale must be .*subnormal.*got 1e-310$"):
        IsolineEnv(error_scale=1e-310)
    with pytest.raises(ValueError, match=r"effort_weight must be .*subnormal.*got 5e-324$"):
        IsolineEnv(effort_weight=5e-324)
    with pytest.raises(TypeError, match="isotrack.Scenario"):
        IsolineEnv(scenario="default")
    short = isotrack.Scenario.default().set("sim.duration_s", 0.05).set("sensor.rate_hz", 10.0)
    with pytest.raises(ValueError, match="at least one step"):  # 0.05 s at 10 Hz: 0 steps
        IsolineEnv(short)
    env = IsolineEnv()
    with pytest.raises(ValueError, match="start"):
        env.reset(options={"start": "elsewhere"})


def test_a_fixed_start_is_held_to_the_scenarios_ranges():
    """Issue 30 (fix30c): ``initial.heading_rad`` is bounded to +-1000 rad and ``initial.x_m``,
    ``y_m`` to +-6.4e7 m in a scenario; a Gymnasium start is held to the same (1e300 rad was
    flown). The bounds themselves are accepted."""
    env = IsolineEnv()
    for bad, needle in [
        ((8.0, 0.0, 1e300), "heading_rad"),
        ((8.0, 0.0, -1000.5), "heading_rad"),
        ((6.5e7, 0.0, 0.0), "x_m"),
        ((8.0, -1e300, 0.0), "y_m"),
    ]:
        with pytest.raises(ValueError, match=needle):
            env.reset(options={"start": bad})
    obs, info = env.reset(options={"start": (8.0, 0.0, 1000.0)})
    assert info["start"] == (8.0, 0.0, 1000.0)
    vec = IsolineVectorEnv(num_envs=2)
    with pytest.raises(ValueError, match="heading_rad"):
        vec.reset(options={"start": (8.0, 0.0, 1e17)})


def test_settings_that_break_an_episode_are_refused_at_construction():
    """Issue 30 (att30b item 7): ``error_scale = 2.3e-308`` (normal, > 0) gave a reward of
    -inf; ``start_radius_m = 1e300`` was accepted and failed only at reset; a start of 1e300
    was echoed with 301 digits; ``max_turn_rate_radps = 1e300`` failed in Gymnasium's Box.
    Each is refused at construction in isotrack's words, numbers short. The bounds: |eps| is
    at most 2e100 (the fields' value bound), so with N samples an episode needs error_scale >=
    2e100 N / 1e300; the action space is float32 (3.4e38); starts within 6.4e7 m."""
    with pytest.raises(ValueError, match=r"error_scale must be at least .*got 2\.3e-308$"):
        IsolineEnv(error_scale=2.3e-308)
    with pytest.raises(ValueError, match=r"error_scale must be at least"):
        IsolineVectorEnv(num_envs=2, error_scale=2.3e-308)
    with pytest.raises(ValueError, match=r"effort_weight must be at most .*got 1e\+?300$"):
        IsolineEnv(effort_weight=1e300)
    with pytest.raises(ValueError, match=r"start_radius_m must be .*6\.4e\+07 m.*got 1e\+300$"):
        IsolineEnv(start_radius_m=1e300)
    with pytest.raises(ValueError, match=r"max_turn_rate_radps must be within .*float32.*got 1e\+?300$"):
        IsolineEnv(max_turn_rate_radps=1e300)
    with pytest.raises(ValueError) as e:
        IsolineEnv().reset(options={"start": (1e300, 0.0, 0.0)})
    assert "1e300" in str(e.value) and len(str(e.value)) < 200, str(e.value)
    # A scale a reward can use, with its reward finite.
    env = IsolineEnv(error_scale=1e-150)
    env.reset(seed=0, options={"start": (100.0, 0.0, 0.0)})
    assert math.isfinite(env.step(np.array([0.5], dtype=np.float32))[1])


def test_scenario_pickles_for_worker_processes():
    """Gymnasium copies an environment's arguments and AsyncVectorEnv pickles them: a scenario
    survives both as the same scenario (its resolved TOML, absolute file paths)."""
    import copy
    import pickle

    sc = isotrack.Scenario.from_file(str(ROOT / "scenarios" / "volcano.toml")).set("sim.duration_s", 10.0)
    back = pickle.loads(pickle.dumps(sc))
    assert back == sc and copy.deepcopy(sc) is sc
    assert back.run().summary["end_position_m"] == sc.run().summary["end_position_m"]


def run_episode(env, action=0.0, **reset):
    """Steps `env` with a constant action to the end of its episode: the infos' sample times,
    the rewards and the observations of every step."""
    obs, info = env.reset(**reset)
    times, rewards, observations = [info["t_s"]], [], [obs]
    while True:
        obs, reward, terminated, truncated, info = env.step(np.array([action]))
        times.append(info["t_s"])
        rewards.append(reward)
        observations.append(obs)
        if terminated or truncated:
            return times, rewards, observations, terminated, truncated, info


@pytest.mark.parametrize("duration_s, rate_hz", [(20.0, 10.0), (3.0, 100.0), (7.5, 2.0), (1.05, 10.0)])
def test_episode_of_duration_d_at_rate_r_takes_d_times_r_steps(duration_s, rate_hz):
    """Samples at t = k/R for k = 0 ... floor(D*R): the reset delivers the first, so an episode
    is floor(D*R) steps (D*R when whole), the k-th step's sample at k/R; the last sample
    truncates it (the run then flies to D with the command held); no sample (time, observation
    or reward) comes twice. (It took one step more, the last repeating the one before.)"""
    sc = isotrack.Scenario.default().set("sim.duration_s", duration_s).set("sensor.rate_hz", rate_hz)
    times, rewards, observations, terminated, truncated, info = run_episode(IsolineEnv(sc), 0.3, seed=4)
    steps = math.floor(duration_s * rate_hz + 1e-9)
    assert len(times) - 1 == steps and truncated and not terminated and info["outcome"] == "completed"
    assert times == pytest.approx([k / rate_hz for k in range(steps + 1)], abs=1e-9)
    assert info["t_s"] == pytest.approx(steps / rate_hz, abs=1e-12)
    assert info["result"]["t_end_s"] == pytest.approx(duration_s, abs=1e-12)  # flown to D
    assert info["result"]["samples"] == steps + 1
    assert np.all(np.diff(times) > 0)
    assert len({tuple(o) for o in observations}) == len(observations)  # moving, no repeats
    assert rewards[-1] != rewards[-2]
    # The vector environment ends its runs at the same step.
    vec = IsolineVectorEnv(sc, num_envs=3)
    vec.reset(seed=4)
    for k in range(1, steps + 1):
        _, _, term, trunc, vinfo = vec.step(np.full((3, 1), 0.3))
        assert not term.any() and trunc.all() == (k == steps) and trunc.any() == (k == steps), k
    assert list(vinfo["outcome"]) == ["completed"] * 3


def test_bad_actions_raise_clearly():
    """Actions are arrays of real numbers of exactly the action space's shape: nothing else is
    reshaped, read as NaN or truncated."""
    env = IsolineEnv()
    env.reset(seed=0)
    for bad, error in [
        (None, TypeError),
        ("0.1", TypeError),
        (["a"], TypeError),
        ([True], TypeError),
        ([object()], TypeError),
        ([1 + 2j], TypeError),
        (0.1, ValueError),  # a scalar: shape () is not (1,)
        ([0.1, 0.2], ValueError),
        ([[0.1]], ValueError),
        ([], ValueError),
        ([[0.1], [0.2, 0.3]], ValueError),  # ragged
    ]:
        with pytest.raises(error, match="action"):
            env.step(bad)
    # None of them stepped the run: the next good step is the first.
    obs, reward, terminated, truncated, info = env.step(np.array([0.0], dtype=np.float32))
    assert info["t_s"] == 0.01 and not terminated
    vec = IsolineVectorEnv(num_envs=3)
    vec.reset(seed=0)
    for bad, error in [(None, TypeError), (np.zeros(3), ValueError), (np.zeros((3, 2)), ValueError),
                       (np.zeros((1, 3)), ValueError), (np.zeros((2, 1)), ValueError), (np.zeros(3, dtype=bool)[:, None], TypeError)]:
        with pytest.raises(error, match="action"):
            vec.step(bad)
    _, _, _, _, vinfo = vec.step(np.zeros((3, 1), dtype=np.int64))
    assert list(vinfo["t_s"]) == [0.01] * 3


def test_num_envs_must_be_a_whole_number_within_the_limit(monkeypatch):
    for bad in (1.5, 2.0, "3", None, True):
        with pytest.raises(TypeError, match="num_envs must be an int"):
            IsolineVectorEnv(num_envs=bad)
    for bad in (0, -1):
        with pytest.raises(ValueError, match="num_envs must be at least 1"):
            IsolineVectorEnv(num_envs=bad)
    with pytest.raises(ValueError, match="16777216 environments"):
        IsolineVectorEnv(num_envs=isotrack.gym.MAX_NUM_ENVS + 1)
    assert IsolineVectorEnv(num_envs=np.int64(2)).num_envs == 2
    # Sized by memory: 10^7 environments with 16 GiB available need more than its half.
    per_env = IsolineVectorEnv(num_envs=1).bytes_per_env
    assert 4096 < per_env < 65536
    monkeypatch.setattr(isotrack.gym, "_available_memory_bytes", lambda: 16 * 2**30)
    fit = 8 * 2**30 // per_env
    with pytest.raises(MemoryError, match=f"at most {fit} environments fit"):
        IsolineVectorEnv(num_envs=10**7)
    with pytest.raises(MemoryError):
        IsolineVectorEnv(num_envs=fit + 1)
    assert IsolineVectorEnv(num_envs=1000).num_envs == 1000  # only what fits is refused


def test_reset_mask_resets_only_those_and_is_checked():
    """`options={"reset_mask": m}` resets the sub-environments where m is true (with the seeds
    s + i) and leaves the others' runs going; a mask of another length, type or dtype, or all
    false, raises as in Gymnasium's own vector environments."""
    sc = isotrack.Scenario.default().set("sim.duration_s", 1.0)
    vec = IsolineVectorEnv(sc, num_envs=3)
    vec.reset(seed=1)
    for _ in range(5):
        before, *_ = vec.step(np.full((3, 1), 0.2))
    obs, info = vec.reset(seed=7, options={"reset_mask": np.array([True, False, True])})
    assert list(info["_start"]) == [True, False, True]
    for i in (0, 2):
        single, single_info = IsolineEnv(sc).reset(seed=7 + i)
        assert np.array_equal(obs[i], single) and tuple(info["start"][i]) == single_info["start"]
    assert np.array_equal(obs[1], before[1])
    _, _, _, _, info = vec.step(np.zeros((3, 1)))
    assert list(info["t_s"]) == pytest.approx([0.01, 0.06, 0.01])  # env 1 went on
    for mask, error in [
        (np.array([True, False]), ValueError),
        (np.ones(4, dtype=bool), ValueError),
        ([True, True, True], TypeError),
        (np.ones(3, dtype=np.int64), TypeError),
        (np.zeros(3, dtype=bool), ValueError),
    ]:
        with pytest.raises(error, match="reset_mask"):
            vec.reset(options={"reset_mask": mask})


def test_same_step_and_disabled_autoreset():
    """SAME_STEP: the ending step returns the new run's first observation and the last one in
    `final_obs` (what a single environment's last step gives); DISABLED: stepping an ended run
    raises until a `reset_mask` reset. Each mode is declared in `metadata["autoreset_mode"]`."""
    from gymnasium.vector import AutoresetMode

    sc = isotrack.Scenario.default().set("sim.duration_s", 0.5)
    follow = IsolineEnv(sc)
    _, _, observations, _, _, _ = run_episode(follow, 0.1, seed=3)
    vec = IsolineVectorEnv(sc, num_envs=2, autoreset_mode=AutoresetMode.SAME_STEP)
    assert vec.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    vec.reset(seed=3)
    for k in range(50):
        obs, reward, term, trunc, info = vec.step(np.full((2, 1), 0.1))
    assert trunc.all() and list(info["_final_obs"]) == [True, True]
    assert np.array_equal(info["final_obs"][0], observations[-1])
    assert list(info["final_info"]["outcome"]) == ["completed"] * 2
    # The new run's first observation: the single environment's next reset from its generator.
    again, again_info = follow.reset()
    assert np.array_equal(obs[0], again) and tuple(info["start"][0]) == again_info["start"]
    _, _, term, trunc, info = vec.step(np.full((2, 1), 0.1))
    assert not (term | trunc).any() and list(info["t_s"]) == [0.01, 0.01]

    off = IsolineVectorEnv(sc, num_envs=2, autoreset_mode="Disabled")
    assert off.metadata["autoreset_mode"] == AutoresetMode.DISABLED
    off.reset(seed=3)
    for _ in range(50):
        off.step(np.zeros((2, 1)))
    with pytest.raises(RuntimeError, match="reset_mask"):
        off.step(np.zeros((2, 1)))
    off.reset(options={"reset_mask": np.array([True, True])})
    _, _, _, _, info = off.step(np.zeros((2, 1)))
    assert list(info["t_s"]) == [0.01, 0.01]


def test_observation_bounds_follow_the_sensor_range():
    """With `sensor.range = [lo, hi]` the measurement is clamped: eps in [lo - s_d, hi - s_d] and
    |deps| <= (hi - lo) * rate; a noisy run that hits both ends stays inside the space."""
    sc = (
        isotrack.Scenario.default()
        .set("sensor.range", [9.5, 10.5])
        .set("sensor.noise_std", 2.0)
        .set("sim.duration_s", 5.0)
    )
    env = IsolineEnv(sc)
    space = env.observation_space
    assert space.low[0] == -0.5 and space.high[0] == 0.5
    assert space.high[1] == pytest.approx(1.0 * 100.0, rel=1e-8) and space.low[1] == -space.high[1]
    _, _, observations, *_ = run_episode(env, 0.0, seed=2)
    obs = np.array(observations)
    assert all(space.contains(o) for o in obs)
    assert obs[:, 0].min() == -0.5 and obs[:, 0].max() == 0.5  # the clamp is reached
    assert np.abs(obs[:, 1]).max() == pytest.approx(100.0)  # a jump from one end to the other


def test_rgb_frame_shows_field_isoline_and_vehicle():
    """The frame is north up and centred on the vehicle, 2 * half_width across: its white
    pixels are where the circular field crosses the level, |p| = 10 ln 2 m (to within the pixel
    grid); the centre is the vehicle (red); the path is drawn."""
    half = 8.0
    env = IsolineEnv(render_mode="rgb_array", render_half_width_m=half)
    env.reset(seed=0, options={"start": (10.0, 0.0, math.pi / 2)})
    frame = env.render()
    assert frame.shape == (256, 256, 3) and frame.dtype == np.uint8
    assert tuple(frame[128, 128]) == (220, 20, 20)
    rows, cols = np.nonzero(np.all(frame == 255, axis=-1))
    px = 2 * half / 256
    x = 10.0 - half + (cols + 0.5) * px
    y = half - (rows + 0.5) * px
    r = np.hypot(x, y)
    assert len(r) > 100 and np.all(np.abs(r - 10 * math.log(2)) < 1.5 * px)
    # West of x = 10 - 6.93 is above the level (brighter, yellow end), east below (violet end).
    assert frame[128, 10, 1] > 200 and frame[128, 250, 1] < 60
    for _ in range(1000):  # 10 s north at 0.5 m/s: to (10, 5)
        env.step([0.0])
    moved = env.render()
    rows, cols = np.nonzero(np.all(moved == (255, 140, 0), axis=-1))
    x = 10.0 - half + (cols + 0.5) * px
    y = 5.0 + half - (rows + 0.5) * px
    # The path behind it: the segment x = 10, y in [0, 5] (80 pixels, 5 hidden by the vehicle).
    assert np.all(np.abs(x - 10.0) < px) and np.all((y > -px) & (y < 5.0))
    assert len(rows) >= 80 - 5 - 1
    with pytest.raises(ValueError, match="render_mode"):
        IsolineEnv(render_mode="ascii")
    with pytest.warns(UserWarning, match="render_mode"):
        assert IsolineEnv().render() is None  # no mode: nothing, with Gymnasium's warning


def test_human_render_draws_into_a_matplotlib_figure():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env = IsolineEnv(render_mode="human")
    before = len(plt.get_fignums())
    env.reset(seed=0)
    assert env.render() is None and len(plt.get_fignums()) == before + 1
    env.step([0.1])
    image = env._renderer._image.get_array()
    assert image.shape == (256, 256, 3)
    env.close()
    assert len(plt.get_fignums()) == before


def test_stable_baselines3_trains_ppo_on_the_vector_env():
    """SB3's adapter: SB3's own checker passes on the single environment; PPO trains a few
    thousand steps on `SB3VecEnv` (8 runs stepped in Rust), every logged episode D*R = 20 steps;
    a run's end comes with SB3's `terminal_observation` (the single environment's last) and
    `TimeLimit.truncated`, and the next observation is the new run's first."""
    pytest.importorskip("stable_baselines3")
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_checker import check_env as sb3_check_env
    from stable_baselines3.common.vec_env import VecMonitor

    from isotrack.gym import SB3VecEnv

    torch.set_num_threads(1)
    sc = isotrack.Scenario.default().set("sim.duration_s", 2.0).set("sensor.rate_hz", 10.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its advice on unbounded observations
        sb3_check_env(IsolineEnv(sc))

    raw = SB3VecEnv(sc, num_envs=2)
    raw.seed(5)
    obs = raw.reset()
    single = IsolineEnv(sc)
    _, _, observations, *_ = run_episode(single, 0.0, seed=5)
    assert np.array_equal(obs[0], observations[0])
    for k in range(20):
        obs, rewards, dones, infos = raw.step(np.zeros((2, 1), dtype=np.float32))
        assert dones.all() == (k == 19) and rewards.dtype == np.float32
    assert infos[0]["TimeLimit.truncated"] and infos[0]["outcome"] == "completed"
    assert np.array_equal(infos[0]["terminal_observation"], observations[-1])
    assert np.array_equal(obs[0], single.reset()[0])

    # The single environment in SB3's own DummyVecEnv: the same episode ends.
    from stable_baselines3.common.vec_env import DummyVecEnv

    dummy = DummyVecEnv([lambda: IsolineEnv(sc)])
    dummy.seed(5)
    assert np.array_equal(dummy.reset()[0], observations[0])
    for k in range(20):
        _, _, dones, infos = dummy.step(np.zeros((1, 1), dtype=np.float32))
        assert dones[0] == (k == 19)
    assert infos[0]["TimeLimit.truncated"] and np.array_equal(infos[0]["terminal_observation"], observations[-1])

    env = VecMonitor(SB3VecEnv(sc, num_envs=8))
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=128, n_epochs=2, seed=0, device="cpu")
    model.learn(total_timesteps=4096)
    assert model.num_timesteps >= 4096
    lengths = {ep["l"] for ep in model.ep_info_buffer}
    assert lengths == {20}
    action, _ = model.predict(env.reset(), deterministic=True)
    assert action.shape == (8, 1) and np.all(np.abs(action) <= 1.0)


def test_bytes_per_env_is_not_below_the_resident_memory_of_an_environment():
    """The limit's estimate holds: the resident memory that 20 000 reset environments add
    (the default scenario and the 6-DOF UAV, the biggest loop state) is at most `bytes_per_env`
    each."""
    import gc

    def resident_bytes():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

    if not os.path.exists("/proc/self/statm"):
        pytest.skip("resident memory is read from /proc (Linux)")
    n = 20_000
    for sc in (isotrack.Scenario.default(), isotrack.Scenario.from_file(str(ROOT / "scenarios" / "paper-fig3-uav.toml"))):
        gc.collect()
        before = resident_bytes()
        vec = IsolineVectorEnv(sc, num_envs=n)
        vec.reset(seed=0)
        gc.collect()
        per_env = (resident_bytes() - before) / n
        assert 0 < per_env <= vec.bytes_per_env, (per_env, vec.bytes_per_env)
        del vec
