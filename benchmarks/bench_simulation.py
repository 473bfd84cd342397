"""Simulated seconds per wall-clock second at 1 kHz (issue 3).

Cases: the 6-joint rigid PUMA 560 with LuGre friction (scenario
``puma560-thesis``, PID of Table 5.2) and a 7-joint flexible arm (panda_gaz
links, K = 5000 N m/rad, torque feedback). Median of several runs.

    .venv/bin/python benchmarks/bench_simulation.py [--seconds 10] [--repeat 3]
"""

from __future__ import annotations

import argparse
import copy
import statistics
import time

import numpy as np

import sensorless as sl
from sensorless.simulation.controllers import JointPID
from sensorless.simulation.plants import FlexiblePlant, TorqueFeedback
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.simulation.simulator import simulate
from sensorless.trajectories import RandomPointToPoint


def real_time_factor(run, seconds: float, repeat: int) -> tuple[float, int]:
    times, substeps = [], 0
    for _ in range(repeat):
        start = time.perf_counter()
        substeps = run().substeps
        times.append(time.perf_counter() - start)
    return seconds / statistics.median(times), substeps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    spec = copy.deepcopy(load_scenario("puma560-thesis").spec)
    spec["duration"] = args.seconds
    puma = Scenario("puma560-thesis", spec)
    rigid, rigid_sub = real_time_factor(lambda: puma.run(), args.seconds, args.repeat)
    free, _ = real_time_factor(lambda: puma.run(collisions=False), args.seconds, args.repeat)

    robot = sl.robots.load("panda_gaz")
    lower, upper = robot.position_limits
    span = upper - lower
    trajectory = RandomPointToPoint(
        7,
        args.seconds,
        lower + 0.2 * span,
        upper - 0.2 * span,
        1.0,
        seed=1,
        segment_time=(1.0, 2.0),
    )
    plant = FlexiblePlant(
        robot,
        stiffness=5000.0,
        damping=5.0,
        motor_inertia=0.3,
        link_friction=robot.friction,
        feedback=TorqueFeedback(motor_inertia=0.1, damping=1.0),
    )
    inertia = np.diag(robot.mass_matrix(trajectory.evaluate(0.0)[0])) + 0.3
    controller = JointPID(kp=inertia * 900.0, ki=0.0, kd=inertia * 60.0, model=robot)
    flexible, flexible_sub = real_time_factor(
        lambda: simulate(plant, controller, trajectory, args.seconds), args.seconds, args.repeat
    )
    print(f"{args.seconds:g} s simulated at 1 kHz, median of {args.repeat} runs")
    print(
        f"rigid PUMA 560 + LuGre, contacts:    {rigid:6.1f} x real time ({rigid_sub} RK4 substeps)"
    )
    print(f"rigid PUMA 560 + LuGre, no contacts: {free:6.1f} x real time")
    print(f"flexible 7-joint arm:   {flexible:6.1f} x real time ({flexible_sub} substeps)")


if __name__ == "__main__":
    main()
