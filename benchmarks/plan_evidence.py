"""Does the planned trajectory (issue 15, thesis § 3.4) detect collisions better than the quintic?

For the robot of each shipped scenario (``puma560-thesis``, ``panda-gaz``,
``lwr4-thesis``), one task (rest to rest, ``--duration`` seconds) is run along
five trajectories with the same ends:

``quintic``
    the project's default, one quintic per joint;
``planned``
    :func:`sensorless.metric.optimize_trajectory` on the scenario's nominal model
    (the model with the scenario's error, as a user has it);
``fixed-B_Q``
    the same planner with B_Q̃ held at the quintic's value (``bq=...``): blind
    to the estimator's lag, which its own motion increases;
``sequenced``, ``early``
    hand-picked piecewise quintics in the style of thesis Table 3.2 / Fig. 3.2
    (whose via points the thesis prints only as a figure): the first half of
    the joints moves first and the rest after; or 80 % of the way is done by
    half time.

Per trajectory the table gives EM[q] (eq. 3.32) and the mean model-based
bound B_c(t) (eq. 3.36 without B_fr, B_d), each with its own B_Q̃ by the
Table 3.1 method as the planner defines it (the largest over 8 noise draws),
but with draws the planner never saw (seed ``--eval-seed``): the planner
fits its own draws a little, so ``EM plan`` (its own figure, seed 0) is
printed beside it. Then, through the simulator (true robot, model error,
sensor noise, the scenario's plant and controller), the model-based
threshold ``model`` is tuned on two collision-free runs of that trajectory
(default margin), and a run with six end-effector impacts (half sines of
0.1 s at fixed times, peaks 2-32 N in a fixed shuffled order, the same for
every trajectory) is judged: contacts detected, false alarms, median
detection delay and the smallest peak force detected. ``B_fr`` is the part of
the bound the fit learns (friction and actuator errors, eq. 3.36), beside the
model part that the trajectory shapes.

    .venv/bin/python benchmarks/plan_evidence.py [--duration 3] [--robots puma560-thesis ...]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from sensorless.evaluation import evaluate
from sensorless.filters import Butterworth
from sensorless.io import Log
from sensorless.metric import (
    error_bound_terms,
    estimation_metric,
    optimize_trajectory,
    parameter_bounds,
    q_error_bounds,
)
from sensorless.monitor import CollisionMonitor, tune
from sensorless.robots.base_parameters import base_parameters
from sensorless.robots.model import RobotModel
from sensorless.simulation.collisions import Contact, ContactSet, HalfSine
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.simulation.simulator import simulate
from sensorless.trajectories import QuinticViaPoints, Trajectory

DEG = np.pi / 180
#: Start and end [rad] of the task of each scenario's robot.
TASKS = {
    # Thesis Table 5.1, rows 1 -> 3, with the scenario's joint_sign (Lee -> Paul convention).
    "puma560-thesis": (
        np.array([0, 90, -90, 0, 0, 0]) * DEG,
        np.array([45, 90, -135, 0, 90, 135]) * DEG,
    ),
    "panda-gaz": (
        np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]),
        np.array([1.2, 0.4, -0.6, -1.5, 0.5, 2.6, 0.0]),
    ),
    # Thesis § 3.6: joints 1, 2 and 4 of the LWR move, the others start and end at zero.
    "lwr4-thesis": (np.zeros(7), np.array([60, 30, 0, -60, 0, 0, 0]) * DEG),
}
PEAKS = [8.0, 2.0, 32.0, 4.0, 16.0, 3.0]  # [N], one per impact, in time order
DT = 1e-3


def alternatives(start: np.ndarray, end: np.ndarray, duration: float) -> dict[str, Trajectory]:
    """The hand-picked piecewise quintics (Table 3.2 style) with the same ends."""
    half = duration / 2
    first = np.arange(start.size) < (start.size + 1) // 2
    sequenced = np.where(first, end, start)
    early = start + 0.8 * (end - start)
    return {
        "sequenced": QuinticViaPoints([0, half, duration], [start, sequenced, end]),
        "early": QuinticViaPoints([0, half, duration], [start, early, end]),
    }


def impacts(robot: RobotModel, duration: float) -> ContactSet:
    """Six end-effector impacts at fixed times, the same for every trajectory."""
    times = np.linspace(0.4, duration - 0.2, len(PEAKS))
    directions = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (-1, 0, 0), (0, -1, 0), (0, 0, -1)]
    return ContactSet(
        [
            Contact(k + 1, robot.n_dof, (0.0, 0.0, 0.1), directions[k], HalfSine(t, 0.1, peak))
            for k, (t, peak) in enumerate(zip(times, PEAKS, strict=True))
        ]
    )


def run(scenario: Scenario, trajectory: Trajectory, seed: int, contacts: ContactSet) -> Log:
    """One run of ``trajectory`` on the scenario's true robot, plant, controller and sensors."""
    setup = scenario.build(seed, collisions=False)
    setup.update(trajectory=trajectory, duration=trajectory.duration + 0.3, contacts=contacts)
    return simulate(**setup).log


def detection(scenario: Scenario, nominal: RobotModel, trajectory: Trajectory) -> dict[str, float]:
    """Tune ``model`` on two free runs of ``trajectory``, judge a run with the impacts."""
    free = [run(scenario, trajectory, seed, ContactSet([])) for seed in (1, 2)]
    threshold, settings = tune(free, nominal, "model", folds=None)
    hit = run(scenario, trajectory, 3, impacts(nominal, trajectory.duration))
    events = CollisionMonitor(nominal, threshold, settings).process(hit).events
    result = evaluate(events, hit, method="model")
    table = result.per_collision
    detected = table[table["detected"]]
    return {
        "B_fr": float(np.mean(threshold.b_fr_)),  # type: ignore[attr-defined]
        "detected": f"{len(detected)}/{len(table)}",
        "false_alarms": result.n_false_alarms,
        "delay": 1e3 * float(detected["start_delay"].median()) if len(detected) else np.nan,
        "smallest": float(detected["peak_force"].min()) if len(detected) else np.nan,
    }


def metric_and_bound(robot: RobotModel, trajectory: Trajectory, seed: int) -> tuple[float, float]:
    """EM [N m s] and the mean model part of B_c(t) [N m] with B_Q̃ by Table 3.1 (8 draws)."""
    t, q, qd, qdd = trajectory.sample(DT)
    estimator = Butterworth(DT, cutoff=20.0, order=5)
    seeds = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(seed).spawn(8)]
    bq = np.max(
        [
            q_error_bounds(q, DT, estimator, noise_std=1e-5, seed=s, reference=(qd, qdd))
            for s in seeds
        ],
        axis=0,
    )
    base = base_parameters(robot)
    theta = base.values_of(robot)
    terms = error_bound_terms(
        robot, base.independent, theta, q, qd, qdd, bq, parameter_bounds(0.02, theta)
    )
    metric = estimation_metric(robot, q, qd, qdd, t, bq, 0.02, base=base)
    return metric, float(np.mean(terms.q_error + terms.cross + terms.parameter_error))


def evidence(name: str, duration: float, eval_seed: int) -> pd.DataFrame:
    scenario = load_scenario(name)
    nominal = scenario.nominal("acceleration")
    start, end = TASKS[name]
    clock = time.perf_counter()
    plan = optimize_trajectory(nominal, start, end, duration, dt=DT)
    seconds = time.perf_counter() - clock
    # The same planner with B_Q̃ held at the quintic's (blind to the filter's lag).
    blind = optimize_trajectory(nominal, start, end, duration, dt=DT, bq=plan.initial_bq)
    candidates = {
        "quintic": plan.initial,
        "planned": plan.trajectory,
        "fixed-B_Q": blind.trajectory,
    }
    candidates.update(alternatives(start, end, duration))
    own = {"quintic": plan.initial_metric, "planned": plan.metric, "fixed-B_Q": blind.metric}
    rows = []
    for label, trajectory in candidates.items():
        metric, bound = metric_and_bound(nominal, trajectory, eval_seed)
        rows.append(
            {
                "robot": nominal.name.split(" ")[0],
                "trajectory": label,
                "EM plan": own.get(label, np.nan),
                "EM": metric,
                "mean B_c": bound,
                **detection(scenario, nominal, trajectory),
            }
        )
    print(
        f"{name}: planned in {seconds:.1f} s ({plan.n_iterations} SLSQP iterations, "
        f"success {plan.success})",
        flush=True,
    )
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3.0, help="task duration [s]")
    parser.add_argument("--robots", nargs="*", default=list(TASKS), choices=list(TASKS))
    parser.add_argument("--eval-seed", type=int, default=1000, help="seed of EM's noise draws")
    args = parser.parse_args()
    clock = time.perf_counter()
    table = pd.concat(
        [evidence(name, args.duration, args.eval_seed) for name in args.robots], ignore_index=True
    )
    print(
        "EM [N m s]; mean B_c: model part of eq. 3.36 [N m]; B_fr: learned rest of the bound, "
        "mean over joints [N m]; delay: median [ms]; smallest: detected peak force [N]"
    )
    with pd.option_context("display.width", 160, "display.float_format", "{:.4g}".format):
        print(table.to_string(index=False))
    print(f"total {time.perf_counter() - clock:.0f} s")


if __name__ == "__main__":
    main()
