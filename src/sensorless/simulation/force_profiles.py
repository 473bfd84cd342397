"""Force profiles: the magnitude of a contact force over time.

A :class:`ForceProfile` is zero outside its window ``[start, end]`` [s] and
gives the force [N] inside it: an impact :class:`HalfSine`, a :class:`Push`
that ramps up, holds and releases, or a :class:`Recorded` force such as the
hand force of thesis Fig. 5.5. A :class:`~sensorless.simulation.contact.Contact`
applies a profile along a direction at a point of a link.

Every profile carries a ground-truth label :attr:`ForceProfile.kind`, one
of :data:`INTERACTION_KINDS`: "collision" (accidental), what the detection
benchmark has always taken a contact for, unless the profile models a
person's intended interaction. The profiles of who or what applies the force
(thesis §6.2 item 7: a guiding hand, a clamp, an impact) are in
:mod:`sensorless.simulation.interaction_profiles`.

Examples
--------
>>> hit = HalfSine(start=1.0, duration=0.2, peak=50.0)
>>> hit(1.1), hit(2.0), round(hit.end, 12)
(50.0, 0.0, 1.2)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from os import PathLike
from typing import Any, ClassVar, overload

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray
from ..exceptions import InputValueError, LogFormatError

__all__ = ["INTERACTION_KINDS", "ForceProfile", "HalfSine", "Push", "Recorded"]

#: Ground-truth labels of a contact (:attr:`ForceProfile.kind`): a person's
#: intended interaction, or an accidental collision.
INTERACTION_KINDS: tuple[str, ...] = ("intended", "collision")


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

    #: Ground-truth label, one of :data:`INTERACTION_KINDS`: "collision"
    #: unless a subclass models a person's intended interaction.
    kind: ClassVar[str] = "collision"

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
