"""Simulated seconds per wall-clock second of the thesis scenarios (issue 14).

Cases, each with its contacts: the rigid PUMA 560 with LuGre friction
(``puma560-thesis``) and the 7-joint flexible LWR with its torque loop
(``lwr4-thesis``), the latter with the implicit spring step and with the RK4
reference integrator side by side. Each case runs on the compiled path
(numba, when installed) and on the reference path (``backend="numpy"``),
``--backend`` picks one; the column after the figures says which path ran
(``numba``: compiled samples, ``numba-plant``: compiled plant period in the
Python loop, ``numpy``: the reference). Runs alternate between the cases so
that a change in the machine's load hits them alike; median of ``--repeat``.
One untimed short run per case first compiles (or loads the cached) kernels.

    .venv/bin/python benchmarks/bench_simulator.py [--puma 10] [--lwr 5] [--repeat 3]
        [--backend both|auto|numpy]
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


def _case(name: str, seconds: float, backend: str, **plant: Any) -> Callable[[], tuple[int, str]]:
    kwargs = load_scenario(name).with_duration(seconds).build()
    if plant:
        kwargs["plant"] = dataclasses.replace(kwargs["plant"], **plant)

    def run() -> tuple[int, str]:
        result = simulate(**kwargs, backend=backend)
        return result.substeps, result.backend

    simulate(**{**kwargs, "duration": 0.01}, backend=backend)  # compile or load the cache
    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--puma", type=float, default=10.0, help="simulated PUMA time [s]")
    parser.add_argument("--lwr", type=float, default=5.0, help="simulated LWR time [s]")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--backend", choices=("both", "auto", "numpy"), default="both")
    args = parser.parse_args()
    backends = ("auto", "numpy") if args.backend == "both" else (args.backend,)
    cases: dict[str, tuple[float, Callable[[], tuple[int, str]]]] = {}
    for backend in backends:
        cases[f"PUMA 560 rigid + LuGre, contacts [{backend}]"] = (
            args.puma, _case("puma560-thesis", args.puma, backend)
        )  # fmt: skip
        cases[f"LWR flexible, implicit springs [{backend}]"] = (
            args.lwr, _case("lwr4-thesis", args.lwr, backend)
        )  # fmt: skip
    cases["LWR flexible, RK4 reference"] = (
        args.lwr, _case("lwr4-thesis", args.lwr, "auto", integrator="rk4")
    )  # fmt: skip
    times: dict[str, list[float]] = {label: [] for label in cases}
    ran: dict[str, tuple[int, str]] = {}
    for _ in range(args.repeat):
        for label, (_, run) in cases.items():
            start = time.perf_counter()
            ran[label] = run()
            times[label].append(time.perf_counter() - start)
    print(f"median of {args.repeat} runs at 1 kHz; load average {os.getloadavg()[0]:.2f}")
    for label, (seconds, _) in cases.items():
        wall = statistics.median(times[label])
        substeps, backend = ran[label]
        print(
            f"{label:44s} {seconds / wall:6.2f} x real time "
            f"({wall:6.2f} s for {seconds:g} s, {substeps} substeps, backend {backend})"
        )


if __name__ == "__main__":
    main()
