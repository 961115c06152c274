"""Linearization from Python against a textbook closed form: a cart-pole (point mass on a
massless pole) upright, pushed by a named input: ẍ = (m g / M) θ + u / M,
θ̈ = (M + m) g / (M l) θ + u / (M l); the command line's NumPy archive of it read by `numpy.load`;
and requests naming what is wrong."""

import subprocess

import numpy as np
import pytest

import dalembert
from conftest import cli

G = 9.81
M, m, L = 2.0, 0.5, 0.8

CART_POLE = f"""
[scene]
gravity = [0.0, -9.81]
[[bodies]]
name = "cart"
mass = {M}
inertia = 0.1
position = [0.0, 0.0]
[[bodies]]
name = "pole"
mass = {m}
inertia = 1e-12
position = [0.0, {L}]
[[joints]]
name = "rail"
type = "prismatic"
bodies = ["ground", "cart"]
at = [0.0, 0.0]
axis = [1.0, 0.0]
[[joints]]
name = "hinge"
type = "revolute"
bodies = ["cart", "pole"]
at = [0.0, 0.0]
[[forces]]
name = "push"
type = "force"
body = "cart"
fx = {{ input = "u" }}
"""


def test_an_upright_cart_pole_has_its_textbook_linear_model():
    # θ the pole's angle from upright (counter-clockwise: the mass moves to −x), x the cart's.
    # From the Lagrangian, linearized upright: M ẍ = u + m g θ, l θ̈ = ẍ + g θ. The pole's
    # inertia of 1e-12 and the differences' O(h⁴) leave 1e-9 relative.
    scene = dalembert.Scene.from_toml(CART_POLE)
    lin = scene.linearize(inputs=["u"], outputs=["pole.x", "rail.fy"], at="initial",
                          states=["cart.x", "pole.angle"])
    assert lin["states"] == ["cart.x", "pole.angle", "cart.vx", "pole.omega"]
    a = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [0, m * G / M, 0, 0], [0, (M + m) * G / (M * L), 0, 0]])
    b = np.array([[0], [0], [1 / M], [1 / (M * L)]])
    assert np.allclose(lin["A"], a, rtol=0, atol=1e-9 * np.abs(a).max())
    assert np.allclose(lin["B"], b, rtol=0, atol=1e-9)
    # Upright is an equilibrium: nothing moves there.
    assert np.abs(lin["drift"]).max() < 1e-9
    # pole.x = x − l sin θ: C's first row [1, −l, 0, 0]; it does not see u.
    assert np.allclose(lin["C"][0], [1, -L, 0, 0], atol=1e-9)
    assert abs(lin["D"][0, 0]) < 1e-9
    # The same state given as a dict: the same model.
    again = scene.linearize(inputs=["u"], at={"q": lin["q"], "qd": lin["qd"]},
                            states=["cart.x", "pole.angle"])
    assert np.allclose(again["A"], lin["A"], rtol=0, atol=1e-12)
    # Unstable upright: a positive real eigenvalue √((M + m) g / (M l)).
    grow = np.sqrt((M + m) * G / (M * L))
    assert np.max(np.linalg.eigvals(lin["A"]).real) == pytest.approx(grow, rel=1e-9)


def test_bad_requests_name_the_cause():
    scene = dalembert.Scene.from_toml(CART_POLE)
    with pytest.raises(ValueError, match="unknown input 'v'.*did you mean 'u'"):
        scene.linearize(inputs=["v"], at="initial")
    with pytest.raises(ValueError, match="unknown output column 'pole.z'"):
        scene.linearize(outputs=["pole.z"], at="initial")
    with pytest.raises(ValueError, match="at = 'upright'"):
        scene.linearize(at="upright")
    with pytest.raises(ValueError, match="at has no 'qd'"):
        scene.linearize(at={"q": [0.0] * 6})


def test_a_simulator_linearizes_where_it_is():
    # The shipped pendulum stepped to 0.4 s, swinging: linearized in its angle at the simulator's
    # state, A = [0 1; −ω² cos(θ − θ_h) 0] and the drift [θ̇, −ω² sin(θ − θ_h)] (ω² = m g d/J_O,
    # θ_h the hanging angle), 1e-8 relative; a cart-pole with its input set keeps that input.
    from conftest import ROOT

    scene = dalembert.Scene.load(str(ROOT / "scenes" / "pendulum.toml"))
    d = np.hypot(0.25, 0.433)
    w2 = G * d / (1 / 12 + d * d)
    hanging = scene.equilibrium()["rod.angle"]
    sim = scene.simulator()
    sim.advance_to(0.4)
    theta, omega = sim["rod.angle"], sim["rod.omega"]
    lin = sim.linearize(states=["rod.angle"])
    assert lin["t"] == pytest.approx(0.4, abs=1e-12)
    assert lin["A"][1, 0] == pytest.approx(-w2 * np.cos(theta - hanging), rel=1e-8)
    assert lin["drift"][0] == pytest.approx(omega, rel=1e-10)
    assert lin["drift"][1] == pytest.approx(-w2 * np.sin(theta - hanging), rel=1e-8)
    cart = dalembert.Scene.from_toml(CART_POLE).simulator()
    cart.set_input("u", 3.0)
    pushed = cart.linearize(states=["cart.x", "pole.angle"])
    # Upright at rest, pushed by u = 3: the drift is B u (the model is linear in u).
    assert pushed["drift"][2] == pytest.approx(3.0 / M, rel=1e-9)
    assert pushed["drift"][3] == pytest.approx(3.0 / (M * L), rel=1e-9)


def test_the_cli_writes_the_linear_model_as_a_numpy_archive(tmp_path):
    """`dalembert linearize --output lin.npz` writes A, B, C, D, the drift, the outputs at the
    operating point and the names as `numpy.load` reads them (its own reader of the format), the
    same numbers as `scene.linearize` (one computation: equal to the last bit)."""
    path = tmp_path / "cart-pole.toml"
    path.write_text(CART_POLE)
    out = tmp_path / "lin.npz"
    subprocess.run(
        [cli(), "linearize", path, "--inputs", "u", "--outputs", "pole.x,rail.fy", "--at", "initial",
         "--states", "cart.x,pole.angle", "--output", out],
        check=True,
        capture_output=True,
    )
    lin = dalembert.Scene.load(path).linearize(inputs=["u"], outputs=["pole.x", "rail.fy"], at="initial",
                                               states=["cart.x", "pole.angle"])
    with np.load(out, allow_pickle=False) as saved:
        assert sorted(saved.files) == ["A", "B", "C", "D", "at", "drift", "inputs", "outputs", "states", "t"]
        for key in ["A", "B", "C", "D", "drift"]:
            assert saved[key].dtype == np.float64 and saved[key].shape == np.shape(lin[key])
            np.testing.assert_array_equal(saved[key], lin[key])
        np.testing.assert_array_equal(saved["at"], lin["outputs_at"])
        for key in ["states", "inputs", "outputs"]:
            assert saved[key].tolist() == lin[key]
        assert saved["t"].shape == () and saved["t"] == 0.0
