"""Type stubs of the native module (kept in step with crates/dalembert-python/src)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class SceneError(ValueError):
    """A scene that cannot be read, built or changed as asked (one line: file, line, element)."""

class IntegrationError(RuntimeError):
    """A run that stopped early."""

    time: Optional[float]
    run: "Run"

class Run:
    """The rows of a run; columns as in the CSV of ``dalembert simulate``."""

    @property
    def t(self) -> npt.NDArray[np.float64]: ...
    @property
    def columns(self) -> List[str]: ...
    @property
    def data(self) -> npt.NDArray[np.float64]: ...
    @property
    def statistics(self) -> Dict[str, Union[int, float]]: ...
    @property
    def warning(self) -> Optional[str]: ...
    @property
    def sensitivity_columns(self) -> List[str]: ...
    def sensitivity(self, column: str, parameter: str) -> npt.NDArray[np.float64]: ...
    def __getitem__(self, name: str) -> npt.NDArray[np.float64]: ...
    def __contains__(self, name: str) -> bool: ...
    def __len__(self) -> int: ...
    def to_pandas(self) -> Any: ...
    def plot(self, *columns: str, ax: Any = None) -> Any: ...
    def animate(
        self,
        path: Union[str, PathLike[str]],
        max_frames: int = 2400,
        packages: Optional[Dict[str, Union[str, PathLike[str]]]] = None,
        any_mesh_path: bool = False,
    ) -> None: ...

class BodyMotion:
    """The motion of the body a code force acts on (global components)."""

    position: Tuple[float, float, float]
    rotation: Tuple[Tuple[float, float, float], Tuple[float, float, float], Tuple[float, float, float]]
    velocity: Tuple[float, float, float]
    angular_velocity: Tuple[float, float, float]
    angle: Optional[float]

class Simulator:
    """A scene driven step by step; inputs held between sets; columns as in the CSV."""

    @property
    def inputs(self) -> List[str]: ...
    @property
    def code_forces(self) -> List[str]: ...
    def set_force(self, name: str, function: Any) -> None: ...
    def set_input(self, name: str, value: float) -> None: ...
    def input(self, name: str) -> float: ...
    @property
    def t(self) -> float: ...
    def step(self) -> None: ...
    def advance_to(self, t: float) -> None: ...
    def __getitem__(self, column: str) -> float: ...
    @property
    def columns(self) -> List[str]: ...
    def row(self) -> Dict[str, float]: ...
    @property
    def state(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    def set_state(self, q: List[float], v: List[float]) -> Dict[str, float]: ...
    def linearize(
        self,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        states: Optional[Sequence[str]] = None,
    ) -> Dict[str, Any]: ...
    def reset(self) -> None: ...
    @property
    def statistics(self) -> Dict[str, Union[int, float]]: ...

class Scene:
    """A mechanism and its run settings, assembled; immutable and picklable."""

    @staticmethod
    def load(path: Union[str, PathLike[str]]) -> "Scene": ...
    @staticmethod
    def from_toml(text: str, origin: str = "<string>") -> "Scene": ...
    @property
    def name(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def origin(self) -> str: ...
    @property
    def columns(self) -> List[str]: ...
    @property
    def bodies(self) -> List[str]: ...
    @property
    def constraints(self) -> List[str]: ...
    @property
    def settings(self) -> Dict[str, Union[str, float, None, List[str]]]: ...
    def with_values(self, values: Dict[str, Any]) -> "Scene": ...
    def check(self) -> Dict[str, Any]: ...
    def equilibrium(self) -> Dict[str, Any]: ...
    def at_equilibrium(self) -> "Scene": ...
    def modes(self) -> Dict[str, Any]: ...
    def animate_mode(self, path: Union[str, PathLike[str]], mode: int = 1, cycles: int = 3) -> None: ...
    def linearize(
        self,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        at: Union[str, Dict[str, Any], None] = None,
        states: Optional[Sequence[str]] = None,
    ) -> Dict[str, Any]: ...
    def simulate(
        self,
        *,
        end: Optional[float] = None,
        formulation: Optional[str] = None,
        integrator: Optional[str] = None,
        step: Optional[float] = None,
        every: Optional[float] = None,
        stabilization: Optional[str] = None,
        redundant: Optional[str] = None,
        coordinates: Optional[str] = None,
        strict: bool = False,
        sensitivities: Optional[Sequence[str]] = None,
        sensitivity_of: Optional[Sequence[str]] = None,
        relative_change: Optional[float] = None,
        **parameters: float,  # the methods' parameters from the registry: rtol, atol, rho_inf, penalty
    ) -> Run: ...
    def simulator(
        self,
        *,
        end: Optional[float] = None,
        formulation: Optional[str] = None,
        integrator: Optional[str] = None,
        step: Optional[float] = None,
        every: Optional[float] = None,
        stabilization: Optional[str] = None,
        redundant: Optional[str] = None,
        coordinates: Optional[str] = None,
        **parameters: float,
    ) -> "Simulator": ...
    @property
    def inputs(self) -> List[str]: ...
    @property
    def code_forces(self) -> List[str]: ...
    def inverse(self, end: Optional[float] = None, every: Optional[float] = None) -> Run: ...
    def trade(
        self,
        *,
        formulations: Optional[List[str]] = None,
        integrators: Optional[List[str]] = None,
        stabilizations: Optional[List[str]] = None,
        steps: Optional[List[float]] = None,
        tolerances: Optional[List[float]] = None,
        end: Optional[float] = None,
        every: Optional[float] = None,
    ) -> List[Dict[str, Any]]: ...
    def animate(
        self,
        path: Union[str, PathLike[str]],
        max_frames: int = 2400,
        packages: Optional[Dict[str, Union[str, PathLike[str]]]] = None,
        any_mesh_path: bool = False,
    ) -> None: ...

def sweep_runs(
    scene: Scene,
    runs: List[Dict[str, Any]],
    outputs: List[str],
    end: Optional[float] = None,
    threads: Optional[int] = None,
) -> List[Tuple[List[float], float, Optional[str]]]: ...
