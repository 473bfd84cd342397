"""The time base of a log: a regular grid by explicit interpolation, and cuts at gaps.

Recorded logs jitter (a 100 Hz controller stamps its samples 8 to 12 ms
apart) and have holes (a dropped connection, a paused recorder). Jitter is
resampled explicitly with :func:`resample`; a hole is not interpolated
across unless asked, because the values there would be invented: a step
between two samples longer than ``max_gap`` periods (:data:`DEFAULT_MAX_GAP`)
is a *gap*, and :func:`split_at_gaps` cuts a log into the regular stretches
between its gaps.

>>> import numpy as np
>>> from sensorless.io import Log
>>> log = Log(t=[0.0, 0.01, 0.02, 1.0, 1.01, 1.02], q=np.zeros((6, 1)))
>>> [segment.t.tolist() for segment in split_at_gaps(log)]
[[0.0, 0.01, 0.02], [1.0, 1.01, 1.02]]
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray, check_dt, check_scalar
from ..exceptions import InputTypeError, InputValueError, LogFormatError
from .log import Log

__all__ = ["DEFAULT_MAX_GAP", "find_gaps", "gap_report", "interpolate", "resample", "split_at_gaps"]

DEFAULT_MAX_GAP = 3.0
"""Longest step between two samples, in sample periods, that counts as jitter, not a gap."""

IntArray = NDArray[np.int64]


def find_gaps(t: FloatArray, tolerance: float) -> IntArray:
    """Indices ``i`` of the steps ``t[i + 1] - t[i]`` longer than ``tolerance`` [s]."""
    return np.flatnonzero(np.diff(t) > tolerance).astype(np.int64)


def gap_report(t: FloatArray, gaps: IntArray) -> list[dict[str, float]]:
    """The gaps as JSON-ready records: last sample before, first after, and length [s]."""
    return [
        {
            "t_start": float(t[i]),
            "t_end": float(t[i + 1]),
            "duration": float(t[i + 1] - t[i]),
        }
        for i in gaps.tolist()
    ]


def interpolate(grid: FloatArray, t: FloatArray, values: FloatArray) -> FloatArray:
    """Linear interpolation of each column of ``values`` (n_samples, n_dof) at ``grid`` [s]."""
    out = np.empty((grid.shape[0], values.shape[1]))
    for joint in range(values.shape[1]):
        out[:, joint] = np.interp(grid, t, values[:, joint])
    return out


def _check_bool(value: Any, name: str) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise InputTypeError(f"{name} must be True or False; got {value!r}")
    return bool(value)


def _check_log(log: Any) -> Log:
    if not isinstance(log, Log):
        raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
    return log


def resample(
    log: Log, dt: float, *, max_gap: float = DEFAULT_MAX_GAP, allow_gaps: bool = False
) -> Log:
    """Put a log on a regular time grid by linear interpolation.

    This is the explicit alternative to the irregular-time error of
    :func:`~sensorless.io.read_log`: read a jittery log with ``check_regular=False`` and
    resample it. The new grid is ``t[0] + k * dt`` for every ``k`` that stays
    within the log. Joint quantities are interpolated linearly;
    ``collision_id`` takes the value of the latest original sample at or
    before each grid time (zero-order hold), so a label shorter than ``dt``
    can fall between grid points.

    A step between two original samples longer than ``max_gap`` periods is a
    gap: the log has no data there, and interpolating would invent it. The
    period is the longer of ``dt`` and the log's median step, so that jitter
    of the original rate is never a gap.

    Parameters
    ----------
    log : Log
        The log to resample (any time base).
    dt : float
        New sample period [s].
    max_gap : float
        Longest step [periods] interpolated across.
    allow_gaps : bool
        Interpolate across longer steps as well. The spans are listed in the
        metadata (``resampled["interpolated_gaps"]``): their values are
        interpolation, not data, and must be treated as faults.

    Returns
    -------
    Log
        The resampled log; its metadata is a copy with ``sample_rate`` [Hz]
        set to ``1 / dt`` and a ``resampled`` entry recording the operation.

    Raises
    ------
    InputValueError
        ``dt`` or ``max_gap`` is not positive and finite, or ``dt`` is longer
        than the log.
    LogFormatError
        The log has a gap and ``allow_gaps`` is False; the message gives the
        time and length of the first gap.

    Examples
    --------
    >>> import numpy as np
    >>> log = Log(t=[0.0, 0.09, 0.2], q=[[0.0], [0.09], [0.2]])
    >>> new = resample(log, 0.05)
    >>> new.t.round(12).tolist(), new.q[:, 0].round(12).tolist()
    ([0.0, 0.05, 0.1, 0.15, 0.2], [0.0, 0.05, 0.1, 0.15, 0.2])
    >>> resample(Log(t=[0.0, 0.01, 0.5, 0.51], q=np.zeros((4, 1))), 0.01)
    Traceback (most recent call last):
    ...
    sensorless.exceptions.LogFormatError: resample refuses to interpolate across a gap: ...
    """
    log = _check_log(log)
    step = check_dt(dt)
    periods = check_scalar(max_gap, "max_gap", "periods")
    allow = _check_bool(allow_gaps, "allow_gaps")
    # A relative slack of 1e-9 keeps the last sample when duration / dt is an integer
    # that floating point puts just below itself.
    n_samples = math.floor(log.duration / step + 1e-9) + 1
    if n_samples < 2:
        raise InputValueError(
            f"dt = {step!r} s is longer than the log ({log.duration!r} s); the resampled log "
            "would have fewer than 2 samples"
        )
    period = max(step, log.dt)
    gaps = find_gaps(log.t, periods * period)
    if gaps.size and not allow:
        first = int(gaps[0])
        before, after = float(log.t[first]), float(log.t[first + 1])
        others = f" (the first of {gaps.size} gaps)" if gaps.size > 1 else ""
        raise LogFormatError(
            "resample refuses to interpolate across a gap: the log has no sample from "
            f"t = {before!r} s (row {first}) to t = {after!r} s (row {first + 1}), "
            f"{after - before:.6g} s = {(after - before) / period:.3g} periods of "
            f"{period:.6g} s{others}; the longest step it interpolates across is "
            f"max_gap = {periods:g} periods. Cut the log at its gaps with "
            "sensorless.io.split_at_gaps, or pass allow_gaps=True to interpolate anyway"
        )
    grid = log.t[0] + step * np.arange(n_samples)
    changes: dict[str, Any] = {"t": grid}
    for group in log.groups:
        changes[group] = interpolate(grid, log.t, getattr(log, group))
    if log.collision_id is not None:
        previous = np.searchsorted(log.t, grid, side="right") - 1
        changes["collision_id"] = log.collision_id[np.clip(previous, 0, log.n_samples - 1)]
    metadata = dict(log.metadata)
    metadata["sample_rate"] = 1.0 / step
    metadata["resampled"] = {
        "dt": step,
        "method": "linear (collision_id: previous sample)",
        "n_samples_before": log.n_samples,
        "max_gap": periods,
        "interpolated_gaps": gap_report(log.t, gaps),
    }
    changes["metadata"] = metadata
    return dataclasses.replace(log, **changes)


def split_at_gaps(log: Log, tolerance: float | None = None) -> list[Log]:
    """Cut a log at its gaps into the stretches of samples between them.

    Parameters
    ----------
    log : Log
        The log to cut (any time base).
    tolerance : float, optional
        Longest step [s] between two samples of one segment; by default
        :data:`DEFAULT_MAX_GAP` times the median step of the log.

    Returns
    -------
    list of Log
        The segments in time order, time stamps kept. A sample alone between
        two gaps cannot make a log and is dropped. Each segment's metadata is
        a copy of the log's with a ``segment`` entry: ``index`` and ``count``
        of the segments, ``first_row`` in the log, ``tolerance`` [s], the
        ``gaps`` (last sample before, first after and length [s]) and the
        number of ``isolated_samples_dropped``. A log without gaps comes back
        as one segment.

    Raises
    ------
    InputValueError
        ``tolerance`` is not positive and finite.
    LogFormatError
        No two consecutive samples are within ``tolerance``.

    Examples
    --------
    >>> import numpy as np
    >>> log = Log(t=[0.0, 0.01, 0.5, 0.51, 0.52], q=np.zeros((5, 1)))
    >>> first, second = split_at_gaps(log, tolerance=0.1)
    >>> second.t.tolist(), second.metadata["segment"]["gaps"]
    ([0.5, 0.51, 0.52], [{'t_start': 0.01, 't_end': 0.5, 'duration': 0.49}])
    """
    log = _check_log(log)
    if tolerance is None:
        limit = DEFAULT_MAX_GAP * log.dt
    else:
        limit = check_scalar(tolerance, "tolerance", "s")
    gaps = find_gaps(log.t, limit)
    starts = [0, *(gaps + 1).tolist()]
    stops = [*(gaps + 1).tolist(), log.n_samples]
    kept = [(a, b) for a, b in zip(starts, stops, strict=True) if b - a >= 2]
    if not kept:
        raise LogFormatError(
            f"no two consecutive samples of the log are within tolerance = {limit:.6g} s "
            f"(its median step is {log.dt:.6g} s); nothing is left between its gaps"
        )
    report = gap_report(log.t, gaps)
    isolated = len(starts) - len(kept)
    segments = []
    for index, (first, stop) in enumerate(kept):
        metadata = dict(log.metadata)
        metadata["segment"] = {
            "index": index,
            "count": len(kept),
            "first_row": first,
            "tolerance": limit,
            "gaps": report,
            "isolated_samples_dropped": isolated,
        }
        changes: dict[str, Any] = {"t": log.t[first:stop], "metadata": metadata}
        for group in log.groups:
            changes[group] = getattr(log, group)[first:stop]
        if log.collision_id is not None:
            changes["collision_id"] = log.collision_id[first:stop]
        segments.append(dataclasses.replace(log, **changes))
    return segments
