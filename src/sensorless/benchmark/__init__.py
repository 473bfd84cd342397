"""A detection benchmark users can trust: many seeded runs, intervals, an oracle, on Dask.

:func:`run_benchmark` tunes every threshold family on N collision-free runs
of each scenario, judges it on M collision and K collision-free test runs
(every seed from one master seed, :func:`plan_runs`), next to an *oracle*:
the same pipeline on the residual of the exact model
(:meth:`~sensorless.simulation.scenario.Scenario.with_exact_model`) of the
same runs. The runs are independent tasks scheduled in this process or on
Dask (:mod:`.engine`), with the same results either way. The
:class:`BenchmarkResult` holds a table of every run, result, collision and
event (:mod:`.tables`), gives a summary per method with Wilson and Poisson
intervals, and writes Parquet/CSV tables, PNG figures and an ``index.html``.
Every event of a collision run is also isolated (link, point, force) and
classified (intended contact or collision) against the ground truth
(:mod:`.contacts`; :meth:`BenchmarkResult.contacts`, :meth:`BenchmarkResult.confusion`);
``BenchmarkScenario(interactions=n)`` fills the collision runs with the
simulator's guiding hands, clamps and impacts so that both classes occur.

Examples
--------
>>> from sensorless.benchmark import quick_config, run_benchmark
>>> result = run_benchmark(quick_config(), scheduler="local", n_workers=2)  # doctest: +SKIP
>>> result.summary()[["method", "detection_rate", "false_alarms_per_hour"]]  # doctest: +SKIP
>>> result.write("out/benchmark")  # doctest: +SKIP
"""

from __future__ import annotations

from .config import (
    DEFAULT_FORCE_BINS,
    DEFAULT_METHODS,
    BenchmarkConfig,
    BenchmarkScenario,
    Detection,
    RunSpec,
    full_config,
    plan_runs,
    quick_config,
)
from .result import BenchmarkResult, run_benchmark
from .tables import wilson_interval

__all__ = [
    "DEFAULT_FORCE_BINS",
    "DEFAULT_METHODS",
    "BenchmarkConfig",
    "BenchmarkResult",
    "BenchmarkScenario",
    "Detection",
    "RunSpec",
    "full_config",
    "plan_runs",
    "quick_config",
    "run_benchmark",
    "wilson_interval",
]
