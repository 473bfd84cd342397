"""Separate bands for accelerating and for steady motion, as libfranka sets them per joint.

A model error shows in the residual mostly through the inertial terms, so a
collision-free residual is larger while the arm accelerates than while it
rests or moves at a steady speed. :class:`PhasedThreshold` holds two
thresholds of any family, one per phase, and gives at every sample the
bounds of the phase the arm is in.

The phase
---------
One phase for the whole arm (the inertia couples the joints: one joint's
acceleration moves the others' residuals), decided causally from the
velocity the observer used (``ObserverSignals.velocity``, ``velocity`` of a
stream), with period dt [s]:

1. the acceleration estimate q̈̂_k is the difference (q̇_k − q̇_{k−1})/dt
   through a first-order low-pass of time constant ``smoothing`` τ [s]:
   y_k = a y_{k−1} + (1 − a) u_k, a = exp(−dt/τ) (τ = 0: the raw difference);
2. the arm **enters** the accelerating phase at the first sample where
   |q̈̂_j| > ``level``_j for some joint j [rad/s²];
3. it **stays** in it while some |q̈̂_j| exceeds the exit level
   (1 − ``hysteresis``)·level_j, and returns to steady at the first sample
   at least ``hold`` seconds after the last sample above the exit level.
   Between the exit and the entry levels the phase does not change, so an
   acceleration near one level does not make it chatter.

A stream starts steady, with its first velocity held since forever (q̈̂ = 0),
as the bounds of every family start. The phase is a function of the
velocities alone, computed by one vectorised rule for a chunk and for one
sample, so a stream cut into chunks gives the phases and the bounds of the
whole run.

Fitting
-------
Each fit run's phases are computed from its start, as a stream's; the
samples after ``transient`` are split into maximal stretches of one phase,
and a copy of each part is fitted on the stretches of its phase (a stretch
of one sample is dropped: a fit run needs two). A part's own ``transient``
applies at the start of every stretch; leave it 0 unless a phase change
should be skipped. Both parts see every sample when bounds are computed
(their filters run on), and the phase picks one of them per sample.

Files
-----
A fitted phased threshold saves to the threshold file format with method
``phased``: its params, and its two fitted parts as the attributes
``accelerating_`` and ``steady_`` (each a complete threshold description).
:func:`~sensorless.thresholds.load_threshold` reads it back.

Units SI and radians; arrays have time along axis 0 and shape (n_samples, n_dof).

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> from sensorless.thresholds import ConstantThreshold
>>> t = np.arange(2000) * 1e-3
>>> qd = np.where(t < 1.0, 0.0, np.minimum(t - 1.0, 0.5))[:, None]  # 1 rad/s² for 0.5 s
>>> r = np.where((t >= 1.05) & (t < 1.5), 0.4, 0.05)[:, None] * np.cos(40 * t)[:, None]
>>> z = np.zeros_like(r)
>>> run = ObserverSignals(t, r, z, z, z, qd, gain=20.0, robot="demo")
>>> phased = PhasedThreshold(ConstantThreshold(), ConstantThreshold(), level=0.5).fit(run)
>>> np.round([phased.accelerating_.beta_[0], phased.steady_.beta_[0]], 2)
array([0.4 , 0.05])
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from scipy import signal as sp_signal

from .._validation import FloatArray, check_duration, check_scalar, per_joint
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..signals import ObserverSignals
from ._phased_file import PHASED_METHOD, phased_to_dict, read_phased
from .base import StreamBounds, Threshold
from .checks import check_same_residual
from .files import READERS
from .fitting import BoolArray
from .state import ThresholdInputs, ThresholdState

__all__ = ["PHASED_METHOD", "PhasedState", "PhasedThreshold", "Phases", "check_threshold"]

_TIME_TOLERANCE = 1e-9
"""A quiet time within this of ``hold`` counts as equal to it [s] (the detector's tolerance)."""
_LONG_AGO = 1 << 40
"""Samples since the last one above the exit level, for a stream that saw none."""


class Phases(NamedTuple):
    """The phase of every sample of a run (:meth:`PhasedThreshold.phases`).

    Attributes
    ----------
    accelerating : ndarray of bool, shape (n_samples,)
        True where the accelerating band applies.
    acceleration : ndarray of shape (n_samples, n_dof)
        The estimate q̈̂ the phase was decided on [rad/s²].
    """

    accelerating: BoolArray
    acceleration: FloatArray


@dataclass(frozen=True, eq=False)
class PhasedState(ThresholdState):
    """Streaming state of a :class:`PhasedThreshold`.

    Attributes
    ----------
    dt, zi
        As :class:`~sensorless.thresholds.ThresholdState` (``zi`` empty).
    accelerating, steady : ThresholdState
        States of the two parts.
    velocity : ndarray of shape (n_dof,)
        Velocity at the last sample [rad/s].
    acceleration : ndarray of shape (n_dof,)
        Acceleration estimate q̈̂ at the last sample [rad/s²].
    active : bool
        Whether the last sample was in the accelerating phase.
    quiet : int
        Samples since the last one above the exit level, at the last sample.
    """

    accelerating: ThresholdState
    steady: ThresholdState
    velocity: FloatArray
    acceleration: FloatArray
    active: bool
    quiet: int


class PhasedThreshold(Threshold):
    """One threshold for accelerating motion, one for steady motion (module docstring).

    Parameters
    ----------
    accelerating, steady : Threshold
        Thresholds of any family (copies are fitted by :meth:`fit`; use
        :meth:`from_fitted` for parts fitted already).
    level : float or array-like of shape (n_dof,)
        Entry level of the accelerating phase, |q̈̂_j| > level_j [rad/s²], > 0.
    hysteresis : float
        The phase is left below (1 − hysteresis)·level [-], in [0, 1).
    hold : float
        Time the estimate must stay below the exit level before the phase is
        steady again [s], >= 0.
    smoothing : float
        Time constant of the low-pass on the velocity difference [s], >= 0.
    transient : float
        Time skipped at the start of every fit run [s].

    Attributes (after :meth:`fit`)
    ------------------------------
    accelerating_, steady_ : Threshold
        The fitted parts.
    level_ : ndarray of shape (n_dof,)
        Entry level per joint [rad/s²].
    accelerating_fraction_ : float
        Fraction of the fit samples in the accelerating phase [-] (NaN from
        :meth:`from_fitted` and from files).
    (and the common attributes of :class:`~sensorless.thresholds.base.Threshold`)
    """

    _state_type = PhasedState

    accelerating_: Threshold
    steady_: Threshold
    level_: FloatArray
    accelerating_fraction_: float

    def __init__(
        self,
        accelerating: Threshold,
        steady: Threshold,
        *,
        level: Any = 1.0,
        hysteresis: float = 0.5,
        hold: float = 0.05,
        smoothing: float = 0.01,
        transient: float = 0.0,
    ) -> None:
        super().__init__(transient=transient)
        self.accelerating = accelerating
        self.steady = steady
        self.level = level
        self.hysteresis = hysteresis
        self.hold = hold
        self.smoothing = smoothing

    # ----------------------------------------------------------------- hyper-parameters

    def _check_hyper_parameters(self, n_dof: int) -> None:
        """Check the hyper-parameters and store the levels of ``n_dof`` joints."""
        check_threshold(self.accelerating, "accelerating", "a threshold family")
        check_threshold(self.steady, "steady", "a threshold family")
        self.level_ = per_joint(self.level, n_dof, "level", "rad/s²", "positive")
        hysteresis = check_scalar(self.hysteresis, "hysteresis", "-", "nonnegative")
        if hysteresis >= 1.0:
            raise InputValueError(f"hysteresis must be in [0, 1) [-]; got {self.hysteresis!r}")
        check_duration(self.hold, "hold")
        check_duration(self.smoothing, "smoothing")

    # ----------------------------------------------------------------- fit

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        self._check_hyper_parameters(runs[0].n_dof)
        parts: dict[bool, list[ObserverSignals]] = {True: [], False: []}
        counts = {True: 0, False: 0}
        for run, kept in zip(runs, keep, strict=True):
            dt = float(np.median(np.diff(run.t)))
            active = self._phases_checked(run.velocity, self._start(run.velocity[:1], dt))[0]
            for first, last in _stretches(active, kept):
                phase = bool(active[first])
                counts[phase] += last - first
                if last - first >= 2:
                    parts[phase].append(_rows(run, first, last))
        for phase, name in ((True, "accelerating"), (False, "steady")):
            if not parts[phase]:
                raise InputValueError(
                    f"no stretch of two or more collision-free samples in the {name} phase "
                    f"(entry level {self.level_.tolist()} rad/s², hysteresis {self.hysteresis}, "
                    f"hold {self.hold} s); change the level or fit on runs with both phases"
                )
        self.accelerating_ = copy.deepcopy(self.accelerating).fit(parts[True])
        self.steady_ = copy.deepcopy(self.steady).fit(parts[False])
        self._check_parts()
        self.accelerating_fraction_ = counts[True] / max(counts[True] + counts[False], 1)

    @classmethod
    def from_fitted(
        cls,
        accelerating: Threshold,
        steady: Threshold,
        *,
        level: Any = 1.0,
        hysteresis: float = 0.5,
        hold: float = 0.05,
        smoothing: float = 0.01,
    ) -> PhasedThreshold:
        """Combine two thresholds fitted already (no refit); parameters as for the class.

        Raises
        ------
        NotFittedError
            A part is not fitted.
        DimensionError, ModelMismatchError, InputValueError
            The parts were fitted for other joint counts, robot models, signal
            kinds or observer gains.
        """
        out = cls(
            accelerating, steady, level=level, hysteresis=hysteresis, hold=hold, smoothing=smoothing
        )
        check_threshold(accelerating, "accelerating", "a fitted threshold")
        check_threshold(steady, "steady", "a fitted threshold")
        accelerating._check_fitted()
        steady._check_fitted()
        out._check_hyper_parameters(accelerating.n_dof_)
        out.accelerating_ = copy.deepcopy(accelerating)
        out.steady_ = copy.deepcopy(steady)
        out._check_parts()
        out._copy_common(out.accelerating_)
        out.accelerating_fraction_ = math.nan
        return out

    def _copy_common(self, part: Threshold) -> None:
        for name in ("robot_", "fingerprint_", "kind_", "n_dof_", "gain_", "dt_"):
            setattr(self, name, copy.deepcopy(getattr(part, name)))

    def _check_parts(self) -> None:
        """Raise unless both fitted parts are for one robot model, signal kind and gain."""
        first, second = self.accelerating_, self.steady_
        check_same_residual(first, second, "the accelerating part", "the steady part")
        if self.level_.shape != (first.n_dof_,):
            raise DimensionError(
                f"level has {self.level_.shape[0]} values; the parts have {first.n_dof_} joints"
            )

    # ----------------------------------------------------------------- delegation

    def _attribute_names(self) -> tuple[str, ...]:
        return ()

    @property
    def monitored_joints_(self) -> tuple[int, ...]:
        """Joints either part monitors, 1-based."""
        self._check_fitted()
        return tuple(
            sorted(set(self.accelerating_.monitored_joints_) | set(self.steady_.monitored_joints_))
        )

    def model_fingerprint(self, kind: str) -> str:
        """Fingerprint of the parts' fit runs of signal ``kind``."""
        return self.accelerating_.model_fingerprint(kind)

    def _check_kind(self, kind: str | None) -> None:
        self.accelerating_._check_kind(kind)
        self.steady_._check_kind(kind)

    def _period(self, t: FloatArray, what: str) -> float:
        self.steady_._period(t, what)
        return self.accelerating_._period(t, what)

    # ----------------------------------------------------------------- the phase

    def _start(self, velocity: FloatArray, dt: float) -> PhasedState:
        """Phase state before a first sample of ``velocity`` (1, n_dof), parts left empty."""
        empty = ThresholdState(dt, np.zeros(0))
        zero = np.zeros(velocity.shape[1])
        return PhasedState(
            dt, np.zeros(0), empty, empty, velocity[0].copy(), zero, False, _LONG_AGO
        )

    def _phases_checked(
        self, velocity: FloatArray, state: PhasedState
    ) -> tuple[BoolArray, FloatArray, PhasedState]:
        """Phase and q̈̂ [rad/s²] of every sample of ``velocity`` (n, n_dof) [rad/s] after ``state``.

        Returns the phases, the estimate and ``state`` with the phase's fields
        advanced (the parts' states untouched).
        """
        n = velocity.shape[0]
        if n == 0:
            return np.zeros(0, dtype=bool), np.zeros_like(velocity), state
        dt = state.dt
        previous = np.concatenate([state.velocity[None], velocity[:-1]])
        difference = (velocity - previous) / dt
        smoothing = float(self.smoothing)
        if smoothing > 0.0:
            pole = math.exp(-dt / smoothing)
            estimate, _ = sp_signal.lfilter(
                [1.0 - pole], [1.0, -pole], difference, axis=0, zi=(pole * state.acceleration)[None]
            )
        else:
            estimate = difference
        size = np.abs(estimate)
        enter = (size > self.level_).any(axis=1)
        busy = (size > (1.0 - float(self.hysteresis)) * self.level_).any(axis=1)
        index = np.arange(n)
        last_busy = np.maximum.accumulate(np.where(busy, index, -1 - state.quiet))
        quiet = index - last_busy
        leave = ~busy & (quiet * dt >= float(self.hold) - _TIME_TOLERANCE)
        before = (-1, -2) if state.active else (-2, -1)
        last_enter = np.maximum.accumulate(np.where(enter, index, before[0]))
        last_leave = np.maximum.accumulate(np.where(leave, index, before[1]))
        active = last_enter > last_leave
        advanced = PhasedState(
            dt,
            state.zi,
            state.accelerating,
            state.steady,
            velocity[-1].copy(),
            np.asarray(estimate[-1], dtype=np.float64).copy(),
            bool(active[-1]),
            int(min(quiet[-1], _LONG_AGO)),
        )
        return active, np.asarray(estimate, dtype=np.float64), advanced

    def phases(self, signals: ObserverSignals) -> Phases:
        """The phase of every sample of a run, and the acceleration estimate it came from.

        Parameters
        ----------
        signals : ObserverSignals
            Run of the robot, signal kind and gain the threshold was fitted for.

        Returns
        -------
        Phases
        """
        self.check_signals(signals)
        if signals.n_samples == 0:
            return Phases(np.zeros(0, dtype=bool), np.zeros((0, self.n_dof_)))
        dt = self.sample_period(signals)
        active, estimate, _ = self._phases_checked(
            signals.velocity, self._start(signals.velocity[:1], dt)
        )
        return Phases(active, estimate)

    # ----------------------------------------------------------------- bounds

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        start = self._start(inputs.velocity[:1], dt)
        return PhasedState(
            dt,
            start.zi,
            self.accelerating_._initial_state_checked(inputs, dt, kind),
            self.steady_._initial_state_checked(inputs, dt, kind),
            start.velocity,
            start.acceleration,
            start.active,
            start.quiet,
        )

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        assert isinstance(state, PhasedState)  # checked by the public entry points
        lower_a, upper_a, state_a = self.accelerating_._process_checked(state.accelerating, inputs)
        lower_s, upper_s, state_s = self.steady_._process_checked(state.steady, inputs)
        active, _, advanced = self._phases_checked(inputs.velocity, state)
        pick = active[:, None]
        lower = np.where(pick, lower_a, lower_s)
        upper = np.where(pick, upper_a, upper_s)
        new_state = PhasedState(
            advanced.dt,
            advanced.zi,
            state_a,
            state_s,
            advanced.velocity,
            advanced.acceleration,
            advanced.active,
            advanced.quiet,
        )
        return lower, upper, new_state

    # ----------------------------------------------------------------- files

    def to_dict(self) -> dict[str, Any]:
        """The fitted threshold as plain values: params and the two parts' descriptions."""
        self._check_fitted()
        return phased_to_dict(self)

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], *, source: str = "threshold description"
    ) -> PhasedThreshold:
        """Rebuild a fitted phased threshold from :meth:`to_dict` output.

        Raises
        ------
        FileFormatError
            The description does not follow the format (every problem with the
            path of its field), or its parts disagree with its envelope.
        """
        return _read(data, source)


def _read(data: Mapping[str, Any], source: str, robot: object = None) -> PhasedThreshold:
    """The reader of ``phased`` descriptions (:data:`~sensorless.thresholds.files.READERS`)."""
    threshold = read_phased(data, source, PhasedThreshold.from_fitted)
    assert isinstance(threshold, PhasedThreshold)  # what from_fitted builds
    return threshold


READERS[PHASED_METHOD] = _read


# --------------------------------------------------------------------------- helpers


def check_threshold(value: Any, name: str, what: str) -> Threshold:
    """``value`` if it is a :class:`Threshold`, else :class:`InputTypeError` saying ``what``."""
    if not isinstance(value, Threshold):
        raise InputTypeError(
            f"{name} must be {what} (a sensorless Threshold, e.g. ConstantThreshold); "
            f"got {type(value).__name__}"
        )
    return value


def _stretches(active: BoolArray, kept: BoolArray) -> list[tuple[int, int]]:
    """Maximal [first, last) stretches of kept samples of one phase."""
    change = np.flatnonzero(np.diff(active.astype(np.int8)) != 0) + 1
    gaps = np.flatnonzero(np.diff(kept.astype(np.int8)) != 0) + 1
    edges = np.unique(np.concatenate([[0], change, gaps, [active.size]]))
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges) if bool(kept[a])]


def _rows(run: ObserverSignals, first: int, last: int) -> ObserverSignals:
    """Samples [first, last) of ``run``."""
    rows = slice(first, last)

    def series(values: FloatArray | None) -> FloatArray | None:
        return None if values is None else values[rows]

    return ObserverSignals(
        t=run.t[rows],
        residual=run.residual[rows],
        model_torque=run.model_torque[rows],
        friction=run.friction[rows],
        sign=run.sign[rows],
        velocity=run.velocity[rows],
        gain=run.gain,
        kind=run.kind,
        robot=run.robot,
        position=series(run.position),
        acceleration=series(run.acceleration),
        metadata=run.metadata,
        fingerprint=run.fingerprint,
    )
