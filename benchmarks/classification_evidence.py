"""Intended contact vs collision on simulated runs: confusion tables, accuracy (issue 12, item 3).

The shipped scenario ``panda-gaz`` (true arm ``panda_gaz`` with the sigmoid
friction of Gaz et al., computed-torque control on the URDF model, random
point-to-point motion) is simulated ``--runs`` times for ``--duration`` s at
``--rate`` Hz, each run with ``--events`` contacts drawn by
:func:`sensorless.simulation.interactions.simulate_interactions`: guiding
hands (intended), clamps and impacts (collisions), uniformly mixed, seeded
from ``--seed``. The same logs are judged twice:

* *model error*: the observer and the threshold on the user's nominal model
  (the URDF, no friction);
* *exact model*: on ``Scenario.with_exact_model().nominal()``, the oracle.

Per model, a time-variant threshold is tuned on two collision-free runs (the
same seeds for both), the :class:`~sensorless.monitor.CollisionMonitor`
detects the events and :func:`sensorless.classification.classify_events`
classes them: with the stated cut-offs, at the end of each event and
``window`` seconds into it (the stream's provisional class); and with cut-offs
fitted by :meth:`InteractionClassifier.fit` in two folds (fit on half the
runs, classify the other half, and back). Printed: the confusion tables (true
class × assigned class, events that detect a contact), the accuracy with a
Wilson 95 % interval, the classes per profile, the false alarms (events that
detect no contact; not classified against any truth), and the CPU time per
sample of the stream classifier beside the detector's stream step (median of
``--repeat`` passes, one thread; CPU time, ``time.process_time``, because
wall time on a shared machine measures the neighbours).

    .venv/bin/python benchmarks/classification_evidence.py [--runs 6] [--duration 40]
        [--events 8] [--rate 1000] [--seed 12] [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
import pandas as pd

from sensorless.classification import InteractionClassifier, classify_events
from sensorless.detection import Detector
from sensorless.evaluation.classification import (
    ClassificationEvaluation,
    classification_table,
    evaluate_classification,
)
from sensorless.io import Log
from sensorless.monitor import CollisionMonitor, tune
from sensorless.robots.model import RobotModel
from sensorless.signals import Event, ObserverSignals
from sensorless.simulation.interactions import simulate_interactions
from sensorless.simulation.scenario import Scenario, load_scenario

FAMILY = "time-variant"


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    if n == 0:
        return math.nan, math.nan
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def seeds(master: int, count: int) -> list[int]:
    return [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(master).spawn(count)]


def simulate(scenario: Scenario, args: argparse.Namespace) -> tuple[list[Log], list[Log]]:
    all_seeds = seeds(args.seed, args.runs + 2)
    start = time.perf_counter()
    free = [scenario.run(seed=s, collisions=False).log for s in all_seeds[:2]]
    runs = [simulate_interactions(scenario, args.events, seed=s).log for s in all_seeds[2:]]
    wall = time.perf_counter() - start
    total = (args.runs + 2) * args.duration
    print(
        f"simulated {args.runs} runs + 2 tuning runs ({total:.0f} s at {args.rate:g} Hz) "
        f"in {wall:.0f} s"
    )
    return free, runs


def detect(
    nominal: RobotModel, free: list[Log], runs: list[Log]
) -> tuple[list[tuple[Log, ObserverSignals, list[Event]]], CollisionMonitor]:
    threshold, settings = tune(free, nominal, FAMILY, folds=None)
    monitor = CollisionMonitor(nominal, threshold, settings)
    found = []
    for log in runs:
        run = monitor.process(log)
        found.append((log, run.signals, run.events))
    return found, monitor


def evaluations(
    judged: list[tuple[Log, ObserverSignals, list[Event]]],
    classifier: InteractionClassifier,
    *,
    provisional: bool = False,
) -> list[ClassificationEvaluation]:
    out = []
    for log, signals, events in judged:
        classes = classify_events(events, signals, classifier, provisional=provisional)
        out.append(evaluate_classification(classes, log))
    return out


def fitted_in_folds(
    judged: list[tuple[Log, ObserverSignals, list[Event]]],
) -> tuple[list[ClassificationEvaluation], list[str]]:
    half = len(judged) // 2
    folds = [(judged[:half], judged[half:]), (judged[half:], judged[:half])]
    out, notes = [], []
    for train, test in folds:
        stated = InteractionClassifier()
        features, labels = [], []
        for evaluation, (_, signals, events) in zip(evaluations(train, stated), train, strict=True):
            feats = stated.features(events, signals)
            for row, feature in zip(evaluation.records.itertuples(), feats, strict=True):
                if row.window > 0:
                    features.append(feature)
                    labels.append(row.true)
        if len(set(labels)) < 2:
            notes.append("a fold without both classes: not fitted")
            continue
        fitted = InteractionClassifier().fit(features, labels)
        cut = fitted.cutoffs_
        notes.append(
            f"fitted on {len(labels)} events: rise rate <= {cut.rise_rate:.4g} N m/s, "
            f"duration >= {cut.duration:.3g} s, HF fraction <= {cut.hf_fraction:.3g}, "
            f"mean power >= {cut.mean_power:.3g} W (converged: {fitted.converged_})"
        )
        out += evaluations(test, fitted)
    return out, notes


def report(name: str, pooled: ClassificationEvaluation) -> None:
    matched = pooled.matched
    n, right = len(matched), int(matched["correct"].sum())
    low, high = wilson(right, n)
    print(
        f"\n--- {name}: {n} classified events of {pooled.n_windows} contacts, "
        f"{pooled.n_false_alarms} false alarms"
    )
    print(pooled.confusion.to_string())
    print(f"accuracy {pooled.accuracy:.3f} (95 % Wilson {low:.3f}-{high:.3f})")
    by_profile = pd.crosstab(matched["profile"], matched["assigned"])
    print("classes per profile:\n" + by_profile.to_string())


def step_timing(
    monitor: CollisionMonitor, signals: ObserverSignals, repeat: int
) -> tuple[float, float, float]:
    """Median CPU µs per sample: detector step, classifier step in events and outside."""
    detector = Detector(monitor.threshold, min_duration=0.005, hold=0.05)
    classifier = InteractionClassifier()
    n = signals.n_samples
    rows = [
        (
            signals.residual[k],
            signals.model_torque[k],
            signals.friction[k],
            signals.sign[k],
            signals.velocity[k],
            float(signals.t[k]),
        )
        for k in range(n)
    ]
    detector_times, inside_times, outside_times = [], [], []
    for _ in range(repeat):
        state = detector.initial_state(signals.dt)
        verdicts, states = [], []
        start = time.process_time()
        for row in rows:
            verdict, state = detector.step(state, *row)
            verdicts.append(verdict)
            states.append(state)
        detector_times.append((time.process_time() - start) / n)
        mine = classifier.initial_state(signals.dt)
        inside = outside = 0.0
        n_inside = 0
        for k in range(n):
            start = time.process_time()
            _, mine = classifier.step(mine, verdicts[k], states[k], rows[k][4])
            spent = time.process_time() - start
            if mine.sums is not None:
                inside += spent
                n_inside += 1
            else:
                outside += spent
        inside_times.append(inside / max(n_inside, 1))
        outside_times.append(outside / max(n - n_inside, 1))
    detector_us, inside_us, outside_us = (
        1e6 * statistics.median(x) for x in (detector_times, inside_times, outside_times)
    )
    return detector_us, inside_us, outside_us


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--duration", type=float, default=40.0)
    parser.add_argument("--events", type=int, default=8)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--seed", type=int, default=12)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    scenario = load_scenario("panda-gaz").with_duration(args.duration).with_sample_rate(args.rate)
    free, runs = simulate(scenario, args)
    models = {
        "model error": scenario.nominal(),
        "exact model": scenario.with_exact_model().nominal(),
    }
    table: dict[str, ClassificationEvaluation] = {}
    monitors = {}
    for name, nominal in models.items():
        judged, monitors[name] = detect(nominal, free, runs)
        stated = ClassificationEvaluation.pooled(evaluations(judged, InteractionClassifier()))
        report(f"{name}, stated cut-offs", stated)
        early = ClassificationEvaluation.pooled(
            evaluations(judged, InteractionClassifier(), provisional=True)
        )
        report(f"{name}, stated cut-offs, provisional class at 0.3 s", early)
        folded, notes = fitted_in_folds(judged)
        for note in notes:
            print(f"{name}: {note}")
        table[f"{name}, stated"] = stated
        table[f"{name}, provisional"] = early
        if folded:
            fitted = ClassificationEvaluation.pooled(folded)
            report(f"{name}, cut-offs fitted on the other half of the runs", fitted)
            table[f"{name}, fitted (2 folds)"] = fitted

    print("\n--- summary (classification_table)")
    print(classification_table(table).round(3).to_string())

    signals = monitors["model error"].settings.observe(runs[0], models["model error"])
    detector_us, inside_us, outside_us = step_timing(monitors["model error"], signals, args.repeat)
    print(
        f"\nstream, one sample, CPU time (median of {args.repeat} passes over run 1, "
        f"{signals.n_samples} samples): Detector.step {detector_us:.1f} µs; "
        f"InteractionClassifier.step {inside_us:.1f} µs inside an event, "
        f"{outside_us:.1f} µs outside"
    )


if __name__ == "__main__":
    main()
