"""Compare threshold families on a scenario: the thesis's comparisons end to end.

:func:`compare` simulates collision-free (tuning) runs and a collision (test)
run of a scenario with seeds derived from one master seed, tunes every
threshold family on the tuning runs, detects on the test run and evaluates
against the ground truth. :func:`real_arm` runs the same families on the
real UR10 recordings when they are at hand (:mod:`sensorless.realarm`), or
says why not. :func:`write_comparison_report` turns the results into a
self-contained HTML report with tables and figures.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .detection import Detector
from .evaluation import Evaluation, comparison_table, efficiency_table, evaluate, summary_table
from .exceptions import InputValueError
from .io import Log
from .monitor import METHOD_NAMES, ObserverSettings, make_threshold
from .plots import plot_held_out, plot_residuals
from .realarm import UR10_FOLDER, RealArmEvaluation, evaluate_ur10, missing_files
from .report import write_report
from .signals import Event, ObserverSignals
from .simulation.scenario import Scenario
from .thresholds import (
    CombinedVelocityThreshold,
    ConstantThreshold,
    Threshold,
    TimeVariantThreshold,
)

__all__ = ["Comparison", "RealArm", "compare", "real_arm", "write_comparison_report"]

FloatArray = np.ndarray


@dataclass
class Comparison:
    """Results of :func:`compare` for one scenario.

    Attributes
    ----------
    scenario : str
    joints : tuple of int or None
        Monitored joints (1-based), None for all.
    thresholds : dict
        Fitted threshold per method.
    evaluations : dict
        :class:`~sensorless.evaluation.Evaluation` per method on the test run.
    signals : dict
        Observer signals of the test run per observer kind ("motor", "joint", "acceleration").
    bounds : dict
        (lower, upper) of each method on the test run.
    events : dict
        Detected events per method.
    test_log : Log
        The collision run.
    seeds : dict
        Seeds of the tuning and test runs.
    kinds : dict
        Observer kind each method label watches ("motor", "joint", "acceleration").
    """

    scenario: str
    joints: tuple[int, ...] | None
    thresholds: dict[str, Threshold]
    evaluations: dict[str, Evaluation]
    signals: dict[str, ObserverSignals]
    bounds: dict[str, tuple[FloatArray, FloatArray]]
    events: dict[str, list[Event]]
    test_log: Log
    seeds: dict[str, Any] = field(default_factory=dict)
    kinds: dict[str, str] = field(default_factory=dict)

    def summary(self) -> pd.DataFrame:
        """One row per method: detected/total, false alarms, delays (Table 5.4 summary)."""
        return summary_table(self.evaluations)

    def per_collision(self) -> pd.DataFrame:
        """Start/end delay per collision and method (Tables 4.3, 5.4 style)."""
        return comparison_table(self.evaluations)

    def efficiency(self) -> pd.DataFrame | None:
        """α, γ, ε_fr, β and eff = α/β of the time-variant threshold (Table 5.7 style)."""
        threshold = self.thresholds.get("time-variant")
        if not isinstance(threshold, TimeVariantThreshold):
            return None
        joints = list(self.joints or range(1, threshold.n_dof_ + 1))
        index = np.asarray(joints) - 1
        table = efficiency_table(
            threshold.alpha_[index],
            threshold.beta_[index],
            extra={"gamma": threshold.gamma_[index], "eps_fr": threshold.eps_fr_[index]},
        )
        table.columns = [f"joint {j}" for j in joints]
        return table


def _simulate(job: tuple[Scenario, int, bool]) -> Log:
    scenario, seed, collisions = job
    return scenario.run(seed=seed, collisions=collisions).log


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
        Processes that simulate the runs in parallel (1: in this process).
        The logs do not depend on it.
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
    children = np.random.SeedSequence(master_seed).spawn(n_tuning + 1)
    seeds = [int(child.generate_state(1)[0]) for child in children]
    jobs = [(scenario, seed, index == n_tuning) for index, seed in enumerate(seeds)]
    say(f"{scenario.name}: simulating {n_tuning} collision-free runs and a collision run")
    if workers > 1:
        with ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
            logs = list(pool.map(_simulate, jobs))
    else:
        logs = [_simulate(job) for job in jobs]
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


REAL_ARM_HEADING = "Real arm (UR10)"
"""Heading of the report's real-arm section."""


def write_comparison_report(
    comparisons: Sequence[Comparison], path: str | Path, real_arm: RealArm | None = None
) -> Path:
    """One self-contained HTML report: tables and residual plots of every comparison.

    With ``real_arm``, a last section "Real arm (UR10)": the held-out
    false-alarm table and the residual of a held-out recording, or why the
    recipe was skipped.
    """
    sections: list[tuple[str, list[Any]]] = []
    for comparison in comparisons:
        items: list[Any] = [
            f"Seeds: tuning runs {comparison.seeds.get('tuning')}, test run "
            f"{comparison.seeds.get('test')}. Monitored joints: "
            f"{list(comparison.joints) if comparison.joints else 'all'}.",
            comparison.summary(),
            comparison.per_collision(),
        ]
        efficiency = comparison.efficiency()
        if efficiency is not None:
            items.append(efficiency)
        for kind, kind_signals in comparison.signals.items():
            kind_methods = [m for m in comparison.bounds if comparison.kinds.get(m) == kind]
            items.append(
                plot_residuals(
                    kind_signals,
                    {m: comparison.bounds[m] for m in kind_methods},
                    log=comparison.test_log,
                    events={m: comparison.events[m] for m in kind_methods},
                    joints=comparison.joints,
                    title=f"{comparison.scenario}: {kind} residual and bounds",
                )
            )
        sections.append((comparison.scenario, items))
    if real_arm is not None:
        sections.append((REAL_ARM_HEADING, real_arm.report_items()))
    return write_report(path, title="sensorless: threshold comparison", sections=sections)


@dataclass(frozen=True)
class RealArm:
    """The real-arm part of the demo: the UR10 recipe's result, or why it was skipped.

    Attributes
    ----------
    folder : Path
        Where the recordings were looked for.
    evaluation : RealArmEvaluation or None
        :func:`sensorless.realarm.evaluate_ur10` on ``folder``; None if skipped.
    skipped : str
        Why it was skipped ("" if it ran).
    seconds : float
        Wall time of the recipe [s].
    plotted : (int, str)
        Fold and name of the held-out recording the report plots.
    """

    folder: Path
    evaluation: RealArmEvaluation | None
    skipped: str = ""
    seconds: float = 0.0
    plotted: tuple[int, str] = (1, "link4.csv second half")

    def summary(self) -> pd.DataFrame | None:
        """Per family: judged held-out seconds, false alarms, rate [1/h] with its 95 % interval."""
        if self.evaluation is None:
            return None
        columns = ["held-out [s]", "false alarms", "per hour", "95 % low", "95 % high"]
        return self.evaluation.summary()[[*columns, "at contacts"]]

    def report_items(self) -> list[Any]:
        """Text, table and plot of the report's section (only the reason if skipped)."""
        if self.evaluation is None:
            return [f"Skipped: {self.skipped}"]
        return [
            "Four recordings of a real UR10 (ext_observer, 100 Hz, measured velocity, motor "
            "currents × UR's gains), without labels. Per fold, a torque offset and Coulomb + "
            "viscous friction are identified on one half of link4.csv, each family is tuned "
            "on that half plus the first quarter of ur-static.csv (margin "
            f"{self.evaluation.margin_fraction:.0%} of the constant β per joint), and the "
            "monitor runs over everything else; both folds pooled. Spans that look like a "
            "hand on the arm are set apart: an alarm there counts under 'at contacts', not "
            "as a false alarm. Rates in false alarms per hour with the exact 95 % Poisson "
            f"interval. The recipe took {self.seconds:.1f} s "
            "(examples/ur10_real_arm.py explains it).",
            self.summary(),
            plot_held_out(self.evaluation.held_out(*self.plotted)),
        ]


def real_arm(folder: str | Path = UR10_FOLDER, **options: Any) -> RealArm:
    """The UR10 recipe on ``folder``, or a :class:`RealArm` that says why it was skipped.

    Parameters
    ----------
    folder : str or Path
        Folder of the UR10 recordings (:data:`sensorless.realarm.UR10_FOLDER`,
        relative to the current directory, by default).
    **options
        Keyword options of :func:`sensorless.realarm.evaluate_ur10`.
    """
    path = Path(folder)
    missing = missing_files(path)
    if missing:
        where = "is not a folder" if not path.is_dir() else f"lacks {missing}"
        reason = (
            f"{path} {where}: the real UR10 recordings (ext_observer) are not there. "
            "Give their folder with --real-data PATH."
        )
        return RealArm(path, None, reason)
    start = time.perf_counter()
    evaluation = evaluate_ur10(path, **options)
    return RealArm(path, evaluation, seconds=time.perf_counter() - start)
