"""A team of coordinate-free vehicles as a PettingZoo ``ParallelEnv`` (docs/TEAMS.md).

>>> import isotrack, isotrack.pettingzoo
>>> sc = isotrack.Scenario.from_file("scenarios/team-circular-4.toml")
>>> env = isotrack.pettingzoo.parallel_env(sc.set("controller.max_turn_rate_radps", 1.0))
>>> obs, infos = env.reset(seed=1)
>>> obs, rewards, terminated, truncated, infos = env.step(
...     {a: infos[a]["builtin_action"] for a in env.agents})

Needs ``pettingzoo`` (``pip install pettingzoo``). The scenario's ``[team]`` section makes the
team: agent ``vehicle_i`` is vehicle ``i`` in its listed order (a ring fixed at deployment:
``team.ring = "listed"``; the discovered ring is refused). Each step goes through the team engine
in Rust (the one step kernel ``Scenario.run()`` uses), paused between each step's samples and
the vehicles' move:

* **step**: ``period_steps`` engine steps, the greatest common divisor of the sensor period,
  the ranging period and the ranging delay (in steps), so that every sample and every range
  delivery falls on a step of the environment.
* **action** (per agent): ``[omega, v]``, a float32 ``Box``: the turn-rate command (rad/s,
  positive turns left) within ``[-omega_max, omega_max]`` (the scenario's turn-rate limit,
  1 rad/s without one) and the speed command (m/s) within ``[team.v_min_mps,
  team.v_max_mps]``. The turn rate takes effect at the agent's sample (as the single-vehicle
  environment's and a built-in law's: without a sample this step, the command is held and the
  turn rate given is not used; ``infos[agent]["sampled"]`` says which); the speed from this step
  on, held. An action of another shape, not finite, or out of the bounds raises (nothing is
  stepped, never reshaped or clipped); so does a missing agent or a dead one.
* **observation** (per agent, float64): ``[eps_m, deps_m, r_ahead_m, ahead_valid, r_behind_m,
  behind_valid]``: the measured error ``s_measured - s_d`` at the agent's latest sample and
  its sampled difference (1/s; 0 at the first sample), as :mod:`isotrack.gym` observes, and
  the latest ranges its ranging unit delivered to its ring neighbours ahead and behind with a
  validity flag each (1: the neighbour answered; 0: it did not, the range reads 0; both 0
  before the first delivery). Nothing else: no position, heading or neighbour position.
* **reward** (per agent): ``-min(|eps| / error_scale, 10) - spacing_weight * ((d_ahead - d_behind) /
  (d_ahead + d_behind))^2 - effort_weight * (omega / omega_max)^2`` at the new pause, with the
  true (noise-free) error and the true distances to its ring neighbours (ground truth, as the
  single-vehicle reward's error): tracking, plus the imbalance of its two gaps (0 when the
  neighbours are equally far), plus effort. ``error_scale`` defaults as the single-vehicle
  environment's (``pi_isoline``'s ``c2``, else 1). On the step that ends an agent off the field
  (where the field has no value) the tracking term is its last one. A terminating step
  (``left_field``, ``diverged``) also pays ``termination_penalty`` (default: ``(10 +
  spacing_weight + effort_weight)`` times the env steps left in the run, the worst a step can
  cost under the tracking term's cap of 10, as in the single-vehicle environment), so that leaving the field never
  scores better than flying on, as in :mod:`isotrack.gym`.
* **termination**: an agent whose run ends early (left the field, diverged) is terminated; at
  the run's end (``sim.duration_s``) every agent still flying is truncated.
* **infos[agent]**: ``t_s``, ``sampled`` (this step has its sample), ``builtin_action``: what
  the scenario's own laws command now (the tracking law's answer to the sample, its held
  command without one; the spacing law's speed, saturated to the envelope): feeding it back as
  the action flies the run ``Scenario.run()`` flies, bit for bit (python/tests/test_team.py).
  It lies in the action space when the scenario limits the turn rate
  (``controller.max_turn_rate_radps``); without a limit the law's answer may exceed the
  default bound of 1 rad/s, and is then refused as an action like any other.

``env.trace()`` is the trace so far (the columns of ``Scenario.run()``'s team trace);
``env.summary()`` the run's ``summary.json`` content once the episode has ended (its
``scenario.sim.seed`` the episode's seed).

``reset(seed=S)`` (``0 <= S <= 2**63-1``, ``sim.seed``'s range) flies the episode of the scenario
with ``sim.seed = S`` (its sensors' and ranging units' noise and dropouts) and seeds a generator,
as Gymnasium's environments do; each later ``reset()`` without a seed flies a new episode, its
seed drawn from that generator. The first reset of all without a seed flies the scenario's own
``sim.seed`` (``Scenario.run()``'s run) and seeds the generator with it. ``env.episode_seed`` is
the seed flown: ``scenario.set("sim.seed", env.episode_seed).run()`` replays the episode the
built-in actions fly. The same seed and actions give the same episode, and the same seeded
sequence of resets the same episodes.
"""

from __future__ import annotations

import json
from typing import Any, Dict, Optional

import numpy as np

from . import Scenario, _check_flag, _check_number, _check_scenario, _native, _type_name

try:
    from gymnasium import spaces
    from gymnasium.utils import seeding
    from pettingzoo import ParallelEnv
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError("isotrack.pettingzoo needs pettingzoo: pip install pettingzoo") from e

__all__ = ["TeamParallelEnv", "parallel_env"]

#: The largest seed (``sim.seed``'s: TOML's integers are 64-bit signed).
_MAX_SEED = 2**63 - 1


class TeamParallelEnv(ParallelEnv):
    """The team of a ``[team]`` scenario as a PettingZoo ``ParallelEnv`` (module docs)."""

    metadata = {"name": "isotrack_team_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(
        self,
        scenario: Scenario,
        max_turn_rate_radps: Optional[float] = None,
        error_scale: Optional[float] = None,
        spacing_weight: float = 1.0,
        effort_weight: float = 0.01,
        record: bool = True,
        termination_penalty: Optional[float] = None,
    ):
        _check_scenario("scenario", scenario)
        self.scenario = scenario
        self._native = _native.TeamEnv(
            scenario._native,
            _check_number("max_turn_rate_radps", max_turn_rate_radps, optional=True),
            _check_number("error_scale", error_scale, optional=True),
            _check_number("spacing_weight", spacing_weight),
            _check_number("effort_weight", effort_weight),
            _check_flag("record", record),
            _check_number("termination_penalty", termination_penalty, optional=True),
        )
        n = self._native.num_agents
        self.possible_agents = [f"vehicle_{i}" for i in range(n)]
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents: list = []
        w = self._native.max_turn_rate_radps
        lo, hi = self._native.speed_range_mps
        self._action_space = spaces.Box(
            low=np.array([-w, lo], dtype=np.float32), high=np.array([w, hi], dtype=np.float32), dtype=np.float32
        )
        self._observation_space = spaces.Box(low=-np.inf, high=np.inf, shape=(6,), dtype=np.float64)
        # The bounds an action is checked against: the true ones, widened to the float32 Box's
        # rounding (a sample of the Box is always accepted; the engine clips that last rounding).
        self._low = np.minimum(np.array([-w, lo]), self._action_space.low.astype(np.float64))
        self._high = np.maximum(np.array([w, hi]), self._action_space.high.astype(np.float64))
        self.period_steps: int = self._native.period_steps
        self.dt_s: float = self._native.dt_s
        self.error_scale: float = self._native.error_scale
        #: The generator unseeded resets draw their episodes' seeds from (seeded by a seeded
        #: reset; by the first reset of all, with the scenario's ``sim.seed``).
        self._np_random: Optional[np.random.Generator] = None
        #: The current (or last) episode's ``sim.seed``; ``None`` before the first reset.
        self.episode_seed: Optional[int] = None

    def observation_space(self, agent):
        """The agent's observation space (the same object at every call)."""
        self._check_agent(agent)
        return self._observation_space

    def action_space(self, agent):
        """The agent's action space (the same object at every call)."""
        self._check_agent(agent)
        return self._action_space

    def _check_agent(self, agent) -> int:
        try:
            return self._index[agent]
        except (KeyError, TypeError):
            raise KeyError(f"no agent {agent!r:.80}: the agents are vehicle_0 .. vehicle_{len(self.possible_agents) - 1}") from None

    def _infos(self, builtin, sampled, t_s) -> Dict[str, Dict[str, Any]]:
        return {
            a: {"t_s": t_s, "sampled": bool(sampled[i]), "builtin_action": builtin[i].copy()}
            for a, i in ((a, self._index[a]) for a in self.agents)
        }

    def reset(self, seed: Optional[int] = None, options: Optional[dict] = None):
        """Starts an episode (module docs): ``seed=S`` flies it as ``sim.seed = S`` and seeds
        the generator later unseeded resets draw their episodes' seeds from; ``None``: the
        generator's next seed (the first reset of all, the scenario's own ``sim.seed``).
        ``episode_seed`` is the seed flown (``sc.set("sim.seed", env.episode_seed).run()``
        replays the episode the built-in actions fly). Raises ``ValueError`` when a data file
        of the scenario changed since the scenario was made (the env flies the field read then;
        ``FileNotFoundError`` when one is gone), as ``Scenario.run()`` does."""
        if seed is not None:
            if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
                raise TypeError(f"seed must be an int >= 0 or None, got {seed!r:.80} ({_type_name(seed)})")
            if not 0 <= int(seed) <= _MAX_SEED:
                raise ValueError(
                    f"seed must be in 0 ..= 2**63-1 ({_MAX_SEED}, the range of sim.seed, which replays "
                    f"the episode), got {int(seed)}"
                )
            seed = int(seed)
        if seed is None and self._np_random is None:
            seed = int(self._native.base_seed)
        if seed is None:
            seed = int(self._np_random.integers(0, _MAX_SEED, endpoint=True))
        else:
            self._np_random, _ = seeding.np_random(seed)
        # The env holds the field as the scenario read it: a data file changed since would fly
        # the old field under the new file's digest in summary() (att39-5).
        self.scenario._check_data_files()
        obs, builtin, sampled, t_s = self._native.reset(seed)
        self.episode_seed = int(self._native.episode_seed)
        self.agents = list(self.possible_agents)
        return {a: obs[self._index[a]] for a in self.agents}, self._infos(builtin, sampled, t_s)

    def _check_action(self, agent: str, a: Any) -> np.ndarray:
        if a is None:
            raise TypeError(f"{agent}: the action must be [turn rate (rad/s), speed (m/s)], got None")
        try:
            x = np.asarray(a)
        except (ValueError, TypeError) as e:
            raise ValueError(f"{agent}: the action must be an array of shape (2,), got {a!r:.80}: {e}") from None
        if x.dtype.kind not in "iuf":
            raise TypeError(f"{agent}: the action must be real numbers [rad/s, m/s], got dtype {x.dtype}")
        if x.shape != (2,):
            raise ValueError(f"{agent}: the action must have shape (2,) [turn rate, speed], got shape {x.shape}")
        x = x.astype(np.float64)
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{agent}: the action {x.tolist()} is not finite")
        if not (np.all(x >= self._low) and np.all(x <= self._high)):
            raise ValueError(
                f"{agent}: the action {x.tolist()} is outside the action space "
                f"[{float(self._low[0])!r}, {float(self._high[0])!r}] rad/s x [{float(self._low[1])!r}, {float(self._high[1])!r}] m/s"
            )
        return x

    def step(self, actions):
        if not isinstance(actions, dict):
            raise TypeError(f"actions must be a dict {{agent: action}}, got {_type_name(actions)}")
        if not self.agents:
            raise ValueError("no agent is live: the episode has ended (or was never reset), call reset()")
        live = set(self.agents)
        unknown = [k for k in actions if k not in live]
        if unknown:
            raise KeyError(f"actions for agents that are not live: {unknown!r:.200}")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise KeyError(f"no action for the live agents {missing!r:.200}")
        n = len(self.possible_agents)
        turn = np.zeros(n)
        speed = np.zeros(n)
        given = np.zeros(n, dtype=bool)
        for a in self.agents:
            x = self._check_action(a, actions[a])
            i = self._index[a]
            turn[i], speed[i], given[i] = x[0], x[1], True
        obs, rew, term, trunc, builtin, sampled, t_s = self._native.step(turn, speed, given)
        agents = self.agents
        observations = {a: obs[self._index[a]] for a in agents}
        rewards = {a: float(rew[self._index[a]]) for a in agents}
        terminated = {a: bool(term[self._index[a]]) for a in agents}
        truncated = {a: bool(trunc[self._index[a]]) for a in agents}
        infos = self._infos(builtin, sampled, t_s)
        self.agents = [a for a in agents if not (terminated[a] or truncated[a])]
        return observations, rewards, terminated, truncated, infos

    def trace(self) -> Dict[str, np.ndarray]:
        """The trace recorded so far: the columns of ``Scenario.run()``'s team trace (with
        ``vehicle``), all of its rows once the episode has ended (``record=False``: empty)."""
        return dict(self._native.trace())

    def summary(self) -> Optional[Dict[str, Any]]:
        """The episode's ``summary.json`` content (``team``, ``vehicles``) once it has ended;
        ``None`` before. ``ValueError`` when a data file changed during the episode (its
        ``data_files`` would name a file the field flown was not read from)."""
        text = self._native.summary_json()
        if text is None:
            return None
        summary = json.loads(text)
        # Its data_files are the files as they are now: the field flown is the one read when the
        # scenario was made (att39-5), so a file changed since is refused, never named.
        self.scenario._check_data_files(summary.get("data_files") or {})
        return summary

    def state(self) -> np.ndarray:
        """The vehicles' true positions, ``float64[n, 2]`` of ``(x_m, y_m)`` at the last pause
        (ground truth, for logs and rendering; never an agent's observation)."""
        return np.array([self._native.position(i) for i in range(len(self.possible_agents))])

    def render(self):
        return None

    def close(self):
        pass


def parallel_env(scenario: Scenario, **kwargs) -> TeamParallelEnv:
    """The team of ``scenario`` (a :class:`isotrack.Scenario` with a ``[team]`` section) as a
    PettingZoo ``ParallelEnv``; ``kwargs``: ``max_turn_rate_radps``, ``error_scale``,
    ``spacing_weight`` (default 1), ``effort_weight`` (default 0.01), ``record`` (keep the
    trace, default True), ``termination_penalty`` (default: see the module docs). Module docs for the spaces and rewards."""
    return TeamParallelEnv(scenario, **kwargs)
