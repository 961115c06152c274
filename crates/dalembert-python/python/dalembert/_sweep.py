"""Parameter sweeps: the cartesian product (or a list) of scene values, run in Rust on all local
cores, or in chunks on any ``concurrent.futures.Executor`` (process pools, Dask, Slurm through
dask-jobqueue). One run's failure is its row's error; it never loses the other rows."""

from __future__ import annotations

import itertools
import math
import os
import time
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np

from ._dalembert import Scene, sweep_runs

#: Wall time one chunk of runs should take on an executor: scheduling a task costs about a
#: millisecond on a Dask LocalCluster (measured in docs/sweeps.md), so half a second of work per
#: task keeps the overhead well below 5 %.
CHUNK_SECONDS = 0.5


def _runs(parameters: Union[Mapping[str, Sequence[Any]], Iterable[Mapping[str, Any]]]) -> List[Dict[str, Any]]:
    if isinstance(parameters, Mapping):
        paths = list(parameters)
        values = []
        for p in paths:
            v = parameters[p]
            if isinstance(v, (str, bytes)) or not hasattr(v, "__iter__"):
                raise TypeError(f"{p}: expected a list of values, got {v!r}")
            values.append(list(v))
        return [dict(zip(paths, combo)) for combo in itertools.product(*values)]
    runs = [dict(r) for r in parameters]
    for r in runs:
        if not isinstance(r, dict):
            raise TypeError("parameters: a dict of path -> list of values, or a list of dicts path -> value")
    return runs


def _plain(v: Any) -> Any:
    """numpy scalars and arrays as plain Python values (they cross process boundaries cheaply)."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def run_chunk(scene: Scene, runs: List[Dict[str, Any]], outputs: List[str], end: Optional[float], threads: Optional[int]):
    """Runs one chunk (used by executors; a module-level function so that it pickles by name)."""
    return sweep_runs(scene, runs, outputs, end=end, threads=threads)


class SweepResult:
    """One row per run: the parameters, the requested outputs, ``wall_time_s`` and ``error``
    (None for a run that finished). ``result["slider.x"]`` is a numpy array over the runs (NaN
    where a run failed); ``to_pandas()`` gives a DataFrame."""

    def __init__(self, parameters: List[str], outputs: List[str], rows: List[Dict[str, Any]], wall_time_s: float):
        self.parameters = parameters
        self.outputs = outputs
        self.rows = rows
        #: Wall time of the whole sweep (s).
        self.wall_time_s = wall_time_s

    @property
    def columns(self) -> List[str]:
        return self.parameters + self.outputs + ["wall_time_s", "error"]

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.columns:
            raise KeyError(f"unknown column '{name}' (expected {', '.join(self.columns)})")
        values = [r[name] for r in self.rows]
        if name in self.outputs or name == "wall_time_s":
            return np.array(values, dtype=float)
        return np.array(values, dtype=object if name == "error" else None)

    @property
    def errors(self) -> List[Dict[str, Any]]:
        """The rows of the runs that failed."""
        return [r for r in self.rows if r["error"] is not None]

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.rows, columns=self.columns)

    def __repr__(self) -> str:
        return f"<dalembert.SweepResult: {len(self.rows)} runs ({len(self.errors)} failed), {self.wall_time_s:.3f} s>"


def sweep(
    scene: Scene,
    parameters: Union[Mapping[str, Sequence[Any]], Iterable[Mapping[str, Any]]],
    *,
    end: Optional[float] = None,
    outputs: Optional[Sequence[str]] = None,
    executor: Any = None,
    chunk_size: Optional[int] = None,
    threads: Optional[int] = None,
) -> SweepResult:
    """Runs ``scene`` once per combination of ``parameters``.

    ``parameters`` is a dict ``{"bodies.slider.mass": [1, 2, 4], ...}`` (cartesian product, the
    first path varying slowest) or a list of dicts ``[{"bodies.slider.mass": 1}, ...]``.
    ``outputs`` names what each row reports: a column's final value (``"slider.x"``), a summary
    over the run (``"max:slider.x"``, ``"min:"``, ``"mean:"``, ``"maxabs:"``) or a statistic
    (``"statistics.steps"``, ``"statistics.evaluations"``,
    ``"statistics.max_constraint_violation"``, ``"statistics.max_energy_change"``); by default
    the final value of every position column.

    Without ``executor`` the runs share the local cores in Rust (rayon, ``threads`` of them; all
    by default), the GIL released. With an executor (``concurrent.futures.ProcessPoolExecutor``,
    ``distributed.Client.get_executor()``, ...) the runs are sent in chunks of ``chunk_size``
    (default: as many as take about ``CHUNK_SECONDS``, from one run timed here first), each chunk
    on one thread of its worker unless ``threads`` says otherwise.
    """
    if isinstance(scene, (str, os.PathLike)):
        scene = Scene.load(scene)
    elif not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a dalembert.Scene or the path of a scene file, got {type(scene).__name__}")
    runs = [{k: _plain(v) for k, v in r.items()} for r in _runs(parameters)]
    paths: List[str] = []
    for r in runs:
        for p in r:
            if p not in paths:
                paths.append(p)
    if outputs is None:
        outputs = [c for c in scene.columns if c.rsplit(".", 1)[-1] in ("x", "y", "angle") and c != "t"]
    outputs = list(outputs)
    start = time.perf_counter()
    if not runs:
        return SweepResult(paths, outputs, [], 0.0)
    if executor is None:
        try:
            results = sweep_runs(scene, runs, outputs, end=end, threads=threads)
        except KeyboardInterrupt as e:
            # The runs in progress stopped at their next step; the rows so far go with the exception.
            e.result = _result(paths, outputs, runs, getattr(e, "rows", []), start)
            raise
    else:
        # One run here first: it checks paths and outputs (errors raised before anything is sent)
        # and times a run to size the chunks.
        first = sweep_runs(scene, runs[:1], outputs, end=end, threads=1)
        if chunk_size is None:
            per_run = max(first[0][1], 1e-6)
            chunk_size = max(1, min(int(CHUNK_SECONDS / per_run), math.ceil((len(runs) - 1) / (os.cpu_count() or 1)) or 1))
        if chunk_size < 1:
            raise ValueError(f"chunk_size must be at least 1, got {chunk_size}")
        rest = runs[1:]
        futures = [
            executor.submit(run_chunk, scene, rest[i : i + chunk_size], outputs, end, threads or 1)
            for i in range(0, len(rest), chunk_size)
        ]
        results = list(first)
        try:
            for f in futures:
                results.extend(f.result())
        except KeyboardInterrupt as e:
            # Chunks not started are cancelled; the finished chunks' rows go with the exception
            # (a chunk already running on a worker finishes there: an executor cannot stop it).
            for f in futures:
                f.cancel()
            e.result = _result(paths, outputs, runs, results, start)
            raise
    return _result(paths, outputs, runs, results, start)


def _result(paths: List[str], outputs: List[str], runs: List[Dict[str, Any]], results, start: float) -> SweepResult:
    """The rows of the runs that have a result (all of them, unless the sweep was interrupted)."""
    rows = []
    for r, (values, wall, error) in zip(runs, results):
        row: Dict[str, Any] = {p: r.get(p) for p in paths}
        row.update(zip(outputs, values))
        row["wall_time_s"] = wall
        row["error"] = error
        rows.append(row)
    return SweepResult(paths, outputs, rows, time.perf_counter() - start)
