"""Type stubs for the isotrack package."""

import os
from typing import Any, Callable, Dict, List, Mapping, Optional, Protocol, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

class ScenarioError(ValueError):
    """An invalid scenario or override; the message is the CLI's (file, line, column, key)."""

class Controller(Protocol):
    """A coordinate-free controller: the sample time (s) and measured value in, omega (rad/s,
    positive turns left) out."""

    def update(self, t_s: float, value: float) -> float: ...

class Run:
    @property
    def summary(self) -> Dict[str, Any]: ...
    @property
    def trace(self) -> Mapping[str, npt.NDArray[np.float64]]: ...
    @property
    def scenario(self) -> Optional[Scenario]: ...
    @property
    def team(self) -> Optional[Dict[str, Any]]: ...
    @property
    def vehicles(self) -> Optional[Tuple[Dict[str, Any], ...]]: ...
    def vehicle_trace(self, i: int) -> Dict[str, npt.NDArray[np.float64]]: ...
    def __init__(
        self,
        summary: Dict[str, Any],
        trace: Dict[str, npt.NDArray[np.float64]],
        scenario: Optional[Scenario] = ...,
        _summary_json: Optional[str] = ...,
    ) -> None: ...
    def to_pandas(self) -> Any: ...
    def save(self, directory: Union[str, os.PathLike[str]]) -> str: ...

RunDirs = Union[str, os.PathLike[str], Run, Sequence[Union[str, os.PathLike[str], Run]]]

class Scenario:
    @staticmethod
    def default() -> Scenario: ...
    @staticmethod
    def from_file(path: str) -> Scenario: ...
    @staticmethod
    def from_toml(text: str) -> Scenario: ...
    @overload
    def set(self, key: str, value: Any) -> Scenario: ...
    @overload
    def set(self, key: Dict[str, Any]) -> Scenario: ...
    def to_toml(self) -> str: ...
    @property
    def level(self) -> float: ...
    @property
    def max_turn_rate_radps(self) -> Optional[float]: ...
    def run(
        self,
        record_rate_hz: Optional[float] = ...,
        controller: Optional[Union[Controller, Sequence[Controller]]] = ...,
    ) -> Run: ...
    def field_values(
        self, x: npt.ArrayLike, y: npt.ArrayLike, t: float = ...
    ) -> npt.NDArray[np.float64]: ...

def check(scenario: Scenario, tube_halfwidth: Optional[float] = ...) -> Dict[str, Any]: ...

def sweep(
    path_or_toml_text: Union[str, os.PathLike[str]],
    threads: Optional[int] = ...,
    progress: bool = ...,
    controller_factory: Optional[Callable[[Scenario], Controller]] = ...,
) -> Dict[str, npt.NDArray[Any]]: ...

def sweep_base(path_or_toml_text: Union[str, os.PathLike[str]]) -> Scenario: ...

def plot(
    runs: RunDirs,
    out: Optional[str] = ...,
    format: str = ...,
    animate: bool = ...,
    x: Optional[str] = ...,
    group: Optional[str] = ...,
    metric: Optional[str] = ...,
) -> str: ...

def report(runs: RunDirs, out: str) -> str: ...

def compare(
    scenario: Scenario,
    controllers: Optional[List[str]] = ...,
    gains: Optional[List[str]] = ...,
    record_rate_hz: Optional[float] = ...,
    out: Optional[str] = ...,
) -> Dict[str, Run]: ...

def benchmark(
    controller_factory: Callable[[Scenario], Controller],
    suite: Optional[str] = ...,
    name: str = ...,
    controllers: Optional[List[str]] = ...,
    tune: bool = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
