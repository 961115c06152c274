"""What a force computed by a Python function costs per call (docs/simulator.md).

The wheel on a pin of tests/data/wheel.toml, RK4 at 1 ms for 10 s (40 000 stages), with and without a Python function giving
its torque; the difference over the number of calls is the cost of one call (the function's own
body included: a few arithmetic operations).

    .venv/bin/python examples/python/force_cost.py
"""

import pathlib
import time

import dalembert

WHEEL = (pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "wheel.toml").read_text()


def run(scene, with_function):
    sim = scene.simulator()
    calls = [0]
    if with_function:

        def torque(t, body):
            calls[0] += 1
            return (0.0, 0.0, -8.0 * body.angle - 0.4 * body.angular_velocity[2])

        sim.set_force("controller", torque)
    start = time.perf_counter()
    for k in range(1, 101):
        sim.advance_to(0.1 * k)
    return time.perf_counter() - start, calls[0]


def main():
    scene = dalembert.Scene.from_toml(WHEEL, "wheel")
    run(scene, False), run(scene, True)
    base = min(run(scene, False)[0] for _ in range(5))
    timed = [run(scene, True) for _ in range(5)]
    best, calls = min(t for t, _ in timed), timed[0][1]
    print(f"without a function: {base * 1e3:.1f} ms; with a Python function: {best * 1e3:.1f} ms "
          f"for {calls} calls: {(best - base) / calls * 1e6:.2f} µs per call")


if __name__ == "__main__":
    main()
