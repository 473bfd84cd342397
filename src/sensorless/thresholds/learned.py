"""The learned family: a small CNN predicts the free-motion residual band, ``fit`` sets its level.

A network trained once per robot on simulated, labelled runs
(:mod:`sensorless.learning`, ``sensorless train-detector``) reads the last
51 samples of each joint's h, filtered friction, filtered sign and q̇ (the
inputs every threshold gets, :mod:`._cnn`) and predicts the centre c_j(t) and
the width w_j(t) of the residual r̂_j expected in free motion [N m]. The
collision score of a sample is how many widths the residual lies from the
centre,

    s_j(t) = |r̂_j(t) - c_j(t)| / w_j(t),

and :meth:`LearnedThreshold.fit` sets the decision level on the user's own
collision-free runs as β is set (eq. 5.32): λ_j = the largest s_j seen there.
The bounds

    c_j(t) ∓ (λ_j·w_j(t) + margin_j)

are those of every family, so the :class:`~sensorless.detection.Detector`,
the monitor and the files work unchanged: with margin 0 the residual leaves
them exactly when the score exceeds the level. Why a band and not a score
of r̂ itself: a threshold sees the inputs besides the residual, never the
residual (the detector compares), and a band keeps that boundary. It is the
time-variant band of eq. (5.33) with γ h + ε_fr f replaced by c(t) and α by
λ·w(t): wide where the model torque is large, narrow at rest, where a small
residual is already unusual.

A stream's :meth:`LearnedThreshold.step` runs the network's compiled step
(:mod:`._cnn_kernel`, numba, the optional extra ``fast``) on its rings and
returns the bounds from it; without numba, the numpy step. Both give the
bounds of :meth:`~LearnedThreshold.bounds` to rounding.

Weights (:mod:`._learned_files`): ``weights=None`` takes the weights shipped
for the fit runs' robot, a name takes shipped ones, a path a trained file.
The network counts samples: signals at a sample period outside the band the
weights were trained on (``period_range``, e.g. 0.8..1.25 ms for a 1 kHz
scenario trained at rates of 0.8..1.25 times its own) or, for weights
trained at one period (no band, weights format 1), more than 1 % from it are
refused, as is another observer gain.

Examples
--------
>>> from sensorless.thresholds import LearnedThreshold
>>> LearnedThreshold(margin=0.1)
LearnedThreshold(weights=None, margin=0.1, joints=None, transient=0.0)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..signals import ObserverSignals
from . import _cnn, _cnn_kernel
from ._learned_files import LearnedWeights, load_weights
from .base import StreamBounds, Threshold
from .checks import check_inputs_finite, check_joints, robot_mismatch
from .fitting import BoolArray
from .state import ThresholdInputs, ThresholdState

__all__ = ["LearnedState", "LearnedThreshold"]

_PERIOD_RTOL = 0.01
"""Tolerance on the period of weights trained at one period (no band) [-]."""
_BAND_RTOL = 1e-9
"""Rounding allowed at the edges of a trained band of periods [-]."""


@dataclass(frozen=True, eq=False)
class LearnedState(ThresholdState):
    """Streaming state of a :class:`LearnedThreshold` (``zi`` is empty).

    Attributes
    ----------
    network : CnnState
        The network's rings of past inputs. :meth:`LearnedThreshold.step`
        advances them in place (a copy per sample would cost more than the
        network): step on from the state a step returned; stepping twice from
        one state is refused. ``process`` and ``bounds`` leave their state as
        it was.
    """

    network: _cnn.CnnState


def _base_name(robot: str) -> str:
    """``"puma560"`` of ``"puma560 (nominal)"``: a scenario's perturbed model keeps its robot."""
    return robot.split(" (")[0]


class LearnedThreshold(Threshold):
    """Bounds c(t) ∓ (λ·w(t) + margin) from a trained CNN; λ fitted on collision-free runs.

    Parameters
    ----------
    weights : str or path, optional
        Shipped weights by robot name, or a weights file (``.json`` of
        :func:`~sensorless.thresholds.save_weights`); None: the shipped
        weights of the fit runs' robot.
    margin : float or array-like of shape (n_dof,)
        Added to the half-width λ·w [N m], >= 0.
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`.

    Attributes
    ----------
    level_ : ndarray of shape (n_dof,)
        Decision level λ: the largest score |r̂ - c|/w on the fit runs [-].
    margin_ : ndarray of shape (n_dof,)
        The margin per joint [N m].
    """

    name = "learned"
    _state_type = LearnedState

    level_: FloatArray
    margin_: FloatArray

    def __init__(
        self,
        weights: str | Path | None = None,
        margin: Any = 0.0,
        *,
        joints: Any = None,
        transient: float = 0.0,
    ) -> None:
        super().__init__(margin, joints=joints, transient=transient)
        # a path is kept as text: the threshold file names it
        self.weights = str(weights) if isinstance(weights, Path) else weights
        self._loaded: tuple[Any, LearnedWeights] | None = None
        # (level_, margin_, joints, weights) when packed, the network, its compiled step's constants
        self._compiled: tuple[tuple[Any, ...], _cnn.Network, FloatArray] | None = None

    # ----------------------------------------------------------------- the network

    def _weights_for(self, robot: str) -> LearnedWeights:
        """The weights of the ``weights`` hyper-parameter (loaded once), for ``robot``."""
        source = self.weights
        if source is not None and not isinstance(source, str | Path):
            raise InputTypeError(
                f"weights must be a robot name, a path or None; got {type(source).__name__}"
            )
        key = _base_name(robot) if source is None else source
        if self._loaded is None or self._loaded[0] != key:
            self._loaded = (key, load_weights(key))
        return self._loaded[1]

    @property
    def weights_(self) -> LearnedWeights:
        """The network in use (after :meth:`fit` or loading)."""
        self._check_fitted()
        return self._weights_for(self.robot_)

    def _check_compatible(self, weights: LearnedWeights, run: ObserverSignals) -> None:
        if run.n_dof != weights.n_dof or _base_name(run.robot) != weights.robot:
            raise robot_mismatch(
                f"weights trained for {weights.robot} ({weights.n_dof} joints); signals come "
                f"from {run.robot or '<unnamed>'} ({run.n_dof} joints)",
                weights.n_dof,
                run.n_dof,
            )
        if run.kind != weights.kind:
            raise InputValueError(
                f"weights read {weights.kind!r} residuals; these signals are {run.kind!r}"
            )
        if not np.allclose(run.gain, weights.gain, rtol=1e-9, atol=0.0):
            raise InputValueError(
                f"weights trained with observer gain K_I = {weights.gain} [1/s]; signals use "
                f"K_I = {run.gain.tolist()}"
            )
        self._check_period(weights, run.dt)

    @staticmethod
    def _check_period(weights: LearnedWeights, dt: float) -> None:
        if weights.period_range is not None:
            low, high = weights.period_range
            if not low * (1.0 - _BAND_RTOL) <= dt <= high * (1.0 + _BAND_RTOL):
                raise InputValueError(
                    f"weights trained at sample periods of {low:.6g} to {high:.6g} s "
                    f"({1.0 / high:.6g} to {1.0 / low:.6g} Hz; the network counts samples); "
                    f"got {dt:.6g} s ({1.0 / dt:.6g} Hz), outside that band: resample the log or "
                    "train for this rate"
                )
            return
        if not abs(dt - weights.dt) <= _PERIOD_RTOL * weights.dt:
            raise InputValueError(
                f"weights trained at a sample period of {weights.dt} s (the network counts "
                f"samples); got {dt} s, more than {_PERIOD_RTOL:.0%} apart: resample the log "
                "or train for this rate"
            )

    @staticmethod
    def _stacked(inputs: ThresholdInputs) -> FloatArray:
        return np.stack([getattr(inputs, name) for name in _cnn.CHANNELS], axis=1)

    def _centre_width(self, weights: LearnedWeights, run: ObserverSignals) -> tuple[Any, Any]:
        x = self._stacked(ThresholdInputs.from_signals(run))
        state = _cnn.initial_state(weights.network, x[0])
        centre, width, _ = _cnn.run(weights.network, state, x)
        return centre, width

    # ----------------------------------------------------------------- estimator hooks

    def _attribute_names(self) -> tuple[str, ...]:
        return ("level_", "margin_")

    def _check_attributes(self) -> None:
        super()._check_attributes()
        for name in self._attribute_names():
            if (getattr(self, name) < 0).any():
                raise InputValueError(f"attribute {name} must be >= 0")
        weights = self._weights_for(self.robot_)
        if weights.n_dof != self.n_dof_:
            raise DimensionError(
                f"weights have {weights.n_dof} joints; the threshold has {self.n_dof_}"
            )

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        weights = self._weights_for(runs[0].robot)
        level = np.zeros(runs[0].n_dof)
        for run, kept in zip(runs, keep, strict=True):
            self._check_compatible(weights, run)
            if not kept.any():
                continue
            centre, width = self._centre_width(weights, run)
            score = np.abs(run.residual - centre) / width
            level = np.maximum(level, score[kept].max(axis=0))
        self.level_ = level
        self.margin_ = margin.copy()

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        weights = self._weights_for(self.robot_)
        self._check_period(weights, dt)
        first = self._stacked(inputs)[0]
        self._packed()  # the compiled step's constants, before the first sample
        return LearnedState(dt, np.zeros(0), _cnn.initial_state(weights.network, first))

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        state = cast(LearnedState, state)  # checked by the public entry points
        network = self._weights_for(self.robot_).network
        if inputs.model_torque.shape[0] == 1:  # a stream's step without numba: the numpy step
            x = np.concatenate([getattr(inputs, name) for name in _cnn.CHANNELS])
            centre, width, after = _cnn.step_numpy(network, state.network, x)
            width *= self.level_
            width += self.margin_
            return (
                (centre - width)[None],
                (centre + width)[None],
                LearnedState(state.dt, state.zi, after),
            )
        centre, width, after = _cnn.run(network, state.network, self._stacked(inputs))
        half = self.level_ * width + self.margin_
        return centre - half, centre + half, LearnedState(state.dt, state.zi, after)

    # ----------------------------------------------------------------- the compiled stream

    def _packed(self) -> tuple[_cnn.Network, FloatArray] | None:
        """Network and constants of the compiled step for the fitted λ, margin and joints.

        None without numba. Packed again when ``level_``, ``margin_``,
        ``joints`` or ``weights`` is another object than when last packed.
        """
        if not _cnn_kernel.available:
            return None
        key = (self.level_, self.margin_, self.joints, self.weights)
        compiled = self._compiled
        if compiled is None or any(a is not b for a, b in zip(compiled[0], key, strict=True)):
            network = self._weights_for(self.robot_).network
            monitored = np.zeros(self.n_dof_, dtype=bool)
            monitored[np.asarray(check_joints(self.joints, self.n_dof_)) - 1] = True
            compiled = (key, network, network.packed(self.level_, self.margin_, monitored))
            self._compiled = compiled
        return compiled[1], compiled[2]

    def _step_checked(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        packed = self._packed()
        if packed is None:
            return super()._step_checked(state, inputs)
        state = cast(LearnedState, state)
        done = _cnn.step_packed(
            packed[0],
            state.network,
            packed[1],
            inputs.model_torque[0],
            inputs.friction[0],
            inputs.sign[0],
            inputs.velocity[0],
        )
        if done is None:  # a non-finite input: NaN bounds, the state as it was (as _cnn.step)
            nan = np.full(self.n_dof_, np.nan)
            return nan, nan.copy(), state
        out, after = done
        return out[2], out[3], _next(state, after)

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
        """Bounds at one sample of a stream (see :meth:`Threshold.step`).

        With numba, a sample of four float arrays of shape (n_dof,) and a
        state of this stream goes straight to the compiled step, which
        checks finiteness before it writes anything; any other sample, and a
        non-finite one, takes the checked path of every family (same
        result, or the same error).
        """
        compiled = self._compiled
        if (
            compiled is not None
            and type(state) is LearnedState
            and position is None
            and acceleration is None
            and compiled[0][0] is self.level_
            and compiled[0][1] is self.margin_
            and compiled[0][2] is self.joints
            and compiled[0][3] is self.weights
        ):
            try:
                done = _cnn.step_packed(
                    compiled[1], state.network, compiled[2], model_torque, friction, sign, velocity
                )
            except TypeError:  # not four float64 arrays: the checked path converts or says why
                done = None
            if done is not None:
                out, after = done
                return out[2], out[3], _next(state, after)
        return super().step(
            state,
            model_torque,
            friction,
            sign,
            velocity,
            position=position,
            acceleration=acceleration,
        )

    # ----------------------------------------------------------------- the score

    def predict(self, signals: ObserverSignals) -> tuple[FloatArray, FloatArray]:
        """Centre c and width w of the free-motion residual over a run [N m].

        Returns
        -------
        centre, width : ndarray of shape (n_samples, n_dof)
        """
        self.check_signals(signals)
        check_inputs_finite(ThresholdInputs.from_signals(signals))
        weights = self._weights_for(self.robot_)
        self._check_compatible(weights, signals)
        if signals.n_samples == 0:
            empty = np.zeros((0, self.n_dof_))
            return empty, empty.copy()
        return self._centre_width(weights, signals)

    def score(self, signals: ObserverSignals) -> FloatArray:
        """Collision score |r̂ - c|/w of every sample and joint [-] (compare with ``level_``)."""
        centre, width = self.predict(signals)
        return np.asarray(np.abs(signals.residual - centre) / width)


def _next(state: LearnedState, network: _cnn.CnnState) -> LearnedState:
    """``state`` with the network's next state, made without the frozen dataclass's ``__init__``.

    Its field-by-field ``object.__setattr__`` costs about 1 µs, a few per cent
    of a compiled step.
    """
    new = object.__new__(LearnedState)
    fields = new.__dict__
    fields["dt"] = state.dt
    fields["zi"] = state.zi
    fields["network"] = network
    return new
