"""Cross-validated false alarms of threshold families on real recordings.

Per :class:`Fold`: the nominal model's correction (offset and friction,
:func:`~sensorless.identification.identify_correction`) is identified on
the fold's identification recordings, every family is tuned with
:func:`~sensorless.monitor.tune` on its tuning recordings (the offset taken
off), and a :class:`~sensorless.monitor.CollisionMonitor` runs over each
held-out recording. Apparent contacts are left out of the identification and
tuning data; an alarm at one is counted apart, and the time they cover is
not judged. :func:`evaluate_folds` returns a :class:`RealArmEvaluation`:
the pooled table (:meth:`~RealArmEvaluation.summary`), the per-recording one
(:meth:`~RealArmEvaluation.details`) and, for plots, every held-out
recording's residual, bounds and events (:class:`HeldOutRun`).
Units SI and radians; time along axis 0, arrays of shape (n_samples, n_dof).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from .._validation import FloatArray, check_duration, check_scalar, check_type
from ..evaluation import evaluate
from ..exceptions import InputValueError, UnknownNameError
from ..identification import NominalCorrection, identify_correction
from ..io import Log
from ..monitor import (
    METHOD_NAMES,
    CollisionMonitor,
    MonitorRun,
    ObserverSettings,
    calibration_of,
    poisson_interval,
    tune,
)
from ..robots import RobotModel
from ..signals import Event, ObserverSignals
from ..thresholds import ConstantThreshold, Threshold
from .recordings import DEFAULT_MIN_PIECE, Recording

__all__ = [
    "DEFAULT_FAMILIES",
    "DEFAULT_MARGIN_FRACTION",
    "Fold",
    "FoldResult",
    "HeldOutRun",
    "RealArmEvaluation",
    "Tuned",
    "Verdict",
    "evaluate_folds",
]

DEFAULT_FAMILIES = ("constant", "time-variant", "velocity")
DEFAULT_MARGIN_FRACTION = 0.1
"""Margin of every family as a fraction of the constant β per joint (the demo's recipe)."""

Bounds = tuple[FloatArray, FloatArray]


@dataclass(frozen=True)
class Fold:
    """The recordings of one fold.

    Attributes
    ----------
    identification : tuple of Recording
        The correction (offset, friction) is identified on their clean pieces.
    tuning : tuple of Recording
        The families are tuned on their clean pieces (usually the
        identification recordings and more).
    held_out : tuple of Recording
        Judged by the tuned monitors.
    """

    identification: tuple[Recording, ...]
    tuning: tuple[Recording, ...]
    held_out: tuple[Recording, ...]


@dataclass(frozen=True)
class Tuned:
    """A family tuned in one fold: threshold, settings and the rate ``tune`` expects [1/h]."""

    family: str
    threshold: Threshold
    settings: ObserverSettings
    expected_rate: float


@dataclass(frozen=True)
class Verdict:
    """One family's verdict on one held-out recording.

    Attributes
    ----------
    seconds : float
        Judged collision-free time [s]: not settling, not at an apparent contact.
    false_alarms : list of Event
        Events away from every apparent contact.
    at_contacts : int
        Events at an apparent contact.
    band_sum : ndarray of shape (n_dof,)
        Sum over the judged samples of upper − lower bound [N m].
    n_band : int
        Number of those samples.
    """

    seconds: float
    false_alarms: list[Event]
    at_contacts: int
    band_sum: FloatArray
    n_band: int


@dataclass(frozen=True)
class HeldOutRun:
    """A held-out recording in one fold: what every family's monitor saw and said.

    Attributes
    ----------
    fold : int
        Fold number, from 1.
    name : str
        The recording's name.
    log : Log
        The recording with the fold's offset taken off ``tau_m`` and its
        apparent contacts as collision windows.
    signals : ObserverSignals
        Observer output (every family watches the same residual r̂ [N m]).
    bounds : dict of str to (lower, upper)
        Each family's bounds [N m], arrays of shape (n_samples, n_dof).
    events : dict of str to list of Event
        Each family's events.
    verdicts : dict of str to Verdict
        Each family's counts.
    """

    fold: int
    name: str
    log: Log
    signals: ObserverSignals
    bounds: dict[str, Bounds]
    events: dict[str, list[Event]]
    verdicts: dict[str, Verdict]


@dataclass(frozen=True)
class FoldResult:
    """One fold: its correction, its tuned families and its held-out runs."""

    fold: int
    correction: NominalCorrection
    tuned: list[Tuned]
    held_out: list[HeldOutRun]


@dataclass(frozen=True)
class RealArmEvaluation:
    """The folds of :func:`evaluate_folds` and their tables.

    Attributes
    ----------
    folds : list of FoldResult
    families : tuple of str
    margin_fraction : float
        Margin of every family as a fraction of the constant β per joint.
    """

    folds: list[FoldResult]
    families: tuple[str, ...]
    margin_fraction: float

    def held_out(self, fold: int, name: str) -> HeldOutRun:
        """The held-out run of recording ``name`` in fold ``fold`` (from 1)."""
        for result in self.folds:
            for run in result.held_out if result.fold == fold else ():
                if run.name == name:
                    return run
        known = [(result.fold, run.name) for result in self.folds for run in result.held_out]
        raise UnknownNameError(f"no held-out run {(fold, name)!r}; the runs: {known}")

    def summary(self, *, readable: bool = False) -> pd.DataFrame:
        """Held-out false alarms per family, every fold pooled.

        One row per family (index ``family``): ``held-out [s]`` judged,
        ``false alarms``, ``per hour`` [1/h], the exact 95 % Poisson
        interval ``95 % low``, ``95 % high`` [1/h], ``at contacts`` (alarms
        at an apparent contact), the rate ``tune``'s own cross-validation of
        each fold's tuning data expects (``tune expects, fold k [1/h]``) and
        the mean band width upper − lower per joint (``band j`` [N m]).
        Recordings held out in several folds count in each, and those counts
        are not independent: the interval is then too narrow.

        With ``readable``, numbers are rounded for a person (seconds and
        bands to 0.1, rates to integers), the interval is one column
        ``95 % interval`` ("low-high") and the expected rates one column
        ``tune expects [1/h]`` ("fold 1 / fold 2 ...").
        """
        rows = []
        for family in self.families:
            verdicts = [run.verdicts[family] for result in self.folds for run in result.held_out]
            seconds = sum(v.seconds for v in verdicts)
            alarms = sum(len(v.false_alarms) for v in verdicts)
            hours = seconds / 3600.0
            low, high = poisson_interval(alarms, hours)
            samples = sum(v.n_band for v in verdicts)
            band = np.sum([v.band_sum for v in verdicts], axis=0) / max(samples, 1)
            expected = [t.expected_rate for r in self.folds for t in r.tuned if t.family == family]
            row: dict[str, Any] = {
                "family": family,
                "held-out [s]": seconds,
                "false alarms": alarms,
                "per hour": alarms / hours if hours > 0 else math.nan,
                "95 % low": low,
                "95 % high": high,
                "at contacts": sum(v.at_contacts for v in verdicts),
            }
            for result, rate in zip(self.folds, expected, strict=True):
                row[f"tune expects, fold {result.fold} [1/h]"] = rate
            for j, width in enumerate(band, start=1):
                row[f"band {j}"] = float(width)
            rows.append(_readable(row) if readable else row)
        return pd.DataFrame(rows).set_index("family")

    def details(self) -> pd.DataFrame:
        """Per fold and held-out recording: judged seconds and "false alarms (at contacts)"."""
        rows = []
        for result in self.folds:
            for run in result.held_out:
                row: dict[str, Any] = {"fold": result.fold, "held out": run.name}
                for family, verdict in run.verdicts.items():
                    row["judged [s]"] = round(verdict.seconds, 1)
                    row[family] = f"{len(verdict.false_alarms)} ({verdict.at_contacts})"
                rows.append(row)
        return pd.DataFrame(rows).set_index(["fold", "held out"])


def _readable(row: dict[str, Any]) -> dict[str, Any]:
    """A summary row rounded for a person (see :meth:`RealArmEvaluation.summary`)."""
    expected = [value for key, value in row.items() if key.startswith("tune expects")]
    rate = row["per hour"]
    out: dict[str, Any] = {
        "family": row["family"],
        "held-out [s]": round(row["held-out [s]"], 1),
        "false alarms": row["false alarms"],
        "per hour": round(rate) if math.isfinite(rate) else rate,
        "95 % interval": f"{row['95 % low']:.0f}-{row['95 % high']:.0f}",
        "at contacts": row["at contacts"],
        "tune expects [1/h]": " / ".join(f"{v:.0f}" for v in expected),
    }
    out.update({key: round(value, 1) for key, value in row.items() if key.startswith("band ")})
    return out


def _check_families(families: Any) -> tuple[str, ...]:
    """Momentum-residual families only: the offset is taken off the motor torque they watch."""
    chosen = (families,) if isinstance(families, str) else tuple(families)
    refused = [
        f"{name!r} is no threshold family"
        if name not in METHOD_NAMES
        else f"{name!r} watches the {METHOD_NAMES[name]} residual"
        for name in chosen
        if METHOD_NAMES.get(name) != "motor"
    ]
    if not chosen or refused:
        options = [name for name, kind in METHOD_NAMES.items() if kind == "motor"]
        raise UnknownNameError(
            f"families must be a non-empty sequence of {options} (they watch the motor "
            f"residual r̂ the offset correction applies to); got {list(chosen)!r}: "
            f"{'; '.join(refused) or 'none given'}"
        )
    return chosen


def tune_families(
    logs: Sequence[Log], robot: RobotModel, families: Sequence[str], margin_fraction: float
) -> list[Tuned]:
    """Every family tuned on ``logs`` with the margin ``margin_fraction`` × constant β per joint.

    The time-variant and hysteretic families use the demo's minimax fit
    (as :func:`sensorless.comparison.compare`).
    """
    base, _ = tune(logs, robot, "constant", folds=None, margin=0.0)
    assert isinstance(base, ConstantThreshold)  # what tune's "constant" makes
    margin = margin_fraction * base.beta_
    tuned = []
    for family in families:
        options: dict[str, Any] = {}
        if family in ("time-variant", "hysteretic"):
            options["fit_method"] = "minimax"
        threshold, settings = tune(logs, robot, family, margin=margin, **options)
        calibration = calibration_of(threshold)
        rate = math.nan if calibration is None else calibration.rate
        tuned.append(Tuned(family, threshold, settings, rate))
    return tuned


def judge(
    tuned: Tuned, robot: RobotModel, recording: Recording
) -> tuple[Verdict, MonitorRun, Bounds]:
    """Run the monitor of ``tuned`` over a held-out recording (offset already taken off).

    An event that meets an apparent contact, or starts within the scoring's
    ``max_delay`` after it, is "at the contact"
    (:func:`~sensorless.evaluation.evaluate`); the same spans are left out of
    the judged time.
    """
    monitor = CollisionMonitor(robot, tuned.threshold, tuned.settings)
    run = monitor.process(recording.log)
    if run.faults:
        raise InputValueError(
            f"{recording.name}: the monitor refused samples at "
            f"{[(f.start, f.end, f.reason) for f in run.faults]}; a held-out recording must be "
            "monitored from end to end"
        )
    scoring = evaluate(run.events, recording.labelled(), method=tuned.family)
    lower, upper = tuned.threshold.bounds(run.signals)
    t = run.signals.t
    judged = ~run.settling
    for start, stop in recording.contacts:
        judged &= (t < start) | (t > stop + scoring.max_delay)
    verdict = Verdict(
        seconds=float(judged.sum() * recording.log.dt),
        false_alarms=list(scoring.false_alarms),
        at_contacts=len(run.events) - len(scoring.false_alarms),
        band_sum=np.sum((upper - lower)[judged], axis=0),
        n_band=int(judged.sum()),
    )
    return verdict, run, (lower, upper)


def _held_out(
    fold: int, tuned: Sequence[Tuned], model: RobotModel, recording: Recording
) -> HeldOutRun:
    runs = {t.family: judge(t, model, recording) for t in tuned}
    # Every family watches the same residual (the motor observer of tune's settings).
    signals = next(iter(runs.values()))[1].signals
    return HeldOutRun(
        fold,
        recording.name,
        recording.labelled(),
        signals,
        bounds={family: found[2] for family, found in runs.items()},
        events={family: found[1].events for family, found in runs.items()},
        verdicts={family: found[0] for family, found in runs.items()},
    )


def evaluate_folds(
    folds: Sequence[Fold],
    robot: RobotModel,
    *,
    families: Sequence[str] = DEFAULT_FAMILIES,
    margin_fraction: float = DEFAULT_MARGIN_FRACTION,
    min_piece: float = DEFAULT_MIN_PIECE,
) -> RealArmEvaluation:
    """Identify, tune and judge every fold (module docstring).

    Parameters
    ----------
    folds : sequence of Fold
        The recordings of every fold; logs with ``q`` [rad], measured ``qd``
        [rad/s] and ``tau_m`` [N m], time along axis 0.
    robot : RobotModel
        The rigid-body nominal model (its friction is replaced by each
        fold's identified one).
    families : sequence of str
        Threshold families that watch the momentum residual r̂ (``constant``,
        ``time-variant``, ``hysteretic``, ``velocity``).
    margin_fraction : float
        Margin of every family as a fraction of the constant β per joint of
        the same tuning data [-].
    min_piece : float
        Shortest clean stretch [s] between apparent contacts used for
        identification and tuning.

    Returns
    -------
    RealArmEvaluation

    Raises
    ------
    InputValueError
        No folds, a fold without recordings of each kind, a held-out
        recording the monitor refuses samples of, or a bad setting.
    UnknownNameError
        A family that does not watch r̂.
    """
    chosen = _check_families(families)
    fraction = check_scalar(margin_fraction, "margin_fraction", "-", "nonnegative")
    shortest = check_duration(min_piece, "min_piece")
    check_type(robot, RobotModel, "robot")
    if not folds:
        raise InputValueError("evaluate_folds needs at least one fold; got none")
    results = []
    for number, fold in enumerate(folds, start=1):
        check_type(fold, Fold, f"folds[{number - 1}]")
        if not (fold.identification and fold.tuning and fold.held_out):
            raise InputValueError(
                f"folds[{number - 1}] needs identification, tuning and held-out recordings; "
                f"got {len(fold.identification)}, {len(fold.tuning)}, {len(fold.held_out)}"
            )
        clean = [log for r in fold.identification for log in r.clean_pieces(shortest)]
        correction = identify_correction(clean, robot)
        model = correction.model(robot)
        pieces = [log for r in fold.tuning for log in r.clean_pieces(shortest)]
        tuned = tune_families([correction.apply(log) for log in pieces], model, chosen, fraction)
        held_out = [
            _held_out(number, tuned, model, dataclasses.replace(r, log=correction.apply(r.log)))
            for r in fold.held_out
        ]
        results.append(FoldResult(number, correction, tuned, held_out))
    return RealArmEvaluation(results, chosen, fraction)
