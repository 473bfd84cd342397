"""The skeleton every threshold family shares: fit on collision-free runs, then give bounds.

A threshold gives, for every joint and every sample, a lower and an upper
bound; a residual outside its bounds indicates a collision (eq. 3.37/3.39,
4.34, 5.31). Every family is an estimator in the scikit-learn sense:

* hyper-parameters are set in ``__init__`` and checked in :meth:`Threshold.fit`;
* :meth:`Threshold.fit` takes one or more collision-free
  :class:`~sensorless.signals.ObserverSignals` runs, learns attributes whose
  names end with an underscore (``beta_``, ``alpha_``, ``gamma_``, ...) and
  returns ``self``; before it, every other method raises
  :class:`~sensorless.exceptions.NotFittedError`;
* :meth:`Threshold.bounds` applies the fitted threshold to a whole run,
  :meth:`Threshold.initial_state`, :meth:`Threshold.step` (one sample) and
  :meth:`Threshold.process` (a chunk) apply it to a live stream; all of them
  run the same code, so a stream cut into chunks gives the bounds of the
  whole run;
* :meth:`Threshold.save` writes a readable YAML file and
  :func:`load_threshold` reads it back (:mod:`.files`).

A threshold gives bounds and knows nothing of events: collision events are
the business of :class:`sensorless.detection.Detector`, which takes a fitted
threshold (``Detector(threshold, min_duration=..., hold=...).detect(signals)``).

Fitting also records what the threshold is valid for: the robot name, the
number of joints, the signal kind (``"motor"``, ``"joint"`` or
``"acceleration"``) and the observer gain K_I. Applying it to signals that
differ in any of them is an error.

Joints are numbered from 1, as in :class:`~sensorless.signals.Event`. The
hyper-parameter ``joints`` selects the monitored joints; the bounds of the
others are ``-inf`` and ``+inf``.

The filter K_I/(s+K_I) is in :mod:`.filtering`, the checks in :mod:`.checks`,
the stream types in :mod:`.state` and the file format in :mod:`.files`.

Writing a new family
--------------------
Subclass :class:`Threshold`, set the class attribute ``name`` (the class is
then registered in :data:`METHODS`), store the hyper-parameters in
``__init__`` and implement ``_fit(runs, keep, margin)``,
``_run(state, inputs)`` and ``_attribute_names()``; override
``_initial_state_checked(inputs, dt, kind)`` when the bounds have a filter state.

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> from sensorless.thresholds import ConstantThreshold
>>> t = np.arange(5) * 1e-3
>>> r = np.array([[0.1, -0.2], [0.3, 0.1], [-0.4, 0.0], [0.2, 0.2], [0.0, -0.1]])
>>> zeros = np.zeros_like(r)
>>> run = ObserverSignals(t, r, zeros, zeros, zeros, zeros, gain=20.0, robot="demo")
>>> threshold = ConstantThreshold(margin=0.05).fit(run)
>>> threshold.beta_
array([0.45, 0.25])
>>> lower, upper = threshold.bounds(run)
>>> upper[0]
array([0.45, 0.25])
"""

from __future__ import annotations

import abc
import inspect
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt, check_duration, check_increasing, per_joint
from ..exceptions import DimensionError, InputTypeError, InputValueError, NotFittedError
from ..signals import ObserverSignals
from .checks import (
    as_inputs,
    as_runs,
    check_inputs_finite,
    check_joints,
    check_runs,
    check_state,
    other_model,
    parameters_differ,
    robot_mismatch,
)
from .files import METHODS, load_threshold, save_threshold, threshold_from_dict, threshold_to_dict
from .filtering import first_order, first_order_step
from .fitting import BoolArray
from .state import ThresholdInputs, ThresholdState

if TYPE_CHECKING:
    from typing_extensions import Self

__all__ = [
    "METHODS",
    "Threshold",
    "ThresholdInputs",
    "ThresholdState",
    "first_order",
    "first_order_step",
    "load_threshold",
]

Bounds = tuple[FloatArray, FloatArray]
"""Lower and upper bounds [N m]."""
StreamBounds = tuple[FloatArray, FloatArray, ThresholdState]
"""Lower and upper bounds [N m] and the state after them."""


class Threshold(abc.ABC):
    """Base of the threshold families: fit on collision-free runs, give lower/upper bounds.

    Subclasses define ``name``, their own hyper-parameters in ``__init__``
    (which passes the common ones to this one) and the fitted attributes.

    Parameters
    ----------
    margin : float or array-like of shape (n_dof,)
        Absolute widening of the bounds [N m], >= 0 (what it widens is
        family-specific).
    joints : sequence of int, optional
        Monitored joints (1-based); None for all.
    transient : float
        Time skipped at the start of every fit run [s], e.g. a few 1/K_I
        while the observer settles.

    Attributes (after :meth:`fit`)
    ------------------------------
    robot_ : str
        Robot name of the fit runs.
    fingerprint_ : str
        Fingerprint of the fit runs' nominal model (:mod:`sensorless.robots.fingerprint`);
        empty when unknown (signals built by hand, files saved without it).
    kind_ : str
        Signal kind of the fit runs (``"motor"``, ``"joint"``, ``"acceleration"``).
    n_dof_ : int
        Number of joints.
    gain_ : ndarray of shape (n_dof,)
        Observer gain K_I of the fit runs [1/s].
    dt_ : float
        Median sample period of the fit runs [s], the default for streaming.
    """

    name: ClassVar[str] = ""
    _integer_attributes: ClassVar[tuple[str, ...]] = ()
    _state_type: ClassVar[type[ThresholdState]] = ThresholdState

    margin: Any
    joints: Any
    transient: Any

    robot_: str
    fingerprint_: str = ""
    kind_: str
    n_dof_: int
    gain_: FloatArray
    dt_: float

    def __init__(self, margin: Any = 0.0, *, joints: Any = None, transient: float = 0.0) -> None:
        self.margin = margin
        self.joints = joints
        self.transient = transient

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        name = cls.__dict__.get("name")
        if name:
            METHODS[name] = cls

    # ----------------------------------------------------------------- parameters

    @classmethod
    def _param_names(cls) -> list[str]:
        parameters = inspect.signature(cls.__init__).parameters.values()
        return [p.name for p in parameters if p.name != "self"]

    def get_params(self) -> dict[str, Any]:
        """Hyper-parameters as given to ``__init__``."""
        return {name: getattr(self, name) for name in self._param_names()}

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({params})"

    # ----------------------------------------------------------------- subclass hooks

    @abc.abstractmethod
    def _attribute_names(self) -> tuple[str, ...]:
        """Names of the fitted attributes written to a file (besides the common ones)."""

    @abc.abstractmethod
    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        """Learn the attributes from checked runs; ``keep`` marks samples after the transient."""

    @abc.abstractmethod
    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        """Bounds of all joints for checked inputs of shape (n_samples, n_dof)."""

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        """State before the first sample of checked ``inputs``; no filter state by default.

        ``kind`` is the residual of the stream where the family bounds more
        than one (None: not given).
        """
        return ThresholdState(dt, np.zeros(0))

    def _period(self, t: FloatArray, what: str) -> float:
        """Sample period [s] used by :meth:`bounds`; families that filter need a regular one."""
        return float(np.median(np.diff(t))) if t.shape[0] > 1 else float(self.dt_)

    def _check_kind(self, kind: str | None) -> None:
        """Raise unless the threshold bounds residuals of signal kind ``kind``."""
        if kind != self.kind_:
            raise InputValueError(
                f"thresholds fitted on {self.kind_!r} signals; these signals are "
                f"{kind!r} (valid: the kind used for fit)"
            )

    def _check_attributes(self) -> None:
        """Check the shapes of attributes read from a file."""
        for name in self._attribute_names():
            value = getattr(self, name)
            if value.shape[-1:] != (self.n_dof_,):
                raise DimensionError(
                    f"attribute {name} must have one value per joint ({self.n_dof_}); "
                    f"got shape {value.shape}"
                )

    # ----------------------------------------------------------------- fit

    def fit(self, signals: ObserverSignals | Sequence[ObserverSignals]) -> Self:
        """Fit the threshold on collision-free runs.

        Parameters
        ----------
        signals : ObserverSignals or sequence of ObserverSignals
            Collision-free runs of one robot, signal kind and observer gain;
            their samples are pooled.

        Returns
        -------
        self
        """
        runs = as_runs(signals)
        check_runs(runs)
        return self._fit_checked(runs, runs[0].kind)

    def _fit_checked(self, runs: list[ObserverSignals], kind: str) -> Self:
        """What every fit does with checked runs: hyper-parameters, transient, common attributes.

        ``kind`` becomes ``kind_``; the runs are those :meth:`_fit` expects.
        """
        first = runs[0]
        margin = per_joint(self.margin, first.n_dof, "margin", "N m", "nonnegative")
        check_joints(self.joints, first.n_dof)
        transient = check_duration(self.transient, "transient")
        keep = [run.t - run.t[0] >= transient for run in runs]
        if not any(k.any() for k in keep):
            raise InputValueError(
                f"no fit sample is left after skipping transient = {transient} s at the start "
                "of every run"
            )
        self._fit(runs, keep, margin)
        steps = np.concatenate([np.diff(run.t) for run in runs])
        self.robot_ = first.robot
        self.fingerprint_ = first.fingerprint
        self.kind_ = kind
        self.n_dof_ = first.n_dof
        self.gain_ = first.gain.copy()
        self.dt_ = float(np.median(steps)) if steps.size else float("nan")
        return self

    def model_fingerprint(self, kind: str) -> str:
        """Fingerprint of the nominal model of the fit runs of signal ``kind``."""
        return self.fingerprint_

    def _check_fitted(self) -> None:
        if not hasattr(self, "n_dof_"):
            raise NotFittedError(
                f"this {type(self).__name__} is not fitted yet; call "
                "fit(collision_free_signals) first"
            )

    @property
    def monitored_joints_(self) -> tuple[int, ...]:
        """Monitored joints, 1-based."""
        self._check_fitted()
        return check_joints(self.joints, self.n_dof_)

    # ----------------------------------------------------------------- a recorded run

    def check_signals(self, signals: ObserverSignals) -> None:
        """Raise unless ``signals`` come from the robot, signal kind and gain the threshold fits.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        DimensionError
            Another number of joints.
        ModelMismatchError
            The same number of joints, another robot model (name).
        InputValueError
            Another signal kind or observer gain.
        """
        self._check_fitted()
        if not isinstance(signals, ObserverSignals):
            raise InputTypeError(
                f"signals must be an ObserverSignals; got {type(signals).__name__}"
            )
        fingerprint = self.model_fingerprint(signals.kind)
        if signals.n_dof != self.n_dof_ or other_model(
            signals.robot, signals.fingerprint, self.robot_, fingerprint
        ):
            raise robot_mismatch(
                f"thresholds fitted for {self.robot_ or '<unnamed>'} ({self.n_dof_} joints); "
                f"signals come from {signals.robot or '<unnamed>'} ({signals.n_dof} joints)"
                + parameters_differ(fingerprint, signals.fingerprint),
                self.n_dof_,
                signals.n_dof,
            )
        self._check_kind(signals.kind)
        if not np.allclose(signals.gain, self.gain_, rtol=1e-9, atol=0.0, equal_nan=True):
            raise InputValueError(
                f"thresholds fitted for observer gain K_I = {self.gain_.tolist()} [1/s]; "
                f"signals use K_I = {signals.gain.tolist()}"
            )

    def sample_period(self, signals: ObserverSignals) -> float:
        """Sample period [s] that :meth:`bounds` uses for ``signals``.

        The median step of ``t``, which must increase strictly; families
        that filter (velocity-based) also require it to be regular.
        """
        check_increasing(signals.t, "signals")
        return self._period(signals.t, "signals")

    def bounds(self, signals: ObserverSignals) -> Bounds:
        """Lower and upper bounds of the residual over a whole run.

        Parameters
        ----------
        signals : ObserverSignals
            Run of the robot, signal kind and gain used for :meth:`fit`.

        Returns
        -------
        lower, upper : ndarray of shape (n_samples, n_dof)
            Bounds [N m]; ``-inf``/``+inf`` for joints that are not monitored.
        """
        self.check_signals(signals)
        if signals.n_samples == 0:
            empty = np.zeros((0, self.n_dof_))
            return empty, empty.copy()
        dt = self.sample_period(signals)
        inputs = ThresholdInputs.from_signals(signals)
        check_inputs_finite(inputs)
        return self._bounds_checked(inputs, dt, signals.kind)

    def _bounds_checked(self, inputs: ThresholdInputs, dt: float, kind: str | None) -> Bounds:
        """Bounds of checked inputs, from the state before their first sample."""
        state = self._initial_state_checked(inputs, dt, kind)
        lower, upper, _ = self._process_checked(state, inputs)
        return lower, upper

    # ----------------------------------------------------------------- a stream

    def initial_state(
        self,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
        dt: float | None = None,
        kind: str | None = None,
    ) -> ThresholdState:
        """Streaming state before the first sample, whose inputs are given.

        Parameters
        ----------
        model_torque, friction, sign, velocity : array-like of shape (n_dof,)
            First sample of h [N m], K_I/(s+K_I)·τ̂_fr [N m], K_I/(s+K_I)·sign(q̇) [-]
            and q̇ [rad/s]. Filters start with this sample held since forever.
        position, acceleration : array-like of shape (n_dof,), optional
            q [rad] and q̈ [rad/s²], for families that use them.
        dt : float, optional
            Sample period of the stream [s]; by default ``dt_`` of the fit runs.
        kind : str, optional
            Signal kind of the stream; must be ``kind_`` when given. A family
            that bounds several residuals requires it to pick one.

        Returns
        -------
        ThresholdState
        """
        self._check_fitted()
        period = float(self.dt_) if dt is None else check_dt(dt)
        if kind is not None:
            self._check_kind(kind)
        inputs = as_inputs(
            self.n_dof_, model_torque, friction, sign, velocity, position, acceleration
        )
        if inputs.model_torque.shape[0] != 1:
            raise DimensionError(
                f"initial_state takes one sample of shape ({self.n_dof_},); "
                f"got {inputs.model_torque.shape[0]} samples"
            )
        return self._initial_state_checked(inputs, period, kind)

    def step(
        self,
        state: ThresholdState,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
    ) -> StreamBounds:
        """Bounds at one sample of a stream.

        Parameters
        ----------
        state : ThresholdState
            From :meth:`initial_state` or the previous call.
        model_torque, friction, sign, velocity, position, acceleration : array-like
            This sample of the inputs of :meth:`process`, each of shape (n_dof,).

        Returns
        -------
        lower, upper : ndarray of shape (n_dof,)
            Bounds [N m].
        state : ThresholdState
            State for the next sample.
        """
        values = (model_torque, friction, sign, velocity, position, acceleration)
        return self._step_checked(state, self._stream_inputs(state, values, "step"))

    def _step_checked(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        """The core of :meth:`step`: bounds of one checked sample, inputs of shape (1, n_dof)."""
        lower, upper, new_state = self._process_checked(state, inputs)
        return lower[0], upper[0], new_state

    def process(
        self,
        state: ThresholdState,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
    ) -> StreamBounds:
        """Bounds over a chunk of a stream (the batch form of :meth:`step`).

        Parameters
        ----------
        state : ThresholdState
            State before the chunk.
        model_torque, friction, sign, velocity : array-like of shape (n_samples, n_dof)
            h [N m], filtered friction [N m], filtered sign [-], q̇ [rad/s].
        position, acceleration : array-like of shape (n_samples, n_dof), optional
            q [rad] and q̈ [rad/s²], for families that use them.

        Returns
        -------
        lower, upper : ndarray of shape (n_samples, n_dof)
            Bounds [N m].
        state : ThresholdState
            State after the chunk.
        """
        values = (model_torque, friction, sign, velocity, position, acceleration)
        return self._process_checked(state, self._stream_inputs(state, values, ""))

    def _stream_inputs(
        self, state: ThresholdState, values: tuple[Any, ...], one_sample: str
    ) -> ThresholdInputs:
        """The checks of :meth:`step` and :meth:`process`: fitted, state and inputs."""
        self._check_fitted()
        check_state(state, self._state_type)
        return as_inputs(self.n_dof_, *values, one_sample=one_sample)

    def _process_checked(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        """Bounds of checked inputs; joints that are not monitored get ``-inf``/``+inf``."""
        lower, upper, new_state = self._run(state, inputs)
        if self.joints is None:  # every joint: nothing to mask (checked at fit)
            return lower, upper, new_state
        joints = check_joints(self.joints, self.n_dof_)
        if len(joints) < self.n_dof_:
            monitored = np.zeros(self.n_dof_, dtype=bool)
            monitored[np.asarray(joints) - 1] = True
            lower[:, ~monitored] = -np.inf
            upper[:, ~monitored] = np.inf
        return lower, upper, new_state

    # ----------------------------------------------------------------- files

    def to_dict(self) -> dict[str, Any]:
        """The fitted threshold as plain Python values (what :meth:`save` writes)."""
        return threshold_to_dict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Threshold:
        """Rebuild a fitted threshold from :meth:`to_dict` output; dispatches on ``method``."""
        return threshold_from_dict(data, cls)

    def save(self, path: str | Path) -> Path:
        """Write the fitted threshold to a readable YAML file and return its path.

        The file holds the method name, the library version, the robot name,
        n_dof, the signal kind, the observer gain, the sample period, the
        hyper-parameters and the fitted attributes as (nested) lists.
        """
        return save_threshold(self, path)
