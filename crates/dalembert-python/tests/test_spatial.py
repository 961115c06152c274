"""Spatial scenes from Python: the heavy top against its conservation laws, read from the
output columns (centre of mass, Euler parameters, global angular velocity)."""

import numpy as np
import pytest

import dalembert


def rotation(e):
    """Rotation matrices (body to global) of rows of Euler parameters [e0, e1, e2, e3]."""
    e0, e1, e2, e3 = e.T
    return np.stack(
        [
            np.stack([e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)], -1),
            np.stack([2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)], -1),
            np.stack([2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2], -1),
        ],
        -2,
    )


def test_heavy_top_keeps_its_conserved_quantities(scenes):
    """A symmetric top on a ball joint at the origin under gravity along −z conserves its energy, the
    vertical component of its angular momentum about the pivot, and its spin about the symmetry
    axis (body y, since J_x = J_z)."""
    scene = dalembert.Scene.load(scenes / "heavy-top.toml")
    assert scene.bodies == ["top"] and scene.constraints == ["pivot"]
    run = scene.simulate(end=1.0)
    m, J = 15.0, np.diag([0.234375, 0.46875, 0.234375])
    r = np.stack([run[f"top.{c}"] for c in "xyz"], -1)
    v = np.stack([run[f"top.v{c}"] for c in "xyz"], -1)
    w = np.stack([run[f"top.w{c}"] for c in "xyz"], -1)
    A = rotation(np.stack([run[f"top.e{k}"] for k in range(4)], -1))
    # L = r × m v + A J Aᵀ ω about the pivot.
    spin_inertia = np.einsum("nij,jk,nlk->nil", A, J, A)
    L = np.cross(r, m * v) + np.einsum("nij,nj->ni", spin_inertia, w)
    spin = np.einsum("ni,ni->n", A[:, :, 1], w)
    energy = run["energy"]
    # RK4 at 1e-4 s with projection (the scene's settings): each quantity changes by ~1e-8 of its
    # size over 1 s; 1e-6 leaves room, and a wrong inertia, sign or column order breaks it by
    # orders of magnitude.
    assert np.ptp(energy) < 1e-6 * abs(energy[0])
    assert np.ptp(L[:, 2]) < 1e-6 * np.abs(L[0]).max()
    assert np.ptp(spin) < 1e-6 * abs(spin[0])
    # The anchors' README: E0 = 5435.6968 J, spin 150 rad/s.
    assert energy[0] == pytest.approx(5435.6968, abs=1e-3) and spin[0] == pytest.approx(150.0, abs=1e-12)
    # The top falls and precesses: it is not standing still.
    assert np.ptp(r[:, 2]) > 0.1


def test_spatial_columns_and_the_3d_viewer(scenes, tmp_path):
    scene = dalembert.Scene.load(scenes / "slider-crank-3d.toml")
    for c in ["crank.e0", "rod.wz", "C.fx", "C.mz", "guide.my"]:
        assert c in scene.columns
    report = scene.check()
    # 3 bodies x 6 - (revolute 5 + prismatic 5 + spherical 3 + universal 4) = 1 (Grübler).
    assert report["dof"] == 1
    run = scene.simulate(end=0.1)
    # The check's reactions are the first output row's (one computation).
    for c in ["C.fx", "C.mz", "guide.fz", "A.my"]:
        assert report["reactions"][c] == pytest.approx(run[c][0], rel=1e-12, abs=1e-15)
    # The revolute and prismatic joints have joint columns; the crank's angle starts at 0 (the
    # file's configuration) and its rate is the crank's angular velocity about the hinge.
    assert run["A.q"][0] == 0.0 and run["A.qd"][0] != 0.0
    assert "guide.q" in run.columns and "C.q" not in run.columns
    # A spatial run animates in the 3D viewer.
    run.animate(tmp_path / "x.html")
    assert 'id="three-source"' in (tmp_path / "x.html").read_text()


def test_joint_coordinates_give_the_absolute_run(scenes):
    """The shipped spatial chain runs in joint coordinates (its scene says so) and in absolute
    coordinates (the keyword): the same columns, the same motion. Both are RK4 at 1 ms on different
    equations for one motion: their states differ by the two truncation errors, below 1e-9 m at
    t = 1 s for this chain (the anchors' errors, docs/performance.md); 1e-8 leaves room. The
    reactions are the model's multipliers at nearly equal states: 1e-6 of their largest."""
    scene = dalembert.Scene.load(scenes / "spatial-chain-16.toml")
    joint = scene.simulate(end=1.0)
    absolute = scene.simulate(end=1.0, coordinates="absolute")
    assert joint.columns == absolute.columns
    # From rest the chain falls in the x-z plane (its z-axis joints carry no load): compare columns
    # that move and reactions that carry load (y components and the moments stay zero in both).
    for c in ["link15.x", "link15.z", "link7.x", "link3.e2"]:
        assert np.max(np.abs(joint[c] - absolute[c])) < 1e-8, c
    for c in ["joint0.fz", "joint8.fx", "joint8.fz"]:
        scale = np.max(np.abs(absolute[c]))
        assert scale > 1.0, c
        assert np.max(np.abs(joint[c] - absolute[c])) < 1e-6 * scale, c
    # The chain falls: a run that stood still would pass the comparisons above.
    assert joint["link15.z"][-1] < -1.0
    with pytest.raises(ValueError, match="joint 'pivot'"):
        dalembert.Scene.load(scenes / "heavy-top.toml").simulate(end=0.1, coordinates="joint")
    with pytest.raises(ValueError, match="coordinates"):
        scene.simulate(end=0.1, coordinates="relative")


FRICTION_CHAIN = """
[scene]
gravity = [0.0, 0.0, -9.81]
[[bodies]]
name = "a"
mass = 1.0
inertia = [0.001, 0.08333333333333333, 0.08333333333333333]
position = [0.5, 0.0, 0.0]
[[bodies]]
name = "b"
mass = 1.0
inertia = [0.001, 0.08333333333333333, 0.08333333333333333]
position = [1.5, 0.0, 0.0]
[[joints]]
name = "p1"
type = "revolute"
bodies = ["ground", "a"]
at = [0.0, 0.0, 0.0]
axis = [0.0, -1.0, 0.0]
friction = { coefficient = 0.3, radius = 0.05 }
[[joints]]
name = "p2"
type = "revolute"
bodies = ["b", "a"]
at = [1.0, 0.0, 0.0]
axis = [0.0, -1.0, 0.0]
friction = { coefficient = 0.3, radius = 0.05 }
[simulation]
end = 3.0
integrator = "dopri5"
rtol = 1e-12
atol = 1e-12
output_every = 0.01
"""


def test_joint_friction_runs_in_joint_coordinates():
    """Two rods on pins with friction (the second pin written child first), released horizontal:
    in joint coordinates the friction's load is the force each joint transmits (the tree's
    Newton-Euler pass), in absolute coordinates the norm of the pin's multipliers; two derivations
    of one law (docs/friction.md, "In joint coordinates"). Both at dopri5 1e-12: the angles, the
    friction torques and the pins' forces within 1e-8 of each column's scale (measured about 1e-10
    at 1e-10), and the chain sticks and slips (its friction torques change sign)."""
    scene = dalembert.Scene.from_toml(FRICTION_CHAIN)
    joint = scene.simulate(coordinates="joint")
    absolute = scene.simulate(coordinates="absolute")
    assert joint.columns == absolute.columns
    for c in ["p1.q", "p2.q", "p1.friction", "p2.friction", "p1.fx", "p1.fz", "p2.fx", "p2.fz", "energy"]:
        scale = max(1.0, np.max(np.abs(absolute[c])))
        assert np.max(np.abs(joint[c] - absolute[c])) < 1e-8 * scale, c
    for c in ["p1.friction", "p2.friction"]:
        assert np.min(absolute[c]) < -0.1 and np.max(absolute[c]) > 0.1, c
