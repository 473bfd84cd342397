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
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np
import pandas as pd
import scipy.optimize
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..robots.base_parameters import BaseParameters
from ..robots.model import N_LINK_PARAMETERS, PARAMETER_NAMES, RobotModel
from ..simulation.model_error import physically_consistent_links, pseudo_inertia

__all__ = ["ConsistentFit", "consistent_parameters"]

# J coordinates (x, y, z, homogeneous) that a declared zero removes from a
# positive semidefinite J, and the J entry an off-diagonal parameter is (up to sign).
_DEAD_COORDINATES = {"XX": (1, 2), "YY": (0, 2), "ZZ": (0, 1), "m": (3,)}
_OFF_DIAGONAL = {"XY": (0, 1), "XZ": (0, 2), "YZ": (1, 2), "mX": (0, 3), "mY": (1, 3), "mZ": (2, 3)}
_ARMATURE = PARAMETER_NAMES.index("Ia")
_ZERO_WEIGHT = 1e3
# Prior weight of each pass relative to ``prior_weight``.
_PASS_FACTORS = (1.0, 1e-3, 1e-6, 1e-9)
_SCALE_FLOOR = 1e-6  # of max|θ|, for base parameters near zero
# In residual (a), base parameters near zero are weighted as this fraction of
# their size with the prior's magnitudes: weighting a zero target by the floor
# above would make the problem too stiff for Levenberg–Marquardt.
_TYPICAL_FRACTION = 1e-2
_KIND_FLOOR = 1e-3  # of the robot's largest prior scale of the same kind
_TINY = 1e-12
# Logarithms are capped here (e^200 ~ 1e87) so that a wild trial step gives a
# huge, finite residual that the solver rejects instead of an overflow.
_LOG_CAP = 100.0
_N_WORST = 5
# Per pass: stop when the cost falls by less than this fraction (the next pass,
# with a smaller prior weight, refines), or the step or gradient is negligible.
_FTOL, _XTOL, _GTOL = 1e-8, 1e-10, 1e-10
# The final correction may take this fraction of the margin.
_POLISH_MARGIN = 1e-2


@dataclass(frozen=True)
class ConsistentFit:
    """Physically consistent standard parameters fitted to base parameters.

    Attributes
    ----------
    robot : RobotModel
        ``base.robot`` with the retrieved standard parameters (kinematics,
        gravity and friction of ``base.robot``).
    parameters : DataFrame of shape (n_dof, 11)
        The retrieved standard parameters π, laid out as
        :meth:`RobotModel.standard_parameters` (taken from π itself, so declared
        zeros are exact zeros; ``robot`` holds them up to Pinocchio round-off):
        ``XX ... ZZ`` [kg m²] about the link frame origin, ``mX, mY, mZ`` [kg m],
        ``m`` [kg], ``Ia`` [kg m²].
    names : list of str
        Base-parameter names, as ``base.names``.
    target : ndarray of shape (count,)
        The requested base parameters θ [units of each parameter].
    reproduced : ndarray of shape (count,)
        ``combinations @ π`` of the retrieved parameters.
    scale : ndarray of shape (count,)
        Scale s_j = max(|θ_j|, 1e-6 max|θ|) of each base parameter; ``success``
        needs |reproduced − target| ≤ tolerance · s everywhere.
    tolerance : float
        Relative tolerance of that test [-].
    min_eigenvalue : ndarray of shape (n_dof,)
        Smallest eigenvalue of each link's 4x4 pseudo-inertia J [mixed: kg m²,
        kg m, kg]: ≥ margin (less at most 1 % of it, the final correction), or
        0 on links whose declared zeros remove a coordinate of J.
    success : bool
        Every base parameter reproduced within tolerance and every link a
        rigid body with non-negative armature.
    message : str
        What was reached, or which base parameters / links failed.
    n_evaluations : int
        Residual evaluations over all passes (Jacobian evaluations not counted).
    """

    robot: RobotModel
    parameters: pd.DataFrame
    names: list[str]
    target: FloatArray
    reproduced: FloatArray
    scale: FloatArray
    tolerance: float
    min_eigenvalue: FloatArray
    success: bool
    message: str
    n_evaluations: int

    @property
    def residual(self) -> FloatArray:
        """``reproduced − target``, shape (count,) [units of each base parameter]."""
        return np.asarray(self.reproduced - self.target)

    @property
    def relative_residual(self) -> float:
        """‖reproduced − target‖ / ‖target‖ [-] (the plain norm if θ = 0)."""
        norm = float(np.linalg.norm(self.target))
        residual = float(np.linalg.norm(self.residual))
        return residual / norm if norm > 0 else residual

    def to_pandas(self) -> pd.DataFrame:
        """One row per base parameter: target, reproduced, residual, scaled_residual."""
        return pd.DataFrame(
            {
                "target": self.target,
                "reproduced": self.reproduced,
                "residual": self.residual,
                "scaled_residual": self.residual / self.scale,
            },
            index=pd.Index(self.names, name="base parameter"),
        )


# --------------------------------------------------------------------------- J <-> π
def _standard_from_pseudo(pseudo: FloatArray) -> FloatArray:
    """The 10 inertial parameters (XX ... m) of pseudo-inertias of shape (..., 4, 4).

    Inverse of :func:`pseudo_inertia`: Ī = tr(Σ)·1 − Σ. Linear, so it also maps
    derivatives of J to derivatives of π.
    """
    s = pseudo[..., :3, :3]
    return np.stack(
        [
            s[..., 1, 1] + s[..., 2, 2],
            -s[..., 0, 1],
            -s[..., 0, 2],
            s[..., 0, 0] + s[..., 2, 2],
            -s[..., 1, 2],
            s[..., 0, 0] + s[..., 1, 1],
            pseudo[..., 0, 3],
            pseudo[..., 1, 3],
            pseudo[..., 2, 3],
            pseudo[..., 3, 3],
        ],
        axis=-1,
    )


@dataclass(frozen=True)
class _Block:
    """One diagonal block of a link's J: ``J_b = margin·1 + e^{2α} V Vᵀ``.

    V is upper triangular with diagonal ``exp(δ)`` (Rucker & Wensing's U = e^α V).
    With the homogeneous coordinate in the block (it is last), V's last diagonal
    entry is 1, e^{2α} = m − margin and V's last column is h / e^{2α} (the
    centre of mass for a negligible margin) [m]; without it there is no α.
    """

    link: int
    coordinates: tuple[int, ...]
    offset: int

    @property
    def size(self) -> int:
        return len(self.coordinates)

    @property
    def has_mass(self) -> bool:
        return self.coordinates[-1] == 3

    @property
    def n_variables(self) -> int:
        return self.size * (self.size + 1) // 2

    @property
    def variables(self) -> list[tuple[int, int]]:
        """Entry of V for each variable: (a, a) log-diagonal, (a, b) a < b free, (-1, -1) α."""
        k = self.size
        logs = [(a, a) for a in range(k - 1 if self.has_mass else k)]
        alpha = [(-1, -1)] if self.has_mass else []
        rows, cols = np.triu_indices(k, 1)
        return logs + alpha + list(zip(rows.tolist(), cols.tolist(), strict=True))

    def factor(self, x: FloatArray) -> tuple[float, FloatArray]:
        """(e^{2α} or 1, V)."""
        factor, scale = np.zeros((self.size, self.size)), 1.0
        if self.has_mass:
            factor[-1, -1] = 1.0
        for k, (a, b) in enumerate(self.variables):
            value = x[self.offset + k]
            if a < 0:
                scale = math.exp(2.0 * min(value, _LOG_CAP))
            elif a == b:
                factor[a, a] = math.exp(min(value, _LOG_CAP))
            else:
                factor[a, b] = value
        return scale, factor

    def derivatives(self, x: FloatArray) -> FloatArray:
        """d J_b / d x of shape (n_variables, size, size)."""
        scale, factor = self.factor(x)
        out = np.zeros((self.n_variables, self.size, self.size))
        for k, (a, b) in enumerate(self.variables):
            if a < 0:
                out[k] = 2.0 * scale * factor @ factor.T
                continue
            # d(V Vᵀ)/dV_ab = e_a V[:, b]ᵀ + V[:, b] e_aᵀ; d V_aa / d δ_a = V_aa.
            out[k, a, :] += factor[:, b]
            out[k, :, a] += factor[:, b]
            out[k] *= scale * (factor[a, a] if a == b else 1.0)
        return out

    def start(self, shifted: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Variables and their prior scales for ``J_b − margin·1 = shifted`` (positive definite).

        The scale is 1 for the logarithms (relative changes of mass and lengths)
        and the block's largest radius of gyration for the free entries
        (centre of mass and shear [m], or [sqrt(kg) m] without the mass).
        """
        scale = shifted[-1, -1] if self.has_mass else 1.0
        normalised = shifted / scale
        flip = normalised[::-1, ::-1]
        factor = np.linalg.cholesky(0.5 * (flip + flip.T))[::-1, ::-1]
        diagonal = np.diag(normalised)[:-1] if self.has_mass else np.diag(normalised)
        length = math.sqrt(float(diagonal.max())) if diagonal.size else 1.0
        values, scales = np.zeros(self.n_variables), np.ones(self.n_variables)
        for k, (a, b) in enumerate(self.variables):
            if a < 0:
                values[k] = 0.5 * math.log(scale)
            elif a == b:
                values[k] = math.log(factor[a, a])
            else:
                values[k], scales[k] = factor[a, b], max(length, _TINY)
        return values, scales


@dataclass(frozen=True)
class _Layout:
    """Map from the unconstrained variables x to the standard parameters π."""

    n_dof: int
    margin: float
    blocks: tuple[_Block, ...]
    armature: tuple[tuple[int, int], ...]  # (link, variable index)
    n_variables: int
    penalised: tuple[int, ...]  # flat indices of declared zeros not built in

    @classmethod
    def build(cls, n_dof: int, zero: set[str], margin: float) -> _Layout:
        blocks: list[_Block] = []
        armature: list[tuple[int, int]] = []
        penalised: list[int] = []
        offset = 0
        for link in range(n_dof):
            declared = {p for p in PARAMETER_NAMES if f"{p}{link + 1}" in zero}
            dead = {c for p, cs in _DEAD_COORDINATES.items() if p in declared for c in cs}
            live = [c for c in range(4) if c not in dead]
            cut = {_OFF_DIAGONAL[p] for p in declared if p in _OFF_DIAGONAL}
            for component in _components(live, cut):
                blocks.append(_Block(link, component, offset))
                offset += blocks[-1].n_variables
                penalised += [
                    link * N_LINK_PARAMETERS + PARAMETER_NAMES.index(p)
                    for p, (a, b) in _OFF_DIAGONAL.items()
                    if p in declared and a in component and b in component
                ]
            if "Ia" not in declared:
                armature.append((link, offset))
                offset += 1
        return cls(n_dof, margin, tuple(blocks), tuple(armature), offset, tuple(sorted(penalised)))

    def parameters(self, x: FloatArray) -> FloatArray:
        """Standard parameters π of shape (11·n_dof,)."""
        pseudo = np.zeros((self.n_dof, 4, 4))
        for block in self.blocks:
            scale, factor = block.factor(x)
            index = np.ix_(block.coordinates, block.coordinates)
            pseudo[block.link][index] = self.margin * np.eye(block.size) + scale * factor @ factor.T
        out = np.zeros((self.n_dof, N_LINK_PARAMETERS))
        out[:, :10] = _standard_from_pseudo(pseudo)
        for link, k in self.armature:
            out[link, _ARMATURE] = x[k] ** 2
        return out.ravel()

    def jacobian(self, x: FloatArray) -> FloatArray:
        """dπ/dx of shape (11·n_dof, n_variables)."""
        out = np.zeros((self.n_dof * N_LINK_PARAMETERS, self.n_variables))
        for block in self.blocks:
            d_pseudo = np.zeros((block.n_variables, 4, 4))
            coords = np.asarray(block.coordinates)
            d_pseudo[:, coords[:, None], coords[None, :]] = block.derivatives(x)
            rows = slice(block.link * N_LINK_PARAMETERS, block.link * N_LINK_PARAMETERS + 10)
            columns = slice(block.offset, block.offset + block.n_variables)
            out[rows, columns] = _standard_from_pseudo(d_pseudo).T
        for link, k in self.armature:
            out[link * N_LINK_PARAMETERS + _ARMATURE, k] = 2.0 * x[k]
        return out

    def start(self, prior: FloatArray, armature_scale: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Variables of the prior's consistent projection, and the scale of each variable.

        Each block of J − margin·1 is projected by clipping its eigenvalues at
        ``max(margin, 1e-12)``. The armature is held off 0 by 1e-12 of its scale
        (at b = 0 its gradient vanishes and it could never grow).
        """
        per_link = prior.reshape(self.n_dof, N_LINK_PARAMETERS)
        pseudo = pseudo_inertia(per_link)
        x, scales = np.zeros(self.n_variables), np.ones(self.n_variables)
        for block in self.blocks:
            index = np.ix_(block.coordinates, block.coordinates)
            shifted = pseudo[block.link][index] - self.margin * np.eye(block.size)
            eigenvalues, vectors = np.linalg.eigh(shifted)
            floor = max(self.margin, _TINY)
            clipped = (vectors * np.maximum(eigenvalues, floor)) @ vectors.T
            span = slice(block.offset, block.offset + block.n_variables)
            x[span], scales[span] = block.start(clipped)
        for link, k in self.armature:
            ia = max(float(per_link[link, _ARMATURE]), _TINY * armature_scale[link])
            x[k], scales[k] = math.sqrt(ia), math.sqrt(armature_scale[link])
        return x, scales


def _components(live: list[int], cut: set[tuple[int, int]]) -> list[tuple[int, ...]]:
    """Connected components of the live J coordinates; an edge is a non-zero entry."""
    remaining = list(live)
    components = []
    while remaining:
        stack, component = [remaining.pop(0)], []
        while stack:
            node = stack.pop()
            component.append(node)
            linked = [c for c in remaining if (min(node, c), max(node, c)) not in cut]
            remaining = [c for c in remaining if c not in linked]
            stack += linked
        components.append(tuple(sorted(component)))
    return components


# --------------------------------------------------------------------------- inputs
def _check_real(value: object, name: str, meaning: str, *, positive: bool = False) -> float:
    bound = "> 0" if positive else ">= 0"
    if isinstance(value, bool) or not isinstance(value, Real):
        raise InputValueError(f"{name} must be a real number {bound} ({meaning}); got {value!r}")
    number = float(value)
    if not math.isfinite(number) or number < 0 or (positive and number == 0):
        raise InputValueError(f"{name} must be finite and {bound} ({meaning}); got {value!r}")
    return number


def _prior_vector(prior: RobotModel | ArrayLike | None, base: BaseParameters) -> FloatArray:
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
    try:
        values = np.asarray(prior, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(
            f"prior must be a RobotModel or standard parameters of shape ({11 * n_dof},) or "
            f"({n_dof}, 11); could not convert {type(prior).__name__} to numbers"
        ) from None
    if values.shape not in ((N_LINK_PARAMETERS * n_dof,), (n_dof, N_LINK_PARAMETERS)):
        raise DimensionError(
            f"prior standard parameters must have shape ({N_LINK_PARAMETERS * n_dof},) or "
            f"({n_dof}, {N_LINK_PARAMETERS}) for a robot with {n_dof} joints; got shape "
            f"{values.shape}"
        )
    values = values.ravel()
    _check_finite(values, "prior standard parameters", base.robot.parameter_names())
    return values


def _target(theta: ArrayLike, base: BaseParameters) -> FloatArray:
    try:
        values = np.asarray(theta, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(
            f"theta must be {base.count} numbers, one per base parameter {base.names}; "
            f"could not convert {type(theta).__name__} to numbers"
        ) from None
    if values.shape != (base.count,):
        raise DimensionError(
            f"theta must have shape ({base.count},), one value per base parameter "
            f"{base.names}; got shape {values.shape}"
        )
    _check_finite(values, "theta", base.names)
    return values


def _check_finite(values: FloatArray, what: str, names: list[str]) -> None:
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputValueError(
            f"{what} must be finite; found {values[bad[0]]} at index {bad[0]} "
            f"({names[bad[0]]}), {bad.size} non-finite value(s) in all"
        )


def _prior_scale(prior: FloatArray) -> FloatArray:
    """Per link and kind the prior's magnitude: inertia, first moment, mass, armature."""
    links = np.abs(prior.reshape(-1, N_LINK_PARAMETERS))
    inertia = links[:, :6].max(axis=1)
    mass = links[:, 9]
    kinds = np.stack(
        [
            inertia,
            np.maximum(links[:, 6:9].max(axis=1), np.sqrt(mass * inertia)),
            mass,
            np.maximum(links[:, _ARMATURE], inertia),
        ],
        axis=1,
    )
    kinds = np.maximum(kinds, np.maximum(_KIND_FLOOR * kinds.max(axis=0), _TINY))
    columns = [0] * 6 + [1] * 3 + [2, 3]
    return kinds[:, columns].ravel()


# --------------------------------------------------------------------------- fit
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
    problem = _Problem.build(base, target, prior_values, margin)
    weights = [weight * factor for factor in _PASS_FACTORS] if weight > 0 else [0.0]
    pi, evaluations, passes = problem.solve(weights, max_evaluations, tolerance, zero_index)
    return _result(
        base, pi, problem, tolerance, evaluations, max_evaluations, weights[passes - 1], passes
    )


@dataclass(frozen=True)
class _Problem:
    """Scaled residuals of one retrieval (module docstring, (a)–(c))."""

    layout: _Layout
    combinations: FloatArray
    target: FloatArray
    scale: FloatArray  # of each base parameter, for the test of success
    weight: FloatArray  # of each base parameter, in residual (a)
    prior_scale: FloatArray  # of each standard parameter
    x_prior: FloatArray
    x_scale: FloatArray

    @classmethod
    def build(
        cls, base: BaseParameters, target: FloatArray, prior: FloatArray, margin: float
    ) -> _Problem:
        layout = _Layout.build(base.robot.n_dof, set(base.zero), margin)
        floor = max(_SCALE_FLOOR * float(np.abs(target).max()), _TINY)
        prior_scale = _prior_scale(prior)
        x_prior, x_scale = layout.start(prior, prior_scale[_ARMATURE::N_LINK_PARAMETERS])
        combinations = base.combinations.to_numpy()
        typical = np.abs(combinations) @ prior_scale
        return cls(
            layout,
            combinations,
            target,
            np.maximum(np.abs(target), floor),
            np.maximum(np.abs(target), np.maximum(_TYPICAL_FRACTION * typical, floor)),
            prior_scale,
            x_prior,
            x_scale,
        )

    def residual(self, x: FloatArray, root: float) -> FloatArray:
        pi = self.layout.parameters(x)
        penalised = list(self.layout.penalised)
        return np.concatenate(
            [
                (self.combinations @ pi - self.target) / self.weight,
                root * (x - self.x_prior) / self.x_scale,
                _ZERO_WEIGHT * pi[penalised] / self.prior_scale[penalised],
            ]
        )

    def jacobian(self, x: FloatArray, root: float) -> FloatArray:
        d_pi = self.layout.jacobian(x)
        penalised = list(self.layout.penalised)
        return np.vstack(
            [
                self.combinations @ d_pi / self.weight[:, None],
                np.diag(root / self.x_scale),
                _ZERO_WEIGHT * d_pi[penalised] / self.prior_scale[penalised, None],
            ]
        )

    def solve(
        self, weights: list[float], budget: int, tolerance: float, zero_index: NDArray[np.intp]
    ) -> tuple[FloatArray, int, int]:
        """Passes of decreasing prior weight; returns (π, evaluations, passes)."""
        x, evaluations, passes = self.x_prior, 0, 0
        pi = self.layout.parameters(x)
        for weight in weights:
            solution = scipy.optimize.least_squares(
                self.residual,
                x,
                jac=self.jacobian,
                method="lm",
                x_scale=self.x_scale,
                ftol=_FTOL,
                xtol=_XTOL,
                gtol=_GTOL,
                max_nfev=budget - evaluations,
                args=(math.sqrt(weight),),
            )
            x, evaluations, passes = solution.x, evaluations + int(solution.nfev), passes + 1
            pi = self.layout.parameters(x)
            pi[zero_index] = 0.0
            pi = self._polish(pi, x, zero_index)
            if self._within(pi, tolerance) or evaluations >= budget:
                break
        return pi, evaluations, passes

    def _within(self, pi: FloatArray, tolerance: float) -> bool:
        return bool(np.all(np.abs(self.combinations @ pi - self.target) <= tolerance * self.scale))

    def _polish(self, pi: FloatArray, x: FloatArray, zero_index: NDArray[np.intp]) -> FloatArray:
        """Remove the last residual by the smallest scaled change of the free parameters.

        Kept only if it helps and costs at most 1 % of the margin on every
        link's smallest pseudo-inertia eigenvalue (and the links stay rigid
        bodies), i.e. when the fit is already close: it turns, e.g., an
        armature b² approaching 0 into an exact 0.
        """
        free = np.flatnonzero(np.any(self.layout.jacobian(x) != 0, axis=1))
        free = np.setdiff1d(free, zero_index)
        error = self.target - self.combinations @ pi
        weighted = self.combinations[:, free] * self.prior_scale[free]
        step, *_ = np.linalg.lstsq(weighted, error, rcond=None)
        polished = pi.copy()
        polished[free] += self.prior_scale[free] * step
        armature = polished[_ARMATURE::N_LINK_PARAMETERS]
        polished[_ARMATURE::N_LINK_PARAMETERS] = np.maximum(armature, 0.0)
        before = np.abs(error) / self.scale
        after = np.abs(self.target - self.combinations @ polished) / self.scale
        margin = self.layout.margin
        old = np.linalg.eigvalsh(pseudo_inertia(pi))[:, 0]
        new = np.linalg.eigvalsh(pseudo_inertia(polished))[:, 0]
        keep = (
            after.max() < before.max()
            and bool(np.all(new >= np.minimum(old, margin) - _POLISH_MARGIN * margin))
            and bool(physically_consistent_links(polished).all())
        )
        return polished if keep else pi


def _result(
    base: BaseParameters,
    pi: FloatArray,
    problem: _Problem,
    tolerance: float,
    evaluations: int,
    budget: int,
    last_weight: float,
    passes: int,
) -> ConsistentFit:
    robot = base.robot.with_standard_parameters(pi)
    target, scale = problem.target, problem.scale
    reproduced = problem.combinations @ pi
    scaled = np.abs(reproduced - target) / scale
    min_eigenvalue = np.asarray(np.linalg.eigvalsh(pseudo_inertia(pi))[:, 0], dtype=float)
    rigid = physically_consistent_links(pi)
    missed = np.flatnonzero(scaled > tolerance)
    success = missed.size == 0 and bool(rigid.all())
    how = f"{passes} pass(es), last prior weight {last_weight:.3g}, {evaluations} evaluations"
    if success:
        message = (
            f"reproduced all {target.size} base parameters within {tolerance:.3g} of their "
            f"scale; every link is a rigid body (smallest pseudo-inertia eigenvalue "
            f"{min_eigenvalue.min():.3g}); {how}"
        )
    else:
        parts = []
        if missed.size:
            worst = missed[np.argsort(scaled[missed])[::-1][:_N_WORST]]
            listed = ", ".join(
                f"{base.names[j]} (target {target[j]:.6g}, reproduced {reproduced[j]:.6g}, "
                f"scaled residual {scaled[j]:.3g})"
                for j in worst
            )
            why = (
                f"the budget of {budget} evaluations ran out"
                if evaluations >= budget
                else "no rigid bodies with the declared zeros give them"
            )
            parts.append(
                f"could not reproduce {missed.size} of {target.size} base parameters within "
                f"{tolerance:.3g} of their scale ({why}); worst: {listed}"
            )
        if not rigid.all():
            bad = [f"link{i + 1}" for i in np.flatnonzero(~rigid)]
            parts.append(
                f"links {bad} are not rigid bodies after setting the declared zeros "
                f"(smallest pseudo-inertia eigenvalues {min_eigenvalue[~rigid]})"
            )
        message = "; ".join(parts) + f"; {how}"
    per_link = pi.reshape(base.robot.n_dof, N_LINK_PARAMETERS)
    index = pd.Index([f"link{i}" for i in range(1, base.robot.n_dof + 1)], name="link")
    return ConsistentFit(
        robot=robot,
        parameters=pd.DataFrame(per_link, index=index, columns=list(PARAMETER_NAMES)),
        names=list(base.names),
        target=target,
        reproduced=reproduced,
        scale=scale,
        tolerance=tolerance,
        min_eigenvalue=min_eigenvalue,
        success=success,
        message=message,
        n_evaluations=evaluations,
    )
