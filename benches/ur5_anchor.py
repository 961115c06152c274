"""The UR5 in the anchors protocol: dalembert and MuJoCo on the same imported arm, in one run.

The protocol of `shared/anchors` (its README: 10 s at a fixed step of 1 ms, medians of repeated
runs, accuracy at t = 1 s against a tight reference, energy drift) applied to a model that protocol
does not define: `scenes/robots/ur5.urdf` (example-robot-data), released at rest from the file's
pose (every joint at 0) under gravity (0, 0, −9.81), contacts off.

* MuJoCo loads the same URDF, its `<visual>` and `<collision>` elements removed (their meshes are
  not needed for the dynamics), with RK4 at 1 ms: the loop of `mj_step` from Python (`sim_s`) and
  `mujoco.rollout` (`sim_native_s`).
* dalembert runs the same file from Python (`Scene.load`), RK4 at 1 ms, in joint coordinates and
  in absolute coordinates (augmented formulation); `sim_s` is the wall time of `simulate`,
  `sim_native_s` its integration loop (`statistics["wall_time_s"]`).
* The reference is Pinocchio's `aba` on the same file integrated by scipy's DOP853 at
  rtol = atol = 1e-12; errors are the largest joint-angle and joint-rate differences at 1 s.

One JSON record per line (the anchors' fields; `scene` is `"ur5"`) to `$ANCHORS_OUT` or
`target/ur5_anchor.jsonl`, and a table on stdout. Run with the test environment (`mujoco`, `pin`,
`scipy` and the package installed, as `bash tests/all.sh` sets up):

    .venv/bin/python benches/ur5_anchor.py            # 5 repeats
    ANCHORS_QUICK=1 .venv/bin/python benches/ur5_anchor.py   # 1 repeat
"""

import json
import os
import pathlib
import re
import statistics
import time

import mujoco
from mujoco import rollout
import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

import dalembert

ROOT = pathlib.Path(__file__).resolve().parent.parent
URDF = ROOT / "scenes" / "robots" / "ur5.urdf"
DT, END, STEPS = 1e-3, 10.0, 10_000
REPEATS = 1 if os.environ.get("ANCHORS_QUICK") else 5


def reference(names):
    """Joint angles and rates at 1 s from Pinocchio's `aba` (DOP853, 1e-12)."""
    model = pin.buildModelFromUrdf(str(URDF))
    data = model.createData()
    order = [list(model.names)[1:].index(n) for n in names]
    damping = np.array([model.damping[j.idx_v] for j in list(model.joints)[1:]])

    def rhs(_, y):
        q, v = y[: model.nq], y[model.nq :]
        return np.concatenate([v, pin.aba(model, data, q, v, -damping * v)])

    y0 = np.zeros(model.nq + model.nv)
    sol = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    q, v = sol.y[: model.nq, -1], sol.y[model.nq :, -1]
    return q[order], v[order]


def mujoco_model():
    text = URDF.read_text()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.S)
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep = DT
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.gravity[:] = (0.0, 0.0, -9.81)
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    model.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    return model


def mujoco_rows(names, ref):
    model = mujoco_model()
    data = mujoco.MjData(model)
    adr = [model.jnt_qposadr[model.joint(n).id] for n in names]
    vadr = [model.jnt_dofadr[model.joint(n).id] for n in names]
    loop = []
    for _ in range(REPEATS):
        mujoco.mj_resetData(model, data)
        mujoco.mj_forward(model, data)
        e0 = data.energy.sum()
        de_max, at_1s = 0.0, None
        start = time.perf_counter()
        for k in range(1, STEPS + 1):
            mujoco.mj_step(model, data)
            if k == 1000:
                at_1s = (data.qpos[adr].copy(), data.qvel[vadr].copy())
            if k % 10 == 0:
                de_max = max(de_max, abs(data.energy.sum() - e0))
        loop.append(time.perf_counter() - start)
        de_end = data.energy.sum() - e0
    native = []
    for _ in range(REPEATS):
        mujoco.mj_resetData(model, data)
        state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
        mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        start = time.perf_counter()
        rollout.rollout(model, data, state[None, :], nstep=STEPS)
        native.append(time.perf_counter() - start)
    return [
        record(
            "mujoco",
            "RK4",
            "RK4",
            statistics.median(loop),
            statistics.median(native),
            at_1s,
            ref,
            (de_end, de_max),
        )
    ]


def dalembert_rows(names, ref):
    scene = dalembert.Scene.load(str(URDF))
    rows = []
    for variant, keywords in [
        ("joint coordinates RK4", {"coordinates": "joint"}),
        ("augmented RK4", {"formulation": "augmented"}),
    ]:
        wall, loop = [], []
        for _ in range(REPEATS):
            start = time.perf_counter()
            run = scene.simulate(end=END, integrator="rk4", step=DT, every=0.01, **keywords)
            wall.append(time.perf_counter() - start)
            loop.append(run.statistics["wall_time_s"])
        k = int(np.argmin(np.abs(run.t - 1.0)))
        at_1s = (
            np.array([run[f"{n}.q"][k] for n in names]),
            np.array([run[f"{n}.qd"][k] for n in names]),
        )
        energy = run["energy"] - run["energy"][0]
        rows.append(
            record(
                "dalembert",
                variant,
                "RK4",
                statistics.median(wall),
                statistics.median(loop),
                at_1s,
                ref,
                (energy[-1], np.max(np.abs(energy))),
            )
        )
    return rows


def record(engine, variant, integrator, sim_s, native_s, at_1s, ref, energy):
    q, v = at_1s
    # Angles compared on the circle: a joint that turned past ±π is the same pose.
    dq = np.angle(np.exp(1j * (q - ref[0])))
    return {
        "engine": engine,
        "variant": variant,
        "scene": "ur5",
        "N": 1,
        "integrator": integrator,
        "sim_s": sim_s,
        "sim_native_s": native_s,
        "dt": DT,
        "steps": STEPS,
        "per_step_us": native_s / STEPS * 1e6,
        "err_pos_1s": float(np.max(np.abs(dq))),
        "err_vel_1s": float(np.max(np.abs(v - ref[1]))),
        "dE_10s": float(energy[0]),
        "dE_max": float(energy[1]),
    }


def main():
    model = mujoco_model()
    names = [model.joint(k).name for k in range(model.njnt)]
    ref = reference(names)
    rows = mujoco_rows(names, ref) + dalembert_rows(names, ref)
    out = pathlib.Path(os.environ.get("ANCHORS_OUT", ROOT / "target" / "ur5_anchor.jsonl"))
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    print(f"UR5, {END:g} s at {DT:g} s, medians of {REPEATS}; records in {out}")
    print("| engine/variant | sim_s | native s | µs/step | q error at 1 s (rad) | v error (rad/s) | ΔE at 10 s (J) | max ΔE (J) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['engine']}/{r['variant']} | {r['sim_s']:.3f} | {r['sim_native_s']:.3f} | "
            f"{r['per_step_us']:.1f} | {r['err_pos_1s']:.1e} | {r['err_vel_1s']:.1e} | "
            f"{r['dE_10s']:.1e} | {r['dE_max']:.1e} |"
        )


if __name__ == "__main__":
    main()
