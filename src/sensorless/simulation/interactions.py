"""Seeded draws of intended contacts and collisions, and runs labelled with them.

:func:`draw_interactions` draws a reproducible mixed set of the profiles of
:mod:`sensorless.simulation.interaction_profiles` (a guiding hand, a clamp,
an impact) from one generator, with directions that make physical sense
when the desired motion is given: a hand pushes the arm the way it is going
(power flows into the robot), an obstacle opposes the motion.
:func:`simulate_interactions` runs a scenario with such a set and writes the
labels into the log's ground truth, ``metadata["collisions"][i]["kind"]``
(``ContactSet.summaries``); :func:`random_interactions` builds the set of
a scenario's ``random_interactions`` section.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, check_int
from ..exceptions import InputTypeError, InputValueError, UnknownNameError
from ..robots.model import RobotModel
from ..trajectories import Trajectory
from .contact import Contact
from .contact_set import ContactSet
from .force_profiles import ForceProfile, _number
from .interaction_profiles import INTERACTION_PROFILES, Clamp, GuidingHand, Impact
from .random_contacts import _link_choices, _unit_vector
from .simulator import SimulationResult, simulate

if TYPE_CHECKING:
    from .scenario import Scenario

__all__ = [
    "RANGES",
    "draw_interactions",
    "random_interactions",
    "simulate_interactions",
]


#: What :func:`draw_interactions` draws, uniformly in each range: for a
#: guiding hand the peak [N], ramp, hold and release [s]; for a clamp the
#: peak [N], contact stiffness [N/m], approach speed [m/s], hold and release
#: [s]; for an impact the peak [N], rise and duration [s].
RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "guiding": {
        "peak": (10.0, 40.0),
        "ramp": (0.3, 1.0),
        "hold": (1.0, 3.0),
        "release": (0.3, 1.0),
    },
    "clamp": {
        "peak": (60.0, 150.0),
        "stiffness": (5e3, 2e4),
        "speed": (0.05, 0.25),
        "hold": (0.5, 2.0),
        "release": (0.05, 0.3),
    },
    "impact": {"peak": (30.0, 120.0), "rise": (0.003, 0.02), "duration": (0.03, 0.1)},
}


# ----------------------------------------------------------------------------- draws


def _draw(rng: np.random.Generator, ranges: Mapping[str, tuple[float, float]]) -> dict[str, float]:
    """One uniform value per range, in the order of ``ranges``."""
    return {key: float(rng.uniform(lo, hi)) for key, (lo, hi) in ranges.items()}


def _profile(kind: str, start: float, values: Mapping[str, float]) -> ForceProfile:
    if kind == "guiding":
        return GuidingHand(start, values["ramp"], values["hold"], values["release"], values["peak"])
    if kind == "clamp":
        return Clamp.from_approach(
            start,
            values["stiffness"],
            values["speed"],
            values["peak"],
            values["hold"],
            values["release"],
        )
    return Impact(start, values["rise"], values["duration"], values["peak"])


def _length(kind: str, values: Mapping[str, float]) -> float:
    if kind == "guiding":
        return values["ramp"] + values["hold"] + values["release"]
    if kind == "clamp":
        build = values["peak"] / (values["stiffness"] * values["speed"])
        return build + values["hold"] + values["release"]
    return values["duration"]


def _place(
    rng: np.random.Generator, lengths: FloatArray, run: float, edge: float, gap: float
) -> FloatArray:
    """Starts [s] of windows of ``lengths``, ``gap`` apart in ``[edge, run - edge]``, uniform."""
    count = lengths.size
    available = run - 2.0 * edge
    needed = float(lengths.sum()) + max(count - 1, 0) * gap
    if needed > available:
        raise InputValueError(
            f"the {count} drawn contacts need {needed:g} s with min_gap {gap} s but "
            f"duration - 2*margin is {available:g} s; lower n or min_gap, or raise duration"
        )
    offsets = np.sort(rng.uniform(0.0, available - needed, size=count))
    return np.asarray(edge + offsets + np.concatenate([[0.0], np.cumsum(lengths[:-1] + gap)]))


def _direction(
    rng: np.random.Generator,
    robot: RobotModel,
    trajectory: Trajectory | None,
    contact: tuple[int, FloatArray, float],
    sense: float,
    spread: float,
) -> FloatArray:
    """Unit force direction: ``sense`` times the point's desired velocity, spread; else random."""
    link, point, start = contact
    noise = rng.standard_normal(3) * spread
    uniform = _unit_vector(rng)
    if trajectory is None:
        return uniform
    q, qd, _ = trajectory.evaluate(np.array([start]))
    velocity = robot.point_jacobian(q, link, point)[0, :3, :] @ qd[0]
    speed = float(np.linalg.norm(velocity))
    if speed < 1e-2:  # a point at rest: no motion to push along or oppose
        return uniform
    direction = sense * velocity / speed + noise
    norm = float(np.linalg.norm(direction))
    return uniform if norm < 1e-9 else direction / norm


def draw_interactions(
    robot: RobotModel,
    n: int,
    duration: float,
    rng: np.random.Generator,
    *,
    trajectory: Trajectory | None = None,
    kinds: Sequence[str] = ("guiding", "clamp", "impact"),
    links: Sequence[int] | None = None,
    point_range: float = 0.05,
    spread: float = 0.3,
    min_gap: float = 1.0,
    margin: float = 0.5,
) -> ContactSet:
    """Draw ``n`` separated guiding, clamp and impact contacts, reproducibly.

    All randomness comes from ``rng``, in this order: the kind of every
    contact (uniform over ``kinds``), the profile values of every contact
    (uniform in :data:`RANGES`), the window starts (uniform among all
    arrangements ``min_gap`` apart in ``[margin, duration - margin]``), then
    per contact its link (uniform over ``links``), its point (uniform in the
    cube ``[-point_range, point_range]³`` around the link-frame origin) and
    its direction. Ids are 1..n in time order.

    With ``trajectory``, the direction follows the desired velocity ``v`` of
    the contact point at the contact's start: ``±v/|v| + spread·N(0, I)``,
    normalised, with ``+`` for a guiding hand (a person pushes the arm the
    way it goes, so power flows into the robot) and ``-`` for a clamp or an
    impact (the obstacle opposes the motion). Without it, or where the point
    moves slower than 1 cm/s, the direction is uniform on the sphere.

    Parameters
    ----------
    robot : RobotModel
        The robot the contacts act on.
    n : int
        Number of contacts, ``>= 0``.
    duration : float
        Length of the run [s].
    rng : numpy.random.Generator
        Source of randomness.
    trajectory : Trajectory, optional
        Desired motion of the run, to orient the forces.
    kinds : sequence of str, default ("guiding", "clamp", "impact")
        Kinds to choose from; keys of :data:`INTERACTION_PROFILES`.
    links : sequence of int, optional
        Links to choose from (1-based); default ``2..n_dof``.
    point_range : float, default 0.05
        Half-width of the cube of contact points around the link origin [m].
    spread : float, default 0.3
        Standard deviation of the Gaussian added to the unit direction [-].
    min_gap : float, default 1.0
        Least time between the end of one contact and the start of the next [s].
    margin : float, default 0.5
        Contact-free time at the start and the end of the run [s].

    Returns
    -------
    ContactSet
    """
    if not isinstance(rng, np.random.Generator):
        raise InputTypeError(
            "rng must be a numpy.random.Generator (numpy.random.default_rng(seed)); "
            f"got {type(rng).__name__}"
        )
    if trajectory is not None and not isinstance(trajectory, Trajectory):
        raise InputTypeError(f"trajectory must be a Trajectory; got {type(trajectory).__name__}")
    count = check_int(n, "n", 0)
    run = _number(duration, "duration", "run length [s]", lower=0.0, strict=True)
    gap = _number(min_gap, "min_gap", "[s]", lower=0.0)
    edge = _number(margin, "margin", "[s]", lower=0.0)
    cube = _number(point_range, "point_range", "[m]", lower=0.0)
    sigma = _number(spread, "spread", "[-]", lower=0.0)
    chosen = [kinds] if isinstance(kinds, str) else list(kinds)
    unknown = [kind for kind in chosen if kind not in INTERACTION_PROFILES]
    if not chosen or unknown:
        raise UnknownNameError(
            f"kinds must name at least one of {sorted(INTERACTION_PROFILES)}; got {kinds!r}"
        )
    choices = _link_choices(robot, links)
    drawn = [chosen[int(i)] for i in rng.integers(len(chosen), size=count)]
    values = [_draw(rng, RANGES[kind]) for kind in drawn]
    starts = _place(
        rng, np.array([_length(k, v) for k, v in zip(drawn, values, strict=True)]), run, edge, gap
    )
    contacts = []
    for index, (kind, value) in enumerate(zip(drawn, values, strict=True)):
        link = choices[int(rng.integers(len(choices)))]
        point = rng.uniform(-cube, cube, size=3)
        start = float(starts[index])
        sense = 1.0 if kind == "guiding" else -1.0
        direction = _direction(rng, robot, trajectory, (link, point, start), sense, sigma)
        contacts.append(Contact(index + 1, link, point, direction, _profile(kind, start, value)))
    return ContactSet(contacts)


def random_interactions(
    spec: Mapping[str, Any],
    robot: RobotModel,
    trajectory: Trajectory,
    duration: float,
    rng: np.random.Generator,
) -> ContactSet:
    """The contacts of a scenario's ``random_interactions`` section (validated).

    Parameters
    ----------
    spec : mapping
        ``count`` and the keyword arguments of :func:`draw_interactions`.
    robot : RobotModel
        The true robot.
    trajectory : Trajectory
        The run's desired motion (orients the forces).
    duration : float
        Length of the run [s].
    rng : numpy.random.Generator
        The run's generator, after the trajectory's draws.
    """
    options = dict(spec)
    count = options.pop("count")
    for key in ("kinds", "links"):
        if options.get(key) is not None:
            options[key] = tuple(options[key])
    return draw_interactions(robot, count, duration, rng, trajectory=trajectory, **options)


def simulate_interactions(
    scenario: Scenario, n: int, seed: int, **options: Any
) -> SimulationResult:
    """Run ``scenario`` with ``n`` drawn interactions instead of its own contacts.

    The robot, controller, motion, sensors and noise are those of
    ``scenario.build(seed, collisions=False)``; the contacts come from
    :func:`draw_interactions` with the run's trajectory and a generator
    seeded by ``(seed, 12)``, a stream apart from the scenario's own. The
    log's ``metadata["collisions"]`` carries every contact's ``kind``
    (:meth:`~sensorless.simulation.contact_set.ContactSet.summaries`).

    Parameters
    ----------
    scenario : Scenario
        A scenario (:func:`~sensorless.simulation.scenario.load_scenario`).
    n : int
        Number of contacts.
    seed : int
        Run seed (noise, random motion, contacts).
    **options
        Keyword arguments of :func:`draw_interactions` (``kinds``, ``links``...).

    Returns
    -------
    SimulationResult
    """
    kwargs = scenario.build(seed, collisions=False)
    rng = np.random.default_rng((check_int(seed, "seed", 0), 12))
    contacts = draw_interactions(
        kwargs["plant"].robot, n, scenario.duration, rng, trajectory=kwargs["trajectory"], **options
    )
    kwargs["contacts"] = contacts
    kwargs["metadata"] = {
        **kwargs["metadata"],
        "collisions_enabled": True,
        "collisions": contacts.summaries(),
    }
    return simulate(**kwargs)
