"""Learned vs time-variant vs oracle on held-out ``panda-gaz`` runs (issue 20, deliverable 4).

Runs of the ``panda-gaz`` scenario whose seeds the shipped Panda weights never
saw (checked: the training runs' seeds are recomputed from the weights'
recipe): ``N_FIT`` collision-free runs to fit on, and, to test on,
``N_COLLISION`` runs with contacts and ``N_FREE`` more collision-free runs,
``SECONDS`` s each. Three detectors, each the way a user builds it:

- ``learned``: :class:`~sensorless.thresholds.LearnedThreshold` with the
  shipped ``panda`` weights, level fitted on the fit runs;
- ``time-variant``: :func:`~sensorless.monitor.tune` on the same runs;
- ``oracle``: the time-variant threshold on the same logs observed with the
  exact model (:meth:`Scenario.with_exact_model`).

All use the default observer (motor torques, K_I = 20 1/s), the settling
time of :class:`~sensorless.monitor.ObserverSettings` as transient, and the
margin :func:`tune` gives by default (10 % of the constant band β_j of the
fit runs, in N m, the same for both model-error detectors). Events come from
:class:`~sensorless.monitor.CollisionMonitor` (its default min_duration and
hold), and are scored by :func:`sensorless.evaluation.evaluate`. Printed:
contacts detected / total, false alarms per hour over all test runs with a
Poisson 95 % interval (chi-square), and the median start delay.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/learned_evidence.py`` (~5 min).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from scipy.stats import chi2

from sensorless.evaluation import evaluate
from sensorless.io import Log
from sensorless.learning import TrainingRecipe
from sensorless.learning.training import _randomised
from sensorless.monitor import CollisionMonitor, ObserverSettings, tune
from sensorless.monitor.tuning import DEFAULT_MARGIN_FRACTION
from sensorless.robots.model import RobotModel
from sensorless.simulation.scenario import load_scenario
from sensorless.thresholds import ConstantThreshold, LearnedThreshold, Threshold, load_weights

SCENARIO, SECONDS = "panda-gaz", 30.0
N_FIT, N_COLLISION, N_FREE = 2, 6, 4
FIRST_SEED = 9001


def training_seeds(weights: str) -> set[int]:
    """The scenario seeds of the weights' training runs (recomputed, nothing simulated)."""
    recipe_info = load_weights(weights).recipe
    fields = TrainingRecipe.__dataclass_fields__
    recipe = TrainingRecipe(**{k: v for k, v in recipe_info.items() if k in fields})
    scenario = load_scenario(recipe.scenario)
    n_runs = max(1, int(np.ceil(recipe.minutes * 60.0 / recipe.run_seconds)))
    seeds = set()
    for child in np.random.SeedSequence(recipe.seed).spawn(n_runs):
        rng = np.random.default_rng(child)
        _randomised(scenario, recipe, rng)  # the same draws as training_runs, in order
        seeds.add(int(rng.integers(2**31)))
    return seeds


def poisson_interval(count: int, hours: float) -> tuple[float, float]:
    """Exact (Garwood) 95 % interval of a Poisson rate [1/h]."""
    low = 0.0 if count == 0 else chi2.ppf(0.025, 2 * count) / 2.0
    high = chi2.ppf(0.975, 2 * count + 2) / 2.0
    return low / hours, high / hours


def score(
    name: str,
    robot: RobotModel,
    threshold: Threshold,
    settings: ObserverSettings,
    tests: list[Log],
) -> dict[str, Any]:
    """Pooled detection, false alarms and delays of one detector on the test logs."""
    monitor = CollisionMonitor(robot, threshold, settings)
    detected = total = alarms = 0
    seconds, delays = 0.0, []
    for log in tests:
        _, events = monitor.run(log)
        result = evaluate(events, log, method=name)
        detected += result.n_detected
        total += len(result.windows)
        alarms += len(result.false_alarms)
        seconds += result.duration
        rows = result.per_collision
        delays.extend(rows.loc[rows["detected"], "start_delay"].tolist())
    hours = seconds / 3600.0
    low, high = poisson_interval(alarms, hours)
    return {
        "detector": name,
        "detected": f"{detected}/{total}",
        "false alarms": alarms,
        "per hour": alarms / hours,
        "95 % interval": f"[{low:.0f}, {high:.0f}]",
        "median delay [ms]": 1e3 * float(np.median(delays)) if delays else float("nan"),
        "hours": hours,
    }


def main() -> None:
    started = time.perf_counter()
    scenario = load_scenario(SCENARIO).with_duration(SECONDS)
    n_runs = N_FIT + N_COLLISION + N_FREE
    seeds = list(range(FIRST_SEED, FIRST_SEED + n_runs))
    overlap = set(seeds) & training_seeds("panda")
    if overlap:
        raise SystemExit(f"seeds {sorted(overlap)} were used in training: pick others")
    fit_logs = [scenario.run(seed=s, collisions=False).log for s in seeds[:N_FIT]]
    collision_logs = [scenario.run(seed=s).log for s in seeds[N_FIT : N_FIT + N_COLLISION]]
    free_logs = [scenario.run(seed=s, collisions=False).log for s in seeds[N_FIT + N_COLLISION :]]
    tests = collision_logs + free_logs
    simulated = time.perf_counter() - started

    nominal = scenario.nominal("motor")
    exact = scenario.with_exact_model().nominal("motor")
    settings = ObserverSettings(kind="motor")
    fit_signals = [settings.observe(log, nominal) for log in fit_logs]
    transient = settings.settle_time(fit_signals[0].dt)
    band = ConstantThreshold(transient=transient).fit(fit_signals)
    margin = DEFAULT_MARGIN_FRACTION * band.beta_  # what tune gives by default
    learned = LearnedThreshold(margin=margin, transient=transient).fit(fit_signals)
    time_variant, _ = tune(fit_logs, nominal, "time-variant", settings, folds=None)
    oracle, _ = tune(fit_logs, exact, "time-variant", settings, folds=None)
    np.testing.assert_allclose(time_variant.margin, margin)  # the same margin rule

    rows = [
        score("learned", nominal, learned, settings, tests),
        score("time-variant", nominal, time_variant, settings, tests),
        score("oracle (time-variant, exact model)", exact, oracle, settings, tests),
    ]
    print(
        f"{SCENARIO}, held-out seeds {seeds[0]}..{seeds[-1]} (none used in training): "
        f"fit on {N_FIT} collision-free runs, tested on {N_COLLISION} collision runs + "
        f"{N_FREE} collision-free runs of {SECONDS:g} s ({rows[0]['hours'] * 3600:.0f} s)"
    )
    print(f"margin (10 % of β) [N m]: {np.round(margin, 3).tolist()}")
    print(f"learned level λ [-]: {np.round(learned.level_, 2).tolist()}")
    header = (
        f"{'detector':36s} {'detected':>9s} {'false alarms':>12s} {'per hour':>9s} "
        f"{'95 % interval':>14s} {'median delay [ms]':>18s}"
    )
    print(header)
    for row in rows:
        print(
            f"{row['detector']:36s} {row['detected']:>9s} {row['false alarms']:>12d} "
            f"{row['per hour']:>9.0f} {row['95 % interval']:>14s} "
            f"{row['median delay [ms]']:>18.1f}"
        )
    total = time.perf_counter() - started
    print(f"simulation {simulated:.0f} s, total {total:.0f} s")


if __name__ == "__main__":
    main()
