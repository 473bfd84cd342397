"""Physically consistent standard parameters that reproduce given base parameters.

Identification gives base parameters θ (thesis Table 2.7), but a simulator, a
Newton–Euler code or a plot of link masses needs standard (classical)
parameters π with ``combinations @ π = θ`` (:mod:`sensorless.robots.base_parameters`)
*and* links that are rigid bodies. Typically only ~25 of the 11·n_dof
unknowns are fixed by θ; the rest are chosen here as those nearest to a prior
model, subject to physical consistency.

Method
------
A link is a rigid body iff its pseudo-inertia matrix

    J = [[Σ, h], [hᵀ, m]],   Σ = ½ tr(Ī) 1 − Ī,   h = (mX, mY, mZ),

is positive semidefinite (Wensing, Kim & Slotine, IEEE RA-L 3(1), 2018;
:func:`~sensorless.simulation.model_error.pseudo_inertia`), with Ī = (XX ...
ZZ) the inertia about the link frame origin [kg m²]. Following Rucker &
Wensing, "Smooth parameterization of rigid-body inertia", IEEE RA-L 7(2),
2022, each J is written through its log-Cholesky factor,

    J = margin·1 + U Uᵀ,   U = e^α [[e^d₁, s₁₂, s₁₃, t₁],
                                    [0,   e^d₂, s₂₃, t₂],
                                    [0,   0,   e^d₃, t₃],
                                    [0,   0,   0,    1 ]],

ten unconstrained numbers per link: α = ½ ln(m − margin), d and s (a
length scale and shear of the mass distribution [m]) and t (the centre of
mass [m] when the margin is negligible). Every iterate is a rigid body
(positive mass, valid moments, triangle inequality) with J ⪰ ``margin``·1,
the sense of "consistent" used here; :attr:`ConsistentFit.min_eigenvalue`
reports each link's smallest eigenvalue. The armature is Ia = b² ≥ 0.

Declared zeros (``base.zero``, e.g. XY, XZ, mX of Table 2.5) are built into
the factor. On a positive semidefinite J a zero "diagonal" parameter removes
whole coordinates: XX = Σ_yy + Σ_zz = 0 removes y and z, YY removes x and z,
ZZ removes x and y, m the homogeneous one (then h = 0 too); the margin only
applies to the coordinates left. A zero off-diagonal parameter (XY = −Σ_xy,
XZ, YZ, mX = h_x, mY, mZ) splits the coordinates left into blocks with a
factor each (U restricted to the block), so the Table 2.5 pattern (XY = XZ =
mX = 0) holds exactly by construction. A declared zero the blocks cannot
express (XY alone, say) is a residual of weight 10³ and is set exactly to
zero at the end, which the margin absorbs. A link whose declared zeros
remove every coordinate (Table 2.5 link 1, all but ZZ1 zero: a single moment
about one axis is no rigid body unless it is zero) gets J = 0.

:func:`scipy.optimize.least_squares` (Levenberg–Marquardt, analytic
Jacobian) minimises the stacked residuals

    (a) (combinations @ π(x) − θ) / v,
    (b) sqrt(w) (x − x_prior) / σ,
    (c) 10³ π_k / p_k for the declared zeros of the last paragraph,

with x the factor variables and armatures, and p_k the prior's magnitude of
the kind of π_k (inertia, first moment, mass, armature) on its link. (a)
weighs base parameters of different units and magnitudes (10⁻⁴ ... 3.5 for
the KUKA LWR) by their relative error: v_j = |θ_j|, but at least 10⁻² of
the value θ_j would have with the prior's magnitudes, Σ_k |combinations_jk|
p_k (a target of exactly zero would otherwise make the problem too stiff).
(b) picks, among the many solutions (θ fixes about 25 of 70 standard
parameters of a 7-link arm), the one nearest to the prior in the factor's own
coordinates: σ = 1 for α and d (relative changes of the mass and the size),
the prior's largest radius of gyration for s and t, and for b the square root
of the prior's armature or, if larger, inertia scale. Linear in x, (b) adds
nothing that Gauss–Newton neglects, which keeps the passes short, and
parameters with no effect on θ (XX1 of a vertical first joint, ...) stay at
the prior. x_prior is the prior with the declared zeros applied and each
block of J − margin·1 eigenvalue-clipped at ``max(margin, 1e-12)``, so any
prior will do.

A prior weight w > 0 leaves a residual of order w in (a). The fit is repeated
from the previous solution with w, 10⁻³ w, 10⁻⁶ w and 10⁻⁹ w, and after each
pass the remaining residual is removed by the smallest scaled change of the
free standard parameters (a least-norm correction), kept only if it moves
no link's smallest eigenvalue down by more than 1 % of the margin. It stops
as soon as every base parameter is within ``tolerance`` of its scale,
``max_j |r_j| / s_j ≤ tolerance`` (default 1e-8) with s_j = max(|θ_j|, 10⁻⁶
max|θ|), or the budget of evaluations runs out. ``success`` means that
criterion holds and every link is a rigid body with a non-negative armature
(:func:`~sensorless.simulation.model_error.physically_consistent_links`). A
target θ that no rigid bodies produce (a negative inertia, say) is a result,
not an error: ``success`` is False, the message names the base parameters
that are missed most, and the model returned is still consistent (such fits
usually use the whole budget; lower ``max_evaluations`` to fail faster).

Examples
--------
>>> import sensorless as sl
>>> from sensorless.identification.consistent import consistent_parameters
>>> from sensorless.simulation.model_error import is_physically_consistent, perturb
>>> true = sl.robots.load("planar2")
>>> base = sl.base_parameters(true)
>>> fit = consistent_parameters(base, base.values, prior=perturb(true, 0.3, seed=1))
>>> fit.success, is_physically_consistent(fit.robot), fit.relative_residual < 1e-8
(True, True, True)
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..robots.base_parameters import BaseParameters
from ..robots.model import N_LINK_PARAMETERS, RobotModel
from ._consistent_fit import ConsistentFit, consistent_fit
from ._consistent_problem import Problem

__all__ = ["ConsistentFit", "consistent_parameters"]

# Prior weight of each pass relative to ``prior_weight``.
_PASS_FACTORS = (1.0, 1e-3, 1e-6, 1e-9)


def consistent_parameters(
    base: BaseParameters,
    theta: ArrayLike,
    *,
    prior: RobotModel | ArrayLike | None = None,
    prior_weight: float = 1e-4,
    margin: float = 1e-6,
    max_evaluations: int = 2000,
    tolerance: float = 1e-8,
) -> ConsistentFit:
    """Physically consistent standard parameters π with ``combinations @ π ≈ θ``.

    Method, scaling and passes are described in the module docstring.

    Parameters
    ----------
    base : BaseParameters
        Grouping of the robot (:func:`~sensorless.base_parameters`); its declared
        zeros ``base.zero`` hold exactly in the result.
    theta : array-like of shape (count,)
        Base parameters to reproduce, ordered as ``base.names`` [kg m², kg m or kg
        per parameter].
    prior : RobotModel or array-like of shape (11·n_dof,) or (n_dof, 11), optional
        Standard parameters to stay near (they settle what θ leaves free);
        default ``base.robot``. Need not be consistent.
    prior_weight : float, default 1e-4
        Weight w ≥ 0 of the relative distance to the prior in the first pass [-].
    margin : float, default 1e-6
        Lower bound on the eigenvalues of each pseudo-inertia J (on the
        coordinates the declared zeros leave), ≥ 0 [kg m², kg m, kg].
    max_evaluations : int, default 2000
        Budget of residual evaluations over all passes.
    tolerance : float, default 1e-8
        Relative tolerance on each base parameter, |r_j| ≤ tolerance·s_j [-].

    Returns
    -------
    ConsistentFit

    Raises
    ------
    InputTypeError
        If ``base`` is not a :class:`BaseParameters`.
    DimensionError
        If θ does not have one entry per base parameter, or the prior another
        number of joints or parameters.
    InputValueError
        If θ or the prior is not finite, or a weight, margin, tolerance or budget
        is negative, zero where it must be positive, or not finite.
    """
    if not isinstance(base, BaseParameters):
        raise InputTypeError(
            f"base must be BaseParameters from sensorless.base_parameters; got "
            f"{type(base).__name__}"
        )
    target = _target(theta, base)
    weight = _check_real(prior_weight, "prior_weight", "relative weight of the prior")
    margin = _check_real(margin, "margin", "smallest pseudo-inertia eigenvalue")
    tolerance = _check_real(tolerance, "tolerance", "relative tolerance", positive=True)
    if (
        isinstance(max_evaluations, bool)
        or not isinstance(max_evaluations, Integral)
        or max_evaluations < 1
    ):
        raise InputValueError(
            f"max_evaluations must be a positive integer; got {max_evaluations!r}"
        )
    robot = base.robot
    zero_index = np.flatnonzero(np.isin(robot.parameter_names(), base.zero))
    prior_values = _prior_vector(prior, base).copy()
    prior_values[zero_index] = 0.0
    problem = Problem.build(base, target, prior_values, margin)
    weights = [weight * factor for factor in _PASS_FACTORS] if weight > 0 else [0.0]
    pi, evaluations, passes = problem.solve(weights, max_evaluations, tolerance, zero_index)
    how = (
        f"{passes} pass(es), last prior weight {weights[passes - 1]:.3g}, {evaluations} evaluations"
    )
    return consistent_fit(base, pi, problem, tolerance, evaluations, max_evaluations, how)


def _check_real(value: object, name: str, meaning: str, *, positive: bool = False) -> float:
    bound = "> 0" if positive else ">= 0"
    if isinstance(value, bool) or not isinstance(value, Real):
        raise InputValueError(f"{name} must be a real number {bound} ({meaning}); got {value!r}")
    number = float(value)
    if not math.isfinite(number) or number < 0 or (positive and number == 0):
        raise InputValueError(f"{name} must be finite and {bound} ({meaning}); got {value!r}")
    return number


def _target(theta: ArrayLike, base: BaseParameters) -> FloatArray:
    """θ of shape (count,), one finite value per base parameter."""
    detail = f", one value per base parameter {base.names}"
    return _parameter_values(theta, "theta", base.names, [(base.count,)], detail)


def _prior_vector(prior: RobotModel | ArrayLike | None, base: BaseParameters) -> FloatArray:
    """The prior's standard parameters π of shape (11·n_dof,)."""
    n_dof = base.robot.n_dof
    if prior is None:
        return base.robot.parameter_vector()
    if isinstance(prior, RobotModel):
        if prior.n_dof != n_dof:
            raise DimensionError(
                f"prior must be a model with {n_dof} joints like the base parameters' robot "
                f"{base.robot.name!r}; got {prior.name!r} with {prior.n_dof} joints"
            )
        return prior.parameter_vector()
    shapes = [(N_LINK_PARAMETERS * n_dof,), (n_dof, N_LINK_PARAMETERS)]
    detail = f" for a robot with {n_dof} joints (or a RobotModel)"
    names = base.robot.parameter_names()
    return _parameter_values(prior, "prior standard parameters", names, shapes, detail)


def _parameter_values(
    value: ArrayLike, what: str, names: list[str], shapes: list[tuple[int, ...]], detail: str
) -> FloatArray:
    """``value`` as a finite float array of shape (len(names),), given in one of ``shapes``.

    ``detail`` completes the shape in the messages ("must have shape (7,){detail}").
    """
    layouts = " or ".join(str(shape) for shape in shapes)
    try:
        values = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(
            f"{what} must be {len(names)} numbers{detail}; could not convert "
            f"{type(value).__name__} to numbers"
        ) from None
    if values.shape not in shapes:
        raise DimensionError(f"{what} must have shape {layouts}{detail}; got shape {values.shape}")
    values = values.ravel()
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputValueError(
            f"{what} must be finite; found {values[bad[0]]} at index {bad[0]} "
            f"({names[bad[0]]}), {bad.size} non-finite value(s) in all"
        )
    return values
