"""isotrack from Python: the same engine, scenarios and outputs as the ``isotrack`` command.

>>> import isotrack
>>> run = isotrack.Scenario.default().run()
>>> run.summary["outcome"]
'completed'
>>> run.trace["error"][-1]          # numpy arrays named as trace.csv's columns
"""

from __future__ import annotations

import json
from typing import Any, Callable, Dict, Optional

import numpy as np

from . import _native

__all__ = [
    "Scenario",
    "Run",
    "ScenarioError",
    "benchmark",
    "check",
    "compare",
    "plot",
    "report",
    "sweep",
    "__version__",
]

__version__: str = _native.version()

#: An invalid scenario or override; the message is the one the CLI prints (file, line, column,
#: key, or the offending assignment).
ScenarioError = _native.ScenarioError


class Run:
    """A finished run.

    ``summary`` is a dict with exactly the keys of ``summary.json``; ``trace`` a dict of 1-D numpy
    arrays named as the columns of ``trace.csv`` (``s_measured`` is NaN where no sample arrived);
    ``scenario`` the scenario flown (``record_rate_hz`` applied).
    """

    def __init__(
        self,
        summary: Dict[str, Any],
        trace: Dict[str, np.ndarray],
        scenario: Optional["Scenario"] = None,
        _summary_json: Optional[str] = None,
    ):
        self.summary = summary
        self.trace = trace
        self.scenario = scenario
        self._summary_json = _summary_json

    def save(self, directory) -> str:
        """Writes the run directory ``isotrack run --out DIR`` writes: ``trace.csv`` (numbers
        that read back bit for bit), ``summary.json`` and the resolved ``scenario.toml``; what
        :func:`plot`, :func:`report` and the ``isotrack`` command take. Creates the directory;
        returns its path."""
        import os

        if self.scenario is None:
            raise ValueError("this Run was not made by Scenario.run(): it has no scenario to save")
        text = self._summary_json if self._summary_json is not None else json.dumps(self.summary, indent=2)
        path = os.fspath(directory)
        _native.write_run(path, text, self.scenario._native, self.trace)
        return path

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
        """A new scenario with the dotted ``key`` set to ``value`` (the rules of ``--set``).

        ``key``: dotted parts of letters, digits, ``_`` and ``-`` (at most 8), never read as
        TOML text. ``value``: a bool, a 64-bit integer (numpy's too), a finite float, a str, or
        a list or tuple of them nested at most 8 deep. Anything else raises
        :class:`ScenarioError` (a ``ValueError``) saying what was wrong."""
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
        summary, trace, flown = self._native.run(record_rate_hz, controller)
        return Run(json.loads(summary), dict(trace), Scenario(flown), summary)

    def field_values(self, x, y, t: float = 0.0) -> np.ndarray:
        """The field at points ``(x, y)`` (m) at time ``t`` (s, within the run:
        ``0 <= t <= sim.duration_s``, else ``ValueError``), NaN where it has no value;
        vectorised over numpy arrays of any one shape (for plotting with matplotlib). Ctrl-C
        stops it."""
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
    """``isotrack check --json`` for a scenario, as a dict; ``tube_halfwidth`` (field units,
    default the controller's ``c2``) must be a finite number > 0 (``ValueError``)."""
    return json.loads(scenario._native.check_json(tube_halfwidth))


#: Columns of ``results.csv`` that hold integers whatever their cells: the run's id, its seed
#: (63 bits: a float64 would round it and re-running the row would give another run) and the
#: sample count.
_INT_COLUMNS = frozenset({"run_id", "sim.seed", "samples"})


def _is_int_cell(c: str) -> bool:
    """A cell written from an integer (isotrack writes every float with a '.' or an exponent)."""
    digits = c[1:] if c[:1] in "+-" else c
    return digits.isdigit()


def _sweep_column(name: str, cells: list) -> np.ndarray:
    """One ``results.csv`` column as numpy: int64 for integers (a masked array where a cell is
    empty: the ``samples`` of an invalid scenario), float64 for numbers (NaN for an empty cell),
    str otherwise."""
    filled = [c for c in cells if c != ""]
    if all(_is_int_cell(c) for c in filled) and (name in _INT_COLUMNS or len(filled) == len(cells)):
        values = np.array([int(c) if c != "" else 0 for c in cells], dtype=np.int64)
        if len(filled) == len(cells):
            return values
        return np.ma.masked_array(values, mask=[c == "" for c in cells])
    try:
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
    except ValueError:
        return np.array(cells, dtype=str)


#: The largest sweep file read (the CLI's limit for scenario and sweep files).
_MAX_SWEEP_FILE_BYTES = 1 << 20


def _sweep_text(path_or_toml_text) -> "tuple[str, str]":
    """A sweep's text and its name for messages (relative paths in it are relative to the
    name's directory). A path (a ``PathLike``, or one line without ``=``, which no sweep text
    is) must name a readable regular file: a mistyped path is an error, not TOML text."""
    import os
    import stat

    if isinstance(path_or_toml_text, os.PathLike) or (
        "\n" not in path_or_toml_text and "=" not in path_or_toml_text
    ) or os.path.lexists(path_or_toml_text):
        path = os.fspath(path_or_toml_text)
        try:
            mode = os.stat(path).st_mode
        except FileNotFoundError:
            raise FileNotFoundError(f"{path}: no such sweep file") from None
        if not stat.S_ISREG(mode):
            # Not opened: a FIFO would block until someone writes to it.
            raise IsADirectoryError(f"{path}: not a regular file") if stat.S_ISDIR(mode) else OSError(
                f"{path}: not a regular file (a FIFO, a device or a socket)"
            )
        if os.stat(path).st_size > _MAX_SWEEP_FILE_BYTES:
            raise ValueError(f"{path}: larger than {_MAX_SWEEP_FILE_BYTES} bytes, not a sweep file")
        with open(path, encoding="utf-8") as f:
            return f.read(), path
    return path_or_toml_text, os.path.join(os.getcwd(), "<toml>")


def sweep(
    path_or_toml_text: str,
    threads: Optional[int] = None,
    progress: bool = False,
    controller_factory: Optional[Callable[["Scenario"], Any]] = None,
) -> Dict[str, np.ndarray]:
    """Runs a sweep (a sweep file's path, or its TOML text, whose ``scenario`` is then relative
    to the current directory) and returns one numpy array per column of ``results.csv``, in
    ``run_id`` order: int64 for integer columns (``run_id``, ``sim.seed``, ``samples``, and any
    swept key whose values are integers; ``samples`` is a masked array where a run was an
    invalid scenario), float64 for the other numeric columns (NaN for an empty cell), str
    otherwise. The same cells as ``isotrack sweep`` writes, exactly: setting a row's swept keys
    (``sim.seed`` included) on the sweep's scenario and running it gives the row's metrics
    again. ``progress=True`` shows the CLI's progress bar on stderr (when stderr is a
    terminal).

    ``controller_factory(scenario)``: fly every run with your own controller instead of the
    scenario's: it is called once per run with that run's :class:`Scenario` and returns an
    object with ``update(t_s, value) -> omega`` (and optionally ``reset()``), as
    ``Scenario.run(controller=...)`` takes; the runs then go one after another (``threads`` and
    ``progress`` do not apply) and an exception inside it is raised here."""
    text, name = _sweep_text(path_or_toml_text)
    if controller_factory is not None:
        header, rows = _native.sweep_cells_with(
            text, name, lambda native: controller_factory(Scenario(native))
        )
    else:
        header, rows = _native.sweep_cells(text, name, threads, bool(progress))
    return {col: _sweep_column(col, [r[k] for r in rows]) for k, col in enumerate(header)}


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

    ``suite``: a suite file (default ``suites/standard-v2.toml`` under the current directory: run
    from the isotrack repository, or pass the path). ``controllers``: which to score (default:
    the suite's built-in laws and yours). ``out``: a directory to write ``leaderboard.csv``,
    ``leaderboard.md``, ``index.html`` and per-task results into.

    Returns a dict: ``overall`` (``[name, score]`` pairs, best first), ``tasks`` (per task:
    ``scores``, ``runs`` with every scored run, ``gains``, ...), ``controllers``, ``suite``,
    ``version``. An exception in your controller is raised here with its traceback.

    ``name`` names your row: a built-in law's name (it would replace that law's row), an empty
    name, or one with ``|`` or a control character (they break the Markdown leaderboard) is a
    ``ValueError``. Ctrl-C stops the benchmark before its next run.
    """
    import os

    if suite is None:
        suite = os.path.join("suites", "standard-v2.toml")
        if not os.path.isfile(suite):
            raise FileNotFoundError(
                "no suite given and suites/standard-v2.toml is not under the current directory: "
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


def _run_dirs(runs, scratch: Optional[str]) -> list:
    """Run directories from paths and :class:`Run` objects (saved into ``scratch/run-N``)."""
    import os

    if isinstance(runs, (str, os.PathLike, Run)):
        runs = [runs]
    dirs = []
    for i, r in enumerate(runs):
        if isinstance(r, Run):
            if scratch is None:
                raise ValueError("pass out=... to plot or report Run objects (they are saved there)")
            dirs.append(r.save(os.path.join(scratch, f"run-{i}")))
        else:
            dirs.append(os.fspath(r))
    return dirs


def plot(
    runs,
    out: Optional[str] = None,
    format: str = "png",
    animate: bool = False,
    x: Optional[str] = None,
    group: Optional[str] = None,
    metric: Optional[str] = None,
) -> str:
    """``isotrack plot``: draws ``trajectory.png`` and ``timeseries.png`` (``format="svg"``:
    SVG; ``animate=True`` adds ``animation.gif``) of one or more runs, overlaid, into ``out``
    (default: the first run directory). ``runs``: run directories (``Run.save``, ``isotrack run
    --out``), :class:`Run` objects (saved under ``out/runs``), or one sweep directory (with
    ``x``, ``group``, ``metric`` as the command's options). Returns the output directory."""
    import os

    if format not in ("png", "svg"):
        raise ValueError(f"format must be 'png' or 'svg', got {format!r}")
    dirs = _run_dirs(runs, None if out is None else os.path.join(os.fspath(out), "runs"))
    _native.plot(dirs, None if out is None else os.fspath(out), format == "svg", bool(animate), x, group, metric)
    return os.fspath(out) if out is not None else dirs[0]


def report(runs, out: str) -> str:
    """``isotrack report``: one self-contained HTML page (the field, the paths with a time
    slider, the error, measurement and turn-rate plots) of one or more runs, written to the file
    ``out``. ``runs``: run directories or :class:`Run` objects (saved beside ``out``, in
    ``OUT_runs/``). Returns ``out``."""
    import os

    out = os.fspath(out)
    dirs = _run_dirs(runs, out + "_runs")
    _native.report(dirs, out)
    return out


def compare(
    scenario: Scenario,
    controllers: Optional[list] = None,
    gains: Optional[list] = None,
    record_rate_hz: Optional[float] = None,
    out: Optional[str] = None,
) -> Dict[str, Run]:
    """``isotrack compare``: the scenario flown by each built-in law (default: all of them) on
    the same field, start, sensor and turn-rate limit, as the command flies them (a law's
    defaults with the scenario's level, side, limit and estimator; ``gains`` as ``--gain``:
    ``["sliding_mode.gamma=0.3"]``). Returns ``{law: Run}`` in order; with ``out``, each run is
    also saved as ``out/LAW`` (run directories for :func:`plot` and :func:`report`)."""
    import os

    kinds = list(controllers) if controllers is not None else _native.controller_kinds()
    runs: Dict[str, Run] = {}
    for k in kinds:
        variant = Scenario(_native.controller_variant(scenario._native, str(k), list(gains or [])))
        runs[k] = variant.run(record_rate_hz=record_rate_hz)
        if out is not None:
            runs[k].save(os.path.join(os.fspath(out), str(k)))
    return runs
