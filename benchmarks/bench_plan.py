"""Time of :func:`sensorless.metric.optimize_trajectory` for a 7-joint, 5 s task (issue 15).

The task: the robot (default ``panda``) moves from 30 % to 70 % of every
joint's range in 5 s, rest to rest, within its position, velocity and torque
limits. Prints the median wall time (and process CPU time) of ``--repeat``
runs after one warm-up run (numba compilation and the base-parameter cache are
excluded), EM of the quintic and of the plan, and the solver's counts.
Goal of the issue: <= 30 s on 2 cores. Then the cost of one evaluation of
the integrand of eq. 3.30 on the 41-point collocation grid of that task,
without and with its gradient (median of 7), against what forward
differences over the 28 free control points would cost (29 evaluations).

    .venv/bin/python benchmarks/bench_plan.py [--robot panda] [--duration 5] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import sensorless as sl
from sensorless.metric import optimize_trajectory, parameter_bounds
from sensorless.metric._objective import SmoothIntegrand, backend_of


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="panda")
    parser.add_argument("--duration", type=float, default=5.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--backend", default="auto", choices=["auto", "numba", "numpy"])
    args = parser.parse_args()

    robot = sl.robots.load(args.robot)
    lower, upper = robot.position_limits
    start, end = lower + 0.3 * (upper - lower), lower + 0.7 * (upper - lower)

    def run() -> sl.metric.PlannedTrajectory:
        return optimize_trajectory(robot, start, end, args.duration, backend=args.backend)

    run()  # compile, fill the base-parameter cache
    walls, cpus = [], []
    for _ in range(args.repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = run()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    print(
        f"{args.robot} ({robot.n_dof} joints), {args.duration:g} s task, backend {args.backend}: "
        f"median {statistics.median(walls):.2f} s wall, {statistics.median(cpus):.2f} s CPU "
        f"over {args.repeat} runs (all wall: {', '.join(f'{w:.2f}' for w in walls)} s)"
    )
    print(
        f"EM {result.initial_metric:.4f} -> {result.metric:.4f} N m s "
        f"({100 * result.improvement:.1f} % lower); mean B_c {result.initial_bound.mean():.4f} -> "
        f"{result.bound.mean():.4f} N m; {result.n_iterations} SLSQP iterations, "
        f"{result.n_values} values, {result.n_gradients} gradients; success {result.success}"
    )
    gradient_cost(robot, backend_of(args.backend))


def gradient_cost(robot: sl.RobotModel, backend: str) -> None:
    """Median time of the integrand without and with its gradient on 41 random samples."""
    base = sl.base_parameters(robot)
    theta = base.values_of(robot)
    n = robot.n_dof
    rng = np.random.default_rng(0)
    bq = rng.uniform(0.0, 1e-2, (n * n + 3 * n + 2) // 2)
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, 41, n))
    btheta = parameter_bounds(0.02, theta)
    integrand = SmoothIntegrand(
        robot, base.independent, theta, btheta, bq, np.ones(n), 1.0, backend
    )
    integrand(q, qd, qdd)

    def median(with_gradient: bool) -> float:
        times = []
        for _ in range(7):
            start = time.perf_counter()
            integrand(q, qd, qdd, with_gradient)
            times.append(time.perf_counter() - start)
        return statistics.median(times)

    value, both = median(False), median(True)
    print(
        f"integrand on 41 samples ({backend}): value {1e3 * value:.2f} ms, value and gradient "
        f"{1e3 * both:.2f} ms; forward differences over 28 control points: "
        f"{29e3 * value:.1f} ms"
    )


if __name__ == "__main__":
    main()
