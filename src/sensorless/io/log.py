"""The :class:`Log` object: one validated robot run, and the operations on it.

A :class:`Log` holds the columns of the :mod:`sensorless.io` layout as
read-only arrays, always validated by :func:`~sensorless.io.validate_table`.
:meth:`Log.slice` cuts it in time; putting it on a regular grid and cutting it
at its gaps is :mod:`sensorless.io.timebase`, reading and writing files
:mod:`sensorless.io.files`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray
from ..exceptions import DimensionError, InputValueError
from .columns import JOINT_GROUPS, OPTIONAL_GROUPS, column_name, show_value
from .validate import TableChecks, as_float_column, validate_table

if TYPE_CHECKING:
    from typing import Unpack

__all__ = ["Log"]

IntArray = NDArray[np.int64]


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


def _is_frozen(arr: NDArray[Any]) -> bool:
    """True if ``arr`` and every array it views are read-only, so nothing can write to it."""
    base: Any = arr
    while isinstance(base, np.ndarray):
        if base.flags.writeable:
            return False
        if base.base is None:
            return True
        base = base.base
    # A view of a foreign buffer (bytes, mmap, ...): its owner may still write to it.
    return False


def _frozen(values: ArrayLike, dtype: type[np.generic]) -> Any:
    if isinstance(values, np.ndarray) and values.dtype == dtype and _is_frozen(values):
        # Already read-only (another log's array, or one handed over by an importer):
        # sharing it saves a copy of a long recording.
        return values
    arr = np.array(values, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Log:
    """One robot run: time, measured joint positions, torques and labels.

    Arrays are copied to float64 (``collision_id`` to int64) and made
    read-only; an array that is already a read-only float64 (int64) array,
    such as another log's, is shared instead of copied. The constructor
    validates them with :func:`~sensorless.io.validate_table` (without the
    regularity check, so that a jittery log read with ``check_regular=False``
    can be passed to :func:`~sensorless.io.resample`).

    Parameters
    ----------
    t : array-like of shape (n_samples,)
        Time stamps [s], strictly increasing.
    q : array-like of shape (n_samples, n_dof)
        Measured joint positions [rad].
    qd : array-like of shape (n_samples, n_dof), optional, keyword-only
        Measured joint velocities [rad/s], as the robot's controller reports
        them (not the simulator's ground truth ``qd_true``).
    tau_m : array-like of shape (n_samples, n_dof), optional
        Motor / commanded joint torques [N m].
    tau_j : array-like of shape (n_samples, n_dof), optional
        Joint-torque-sensor torques [N m].
    tau_ext : array-like of shape (n_samples, n_dof), optional, keyword-only
        The robot vendor's own external-torque estimate [N m] (e.g. Franka's
        ``tau_ext_hat_filtered``), a baseline to compare residuals with.
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
    allow_missing : bool, keyword-only
        Accept NaN or inf in the joint groups as samples the recorder lost
        (the time column must still be finite). Such a log can be *monitored*
        (:meth:`sensorless.monitor.CollisionMonitor.process` reports the spans
        as faults and restarts after them); observers and tuning refuse it.

    Raises
    ------
    DimensionError
        An array does not have the shape above.
    LogFormatError
        The values fail :func:`~sensorless.io.validate_table`.
    InputValueError
        ``metadata`` is not JSON-serialisable.
    """

    t: FloatArray
    q: FloatArray
    # Keyword-only: added after the other fields, they must not shift positional arguments.
    qd: FloatArray | None = field(default=None, kw_only=True)
    tau_m: FloatArray | None = None
    tau_j: FloatArray | None = None
    tau_ext: FloatArray | None = field(default=None, kw_only=True)
    q_true: FloatArray | None = None
    qd_true: FloatArray | None = None
    tau_c: FloatArray | None = None
    collision_id: IntArray | None = None
    metadata: dict[str, Any] = field(default_factory=dict)
    allow_missing: bool = field(default=False, kw_only=True)

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
        for group in OPTIONAL_GROUPS:
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
                columns[column_name(group, joint + 1)] = arr[:, joint]
        if collision_id is not None:
            columns["collision_id"] = collision_id
        validate_table(columns, check_regular=False, allow_missing=self.allow_missing)

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
            column_name(group, joint) for group in self.groups for joint in range(1, self.n_dof + 1)
        ]
        if self.collision_id is not None:
            names.append("collision_id")
        return names

    def to_pandas(self) -> pd.DataFrame:
        """Return the log as a table.

        Returns
        -------
        DataFrame
            Columns ``t``, then ``q_1..q_n``, ``qd_1..``, ``tau_m_1..``,
            ``tau_j_1..``, ``tau_ext_1..``, ``q_true_1..``, ``qd_true_1..``,
            ``tau_c_1..`` (present groups only, 1-based joint numbers, float64)
            and ``collision_id`` (int64) if present.
        """
        data: dict[str, NDArray[Any]] = {"t": self.t}
        for group in self.groups:
            arr = getattr(self, group)
            for joint in range(self.n_dof):
                data[column_name(group, joint + 1)] = arr[:, joint]
        if self.collision_id is not None:
            data["collision_id"] = self.collision_id
        return pd.DataFrame(data)

    @classmethod
    def from_pandas(
        cls,
        df: pd.DataFrame,
        metadata: Mapping[str, Any] | None = None,
        n_dof: int | None = None,
        **checks: Unpack[TableChecks],
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
        check_regular, rtol, allow_missing : keyword-only
            As in :func:`~sensorless.io.validate_table`.

        Raises
        ------
        LogFormatError, DimensionError
            As :func:`~sensorless.io.validate_table`.
        """
        n_found = validate_table(df, n_dof, **checks)
        arrays: dict[str, Any] = {}
        for group in JOINT_GROUPS:
            names = [column_name(group, joint) for joint in range(1, n_found + 1)]
            if names[0] in df.columns:
                arrays[group] = np.column_stack(
                    [as_float_column(name, df[name].to_numpy()) for name in names]
                )
        if "collision_id" in df.columns:
            arrays["collision_id"] = as_float_column(
                "collision_id", df["collision_id"].to_numpy()
            ).astype(np.int64)
        return cls(
            t=as_float_column("t", df["t"].to_numpy()),
            metadata=dict(metadata) if metadata is not None else {},
            allow_missing=checks.get("allow_missing", False),
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
                f"log, which spans [{show_value(self.t[0])}, {show_value(self.t[-1])}] s; "
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
