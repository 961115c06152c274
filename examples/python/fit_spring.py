"""Recover a spring's stiffness and damping from a noisy recording, with the run's sensitivities
as the Jacobian of the fit (docs/sensitivities.md).

The "recording" is the closed-form motion of the slider of tests/data/hanging-spring.toml
(2 kg on a vertical guide hanging from a spring-damper, released at the spring's free length)
with k = 400 N/m and c = 4 N·s/m, sampled every 10 ms for 2 s, plus Gaussian noise of 0.5 mm.
The fit starts from k = 250 N/m and c = 1 N·s/m; each evaluation of the model is one dalembert run
that carries d(slider.y)/dk and d(slider.y)/dc along with it, and scipy's least_squares uses them
as its Jacobian.

    .venv/bin/python examples/python/fit_spring.py
"""

import pathlib

import numpy as np
from scipy.optimize import least_squares

import dalembert

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "hanging-spring.toml"
PARAMETERS = ["forces.spring.stiffness", "forces.spring.damping"]
MASS, G = 2.0, 9.81


def closed_form(t, k, c, m=MASS):
    """y(t) of the slider: m ü + c u̇ + k u = −m g with u = y + 1, from rest at u = 0."""
    w = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    wd = w * np.sqrt(1.0 - zeta**2)
    ue = -m * G / k
    return -1.0 + ue * (1.0 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t)))


def recording(k=400.0, c=4.0, noise=5e-4, seed=7):
    t = np.arange(0.0, 2.0 + 1e-9, 0.01)
    rng = np.random.default_rng(seed)
    return t, closed_form(t, k, c) + noise * rng.standard_normal(t.size)


class Model:
    """The scene with (k, c) set; one run per new (k, c) gives both the residuals and their
    Jacobian."""

    def __init__(self, t, y):
        self.scene = dalembert.Scene.load(SCENE)
        self.t, self.y = t, y
        self.runs = 0
        self._cache = None

    def _run(self, x):
        if self._cache is None or not np.array_equal(self._cache[0], x):
            scene = self.scene.with_values({PARAMETERS[0]: float(x[0]), PARAMETERS[1]: float(x[1])})
            run = scene.simulate(end=2.0, every=0.01, sensitivities=PARAMETERS, sensitivity_of=["slider.y"])
            self.runs += 1
            jac = np.column_stack([run.sensitivity("slider.y", p) for p in PARAMETERS])
            self._cache = (np.array(x), run["slider.y"], jac)
        return self._cache

    def residuals(self, x):
        return self._run(x)[1] - self.y

    def jacobian(self, x):
        return self._run(x)[2]


def fit(start=(250.0, 1.0)):
    t, y = recording()
    model = Model(t, y)
    result = least_squares(model.residuals, np.array(start), jac=model.jacobian, x_scale=np.array([100.0, 1.0]))
    # Standard errors from the Jacobian at the solution and the residuals' variance.
    dof = t.size - 2
    sigma2 = float(result.fun @ result.fun) / dof
    cov = sigma2 * np.linalg.inv(result.jac.T @ result.jac)
    return result, np.sqrt(np.diag(cov)), model.runs


def main():
    result, errors, runs = fit()
    k, c = result.x
    print(f"k = {k:.3f} ± {errors[0]:.3f} N/m (true 400), c = {c:.4f} ± {errors[1]:.4f} N·s/m (true 4)")
    print(f"{runs} runs with sensitivities, {result.njev} Jacobians, {result.nfev} residual evaluations")
    return result, errors, runs


if __name__ == "__main__":
    main()
