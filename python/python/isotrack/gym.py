"""Gymnasium environments: learn or test a coordinate-free isoline tracker on isotrack's fields,
vehicles and sensors.

``IsolineEnv(scenario)`` is one run of a scenario, registered as ``isotrack/Isoline-v0``;
``IsolineVectorEnv(scenario, num_envs)`` steps ``num_envs`` of them in one call into the Rust
engine (numpy in, numpy out), with Gymnasium's vector API (next-step autoreset by default;
same-step and disabled on request, declared in ``metadata["autoreset_mode"]``). Sub-environment
``i`` of a vector environment reset with ``seed=s`` is the same run, step for step, as an
``IsolineEnv`` reset with ``seed=s + i``. ``SB3VecEnv`` is the vector environment with
Stable-Baselines3's ``VecEnv`` API (needs stable-baselines3).

The environment's definition (the same for both):

* **step**: one sensor sample. The command is held from one delivered sample to the next, so a step
  spans ``1 / sensor.rate_hz`` seconds (more when the sensor drops a sample). The reset delivers
  the sample at t = 0, so a run of ``sim.duration_s = D`` at ``R`` Hz is ``floor(D * R)`` steps
  (``D * R`` when whole), the last one's sample at ``t = floor(D * R) / R``: it ends the episode
  (truncated), and the run flies on to ``D`` with the last action held. (Should the sensor drop
  the last samples, the step that reaches ``D`` without one repeats the last observation.)
* **action**: the turn-rate command ``omega`` (rad/s, positive turns left), a float32 ``Box`` of
  shape ``(1,)`` within ``[-omega_max, omega_max]``: the scenario's turn-rate limit
  (``controller.max_turn_rate_radps``, or the airframe's for the fixed-wing UAV), else 1 rad/s,
  or the ``max_turn_rate_radps`` argument. ``step`` takes an array of exactly that shape of any
  real dtype (float64 keeps its precision). Finite actions beyond the bound are clipped; an
  invalid action raises, as Gymnasium's convention is, and steps nothing: another shape or a
  NaN or infinite value ``ValueError``, ``None`` or a non-numeric value ``TypeError``.
* **observation**: ``[eps_m, deps_m]``, float64: the measured error ``eps_m = s_measured - s_d``
  (field units) and its sampled difference ``(eps_m[k] - eps_m[k-1]) / (t[k] - t[k-1])`` (field
  units per second, 0 at the first sample). That is all a coordinate-free controller can know:
  no position, heading or gradient. The bounds are finite where the sensor has a ``range =
  [lo, hi]`` (``eps_m`` in ``[lo - s_d, hi - s_d]``, ``|deps_m| <= (hi - lo) * rate_hz``), else
  infinite (a field value has no bound a noisy sensor respects).
* **reward**: ``-min(|eps| / error_scale, 10) - effort_weight * (omega / omega_max)**2``, with
  ``eps`` the true (noise-free) error at the new sample (the tracking term capped at 10), ``error_scale`` the scenario controller's ``c2``
  (the paper's error scale; 1 if unset) unless given, ``effort_weight`` 0.01 unless given.
  A terminating step also pays ``termination_penalty`` (default: ``(10 + effort_weight)`` times
  the samples left in the run, so that leaving the field never scores better than staying).
  The settings are checked at construction so that an episode of ``N`` samples sums to less
  than 1e300 in magnitude: ``error_scale >= 2e100 * N / 1e300`` (|eps| is at most 2e100, the
  fields' value bound), ``effort_weight`` and ``termination_penalty`` at most ``1e300 / N``;
  ``max_turn_rate_radps`` within float32's range (the action space), ``start_radius_m`` at most
  6.4e7 m (the scenario's coordinate range).
* **terminated**: the run ended as ``left_field`` (the vehicle reached a point where the field has
  no value) or ``diverged``; **truncated**: it reached the scenario's ``sim.duration_s``.
* **reset(seed=..., options=...)**: reproducible from ``seed``. The start is drawn uniformly in
  the disc of radius ``start_radius_m`` round the scenario's start (default: 1 % of the distance
  the vehicle covers in ``sim.duration_s``), the heading uniformly in ``[-pi, pi)`` unless
  ``random_heading=False`` (then the scenario's), redrawn where the field has no value; the
  sensor's noise and dropouts are seeded from the same generator. ``options={"start": (x_m,
  y_m, heading_rad)}`` fixes the start; ``options={"start": "scenario"}`` is the scenario's own
  run (its start and ``sim.seed``): answered by the scenario's controller it is
  ``Scenario.run()``, bit for bit, when the scenario has a turn-rate limit (the action space's
  bound is then that limit). Without one, the environment clips actions to its bound (1 rad/s,
  or the ``max_turn_rate_radps`` argument) where ``Scenario.run()`` does not clip: the two
  differ once the law commands more than that.
* **info**: ``t_s`` (time of the sample, s); at a reset ``start`` (``(x_m, y_m, heading_rad)``,
  ground truth for logs and plots, never part of the observation); at the end of a run
  ``outcome`` (``completed``, ``left_field``, ``diverged``) and ``result`` (the run's outcome and
  metrics, as in ``summary.json``).
* **rendering** (``IsolineEnv(render_mode=...)``, ``metadata["render_fps"]`` = the sensor rate,
  one frame per step; ``IsolineVectorEnv(render_mode="rgb_array")`` returns a tuple of one such
  frame per sub-environment): ``"rgb_array"`` returns a ``uint8[256, 256, 3]`` top-down frame, north
  up, centred on the vehicle and ``2 * render_half_width_m`` across (default ten turn radii):
  the field (a colour ramp over the frame's values; dark grey off the field), the isoline
  ``s = s_d`` (white), the path since the reset (orange) and the vehicle (red, a tick along its
  heading). numpy only. ``"human"`` draws the same frames in a matplotlib window at every reset
  and step, pausing one sample period (real time; matplotlib needed).
* **limits**: a vector environment holds at most ``MAX_NUM_ENVS`` (2^24) sub-environments,
  and at most as many as fit in half the memory available when it is built
  (``bytes_per_env``, an upper estimate of about 8 KiB each with its numpy generator): more raises ``MemoryError``
  saying how many fit. ``num_envs`` must be an int (``1.5`` raises ``TypeError``).

Gymnasium is an optional dependency: ``pip install "./python[gym]"``.
"""

from __future__ import annotations

import json
import os
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

from . import Scenario, _check_flag, _check_number, _native

def _have_sb3() -> bool:
    """Whether stable-baselines3 is installed (looked up, not imported: it imports torch)."""
    import importlib.util

    try:
        return importlib.util.find_spec("stable_baselines3") is not None
    except (ImportError, ValueError):
        return False


# ``SB3VecEnv`` only where it imports: ``from isotrack.gym import *`` never fails.
__all__ = ["IsolineEnv", "IsolineVectorEnv", "ENV_ID", "MAX_NUM_ENVS"] + (["SB3VecEnv"] if _have_sb3() else [])

#: The registered id: ``gymnasium.make("isotrack/Isoline-v0", scenario=...)``.
ENV_ID = "isotrack/Isoline-v0"

#: Most sub-environments one vector environment holds, whatever the memory (2^24).
MAX_NUM_ENVS = 1 << 24

#: What one sub-environment holds on the Python side, bytes: its numpy ``Generator`` (with its
#: bit generator and seed sequence) and its share of the batched arrays, rounded up (measured
#: with ``tracemalloc`` over 2 x 10^4 generators: 0.85 KiB).
_PY_BYTES_PER_ENV = 2048

#: Share of the memory available when a vector environment is built that its environments may
#: take.
_MEMORY_SHARE = 0.5

#: Redraws of a random start before giving up (a start disc mostly off the field).
_MAX_START_DRAWS = 1000

#: Side of a rendered frame, pixels.
_FRAME_PX = 256


def _available_memory_bytes() -> Optional[int]:
    """The memory the process may still use: ``MemAvailable`` of ``/proc/meminfo`` (Linux), else
    the free physical pages (``os.sysconf``), else ``None`` (unknown: only ``MAX_NUM_ENVS``
    bounds ``num_envs``)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def _check_num_envs(num_envs: Any) -> int:
    """``num_envs`` as an int in ``[1, MAX_NUM_ENVS]``; a ``TypeError`` for anything but an
    integer (``1.5``, ``"3"``, ``True``)."""
    if isinstance(num_envs, (bool, np.bool_)) or not isinstance(num_envs, (int, np.integer)):
        raise TypeError(f"num_envs must be an int, got {num_envs!r} ({type(num_envs).__name__})")
    n = int(num_envs)
    if n < 1:
        raise ValueError(f"num_envs must be at least 1, got {n}")
    if n > MAX_NUM_ENVS:
        raise ValueError(f"num_envs = {n} is more than the {MAX_NUM_ENVS} environments one vector environment holds")
    return n


def _check_memory(num_envs: int, bytes_per_env: int, available: Optional[int]) -> None:
    """Refuses ``num_envs`` environments of ``bytes_per_env`` each when they need more than
    ``_MEMORY_SHARE`` of ``available`` bytes (a clear error instead of an allocation failure that
    aborts the interpreter)."""
    if available is None:
        return
    need = num_envs * bytes_per_env
    budget = int(_MEMORY_SHARE * available)
    if need > budget:
        raise MemoryError(
            f"num_envs = {num_envs} needs about {need / 2**30:.2f} GiB ({bytes_per_env} bytes per environment), "
            f"more than half the {available / 2**30:.2f} GiB of memory available: at most "
            f"{max(budget // bytes_per_env, 0)} environments fit"
        )


def _spaces(batch: "_native.EnvBatch") -> Tuple[spaces.Box, spaces.Box]:
    """The action space (float32, ``[-omega_max, omega_max]``) and the observation space
    (float64; finite where the sensor's ``range`` bounds the measurement)."""
    w = batch.max_turn_rate_radps
    action = spaces.Box(low=-w, high=w, shape=(1,), dtype=np.float32)
    bounds = batch.observation_bounds
    if bounds is None:
        observation = spaces.Box(low=-np.inf, high=np.inf, shape=(2,), dtype=np.float64)
    else:
        observation = spaces.Box(low=np.array(bounds[0]), high=np.array(bounds[1]), dtype=np.float64)
    return action, observation


def _check_actions(actions: Any, shape: Tuple[int, ...]) -> np.ndarray:
    """``actions`` as a float64 array of exactly ``shape``: a ``TypeError`` for what is not an
    array of real numbers (``None``, strings, booleans, objects), a ``ValueError`` for another
    shape (never reshaped) or a value that is not finite (NaN, infinity: Gymnasium's convention,
    an invalid action raises; nothing is stepped). Finite values beyond the bound clip."""
    if actions is None:
        raise TypeError(f"the action must be an array of shape {shape} of turn rates (rad/s), got None")
    try:
        a = np.asarray(actions)
    except (ValueError, TypeError) as e:
        raise ValueError(f"the action must be an array of shape {shape}, got {actions!r}: {e}") from None
    if a.dtype.kind not in "iuf":
        raise TypeError(f"the action must be an array of real numbers (rad/s), got dtype {a.dtype}")
    if a.shape != shape:
        raise ValueError(f"the action must have shape {shape}, got shape {a.shape}")
    a = a.astype(np.float64)
    bad = ~np.isfinite(a)
    if bad.any():
        where = np.argwhere(bad)[:10, 0].tolist()
        what = f"sub-environments {where}" if len(shape) == 2 else "the action"
        raise ValueError(
            f"the action must be a finite turn rate (rad/s): {what} got {a[bad][0]} (nothing was stepped)"
        )
    return a


class _Starts:
    """How resets draw their starts (one rule for both environments)."""

    def __init__(self, batch: "_native.EnvBatch", start_radius_m: Optional[float], random_heading: bool):
        r = batch.default_start_radius_m if start_radius_m is None else _check_number("start_radius_m", start_radius_m)
        most = batch.max_start_radius_m
        if not (np.isfinite(r) and 0.0 <= r <= most):
            # The scenario's coordinate range (issue 30, att30b item 7: 1e300 was accepted and
            # failed only at reset, echoed with 300 digits).
            raise ValueError(f"start_radius_m must be finite, >= 0 and at most {most:g} m (the scenario's coordinate range), got {r:.6g}")
        self.radius_m = r
        self.random_heading = _check_flag("random_heading", random_heading)
        self.batch = batch
        self.origin = batch.start

    def reset(
        self, i: int, rng: np.random.Generator, options: Optional[Dict[str, Any]]
    ) -> Tuple[np.ndarray, Tuple[float, float, float]]:
        """Resets sub-environment ``i`` from a start drawn with ``rng``: its observation and
        its start ``(x_m, y_m, heading_rad)``."""
        x0, y0, h0 = self.origin
        fixed = (options or {}).get("start")
        if isinstance(fixed, str):
            if fixed != "scenario":
                raise ValueError(f'options["start"] must be "scenario" or (x_m, y_m, heading_rad), got {fixed!r}')
            return self.batch.reset(i, x0, y0, h0, None), (x0, y0, h0)
        if fixed is not None:
            try:
                x, y, h = (_check_number('options["start"]', v) for v in fixed)  # no strings
            except (TypeError, ValueError):
                raise ValueError(f'options["start"] must be "scenario" or (x_m, y_m, heading_rad), got {fixed!r}') from None
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
    checked = {k: _check_number(k, v, optional=k != "effort_weight") for k, v in reward.items()}
    return _native.EnvBatch(scenario._native, num_envs, **checked)


class _Renderer:
    """Top-down frames of one sub-environment: the field round the vehicle (a colour ramp, dark
    grey off the field), the isoline ``s = s_d`` (white: pixels where the field crosses the level),
    the path since the reset (orange) and the vehicle (red, with a heading tick). numpy only;
    ``"human"`` shows the frames in a matplotlib window."""

    _LOW = np.array([68.0, 1.0, 84.0])  # the ends of viridis
    _HIGH = np.array([253.0, 231.0, 37.0])

    def __init__(
        self,
        scenario: Scenario,
        batch: "_native.EnvBatch",
        mode: Optional[str],
        half_width_m: Optional[float],
        modes: Sequence[str] = ("rgb_array", "human"),
    ):
        if mode is not None and mode not in modes:
            shown = " or ".join(f'"{m}"' for m in modes)
            raise ValueError(f"render_mode must be None or {shown}, got {mode!r:.80}")
        if half_width_m is None:
            half_width_m = 10.0 * batch.speed_mps / batch.max_turn_rate_radps  # ten turn radii
            if not (np.isfinite(half_width_m) and half_width_m > 0.0):
                # Not the caller's render_half_width_m (they gave none): the turn-rate limit's.
                raise ValueError(
                    f"max_turn_rate_radps = {batch.max_turn_rate_radps!r} rad/s gives turn radii of "
                    f"{half_width_m!r} m: pass render_half_width_m (or a larger limit)"
                )
        if isinstance(half_width_m, (bool, np.bool_)) or not isinstance(half_width_m, (int, float, np.integer, np.floating)):
            raise TypeError(f"render_half_width_m must be a number (m), got {half_width_m!r:.80}")
        if not (np.isfinite(half_width_m) and half_width_m > 0.0):
            raise ValueError(f"render_half_width_m must be finite and > 0, got {half_width_m}")
        if mode == "human":
            try:
                import matplotlib.pyplot  # noqa: F401
            except ImportError as e:
                raise gymnasium.error.DependencyNotInstalled(
                    'render_mode="human" needs matplotlib: pip install matplotlib'
                ) from e
        self.mode, self.scenario, self.batch, self.half_width_m = mode, scenario, batch, float(half_width_m)
        self.level = scenario.level
        # The path of each sub-environment since its reset (kept only when rendering).
        self.paths: List[List[Tuple[float, float]]] = [[] for _ in range(batch.num_envs)] if mode else []
        self._figure: Any = None

    def record(self, i: int, reset: bool) -> None:
        """Notes sub-environment ``i``'s position (after a step, or a reset when ``reset``)."""
        if self.mode is None:
            return
        if reset:
            self.paths[i] = []
        x, y, _, _ = self.batch.pose(i)
        self.paths[i].append((x, y))
        if self.mode == "human":
            self.show(self.frame(i))

    def record_all(self, reset: np.ndarray, moved: np.ndarray) -> None:
        """Notes every sub-environment's position in one call: a new path where ``reset``, one
        more point where ``moved``."""
        if self.mode is None:
            return
        poses = self.batch.poses()
        for i in np.flatnonzero(reset | moved).tolist():
            if reset[i]:
                self.paths[i] = []
            self.paths[i].append((float(poses[i, 0]), float(poses[i, 1])))

    def frame(self, i: int) -> np.ndarray:
        """The frame, ``uint8[256, 256, 3]``, north up, centred on the vehicle, ``2 *
        half_width_m`` across."""
        x, y, heading, t = self.batch.pose(i)
        n, w = _FRAME_PX, self.half_width_m
        centres = (np.arange(n) + 0.5) / n * 2.0 * w - w
        xs, ys = np.meshgrid(x + centres, y - centres)
        v = self.scenario.field_values(xs.ravel(), ys.ravel(), t).reshape(n, n)
        on = np.isfinite(v)
        img = np.full((n, n, 3), 40, dtype=np.uint8)
        if on.any():
            lo, hi = float(v[on].min()), float(v[on].max())
            g = (v - lo) / (hi - lo) if hi > lo else np.full_like(v, 0.5)
            ramp = self._LOW + np.clip(np.nan_to_num(g), 0.0, 1.0)[..., None] * (self._HIGH - self._LOW)
            img[on] = ramp[on].astype(np.uint8)
            above = v >= self.level
            edge = np.zeros((n, n), dtype=bool)
            edge[:, :-1] |= (above[:, 1:] != above[:, :-1]) & on[:, 1:] & on[:, :-1]
            edge[:-1, :] |= (above[1:, :] != above[:-1, :]) & on[1:, :] & on[:-1, :]
            img[edge] = 255
        scale = n / (2.0 * w)  # pixels per metre
        if self.paths[i]:
            p = np.array(self.paths[i])
            cols = np.floor((p[:, 0] - x + w) * scale).astype(np.int64)
            rows = np.floor((y + w - p[:, 1]) * scale).astype(np.int64)
            inside = (cols >= 0) & (cols < n) & (rows >= 0) & (rows < n)
            img[rows[inside], cols[inside]] = (255, 140, 0)
        c = n // 2
        rr, cc = np.mgrid[-4:5, -4:5]
        disc = rr**2 + cc**2 <= 16
        img[c + rr[disc], c + cc[disc]] = (220, 20, 20)
        tick = np.arange(5, 14)
        img[np.clip(c - np.round(tick * np.sin(heading)).astype(int), 0, n - 1),
            np.clip(c + np.round(tick * np.cos(heading)).astype(int), 0, n - 1)] = (220, 20, 20)
        return img

    def show(self, frame: np.ndarray) -> None:
        """Draws ``frame`` in the matplotlib window (opened on the first frame); with an
        interactive backend it pauses one sample period of simulated time per frame."""
        import matplotlib.pyplot as plt

        if self._figure is None:
            self._figure, ax = plt.subplots(figsize=(4, 4))
            self._image = ax.imshow(frame)
            ax.set_axis_off()
        else:
            self._image.set_data(frame)
        if getattr(self._figure.canvas, "required_interactive_framework", None) is None:
            self._figure.canvas.draw()  # a non-interactive backend (Agg): no window to show
        else:
            plt.pause(self.batch.sensor_period_s)

    def close(self) -> None:
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None


class IsolineEnv(gymnasium.Env):
    """One run of a scenario as a Gymnasium environment (see the module documentation for the
    action, observation, reward, termination, reset and rendering rules).

    Args:
        scenario: the scenario (``Scenario.default()``, the paper's Fig. 2(b) setting, if None).
        start_radius_m: radius of the random start disc round the scenario's start, m.
        random_heading: draw the start heading uniformly (else the scenario's).
        max_turn_rate_radps: the action bound, rad/s (default: the scenario's limit, else 1).
        error_scale: the reward's error scale, field units (default: the controller's ``c2``).
        effort_weight: weight of the effort term ``(omega / omega_max)**2`` (default 0.01).
        termination_penalty: what ending as ``left_field``/``diverged`` costs (default: see above).
        render_mode: ``None``, ``"rgb_array"`` (``render()`` returns a ``uint8[256, 256, 3]``
            frame) or ``"human"`` (a matplotlib window, updated at every reset and step).
        render_half_width_m: half the side of the rendered square, m (default: ten turn radii,
            ``10 * speed / omega_max``).
    """

    metadata = {"render_modes": ["rgb_array", "human"]}

    def __init__(
        self,
        scenario: Optional[Scenario] = None,
        start_radius_m: Optional[float] = None,
        random_heading: bool = True,
        max_turn_rate_radps: Optional[float] = None,
        error_scale: Optional[float] = None,
        effort_weight: float = 0.01,
        termination_penalty: Optional[float] = None,
        render_mode: Optional[str] = None,
        render_half_width_m: Optional[float] = None,
    ):
        scenario = Scenario.default() if scenario is None else scenario
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
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / self._batch.sensor_period_s}
        self.render_mode = render_mode
        self._renderer = _Renderer(scenario, self._batch, render_mode, render_half_width_m)
        self._active = np.ones(1, dtype=bool)
        self._running = False
        self._reset_once = False

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None):
        """Starts a run (see the module documentation): ``(observation, info)``. ``seed``: None
        or an int >= 0 (numpy's too, taken exactly)."""
        super().reset(seed=_check_seed(seed))
        options = _check_options(options)
        obs, start = self._starts.reset(0, self.np_random, options)
        self._running = self._reset_once = True
        self._renderer.record(0, reset=True)
        return obs, {"t_s": 0.0, "start": start}

    def step(self, action):
        """One sample: ``(observation, reward, terminated, truncated, info)``. ``action``: an
        array of shape ``(1,)`` (any real dtype; float64 keeps its precision)."""
        a = _check_actions(action, (1,))
        if not self._running:
            raise RuntimeError("the run has ended (or never started): call reset()")
        obs, reward, terminated, truncated, t = self._batch.step(a, self._active)
        term, trunc = bool(terminated[0]), bool(truncated[0])
        info: Dict[str, Any] = {"t_s": float(t[0])}
        if term or trunc:
            self._running = False
            result = json.loads(self._batch.result_json(0))
            info["outcome"] = result["outcome"]
            info["result"] = result
        self._renderer.record(0, reset=False)
        return obs[0].copy(), float(reward[0]), term, trunc, info

    def render(self):
        """``"rgb_array"``: the current frame (``uint8[256, 256, 3]``); ``"human"``: draws it;
        ``None``: nothing (with Gymnasium's warning)."""
        if self.render_mode is None:
            gymnasium.logger.warn('render() without a render_mode: make the environment with render_mode="rgb_array"')
            return None
        if not self._reset_once:
            raise RuntimeError("call reset() before render()")
        frame = self._renderer.frame(0)
        if self.render_mode == "human":
            self._renderer.show(frame)
            return None
        return frame

    def close(self) -> None:
        """Closes the ``"human"`` window, if any."""
        self._renderer.close()

    def result(self) -> Dict[str, Any]:
        """The current run's outcome and metrics so far (as in ``summary.json``)."""
        return json.loads(self._batch.result_json(0))


_AUTORESET_MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)


def _check_seed(seed: Any, name: str = "seed") -> Optional[int]:
    """A reset's seed exactly: ``None``, or a Python or numpy integer >= 0 as a Python int (never
    through a float). A ``TypeError`` for anything else (floats, booleans, strings), a
    ``ValueError`` for a negative one."""
    if seed is None:
        return None
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"{name} must be None or an int >= 0, got {seed!r:.80} ({type(seed).__name__})")
    s = int(seed)
    if s < 0:
        raise ValueError(f"{name} must be >= 0, got {s}")
    return s


def _check_options(options: Any, known: Sequence[str] = ("start",)) -> Optional[Dict[str, Any]]:
    """A reset's ``options``: ``None`` or a dict of the ``known`` keys (a ``TypeError`` naming
    ``options`` otherwise, a ``ValueError`` naming a key it does not know: a misspelt
    ``"strat"`` is not ignored)."""
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options must be None or a dict, got {options!r:.80} ({type(options).__name__})")
    for k in options or {}:
        if k not in known:
            raise ValueError(f"options: unknown key {k!r:.80} (known: {', '.join(repr(x) for x in known)})")
    return options


def _check_reset_mask(mask: Any, num_envs: int) -> np.ndarray:
    """``options["reset_mask"]`` checked as Gymnasium's own vector environments do."""
    if not isinstance(mask, np.ndarray):
        raise TypeError(f"options['reset_mask'] must be a numpy array, got {type(mask).__name__}")
    if mask.shape != (num_envs,):
        raise ValueError(f"options['reset_mask'] must have shape ({num_envs},), got {mask.shape}")
    if mask.dtype != np.bool_:
        raise TypeError(f"options['reset_mask'] must have dtype bool, got {mask.dtype}")
    if not mask.any():
        raise ValueError("options['reset_mask'] must reset at least one sub-environment (all False)")
    return mask


class IsolineVectorEnv(VectorEnv):
    """``num_envs`` runs of a scenario stepped together in Rust, one call per step, with
    Gymnasium's vector API. Arguments as :class:`IsolineEnv`, and:

    Args:
        num_envs: the number of sub-environments, an int in ``[1, MAX_NUM_ENVS]`` whose memory
            (``num_envs * bytes_per_env``, about 8 KiB each) fits in half the memory available
            when it is built (else ``MemoryError``, naming how many fit).
        autoreset_mode: ``AutoresetMode.NEXT_STEP`` (default: the step after a run ends resets
            it and returns its first observation with reward 0), ``SAME_STEP`` (the ending step
            resets it at once and returns the new run's first observation; the last one is
            ``info["final_obs"][i]``, its info ``info["final_info"]``) or ``DISABLED`` (stepping
            an ended run raises; reset it with ``options={"reset_mask": mask}``). Declared in
            ``metadata["autoreset_mode"]``.
        render_mode: ``None`` or ``"rgb_array"``: ``render()`` returns a tuple of ``num_envs``
            frames, ``uint8[256, 256, 3]`` each, drawn as :class:`IsolineEnv` draws them (each
            sub-environment's path since its own reset); ``np.stack(vec.render())`` is
            ``uint8[num_envs, 256, 256, 3]``. Drawing costs about a field evaluation per
            pixel per sub-environment: render a few environments, not thousands.
        render_half_width_m: as :class:`IsolineEnv`'s.

    ``reset(seed=s)`` seeds sub-environment ``i`` with ``s + i`` (a list gives one seed each), as
    ``gymnasium.vector.SyncVectorEnv`` does; ``options`` apply to every sub-environment, and
    ``options={"reset_mask": mask}`` (a bool array of shape ``(num_envs,)``) resets only those
    where ``mask`` is true (the others keep their runs and observations).
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

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
        autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
        render_mode: Optional[str] = None,
        render_half_width_m: Optional[float] = None,
    ):
        n = _check_num_envs(num_envs)
        mode = AutoresetMode(autoreset_mode)
        self._batch = _make_batch(
            scenario,
            1,
            max_turn_rate_radps=max_turn_rate_radps,
            error_scale=error_scale,
            effort_weight=effort_weight,
            termination_penalty=termination_penalty,
        )
        self.bytes_per_env = self._batch.bytes_per_env + _PY_BYTES_PER_ENV
        _check_memory(n, self.bytes_per_env, _available_memory_bytes())
        self._batch = _make_batch(
            scenario,
            n,
            max_turn_rate_radps=max_turn_rate_radps,
            error_scale=error_scale,
            effort_weight=effort_weight,
            termination_penalty=termination_penalty,
        )
        self._starts = _Starts(self._batch, start_radius_m, random_heading)
        self.render_mode = render_mode
        self._renderer = _Renderer(
            Scenario.default() if scenario is None else scenario, self._batch, render_mode, render_half_width_m, modes=("rgb_array",)
        )
        self.num_envs = n
        self.metadata = {**type(self).metadata, "autoreset_mode": mode, "render_fps": 1.0 / self._batch.sensor_period_s}
        self.single_action_space, self.single_observation_space = _spaces(self._batch)
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        # One generator per sub-environment, made at its first reset (seeded or not).
        self._rngs: List[Optional[np.random.Generator]] = [None] * n
        self._options: Optional[Dict[str, Any]] = None
        self._obs = np.zeros((n, 2), dtype=np.float64)
        self._ended = np.zeros(n, dtype=bool)
        self._reset_done = np.zeros(n, dtype=bool)

    def _rng(self, i: int) -> np.random.Generator:
        rng = self._rngs[i]
        if rng is None:
            rng = self._rngs[i] = seeding.np_random()[0]
        return rng

    def _reset_some(self, indices: np.ndarray, options: Optional[Dict[str, Any]]) -> Tuple[np.ndarray, np.ndarray]:
        """Resets the sub-environments ``indices``: their observations and starts."""
        obs = np.empty((len(indices), 2), dtype=np.float64)
        starts = np.empty((len(indices), 3), dtype=np.float64)
        for k, i in enumerate(indices.tolist()):
            obs[k], starts[k] = self._starts.reset(i, self._rng(i), options)
        return obs, starts

    def reset(
        self,
        *,
        seed: Optional[Union[int, Sequence[Optional[int]]]] = None,
        options: Optional[Dict[str, Any]] = None,
    ):
        """Starts every run (or those of ``options["reset_mask"]``): ``(observations[num_envs,
        2], info)`` with ``info["start"]`` (and ``info["_start"]``, which were reset)."""
        n = self.num_envs
        options = _check_options(options, ("start", "reset_mask"))
        if options is not None and "reset_mask" in options:
            options = dict(options)
            mask = _check_reset_mask(options.pop("reset_mask"), n)
        else:
            mask = np.ones(n, dtype=bool)
        if seed is None:
            seeds: Sequence[Optional[int]] = [None] * n
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, (bool, np.bool_)):
            first = _check_seed(seed)
            seeds = [first + i for i in range(n)]
            self._np_random, self._np_random_seed = seeding.np_random(first)
        elif isinstance(seed, (str, bytes, float, bool, np.bool_)) or not isinstance(seed, (list, tuple, np.ndarray)):
            # A sequence in order only: a dict's keys or a set's order are not seeds.
            raise TypeError(f"seed must be None, an int or a sequence of {n} ints (or None), got {seed!r:.80}")
        else:
            seeds = [_check_seed(s, f"seed[{k}]") for k, s in enumerate(seed)]
            if len(seeds) != n:
                raise ValueError(f"expected {n} seeds, got {len(seeds)}")
        indices = np.flatnonzero(mask)
        for i in indices.tolist():
            if seeds[i] is not None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
        self._options = options
        fresh, fresh_starts = self._reset_some(indices, options)
        self._obs[indices] = fresh
        starts = np.zeros((n, 3), dtype=np.float64)
        starts[indices] = fresh_starts
        self._ended[indices] = False
        self._reset_done[indices] = True
        self._renderer.record_all(mask, np.zeros(n, dtype=bool))
        return self._obs.copy(), {"t_s": np.zeros(n), "start": starts, "_start": mask.copy()}

    def step(self, actions):
        """One sample in every run: arrays of observations, rewards, terminated and truncated
        flags, and the info dict (autoreset as ``metadata["autoreset_mode"]``). ``actions``: an
        array of shape ``(num_envs, 1)`` (any real dtype; float64 keeps its precision)."""
        n = self.num_envs
        a = _check_actions(actions, (n, 1)).reshape(n)
        if not self._reset_done.all():
            raise RuntimeError("call reset() before step() (every sub-environment)")
        mode = self.metadata["autoreset_mode"]
        resetting = self._ended.copy()
        if mode == AutoresetMode.DISABLED and resetting.any():
            raise RuntimeError(
                f"sub-environments {np.flatnonzero(resetting)[:10].tolist()} have ended: reset them with "
                "reset(options={'reset_mask': mask}) (autoreset_mode DISABLED)"
            )
        obs, reward, terminated, truncated, t = self._batch.step(a, ~resetting)
        info: Dict[str, Any] = {"t_s": t}
        fresh = resetting.copy()  # the sub-environments that start a new run at this step
        if resetting.any():  # NEXT_STEP: the runs that ended at the last step start again now
            idx = np.flatnonzero(resetting)
            obs[idx], fresh_starts = self._reset_some(idx, self._options)
            t[idx] = 0.0
            starts = np.zeros((n, 3))
            starts[idx] = fresh_starts
            info.update({"start": starts, "_start": resetting})
        ended = terminated | truncated
        if ended.any():
            end_info = self._end_info(ended)
            if mode == AutoresetMode.SAME_STEP:
                idx = np.flatnonzero(ended)
                final_obs = np.full(n, None, dtype=object)
                for i in idx.tolist():
                    final_obs[i] = obs[i].copy()
                final_info = {"t_s": np.where(ended, t, 0.0), "_t_s": ended.copy(), **end_info}
                info.update({"final_obs": final_obs, "_final_obs": ended.copy(), "final_info": final_info, "_final_info": ended.copy()})
                obs[idx], fresh_starts = self._reset_some(idx, self._options)
                t[idx] = 0.0
                starts = np.zeros((n, 3))
                starts[idx] = fresh_starts
                info.update({"start": starts, "_start": ended.copy()})
                fresh |= ended
                ended = np.zeros(n, dtype=bool)
            else:
                info.update(end_info)
        self._ended = ended
        self._obs = obs
        self._renderer.record_all(fresh, ~fresh)
        return obs.copy(), reward, terminated, truncated, info

    def render(self) -> Optional[Tuple[np.ndarray, ...]]:
        """``render_mode="rgb_array"``: one frame per sub-environment, a tuple of ``num_envs``
        ``uint8[256, 256, 3]`` arrays (Gymnasium's vector convention, as ``SyncVectorEnv``
        returns; ``np.stack`` makes them ``uint8[num_envs, 256, 256, 3]``), each as
        :class:`IsolineEnv` draws it; ``None`` without a render mode (with Gymnasium's
        warning)."""
        if self.render_mode is None:
            gymnasium.logger.warn('render() without a render_mode: make the environment with render_mode="rgb_array"')
            return None
        if not self._reset_done.all():
            raise RuntimeError("call reset() before render() (every sub-environment)")
        return tuple(self._renderer.frame(i) for i in range(self.num_envs))

    def _end_info(self, ended: np.ndarray) -> Dict[str, Any]:
        """``outcome`` and ``result`` of the runs that ended (with their masks)."""
        n = self.num_envs
        outcome = np.full(n, "", dtype=object)
        result = np.full(n, None, dtype=object)
        for i in np.flatnonzero(ended).tolist():
            r = json.loads(self._batch.result_json(i))
            outcome[i], result[i] = r["outcome"], r
        return {
            "outcome": outcome,
            "_outcome": ended.copy(),
            "result": result,
            "_result": ended.copy(),
        }


def __getattr__(name: str) -> Any:
    """``SB3VecEnv`` is built on first use (importing stable-baselines3 imports torch)."""
    if name == "SB3VecEnv":
        try:
            from ._sb3 import SB3VecEnv
        except ImportError as e:
            # An AttributeError, so that hasattr() and getattr(..., default) answer False.
            raise AttributeError(
                f"isotrack.gym.SB3VecEnv needs stable-baselines3 (pip install stable-baselines3): {e}"
            ) from e

        return SB3VecEnv
    raise AttributeError(f"module 'isotrack.gym' has no attribute {name!r}")


def _register() -> None:
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="isotrack.gym:IsolineEnv",
            vector_entry_point="isotrack.gym:IsolineVectorEnv",
        )


_register()
