"""The margin for a stated false-alarm rate, from the tail of held-out excursions.

:func:`margin_for_rate` answers "how wide must the band be for at most λ
false alarms per hour?" (issue 13, item 1) for any threshold family whose
``margin`` widens both bounds by the same amount (all of them). It

1. fits the family's shape with margin 0 on all folds but one
   (:mod:`._heldout`) and computes, on the fold held out, the *excursion*
   e_j(t) = max(r̂_j − upper_j, lower_j − r̂_j) beyond that zero-margin band
   (negative inside it). A margin m raises an alarm on joint j wherever
   e_j > m, so every margin's false alarms follow from one set of fits.
2. turns e_j into the *alarm level* a_j(t), the largest margin at which an
   event starting at t would still be reported: with the detector's
   ``min_duration`` and ``hold``, an event needs a second sample beyond the
   margin at least ``min_duration`` and less than ``hold`` later (or, when
   ``hold`` is too short for that, ``min_duration`` of consecutive samples).
3. declusters a_j with the detector's own rule (exceedances less than
   ``hold`` apart are one) and keeps the peaks of the clusters above a high
   level u_j: the largest ``peaks`` clusters or more.
4. fits a generalized Pareto distribution (GPD) to the excesses of these
   peaks over u_j. Clusters above u_j arrive at λ_u = n_u/T per hour, so the
   rate of alarms at margin m ≥ u_j is λ_u · S(m − u_j), S the GPD survival
   function (scipy.stats.genpareto); the margin is its inverse at the rate.

**Why peaks over a threshold (GPD) and not block maxima (GEV).** A user has
minutes of collision-free data, not days: block maxima keep one value per
block, peaks over a threshold keep every large excursion. The clusters above
a level arrive as a Poisson process whose rate *is* the false-alarm rate, so
no block length has to be chosen and no block probability converted; and
the clusters are grouped by the detector's own ``hold``, so at the observed
levels their count equals the detector's count. The GPD is fitted by
probability-weighted moments (Hosking & Wallis 1987, Technometrics 29:339):
a closed form, with no optimiser that can fail, and less biased than
maximum likelihood on a few dozen peaks when the shape ξ is below 1/2 (light
or moderately heavy tails, as residual noise has).

The stated rate is per robot: it is split equally between the monitored
joints (λ/n each), so joints that alarm together make the actual rate lower
than stated, never higher. Each fold's zero-margin band comes from
(k−1)/k of the data; the threshold refitted on all runs is a little wider,
which also errs on the safe side. The predicted rate comes with a seeded
parametric-bootstrap interval: the count above u_j is redrawn from a Poisson
law, the excesses from the fitted GPD, the GPD refitted, and the rate at the
chosen margin recomputed. Units SI and radians; rates per hour.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import stats

from .._validation import FloatArray, check_int, check_scalar
from ..exceptions import InputValueError
from ..signals import ObserverSignals
from ..thresholds import Threshold
from ..thresholds.checks import check_joints
from ._heldout import (
    DEFAULT_HOLD,
    DEFAULT_MIN_DURATION,
    check_calibration_inputs,
    copy_threshold,
    format_hours,
    format_rate,
    held_out_pieces,
    hours_needed,
)

__all__ = ["MIN_PEAKS", "RateMargin", "alarm_level", "cluster_peaks", "margin_for_rate"]

MIN_PEAKS = 10
"""Fewest cluster peaks a GPD is fitted to."""

Segment = tuple[FloatArray, float]
"""Alarm levels of one joint over one held-out piece [N m] and its sample period [s]."""


@dataclass(frozen=True)
class RateMargin:
    """The margin chosen for a stated false-alarm rate (:func:`margin_for_rate`).

    Attributes
    ----------
    rate : float
        Stated false alarms per hour, for the whole robot [1/h].
    margin : tuple of float
        Margin per joint [N m] (0 for joints not monitored).
    predicted : float
        False alarms per hour the tail model predicts at ``margin`` [1/h]:
        ``rate`` unless the zero-margin band already meets it.
    interval : tuple of float
        Parametric-bootstrap interval of ``predicted`` [1/h].
    confidence : float
        Level of ``interval``.
    hours : float
        Held-out collision-free time the tail was fitted on [h].
    joints : tuple of int
        Monitored joints (1-based), one tail each.
    level : tuple of float
        Level u_j above which cluster peaks were kept [N m], per monitored joint.
    shape, scale : tuple of float
        GPD shape ξ_j [-] and scale σ_j [N m], per monitored joint.
    peaks : tuple of int
        Cluster peaks above u_j, per monitored joint.
    """

    rate: float
    margin: tuple[float, ...]
    predicted: float
    interval: tuple[float, float]
    confidence: float
    hours: float
    joints: tuple[int, ...]
    level: tuple[float, ...]
    shape: tuple[float, ...]
    scale: tuple[float, ...]
    peaks: tuple[int, ...]

    @property
    def hours_needed(self) -> float:
        """Collision-free time [h] in which zero false alarms would confirm ``rate``."""
        return hours_needed(self.rate, self.confidence)

    def describe(self) -> str:
        """One line for a person."""
        margin = ", ".join(f"{m:.3g}" for m in self.margin)
        lower, upper = self.interval
        return (
            f"stated rate {format_rate(self.rate)} /h: margin [{margin}] N m, predicted "
            f"{format_rate(self.predicted)} /h ({100 * self.confidence:g} % interval "
            f"{format_rate(lower)}–{format_rate(upper)} /h) from {format_hours(self.hours)} of "
            f"held-out excursions; confirming it needs {format_hours(self.hours_needed)} of "
            "collision-free motion without a false alarm"
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain values for a YAML file."""
        return {
            "rate": self.rate,
            "margin": list(self.margin),
            "predicted": self.predicted,
            "interval": list(self.interval),
            "confidence": self.confidence,
            "hours": self.hours,
            "hours_needed": self.hours_needed,
            "joints": list(self.joints),
            "level": list(self.level),
            "shape": list(self.shape),
            "scale": list(self.scale),
            "peaks": list(self.peaks),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RateMargin:
        """Inverse of :meth:`to_dict` (``hours_needed`` is recomputed)."""

        def floats(key: str) -> tuple[float, ...]:
            return tuple(float(v) for v in data[key])

        lower, upper = floats("interval")
        return cls(
            rate=float(data["rate"]),
            margin=floats("margin"),
            predicted=float(data["predicted"]),
            interval=(lower, upper),
            confidence=float(data["confidence"]),
            hours=float(data["hours"]),
            joints=tuple(int(v) for v in data["joints"]),
            level=floats("level"),
            shape=floats("shape"),
            scale=floats("scale"),
            peaks=tuple(int(v) for v in data["peaks"]),
        )


def alarm_level(excursion: FloatArray, dt: float, min_duration: float, hold: float) -> FloatArray:
    """Largest margin at which an event starting at each sample is reported [N m].

    At a margin m, the detector sees the samples whose excursion exceeds m,
    joins two of them less than ``hold`` apart into one event and reports
    the events lasting at least ``min_duration``. In level terms that is a
    morphological closing of the excursion (every sample gets the best level
    of a pair of samples less than ``hold`` apart around it) followed by a
    running minimum over ``min_duration``: an event starts at t for every
    margin below the result at t, exactly. A duration that is a whole
    number of samples is reached (``min_duration``) or not (``hold``) as
    counted in samples, where the detector's subtraction of float times may
    go either way: such ties count as alarms, never fewer.

    Parameters
    ----------
    excursion : ndarray of shape (n_samples, n_dof)
        Residual beyond the zero-margin band [N m] (negative inside).
    dt : float
        Sample period [s].
    min_duration, hold : float
        Detector settings [s].

    Returns
    -------
    ndarray of shape (n_samples − k, n_dof)
        With k = ⌈min_duration/dt⌉: the last k samples cannot start an event.
    """
    n = excursion.shape[0]
    first = math.ceil(min_duration / dt - 1e-9)
    reach = max(1, math.ceil(hold / dt - 1e-9) - 1)
    closed = excursion
    if reach > 1:
        floor = np.full((reach, excursion.shape[1]), -np.inf)
        ahead = np.concatenate([excursion, floor])
        behind = np.concatenate([floor, excursion])
        later = excursion.copy()  # the best sample from t to t + width
        closed = excursion.copy()
        for width in range(reach + 1):
            if width:
                later = np.maximum(later, ahead[width : width + n])
            earlier = behind[width : width + n]  # pairs (t - (reach - width), t + width)
            closed = np.maximum(closed, np.minimum(earlier, later))
    if first == 0:
        return closed
    if n <= first:
        return closed[:0]
    return np.asarray(sliding_window_view(closed, first + 1, axis=0).min(axis=-1))


def cluster_peaks(level: FloatArray, above: float, dt: float, hold: float) -> FloatArray:
    """Peaks of the clusters of ``level > above``; exceedances less than ``hold`` apart are one.

    ``level`` has shape (n_samples,); the detector merges two events whose
    gap (start of the second minus end of the first) is shorter than ``hold``.
    """
    index = np.flatnonzero(level > above)
    if index.size == 0:
        return np.zeros(0)
    gaps = np.diff(index)
    starts = np.concatenate([[0], np.flatnonzero((gaps > 1) & (gaps * dt >= hold)) + 1])
    return np.asarray(np.maximum.reduceat(level[index], starts))


def _gpd_pwm(excess: FloatArray) -> tuple[float, float]:
    """GPD shape ξ and scale σ by probability-weighted moments (Hosking & Wallis 1987).

    NaN when the sample has no tail to fit (all equal).
    """
    x = np.sort(excess)
    n = x.size
    a0 = float(x.mean())
    a1 = float(np.mean((1.0 - (np.arange(1, n + 1) - 0.35) / n) * x))
    denominator = a0 - 2.0 * a1
    if not denominator > 0.0 or not a1 > 0.0:
        return math.nan, math.nan
    return 2.0 - a0 / denominator, 2.0 * a0 * a1 / denominator


@dataclass(frozen=True)
class _Tail:
    """The tail of one joint's alarm levels over all held-out pieces."""

    hours: float
    level: float
    count: int
    shape: float
    scale: float

    @classmethod
    def fit(cls, segments: list[Segment], hold: float, hours: float, wanted: int) -> _Tail:
        """Highest level u with ``wanted`` cluster peaks above it; else the level with most."""
        values = np.sort(np.concatenate([s for s, _ in segments]))[::-1]
        values = values[np.isfinite(values)]
        best = (math.inf, np.zeros(0))
        factor = 1.0
        while values.size:
            rank = min(values.size - 1, math.ceil(wanted * factor))
            level = float(values[rank])
            peaks = np.concatenate([cluster_peaks(s, level, dt, hold) for s, dt in segments])
            if peaks.size > best[1].size:
                best = (level, peaks)
            if peaks.size >= wanted or rank == values.size - 1:
                break
            factor *= 1.25
        level, peaks = best
        shape, scale = _gpd_pwm(peaks - level) if peaks.size >= MIN_PEAKS else (math.nan,) * 2
        return cls(hours, level, int(peaks.size), shape, scale)

    def rate(
        self, margin: float, shape: float | None = None, scale: float = 0.0, count: int = 0
    ) -> float:
        """Clusters per hour above ``margin`` ≥ u [1/h]; by default for the fitted tail."""
        if shape is None:
            shape, scale, count = self.shape, self.scale, self.count
        return count / self.hours * float(stats.genpareto.sf(margin - self.level, shape, 0, scale))

    def margin(self, rate: float) -> float:
        """Margin ≥ max(u, 0) [N m] at which the tail gives ``rate`` clusters per hour."""
        ratio = min(1.0, rate * self.hours / self.count)
        excess = float(stats.genpareto.isf(ratio, self.shape, 0, self.scale))
        return max(0.0, self.level + excess)

    def resample(self, margin: float, rng: np.random.Generator, n: int) -> FloatArray:
        """Parametric-bootstrap rates at ``margin`` [1/h], ``n`` replicates."""
        out = np.empty(n)
        for b in range(n):
            count = int(rng.poisson(self.count))
            excess = stats.genpareto.isf(rng.random(count), self.shape, 0, self.scale)
            shape, scale = _gpd_pwm(excess) if count >= MIN_PEAKS else (self.shape, self.scale)
            out[b] = self.rate(margin, shape, scale, count) if math.isfinite(scale) else math.nan
        return out


def margin_for_rate(
    signals: ObserverSignals | Sequence[ObserverSignals],
    threshold: Threshold,
    rate: float,
    *,
    folds: str | int = "runs",
    min_duration: float = DEFAULT_MIN_DURATION,
    hold: float = DEFAULT_HOLD,
    confidence: float = 0.95,
    peaks: int = 50,
    resamples: int = 200,
    seed: int = 0,
) -> RateMargin:
    """Margin per joint for a stated false-alarm rate, from held-out excursions (module doc).

    Parameters
    ----------
    signals : ObserverSignals or sequence of ObserverSignals
        Collision-free runs of one robot, signal kind and observer gain.
    threshold : Threshold
        The family and its hyper-parameters; its ``margin`` is ignored (the
        shape is fitted with margin 0). Copied, never changed.
    rate : float
        Stated false alarms per hour for the robot [1/h], > 0.
    folds : "runs" or int
        As for :func:`~sensorless.monitor.cross_validate`.
    min_duration, hold : float
        Detector settings [s], as the monitor will use them.
    confidence : float
        Level of the bootstrap interval.
    peaks : int
        Cluster peaks per joint the GPD is fitted to, at least (≥ 10).
    resamples : int
        Bootstrap replicates (≥ 10).
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    RateMargin

    Raises
    ------
    InputValueError
        No fold outlasts the transient, or a joint has fewer than
        :data:`MIN_PEAKS` excursion clusters to fit.
    """
    runs, min_duration, hold, level = check_calibration_inputs(
        signals, threshold, min_duration, hold, confidence
    )
    stated = check_scalar(rate, "false_alarm_rate", "1/h")
    wanted = check_int(peaks, "peaks", MIN_PEAKS, "margin_for_rate")
    replicates = check_int(resamples, "resamples", 10, "margin_for_rate")
    joints = check_joints(threshold.joints, runs[0].n_dof)
    segments, hours = _excursions(runs, threshold, folds, min_duration, hold)
    share = stated / len(joints)
    tails = []
    for j in joints:
        column = [(s[:, j - 1], dt) for s, dt in segments]
        tail = _Tail.fit(column, hold, hours, max(wanted, math.ceil(2 * share * hours)))
        if not math.isfinite(tail.scale):
            raise InputValueError(
                f"joint {j}: {tail.count} excursion cluster(s) in {format_hours(hours)} of "
                f"held-out data, too few or too alike to fit a tail (at least {MIN_PEAKS}); "
                "record more collision-free motion"
            )
        tails.append(tail)
    margins = [tail.margin(share) for tail in tails]
    predicted = sum(tail.rate(m) for tail, m in zip(tails, margins, strict=True))
    rng = np.random.default_rng(seed)
    draws = sum(
        (tail.resample(m, rng, replicates) for tail, m in zip(tails, margins, strict=True)),
        np.zeros(replicates),
    )
    alpha = 1.0 - level
    lower, upper = np.nanquantile(draws, [alpha / 2, 1 - alpha / 2])
    margin = np.zeros(runs[0].n_dof)
    margin[np.asarray(joints) - 1] = margins
    return RateMargin(
        rate=stated,
        margin=tuple(float(m) for m in margin),
        predicted=predicted,
        interval=(float(lower), float(upper)),
        confidence=level,
        hours=hours,
        joints=joints,
        level=tuple(t.level for t in tails),
        shape=tuple(t.shape for t in tails),
        scale=tuple(t.scale for t in tails),
        peaks=tuple(t.count for t in tails),
    )


def _excursions(
    runs: list[ObserverSignals], threshold: Threshold, folds: Any, min_duration: float, hold: float
) -> tuple[list[Segment], float]:
    """Alarm levels of every held-out piece beyond its fold's zero-margin band, and the hours."""
    _, _, pieces = held_out_pieces(runs, folds, threshold)
    zero = copy_threshold(threshold, margin=0.0)
    segments = []
    hours = 0.0
    for k, judged in enumerate(pieces.judged):
        if not (judged and pieces.trainable(k)):
            continue
        fitted = copy_threshold(zero).fit(pieces.training(k))
        for piece in judged:
            lower, upper = fitted.bounds(piece)
            excursion = np.maximum(piece.residual - upper, lower - piece.residual)
            segments.append((alarm_level(excursion, piece.dt, min_duration, hold), piece.dt))
            hours += piece.n_samples * piece.dt / 3600.0
    if hours == 0.0:
        raise InputValueError(
            f"no fold outlasts the transient of {pieces.transient:g} s: there is no held-out "
            "excursion to fit; record longer collision-free runs"
        )
    return segments, hours
