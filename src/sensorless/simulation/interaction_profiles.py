"""Who or what applies a contact force: a guiding hand, a clamp, an impact.

Thesis §6.2 item 7 asks to tell a person's intended interaction from an
accidental collision. Three force profiles model them, each with its
ground-truth label :attr:`~sensorless.simulation.force_profiles.ForceProfile.kind`:

* :class:`GuidingHand` (``"intended"``): a hand builds up 10–40 N over
  0.3–1 s with a raised cosine, holds it for 1–3 s and lets go as slowly;
* :class:`Clamp` (``"collision"``): the arm runs into an obstacle; the force
  grows linearly at contact stiffness × approach speed, stays while the arm
  is held, and falls when it backs off;
* :class:`Impact` (``"collision"``): a rise of a few milliseconds (< 20 ms)
  and a fall, 30–100 ms in all.

A :class:`~sensorless.simulation.contact.Contact` applies a profile at a point
fixed in a link frame, so every contact moves with its link; the direction
is fixed in the base frame. :func:`interaction_profile` builds one from a
scenario's contact entry (``profile: guiding``, ``clamp`` or ``impact``);
:func:`kind_of_profile` gives the label of a profile class by its name, for
logs whose ground truth names only the ``profile``. Seeded draws of mixed
sets: :mod:`sensorless.simulation.interactions`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..exceptions import InputValueError, UnknownNameError
from .force_profiles import ForceProfile, Push, _number

__all__ = [
    "INTERACTION_PROFILES",
    "Clamp",
    "GuidingHand",
    "Impact",
    "interaction_profile",
    "kind_of_profile",
]


class GuidingHand(Push):
    """A person's hand guiding the arm: a slow raised-cosine ramp, a hold, a ramp down.

    The force of :class:`~sensorless.simulation.force_profiles.Push`,
    ``peak (1 - cos(π s / ramp)) / 2`` for the time ``s`` since ``start`` and
    its mirror image before ``end``, labelled ``kind = "intended"``. Rise
    time ``ramp``, steepest slope ``π peak / (2 ramp)`` [N/s], integral
    ``peak (ramp / 2 + hold + release / 2)`` [N s].
    :data:`~sensorless.simulation.interactions.RANGES` holds the values of a
    hand that :func:`~sensorless.simulation.interactions.draw_interactions`
    draws; any positive values are accepted here.

    Parameters
    ----------
    start : float
        Instant the hand starts to push [s].
    ramp : float
        Rise time from 0 to ``peak`` [s], ``> 0``.
    hold : float
        Time at ``peak`` [s], ``>= 0``.
    release : float
        Fall time from ``peak`` to 0 [s], ``> 0``.
    peak : float
        Held force [N], ``>= 0``.
    """

    kind = "intended"

    def __init__(self, start: float, ramp: float, hold: float, release: float, peak: float) -> None:
        # Checked under this class's name first, so that a message names the guiding hand.
        _number(start, "GuidingHand start", "time [s]")
        _number(ramp, "GuidingHand ramp", "rise time [s]", lower=0.0, strict=True)
        _number(hold, "GuidingHand hold", "time at peak [s]", lower=0.0)
        _number(release, "GuidingHand release", "fall time [s]", lower=0.0, strict=True)
        _number(peak, "GuidingHand peak", "force [N]", lower=0.0)
        super().__init__(start, ramp, hold, release, peak)


class Clamp(ForceProfile):
    """Clamping against an obstacle: a linear build-up, a hold, a raised-cosine release.

    What is modelled: the contact point moves at a constant speed ``v``
    [m/s] into an obstacle of contact stiffness ``k`` [N/m], so the force
    grows at the constant rate ``k v`` [N/s] from the first touch (a kink at
    ``start``, unlike a hand's smooth onset) until the arm is stopped at
    ``peak``; it stays there for ``hold`` while the arm is held, and falls
    over ``release`` with a raised cosine when the arm backs off. The force
    is a function of time only, as every profile is: the simulated arm feels
    it but is not stopped by it. Rise time ``build``, rise rate
    ``peak / build`` [N/s], integral ``peak (build / 2 + hold + release / 2)``
    [N s]. Labelled ``kind = "collision"``.

    Parameters
    ----------
    start : float
        Instant of first contact [s].
    build : float
        Time from first contact to ``peak`` [s], ``> 0``.
    hold : float
        Time at ``peak`` [s], ``>= 0``.
    release : float
        Fall time from ``peak`` to 0 [s], ``> 0``.
    peak : float
        Clamping force [N], ``>= 0``.

    Examples
    --------
    >>> clamp = Clamp.from_approach(start=1.0, stiffness=5000.0, speed=0.02,
    ...                             peak=100.0, hold=1.0, release=0.2)
    >>> clamp.build, clamp.rate, clamp(1.5), clamp(2.5)
    (1.0, 100.0, 50.0, 100.0)
    """

    def __init__(
        self, start: float, build: float, hold: float, release: float, peak: float
    ) -> None:
        start_ = _number(start, "Clamp start", "time [s]")
        self._build = _number(build, "Clamp build", "build-up time [s]", lower=0.0, strict=True)
        self._hold = _number(hold, "Clamp hold", "time at peak [s]", lower=0.0)
        self._release = _number(release, "Clamp release", "fall time [s]", lower=0.0, strict=True)
        peak_ = _number(peak, "Clamp peak", "force [N]", lower=0.0)
        super().__init__(start_, start_ + self._build + self._hold + self._release, peak_)

    @classmethod
    def from_approach(
        cls, start: float, stiffness: float, speed: float, peak: float, hold: float, release: float
    ) -> Clamp:
        """The clamp of a point moving at ``speed`` into an obstacle of ``stiffness``.

        Parameters
        ----------
        start : float
            Instant of first contact [s].
        stiffness : float
            Contact stiffness of the obstacle [N/m], ``> 0``.
        speed : float
            Approach speed of the contact point [m/s], ``> 0``.
        peak, hold, release : float
            Clamping force [N] (``> 0``), time at it [s] and fall time [s].

        Returns
        -------
        Clamp
            With ``build = peak / (stiffness speed)``.
        """
        k = _number(stiffness, "Clamp stiffness", "[N/m]", lower=0.0, strict=True)
        v = _number(speed, "Clamp speed", "approach speed [m/s]", lower=0.0, strict=True)
        force = _number(peak, "Clamp peak", "force [N]", lower=0.0, strict=True)
        return cls(start, force / (k * v), hold, release, force)

    @property
    def build(self) -> float:
        """Time from first contact to the peak [s]."""
        return self._build

    @property
    def rate(self) -> float:
        """Rise rate of the force during the build-up, ``peak / build`` [N/s]."""
        return self._peak / self._build

    def _inside(self, t: FloatArray) -> FloatArray:
        rise = np.minimum((t - self._start) / self._build, 1.0)
        fall = 0.5 * (1.0 - np.cos(np.pi * np.minimum((self._end - t) / self._release, 1.0)))
        return self._peak * np.minimum(rise, fall)

    def parameters(self) -> dict[str, Any]:
        """Constructor arguments: ``start``, ``build``, ``hold``, ``release``, ``peak``."""
        return {
            "start": self._start,
            "build": self._build,
            "hold": self._hold,
            "release": self._release,
            "peak": self._peak,
        }


class Impact(ForceProfile):
    """Impact: a fast raised-cosine rise and a raised-cosine fall, short overall.

    ``peak (1 - cos(π s / rise)) / 2`` for the time ``s`` since ``start`` up
    to ``rise``, then ``peak (1 + cos(π (s - rise) / (duration - rise))) / 2``
    down to 0 at ``start + duration``. Unlike a
    :class:`~sensorless.simulation.force_profiles.HalfSine`, the rise can be
    much shorter than the fall, as when a moving arm hits a rigid object.
    Rise time ``rise``, impulse ``peak duration / 2`` [N s]. Labelled
    ``kind = "collision"``.

    Parameters
    ----------
    start : float
        Instant of first contact [s].
    rise : float
        Time from first contact to ``peak`` [s], ``0 < rise < duration``.
    duration : float
        Length of the impact [s].
    peak : float
        Largest force [N], ``>= 0``.

    Examples
    --------
    >>> hit = Impact(start=1.0, rise=0.01, duration=0.05, peak=80.0)
    >>> hit(1.01), round(hit(1.03), 9), round(hit.end, 12)
    (80.0, 40.0, 1.05)
    """

    def __init__(self, start: float, rise: float, duration: float, peak: float) -> None:
        start_ = _number(start, "Impact start", "time [s]")
        self._rise = _number(rise, "Impact rise", "rise time [s]", lower=0.0, strict=True)
        self._length = _number(duration, "Impact duration", "[s]", lower=0.0, strict=True)
        if not self._rise < self._length:
            raise InputValueError(
                f"Impact rise must be shorter than its duration; got rise = {rise!r} s, "
                f"duration = {duration!r} s"
            )
        peak_ = _number(peak, "Impact peak", "force [N]", lower=0.0)
        super().__init__(start_, start_ + self._length, peak_)

    @property
    def rise(self) -> float:
        """Time from first contact to the peak [s]."""
        return self._rise

    def _inside(self, t: FloatArray) -> FloatArray:
        since = t - self._start
        up = 0.5 * (1.0 - np.cos(np.pi * np.minimum(since / self._rise, 1.0)))
        fraction = np.clip((since - self._rise) / (self._length - self._rise), 0.0, 1.0)
        down = 0.5 * (1.0 + np.cos(np.pi * fraction))
        return self._peak * np.where(since <= self._rise, up, down)

    def parameters(self) -> dict[str, Any]:
        """Constructor arguments: ``start``, ``rise``, ``duration``, ``peak``."""
        return {
            "start": self._start,
            "rise": self._rise,
            "duration": self._length,
            "peak": self._peak,
        }


#: Profile of each interaction kind a scenario file names (``profile: guiding`` ...).
INTERACTION_PROFILES: dict[str, type[ForceProfile]] = {
    "guiding": GuidingHand,
    "clamp": Clamp,
    "impact": Impact,
}


def interaction_profile(spec: Mapping[str, Any]) -> ForceProfile:
    """The profile a scenario's contact entry names: ``profile`` guiding, clamp or impact.

    Parameters
    ----------
    spec : mapping
        A contact entry of a scenario file (validated), with ``profile`` and
        the arguments of that profile's class (``start``, ...).

    Raises
    ------
    UnknownNameError
        ``profile`` is not one of :data:`INTERACTION_PROFILES`.
    """
    kind = spec.get("profile")
    if kind not in INTERACTION_PROFILES:
        raise UnknownNameError(
            f"unknown interaction profile {kind!r}; options: {sorted(INTERACTION_PROFILES)}"
        )
    cls = INTERACTION_PROFILES[kind]
    if cls is Impact:
        return Impact(spec["start"], spec["rise"], spec["duration"], spec["peak"])
    if cls is Clamp:
        return Clamp(spec["start"], spec["build"], spec["hold"], spec["release"], spec["peak"])
    return GuidingHand(spec["start"], spec["ramp"], spec["hold"], spec["release"], spec["peak"])


def _profile_classes(root: type[ForceProfile] = ForceProfile) -> dict[str, type[ForceProfile]]:
    found: dict[str, type[ForceProfile]] = {}
    for sub in root.__subclasses__():
        found[sub.__name__] = sub
        found.update(_profile_classes(sub))
    return found


def kind_of_profile(name: str) -> str:
    """Ground-truth label of a profile class by its name; "collision" if unknown.

    The simulator writes the class name of each contact's profile into the
    log (``metadata["collisions"][i]["profile"]``); this maps it back to its
    :attr:`~sensorless.simulation.force_profiles.ForceProfile.kind`.

    Examples
    --------
    >>> kind_of_profile("GuidingHand"), kind_of_profile("HalfSine"), kind_of_profile("?")
    ('intended', 'collision', 'collision')
    """
    cls = _profile_classes().get(name)
    return "collision" if cls is None else cls.kind
