"""Return codes of one stream sample, shared by the compiled and the numpy streams.

A code is ``status | EVENT | joints_mask << JOINTS_SHIFT``: the status in the
low four bits (``OK``, ``COLLISION``, ``SETTLING``, then the faults from
``FAULT`` on, each naming what it refused, ``REASONS[status - FAULT]``), the
``EVENT`` bit when an event closed at the sample, and the joints outside
their bounds as a bit mask (bit j: joint j + 1). ``UNJUDGED``: the entry of
the common sample did not judge it and changed nothing; the Python checks
say why. Imports nothing, so that the numpy stream runs without numba.
"""

from __future__ import annotations

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
]

OK, COLLISION, SETTLING, FAULT_TIME, FAULT_Q, FAULT_TAU_M, FAULT_TAU_J = range(7)
FAULT_EARLY, FAULT_GAP, FAULT_VELOCITY, FAULT_OBSERVER, FAULT_BOUNDS = range(7, 12)
FAULT, EVENT, JOINTS_SHIFT = FAULT_TIME, 16, 5
UNJUDGED = 15
MAX_JOINTS = 58  # the joints mask fits in an int64 beside the status bits
STATUSES = ("ok", "collision", "settling")
REASONS = ("time", "q", "tau_m", "tau_j", "early", "gap", "qd", "observer", "bounds")
"""What a fault refused: a time not past the last, a limit, a time rule, a non-finite result."""
