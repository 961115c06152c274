"""MJCF `equality joint` couplings against MuJoCo's own mass matrix and bias forces.

MuJoCo's equality constraints are soft (its `qacc` would follow `solref`, not the coupling), so
the reference is MuJoCo's `qM` and `qfrc_bias` at a state that satisfies the couplings, reduced to
the leading joint: with `q = (θ, p(θ), r(θ))`, `q̇ = G θ̇`, `q̈ = G θ̈ + c` (`c` the followers'
`p″ θ̇²`), `(Gᵀ M G) θ̈ = −Gᵀ (h + M c)`; each coupling's effort is the residual `M q̈ + h` on its
follower. dalembert keeps each coupling as one exact constraint equation."""

import mujoco
import numpy as np
from scipy.integrate import solve_ivp

import dalembert
from test_mjcf import placed

# A hinge `jb` following hinge `ja` by a quadratic with an offset, and a slide `jc` following it
# linearly (metres per radian).
MJCF = """<mujoco model="coupled">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 -1" size="0.05" mass="2"/>
    </body>
    <body name="b" pos="1 0 0">
      <joint name="jb" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 -0.6" size="0.04" mass="1"/>
    </body>
    <body name="c" pos="0 1 0">
      <joint name="jc" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.1 0.1 0.1" mass="0.5"/>
    </body>
  </worldbody>
  <equality>
    <joint name="swing" joint1="jb" joint2="ja" polycoef="0.1 0.8 -0.5 0 0"/>
    <joint name="rack" joint1="jc" joint2="ja" polycoef="0 0.2 0 0 0"/>
  </equality>
</mujoco>
"""
SWING = np.array([0.1, 0.8, -0.5])
RACK = np.array([0.0, 0.2])


def poly(c, x):
    """p(x), p′(x), p″(x)."""
    p = np.polynomial.Polynomial(c)
    return p(x), p.deriv(1)(x), p.deriv(2)(x)


def full_state(theta, rate):
    (pb, db, _), (pc, dc, _) = poly(SWING, theta), poly(RACK, theta)
    return np.array([theta, pb, pc]), np.array([rate, db * rate, dc * rate])


def reduced(model, data, theta, rate):
    """`θ̈` and the residual `M q̈ + h` (the couplings' generalized forces) at `(θ, θ̇)`."""
    qpos, qvel = full_state(theta, rate)
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, data)
    m = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, m)
    h = data.qfrc_bias.copy()
    (_, db, d2b), (_, dc, d2c) = poly(SWING, theta), poly(RACK, theta)
    g = np.array([1.0, db, dc])
    c = np.array([0.0, d2b * rate**2, d2c * rate**2])
    acc = -(g @ (h + m @ c)) / (g @ m @ g)
    qacc = g * acc + c
    return acc, m @ qacc + h


def test_mjcf_joint_couplings_accelerate_as_mujocos_reduced_equations(tmp_path):
    """At 200 random states satisfying both couplings (θ in ±π, θ̇ in ±2): `JOINT.qdd` within 1e-9
    of the largest of the reference's and each coupling's effort within 1e-9 N·m (or N) of its
    follower's residual, every formulation; then a 0.5 s run from one of them within 1e-8 rad
    of the reduced equation integrated by DOP853 (dopri5 at 1e-12)."""
    path = tmp_path / "coupled.xml"
    path.write_text(MJCF)
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    scene = dalembert.Scene.load(path)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in scene.bodies]
    rng = np.random.default_rng(20261127)
    states = [(rng.uniform(-np.pi, np.pi), rng.uniform(-2.0, 2.0)) for _ in range(200)]
    for settings in [dict(formulation=f) for f in ("augmented", "embedding", "amalgamated")]:
        sim = scene.simulator(**settings)
        worst, worst_effort, largest_effort = 0.0, 0.0, 0.0
        for theta, rate in states:
            acc, residual = reduced(model, data, theta, rate)
            q, v = placed(model, data, ids, *full_state(theta, rate))
            moved = sim.set_state(q, v)
            assert moved["positions"] < 1e-12 and moved["velocities"] < 1e-12, f"assembly moved {moved}"
            (_, db, d2b), (_, dc, d2c) = poly(SWING, theta), poly(RACK, theta)
            expected = np.array([acc, db * acc + d2b * rate**2, dc * acc + d2c * rate**2])
            got = np.array([sim[f"{j}.qdd"] for j in ("ja", "jb", "jc")])
            worst = max(worst, np.max(np.abs(got - expected)) / np.max(np.abs(expected)))
            efforts = np.array([sim["swing.effort"], sim["rack.effort"]])
            worst_effort = max(worst_effort, np.max(np.abs(efforts - residual[1:])))
            largest_effort = max(largest_effort, np.max(np.abs(residual[1:])))
        print(f"{settings}: qdd {worst:.2e} of the largest, efforts {worst_effort:.2e} of {largest_effort:.2f}")
        assert worst < 1e-9, f"{settings}: {worst:.2e}"
        assert worst_effort < 1e-9, f"{settings}: efforts off by {worst_effort:.2e}"
        assert largest_effort > 1.0, "the couplings carry forces worth checking"

    theta0, rate0 = states[0]
    flow = lambda _, x: [x[1], reduced(model, data, x[0], x[1])[0]]  # noqa: E731
    end = solve_ivp(flow, (0.0, 0.5), [theta0, rate0], method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
    q, v = placed(model, data, ids, *full_state(theta0, rate0))
    for settings in [dict(formulation=f) for f in ("augmented", "embedding", "amalgamated")]:
        sim = scene.simulator(integrator="dopri5", rtol=1e-12, atol=1e-13, **settings)
        sim.set_state(q, v)
        sim.advance_to(0.5)
        assert abs(sim["ja.q"] - end[0]) < 1e-8, f"{settings}: {sim['ja.q']} vs {end[0]}"
        assert abs(sim["jc.q"] - 0.2 * sim["ja.q"]) < 1e-10


def test_the_file_configuration_is_moved_onto_the_coupling(tmp_path):
    """The file's configuration has `jb` at 0 where the coupling asks for its offset 0.1 rad:
    the scene starts with the follower placed there."""
    path = tmp_path / "coupled.xml"
    path.write_text(MJCF)
    sim = dalembert.Scene.load(path).simulator()
    assert abs(sim["jb.q"] - 0.1) < 1e-12 and abs(sim["jc.q"]) < 1e-12
