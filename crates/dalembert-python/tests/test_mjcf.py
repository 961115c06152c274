"""MJCF import against MuJoCo: the same file, read by both, with contacts off.

MuJoCo (`mujoco`, a test-only dependency) computes the joint accelerations (`mj_forward`'s
`qacc`; its inertias from the geoms, as dalembert's reader computes them) and scipy's DOP853
integrates them at tolerances far below the bar. dalembert reads the file into absolute
coordinates, a body per moving MuJoCo body, and runs it with each formulation and in joint
coordinates (where the model allows); its `JOINT.q` columns are compared with MuJoCo's `qpos`."""

import json

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dalembert

MODELS = ["arm-3"]

# Every formulation in absolute coordinates, and joint coordinates (the articulated-body
# algorithm; the slide's spring, damper and motor act along its coordinate there).
SETTINGS = [dict(formulation=f) for f in ("augmented", "embedding", "amalgamated")] + [dict(coordinates="joint")]


def mujoco_run(path, end, qpos=None, qvel=None):
    """`qpos`, `qvel` of the model at `end` from the given state (rest at 0 by default)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)

    def rate(_, x):
        data.qpos[:], data.qvel[:] = x[: model.nq], x[model.nq :]
        mujoco.mj_forward(model, data)
        return np.concatenate([data.qvel, data.qacc])

    x0 = np.concatenate([np.zeros(model.nq) if qpos is None else qpos, np.zeros(model.nv) if qvel is None else qvel])
    x = solve_ivp(rate, (0.0, end), x0, method="DOP853", rtol=1e-12, atol=1e-13).y[:, -1]
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    return dict(zip(names, x[: model.nq])), dict(zip(names, x[model.nq :]))


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_run_from_rest_matches_mujoco(scenes, name):
    """From rest, 0.6 s: joint values within 1e-7 (rad or m) of MuJoCo's, rates within 1e-6, with
    every formulation and in joint coordinates."""
    path = scenes / "mjcf" / f"{name}.xml"
    values, rates = mujoco_run(path, 0.6)
    scene = dalembert.Scene.load(path)
    assert max(abs(v) for v in values.values()) > 0.05, "the arm moves"
    for settings in SETTINGS:
        run = scene.simulate(end=0.6, integrator="dopri5", rtol=1e-11, atol=1e-12, **settings)
        for joint, expected in values.items():
            assert abs(run[f"{joint}.q"][-1] - expected) < 1e-7, f"{settings} {joint}: {run[f'{joint}.q'][-1]} vs {expected}"
            assert abs(run[f"{joint}.qd"][-1] - rates[joint]) < 1e-6, f"{settings} {joint} rate"


def welded_to(model, k):
    """The nearest ancestor of body `k` (itself excluded) that has a joint, or the world (0)."""
    k = model.body_parentid[k]
    while k != 0 and model.body_jntnum[k] == 0:
        k = model.body_parentid[k]
    return k


def random_qpos(model, rng):
    """Hinge angles in ±π, slides in ±0.1 m; a hinge with a spring within 0.8π of the angle where
    it relaxes (dalembert's rotational spring measures its deflection within ±π and stops a run
    past 0.9π: docs/scenes.md; MuJoCo's follows any number of turns)."""
    hinge = mujoco.mjtJoint.mjJNT_HINGE

    def one(j):
        if model.jnt_type[j] != hinge:
            return rng.uniform(-0.1, 0.1)
        if model.jnt_stiffness[j] > 0:
            rest = model.qpos_spring[model.jnt_qposadr[j]]
            return rng.uniform(rest - 0.8 * np.pi, rest + 0.8 * np.pi)
        return rng.uniform(-np.pi, np.pi)

    return np.array([one(j) for j in range(model.njnt)])


def placed(model, data, ids, qpos, qvel):
    """dalembert's absolute state of MuJoCo's `qpos`, `qvel` (after `mj_forward`, which this
    runs): each body's centre of mass `xipos`, frame `xquat`, velocities from `mj_objectVelocity`
    at `xipos`; bodies welded to one another are one body in dalembert, at their centre of mass."""
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, data)
    q, v = [], []
    for i in ids:
        R = data.xmat[i].reshape(3, 3)
        w, x, y, z = data.xquat[i]
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, i, velocity, 0)
        omega, linear = velocity[:3], velocity[3:]
        welded = [i] + [k for k in range(model.nbody) if model.body_jntnum[k] == 0 and welded_to(model, k) == i]
        mass = sum(model.body_mass[k] for k in welded)
        centre = sum(model.body_mass[k] * data.xipos[k] for k in welded) / mass
        q += [*centre, w, x, y, z]
        v += [*(linear + np.cross(omega, centre - data.xipos[i])), *(R.T @ omega)]
    return q, v


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_motion_from_random_states_matches_mujoco(scenes, name):
    """From 10 random states placed from MuJoCo's own forward kinematics (each body's centre of
    mass `xipos`, frame `xquat`, velocities from `mj_objectVelocity` at `xipos`; bodies welded to
    one another merged): the assembly moves them by
    less than 1e-12 (both readers place every body alike) and 0.05 s later the joint values agree
    within 1e-9."""
    path = scenes / "mjcf" / f"{name}.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    scene = dalembert.Scene.load(path)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in scene.bodies]
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    rng = np.random.default_rng(20261126)
    for _ in range(10):
        qpos = random_qpos(model, rng)
        qvel = rng.uniform(-2.0, 2.0, model.nv)
        q, v = placed(model, data, ids, qpos, qvel)
        values, _ = mujoco_run(path, 0.05, qpos, qvel)
        for settings in SETTINGS:
            sim = scene.simulator(integrator="dopri5", rtol=1e-12, atol=1e-13, **settings)
            moved = sim.set_state(q, v)
            assert moved["positions"] < 1e-12 and moved["velocities"] < 1e-12, f"assembly moved {moved}"
            sim.advance_to(0.05)
            for joint in names:
                got, expected = sim[f"{joint}.q"], values[joint]
                gap = abs((got - expected + np.pi) % (2 * np.pi) - np.pi)
                assert gap < 1e-9, f"{settings} {joint}: {got} vs MuJoCo {expected}"


def rotation(e):
    """The rotation matrix of Euler parameters `e0, e1, e2, e3`."""
    e0, e1, e2, e3 = e
    return np.array([
        [e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
        [2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)],
        [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3],
    ])


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_geoms_are_drawn_where_mujoco_places_them(scenes, name, tmp_path):
    """The 3D viewer draws a body's sphere, box, cylinder and capsule geoms (a capsule as its
    cylinder and two balls). At the file's configuration, each one's centre (the page's visual, in
    its body's frame, placed by the run's first row) is MuJoCo's `geom_xpos` within 1e-9 m, a box's
    axes `geom_xmat` within 1e-9 (a cylinder's axis up to its sign; a sphere has none to check),
    and its size MuJoCo's `geom_size`."""
    path = scenes / "mjcf" / f"{name}.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    scene = dalembert.Scene.load(path)
    run = scene.simulate(end=0.001)
    page = tmp_path / "page.html"
    run.animate(page)
    html = page.read_text()
    start = html.index(">", html.index('id="dalembert-data"')) + 1
    drawing = json.loads(html[start : html.index("</script>", start)])["drawing"]["spatial"]
    placed = []
    for body in drawing["bodies"]:
        c = np.array([run[f"{body['name']}.{k}"][0] for k in "xyz"])
        R = rotation([run[f"{body['name']}.e{k}"][0] for k in range(4)])
        for v in body["visuals"]:
            placed.append((v["shape"], c + R @ v["position"], R @ rotation(v["rotation"])))
    kinds = {int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere", int(mujoco.mjtGeom.mjGEOM_BOX): "box",
             int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder", int(mujoco.mjtGeom.mjGEOM_CAPSULE): "cylinder"}
    checked = 0
    for g in range(model.ngeom):
        if model.geom_bodyid[g] == 0:
            continue  # the world's floor: not drawn
        kind, size = kinds[int(model.geom_type[g])], model.geom_size[g]
        near = [p for p in placed if p[0]["kind"] == kind and np.max(np.abs(p[1] - data.geom_xpos[g])) < 1e-9]
        assert len(near) == 1, f"geom {g} ({kind}) at {data.geom_xpos[g]}: {len(near)} visuals there"
        shape, _, axes = near[0]
        expected_axes = data.geom_xmat[g].reshape(3, 3)
        if kind == "box":
            assert np.max(np.abs(axes - expected_axes)) < 1e-9, f"geom {g}: axes"
        elif kind == "cylinder":  # its axis, either way (MuJoCo's fromto turns z from 'to' to 'from')
            assert abs(abs(axes[:, 2] @ expected_axes[:, 2]) - 1.0) < 1e-9, f"geom {g}: axis"
        expected = {"sphere": [size[0]], "box": list(2 * size), "cylinder": [size[0], 2 * size[1]]}[kind]
        got = {"sphere": lambda s: [s["radius"]], "box": lambda s: s["size"], "cylinder": lambda s: [s["radius"], s["length"]]}[kind](shape)
        assert np.allclose(got, expected, rtol=0, atol=1e-12), f"geom {g}: {got} vs {expected}"
        checked += 1
    assert checked == model.ngeom - 1


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_accelerations_from_1000_random_states_match_mujoco(scenes, name):
    """At 1 000 random states (hinge angles in ±π, slides in ±0.1 m, rates in ±2), the joint
    accelerations `JOINT.qdd` of every formulation and of joint coordinates are MuJoCo's `qacc`
    (contacts off, the joint dampers in both) within 1e-9 of the largest of them."""
    path = scenes / "mjcf" / f"{name}.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    scene = dalembert.Scene.load(path)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in scene.bodies]
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    rng = np.random.default_rng(1000)
    cases = []
    for _ in range(1000):
        qpos = random_qpos(model, rng)
        q, v = placed(model, data, ids, qpos, rng.uniform(-2.0, 2.0, model.nv))
        cases.append((q, v, data.qacc.copy()))
    for settings in SETTINGS:
        sim = scene.simulator(**settings)
        worst = 0.0
        for q, v, qacc in cases:
            moved = sim.set_state(q, v)
            assert moved["positions"] < 1e-12 and moved["velocities"] < 1e-12
            got = np.array([sim[f"{joint}.qdd"] for joint in names])
            worst = max(worst, np.max(np.abs(got - qacc)) / np.max(np.abs(qacc)))
        assert worst < 1e-9, f"{settings}: {worst:.2e}"
        print(f"{name} {settings}: worst relative difference {worst:.2e}")


def relative_qdd_difference(sim, state, inputs, joints, qacc):
    """`sim`'s `JOINT.qdd` at the absolute `state` with `inputs` set (names to values), against
    MuJoCo's `qacc`, relative to its largest; the assembly must not move the state (1e-12)."""
    for name, u in inputs.items():
        sim.set_input(name, u)
    moved = sim.set_state(*state)
    assert moved["positions"] < 1e-12 and moved["velocities"] < 1e-12, f"assembly moved {moved}"
    got = np.array([sim[f"{joint}.qdd"] for joint in joints])
    return np.max(np.abs(got - qacc)) / np.max(np.abs(qacc))


@pytest.mark.parametrize("name", MODELS)
def test_mjcf_motors_accelerate_as_mujocos_at_random_states_and_controls(scenes, name):
    """Motors are named inputs times their gear (a torque about a hinge, a force along a slide),
    the control held in `ctrlrange` and the force in `forcerange` (arm-3's are ±2 and [−1.5, 1]):
    at 200 random states with random controls in ±3 (MuJoCo's `ctrl`, dalembert's inputs),
    `JOINT.qdd` of every formulation and of joint coordinates is MuJoCo's `qacc` within 1e-9 of
    the largest. With the
    inputs at 0 instead the accelerations differ by far more than that: the motors act."""
    path = scenes / "mjcf" / f"{name}.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    scene = dalembert.Scene.load(path)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in scene.bodies]
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    motors = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu)]
    assert motors and set(motors) <= set(scene.simulator().inputs)
    rng = np.random.default_rng(77)
    cases = []
    for _ in range(200):
        data.ctrl[:] = rng.uniform(-3.0, 3.0, model.nu)
        q, v = placed(model, data, ids, random_qpos(model, rng), rng.uniform(-2.0, 2.0, model.nv))
        cases.append((q, v, data.ctrl.copy(), data.qacc.copy()))
    for settings in SETTINGS:
        sim = scene.simulator(**settings)
        worst, unmoved = 0.0, 0.0
        for q, v, ctrl, qacc in cases:
            idle = relative_qdd_difference(sim, (q, v), dict.fromkeys(motors, 0.0), names, qacc)
            unmoved = max(unmoved, idle)
            worst = max(worst, relative_qdd_difference(sim, (q, v), dict(zip(motors, ctrl)), names, qacc))
        assert worst < 1e-9, f"{settings}: {worst:.2e}"
        assert unmoved > 1e-2, f"{settings}: the motors change the accelerations by {unmoved:.2e} only"
        print(f"{name} {settings} with controls: worst relative difference {worst:.2e}")
