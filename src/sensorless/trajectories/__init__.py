"""Joint-space reference trajectories: via points, random moves, Fourier, velocity sweeps.

Every trajectory is a :class:`Trajectory`: it has ``n_dof`` joints, lasts
``duration`` [s] from ``t = 0`` and gives the joint positions ``q`` [rad],
velocities ``qd`` [rad/s] and accelerations ``qdd`` [rad/s²] at any time with
:meth:`Trajectory.evaluate`, or on a regular grid with
:meth:`Trajectory.sample`. Time runs along axis 0.

Outside ``[0, duration]`` a trajectory holds still: before ``t = 0`` it stays
at ``q(0)`` and after ``t = duration`` at ``q(duration)``, both with zero
velocity and acceleration. A simulation that runs a little longer than its
reference therefore sees a robot commanded to stand still, not an
extrapolated polynomial.

Four families are provided.

:class:`QuinticViaPoints`
    The trajectories of the thesis (Tables 5.1 and 5.8): "a five-order
    polynomial passing through the given points", one quintic per joint and
    per segment between consecutive time-stamped via points, matching
    position, velocity and acceleration at both ends of the segment.
:class:`RandomPointToPoint`
    Seeded random rest-to-rest quintic moves between uniformly drawn targets,
    with the duration of each move long enough to respect a velocity limit.
    Useful to tune thresholds on "a few different trajectories" (section 5.3).
:class:`FourierSeries`
    The finite Fourier series of Swevers et al. (1997), the usual
    parametrisation of excitation trajectories for identification.
:class:`VelocitySweep`
    One joint at a time at constant velocities, the friction experiments of
    section 2.4.1.

Each family has its own module (``quintic``, ``random_ptp``, ``fourier``,
``sweeps``); ``base`` holds :class:`Trajectory` and the input checks they
share. Import the classes from this package.

Examples
--------
>>> import numpy as np
>>> from sensorless.trajectories import QuinticViaPoints
>>> traj = QuinticViaPoints.from_degrees([0.0, 1.0, 2.0], [[0.0], [90.0], [0.0]])
>>> q, qd, qdd = traj.evaluate(1.0)
>>> float(np.rad2deg(q[0])), float(qd[0])
(90.0, 0.0)
>>> t, q, qd, qdd = traj.sample(0.5)
>>> t
array([0. , 0.5, 1. , 1.5, 2. ])
>>> q.shape
(5, 1)
"""

from __future__ import annotations

from .base import Evaluation as Evaluation
from .base import Trajectory
from .fourier import FourierSeries
from .quintic import QuinticViaPoints
from .random_ptp import RandomPointToPoint
from .spline import SplineTrajectory
from .sweeps import VelocitySweep

__all__ = [
    "FourierSeries",
    "QuinticViaPoints",
    "RandomPointToPoint",
    "SplineTrajectory",
    "Trajectory",
    "VelocitySweep",
]
