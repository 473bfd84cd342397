"""Model error: a *nominal* robot model that differs from the *true* one.

Every threshold in the thesis has to live with the difference between the
robot and the model the observer uses. Thesis §5.4 assumes "an estimation of
the inertia parameters within 15% error" and "LuGre parameters with 15%
error ... obtained by using random functions". This module draws such a
nominal model from a true one, reproducibly (one seed) and so that the result
is still a set of rigid bodies.

Perturbation
------------
Each factor is ``1 + u`` with ``u ~ Uniform(-relative, relative)``, drawn
independently. Per link: the mass, each coordinate of the centre of mass in
the link frame (a zero coordinate stays zero, so the symmetry pattern is
kept), the three principal moments of the inertia about the centre of mass
(the principal axes are kept) and the joint armature. Per friction
parameter and joint: the value itself (signs and zeros are kept). With
``relative < 1`` every factor is positive, so masses stay positive.

Physical consistency
--------------------
A link is a rigid body if and only if its pseudo-inertia matrix (Wensing,
Kim & Slotine, "Linear matrix inequalities for physically consistent
inertial parameter identification", IEEE RA-L 3(1), 2018)

    J = [[½ tr(Ī) E − Ī, h], [hᵀ, m]],   h = m c,

is positive semidefinite, with Ī the inertia tensor about the link frame
origin [kg m²]. For m > 0 this holds if and only if the principal moments
about the centre of mass satisfy the triangle inequality (each is at most the
sum of the other two, which also makes them non-negative). Scaling the
moments independently can break it for a flat or slender body; the largest
moment is then clipped to the sum of the other two. For a link whose true
moments satisfy the inequality, the clipped value still lies within the
requested band: it is at least ``(1 - relative)`` times the sum of the other
two true moments, which is at least the true largest moment.

Links that are *not* rigid bodies in the true model are perturbed factor-wise
and not clipped: the perturbation does not repair the true model's data (a
draw may make such a link consistent by chance, never the other way round:
every link that is a rigid body in the true model is one in the perturbed
model). The built-in ``puma560`` has two such links, from the data of
Armstrong, Khatib & Burdick (1986): link 1 is massless with a single
principal moment, 0.35 kg m² about the joint-1 axis (the only moment that
enters the dynamics of a link turning about a fixed axis), and link 3 has the
principal moments 0.066, 0.086 and 0.0125 kg m², where 0.086 > 0.066 +
0.0125. Clipping them would delete link 1's inertia and shrink link 3's by
up to about 22 %, an error that was not asked for.
:func:`physically_consistent_links` reports such links;
:func:`is_physically_consistent` is False for the PUMA 560 and its
perturbations (link 1 can never pass), True for ``panda_gaz``, ``panda`` and
``planar2`` and theirs.

Examples
--------
>>> import sensorless as sl
>>> from sensorless.simulation.model_error import is_physically_consistent, perturb
>>> true = sl.robots.load("panda_gaz")
>>> nominal = perturb(true, relative=0.15, seed=1)
>>> bool(is_physically_consistent(nominal))
True
>>> ratio = nominal.parameter_vector()[9::11] / true.parameter_vector()[9::11]
>>> bool(((ratio >= 0.85) & (ratio <= 1.15)).all())  # link masses
True
"""

from __future__ import annotations

import dataclasses
import math
from numbers import Real
from typing import TypeAlias, TypeVar, overload

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray
from ..exceptions import DimensionError, InputValueError, ModelError
from ..friction import FrictionModel, LuGre
from ..robots.model import N_LINK_PARAMETERS, RobotModel

__all__ = [
    "is_physically_consistent",
    "perturb",
    "perturb_friction",
    "perturb_inertia",
    "physically_consistent_links",
    "pseudo_inertia",
]

#: Anything :func:`numpy.random.default_rng` accepts: a seed or a generator.
RandomLike: TypeAlias = "int | np.random.SeedSequence | np.random.Generator | None"

_Friction = TypeVar("_Friction", bound="FrictionModel | LuGre")

# Entries of an inertia tensor below this fraction of its largest entry are
# round-off of rotating the link data into the joint frame. Left in, they can
# turn the principal axes of a symmetric body by up to 45° inside a degenerate
# eigenspace (LAPACK only deflates residues near machine epsilon), and distinct
# factors on those axes would create products of inertia the true link lacks.
_ROUND_OFF = 1e-12
# Per link: mass, centre of mass x, y, z, three principal moments, armature.
_N_FACTORS = 8
_DEFAULT_TOL = 1e-12


def _check_relative(value: object, name: str) -> float:
    """Return ``value`` as a float after checking it is a fraction in [0, 1)."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise InputValueError(
            f"{name} must be a real number in [0, 1) (0.15 for 15 %); got {value!r}"
        )
    relative = float(value)
    if not (math.isfinite(relative) and 0.0 <= relative < 1.0):
        raise InputValueError(
            f"{name} must be a finite fraction in [0, 1) (0.15 for 15 %; 1 or more would "
            f"allow zero or negative masses); got {value!r}"
        )
    return relative


def _check_tol(tol: object) -> float:
    if isinstance(tol, bool) or not isinstance(tol, Real) or not (0.0 <= float(tol) < 1.0):
        raise InputValueError(f"tol must be a relative tolerance in [0, 1); got {tol!r}")
    return float(tol)


def _factors(rng: np.random.Generator, relative: float, shape: tuple[int, ...]) -> FloatArray:
    return 1.0 + rng.uniform(-relative, relative, size=shape)


def _per_link(parameters: RobotModel | ArrayLike) -> FloatArray:
    """Standard parameters as an array of shape (n_dof, 11)."""
    if isinstance(parameters, RobotModel):
        values = parameters.parameter_vector()
    else:
        values = np.asarray(parameters, dtype=float)
    flat = values.ndim == 1 and values.size % N_LINK_PARAMETERS == 0
    table = values.ndim == 2 and values.shape[1] == N_LINK_PARAMETERS
    if values.size == 0 or not (flat or table):
        raise DimensionError(
            f"standard parameters must have shape (11·n_dof,) or (n_dof, 11); got shape "
            f"{values.shape}"
        )
    if not np.isfinite(values).all():
        raise InputValueError("standard parameters must be finite")
    return values.reshape(-1, N_LINK_PARAMETERS)


def pseudo_inertia(robot: RobotModel | ArrayLike) -> FloatArray:
    """Pseudo-inertia matrix of every link (Wensing, Kim & Slotine 2018).

    ``J = [[½ tr(Ī) E − Ī, h], [hᵀ, m]]`` with Ī the inertia tensor about the
    link frame origin [kg m²], ``h = (mX, mY, mZ)`` the first moments [kg m] and
    ``m`` the mass [kg]. ``J`` is the second moment of the mass distribution in
    homogeneous coordinates, ``∫ [p; 1][p; 1]ᵀ dm``, so it is positive
    semidefinite for every rigid body. The armature is not part of it.

    Parameters
    ----------
    robot : RobotModel or array-like of shape (11·n_dof,) or (n_dof, 11)
        A model, or standard parameters in the order of
        :meth:`RobotModel.parameter_names`.

    Returns
    -------
    ndarray of shape (n_dof, 4, 4)
        Entries [kg m²] in the upper-left block, [kg m] in the last column and
        row, [kg] in the corner.
    """
    links = _per_link(robot)
    xx, xy, xz, yy, yz, zz = links[:, :6].T
    inertia = np.stack(
        [np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], 1
    )
    half_trace = 0.5 * np.trace(inertia, axis1=1, axis2=2)
    out = np.zeros((links.shape[0], 4, 4))
    out[:, :3, :3] = half_trace[:, None, None] * np.eye(3) - inertia
    out[:, :3, 3] = links[:, 6:9]
    out[:, 3, :3] = links[:, 6:9]
    out[:, 3, 3] = links[:, 9]
    return out


def _rigid_bodies(robot: RobotModel | ArrayLike, tol: float) -> NDArray[np.bool_]:
    """Per link: is the pseudo-inertia J positive semidefinite up to ``tol`` (relative)?"""
    eigenvalues = np.linalg.eigvalsh(pseudo_inertia(robot))
    scale = np.abs(eigenvalues).max(axis=1)
    return np.asarray(eigenvalues[:, 0] >= -tol * scale)


def physically_consistent_links(
    robot: RobotModel | ArrayLike, tol: float = _DEFAULT_TOL
) -> NDArray[np.bool_]:
    """Which links are rigid bodies: pseudo-inertia J ⪰ 0 and armature ≥ 0.

    A massless link passes if its inertia is zero or, more generally, if its
    principal moments satisfy the triangle inequality (the limit of a body of
    vanishing mass far from the axis, e.g. a rotor idealised as a massless
    ring). The massless PUMA 560 link 1 does not: its single moment about the
    joint axis is not the inertia of any body (see the module docstring).

    Parameters
    ----------
    robot : RobotModel or array-like of shape (11·n_dof,) or (n_dof, 11)
        A model or its standard parameters.
    tol : float, default 1e-12
        Relative tolerance: an eigenvalue of a link's J counts as non-negative
        if it is at least ``-tol`` times the largest eigenvalue magnitude of
        that J (round-off of J built from clipped moments is about 1e-16).

    Returns
    -------
    ndarray of bool of shape (n_dof,)
        True where link *i* (index i − 1) is physically consistent. Masses are
        then non-negative too: m is a diagonal entry of J.
    """
    armature = _per_link(robot)[:, 10]
    return np.asarray(_rigid_bodies(robot, _check_tol(tol)) & (armature >= 0.0))


def is_physically_consistent(robot: RobotModel | ArrayLike, tol: float = _DEFAULT_TOL) -> bool:
    """True if every link is a rigid body; see :func:`physically_consistent_links`.

    Parameters
    ----------
    robot : RobotModel or array-like of shape (11·n_dof,) or (n_dof, 11)
        A model or its standard parameters.
    tol : float, default 1e-12
        Relative tolerance on the eigenvalues of the pseudo-inertia matrices.

    Returns
    -------
    bool
        False for the built-in ``puma560`` (links 1 and 3, see the module
        docstring).
    """
    return bool(physically_consistent_links(robot, tol).all())


def _principal_frame(inertia: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Principal moments (ascending) [kg m²] and axes (columns) of an inertia tensor."""
    cleaned = np.where(np.abs(inertia) > _ROUND_OFF * np.abs(inertia).max(), inertia, 0.0)
    moments, axes = np.linalg.eigh(cleaned)
    return moments, axes


def _clip_triangle(moments: FloatArray) -> FloatArray:
    """Clip the largest principal moment to the sum of the other two if it exceeds it."""
    out = moments.copy()
    largest = int(np.argmax(out))
    others = out.sum() - out[largest]
    out[largest] = min(out[largest], others)
    return out


def perturb_inertia(
    robot: RobotModel, relative: float, rng: RandomLike, *, name: str | None = None
) -> RobotModel:
    """Copy of ``robot`` with randomly scaled, physically consistent inertial parameters.

    Per link, in this order of draws: mass, centre of mass x, y, z (in the
    link frame), the three principal moments about the centre of mass
    (ascending), armature; each is multiplied by ``1 + u``, ``u ~ U(-relative,
    relative)``. A violated triangle inequality is repaired by clipping the
    largest moment (module docstring); links that are not rigid bodies in
    ``robot`` are left unclipped. Kinematics, limits, gravity and friction are
    kept.

    Parameters
    ----------
    robot : RobotModel
        The true model.
    relative : float
        Half-width of the relative error band [-], in [0, 1); 0.15 for 15 %.
    rng : numpy.random.Generator or seed
        Source of the draws; a seed is passed to :func:`numpy.random.default_rng`.
    name : str, optional
        Name of the new model; by default that of ``robot``.

    Returns
    -------
    RobotModel
        The perturbed model, with the friction model of ``robot``.

    Raises
    ------
    InputValueError
        If ``relative`` is not a finite number in [0, 1).
    """
    fraction = _check_relative(relative, "relative")
    model = _perturbed_inertias(robot, fraction, np.random.default_rng(rng))
    return RobotModel(model, name or robot.name, robot.friction, robot.description)


def _perturbed_inertias(
    robot: RobotModel, fraction: float, generator: np.random.Generator
) -> pin.Model:
    """Copy of ``robot``'s Pinocchio model with the draws of :func:`perturb_inertia` applied."""
    factors = _factors(generator, fraction, (robot.n_dof, _N_FACTORS))
    rigid = _rigid_bodies(robot, _DEFAULT_TOL)
    # Rebuilt from (m, c, I_com) rather than through with_standard_parameters,
    # which divides the first moments by the mass (NaN for a massless link).
    model = robot.pinocchio_model.copy()
    for i in range(robot.n_dof):
        link = model.inertias[i + 1]
        moments, axes = _principal_frame(np.array(link.inertia))
        moments = moments * factors[i, 4:7]
        if rigid[i]:
            moments = _clip_triangle(moments)
        model.inertias[i + 1] = pin.Inertia(
            float(link.mass) * factors[i, 0],
            np.array(link.lever) * factors[i, 1:4],
            axes @ np.diag(moments) @ axes.T,
        )
    model.armature = robot.armature * factors[:, 7]
    return model


@overload
def perturb_friction(friction: None, relative: float, rng: RandomLike) -> None: ...
@overload
def perturb_friction(friction: _Friction, relative: float, rng: RandomLike) -> _Friction: ...
def perturb_friction(
    friction: _Friction | None, relative: float, rng: RandomLike
) -> _Friction | None:
    """Friction model of the same class with every per-joint parameter scaled.

    Each parameter of each joint is multiplied by ``1 + u``, ``u ~
    U(-relative, relative)``, drawn field by field in the order of
    :func:`dataclasses.fields`. The factors are positive, so signs, zeros and
    the constructor's constraints (``c_neg <= 0`` of :class:`Coulomb`,
    ``sigma0 > 0`` of :class:`LuGre`, ...) hold for the result.

    Parameters
    ----------
    friction : friction model of :mod:`sensorless.friction` or None
        A frozen dataclass whose fields are the per-joint parameters and whose
        constructor takes them by name. None gives None (no draws).
    relative : float
        Half-width of the relative error band [-], in [0, 1).
    rng : numpy.random.Generator or seed
        Source of the draws.

    Returns
    -------
    friction model of the same class, or None

    Raises
    ------
    InputValueError
        If ``relative`` is not a finite number in [0, 1).
    ModelError
        If ``friction`` is not a dataclass of numeric parameters.
    """
    fraction = _check_relative(relative, "relative")
    if friction is None:
        return None
    cls = type(friction)
    if not dataclasses.is_dataclass(friction) or isinstance(friction, type):
        raise ModelError(
            "perturb_friction needs a friction model that is a dataclass of per-joint "
            f"parameters (a class of sensorless.friction); got {type(friction).__name__}"
        )
    generator = np.random.default_rng(rng)
    values: dict[str, FloatArray] = {}
    for item in dataclasses.fields(friction):
        if not item.init:
            continue
        try:
            value = np.asarray(getattr(friction, item.name), dtype=float)
        except (TypeError, ValueError):
            raise ModelError(
                f"{type(friction).__name__}.{item.name} is not numeric; perturb_friction "
                "scales per-joint numeric parameters only"
            ) from None
        values[item.name] = value * _factors(generator, fraction, value.shape)
    return cls(**values)


def perturb(
    robot: RobotModel,
    relative: float = 0.15,
    seed: RandomLike = 0,
    friction_relative: float | None = None,
    name: str | None = None,
) -> RobotModel:
    """Nominal model: ``robot`` with inertial and friction parameters in a random band.

    The inertial parameters are drawn first (:func:`perturb_inertia`), then the
    friction (:func:`perturb_friction`), from one generator, so one seed fixes
    the whole nominal model. Thesis §5.4 uses 15 % on both.

    Parameters
    ----------
    robot : RobotModel
        The true model.
    relative : float, default 0.15
        Half-width of the relative band of the inertial parameters [-], in [0, 1).
    seed : int, numpy.random.SeedSequence, numpy.random.Generator or None, default 0
        Seed of :func:`numpy.random.default_rng`. The default is fixed so that
        a script gives the same nominal model on every run; None draws fresh
        entropy.
    friction_relative : float, optional
        Half-width of the relative band of the friction parameters [-], in
        [0, 1); by default ``relative``.
    name : str, optional
        Name of the new model; by default that of ``robot``.

    Returns
    -------
    RobotModel
        The nominal model, with inertial parameters as :func:`perturb_inertia`
        and friction as :func:`perturb_friction` would draw them.

    Raises
    ------
    InputValueError
        If ``relative`` or ``friction_relative`` is not a finite number in [0, 1).
    ModelError
        If the friction model of ``robot`` is not a dataclass of numeric parameters.
    """
    fraction = _check_relative(relative, "relative")
    friction_fraction = (
        fraction
        if friction_relative is None
        else _check_relative(friction_relative, "friction_relative")
    )
    generator = np.random.default_rng(seed)
    model = _perturbed_inertias(robot, fraction, generator)
    friction = perturb_friction(robot.friction, friction_fraction, generator)
    return RobotModel(model, name or robot.name, friction, robot.description)
