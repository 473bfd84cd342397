"""Isolation: which link was touched, where, and how hard.

A contact force F on link k at a point c produces the external joint torque
τ_c = J_c(q)ᵀ F (eq. 5.34), zero beyond joint k, and the residual r̂ follows
τ_c through K_I/(s+K_I) (eq. 3.6). From r̂ and the threshold's bounds, an
:class:`Isolator` finds

* the link: the last joint whose residual leaves its band bounds it from
  below; the fit of the residual's direction on every link above decides;
* the point and the force: a least-squares fit of F over candidate points on
  the link's surface (:mod:`~sensorless.isolation.surfaces`: collision
  geometry of a URDF, or a capsule around the link), refined on the surface;
* the force's worst-case uncertainty from the bands' half-widths, and how
  |F̂| compares with the quasi-static limits of ISO/TS 15066 (65–210 N).

:meth:`Isolator.step` judges one sample, :meth:`Isolator.run` a recorded
run with the same result, :meth:`Isolator.isolate_events` gives one
:class:`ContactEstimate` per detected :class:`~sensorless.signals.Event`, and
:meth:`Isolator.force_series` F̂(t) at a fixed point. The method and its
limits are in :mod:`sensorless.isolation.estimate`; evaluation against the
simulator's ground truth in :mod:`sensorless.evaluation.isolation`.

Examples
--------
A 30 N push on link 6 of a PUMA 560 at a known point of its capsule, seen
without error (r̂ = τ_c) and judged against bands of ±0.01 N m: the link,
the point and the force come back.

>>> import numpy as np
>>> import sensorless as sl
>>> from sensorless.isolation import Isolator
>>> robot = sl.robots.load("puma560")
>>> isolator = Isolator(robot)
>>> q = np.array([0.3, -0.5, 0.4, 0.2, 0.8, -0.3])
>>> point = isolator.surfaces[6].points[40]         # on the capsule around joint 6's axis
>>> normal = isolator.surfaces[6].normals[40]       # outward, radial there
>>> side = np.cross([0.0, 0.0, 1.0], normal)        # so that joint 6 feels the push too
>>> rotation = robot.link_pose(q, 6)[:3, :3]
>>> force = 30.0 * rotation @ (-0.8 * normal + 0.6 * side)
>>> r = robot.point_jacobian(q, 6, point)[:3].T @ force
>>> estimate = isolator.step(q, r, -0.01 * np.ones(6), 0.01 * np.ones(6))
>>> estimate.link, bool(np.allclose(estimate.point_link, point, atol=1e-9))
(6, True)
>>> bool(np.allclose(estimate.force, force, atol=1e-6)), round(estimate.magnitude, 6)
(True, 30.0)
"""

from __future__ import annotations

from .isolator import SEARCHES, Isolator
from .results import (
    QUASI_STATIC_LIMITS,
    TRANSIENT_FACTOR,
    ContactEstimate,
    ForceSeries,
    IsolationResult,
)
from .surfaces import CapsuleSurface, MeshSurface, Surface, capsule_surfaces, urdf_surfaces

__all__ = [
    "QUASI_STATIC_LIMITS",
    "SEARCHES",
    "TRANSIENT_FACTOR",
    "CapsuleSurface",
    "ContactEstimate",
    "ForceSeries",
    "IsolationResult",
    "Isolator",
    "MeshSurface",
    "Surface",
    "capsule_surfaces",
    "urdf_surfaces",
]
