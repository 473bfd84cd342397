"""Scheduling the benchmark's tasks: in this process, or on Dask (a local cluster or any).

The task graph of one scenario: ``n_tuning`` simulations of collision-free
runs, then one tuning task per detector (it needs every tuning run), then one
test task per collision or collision-free test run (it needs every tuned
detector). The scenarios are independent. :func:`execute` runs that graph

* ``scheduler="serial"``: the same task functions, one after the other, in
  this process;
* ``scheduler="local"``: on a ``distributed.LocalCluster`` of ``n_workers``
  processes with one thread each (the simulations hold the GIL);
* ``scheduler="tcp://host:port"``: on the Dask cluster of that scheduler
  (the workers need ``sensorless`` installed);
* ``scheduler=client``: on an existing ``distributed.Client``.

Every task is submitted with ``retries``: a task that raises is run again,
and a task whose worker process dies (killed, out of memory) is moved to
another worker by the scheduler (``distributed.scheduler.allowed-failures``,
3 by default). The tasks are pure functions of their seeds, so a retried
task gives the same value, and the results do not depend on the scheduler or
on the order in which tasks finish: they are collected by name, in plan order.
"""

from __future__ import annotations

import logging
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..exceptions import InputTypeError, InputValueError
from ..io import Log
from ..simulation.scenario import Scenario
from .config import BenchmarkConfig, BenchmarkScenario, RunSpec, plan_runs
from .tasks import BeforeTask, RunRecords, TaskOutput, Tuned, judge_run, simulate_run, tune_detector

__all__ = ["Progress", "RawResults", "execute"]

Progress = Callable[[int, int, str], None]
"""Told ``(tasks done, tasks in all, name of the task just done)``."""


@dataclass
class RawResults:
    """What the tasks returned, in plan order.

    Attributes
    ----------
    tuning : list of (RunSpec, Log)
        Tuning runs.
    tuned : dict
        ``{(scenario name, label): Tuned}``.
    records : list of RunRecords
        One per test run.
    timings : list of TaskOutput
        Every task's name, wall time and process (values dropped).
    workers : int
        Processes that ran the tasks (1 for the serial scheduler).
    """

    tuning: list[tuple[RunSpec, Log]]
    tuned: dict[tuple[str, str], Tuned]
    records: list[RunRecords]
    timings: list[TaskOutput[None]]
    workers: int


class _Plan:
    """The scenarios, their runs by role and their detectors."""

    def __init__(self, config: BenchmarkConfig) -> None:
        self.config = config
        self.scenarios: list[Scenario] = [choice.load() for choice in config.scenarios]
        self.runs = plan_runs(config)

    def of(self, position: int, role: str) -> list[RunSpec]:
        return [s for s in self.runs if s.scenario_index == position and s.role == role]

    def choice(self, position: int) -> BenchmarkScenario:
        return self.config.scenarios[position]

    @property
    def n_tasks(self) -> int:
        tuning = sum(1 for s in self.runs if s.role == "tuning")
        tests = len(self.runs) - tuning
        detectors = sum(len(self.config.detections(c)) for c in self.config.scenarios)
        return tuning + tests + detectors


def _strip(output: TaskOutput[Any]) -> TaskOutput[None]:
    return TaskOutput(None, output.name, output.seconds, output.pid)


def _serial(plan: _Plan, log_dir: str | None, before: BeforeTask, progress: Progress) -> RawResults:
    done, total = 0, plan.n_tasks
    timings: list[TaskOutput[None]] = []

    def count(output: TaskOutput[Any]) -> None:
        nonlocal done
        done += 1
        timings.append(_strip(output))
        progress(done, total, output.name)

    tuning, tuned, records = [], {}, []
    for position, scenario in enumerate(plan.scenarios):
        runs = []
        for spec in plan.of(position, "tuning"):
            output = simulate_run(scenario, spec, log_dir, before)
            count(output)
            runs.append(output)
            tuning.append((spec, output.value))
        fitted = []
        for detection in plan.config.detections(plan.choice(position)):
            fit = tune_detector(
                scenario, plan.choice(position), plan.config, detection, before, *runs
            )
            count(fit)
            fitted.append(fit)
            tuned[(scenario.name, detection.label)] = fit.value
        for spec in plan.of(position, "collision") + plan.of(position, "free"):
            record = judge_run(scenario, plan.config, spec, log_dir, before, *fitted)
            count(record)
            records.append(record.value)
    return RawResults(tuning, tuned, records, timings, 1)


def _dask(
    plan: _Plan, client: Any, retries: int, log_dir: str | None, before: BeforeTask,
    progress: Progress,
) -> RawResults:  # fmt: skip
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]  # unique keys: a client may run several benchmarks
    options = {"retries": retries, "pure": False}
    simulations, fits, tests = [], [], []
    for position, scenario in enumerate(plan.scenarios):
        runs = []
        for spec in plan.of(position, "tuning"):
            key = f"simulate-{token}-{spec.key}"
            runs.append(
                client.submit(simulate_run, scenario, spec, log_dir, before, key=key, **options)
            )
            simulations.append((spec, runs[-1]))
        fitted = []
        for detection in plan.config.detections(plan.choice(position)):
            key = f"tune-{token}-{scenario.name}/{detection.label}"
            fitted.append(
                client.submit(
                    tune_detector,
                    scenario,
                    plan.choice(position),
                    plan.config,
                    detection,
                    before,
                    *runs,
                    key=key,
                    **options,
                )
            )
            fits.append(((scenario.name, detection.label), fitted[-1]))
        for spec in plan.of(position, "collision") + plan.of(position, "free"):
            key = f"judge-{token}-{spec.key}"
            tests.append(
                client.submit(
                    judge_run,
                    scenario,
                    plan.config,
                    spec,
                    log_dir,
                    before,
                    *fitted,
                    key=key,
                    **options,
                )
            )
    futures = [f for _, f in simulations] + [f for _, f in fits] + tests
    values: dict[str, TaskOutput[Any]] = {}
    try:
        # Raises the first task error left after the retries.
        for future, output in as_completed(futures, with_results=True):
            values[future.key] = output
            progress(len(values), len(futures), output.name)
    finally:
        client.cancel(futures)
    outputs = [values[future.key] for future in futures]
    n_sim, n_fit = len(simulations), len(fits)
    tuning = [(spec, out.value) for (spec, _), out in zip(simulations, outputs, strict=False)]
    tuned = {name: out.value for (name, _), out in zip(fits, outputs[n_sim:], strict=False)}
    records = [out.value for out in outputs[n_sim + n_fit :]]
    pids = {out.pid for out in outputs}
    return RawResults(tuning, tuned, records, [_strip(out) for out in outputs], len(pids))


def execute(
    config: BenchmarkConfig,
    *,
    scheduler: Any = "local",
    n_workers: int | None = None,
    retries: int = 2,
    log_dir: str | None = None,
    before_task: BeforeTask = None,
    progress: Progress | None = None,
) -> RawResults:
    """Run every task of a benchmark (module docstring) and return their values in plan order.

    Parameters
    ----------
    config : BenchmarkConfig
    scheduler : "serial", "local", str or distributed.Client
        Where the tasks run (module docstring).
    n_workers : int, optional
        Worker processes of the local cluster; default the CPU count.
    retries : int
        Times a failed task is run again.
    log_dir : str, optional
        fsspec URL (a folder, ``s3://...``) every simulated run's log is written to.
    before_task : callable(str), optional
        Called with the task's name where it runs, before it runs
        (instrumentation; the tests kill a worker with it). Must be picklable
        for Dask.
    progress : callable(done, total, name), optional
        Told each time a task finishes.
    """
    plan = _Plan(config)
    say = progress or (lambda done, total, name: None)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise InputValueError(f"retries must be an integer >= 0; got {retries!r}")
    if isinstance(scheduler, str) and scheduler == "serial":
        return _serial(plan, log_dir, before_task, say)
    if isinstance(scheduler, str) and scheduler == "local":
        return _on_local_cluster(plan, n_workers, retries, log_dir, before_task, say)
    if isinstance(scheduler, str):
        if "://" not in scheduler:
            raise InputValueError(
                "scheduler must be 'serial', 'local', a scheduler address such as "
                f"'tcp://host:8786', or a distributed.Client; got {scheduler!r}"
            )
        from distributed import Client

        with Client(scheduler) as client:
            return _dask(plan, client, retries, log_dir, before_task, say)
    if type(scheduler).__name__ != "Client":
        raise InputTypeError(
            "scheduler must be 'serial', 'local', a scheduler address or a distributed.Client; "
            f"got {type(scheduler).__name__}"
        )
    return _dask(plan, scheduler, retries, log_dir, before_task, say)


def _on_local_cluster(
    plan: _Plan, n_workers: int | None, retries: int, log_dir: str | None, before: BeforeTask,
    progress: Progress,
) -> RawResults:  # fmt: skip
    import os

    from distributed import Client, LocalCluster

    workers = n_workers or os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputValueError(f"n_workers must be a positive integer; got {n_workers!r}")
    with (
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.ERROR,
        ) as cluster,
        Client(cluster) as client,
    ):  # fmt: skip
        return _dask(plan, client, retries, log_dir, before, progress)
