"""Sensitivities from Python: against the closed form of a spring-damper mass, the fit of
examples/python/fit_spring.py, and the errors a user meets."""

import importlib.util

import numpy as np
import pytest

import dalembert

G = 9.81


def slider_y(t, k, c, m):
    """tests/data/hanging-spring.toml in closed form: m ü + c u̇ + k u = −m g, u = y + 1."""
    w = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    wd = w * np.sqrt(1.0 - zeta**2)
    ue = -m * G / k
    return -1.0 + ue * (1.0 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t)))


def derivative(f, x):
    """Richardson-extrapolated central differences of the closed form (1e-12 relative)."""
    h = 1e-3 * x
    d = lambda h: (f(x + h) - f(x - h)) / (2.0 * h)  # noqa: E731
    return (4.0 * d(h / 2.0) - d(h)) / 3.0


def fit_spring(root):
    spec = importlib.util.spec_from_file_location("fit_spring", root / "examples" / "python" / "fit_spring.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_spring_damper_mass_has_the_sensitivities_of_its_closed_form(root):
    # RK4 at 1 ms over 1 s: the motion and its derivatives within 1e-7 of their scale (the Rust
    # test tests/sensitivities.rs gives the budget: method error 5e-9, differences δ² ≈ 2e-8).
    scene = dalembert.Scene.load(root / "tests" / "data" / "hanging-spring.toml")
    params = ["forces.spring.stiffness", "forces.spring.damping", "bodies.slider.mass"]
    run = scene.simulate(end=1.0, every=0.01, sensitivities=params, sensitivity_of=["slider.y"])
    assert run.sensitivity_columns == [f"d(slider.y)/d({p})" for p in params]
    t = run.t
    k, c, m = 400.0, 4.0, 2.0
    exact = {
        params[0]: derivative(lambda k: slider_y(t, k, c, m), k),
        params[1]: derivative(lambda c: slider_y(t, k, c, m), c),
        params[2]: derivative(lambda m: slider_y(t, k, c, m), m),
    }
    for p, want in exact.items():
        got = run.sensitivity("slider.y", p)
        assert got.shape == t.shape
        assert np.max(np.abs(got - want)) < 1e-7 * np.max(np.abs(want)), p


def test_the_fitting_example_recovers_stiffness_and_damping(root):
    # Without noise the fit returns the closed form's own k = 400, c = 4 (to the simulation's
    # 1e-7 relative accuracy: 1e-5 relative); with 0.5 mm of noise within four of its standard
    # errors. Each model evaluation is one run carrying both derivatives, so the fit takes a few
    # runs, not three per Jacobian.
    module = fit_spring(root)
    t, y = module.recording(noise=0.0)
    model = module.Model(t, y)
    from scipy.optimize import least_squares

    exact = least_squares(model.residuals, np.array([250.0, 1.0]), jac=model.jacobian, x_scale=np.array([100.0, 1.0]))
    assert abs(exact.x[0] - 400.0) < 4e-3 and abs(exact.x[1] - 4.0) < 4e-5, exact.x
    result, errors, runs = module.fit()
    assert abs(result.x[0] - 400.0) < 4 * errors[0] and abs(result.x[1] - 4.0) < 4 * errors[1], (result.x, errors)
    assert runs == result.nfev and runs < 20


def test_sensitivity_errors_name_what_is_wrong(root):
    scene = dalembert.Scene.load(root / "tests" / "data" / "hanging-spring.toml")
    with pytest.raises(dalembert.SceneError, match="no force named 'sprung'"):
        scene.simulate(end=0.1, sensitivities=["forces.sprung.stiffness"])
    with pytest.raises(ValueError, match="slider.z"):
        scene.simulate(end=0.1, sensitivities=["forces.spring.stiffness"], sensitivity_of=["slider.z"])
    with pytest.raises(ValueError, match="a run setting"):
        scene.simulate(end=0.1, sensitivities=["simulation.step"])
    with pytest.raises(ValueError, match="need sensitivities"):
        scene.simulate(end=0.1, sensitivity_of=["slider.y"])
    run = scene.simulate(end=0.1)
    with pytest.raises(KeyError, match="no sensitivities"):
        run.sensitivity("slider.y", "forces.spring.stiffness")
