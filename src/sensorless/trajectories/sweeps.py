"""Constant-velocity friction experiments: one joint at a time (thesis §2.4.1-2.4.2).

Plateaus of constant velocity joined by cosine ramps, in pairs ``+v, -v``
so that each joint ends its sweep at rest where it started.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt, per_joint
from ..exceptions import DimensionError, InputTypeError, InputValueError
from .base import Evaluation, Trajectory, _check_radians, _vector

__all__ = ["VelocitySweep", "sweep_velocities"]


def _ramp_shape(tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cosine ramp ``s(τ) = (1 - cos πτ) / 2`` on ``0 <= τ <= 1``: its integral, value, slope.

    ``s`` goes from 0 to 1 with zero slope at both ends, so a velocity
    ``v0 + (v1 - v0) s`` joins two plateaus with a continuous acceleration.
    """
    integral = 0.5 * tau - np.sin(np.pi * tau) / (2.0 * np.pi)
    value = 0.5 * (1.0 - np.cos(np.pi * tau))
    slope = 0.5 * np.pi * np.sin(np.pi * tau)
    return integral, value, slope


def _grid(lo: float, hi: float, step: float) -> FloatArray:
    if not (np.isfinite([lo, hi, step]).all() and step > 0.0 and hi >= lo):
        raise InputValueError(
            f"a sweep must be (low, high, step) with low <= high and step > 0; got {(lo, hi, step)}"
        )
    n = int(np.floor((hi - lo) / step + 1e-9))
    # Rounding removes the float noise of lo + k*step so that both sweeps share values.
    return np.round(lo + step * np.arange(n + 1), 12)


def sweep_velocities(
    fast: tuple[float, float, float] = (-2.0, 2.0, 0.16),
    slow: tuple[float, float, float] = (-0.11, 0.11, 0.01),
) -> FloatArray:
    """Constant velocities of the friction experiments, thesis §2.4.1.

    Parameters
    ----------
    fast : tuple (low, high, step), default (-2, 2, 0.16)
        Wide sweep [rad/s].
    slow : tuple (low, high, step), default (-0.11, 0.11, 0.01)
        Slow sweep [rad/s].

    Returns
    -------
    velocities : ndarray of shape (n_velocities,)
        Sorted, unique velocities of both sweeps [rad/s]; zero is excluded.

    Examples
    --------
    >>> v = sweep_velocities()
    >>> v.size, float(v[0]), float(v[-1]), bool((v != 0).all())
    (46, -2.0, 2.0, True)
    """
    values = np.unique(np.concatenate([_grid(*fast), _grid(*slow)]))
    return values[values != 0.0]


class VelocitySweep(Trajectory):
    """Constant-velocity friction experiment: one joint at a time (thesis §2.4.1-2.4.2).

    Each joint of ``joints`` in turn visits every velocity of
    ``velocities`` as a plateau of ``hold`` seconds while the other joints
    rest at ``home``. Consecutive plateaus are joined by cosine velocity
    ramps of ``ramp`` seconds, ``qd = v0 + (v1 - v0) (1 - cos πτ) / 2`` with
    ``τ`` from 0 to 1, so the acceleration is continuous, zero on the
    plateaus and at most ``π |v1 - v0| / (2 ramp)`` [rad/s²].

    The velocities must come in pairs ``+v, -v``: each joint visits the
    speeds in increasing order, ``+v`` then ``-v`` for each, so every pair
    goes out and comes back by the same distance ``v · hold``, and the ramp
    displacements cancel over the sequence; the joint ends its sweep at rest
    at ``home``. The excursion of a pair is one-sided, of about
    ``v (hold + ramp)``; it is put on the side of ``home`` with more room in
    ``position_limits`` (the sign order becomes ``-v, +v`` when there is more
    room below). The exact travel is checked at construction.

    Parameters
    ----------
    home : array-like of shape (n_dof,)
        Rest pose [rad]; every joint starts and ends its sweep there.
    joints : int or sequence of int, optional
        Joints to sweep, numbered from 1, in the order given; all joints by
        default.
    velocities : array-like of shape (n_velocities,), optional
        Plateau velocities [rad/s], nonzero, in pairs ``+v, -v`` (matched
        to 1e-9 rad/s; the negative ones are then taken as the exact mirror
        of the positive ones); duplicates are dropped. By default the thesis's
        :func:`sweep_velocities`.
    hold : float, default 1.0
        Duration of each plateau [s].
    ramp : float, default 0.5
        Duration of each velocity ramp between plateaus [s].
    position_limits : (lower, upper), optional
        Joint limits [rad], each a float or an array of shape (n_dof,),
        e.g. ``robot.position_limits``. ``home`` must lie inside them and
        the sweep must stay inside them. No travel check by default.

    Raises
    ------
    DimensionError
        If an array has the wrong shape.
    InputValueError
        If ``joints`` is not a list of distinct joint numbers in
        ``1..n_dof``, a velocity is zero or lacks its opposite, ``hold`` or
        ``ramp`` is not positive, ``home`` is outside ``position_limits``, or
        a joint would leave ``position_limits`` during its sweep.

    Examples
    --------
    >>> sweep = VelocitySweep([0.0, 0.5], joints=[2], velocities=[-0.2, 0.2], hold=2.0)
    >>> sweep.schedule()
       joint  velocity  start  end
    0      2       0.2    0.5  2.5
    1      2      -0.2    3.0  5.0
    >>> q, qd, qdd = sweep.evaluate(1.5)
    >>> float(qd[1]), float(qdd[1]), float(q[0])
    (0.2, 0.0, 0.0)
    >>> float(sweep.evaluate(sweep.duration)[0][1])  # back home
    0.5
    """

    def __init__(
        self,
        home: ArrayLike,
        joints: int | ArrayLike | None = None,
        velocities: ArrayLike | None = None,
        *,
        hold: float = 1.0,
        ramp: float = 0.5,
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        home_arr = _vector(home, "home", "n_dof", 1, "one joint [rad]")
        _check_radians(home_arr, "home")
        n_dof = home_arr.size
        if velocities is None:
            velocities = sweep_velocities()
        self.home = home_arr
        self.joints = self._check_joints(joints, n_dof)
        self.velocities = self._check_velocities(velocities)
        self.hold = check_dt(hold, "hold")
        self.ramp = check_dt(ramp, "ramp")
        self.position_limits = self._check_limits(position_limits, home_arr)
        for arr in (self.home, self.velocities, *self.position_limits):
            arr.setflags(write=False)
        self._build_segments()
        self._check_travel()

    @staticmethod
    def _check_joints(joints: int | ArrayLike | None, n_dof: int) -> tuple[int, ...]:
        if joints is None:
            return tuple(range(1, n_dof + 1))
        values = np.atleast_1d(np.asarray(joints))
        valid = values.ndim == 1 and values.size > 0 and values.dtype.kind in "iu"
        if not valid or np.any((values < 1) | (values > n_dof)):
            raise InputValueError(
                f"joints must be joint numbers from 1 to n_dof = {n_dof}; got {joints!r}"
            )
        if np.unique(values).size != values.size:
            raise InputValueError(f"joints must be distinct; got {values.tolist()}")
        return tuple(int(j) for j in values)

    @staticmethod
    def _check_velocities(velocities: ArrayLike) -> FloatArray:
        arr = _vector(velocities, "velocities", "n_velocities", 1, "one pair +v, -v [rad/s]")
        if (arr == 0.0).any():
            raise InputValueError(
                f"velocities must be nonzero [rad/s] (a zero velocity is a rest, not a friction "
                f"measurement); got 0 at index {int(np.argmax(arr == 0.0))}"
            )
        positive, negative = np.unique(arr[arr > 0.0]), np.unique(-arr[arr < 0.0])
        matched = np.abs(positive[:, None] - negative[None, :]) <= 1e-9
        unpaired = [*positive[~matched.any(axis=1)], *(-negative[~matched.any(axis=0)])]
        if unpaired:
            raise InputValueError(
                "velocities must come in pairs +v, -v so that each joint returns home; "
                f"got no opposite for {sorted(float(v) for v in unpaired)} rad/s"
            )
        return np.concatenate([-positive[::-1], positive])

    @staticmethod
    def _check_limits(
        limits: tuple[ArrayLike, ArrayLike] | None, home: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        n_dof = home.size
        if limits is None:
            return np.full(n_dof, -np.inf), np.full(n_dof, np.inf)
        if len(limits) != 2:
            raise DimensionError(
                f"position_limits must be a pair (lower, upper) [rad]; got {len(limits)} items"
            )
        # ±inf is a side without a stop.
        lower = per_joint(limits[0], n_dof, "position_limits lower", "rad", allow_inf=True)
        upper = per_joint(limits[1], n_dof, "position_limits upper", "rad", allow_inf=True)
        if (lower >= upper).any():
            j = int(np.argmax(lower >= upper))
            raise InputValueError(
                f"position_limits must have lower < upper [rad]; joint {j + 1} has "
                f"[{lower[j]:.6g}, {upper[j]:.6g}]"
            )
        outside = (home < lower) | (home > upper)
        if outside.any():
            j = int(np.argmax(outside))
            raise InputValueError(
                f"home must lie inside position_limits; joint {j + 1} has home = "
                f"{home[j]:.6g} rad, limits [{lower[j]:.6g}, {upper[j]:.6g}] rad"
            )
        return lower, upper

    def _build_segments(self) -> None:
        """Segments ``(start, duration, joint index, v0, v1, q0)``: plateaus and ramps."""
        lower, upper = self.position_limits
        speeds = self.velocities[self.velocities > 0.0]
        rows: list[tuple[float, float, int, float, float, float]] = []
        t = 0.0
        for joint in self.joints:
            j = joint - 1
            # The excursion of each pair goes to the side of home with more room.
            first = 1.0 if upper[j] - self.home[j] >= self.home[j] - lower[j] else -1.0
            plateaus = np.ravel(np.column_stack([first * speeds, -first * speeds])).tolist()
            q = float(self.home[j])
            segments = [(0.0, plateaus[0], self.ramp)]
            for v, following in zip(plateaus, [*plateaus[1:], 0.0], strict=True):
                segments += [(v, v, self.hold), (v, following, self.ramp)]
            for v0, v1, length in segments:
                rows.append((t, length, j, v0, v1, q))
                t += length
                q += 0.5 * length * (v0 + v1)
        table = np.array(rows)
        self._start = table[:, 0]
        self._length = table[:, 1]
        self._joint = table[:, 2].astype(np.intp)
        self._v0, self._v1, self._q0 = table[:, 3], table[:, 4], table[:, 5]
        self._duration = t

    def _segment_extremes(self) -> tuple[FloatArray, FloatArray]:
        """Lowest and highest position [rad] of each segment (exact)."""
        end = self._q0 + 0.5 * self._length * (self._v0 + self._v1)
        low, high = np.minimum(self._q0, end), np.maximum(self._q0, end)
        reverses = self._v0 * self._v1 < 0.0
        # Where a ramp reverses, the position turns at s(τ) = v0 / (v0 - v1).
        s = np.where(reverses, self._v0 / np.where(reverses, self._v0 - self._v1, 1.0), 0.0)
        tau = np.arccos(1.0 - 2.0 * s) / np.pi
        integral = _ramp_shape(tau)[0]
        turn = self._q0 + self._length * (self._v0 * tau + (self._v1 - self._v0) * integral)
        low = np.where(reverses, np.minimum(low, turn), low)
        high = np.where(reverses, np.maximum(high, turn), high)
        return low, high

    def _check_travel(self) -> None:
        lower, upper = self.position_limits
        low, high = self._segment_extremes()
        for joint in self.joints:
            mine = self._joint == joint - 1
            q_min, q_max = float(low[mine].min()), float(high[mine].max())
            j = joint - 1
            if q_min < lower[j] or q_max > upper[j]:
                fastest = float(self.velocities[-1])
                raise InputValueError(
                    f"joint {joint} would travel over [{q_min:.4g}, {q_max:.4g}] rad during "
                    f"its sweep, outside position_limits [{lower[j]:.4g}, {upper[j]:.4g}] rad "
                    f"(home {self.home[j]:.4g} rad); a plateau at {fastest:g} rad/s alone "
                    f"covers {fastest * self.hold:.4g} rad: shorten hold ({self.hold:g} s) or "
                    f"ramp ({self.ramp:g} s), or drop the fastest velocities"
                )

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.home.size)

    @property
    def duration(self) -> float:
        """Duration of the whole sweep [s]."""
        return self._duration

    def schedule(self) -> pd.DataFrame:
        """The constant-velocity plateaus in time order.

        Returns
        -------
        schedule : DataFrame
            One row per plateau with columns ``joint`` (numbered from 1),
            ``velocity`` [rad/s], ``start`` and ``end`` [s].
        """
        plateau = self._v0 == self._v1
        return pd.DataFrame(
            {
                "joint": self._joint[plateau] + 1,
                "velocity": self._v0[plateau],
                "start": self._start[plateau],
                "end": self._start[plateau] + self._length[plateau],
            }
        )

    def to_dict(self) -> dict[str, Any]:
        """The sweep as plain Python values, SI units, for a YAML or JSON file.

        Returns
        -------
        dict
            ``{"type": "velocity_sweep", "home": [rad], "joints": [...],
            "velocities": [rad/s], "hold": [s], "ramp": [s]}``; the position
            limits are not included (a scenario takes them from its robot).
            :meth:`from_dict` rebuilds the same sweep.
        """
        return {
            "type": "velocity_sweep",
            "home": [float(v) for v in self.home],
            "joints": list(self.joints),
            "velocities": [float(v) for v in self.velocities],
            "hold": float(self.hold),
            "ramp": float(self.ramp),
        }

    @classmethod
    def from_dict(
        cls,
        spec: Mapping[str, Any],
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> VelocitySweep:
        """Build from a specification such as :meth:`to_dict` writes or a scenario holds.

        Parameters
        ----------
        spec : mapping
            Key ``home`` [rad] (required); optional ``type`` (must be
            ``"velocity_sweep"``), ``joints``, ``hold`` [s], ``ramp`` [s],
            and either ``velocities`` [rad/s] or the sweep tuples ``fast``
            and/or ``slow`` ``[low, high, step]`` [rad/s] of
            :func:`sweep_velocities`
            (``slow: null`` keeps the fast sweep alone).
        position_limits : (lower, upper), optional
            Joint limits [rad] checked at construction.

        Returns
        -------
        VelocitySweep

        Raises
        ------
        InputTypeError
            If ``spec`` is not a mapping or has unknown keys.
        InputValueError
            If ``home`` is missing, ``type`` is wrong, ``velocities`` is
            given together with ``fast``/``slow``, or for the checks of the
            constructor.

        Examples
        --------
        >>> spec = {"home": [0.0], "fast": [-1.0, 1.0, 0.5], "slow": None, "hold": 0.5}
        >>> VelocitySweep.from_dict(spec).velocities
        array([-1. , -0.5,  0.5,  1. ])
        """
        keys = ("type", "home", "joints", "velocities", "fast", "slow", "hold", "ramp")
        if not isinstance(spec, Mapping):
            raise InputTypeError(
                f"a velocity sweep specification must be a mapping with keys {list(keys)}; "
                f"got {type(spec).__name__}"
            )
        unknown = sorted(str(key) for key in spec if key not in keys)
        if unknown:
            raise InputTypeError(
                f"unknown keys {unknown} in a velocity sweep specification; valid keys: "
                f"{list(keys)}"
            )
        if "home" not in spec:
            raise InputValueError("a velocity sweep specification needs the key 'home' [rad]")
        kind = spec.get("type", "velocity_sweep")
        if kind != "velocity_sweep":
            raise InputValueError(
                f"type must be 'velocity_sweep' for a VelocitySweep specification; got {kind!r}"
            )
        velocities = spec.get("velocities")
        if "fast" in spec or "slow" in spec:
            if velocities is not None:
                raise InputValueError(
                    "give either 'velocities' or the sweep tuples 'fast'/'slow', not both"
                )
            fast = tuple(spec.get("fast", (-2.0, 2.0, 0.16)))
            slow = spec.get("slow", (-0.11, 0.11, 0.01))
            velocities = sweep_velocities(fast, fast if slow is None else tuple(slow))
        return cls(
            spec["home"],
            spec.get("joints"),
            velocities,
            hold=spec.get("hold", 1.0),
            ramp=spec.get("ramp", 0.5),
            position_limits=position_limits,
        )

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        index = np.clip(np.searchsorted(self._start, t, side="right") - 1, 0, None)
        length = self._length[index]
        tau = np.clip((t - self._start[index]) / length, 0.0, 1.0)
        v0, dv = self._v0[index], self._v1[index] - self._v0[index]
        integral, value, slope = _ramp_shape(tau)
        rows = np.arange(t.size)
        columns = self._joint[index]
        q = np.tile(self.home, (t.size, 1))
        qd = np.zeros_like(q)
        qdd = np.zeros_like(q)
        q[rows, columns] = self._q0[index] + length * (v0 * tau + dv * integral)
        qd[rows, columns] = v0 + dv * value
        qdd[rows, columns] = dv * slope / length
        return q, qd, qdd
