"""isotrack from Python: the same engine, scenarios and outputs as the ``isotrack`` command.

>>> import isotrack
>>> run = isotrack.Scenario.default().run()
>>> run.summary["outcome"]
'completed'
>>> run.trace["error"][-1]          # numpy arrays named as trace.csv's columns
"""

from __future__ import annotations

import json
from typing import Any, Dict, Optional

import numpy as np

from . import _native

__all__ = ["Scenario", "Run", "ScenarioError", "benchmark", "check", "sweep", "__version__"]

__version__: str = _native.version()

#: An invalid scenario or override; the message is the one the CLI prints (file, line, column,
#: key, or the offending assignment).
ScenarioError = _native.ScenarioError


class Run:
    """A finished run.

    ``summary`` is a dict with exactly the keys of ``summary.json``; ``trace`` a dict of 1-D numpy
    arrays named as the columns of ``trace.csv`` (``s_measured`` is NaN where no sample arrived).
    """

    def __init__(self, summary: Dict[str, Any], trace: Dict[str, np.ndarray]):
        self.summary = summary
        self.trace = trace

    def to_pandas(self):
        """The trace as a pandas DataFrame (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Run.to_pandas() needs pandas: pip install pandas") from e
        return pd.DataFrame(self.trace)

    def __repr__(self) -> str:
        s = self.summary
        return f"Run(outcome={s['outcome']!r}, t_end_s={s['t_end_s']}, rows={len(self.trace['t_s'])})"


class Scenario:
    """A resolved scenario (every default filled in), immutable: ``set`` returns a new one."""

    def __init__(self, native: "_native.Scenario"):
        self._native = native

    @staticmethod
    def default() -> "Scenario":
        """The built-in default: the paper's Fig. 2(b) setting."""
        return Scenario(_native.Scenario.default())

    @staticmethod
    def from_file(path: str) -> "Scenario":
        """A scenario file (TOML); the files it names are relative to it."""
        return Scenario(_native.Scenario.from_file(str(path)))

    @staticmethod
    def from_toml(text: str) -> "Scenario":
        """Scenario text (TOML); the files it names are relative to the current directory."""
        return Scenario(_native.Scenario.from_toml(text))

    def set(self, key: str, value: Any) -> "Scenario":
        """A new scenario with the dotted ``key`` set to ``value`` (the rules of ``--set``)."""
        return Scenario(self._native.set(key, value))

    def to_toml(self) -> str:
        """The resolved scenario as TOML (what ``isotrack show`` prints)."""
        return self._native.to_toml()

    @property
    def level(self) -> float:
        """The level ``s_d`` the scenario tracks (field units)."""
        return self._native.level

    @property
    def max_turn_rate_radps(self) -> Optional[float]:
        """The turn-rate limit applied to every controller's command, rad/s (None: no limit)."""
        return self._native.max_turn_rate_radps

    def run(self, record_rate_hz: Optional[float] = None, controller: Any = None) -> Run:
        """Runs the scenario.

        ``controller``: any object with ``update(t_s, value) -> omega`` (rad/s, positive turns
        left) and optionally ``reset()``: it replaces the scenario's controller and sees only what
        a coordinate-free controller sees, the time and the measured value of each sample. Its
        command is held until the next sample and clipped to the scenario's turn-rate limit
        (``controller.max_turn_rate_radps``, or the airframe's for the fixed-wing UAV), as the
        built-in laws' are. An exception inside it ends the run and is raised here with its
        traceback.
        """
        summary, trace = self._native.run(record_rate_hz, controller)
        return Run(json.loads(summary), dict(trace))

    def field_values(self, x, y, t: float = 0.0) -> np.ndarray:
        """The field at points ``(x, y)`` (m) at time ``t`` (s), NaN where it has no value;
        vectorised over numpy arrays of any one shape (for plotting with matplotlib)."""
        xa = np.ascontiguousarray(x, dtype=np.float64)
        ya = np.ascontiguousarray(y, dtype=np.float64)
        if xa.shape != ya.shape:
            raise ValueError(f"x and y differ in shape ({xa.shape} and {ya.shape})")
        v = self._native.field_values(xa.ravel(), ya.ravel(), float(t))
        return v.reshape(xa.shape)

    # Immutable: copies share it. Pickled as its resolved TOML (file paths in it are absolute),
    # so that Gymnasium can copy an environment's arguments and send them to worker processes.
    def __copy__(self) -> "Scenario":
        return self

    def __deepcopy__(self, memo) -> "Scenario":
        return self

    def __reduce__(self):
        return (Scenario.from_toml, (self.to_toml(),))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scenario) and self.to_toml() == other.to_toml()

    def __hash__(self) -> int:
        return hash(self.to_toml())

    def __repr__(self) -> str:
        first = next((line for line in self.to_toml().splitlines() if line.startswith("name")), "")
        return f"Scenario({first})" if first else "Scenario(<unnamed>)"


def check(scenario: Scenario, tube_halfwidth: Optional[float] = None) -> Dict[str, Any]:
    """``isotrack check --json`` for a scenario, as a dict."""
    return json.loads(scenario._native.check_json(tube_halfwidth))


def sweep(path_or_toml_text: str, threads: Optional[int] = None, progress: bool = False) -> Dict[str, np.ndarray]:
    """Runs a sweep (a sweep file's path, or its TOML text, whose ``scenario`` is then relative
    to the current directory) and returns one numpy array per column of ``results.csv``, in
    ``run_id`` order: float64 for numeric columns (NaN for an empty cell), str otherwise. The
    same cells as ``isotrack sweep`` writes. ``progress=True`` shows the CLI's progress bar on
    stderr (when stderr is a terminal)."""
    import os

    if os.path.isfile(path_or_toml_text):
        with open(path_or_toml_text, encoding="utf-8") as f:
            text, name = f.read(), path_or_toml_text
    else:
        text, name = path_or_toml_text, os.path.join(os.getcwd(), "<toml>")
    header, rows = _native.sweep_cells(text, name, threads, bool(progress))
    out: Dict[str, np.ndarray] = {}
    for k, col in enumerate(header):
        cells = [r[k] for r in rows]
        try:
            out[col] = np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
        except ValueError:
            out[col] = np.array(cells, dtype=str)
    return out


def benchmark(
    controller_factory,
    suite: Optional[str] = None,
    name: str = "python",
    controllers: Optional[list] = None,
    tune: bool = False,
    out: Optional[str] = None,
) -> Dict[str, Any]:
    """Scores your controller with isotrack's benchmark, on the same tasks and seeds as the
    built-in laws (the ``isotrack benchmark`` command's engine).

    ``controller_factory(scenario)`` is called once per run with that run's :class:`Scenario`
    (read ``scenario.level``, ``scenario.max_turn_rate_radps``; never the vehicle's position) and
    returns an object with ``update(t_s, value) -> omega``. Its commands are clipped to the
    task's turn-rate limit. It is scored with the gains it sets itself (the built-in laws run
    with the suite's tuned gains, or retuned with ``tune=True``).

    ``suite``: a suite file (default ``suites/standard-v1.toml`` under the current directory: run
    from the isotrack repository, or pass the path). ``controllers``: which to score (default:
    the suite's built-in laws and yours). ``out``: a directory to write ``leaderboard.csv``,
    ``leaderboard.md``, ``index.html`` and per-task results into.

    Returns a dict: ``overall`` (``[name, score]`` pairs, best first), ``tasks`` (per task:
    ``scores``, ``runs`` with every scored run, ``gains``, ...), ``controllers``, ``suite``,
    ``version``. An exception in your controller is raised here with its traceback.
    """
    import os

    if suite is None:
        suite = os.path.join("suites", "standard-v1.toml")
        if not os.path.isfile(suite):
            raise FileNotFoundError(
                "no suite given and suites/standard-v1.toml is not under the current directory: "
                "run from the isotrack repository or pass suite=PATH"
            )
    if out is not None:
        os.makedirs(out, exist_ok=True)
    text = _native.benchmark_json(
        lambda native: controller_factory(Scenario(native)),
        name,
        str(suite),
        list(controllers) if controllers is not None else None,
        bool(tune),
        None if out is None else str(out),
    )
    return json.loads(text)
