"""Gymnasium environments: learn or test a coordinate-free isoline tracker on isotrack's fields,
vehicles and sensors.

``IsolineEnv(scenario)`` is one run of a scenario, registered as ``isotrack/Isoline-v0``;
``IsolineVectorEnv(scenario, num_envs)`` steps ``num_envs`` of them in one call into the Rust
engine (numpy in, numpy out), with Gymnasium's vector API and next-step autoreset. Sub-environment
``i`` of a vector environment reset with ``seed=s`` is the same run, step for step, as an
``IsolineEnv`` reset with ``seed=s + i``.

The environment's definition (the same for both):

* **step**: one sensor sample. The command is held from one delivered sample to the next, so a step
  spans ``1 / sensor.rate_hz`` seconds (more when the sensor drops a sample).
* **action**: the turn-rate command ``omega`` (rad/s, positive turns left), a ``Box`` of shape
  ``(1,)`` within ``[-omega_max, omega_max]``: the scenario's turn-rate limit
  (``controller.max_turn_rate_radps``, or the airframe's for the fixed-wing UAV), else 1 rad/s,
  or the ``max_turn_rate_radps`` argument. Actions beyond it are clipped; a NaN ends the run as
  ``diverged``.
* **observation**: ``[eps_m, deps_m]``, float64: the measured error ``eps_m = s_measured - s_d``
  (field units) and its sampled difference ``(eps_m[k] - eps_m[k-1]) / (t[k] - t[k-1])`` (field
  units per second, 0 at the first sample). That is all a coordinate-free controller can know:
  no position, heading or gradient.
* **reward**: ``-|eps| / error_scale - effort_weight * (omega / omega_max)**2``, with ``eps`` the
  true (noise-free) error at the new sample, ``error_scale`` the scenario controller's ``c2``
  (the paper's error scale; 1 if unset) unless given, ``effort_weight`` 0.01 unless given.
  A terminating step also pays ``termination_penalty`` (default: ``(10 + effort_weight)`` times
  the samples left in the run, so that leaving the field never scores better than staying).
* **terminated**: the run ended as ``left_field`` (the vehicle reached a point where the field has
  no value) or ``diverged``; **truncated**: it reached the scenario's ``sim.duration_s``.
* **reset(seed=..., options=...)**: reproducible from ``seed``. The start is drawn uniformly in
  the disc of radius ``start_radius_m`` round the scenario's start (default: 1 % of the distance
  the vehicle covers in ``sim.duration_s``), the heading uniformly in ``[-pi, pi)`` unless
  ``random_heading=False`` (then the scenario's), redrawn where the field has no value; the
  sensor's noise and dropouts are seeded from the same generator. ``options={"start": (x_m,
  y_m, heading_rad)}`` fixes the start; ``options={"start": "scenario"}`` is the scenario's own
  run (its start and ``sim.seed``): answered by the scenario's controller it is
  ``Scenario.run()``, bit for bit.
* **info**: ``t_s`` (time of the sample, s); at a reset ``start`` (``(x_m, y_m, heading_rad)``,
  ground truth for logs and plots, never part of the observation); at the end of a run
  ``outcome`` (``completed``, ``left_field``, ``diverged``) and ``result`` (the run's outcome and
  metrics, as in ``summary.json``).

Gymnasium is an optional dependency: ``pip install "./python[gym]"``.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

try:
    import gymnasium
    from gymnasium import spaces
    from gymnasium.utils import seeding
    from gymnasium.vector import AutoresetMode, VectorEnv
    from gymnasium.vector.utils import batch_space
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError('isotrack.gym needs gymnasium >= 1.0: pip install "gymnasium>=1.0"') from e

from . import Scenario, _native

__all__ = ["IsolineEnv", "IsolineVectorEnv", "ENV_ID"]

#: The registered id: ``gymnasium.make("isotrack/Isoline-v0", scenario=...)``.
ENV_ID = "isotrack/Isoline-v0"

#: Redraws of a random start before giving up (a start disc mostly off the field).
_MAX_START_DRAWS = 1000


def _spaces(batch: "_native.EnvBatch") -> Tuple[spaces.Box, spaces.Box]:
    w = batch.max_turn_rate_radps
    action = spaces.Box(low=-w, high=w, shape=(1,), dtype=np.float64)
    observation = spaces.Box(low=-np.inf, high=np.inf, shape=(2,), dtype=np.float64)
    return action, observation


class _Starts:
    """How resets draw their starts (one rule for both environments)."""

    def __init__(self, batch: "_native.EnvBatch", start_radius_m: Optional[float], random_heading: bool):
        r = batch.default_start_radius_m if start_radius_m is None else float(start_radius_m)
        if not (np.isfinite(r) and r >= 0.0):
            raise ValueError(f"start_radius_m must be finite and >= 0, got {start_radius_m}")
        self.radius_m = r
        self.random_heading = bool(random_heading)
        self.batch = batch

    def reset(
        self, i: int, rng: np.random.Generator, options: Optional[Dict[str, Any]]
    ) -> Tuple[np.ndarray, Tuple[float, float, float]]:
        """Resets sub-environment ``i`` from a start drawn with ``rng``: its observation and
        its start ``(x_m, y_m, heading_rad)``."""
        x0, y0, h0 = self.batch.start
        fixed = (options or {}).get("start")
        if isinstance(fixed, str):
            if fixed != "scenario":
                raise ValueError(f'options["start"] must be "scenario" or (x_m, y_m, heading_rad), got {fixed!r}')
            return self.batch.reset(i, x0, y0, h0, None), (x0, y0, h0)
        if fixed is not None:
            x, y, h = (float(v) for v in fixed)
            return self.batch.reset(i, x, y, h, int(rng.integers(0, 2**63))), (x, y, h)
        last_error = None
        for _ in range(_MAX_START_DRAWS):
            # Uniform in the disc: radius ~ R*sqrt(u).
            rho = self.radius_m * np.sqrt(rng.uniform())
            phi = rng.uniform(-np.pi, np.pi)
            x, y = float(x0 + rho * np.cos(phi)), float(y0 + rho * np.sin(phi))
            h = float(rng.uniform(-np.pi, np.pi)) if self.random_heading else h0
            seed = int(rng.integers(0, 2**63))
            if not self.batch.has_value(x, y):
                continue
            try:
                return self.batch.reset(i, x, y, h, seed), (x, y, h)
            except ValueError as e:  # ended before its first sample: draw again
                last_error = e
        raise ValueError(
            f"no start with a field value found in {_MAX_START_DRAWS} draws within start_radius_m = "
            f"{self.radius_m} m of ({x0}, {y0}) m" + (f"; last: {last_error}" if last_error else "")
        )


def _make_batch(scenario: Optional[Scenario], num_envs: int, **reward: Any) -> "_native.EnvBatch":
    scenario = Scenario.default() if scenario is None else scenario
    if not isinstance(scenario, Scenario):
        raise TypeError(f"scenario must be an isotrack.Scenario, got {type(scenario).__name__}")
    return _native.EnvBatch(scenario._native, int(num_envs), **reward)


class IsolineEnv(gymnasium.Env):
    """One run of a scenario as a Gymnasium environment (see the module documentation for the
    action, observation, reward, termination and reset rules).

    Args:
        scenario: the scenario (``Scenario.default()``, the paper's Fig. 2(b) setting, if None).
        start_radius_m: radius of the random start disc round the scenario's start, m.
        random_heading: draw the start heading uniformly (else the scenario's).
        max_turn_rate_radps: the action bound, rad/s (default: the scenario's limit, else 1).
        error_scale: the reward's error scale, field units (default: the controller's ``c2``).
        effort_weight: weight of the effort term ``(omega / omega_max)**2`` (default 0.01).
        termination_penalty: what ending as ``left_field``/``diverged`` costs (default: see above).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        start_radius_m: Optional[float] = None,
        random_heading: bool = True,
        max_turn_rate_radps: Optional[float] = None,
        error_scale: Optional[float] = None,
        effort_weight: float = 0.01,
        termination_penalty: Optional[float] = None,
    ):
        self._batch = _make_batch(
            scenario,
            1,
            max_turn_rate_radps=max_turn_rate_radps,
            error_scale=error_scale,
            effort_weight=effort_weight,
            termination_penalty=termination_penalty,
        )
        self._starts = _Starts(self._batch, start_radius_m, random_heading)
        self.action_space, self.observation_space = _spaces(self._batch)
        self._action = np.zeros(1, dtype=np.float64)
        self._active = np.ones(1, dtype=bool)
        self._running = False

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None):
        """Starts a run (see the module documentation): ``(observation, info)``."""
        super().reset(seed=seed)
        obs, start = self._starts.reset(0, self.np_random, options)
        self._running = True
        return obs, {"t_s": 0.0, "start": start}

    def step(self, action):
        """One sample: ``(observation, reward, terminated, truncated, info)``."""
        if not self._running:
            raise RuntimeError("the run has ended (or never started): call reset()")
        self._action[0] = np.asarray(action, dtype=np.float64).reshape(-1)[0]
        obs, reward, terminated, truncated, t = self._batch.step(self._action, self._active)
        term, trunc = bool(terminated[0]), bool(truncated[0])
        info: Dict[str, Any] = {"t_s": float(t[0])}
        if term or trunc:
            self._running = False
            result = json.loads(self._batch.result_json(0))
            info["outcome"] = result["outcome"]
            info["result"] = result
        return obs[0].copy(), float(reward[0]), term, trunc, info

    def result(self) -> Dict[str, Any]:
        """The current run's outcome and metrics so far (as in ``summary.json``)."""
        return json.loads(self._batch.result_json(0))


class IsolineVectorEnv(VectorEnv):
    """``num_envs`` runs of a scenario stepped together in Rust, one call per step, with
    Gymnasium's vector API (next-step autoreset: the step after a run ends resets it and returns
    its first observation with reward 0). Arguments as :class:`IsolineEnv`.

    ``reset(seed=s)`` seeds sub-environment ``i`` with ``s + i`` (a list gives one seed each), as
    ``gymnasium.vector.SyncVectorEnv`` does; ``options`` apply to every sub-environment.
    """

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        num_envs: int = 1,
        start_radius_m: Optional[float] = None,
        random_heading: bool = True,
        max_turn_rate_radps: Optional[float] = None,
        error_scale: Optional[float] = None,
        effort_weight: float = 0.01,
        termination_penalty: Optional[float] = None,
    ):
        if int(num_envs) < 1:
            raise ValueError(f"num_envs must be at least 1, got {num_envs}")
        self._batch = _make_batch(
            scenario,
            num_envs,
            max_turn_rate_radps=max_turn_rate_radps,
            error_scale=error_scale,
            effort_weight=effort_weight,
            termination_penalty=termination_penalty,
        )
        self._starts = _Starts(self._batch, start_radius_m, random_heading)
        self.num_envs = int(num_envs)
        self.single_action_space, self.single_observation_space = _spaces(self._batch)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._rngs: List[np.random.Generator] = [seeding.np_random()[0] for _ in range(self.num_envs)]
        self._options: Optional[Dict[str, Any]] = None
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    def reset(
        self,
        *,
        seed: Optional[Union[int, Sequence[Optional[int]]]] = None,
        options: Optional[Dict[str, Any]] = None,
    ):
        """Starts every run: ``(observations[num_envs, 2], info)``."""
        if seed is None:
            seeds: Sequence[Optional[int]] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(self.num_envs)]
            self._np_random, self._np_random_seed = seeding.np_random(int(seed))
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
        for i, s in enumerate(seeds):
            if s is not None:
                self._rngs[i] = seeding.np_random(s)[0]
        self._options = options
        obs = np.empty((self.num_envs, 2), dtype=np.float64)
        starts = np.empty((self.num_envs, 3), dtype=np.float64)
        for i in range(self.num_envs):
            obs[i], starts[i] = self._starts.reset(i, self._rngs[i], options)
        self._autoreset[:] = False
        self._started = True
        return obs, {"t_s": np.zeros(self.num_envs), "start": starts}

    def step(self, actions):
        """One sample in every run (next-step autoreset): arrays of observations, rewards,
        terminated and truncated flags, and the info dict."""
        if not self._started:
            raise RuntimeError("call reset() before step()")
        a = np.ascontiguousarray(actions, dtype=np.float64).reshape(self.num_envs)
        resetting = self._autoreset
        if resetting.any():
            fresh = {int(i): self._starts.reset(int(i), self._rngs[i], self._options) for i in np.flatnonzero(resetting)}
            obs, reward, terminated, truncated, t = self._batch.step(a, ~resetting)
            starts = np.zeros((self.num_envs, 3))
            for i, (o, start) in fresh.items():
                obs[i], starts[i] = o, start
                t[i] = 0.0
            info: Dict[str, Any] = {"t_s": t, "start": starts, "_start": resetting.copy()}
        else:
            obs, reward, terminated, truncated, t = self._batch.step(a, ~resetting)
            info = {"t_s": t}
        ended = terminated | truncated
        if ended.any():
            outcome = np.full(self.num_envs, "", dtype=object)
            result = np.full(self.num_envs, None, dtype=object)
            for i in np.flatnonzero(ended):
                r = json.loads(self._batch.result_json(int(i)))
                outcome[i], result[i] = r["outcome"], r
            info.update({"outcome": outcome, "_outcome": ended.copy(), "result": result, "_result": ended.copy()})
        self._autoreset = ended
        return obs, reward, terminated, truncated, info


def _register() -> None:
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="isotrack.gym:IsolineEnv",
            vector_entry_point="isotrack.gym:IsolineVectorEnv",
        )


_register()
