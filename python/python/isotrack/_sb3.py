"""Stable-Baselines3's vector-environment API over :class:`isotrack.gym.IsolineVectorEnv`
(imported by ``isotrack.gym.SB3VecEnv`` on first use: stable-baselines3 is optional)."""

from __future__ import annotations

from typing import Any, Iterable, List, Optional, Sequence, Type, Union

import numpy as np

try:
    import gymnasium
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError("isotrack.gym.SB3VecEnv needs stable-baselines3: pip install stable-baselines3") from e

from gymnasium.vector import AutoresetMode

from .gym import IsolineVectorEnv


class SB3VecEnv(VecEnv):
    """``num_envs`` runs of a scenario as a Stable-Baselines3 ``VecEnv``, stepped together in
    Rust (an :class:`~isotrack.gym.IsolineVectorEnv` with same-step autoreset underneath).

    SB3's conventions: ``reset()`` returns the observations only (seeds from ``seed(s)``: run
    ``i`` gets ``s + i``, as in the Gymnasium vector environment; options from
    ``set_options``); ``step`` returns ``(obs, rewards, dones, infos)`` with ``dones =
    terminated | truncated``, a list of one info dict per run, and a run that ended is reset at
    once: its last observation is ``infos[i]["terminal_observation"]``,
    ``infos[i]["TimeLimit.truncated"]`` says it reached ``sim.duration_s`` (SB3 then
    bootstraps its value), ``infos[i]["outcome"]`` how it ended. Arguments as
    :class:`~isotrack.gym.IsolineVectorEnv` (``autoreset_mode`` excepted). Wrap it in SB3's
    ``VecMonitor`` for episode returns in the logs::

        from stable_baselines3 import PPO
        from stable_baselines3.common.vec_env import VecMonitor
        env = VecMonitor(isotrack.gym.SB3VecEnv(isotrack.Scenario.default(), num_envs=8))
        PPO("MlpPolicy", env).learn(10_000)
    """

    def __init__(self, scenario: Any = None, num_envs: int = 1, **kwargs: Any):
        if "autoreset_mode" in kwargs:
            raise TypeError("SB3VecEnv resets a run in the step that ends it (SB3's rule): no autoreset_mode")
        self.venv = IsolineVectorEnv(scenario, num_envs, autoreset_mode=AutoresetMode.SAME_STEP, **kwargs)
        super().__init__(self.venv.num_envs, self.venv.single_observation_space, self.venv.single_action_space)
        self._actions: Optional[np.ndarray] = None

    def reset(self) -> np.ndarray:
        """Starts every run: the observations ``[num_envs, 2]``."""
        seeds = self._seeds
        seed = None if all(s is None for s in seeds) else seeds
        options = self._options[0] if self._options else {}
        if any(o != options for o in self._options):
            raise ValueError("SB3VecEnv applies one options dict to every run: set_options(dict)")
        obs, info = self.venv.reset(seed=seed, options=options or None)
        self.reset_infos = [{"start": tuple(info["start"][i])} for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        """``(obs, rewards, dones, infos)`` (see the class documentation)."""
        if self._actions is None:
            raise RuntimeError("step_async() before step_wait()")
        actions, self._actions = self._actions, None
        obs, reward, terminated, truncated, info = self.venv.step(actions)
        dones = terminated | truncated
        infos: List[dict] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final_info = info["final_info"]
            for i in np.flatnonzero(dones).tolist():
                infos[i] = {
                    "terminal_observation": info["final_obs"][i],
                    "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                    "outcome": final_info["outcome"][i],
                }
        return obs, reward.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> List[Any]:
        """The vector environment's attribute, once per run in ``indices``."""
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        raise AttributeError("SB3VecEnv's runs share one engine: set attributes on the scenario instead")

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> List[Any]:
        raise AttributeError(f"SB3VecEnv's runs are not separate environments: no method {method_name!r} per run")

    def env_is_wrapped(self, wrapper_class: Type[gymnasium.Wrapper], indices: Any = None) -> List[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[Optional[np.ndarray]]:
        """One frame per run (``render_mode="rgb_array"``, as ``IsolineVectorEnv`` draws them)."""
        if self.venv.render_mode != "rgb_array":
            raise NotImplementedError('SB3VecEnv renders with render_mode="rgb_array" only')
        return list(self.venv.render())

    def _get_indices(self, indices: Union[None, int, Iterable[int]]) -> Iterable[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return indices
