"""A set of contacts on one robot and its ground truth: labels and collision windows.

:class:`ContactSet` sums the joint torques of its contacts, eq. (5.34), and
gives the ground-truth label of every sample (:meth:`ContactSet.active_id`)
and the collision windows (:meth:`ContactSet.windows`) used to score a
detector. :meth:`ContactSet.random` draws a reproducible benchmark set
(:mod:`sensorless.simulation.random_contacts`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray
from ..exceptions import InputTypeError, InputValueError
from ..robots.model import RobotModel
from .contact import Contact, joint_torque_sum
from .force_profiles import _times
from .random_contacts import PROFILE_KINDS, draw_contacts

__all__ = ["ContactSet"]


class ContactSet:
    """Several contacts acting on one robot, with ground-truth labels.

    Parameters
    ----------
    contacts : iterable of Contact
        Contacts with unique ids. Their windows may overlap; the set keeps
        the given order.
    """

    def __init__(self, contacts: Iterable[Contact] = ()) -> None:
        items = list(contacts)
        seen: dict[int, int] = {}
        for position, contact in enumerate(items):
            if not isinstance(contact, Contact):
                raise InputTypeError(
                    f"ContactSet takes Contact objects; item {position} is {type(contact).__name__}"
                )
            if contact.id in seen:
                raise InputValueError(
                    f"contact ids must be unique; id {contact.id} is used by items "
                    f"{seen[contact.id]} and {position}"
                )
            seen[contact.id] = position
        self._contacts: tuple[Contact, ...] = tuple(items)

    def __len__(self) -> int:
        return len(self._contacts)

    def __iter__(self) -> Iterator[Contact]:
        return iter(self._contacts)

    def __getitem__(self, index: int) -> Contact:
        return self._contacts[index]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ContactSet):
            return NotImplemented
        return self._contacts == other._contacts

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"ContactSet({list(self._contacts)!r})"

    def check(self, robot: RobotModel) -> None:
        """Raise :class:`InputValueError` naming the first contact on a link ``robot`` lacks."""
        for contact in self._contacts:
            contact.check(robot)

    def joint_torque(self, robot: RobotModel, q: ArrayLike, t: ArrayLike) -> FloatArray:
        """Sum of the contacts' joint torques [N m], eq. (5.34).

        Arguments and result as in :meth:`Contact.joint_torque`; an empty
        set gives zeros.
        """
        return joint_torque_sum(self._contacts, robot, q, t)

    @overload
    def active_id(self, t: float) -> int: ...

    @overload
    def active_id(self, t: NDArray[Any] | Sequence[float]) -> NDArray[np.int64]: ...

    def active_id(self, t: ArrayLike) -> int | NDArray[np.int64]:
        """Ground-truth label: id of the contact acting at time(s) ``t`` [s], 0 if none.

        A contact acts on its closed window ``[start, end]``. When windows
        overlap, the contact with the largest force magnitude wins; on a tie
        (e.g. two windows that touch, both at zero force) the one listed
        first.

        Returns
        -------
        int, or ndarray of int of the shape of ``t``
        """
        times = _times(t)
        flat = times.reshape(-1)
        labels = np.zeros(flat.shape, dtype=np.int64)
        if self._contacts:
            strength = np.full((len(self._contacts), flat.size), -np.inf)
            for k, contact in enumerate(self._contacts):
                inside = (flat >= contact.start) & (flat <= contact.end)
                strength[k, inside] = np.abs(contact.profile(flat[inside]))
            ids = np.array([contact.id for contact in self._contacts], dtype=np.int64)
            labels = np.where(np.isfinite(strength.max(axis=0)), ids[strength.argmax(axis=0)], 0)
        return int(labels[0]) if times.ndim == 0 else labels.reshape(times.shape)

    def windows(self) -> list[tuple[int, float, float]]:
        """``(id, start, end)`` of every contact [s], in the set's order."""
        return [(c.id, c.start, c.end) for c in self._contacts]

    def summaries(self) -> list[dict[str, Any]]:
        """:meth:`Contact.summary` of every contact."""
        return [c.summary() for c in self._contacts]

    @classmethod
    def random(
        cls,
        robot: RobotModel,
        n: int,
        duration: float,
        rng: np.random.Generator,
        *,
        links: Sequence[int] | None = None,
        kinds: Sequence[str] = PROFILE_KINDS,
        peak_range: tuple[float, float] = (20.0, 80.0),
        duration_range: tuple[float, float] = (0.1, 0.5),
        min_gap: float = 1.0,
        margin: float = 0.5,
        point_range: float = 0.05,
    ) -> ContactSet:
        """Draw ``n`` separated contacts at random times, links, points and directions.

        All randomness comes from ``rng``, so the same generator state gives
        the same set. Windows lie in ``[margin, duration - margin]`` and are
        separated by at least ``min_gap``; their positions are uniform among
        all such arrangements. Ids are 1..n in time order.

        Each contact draws, in this order: its profile kind (uniform over
        ``kinds``), its link (uniform over ``links``), a point uniform in the
        cube ``[-point_range, point_range]³`` around the link-frame origin,
        a direction uniform on the unit sphere, and a peak force uniform in
        ``peak_range``. A push spends 20–40 % of its window on each ramp.

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
        links : sequence of int, optional
            Links to choose from (1-based); default ``2..n_dof`` (link 1
            when ``n_dof == 1``), since a force on the base link often
            produces little joint torque.
        kinds : sequence of str, default ("half_sine", "push")
            Profile kinds to choose from; see :data:`PROFILE_KINDS`.
        peak_range : (float, float), default (20, 80)
            Range of peak forces [N].
        duration_range : (float, float), default (0.1, 0.5)
            Range of contact window lengths [s].
        min_gap : float, default 1.0
            Least time between the end of one contact and the start of the next [s].
        margin : float, default 0.5
            Contact-free time at the start and the end of the run [s].
        point_range : float, default 0.05
            Half-width of the cube of contact points around the link origin [m].
        """
        return cls(
            draw_contacts(
                robot,
                n,
                duration,
                rng,
                links,
                kinds,
                peak_range,
                duration_range,
                min_gap,
                margin,
                point_range,
            )
        )
