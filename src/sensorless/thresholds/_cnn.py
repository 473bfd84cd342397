"""The small causal dilated 1-D CNN of the learned family, in numpy: stream and batch.

One network, shared by all joints, reads at every sample the last
``receptive_field`` samples of four signals of one joint, the observer
inputs a threshold gets (:class:`~sensorless.thresholds.ThresholdInputs`):

    h_j (model torque) [N m], K_I/(s+K_I)·τ̂_fr,j [N m], K_I/(s+K_I)·sign(q̇_j) [-], q̇_j [rad/s],

each normalised by a per-joint mean and scale. Five causal convolutions of
kernel 3 with dilations (1, 2, 4, 8, 8) and tanh see the last 51 samples
(51 ms at 1 kHz); the first layer has a bias per joint, so the shared
network can still tell joints apart. Layers after the first read their input
one sample late (taps at t - 1, t - 1 - d, t - 1 - 2d): then every layer of a
streaming step depends only on the state and the new input, and one batched
matrix product computes them all (:func:`step`, a few numpy calls per
sample whatever the depth); the output lags the newest input by 4 samples.
A 1×1 head gives two numbers per joint and sample, the centre c_j and the
width w_j of the residual expected in
free motion, both in N m:

    c_j = m_j + s_j·o_1,    w_j = s_j·(softplus(o_2) + floor),

with the per-joint output mean m_j and scale s_j of the training residuals.

State (:class:`CnnState`): the inputs of every layer over the last
max(2d + δ + 1) = 18 samples, in one array of time slots, and the
index of the last sample. :func:`run` takes that state and any number of new
samples, computes layer by layer over the whole chunk and returns the outputs
and a new state; :func:`step` computes one sample and writes it into the
state's array in place (the old state is then spent, see :class:`CnnState`).
With numba installed :func:`step` runs the compiled kernel of
:mod:`._cnn_kernel` on the same rings (:func:`step_numpy` is the fallback
and the reference). All compute the same sums, so stream equals batch to
rounding and chunked equals whole. A row with a
non-finite input is skipped (NaN outputs, state unchanged), as a stream
skips a faulty sample. Inputs are clipped to ±``INPUT_CLIP`` normalised
units, so no finite input can overflow.

The backward pass used for training (no framework) is in
:mod:`sensorless.learning._backward`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray
from ..exceptions import InputValueError
from . import _cnn_kernel

__all__ = [
    "CHANNELS",
    "DILATIONS",
    "INPUT_CLIP",
    "CnnState",
    "Network",
    "initial_state",
    "run",
    "step",
    "step_numpy",
    "step_packed",
]

CHANNELS = ("model_torque", "friction", "sign", "velocity")
"""The per-joint input channels, in order (fields of ThresholdInputs)."""
DILATIONS = (1, 2, 4, 8, 8)
"""Dilation of each kernel-3 causal convolution."""
INPUT_CLIP = 100.0
"""Normalised inputs are clipped to ±this (a finite input never overflows the network)."""
IntArray = NDArray[np.intp]


@dataclass(frozen=True, eq=False)
class Network:
    """The arrays of the network (see the module docstring for the equations).

    Attributes
    ----------
    kernels : tuple of ndarray, each of shape (channels, 3 * channels_in)
        Convolution weights; columns are the taps at the newest, the middle
        and the oldest sample, each ``channels_in`` wide.
    biases : tuple of ndarray
        Biases; the first of shape (channels, n_dof) (one per joint), the
        others (channels, 1).
    head : ndarray of shape (2, channels)
        The 1×1 output layer (centre, width before softplus).
    head_bias : ndarray of shape (2, 1)
    dilations : tuple of int
    input_mean, input_scale : ndarray of shape (4, n_dof)
        Normalisation of the inputs (:data:`CHANNELS`), in their units.
    output_mean, output_scale : ndarray of shape (n_dof,)
        Mean and scale of the training residuals [N m].
    floor : float
        Smallest width in output-scale units [-].
    """

    kernels: tuple[FloatArray, ...]
    biases: tuple[FloatArray, ...]
    head: FloatArray
    head_bias: FloatArray
    dilations: tuple[int, ...]
    input_mean: FloatArray
    input_scale: FloatArray
    output_mean: FloatArray
    output_scale: FloatArray
    floor: float

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.output_scale.shape[0])

    @property
    def delays(self) -> tuple[int, ...]:
        """Samples by which each layer reads its input late (0 for the first, then 1)."""
        return tuple(0 if k == 0 else 1 for k in range(len(self.dilations)))

    @property
    def receptive_field(self) -> int:
        """Samples the output at t depends on, t included."""
        return 1 + sum(2 * d + e for d, e in zip(self.dilations, self.delays, strict=True))

    @property
    def n_parameters(self) -> int:
        """Number of trained numbers (normalisation excluded)."""
        return int(sum(a.size for a in self.parameters()))

    def parameters(self) -> list[FloatArray]:
        """The trained arrays in a fixed order: kernels, biases, head, head bias."""
        return [*self.kernels, *self.biases, self.head, self.head_bias]

    def with_parameters(self, values: list[FloatArray]) -> Network:
        """The same network with the trained arrays ``values`` (order of :meth:`parameters`)."""
        n = len(self.kernels)
        return Network(
            tuple(values[:n]),
            tuple(values[n : 2 * n]),
            values[2 * n],
            values[2 * n + 1],
            self.dilations,
            self.input_mean,
            self.input_scale,
            self.output_mean,
            self.output_scale,
            self.floor,
        )

    @functools.cached_property
    def _stream(self) -> _Stream:
        return _Stream.of(self)

    def packed(self, level: FloatArray, margin: FloatArray, monitored: Any) -> FloatArray:
        """Constants of the compiled step (:func:`step_packed`) for bounds c ∓ (level·w + margin).

        ``level`` [-] and ``margin`` [N m] of shape (n_dof,); ``monitored`` a
        boolean mask of shape (n_dof,) (the others get ∓inf).
        """
        s = self._stream
        return _cnn_kernel.pack(
            self.kernels,
            s.biases,
            self.head,
            self.head_bias[:, 0],
            {
                "inverse_scale": s.inverse_scale,
                "shift": s.shift,
                "output_scale": self.output_scale,
                "centre_shift": s.head_shift[0],
                "level": np.broadcast_to(level, (self.n_dof,)),
                "margin": np.broadcast_to(margin, (self.n_dof,)),
                "monitored": np.broadcast_to(monitored, (self.n_dof,)).astype(float),
            },
            self.floor,
        )

    @functools.cached_property
    def _unit_packed(self) -> FloatArray:
        """Constants of :func:`step`: level 1, margin 0, every joint (bounds c ∓ w)."""
        ones = np.ones(self.n_dof)
        return self.packed(ones, np.zeros(self.n_dof), ones)


class _Buffer:
    """The rings of one stream, advanced in place by :func:`step` (``version`` counts the steps).

    Keeps, per time slot, the views :func:`step` writes to (the new input,
    the layers' outputs, the head's input); a copy rebuilds them.
    """

    __slots__ = ("heads", "inputs", "outputs", "ring", "version")

    def __init__(self, ring: FloatArray, entries: int, version: int = 0) -> None:
        self.ring = ring
        self.version = version
        slots = range(0, ring.shape[0], entries)
        self.inputs = [ring[row, : len(CHANNELS)] for row in slots]
        self.outputs = [ring[row + 1 : row + entries] for row in slots]
        self.heads = [ring[row + entries - 1] for row in slots]

    def __reduce__(self) -> tuple[Any, ...]:
        entries = self.outputs[0].shape[0] + 1
        return (_Buffer, (self.ring, entries, self.version))


class CnnState(NamedTuple):
    """Streaming state of the network: the rings of the layers' inputs and the last sample.

    :func:`step` advances the rings in place and returns a new state that
    shares them (copying ~90 kB every sample would cost more than the
    network); the state it was given is then spent, and using it again is an
    error. :meth:`copy` keeps a state to step from twice; :func:`run` does
    not advance its state.

    A named tuple: it is made at every sample, and a tuple is made fastest.

    Attributes
    ----------
    buffer : _Buffer
        The rings, shared by the states of one stream.
    last : int
        Index of the last sample, modulo the period of the rings.
    version : int
        Steps the rings had taken when this state was made.

    Properties
    ----------
    ring : ndarray of shape (period * (n_layers + 1), channels, n_dof)
        Row ``τ mod period`` · (n_layers + 1) + k holds layer k's input at
        time τ (the first layer's 4 channels padded with zeros), row + n_layers
        the last layer's output (read by the head).
    """

    buffer: _Buffer
    last: int
    version: int = 0

    @property
    def ring(self) -> FloatArray:
        """The rings (see the class docstring)."""
        return self.buffer.ring

    @property
    def spent(self) -> bool:
        """Whether a later :func:`step` has advanced the rings past this state."""
        return self.version != self.buffer.version

    def copy(self) -> CnnState:
        """An independent state at the same sample."""
        self._check_current()
        return CnnState(
            _Buffer(self.buffer.ring.copy(), len(self.buffer.outputs[0]) + 1), self.last
        )

    def _check_current(self) -> None:
        if self.version != self.buffer.version:
            raise InputValueError(
                "this network state was advanced by a later step (steps update the rings in "
                "place); use the state that step returned, or CnnState.copy() to step twice "
                "from one state"
            )


@dataclass(frozen=True, eq=False)
class _Stream:
    """What :func:`step` precomputes: stacked weights, folded head and the rows of every phase."""

    kernels: FloatArray  # (n_layers, channels, 3 channels), the first padded
    biases: FloatArray  # (n_layers, channels, n_dof)
    inverse_scale: FloatArray  # (4, n_dof)
    shift: FloatArray  # mean / scale
    head_scale: FloatArray  # (2, n_dof): output scale, 1
    head_shift: FloatArray  # (2, n_dof): head bias · output scale + output mean, head bias + floor
    floor: FloatArray  # (n_dof,): softplus(o) + floor = logaddexp(floor, o + floor)
    lengths: tuple[int, ...]  # ring length per layer: 2 d + δ + 1
    entries: int  # rows per time slot: n_layers + 1
    period: int  # time slots: the longest ring
    taps_shape: tuple[int, int, int]  # (n_layers, 3 channels, n_dof)
    reads: list[IntArray]  # per phase: the rows of the taps, layer by layer
    read_table: IntArray  # the same, (period, 3 n_layers), for the compiled step

    @classmethod
    def of(cls, net: Network) -> _Stream:
        channels = net.kernels[-1].shape[0]
        n_layers = len(net.dilations)
        lengths = tuple(2 * d + e + 1 for d, e in zip(net.dilations, net.delays, strict=True))
        period = max(lengths)
        entries = n_layers + 1
        first = np.zeros((channels, 3, channels))
        first[:, :, : len(CHANNELS)] = net.kernels[0].reshape(channels, 3, len(CHANNELS))
        kernels = np.stack([first.reshape(channels, 3 * channels), *net.kernels[1:]])
        biases = np.stack([np.broadcast_to(b, (channels, net.n_dof)) for b in net.biases])
        lags = np.array(
            [e + np.arange(3) * d for d, e in zip(net.dilations, net.delays, strict=True)]
        )
        reads = [
            np.asarray(((t - lags) % period * entries + np.arange(n_layers)[:, None]).ravel())
            for t in range(period)
        ]
        scale = net.output_scale
        return cls(
            kernels,
            biases,
            1.0 / net.input_scale,
            net.input_mean / net.input_scale,
            np.stack((scale, np.ones_like(scale))),
            np.stack(
                (
                    net.head_bias[0] * scale + net.output_mean,
                    np.repeat(net.head_bias[1] + net.floor, net.n_dof),
                )
            ),
            np.full(net.n_dof, net.floor),
            lengths,
            entries,
            period,
            (n_layers, 3 * channels, net.n_dof),
            reads,
            np.ascontiguousarray(np.stack(reads)),
        )

    def histories(self, state: CnnState) -> list[FloatArray]:
        """Each layer's inputs before the next sample, oldest first (what :func:`run` needs)."""
        state._check_current()
        found = []
        for k, length in enumerate(self.lengths):
            times = (state.last + np.arange(2 - length, 1)) % self.period
            found.append(state.ring[times * self.entries + k])
        return found

    def state_of(self, histories: list[FloatArray], last: int) -> CnnState:
        """The state whose layers' inputs up to sample ``last`` are ``histories``."""
        n_dof = histories[0].shape[-1]
        ring = np.zeros((self.period * self.entries, self.taps_shape[1] // 3, n_dof))
        for k, (length, history) in enumerate(zip(self.lengths, histories, strict=True)):
            times = (last + np.arange(2 - length, 1)) % self.period
            ring[times * self.entries + k, : history.shape[1]] = history
        return CnnState(_Buffer(ring, self.entries), last % self.period)


def _softplus(x: FloatArray) -> FloatArray:
    return np.asarray(np.logaddexp(0.0, x))


def _normalised(net: Network, x: FloatArray) -> FloatArray:
    """Inputs (..., 4, n_dof) in normalised units, clipped."""
    return np.clip((x - net.input_mean) / net.input_scale, -INPUT_CLIP, INPUT_CLIP)


def _taps(h: FloatArray, d: int, n: int, axis: int) -> FloatArray:
    """The newest, middle and oldest tap of ``n`` outputs from inputs ``h`` along ``axis``."""
    newest = np.take(h, np.arange(2 * d, 2 * d + n), axis=axis)
    middle = np.take(h, np.arange(d, d + n), axis=axis)
    oldest = np.take(h, np.arange(n), axis=axis)
    return np.concatenate((newest, middle, oldest), axis=axis + 1)


def _outputs(net: Network, out: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Centre and width [N m] of the head's output ``out`` (n, 2, n_dof)."""
    centre = out[:, 0] * net.output_scale + net.output_mean
    width = (_softplus(out[:, 1]) + net.floor) * net.output_scale
    return centre, width


def initial_state(net: Network, first: FloatArray) -> CnnState:
    """The state of a stream whose first sample ``first`` (4, n_dof) was held since forever.

    ``first`` must be finite (the callers check it).
    """
    a = _normalised(net, first[None])
    histories = []
    for k, length in enumerate(net._stream.lengths):
        histories.append(np.repeat(a, length - 1, axis=0))
        # A constant input gives a constant output: the next layer's held input.
        a = np.tanh(net.kernels[k] @ np.concatenate((a, a, a), axis=1) + net.biases[k])
    return net._stream.state_of(histories, 0)


def run(net: Network, state: CnnState, x: FloatArray) -> tuple[FloatArray, FloatArray, CnnState]:
    """Centre and width of samples ``x`` after ``state``, layer by layer; the state after them.

    Parameters
    ----------
    net : Network
    state : CnnState
        From :func:`initial_state` or the previous call.
    x : ndarray of shape (n_samples, 4, n_dof)
        Inputs in :data:`CHANNELS` order, in their units. Rows with a
        non-finite value are skipped: their outputs are NaN and they leave
        the state as it was.

    Returns
    -------
    centre, width : ndarray of shape (n_samples, n_dof)
        [N m].
    state : CnnState
    """
    good = np.isfinite(x).all(axis=(1, 2))
    if not good.all():
        centre = np.full((x.shape[0], net.n_dof), np.nan)
        width = centre.copy()
        if good.any():
            centre[good], width[good], state = run(net, state, x[good])
        return centre, width, state
    n = x.shape[0]
    if n == 0:
        empty = np.zeros((0, net.n_dof))
        return empty, empty.copy(), state
    stream = net._stream
    a = _normalised(net, x)
    kept = []
    for k, (d, history) in enumerate(zip(net.dilations, stream.histories(state), strict=True)):
        h = np.concatenate((history[:, : a.shape[1]], a), axis=0)
        kept.append(h[n:])
        a = np.tanh(net.kernels[k] @ _taps(h, d, n, 0) + net.biases[k])
    centre, width = _outputs(net, net.head @ a + net.head_bias)
    return centre, width, stream.state_of(kept, state.last + n)


def step(net: Network, state: CnnState, x: FloatArray) -> tuple[FloatArray, FloatArray, CnnState]:
    """Centre and width of one sample ``x`` (4, n_dof) after ``state``; the state after it.

    The streaming form of :func:`run`: compiled (:func:`step_packed`) when
    numba is installed, else :func:`step_numpy`; both give the outputs of
    :func:`run` to rounding. It advances the rings of ``state`` in place
    (see :class:`CnnState`). A non-finite ``x`` gives NaN outputs and
    ``state`` itself, untouched: the sample is checked before anything is
    written.
    """
    if not _cnn_kernel.available:
        return step_numpy(net, state, x)
    x = np.asarray(x, dtype=float)
    done = step_packed(net, state, net._unit_packed, x[0], x[1], x[2], x[3])
    if done is None:
        nan = np.full(net.n_dof, np.nan)
        return nan, nan.copy(), state
    out, after = done
    return out[0], out[1], after


def step_packed(
    net: Network,
    state: CnnState,
    packed: FloatArray,
    model_torque: Any,
    friction: Any,
    sign: Any,
    velocity: Any,
) -> tuple[FloatArray, CnnState] | None:
    """The compiled step (numba required): rows centre, width, lower, upper (4, n_dof) [N m].

    ``packed`` from :meth:`Network.packed`; the inputs float arrays of shape
    (n_dof,). None, and ``state`` untouched, if an input is not finite or
    not n_dof long; a ``TypeError`` if one is not a one-dimensional float64
    array, an ``InputValueError`` if ``state`` is another network's.
    """
    buffer = state.buffer
    if state.version != buffer.version:
        state._check_current()
    s = net._stream
    t = state.last + 1
    if t == s.period:
        t = 0
    out = np.empty((4, net.n_dof))
    code = _cnn_kernel.compiled()(
        buffer.ring, s.read_table, t, packed, model_torque, friction, sign, velocity, out
    )
    if code == _cnn_kernel.WRONG_STATE:
        raise InputValueError(
            "this network state holds the rings of a network of another shape; use the state "
            "of this network (initial_state, step, run)"
        )
    if code:
        return None
    buffer.version += 1
    return out, CnnState(buffer, t, buffer.version)


def step_numpy(
    net: Network, state: CnnState, x: FloatArray
) -> tuple[FloatArray, FloatArray, CnnState]:
    """:func:`step` in numpy (the fallback without numba): all layers in one batched product."""
    buffer = state.buffer
    if state.version != buffer.version:
        state._check_current()
    # x·x is finite for a finite x unless it overflows: then the exact check decides
    if not math.isfinite(np.vdot(x, x)) and not np.isfinite(x).all():
        nan = np.full(net.n_dof, np.nan)
        return nan, nan.copy(), state
    s = net._stream
    t = state.last + 1
    if t == s.period:
        t = 0
    a = buffer.inputs[t]
    np.multiply(x, s.inverse_scale, out=a)
    a -= s.shift
    np.minimum(a, INPUT_CLIP, out=a)
    np.maximum(a, -INPUT_CLIP, out=a)
    y = np.matmul(s.kernels, buffer.ring[s.reads[t]].reshape(s.taps_shape))
    y += s.biases
    # the layers' outputs go straight into this slot's rows: inputs of the next layers, head input
    np.tanh(y, out=buffer.outputs[t])
    out = np.dot(net.head, buffer.heads[t])
    out *= s.head_scale
    out += s.head_shift
    width = np.logaddexp(s.floor, out[1])
    width *= net.output_scale
    buffer.version += 1
    return out[0], width, CnnState(buffer, t, buffer.version)
