"""Joint limits and rigid contact from Python (docs/limits.md): numbers checked against
Newton's impact law in closed form and against the command line."""

import math
import subprocess

import numpy as np

import dalembert
from conftest import cli

G = 9.81

# A slider of 2 kg on a vertical guide with a stop 1 m below its start, e = 0.8.
DROP = """
[scene]
gravity = [0.0, -9.81]

[[bodies]]
name = "slider"
mass = 2.0
shape = { rectangle = [0.2, 0.1] }
position = [0.0, 1.0]

[[joints]]
name = "guide"
type = "prismatic"
bodies = ["ground", "slider"]
at = [0.0, 1.0]
axis = [0.0, 1.0]
limits = [-1.0, 0.5]
restitution = 0.8

[simulation]
end = 1.1
integrator = "dopri5"
rtol = 1e-10
atol = 1e-10
output_every = 0.01
"""


def test_a_dropped_slider_rebounds_to_e_squared_its_height():
    """Impact at t1 = sqrt(2 d / g) with speed v1 = g t1; the first flight is a parabola of
    height e² d above the stop: q(t) = −d + e v1 (t − t1) − g (t − t1)² / 2 until
    t1 + 2 e v1 / g (1.17 s, past the run's 1.1 s). Bar 1e-8 m, as the Rust test's."""
    run = dalembert.Scene.from_toml(DROP).simulate()
    t, q = run.t, run["guide.q"]
    t1 = math.sqrt(2.0 / G)
    v1 = G * t1
    expected = np.where(t <= t1, -0.5 * G * t**2, -1.0 + 0.8 * v1 * (t - t1) - 0.5 * G * (t - t1) ** 2)
    assert np.max(np.abs(q - expected)) < 1e-8
    # The energy after the impact (datum: the centre of mass at the stop, y = 0): e² of the
    # m g d it had, 0.64 × 19.62 J, within 1e-7 J.
    after = run["energy"][t > t1 + 0.01]
    assert np.max(np.abs(after - 0.8**2 * 2.0 * G * 1.0)) < 1e-7


def test_the_shipped_stop_scene_rests_against_its_stop_as_the_cli_says(scenes, tmp_path):
    """scenes/slider-crank-stop.toml: the slider comes to rest against its stop at 0.2 m, held
    by the stop's force, and the package's run is the command line's CSV bit for bit."""
    scene = dalembert.Scene.load(scenes / "slider-crank-stop.toml")
    run = scene.simulate(end=3.0)
    held = run["guide.limit"] != 0.0
    assert held[-1] and np.all(np.abs(run["guide.q"][held] - 0.2) < 1e-12)
    assert np.all(run["guide.limit"][held] < 0.0), "the upper stop pushes the slider back"
    out = tmp_path / "run.csv"
    subprocess.run(
        [str(cli()), "simulate", str(scenes / "slider-crank-stop.toml"), "--end", "3", "--output", str(out)],
        check=True,
        capture_output=True,
    )
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    header = out.read_text().splitlines()[0].split(",")
    assert header == list(run.columns)
    assert np.array_equal(data, run.data)


def test_a_ball_on_a_rigid_floor_with_friction_rolls_at_its_closed_form(scenes):
    """scenes/ball-slides-then-rolls.toml (docs/limits.md, "Friction in spatial rigid contact"): a
    ball thrown spinning on a floor with mu = 0.3 slides against its slip w0 = v0 + omega0 x (-R n)
    until t* = 2 |w0| / (7 mu g), its friction mu m g, then rolls at v0 - (2/7) w0 with no friction;
    the contact's force columns hold the friction with the normal force. Bars 1e-9 m/s and N: the
    slip stops at an event located to 1e-9 m/s (measured 5e-13 m/s)."""
    run = dalembert.Scene.load(scenes / "ball-slides-then-rolls.toml").simulate()
    t = run["t"]
    v0, w0, r, mu, m = np.array([2.0, 1.0, 0.0]), np.array([3.0, -4.0, 2.0]), 0.1, 0.3, 2.0
    slip = v0 + np.cross(w0, [0.0, 0.0, -r])
    t_star = 2.0 * np.linalg.norm(slip) / (7.0 * mu * G)
    rolling = v0 - 2.0 / 7.0 * slip
    after, before = t > t_star + 1e-6, t < t_star - 1e-6
    assert np.max(np.abs(run["ball.vx"][after] - rolling[0])) < 1e-9
    assert np.max(np.abs(run["ball.vy"][after] - rolling[1])) < 1e-9
    assert np.max(np.abs(run["floor.friction"][after])) < 1e-9
    assert np.max(np.abs(run["floor.friction"][before] - mu * m * G)) < 1e-9
    tangential = np.hypot(run["floor.fx"][before], run["floor.fy"][before])
    assert np.max(np.abs(tangential - mu * m * G)) < 1e-9
    assert np.max(np.abs(run["floor.fz"] - m * G)) < 1e-9


def test_a_ball_rolls_off_a_fixed_sphere_with_the_forces_of_its_free_body_diagram(scenes):
    """scenes/ball-rolls-off-sphere.toml (docs/limits.md, "Friction in spatial rigid contact"): a
    ball released at rest theta0 = 0.1 rad from the top of a fixed sphere, mu = 0.3. While it rolls
    (before the slip's onset at 2 sin(theta) = mu (17 cos(theta) - 10 cos(theta0)), 0.738 s), at
    each sample's angle: its speed from the energy, v^2 = (10/7) g rho (cos(theta0) - cos(theta)),
    its friction (2/7) m g sin(theta) and normal force (m g / 7)(17 cos(theta) - 10 cos(theta0)), its
    spin v / r; then, slipping, a friction of mu N; after it leaves (0.853 s) no contact force. Bars 1e-9 m/s, 1e-8 N, 1e-8 rad/s."""
    run = dalembert.Scene.load(scenes / "ball-rolls-off-sphere.toml").simulate()
    t = run["t"]
    m, r, rho, mu, theta0 = 2.0, 0.1, 0.6, 0.3, 0.1
    theta = np.arctan2(run["ball.x"], run["ball.z"])
    rolling = t < 0.73
    speed = np.hypot(run["ball.vx"], run["ball.vz"])
    energy = np.sqrt(10.0 / 7.0 * G * rho * (np.cos(theta0) - np.cos(theta)))
    assert np.max(np.abs(speed[rolling] - energy[rolling])) < 1e-9
    friction = 2.0 / 7.0 * m * G * np.sin(theta)
    normal = m * G / 7.0 * (17.0 * np.cos(theta) - 10.0 * np.cos(theta0))
    assert np.max(np.abs(run["touch.friction"][rolling] - friction[rolling])) < 1e-8
    assert np.max(np.abs(run["touch.normal"][rolling] - normal[rolling])) < 1e-8
    assert np.max(np.abs(run["ball.wy"][rolling] - speed[rolling] / r)) < 1e-8
    slipping = (t > 0.74) & (t < 0.85)
    assert np.max(np.abs(run["touch.friction"][slipping] - mu * run["touch.normal"][slipping])) < 1e-8
    flying = t > 0.86
    assert flying.any()
    assert np.max(np.abs(run["touch.normal"][flying])) == 0.0
    assert np.max(np.abs(run["touch.friction"][flying])) == 0.0
