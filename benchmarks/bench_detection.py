"""Cost of the detection pipeline on the 7-joint Panda (issue 4).

Streaming: one ``CollisionMonitor.step`` (finite-difference velocity,
momentum observer, time-variant threshold, detector), median and p99 over
all samples of a run. Batch: samples per second of ``CollisionMonitor.run``
on the whole log (observer + bounds + events), median of several runs.

    .venv/bin/python benchmarks/bench_detection.py [--seconds 20] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from sensorless.monitor import CollisionMonitor, tune
from sensorless.simulation.scenario import load_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    scenario = load_scenario("panda-gaz").with_duration(args.seconds)
    free = scenario.run(seed=1, collisions=False).log
    test = scenario.run(seed=2).log
    nominal = scenario.robots()[1]
    threshold, settings = tune([free], nominal, "time-variant", margin=0.05, folds=None)

    step_times = []
    for _ in range(args.repeat):
        monitor = CollisionMonitor(nominal, threshold, settings)
        for k in range(test.n_samples):
            start = time.perf_counter()
            monitor.step(test.t[k], test.q[k], test.tau_m[k])
            step_times.append(time.perf_counter() - start)
    micro = np.asarray(step_times) * 1e6

    batch = []
    for _ in range(args.repeat):
        monitor = CollisionMonitor(nominal, threshold, settings)
        start = time.perf_counter()
        monitor.run(test)
        batch.append(test.n_samples / (time.perf_counter() - start))

    print(f"panda-gaz, {test.n_samples} samples, momentum observer + time-variant threshold")
    print(
        f"streaming step: median {np.median(micro):.1f} us, p99 {np.percentile(micro, 99):.1f} us"
    )
    print(f"batch pipeline: {statistics.median(batch):,.0f} samples/s (median of {args.repeat})")


if __name__ == "__main__":
    main()
