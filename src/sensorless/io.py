"""The log format that every tool of :mod:`sensorless` reads and writes.

A log is one simulated or recorded robot run: a table with time along axis 0,
SI units and angles in radians. Its columns are (joint numbers ``j`` start at
1 and run to ``n_dof``):

=================  ==========  ====================================================
column             unit        meaning
=================  ==========  ====================================================
``t``              s           time stamp, strictly increasing
``q_j``            rad         measured joint position (required)
``tau_m_j``        N m         motor / commanded joint torque (optional)
``tau_j_j``        N m         joint-torque-sensor torque (optional)
``q_true_j``       rad         ground-truth joint position (optional)
``qd_true_j``      rad/s       ground-truth joint velocity (optional)
``tau_c_j``        N m         ground-truth external joint torque (optional)
``collision_id``   1           integer label, 0 = no collision (optional)
=================  ==========  ====================================================

An optional group is either present for every joint or absent. Any other
column is an error, so that a typo such as ``tau_M_1`` cannot be silently
ignored. Rows are counted from 0 in error messages (the position in the
table, as ``df.iloc``; the CSV header is not a row).

On disk a log is a Parquet or CSV table plus a JSON sidecar
``<path>.meta.json`` with ``n_dof``, the column list, the units, the sample
rate [Hz] and the user metadata. Both formats keep float64 values exactly.

:func:`validate_table` is the single validation routine: :func:`read_log`,
:meth:`Log.from_pandas` and the :class:`Log` constructor all go through it,
so a :class:`Log` cannot hold an inconsistent run. Irregular time stamps are
an error on read; :func:`resample` is the explicit way to put a jittery log
on a regular grid.

>>> import numpy as np
>>> t = np.arange(5) * 0.001
>>> log = Log(t=t, q=np.zeros((5, 2)), tau_m=np.ones((5, 2)))
>>> list(log.to_pandas().columns)
['t', 'q_1', 'q_2', 'tau_m_1', 'tau_m_2']
>>> log.n_dof, log.n_samples, round(log.dt, 9)
(2, 5, 0.001)
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from ._validation import FloatArray, check_dt
from .exceptions import DimensionError, InputValueError, LogFormatError

__all__ = [
    "ANGLE_LIMIT",
    "FORMATS",
    "JOINT_GROUPS",
    "UNITS",
    "Log",
    "read_log",
    "resample",
    "sidecar_path",
    "validate_table",
    "write_log",
]

JOINT_GROUPS: tuple[str, ...] = ("q", "tau_m", "tau_j", "q_true", "qd_true", "tau_c")
"""Per-joint column groups in table order; ``q`` is required, the others optional."""

_OPTIONAL_GROUPS: tuple[str, ...] = JOINT_GROUPS[1:]

UNITS: dict[str, str] = {
    "t": "s",
    "q": "rad",
    "tau_m": "N m",
    "tau_j": "N m",
    "q_true": "rad",
    "qd_true": "rad/s",
    "tau_c": "N m",
    "collision_id": "1",
}
"""Unit of each column group (``"1"``: dimensionless)."""

FORMATS: tuple[str, ...] = ("parquet", "csv")
"""File formats understood by :func:`write_log` and :func:`read_log`."""

ANGLE_LIMIT = 4.0 * math.pi
"""Largest |angle| [rad] accepted in ``q``/``q_true``; beyond it the log looks like degrees."""

_SUFFIXES = {".parquet": "parquet", ".pq": "parquet", ".csv": "csv"}
_SIDECAR_SUFFIX = ".meta.json"
_FORMAT_VERSION = 1
_COLUMN_PATTERN = re.compile(r"(q|tau_m|tau_j|q_true|qd_true|tau_c)_([1-9][0-9]*)")
_KNOWN_COLUMNS = (
    "'t', 'q_<j>', 'tau_m_<j>', 'tau_j_<j>', 'q_true_<j>', 'qd_true_<j>', 'tau_c_<j>', "
    "'collision_id' (joint numbers j = 1..n_dof)"
)
_ANGLE_GROUPS = ("q", "q_true")
# pandas before 3.1 parses CSV floats with a fast converter that is not guaranteed to be
# correctly rounded; its "round_trip" converter is. From 3.1 on every mode uses the exact
# converter and passing the option only warns.
_CSV_READ_OPTIONS: dict[str, Any] = (
    {"float_precision": "round_trip"}
    if tuple(map(int, re.findall(r"\d+", pd.__version__)[:2])) < (3, 1)
    else {}
)

IntArray = NDArray[np.int64]


def _column(group: str, joint: int) -> str:
    """Column name of 1-based ``joint`` in ``group``."""
    return f"{group}_{joint}"


def _value(x: Any) -> str:
    """``repr`` of a value with numpy scalars shown as plain Python numbers."""
    return repr(x.item() if isinstance(x, np.generic) else x)


def _abbreviate(names: list[Any], limit: int = 12) -> str:
    """List at most ``limit`` names so that messages stay readable for wide tables."""
    shown = ", ".join(repr(name) for name in names[:limit])
    more = f", ... ({len(names) - limit} more)" if len(names) > limit else ""
    return f"[{shown}{more}]"


# --------------------------------------------------------------------------- validation


def _check_n_dof(n_dof: Any) -> int | None:
    if n_dof is None:
        return None
    if isinstance(n_dof, bool) or not isinstance(n_dof, int | np.integer) or n_dof < 1:
        raise InputValueError(f"n_dof must be a positive integer or None; got {n_dof!r}")
    return int(n_dof)


def _check_rtol(rtol: Any) -> float:
    try:
        value = float(rtol)
    except (TypeError, ValueError):
        raise InputValueError(f"rtol must be a non-negative number; got {rtol!r}") from None
    if not math.isfinite(value) or value < 0.0:
        raise InputValueError(f"rtol must be a finite, non-negative number; got {rtol!r}")
    return value


def _parse_columns(names: list[Any], n_dof: int | None) -> tuple[int, list[str]]:
    """Check the column set; return the joint count and the present groups in table order."""
    joints: dict[str, set[int]] = {}
    unknown: list[Any] = []
    for name in names:
        match = _COLUMN_PATTERN.fullmatch(name) if isinstance(name, str) else None
        if match is not None:
            joints.setdefault(match[1], set()).add(int(match[2]))
        elif name not in ("t", "collision_id"):
            unknown.append(name)
    if unknown:
        raise LogFormatError(
            f"unknown column(s) {_abbreviate(unknown)}; known columns are {_KNOWN_COLUMNS}"
        )
    if "t" not in names or "q" not in joints:
        expected_q = "'q_1'..'q_<n_dof>'" if n_dof is None else f"'q_1'..'q_{n_dof}'"
        present = (("'t'", "t" in names), (expected_q, "q" in joints))
        missing = [label for label, ok in present if not ok]
        raise LogFormatError(
            f"a log needs the time column 't' and the joint positions {expected_q}; "
            f"missing {', '.join(missing)}; found columns {_abbreviate(names)}"
        )
    groups = [group for group in JOINT_GROUPS if group in joints]
    n_found = max(max(indices) for indices in joints.values())
    missing_columns = [
        _column(group, joint)
        for group in groups
        for joint in range(1, n_found + 1)
        if joint not in joints[group]
    ]
    if missing_columns:
        counts = ", ".join(f"{group}: {len(joints[group])}" for group in groups)
        raise LogFormatError(
            f"joint groups have inconsistent joint counts ({counts}); every present group "
            f"needs columns <group>_1..<group>_{n_found}; missing column(s) "
            f"{_abbreviate(missing_columns)}"
        )
    if n_dof is not None and n_dof != n_found:
        raise DimensionError(
            f"n_dof mismatch: robot has {n_dof} joints, log has {n_found} "
            f"(columns q_1..q_{n_found})"
        )
    return n_found, groups


def _as_float_column(name: str, values: ArrayLike) -> FloatArray:
    """Convert one column to float64, naming the first row that is not a number."""
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise LogFormatError(f"column {name!r} must be one-dimensional; got shape {arr.shape}")
    if arr.dtype.kind in "iuf":
        return arr.astype(np.float64, copy=False)
    if arr.dtype.kind not in "OUS":
        raise LogFormatError(f"column {name!r} must be numeric; it has dtype {arr.dtype}")
    # Object and text columns come from CSV files with a stray word in them, or from
    # nullable pandas dtypes; numbers written as text are fine, anything else is not.
    out = np.empty(arr.shape, dtype=np.float64)
    for row, value in enumerate(arr.tolist()):
        if value is None or value is pd.NA:
            out[row] = math.nan
            continue
        if isinstance(value, bool):
            number = None
        elif isinstance(value, int | float):
            number = float(value)
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                number = None
        if number is None:
            raise LogFormatError(
                f"column {name!r} must be numeric; row {row} holds the non-numeric value {value!r}"
            )
        out[row] = number
    return out


def _check_time(t: FloatArray, check_regular: bool, rtol: float) -> None:
    step = np.diff(t)
    not_increasing = np.flatnonzero(step <= 0.0)
    if not_increasing.size:
        row = int(not_increasing[0]) + 1
        before, after = float(t[row - 1]), float(t[row])
        how = "repeats" if after == before else "goes backwards"
        raise LogFormatError(
            f"column 't' must be strictly increasing; it {how} at row {row}: "
            f"t = {after!r} s at row {row} after t = {before!r} s at row {row - 1}"
        )
    if not check_regular:
        return
    median = float(np.median(step))
    # Time stamps far from zero (e.g. Unix time) carry rounding of their own spacing; a
    # few ulps of the largest stamp are not jitter.
    tolerance = rtol * median + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    irregular = np.flatnonzero(np.abs(step - median) > tolerance)
    if irregular.size:
        row = int(irregular[0]) + 1
        before, after = float(t[row - 1]), float(t[row])
        deviation = abs(step[row - 1] - median) / median
        raise LogFormatError(
            f"column 't' is not regularly sampled: the step from row {row - 1} to row {row} "
            f"(t = {before!r} -> {after!r} s) is {step[row - 1]:.9g} s, the median step "
            f"is {median:.9g} s; relative deviation {deviation:.3g} exceeds rtol = {rtol:g}. "
            "Resample explicitly with sensorless.io.resample(log, dt) on a log read with "
            "check_regular=False, or pass check_regular=False"
        )


def _check_collision_id(values: FloatArray) -> None:
    bad = np.flatnonzero((values < 0.0) | (values != np.round(values)))
    if bad.size:
        row = int(bad[0])
        raise LogFormatError(
            "column 'collision_id' must hold non-negative integers (0 = no collision); "
            f"row {row} holds {_value(values[row])}"
        )


def _check_angles(name: str, values: FloatArray) -> None:
    too_large = np.flatnonzero(np.abs(values) > ANGLE_LIMIT)
    if too_large.size:
        row = int(too_large[0])
        raise LogFormatError(
            f"column {name!r} looks like degrees, but angles must be radians: row {row} "
            f"holds {_value(values[row])}, beyond ±4π = ±{ANGLE_LIMIT:.6g} rad; convert with "
            "numpy.deg2rad"
        )


def validate_table(
    df: pd.DataFrame | Mapping[str, ArrayLike],
    n_dof: int | None = None,
    check_regular: bool = True,
    rtol: float = 1e-6,
) -> int:
    """Check that a table is a valid log and return its number of joints.

    This is the one validation routine of the log format; the reader and the
    :class:`Log` constructor both call it.

    Parameters
    ----------
    df : DataFrame or mapping of column name to array-like of shape (n_samples,)
        The log table, columns named as in the module docstring.
    n_dof : int, optional
        Number of joints of the robot the log is meant for; checked against the log.
    check_regular : bool
        Require a regular time base: every time step [s] within ``rtol``
        times the median step of the median step.
    rtol : float
        Relative tolerance of the regularity check.

    Returns
    -------
    n_dof : int
        Number of joints in the log.

    Raises
    ------
    LogFormatError
        Unknown, missing or duplicate columns; joint groups of different
        lengths; fewer than 2 samples; a non-numeric, NaN or infinite value;
        time not strictly increasing or (with ``check_regular``) irregular;
        angles beyond ±4π rad (degrees); a negative or fractional
        ``collision_id``. The message names the column and the first bad row.
    DimensionError
        ``n_dof`` differs from the joint count of the log.
    InputValueError
        ``n_dof`` or ``rtol`` is not a valid value.

    Examples
    --------
    >>> import pandas as pd
    >>> validate_table(pd.DataFrame({"t": [0.0, 0.1, 0.2], "q_1": [0.0, 0.1, 0.2]}))
    1
    >>> validate_table(pd.DataFrame({"t": [0.0, 0.1], "q_1": [0.0, 90.0]}))
    Traceback (most recent call last):
    ...
    sensorless.exceptions.LogFormatError: column 'q_1' looks like degrees, ...
    """
    expected = _check_n_dof(n_dof)
    tolerance = _check_rtol(rtol)
    if isinstance(df, pd.DataFrame):
        names: list[Any] = list(df.columns)
        duplicated = [name for name in names if names.count(name) > 1]
        if duplicated:
            raise LogFormatError(f"duplicate column(s) {_abbreviate(sorted(set(duplicated)))}")
        columns: Mapping[Any, ArrayLike] = {name: df[name].to_numpy() for name in names}
    elif isinstance(df, Mapping):
        names = list(df)
        columns = df
    else:
        raise LogFormatError(
            f"a log table must be a pandas DataFrame or a mapping of columns; got {type(df)}"
        )
    n_found, groups = _parse_columns(names, expected)

    ordered = ["t"] + [_column(g, j) for g in groups for j in range(1, n_found + 1)]
    if "collision_id" in names:
        ordered.append("collision_id")
    values = {name: _as_float_column(name, columns[name]) for name in ordered}
    lengths = {len(column) for column in values.values()}
    if len(lengths) > 1:
        raise LogFormatError(f"all columns must have the same length; got lengths {lengths}")
    n_samples = lengths.pop()
    if n_samples < 2:
        raise LogFormatError(
            f"a log needs at least 2 samples to define its time base; got {n_samples}"
        )
    for name, column in values.items():
        bad = np.flatnonzero(~np.isfinite(column))
        if bad.size:
            row = int(bad[0])
            raise LogFormatError(
                f"column {name!r} must be finite; row {row} holds {_value(column[row])}"
            )
    if "collision_id" in values:
        _check_collision_id(values["collision_id"])
    _check_time(values["t"], check_regular, tolerance)
    for group in _ANGLE_GROUPS:
        if group in groups:
            for joint in range(1, n_found + 1):
                name = _column(group, joint)
                _check_angles(name, values[name])
    return n_found


# --------------------------------------------------------------------------- the Log object


def _normalise_metadata(metadata: Any) -> dict[str, Any]:
    """Return a JSON round-tripped copy, so that a written and re-read log compare equal."""
    if not isinstance(metadata, Mapping):
        raise InputValueError(f"metadata must be a dict; got {type(metadata).__name__}")

    def to_builtin(value: Any) -> Any:
        if isinstance(value, np.generic):
            return value.item()
        if isinstance(value, np.ndarray):
            return value.tolist()
        raise TypeError(f"object of type {type(value).__name__} is not JSON serializable")

    try:
        text = json.dumps(dict(metadata), default=to_builtin, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputValueError(
            "metadata must be JSON-serialisable (dicts with string keys, lists, strings, "
            f"finite numbers, booleans, None); {exc}"
        ) from None
    result: dict[str, Any] = json.loads(text)
    return result


def _frozen(values: ArrayLike, dtype: type[np.generic]) -> Any:
    arr = np.array(values, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Log:
    """One robot run: time, measured joint positions, torques and labels.

    Arrays are copied to float64 (``collision_id`` to int64) and made
    read-only; the constructor validates them with :func:`validate_table`
    (without the regularity check, so that a jittery log read with
    ``check_regular=False`` can be passed to :func:`resample`).

    Parameters
    ----------
    t : array-like of shape (n_samples,)
        Time stamps [s], strictly increasing.
    q : array-like of shape (n_samples, n_dof)
        Measured joint positions [rad].
    tau_m : array-like of shape (n_samples, n_dof), optional
        Motor / commanded joint torques [N m].
    tau_j : array-like of shape (n_samples, n_dof), optional
        Joint-torque-sensor torques [N m].
    q_true : array-like of shape (n_samples, n_dof), optional
        Ground-truth joint positions [rad].
    qd_true : array-like of shape (n_samples, n_dof), optional
        Ground-truth joint velocities [rad/s].
    tau_c : array-like of shape (n_samples, n_dof), optional
        Ground-truth external joint torques [N m].
    collision_id : array-like of shape (n_samples,), optional
        Integer collision label, 0 = no collision.
    metadata : dict
        JSON-serialisable description of the run (scenario, seed, robot,
        nominal_robot, sample_rate [Hz], units, library version, collisions,
        ...). Stored as a JSON round-tripped copy (numpy scalars become
        Python numbers, tuples become lists).

    Raises
    ------
    DimensionError
        An array does not have the shape above.
    LogFormatError
        The values fail :func:`validate_table`.
    InputValueError
        ``metadata`` is not JSON-serialisable.
    """

    t: FloatArray
    q: FloatArray
    tau_m: FloatArray | None = None
    tau_j: FloatArray | None = None
    q_true: FloatArray | None = None
    qd_true: FloatArray | None = None
    tau_c: FloatArray | None = None
    collision_id: IntArray | None = None
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t)
        if t.ndim != 1:
            raise DimensionError(f"t must have shape (n_samples,); got shape {t.shape}")
        n_samples = t.shape[0]
        q = np.asarray(self.q)
        if q.ndim != 2 or q.shape[0] != n_samples or q.shape[1] < 1:
            raise DimensionError(
                f"q must have shape (n_samples, n_dof) = ({n_samples}, n_dof) with "
                f"n_samples = len(t) = {n_samples} and n_dof >= 1; got shape {q.shape}"
            )
        groups: dict[str, NDArray[Any]] = {"q": q}
        for group in _OPTIONAL_GROUPS:
            value = getattr(self, group)
            if value is not None:
                arr = np.asarray(value)
                if arr.shape != q.shape:
                    raise DimensionError(
                        f"{group} must have the shape of q, (n_samples, n_dof) = {q.shape}; "
                        f"got shape {arr.shape}"
                    )
                groups[group] = arr
        collision_id = None
        if self.collision_id is not None:
            collision_id = np.asarray(self.collision_id)
            if collision_id.shape != (n_samples,):
                raise DimensionError(
                    f"collision_id must have shape (n_samples,) = ({n_samples},); "
                    f"got shape {collision_id.shape}"
                )
        columns: dict[str, ArrayLike] = {"t": t}
        for group, arr in groups.items():
            for joint in range(q.shape[1]):
                columns[_column(group, joint + 1)] = arr[:, joint]
        if collision_id is not None:
            columns["collision_id"] = collision_id
        validate_table(columns, check_regular=False)

        object.__setattr__(self, "t", _frozen(t, np.float64))
        for group, arr in groups.items():
            object.__setattr__(self, group, _frozen(arr, np.float64))
        if collision_id is not None:
            object.__setattr__(self, "collision_id", _frozen(collision_id, np.int64))
        object.__setattr__(self, "metadata", _normalise_metadata(self.metadata))

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.q.shape[1])

    @property
    def n_samples(self) -> int:
        """Number of samples (rows)."""
        return int(self.t.shape[0])

    @property
    def dt(self) -> float:
        """Median sample period [s]."""
        return float(np.median(np.diff(self.t)))

    @property
    def duration(self) -> float:
        """Time from the first to the last sample [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def groups(self) -> list[str]:
        """Present per-joint groups in table order, e.g. ``['q', 'tau_m']``."""
        return [group for group in JOINT_GROUPS if getattr(self, group) is not None]

    @property
    def columns(self) -> list[str]:
        """Column names of :meth:`to_pandas`, in order."""
        names = ["t"] + [
            _column(group, joint) for group in self.groups for joint in range(1, self.n_dof + 1)
        ]
        if self.collision_id is not None:
            names.append("collision_id")
        return names

    def to_pandas(self) -> pd.DataFrame:
        """Return the log as a table.

        Returns
        -------
        DataFrame
            Columns ``t``, then ``q_1..q_n``, ``tau_m_1..``, ``tau_j_1..``,
            ``q_true_1..``, ``qd_true_1..``, ``tau_c_1..`` (present groups only,
            1-based joint numbers, float64) and ``collision_id`` (int64) if present.
        """
        data: dict[str, NDArray[Any]] = {"t": self.t}
        for group in self.groups:
            arr = getattr(self, group)
            for joint in range(self.n_dof):
                data[_column(group, joint + 1)] = arr[:, joint]
        if self.collision_id is not None:
            data["collision_id"] = self.collision_id
        return pd.DataFrame(data)

    @classmethod
    def from_pandas(
        cls,
        df: pd.DataFrame,
        metadata: Mapping[str, Any] | None = None,
        n_dof: int | None = None,
        *,
        check_regular: bool = True,
        rtol: float = 1e-6,
    ) -> Log:
        """Build a log from a table with the columns of :meth:`to_pandas`.

        Parameters
        ----------
        df : DataFrame
            The table; column order does not matter.
        metadata : dict, optional
            Description of the run (JSON-serialisable).
        n_dof : int, optional
            Number of joints of the robot; checked against the table.
        check_regular, rtol
            As in :func:`validate_table`.

        Raises
        ------
        LogFormatError, DimensionError
            As :func:`validate_table`.
        """
        n_found = validate_table(df, n_dof, check_regular=check_regular, rtol=rtol)
        arrays: dict[str, Any] = {}
        for group in JOINT_GROUPS:
            names = [_column(group, joint) for joint in range(1, n_found + 1)]
            if names[0] in df.columns:
                arrays[group] = np.column_stack(
                    [_as_float_column(name, df[name].to_numpy()) for name in names]
                )
        if "collision_id" in df.columns:
            arrays["collision_id"] = _as_float_column(
                "collision_id", df["collision_id"].to_numpy()
            ).astype(np.int64)
        return cls(
            t=_as_float_column("t", df["t"].to_numpy()),
            metadata=dict(metadata) if metadata is not None else {},
            **arrays,
        )

    def slice(self, start: float | None = None, stop: float | None = None) -> Log:
        """Return the samples with ``start <= t < stop`` as a new log.

        Parameters
        ----------
        start, stop : float, optional
            Time bounds [s] (absolute time stamps, as in ``t``); None means
            unbounded. The time stamps are kept, not shifted to zero; the
            metadata is copied unchanged.

        Raises
        ------
        InputValueError
            A bound is not a number, ``stop <= start``, or fewer than 2
            samples fall in the interval.
        """
        lower = -math.inf if start is None else _time_bound(start, "start")
        upper = math.inf if stop is None else _time_bound(stop, "stop")
        if upper <= lower:
            raise InputValueError(f"stop must be after start; got start={start!r}, stop={stop!r}")
        first = int(np.searchsorted(self.t, lower, side="left"))
        last = int(np.searchsorted(self.t, upper, side="left"))
        if last - first < 2:
            raise InputValueError(
                f"the interval [{lower!r}, {upper!r}) s holds {last - first} sample(s) of the "
                f"log, which spans [{_value(self.t[0])}, {_value(self.t[-1])}] s; "
                "a log needs at least 2"
            )
        changes: dict[str, Any] = {"t": self.t[first:last]}
        for group in self.groups:
            changes[group] = getattr(self, group)[first:last]
        if self.collision_id is not None:
            changes["collision_id"] = self.collision_id[first:last]
        return dataclasses.replace(self, **changes)


def _time_bound(value: Any, name: str) -> float:
    try:
        bound = float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be a time [s] or None; got {value!r}") from None
    if math.isnan(bound):
        raise InputValueError(f"{name} must be a time [s] or None; got {value!r}")
    return bound


# --------------------------------------------------------------------------- resampling


def resample(log: Log, dt: float) -> Log:
    """Put a log on a regular time grid by linear interpolation.

    This is the explicit alternative to the irregular-time error of
    :func:`read_log`: read a jittery log with ``check_regular=False`` and
    resample it. The new grid is ``t[0] + k * dt`` for every ``k`` that stays
    within the log. Joint quantities are interpolated linearly;
    ``collision_id`` takes the value of the latest original sample at or
    before each grid time (zero-order hold), so a label shorter than ``dt``
    can fall between grid points.

    Parameters
    ----------
    log : Log
        The log to resample (any time base).
    dt : float
        New sample period [s].

    Returns
    -------
    Log
        The resampled log; its metadata is a copy with ``sample_rate`` [Hz]
        set to ``1 / dt`` and a ``resampled`` entry recording the operation.

    Raises
    ------
    InputValueError
        ``dt`` is not positive and finite, or longer than the log.

    Examples
    --------
    >>> import numpy as np
    >>> log = Log(t=[0.0, 0.09, 0.2], q=[[0.0], [0.09], [0.2]])
    >>> new = resample(log, 0.05)
    >>> new.t.round(12).tolist(), new.q[:, 0].round(12).tolist()
    ([0.0, 0.05, 0.1, 0.15, 0.2], [0.0, 0.05, 0.1, 0.15, 0.2])
    """
    step = check_dt(dt)
    # A relative slack of 1e-9 keeps the last sample when duration / dt is an integer
    # that floating point puts just below itself.
    n_samples = math.floor(log.duration / step + 1e-9) + 1
    if n_samples < 2:
        raise InputValueError(
            f"dt = {step!r} s is longer than the log ({log.duration!r} s); the resampled log "
            "would have fewer than 2 samples"
        )
    grid = log.t[0] + step * np.arange(n_samples)
    changes: dict[str, Any] = {"t": grid}
    for group in log.groups:
        values = getattr(log, group)
        changes[group] = np.column_stack(
            [np.interp(grid, log.t, values[:, joint]) for joint in range(log.n_dof)]
        )
    if log.collision_id is not None:
        previous = np.searchsorted(log.t, grid, side="right") - 1
        changes["collision_id"] = log.collision_id[np.clip(previous, 0, log.n_samples - 1)]
    metadata = dict(log.metadata)
    metadata["sample_rate"] = 1.0 / step
    metadata["resampled"] = {
        "dt": step,
        "method": "linear (collision_id: previous sample)",
        "n_samples_before": log.n_samples,
    }
    changes["metadata"] = metadata
    return dataclasses.replace(log, **changes)


# --------------------------------------------------------------------------- files


def sidecar_path(path: str | Path) -> Path:
    """Path of the metadata sidecar of the log file ``path``: ``<path>.meta.json``."""
    path = Path(path)
    return path.with_name(path.name + _SIDECAR_SUFFIX)


def _check_format(format: Any) -> str:
    if format not in FORMATS:
        raise InputValueError(f"format must be one of {list(FORMATS)} or None; got {format!r}")
    return str(format)


def _library_version() -> str:
    try:
        return importlib_metadata.version("sensorless")
    except importlib_metadata.PackageNotFoundError:
        return "unknown"


def write_log(log: Log, path: str | Path, format: str | None = None) -> Path:
    """Write a log table and its metadata sidecar ``<path>.meta.json``.

    Parameters
    ----------
    log : Log
        The log to write.
    path : str or Path
        Destination of the table.
    format : {'parquet', 'csv'}, optional
        File format; by default taken from the suffix (``.csv`` -> CSV,
        ``.parquet``/``.pq`` -> Parquet) and Parquet for any other suffix.

    Returns
    -------
    Path
        ``path``.

    Notes
    -----
    Parquet stores float64 exactly; CSV writes every float with 17
    significant digits (``%.17g``), which also reads back exactly. The same
    log written twice gives the same bytes for CSV and the same table for
    Parquet. The sidecar is pretty-printed JSON with ``format``, ``n_dof``,
    ``n_samples``, ``columns``, ``units``, ``sample_rate`` [Hz] (from the
    median step), ``sensorless_version`` and the user ``metadata``.

    Raises
    ------
    InputValueError
        ``format`` is not one of ``'parquet'``, ``'csv'`` or None.
    """
    path = Path(path)
    if format is None:
        fmt = _SUFFIXES.get(path.suffix.lower(), "parquet")
    else:
        fmt = _check_format(format)
    table = log.to_pandas()
    if fmt == "parquet":
        table.to_parquet(path, engine="pyarrow", index=False)
    else:
        table.to_csv(path, index=False, float_format="%.17g", lineterminator="\n")
    present = ["t", *log.groups] + (["collision_id"] if log.collision_id is not None else [])
    sidecar = {
        "format": fmt,
        "format_version": _FORMAT_VERSION,
        "sensorless_version": _library_version(),
        "n_dof": log.n_dof,
        "n_samples": log.n_samples,
        "columns": list(table.columns),
        "units": {name: UNITS[name] for name in present},
        "sample_rate": 1.0 / log.dt,
        "metadata": log.metadata,
    }
    sidecar_path(path).write_text(
        json.dumps(sidecar, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    return path


def _read_sidecar(path: Path) -> dict[str, Any] | None:
    meta_path = sidecar_path(path)
    if not meta_path.exists():
        return None
    try:
        sidecar = json.loads(meta_path.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise LogFormatError(f"metadata sidecar {meta_path} is not valid JSON: {exc}") from None
    if not isinstance(sidecar, dict):
        raise LogFormatError(
            f"metadata sidecar {meta_path} must hold a JSON object; got {type(sidecar).__name__}"
        )
    if not isinstance(sidecar.get("metadata", {}), dict):
        raise LogFormatError(f"'metadata' in {meta_path} must be a JSON object")
    return sidecar


def read_log(
    path: str | Path,
    n_dof: int | None = None,
    *,
    format: str | None = None,
    check_regular: bool = True,
    rtol: float = 1e-6,
) -> Log:
    """Read and validate a log written by :func:`write_log` (or by hand).

    Parameters
    ----------
    path : str or Path
        The table file.
    n_dof : int, optional
        Number of joints of the robot the log is for; checked against the log.
    format : {'parquet', 'csv'}, optional
        File format; by default from the suffix, else from the sidecar.
    check_regular : bool
        Require a regular time base (see :func:`validate_table`); pass False
        to read a jittery log and then :func:`resample` it.
    rtol : float
        Relative tolerance of the regularity check.

    Returns
    -------
    Log
        With the sidecar's user metadata, or empty metadata when the file
        has no sidecar.

    Raises
    ------
    LogFormatError
        The format cannot be determined, the file cannot be parsed, the table
        fails :func:`validate_table`, or the sidecar is invalid or disagrees
        with the table (``n_dof``, ``columns``).
    DimensionError
        ``n_dof`` differs from the joint count of the log.
    FileNotFoundError
        ``path`` does not exist.
    """
    path = Path(path)
    sidecar = _read_sidecar(path)
    if format is not None:
        fmt = _check_format(format)
    elif path.suffix.lower() in _SUFFIXES:
        fmt = _SUFFIXES[path.suffix.lower()]
    elif sidecar is not None and sidecar.get("format") in FORMATS:
        fmt = str(sidecar["format"])
    else:
        raise LogFormatError(
            f"cannot tell the format of {path} from its suffix {path.suffix!r}; known "
            f"suffixes are {sorted(_SUFFIXES)}, or pass format= one of {list(FORMATS)}"
        )
    if not path.exists():
        raise FileNotFoundError(f"log file {path} does not exist")
    try:
        if fmt == "parquet":
            table = pd.read_parquet(path, engine="pyarrow")
        else:
            table = pd.read_csv(path, **_CSV_READ_OPTIONS)
    except ValueError as exc:
        raise LogFormatError(f"cannot read {path} as {fmt}: {exc}") from None
    metadata = sidecar.get("metadata", {}) if sidecar is not None else {}
    log = Log.from_pandas(table, metadata, n_dof, check_regular=check_regular, rtol=rtol)
    if sidecar is not None:
        meta_path = sidecar_path(path)
        if "n_dof" in sidecar and sidecar["n_dof"] != log.n_dof:
            raise LogFormatError(
                f"sidecar {meta_path} says n_dof = {sidecar['n_dof']!r}, but the table "
                f"{path} has {log.n_dof} joints"
            )
        if "columns" in sidecar and list(sidecar["columns"]) != list(table.columns):
            raise LogFormatError(
                f"sidecar {meta_path} lists columns {_abbreviate(list(sidecar['columns']))}, "
                f"but the table {path} has {_abbreviate(list(table.columns))}"
            )
    return log
