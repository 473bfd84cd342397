"""Held-out data for calibration: folds of collision-free runs, Poisson rates.

Shared by :mod:`.calibration` (cross-validated false alarms) and
:mod:`.rate_margin` (the margin for a stated rate). A fold is a list of
*pieces*: whole runs, or contiguous time blocks of one run. A piece is
treated as a run of its own: its first ``transient`` seconds (the threshold's
hyper-parameter) are neither fitted nor judged.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from .._validation import check_duration, check_int, check_scalar
from ..exceptions import InputTypeError, InputValueError
from ..signals import ObserverSignals
from ..thresholds import Threshold
from ..thresholds.checks import as_runs, check_runs

__all__ = [
    "DEFAULT_HOLD",
    "DEFAULT_MIN_DURATION",
    "Pieces",
    "check_calibration_inputs",
    "check_confidence",
    "copy_threshold",
    "format_hours",
    "format_rate",
    "held_out_pieces",
    "hours_needed",
    "poisson_interval",
]

DEFAULT_MIN_DURATION = 0.005
"""Shortest event [s] the live monitor reports (``CollisionMonitor``'s default)."""
DEFAULT_HOLD = 0.05
"""Gap [s] below which the live monitor merges two events (``CollisionMonitor``'s default)."""

_ARRAYS = ("t", "residual", "model_torque", "friction", "sign", "velocity")
_OPTIONAL = ("position", "acceleration")


def check_confidence(confidence: Any) -> float:
    """``confidence`` as a float in (0, 1)."""
    level = check_scalar(confidence, "confidence", "-")
    if level >= 1.0:
        raise InputValueError(f"confidence must be in (0, 1); got {confidence!r}")
    return level


def poisson_interval(events: int, hours: float, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Garwood) two-sided confidence interval of a Poisson rate [1/h].

    Parameters
    ----------
    events : int
        Events counted.
    hours : float
        Time over which they were counted [h].
    confidence : float
        Confidence level in (0, 1).

    Returns
    -------
    lower, upper : float
        Bounds of the rate [1/h] from the chi-square quantiles; ``(0, inf)``
        when ``hours`` is 0.

    Examples
    --------
    >>> [round(v, 3) for v in poisson_interval(0, 1.0)]
    [0.0, 3.689]
    """
    count = check_int(events, "events", 0)
    alpha = 1.0 - check_confidence(confidence)
    if hours <= 0:
        return 0.0, math.inf
    lower = 0.0 if count == 0 else float(stats.chi2.ppf(alpha / 2, 2 * count)) / 2
    upper = float(stats.chi2.ppf(1 - alpha / 2, 2 * count + 2)) / 2
    return lower / hours, upper / hours


def hours_needed(rate: float, confidence: float = 0.95) -> float:
    """Collision-free time [h] in which zero false alarms show a rate below ``rate`` [1/h].

    −ln(1 − confidence)/rate: about 3/rate hours at 95 %.

    Examples
    --------
    >>> round(hours_needed(1.0), 2)
    3.0
    """
    value = check_scalar(rate, "false-alarm rate", "1/h")
    return -math.log1p(-check_confidence(confidence)) / value


def format_rate(rate: float) -> str:
    """A rate [1/h] for a person: three significant digits, no exponent below a million."""
    if not math.isfinite(rate) or rate >= 1e6:
        return f"{rate:.3g}"
    return f"{rate:.0f}" if rate >= 100 else f"{rate:.3g}"


def format_hours(hours: float) -> str:
    """A duration given in hours, in s, min or h for a person."""
    seconds = 3600.0 * hours
    if seconds < 120:
        return f"{seconds:.3g} s"
    return f"{seconds / 60:.3g} min" if seconds < 7200 else f"{hours:.3g} h"


def check_calibration_inputs(
    signals: ObserverSignals | Sequence[ObserverSignals],
    threshold: Any,
    min_duration: Any,
    hold: Any,
    confidence: Any,
) -> tuple[list[ObserverSignals], float, float, float]:
    """What cross-validation and the stated rate check: runs, min_duration, hold, confidence."""
    runs = as_runs(signals)
    check_runs(runs)
    if not isinstance(threshold, Threshold):
        raise InputTypeError(f"threshold must be a Threshold; got {type(threshold).__name__}")
    durations = check_duration(min_duration, "min_duration"), check_duration(hold, "hold")
    return runs, *durations, check_confidence(confidence)


def copy_threshold(threshold: Threshold, **params: Any) -> Threshold:
    """An unfitted threshold with the hyper-parameters of ``threshold``, some replaced."""
    return type(threshold)(**{**threshold.get_params(), **params})


def rows(signals: ObserverSignals, start: int, stop: int | None = None) -> ObserverSignals:
    """Samples ``start:stop`` of ``signals``."""
    part = slice(start, stop)
    arrays = {name: getattr(signals, name)[part] for name in _ARRAYS}
    for name in _OPTIONAL:
        value = getattr(signals, name)
        arrays[name] = None if value is None else value[part]
    return dataclasses.replace(signals, **arrays)


@dataclass(frozen=True)
class Pieces:
    """The folds of a cross-validation.

    Attributes
    ----------
    folds : list of list of ObserverSignals
        The pieces of every fold, whole.
    judged : list of list of ObserverSignals
        The same pieces after their transient; pieces left empty are dropped.
    transient : float
        Start of every piece neither fitted nor judged [s].
    """

    folds: list[list[ObserverSignals]]
    judged: list[list[ObserverSignals]]
    transient: float

    def training(self, k: int) -> list[ObserverSignals]:
        """The pieces of all folds but ``k``."""
        return [piece for i, fold in enumerate(self.folds) if i != k for piece in fold]

    def trainable(self, k: int) -> bool:
        """Whether some fold but ``k`` has samples after the transient to fit on."""
        return any(fold for i, fold in enumerate(self.judged) if i != k)


def held_out_pieces(
    runs: list[ObserverSignals], folds: Any, threshold: Threshold
) -> tuple[str, tuple[str, ...], Pieces]:
    """Cut checked runs into folds: the scheme ("runs" or "blocks"), fold labels and pieces.

    ``folds`` is "runs" (every run once; one run: two blocks) or an int k ≥ 2
    (k folds of consecutive runs, or k time blocks of a single run).
    """
    transient = check_duration(threshold.transient, "transient")
    n_runs = len(runs)
    if isinstance(folds, str):
        if folds != "runs":
            raise InputValueError(f"folds must be 'runs' or an integer >= 2; got {folds!r}")
        count = n_runs if n_runs > 1 else 2
    else:
        count = check_int(folds, "folds", 2, "cross-validation")
    if n_runs == 1:
        run = runs[0]
        if count > run.n_samples // 2:  # each block needs two samples
            raise InputValueError(
                f"folds = {count}: one run of {run.n_samples} samples cannot be cut into {count} "
                f"time blocks of at least 2 samples (at most {run.n_samples // 2})"
            )
        cuts = np.searchsorted(run.t, np.linspace(run.t[0], run.t[-1], count + 1)[1:-1])
        edges = [0, *cuts.tolist(), run.n_samples]
        parts = [[rows(run, a, b)] for a, b in itertools.pairwise(edges)]
        labels = tuple(f"block {k + 1} of {count}" for k in range(count))
        scheme = "blocks"
    elif n_runs >= count:
        groups = np.array_split(np.arange(n_runs), count)
        parts = [[runs[i] for i in group] for group in groups]
        labels = tuple(
            f"run {g[0] + 1}" if g.size == 1 else f"runs {g[0] + 1}-{g[-1] + 1}" for g in groups
        )
        scheme = "runs"
    else:
        raise InputValueError(
            f"folds = {count} needs at least {count} runs, or one run to cut into {count} time "
            f"blocks; got {n_runs} runs"
        )
    judged = [[_after(piece, transient) for piece in fold] for fold in parts]
    kept = [[piece for piece in fold if piece.n_samples > 1] for fold in judged]
    return scheme, labels, Pieces(parts, kept, transient)


def _after(piece: ObserverSignals, transient: float) -> ObserverSignals:
    """The samples of ``piece`` from ``transient`` seconds after its start (as fit keeps)."""
    first = int(np.searchsorted(piece.t - piece.t[0], transient, side="left"))
    return rows(piece, first)
