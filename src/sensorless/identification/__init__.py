"""Identification of friction and dynamic parameters (thesis chapter 2).

- Friction from constant-velocity sweeps and presliding motion (§2.4.1-2.4.2):
  :func:`identify_friction`, :func:`steady_state_map`, ``fit_*``.
- Base parameters by least squares with statistics, pooling, relative weights
  and the elimination of Table 2.7 (§2.4.3): :func:`identify_base_parameters`,
  :func:`identify_from_logs`, :class:`RegressionAccumulator`,
  :func:`relative_weights`, :func:`eliminate`.
- From a controller's sampled M(q) and g(q) (eq. 2.14-2.15):
  :func:`identify_from_matrices`, :func:`contributing_terms`.
- Excitation trajectories (Swevers et al. 1997): :func:`optimize_excitation`.
- Physically consistent classical parameters from base parameters:
  :func:`consistent_parameters`.
- What a rigid-body model lacks on a real arm, joint by joint from its error
  on logs: a motor-torque offset and asymmetric Coulomb + viscous friction,
  :func:`identify_correction` → :class:`NominalCorrection`.
- An unknown payload's mass and centre of mass from the momentum residual of
  a collision-free motion: :func:`estimate_payload`, :class:`PayloadEstimator`.
"""

from .consistent import ConsistentFit, consistent_parameters
from .correction import NominalCorrection, identify_correction
from .excitation import ExcitationResult, load_excitation, optimize_excitation
from .friction import (
    FrictionFit,
    FrictionIdentification,
    fit_coulomb,
    fit_coulomb_viscous,
    fit_lugre_dynamic,
    fit_stribeck,
    identify_friction,
    plot_friction_map,
    steady_state_map,
    sweep_velocities,
)
from .logs import identify_from_logs
from .matrices import contributing_terms, identify_from_matrices, matrix_regressors
from .payload import PayloadEstimate, PayloadEstimator, estimate_payload
from .regression import (
    EliminationReport,
    RegressionAccumulator,
    RegressionResult,
    RelativeWeightSignificance,
    eliminate,
    identify_base_parameters,
    least_squares,
    relative_weight_significance,
    relative_weights,
)

__all__ = [
    "ConsistentFit",
    "EliminationReport",
    "ExcitationResult",
    "FrictionFit",
    "FrictionIdentification",
    "NominalCorrection",
    "PayloadEstimate",
    "PayloadEstimator",
    "RegressionAccumulator",
    "RegressionResult",
    "RelativeWeightSignificance",
    "consistent_parameters",
    "contributing_terms",
    "eliminate",
    "estimate_payload",
    "fit_coulomb",
    "fit_coulomb_viscous",
    "fit_lugre_dynamic",
    "fit_stribeck",
    "identify_base_parameters",
    "identify_correction",
    "identify_friction",
    "identify_from_logs",
    "identify_from_matrices",
    "least_squares",
    "load_excitation",
    "matrix_regressors",
    "optimize_excitation",
    "plot_friction_map",
    "relative_weight_significance",
    "relative_weights",
    "steady_state_map",
    "sweep_velocities",
]
