"""External contacts with ground truth: τ_c = J_c(q)ᵀ [f_c; m_c], eq. (5.34).

A collision is a force applied at a point fixed on one link. Its magnitude
over time is a :class:`ForceProfile` (an impact :class:`HalfSine`, a
:class:`Push` that ramps up, holds and releases, or a :class:`Recorded`
force such as the hand force of thesis Fig. 5.5); its direction is a unit
vector in the base frame. :class:`Contact` maps it to joint torques through
the point Jacobian of :meth:`sensorless.robots.RobotModel.point_jacobian`,

    τ_c(t) = J_c(q)ᵀ [f(t) d; 0]                                 eq. (5.34)

with ``d`` the unit direction and no applied moment. :class:`ContactSet`
sums several contacts and gives the ground-truth label of every sample
(:meth:`ContactSet.active_id`) and the collision windows used to score a
detector. :meth:`ContactSet.random` draws a reproducible benchmark set from a
:class:`numpy.random.Generator`.

Units are SI: time [s], force [N], lengths [m], torques [N m]. Links are
numbered from 1 (the link moved by joint 1) to ``n_dof``.

The code lives in one module per concern, all re-exported here:
:mod:`~sensorless.simulation.force_profiles` (the profiles),
:mod:`~sensorless.simulation.contact` (:class:`Contact` and eq. (5.34)),
:mod:`~sensorless.simulation.contact_set` (:class:`ContactSet` and the
ground-truth labels) and :mod:`~sensorless.simulation.random_contacts`
(the draws of :meth:`ContactSet.random`).

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> robot = sl.robots.load("puma560")
>>> hit = Contact(1, link=3, point=[0.2, 0.0, 0.0], direction=[0, 0, -1],
...               profile=HalfSine(start=1.0, duration=0.2, peak=50.0))
>>> contacts = ContactSet([hit])
>>> tau_c = contacts.joint_torque(robot, np.zeros(6), 1.1)  # at the peak
>>> tau_c.shape, bool(np.all(tau_c[3:] == 0.0))
((6,), True)
>>> contacts.active_id(1.1), contacts.active_id(2.0)
(1, 0)
"""

from __future__ import annotations

from .contact import Contact
from .contact_set import ContactSet
from .force_profiles import ForceProfile, HalfSine, Push, Recorded
from .random_contacts import PROFILE_KINDS

__all__ = [
    "PROFILE_KINDS",
    "Contact",
    "ContactSet",
    "ForceProfile",
    "HalfSine",
    "Push",
    "Recorded",
]
