"""External contacts with ground truth: τ_c = J_c(q)ᵀ [f_c; m_c], eq. (5.34).

A collision is a force applied at a point fixed on one link. Its magnitude
over time is a :class:`ForceProfile` (an impact :class:`HalfSine`, a
:class:`Push` that ramps up, holds and releases, or a :class:`Recorded`
force such as the hand force of thesis Fig. 5.5); its direction is a unit
vector in the base frame. :class:`Contact` maps it to joint torques through
the point Jacobian of :meth:`sensorless.robots.RobotModel.point_jacobian`,

    τ_c(t) = J_c(q)ᵀ [f(t) d; 0]                                 eq. (5.34)

with ``d`` the unit direction and no applied moment. :class:`ContactSet`
sums several contacts and gives the ground-truth label of every sample
(:meth:`ContactSet.active_id`) and the collision windows used to score a
detector. :meth:`ContactSet.random` draws a reproducible benchmark set from a
:class:`numpy.random.Generator`.

Units are SI: time [s], force [N], lengths [m], torques [N m]. Links are
numbered from 1 (the link moved by joint 1) to ``n_dof``.

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> robot = sl.robots.load("puma560")
>>> hit = Contact(1, link=3, point=[0.2, 0.0, 0.0], direction=[0, 0, -1],
...               profile=HalfSine(start=1.0, duration=0.2, peak=50.0))
>>> contacts = ContactSet([hit])
>>> tau_c = contacts.joint_torque(robot, np.zeros(6), 1.1)  # at the peak
>>> tau_c.shape, bool(np.all(tau_c[3:] == 0.0))
((6,), True)
>>> contacts.active_id(1.1), contacts.active_id(2.0)
(1, 0)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Any, overload

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray, as_joint_array
from ..exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    LogFormatError,
    UnknownNameError,
)
from ..robots.model import RobotModel

__all__ = [
    "PROFILE_KINDS",
    "Contact",
    "ContactSet",
    "ForceProfile",
    "HalfSine",
    "Push",
    "Recorded",
]

#: Profile kinds that :meth:`ContactSet.random` can draw.
PROFILE_KINDS: tuple[str, ...] = ("half_sine", "push")


def _number(
    value: Any, name: str, meaning: str, *, lower: float | None = None, strict: bool = False
) -> float:
    """Return ``value`` as a finite float, optionally bounded below; else InputValueError."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be a number ({meaning}); got {value!r}") from None
    if not math.isfinite(number):
        raise InputValueError(f"{name} must be finite ({meaning}); got {value!r}")
    if lower is not None and (number <= lower if strict else number < lower):
        relation = ">" if strict else ">="
        raise InputValueError(f"{name} must be {relation} {lower} ({meaning}); got {value!r}")
    return number


def _times(t: ArrayLike) -> FloatArray:
    try:
        arr = np.asarray(t, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(f"t must be a time or an array of times [s]; got {t!r}") from None
    if not np.isfinite(arr).all():
        raise InputValueError(f"t must be finite [s]; got {t!r}")
    return arr


class ForceProfile(ABC):
    """Magnitude of a contact force over time, zero outside ``[start, end]``.

    Subclasses give the force inside the window; calling the profile with a
    time or an array of times [s] returns the force [N] with the shape of
    ``t`` (a float for a scalar ``t``).
    """

    def __init__(self, start: float, end: float, peak: float) -> None:
        self._start = start
        self._end = end
        self._peak = peak

    @property
    def start(self) -> float:
        """First instant of the contact window [s]."""
        return self._start

    @property
    def end(self) -> float:
        """Last instant of the contact window [s]."""
        return self._end

    @property
    def duration(self) -> float:
        """Length of the contact window ``end - start`` [s]."""
        return self._end - self._start

    @property
    def peak(self) -> float:
        """Largest force magnitude over the window [N]."""
        return self._peak

    @abstractmethod
    def _inside(self, t: FloatArray) -> FloatArray:
        """Force [N] at times ``t`` [s] that all lie in ``[start, end]``."""

    @abstractmethod
    def parameters(self) -> dict[str, Any]:
        """Constructor arguments of this profile."""

    @overload
    def __call__(self, t: float) -> float: ...

    @overload
    def __call__(self, t: NDArray[Any] | Sequence[float]) -> FloatArray: ...

    def __call__(self, t: ArrayLike) -> float | FloatArray:
        """Force magnitude [N] at time(s) ``t`` [s]; zero outside the window."""
        arr = _times(t)
        force = np.zeros(arr.shape)
        inside = (arr >= self._start) & (arr <= self._end)
        force[inside] = self._inside(arr[inside])
        return float(force) if force.ndim == 0 else force

    def __repr__(self) -> str:
        args = ", ".join(f"{key}={value!r}" for key, value in self.parameters().items())
        return f"{type(self).__name__}({args})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ForceProfile) or type(other) is not type(self):
            return NotImplemented
        mine, theirs = self.parameters(), other.parameters()
        return all(np.array_equal(mine[key], theirs[key]) for key in mine)

    __hash__ = None  # type: ignore[assignment]


class HalfSine(ForceProfile):
    """Impact: one half period of a sine, ``peak sin(π (t - start) / duration)``.

    Its impulse is ``2 peak duration / π`` [N s].

    Parameters
    ----------
    start : float
        Instant of first contact [s].
    duration : float
        Length of the impact [s], ``> 0``.
    peak : float
        Largest force [N], ``>= 0``, reached at ``start + duration / 2``.
    """

    def __init__(self, start: float, duration: float, peak: float) -> None:
        start_ = _number(start, "HalfSine start", "time [s]")
        duration_ = _number(duration, "HalfSine duration", "[s]", lower=0.0, strict=True)
        peak_ = _number(peak, "HalfSine peak", "force [N]", lower=0.0)
        super().__init__(start_, start_ + duration_, peak_)
        self._length = duration_

    def _inside(self, t: FloatArray) -> FloatArray:
        return self._peak * np.sin(np.pi * (t - self._start) / self._length)

    def parameters(self) -> dict[str, Any]:
        """Constructor arguments: ``start``, ``duration``, ``peak``."""
        return {"start": self._start, "duration": self._length, "peak": self._peak}


class Push(ForceProfile):
    """Push or clamp: smooth ramp up, hold at ``peak``, smooth ramp down.

    The ramps are raised cosines, ``peak (1 - cos(π s / ramp)) / 2`` for the
    time ``s`` since ``start``, so the force and its slope are continuous at
    both ends of each ramp. Use short ramps for a near-step.

    Parameters
    ----------
    start : float
        Instant of first contact [s].
    ramp : float
        Rise time from 0 to ``peak`` [s], ``> 0``.
    hold : float
        Time at ``peak`` [s], ``>= 0``.
    release : float
        Fall time from ``peak`` to 0 [s], ``> 0``.
    peak : float
        Held force [N], ``>= 0``.
    """

    def __init__(self, start: float, ramp: float, hold: float, release: float, peak: float) -> None:
        start_ = _number(start, "Push start", "time [s]")
        self._ramp = _number(ramp, "Push ramp", "rise time [s]", lower=0.0, strict=True)
        self._hold = _number(hold, "Push hold", "time at peak [s]", lower=0.0)
        self._release = _number(release, "Push release", "fall time [s]", lower=0.0, strict=True)
        peak_ = _number(peak, "Push peak", "force [N]", lower=0.0)
        super().__init__(start_, start_ + self._ramp + self._hold + self._release, peak_)

    def _inside(self, t: FloatArray) -> FloatArray:
        since_start = t - self._start
        until_end = self._end - t
        rise = 0.5 * (1.0 - np.cos(np.pi * np.minimum(since_start / self._ramp, 1.0)))
        fall = 0.5 * (1.0 - np.cos(np.pi * np.minimum(until_end / self._release, 1.0)))
        return self._peak * np.minimum(rise, fall)

    def parameters(self) -> dict[str, Any]:
        """Constructor arguments: ``start``, ``ramp``, ``hold``, ``release``, ``peak``."""
        return {
            "start": self._start,
            "ramp": self._ramp,
            "hold": self._hold,
            "release": self._release,
            "peak": self._peak,
        }


class Recorded(ForceProfile):
    """A measured force, linearly interpolated between samples and zero outside.

    The record is shifted in time so that its first sample falls at
    ``start``: sample ``k`` acts at ``start + times[k] - times[0]``.

    Parameters
    ----------
    times : array-like of shape (n,)
        Sample instants of the record [s], strictly increasing, ``n >= 2``.
    values : array-like of shape (n,)
        Force along the contact direction [N]; negative values pull.
    start : float, default 0.0
        Instant at which the first sample acts [s].
    scale : float, default 1.0
        Factor applied to ``values`` [-] (e.g. to turn a record into a
        harder or softer collision).
    """

    def __init__(
        self, times: ArrayLike, values: ArrayLike, start: float = 0.0, scale: float = 1.0
    ) -> None:
        self._times_raw, self._values = _check_record(times, values, "Recorded")
        self._scale = _number(scale, "Recorded scale", "factor [-]")
        start_ = _number(start, "Recorded start", "time [s]")
        end = start_ + float(self._times_raw[-1] - self._times_raw[0])
        peak = float(np.max(np.abs(self._values))) * abs(self._scale)
        super().__init__(start_, end, peak)

    @classmethod
    def from_csv(
        cls,
        path: str | PathLike[str],
        start: float = 0.0,
        scale: float = 1.0,
        time_column: str = "t",
        force_column: str = "f",
    ) -> Recorded:
        """Read a recorded force from a CSV file with a header row.

        Parameters
        ----------
        path : str or path-like
            CSV file.
        start : float, default 0.0
            Instant at which the first sample acts [s].
        scale : float, default 1.0
            Factor applied to the force [-].
        time_column : str, default "t"
            Column with the sample instants [s], strictly increasing.
        force_column : str, default "f"
            Column with the force [N].

        Raises
        ------
        LogFormatError
            A column is missing, a value is not a finite number or the time
            is not strictly increasing.
        """
        table = pd.read_csv(path)
        missing = [col for col in (time_column, force_column) if col not in table.columns]
        if missing:
            raise LogFormatError(
                f"{path}: missing column(s) {missing}; columns found: {list(table.columns)} "
                "(choose them with time_column= and force_column=)"
            )
        columns = {}
        for col in (time_column, force_column):
            numeric = pd.to_numeric(table[col], errors="coerce")
            if numeric.isna().any():
                row = int(np.argmax(numeric.isna().to_numpy()))
                raise LogFormatError(
                    f"{path}: column {col!r} must hold finite numbers; "
                    f"data row {row + 1} is {table[col].iloc[row]!r}"
                )
            columns[col] = numeric.to_numpy(dtype=np.float64)
        times, values = _check_record(columns[time_column], columns[force_column], str(path))
        return cls(times, values, start=start, scale=scale)

    def _inside(self, t: FloatArray) -> FloatArray:
        local = t - self._start + self._times_raw[0]
        return self._scale * np.interp(local, self._times_raw, self._values)

    @property
    def times(self) -> FloatArray:
        """Sample instants of the record as given [s] (read-only)."""
        return self._times_raw

    @property
    def values(self) -> FloatArray:
        """Recorded force before scaling [N] (read-only)."""
        return self._values

    def parameters(self) -> dict[str, Any]:
        """Constructor arguments: ``times``, ``values``, ``start``, ``scale``."""
        return {
            "times": self._times_raw,
            "values": self._values,
            "start": self._start,
            "scale": self._scale,
        }

    def __repr__(self) -> str:
        return (
            f"Recorded(<{self._times_raw.size} samples>, start={self._start!r}, "
            f"scale={self._scale!r})"
        )


def _check_record(
    times: ArrayLike, values: ArrayLike, source: str
) -> tuple[FloatArray, FloatArray]:
    """Validate a recorded force: 1-D, same length >= 2, finite, strictly increasing time."""
    t = np.array(times, dtype=np.float64)
    f = np.array(values, dtype=np.float64)
    if t.ndim != 1 or f.ndim != 1 or t.shape != f.shape or t.size < 2:
        raise LogFormatError(
            f"{source}: times and values must be 1-D arrays of one length n >= 2; "
            f"got shapes {t.shape} and {f.shape}"
        )
    for name, arr in (("time", t), ("force", f)):
        if not np.isfinite(arr).all():
            row = int(np.argmin(np.isfinite(arr)))
            raise LogFormatError(f"{source}: {name} must be finite; sample {row} is {arr[row]}")
    steps = np.diff(t)
    if (steps <= 0).any():
        row = int(np.argmax(steps <= 0)) + 1
        raise LogFormatError(
            f"{source}: time must be strictly increasing; sample {row} is {t[row]} s "
            f"after {t[row - 1]} s"
        )
    t.setflags(write=False)
    f.setflags(write=False)
    return t, f


def _vector3(value: ArrayLike, name: str) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise DimensionError(f"{name} must be a 3-vector; got {value!r}") from None
    if arr.shape != (3,):
        raise DimensionError(f"{name} must be a 3-vector; got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputValueError(f"{name} must be finite; got {arr}")
    return arr


def _positive_int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise InputValueError(f"{name} must be an integer >= 1; got {value!r}")
    return int(value)


@dataclass(frozen=True, eq=False)
class Contact:
    """A force applied at a point fixed on one link, eq. (5.34).

    Parameters
    ----------
    id : int
        Label of the contact in logs and evaluations, ``>= 1`` (0 means
        "no contact").
    link : int
        Link number, 1-based (link ``k`` is moved by joint ``k``).
    point : array-like of shape (3,)
        Point of application in the link frame [m].
    direction : array-like of shape (3,)
        Direction of the force in the base frame; normalised to a unit
        vector on construction (the zero vector is an error).
    profile : ForceProfile
        Force magnitude over time [N].
    """

    id: int
    link: int
    point: FloatArray
    direction: FloatArray
    profile: ForceProfile

    def __post_init__(self) -> None:
        object.__setattr__(self, "id", _positive_int(self.id, "contact id"))
        object.__setattr__(self, "link", _positive_int(self.link, f"contact {self.id}: link"))
        point = _vector3(self.point, f"contact {self.id}: point [m]")
        direction = _vector3(self.direction, f"contact {self.id}: direction")
        norm = float(np.linalg.norm(direction))
        if norm == 0.0:
            raise InputValueError(
                f"contact {self.id}: direction must be a non-zero vector in the base frame; "
                f"got {direction}"
            )
        direction = direction / norm
        point.setflags(write=False)
        direction.setflags(write=False)
        object.__setattr__(self, "point", point)
        object.__setattr__(self, "direction", direction)
        if not isinstance(self.profile, ForceProfile):
            raise InputTypeError(
                f"contact {self.id}: profile must be a ForceProfile (HalfSine, Push, "
                f"Recorded); got {type(self.profile).__name__}"
            )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Contact):
            return NotImplemented
        return (
            self.id == other.id
            and self.link == other.link
            and np.array_equal(self.point, other.point)
            and np.array_equal(self.direction, other.direction)
            and self.profile == other.profile
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def start(self) -> float:
        """First instant of the contact window [s]."""
        return self.profile.start

    @property
    def end(self) -> float:
        """Last instant of the contact window [s]."""
        return self.profile.end

    def force(self, t: ArrayLike) -> FloatArray:
        """Force vector in the base frame [N] at time(s) ``t`` [s].

        Returns
        -------
        ndarray of shape (3,) or (n_samples, 3)
        """
        magnitude = np.asarray(self.profile(np.asarray(t, dtype=np.float64)))
        return np.asarray(magnitude[..., None] * self.direction)

    def wrench(self, t: ArrayLike) -> FloatArray:
        """Wrench ``[f; m]`` in base axes at the contact point, ``m = 0`` [N, N m].

        Returns
        -------
        ndarray of shape (6,) or (n_samples, 6)
        """
        f = self.force(t)
        return np.concatenate([f, np.zeros_like(f)], axis=-1)

    def check(self, robot: RobotModel) -> None:
        """Raise :class:`InputValueError` if the link is not one of ``robot``'s links."""
        if self.link > robot.n_dof:
            raise InputValueError(
                f"contact {self.id}: link {self.link} does not exist on {robot.name!r}; "
                f"valid links are 1..{robot.n_dof}"
            )

    def joint_torque(self, robot: RobotModel, q: ArrayLike, t: ArrayLike) -> FloatArray:
        """Joint torques caused by the contact, τ_c = J_c(q)ᵀ [f; 0], eq. (5.34).

        The Jacobian is only evaluated at samples where the force is non-zero.

        Parameters
        ----------
        robot : RobotModel
            The robot the contact acts on.
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        t : float or array-like of shape (n_samples,)
            Time(s) [s]; a scalar applies to every sample.

        Returns
        -------
        tau_c : ndarray of the shape of ``q``
            External joint torques [N m].
        """
        self.check(robot)
        qs, single = as_joint_array(q, robot.n_dof, "q")
        times = _sample_times(t, qs.shape[0])
        forces = self.force(times)
        tau = np.zeros_like(qs)
        rows = np.flatnonzero(np.any(forces != 0.0, axis=1))
        if rows.size:
            jac = robot.point_jacobian(qs[rows], self.link, self.point)
            tau[rows] = np.einsum("kij,ki->kj", jac[:, :3, :], forces[rows])
        return tau[0] if single else tau

    def summary(self) -> dict[str, Any]:
        """Plain description for log metadata (JSON/YAML friendly).

        Keys: ``id``, ``link``, ``point`` [m], ``direction`` (unit, base
        frame), ``start`` [s], ``end`` [s], ``peak`` [N], ``profile`` (class
        name).
        """
        return {
            "id": self.id,
            "link": self.link,
            "point": [float(x) for x in self.point],
            "direction": [float(x) for x in self.direction],
            "start": self.start,
            "end": self.end,
            "peak": self.profile.peak,
            "profile": type(self.profile).__name__,
        }


def _sample_times(t: ArrayLike, n_samples: int) -> FloatArray:
    times = _times(t)
    if times.ndim == 0:
        return np.full(n_samples, float(times))
    if times.shape != (n_samples,):
        raise DimensionError(
            f"t must be a scalar or have shape ({n_samples},) to match q; got shape {times.shape}"
        )
    return times


class ContactSet:
    """Several contacts acting on one robot, with ground-truth labels.

    Parameters
    ----------
    contacts : iterable of Contact
        Contacts with unique ids. Their windows may overlap; the set keeps
        the given order.
    """

    def __init__(self, contacts: Iterable[Contact] = ()) -> None:
        items = list(contacts)
        seen: dict[int, int] = {}
        for position, contact in enumerate(items):
            if not isinstance(contact, Contact):
                raise InputTypeError(
                    f"ContactSet takes Contact objects; item {position} is {type(contact).__name__}"
                )
            if contact.id in seen:
                raise InputValueError(
                    f"contact ids must be unique; id {contact.id} is used by items "
                    f"{seen[contact.id]} and {position}"
                )
            seen[contact.id] = position
        self._contacts: tuple[Contact, ...] = tuple(items)

    def __len__(self) -> int:
        return len(self._contacts)

    def __iter__(self) -> Iterator[Contact]:
        return iter(self._contacts)

    def __getitem__(self, index: int) -> Contact:
        return self._contacts[index]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ContactSet):
            return NotImplemented
        return self._contacts == other._contacts

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"ContactSet({list(self._contacts)!r})"

    def check(self, robot: RobotModel) -> None:
        """Raise :class:`InputValueError` naming the first contact on a link ``robot`` lacks."""
        for contact in self._contacts:
            contact.check(robot)

    def joint_torque(self, robot: RobotModel, q: ArrayLike, t: ArrayLike) -> FloatArray:
        """Sum of the contacts' joint torques, eq. (5.34).

        Parameters
        ----------
        robot : RobotModel
            The robot the contacts act on.
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        t : float or array-like of shape (n_samples,)
            Time(s) [s].

        Returns
        -------
        tau_c : ndarray of the shape of ``q``
            External joint torques [N m].
        """
        self.check(robot)
        qs, single = as_joint_array(q, robot.n_dof, "q")
        times = _sample_times(t, qs.shape[0])
        tau = np.zeros_like(qs)
        for contact in self._contacts:
            tau += contact.joint_torque(robot, qs, times)
        return tau[0] if single else tau

    @overload
    def active_id(self, t: float) -> int: ...

    @overload
    def active_id(self, t: NDArray[Any] | Sequence[float]) -> NDArray[np.int64]: ...

    def active_id(self, t: ArrayLike) -> int | NDArray[np.int64]:
        """Ground-truth label: id of the contact acting at time(s) ``t`` [s], 0 if none.

        A contact acts on its closed window ``[start, end]``. When windows
        overlap, the contact with the largest force magnitude wins; on a tie
        (e.g. two windows that touch, both at zero force) the one listed
        first.

        Returns
        -------
        int, or ndarray of int of the shape of ``t``
        """
        times = _times(t)
        flat = times.reshape(-1)
        labels = np.zeros(flat.shape, dtype=np.int64)
        if self._contacts:
            strength = np.full((len(self._contacts), flat.size), -np.inf)
            for k, contact in enumerate(self._contacts):
                inside = (flat >= contact.start) & (flat <= contact.end)
                strength[k, inside] = np.abs(contact.profile(flat[inside]))
            ids = np.array([contact.id for contact in self._contacts], dtype=np.int64)
            labels = np.where(np.isfinite(strength.max(axis=0)), ids[strength.argmax(axis=0)], 0)
        return int(labels[0]) if times.ndim == 0 else labels.reshape(times.shape)

    def windows(self) -> list[tuple[int, float, float]]:
        """``(id, start, end)`` of every contact [s], in the set's order."""
        return [(c.id, c.start, c.end) for c in self._contacts]

    def summaries(self) -> list[dict[str, Any]]:
        """:meth:`Contact.summary` of every contact."""
        return [c.summary() for c in self._contacts]

    @classmethod
    def random(
        cls,
        robot: RobotModel,
        n: int,
        duration: float,
        rng: np.random.Generator,
        *,
        links: Sequence[int] | None = None,
        kinds: Sequence[str] = PROFILE_KINDS,
        peak_range: tuple[float, float] = (20.0, 80.0),
        duration_range: tuple[float, float] = (0.1, 0.5),
        min_gap: float = 1.0,
        margin: float = 0.5,
        point_range: float = 0.05,
    ) -> ContactSet:
        """Draw ``n`` separated contacts at random times, links, points and directions.

        All randomness comes from ``rng``, so the same generator state gives
        the same set. Windows lie in ``[margin, duration - margin]`` and are
        separated by at least ``min_gap``; their positions are uniform among
        all such arrangements. Ids are 1..n in time order.

        Each contact draws, in this order: its profile kind (uniform over
        ``kinds``), its link (uniform over ``links``), a point uniform in the
        cube ``[-point_range, point_range]³`` around the link-frame origin,
        a direction uniform on the unit sphere, and a peak force uniform in
        ``peak_range``. A push spends 20–40 % of its window on each ramp.

        Parameters
        ----------
        robot : RobotModel
            The robot the contacts act on.
        n : int
            Number of contacts, ``>= 0``.
        duration : float
            Length of the run [s].
        rng : numpy.random.Generator
            Source of randomness.
        links : sequence of int, optional
            Links to choose from (1-based); default ``2..n_dof`` (link 1
            when ``n_dof == 1``), since a force on the base link often
            produces little joint torque.
        kinds : sequence of str, default ("half_sine", "push")
            Profile kinds to choose from; see :data:`PROFILE_KINDS`.
        peak_range : (float, float), default (20, 80)
            Range of peak forces [N].
        duration_range : (float, float), default (0.1, 0.5)
            Range of contact window lengths [s].
        min_gap : float, default 1.0
            Least time between the end of one contact and the start of the next [s].
        margin : float, default 0.5
            Contact-free time at the start and the end of the run [s].
        point_range : float, default 0.05
            Half-width of the cube of contact points around the link origin [m].
        """
        if not isinstance(rng, np.random.Generator):
            raise InputTypeError(
                f"rng must be a numpy.random.Generator (numpy.random.default_rng(seed)); "
                f"got {type(rng).__name__}"
            )
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
            raise InputValueError(f"n must be an integer >= 0 (number of contacts); got {n!r}")
        run = _number(duration, "duration", "run length [s]", lower=0.0, strict=True)
        gap = _number(min_gap, "min_gap", "[s]", lower=0.0)
        edge = _number(margin, "margin", "[s]", lower=0.0)
        spread = _number(point_range, "point_range", "[m]", lower=0.0)
        d_lo, d_hi = _range(duration_range, "duration_range", "contact length [s]")
        f_lo, f_hi = _range(peak_range, "peak_range", "peak force [N]")
        choices = _link_choices(robot, links)
        kind_list = _kinds(kinds)
        available = run - 2.0 * edge
        worst = n * d_hi + max(n - 1, 0) * gap
        if worst > available:
            raise InputValueError(
                f"cannot fit {n} contacts of up to {d_hi} s with min_gap {gap} s "
                f"({worst:g} s) into duration - 2*margin = {available:g} s; "
                "lower n, duration_range[1] or min_gap, or raise duration"
            )
        lengths = rng.uniform(d_lo, d_hi, size=n)
        slack = available - lengths.sum() - max(n - 1, 0) * gap
        offsets = np.sort(rng.uniform(0.0, slack, size=n))
        starts = edge + offsets + np.concatenate([[0.0], np.cumsum(lengths[:-1] + gap)])[:n]
        contacts = []
        for k in range(n):
            kind = kind_list[int(rng.integers(len(kind_list)))]
            link = choices[int(rng.integers(len(choices)))]
            point = rng.uniform(-spread, spread, size=3)
            direction = _unit_vector(rng)
            peak = float(rng.uniform(f_lo, f_hi))
            profile: ForceProfile
            if kind == "half_sine":
                profile = HalfSine(float(starts[k]), float(lengths[k]), peak)
            else:
                ramp, release = rng.uniform(0.2, 0.4, size=2) * lengths[k]
                hold = float(lengths[k] - ramp - release)
                profile = Push(float(starts[k]), float(ramp), hold, float(release), peak)
            contacts.append(Contact(k + 1, link, point, direction, profile))
        return cls(contacts)


def _range(value: Sequence[float], name: str, meaning: str) -> tuple[float, float]:
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise InputValueError(
            f"{name} must be a pair (low, high) of {meaning}; got {value!r}"
        ) from None
    low = _number(lo, f"{name}[0]", meaning, lower=0.0, strict=True)
    high = _number(hi, f"{name}[1]", meaning, lower=0.0, strict=True)
    if low > high:
        raise InputValueError(f"{name} must have low <= high ({meaning}); got {value!r}")
    return low, high


def _link_choices(robot: RobotModel, links: Sequence[int] | None) -> list[int]:
    if links is None:
        return list(range(2, robot.n_dof + 1)) or [1]
    choices = [_positive_int(link, "links entry") for link in links]
    bad = [link for link in choices if link > robot.n_dof]
    if not choices or bad:
        raise InputValueError(
            f"links must be a non-empty sequence of link numbers in 1..{robot.n_dof}; "
            f"got {list(links)!r}"
        )
    return choices


def _kinds(kinds: Sequence[str]) -> list[str]:
    chosen = [kinds] if isinstance(kinds, str) else list(kinds)
    if not chosen:
        raise InputValueError(
            f"kinds must name at least one of {list(PROFILE_KINDS)}; got {kinds!r}"
        )
    unknown = [kind for kind in chosen if kind not in PROFILE_KINDS]
    if unknown:
        raise UnknownNameError(f"unknown profile kind(s) {unknown}; options: {list(PROFILE_KINDS)}")
    return chosen


def _unit_vector(rng: np.random.Generator) -> FloatArray:
    """A direction uniform on the unit sphere (normalised Gaussian)."""
    while True:
        v = rng.standard_normal(3)
        norm = float(np.linalg.norm(v))
        if norm > 1e-12:
            return v / norm
