"""Two MuJoCo Menagerie robots, read by MuJoCo and by dalembert's MJCF reader, with contacts off.

`tests/data/menagerie` holds unchanged copies of the KUKA iiwa 14 (`general` actuators with an
affine bias: position servos) and the Kinova Gen3 (`position` actuators with `kv` and
`forcerange`). Their meshes are not copied: every body gives its `<inertial>`, so the mesh geoms
carry no dynamics, and MuJoCo, which would open the files, reads the model with them removed.
MuJoCo's `qacc` (`mj_forward`) is the reference; dalembert's `JOINT.qdd` is compared with it at
random states and controls, and a run from rest with MuJoCo's accelerations integrated by DOP853."""

import pathlib
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dalembert
from test_mjcf import SETTINGS, placed, relative_qdd_difference

ROBOTS = {
    "iiwa14": "menagerie/kuka_iiwa_14/iiwa14.xml",
    "gen3": "menagerie/kinova_gen3/gen3.xml",
    # Not a Menagerie model: position servos with gears on a slide and a hinge, and a velocity
    # servo (tests/data/imported/servos.xml).
    "servos": "imported/servos.xml",
}

# SETTINGS (from test_mjcf): every formulation in absolute coordinates, and joint coordinates
# (the articulated-body algorithm, where a servo reads its joint's coordinate).


def menagerie(root: pathlib.Path, name: str) -> pathlib.Path:
    return root / "tests" / "data" / ROBOTS[name]


def mujoco_model(path: pathlib.Path):
    """MuJoCo's model of the file without its mesh geoms and mesh assets (their files are not
    copied; with every body's `<inertial>` given they carry no mass), contacts off."""
    tree = ET.parse(path)
    for parent in tree.iter():
        for child in list(parent):
            if (child.tag == "geom" and "mesh" in child.attrib) or (parent.tag == "asset" and child.tag == "mesh"):
                parent.remove(child)
    model = mujoco.MjModel.from_xml_string(ET.tostring(tree.getroot(), encoding="unicode"))
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return model


def states(model, rng, count):
    """`count` random states and controls: angles within each joint's range (±π where it has
    none), a control whose target is near the angle (or the rate), within 0.8π of it (dalembert's servo measures the distance
    within ±π and stops a run past 0.9π; MuJoCo's follows any number of turns), a fifth of them
    beyond `ctrlrange` where the actuator has one (MuJoCo and dalembert hold it there). Half the
    states are slow and near their targets, where the servos' forces stay inside `forcerange`;
    the other half push them to its bounds."""
    out = []
    for k in range(count):
        near = k % 2 == 0
        qpos = np.empty(model.njnt)
        for j in range(model.njnt):
            lo, hi = model.jnt_range[j] if model.jnt_limited[j] else (-np.pi, np.pi)
            qpos[j] = rng.uniform(lo + 0.05, hi - 0.05)
        qvel = rng.uniform(-0.05, 0.05, model.nv) if near else rng.uniform(-2.0, 2.0, model.nv)
        ctrl = np.empty(model.nu)
        for a in range(model.nu):
            j = model.actuator_trnid[a, 0]
            q, rate = qpos[j], qvel[model.jnt_dofadr[j]]
            spread = 0.01 if near else 2.0
            # A control whose target (a position servo's g ū / (−b₁ gear), a velocity servo's
            # g ū / (−b₂ gear)) is near the joint's angle or rate.
            gain, b1, b2, gear = (model.actuator_gainprm[a, 0], model.actuator_biasprm[a, 1],
                                  model.actuator_biasprm[a, 2], model.actuator_gear[a, 0])
            if b1 != 0:
                ctrl[a] = (q + rng.uniform(-spread, spread)) * (-b1 * gear) / gain
            elif b2 != 0:
                ctrl[a] = (rate + rng.uniform(-spread, spread)) * (-b2 * gear) / gain
            else:
                ctrl[a] = rng.uniform(-spread, spread)
            lo, hi = model.actuator_ctrlrange[a] if model.actuator_ctrllimited[a] else (-np.inf, np.inf)
            if model.actuator_ctrllimited[a] and rng.uniform() < 0.2:
                ctrl[a] = rng.choice([lo - 0.2, hi + 0.2])
            # A position servo's target angle, g ū / (−b₁ gear): within 0.8π of the angle.
            gain, b1, gear = model.actuator_gainprm[a, 0], model.actuator_biasprm[a, 1], model.actuator_gear[a, 0]
            if b1 != 0 and abs(gain * np.clip(ctrl[a], lo, hi) / (-b1 * gear) - q) > 0.8 * np.pi:
                ctrl[a] = q * (-b1 * gear) / gain
        out.append((qpos, qvel, ctrl))
    return out


@pytest.mark.parametrize("name", ROBOTS)
def test_menagerie_accelerations_match_mujoco_at_random_states_and_controls(root, name):
    """At 300 random states and controls (`states`), `JOINT.qdd` of every formulation and of joint
    coordinates is MuJoCo's
    `qacc` within 1e-9 of the largest; some states have every servo's force inside its range and
    some hold forces at a bound (the range's effect is checked, not assumed); with the controls
    moved 0.3 toward the angles instead the accelerations differ by more than 1e-2: the
    actuators act."""
    path = menagerie(root, name)
    model = mujoco_model(path)
    data = mujoco.MjData(model)
    scene = dalembert.Scene.load(path)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in scene.bodies]
    joints = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    actuators = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu)]
    assert actuators and set(actuators) <= set(scene.simulator().inputs)
    rng = np.random.default_rng(2026_11_28)
    cases, clamped = [], 0
    states_used = states(model, rng, 300)
    for qpos, qvel, ctrl in states_used:
        data.ctrl[:] = ctrl
        q, v = placed(model, data, ids, qpos, qvel)
        held = model.actuator_forcelimited.astype(bool) & np.isclose(
            np.abs(data.actuator_force), np.abs(model.actuator_forcerange).max(axis=1), rtol=0, atol=1e-12
        )
        clamped += bool(held.any())
        cases.append((q, v, ctrl, data.qacc.copy()))
    if model.actuator_forcelimited.any():
        assert 30 < clamped < 270, f"{clamped} of 300 states hold a force at a bound"
    for settings in SETTINGS:
        sim = scene.simulator(**settings)
        worst, idle = 0.0, 0.0
        for (q, v, ctrl, qacc), (qpos, _, _) in zip(cases, states_used):
            toward = {a: u - 0.3 * np.sign(u - qpos[j]) for a, u, j in zip(actuators, ctrl, model.actuator_trnid[:, 0])}
            idle = max(idle, relative_qdd_difference(sim, (q, v), toward, joints, qacc))
            worst = max(worst, relative_qdd_difference(sim, (q, v), dict(zip(actuators, ctrl)), joints, qacc))
        print(f"{name} {settings}: worst relative difference {worst:.2e}")
        assert worst < 1e-9, f"{settings}: {worst:.2e}"
        assert idle > 1e-2, f"{settings}: the actuators change the accelerations by {idle:.2e} only"


@pytest.mark.parametrize("name", ROBOTS)
def test_menagerie_run_from_rest_holds_its_servos_as_mujoco(root, name):
    """From the file's configuration at rest, the controls at 0.3 rad (within every range), 0.2 s:
    the servos pull each joint toward 0.3 against gravity; dalembert's joint values are MuJoCo's
    (its `qacc` integrated by DOP853 at 1e-12) within 1e-8 rad, rates within 1e-6 rad/s, with
    every formulation and in joint coordinates (dopri5 at 1e-12; the servos' damping makes the motion stiff, so both take
    small steps)."""
    path = menagerie(root, name)
    model = mujoco_model(path)
    data = mujoco.MjData(model)
    data.ctrl[:] = 0.3

    def rate(_, x):
        data.qpos[:], data.qvel[:] = x[: model.nq], x[model.nq :]
        mujoco.mj_forward(model, data)
        return np.concatenate([data.qvel, data.qacc])

    end = 0.2
    x = solve_ivp(rate, (0.0, end), np.zeros(model.nq + model.nv), method="DOP853", rtol=1e-12, atol=1e-13).y[:, -1]
    joints = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)]
    actuators = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu)]
    assert np.max(np.abs(x[: model.nq])) > 0.1, "the joints move"
    scene = dalembert.Scene.load(path)
    for settings in SETTINGS:
        sim = scene.simulator(integrator="dopri5", rtol=1e-12, atol=1e-13, **settings)
        for a in actuators:
            sim.set_input(a, 0.3)
        sim.advance_to(end)
        for k, j in enumerate(joints):
            assert abs(sim[f"{j}.q"] - x[k]) < 1e-8, f"{settings} {j}: {sim[f'{j}.q']} vs MuJoCo {x[k]}"
            assert abs(sim[f"{j}.qd"] - x[model.nq + k]) < 1e-6, f"{settings} {j} rate"
