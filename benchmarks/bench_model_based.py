"""Cost of the model-based threshold B_c(t) of eq. 3.36 on the 7-joint Panda (issue 14).

Two collision-free ``panda-gaz`` runs of ``--seconds`` each (60 s: 2 × 60 000
samples) are observed with the acceleration-based estimate τ̂_c (eq. 3.16).
Prints, beside the Pinocchio floor (one ``computeJointTorqueRegressor`` call
per sample from Python, what any per-sample use of Pinocchio costs at least):

- the wall time of :meth:`ModelBasedThreshold.fit` on both runs (median of
  ``--repeat``) and its cost per sample;
- the median and p99 of one :meth:`ModelBasedThreshold.step` over
  ``--steps`` samples of a run;
- the cost per sample of the bound terms in their numpy form
  (:func:`sensorless.metric.error_bound_terms` with ``backend="numpy"``, what
  an install without numba runs), over ``--numpy-samples`` samples.

Compile time (numba, when installed) is excluded: a short fit runs first.

    .venv/bin/python benchmarks/bench_model_based.py [--seconds 60] [--repeat 1] [--steps 5000]
        [--numpy-samples 20000]
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np
import pinocchio as pin

from sensorless.metric import error_bound_terms
from sensorless.observers import observe
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import load_scenario
from sensorless.thresholds import ModelBasedThreshold


def pinocchio_floor(model: pin.Model, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> float:
    """Median cost [µs] of one joint-torque regressor call per sample in a Python loop."""
    data = model.createData()
    times = []
    for _ in range(3):
        start = time.perf_counter()
        for k in range(q.shape[0]):
            pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k])
        times.append((time.perf_counter() - start) / q.shape[0])
    return statistics.median(times) * 1e6


def head(run: ObserverSignals, n_samples: int) -> ObserverSignals:
    """The first ``n_samples`` of ``run``."""
    series = ("t", "residual", "model_torque", "friction", "sign", "velocity")
    fields = {name: getattr(run, name)[:n_samples] for name in series}
    assert run.position is not None and run.acceleration is not None
    fields.update(position=run.position[:n_samples], acceleration=run.acceleration[:n_samples])
    return dataclasses.replace(run, **fields)


def step_times(threshold: ModelBasedThreshold, run: ObserverSignals, n_steps: int) -> np.ndarray:
    """Wall time [µs] of each of ``n_steps`` calls of ``step`` along ``run``."""
    assert run.position is not None and run.acceleration is not None
    first = (run.model_torque[0], run.friction[0], run.sign[0], run.velocity[0])
    state = threshold.initial_state(
        *first, position=run.position[0], acceleration=run.acceleration[0]
    )
    times = np.empty(n_steps)
    for k in range(n_steps):
        inputs = (run.model_torque[k], run.friction[k], run.sign[k], run.velocity[k])
        position, acceleration = run.position[k], run.acceleration[k]
        start = time.perf_counter()
        _, _, state = threshold.step(state, *inputs, position=position, acceleration=acceleration)
        times[k] = time.perf_counter() - start
    return times * 1e6


def numpy_cost(threshold: ModelBasedThreshold, run: ObserverSignals, n_samples: int) -> float:
    """Cost [µs] per sample of the numpy form of the bound terms over ``n_samples`` of ``run``."""
    assert run.position is not None and run.acceleration is not None
    rows = slice(0, min(n_samples, run.n_samples))
    states = run.position[rows], run.velocity[rows], run.acceleration[rows]
    weights = threshold.independent_, threshold.theta_
    start = time.perf_counter()
    error_bound_terms(
        threshold.robot_model(), *weights, *states, threshold.bq_, threshold.btheta_,
        backend="numpy",
    )  # fmt: skip
    return (time.perf_counter() - start) / states[0].shape[0] * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--numpy-samples", type=int, default=20000)
    args = parser.parse_args()

    scenario = load_scenario("panda-gaz").with_duration(args.seconds)
    nominal = scenario.robots()[1]
    logs = [scenario.run(seed=seed, collisions=False).log for seed in (1, 2)]
    runs = [observe(log, nominal, kind="acceleration") for log in logs]
    n_samples = sum(run.n_samples for run in runs)
    run = runs[0]
    assert run.position is not None and run.acceleration is not None

    floor = pinocchio_floor(
        nominal.pinocchio_model, run.position[:2000], run.velocity[:2000], run.acceleration[:2000]
    )
    ModelBasedThreshold(nominal).fit(head(run, 100))  # compile, fill caches
    fits = []
    for _ in range(args.repeat):
        start = time.perf_counter()
        threshold = ModelBasedThreshold(nominal).fit(runs)
        fits.append(time.perf_counter() - start)
    fit = statistics.median(fits)
    micro = step_times(threshold, run, min(args.steps, run.n_samples))
    numpy_us = numpy_cost(threshold, run, args.numpy_samples)

    print(f"panda-gaz, 2 collision-free runs of {args.seconds:g} s ({n_samples} samples)")
    print(f"Pinocchio floor (one regressor call per sample): {floor:.1f} us")
    print(f"model-based fit: {fit:.2f} s ({fit / n_samples * 1e6:.1f} us per sample)")
    median, p99 = np.median(micro), np.percentile(micro, 99)
    print(f"model-based step: median {median:.1f} us, p99 {p99:.1f} us")
    print(f"bound terms, numpy form (no numba): {numpy_us:.1f} us per sample")


if __name__ == "__main__":
    main()
