"""Isolation on a shipped scenario (issue 12): its cost beside detection, and its accuracy.

For each scenario (its model error, and the same runs observed with the exact
model, ``Scenario.with_exact_model().nominal()``): a time-variant threshold
is tuned on one collision-free run, a ``CollisionMonitor`` detects the
contacts of a test run, and an ``Isolator`` (capsules around the links)
estimates link, point and force at each event's peak; ``evaluate_isolation``
compares them with the simulator's ground truth.

Cost, median of ``--repeat`` runs: ``Isolator.isolate_events`` per event [µs];
``Isolator.step`` per stream sample [µs], on the samples of the events (where
a joint is outside its band) and on the others (which return at once);
one ``CollisionMonitor.step`` for comparison [µs]; and what ``sensorless
benchmark`` spends per event of a collision run
(:func:`sensorless.benchmark.contacts.score_events`: the isolation at the
event's peak, the ground truth's force over every contact sample, the class)
[ms].

    .venv/bin/python benchmarks/bench_isolation.py [--scenario panda-gaz ...]
        [--seconds S] [--repeat 3] [--search all|pruned]
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

from sensorless.benchmark.contacts import DetectorRun, score_events
from sensorless.evaluation import evaluate_isolation
from sensorless.isolation import Isolator
from sensorless.monitor import CollisionMonitor, tune
from sensorless.simulation.scenario import Scenario, load_scenario


def _pipeline(scenario: Scenario, nominal: Any, free: Any, test: Any) -> dict[str, Any]:
    threshold, settings = tune([free], nominal, "time-variant", folds=None)
    monitor = CollisionMonitor(nominal, threshold, settings)
    run = monitor.process(test)
    bounds = monitor.detector.run(run.signals, skip_nonfinite=True)
    return {
        "monitor": monitor,
        "events": run.events,
        "signals": run.signals,
        "bounds": bounds,
        "gain": settings.gain,
    }


def _accuracy(
    name: str, label: str, scenario: Scenario, nominal: Any, free: Any, test: Any, search: str
) -> tuple[dict[str, Any], Isolator, list[Any]]:
    found = _pipeline(scenario, nominal, free, test)
    signals, bounds = found["signals"], found["bounds"]
    isolator = Isolator(nominal, search=search)
    args = (signals.t, signals.position, signals.residual, bounds)
    estimates = isolator.isolate_events(found["events"], *args, skip_nonfinite=True)
    true_robot = scenario.robots()[0]
    evaluation = evaluate_isolation(estimates, test, true_robot, gain=found["gain"])
    s = evaluation.summary()
    print(
        f"{name:16s} {label:6s} events {s['n_events']:3d}, matched {s['n_matched']:3d}: "
        f"link {s['link_rate']:.2f}, |F| error median {s['median_abs_magnitude_error']:.2f} "
        f"(vs filtered {s['median_abs_magnitude_error_filtered']:.2f}), direction "
        f"{s['median_direction_error']:.2f} rad, line {s['median_line_distance'] * 1e3:.0f} mm, "
        f"point {s['median_point_error'] * 1e3:.0f} mm (right link), within the bound "
        f"{s['bound_coverage']:.2f}"
    )
    return found, isolator, estimates


def _costs(found: dict[str, Any], isolator: Isolator, test: Any, repeat: int) -> None:
    signals, bounds = found["signals"], found["bounds"]
    events = found["events"]
    if not events:
        print("no events: no cost figures")
        return
    args = (signals.t, signals.position, signals.residual, bounds)
    per_event = []
    for _ in range(repeat):
        start = time.perf_counter()
        isolator.isolate_events(events, *args, skip_nonfinite=True)
        per_event.append((time.perf_counter() - start) / len(events))
    lower, upper = bounds.lower, bounds.upper
    ok = np.isfinite(lower).all(axis=1) & np.isfinite(signals.residual).all(axis=1)
    outside = ok & ((signals.residual > upper) | (signals.residual < lower)).any(axis=1)
    inside = np.flatnonzero(ok & ~outside)[:2000]
    busy = np.flatnonzero(outside)[:: max(1, int(outside.sum()) // 300)]
    q, r = signals.position, signals.residual
    step = {}
    for label, rows in (("outside", busy), ("inside", inside)):
        times = []
        for _ in range(repeat):
            for k in rows:
                start = time.perf_counter()
                isolator.step(q[k], r[k], lower[k], upper[k])
                times.append(time.perf_counter() - start)
        step[label] = (1e6 * float(np.median(times)), rows.size)
    monitor_times = []
    for _ in range(repeat):
        monitor = CollisionMonitor(
            found["monitor"].robot, found["monitor"].threshold, found["monitor"].settings
        )
        for k in range(min(test.n_samples, 5000)):
            start = time.perf_counter()
            monitor.step(test.t[k], test.q[k], test.tau_m[k])
            monitor_times.append(time.perf_counter() - start)
    print(
        f"  isolate_events: {1e6 * statistics.median(per_event):,.0f} us per event "
        f"({len(events)} events, median of {repeat})"
    )
    print(
        f"  Isolator.step: {step['outside'][0]:,.0f} us per sample outside a band "
        f"({step['outside'][1]} samples), {step['inside'][0]:.1f} us inside (median)"
    )
    print(f"  CollisionMonitor.step: {1e6 * float(np.median(monitor_times)):.1f} us (median)")


def _benchmark_cost(
    found: dict[str, Any], isolator: Isolator, scenario: Scenario, test: Any, repeat: int
) -> None:
    """Wall time of the benchmark's per-run scoring (score_events), per event."""
    events = found["events"]
    if not events:
        return
    run = DetectorRun(events, found["signals"], found["bounds"], isolator)
    true_robot = scenario.robots()[0]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        score_events([run], test, true_robot, max_delay=0.5)
        times.append((time.perf_counter() - start) / len(events))
    print(
        f"  benchmark score_events: {1e3 * statistics.median(times):,.1f} ms per event "
        f"(isolation, true force over {int((test.collision_id > 0).sum())} contact samples, "
        f"class; {len(events)} events, median of {repeat})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", nargs="+", default=["panda-gaz"])
    parser.add_argument("--seconds", type=float, default=None, help="default: the scenario's")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--search", default="all", choices=["all", "pruned"])
    args = parser.parse_args()
    for name in args.scenario:
        scenario = load_scenario(name)
        if args.seconds is not None:
            scenario = scenario.with_duration(args.seconds)
        free = scenario.run(seed=scenario.seed + 100, collisions=False).log
        test = scenario.run().log
        nominal = scenario.nominal("motor")
        exact = scenario.with_exact_model().nominal("motor")
        found, isolator, _ = _accuracy(name, "model", scenario, nominal, free, test, args.search)
        _accuracy(name, "exact", scenario, exact, free, test, args.search)
        _costs(found, isolator, test, args.repeat)
        _benchmark_cost(found, isolator, scenario, test, args.repeat)


if __name__ == "__main__":
    main()
