"""The isolator: contact link, point and force from residuals and threshold bounds.

See :mod:`sensorless.isolation.estimate` for the method. :class:`Isolator`
judges one sample at a time (:meth:`Isolator.step`), a recorded run
(:meth:`Isolator.run`) or the events of a detector (:meth:`Isolator.isolate_events`);
all three call the same per-sample fit, and a sample's estimate depends on
that sample only (no state), so the batch is the stream by construction.
Units SI and radians; arrays have time along axis 0 and shape
``(n_samples, n_dof)``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_float_array,
    as_joint_array,
    check_duration,
    check_finite,
    check_scalar,
    check_type,
)
from ..exceptions import DimensionError, InputTypeError, InputValueError, UnknownNameError
from ..robots.model import RobotModel
from ..signals import Event
from ._linalg import RCOND, force_bound
from .estimate import Settings, Solver
from .results import (
    QUASI_STATIC_LIMITS,
    TRANSIENT_FACTOR,
    ContactEstimate,
    ForceSeries,
    IsolationResult,
)
from .surfaces import DEFAULT_RADIUS, DEFAULT_SPACING, Surface, capsule_surfaces

__all__ = ["SEARCHES", "Isolator"]

SEARCHES = ("all", "pruned")
"""How many links :class:`Isolator` fits (its ``search``)."""

BoundsLike = Any
"""A pair ``(lower, upper)`` of arrays of shape (n_samples, n_dof) [N m], or an
object with ``lower`` and ``upper`` attributes such as a
:class:`~sensorless.detection.DetectionResult`."""


class Isolator:
    """Find the contact link, point and force from the residual and its bounds.

    Parameters
    ----------
    robot : RobotModel
        The nominal model the residual was computed with.
    surfaces : mapping of int to Surface, optional
        Candidate surface of each link (1-based), e.g. from
        :func:`~sensorless.isolation.urdf_surfaces`; links left out get a
        capsule. By default a capsule around every link
        (:func:`~sensorless.isolation.capsule_surfaces`).
    radius : float or array-like of shape (n_dof,)
        Capsule radius [m] where capsules are made.
    spacing : float
        Distance between candidate points on the capsules [m].
    require_push : bool
        Keep only candidates where F̂ pushes into the surface (F̂·n <= 0),
        when a link has any; a line of action crosses a closed surface twice
        and only the entry point pushes.
    center : bool
        Fit r̂ minus the midpoint of its band (the model error the threshold
        expects there); False fits r̂ itself.
    refine : bool
        Refine the best candidate on the surface (Gauss–Newton); without it
        the point is the nearest candidate, ``spacing`` apart.
    band_floor : float
        Smallest half-width used in the weights 1/δ [N m], > 0.
    link_tolerance : float
        Penalty of a link's fit per number it adjusts, in squared band
        half-widths [-], >= 0; links whose score is within it of the least
        are reported as consistent (see :mod:`sensorless.isolation.estimate`).
    search : {"all", "pruned"}
        ``"all"`` fits every link from the last significant joint on;
        ``"pruned"`` (faster, for streams) stops where no link further out
        can win (its misfit is at least the residual of the joints it cannot
        move): the same link, but ``consistent_links`` only among the links
        it fitted.
    force_limits : (float, float)
        Lowest and highest quasi-static force limit [N] compared with |F̂|
        (ISO/TS 15066 body regions: 65 and 210 N by default).
    transient_factor : float
        Transient limits are this multiple of the quasi-static ones [-].
    """

    def __init__(
        self,
        robot: RobotModel,
        surfaces: Mapping[int, Surface] | None = None,
        *,
        radius: float | ArrayLike = DEFAULT_RADIUS,
        spacing: float = DEFAULT_SPACING,
        require_push: bool = True,
        center: bool = True,
        refine: bool = True,
        band_floor: float = 1e-6,
        link_tolerance: float = 1.0,
        search: str = "all",
        force_limits: tuple[float, float] = QUASI_STATIC_LIMITS,
        transient_factor: float = TRANSIENT_FACTOR,
    ) -> None:
        self.robot = check_type(robot, RobotModel, "robot")
        chosen = capsule_surfaces(robot, radius, spacing)
        if surfaces is not None:
            if not isinstance(surfaces, Mapping):
                raise InputTypeError(
                    f"surfaces must be a mapping of link number to Surface; got "
                    f"{type(surfaces).__name__}"
                )
            for link, surface in surfaces.items():
                if link not in chosen:
                    raise InputValueError(
                        f"surfaces: link {link!r} is not a link of {robot.name!r} "
                        f"(1..{robot.n_dof})"
                    )
                if not isinstance(surface, Surface):
                    raise InputTypeError(
                        f"surfaces[{link}] must be a Surface (CapsuleSurface, MeshSurface); got "
                        f"{type(surface).__name__}"
                    )
                chosen[link] = surface
        self.surfaces = chosen
        low, high = _limits(force_limits)
        self.settings = Settings(
            require_push=bool(require_push),
            center=bool(center),
            refine=bool(refine),
            band_floor=check_scalar(band_floor, "band_floor", "N m"),
            limits=(low, high),
            transient_factor=check_scalar(transient_factor, "transient_factor", "-"),
            link_tolerance=check_scalar(link_tolerance, "link_tolerance", "-", "nonnegative"),
            search=_search(search),
        )
        self._solver = Solver(robot, self.surfaces, self.settings)

    def __repr__(self) -> str:
        return f"Isolator({self.robot!r}, {self.settings!r})"

    # ----------------------------------------------------------------- stream

    def step(
        self,
        q: ArrayLike,
        r: ArrayLike,
        lower: ArrayLike,
        upper: ArrayLike,
        *,
        t: float = math.nan,
    ) -> ContactEstimate | None:
        """Estimate the contact from one sample.

        Parameters
        ----------
        q : array-like of shape (n_dof,)
            Joint positions [rad].
        r : array-like of shape (n_dof,)
            Residual r̂ [N m].
        lower, upper : array-like of shape (n_dof,)
            Threshold bounds at this sample [N m]; ±inf for a joint without
            a bound (it is then never significant and carries no weight).
        t : float, optional
            Time of the sample [s], copied into the estimate.

        Returns
        -------
        ContactEstimate or None
            None when every residual is inside its band.

        Raises
        ------
        DimensionError
            An input of the wrong shape.
        InputValueError
            NaN or inf in ``q`` or ``r``, NaN in a bound, or ``lower > upper``.
        """
        n = self.robot.n_dof
        arrays = []
        for value, name in ((q, "q"), (r, "r"), (lower, "lower"), (upper, "upper")):
            arr, single = as_joint_array(value, n, name, allow_nonfinite=name in ("lower", "upper"))
            if not single:
                raise DimensionError(
                    f"{name} must be one sample of shape ({n},) in step; got shape "
                    f"{np.shape(value)}"
                )
            arrays.append(arr)
        _check_bounds(arrays[2], arrays[3])
        return self._solver.estimate(
            arrays[0][0], arrays[1][0], arrays[2][0], arrays[3][0], _time(t)
        )

    # ----------------------------------------------------------------- batch

    def run(
        self,
        q: ArrayLike,
        r: ArrayLike,
        bounds: BoundsLike,
        *,
        t: ArrayLike | None = None,
        skip_nonfinite: bool = False,
    ) -> IsolationResult:
        """Estimate the contact at every sample of a run, as :meth:`step` does.

        Parameters
        ----------
        q : array-like of shape (n_samples, n_dof)
            Joint positions [rad].
        r : array-like of shape (n_samples, n_dof)
            Residual r̂ [N m].
        bounds : (lower, upper) or DetectionResult
            Threshold bounds of shape (n_samples, n_dof) each [N m].
        t : array-like of shape (n_samples,), optional
            Time [s]; by default the sample index.
        skip_nonfinite : bool
            Give no estimate for samples with NaN/inf in q or r̂ or NaN in a
            bound (a monitor's refused samples); by default they are an error.

        Returns
        -------
        IsolationResult

        Raises
        ------
        DimensionError
            Inputs of the wrong shapes or lengths.
        InputValueError
            NaN/inf in q or r̂, NaN in a bound (unless ``skip_nonfinite``), or
            ``lower > upper``.
        """
        times, qs, rs, lower, upper, valid = self._series(q, r, bounds, t, skip_nonfinite)
        solve = self._solver.estimate
        estimates = [
            solve(qs[k], rs[k], lower[k], upper[k], float(times[k])) if valid[k] else None
            for k in range(times.size)
        ]
        return IsolationResult(times, estimates)

    def isolate_events(
        self,
        events: Iterable[Event],
        t: ArrayLike,
        q: ArrayLike,
        r: ArrayLike,
        bounds: BoundsLike,
        *,
        window: float = 0.0,
        skip_nonfinite: bool = False,
    ) -> list[ContactEstimate]:
        """One estimate per detected event, at its peak.

        The peak is the sample of the largest excursion beyond a bound inside
        ``[event.start, event.end]`` (the detector's ``peak``). With ``window``
        > 0, q, r̂ and the bounds are averaged over the event's samples within
        ``window``/2 of the peak first (less noise; the force is taken as
        constant over the window). If no joint is outside its band there, the
        event's last joint bounds the link from below.

        Parameters
        ----------
        events : iterable of Event
            Events of a detector run on the same residual.
        t : array-like of shape (n_samples,)
            Time [s], increasing.
        q, r, bounds
            As in :meth:`run`.
        window : float
            Averaging window around the peak [s], >= 0.
        skip_nonfinite : bool
            Leave out samples with NaN/inf (as in :meth:`run`).

        Returns
        -------
        list of ContactEstimate
            In the order of ``events``, each with its ``event``.

        Raises
        ------
        InputValueError
            An event has no (usable) sample in ``t``, or ``t`` does not increase;
            and as :meth:`run`.
        """
        span = check_duration(window, "window")
        times, qs, rs, lower, upper, valid = self._series(q, r, bounds, t, skip_nonfinite)
        if np.any(np.diff(times) <= 0.0):
            raise InputValueError("t must be strictly increasing [s] to place the events")
        with np.errstate(invalid="ignore"):
            excursion = np.maximum(rs - upper, lower - rs).max(axis=1)
        out = []
        for event in events:
            check_type(event, Event, "each event")
            rows = np.flatnonzero((times >= event.start) & (times <= event.end) & valid)
            if rows.size == 0:
                raise InputValueError(
                    f"event at [{event.start!r}, {event.end!r}] s has no sample in t "
                    f"([{times[0]!r}, {times[-1]!r}] s)"
                )
            peak = int(rows[np.argmax(excursion[rows])])
            near = rows[np.abs(times[rows] - times[peak]) <= 0.5 * span] if span > 0 else [peak]
            least = max(event.joints) if event.joints else 1
            estimate = self._solver.estimate(
                qs[near].mean(axis=0),
                rs[near].mean(axis=0),
                lower[near].mean(axis=0),
                upper[near].mean(axis=0),
                float(times[peak]),
                least_link=least,
            )
            assert estimate is not None  # least_link >= 1 always gives one
            out.append(dataclasses.replace(estimate, event=event))
        return out

    def force_series(
        self,
        estimate: ContactEstimate,
        t: ArrayLike,
        q: ArrayLike,
        r: ArrayLike,
        bounds: BoundsLike,
        *,
        start: float | None = None,
        end: float | None = None,
        skip_nonfinite: bool = False,
    ) -> ForceSeries:
        """F̂(t) with the link and point of ``estimate`` held, sample by sample.

        Parameters
        ----------
        estimate : ContactEstimate
            Gives the link and the point (in the link frame).
        t, q, r, bounds
            As in :meth:`run` (``t`` required).
        start, end : float, optional
            Time span [s]; by default the estimate's event, else the whole run.
        skip_nonfinite : bool
            Leave out samples with NaN/inf (as in :meth:`run`).

        Returns
        -------
        ForceSeries
        """
        check_type(estimate, ContactEstimate, "estimate")
        times, qs, rs, lower, upper, valid = self._series(q, r, bounds, t, skip_nonfinite)
        event = estimate.event
        first = start if start is not None else (event.start if event else -np.inf)
        last = end if end is not None else (event.end if event else np.inf)
        rows = np.flatnonzero((times >= first) & (times <= last) & valid)
        link, point = estimate.link, estimate.point_link
        force = np.full((rows.size, 3), np.nan)
        bound = np.full((rows.size, 3), np.nan)
        if rows.size:
            jac = self.robot.point_jacobian(qs[rows], link, point)[:, :3, :link]
            for i, row in enumerate(rows):
                mid, half, weight = self._solver.weights(lower[row], upper[row])
                b = weight[:link, None] * jac[i].T
                y = weight[:link] * (rs[row, :link] - mid[:link])
                force[i] = np.linalg.pinv(b, rcond=RCOND) @ y
                bound[i] = force_bound(b, weight[:link], half[:link])[0]
        return ForceSeries(times[rows], force, bound, link, point.copy())

    # ----------------------------------------------------------------- checks

    def _series(
        self, q: ArrayLike, r: ArrayLike, bounds: BoundsLike, t: ArrayLike | None, skip: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, np.ndarray]:
        """Checked time, q, r̂, lower, upper of a run and the samples to use.

        With ``skip``, samples with NaN/inf in q or r̂ or NaN in a bound are
        marked unused instead of being an error.
        """
        n = self.robot.n_dof
        lower, upper = _pair(bounds)
        qs, _ = as_joint_array(q, n, "q", allow_nonfinite=skip)
        rs, _ = as_joint_array(r, n, "r", allow_nonfinite=skip)
        lows, _ = as_joint_array(lower, n, "lower", allow_nonfinite=True)
        highs, _ = as_joint_array(upper, n, "upper", allow_nonfinite=True)
        lengths = [a.shape[0] for a in (qs, rs, lows, highs)]
        if t is None:
            times = np.arange(lengths[0], dtype=float)
        else:
            times = as_float_array(t, "t", "(n_samples,)")
            if times.ndim != 1:
                raise DimensionError(f"t must have shape (n_samples,); got shape {times.shape}")
            check_finite(times, "t")
        if len({*lengths, times.size}) > 1:
            raise DimensionError(
                "t, q, r, lower and upper must have the same number of samples; got "
                f"{[times.size, *lengths]}"
            )
        valid = np.ones(times.size, dtype=bool)
        if skip:
            finite = np.isfinite(qs).all(axis=1) & np.isfinite(rs).all(axis=1)
            valid = np.asarray(finite & ~(np.isnan(lows) | np.isnan(highs)).any(axis=1), dtype=bool)
        _check_bounds(lows[valid], highs[valid])
        return times, qs, rs, lows, highs, valid


def _pair(bounds: BoundsLike) -> tuple[Any, Any]:
    """``(lower, upper)`` of a pair or of an object with ``lower`` and ``upper``."""
    if hasattr(bounds, "lower") and hasattr(bounds, "upper"):
        return bounds.lower, bounds.upper
    if isinstance(bounds, Sequence) and not isinstance(bounds, str) and len(bounds) == 2:
        return bounds[0], bounds[1]
    raise InputTypeError(
        "bounds must be a pair (lower, upper) of arrays of shape (n_samples, n_dof) [N m] or a "
        f"DetectionResult; got {type(bounds).__name__}"
    )


def _check_bounds(lower: FloatArray, upper: FloatArray) -> None:
    """No NaN, and lower <= upper everywhere [N m]."""
    for name, values in (("lower", lower), ("upper", upper)):
        if np.isnan(values).any():
            k, j = (int(i) for i in np.argwhere(np.isnan(values))[0])
            raise InputValueError(
                f"{name} bound must not be NaN (±inf marks a joint without a bound); "
                f"found NaN at sample {k}, joint {j + 1}"
            )
    bad = np.argwhere(lower > upper)
    if bad.size:
        k, j = (int(i) for i in bad[0])
        raise InputValueError(
            f"lower bound must be <= upper bound [N m]; at sample {k}, joint {j + 1}: "
            f"{lower[k, j]!r} > {upper[k, j]!r}"
        )


def _time(value: Any) -> float:
    """A sample's time [s] as a float (NaN allowed: no time)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"t must be a time in seconds; got {value!r}") from None


def _search(value: Any) -> str:
    if value not in SEARCHES:
        raise UnknownNameError(f"unknown search {value!r}; options: {list(SEARCHES)}")
    return str(value)


def _limits(value: Any) -> tuple[float, float]:
    try:
        low, high = value
    except (TypeError, ValueError):
        raise InputValueError(
            f"force_limits must be a pair (lowest, highest) of forces [N]; got {value!r}"
        ) from None
    low = check_scalar(low, "force_limits[0]", "N")
    high = check_scalar(high, "force_limits[1]", "N")
    if low > high:
        raise InputValueError(f"force_limits must be (lowest, highest) [N]; got {value!r}")
    return low, high
