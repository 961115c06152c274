"""dalembert: constrained multibody dynamics from scene files.

>>> import dalembert
>>> scene = dalembert.Scene.load("scenes/slider-crank.toml")
>>> run = scene.simulate(end=1.0, formulation="embedding", integrator="rk4", step=1e-3)
>>> run.t[-1], run["slider.x"][-1]          # numpy arrays            # doctest: +SKIP

``scene.simulator(...)`` drives a scene step by step: ``set_input`` holds a named input
(``{ input = "push" }`` in the scene) until set again, ``advance_to(t)`` goes to exactly ``t``,
``sim["slider.x"]`` reads any output column.

Scenes are immutable (``with_values`` returns a changed copy) and picklable, runs hold numpy
arrays, and ``sweep`` runs many variants of a scene on all local cores or on any
``concurrent.futures.Executor`` (a Dask cluster's included). Errors are ``SceneError`` and
``IntegrationError`` with the command line's one-line messages.
"""

from ._dalembert import BodyMotion, IntegrationError, Run, Scene, SceneError, Simulator, __version__
from ._sweep import SweepResult, sweep

__all__ = ["Scene", "Run", "Simulator", "BodyMotion", "SceneError", "IntegrationError", "sweep", "SweepResult", "__version__"]
