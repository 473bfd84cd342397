"""Immutable robot models built on Pinocchio.

A :class:`RobotModel` holds the constants of a serial arm (kinematics,
inertial parameters, armature, optional friction) in a Pinocchio ``Model``;
the scratch ``Data`` Pinocchio needs is private to the instance. Every
dynamics method accepts one sample, arrays of shape ``(n_dof,)``, or a time
series, arrays of shape ``(n_samples, n_dof)`` with time along axis 0, and
returns results of the matching rank. Units are SI and radians.

Standard inertial parameters and their order are those of
:mod:`sensorless.robots.inertia` (thesis Table 2.5 plus the armature ``Ia``).
The link frame is the frame of the joint that moves the link (for a modified
DH table it is Craig's frame *i*). The Pinocchio models themselves are built
in :mod:`sensorless.robots.builders`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, as_joint_array, check_finite
from ..exceptions import DimensionError, InputValueError, ModelError
from . import kinematics, regressors
from .builders import (
    Convention,
    LinksLike,
    MotorsLike,
    TableOptions,
    model_from_table,
    model_from_urdf,
)
from .fingerprint import model_fingerprint
from .inertia import (
    N_LINK_PARAMETERS,
    PARAMETER_NAMES,
    LinkInertia,
    MotorData,
    inertia_from_parameters,
    parameters_from_inertia,
)

if TYPE_CHECKING:
    from typing import Unpack

    from ..friction import FrictionModel

__all__ = [
    "N_LINK_PARAMETERS",
    "PARAMETER_NAMES",
    "DHOptions",
    "LinkInertia",
    "MotorData",
    "RobotModel",
]


class DHOptions(TableOptions, total=False):
    """Keyword options of :meth:`RobotModel.from_mdh` and :meth:`RobotModel.from_dh`."""

    friction: FrictionModel | None
    description: str


@dataclass(frozen=True, eq=False)
class RobotModel:
    """Immutable model of a serial manipulator with revolute joints.

    Build it with :meth:`from_mdh`, :meth:`from_dh`, :meth:`from_urdf` or
    :meth:`from_pinocchio`; derive variants with :meth:`with_standard_parameters`.
    Not thread-safe: give each thread its own model (``copy.deepcopy``).

    Parameters
    ----------
    pinocchio_model : pinocchio.Model
        Rigid-body model; it is copied, and must have ``n_dof`` one-DoF joints
        (``nq == nv``). Do not mutate :attr:`pinocchio_model` afterwards.
    name : str
        Human-readable name.
    friction : FrictionModel or None
        Joint friction model (see :mod:`sensorless.friction`), or None.
    description : str
        Where the numbers come from.
    """

    pinocchio_model: pin.Model
    name: str = "robot"
    friction: FrictionModel | None = None
    description: str = ""
    _data: pin.Data = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        model = self.pinocchio_model.copy()
        if model.nq != model.nv or model.nv == 0:
            raise ModelError(
                "RobotModel needs a chain of one-DoF joints (nq == nv > 0); "
                f"got nq={model.nq}, nv={model.nv}"
            )
        object.__setattr__(self, "pinocchio_model", model)
        object.__setattr__(self, "_data", model.createData())
        friction_dof = getattr(self.friction, "n_dof", model.nv)
        if self.friction is not None and friction_dof != model.nv:
            raise DimensionError(
                f"friction model has {friction_dof} joints; the robot has {model.nv}"
            )

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_mdh(
        cls, table: Any, links: LinksLike, motors: MotorsLike = None, **options: Unpack[DHOptions]
    ) -> RobotModel:
        """Build a revolute arm from a modified DH table (Craig convention).

        Frame *i* follows frame *i-1* by Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i),
        θ_i = q_i + θ offset; the row of joint *i* holds (α_{i-1}, a_{i-1}, θ offset,
        d_i) as in thesis Table 2.4.

        Parameters
        ----------
        table : DataFrame, sequence of mappings or sequence of 4-sequences
            One row per joint with ``alpha`` [rad], ``a`` [m], ``theta`` offset [rad],
            ``d`` [m].
        links : sequence of LinkInertia or mappings
            Mass [kg], centre of mass [m] and inertia about the centre of mass
            [kg m²] of each link, in its link frame *i*.
        motors : MotorData or mapping, optional
            Rotor inertia [kg m²] and gear ratio per joint; armature = Jm·G².
        gravity : array-like of shape (3,), default (0, 0, -9.81)
            Gravity in the base frame [m/s²] (keyword only, as all that follow).
        friction : FrictionModel, optional
            Joint friction.
        name : str, default "robot"
            Human-readable name.
        description : str, default ""
            Where the numbers come from.
        position_limits, velocity_limits, effort_limits : optional
            Joint limits (lower, upper) [rad], [rad/s], [N m]; unlimited by default.
        """
        return cls._from_table("modified", table, links, motors, **options)

    @classmethod
    def from_dh(
        cls, table: Any, links: LinksLike, motors: MotorsLike = None, **options: Unpack[DHOptions]
    ) -> RobotModel:
        """Build a revolute arm from a standard (distal) DH table.

        Frame *i* follows frame *i-1* by Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i); joint *i*
        turns about z_{i-1}. Inertial data of link *i* are given in frame *i*
        (as in Corke's toolbox). The model's link frame for the standard
        parameters is the joint frame z_{i-1} rotated by q_i.
        Parameters as in :meth:`from_mdh`.
        """
        return cls._from_table("standard", table, links, motors, **options)

    @classmethod
    def _from_table(
        cls,
        convention: Convention,
        table: Any,
        links: LinksLike,
        motors: MotorsLike,
        *,
        friction: FrictionModel | None = None,
        description: str = "",
        **options: Unpack[TableOptions],
    ) -> RobotModel:
        model = model_from_table(table, links, motors, convention=convention, **options)
        return cls(model, model.name, friction, description)

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        joints: Sequence[str] | None = None,
        *,
        tip: str | None = None,
        friction: FrictionModel | None = None,
        armature: ArrayLike | None = None,
        name: str | None = None,
        description: str = "",
    ) -> RobotModel:
        """Build a model from a URDF file with Pinocchio's parser.

        Parameters
        ----------
        path : str or Path
            URDF file.
        joints : sequence of str, optional
            Names of the arm joints to keep, in order; every other movable joint
            is locked at zero (its links stay, rigidly attached). By default,
            every movable joint whose name does not mention a gripper
            (finger, gripper, hand).
        tip : str, optional
            Link name at which to cut the tree: links that are not ancestors of
            ``tip`` (a gripper, a hand, sensors) are removed, mass included.
        friction : FrictionModel, optional
            Joint friction (URDF ``<dynamics>`` tags are ignored).
        armature : array-like of shape (n_dof,), optional
            Joint-side rotor inertia Jm·G² [kg m²].
        name : str, optional
            Human-readable name; by default the URDF's robot name.
        description : str
            Where the numbers come from.
        """
        model = model_from_urdf(path, joints, tip=tip, armature=armature)
        return cls(model, name or model.name, friction, description)

    @classmethod
    def from_pinocchio(
        cls, model: pin.Model, *, name: str | None = None, friction: FrictionModel | None = None
    ) -> RobotModel:
        """Wrap an existing Pinocchio model (copied); its ``armature`` is the joint armature."""
        return cls(model, name or model.name or "robot", friction)

    # ------------------------------------------------------------------ properties
    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.pinocchio_model.nv)

    @property
    def joint_names(self) -> list[str]:
        """Joint names in model order."""
        return [self.pinocchio_model.names[j] for j in range(1, self.pinocchio_model.njoints)]

    @property
    def armature(self) -> FloatArray:
        """Joint-side armature Jm·G² [kg m²], shape (n_dof,)."""
        return np.array(self.pinocchio_model.armature, dtype=float)

    @property
    def position_limits(self) -> tuple[FloatArray, FloatArray]:
        """Lower and upper joint limits [rad]."""
        m = self.pinocchio_model
        return np.array(m.lowerPositionLimit), np.array(m.upperPositionLimit)

    @property
    def velocity_limits(self) -> FloatArray:
        """Joint speed limits [rad/s] (inf when unknown)."""
        return np.array(self.pinocchio_model.velocityLimit)

    @property
    def effort_limits(self) -> FloatArray:
        """Joint torque limits [N m] (inf when unknown)."""
        return np.array(self.pinocchio_model.effortLimit)

    @property
    def fingerprint(self) -> str:
        """Fingerprint of the dynamic parameters (:mod:`sensorless.robots.fingerprint`)."""
        cached: str | None = getattr(self, "_fingerprint", None)
        if cached is None:
            cached = model_fingerprint(self.pinocchio_model, self.friction)
            object.__setattr__(self, "_fingerprint", cached)
        return cached

    @property
    def gravity_vector(self) -> FloatArray:
        """Gravity acceleration in the base frame [m/s²]."""
        return np.array(self.pinocchio_model.gravity.linear)

    def __repr__(self) -> str:
        return f"RobotModel(name={self.name!r}, n_dof={self.n_dof})"

    # ------------------------------------------------------------------ parameters
    def parameter_names(self) -> list[str]:
        """Names of the standard parameters, ``XX1 ... Ia1, XX2, ...`` (11 per link)."""
        return [f"{p}{i}" for i in range(1, self.n_dof + 1) for p in PARAMETER_NAMES]

    def parameter_vector(self) -> FloatArray:
        """Standard parameters π of shape (11·n_dof,), ordered as :meth:`parameter_names`."""
        model = self.pinocchio_model
        out = np.empty((self.n_dof, N_LINK_PARAMETERS))
        for i in range(self.n_dof):
            out[i, :10] = parameters_from_inertia(model.inertias[i + 1])
        out[:, 10] = model.armature
        return out.ravel()

    def standard_parameters(self) -> pd.DataFrame:
        """Standard inertial parameters, one row per link (thesis Table 2.5 names).

        Returns
        -------
        DataFrame of shape (n_dof, 11)
            Columns ``XX, XY, XZ, YY, YZ, ZZ`` [kg m²] about the link frame origin,
            ``mX, mY, mZ`` [kg m], ``m`` [kg], ``Ia`` [kg m²]; index ``link1 ...``.
        """
        values = self.parameter_vector().reshape(self.n_dof, N_LINK_PARAMETERS)
        index = pd.Index([f"link{i}" for i in range(1, self.n_dof + 1)], name="link")
        return pd.DataFrame(values, index=index, columns=list(PARAMETER_NAMES))

    def with_standard_parameters(
        self, parameters: ArrayLike, *, friction: Any = "keep", name: str | None = None
    ) -> RobotModel:
        """Return a copy whose standard parameters are ``parameters``.

        Parameters
        ----------
        parameters : array-like of shape (11·n_dof,) or (n_dof, 11) or DataFrame
            Values in the order of :meth:`parameter_names`.
        friction : FrictionModel or None, optional
            New friction model; by default the current one is kept.
        """
        expected = self.n_dof * N_LINK_PARAMETERS
        shape = f"({expected},) or ({self.n_dof}, {N_LINK_PARAMETERS})"
        values = as_float_array(parameters, "standard parameters", shape).reshape(-1)
        if values.shape != (expected,):
            raise DimensionError(
                f"expected {expected} standard parameters ({self.n_dof} links x 11); "
                f"got {np.size(parameters)}"
            )
        check_finite(values, "standard parameters")
        per_link = values.reshape(self.n_dof, N_LINK_PARAMETERS)
        model = self.pinocchio_model.copy()
        for i in range(self.n_dof):
            model.inertias[i + 1] = inertia_from_parameters(per_link[i, :10], i + 1)
        model.armature = per_link[:, 10].copy()
        new_friction = self.friction if friction == "keep" else friction
        return RobotModel(model, name or self.name, new_friction, self.description)

    # ------------------------------------------------------------------ helpers
    def _states(self, *arrays: tuple[ArrayLike, str]) -> tuple[list[FloatArray], bool]:
        out, singles, lengths = [], set(), set()
        for value, label in arrays:
            arr, single = as_joint_array(value, self.n_dof, label)
            out.append(arr)
            singles.add(single)
            lengths.add(arr.shape[0])
        if len(lengths) > 1:
            raise DimensionError(
                f"{', '.join(label for _, label in arrays)} must have the same number of "
                f"samples; got {[a.shape[0] for a in out]}"
            )
        return out, singles == {True}

    def _per_sample(
        self, algorithm: Callable[..., Any], shape: tuple[int, ...], *states: tuple[ArrayLike, str]
    ) -> FloatArray:
        """Apply ``algorithm(model, data, *state)`` to every sample of the (value, label) states.

        The result has ``shape`` per sample, with a leading sample axis unless
        every state was one sample of shape ``(n_dof,)``.
        """
        arrays, single = self._states(*states)
        model, data = self.pinocchio_model, self._data
        out = np.empty((arrays[0].shape[0], *shape))
        for k, sample in enumerate(zip(*arrays, strict=True)):
            out[k] = algorithm(model, data, *sample)
        if not np.isfinite(out).all():
            k = int(np.flatnonzero(~np.isfinite(out.reshape(out.shape[0], -1)).all(axis=1))[0])
            raise InputValueError(
                f"the result is not finite at sample {k}: the state "
                f"({', '.join(label for _, label in states)}) is beyond what the model can "
                "evaluate in floating point (values of 1e150 and more?)"
            )
        return out[0] if single else out

    def link_id(self, link: int | str) -> int:
        """Pinocchio joint id of ``link``: a 1-based link number or a joint name."""
        if isinstance(link, str):
            if link not in self.joint_names:
                raise ModelError(f"unknown joint {link!r}; options: {self.joint_names}")
            return int(self.pinocchio_model.getJointId(link))
        if isinstance(link, (int, np.integer)) and 1 <= int(link) <= self.n_dof:
            return int(link)
        raise ModelError(
            f"link must be a number from 1 to {self.n_dof} or a joint name; got {link!r}"
        )

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Joint-space inertia matrix M(q), armature included [kg m²].

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].

        Returns
        -------
        ndarray of shape (n_dof, n_dof) or (n_samples, n_dof, n_dof)
        """
        upper = self._per_sample(pin.crba, (self.n_dof, self.n_dof), (q, "q"))
        # CRBA fills the upper triangle; mirror it once for the whole batch.
        return np.triu(upper) + np.swapaxes(np.triu(upper, 1), -1, -2)

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Coriolis/centrifugal matrix C(q, q̇) with Ṁ − 2C skew-symmetric [kg m²/s].

        ``q`` [rad] and ``qd`` [rad/s] of shape (n_dof,) or (n_samples, n_dof) give
        C of shape (n_dof, n_dof) or (n_samples, n_dof, n_dof), as :meth:`mass_matrix`.
        """
        shape = (self.n_dof, self.n_dof)
        return self._per_sample(pin.computeCoriolisMatrix, shape, (q, "q"), (qd, "qd"))

    def coriolis_transpose_velocity(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇)ᵀ q̇ [N m], the term of the momentum observer (eq. 4.4).

        ``q`` [rad] and ``qd`` [rad/s] of shape (n_dof,) or (n_samples, n_dof) give
        a result of the same shape.
        """
        return self._per_sample(_coriolis_transpose_velocity, (self.n_dof,), (q, "q"), (qd, "qd"))

    def gravity(self, q: ArrayLike) -> FloatArray:
        """Gravity torque g(q) [N m].

        ``q`` [rad] of shape (n_dof,) or (n_samples, n_dof) gives g of the same shape.
        """
        return self._per_sample(pin.computeGeneralizedGravity, (self.n_dof,), (q, "q"))

    def nonlinear_effects(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇) q̇ + g(q) [N m]; arguments and shapes as :meth:`coriolis_transpose_velocity`."""
        return self._per_sample(pin.nonLinearEffects, (self.n_dof,), (q, "q"), (qd, "qd"))

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Rigid-body torque M(q) q̈ + C(q, q̇) q̇ + g(q) [N m] (RNEA), friction excluded.

        Parameters
        ----------
        q, qd, qdd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns
        -------
        ndarray of shape (n_dof,) or (n_samples, n_dof)
        """
        states = (q, "q"), (qd, "qd"), (qdd, "qdd")
        return self._per_sample(pin.rnea, (self.n_dof,), *states)

    def friction_torque(self, qd: ArrayLike) -> FloatArray:
        """Steady-state friction torque of the attached friction model [N m].

        Zero when the model has no friction. Stateful models (LuGre) give their
        steady-state curve here; simulate them with their own ``step``.
        """
        (qds,), single = self._states((qd, "qd"))
        if self.friction is None:
            out = np.zeros_like(qds)
        elif hasattr(self.friction, "steady_state"):
            out = self.friction.steady_state(qds)
        else:
            out = self.friction.torque(qds)
        return out[0] if single else out

    # ------------------------------------------------------------------ regressors
    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Regressor Y(q, q̇, q̈) of the standard parameters: Y π = inverse dynamics (eq. 2.11).

        See :func:`sensorless.robots.regressors.regressor`.
        """
        return regressors.regressor(self, q, qd, qdd)

    def regressor_terms(self, q: ArrayLike) -> FloatArray:
        """Split regressor Y_k^q(q) of eq. 3.10–3.12: Y(q, q̇, q̈) = Σ_k Y_k^q(q) Q_k.

        See :func:`sensorless.robots.regressors.regressor_terms`.
        """
        return regressors.regressor_terms(self, q)

    def regressor_term_labels(self) -> list[str]:
        """Labels of :meth:`regressor_terms`: ``M1.., B12.., C1.., g``."""
        return regressors.regressor_term_labels(self.n_dof)

    def q_vector(self, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """The vector Q = [q̈; q̇_i q̇_j (i<j); q̇_i²; 1] of eq. 3.11.

        ``qd`` [rad/s] and ``qdd`` [rad/s²] have shape (n_dof,) or (n_samples, n_dof);
        Q has shape (l,) or (n_samples, l). See :func:`sensorless.robots.regressors.q_vector`.
        """
        (qds, qdds), single = self._states((qd, "qd"), (qdd, "qdd"))
        out = regressors.q_vector(qds, qdds)
        return out[0] if single else out

    # ------------------------------------------------------------------ kinematics
    def link_pose(self, q: ArrayLike, link: int | str) -> FloatArray:
        """Homogeneous transform of a link frame in the base frame [m].

        See :func:`sensorless.robots.kinematics.link_pose`.
        """
        return kinematics.link_pose(self, q, link)

    def forward_kinematics(
        self, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
    ) -> FloatArray:
        """Position in the base frame [m] of a point fixed on a link.

        See :func:`sensorless.robots.kinematics.forward_kinematics`.
        """
        return kinematics.forward_kinematics(self, q, link, point)

    def point_jacobian(
        self, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
    ) -> FloatArray:
        """Geometric Jacobian of a point fixed on a link, in base-frame axes.

        See :func:`sensorless.robots.kinematics.point_jacobian`.
        """
        return kinematics.point_jacobian(self, q, link, point)


def _coriolis_transpose_velocity(
    model: pin.Model, data: pin.Data, q: FloatArray, qd: FloatArray
) -> FloatArray:
    """C(q, q̇)ᵀ q̇ [N m] of one sample."""
    return np.asarray(pin.computeCoriolisMatrix(model, data, q, qd).T @ qd)
