"""Evidence for two reaction levels (issue 12, item 2) on a shipped scenario.

Tunes a contact and a collision level on collision-free runs of a scenario
(three pairs: constant/constant, time-variant/time-variant, a phased constant
contact band under a constant collision band), then counts, per level, the
events, the true contacts detected and the false alarms on runs with
contacts and on collision-free runs; and times one stream step of the
collision monitor alone and with the contact level (median of ``--repeat``
runs). Every run is seeded.

    python benchmarks/levels_evidence.py [--scenario panda-gaz] [--duration 30]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from sensorless.evaluation import evaluate
from sensorless.monitor import CollisionMonitor, LevelledMonitor, tune, tune_levels
from sensorless.simulation.scenario import load_scenario
from sensorless.thresholds import ConstantThreshold, PhasedThreshold


def _chosen(found, level: str) -> list:
    """The events a level reacts to: every excursion (contact) or the collision band's own."""
    if level == "contact":
        return [e.event for e in found.events]
    return [c for e in found.events for c in e.collisions]


def _per_level(levels: LevelledMonitor, hits: list, quiet: list) -> list[dict]:
    found_hits = [levels.process(log) for log in hits]
    found_quiet = [levels.process(log) for log in quiet]
    hours = sum(log.duration for log in quiet) / 3600.0
    rows = []
    for level in ("contact", "collision"):
        detected = total = alarms = events = 0
        delays: list[float] = []
        for log, found in zip(hits, found_hits, strict=True):
            chosen = _chosen(found, level)
            scored = evaluate(chosen, log, method=level)
            detected += scored.n_detected
            total += scored.n_detected + scored.n_missed
            alarms += len(scored.false_alarms)
            events += len(chosen)
            delays += scored.per_collision["start_delay"].dropna().tolist()
        quiet_events = sum(len(_chosen(found, level)) for found in found_quiet)
        rows.append(
            {
                "level": level,
                "events (contact runs)": events,
                "detected": f"{detected}/{total}",
                "false alarms (contact runs)": alarms,
                "median delay [ms]": 1e3 * float(np.median(delays)) if delays else np.nan,
                "events (collision-free runs)": quiet_events,
                "false alarms [1/h] (collision-free)": quiet_events / hours,
            }
        )
    return rows


def _step_time(monitor, log, repeat: int) -> float:
    """Median over ``repeat`` runs of the mean time of one step [µs]."""
    times = []
    for _ in range(repeat):
        monitor.reset()
        start = time.perf_counter()
        for k in range(log.n_samples):
            monitor.step(log.t[k], log.q[k], log.tau_m[k])
        times.append((time.perf_counter() - start) / log.n_samples * 1e6)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="panda-gaz")
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--tuning", type=int, default=3, help="collision-free tuning runs")
    parser.add_argument("--hits", type=int, default=3, help="runs with contacts")
    parser.add_argument("--quiet", type=int, default=2, help="collision-free test runs")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scenario = load_scenario(args.scenario).with_duration(args.duration)
    nominal = scenario.robots()[1]
    free = [scenario.run(seed=100 + s, collisions=False).log for s in range(args.tuning)]
    hits = [scenario.run(seed=200 + s, collisions=True).log for s in range(args.hits)]
    quiet = [scenario.run(seed=300 + s, collisions=False).log for s in range(args.quiet)]
    settle = 0.25  # 5/K_I at K_I = 20, the transient tune() skips
    pairs = {
        "constant / constant": {"contact": "constant"},
        "time-variant / time-variant": {"contact": "time-variant"},
        "phased constant (2 rad/s²) / constant": {
            "contact": PhasedThreshold(
                ConstantThreshold(), ConstantThreshold(), level=2.0, transient=settle
            ),
            "collision": "constant",
        },
    }
    rows = []
    for name, spec in pairs.items():
        levels = tune_levels(free, nominal, folds=None, **spec)
        for row in _per_level(levels, hits, quiet):
            rows.append({"pair (contact / collision)": name, **row})
        contact = levels.contact
        if isinstance(contact, PhasedThreshold):
            print(
                f"{name}: accelerating fraction of the fit samples "
                f"{contact.accelerating_fraction_:.3f}; band per joint [N m] accelerating "
                f"{np.round(contact.accelerating_.beta_, 2).tolist()}, steady "
                f"{np.round(contact.steady_.beta_, 2).tolist()}"
            )
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(pd.DataFrame(rows).to_string(index=False))
    part = hits[0].slice(0.0, 2.0)
    collision, settings = tune(free, nominal, "constant", folds=None)
    contact_c, _ = tune(free, nominal, "constant", settings, margin_fraction=0.0, folds=None)
    contact_tv, _ = tune(free, nominal, "time-variant", settings, margin_fraction=0.0, folds=None)
    for backend in ("numba", "python"):
        alone = CollisionMonitor(nominal, collision, settings, backend=backend)
        costs = [
            _step_time(monitor, part, args.repeat)
            for monitor in (
                alone,
                LevelledMonitor(
                    CollisionMonitor(nominal, collision, settings, backend=backend), contact_c
                ),
                LevelledMonitor(
                    CollisionMonitor(nominal, collision, settings, backend=backend), contact_tv
                ),
            )
        ]
        print(
            f"stream step [µs], backend {backend}: collision monitor {costs[0]:.1f}; with a "
            f"constant contact level {costs[1]:.1f}; with a time-variant one {costs[2]:.1f}"
        )


if __name__ == "__main__":
    main()
