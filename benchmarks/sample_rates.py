"""Detection results of the shipped scenarios at several sample rates (issue 11, item 3).

Not a speed benchmark (hence not ``bench_*.py``, which ``make bench`` runs):
for each scenario and rate, :meth:`Scenario.with_sample_rate` sets the
controller, sensor and log period, :func:`sensorless.comparison.compare`
tunes every threshold family on collision-free runs at that rate and
evaluates it on a collision run at that rate (the demo's settings: monitored
joints and residuals of ``DEMO_SCENARIOS``, margin 10 % of the constant β,
min_duration 5 ms, hold 50 ms). It prints one row per scenario, rate and
family: detected collisions, detection rate, median and largest start delay
[ms] over the detected collisions, and false alarms on the collision run.

    .venv/bin/python benchmarks/sample_rates.py                      # all, ~10 min
    .venv/bin/python benchmarks/sample_rates.py --scenario panda-gaz --duration 20
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from sensorless.cli.demo import DEMO_SCENARIOS
from sensorless.comparison import compare
from sensorless.simulation.scenario import available_scenarios, load_scenario

#: Simulated time [s] per run by default: the LWR's flexible joints need ~1 s of CPU per
#: simulated second at every rate, so its runs are cut to the first four contacts.
DURATIONS = {"puma560-thesis": 60.0, "panda-gaz": 60.0, "lwr4-thesis": 30.0}
#: Scenarios left out by default: a 31-minute run whose contacts start after 300 s.
SKIPPED = {"puma560-warmup"}
FAMILIES = ("constant", "time-variant", "hysteretic", "velocity")


def measure(
    name: str,
    rates: list[float],
    duration: float | None,
    n_tuning: int,
    seed: int,
    methods: tuple[str, ...],
) -> pd.DataFrame:
    """Rows (scenario, rate, family) of the detection results of one scenario."""
    joints, residuals, _ = DEMO_SCENARIOS.get(name, (None, ("motor",), None))
    scenario = load_scenario(name)
    seconds = duration or DURATIONS.get(name, scenario.duration)
    scenario = scenario.with_duration(seconds)
    rows = []
    for rate in rates:
        start = time.perf_counter()
        result = compare(
            scenario.with_sample_rate(rate),
            methods=methods,
            joints=joints,
            residuals=residuals,
            n_tuning=n_tuning,
            master_seed=seed,
        )
        wall = time.perf_counter() - start
        for label, evaluation in result.evaluations.items():
            delays = evaluation.per_collision["start_delay"].to_numpy(dtype=float)
            found = delays[np.isfinite(delays)]
            rows.append(
                {
                    "scenario": name,
                    "rate [Hz]": rate,
                    "family": label,
                    "detected": f"{evaluation.n_detected}/{evaluation.n_collisions}",
                    "detection rate": evaluation.n_detected / max(evaluation.n_collisions, 1),
                    "median delay [ms]": 1e3 * float(np.median(found)) if found.size else np.nan,
                    "max delay [ms]": 1e3 * float(found.max()) if found.size else np.nan,
                    "false alarms": evaluation.n_false_alarms,
                    "run [s]": seconds,
                    "wall [s]": round(wall, 1),
                }
            )
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", action="append", help="scenario name (repeatable)")
    parser.add_argument(
        "--rates", default="1000,250,100", help="sample rates [Hz], comma-separated"
    )
    parser.add_argument("--duration", type=float, help="simulated time per run [s]")
    parser.add_argument("--tuning", type=int, default=2, help="collision-free tuning runs")
    parser.add_argument("--seed", type=int, default=0, help="master seed of compare()")
    parser.add_argument("--methods", default=",".join(FAMILIES), help="threshold families")
    args = parser.parse_args()
    names = args.scenario or [s for s in available_scenarios() if s not in SKIPPED]
    rates = [float(r) for r in args.rates.split(",")]
    methods = tuple(args.methods.split(","))
    tables = [measure(n, rates, args.duration, args.tuning, args.seed, methods) for n in names]
    table = pd.concat(tables, ignore_index=True)
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(table.to_string(index=False, float_format=lambda x: f"{x:.3g}"))


if __name__ == "__main__":
    main()
