"""Model-based time-varying threshold B_c(t) for the acceleration-based estimate τ̂_c (§ 3.5).

With zero external torque, τ̂_c = τ̃_c (eq. 3.38), and eq. 3.34–3.36 bound it
at joint j by

    B_cj(t) = Σ_k |Y_kj^q(q) Θ̂| B_Q̃k + Σ_p Σ_k |Y_kjp^q(q)| B_Q̃k B_Θ̃p
              + Σ_p |Y_jp(q, q̂̇, q̂̈)| B_Θ̃p + B_fr,j + B_dj,

so a collision is |τ̂_cj(t)| > B_cj(t) (eq. 3.39): the bounds are ±B_c. The
three trajectory terms are those of :mod:`sensorless.metric` (Θ are the base
parameters of the nominal robot, Y_k^q its split regressor, eq. 3.12), but
evaluated on the *measured* q and the *estimated* q̂̇, q̂̈ the observer used,
so the threshold can run online.

What :meth:`ModelBasedThreshold.fit` learns from collision-free runs
(kind ``"acceleration"``, with ``position`` and ``acceleration`` present):

``bq_``
    B_Q̃ (eq. 3.26) = max_t |Q̂ − Q_ref| per entry of Q (eq. 3.11, 3.18), the
    last entry 0. Q̂ is built from the run's q̂̇, q̂̈; Q_ref from zero-phase
    Savitzky–Golay derivatives of the measured positions
    (:class:`~sensorless.filters.SavitzkyGolay`, window ``reference_window``
    seconds, cubic). On a log the true derivatives are unknown; a centred,
    delay-free polynomial fit over a short window stands in for them, the
    offline counterpart of the Table 3.1 method (which needs the planned
    trajectory, see :func:`sensorless.metric.q_error_bounds`). Pass ``bq``
    to use bounds computed that way instead.
``theta_``, ``independent_``
    Θ̂, the base-parameter values of the nominal ``robot``, and their
    columns in the standard regressor.
``btheta_``
    B_Θ̃ (eq. 3.27): ``btheta``·|Θ̂| for a float (0.02, eq. 3.40) or the
    given bound per base parameter.
``b_fr_``
    B_fr,j, the bound on the actuator and friction model errors |τ̃_L| +
    |τ̃_fr| of eq. 3.36, which the thesis leaves to the user: the smallest
    constant such that no fit sample leaves the bound, max_t(|τ̂_cj| −
    (model part + B_dj)) clipped at 0, plus ``margin`` (and a rounding guard).
``b_d_``
    B_d, the disturbance bound ``disturbance`` per joint [N m].

The bound is memoryless: it depends only on the sample's q, q̂̇, q̂̈, so
:meth:`~Threshold.step`, :meth:`~Threshold.process` and
:meth:`~Threshold.bounds` give the same values sample by sample.

The nominal robot is a hyper-parameter. In a saved file it is written as a
rigid-body description (joint placements and types, gravity and the
standard parameters), from which :func:`~sensorless.thresholds.base.load_threshold`
rebuilds an equivalent :class:`RobotModel` (without friction or limits,
which the threshold does not use).
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import FloatArray, per_joint
from ..exceptions import DimensionError, InputTypeError, InputValueError, ModelError
from ..filters import SavitzkyGolay
from ..metric import (
    DEFAULT_CHUNK_SIZE,
    BoundTerms,
    check_bq,
    error_bound_terms,
    parameter_bounds,
    q_length,
    q_vector,
)
from ..robots import load as load_robot
from ..robots.base_parameters import BaseParameters, base_parameters
from ..robots.model import N_LINK_PARAMETERS, RobotModel
from ..signals import ObserverSignals
from .base import StreamBounds, Threshold
from .checks import regular_period
from .fitting import BoolArray, rounding_guard
from .state import ThresholdInputs, ThresholdState

__all__ = ["ModelBasedThreshold"]

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ")
_UNALIGNED = "JointModelRevoluteUnaligned"
# The QR behind base_parameters is the slow part of a refit; models are immutable.
_BASE_CACHE: weakref.WeakKeyDictionary[RobotModel, BaseParameters] = weakref.WeakKeyDictionary()

States = tuple[FloatArray, FloatArray]
"""Positions q [rad] and estimated accelerations q̂̈ [rad/s²], each (n_samples, n_dof)."""


class ModelBasedThreshold(Threshold):
    """Bounds ±B_c(t) of eq. 3.36 for the acceleration-based estimate τ̂_c (eq. 3.16, 3.39).

    Parameters
    ----------
    robot : RobotModel, str or mapping
        Nominal robot model (Θ̂ are its base parameters): a :class:`RobotModel`,
        the name of a built-in robot (:func:`sensorless.robots.load`) or the
        description written in a saved file.
    btheta : float or array-like of shape (n_base,)
        B_Θ̃: relative to |Θ̂| (default 0.02 = 2 %, eq. 3.40) or one bound per
        base parameter in its unit (e.g. regression confidence intervals).
    bq : array-like of shape (l,), optional
        Fixed B_Q̃ (eq. 3.26), e.g. from :func:`sensorless.metric.q_error_bounds`;
        by default learned from the fit runs (see the module docstring).
    margin : float or array-like of shape (n_dof,)
        Added to B_fr [N m], >= 0.
    disturbance : float or array-like of shape (n_dof,)
        B_d, bound of the disturbance torque |τ_d| [N m], >= 0 (eq. 3.36).
    reference_window : float
        Length [s] of the Savitzky–Golay window that gives the reference
        derivatives when ``bq`` is learned; at least 5 samples.
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`
        (``transient`` e.g. the start-up of the velocity/acceleration filter).
    chunk_size : int
        Samples per block of the bound terms in their numpy form (bounds
        memory); the compiled form, used when numba is installed, needs none.

    Attributes
    ----------
    bq_ : ndarray of shape (l,)
        B_Q̃ [rad/s², rad²/s²], l = (n² + 3n + 2)/2.
    theta_ : ndarray of shape (n_base,)
        Base-parameter values Θ̂ of the nominal robot.
    independent_ : ndarray of int of shape (n_base,)
        Columns of the base parameters in the standard regressor.
    btheta_ : ndarray of shape (n_base,)
        B_Θ̃ (eq. 3.27).
    b_fr_ : ndarray of shape (n_dof,)
        B_fr, the learned actuator/friction error bound [N m], margin included.
    b_d_ : ndarray of shape (n_dof,)
        B_d [N m].

    Examples
    --------
    >>> import numpy as np
    >>> import sensorless as sl
    >>> from sensorless.signals import ObserverSignals
    >>> robot = sl.robots.load("planar2")
    >>> t = np.arange(400) * 1e-3
    >>> q = np.column_stack([np.sin(t), 0.5 * t**2])
    >>> qd = np.column_stack([np.cos(t), t])
    >>> qdd = np.column_stack([-np.sin(t), np.ones_like(t)])
    >>> tau_c = 0.01 * np.cos(40 * t)[:, None] * np.ones(2)    # an estimate with small errors
    >>> z = np.zeros_like(q)
    >>> run = ObserverSignals(t, tau_c, z, z, z, qd, gain=1.0, kind="acceleration",
    ...                       robot="planar2", position=q, acceleration=qdd)
    >>> threshold = ModelBasedThreshold(robot, btheta=0.02).fit(run)
    >>> lower, upper = threshold.bounds(run)
    >>> bool(np.all(np.abs(tau_c) <= upper))
    True
    """

    name = "model"
    _integer_attributes = ("independent_",)

    bq_: FloatArray
    theta_: FloatArray
    independent_: NDArray[np.int64]
    btheta_: FloatArray
    b_fr_: FloatArray
    b_d_: FloatArray
    _robot_cache: tuple[Any, RobotModel]

    def __init__(
        self,
        robot: RobotModel | str | Mapping[str, Any],
        btheta: Any = 0.02,
        bq: Any = None,
        margin: Any = 0.0,
        disturbance: Any = 0.0,
        *,
        reference_window: float = 0.05,
        joints: Any = None,
        transient: float = 0.0,
        chunk_size: int = DEFAULT_CHUNK_SIZE,
    ) -> None:
        super().__init__(margin, joints=joints, transient=transient)
        self.robot = robot
        self.btheta = btheta
        self.bq = bq
        self.disturbance = disturbance
        self.reference_window = reference_window
        self.chunk_size = chunk_size

    # ----------------------------------------------------------------- robot

    def robot_model(self) -> RobotModel:
        """The nominal robot as a :class:`RobotModel` (built from a name or a description)."""
        cached = getattr(self, "_robot_cache", None)
        if cached is not None and cached[0] is self.robot:
            return cached[1]
        if isinstance(self.robot, RobotModel):
            model = self.robot
        elif isinstance(self.robot, str):
            model = load_robot(self.robot)
        elif isinstance(self.robot, Mapping):
            model = _robot_from_description(self.robot)
        else:
            raise InputTypeError(
                "robot must be a RobotModel, the name of a built-in robot or a saved robot "
                f"description (mapping); got {type(self.robot).__name__}"
            )
        self._robot_cache = (self.robot, model)
        return model

    def to_dict(self) -> dict[str, Any]:
        """The fitted threshold as plain values; the robot becomes a rigid-body description."""
        data = super().to_dict()
        params = dict(data["params"])
        if isinstance(self.robot, RobotModel):
            params["robot"] = _describe_robot(self.robot)
        elif isinstance(self.robot, Mapping):
            params["robot"] = dict(self.robot)
        data["params"] = params
        return data

    # ----------------------------------------------------------------- hooks

    def _attribute_names(self) -> tuple[str, ...]:
        return ("bq_", "theta_", "independent_", "btheta_", "b_fr_", "b_d_")

    def _check_attributes(self) -> None:
        n = self.n_dof_
        n_base = self.theta_.shape
        expected = {
            "bq_": (q_length(n),),
            "theta_": n_base,
            "independent_": n_base,
            "btheta_": n_base,
            "b_fr_": (n,),
            "b_d_": (n,),
        }
        for name, shape in expected.items():
            value = getattr(self, name)
            if value.shape != shape or len(shape) != 1:
                raise DimensionError(
                    f"attribute {name} must have shape {shape} for {n} joints and "
                    f"{n_base[0] if n_base else '?'} base parameters; got shape {value.shape}"
                )
        columns = self.independent_
        if columns.size and (columns.min() < 0 or columns.max() >= n * N_LINK_PARAMETERS):
            raise InputValueError(
                f"independent_ must index the {n * N_LINK_PARAMETERS} standard parameters of "
                f"{n} links; got {columns.tolist()}"
            )

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        robot = self.robot_model()
        n_dof = robot.n_dof
        states = [self._check_run(run, n_dof, f"fit run {i}") for i, run in enumerate(runs)]
        b_d = per_joint(self.disturbance, n_dof, "disturbance", "N m", "nonnegative")
        bq = self._learn_bq(runs, keep, states) if self.bq is None else check_bq(self.bq, n_dof)
        base = _base_parameters(robot)
        theta = base.values_of(robot)
        btheta = parameter_bounds(self.btheta, theta)
        excess = np.zeros(n_dof)
        guard = np.zeros(n_dof)
        for run, k, (position, acceleration) in zip(runs, keep, states, strict=True):
            terms = error_bound_terms(
                robot, base.independent, theta, position[k], run.velocity[k], acceleration[k],
                bq, btheta, chunk_size=self.chunk_size,
            )  # fmt: skip
            model = _model_part(terms)
            residual = run.residual[k]
            if residual.shape[0]:
                excess = np.maximum(excess, np.max(np.abs(residual) - model - b_d, axis=0))
                guard = np.maximum(guard, rounding_guard(residual, model + b_d))
        self.bq_ = bq
        self.theta_ = theta
        self.independent_ = np.asarray(base.independent, dtype=np.int64)
        self.btheta_ = btheta
        self.b_fr_ = excess + margin + guard
        self.b_d_ = b_d

    def _learn_bq(
        self, runs: list[ObserverSignals], keep: list[BoolArray], states: list[States]
    ) -> FloatArray:
        """B_Q̃ from checked runs and their (position, acceleration)."""
        bq = np.zeros(q_length(runs[0].n_dof))
        for i, (run, (position, acceleration)) in enumerate(zip(runs, states, strict=True)):
            dt = regular_period(run.t, f"fit run {i}")
            window = _window_samples(self.reference_window, dt)
            reference = SavitzkyGolay(dt, window, polyorder=3).filter(position)
            error = q_vector(run.velocity, acceleration) - q_vector(
                reference.velocity, reference.acceleration
            )
            if keep[i].any():
                bq = np.maximum(bq, np.abs(error[keep[i]]).max(axis=0))
        bq[-1] = 0.0
        return bq

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        # The one check of streamed inputs: step and process do not know what a family reads.
        position, acceleration = _require_states(inputs.position, inputs.acceleration, "inputs")
        terms = self._terms(position, inputs.velocity, acceleration)
        upper = _model_part(terms) + self.b_fr_ + self.b_d_
        return -upper, upper, state

    def _terms(
        self, position: FloatArray, velocity: FloatArray, acceleration: FloatArray
    ) -> BoundTerms:
        """The trajectory terms of B_c (eq. 3.36) for checked q, q̂̇, q̂̈."""
        return error_bound_terms(
            self.robot_model(), self.independent_, self.theta_, position, velocity,
            acceleration, self.bq_, self.btheta_, chunk_size=self.chunk_size,
        )  # fmt: skip

    def check_signals(self, signals: ObserverSignals) -> None:
        """As :meth:`Threshold.check_signals`, and require positions and accelerations."""
        self._signal_states(signals)

    def _signal_states(self, signals: ObserverSignals) -> States:
        """:meth:`check_signals`, returning the positions and accelerations of ``signals``."""
        super().check_signals(signals)
        states = _require_states(signals.position, signals.acceleration, "signals")
        if self.robot_model().n_dof != signals.n_dof:
            raise DimensionError(
                f"the nominal robot has {self.robot_model().n_dof} joints; signals have "
                f"{signals.n_dof}"
            )
        return states

    def bound_terms(self, signals: ObserverSignals) -> BoundTerms:
        """The three trajectory terms of B_c (eq. 3.36) over a run, for plots [N m].

        Parameters
        ----------
        signals : ObserverSignals
            Run with ``position`` and ``acceleration``.

        Returns
        -------
        BoundTerms
            ``q_error``, ``cross`` and ``parameter_error``, each of shape
            (n_samples, n_dof); B_c is their sum plus ``b_fr_ + b_d_``.
        """
        position, acceleration = self._signal_states(signals)
        return self._terms(position, signals.velocity, acceleration)

    def _check_run(self, run: ObserverSignals, n_dof: int, what: str) -> States:
        """Check a fit run; return its positions [rad] and accelerations [rad/s²]."""
        if run.kind != "acceleration":
            raise InputValueError(
                f"ModelBasedThreshold bounds the acceleration-based estimate τ̂_c (eq. 3.16): "
                f"{what} must be of kind 'acceleration'; got {run.kind!r}"
            )
        if run.n_dof != n_dof:
            raise DimensionError(f"the nominal robot has {n_dof} joints; {what} has {run.n_dof}")
        return _require_states(run.position, run.acceleration, what)


# ------------------------------------------------------------------------- helpers


def _base_parameters(robot: RobotModel) -> BaseParameters:
    """Base parameters of ``robot``, computed once per (immutable) model."""
    base = _BASE_CACHE.get(robot)
    if base is None:
        base = _BASE_CACHE[robot] = base_parameters(robot)
    return base


def _model_part(terms: BoundTerms) -> FloatArray:
    return np.asarray(terms.q_error + terms.cross + terms.parameter_error)


def _require_states(
    position: FloatArray | None, acceleration: FloatArray | None, what: str
) -> States:
    missing = [
        name
        for name, value in (("position", position), ("acceleration", acceleration))
        if value is None
    ]
    if missing or position is None or acceleration is None:
        raise InputValueError(
            "ModelBasedThreshold needs the joint positions q [rad], estimated velocities "
            "q̂̇ [rad/s] and accelerations q̂̈ [rad/s²] the estimate τ̂_c used; "
            f"{what or 'signals'} lack {' and '.join(missing)} (give ObserverSignals.position "
            "and .acceleration, or position= and acceleration= when streaming)"
        )
    return position, acceleration


def _window_samples(window: Any, dt: float) -> int:
    try:
        seconds = float(window)
    except (TypeError, ValueError):
        seconds = float("nan")
    samples = round(seconds / dt) if np.isfinite(seconds) else 0
    samples += 1 - samples % 2  # odd, centred window
    if samples < 5:
        raise InputValueError(
            f"reference_window must be a time [s] of at least 5 samples (5 dt = {5 * dt:g} s); "
            f"got {window!r}"
        )
    return samples


def _describe_robot(robot: RobotModel) -> dict[str, Any]:
    """Rigid-body description of ``robot``: what its regressor and Θ̂ depend on."""
    model = robot.pinocchio_model
    joints = []
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        kind = joint.shortname()
        placement = model.jointPlacements[jid]
        entry: dict[str, Any] = {
            "name": str(model.names[jid]),
            "type": kind,
            "parent": int(model.parents[jid]),
            "rotation": np.asarray(placement.rotation).tolist(),
            "translation": np.asarray(placement.translation).tolist(),
        }
        if kind == _UNALIGNED:
            entry["axis"] = np.asarray(joint.extract().axis).tolist()
        elif kind not in _REVOLUTE:
            raise ModelError(
                f"cannot save joint {entry['name']!r} of type {kind}; a saved robot may have "
                f"{[*_REVOLUTE, _UNALIGNED]} joints"
            )
        joints.append(entry)
    return {
        "name": robot.name,
        "gravity": robot.gravity_vector.tolist(),
        "joints": joints,
        "standard_parameters": robot.parameter_vector().tolist(),
    }


def _robot_from_description(description: Mapping[str, Any]) -> RobotModel:
    """Inverse of :func:`_describe_robot`."""
    missing = [
        k for k in ("name", "gravity", "joints", "standard_parameters") if k not in description
    ]
    if missing:
        raise ModelError(
            f"a robot description needs keys name, gravity, joints, standard_parameters; "
            f"missing {missing}"
        )
    model = pin.Model()
    model.name = str(description["name"])
    for index, entry in enumerate(description["joints"], start=1):
        try:
            kind = str(entry["type"])
            if kind == _UNALIGNED:
                joint = pin.JointModelRevoluteUnaligned(*np.asarray(entry["axis"], dtype=float))
            elif kind in _REVOLUTE:
                joint = getattr(pin, kind)()
            else:
                raise ModelError(
                    f"joint {index} has type {kind!r}; valid types: {[*_REVOLUTE, _UNALIGNED]}"
                )
            placement = pin.SE3(
                np.asarray(entry["rotation"], dtype=float),
                np.asarray(entry["translation"], dtype=float),
            )
            jid = model.addJoint(int(entry["parent"]), joint, placement, str(entry["name"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelError(
                f"joint {index} of the robot description is invalid ({exc}); it needs name, "
                "type, parent, rotation (3x3), translation (3) and, if unaligned, axis (3)"
            ) from None
        model.appendBodyToJoint(jid, pin.Inertia.Zero(), pin.SE3.Identity())
    gravity = np.asarray(description["gravity"], dtype=float)
    if gravity.shape != (3,):
        raise ModelError(f"gravity must be a 3-vector [m/s²]; got shape {gravity.shape}")
    model.gravity = pin.Motion(gravity, np.zeros(3))
    robot = RobotModel.from_pinocchio(model, name=model.name)
    return robot.with_standard_parameters(description["standard_parameters"])
