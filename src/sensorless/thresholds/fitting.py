"""What the fits of the threshold families share: pooled samples and the rounding guard."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray
from ..signals import ObserverSignals

__all__ = ["ROUNDING_GUARD", "BoolArray", "rounding_guard", "stack"]

BoolArray = NDArray[np.bool_]

ROUNDING_GUARD = 1e-12
"""Relative widening of fitted bounds [-] so that rounding never puts fit data outside them.

A bound is computed as ``centre + alpha`` while ``alpha`` was fitted as
``max |r - centre|``; the two roundings can differ by an ulp. Each family
widens its constant part by ``ROUNDING_GUARD * max_t (|r| + |centre|)``.
"""


def stack(runs: Sequence[ObserverSignals], keep: Sequence[BoolArray], name: str) -> FloatArray:
    """Rows of series ``name`` of all runs where ``keep`` is true, stacked along axis 0."""
    return np.concatenate([getattr(run, name)[k] for run, k in zip(runs, keep, strict=True)])


def rounding_guard(*terms: FloatArray) -> FloatArray:
    """Per-joint widening ``ROUNDING_GUARD * max_t sum |terms|`` [N m]; see ROUNDING_GUARD."""
    total = np.sum([np.abs(term) for term in terms], axis=0)
    return ROUNDING_GUARD * np.max(total, axis=0)
