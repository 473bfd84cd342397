"""The benchmark's tasks: simulate a tuning run, tune one detector, judge one test run.

Each task is a pure function of its arguments (the seeds are in them), so the
serial path and every Dask worker compute the same values, and a task that is
run again after a failure gives the same result. Tasks are coarse: a tuning
run is one simulation; a tuning task fits one detector on all tuning runs of
its scenario (the runs are shared by every detector); a test task simulates
one run and judges it with every detector. Every task returns a
:class:`TaskOutput`: its value and how long it took (the timing is reported
apart from the results, which stay identical from run to run).
A test task on a collision run also isolates and classifies every event
(:mod:`.contacts`, with ``config.isolation``), and, for a scenario with
``interactions``, simulates the simulator's random interactions instead of
the scenario's own contacts.
Units SI and radians; time along axis 0, arrays of shape ``(n_samples, n_dof)``.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np

from ..evaluation import evaluate
from ..io import Log, write_log
from ..isolation import Isolator
from ..monitor import CollisionMonitor, ObserverSettings, tune
from ..robots.model import RobotModel
from ..simulation.interactions import simulate_interactions
from ..simulation.scenario import Scenario
from ..thresholds import ConstantThreshold, Threshold, TimeVariantThreshold
from ..thresholds.checks import check_joints
from .config import BenchmarkConfig, BenchmarkScenario, Detection, RunSpec
from .contacts import DetectorRun, score_events

__all__ = ["RunRecords", "TaskOutput", "Tuned", "judge_run", "simulate_run", "tune_detector"]

T = TypeVar("T")
BeforeTask = Callable[[str], None] | None


@dataclass(frozen=True)
class TaskOutput(Generic[T]):
    """A task's value, its name, its wall time [s] and the process that ran it."""

    value: T
    name: str
    seconds: float
    pid: int


@dataclass(frozen=True)
class Tuned:
    """A detector tuned on the tuning runs of one scenario."""

    detection: Detection
    threshold: Threshold
    settings: ObserverSettings


@dataclass(frozen=True)
class RunRecords:
    """Rows of the benchmark tables made by one test run (lists of plain dicts)."""

    run: dict[str, Any]
    results: list[dict[str, Any]]
    collisions: list[dict[str, Any]]
    events: list[dict[str, Any]]


def _timed(name: str, before: BeforeTask, work: Callable[[], T]) -> TaskOutput[T]:
    if before is not None:
        before(name)
    start = time.perf_counter()
    value = work()
    return TaskOutput(value, name, time.perf_counter() - start, os.getpid())


def _model(scenario: Scenario, detection: Detection) -> RobotModel:
    source = scenario.with_exact_model() if detection.oracle else scenario
    return source.nominal(detection.kind)


def store_log(log: Log, log_dir: str, spec: RunSpec) -> None:
    """Write a run's log (Parquet + JSON sidecar) under ``log_dir``, any fsspec URL.

    ``<log_dir>/<scenario>/<role>-<index>.parquet`` and its ``.meta.json``:
    a local folder, ``s3://bucket/prefix``, ``memory://...``, ...
    """
    import fsspec  # type: ignore[import-untyped]  # a dependency of dask

    filesystem, root = fsspec.core.url_to_fs(log_dir)
    folder = f"{root.rstrip('/')}/{spec.scenario}"
    filesystem.makedirs(folder, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        write_log(log, Path(scratch) / f"{spec.role}-{spec.index:03d}.parquet")
        for path in sorted(Path(scratch).iterdir()):
            filesystem.put_file(str(path), f"{folder}/{path.name}")


def _simulate(
    scenario: Scenario, spec: RunSpec, log_dir: str | None, interactions: int | None = None
) -> Log:
    if spec.role == "collision" and interactions is not None:
        log = simulate_interactions(scenario, interactions, seed=spec.seed).log
    else:
        log = scenario.run(seed=spec.seed, collisions=spec.role == "collision").log
    if log_dir is not None:
        store_log(log, log_dir, spec)
    return log


def simulate_run(
    scenario: Scenario, spec: RunSpec, log_dir: str | None = None, before: BeforeTask = None
) -> TaskOutput[Log]:
    """Task: simulate one (collision-free) tuning run."""
    return _timed(spec.key, before, lambda: _simulate(scenario, spec, log_dir))


def _margin(
    logs: Sequence[Log], scenario: Scenario, choice: BenchmarkScenario, config: BenchmarkConfig,
    detection: Detection,
) -> Any:  # fmt: skip
    """margin_fraction × the constant β of the residual the detector watches (per joint)."""
    kind = "motor" if detection.kind == "acceleration" else detection.kind
    reference = Detection("constant", "constant", kind, detection.oracle)
    constant, _ = tune(
        logs, _model(scenario, reference), "constant", ObserverSettings(kind=kind), folds=None,
        joints=choice.joints, margin=0.0,
    )  # fmt: skip
    assert isinstance(constant, ConstantThreshold)
    return config.margin_fraction * constant.beta_


def _tune(
    logs: Sequence[Log], scenario: Scenario, choice: BenchmarkScenario, config: BenchmarkConfig,
    detection: Detection,
) -> Tuned:  # fmt: skip
    options: dict[str, Any] = {"joints": choice.joints}
    if detection.method in ("time-variant", "hysteretic"):
        options["fit_method"] = "minimax"
    detector = {"min_duration": config.min_duration, "hold": config.hold}
    if config.false_alarm_rate is None:
        options["margin"] = _margin(logs, scenario, choice, config, detection)
        tuning: dict[str, Any] = {"folds": None}
    else:
        tuning = {
            "false_alarm_rate": config.false_alarm_rate, "folds": "runs",
            "confidence": config.confidence, **detector,
        }  # fmt: skip
    threshold, settings = tune(
        logs, _model(scenario, detection), detection.method,
        ObserverSettings(kind=detection.kind), **tuning, **options,
    )  # fmt: skip
    return Tuned(detection, threshold, settings)


def tune_detector(
    scenario: Scenario,
    choice: BenchmarkScenario,
    config: BenchmarkConfig,
    detection: Detection,
    before: BeforeTask,
    *runs: TaskOutput[Log],
) -> TaskOutput[Tuned]:
    """Task: tune one detector on every tuning run of its scenario."""
    name = f"{scenario.name}/tune/{detection.label}"
    logs = [run.value for run in runs]
    return _timed(name, before, lambda: _tune(logs, scenario, choice, config, detection))


def _event_rows(
    spec: RunSpec, label: str, evaluation: Any, max_delay: float,
    contacts: Sequence[dict[str, Any]] = (),
) -> list[dict[str, Any]]:  # fmt: skip
    detections = {id(e) for e in evaluation.detections}
    false_alarms = {id(e) for e in evaluation.false_alarms}
    rows = []
    for index, event in enumerate(evaluation.events):
        # The windows this event detects, by the rule of sensorless.evaluation.
        hits = [
            w.id
            for w in evaluation.windows
            if event.start <= w.end + max_delay and event.end >= w.start
        ]
        outcome = (
            "detection"
            if id(event) in detections
            else ("false_alarm" if id(event) in false_alarms else "excused")
        )
        rows.append(
            {
                "scenario": spec.scenario, "role": spec.role, "run": spec.index,
                "method": label, "start": float(event.start), "end": float(event.end),
                "joints": ",".join(map(str, event.joints)), "peak": float(event.peak),
                "peak_residual": float(event.peak_residual), "outcome": outcome,
                "collisions": ",".join(map(str, hits)),
                **(contacts[index] if contacts else {}),
            }
        )  # fmt: skip
    return rows


def _result_row(
    spec: RunSpec, detection: Detection, evaluation: Any, judged_seconds: float
) -> dict[str, Any]:
    return {
        "scenario": spec.scenario, "role": spec.role, "run": spec.index,
        "method": detection.label, "family": detection.method, "kind": detection.kind,
        "oracle": detection.oracle, "judged_seconds": judged_seconds,
        "n_collisions": evaluation.n_collisions, "n_detected": evaluation.n_detected,
        "n_events": len(evaluation.events), "n_false_alarms": evaluation.n_false_alarms,
        "n_excused": len(evaluation.excused),
    }  # fmt: skip


def _collision_rows(spec: RunSpec, detection: Detection, evaluation: Any) -> list[dict[str, Any]]:
    return [
        {
            "scenario": spec.scenario, "role": spec.role, "run": spec.index,
            "collision": int(row["id"]), "method": detection.label,
            "oracle": detection.oracle, "start": float(row["start"]),
            "end": float(row["end"]), "peak_force": float(row["peak_force"]),
            "detected": bool(row["detected"]),
            "start_delay": float(row["start_delay"]), "end_delay": float(row["end_delay"]),
            "n_events": int(row["n_events"]),
        }
        for row in evaluation.per_collision.reset_index().to_dict("records")
    ]  # fmt: skip


def _judge(
    scenario: Scenario, config: BenchmarkConfig, spec: RunSpec, tuned: Sequence[Tuned],
    log_dir: str | None,
) -> RunRecords:  # fmt: skip
    log = _simulate(scenario, spec, log_dir, config.scenarios[spec.scenario_index].interactions)
    models: dict[tuple[bool, str], RobotModel] = {}
    isolators: dict[tuple[bool, str], Isolator] = {}
    # Isolation and classification need the ground truth of the contacts: collision runs.
    true_robot = scenario.robots()[0] if config.isolation and spec.role == "collision" else None
    evaluations: list[tuple[str, Any]] = []
    isolated: list[DetectorRun] = []
    results, collisions = [], []
    run = {
        "scenario": spec.scenario, "role": spec.role, "run": spec.index, "seed": spec.seed,
        "duration": log.duration, "n_samples": log.n_samples,
        "n_contacts": len(log.metadata.get("collisions", [])),
    }  # fmt: skip
    for item in tuned:
        detection = item.detection
        place = (detection.oracle, detection.kind)
        if place not in models:
            models[place] = _model(scenario, detection)
        monitor = CollisionMonitor(
            models[place], item.threshold, item.settings,
            min_duration=config.min_duration, hold=config.hold,
        )  # fmt: skip
        outcome = monitor.process(log)
        evaluation = evaluate(
            outcome.events, log, method=detection.label, max_delay=config.max_delay
        )
        judged = ~outcome.settling & np.isfinite(outcome.signals.residual).all(axis=1)
        results.append(_result_row(spec, detection, evaluation, float(judged.sum() * log.dt)))
        collisions.extend(_collision_rows(spec, detection, evaluation))
        evaluations.append((detection.label, evaluation))
        if true_robot is not None:
            if place not in isolators:
                isolators[place] = Isolator(models[place])
            bounds = monitor.detector.run(outcome.signals, skip_nonfinite=True)
            isolated.append(
                DetectorRun(evaluation.events, outcome.signals, bounds, isolators[place])
            )
    contacts = (
        score_events(isolated, log, true_robot, config.max_delay) if true_robot is not None else []
    )
    events = []
    for index, (label, evaluation) in enumerate(evaluations):
        found = contacts[index] if contacts else ()
        events.extend(_event_rows(spec, label, evaluation, config.max_delay, found))
    return RunRecords(run, results, collisions, events)


def judge_run(
    scenario: Scenario,
    config: BenchmarkConfig,
    spec: RunSpec,
    log_dir: str | None,
    before: BeforeTask,
    *tuned: TaskOutput[Tuned],
) -> TaskOutput[RunRecords]:
    """Task: simulate one test run and judge it with every tuned detector of its scenario."""
    detectors = [item.value for item in tuned]
    return _timed(spec.key, before, lambda: _judge(scenario, config, spec, detectors, log_dir))


def tuning_record(spec: RunSpec, log: Log) -> dict[str, Any]:
    """The runs-table row of a tuning run."""
    return {
        "scenario": spec.scenario, "role": spec.role, "run": spec.index, "seed": spec.seed,
        "duration": log.duration, "n_samples": log.n_samples,
        "n_contacts": len(log.metadata.get("collisions", [])),
    }  # fmt: skip


def efficiency(threshold: Threshold) -> tuple[float, str]:
    """Mean eff = α/β over the monitored joints (Table 5.7), and the values; NaN if undefined."""
    if not isinstance(threshold, TimeVariantThreshold):
        return math.nan, ""
    values = np.asarray(threshold.efficiency_, dtype=np.float64)
    joints = check_joints(threshold.joints, threshold.n_dof_)
    picked = values[np.asarray(joints) - 1]
    return float(picked.mean()), ", ".join(f"{v:.4f}" for v in picked)
