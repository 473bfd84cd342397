"""Friction identification from constant-velocity sweeps and presliding motion.

The procedure of the thesis, §2.4.1-2.4.2: each joint is moved alone at
constant velocities (-2 ... +2 rad/s in 0.16 rad/s steps, and -0.11 ...
+0.11 rad/s in 0.01 rad/s steps, :func:`sweep_velocities`); the mean
friction torque on each plateau gives the steady-state friction map of
Fig. 2.2 (:func:`steady_state_map`, :func:`plot_friction_map`); a static
model is fitted to that map (:func:`fit_coulomb`, eq. (2.7) and Table 2.2;
:func:`fit_coulomb_viscous`; :func:`fit_stribeck`), and the dynamic LuGre
parameters sigma0, sigma1 are fitted to small presliding motion
(:func:`fit_lugre_dynamic`, Canudas de Wit et al. 1995).

Sign convention and units are those of :mod:`sensorless.friction`: the
friction torque [N m] has the sign of the joint velocity [rad/s]. The map
and fit functions work on one joint; arrays have shape ``(n_samples,)``;
:func:`identify_friction` runs them on every swept joint of a log and
returns a :class:`FrictionIdentification`. Fits return a
:class:`FrictionFit` holding the fitted model (with ``n_dof = 1``) and its
RMS residual.

This module is the public home of these names; the code lives in one
module per concern:

- ``_friction_map``: sweep velocities, plateaus and the steady-state map;
- ``_friction_models``: :class:`FrictionFit` and the static fits;
- ``_friction_lugre``: the LuGre sigma0, sigma1 fit;
- ``_friction_sweep``: :func:`identify_friction` on a whole-robot log;
- ``_friction_result``: :class:`FrictionIdentification`;
- ``_friction_plots``: the figures.
"""

from __future__ import annotations

from ._friction_lugre import fit_lugre_dynamic
from ._friction_map import steady_state_map, sweep_velocities
from ._friction_models import FrictionFit, fit_coulomb, fit_coulomb_viscous, fit_stribeck
from ._friction_plots import plot_friction_map
from ._friction_result import FrictionIdentification
from ._friction_sweep import identify_friction

__all__ = [
    "FrictionFit",
    "FrictionIdentification",
    "fit_coulomb",
    "fit_coulomb_viscous",
    "fit_lugre_dynamic",
    "fit_stribeck",
    "identify_friction",
    "plot_friction_map",
    "steady_state_map",
    "sweep_velocities",
]
