"""Isolation against the simulator's ground truth: link, point, force per event.

A simulated log knows each contact: ``metadata["collisions"]`` gives its
link, point (link frame) and direction (base frame), and the ``tau_c``,
``q_true`` and ``collision_id`` columns give its force over time, exactly,
while it is the only contact:

    f(t) = aᵀ τ_c(t) / aᵀa,   a = J_c(q_true(t))ᵀ d,   F(t) = f(t) d

(τ_c = J_cᵀ F, eq. 5.34, with F along the unit direction d). Each estimate of
:meth:`Isolator.isolate_events <sensorless.isolation.Isolator.isolate_events>`
is matched to the contact whose window ``[start, end + max_delay]`` holds its
event's start (the detection rule of :mod:`sensorless.evaluation`) and
compared at the estimate's time:

* ``link_ok`` — the link is the contact's;
* ``point_error`` [m] — distance between the estimated and the true point,
  both in the base frame; ``line_distance`` [m] — distance of the true point
  from the estimated line of action (all a residual can tell when the point
  is not identifiable);
* ``magnitude_error`` [-] — (|F̂| − |F|)/|F|; ``direction_error`` [rad] —
  angle between F̂ and F;
* the same magnitude error against the force passed through the observer's
  filter K_I/(s+K_I) (``gain`` given): what is left once the lag of the
  residual, which no isolation can undo, is taken out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.signal import lfilter

from .._validation import FloatArray, check_type
from ..exceptions import LogFormatError
from ..io import Log
from ..isolation import ContactEstimate, ForceSeries
from ..robots.model import RobotModel
from .scoring import DEFAULT_MAX_DELAY

__all__ = [
    "COLUMNS",
    "EventForces",
    "IsolationEvaluation",
    "TrueContact",
    "evaluate_isolation",
    "true_contacts",
    "true_force",
]


COLUMNS = (
    "event_start",
    "t",
    "id",
    "link_true",
    "link",
    "link_ok",
    "point_error",
    "line_distance",
    "force_true",
    "force_estimated",
    "magnitude_error",
    "direction_error",
    "force_filtered",
    "magnitude_error_filtered",
    "magnitude_bound",
    "within_bound",
    "point_identifiable",
    "exceeds_quasi_static_min",
)
"""Columns of :attr:`IsolationEvaluation.per_event`, in order."""


@dataclass(frozen=True)
class TrueContact:
    """A simulated contact as the log's metadata describes it.

    Attributes
    ----------
    id : int
        Collision id (> 0).
    link : int
        Link, 1-based.
    point : ndarray of shape (3,)
        Point in the link frame [m].
    direction : ndarray of shape (3,)
        Unit direction of the force in the base frame.
    start, end : float
        Window [s].
    """

    id: int
    link: int
    point: FloatArray
    direction: FloatArray
    start: float
    end: float


@dataclass(frozen=True, eq=False)
class EventForces:
    """Estimated and true force over the time of one event (for the plot).

    Attributes
    ----------
    id : int
        Matched collision id (0: a false alarm).
    t : ndarray of shape (n_samples,)
        Time [s].
    estimated, bound : ndarray of shape (n_samples, 3)
        F̂ and its worst-case error per component [N] (:class:`~sensorless.isolation.ForceSeries`).
    true : ndarray of shape (n_samples, 3)
        F [N] (zeros for a false alarm).
    filtered : ndarray of shape (n_samples, 3) or None
        K_I/(s+K_I)·F [N] when the gain is known.
    """

    id: int
    t: FloatArray
    estimated: FloatArray
    bound: FloatArray
    true: FloatArray
    filtered: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class IsolationEvaluation:
    """Isolation performance on one log (:func:`evaluate_isolation`).

    Attributes
    ----------
    per_event : DataFrame
        One row per estimate: ``event_start``, ``t`` [s], ``id`` (matched
        collision, 0 if none), ``link_true``, ``link``, ``link_ok``,
        ``point_error``, ``line_distance`` [m], ``force_true``,
        ``force_estimated`` [N], ``magnitude_error`` [-], ``direction_error``
        [rad], ``force_filtered`` [N] and ``magnitude_error_filtered`` [-]
        (NaN without a gain), ``magnitude_bound`` [N], ``within_bound``
        (‖F̂ − F‖ <= ``magnitude_bound``, F filtered when the gain is known:
        the bound leaves out the lag; False when unmatched),
        ``point_identifiable`` and ``exceeds_quasi_static_min``. Errors are
        NaN for an unmatched estimate; point errors need the right link.
    forces : list of EventForces
        Force over time per estimate given a series (else empty).
    """

    per_event: pd.DataFrame
    forces: list[EventForces] = field(default_factory=list)

    def to_pandas(self) -> pd.DataFrame:
        """The per-event table (a copy)."""
        return self.per_event.copy()

    def summary(self) -> dict[str, Any]:
        """One-row summary over the matched estimates.

        Returns
        -------
        dict
            ``n_events``, ``n_matched``, ``link_rate`` [-] (link found /
            matched), medians of ``point_error``, ``line_distance`` [m],
            ``abs_magnitude_error``, ``abs_magnitude_error_filtered`` [-] and
            ``direction_error`` [rad] (on the right link for the point), and
            ``bound_coverage`` [-] (matched estimates ``within_bound``).
        """
        table = self.per_event
        matched = table[table["id"] > 0] if len(table) else table
        n = len(matched)

        def median(name: str, absolute: bool = False) -> float:
            values = matched[name].to_numpy(dtype=float) if n else np.array([])
            values = np.abs(values) if absolute else values
            values = values[np.isfinite(values)]
            return float(np.median(values)) if values.size else math.nan

        return {
            "n_events": len(table),
            "n_matched": n,
            "link_rate": float(matched["link_ok"].mean()) if n else math.nan,
            "median_point_error": median("point_error"),
            "median_line_distance": median("line_distance"),
            "median_abs_magnitude_error": median("magnitude_error", True),
            "median_abs_magnitude_error_filtered": median("magnitude_error_filtered", True),
            "median_direction_error": median("direction_error"),
            "bound_coverage": float(matched["within_bound"].mean()) if n else math.nan,
        }


def true_contacts(log: Log) -> dict[int, TrueContact]:
    """The contacts of a simulated log by id, from ``metadata["collisions"]``.

    Raises
    ------
    LogFormatError
        An entry lacks ``id``, ``link``, ``point``, ``direction``, ``start`` or
        ``end``, or has a value of the wrong form.
    """
    entries = log.metadata.get("collisions", [])
    if not isinstance(entries, list):
        raise LogFormatError(
            f"metadata['collisions'] must be a list of dicts; got {type(entries).__name__}"
        )
    out: dict[int, TrueContact] = {}
    for index, entry in enumerate(entries):
        where = f"metadata['collisions'][{index}]"
        if not isinstance(entry, Mapping):
            raise LogFormatError(f"{where} must be a dict; got {type(entry).__name__}")
        missing = [
            k for k in ("id", "link", "point", "direction", "start", "end") if k not in entry
        ]
        if missing:
            raise LogFormatError(
                f"{where} lacks {missing}: isolation needs the simulator's link, point and "
                "direction"
            )
        try:
            point = np.array(entry["point"], dtype=float).reshape(3)
            direction = np.array(entry["direction"], dtype=float).reshape(3)
            contact = TrueContact(
                int(entry["id"]),
                int(entry["link"]),
                point,
                direction / np.linalg.norm(direction),
                float(entry["start"]),
                float(entry["end"]),
            )
        except (TypeError, ValueError) as exc:
            raise LogFormatError(
                f"{where}: id and link must be integers, point and direction 3-vectors, start "
                f"and end numbers [s]; {exc}"
            ) from None
        out[contact.id] = contact
    return out


def true_force(log: Log, robot: RobotModel, contact: TrueContact) -> FloatArray:
    """Force of ``contact`` on the arm at every sample [N], shape (n_samples, 3).

    f(t) = aᵀτ_c / aᵀa with a = J_c(q_true)ᵀ d on the samples labelled with
    the contact (``collision_id``), zero elsewhere; exact while it is the
    only contact (module docstring).

    Raises
    ------
    LogFormatError
        The log lacks ``tau_c``, ``q_true`` or ``collision_id``.
    """
    check_type(robot, RobotModel, "robot")
    if log.tau_c is None or log.q_true is None or log.collision_id is None:
        raise LogFormatError(
            "the true force needs a simulated log with tau_c, q_true and collision_id columns"
        )
    rows = np.flatnonzero(log.collision_id == contact.id)
    force = np.zeros((log.n_samples, 3))
    if rows.size:
        jac = robot.point_jacobian(log.q_true[rows], contact.link, contact.point)[:, :3, :]
        a = np.einsum("kij,i->kj", jac, contact.direction)
        norm = np.einsum("kj,kj->k", a, a)
        f = np.einsum("kj,kj->k", a, log.tau_c[rows]) / np.where(norm > 0.0, norm, np.inf)
        force[rows] = f[:, None] * contact.direction
    return force


def _filtered(force: FloatArray, gain: float, dt: float) -> FloatArray:
    """K_I/(s+K_I) of each column, discretised with a zero-order hold [N]."""
    pole = math.exp(-gain * dt)
    return np.asarray(lfilter([1.0 - pole], [1.0, -pole], force, axis=0))


def evaluate_isolation(
    estimates: Sequence[ContactEstimate],
    log: Log,
    robot: RobotModel,
    *,
    series: Sequence[ForceSeries] | None = None,
    gain: float | ArrayLike | None = None,
    max_delay: float = DEFAULT_MAX_DELAY,
) -> IsolationEvaluation:
    """Compare isolation estimates with the contacts of a simulated log.

    Parameters
    ----------
    estimates : sequence of ContactEstimate
        From :meth:`Isolator.isolate_events` (each with its ``event``).
    log : Log
        The simulated run (``tau_c``, ``q_true``, ``collision_id`` and the
        contacts in ``metadata["collisions"]``).
    robot : RobotModel
        The *true* robot (its kinematics place the true point).
    series : sequence of ForceSeries, optional
        F̂(t) per estimate (:meth:`Isolator.force_series`), for :attr:`IsolationEvaluation.forces`.
    gain : float, optional
        Observer gain K_I [1/s] (one value; the first of an array); adds the
        comparison with the filtered force.
    max_delay : float
        Matching window after a contact's end [s].

    Returns
    -------
    IsolationEvaluation
    """
    check_type(robot, RobotModel, "robot")
    contacts = true_contacts(log)
    forces = {c.id: true_force(log, robot, c) for c in contacts.values()}
    k_i = None if gain is None else float(np.ravel(np.asarray(gain, dtype=float))[0])
    dt = float(np.median(np.diff(log.t))) if log.n_samples > 1 else 1.0
    filtered = {} if k_i is None else {i: _filtered(f, k_i, dt) for i, f in forces.items()}
    rows = []
    for estimate in estimates:
        check_type(estimate, ContactEstimate, "each estimate")
        contact = _match(estimate, contacts, max_delay)
        k = int(np.clip(np.searchsorted(log.t, estimate.t), 0, log.n_samples - 1))
        rows.append(_row(estimate, contact, robot, log, k, forces, filtered))
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    out_forces = []
    for estimate, one in zip(estimates, series or [], strict=False):
        contact = _match(estimate, contacts, max_delay)
        idx = np.clip(np.searchsorted(log.t, one.t), 0, log.n_samples - 1)
        ident = 0 if contact is None else contact.id
        true = forces[ident][idx] if ident else np.zeros_like(one.force)
        lagged = filtered[ident][idx] if ident and filtered else None
        out_forces.append(EventForces(ident, one.t, one.force, one.force_bound, true, lagged))
    return IsolationEvaluation(table, out_forces)


def _match(
    estimate: ContactEstimate, contacts: Mapping[int, TrueContact], max_delay: float
) -> TrueContact | None:
    start = estimate.event.start if estimate.event is not None else estimate.t
    inside = [c for c in contacts.values() if c.start <= start <= c.end + max_delay]
    return min(inside, key=lambda c: c.start) if inside else None


def _row(
    estimate: ContactEstimate,
    contact: TrueContact | None,
    robot: RobotModel,
    log: Log,
    k: int,
    forces: Mapping[int, FloatArray],
    filtered: Mapping[int, FloatArray],
) -> dict[str, Any]:
    """One row of :attr:`IsolationEvaluation.per_event`."""
    nan = math.nan
    row: dict[str, Any] = {
        "event_start": estimate.event.start if estimate.event is not None else nan,
        "t": estimate.t,
        "id": 0 if contact is None else contact.id,
        "link_true": 0 if contact is None else contact.link,
        "link": estimate.link,
        "link_ok": contact is not None and contact.link == estimate.link,
        "point_error": nan,
        "line_distance": nan,
        "force_true": nan,
        "force_estimated": estimate.magnitude,
        "magnitude_error": nan,
        "direction_error": nan,
        "force_filtered": nan,
        "magnitude_error_filtered": nan,
        "magnitude_bound": estimate.magnitude_bound,
        "within_bound": False,
        "point_identifiable": estimate.point_identifiable,
        "exceeds_quasi_static_min": estimate.exceeds_quasi_static_min,
    }
    if contact is None or log.q_true is None:
        return row
    point = robot.forward_kinematics(log.q_true[k], contact.link, contact.point)
    if row["link_ok"]:
        row["point_error"] = float(np.linalg.norm(point - estimate.point_world))
    if estimate.magnitude > 0.0:
        axis = estimate.force / estimate.magnitude
        offset = point - estimate.point_world
        row["line_distance"] = float(np.linalg.norm(offset - (offset @ axis) * axis))
    true = forces[contact.id][k]
    reference = filtered[contact.id][k] if filtered else true
    row["within_bound"] = bool(
        np.linalg.norm(estimate.force - reference) <= estimate.magnitude_bound
    )
    size = float(np.linalg.norm(true))
    row["force_true"] = size
    if size > 0.0:
        row["magnitude_error"] = (estimate.magnitude - size) / size
        if estimate.magnitude > 0.0:
            cosine = float(true @ estimate.force) / (size * estimate.magnitude)
            row["direction_error"] = math.acos(max(-1.0, min(1.0, cosine)))
    if filtered:
        lagged = float(np.linalg.norm(filtered[contact.id][k]))
        row["force_filtered"] = lagged
        if lagged > 0.0:
            row["magnitude_error_filtered"] = (estimate.magnitude - lagged) / lagged
    return row
