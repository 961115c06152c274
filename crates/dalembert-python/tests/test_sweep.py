"""Sweeps: every row equals the run it stands for, whatever executes it; failures stay in their
row."""

import concurrent.futures
import csv
import subprocess

import numpy as np
import pytest

import dalembert
from conftest import cli

PARAMS = {"bodies.slider.mass": [1.0, 2.0, 4.0], "forces.return-spring.stiffness": [50.0, 80.0]}
OUTPUTS = ["slider.x", "max:slider.x", "mean:crank.omega", "maxabs:guide.fy", "statistics.steps"]


@pytest.fixture
def scene(scenes):
    return dalembert.Scene.load(scenes / "slider-crank.toml")


def expected(scene, assignment, end=0.5):
    """The outputs of one run, computed from a whole Run with numpy."""
    run = scene.with_values(assignment).simulate(end=end)
    return [
        run["slider.x"][-1],
        run["slider.x"].max(),
        run["crank.omega"].mean(),
        np.abs(run["guide.fy"]).max(),
        run.statistics["steps"],
    ]


def test_cartesian_product_on_local_cores(scene):
    res = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS)
    assert len(res) == 6 and res.parameters == list(PARAMS) and res.outputs == OUTPUTS
    # The first path varies slowest.
    assert [r["bodies.slider.mass"] for r in res] == [1.0, 1.0, 2.0, 2.0, 4.0, 4.0]
    for row in res:
        a = {p: row[p] for p in PARAMS}
        want = expected(scene, a)
        got = [row[o] for o in OUTPUTS]
        # Same computation, same order of operations: equal to the bit except the mean, summed
        # in another order (1e-12 relative).
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
        assert row["error"] is None and row["wall_time_s"] > 0


def test_one_failure_keeps_the_other_rows(scene):
    runs = [{"bodies.slider.mass": 1.0}, {"bodies.slider.mass": -1.0}, {"simulation.integrator": "rk5"}, {"bodies.slider.mass": 2.0}]
    res = dalembert.sweep(scene, runs, end=0.2, outputs=["slider.x"])
    errors = [r["error"] for r in res]
    assert errors[0] is None and errors[3] is None
    assert "mass must be finite and non-negative, got -1" in errors[1]
    assert "unknown integrator 'rk5'" in errors[2]
    assert np.isnan(res["slider.x"][1]) and np.isfinite(res["slider.x"][3])
    assert len(res.errors) == 2


def test_bad_paths_and_outputs_fail_before_any_run(scene):
    with pytest.raises(dalembert.SceneError, match="no force named 'spring'"):
        dalembert.sweep(scene, {"forces.spring.stiffness": [1.0]}, end=0.1)
    # A key the element does not have: named with the element's keys and the nearest.
    with pytest.raises(dalembert.SceneError, match=r"cannot set 'bodies.slider.masss': bodies.slider has no key 'masss' \(its keys: name, mass, .*\); did you mean 'bodies.slider.mass'\?$"):
        dalembert.sweep(scene, {"bodies.slider.masss": [1.0, 2.0]}, end=0.1)
    with pytest.raises(dalembert.SceneError, match="unknown output 'slider.z'"):
        dalembert.sweep(scene, {"bodies.slider.mass": [1.0]}, end=0.1, outputs=["slider.z"])


def test_process_pool_gives_the_same_rows(scene):
    local = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS)
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        remote = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS, executor=pool, chunk_size=2)
    for a, b in zip(local, remote):
        assert [a[o] for o in OUTPUTS] == [b[o] for o in OUTPUTS]
        assert [a[p] for p in PARAMS] == [b[p] for p in PARAMS]


def test_dask_local_cluster(scene):
    distributed = pytest.importorskip("distributed")
    local = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            res = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS, executor=client.get_executor())
            # The runs really went to the workers' processes.
            assert len(client.scheduler_info()["workers"]) == 2
    assert len(res) == 6
    for a, b in zip(local, res):
        assert [a[o] for o in OUTPUTS] == [b[o] for o in OUTPUTS]


def test_a_sweep_takes_the_path_of_a_scene(scenes):
    res = dalembert.sweep(str(scenes / "slider-crank.toml"), {"bodies.slider.mass": [1.0, 2.0]}, end=0.1, outputs=["slider.x"])
    direct = dalembert.sweep(dalembert.Scene.load(scenes / "slider-crank.toml"), {"bodies.slider.mass": [1.0, 2.0]}, end=0.1, outputs=["slider.x"])
    np.testing.assert_array_equal(res["slider.x"], direct["slider.x"])
    with pytest.raises(TypeError, match="^scene: expected a dalembert.Scene or the path of a scene file, got int$"):
        dalembert.sweep(3, {"bodies.slider.mass": [1.0]})


def test_ctrl_c_stops_a_sweep_and_keeps_its_rows(scenes):
    """Ctrl-C during a sweep of runs that would each take hours: the runs in progress stop at their
    next step, KeyboardInterrupt carries the rows (`.result`), the first run (0.05 s) finished."""
    import os
    import signal
    import threading
    import time

    scene = dalembert.Scene.load(scenes / "chain-8.toml")
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt) as info:
        dalembert.sweep(scene, {"simulation.end": [0.05, 1e5, 1e5, 1e5]}, outputs=["link0.x"], threads=2)
    assert time.perf_counter() - start < 3.0
    res = info.value.result
    assert len(res) == 4
    errors = [r["error"] for r in res]
    assert errors[0] is None and np.isfinite(res["link0.x"][0])
    assert all(e.startswith("interrupted at t = ") or e == "cancelled" for e in errors[1:]), errors
    assert any(e.startswith("interrupted at t = ") for e in errors[1:]), errors


def test_cli_sweep_writes_the_same_numbers(scene, scenes, tmp_path):
    out = tmp_path / "sweep.csv"
    subprocess.run(
        [
            cli(),
            "sweep",
            scenes / "slider-crank.toml",
            "--set",
            "bodies.slider.mass=1,2,4",
            "--set",
            "forces.return-spring.stiffness=50,80",
            "--end",
            "0.5",
            "--outputs",
            ",".join(OUTPUTS),
            "--output",
            out,
        ],
        check=True,
        capture_output=True,
    )
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    res = dalembert.sweep(scene, PARAMS, end=0.5, outputs=OUTPUTS)
    assert len(rows) == 6
    for cli_row, row in zip(rows, res):
        assert float(cli_row["bodies.slider.mass"]) == row["bodies.slider.mass"]
        assert [float(cli_row[o]) for o in OUTPUTS] == [row[o] for o in OUTPUTS]
        assert cli_row["error"] == ""


def test_to_pandas(scene):
    pd = pytest.importorskip("pandas")
    res = dalembert.sweep(scene, PARAMS, end=0.1, outputs=["slider.x"])
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == res.columns and len(df) == 6
