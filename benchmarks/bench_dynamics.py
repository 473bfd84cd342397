"""Throughput of the dynamics on the 7-joint Panda (issue 2).

Prints samples per second (median of several runs) of M(q), g(q), C(q, q̇)ᵀq̇
and the regressor, batch (one call on (n_samples, 7) arrays) and per sample
(one call per sample), next to a bare Pinocchio ``rnea`` loop measured in the
same run: the floor set by calling Pinocchio from Python.

    .venv/bin/python benchmarks/bench_dynamics.py [--samples 100000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import sensorless as sl


def median_rate(run: Callable[[], object], n_samples: int, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return n_samples / statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument(
        "--per-sample", type=int, default=20_000, help="samples of the per-sample loops"
    )
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    robot = sl.robots.load("panda_gaz")
    rng = np.random.default_rng(0)
    shape = (args.samples, robot.n_dof)
    q, qd, qdd = rng.uniform(-2, 2, shape), rng.standard_normal(shape), rng.standard_normal(shape)
    model = robot.pinocchio_model
    data = model.createData()
    m = args.per_sample

    def rnea_floor() -> None:
        for k in range(m):
            pin.rnea(model, data, q[k], qd[k], qdd[k])

    rows = [("bare pin.rnea loop (floor)", None, median_rate(rnea_floor, m, args.repeat))]
    cases: list[tuple[str, Callable[[np.ndarray, np.ndarray, np.ndarray], object]]] = [
        ("mass_matrix M(q)", lambda a, b, c: robot.mass_matrix(a)),
        ("gravity g(q)", lambda a, b, c: robot.gravity(a)),
        (
            "coriolis_transpose_velocity Cᵀq̇",
            lambda a, b, c: robot.coriolis_transpose_velocity(a, b),
        ),
        ("inverse_dynamics (RNEA)", lambda a, b, c: robot.inverse_dynamics(a, b, c)),
        ("regressor Y(q, q̇, q̈)", lambda a, b, c: robot.regressor(a, b, c)),
    ]
    for label, call in cases:
        batch = median_rate(lambda call=call: call(q, qd, qdd), args.samples, args.repeat)

        def per_sample(call=call) -> None:
            for k in range(m):
                call(q[k], qd[k], qdd[k])

        rows.append((label, batch, median_rate(per_sample, m, args.repeat)))

    print(f"panda_gaz (7 joints): {args.samples} samples batch, {m} per sample")
    print(f"median of {args.repeat} runs")
    print(f"{'quantity':36s} {'batch [samples/s]':>18s} {'per sample [samples/s]':>24s}")
    for label, batch, single in rows:
        batch_text = "-" if batch is None else f"{batch:,.0f}"
        print(f"{label:36s} {batch_text:>18s} {single:>24,.0f}")


if __name__ == "__main__":
    main()
