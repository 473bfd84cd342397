"""A recording of a real arm with the spans where something seems to touch it.

Real recordings carry no ground truth. A :class:`Recording` pairs a log with
*apparent contacts*: time spans [s] that a person read off the residuals as
"looks like a hand on the arm". They are left out of identification and
tuning data (:meth:`Recording.clean_pieces`), and an alarm at one of them is
counted apart from the false alarms (:meth:`Recording.labelled` turns them
into collision windows for :func:`~sensorless.evaluation.evaluate`).
Units SI and radians; time along axis 0.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import as_float_array, check_duration, check_finite
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..io import Log

__all__ = ["DEFAULT_MIN_PIECE", "Recording", "Windows"]

Windows = tuple[tuple[float, float], ...]
"""Time spans ``(start, stop)`` [s]."""

DEFAULT_MIN_PIECE = 1.0
"""Shortest stretch [s] between two apparent contacts kept as clean data."""


def _windows(contacts: Any) -> Windows:
    """``contacts`` as sorted ``(start, stop)`` pairs of finite floats with start < stop [s]."""
    if not isinstance(contacts, Sequence) or isinstance(contacts, str):
        raise InputTypeError(
            f"contacts must be a sequence of (start, stop) pairs [s]; got {type(contacts).__name__}"
        )
    if not contacts:
        return ()
    spans = as_float_array(contacts, "contacts", "(n_contacts, 2)")
    if spans.ndim != 2 or spans.shape[1] != 2:
        raise DimensionError(
            f"contacts must be (start, stop) pairs [s], shape (n_contacts, 2); got {contacts!r}"
        )
    check_finite(spans, "contacts")
    backwards = np.flatnonzero(spans[:, 0] >= spans[:, 1])
    if backwards.size:
        k = int(backwards[0])
        raise InputValueError(f"contacts[{k}] must have start < stop [s]; got {contacts[k]!r}")
    return tuple(sorted((float(a), float(b)) for a, b in spans))


@dataclass(frozen=True)
class Recording:
    """One imported segment of a real arm's file and the apparent contacts in it.

    Parameters
    ----------
    name : str
        Name in tables and titles (by convention the file name, with ``#k``
        for the k-th segment of a file cut at a gap).
    log : Log
        The segment; time [s] along axis 0, arrays of shape (n_samples, n_dof).
    contacts : sequence of (float, float)
        Apparent contacts ``(start, stop)`` [s] on the log's clock; kept sorted.
    """

    name: str
    log: Log
    contacts: Windows = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise InputTypeError(f"name must be a str; got {type(self.name).__name__}")
        if not isinstance(self.log, Log):
            raise InputTypeError(f"log must be a Log; got {type(self.log).__name__}")
        object.__setattr__(self, "contacts", _windows(self.contacts))

    def part(self, start: float | None, stop: float | None, suffix: str) -> Recording:
        """The samples with ``start <= t < stop`` [s] (None: unbounded), named "<name> <suffix>".

        Apparent contacts that overlap the part are kept.
        """
        log = self.log.slice(start, stop)
        lo, hi = float(log.t[0]), float(log.t[-1])
        inside = tuple((a, b) for a, b in self.contacts if b >= lo and a <= hi)
        return Recording(f"{self.name} {suffix}", log, inside)

    def clean_pieces(self, min_piece: float = DEFAULT_MIN_PIECE) -> list[Log]:
        """The stretches between apparent contacts that last at least ``min_piece`` [s]."""
        shortest = check_duration(min_piece, "min_piece")
        edges = [float(self.log.t[0]), *[v for span in self.contacts for v in span]]
        edges.append(float(self.log.t[-1]) + self.log.dt)
        pieces = []
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            if stop - start >= shortest:
                pieces.append(self.log.slice(start, stop))
        return pieces

    def labelled(self) -> Log:
        """The log with its apparent contacts as collision windows (metadata ``collisions``)."""
        collisions = [{"id": k + 1, "start": a, "end": b} for k, (a, b) in enumerate(self.contacts)]
        return dataclasses.replace(
            self.log, metadata={**self.log.metadata, "collisions": collisions}
        )
