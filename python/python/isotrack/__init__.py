"""isotrack from Python: the same engine, scenarios and outputs as the ``isotrack`` command.

>>> import isotrack
>>> run = isotrack.Scenario.default().run()
>>> run.summary["outcome"]
'completed'
>>> run.trace["error"][-1]          # numpy arrays named as trace.csv's columns
"""

from __future__ import annotations

import json
from typing import Any, Callable, Dict, Mapping, Optional

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
    "sweep_base",
    "__version__",
]

__version__: str = _native.version()

#: An invalid scenario or override; the message is the one the CLI prints (file, line, column,
#: key, or the offending assignment).
ScenarioError = _native.ScenarioError


def _type_name(v: Any) -> str:
    return type(v).__name__


def _check_path(name: str, v: Any) -> str:
    """``v`` as a path (a ``str`` or an ``os.PathLike``), else a ``TypeError`` naming ``name``."""
    import os

    if isinstance(v, str):
        return v
    if isinstance(v, os.PathLike):
        p = os.fspath(v)
        if isinstance(p, str):
            return p
    raise TypeError(f"{name} must be a path (str or os.PathLike), got {v!r:.80} ({_type_name(v)})")


def _check_number(name: str, v: Any, optional: bool = False) -> Optional[float]:
    """``v`` as a float: a Python or numpy real number (never a bool, a string or ``None`` unless
    ``optional``), else a ``TypeError`` naming ``name``."""
    if v is None and optional:
        return None
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, got {v!r:.80} ({_type_name(v)})")
    try:
        return float(v)
    except OverflowError:
        raise ValueError(f"{name}: an integer of {int(v).bit_length()} bits is beyond any float") from None


def _check_flag(name: str, v: Any) -> bool:
    """``v`` as a bool (``True``/``False``, numpy's too), else a ``TypeError`` naming ``name``."""
    if not isinstance(v, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {v!r:.80} ({_type_name(v)})")
    return bool(v)


def _check_scenario(name: str, v: Any) -> "Scenario":
    if not isinstance(v, Scenario):
        raise TypeError(f"{name} must be an isotrack.Scenario, got {v!r:.80} ({_type_name(v)})")
    return v


def _check_names(name: str, v: Any) -> Optional[list]:
    """``v`` as a list of strings (``None`` passes), else a ``TypeError`` naming ``name`` (a
    single string too: it is not read as a list of its characters)."""
    if v is None:
        return None
    if isinstance(v, (str, bytes)) or not hasattr(v, "__iter__"):
        raise TypeError(f"{name} must be a list of strings, got {v!r:.80} ({_type_name(v)})")
    items = list(v)
    for x in items:
        if not isinstance(x, str):
            raise TypeError(f"{name} must be a list of strings, holds {x!r:.80} ({_type_name(x)})")
    return items


def _check_controller(name: str, v: Any) -> Any:
    if not callable(getattr(v, "update", None)):
        raise TypeError(
            f"{name} must be an object with update(t_s, value) -> omega, got {v!r:.80} ({_type_name(v)})"
        )
    return v


def _team_controllers(controller: Any, count: int) -> list:
    """A team's controllers, one per vehicle: a list or tuple of ``count`` distinct objects as
    given (one object listed twice is a ``ValueError`` naming both indices: the vehicles would
    share its state), or ``count`` deep copies of one object (each vehicle its own instance)."""
    if isinstance(controller, (list, tuple)):
        if len(controller) != count:
            raise ValueError(f"controller: {len(controller)} controllers for a team of {count}: give one per vehicle")
        first: Dict[int, int] = {}
        for i, c in enumerate(controller):
            j = first.setdefault(id(c), i)
            if j != i:
                raise ValueError(
                    f"controller[{j}] and controller[{i}] are the same object: each vehicle flies its own "
                    "instance (its state is its own, never shared); give one object per vehicle, or pass "
                    "one controller alone (each vehicle then flies its own copy.deepcopy of it)"
                )
        return [_check_controller(f"controller[{i}]", c) for i, c in enumerate(controller)]
    _check_controller("controller", controller)
    import copy

    try:
        return [copy.deepcopy(controller) for _ in range(count)]
    except Exception as e:
        raise TypeError(
            f"controller: a team's vehicles each fly their own copy, but {_type_name(controller)} "
            f"cannot be deep-copied ({e!r:.120}); pass a list of {count} controllers instead"
        ) from e


def _coordinates(name: str, v: Any) -> np.ndarray:
    """Coordinates as a float64 array: real numbers only (a ``TypeError`` naming ``name`` for
    strings, objects, booleans, complex numbers)."""
    a = np.asarray(v)
    if a.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be real numbers (m), got {v!r:.80} (dtype {a.dtype})")
    return np.ascontiguousarray(a, dtype=np.float64)


def _refuse_non_regular(paths: "list[str]") -> None:
    """An ``OSError`` for an output path that exists and is not a regular file (a FIFO would
    block the write until someone reads it, a device would swallow it): checked before anything
    is written, so that nothing blocks and nothing is half written."""
    import os
    import stat

    for p in paths:
        try:
            mode = os.stat(p).st_mode
        except (FileNotFoundError, NotADirectoryError):
            continue
        if not stat.S_ISREG(mode):
            kind = "a directory" if stat.S_ISDIR(mode) else "a FIFO, a device or a socket"
            raise OSError(f"{p}: not a regular file ({kind}): not written")


def _input_file(path: str, what: str) -> None:
    """An input file (a scenario, sweep or suite file) as every function takes it, before it is
    opened: ``FileNotFoundError`` ("no such WHAT") when it does not exist, ``IsADirectoryError``
    for a directory, ``OSError`` for a FIFO, a device or a socket (never opened: a FIFO would
    block until someone writes to it); all three are ``OSError``s with one message per case."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        raise FileNotFoundError(f"{path}: no such {what}") from None
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(f"{path}: not a regular file (a directory)")
    if not stat.S_ISREG(mode):
        raise OSError(f"{path}: not a regular file (a FIFO, a device or a socket)")


#: The largest scenario or sweep text read, bytes (the CLI's limit for scenario and sweep files).
_MAX_TEXT_BYTES = 1 << 20
# `Scenario.set`'s missing value (None is not a value a key takes, but a sentinel says so plainly).
_UNSET = object()


def _check_text_size(name: str, text: str) -> None:
    """A ``ValueError`` for TOML text larger than the CLI reads from a file (1 MiB)."""
    if len(text) > _MAX_TEXT_BYTES or (len(text) * 4 > _MAX_TEXT_BYTES and len(text.encode("utf-8")) > _MAX_TEXT_BYTES):
        raise ValueError(f"{name}: larger than {_MAX_TEXT_BYTES} bytes, not scenario or sweep text")


def _frozen(a: Any) -> np.ndarray:
    """A read-only view of a read-only array: neither it nor anything made from it can write to
    the data a :class:`Run` saves (numpy refuses to make the view writeable again)."""
    a = np.asarray(a)
    a.flags.writeable = False
    return a.view()


def _controller_class(controller: Any) -> str:
    """A Python controller's class, ``module.QualName``, on one line (for summary.json)."""
    cls = type(controller)
    name = f"{getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', cls.__name__)}"
    return " ".join(name.split())[:200]


def _python_summary(summary_json: str, name: str) -> str:
    """``summary.json`` of a run flown by a Python controller: ``controller`` (top level) and
    ``scenario.controller`` say ``kind = "python"`` and its class, not the scenario's built-in
    law (which did not fly; its level and turn-rate limit did apply and are kept)."""
    s = json.loads(summary_json)
    flown = {"kind": "python", "class": name}
    scenario = s.get("scenario")
    if isinstance(scenario, dict):
        law = scenario.get("controller") or {}
        kept = {k: law[k] for k in ("level", "max_turn_rate_radps") if k in law}
        scenario["controller"] = {**flown, **kept}
    s["controller"] = flown
    return json.dumps(s, indent=2, allow_nan=False)


def _python_controller_note(name: str) -> str:
    """The comment that heads ``scenario.toml`` of a run a Python controller flew."""
    return (
        f"# This run was flown by a Python controller ({name}), not by the [controller] law below\n"
        "# (its level and turn-rate limit applied): `isotrack run` on this file flies that built-in\n"
        "# law instead and cannot replay this run without the Python controller.\n"
    )


class Run:
    """A finished run.

    ``summary`` is a dict with exactly the keys of ``summary.json``; ``trace`` a read-only mapping
    of read-only 1-D numpy arrays named as the columns of ``trace.csv`` (``s_measured`` is NaN
    where no sample arrived; ``run.trace["error"].copy()`` to edit one); ``scenario`` the
    scenario flown (``record_rate_hz`` applied). A run cannot be edited: ``summary`` is a fresh
    dict at every access, and :meth:`save` always writes what was simulated.
    """

    def __init__(
        self,
        summary: Dict[str, Any],
        trace: Dict[str, np.ndarray],
        scenario: Optional["Scenario"] = None,
        _summary_json: Optional[str] = None,
    ):
        if scenario is not None:
            _check_scenario("scenario", scenario)
        try:
            # Never the invalid JSON tokens NaN or Infinity.
            text = _summary_json if _summary_json is not None else json.dumps(summary, indent=2, allow_nan=False)
        except ValueError as e:
            raise ValueError(f"summary: {e} (summary.json holds null for a non-finite number)") from None
        # Copies: the caller's arrays stay theirs (and writeable).
        self._init(text, {str(k): np.array(v, dtype=np.float64) for k, v in dict(trace).items()}, scenario)
        # Made by hand, not by a simulation: :meth:`save` refuses it (a run directory is what
        # the engine flew, never a forgery).
        self._simulated = False

    @classmethod
    def _from_native(
        cls, summary_json: str, trace: Dict[str, np.ndarray], scenario: "Scenario", python_controller: Optional[str] = None
    ) -> "Run":
        """A run from the engine's answer (its arrays taken, not copied); ``python_controller``
        names the class of the Python controller that flew it (None: the scenario's own law)."""
        run = cls.__new__(cls)
        run._init(summary_json, trace, scenario)
        run._simulated = True
        run._python_controller = python_controller
        return run

    def _init(self, summary_json: str, trace: Dict[str, np.ndarray], scenario: Optional["Scenario"]) -> None:
        import types

        self._summary_json = summary_json
        self._trace = {k: _frozen(v) for k, v in trace.items()}
        self._trace_view = types.MappingProxyType(self._trace)
        self._scenario = scenario
        self._python_controller: Optional[str] = None

    @property
    def summary(self) -> Dict[str, Any]:
        """The keys of ``summary.json`` (a fresh dict at every access)."""
        return json.loads(self._summary_json)

    @property
    def trace(self) -> "Mapping[str, np.ndarray]":
        """The columns of ``trace.csv``, read-only numpy arrays."""
        return self._trace_view

    @property
    def scenario(self) -> Optional["Scenario"]:
        """The scenario flown (``record_rate_hz`` applied)."""
        return self._scenario

    @property
    def team(self) -> Optional[Dict[str, Any]]:
        """A team's run: ``summary.json``'s ``team`` object (the spacing law, the neighbours,
        the team metrics ``gap_cv``, ``revisit_time_max_s``, ...; a fresh dict at every
        access). ``None`` for one vehicle."""
        return self.summary.get("team")

    @property
    def vehicles(self) -> Optional[tuple]:
        """A team's run: each vehicle's outcome and metrics, in the listed order (the keys of
        a single run's ``summary.json`` metrics: ``outcome``, ``steady_state_max_abs_error``,
        ...; fresh dicts). ``None`` for one vehicle."""
        v = self.summary.get("vehicles")
        return None if v is None else tuple(v)

    def vehicle_trace(self, i: int) -> Dict[str, np.ndarray]:
        """A team's run: vehicle ``i``'s rows of the trace (read-only arrays, without the
        ``vehicle`` column), as a single run's ``trace``."""
        if "vehicle" not in self._trace:
            raise ValueError("not a team's run: its trace is run.trace")
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"i must be a vehicle's index (an int), got {i!r:.80} ({_type_name(i)})")
        count = len(self.summary.get("vehicles") or ())
        if not 0 <= i < count:
            raise IndexError(f"no vehicle {i}: the team has {count} (0 .. {count - 1})")
        rows = self._trace["vehicle"] == i
        return {k: _frozen(v[rows]) for k, v in self._trace.items() if k != "vehicle"}

    def save(self, directory) -> str:
        """Writes the run directory ``isotrack run --out DIR`` writes: ``trace.csv`` (numbers
        that read back bit for bit), ``summary.json`` and the resolved ``scenario.toml``; what
        :func:`plot`, :func:`report` and the ``isotrack`` command take. Creates the directory;
        returns its path.

        Holds the directory's lock (``.isotrack.lock``) as ``isotrack run --out`` does while it
        writes: another writer there (a ``run --out``, another save) makes it raise an
        ``OSError`` naming the holder (``run pid 1234 on node7``), and a ``run --out`` there
        while this saves exits 73.

        Ctrl-C raises ``KeyboardInterrupt`` within a few thousand rows, the trace being copied
        or written, under one rule: either what is left is what was there before (the trace
        is written into a temporary file beside ``trace.csv``, removed then, and a directory
        this call created is removed; no temporary file and no lock file), or the save
        completed: an interrupt that comes during the final writes (after the last row, once
        the earlier run is being replaced) or as the call returns is held until they end and then raised as a
        ``KeyboardInterrupt`` saying "interrupted after the save completed: DIR holds the new
        run". SIGTERM (what Slurm sends at a time limit) is not caught by Python: the process
        ends at once, leaving the earlier run's files (or, during the final writes, the new
        trace without its ``summary.json``: no run that :func:`plot` or :func:`report` takes),
        a ``.trace.csv.PID.tmp`` that the next save or ``isotrack run --out`` there removes,
        and no lock held (the OS lock ends with the process); ``signal.signal(signal.SIGTERM,
        signal.default_int_handler)`` makes SIGTERM end a save as Ctrl-C does."""
        path = _check_path("directory", directory)
        if path == "":
            raise ValueError("directory is empty: name the run directory to write (as `isotrack run --out DIR`)")
        if self._scenario is None or not getattr(self, "_simulated", False):
            raise ValueError(
                "this Run was not made by a simulation (Scenario.run(), compare()): it is not saved "
                "as a run directory (which holds only what the engine flew)"
            )
        import os

        _refuse_non_regular([os.path.join(path, f) for f in ("trace.csv", "summary.json", "scenario.toml")])
        # The [controller] table is the scenario's built-in law, which did not fly a Python
        # controller's run: said at the top of scenario.toml (written under the directory's
        # lock with the rest), so that nobody replays it with the CLI as if it were this run.
        note = "" if self._python_controller is None else _python_controller_note(self._python_controller)
        write = _native.write_team_run if "vehicle" in self._trace else _native.write_run
        done = []  # [True] once the new run is in place (the native call's commit)
        try:
            write(path, self._summary_json, self._scenario._native, dict(self._trace), note, done)
        except KeyboardInterrupt as e:
            # CPython delivers a signal that came while the call was returning right after it
            # returned, here: the new run is in place, and the interrupt says so.
            if done and not str(e).startswith("interrupted after the save completed"):
                raise KeyboardInterrupt(_native.after_save_message(path)) from e
            raise
        return path

    def __reduce__(self):
        # Pickled as its parts (MappingProxyType itself does not pickle): multiprocessing workers
        # can return runs.
        if not getattr(self, "_simulated", False):
            return (Run, (self.summary, {k: np.array(v) for k, v in self._trace.items()}, self._scenario))
        return (
            Run._from_native,
            (self._summary_json, {k: np.array(v) for k, v in self._trace.items()}, self._scenario, self._python_controller),
        )

    def to_pandas(self):
        """The trace as a pandas DataFrame (needs pandas; a copy, free to edit)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Run.to_pandas() needs pandas: pip install pandas") from e
        return pd.DataFrame({k: v.copy() for k, v in self._trace.items()})

    def __repr__(self) -> str:
        s = self.summary
        s = s if isinstance(s, dict) else {}
        rows = len(self._trace["t_s"]) if "t_s" in self._trace else 0
        return f"Run(outcome={s.get('outcome')!r:.80}, t_end_s={s.get('t_end_s')!r:.40}, rows={rows})"


#: SHA-256 of data files already hashed (the check before each run of a scenario), by path,
#: device, inode, size, modification and status-change times: a file rewritten in place keeps
#: its inode and may keep its size and, through ``touch -r`` or a coarse clock, its
#: modification time, but every write sets its status-change time, which no user tool sets
#: back (att40-9: keyed on path, size and modification time alone, such an edit was missed).
_DIGESTS: Dict[tuple, str] = {}


def _sha256(path: str, cached: bool = True) -> str:
    """The file's SHA-256 (hex), from isotrack's one content digest (the Rust function that
    also records a run's data files in ``summary.json``)."""
    import os

    st = os.stat(path)
    key = (path, st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    if cached and key in _DIGESTS:
        return _DIGESTS[key]
    _DIGESTS[key] = _native.file_sha256(path)
    return _DIGESTS[key]


class Scenario:
    """A resolved scenario (every default filled in), immutable: ``set`` returns a new one.

    It pickles as its resolved TOML with the SHA-256 of every data file it read (taken when
    it was made); unpickling (a multiprocessing worker) reads the files again and raises
    ``ValueError`` if one changed since (``FileNotFoundError`` if one is gone): a worker never
    flies another field than the one the parent holds."""

    def __init__(self, native: "_native.Scenario"):
        if not isinstance(native, _native.Scenario):
            raise TypeError(
                "make a Scenario with Scenario.default(), Scenario.from_file(path) or "
                f"Scenario.from_toml(text), not Scenario({native!r:.80})"
            )
        self._native = native
        # The digests of the bytes the field was parsed from (one read), not of a second read
        # of the files after it (a file changed in between would be recorded as the one flown).
        parsed = native.data_file_digests()
        self._digests = {p: parsed.get(p) or _sha256(p) for p in dict.fromkeys(native.data_files())}

    def _derived(self, native: "_native.Scenario") -> "Scenario":
        """A scenario made from this one (``set``): where it flies this one's field as read
        (no file read again), it carries this one's digests, taken when the files were read
        (att39-5: it took them from the files as they are now, so a changed file passed the
        check while the old field flew); otherwise its own, from the files it just read."""
        new = Scenario(native)
        if self._native.shares_field(native):
            new._digests = {p: self._digests.get(p, d) for p, d in new._digests.items()}
        return new

    @staticmethod
    def _unpickle(
        text: str, digests: Dict[str, str], origin: Optional[str] = None, folder: Optional[str] = None
    ) -> "Scenario":
        """A pickled scenario, its data files checked against the digests taken when it was
        made (read afresh, never from the cache); ``origin`` and ``folder`` (absolute: where a
        relative path given to ``set`` is read, taken when its file was read) as it had them."""
        import os

        for p, want in digests.items():
            if not os.path.isfile(p):
                raise FileNotFoundError(f"{p}: the scenario's data file is gone since the scenario was pickled")
            if _sha256(p, cached=False) != want:
                raise ValueError(
                    f"{p}: the scenario's data file changed since the scenario was made (SHA-256 "
                    f"{want[:16]}... then): unpickled, it would fly another field"
                )
        scenario = Scenario.from_toml(text)
        if origin is not None:  # (None: pickled by an isotrack without the folder: as it was then)
            scenario = Scenario(scenario._native.relocated(origin, folder))
        # Again on the bytes the field was parsed from: a file changed between the check above
        # and the read would otherwise fly unnoticed.
        for p, want in digests.items():
            if scenario._digests.get(p, want) != want:
                raise ValueError(
                    f"{p}: the scenario's data file changed while the scenario was unpickled "
                    f"(SHA-256 {want[:16]}... then): unpickled, it would fly another field"
                )
        return scenario

    @staticmethod
    def default() -> "Scenario":
        """The built-in default: the paper's Fig. 2(b) setting."""
        return Scenario(_native.Scenario.default())

    @staticmethod
    def from_file(path: str) -> "Scenario":
        """A scenario file (TOML); the files it names are relative to it, and so is a relative
        file path later given to :meth:`set` (``field.path``, ``field.paths``, as ``isotrack run
        FILE --set`` reads it): the file's folder is taken as an absolute path when it is read,
        so that a later ``os.chdir``, the file's removal, a copy or a pickle (a
        ``multiprocessing`` worker) reads the same files. A path that does not
        exist is a ``FileNotFoundError``, a directory an ``IsADirectoryError``, a FIFO, device
        or socket an ``OSError`` (not opened), as for :func:`sweep` and :func:`benchmark`; one
        that is not a path a ``TypeError``."""
        p = _check_path("path", path)
        _input_file(p, "scenario file")
        return Scenario(_native.Scenario.from_file(p))

    @staticmethod
    def from_toml(text: str) -> "Scenario":
        """Scenario text (TOML); the files it names are relative to the current directory."""
        if not isinstance(text, str):
            raise TypeError(f"text must be scenario text (a str), got {_type_name(text)}")
        _check_text_size("text", text)
        return Scenario(_native.Scenario.from_toml(text))

    def set(self, key: Any, value: Any = _UNSET) -> "Scenario":
        """A new scenario with the dotted ``key`` set to ``value`` (the rules of ``--set``), or
        with every ``key: value`` of a dict set at once (``set({"team.v_min_mps": 0.6,
        "vehicle.speed_mps": 0.7})``, the rules of several ``--set`` in one command: keys that
        bound each other are checked together, in any order; one ``set`` at a time checks each
        against the scenario as it stands).

        ``key``: dotted parts of letters, digits, ``_`` and ``-`` (at most 8), never read as
        TOML text. ``value``: a bool, a 64-bit integer (numpy's too), a finite float, a str, a
        list or tuple of them, or a dict of them (a TOML table, its keys dotted keys: merged
        key by key into the scenario's table, as ``--set 'controller={kp = 2.0}'`` is; a
        list of dicts for ``team.vehicles``), nested at most 8 deep. Anything else raises
        :class:`ScenarioError` (a ``ValueError``) saying what was wrong. A key longer than
        256 bytes is refused before it is read (no scenario key is half as long). One dict
        that sets one key twice (``{"sim": {"seed": 1}, "sim.seed": 2}``: a table holding a
        key and the key itself) is a :class:`ScenarioError` naming both (a table and a key it
        does not hold merge); separate ``set`` calls take the last, as separate ``--set`` do."""
        if isinstance(key, dict):
            if value is not _UNSET:
                raise TypeError("set(dict) takes no value: the dict holds them")
            pairs = []
            for k, v in key.items():
                if not isinstance(k, str):
                    raise TypeError(f"key must be a dotted key (a str), got {k!r:.80} ({_type_name(k)})")
                if isinstance(v, np.ndarray) and v.ndim == 0:
                    v = v[()]
                pairs.append((k, v))
            if not pairs:
                return self
            new = self._derived(self._native.set_many(pairs))
            key = ", ".join(k for k, _ in pairs)
        else:
            if not isinstance(key, str):
                raise TypeError(f"key must be a dotted key (a str), got {key!r:.80} ({_type_name(key)})")
            if value is _UNSET:
                raise TypeError(f"set({key!r:.80}) needs a value")
            if isinstance(value, np.ndarray) and value.ndim == 0:
                value = value[()]  # a 0-d array is its scalar (np.array(3.0) as 3.0, np.array(5) as 5)
            new = self._derived(self._native.set(key, value))
        # Held to the CLI's limit for scenario text, so that what is set also pickles (a pickled
        # scenario is its TOML) and saves as a scenario file the CLI reads.
        if len(new.to_toml().encode("utf-8")) > _MAX_TEXT_BYTES:
            raise ScenarioError(
                f"`{key:.80}`: the scenario would be larger than {_MAX_TEXT_BYTES} bytes of TOML "
                "(the limit of a scenario file)"
            )
        return new

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

        A scenario with a ``[team]`` section runs its team (docs/TEAMS.md), as ``isotrack run``
        does: ``run.trace`` holds every vehicle's rows with a ``vehicle`` column (int64, the
        vehicle's index; the rows of ``trace.csv``, in its order), ``run.summary`` the team's
        ``summary.json`` (top-level metrics vehicle 0's), ``run.team`` the team metrics and
        ``run.vehicles[i]`` vehicle ``i``'s outcome and metrics.

        ``controller``: any object with ``update(t_s, value) -> omega`` (rad/s, positive turns
        left) and optionally ``reset()``: it replaces the scenario's controller and sees only what
        a coordinate-free controller sees, the time and the measured value of each sample. Its
        command is held until the next sample and clipped to the scenario's turn-rate limit
        (``controller.max_turn_rate_radps``, or the airframe's for the fixed-wing UAV), as the
        built-in laws' are. An exception inside it ends the run and is raised here with its
        traceback.

        For a team, each vehicle flies its own controller instance (the spacing law still sets
        the speeds): ``controller`` is either a list (or tuple) of ``team.count`` objects, one
        per vehicle in the listed order (each a distinct object: one listed twice is a
        ``ValueError`` naming both indices), or one object, of which every vehicle flies its own
        ``copy.deepcopy`` (made before the run; the object passed is not flown). Each sees only
        its own vehicle's samples; the first exception in any of them stops the run.
        """
        rate = _check_number("record_rate_hz", record_rate_hz, optional=True)
        self._check_data_files()
        run = self._run(rate, controller)
        self._check_data_files(run.summary.get("data_files") or {})
        return run

    def _check_data_files(self, recorded: Optional[Dict[str, str]] = None) -> None:
        """Raises if a data file of the scenario changed since it was made (att36-10): the
        scenario holds the field as it was read then, so a run would fly that field while its
        ``summary.json`` named the file as it is now (``recorded``: the digests a run's summary
        took, checked after it; ``None``: the files now, before it)."""
        import os

        for p, want in self._digests.items():
            if recorded is None:
                if not os.path.isfile(p):
                    raise FileNotFoundError(
                        f"{p}: the scenario's data file is gone since the scenario was made: make "
                        "the scenario again to fly the files as they are now"
                    )
                now = _sha256(p)
            else:
                now = recorded.get(p, "(not readable at the run's end)")
            if now != want:
                raise ValueError(
                    f"{p}: the scenario's data file changed since the scenario was made (SHA-256 "
                    f"{want[:16]}... then, {now[:16]}... now): the scenario holds the field as it "
                    "was read then, so a run would not be the file's; make the scenario again "
                    "(Scenario.from_file, Scenario.from_toml) to fly the file as it is now"
                )

    def _run(self, rate: Optional[float], controller: Any) -> Run:
        if _native.is_team(self._native):
            if controller is None:
                summary, trace, flown = _native.team_run(self._native, rate)
                return Run._from_native(summary, dict(trace), self._derived(flown))
            controllers = _team_controllers(controller, _native.team_count(self._native))
            summary, trace, flown = _native.team_run(self._native, rate, controllers)
            name = ", ".join(dict.fromkeys(_controller_class(c) for c in controllers))
            return Run._from_native(_python_summary(summary, name), dict(trace), self._derived(flown), name)
        if controller is not None:
            _check_controller("controller", controller)
        summary, trace, flown = self._native.run(rate, controller)
        if controller is None:
            return Run._from_native(summary, dict(trace), self._derived(flown))
        name = _controller_class(controller)
        return Run._from_native(_python_summary(summary, name), dict(trace), self._derived(flown), name)

    def field_values(self, x, y, t: float = 0.0) -> np.ndarray:
        """The field at points ``(x, y)`` (m) at time ``t`` (s, within the run:
        ``0 <= t <= sim.duration_s``, else ``ValueError``), NaN where it has no value;
        vectorised over numpy arrays of any one shape (for plotting with matplotlib). Ctrl-C
        stops it."""
        xa, ya = _coordinates("x", x), _coordinates("y", y)
        if xa.shape != ya.shape:
            raise ValueError(f"x and y differ in shape ({xa.shape} and {ya.shape})")
        v = self._native.field_values(xa.ravel(), ya.ravel(), _check_number("t", t))
        return v.reshape(xa.shape)

    # Immutable: copies share it. Pickled as its resolved TOML (file paths in it are absolute),
    # so that Gymnasium can copy an environment's arguments and send them to worker processes.
    def __copy__(self) -> "Scenario":
        return self

    def __deepcopy__(self, memo) -> "Scenario":
        return self

    def __reduce__(self):
        # The folder travels with it (att30n-11: a spawn worker read a relative `set` path
        # against its own working directory, another file).
        native = self._native
        return (Scenario._unpickle, (self.to_toml(), dict(self._digests), native.origin, native.folder))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scenario) and self.to_toml() == other.to_toml()

    def __hash__(self) -> int:
        return hash(self.to_toml())

    def __repr__(self) -> str:
        text = self.to_toml()
        name = None
        try:
            import tomllib  # Python >= 3.11

            name = tomllib.loads(text).get("name")
        except ImportError:  # pragma: no cover - Python < 3.11: the name's line as written
            first = next((line for line in text.splitlines() if line.startswith("name")), "")
            return f"Scenario({first[:100]})" if first else "Scenario(<unnamed>)"
        # One line, whatever the name holds (its newlines shown as \n by repr).
        return f"Scenario(name = {name!r:.100})" if isinstance(name, str) else "Scenario(<unnamed>)"


def check(scenario: Scenario, tube_halfwidth: Optional[float] = None) -> Dict[str, Any]:
    """``isotrack check --json`` for a scenario, as a dict; ``tube_halfwidth`` (field units,
    default the controller's ``c2``) must be a finite number > 0 (``ValueError``)."""
    _check_scenario("scenario", scenario)
    return json.loads(scenario._native.check_json(_check_number("tube_halfwidth", tube_halfwidth, optional=True)))


def _sweep_column(kind: str, cells: list, masked: bool = False) -> np.ndarray:
    """One ``results.csv`` column as numpy, by the column's kind (from the sweep's plan, never
    guessed from the cells): ``"int"`` int64 (with ``masked``, always a masked array, masked
    where a cell is empty: the ``samples`` of an invalid scenario), ``"float"`` float64 (NaN
    for an empty cell), ``"bool"`` bool, ``"str"`` str (``""`` for an empty cell), ``"table"``
    (a swept key with tables among its values) an object array of the values themselves, each
    cell a TOML literal read back (a table a dict, a string a str)."""
    if kind == "int":
        values = np.array([int(c) if c != "" else 0 for c in cells], dtype=np.int64)
        empty = np.array([c == "" for c in cells], dtype=bool)
        if masked:
            return np.ma.masked_array(values, mask=empty)
        if empty.any():  # pragma: no cover - only `samples` has empty integer cells
            raise RuntimeError("internal error in isotrack: an empty cell in an integer column")
        return values
    if kind == "float":
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
    if kind == "table":
        # An object array, filled item by item (np.array would make a list cell a new axis).
        values = np.empty(len(cells), dtype=object)
        for i, c in enumerate(cells):
            values[i] = _native.toml_cell(c)
        return values
    if kind == "bool":
        values = np.array([c == "true" for c in cells], dtype=np.bool_)
        if masked:
            return np.ma.masked_array(values, mask=np.array([c == "" for c in cells], dtype=bool))
        return values
    return np.array(cells, dtype=np.str_) if cells else np.array([], dtype="<U1")


class _Progress:
    """A sweep's progress on ``sys.stderr`` (what Jupyter and log files capture): on a terminal
    one line redrawn in place at most ten times a second; elsewhere (a notebook, a file, a pipe)
    whole lines, at most one every ``LINE_PERIOD_S`` seconds, plus the first and the last."""

    LINE_PERIOD_S = 5.0

    def __init__(self, stream: Any = None):
        import sys
        import time

        self.stream = sys.stderr if stream is None else stream
        try:
            self.tty = bool(self.stream.isatty())
        except (AttributeError, ValueError, OSError):
            self.tty = False
        self.t0 = time.monotonic()
        self.last = -float("inf")
        self.shown_done: Optional[int] = None

    def __call__(self, done: int, total: int) -> None:
        import time

        if self.stream is None:  # no standard error at all (pythonw)
            return
        now = time.monotonic()
        final = done >= total
        period = 0.1 if self.tty else self.LINE_PERIOD_S
        if not final and self.shown_done is not None and now - self.last < period:
            return
        if final and self.shown_done == done:
            return
        self.last, self.shown_done = now, done
        pct = 100.0 * done / total if total else 100.0
        text = f"sweep: {done}/{total} runs ({pct:.0f} %), {now - self.t0:.1f} s"
        try:
            if self.tty:
                self.stream.write("\r" + text + ("\n" if final else ""))
            else:
                self.stream.write(text + "\n")
            self.stream.flush()
        except Exception:  # noqa: BLE001 - a broken stderr (closed pipe, full disk, closed file)
            # Progress is never worth the sweep's results: no more progress, the sweep goes on.
            self.stream = None


#: The largest sweep file read (the CLI's limit for scenario and sweep files).
_MAX_SWEEP_FILE_BYTES = 1 << 20


def _sweep_text(path_or_toml_text) -> "tuple[str, str]":
    """A sweep's text and its name for messages (relative paths in it are relative to the
    name's directory). A path (a ``PathLike``, or one line without ``=``, which no sweep text
    is) must name a readable regular file: a mistyped path is an error, not TOML text."""
    import os

    if not isinstance(path_or_toml_text, (str, os.PathLike)):
        raise TypeError(
            f"path_or_toml_text must be a sweep file's path or its TOML text, got {path_or_toml_text!r:.80} "
            f"({_type_name(path_or_toml_text)})"
        )
    if isinstance(path_or_toml_text, str) and not path_or_toml_text.strip():
        raise ValueError("path_or_toml_text is empty: give a sweep file's path or its TOML text")
    one_line = isinstance(path_or_toml_text, str) and "\n" not in path_or_toml_text
    if isinstance(path_or_toml_text, os.PathLike) or (
        one_line
        and (
            "=" not in path_or_toml_text
            # A file name with `=` (`out/kp=1.toml`): no TOML line ends in `.toml` outside quotes.
            or (path_or_toml_text.rstrip().endswith(".toml") and not any(q in path_or_toml_text for q in "\"'"))
        )
    ) or os.path.lexists(path_or_toml_text):
        path = os.fspath(path_or_toml_text)
        _input_file(path, "sweep file")
        if os.stat(path).st_size > _MAX_SWEEP_FILE_BYTES:
            raise ValueError(f"{path}: larger than {_MAX_SWEEP_FILE_BYTES} bytes, not a sweep file")
        with open(path, encoding="utf-8") as f:
            return f.read(), path
    _check_text_size("path_or_toml_text", path_or_toml_text)
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
    swept key whose values are integers; ``samples`` is always a masked array, masked where a
    run was an invalid scenario), float64 for the other numeric columns (NaN for an empty cell), str
    otherwise; a swept key with tables among its values (``controller = [{kp = 2.0}, {ki =
    3.0}]``, ``team.vehicles = [[{index = 1, speed_mps = 0.4}], ...]``) an object array of the
    values (a table a dict, which :meth:`Scenario.set` takes back and merges key by key, as
    ``--set`` does). The same cells as ``isotrack sweep`` writes, exactly: setting a row's swept
    keys (``sim.seed`` included; a key whose values are arrays comes back split into ``KEY[0]``,
    ``KEY[1]``, ... columns: set ``KEY`` to the list of them) on :func:`sweep_base` of the same
    sweep and running it gives the row's metrics again (a relative ``field.path`` cell is
    relative to the sweep file's folder, as ``sweep_base`` reads it). Every column's dtype follows from the sweep file alone, whatever its runs give:
    ``outcome`` and ``outcome_detail`` are str (``""`` where a run has no detail), a swept key
    of booleans is bool, of other text str. ``progress=True`` shows the progress on
    ``sys.stderr``: one line redrawn in place on a terminal, else (Jupyter, a log file) a line
    at most every 5 s, and the first and last.

    A sweep of a team scenario (``[team]``) has the team columns after the metric columns, as
    ``isotrack sweep`` writes them (the metric columns vehicle 0's): ``gap_cv``,
    ``time_to_even_s``, ``revisit_time_max_s``, ``revisit_time_mean_s``,
    ``revisit_time_ideal_s``, ``min_separation_m`` (float64, NaN where a run has no team
    metrics) and ``order_preserved`` (a masked bool array, masked where empty).

    ``controller_factory(scenario)``: fly every run with your own controller instead of the
    scenario's: it is called once per run with that run's :class:`Scenario` (for a team, once
    per vehicle of each run: each vehicle its own instance, so that one object returned for
    two vehicles of a run is a ``ValueError`` naming them) and returns an object with
    ``update(t_s, value) -> omega`` (and optionally ``reset()``), as
    ``Scenario.run(controller=...)`` takes; the runs then go one after another (``threads``
    does not apply) and an exception inside it is raised here. Every run flies a new object:
    one the factory already returned for an earlier run is a ``ValueError`` naming both runs
    (its state would carry from run to run, so that a row would depend on the rows before it
    and could not be run again alone); it is refused, never copied. The objects returned are
    held (by weak reference where they allow one) until the sweep returns.

    A sweep file's ``scenario =`` that is missing is a ``FileNotFoundError``, a directory an
    ``IsADirectoryError``, a FIFO, a device or a socket an ``OSError`` (never opened), as the
    same path gets as this function's own argument. A data file a run would read
    (``field.path`` or ``field.paths`` of the scenario, ``[base]`` or ``[grid]``) that cannot be
    read (missing, not a regular file, unreadable) is a ``FileNotFoundError`` before any run,
    with the message ``isotrack sweep`` exits 66 with.

    ``threads``: an int >= 1 (default: all cores; capped at 8 per core). Arguments of the wrong
    type are a ``TypeError`` naming the argument."""
    if threads is not None:
        if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)):
            raise TypeError(f"threads must be an int >= 1 or None, got {threads!r:.80} ({_type_name(threads)})")
        if threads < 1:
            raise ValueError(f"threads must be >= 1, got {threads}")
        import os

        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        if threads > 8 * cores:
            import warnings

            warnings.warn(
                f"threads={int(threads)} capped to {8 * cores} (8 per core on {cores} cores); results do not depend on it",
                stacklevel=2,
            )
            threads = 8 * cores
        threads = int(threads)
    show = _Progress() if _check_flag("progress", progress) else None
    if controller_factory is not None and not callable(controller_factory):
        raise TypeError(f"controller_factory must be callable (scenario -> controller), got {_type_name(controller_factory)}")
    text, name = _sweep_text(path_or_toml_text)
    if controller_factory is not None:
        header, kinds, rows = _native.sweep_cells_with(
            text, name, lambda native: _check_controller("controller_factory(scenario)", controller_factory(Scenario(native))), show
        )
    else:
        header, kinds, rows = _native.sweep_cells(text, name, threads, show)
    if len(kinds) != len(header):  # pragma: no cover - the engine's invariant
        raise RuntimeError(f"internal error in isotrack: {len(header)} columns but {len(kinds)} kinds")
    masked = ("samples", "order_preserved")
    return {col: _sweep_column(kinds[k], [r[k] for r in rows], masked=col in masked) for k, col in enumerate(header)}


def sweep_base(path_or_toml_text: str) -> Scenario:
    """The scenario every run of a sweep is made from: the sweep file's ``scenario`` with its
    ``[base]`` keys set (a path or TOML text, as :func:`sweep` takes). Setting a row's swept
    keys (``sim.seed`` included) on it and running it gives the row's metrics again, bit for
    bit, the cells as :func:`sweep` returns them: a relative file path given to its ``set``
    (a ``[grid] field.path`` or ``field.paths`` cell) is read against the sweep file's folder
    (absolute, taken now), as the sweep reads it, not against the ``scenario`` file's. Its
    errors are :func:`sweep`'s (a data file a run would read that cannot be read is a
    ``FileNotFoundError``)."""
    text, name = _sweep_text(path_or_toml_text)
    return Scenario(_native.sweep_base_scenario(text, name))


def benchmark(
    controller_factory,
    suite: Optional[str] = None,
    name: str = "python",
    controllers: Optional[list] = None,
    tune: bool = False,
    out: Optional[str] = None,
    resume: bool = False,
) -> Dict[str, Any]:
    """Scores your controller with isotrack's benchmark, on the same tasks and seeds as the
    built-in laws (the ``isotrack benchmark`` command's engine).

    ``controller_factory(scenario)`` is called once per run with that run's :class:`Scenario`
    (read ``scenario.level``, ``scenario.max_turn_rate_radps``; never the vehicle's position) and
    returns an object with ``update(t_s, value) -> omega``: a new one at every call (an object
    it already returned for another run is a ``ValueError`` naming both runs, nothing written:
    its state would carry from one seed's run to the next and into the scores). Its commands are clipped to the
    task's turn-rate limit. It is scored with the gains it sets itself (the built-in laws run
    with the suite's tuned gains, or retuned with ``tune=True``).

    ``suite``: a suite file (default ``suites/standard-v2.toml`` under the current directory: run
    from the isotrack repository's root, or pass the path; the package ships no suite, whose
    tasks' scenarios and data files are the repository's). A missing suite file is a
    ``FileNotFoundError``, a directory an ``IsADirectoryError``, a FIFO an ``OSError``. ``controllers``: which to score (default:
    the suite's built-in laws and yours). ``out``: a directory to write ``leaderboard.csv``,
    ``leaderboard.md``, ``index.html``, ``suite.toml`` (the suite as run, with the gains
    its scores used) and per-task results into, as ``isotrack benchmark --out``: a directory
    that already holds a benchmark is refused (``OSError``) unless ``resume=True`` (its task
    results reused), and one that another benchmark or sweep is writing (its lock held) too.
    A task is reused only when its suite entry, scenario file and data files are unchanged, but
    your controller's code is not part of that check: after changing the controller, pass
    another ``name`` or ``out`` (a reused task keeps the old controller's scores).

    Returns a dict: ``overall`` (``[name, score]`` pairs, best first), ``tasks`` (per task:
    ``scores``, ``runs`` with every scored run, ``gains``, ...), ``controllers``, ``suite``,
    ``version``. An exception in your controller is raised here with its traceback.

    ``name`` names your row: a built-in law's name (it would replace that law's row), an empty
    name, or one with ``|`` or a control character (they break the Markdown leaderboard) is a
    ``ValueError``. Ctrl-C stops the benchmark before its next run.
    """
    import os

    if not callable(controller_factory):
        raise TypeError(f"controller_factory must be callable (scenario -> controller), got {_type_name(controller_factory)}")
    if not isinstance(name, str):
        raise TypeError(f"name must be a str, got {name!r:.80} ({_type_name(name)})")
    controllers = _check_names("controllers", controllers)
    if controllers is not None and not controllers:
        raise ValueError("controllers is empty: name at least one controller to score (or pass None for all)")
    tune = _check_flag("tune", tune)
    resume = _check_flag("resume", resume)
    out = None if out is None else _check_path("out", out)
    if suite is not None:
        suite = _check_path("suite", suite)
        if os.path.lexists(suite):  # a missing one: FileNotFoundError, after the name's check
            _input_file(suite, "suite file")
    if suite is None:
        suite = os.path.join("suites", "standard-v2.toml")
        if not os.path.isfile(suite):
            raise FileNotFoundError(
                "no suite given and suites/standard-v2.toml is not under the current directory: "
                "run from the isotrack repository's root or pass suite= a checkout's "
                "suites/standard-v2.toml (the package ships no suite: its tasks' scenarios and "
                "data files are the repository's)"
            )
    if out is not None:
        if out == "":
            raise ValueError("out is empty: name the benchmark directory to write")
        _refuse_non_regular(
            [os.path.join(out, f) for f in ("leaderboard.csv", "leaderboard.md", "index.html", "suite.toml")]
        )
    text = _native.benchmark_json(
        lambda native: _check_controller("controller_factory(scenario)", controller_factory(Scenario(native))),
        name,
        suite,
        controllers,
        tune,
        out,
        resume,
    )
    return json.loads(text)


def _run_dirs(runs, scratch: Optional[str]) -> list:
    """Run directories from paths and :class:`Run` objects (saved into ``scratch/run-N``)."""
    import os

    if isinstance(runs, (str, os.PathLike, Run)):
        runs = [runs]
    if isinstance(runs, bytes) or not hasattr(runs, "__iter__"):
        raise TypeError(
            f"runs must be a run directory, a Run, or a list of them, got {runs!r:.80} ({_type_name(runs)})"
        )
    runs = list(runs)
    if not runs:
        raise ValueError("runs is empty: give at least one run directory or Run")
    dirs = []
    for i, r in enumerate(runs):
        if isinstance(r, Run):
            continue
        d = _check_path(f"runs[{i}]", r)
        if not os.path.lexists(d):
            raise FileNotFoundError(f"runs[{i}]: {d}: no such run directory")
        if not os.path.isdir(d):
            raise NotADirectoryError(f"runs[{i}]: {d}: not a run directory")
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
    ``x``, ``group``, ``metric`` as the command's options). Returns the output directory (the
    figures are the files named above in it), not a list of files."""
    import os

    if format not in ("png", "svg"):
        raise ValueError(f"format must be 'png' or 'svg', got {format!r:.80}")
    out = None if out is None else _check_path("out", out)
    animate = _check_flag("animate", animate)
    for arg, v in (("x", x), ("group", group), ("metric", metric)):
        if v is not None and not isinstance(v, str):
            raise TypeError(f"{arg} must be a column name (str) or None, got {v!r:.80} ({_type_name(v)})")
    dirs = _run_dirs(runs, None if out is None else os.path.join(os.fspath(out), "runs"))
    sweep_options = [a for a, v in (("x", x), ("group", group), ("metric", metric)) if v is not None]
    if sweep_options and not (len(dirs) == 1 and os.path.isfile(os.path.join(dirs[0], "results.csv"))):
        raise TypeError(
            f"{', '.join(sweep_options)}: options of a sweep directory's plot (results.csv), "
            "not of run directories: not ignored"
        )
    ext = "svg" if format == "svg" else "png"
    _refuse_non_regular(
        [os.path.join(out if out is not None else dirs[0], f) for f in (f"trajectory.{ext}", f"timeseries.{ext}", "animation.gif")]
    )
    _native.plot(dirs, None if out is None else os.fspath(out), format == "svg", bool(animate), x, group, metric)
    return os.fspath(out) if out is not None else dirs[0]


def report(runs, out: str) -> str:
    """``isotrack report``: one self-contained HTML page (the field, the paths with a time
    slider, the error, measurement and turn-rate plots) of one or more runs, written to the file
    ``out``. ``runs``: run directories or :class:`Run` objects (saved beside ``out``, in
    ``OUT_runs/``). Returns ``out``."""
    import os

    out = _check_path("out", out)
    _refuse_non_regular([out])
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
    defaults with the scenario's level, side, limit, estimator and search phase; ``gains`` as ``--gain``:
    ``["sliding_mode.gamma=0.3"]``); ``controllers`` empty or naming a law twice is a
    ``ValueError`` (a comparison of nothing, or a dict that would drop a run). Returns
    ``{law: Run}`` in order; with ``out``, each run is
    also saved as ``out/LAW`` (run directories for :func:`plot` and :func:`report`)."""
    import os

    _check_scenario("scenario", scenario)
    kinds = _check_names("controllers", controllers)
    if kinds is None:
        kinds = _native.controller_kinds()
    elif not kinds:
        raise ValueError("controllers is empty: name at least one built-in law (or pass None for all)")
    known = list(_native.controller_kinds())
    seen = set()
    for k in kinds:
        if k not in known:
            # Exactly a law's name: " pi_isoline" would be a dict key and an out/ directory
            # name with a blank in it.
            raise ValueError(
                f"unknown controller {k!r:.80}: not exactly a built-in law's name (known: {', '.join(known)})"
            )
        if k in seen:
            raise ValueError(f"controllers names {k!r:.80} twice: each law is flown once")
        seen.add(k)
    gains = _check_names("gains", gains) or []
    rate = _check_number("record_rate_hz", record_rate_hz, optional=True)
    out = None if out is None else _check_path("out", out)
    variants = [Scenario(_native.controller_variant(scenario._native, k, gains)) for k in kinds]
    runs: Dict[str, Run] = {}
    for k, variant in zip(kinds, variants):
        runs[k] = variant.run(record_rate_hz=rate)
        if out is not None:
            runs[k].save(os.path.join(os.fspath(out), str(k)))
    return runs
