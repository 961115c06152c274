"""Static equilibrium and vibration modes from Python against closed forms: a mass on a spring
(static deflection m g / k, ω_n = √(k/m), ζ = c / (2√(k m))) and the shipped pendulum (the pivot
carries the weight; ω² = m g d / (m L²/12 + m d²)); a free body is refused naming the cause."""

import math

import numpy as np
import pytest

import dalembert

from conftest import ROOT

G = 9.81

SPRING = (ROOT / "tests" / "data" / "hanging-spring.toml").read_text()


def test_a_mass_on_a_spring_rests_and_rings_at_its_closed_forms():
    scene = dalembert.Scene.from_toml(SPRING)
    eq = scene.equilibrium()
    # Newton to the assembly's 1e-12; the damped pair of eigenvalues to 1e-10 relative.
    assert abs(eq["slider.y"] - (-1.0 - 2.0 * G / 400.0)) < 1e-12
    assert eq["stable"] and eq["free_directions"] == []
    modes = scene.modes()
    assert isinstance(modes["frequencies"], np.ndarray)
    wn = math.sqrt(400.0 / 2.0)
    assert abs(modes["frequencies"][0] - wn / (2 * math.pi)) < 1e-10 * wn
    assert abs(modes["damping_ratios"][0] - 4.0 / (2 * math.sqrt(800.0))) < 1e-10
    assert modes["shapes"].shape == (1, len(modes["columns"]))
    assert modes["shapes"][0][modes["columns"].index("slider.y")] == pytest.approx(1.0, abs=1e-12)


def test_the_pendulum_hangs_with_its_weight_on_the_pivot():
    scene = dalembert.Scene.load(str(ROOT / "scenes" / "pendulum.toml"))
    eq = scene.equilibrium()
    d = math.hypot(0.25, 0.433)  # the file's centre of mass from the pivot
    assert abs(eq["rod.y"] + d) < 1e-12
    assert abs(eq["reactions"]["pivot.fy"] + G) < 1e-10
    f = scene.modes()["frequencies"][0]
    expected = math.sqrt(G * d / (1.0 / 12.0 + d * d)) / (2 * math.pi)
    assert abs(f - expected) < 1e-10 * expected


def test_a_free_body_has_no_equilibrium():
    scene = dalembert.Scene.from_toml(
        '[scene]\ngravity = [0.0, -9.81]\n[[bodies]]\nname = "stone"\nmass = 2.0\ninertia = 0.1\nposition = [0.0, 1.0]\n'
    )
    with pytest.raises(ValueError, match="there is none: a net force of 19.62 acts along stone.y"):
        scene.equilibrium()


def test_a_mode_page_holds_the_mode_swinging(tmp_path):
    # The page is titled with the mode and its closed-form frequency (the frames themselves are
    # checked in tests/statics.rs); a mode the scene lacks is refused.
    scene = dalembert.Scene.load(str(ROOT / "scenes" / "pendulum.toml"))
    page = tmp_path / "mode.html"
    scene.animate_mode(page, mode=1, cycles=1)
    text = page.read_text()
    assert "pendulum: mode 1 at" in text
    d = math.hypot(0.25, 0.433)
    f = math.sqrt(G * d / (1 / 12 + d * d)) / (2 * math.pi)
    assert f"{f:.6f} Hz" in text
    with pytest.raises(ValueError, match="mode 2 asked for: the scene has 1 mode"):
        scene.animate_mode(tmp_path / "none.html", mode=2)


def test_a_scene_at_its_equilibrium_starts_there_at_rest():
    # The shipped double pendulum started horizontal: the scene at rest at its equilibrium starts
    # at the positions equilibrium() gives (1e-12) and does not move over 1 s (1e-9).
    scene = dalembert.Scene.load(str(ROOT / "scenes" / "double-pendulum.toml"))
    eq = scene.equilibrium()
    resting = scene.at_equilibrium()
    assert "[initial.positions]" in resting.source
    run = resting.simulate(end=1.0)
    for column in ("upper.x", "upper.y", "upper.angle", "lower.x", "lower.y", "lower.angle"):
        assert abs(run[column][0] - eq[column]) < 1e-12
        assert np.abs(run[column] - eq[column]).max() < 1e-9
    assert np.abs(run["lower.omega"]).max() < 1e-9


ROD_ON_A_STOP = """
[scene]
gravity = [0.0, -9.81]

[[bodies]]
name = "rod"
mass = 1.0
shape = { rod = 1.0 }
position = [0.5, 0.0]

[[joints]]
name = "pin"
type = "revolute"
bodies = ["ground", "rod"]
at = [0.0, 0.0]
limits = [-0.5, 0.5]
"""


def test_a_rod_rests_on_its_stop_with_the_torque_its_weight_needs():
    # Hanging straight down lies beyond the stops: the rod rests on the lower one, which
    # carries its weight's torque m g (L/2) cos 0.5 (1e-10 of the weight: the residual's
    # tolerance); the angle at the bound to Newton's 1e-12.
    eq = dalembert.Scene.from_toml(ROD_ON_A_STOP).equilibrium()
    assert eq["held"] == ["pin"]
    assert abs(eq["rod.angle"] + 0.5) < 1e-12
    assert abs(eq["reactions"]["pin.limit"] - G * 0.5 * math.cos(0.5)) < 1e-10 * G
