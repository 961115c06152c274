"""A URDF `mimic` coupling against Pinocchio: the Panda, whose second finger mimics the first.

Pinocchio reads the same file with each finger a joint of its own (`mimic=False`); its mass matrix
`pin.crba` and bias `pin.rnea(q, v, 0)` at the full configuration, reduced to the independent
joints by the coupling's map `G` (`q = G q_r`, the second finger's row a copy of the first's),
give the accelerations of the coupled robot, `(Gᵀ M G) a_r = −Gᵀ (h + D v)` with the file's joint
damping `D`, and the torque the coupling applies to the second finger, the residual of its own
row: `(M G a_r + h + D v)` there. dalembert's run keeps the coupling as one constraint equation
over four bodies; its `JOINT.qdd` columns and `panda_finger_joint2-mimic.effort` are compared."""

import numpy as np
import pinocchio as pin  # a test dependency (the package's `test` extra installs `pin`)
import pytest
from scipy.integrate import solve_ivp

import dalembert
from test_urdf import absolute_state, link_centres

FINGERS = ("panda_finger_joint1", "panda_finger_joint2")


def panda(scenes):
    path = scenes / "robots" / "panda.urdf"
    model = pin.buildModelFromUrdf(str(path))
    names = list(model.names)[1:]
    lead, follow = names.index(FINGERS[0]), names.index(FINGERS[1])
    g = np.eye(model.nv)
    g[follow, :] = g[lead, :]  # the second finger's value is the first's (multiplier 1, offset 0)
    g = np.delete(g, follow, axis=1)
    damping = np.array([model.damping[j.idx_v] for j in list(model.joints)[1:]])
    return path, model, names, g, damping


def random_states(model, names, count, seed, rates=2.0):
    """Joint values well inside the stops (a tenth of each range from each bound, the
    fingers' common opening inside theirs), rates in ±`rates` (rad/s; less for a range under
    π): no stop is touched in the runs below."""
    rng = np.random.default_rng(seed)
    lo, hi = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    # Joint 4's range excludes the file's configuration: dalembert leaves its stops out; ±π.
    j4 = names.index("panda_joint4")
    lo[j4], hi[j4] = -np.pi, np.pi
    lead, follow = names.index(FINGERS[0]), names.index(FINGERS[1])
    states = []
    for _ in range(count):
        span = hi - lo
        theta = rng.uniform(lo + 0.1 * span, hi - 0.1 * span)
        # Rates scaled to each range over π (the fingers' 4 cm: ±0.025 m/s at `rates` = 2).
        rate = rng.uniform(-rates, rates, model.nv) * np.minimum(1.0, span / np.pi)
        theta[follow], rate[follow] = theta[lead], rate[lead]
        states.append((theta, rate))
    return states


def reduced(model, data, g, damping, theta, rate):
    """The coupled robot's joint accelerations (full) and the coupling's torque on the second
    finger, from Pinocchio's M and h (see the module's documentation)."""
    m = pin.crba(model, data, theta)
    m = np.triu(m) + np.triu(m, 1).T
    h = pin.rnea(model, data, theta, rate, np.zeros(model.nv)) + damping * rate
    a = g @ np.linalg.solve(g.T @ m @ g, -g.T @ h)
    return a, m @ a + h


# The embedding's and the amalgamated formulation's Schur complement B_iᵀ M B_i squares B_i's
# scale and loses digits at some of these states (1.3e-8 of the largest without the refinement
# step each takes: 9.8e-13 and 9.8e-13 with it).
FORMULATIONS = ["augmented", "embedding", "amalgamated"]


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_the_panda_fingers_coupled_by_mimic_accelerate_as_pinocchios_reduced_equations(scenes, formulation):
    """At 300 random states inside the stops: every `JOINT.qdd` within 1e-9 of the largest of
    the reference's (both exact to round-off), and the coupling's effort within 1e-8 N of the
    second finger's residual torque (the fingers weigh 15 g: their forces are a few newtons)."""
    path, model, names, g, damping = panda(scenes)
    data = model.createData()
    scene = dalembert.Scene.load(path)
    centres = link_centres(model, data, scene)
    follow = names.index(FINGERS[1])
    states = random_states(model, names, 300, 20261127)
    for settings in [dict(formulation=formulation)]:
        sim = scene.simulator(**settings)
        worst, worst_effort, largest_effort = 0.0, 0.0, 0.0
        for theta, rate in states:
            expected, residual = reduced(model, data, g, damping, theta, rate)
            q, v = absolute_state(model, data, scene.bodies, centres, theta, rate)
            moved = sim.set_state(q, v)
            assert moved["positions"] < 1e-12 and moved["velocities"] < 1e-12, f"assembly moved {moved}"
            got = np.array([sim[f"{n}.qdd"] for n in names])
            worst = max(worst, np.max(np.abs(got - expected)) / np.max(np.abs(expected)))
            effort = sim["panda_finger_joint2-mimic.effort"]
            worst_effort = max(worst_effort, abs(effort - residual[follow]))
            largest_effort = max(largest_effort, abs(residual[follow]))
        print(f"panda {settings}: qdd {worst:.2e} of the largest, effort {worst_effort:.2e} N of {largest_effort:.2f} N")
        assert worst < 1e-9, f"panda {settings}: {worst:.2e}"
        assert worst_effort < 1e-8, f"panda {settings}: effort off by {worst_effort:.2e} N"
        assert largest_effort > 0.1, "the coupling carries a force worth checking"


def test_the_panda_run_from_a_random_state_follows_pinocchios_reduced_equations(scenes):
    """Three random states inside the stops at modest rates, 0.1 s later: the joint values within
    1e-8 rad (or m) of the reduced equations integrated by DOP853 at 1e-13 (dopri5 at 1e-12 here;
    both ~1e-10 from exact over this span), every formulation; the fingers stay coupled."""
    path, model, names, g, damping = panda(scenes)
    data = model.createData()
    scene = dalembert.Scene.load(path)
    centres = link_centres(model, data, scene)
    lead, follow = names.index(FINGERS[0]), names.index(FINGERS[1])
    for theta, rate in random_states(model, names, 3, 7, rates=0.3):

        def flow(_, x):
            return np.concatenate([x[model.nv :], reduced(model, data, g, damping, x[: model.nv], x[model.nv :])[0]])

        end = solve_ivp(flow, (0.0, 0.1), np.concatenate([theta, rate]), method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
        q, v = absolute_state(model, data, scene.bodies, centres, theta, rate)
        for settings in [dict(formulation=f) for f in ("augmented", "embedding", "amalgamated")]:
            sim = scene.simulator(integrator="dopri5", rtol=1e-12, atol=1e-13, **settings)
            sim.set_state(q, v)
            sim.advance_to(0.1)
            for k, name in enumerate(names):
                got = sim[f"{name}.q"]
                assert abs(got - end[k]) < 1e-8, f"panda {settings} {name}: {got} vs {end[k]}"
            assert abs(sim[f"{FINGERS[1]}.q"] - sim[f"{FINGERS[0]}.q"]) < 1e-10


def test_a_mimic_naming_a_missing_joint_is_refused_by_line(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text(
        '<robot name="r">\n<link name="base"/>\n'
        '<link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>\n'
        '<joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>\n'
        '<mimic joint="nowhere"/></joint>\n</robot>\n'
    )
    with pytest.raises(dalembert.SceneError) as e:
        dalembert.Scene.load(bad)
    assert "nowhere" in str(e.value) and ":5:" in str(e.value), str(e.value)
