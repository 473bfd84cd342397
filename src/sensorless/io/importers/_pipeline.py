"""What every importer does after reading its format: check, clean, regularise, record.

A format reader produces a :class:`Recording` (time [s] and joint groups in
SI units, rows in file order), checking each value as it reads it with
:func:`~._checks.checked_column` so that an error names the file, the column
and the row. :func:`regularize` then turns the recording into logs:

1. rows out of time order are sorted (counted);
2. rows that repeat a time stamp are dropped, the first one kept (counted,
   and counted again if their values differ from the kept row's);
3. the nominal period is the median step (to 9 significant digits) unless
   given; a step longer than the gap tolerance
   (:data:`~sensorless.io.timebase.DEFAULT_MAX_GAP` periods unless given) is
   a gap, and the recording is cut there into segments rather than
   interpolated across;
4. time is measured from the earliest sample (``t = 0``), whose time in the
   file's own clock is reported as ``time_origin`` [s];
5. a segment whose steps are not all the nominal period (jitter) is resampled
   by linear interpolation onto ``t0 + k * dt`` (labels: previous sample);
   a regular segment keeps its samples untouched.

Every log's metadata records the provenance (``import``: format, source
file, importer and its version, source units, column mapping, gains) and the
cleaning report (rows read, duplicates and out-of-order rows, nominal period,
maximum jitter, gaps, segments), plus ``resampled`` when its segment was
resampled.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypedDict, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._validation import FloatArray, check_dt, check_scalar
from ..._version import __version__
from ...exceptions import LogFormatError
from ..columns import JOINT_GROUPS
from ..log import Log
from ..timebase import DEFAULT_MAX_GAP, find_gaps, gap_report, interpolate

__all__ = ["Provenance", "Recording", "RowBuffer", "regularize"]

# Relative tolerance of "regular" steps, as the log reader's default check.
_REGULAR_RTOL = 1e-6


@dataclass
class Recording:
    """The columns of one foreign file in SI units, rows in file order.

    Attributes
    ----------
    t : ndarray of shape (n_rows,)
        Time stamps [s], in any order, possibly repeated.
    groups : dict of str to ndarray of shape (n_rows, n_dof)
        Per-joint groups of the log format (``q``, ``qd``, ``tau_m``, ...).
    collision_id : ndarray of shape (n_rows,), optional
        Labels (non-negative integers as floats).
    time_origin : float
        Time [s] in the file's own clock of ``t = 0``. Readers measure ``t``
        from their first row, so that stamps far from zero (seconds since
        1970) keep their resolution.
    """

    t: FloatArray
    groups: dict[str, FloatArray]
    collision_id: FloatArray | None = None
    time_origin: float = 0.0


class RowBuffer:
    """Columns filled chunk by chunk into arrays allocated once.

    A long recording read in chunks and concatenated at the end would be held
    twice; here every column is allocated for ``capacity`` rows up front (an
    estimate from the file's size, the bag's message count) and only grown, by
    doubling, if that estimate falls short.

    Parameters
    ----------
    capacity : int
        Expected number of rows.
    widths : dict of str to int
        Columns by name: 0 for one value per row, else the number of values.
    dtypes : dict of str to numpy dtype, optional
        dtype of a column (default float64).
    """

    def __init__(
        self, capacity: int, widths: dict[str, int], dtypes: dict[str, Any] | None = None
    ) -> None:
        kinds = dtypes or {}
        self.size = 0
        self._columns: dict[str, NDArray[Any]] = {
            name: np.empty(
                (max(capacity, 1), width) if width else max(capacity, 1),
                kinds.get(name, np.float64),
            )
            for name, width in widths.items()
        }

    def take(self, count: int) -> dict[str, NDArray[Any]]:
        """The next ``count`` rows of every column, to be filled in place (views)."""
        stop = self.size + count
        for name, column in self._columns.items():
            if stop > column.shape[0]:
                grown = np.empty((max(stop, 2 * column.shape[0]), *column.shape[1:]), column.dtype)
                grown[: self.size] = column[: self.size]
                self._columns[name] = grown
        rows = {name: column[self.size : stop] for name, column in self._columns.items()}
        self.size = stop
        return rows

    def extend(self, values: Mapping[str, ArrayLike]) -> None:
        """Append rows: one array per column, all of the same length."""
        count = len(np.asarray(next(iter(values.values()))))
        for name, rows in self.take(count).items():
            rows[...] = values[name]

    def arrays(self) -> dict[str, NDArray[Any]]:
        """The filled rows of every column (views, or the arrays themselves when full)."""
        return {
            name: column if column.shape[0] == self.size else column[: self.size]
            for name, column in self._columns.items()
        }


@dataclass(frozen=True)
class Provenance:
    """Where a recording came from and how its values were converted.

    Attributes
    ----------
    format : str
        Format name, as :func:`~sensorless.io.import_log` spells it.
    source : Path
        The file read.
    importer : str
        Module of the importer.
    importer_version : int
        Version of that importer's conversion rules.
    source_units : dict of str to str
        Unit of each log group in the file, e.g. ``{"tau_m": "A"}``.
    columns : dict of str to Any
        The file's column (or field) behind each log column group.
    conversions : dict of str to Any
        How values were converted (gains [N m/A], unit factors), by group.
    robot : str, optional
        Robot name, stored as ``metadata["robot"]``.
    report : dict of str to Any
        What the reader itself counted (e.g. skipped messages), added to the
        cleaning report.
    """

    format: str
    source: Path
    importer: str
    importer_version: int
    source_units: dict[str, str]
    columns: dict[str, Any]
    conversions: dict[str, Any] = field(default_factory=dict)
    robot: str | None = None
    report: dict[str, Any] = field(default_factory=dict)

    def as_metadata(self) -> dict[str, Any]:
        """The JSON-ready ``import`` entry of the logs' metadata."""
        return {
            "format": self.format,
            "source": str(self.source),
            "importer": self.importer,
            "importer_version": self.importer_version,
            "sensorless_version": __version__,
            "source_units": dict(self.source_units),
            "columns": dict(self.columns),
            "conversions": dict(self.conversions),
        }


def _freeze(arr: FloatArray) -> FloatArray:
    """Make ``arr`` and the arrays it views read-only, so that logs share it, not copy it."""
    base: Any = arr
    while isinstance(base, np.ndarray):
        base.setflags(write=False)
        base = base.base
    return arr


def _sort_and_deduplicate(recording: Recording, report: dict[str, Any]) -> Recording:
    """Sort rows by time (stable) and drop rows repeating a time stamp; count both."""
    t = recording.t
    backwards = int(np.count_nonzero(np.diff(t) < 0.0))
    report["out_of_order_rows"] = backwards
    if backwards:
        order = np.argsort(t, kind="stable")
        t = t[order]
        for group in list(recording.groups):
            recording.groups[group] = recording.groups[group][order]
        if recording.collision_id is not None:
            recording.collision_id = recording.collision_id[order]
    repeated = np.flatnonzero(np.diff(t) == 0.0) + 1
    report["duplicate_rows_dropped"] = int(repeated.size)
    differing = np.zeros(repeated.size, dtype=bool)
    for values in [*recording.groups.values(), recording.collision_id]:
        if values is not None and repeated.size:
            change = values[repeated] != values[repeated - 1]
            differing |= change.any(axis=1) if change.ndim == 2 else change
    report["duplicates_with_other_values"] = int(np.count_nonzero(differing))
    if repeated.size:
        keep = np.ones(t.size, dtype=bool)
        keep[repeated] = False
        t = t[keep]
        for group in list(recording.groups):
            recording.groups[group] = recording.groups[group][keep]
        if recording.collision_id is not None:
            recording.collision_id = recording.collision_id[keep]
    recording.t = t
    return recording


def _is_regular(t: FloatArray, dt: float) -> bool:
    slack = _REGULAR_RTOL * dt + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    return bool(np.all(np.abs(np.diff(t) - dt) <= slack))


def _median_period(steps: FloatArray) -> float:
    """The median step [s], to 9 significant digits.

    Time stamps far from zero carry rounding of their own (0.0099999999999909 s
    between two stamps near 333 s); the nominal period is the round figure.
    """
    median = float(np.median(steps))
    return round(median, 8 - math.floor(math.log10(median)))


def _grid_size(start: float, stop: float, dt: float) -> int:
    """Points of the grid ``start + k dt`` within ``[start, stop]``."""
    # The relative slack keeps the last point when (stop - start) / dt is an integer
    # that floating point puts just below itself.
    return math.floor((stop - start) / dt + 1e-9) + 1


def _max_jitter(steps: FloatArray, dt: float) -> float:
    return float(np.max(np.abs(steps - dt))) if steps.size else 0.0


class _Segment:
    """Rows ``start:stop`` of a sorted recording and the time grid [s] of their log."""

    def __init__(self, start: int, stop: int, t: FloatArray, period: float) -> None:
        self.start, self.stop = start, stop
        self.regular = _is_regular(t[start:stop], period)
        size = _grid_size(t[start], t[stop - 1], period)
        self.grid = t[start:stop] if self.regular else _freeze(t[start] + period * np.arange(size))

    def values(self, t: FloatArray, values: FloatArray) -> FloatArray:
        """A group's values on the grid: the rows themselves, or linearly interpolated."""
        rows = values[self.start : self.stop]
        if self.regular:
            return rows
        with np.errstate(over="ignore", invalid="ignore"):  # refused by regularize
            return _freeze(interpolate(self.grid, t[self.start : self.stop], rows))

    def labels(self, t: FloatArray, labels: NDArray[np.int64]) -> NDArray[np.int64]:
        """Labels on the grid: those of the latest row at or before each grid time."""
        previous = np.searchsorted(t[self.start : self.stop], self.grid, side="right") - 1
        return labels[self.start : self.stop][np.clip(previous, 0, self.stop - self.start - 1)]


def _segment_columns(
    recording: Recording, t: FloatArray, segments: list[_Segment]
) -> list[dict[str, Any]]:
    """Each segment's groups and labels on its grid; the recording's groups are consumed."""
    columns: list[dict[str, Any]] = [{} for _ in segments]
    # Group by group, so that a long recording is never held twice in full.
    for group in [g for g in JOINT_GROUPS if g in recording.groups]:
        values = _freeze(recording.groups.pop(group))
        for segment, out in zip(segments, columns, strict=True):
            out[group] = segment.values(t, values)
    if recording.collision_id is not None:
        labels = recording.collision_id.astype(np.int64)
        for segment, out in zip(segments, columns, strict=True):
            out["collision_id"] = segment.labels(t, labels)
    return columns


def regularize(
    recording: Recording,
    provenance: Provenance,
    *,
    dt: float | None = None,
    gap_tolerance: float | None = None,
) -> list[Log]:
    """Sort, de-duplicate, cut at gaps and resample a recording into logs.

    Parameters
    ----------
    recording : Recording
        Checked values in SI units; its arrays are consumed (reordered, freed).
    provenance : Provenance
        Recorded in every log's metadata.
    dt : float, optional
        Nominal sample period [s]; by default the median step.
    gap_tolerance : float, optional
        Longest step [s] within a segment; by default
        :data:`~sensorless.io.timebase.DEFAULT_MAX_GAP` times ``dt``.

    Returns
    -------
    list of Log
        The segments in time order (usually one), each on a regular grid.

    Raises
    ------
    LogFormatError
        Fewer than 2 distinct time stamps, stamps too far apart for float64
        to keep their steps once measured from the earliest, or no two
        consecutive ones within the gap tolerance.
    InputValueError
        ``dt`` or ``gap_tolerance`` is not positive and finite.
    """
    source = provenance.source
    report: dict[str, Any] = {"rows_read": int(recording.t.size), **provenance.report}
    recording = _sort_and_deduplicate(recording, report)
    if recording.t.size < 2:
        raise LogFormatError(
            f"{source}: holds {recording.t.size} distinct time stamp(s); a log needs at least 2"
        )
    start = float(recording.t[0])
    report["time_origin"] = recording.time_origin + start
    with np.errstate(over="ignore", invalid="ignore"):  # refused, with the span, below
        t = _freeze(recording.t - start)
        steps = np.diff(t)
    if not (np.all(np.isfinite(t)) and np.all(steps > 0.0)):
        raise LogFormatError(
            f"{source}: the time stamps run from {start!r} to {float(recording.t[-1])!r} s (from "
            "the first row): too wide a span for float64 to keep every step apart once measured "
            "from the earliest; is a time stamp wrong?"
        )
    period = _median_period(steps) if dt is None else check_dt(dt)
    tolerance = (
        DEFAULT_MAX_GAP * period
        if gap_tolerance is None
        else check_scalar(gap_tolerance, "gap_tolerance", "s")
    )
    gaps = find_gaps(t, tolerance)
    jitter = np.ones(steps.size, dtype=bool)
    jitter[gaps] = False
    bounds = zip([0, *(gaps + 1).tolist()], [*(gaps + 1).tolist(), t.size], strict=True)
    # A segment needs two grid points; what is left between gaps is reported, not kept.
    kept = [(a, b) for a, b in bounds if _grid_size(t[a], t[b - 1], period) >= 2]
    if not kept:
        raise LogFormatError(
            f"{source}: no two consecutive time stamps are within the gap tolerance "
            f"{tolerance:.6g} s (nominal period {period:.6g} s); pass a longer gap_tolerance"
        )
    report |= {
        "nominal_dt": period,
        "max_jitter": _max_jitter(steps[jitter], period),
        "gap_tolerance": tolerance,
        "gaps": gap_report(t, gaps),
        "rows_dropped_between_gaps": int(t.size - sum(b - a for a, b in kept)),
        "segments": len(kept),
    }
    segments = [_Segment(a, b, t, period) for a, b in kept]
    columns = _segment_columns(recording, t, segments)
    for segment, out in zip(segments, columns, strict=True):
        if segment.regular:  # its samples as read: checked already
            continue
        overflowed = [group for group, values in out.items() if not np.isfinite(values).all()]
        if overflowed:
            # Between +-1e308 and -+1e308 the linear interpolation overflows.
            raise LogFormatError(
                f"{source}: {overflowed[0]} holds values too large to resample onto the regular "
                f"grid (the interpolation overflows float64 near t = {t[segment.start]:.6g} s)"
            )
    logs = []
    for index, segment in enumerate(segments):
        metadata: dict[str, Any] = {} if provenance.robot is None else {"robot": provenance.robot}
        metadata["sample_rate"] = 1.0 / period
        metadata["import"] = provenance.as_metadata() | {
            "report": report,
            "segment": {
                "index": index,
                "count": len(segments),
                "first_sample": segment.start,
                "n_samples_before": segment.stop - segment.start,
                "max_jitter": _max_jitter(np.diff(t[segment.start : segment.stop]), period),
            },
        }
        if not segment.regular:
            # As sensorless.io.resample writes it; the segment has no gap by construction.
            metadata["resampled"] = {
                "dt": period,
                "method": "linear (collision_id: previous sample)",
                "n_samples_before": segment.stop - segment.start,
                "max_gap": tolerance / period,
                "interpolated_gaps": [],
            }
        logs.append(Log(t=segment.grid, metadata=metadata, **columns[index]))
    return logs


TIMEBASE_DOC = """dt : float, optional
        Sample period [s] of the logs; by default the median step.
    gap_tolerance : float, optional
        Longest step [s] within one log; longer steps cut the recording
        into segments. By default 3 periods.

    Returns
    -------
    list of Log
        The segments of the recording, on regular grids, with the
        provenance and the cleaning report in ``metadata["import"]`` (see
        :mod:`sensorless.io.importers`)."""

Importer = TypeVar("Importer", bound=Callable[..., Any])


class Timebase(TypedDict, total=False):
    """Keyword options every importer passes to :func:`regularize` (``dt``, ``gap_tolerance``)."""

    dt: float | None
    gap_tolerance: float | None


def timebase_doc(function: Importer) -> Importer:
    """Fill in the parameters every importer shares (``dt``, ``gap_tolerance``) and Returns."""
    function.__doc__ = (function.__doc__ or "").replace("{timebase}", TIMEBASE_DOC)
    return function
