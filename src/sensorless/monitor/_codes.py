"""Return codes of one stream sample, shared by the compiled and the numpy streams.

A code is ``status | EVENT | joints_mask << JOINTS_SHIFT``: the status in the
low four bits (``OK``, ``COLLISION``, ``SETTLING``, then the faults from
``FAULT`` on, each naming what it refused, ``REASONS[status - FAULT]``), the
``EVENT`` bit when an event closed at the sample, and the joints outside
their bounds as a bit mask (bit j: joint j + 1). ``UNJUDGED``: the entry of
the common sample did not judge it and changed nothing; the Python checks
say why. :func:`joints` and :func:`event_of` read a mask and a closed event
back; :func:`refusal` holds what both streams decline and :class:`StreamCodes`
what both do with a code; :class:`CompiledStep` hands the compiled step to a
user's own compiled loop. Imports no numba, so that the numpy stream runs
without it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from .._validation import FloatArray
from ..signals import Event
from ._layout import N_FLAGS, OPEN_START

if TYPE_CHECKING:
    from .stream import CollisionMonitor

__all__ = [
    "COLLISION",
    "EVENT",
    "FAULT",
    "FAULT_BOUNDS",
    "FAULT_EARLY",
    "FAULT_GAP",
    "FAULT_OBSERVER",
    "FAULT_Q",
    "FAULT_TAU_J",
    "FAULT_TAU_M",
    "FAULT_TIME",
    "FAULT_VELOCITY",
    "JOINTS_SHIFT",
    "MAX_JOINTS",
    "OK",
    "REASONS",
    "SETTLING",
    "STATUSES",
    "UNJUDGED",
    "CompiledStep",
    "StreamCodes",
    "event_of",
    "joints",
    "name_of",
    "refusal",
]

OK, COLLISION, SETTLING, FAULT_TIME, FAULT_Q, FAULT_TAU_M, FAULT_TAU_J = range(7)
FAULT_EARLY, FAULT_GAP, FAULT_VELOCITY, FAULT_OBSERVER, FAULT_BOUNDS = range(7, 12)
FAULT, EVENT, JOINTS_SHIFT = FAULT_TIME, 16, 5
UNJUDGED = 15
MAX_JOINTS = 58  # the joints mask fits in an int64 beside the status bits
STATUSES = ("ok", "collision", "settling")
REASONS = ("time", "q", "tau_m", "tau_j", "early", "gap", "qd", "observer", "bounds")
"""What a fault refused: a time not past the last, a limit, a time rule, a non-finite result."""


def refusal(monitor: CollisionMonitor, families: tuple[type, ...], stream: str) -> str:
    """Why neither the compiled nor the numpy stream (``stream`` names it) runs ``monitor``:
    its observer kind, threshold family (not one of ``families``) or joint count ("" if none).
    """
    kind, threshold, n_dof = monitor.settings.kind, monitor.threshold, monitor.robot.n_dof
    if kind not in ("motor", "joint"):
        return f"the {kind!r} observer runs on the Python path only"
    if type(threshold) not in families:
        return f"the {threshold.name!r} threshold family runs on the Python path only"
    if n_dof > MAX_JOINTS:
        return f"the {stream} handles at most {MAX_JOINTS} joints; the robot has {n_dof}"
    return ""


def joints(mask: int) -> tuple[int, ...]:
    """The joints (1-based) of a joints mask (bit j: joint j + 1)."""
    return tuple(j + 1 for j in range(mask.bit_length()) if mask >> j & 1)


def name_of(status: int) -> str:
    """A status (``code & 15``) by name: "ok", "collision", "settling", what a fault
    refused (an entry of ``REASONS``), or "unjudged"."""
    if status == UNJUDGED:
        return "unjudged"
    return STATUSES[status] if status < FAULT else REASONS[status - FAULT]


def event_of(fields: tuple[float, ...] | list[float], method: str) -> Event:
    """An event from its (start, end, joints mask, peak, peak residual)."""
    start, end, mask, peak, peak_residual = fields
    return Event(start, end, joints(int(mask)), peak, peak_residual, method)


class StreamCodes(ABC):
    """The codes of the compiled and the numpy streams, and their reading.

    ``FAULT``, ``SETTLING`` and ``UNJUDGED`` are status codes (``code & 15``),
    ``EVENT`` the flag of an event closed at the sample, and ``JOINTS_SHIFT``
    where the mask of the joints outside their bounds starts. A subclass
    calls :meth:`_decode_masks` once and gives :meth:`closed`.
    """

    FAULT, SETTLING, EVENT, UNJUDGED, JOINTS_SHIFT = FAULT, SETTLING, EVENT, UNJUDGED, JOINTS_SHIFT
    _masks: list[tuple[int, ...]] | None

    def _decode_masks(self, n_dof: int) -> None:
        """Decode every joints mask once, for up to 10 joints (1024 tuples)."""
        self._masks = [joints(mask) for mask in range(1 << n_dof)] if n_dof <= 10 else None

    def joints(self, code: int) -> tuple[int, ...]:
        """The joints (1-based) outside their bounds, from a return code."""
        mask = code >> JOINTS_SHIFT
        return joints(mask) if self._masks is None else self._masks[mask]

    @abstractmethod
    def closed(self, method: str) -> Event:
        """The event that closed at the last sample run (its code has ``EVENT``)."""

    @staticmethod
    def reason(status: int) -> str:
        """What a fault status refused (an entry of ``REASONS``)."""
        return REASONS[status - FAULT]

    def decoded(self, code: int, method: str) -> tuple[str, tuple[int, ...], Event | None]:
        """The status ("ok", "collision", "settling") or, for a fault, what it refused
        (an entry of ``REASONS``); the joints outside their bounds; the event that closed
        at the sample (found by ``method``), if any."""
        status = code & 15
        if status >= FAULT:
            return name_of(status), (), None
        event = self.closed(method) if code & EVENT else None
        return name_of(status), self.joints(code), event


@dataclass(frozen=True)
class CompiledStep:
    """One stream step for the user's own loop compiled with numba, on a monitor's state.

    From :meth:`CollisionMonitor.compiled_step
    <sensorless.monitor.CollisionMonitor.compiled_step>`. Inside an
    ``@numba.njit`` function that receives the three fields,
    ``code = function(t, q, tau_m, tau_j, model, buffers, out)`` judges one
    sample as :meth:`~sensorless.monitor.CollisionMonitor.step` does, on the
    same state: the monitor's ``step``, ``latched`` and ``finish`` go on
    from where the loop stopped, and the reverse.

    - ``t``: float, the sample's time [s];
    - ``q``: (n_dof,) joint positions [rad]; ``tau_m``, ``tau_j``: (n_dof,)
      motor and joint-sensor torques [N m] (``tau_j`` is ``tau_m`` for the
      motor-torque observer); float64 and C-contiguous, writable or not
      (numba refuses other types when it compiles the loop);
    - ``out``: a writable float64 (3, n_dof) array; a judged sample writes its
      residual, lower and upper bound [N m] there.

    ``code & 15`` is the status: ``OK``, ``COLLISION`` (latched) or
    ``SETTLING``; from ``FAULT`` on, a fault that changed no state, which
    :meth:`reason` names; ``UNJUDGED`` for samples of the wrong length or a
    non-finite time, which change nothing. ``code >> JOINTS_SHIFT`` is the
    mask of the joints outside their bounds (bit j: joint j + 1). With
    ``code & EVENT``, an event closed at the sample; its (start [s], end [s],
    joints mask, peak excursion [N m], peak residual [N m]) are
    ``buffers[EVENT_AT:EVENT_AT + 5]`` until the next sample.

    The Python ``step`` also gives a fault's message, and counts a bad sample
    the loop leaves unjudged toward the gap rule.
    """

    function: Any
    """``fused_step_sample`` of :mod:`sensorless.monitor._compiled` (a numba dispatcher)."""
    model: FloatArray
    """The monitor's constants, read-only."""
    buffers: FloatArray
    """The stream's state, written by each judged sample."""

    OK: ClassVar[int] = OK
    COLLISION: ClassVar[int] = COLLISION
    SETTLING: ClassVar[int] = SETTLING
    FAULT: ClassVar[int] = FAULT
    UNJUDGED: ClassVar[int] = UNJUDGED
    EVENT: ClassVar[int] = EVENT
    JOINTS_SHIFT: ClassVar[int] = JOINTS_SHIFT
    EVENT_AT: ClassVar[int] = 2 * N_FLAGS + OPEN_START

    def __iter__(self) -> Iterator[Any]:
        return iter((self.function, self.model, self.buffers))

    @staticmethod
    def reason(code: int) -> str:
        """The status of ``code`` as :class:`~sensorless.detection.Verdict` names it ("ok",
        "collision", "settling"), what a fault refused (an entry of ``REASONS``), or
        "unjudged"."""
        return name_of(code & 15)
