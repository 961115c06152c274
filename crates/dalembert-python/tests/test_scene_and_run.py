"""Scenes, runs and errors: numbers checked against the command line, closed forms and the
other formulations."""

import csv
import math
import pickle
import subprocess
import threading
import time

import numpy as np
import pytest

import dalembert
from conftest import cli

# A uniform rod pinned at one end, written exactly (horizontal) so that the pivot is exactly
# L/2 = 0.5 m from the centre of mass.
PENDULUM = """
[scene]
name = "pendulum"
gravity = [0.0, -9.81]

[[bodies]]
name = "rod"
mass = 1.0
shape = { rod = 1.0 }
position = [0.5, 0.0]
angle = 0.0

[[joints]]
name = "pivot"
type = "revolute"
bodies = ["ground", "rod"]
at = [0.0, 0.0]

[simulation]
end = 2.0
integrator = "rk4"
step = 1e-4
output_every = 0.01
stabilization = "projection"
"""


def test_readme_api(scenes):
    scene = dalembert.Scene.load(scenes / "slider-crank.toml")
    run = scene.simulate(end=1.0, formulation="embedding", integrator="rk4", step=1e-3)
    assert isinstance(run.t, np.ndarray) and run.t[0] == 0.0 and run.t[-1] == pytest.approx(1.0, abs=1e-12)
    assert run["slider.x"].shape == run.t.shape == (101,)
    assert run.columns[0] == "t" and "guide.fy" in run.columns
    assert run.statistics["steps"] == 1000
    assert run.data.shape == (101, len(run.columns))


def test_run_is_the_cli_csv_bit_for_bit(scenes, tmp_path):
    """The package and `dalembert simulate --output` are one computation: same columns, same
    numbers (the CSV holds shortest round-trip decimals, so equality is exact)."""
    out = tmp_path / "run.csv"
    subprocess.run(
        [cli(), "simulate", scenes / "slider-crank.toml", "--end", "0.5", "--formulation", "amalgamated", "--output", out],
        check=True,
        capture_output=True,
    )
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    run = dalembert.Scene.load(scenes / "slider-crank.toml").simulate(end=0.5, formulation="amalgamated")
    assert rows[0] == run.columns
    np.testing.assert_array_equal(np.array(rows[1:], dtype=float), run.data)


def test_formulations_agree(scenes):
    """Same scene, same integrator, three formulations: each step solves the same equations, so
    the trajectories agree to near round-off accumulated over 1000 steps (1e-9 m)."""
    scene = dalembert.Scene.load(scenes / "four-bar.toml")
    runs = {f: scene.simulate(end=1.0, formulation=f, integrator="rk4", step=1e-3) for f in ("augmented", "embedding", "amalgamated")}
    ref = runs["augmented"]
    for f, r in runs.items():
        for c in ("coupler.x", "coupler.y", "rocker.angle"):
            np.testing.assert_allclose(r[c], ref[c], rtol=0, atol=1e-9, err_msg=f"{f} {c}")


def test_gravity_scaling_law():
    """θ(t) under gravity 4g equals θ(2t) under g (the time scale is sqrt(L/g)); the same mass,
    any mass (Galileo): a closed-form similarity checked through with_values."""
    base = dalembert.Scene.from_toml(PENDULUM)
    slow = base.simulate(end=2.0)
    fast = base.with_values({"scene.gravity": [0.0, -4 * 9.81], "bodies.rod.mass": 7.5}).simulate(end=1.0, every=0.005)
    # fast at t = 0.005 k against slow at t = 0.01 k.
    np.testing.assert_allclose(fast["rod.angle"], slow["rod.angle"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast["rod.omega"], 2 * slow["rod.omega"], rtol=0, atol=1e-8)


def test_check_matches_gruebler(scenes):
    """Slider-crank: 3 bodies (9 coordinates), 3 pins and a prismatic joint (8 equations): 1 DOF."""
    r = dalembert.Scene.load(scenes / "slider-crank.toml").check()
    assert (r["coordinates"], r["equations"], r["rank"], r["dof"]) == (9, 8, 8, 1)
    assert r["problems"] == [] and r["redundant"] == []
    assert set(r["accelerations"]) == {f"{b}.{c}" for b in ("crank", "rod", "slider") for c in ("x", "y", "angle")}
    assert "guide.fy" in r["reactions"]
    # The slider stays on its guide: its vertical acceleration is zero.
    assert abs(r["accelerations"]["slider.y"]) < 1e-12


def test_inverse_dynamics_closed_form():
    """A rod driven at a constant rate about its pivot needs the torque dV/dθ = m g (L/2) cos θ
    (θ measured from the horizontal, no angular acceleration)."""
    text = PENDULUM + """
[[drivers]]
name = "motor"
type = "joint-angle"
joint = "pivot"
function = { kind = "linear", rate = 2.0 }
"""
    run = dalembert.Scene.from_toml(text).inverse(end=1.0, every=0.05)
    assert len(run) == 21
    theta = run["rod.angle"]
    np.testing.assert_allclose(run["rod.omega"], 2.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run["motor.effort"], 1.0 * 9.81 * 0.5 * np.cos(theta), rtol=0, atol=1e-8)


def test_with_values_errors_are_one_line(scenes):
    scene = dalembert.Scene.load(scenes / "slider-crank.toml")
    with pytest.raises(dalembert.SceneError, match=r"no body named 'slidr' \(the scene's bodies: crank, rod, slider\)"):
        scene.with_values({"bodies.slidr.mass": 2.0})
    with pytest.raises(dalembert.SceneError, match=r"body 'slider': mass must be finite and non-negative, got -1"):
        scene.with_values({"bodies.slider.mass": -1.0})
    with pytest.raises(TypeError, match="bodies.slider.mass"):
        scene.with_values({"bodies.slider.mass": object()})
    with pytest.raises(dalembert.SceneError, match=r":3:1: "):
        dalembert.Scene.from_toml("[scene]\nname = 'x'\nbogus = 1\n", "x.toml")


def test_settings_name_the_independent_coordinates():
    # The scene key `independent` reads back by name (the model's velocity names), and runs: the
    # embedding with the rod's angle independent keeps the augmented formulation's motion to the
    # projection's tolerance (both RK4 at 1e-4 s from the same state; 1e-9 rad leaves room for the
    # 1e-12 Newton tolerance accumulated over 20 000 steps).
    scene = dalembert.Scene.from_toml(PENDULUM.replace('step = 1e-4', 'step = 1e-4\nformulation = "embedding"\nindependent = ["rod.angle"]'))
    assert scene.settings["independent"] == ["rod.angle"]
    assert dalembert.Scene.from_toml(PENDULUM).settings["independent"] is None
    emb = scene.simulate()
    # The other formulations have no partition: simulate says it ignores the key.
    with pytest.warns(UserWarning, match="embedding formulation only"):
        aug = scene.simulate(formulation="augmented")
    assert abs(emb["rod.angle"][-1] - aug["rod.angle"][-1]) < 1e-9


def test_bad_keywords_name_the_keyword(scenes):
    scene = dalembert.Scene.load(scenes / "slider-crank.toml")
    with pytest.raises(ValueError, match="^step must be positive, got -0.001$"):
        scene.simulate(step=-1e-3)
    with pytest.raises(ValueError, match=r"^unknown integrator 'rk5' \(expected symplectic-euler, rk4, dopri5, generalized-alpha, ali3-p\); did you mean 'rk4'\?$"):
        scene.simulate(integrator="rk5")
    # A mistyped keyword: every keyword listed, the nearest suggested.
    with pytest.raises(TypeError, match=r"^simulate\(\) got an unexpected keyword 'ende' \(keywords: end, formulation, integrator, step, every, stabilization, redundant, coordinates, strict, rtol, atol, rho_inf, penalty\); did you mean 'end'\?$"):
        scene.simulate(ende=1.0)
    with pytest.raises(TypeError, match=r"did you mean 'rho_inf'\?$"):
        scene.simulate(rho_ind=0.5)
    with pytest.warns(UserWarning, match="rtol applies to dopri5 only"):
        scene.simulate(end=0.01, rtol=1e-6)
    with pytest.raises(KeyError, match="unknown column 'slider.z'"):
        scene.simulate(end=0.01)["slider.z"]


def test_integration_error_keeps_the_rows(scenes):
    """The driven four-bar with C rounded to five digits (coupler 3.3 um too long) locks at its dead
    point, where |BD|^2 = 5 - 4 cos(phi) (phi = pi + 2t the crank angle) falls to (coupler - rocker)^2,
    t = 1.5697 s: the exception carries the time of the last row kept and every row before it."""
    text = (scenes / "driven-four-bar.toml").read_text()
    exact = "at = [1.1666666666666665, -1.2472191289246475]"
    assert exact in text
    scene = dalembert.Scene.from_toml(text.replace(exact, "at = [1.16667, -1.24722]"), "rounded.toml")
    with pytest.raises(dalembert.IntegrationError) as info:
        scene.simulate()
    e = info.value
    assert "position analysis" in str(e) or "singular" in str(e) or "rank" in str(e)
    # Dead point: 5 - 4 cos(phi) = (coupler - rocker)^2 with phi = 2t + pi, coupler from the points.
    coupler = math.hypot(1.16667 + 1.0, -1.24722)
    rocker = math.hypot(1.16667 - 2.0, -1.24722)
    t_dead = (math.pi - math.acos((5.0 - (coupler - rocker) ** 2) / 4.0)) / 2.0
    every = 0.05  # the scene's output interval: the last row kept is the one before the dead point
    assert t_dead - every < e.time <= t_dead
    assert len(e.run) > 10 and e.run.t[-1] == e.time


def test_driven_four_bar_passes_its_change_point(scenes):
    """The shipped (exact) change-point four-bar runs to its end and leaves on the smooth branch: at
    t = pi the crank is back at its start and the coupler is mirrored (angle +0.5223 instead of
    -0.5223, from the circle intersection)."""
    run = dalembert.Scene.load(scenes / "driven-four-bar.toml").simulate()
    assert abs(run.t[-1] - math.pi) < 1e-12
    assert abs(run["coupler.angle"][-1] - 0.5223148218060488) < 1e-6


def test_scenes_pickle_as_their_text(scenes):
    scene = dalembert.Scene.load(scenes / "slider-crank.toml").with_values({"bodies.slider.mass": 3.0})
    back = pickle.loads(pickle.dumps(scene))
    assert back.source == scene.source and back.origin == scene.origin
    a, b = scene.simulate(end=0.2), back.simulate(end=0.2)
    np.testing.assert_array_equal(a.data, b.data)


def test_gil_is_released_during_a_run(scenes):
    """Another Python thread keeps running while a simulation runs."""
    scene = dalembert.Scene.load(scenes / "chain-8.toml")
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    start = time.perf_counter()
    run = scene.simulate(end=30.0)
    done.set()
    t.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.1, "the run is too short to tell"
    during = [x for x in ticks if start < x < start + elapsed]
    # With the GIL held the ticker would not run at all during the call.
    assert len(during) > 20, (len(during), elapsed)
    assert run.t[-1] == pytest.approx(30.0)


def test_ctrl_c_stops_a_run_and_keeps_the_rows(scenes):
    import os
    import signal

    scene = dalembert.Scene.load(scenes / "chain-8.toml")
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt) as info:
        scene.simulate(end=10000.0)
    assert time.perf_counter() - start < 5.0
    run = info.value.run
    assert len(run) > 1 and 0 < run.t[-1] < 10000.0


def test_integration_error_time_is_where_the_run_stopped(scenes):
    """A run that fails at t = 5e305 (its first step: a spring force overflows) says so in its
    message and in `.time`, though its only row is t = 0."""
    scene = dalembert.Scene.load(scenes / "slider-crank.toml")
    with pytest.raises(dalembert.IntegrationError) as info:
        scene.simulate(end=1e308, every=1e307, step=1e306)
    e = info.value
    assert "t = 5e305:" in str(e)
    assert e.time == 5e305
    assert list(e.run.t) == [0.0]


def test_pandas_and_plot(scenes, tmp_path):
    pd = pytest.importorskip("pandas")
    plt = pytest.importorskip("matplotlib.pyplot")
    run = dalembert.Scene.load(scenes / "slider-crank.toml").simulate(end=0.2)
    df = run.to_pandas()
    assert isinstance(df, pd.DataFrame) and df.index.name == "t"
    np.testing.assert_array_equal(df["slider.x"].to_numpy(), run["slider.x"])
    fig, ax = plt.subplots()
    assert run.plot("slider.x", "crank.angle", ax=ax) is ax
    assert [l.get_label() for l in ax.get_lines()] == ["slider.x", "crank.angle"]
    np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), run["slider.x"])
    plt.close(fig)


def test_trade_table(scenes):
    scene = dalembert.Scene.load(scenes / "pendulum.toml")
    rows = scene.trade(formulations=["augmented"], integrators=["rk4"], stabilizations=["projection"], steps=[1e-2, 1e-3], end=1.0)
    assert [r["parameter"] for r in rows] == [1e-2, 1e-3]
    # RK4 is fourth order: ten times smaller steps give an error at least 1000× smaller (the
    # reference is dopri5 at 1e-12).
    assert rows[1]["error"] < rows[0]["error"] / 1e3
    assert rows[1]["pareto"]


def test_animation_of_a_run(scenes, tmp_path):
    run = dalembert.Scene.load(scenes / "four-bar.toml").simulate(end=0.5)
    path = tmp_path / "four-bar.html"
    run.animate(path)
    html = path.read_text()
    assert html.startswith("<!DOCTYPE html>") and "coupler" in html
