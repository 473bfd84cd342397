"""The runs of a comparison: seeds, simulation (here, a process pool or Dask), tuning, detection."""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..detection import Detector
from ..evaluation import Evaluation, evaluate
from ..exceptions import InputValueError
from ..io import Log
from ..monitor import METHOD_NAMES, ObserverSettings, make_threshold
from ..signals import Event
from ..simulation.scenario import Scenario
from ..thresholds import (
    CombinedVelocityThreshold,
    ConstantThreshold,
    Threshold,
)
from .results import Comparison

Job = tuple[Scenario, int, bool]
"""One simulated run of :func:`compare`: scenario, run seed, contacts on."""


def _simulate(job: Job) -> Log:
    scenario, seed, collisions = job
    return scenario.run(seed=seed, collisions=collisions).log


def _jobs(scenario: Scenario, n_tuning: int, master_seed: int) -> tuple[list[int], list[Job]]:
    """Seeds and runs of :func:`compare`: ``n_tuning`` collision-free runs, then the test run."""
    children = np.random.SeedSequence(master_seed).spawn(n_tuning + 1)
    seeds = [int(child.generate_state(1)[0]) for child in children]
    return seeds, [(scenario, seed, index == n_tuning) for index, seed in enumerate(seeds)]


def _job_key(job: Job) -> str:
    """A Dask key that names a run by its content: the same run submitted twice runs once."""
    scenario, seed, collisions = job
    spec = json.dumps(scenario.spec, sort_keys=True, default=str)
    digest = hashlib.sha256(f"{spec}|{seed}|{collisions}".encode()).hexdigest()[:16]
    return f"compare-{scenario.name}-{'collision' if collisions else 'free'}-{digest}"


def _submit_runs(client: Any, jobs: Sequence[Job]) -> list[Any]:
    """Submit runs to a ``distributed.Client`` (retried twice if a task fails); their futures.

    Keys are content hashes (:func:`_job_key`): submitting runs that are
    already pending or done returns the existing futures, so a caller can
    submit the runs of several comparisons up front and let the workers
    simulate the next one while this process tunes the last.
    """
    return [client.submit(_simulate, job, key=_job_key(job), retries=2) for job in jobs]


@contextmanager
def _dask_client(scheduler: Any, workers: int) -> Iterator[Any]:
    """A ``distributed.Client`` for ``scheduler``: itself, a LocalCluster or an address."""
    if type(scheduler).__name__ == "Client":
        yield scheduler
        return
    from distributed import Client, LocalCluster

    if scheduler == "local":
        with (
            LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.ERROR,
            ) as cluster,
            Client(cluster) as client,
        ):  # fmt: skip
            yield client
        return
    if isinstance(scheduler, str) and "://" in scheduler:
        with Client(scheduler) as client:
            yield client
        return
    raise InputValueError(
        "scheduler must be None, 'local', a scheduler address such as 'tcp://host:8786' "
        f"or a distributed.Client; got {scheduler!r}"
    )


def _run_all(jobs: list[Job], workers: int, scheduler: Any) -> list[Log]:
    """The logs of ``jobs`` in order: here, in a process pool or on Dask (same values)."""
    if scheduler is not None:
        with _dask_client(scheduler, workers) as client:
            return [future.result() for future in _submit_runs(client, jobs)]
    if workers > 1:
        with ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
            return list(pool.map(_simulate, jobs))
    return [_simulate(job) for job in jobs]


def compare(
    scenario: Scenario,
    *,
    methods: Sequence[str] = ("constant", "time-variant", "hysteretic", "velocity", "model"),
    n_tuning: int = 2,
    master_seed: int = 0,
    joints: Sequence[int] | None = None,
    margin_fraction: float = 0.1,
    min_duration: float = 0.005,
    hold: float = 0.05,
    model_tuning_runs: int = 1,
    residuals: Sequence[str] = ("motor",),
    workers: int = 1,
    scheduler: Any = None,
    progress: Callable[[str], None] | None = None,
) -> Comparison:
    """Tune every method on collision-free runs of ``scenario`` and evaluate on a collision run.

    Parameters
    ----------
    scenario : Scenario
    methods : sequence of str
        Threshold families (:data:`sensorless.monitor.METHOD_NAMES`).
    n_tuning : int
        Collision-free tuning runs.
    master_seed : int
        Seeds of the tuning runs and of the test run come from
        ``SeedSequence(master_seed).spawn(n_tuning + 1)`` and never coincide.
    joints : sequence of int, optional
        Monitored joints (1-based); the thesis watches joints 1–3 of the PUMA.
    margin_fraction : float
        Every method gets the same absolute margin, ``margin_fraction`` × β_j
        of the constant threshold (β = max|r̂| on the tuning runs): without
        one, a threshold fitted at the exact maximum of a few runs raises
        alarms on any new run.
    min_duration, hold : float
        Event filtering [s] (:class:`~sensorless.detection.Detector`).
    model_tuning_runs : int
        Tuning runs the model-based threshold is fitted on (its fit is the
        slowest: the split regressor at every sample).
    residuals : sequence of {"motor", "joint"}
        Residuals the momentum methods watch: r̂ from motor torques (eq. 4.4)
        and, on a robot with joint torque sensors, r̂_s (eq. 4.9). Methods
        on r̂_s are labelled ``"<method> (joint)"``; each residual's margin
        comes from its own constant β.
    workers : int
        Processes that simulate the runs in parallel (1: in this process);
        with ``scheduler="local"``, the workers of the local Dask cluster.
    scheduler : None, "local", str or distributed.Client
        None: the runs are simulated here or in a pool of ``workers``
        processes. Otherwise they are Dask tasks (retried twice on failure):
        ``"local"`` starts a ``LocalCluster`` for this call, ``"tcp://host:port"``
        uses that scheduler, a ``distributed.Client`` is used as is (pass one
        to share its workers between calls). The logs, hence every result,
        do not depend on ``workers`` or ``scheduler``.
    progress : callable(str), optional
        Told what is being done.
    """
    say = progress or (lambda _: None)
    if not residuals or set(residuals) - {"motor", "joint"}:
        raise InputValueError(
            f"residuals must be a non-empty subset of ('motor', 'joint'); got {residuals!r}"
        )
    if not isinstance(workers, int) or workers < 1:
        raise InputValueError(f"workers must be a positive integer; got {workers!r}")
    seeds, jobs = _jobs(scenario, n_tuning, master_seed)
    say(
        f"{scenario.name}: simulating {n_tuning} collision-free runs and a collision run, "
        f"{scenario.duration:g} s each"
    )
    logs = _run_all(jobs, workers, scheduler)
    tuning, test = logs[:-1], logs[-1]
    joint_tuple = None if joints is None else tuple(int(j) for j in joints)

    # (label, method, observer kind): momentum methods watch every requested residual.
    plan = []
    for method in methods:
        watched = METHOD_NAMES[method]
        for kind in residuals if watched == "motor" else (watched,):
            plan.append((f"{method} (joint)" if kind == "joint" else method, method, kind))
    # One observer pass per residual kind, shared by every method that watches it.
    kinds = {kind for _, _, kind in plan} | set(residuals)
    nominal = {kind: scenario.nominal(kind) for kind in kinds}
    settings = {kind: ObserverSettings(kind=kind) for kind in kinds}
    tuning_signals = {k: [settings[k].observe(log, nominal[k]) for log in tuning] for k in kinds}
    signals = {kind: settings[kind].observe(test, nominal[kind]) for kind in kinds}

    # The margin of every method is a fraction of the constant β of the residual it watches.
    margins = {}
    for kind in residuals:
        constant = make_threshold("constant", nominal[kind], joints=joint_tuple)
        constant.fit(tuning_signals[kind])
        assert isinstance(constant, ConstantThreshold)
        margins[kind] = margin_fraction * constant.beta_
    margins["acceleration"] = margins["motor" if "motor" in residuals else "joint"]
    thresholds: dict[str, Threshold] = {}
    evaluations: dict[str, Evaluation] = {}
    bounds: dict[str, tuple[FloatArray, FloatArray]] = {}
    events: dict[str, list[Event]] = {}
    kind_of: dict[str, str] = {}

    def detect(label: str, threshold: Threshold, kind: str) -> None:
        # One pass gives both bounds and events (the model-based bound is costly).
        detection = Detector(threshold, min_duration=min_duration, hold=hold).run(signals[kind])
        bounds[label] = (detection.lower, detection.upper)
        events[label] = detection.events
        evaluations[label] = evaluate(events[label], test, method=label)
        kind_of[label] = kind

    for label, method, kind in plan:
        say(f"{scenario.name}: tuning and detecting with {label}")
        options: dict[str, Any] = {"joints": joint_tuple, "margin": margins[kind]}
        if method in ("time-variant", "hysteretic"):
            options["fit_method"] = "minimax"
        fit_runs = tuning_signals[kind]
        if kind == "acceleration":
            # Its bound needs the split regressor at every sample (l Pinocchio
            # regressor calls each): the costliest fit by far.
            fit_runs = fit_runs[:model_tuning_runs]
        thresholds[label] = make_threshold(method, nominal[kind], **options).fit(fit_runs)
        detect(label, thresholds[label], kind)
    if "velocity" in methods and {"motor", "joint"} <= set(residuals):
        # Both residuals of the same runs: one fit with a shared γ (eq. 4.21, 4.47).
        say(f"{scenario.name}: tuning and detecting with velocity-combined")
        combined = CombinedVelocityThreshold(joints=joint_tuple).fit(
            list(zip(tuning_signals["motor"], tuning_signals["joint"], strict=True))
        )
        for kind in ("motor", "joint"):
            label = "velocity-combined" + ("" if kind == "motor" else " (joint)")
            single = combined.for_kind(kind)
            # Fitted without margin: each residual gets the margin of its own β.
            single.lower_ = single.lower_ - margins[kind]
            single.upper_ = single.upper_ + margins[kind]
            thresholds[label] = combined
            detect(label, single, kind)
    return Comparison(
        scenario.name,
        joint_tuple,
        thresholds,
        evaluations,
        signals,
        bounds,
        events,
        test,
        {"tuning": seeds[:-1], "test": seeds[-1], "master": master_seed},
        kind_of,
    )
