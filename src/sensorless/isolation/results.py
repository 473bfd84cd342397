"""What the isolator returns: one estimate, the estimates of a run, F̂(t) at a fixed point.

Forces in N, in the base frame; points in m; time in s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from .._validation import FloatArray
from ..signals import Event

__all__ = [
    "QUASI_STATIC_LIMITS",
    "TRANSIENT_FACTOR",
    "ContactEstimate",
    "ForceSeries",
    "IsolationResult",
]

QUASI_STATIC_LIMITS = (65.0, 210.0)
"""Range of the quasi-static force limits of ISO/TS 15066 over body regions [N] (issue 12).

The lowest applies to the face, the highest to the least sensitive regions; a
force above the lower one may hurt somewhere, above the upper one anywhere.
Check the standard's table for the body region at hand.
"""

TRANSIENT_FACTOR = 2.0
"""Transient (impact) limits are at least this multiple of the quasi-static ones [-]."""


@dataclass(frozen=True, eq=False)
class ContactEstimate:
    """Where and how hard the arm is touched, from one sample (or one event).

    Attributes
    ----------
    t : float
        Time of the sample [s] (NaN when none was given).
    link : int
        Contact link, 1-based.
    point_world : ndarray of shape (3,)
        Contact point in the base frame [m].
    point_link : ndarray of shape (3,)
        Contact point in the link frame [m].
    normal_world : ndarray of shape (3,)
        Outward surface normal at the point, base frame.
    force : ndarray of shape (3,)
        Estimated force on the arm F̂, base frame [N].
    force_bound : ndarray of shape (3,)
        Worst-case error of each component of F̂ from the band half-widths [N]
        (inf for a direction the joints do not see).
    magnitude : float
        |F̂| [N].
    magnitude_bound : float
        Bound on ‖F̂ − F‖, hence on ||F̂| − |F|| [N].
    cost : float
        Weighted squared residual of the fit, in squared band half-widths [-].
    force_rank : int
        Force directions the joints in front of the point see (3: all).
    point_identifiable : bool
        The point is determined by the residual (>= 5 joints, full rank); if
        not, it is the best candidate and any point on the line of action
        explains the residual as well.
    pushing : bool
        F̂ points into the surface (F̂·n <= 0).
    last_significant_joint : int
        Last joint outside its band (the lower bound of the link), 1-based.
    consistent_links : tuple of int
        Every link whose fit scores within ``link_tolerance`` of the best
        one, ``link`` among them: more than one means the residual hardly
        tells them apart (a force through the axes of the joints between
        them), and their forces may differ.
    exceeds_quasi_static_min, exceeds_quasi_static_max : bool
        |F̂| above the lowest (65 N) and the highest (210 N) quasi-static
        limit of ISO/TS 15066 (:data:`QUASI_STATIC_LIMITS`).
    exceeds_transient_min : bool
        |F̂| above twice the lowest quasi-static limit (the lowest transient limit).
    event : Event or None
        The detected event this estimate is for (:meth:`Isolator.isolate_events`).
    """

    t: float
    link: int
    point_world: FloatArray
    point_link: FloatArray
    normal_world: FloatArray
    force: FloatArray
    force_bound: FloatArray
    magnitude: float
    magnitude_bound: float
    cost: float
    force_rank: int
    point_identifiable: bool
    pushing: bool
    last_significant_joint: int
    consistent_links: tuple[int, ...]
    exceeds_quasi_static_min: bool
    exceeds_quasi_static_max: bool
    exceeds_transient_min: bool
    event: Event | None = None

    def to_dict(self) -> dict[str, Any]:
        """Flat record: vectors as ``<name>_x``, ``_y``, ``_z``; the event's start and end [s]."""
        out: dict[str, Any] = {"t": self.t, "link": self.link}
        for name in ("point_world", "point_link", "normal_world", "force", "force_bound"):
            for axis, value in zip("xyz", getattr(self, name), strict=True):
                out[f"{name}_{axis}"] = float(value)
        for name in (
            "magnitude",
            "magnitude_bound",
            "cost",
            "force_rank",
            "point_identifiable",
            "pushing",
            "last_significant_joint",
            "exceeds_quasi_static_min",
            "exceeds_quasi_static_max",
            "exceeds_transient_min",
        ):
            out[name] = getattr(self, name)
        out["consistent_links"] = " ".join(str(k) for k in self.consistent_links)
        out["event_start"] = math.nan if self.event is None else self.event.start
        out["event_end"] = math.nan if self.event is None else self.event.end
        return out


@dataclass(frozen=True, eq=False)
class IsolationResult:
    """Per-sample estimates of a run (:meth:`Isolator.run`).

    Attributes
    ----------
    t : ndarray of shape (n_samples,)
        Time [s] (the sample index when none was given).
    estimates : list of ContactEstimate or None
        One per sample; None where no joint is outside its band.
    """

    t: FloatArray
    estimates: list[ContactEstimate | None]

    @property
    def link(self) -> np.ndarray:
        """Estimated link per sample, 0 where there is no estimate."""
        return np.array([0 if e is None else e.link for e in self.estimates], dtype=np.int64)

    @property
    def force(self) -> FloatArray:
        """F̂ per sample, shape (n_samples, 3) [N]; NaN where there is no estimate."""
        nan = np.full(3, np.nan)
        return np.array([nan if e is None else e.force for e in self.estimates]).reshape(-1, 3)

    def to_pandas(self) -> pd.DataFrame:
        """One row per sample with an estimate (:meth:`ContactEstimate.to_dict` columns)."""
        rows = [e.to_dict() for e in self.estimates if e is not None]
        return pd.DataFrame(rows)


@dataclass(frozen=True, eq=False)
class ForceSeries:
    """F̂(t) at a fixed link and point over a time span (:meth:`Isolator.force_series`).

    Attributes
    ----------
    t : ndarray of shape (n_samples,)
        Time [s].
    force : ndarray of shape (n_samples, 3)
        F̂ in the base frame [N].
    force_bound : ndarray of shape (n_samples, 3)
        Worst-case error per component [N] (see :mod:`sensorless.isolation.estimate`).
    link : int
        The link, 1-based.
    point_link : ndarray of shape (3,)
        The point in the link frame [m].
    """

    t: FloatArray
    force: FloatArray
    force_bound: FloatArray
    link: int
    point_link: FloatArray

    @property
    def magnitude(self) -> FloatArray:
        """|F̂| per sample [N]."""
        return np.asarray(np.linalg.norm(self.force, axis=1))

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t``, ``force_x``..``force_z``, ``bound_x``..``bound_z``, ``magnitude`` [N]."""
        table = {"t": self.t}
        for i, axis in enumerate("xyz"):
            table[f"force_{axis}"] = self.force[:, i]
        for i, axis in enumerate("xyz"):
            table[f"bound_{axis}"] = self.force_bound[:, i]
        table["magnitude"] = self.magnitude
        return pd.DataFrame(table)
