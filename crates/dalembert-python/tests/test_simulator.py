"""The step-by-step simulator from Python: a controller in the loop against the exact discrete
closed loop, chunked runs against a whole run, bad requests, Ctrl-C."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import dalembert

from conftest import ROOT

SLIDER = (ROOT / "tests" / "data" / "pushed-slider.toml").read_text()


@pytest.mark.parametrize("formulation", ["augmented", "embedding", "amalgamated"])
def test_a_pd_loop_equals_the_exact_discrete_closed_loop(formulation):
    """A force held over each control period moves the slider along a quadratic, which RK4
    integrates exactly: the loop must equal x+ = x + v T + u T²/2m, v+ = v + u T/m to round-off
    (1e-11 over 400 periods, each sample between two steps: T = 3.7 steps)."""
    scene = dalembert.Scene.from_toml(SLIDER)
    assert scene.inputs == ["push"]
    sim = scene.simulator(formulation=formulation)
    assert sim.inputs == ["push"]
    kp, kd, m, period = 40.0, 12.0, 2.0, 3.7e-3
    x = v = 0.0
    for k in range(1, 401):
        sim.set_input("push", kp * (1.0 - sim["slider.x"]) - kd * sim["slider.vx"])
        sim.advance_to(k * period)
        u = kp * (1.0 - x) - kd * v
        x, v = x + v * period + u * period**2 / (2 * m), v + u * period / m
    assert sim.t == pytest.approx(400 * period, abs=1e-12)
    assert abs(sim["slider.x"] - x) < 1e-11 and abs(sim["slider.vx"] - v) < 1e-11
    assert sim.input("push") != 0.0


def test_chunks_equal_the_whole_run(scenes):
    """Advanced in uneven chunks, the simulator lands on simulate's last row exactly."""
    scene = dalembert.Scene.load(scenes / "four-bar.toml")
    run = scene.simulate(end=0.5)
    sim = scene.simulator(end=0.5)
    for t in list(np.linspace(0.0, 0.5, 12)[1:-1] ** 1.3 / 0.5**0.3) + [0.5]:
        sim.advance_to(t)
    row = sim.row()
    for column in run.columns:
        assert row[column] == run[column][-1], column
    q, v = sim.state
    assert len(q) == len(v) == 9


def test_bad_requests_leave_it_usable():
    scene = dalembert.Scene.from_toml(SLIDER)
    sim, clean = scene.simulator(), scene.simulator()
    for s in (sim, clean):
        s.set_input("push", 2.0)
        s.advance_to(0.5)
    with pytest.raises(ValueError, match=r"unknown input 'pus' \(expected push\); did you mean 'push'\?"):
        sim.set_input("pus", 1.0)
    with pytest.raises(ValueError, match="input 'push': NaN is not a finite value"):
        sim.set_input("push", float("nan"))
    with pytest.raises(ValueError, match="cannot advance to t = 0.2: the simulator is at t = 0.5"):
        sim.advance_to(0.2)
    with pytest.raises(KeyError, match="unknown column 'slider.z'"):
        sim["slider.z"]
    with pytest.raises(ValueError, match="the model has 3 positions and 3 velocities; 2 and 3 were given"):
        sim.set_state([0.0, 0.0], [0.0, 0.0, 0.0])
    for s in (sim, clean):
        s.advance_to(1.0)
    assert sim["slider.x"] == clean["slider.x"]
    # set_state assembles: a state off the guide comes back to it, and says how far it moved.
    moved = sim.set_state([1.0, 0.25, 0.0], [0.0, 0.0, 0.0])
    assert moved["positions"] == pytest.approx(0.25, abs=1e-12)
    assert abs(sim["slider.y"]) < 1e-12 and sim["slider.x"] == pytest.approx(1.0, abs=1e-12)
    sim.reset()
    assert sim.t == 0.0 and sim.input("push") == 0.0 and sim["slider.x"] == 0.0


def test_ctrl_c_stops_advance_to_and_it_can_go_on(scenes):
    """A run of hours stops within a second of Ctrl-C; the simulator is at the step reached."""
    sim = dalembert.Scene.load(scenes / "slider-crank.toml").simulator()
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        sim.advance_to(1e5)
    assert time.perf_counter() - start < 1.5
    reached = sim.t
    assert 0.0 < reached < 1e5
    sim.advance_to(reached + 0.01)
    assert sim.t == pytest.approx(reached + 0.01, abs=1e-12)


WHEEL = (ROOT / "tests" / "data" / "wheel.toml").read_text()


def test_a_torque_from_python_follows_the_damped_oscillator():
    """J θ̈ = τ0 − k θ − c θ̇ from rest: the damped oscillator's closed form; RK4 at 1 ms on ω = 4
    rad/s errs by about (ωh)^4 of the amplitude: 1e-8 rad. The Rust closure (tests/simulator.rs)
    gives the same run, so the Python function is called with the same states."""
    j, k, c, tau0 = 0.5, 8.0, 0.4, 2.0
    scene = dalembert.Scene.from_toml(WHEEL)
    assert scene.code_forces == ["controller"]
    sim = scene.simulator()
    calls = []

    def controller(t, body):
        calls.append(t)
        return (10.0, 0.0, tau0 - k * body.angle - c * body.angular_velocity[2])

    sim.set_force("controller", controller)
    sim.advance_to(3.0)
    w = (k / j) ** 0.5
    zeta = c / (2 * (k * j) ** 0.5)
    wd = w * (1 - zeta**2) ** 0.5
    exact = tau0 / k * (1 - np.exp(-zeta * w * 3.0) * (np.cos(wd * 3.0) + zeta * w / wd * np.sin(wd * 3.0)))
    assert abs(sim["wheel.angle"] - exact) < 1e-8
    assert abs(abs(sim["pin.fx"]) - 10.0) < 1e-9
    assert len(calls) >= 4 * 3000  # four stages per RK4 step


def test_an_exception_in_a_force_function_is_raised_by_the_step():
    sim = dalembert.Scene.from_toml(WHEEL).simulator()

    def broken(t, body):
        if t > 0.01:
            raise ZeroDivisionError("controller gave up")
        return (0.0, 0.0, 1.0)

    sim.set_force("controller", broken)
    with pytest.raises(ZeroDivisionError, match="controller gave up"):
        sim.advance_to(1.0)
    sim2 = dalembert.Scene.from_toml(WHEEL).simulator()
    sim2.set_force("controller", lambda t, body: (1.0, 2.0))
    with pytest.raises(ValueError, match=r"code force 'controller': the function returned 2 numbers"):
        sim2.step()
    with pytest.raises(ValueError, match=r"unknown code force 'controler' \(expected controller\); did you mean 'controller'\?"):
        sim2.set_force("controler", lambda t, body: (0.0, 0.0, 0.0))


def test_ctrl_c_reaches_a_simulator_with_a_python_force(scenes):
    """With a force function the simulator steps with the GIL held; Ctrl-C arrives in the function
    and stops the run there, and the simulator goes on from the last step."""
    sim = dalembert.Scene.from_toml(WHEEL).simulator()
    sim.set_force("controller", lambda t, body: (0.0, 0.0, -8.0 * body.angle + 1.0))
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        sim.advance_to(1e5)
    assert time.perf_counter() - start < 1.5
    reached = sim.t
    assert 0.0 < reached < 1e5 and np.isfinite(sim["wheel.angle"])
    sim.advance_to(reached + 0.01)
