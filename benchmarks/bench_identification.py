"""Inertial identification on 30 minutes of 1 kHz data of the 7-joint Panda (issue 5).

Random states stand in for a recorded excitation; the torques are the
panda_gaz inverse dynamics plus white noise (0.05 N m). The data are
made and consumed one segment at a time, as a reader of a long log would, so
peak memory stays that of one segment. Prints wall time and peak RSS.

    .venv/bin/python benchmarks/bench_identification.py [--minutes 30] [--segment 60000]
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

import sensorless as sl
from sensorless.identification.regression import RegressionAccumulator


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--segment", type=int, default=60_000)
    args = parser.parse_args()

    robot = sl.robots.load("panda_gaz")
    base = sl.base_parameters(robot)
    rng = np.random.default_rng(0)
    n_total = int(args.minutes * 60 * 1000)
    accumulator = RegressionAccumulator(base.count)
    start = time.perf_counter()
    done = 0
    while done < n_total:
        size = min(args.segment, n_total - done)
        shape = (size, robot.n_dof)
        q, qd, qdd = (
            rng.uniform(-2, 2, shape),
            rng.standard_normal(shape),
            rng.standard_normal(shape),
        )
        tau = robot.inverse_dynamics(q, qd, qdd) + 0.05 * rng.standard_normal(shape)
        accumulator.add(base.regressor(q, qd, qdd).reshape(-1, base.count), tau.reshape(-1))
        done += size
    result = accumulator.result(base.names)
    elapsed = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    error = np.abs(result.estimates - base.values).max()
    print(f"{n_total} samples (7 joints, {base.count} base parameters), segments of {args.segment}")
    print(f"wall time {elapsed:.1f} s (data generation included), peak RSS {peak:.0f} MiB")
    print(f"max |estimate - true| = {error:.2e}, R² = {result.r_squared:.6f}")


if __name__ == "__main__":
    main()
