"""Calibration: the false-alarm rate a tuned threshold will have, measured on held-out runs.

A threshold fitted on collision-free runs bounds exactly those runs; how often
it raises a false alarm on the next run is a different question, and the
only honest answer comes from data the fit did not see. :func:`cross_validate`
cuts the collision-free runs into folds (one fold per run, or contiguous time
blocks of one long run), fits the threshold on all folds but one, counts the
:class:`~sensorless.detection.Detector` events on the fold held out, and
reports false alarms per hour with an exact Poisson interval, the
collision-free hours used, the counts per fold, and warnings when the data
cannot support the figure. :func:`margin_for_rate` (:mod:`.rate_margin`)
chooses the margin for a stated rate. The result is a :class:`Calibration`;
:func:`~sensorless.monitor.tune` attaches it to the threshold it fits
(:func:`calibration_of`), and :func:`~sensorless.monitor.save_tuned` writes
it to the YAML file next to the threshold.

Every fold is a *piece* of a run treated as a run of its own: its first
``transient`` seconds (the threshold's hyper-parameter) are neither fitted
nor judged, as the live monitor does not judge its settling either. Each
fold's threshold is fitted on a fraction (k−1)/k of the data, so its band is
slightly narrower than that of the threshold fitted on all runs: the
cross-validated rate leans to the pessimistic side, the more so the fewer the
folds. When the margin was chosen for a stated rate (:func:`margin_for_rate`),
it was chosen on the same held-out folds: the cross-validated count at that
margin is then a consistency check, not an independent test; only runs kept
out of tuning altogether give that. Units SI and radians; time along axis 0;
rates per hour.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from .._validation import FloatArray, check_scalar
from ..detection import Detector
from ..exceptions import InputTypeError, InputValueError
from ..signals import ObserverSignals
from ..thresholds import Threshold
from ..thresholds.checks import check_joints
from ..thresholds.files import family_name
from ..thresholds.velocity_bins import MIN_BIN_TIME
from ._heldout import (
    DEFAULT_HOLD,
    DEFAULT_MIN_DURATION,
    check_calibration_inputs,
    copy_threshold,
    format_hours,
    format_rate,
    held_out_pieces,
    hours_needed,
    poisson_interval,
)
from .rate_margin import RateMargin, margin_for_rate

__all__ = [
    "DEFAULT_HOLD",
    "DEFAULT_MIN_DURATION",
    "SHORT_HOURS",
    "Calibration",
    "RateMargin",
    "attach_calibration",
    "calibration_of",
    "cross_validate",
    "data_warnings",
    "hours_needed",
    "margin_for_rate",
    "poisson_interval",
    "with_stated",
]

SHORT_HOURS = 10.0 / 60.0
"""Collision-free time [h] below which a per-hour figure rests on a handful of motions."""
STILL_VELOCITY = 0.02
"""Speed [rad/s] below which a joint counts as still (in 99 % of its samples)."""

_ATTRIBUTE = "calibration_"


@dataclass(frozen=True)
class Calibration:
    """Cross-validated false alarms of a threshold family on collision-free runs.

    Attributes
    ----------
    method : str
        Name of the threshold family.
    scheme : {"runs", "blocks"}
        Folds of whole runs, or contiguous time blocks of one run.
    fold_labels : tuple of str
        What each fold held out ("run 2", "block 1 of 2").
    fold_events : tuple of int
        False-alarm events on each held-out fold.
    fold_hours : tuple of float
        Judged collision-free time of each held-out fold [h].
    min_duration, hold : float
        Detector settings the events were counted with [s].
    confidence : float
        Level of the intervals.
    warnings : tuple of str
        Why the data may not support the figure.
    target_rate : float or None
        Stated false-alarm rate [1/h], if any.
    stated : RateMargin or None
        The margin chosen for ``target_rate`` (:func:`margin_for_rate`).
    """

    method: str
    scheme: str
    fold_labels: tuple[str, ...]
    fold_events: tuple[int, ...]
    fold_hours: tuple[float, ...]
    min_duration: float
    hold: float
    confidence: float
    warnings: tuple[str, ...] = ()
    target_rate: float | None = None
    stated: RateMargin | None = None

    @property
    def events(self) -> int:
        """False-alarm events over all held-out folds."""
        return int(sum(self.fold_events))

    @property
    def hours(self) -> float:
        """Collision-free time judged over all held-out folds [h]."""
        return float(sum(self.fold_hours))

    @property
    def rate(self) -> float:
        """False alarms per hour (NaN without data) [1/h]."""
        return self.events / self.hours if self.hours > 0 else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        """Exact Poisson confidence interval of :attr:`rate` [1/h]."""
        return poisson_interval(self.events, self.hours, self.confidence)

    def summary(self) -> list[str]:
        """Lines for a person: the rate and its interval, the stated rate, the warnings."""
        lower, upper = self.interval
        lines = [
            f"false alarms: {format_rate(self.rate)} /h ({100 * self.confidence:g} % interval "
            f"{format_rate(lower)}–{format_rate(upper)} /h), cross-validated over "
            f"{format_hours(self.hours)} of collision-free motion ({len(self.fold_events)} folds "
            f"by {self.scheme[:-1]}, {self.events} event(s))"
        ]
        if self.stated is not None:
            lines.append(self.stated.describe())
        lines.extend(f"warning: {text}" for text in self.warnings)
        return lines

    def to_pandas(self) -> pd.DataFrame:
        """One row per fold: what it held out, hours, events and events per hour."""
        hours = np.asarray(self.fold_hours, dtype=float)
        events = np.asarray(self.fold_events, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = np.where(hours > 0, events / hours, np.nan)
        return pd.DataFrame(
            {"held_out": list(self.fold_labels), "hours": hours, "events": events, "rate": rate}
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain values for a YAML file (rate and interval included for the reader)."""
        lower, upper = self.interval
        return {
            "method": self.method,
            "false_alarms_per_hour": self.rate,
            "interval_per_hour": [lower, upper],
            "confidence": self.confidence,
            "collision_free_hours": self.hours,
            "folds": self.scheme,
            "fold_labels": list(self.fold_labels),
            "fold_events": list(self.fold_events),
            "fold_hours": list(self.fold_hours),
            "min_duration": self.min_duration,
            "hold": self.hold,
            "warnings": list(self.warnings),
            "target_rate": self.target_rate,
            "stated": None if self.stated is None else self.stated.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Calibration:
        """Inverse of :meth:`to_dict`; the derived figures are recomputed from the counts."""
        if not isinstance(data, Mapping):
            raise InputValueError(f"a calibration must be a mapping; got {type(data).__name__}")
        try:
            stated = data.get("stated")
            target = data.get("target_rate")
            calibration = cls(
                method=str(data["method"]),
                scheme=str(data["folds"]),
                fold_labels=tuple(str(v) for v in data["fold_labels"]),
                fold_events=tuple(int(v) for v in data["fold_events"]),
                fold_hours=tuple(float(v) for v in data["fold_hours"]),
                min_duration=float(data["min_duration"]),
                hold=float(data["hold"]),
                confidence=float(data["confidence"]),
                warnings=tuple(str(v) for v in data.get("warnings", ())),
                target_rate=None if target is None else float(target),
                stated=None if stated is None else RateMargin.from_dict(stated),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise InputValueError(f"not a calibration description: {exc!r}") from None
        sizes = {len(calibration.fold_labels), len(calibration.fold_events)}
        if sizes != {len(calibration.fold_hours)}:
            raise InputValueError("a calibration needs one label, count and duration per fold")
        return calibration


def calibration_of(threshold: Threshold) -> Calibration | None:
    """The :class:`Calibration` :func:`~sensorless.monitor.tune` attached, or None."""
    value = getattr(threshold, _ATTRIBUTE, None)
    return value if isinstance(value, Calibration) else None


def attach_calibration(threshold: Threshold, calibration: Calibration) -> Threshold:
    """Record ``calibration`` as the fitted threshold's ``calibration_`` and return it.

    Part of tuning, like the attributes ``fit`` learns: the calibration then
    travels with the threshold through :func:`~sensorless.monitor.save_tuned`.
    """
    if not isinstance(calibration, Calibration):
        raise InputTypeError(f"calibration must be a Calibration; got {type(calibration).__name__}")
    threshold._check_fitted()
    setattr(threshold, _ATTRIBUTE, calibration)
    return threshold


def cross_validate(
    signals: ObserverSignals | Sequence[ObserverSignals],
    threshold: Threshold,
    *,
    folds: str | int = "runs",
    min_duration: float = DEFAULT_MIN_DURATION,
    hold: float = DEFAULT_HOLD,
    confidence: float = 0.95,
    target_rate: float | None = None,
) -> Calibration:
    """False alarms per hour of a threshold family, cross-validated on collision-free runs.

    Parameters
    ----------
    signals : ObserverSignals or sequence of ObserverSignals
        Collision-free runs of one robot, signal kind and observer gain.
    threshold : Threshold
        The family and its hyper-parameters (``margin``, ``transient``, ...);
        it is copied for every fold, never changed. When it is fitted (on
        the same runs), the sparse-bin check reads its velocity table.
    folds : "runs" or int
        "runs": every run is held out once (one run: two time blocks); an
        int k ≥ 2: k folds of consecutive runs, or k time blocks of one run.
    min_duration, hold : float
        Detector settings [s], as the monitor will use them.
    confidence : float
        Level of the Poisson interval.
    target_rate : float, optional
        A rate the user wants to check [1/h]: a warning says when the data
        are too short for it.

    Returns
    -------
    Calibration
        Without any fold that outlasts the transient, a calibration of no
        hours whose warning says so.
    """
    runs, min_duration, hold, level = check_calibration_inputs(
        signals, threshold, min_duration, hold, confidence
    )
    target = None if target_rate is None else check_scalar(target_rate, "target_rate", "1/h")
    scheme, labels, pieces = held_out_pieces(runs, folds, threshold)
    counts: list[int] = []
    hours: list[float] = []
    for k, judged in enumerate(pieces.judged):
        if not (judged and pieces.trainable(k)):
            counts.append(0)
            hours.append(0.0)
            continue
        fitted = copy_threshold(threshold).fit(pieces.training(k))
        detector = Detector(fitted, min_duration=min_duration, hold=hold)
        counts.append(sum(len(detector.detect(piece)) for piece in judged))
        hours.append(sum(piece.n_samples * piece.dt for piece in judged) / 3600.0)
    warnings = data_warnings(runs, threshold, sum(hours), level, target, pieces.transient)
    return Calibration(
        family_name(threshold), scheme, labels, tuple(counts), tuple(hours), min_duration, hold,
        level, tuple(warnings), target,
    )  # fmt: skip


def data_warnings(
    runs: list[ObserverSignals],
    threshold: Threshold,
    hours: float,
    confidence: float,
    target_rate: float | None,
    transient: float,
) -> list[str]:
    """Why collision-free data may not support a false-alarm figure (checked inputs).

    Too little time for the stated rate (or under :data:`SHORT_HOURS`),
    monitored joints that never moved, and, for the velocity family, velocity
    bins with less than the threshold's ``min_bin_time`` of fit data (pooled). ``hours`` is the
    judged time [h], ``transient`` [s] the start of every run left out.
    """
    warnings = []
    if hours == 0.0:
        warnings.append(
            f"no fold outlasts the transient of {transient:g} s: nothing was cross-validated; "
            "record longer collision-free runs"
        )
    elif target_rate is not None and hours < hours_needed(target_rate, confidence):
        warnings.append(
            f"{format_hours(hours)} of collision-free data cannot confirm "
            f"{format_rate(target_rate)} false alarms/h: that needs "
            f"{format_hours(hours_needed(target_rate, confidence))} without a false alarm "
            f"({100 * confidence:g} % confidence); until then the stated rate is extrapolated"
        )
    elif target_rate is None and hours < SHORT_HOURS:
        upper = poisson_interval(0, hours, confidence)[1]
        warnings.append(
            f"only {format_hours(hours)} of collision-free data: even without a false alarm "
            f"they would bound the rate only below {format_rate(upper)} /h; confirming 1 /h "
            f"needs {format_hours(hours_needed(1.0, confidence))}"
        )
    kept = [run.velocity[run.t - run.t[0] >= transient] for run in runs]
    if not any(v.size for v in kept):
        return warnings
    velocity = np.concatenate(kept)
    joints = check_joints(threshold.joints, runs[0].n_dof)
    still = [j for j in joints if np.quantile(np.abs(velocity[:, j - 1]), 0.99) < STILL_VELOCITY]
    if still:
        warnings.append(
            f"joint(s) {', '.join(map(str, still))} never moved (|q̇| < {STILL_VELOCITY:g} rad/s "
            "in 99 % of the samples): the figure says nothing of their false alarms in motion"
        )
    sparse = _sparse_bins(runs, threshold, velocity, joints)
    if sparse:
        warnings.append(
            f"velocity bins with less than {_min_bin_time(threshold):g} s of fit data: "
            f"{'; '.join(sparse)}; their L and U are pooled with neighbouring bins "
            "(min_bin_time)"
        )
    return warnings


def _min_bin_time(threshold: Threshold) -> float:
    """The threshold's own ``min_bin_time`` [s], or the velocity family's default."""
    return float(getattr(threshold, "min_bin_time", MIN_BIN_TIME))


def _sparse_bins(
    runs: list[ObserverSignals],
    threshold: Threshold,
    velocity: FloatArray,
    joints: tuple[int, ...],
) -> list[str]:
    """Per joint, "joint j: n of m bins": the sparse bins of the velocity family."""
    if hasattr(threshold, "counts_"):
        counts = np.asarray(threshold.counts_)
    elif hasattr(threshold, "bin_width"):
        width = check_scalar(threshold.bin_width, "bin_width", "rad/s")
        first = math.floor(float(velocity.min()) / width)
        last = math.floor(float(velocity.max()) / width)
        edges = np.arange(first, last + 2, dtype=float) * width
        counts = np.stack(
            [np.histogram(velocity[:, j], edges)[0] for j in range(velocity.shape[1])], axis=1
        )
    else:
        return []
    period = float(np.median(np.concatenate([np.diff(run.t) for run in runs])))
    least = _min_bin_time(threshold) / period
    found = []
    for j in joints:
        visited = np.flatnonzero(counts[:, j - 1] > 0)
        span = counts[visited[0] : visited[-1] + 1, j - 1] if visited.size else visited
        sparse = int(np.count_nonzero(span < least))
        if sparse:
            found.append(f"joint {j}: {sparse} of {span.size}")
    return found


def with_stated(calibration: Calibration, stated: RateMargin) -> Calibration:
    """``calibration`` with the margin chosen for its stated rate."""
    return dataclasses.replace(calibration, stated=stated, target_rate=stated.rate)
