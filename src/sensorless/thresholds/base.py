"""Common interface of the threshold families, their file format and the K_I/(s+K_I) filter.

A threshold gives, for every joint and every sample, a lower and an upper
bound; a residual outside its bounds indicates a collision (eq. 3.37/3.39,
4.34, 5.31). Every family is an estimator in the scikit-learn sense:

* hyper-parameters are set in ``__init__`` and checked in :meth:`Threshold.fit`;
* :meth:`Threshold.fit` takes one or more collision-free
  :class:`~sensorless.signals.ObserverSignals` runs, learns attributes whose
  names end with an underscore (``beta_``, ``alpha_``, ``gamma_``, ...) and
  returns ``self``; before it, every other method raises
  :class:`~sensorless.exceptions.NotFittedError`;
* :meth:`Threshold.bounds` applies the fitted threshold to a whole run and
  :meth:`Threshold.detect` returns its collision events,
  :meth:`Threshold.initial_state`, :meth:`Threshold.step` (one sample) and
  :meth:`Threshold.process` (a chunk) apply it to a live stream; all of them
  run the same code, so a stream cut into chunks gives the bounds of the
  whole run;
* :meth:`Threshold.save` writes a readable YAML file and
  :func:`load_threshold` reads it back.

Fitting also records what the threshold is valid for: the robot name, the
number of joints, the signal kind (``"motor"``, ``"joint"`` or
``"acceleration"``) and the observer gain K_I. Applying it to signals that
differ in any of them is an error.

Joints are numbered from 1, as in :class:`~sensorless.signals.Event`. The
hyper-parameter ``joints`` selects the monitored joints; the bounds of the
others are ``-inf`` and ``+inf``.

The observer filter
-------------------
Every filtered signal of the observer, and the filtered friction term of the
velocity-based threshold, is K_I/(s+K_I) discretised with a zero-order hold
on the input:

    y[0] = zi,    y[k+1] = a y[k] + (1 - a) x[k],    a = exp(-K_I dt).

:func:`first_order` applies it to an array (with :func:`scipy.signal.lfilter`)
and :func:`first_order_step` to one sample; the state is the next output,
so ``zi`` defaults to ``x[0]`` (the input held since forever).

Writing a new family
--------------------
Subclass :class:`Threshold`, set the class attribute ``name`` (the class is
then registered in :data:`METHODS`), store the hyper-parameters in
``__init__`` and implement ``_fit(runs, keep, margin)``,
``_run(state, inputs)`` and ``_attribute_names()``; override
``_initial_zi(inputs, dt)`` when the bounds have a filter state.

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
import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any, ClassVar, NamedTuple

import numpy as np
import yaml
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from .._validation import FloatArray, as_joint_array, check_dt, check_finite
from ..exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    NotFittedError,
    UnknownNameError,
)
from ..signals import Event, ObserverSignals

__all__ = [
    "METHODS",
    "Threshold",
    "ThresholdInputs",
    "ThresholdState",
    "first_order",
    "first_order_step",
    "load_threshold",
]

BoolArray = NDArray[np.bool_]

METHODS: dict[str, type[Threshold]] = {}
"""Threshold families by name (``"constant"``, ``"time_variant"``, ``"velocity"``, ...)."""

ROUNDING_GUARD = 1e-12
"""Relative widening of fitted bounds [-] so that rounding never puts fit data outside them.

A bound is computed as ``centre + alpha`` while ``alpha`` was fitted as
``max |r - centre|``; the two roundings can differ by an ulp. Each family
widens its constant part by ``ROUNDING_GUARD * max_t (|r| + |centre|)``.
"""

_SERIES = ("model_torque", "friction", "sign", "velocity")
_FILE_KEYS = ("method", "robot", "kind", "n_dof", "gain", "dt", "params", "attributes")
_FILE_HEADER = (
    "# sensorless fitted threshold; read it with sensorless.thresholds.load_threshold(path)\n"
)


# --------------------------------------------------------------------------- filter


def _filter_coefficients(gain: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    if not np.all(np.isfinite(gain)) or np.any(gain <= 0.0):
        raise InputValueError(
            f"gain K_I must be positive and finite [1/s]; got {np.asarray(gain).tolist()}"
        )
    step = gain * check_dt(dt)
    return np.exp(-step), -np.expm1(-step)


def _broadcast(value: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    try:
        return np.broadcast_to(np.asarray(value, dtype=np.float64), shape)
    except ValueError:
        raise DimensionError(
            f"{name} must be a scalar or broadcast to shape {shape}; got shape {np.shape(value)}"
        ) from None


def first_order(
    x: ArrayLike, gain: ArrayLike, dt: float, zi: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Filter ``x`` by K_I/(s+K_I), discretised with a zero-order hold (the observer's filter).

    ``y[0] = zi`` and ``y[k+1] = a y[k] + (1 - a) x[k]`` with ``a = exp(-K_I dt)``.

    Parameters
    ----------
    x : array-like of shape (n_samples, ...)
        Input, time along axis 0 (any unit; the output has the same).
    gain : float or array-like broadcastable to ``x.shape[1:]``
        K_I of each column [1/s].
    dt : float
        Sample period [s].
    zi : array-like broadcastable to ``x.shape[1:]``, optional
        Filter state before ``x[0]``, which is also ``y[0]``. By default
        ``x[0]``: the input held since forever, no start-up transient.

    Returns
    -------
    y : ndarray of shape (n_samples, ...)
        Filtered signal.
    zf : ndarray of shape ``x.shape[1:]``
        State after the last sample, the ``zi`` of the next chunk.

    Examples
    --------
    >>> y, zf = first_order([0.0, 1.0, 1.0, 1.0], gain=10.0, dt=0.1)
    >>> np.round(y, 4)
    array([0.    , 0.    , 0.6321, 0.8647])
    >>> y2, _ = first_order([1.0, 1.0], gain=10.0, dt=0.1, zi=y[2])
    >>> bool(np.allclose(y2, y[2:]))
    True
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 0:
        raise DimensionError("x must have a time axis: shape (n_samples, ...); got a scalar")
    trailing = arr.shape[1:]
    if zi is None:
        if arr.shape[0] == 0:
            raise DimensionError("x has no samples; pass zi to filter an empty chunk")
        zi = arr[0]
    state = _broadcast(zi, trailing, "zi").reshape(-1)
    pole, weight = _filter_coefficients(_broadcast(gain, trailing, "gain").reshape(-1), dt)
    flat = arr.reshape(arr.shape[0], -1)
    y = np.empty_like(flat)
    zf = state.copy()
    if arr.shape[0] > 0:
        # Columns with equal gain share one lfilter call; usually K_I is the same for all.
        for value in np.unique(pole):
            cols = pole == value
            b = [0.0, float(weight[cols][0])]
            y[:, cols], z = signal.lfilter(
                b, [1.0, -float(value)], flat[:, cols], axis=0, zi=state[cols][None, :]
            )
            zf[cols] = z[0]
    return y.reshape(arr.shape), zf.reshape(trailing)


def first_order_step(
    x: ArrayLike, gain: ArrayLike, dt: float, z: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """One sample of :func:`first_order`.

    Parameters
    ----------
    x : array-like
        Input at this sample.
    gain : float or array-like broadcastable to the shape of ``x``
        K_I [1/s].
    dt : float
        Sample period [s].
    z : array-like of the shape of ``x``
        State (the output at this sample), e.g. ``x`` at the first sample.

    Returns
    -------
    y : ndarray
        Output at this sample (equal to ``z``).
    z_next : ndarray
        State for the next sample.

    Examples
    --------
    >>> y, z = first_order_step(1.0, 10.0, 0.1, 0.0)
    >>> float(y), round(float(z), 4)
    (0.0, 0.6321)
    """
    arr = np.asarray(x, dtype=np.float64)
    y = _broadcast(z, arr.shape, "z").copy()
    pole, weight = _filter_coefficients(_broadcast(gain, arr.shape, "gain"), dt)
    return y, weight * arr + pole * y


# --------------------------------------------------------------------------- checks


def _check_margin(margin: Any, n_dof: int) -> FloatArray:
    try:
        value = np.asarray(margin, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(
            f"margin must be a number or a sequence of {n_dof} numbers [N m]; got {margin!r}"
        ) from None
    if value.ndim == 0:
        value = np.full(n_dof, float(value))
    elif value.shape != (n_dof,):
        raise DimensionError(
            f"margin must be a scalar or have shape ({n_dof},) for {n_dof} joints; "
            f"got shape {value.shape}"
        )
    if not np.all(np.isfinite(value)) or np.any(value < 0.0):
        raise InputValueError(f"margin must be finite and >= 0 [N m]; got {margin!r}")
    return value


def check_joints(joints: Any, n_dof: int) -> tuple[int, ...]:
    """Return the monitored joints (1-based, sorted) after checking them; None means all."""
    if joints is None:
        return tuple(range(1, n_dof + 1))
    message = (
        f"joints must be distinct joint numbers between 1 and {n_dof} (1-based), "
        f"or None for all; got {joints!r}"
    )
    try:
        values = [operator.index(j) for j in joints]
    except TypeError:
        raise InputValueError(message) from None
    if not values or len(set(values)) != len(values) or not all(1 <= j <= n_dof for j in values):
        raise InputValueError(message)
    return tuple(sorted(values))


def check_seconds(value: Any, name: str) -> float:
    """Return a non-negative, finite duration [s]."""
    try:
        seconds = float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be a number of seconds >= 0; got {value!r}") from None
    if not np.isfinite(seconds) or seconds < 0.0:
        raise InputValueError(f"{name} must be a finite number of seconds >= 0; got {value!r}")
    return seconds


def _check_increasing(t: FloatArray, what: str) -> None:
    check_finite(t, f"t of {what}")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        raise InputValueError(
            f"t of {what} must be strictly increasing; t[{k}] = {t[k]!r} s follows "
            f"t[{k - 1}] = {t[k - 1]!r} s"
        )


def regular_period(t: FloatArray, what: str, rtol: float = 1e-6) -> float:
    """Sample period [s] of regular time stamps; irregular ones are an error, never resampled."""
    if t.shape[0] < 2:
        raise InputValueError(
            f"{what} has {t.shape[0]} sample(s); at least 2 are needed to know the sample period"
        )
    step = np.diff(t)
    median = float(np.median(step))
    tolerance = rtol * median + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    bad = np.flatnonzero(np.abs(step - median) > tolerance)
    if bad.size:
        k = int(bad[0])
        raise InputValueError(
            f"t of {what} is not regularly sampled: t[{k + 1}] - t[{k}] = {step[k]:.9g} s, "
            f"the median step is {median:.9g} s (rtol {rtol:g}); resample the log explicitly "
            "with sensorless.io.resample"
        )
    return median


def _as_runs(signals: Any) -> list[ObserverSignals]:
    runs = [signals] if isinstance(signals, ObserverSignals) else signals
    if not isinstance(runs, Sequence) or not all(isinstance(r, ObserverSignals) for r in runs):
        raise InputTypeError(
            "fit takes an ObserverSignals or a sequence of ObserverSignals (collision-free "
            f"runs); got {type(signals).__name__}"
        )
    if not runs:
        raise InputValueError("fit needs at least one collision-free run; got an empty sequence")
    return list(runs)


def _check_runs(runs: list[ObserverSignals]) -> None:
    first = runs[0]
    for i, run in enumerate(runs):
        what = f"fit run {i}"
        if run.n_dof != first.n_dof or run.robot != first.robot:
            raise DimensionError(
                f"all fit runs must come from one robot; run 0 is {first.robot!r} "
                f"({first.n_dof} joints), {what} is {run.robot!r} ({run.n_dof} joints)"
            )
        if run.kind != first.kind:
            raise InputValueError(
                f"all fit runs must be of one signal kind; run 0 is {first.kind!r}, "
                f"{what} is {run.kind!r}"
            )
        if not np.allclose(run.gain, first.gain, rtol=1e-9, atol=0.0, equal_nan=True):
            raise InputValueError(
                f"all fit runs must use one observer gain K_I; run 0 has {first.gain.tolist()}, "
                f"{what} has {run.gain.tolist()} [1/s]"
            )
        _check_increasing(run.t, what)
        for name in ("residual", *_SERIES):
            check_finite(getattr(run, name), f"{name} of {what}")


def stack(runs: Sequence[ObserverSignals], keep: Sequence[BoolArray], name: str) -> FloatArray:
    """Rows of series ``name`` of all runs where ``keep`` is true, stacked along axis 0."""
    return np.concatenate([getattr(run, name)[k] for run, k in zip(runs, keep, strict=True)])


def rounding_guard(*terms: FloatArray) -> FloatArray:
    """Per-joint widening ``ROUNDING_GUARD * max_t sum |terms|`` [N m]; see ROUNDING_GUARD."""
    total = np.sum([np.abs(term) for term in terms], axis=0)
    return ROUNDING_GUARD * np.max(total, axis=0)


def _library_version() -> str:
    try:
        return importlib_metadata.version("sensorless")
    except importlib_metadata.PackageNotFoundError:
        return "unknown"


def _to_builtin(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple | list):
        return [_to_builtin(v) for v in value]
    return value


# --------------------------------------------------------------------------- state


class ThresholdInputs(NamedTuple):
    """Per-sample signals a threshold needs besides the residual, each (n_samples, n_dof).

    ``position`` and ``acceleration`` are only used by families that need
    them (model-based thresholds) and may be None otherwise.
    """

    model_torque: FloatArray
    friction: FloatArray
    sign: FloatArray
    velocity: FloatArray
    position: FloatArray | None = None
    acceleration: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class ThresholdState:
    """Streaming state of a threshold; obtain it from :meth:`Threshold.initial_state`.

    Attributes
    ----------
    dt : float
        Sample period of the stream [s].
    zi : ndarray
        Filter state of the family (the next output of its K_I/(s+K_I)
        filter, shape (n_dof,)); empty for families without memory.
    """

    dt: float
    zi: FloatArray


def _check_state(state: Any) -> None:
    if not isinstance(state, ThresholdState):
        raise InputTypeError(
            f"state must be a ThresholdState from initial_state, step or process; "
            f"got {type(state).__name__}"
        )


# --------------------------------------------------------------------------- base


class Threshold(abc.ABC):
    """Base of the threshold families: fit on collision-free runs, give lower/upper bounds.

    Subclasses define ``name``, their hyper-parameters in ``__init__`` and the
    fitted attributes. Every family has the hyper-parameters ``margin``
    (absolute widening of the bounds [N m], scalar or one per joint, >= 0),
    ``joints`` (1-based monitored joints, None for all) and ``transient``
    (time [s] skipped at the start of every fit run, e.g. a few 1/K_I while
    the observer settles).

    Attributes (after :meth:`fit`)
    ------------------------------
    robot_ : str
        Robot name of the fit runs.
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

    margin: Any
    joints: Any
    transient: Any

    robot_: str
    kind_: str
    n_dof_: int
    gain_: FloatArray
    dt_: float

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
    def _run(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        """Bounds of all joints for checked inputs of shape (n_samples, n_dof)."""

    def _initial_zi(self, inputs: ThresholdInputs, dt: float) -> FloatArray:
        """Filter state before the first sample ``inputs[k][0]``; none by default."""
        return np.zeros(0)

    def _period(self, t: FloatArray, what: str) -> float:
        """Sample period [s] used by :meth:`bounds`; families that filter need a regular one."""
        return float(np.median(np.diff(t))) if t.shape[0] > 1 else float(self.dt_)

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

    def fit(self, signals: ObserverSignals | Sequence[ObserverSignals]) -> Threshold:
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
        runs = _as_runs(signals)
        _check_runs(runs)
        first = runs[0]
        margin = _check_margin(self.margin, first.n_dof)
        check_joints(self.joints, first.n_dof)
        transient = check_seconds(self.transient, "transient")
        keep = [run.t - run.t[0] >= transient for run in runs]
        if not any(k.any() for k in keep):
            raise InputValueError(
                f"no fit sample is left after skipping transient = {transient} s at the start "
                "of every run"
            )
        self._fit(runs, keep, margin)
        steps = np.concatenate([np.diff(run.t) for run in runs])
        self.robot_ = first.robot
        self.kind_ = first.kind
        self.n_dof_ = first.n_dof
        self.gain_ = first.gain.copy()
        self.dt_ = float(np.median(steps)) if steps.size else float("nan")
        return self

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

    # ----------------------------------------------------------------- apply

    def check_signals(self, signals: ObserverSignals) -> None:
        """Raise unless ``signals`` come from the robot, signal kind and gain the threshold fits.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        DimensionError
            Another number of joints.
        InputValueError
            Another robot name, signal kind or observer gain.
        """
        self._check_fitted()
        if not isinstance(signals, ObserverSignals):
            raise InputTypeError(
                f"signals must be an ObserverSignals; got {type(signals).__name__}"
            )
        if signals.n_dof != self.n_dof_ or signals.robot != self.robot_:
            error = DimensionError if signals.n_dof != self.n_dof_ else InputValueError
            raise error(
                f"thresholds fitted for {self.robot_ or '<unnamed>'} ({self.n_dof_} joints); "
                f"signals come from {signals.robot or '<unnamed>'} ({signals.n_dof} joints)"
            )
        if signals.kind != self.kind_:
            raise InputValueError(
                f"thresholds fitted on {self.kind_!r} signals; these signals are "
                f"{signals.kind!r} (valid: the kind used for fit)"
            )
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
        _check_increasing(signals.t, "signals")
        return self._period(signals.t, "signals")

    def bounds(self, signals: ObserverSignals) -> tuple[FloatArray, FloatArray]:
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
        inputs = self._inputs(
            signals.model_torque,
            signals.friction,
            signals.sign,
            signals.velocity,
            signals.position,
            signals.acceleration,
        )
        state = ThresholdState(dt, self._initial_zi(inputs, dt))
        lower, upper, _ = self._apply(state, inputs)
        return lower, upper

    def detect(
        self, signals: ObserverSignals, *, min_duration: float = 0.0, hold: float = 0.0
    ) -> list[Event]:
        """Collision events of a recorded run.

        A shortcut for ``Detector(self, min_duration=..., hold=...).detect(signals)``;
        see :class:`sensorless.detection.Detector` for the grouping rules.
        """
        from ..detection import Detector  # detection builds on this module

        return Detector(self, min_duration=min_duration, hold=hold).detect(signals)

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

        Returns
        -------
        ThresholdState
        """
        self._check_fitted()
        period = float(self.dt_) if dt is None else check_dt(dt)
        inputs = self._inputs(model_torque, friction, sign, velocity, position, acceleration)
        if inputs.model_torque.shape[0] != 1:
            raise DimensionError(
                f"initial_state takes one sample of shape ({self.n_dof_},); "
                f"got {inputs.model_torque.shape[0]} samples"
            )
        return ThresholdState(period, self._initial_zi(inputs, period))

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
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        """Bounds at one sample of a stream.

        Parameters
        ----------
        state : ThresholdState
            From :meth:`initial_state` or the previous call.
        model_torque, friction, sign, velocity : array-like of shape (n_dof,)
            This sample's h [N m], filtered friction [N m], filtered sign [-], q̇ [rad/s].
        position, acceleration : array-like of shape (n_dof,), optional
            q [rad] and q̈ [rad/s²], for families that use them.

        Returns
        -------
        lower, upper : ndarray of shape (n_dof,)
            Bounds [N m].
        state : ThresholdState
            State for the next sample.
        """
        self._check_fitted()
        for name, value in zip(_SERIES, (model_torque, friction, sign, velocity), strict=True):
            if np.ndim(value) != 1:
                raise DimensionError(
                    f"step takes one sample: {name} of shape ({self.n_dof_},); got shape "
                    f"{np.shape(value)}; use process for a chunk"
                )
        _check_state(state)
        inputs = self._inputs(model_torque, friction, sign, velocity, position, acceleration)
        return self._step_checked(state, inputs)

    def _step_checked(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        """The core of :meth:`step`: bounds of one checked sample, inputs of shape (1, n_dof)."""
        lower, upper, new_state = self._apply(state, inputs)
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
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
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
        self._check_fitted()
        _check_state(state)
        inputs = self._inputs(model_torque, friction, sign, velocity, position, acceleration)
        return self._apply(state, inputs)

    def _inputs(
        self,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        position: ArrayLike | None,
        acceleration: ArrayLike | None,
    ) -> ThresholdInputs:
        values: dict[str, ArrayLike | None] = {
            "model_torque": model_torque,
            "friction": friction,
            "sign": sign,
            "velocity": velocity,
            "position": position,
            "acceleration": acceleration,
        }
        arrays: dict[str, FloatArray | None] = {}
        n_samples = None
        for name, value in values.items():
            if value is None:
                arrays[name] = None
                continue
            arr, _ = as_joint_array(value, self.n_dof_, name)
            if n_samples is not None and arr.shape[0] != n_samples:
                raise DimensionError(
                    f"{name} has {arr.shape[0]} samples; model_torque has {n_samples}"
                )
            n_samples = arr.shape[0]
            arrays[name] = arr
        return ThresholdInputs(**arrays)  # type: ignore[arg-type]

    def _apply(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        lower, upper, new_state = self._run(state, inputs)
        joints = self.monitored_joints_
        if len(joints) < self.n_dof_:
            monitored = np.zeros(self.n_dof_, dtype=bool)
            monitored[np.asarray(joints) - 1] = True
            lower[:, ~monitored] = -np.inf
            upper[:, ~monitored] = np.inf
        return lower, upper, new_state

    # ----------------------------------------------------------------- files

    def to_dict(self) -> dict[str, Any]:
        """The fitted threshold as plain Python values (what :meth:`save` writes)."""
        self._check_fitted()
        return {
            "method": self.name,
            "library_version": _library_version(),
            "robot": self.robot_,
            "kind": self.kind_,
            "n_dof": int(self.n_dof_),
            "gain": self.gain_.tolist(),
            "dt": float(self.dt_),
            "params": {k: _to_builtin(v) for k, v in self.get_params().items()},
            "attributes": {
                name: np.asarray(getattr(self, name)).tolist() for name in self._attribute_names()
            },
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Threshold:
        """Rebuild a fitted threshold from :meth:`to_dict` output; dispatches on ``method``."""
        if not isinstance(data, Mapping):
            raise InputValueError(
                f"a threshold description must be a mapping; got {type(data).__name__}"
            )
        missing = [key for key in _FILE_KEYS if key not in data]
        if missing:
            raise InputValueError(
                f"threshold description lacks {missing}; expected keys {list(_FILE_KEYS)}"
            )
        method = data["method"]
        target = METHODS.get(method)
        if target is None:
            raise UnknownNameError(
                f"unknown threshold method {method!r}; valid methods: {sorted(METHODS)}"
            )
        if cls is not Threshold and not issubclass(target, cls):
            raise InputValueError(f"the description holds a {method!r} threshold, not {cls.name!r}")
        threshold = target(**dict(data["params"]))
        threshold.robot_ = str(data["robot"])
        threshold.kind_ = str(data["kind"])
        threshold.n_dof_ = int(data["n_dof"])
        threshold.gain_ = np.asarray(data["gain"], dtype=np.float64)
        threshold.dt_ = float(data["dt"])
        if threshold.gain_.shape != (threshold.n_dof_,):
            raise DimensionError(
                f"gain must have {threshold.n_dof_} values; got shape {threshold.gain_.shape}"
            )
        attributes = dict(data["attributes"])
        expected = threshold._attribute_names()
        if sorted(attributes) != sorted(expected):
            raise InputValueError(
                f"a {method!r} threshold has attributes {list(expected)}; "
                f"the description has {sorted(attributes)}"
            )
        for name in expected:
            dtype = np.int64 if name in threshold._integer_attributes else np.float64
            try:
                value = np.asarray(attributes[name], dtype=dtype)
            except (TypeError, ValueError):
                raise InputValueError(
                    f"attribute {name} must be a (nested) list of numbers; got {attributes[name]!r}"
                ) from None
            setattr(threshold, name, value)
        threshold._check_attributes()
        return threshold

    def save(self, path: str | Path) -> Path:
        """Write the fitted threshold to a readable YAML file and return its path.

        The file holds the method name, the library version, the robot name,
        n_dof, the signal kind, the observer gain, the sample period, the
        hyper-parameters and the fitted attributes as (nested) lists.
        """
        text = yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None, width=100)
        out = Path(path)
        out.write_text(_FILE_HEADER + text, encoding="utf-8")
        return out


def load_threshold(path: str | Path) -> Threshold:
    """Read a threshold written by :meth:`Threshold.save`.

    Raises
    ------
    FileNotFoundError
        No such file.
    InputValueError
        Not a threshold file.
    UnknownNameError
        A method that is not in :data:`METHODS`.
    """
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputValueError(f"{path} is not a YAML threshold file: {exc}") from None
    return Threshold.from_dict(data)
