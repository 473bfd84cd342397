"""Reproducible random collisions for benchmarks: the draws of :meth:`ContactSet.random`.

:func:`draw_contacts` validates the options of
:meth:`ContactSet.random <sensorless.simulation.contact_set.ContactSet.random>`
(documented there) and draws the contacts from one
:class:`numpy.random.Generator`, in a fixed order, so that a seed gives the
same benchmark set on every run.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._validation import FloatArray, check_int
from ..exceptions import InputTypeError, InputValueError, UnknownNameError
from ..robots.model import RobotModel
from .contact import Contact
from .force_profiles import ForceProfile, HalfSine, Push, _number

__all__ = ["PROFILE_KINDS", "draw_contacts"]

#: Profile kinds that :meth:`ContactSet.random` can draw.
PROFILE_KINDS: tuple[str, ...] = ("half_sine", "push")


def draw_contacts(
    robot: RobotModel,
    n: int,
    duration: float,
    rng: np.random.Generator,
    links: Sequence[int] | None,
    kinds: Sequence[str],
    peak_range: tuple[float, float],
    duration_range: tuple[float, float],
    min_gap: float,
    margin: float,
    point_range: float,
) -> list[Contact]:
    """The contacts of :meth:`ContactSet.random`, with its arguments (all required here)."""
    if not isinstance(rng, np.random.Generator):
        raise InputTypeError(
            f"rng must be a numpy.random.Generator (numpy.random.default_rng(seed)); "
            f"got {type(rng).__name__}"
        )
    count = check_int(n, "n", 0)
    run = _number(duration, "duration", "run length [s]", lower=0.0, strict=True)
    gap = _number(min_gap, "min_gap", "[s]", lower=0.0)
    edge = _number(margin, "margin", "[s]", lower=0.0)
    spread = _number(point_range, "point_range", "[m]", lower=0.0)
    lengths_range = _range(duration_range, "duration_range", "contact length [s]")
    f_lo, f_hi = _range(peak_range, "peak_range", "peak force [N]")
    choices = _link_choices(robot, links)
    kind_list = _kinds(kinds)
    starts, lengths = _windows(rng, count, run, edge, lengths_range, gap)
    contacts = []
    for k in range(count):
        kind = kind_list[int(rng.integers(len(kind_list)))]
        link = choices[int(rng.integers(len(choices)))]
        point = rng.uniform(-spread, spread, size=3)
        direction = _unit_vector(rng)
        peak = float(rng.uniform(f_lo, f_hi))
        start, length = float(starts[k]), float(lengths[k])
        profile: ForceProfile
        if kind == "half_sine":
            profile = HalfSine(start, length, peak)
        else:
            ramp, release = rng.uniform(0.2, 0.4, size=2) * length
            profile = Push(start, float(ramp), float(length - ramp - release), float(release), peak)
        contacts.append(Contact(k + 1, link, point, direction, profile))
    return contacts


def _windows(
    rng: np.random.Generator,
    count: int,
    run: float,
    edge: float,
    lengths_range: tuple[float, float],
    gap: float,
) -> tuple[FloatArray, FloatArray]:
    """Starts and lengths [s] of ``count`` windows ``gap`` apart in ``[edge, run - edge]``.

    The positions are uniform among all such arrangements: the free time is
    cut at sorted uniform points.
    """
    d_lo, d_hi = lengths_range
    available = run - 2.0 * edge
    worst = count * d_hi + max(count - 1, 0) * gap
    if worst > available:
        raise InputValueError(
            f"cannot fit {count} contacts of up to {d_hi} s with min_gap {gap} s "
            f"({worst:g} s) into duration - 2*margin = {available:g} s; "
            "lower n, duration_range[1] or min_gap, or raise duration"
        )
    lengths = rng.uniform(d_lo, d_hi, size=count)
    slack = available - lengths.sum() - max(count - 1, 0) * gap
    offsets = np.sort(rng.uniform(0.0, slack, size=count))
    starts = edge + offsets + np.concatenate([[0.0], np.cumsum(lengths[:-1] + gap)])[:count]
    return starts, lengths


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
    choices = [check_int(link, "links entry", 1) for link in links]
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
