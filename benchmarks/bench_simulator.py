"""Simulated seconds per wall-clock second of the thesis scenarios (issue 14).

Cases, each with its contacts: the rigid PUMA 560 with LuGre friction
(``puma560-thesis``) and the 7-joint flexible LWR with its torque loop
(``lwr4-thesis``), the latter with the implicit spring step and with the RK4
reference integrator side by side. Runs alternate between the cases so
that a change in the machine's load hits them alike; median of ``--repeat``.

    .venv/bin/python benchmarks/bench_simulator.py [--puma 10] [--lwr 5] [--repeat 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.simulator import simulate


def _case(name: str, seconds: float, **plant: Any) -> Callable[[], int]:
    kwargs = load_scenario(name).with_duration(seconds).build()
    if plant:
        kwargs["plant"] = dataclasses.replace(kwargs["plant"], **plant)
    return lambda: simulate(**kwargs).substeps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--puma", type=float, default=10.0, help="simulated PUMA time [s]")
    parser.add_argument("--lwr", type=float, default=5.0, help="simulated LWR time [s]")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    cases = {
        "PUMA 560 rigid + LuGre, contacts": (args.puma, _case("puma560-thesis", args.puma)),
        "LWR flexible, implicit springs": (args.lwr, _case("lwr4-thesis", args.lwr)),
        "LWR flexible, RK4 reference": (
            args.lwr,
            _case("lwr4-thesis", args.lwr, integrator="rk4"),
        ),
    }
    times: dict[str, list[float]] = {label: [] for label in cases}
    substeps: dict[str, int] = {}
    for _ in range(args.repeat):
        for label, (_, run) in cases.items():
            start = time.perf_counter()
            substeps[label] = run()
            times[label].append(time.perf_counter() - start)
    print(f"median of {args.repeat} runs at 1 kHz; load average {os.getloadavg()[0]:.2f}")
    for label, (seconds, _) in cases.items():
        wall = statistics.median(times[label])
        print(
            f"{label:34s} {seconds / wall:6.2f} x real time "
            f"({wall:6.2f} s for {seconds:g} s, {substeps[label]} substeps)"
        )


if __name__ == "__main__":
    main()
