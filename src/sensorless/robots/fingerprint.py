"""A short fingerprint of a robot model's dynamic parameters.

Two models with the same name and joint count can still differ: a payload on
the last link, an identified parameter set, another friction model. Residuals
observed with one model and thresholds fitted on them are only meaningful for
that model, so :class:`~sensorless.signals.ObserverSignals`, fitted thresholds
and threshold files carry the fingerprint of the nominal model, and a
mismatch is a :class:`~sensorless.exceptions.ModelMismatchError`.

The fingerprint covers what the momentum residual depends on: joint types,
joint placements, the inertia of every body (mass [kg], centre of mass [m],
rotational inertia [kg m²]), armature [kg m²], gravity [m/s²] and the friction
model's class and parameters. Numbers are rounded to 9 decimals so that the
same model rebuilt from its saved parameters has the same fingerprint.
Names, limits and descriptions are left out.
"""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Any

import numpy as np
import pinocchio as pin

__all__ = ["DIGITS", "model_fingerprint"]

#: Decimals kept of every number before hashing.
DIGITS = 9


def _numbers(values: Any) -> bytes:
    rounded = np.round(np.asarray(values, dtype=float).reshape(-1), DIGITS) + 0.0  # no -0.0
    return rounded.astype("<f8").tobytes()


def _friction_parts(friction: Any) -> list[bytes]:
    if friction is None:
        return [b"no friction"]
    parts = [type(friction).__name__.encode()]
    if dataclasses.is_dataclass(friction):
        for item in dataclasses.fields(friction):
            value = getattr(friction, item.name)
            if dataclasses.is_dataclass(value):
                parts += [item.name.encode(), *_friction_parts(value)]
            else:
                try:
                    parts += [item.name.encode(), _numbers(value)]
                except (TypeError, ValueError):
                    parts += [item.name.encode(), repr(value).encode()]
    else:
        parts.append(repr(friction).encode())
    return parts


def model_fingerprint(model: pin.Model, friction: Any = None) -> str:
    """Fingerprint of a Pinocchio model and its friction model: 16 hexadecimal digits.

    Parameters
    ----------
    model : pinocchio.Model
        The rigid-body model (SI units).
    friction : FrictionModel or None
        The joint friction model.

    Returns
    -------
    str
        The first 16 hexadecimal digits of a SHA-256 over the parameters listed
        in the module docstring.
    """
    digest = hashlib.sha256()
    for j in range(1, model.njoints):
        placement = model.jointPlacements[j]
        inertia = model.inertias[j]
        digest.update(model.joints[j].shortname().encode())
        digest.update(_numbers(placement.rotation))
        digest.update(_numbers(placement.translation))
        digest.update(_numbers([inertia.mass, *inertia.lever, *inertia.inertia.reshape(-1)]))
    digest.update(_numbers(model.armature))
    digest.update(_numbers(model.gravity.linear))
    for part in _friction_parts(friction):
        digest.update(part)
    return digest.hexdigest()[:16]
