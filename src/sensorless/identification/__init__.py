"""Identification of friction and dynamic parameters from experiment logs."""

from .friction import (
    FrictionFit,
    fit_coulomb,
    fit_coulomb_viscous,
    fit_lugre_dynamic,
    fit_stribeck,
    plot_friction_map,
    steady_state_map,
    sweep_velocities,
)
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
    "EliminationReport",
    "FrictionFit",
    "RegressionAccumulator",
    "RegressionResult",
    "RelativeWeightSignificance",
    "eliminate",
    "fit_coulomb",
    "fit_coulomb_viscous",
    "fit_lugre_dynamic",
    "fit_stribeck",
    "identify_base_parameters",
    "least_squares",
    "plot_friction_map",
    "relative_weight_significance",
    "relative_weights",
    "steady_state_map",
    "sweep_velocities",
]
