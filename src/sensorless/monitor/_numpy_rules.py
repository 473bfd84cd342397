"""The detector and the latch of the numpy stream (:mod:`._numpy_stream`) on its scalars.

:class:`EventRules` is ``Detector._step_checked`` and the latch on the
stream's :class:`Flags` (time rules, open event, latch), from the bounds'
excursions of one sample. Needs no numba. Units SI.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validation import FloatArray
from ._codes import (
    COLLISION,
    FAULT_GAP,
    FAULT_Q,
    FAULT_TAU_J,
    FAULT_TAU_M,
    FAULT_VELOCITY,
    JOINTS_SHIFT,
    OK,
)  # fmt: skip

__all__ = ["EventRules", "Flags", "refused"]


class EventRules:
    """``Detector._step_checked`` and the latch on the stream's :class:`Flags`.

    ``monitored``: the joints watched (0-based); durations [s] already less
    the Detector's time tolerance; ``release`` NaN for a latch that holds;
    ``pair`` (2, n_dof) the excursions the bounds write (r̂ − U and L − r̂,
    either order; −∞ for a joint not monitored).
    """

    def __init__(
        self, monitored: list[int], min_duration: float, hold: float, release: float,
        pair: FloatArray,
    ) -> None:  # fmt: skip
        self._monitored, self._min_duration, self._hold = monitored, min_duration, hold
        self._release = release
        self._pair, self._zero, self._above = pair, np.zeros_like(pair), np.empty(pair.shape, bool)
        # the joints mask by the bytes of excursions > 0, for the patterns met (at most 4096)
        self._masks: dict[bytes, int] = {}

    def __call__(
        self, fl: Flags, time: float, worst: float, excursions: list[float], out: FloatArray,
        closed: tuple[float, ...],
    ) -> tuple[int, tuple[float, ...]]:  # fmt: skip
        """``Detector._step_checked`` and the latch on the flags: (status | mask << 5, event).

        ``excursions`` are the rows of ``pair`` as one list [N m], ``worst`` their
        largest (a joint is outside its bounds if it is > 0); ``out`` holds the
        residual in its first row.
        """
        mask = 0
        if worst > 0.0:  # a monitored joint's: the others are −∞
            above = self._above
            _greater(self._pair, self._zero, above)  # an array: a float converts each time
            bits = above.tobytes()
            mask = self._masks.get(bits, -1)
            if mask < 0:
                mask = sum(1 << j for j in self._monitored if above[:, j].any())
                if len(self._masks) < 4096:
                    self._masks[bits] = mask
            if fl.open and (fl.outside or time - fl.open_end < self._hold):
                fl.open_end = time
                fl.open_joints |= mask
                if not worst <= fl.open_peak:
                    fl.open_peak, fl.open_peak_residual = worst, _residual(worst, excursions, out)
            else:
                closed = self.lasted(fl) or closed
                fl.open, fl.open_start, fl.open_end = True, time, time
                fl.open_joints, fl.open_peak = mask, worst
                fl.open_peak_residual = _residual(worst, excursions, out)
        elif fl.open and time - fl.open_end >= self._hold:
            closed = self.lasted(fl) or closed
            fl.open = False
        fl.outside = mask != 0
        if mask and fl.open and time - fl.open_start >= self._min_duration:
            fl.latched, fl.inside_since = True, math.nan
            return COLLISION | mask << JOINTS_SHIFT, closed
        if fl.latched and not math.isnan(self._release):
            if mask:
                fl.inside_since = math.nan
            elif math.isnan(fl.inside_since):
                fl.inside_since = time
            if time - fl.inside_since >= self._release:
                fl.latched, fl.inside_since = False, math.nan
        return (COLLISION if fl.latched else OK) | mask << JOINTS_SHIFT, closed

    def lasted(self, fl: Flags) -> tuple[float, ...]:
        """The open event's fields if it lasted ``min_duration``, else ()."""
        if fl.open and fl.open_end - fl.open_start >= self._min_duration:
            return (fl.open_start, fl.open_end, fl.open_joints, fl.open_peak, fl.open_peak_residual)
        return ()


class Flags:
    """The stream's scalars: time rules, detector and latch."""

    __slots__ = (
        "floor", "has_detector", "has_stream", "inside_since", "latched", "open", "open_end",
        "open_joints", "open_peak", "open_peak_residual", "open_start", "outside", "pending",
        "start", "t_last",
    )  # fmt: skip

    def __init__(self) -> None:
        self.has_stream = self.has_detector = self.latched = self.open = self.outside = False
        self.start = self.t_last = self.open_start = self.open_end = 0.0
        self.open_peak = self.open_peak_residual = 0.0
        self.floor = self.pending = -math.inf
        self.inside_since = math.nan
        self.open_joints = 0

    def __copy__(self) -> Flags:
        new = Flags.__new__(Flags)
        for name in self.__slots__:
            setattr(new, name, getattr(self, name))
        return new


def _residual(worst: float, excursions: list[float], out: FloatArray) -> float:
    """The residual [N m] (first row of ``out``) of the first joint whose larger excursion
    is ``worst`` (``excursions``: one row per kind, joints along it)."""
    n = out.shape[1]
    best = excursions.index(worst) % n
    if excursions.count(worst) > 1:  # the first joint, not the first in the list
        best = min(j % n for j, x in enumerate(excursions) if x == worst)
    return float(out[0, best])


def refused(fl: Flags, inside: Any, time: float, time_fault: int) -> int:
    """The fault of a sample outside the limits or the time rules, in the kernel's order.

    ``inside`` (2, rows, n_dof) are both comparisons of the rows q̇, q, τ_m (, τ_J)
    with their limits; the gap rule's pending time goes into ``fl``.
    """
    rows = [bool(inside[:, row].all()) for row in range(inside.shape[1])]
    for row, code in zip(rows[1:], (FAULT_Q, FAULT_TAU_M, FAULT_TAU_J), strict=False):
        if not row:
            fl.pending = time
            return code
    if time_fault:
        if time_fault == FAULT_GAP:
            fl.pending = time
        return time_fault
    fl.pending = time
    return FAULT_VELOCITY


# Bound once: each module attribute lookup costs as much as a line of arithmetic.
_greater = np.greater
