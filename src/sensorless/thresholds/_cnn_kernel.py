"""One streaming step of the learned family's CNN, compiled by numba (numpy's is the fallback).

:func:`step_into` does what :func:`sensorless.thresholds._cnn.step_numpy`
does, on the same rings in place (so a stream may switch between them and
:func:`~sensorless.thresholds._cnn.run` continues from either), and goes on
to the bounds of :class:`~sensorless.thresholds.LearnedThreshold`:

    centre c, width w, lower c - (λ·w + margin), upper c + (λ·w + margin),

written into the rows of ``out``; a joint that is not monitored gets ∓inf.
The constants (weights, normalisation, λ, margin, the monitored joints) are
packed once into one flat array by :func:`pack`: a compiled call costs per
argument, and a stream pays it at every sample.

Two things differ from the numpy step, both at rounding level (the tests
compare the two to 1e-12): the sums run in another order, and tanh is
computed by :func:`_tanh`, arithmetic only, so that the compiler vectorises
it (the libm tanh takes most of a numpy step's time on 560 values).

A sample with a non-finite input, or inputs of another length than the
rings', writes nothing and returns a nonzero code; the callers report it
(NaN outputs, or the error of the checked path). :func:`compiled` compiles
the step for its one signature at its first call (then from numba's disk
cache): any other argument types are a ``TypeError``, never a new
compilation in the middle of a stream.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from .._validation import FloatArray

__all__ = [
    "NOT_FINITE",
    "OK",
    "WRONG_LENGTH",
    "WRONG_STATE",
    "available",
    "compiled",
    "pack",
    "step_into",
]

# no "nnan"/"ninf": the finiteness check of the inputs must stay exact
_FAST_MATH = {"reassoc", "contract", "nsz", "arcp"}
OK, NOT_FINITE, WRONG_LENGTH, WRONG_STATE = 0, 1, 2, 3
"""Codes :func:`step_into` returns."""
_N_INPUTS = 4
_CLIP = 100.0  # _cnn.INPUT_CLIP (that module imports this one)
_N_ROWS = 2 * _N_INPUTS + 5
"""Rows of the per-joint block of the constants (see :func:`pack`)."""
_SQUARINGS = 6
"""tanh(x) uses expm1(-2|x|) = expm1(-2|x|/2^6) doubled six times: |x| ≤ 20 gives |u| ≤ 0.625."""
_TAYLOR = tuple(1.0 / math.factorial(k) for k in range(16, 0, -1))
"""Taylor coefficients of expm1, highest first: on |u| ≤ 0.625 the first one left out is < 1e-16."""


def pack(
    kernels: tuple[FloatArray, ...],
    biases: FloatArray,
    head: FloatArray,
    head_bias: FloatArray,
    rows: dict[str, FloatArray],
    floor: float,
) -> FloatArray:
    """The flat constants :func:`step_into` reads, in its order.

    Parameters
    ----------
    kernels : tuple of ndarray
        Per layer (channels, 3 · channels_in), the first with 4 inputs.
    biases : ndarray of shape (n_layers, channels, n_dof)
    head : ndarray of shape (2, channels)
    head_bias : ndarray of shape (2,)
    rows : dict
        ``inverse_scale`` and ``shift`` (4, n_dof); ``output_scale``,
        ``centre_shift`` (head bias · output scale + output mean), ``level``,
        ``margin``, ``monitored`` (1 or 0), each (n_dof,).
    floor : float
        Smallest width in output-scale units [-].
    """
    per_joint = np.vstack(
        [
            rows["inverse_scale"],
            rows["shift"],
            rows["output_scale"],
            rows["centre_shift"],
            rows["level"],
            rows["margin"],
            rows["monitored"],
        ]
    )
    # biases joint-major: the compiled step computes a joint's channels together
    parts = [*(k.ravel() for k in kernels), biases.transpose(0, 2, 1).ravel()]
    parts += [head.ravel(), per_joint.ravel()]
    parts.append(np.array([head_bias[1], floor]))
    packed = np.ascontiguousarray(np.concatenate(parts), dtype=float)
    packed.flags.writeable = False
    return packed


def _tanh(x: float) -> float:
    """tanh(x) within a few ulp, by arithmetic only (see ``_SQUARINGS``, ``_TAYLOR``)."""
    u = min(abs(x), 20.0) * (-2.0 / 2**_SQUARINGS)  # tanh(20) is 1 in double precision
    q = _TAYLOR[0]
    q = q * u + _TAYLOR[1]
    q = q * u + _TAYLOR[2]
    q = q * u + _TAYLOR[3]
    q = q * u + _TAYLOR[4]
    q = q * u + _TAYLOR[5]
    q = q * u + _TAYLOR[6]
    q = q * u + _TAYLOR[7]
    q = q * u + _TAYLOR[8]
    q = q * u + _TAYLOR[9]
    q = q * u + _TAYLOR[10]
    q = q * u + _TAYLOR[11]
    q = q * u + _TAYLOR[12]
    q = q * u + _TAYLOR[13]
    q = q * u + _TAYLOR[14]
    q = (q * u + _TAYLOR[15]) * u  # expm1(u), Horner written out so that it vectorises
    for _ in range(_SQUARINGS):  # expm1(2u) = expm1(u)·(2 + expm1(u))
        q *= 2.0 + q
    return math.copysign(-q / (2.0 + q), x)


def _normalise(values: FloatArray, rows: FloatArray, c: int, slot: FloatArray) -> None:
    """Input channel ``c`` in normalised units, clipped, into its row of a time slot."""
    for j in range(values.shape[0]):
        a = values[j] * rows[c, j] - rows[_N_INPUTS + c, j]
        slot[c, j] = min(max(a, -_CLIP), _CLIP)


def step_into(
    ring: FloatArray,
    reads: Any,
    t: int,
    constants: FloatArray,
    model_torque: FloatArray,
    friction: FloatArray,
    sign: FloatArray,
    velocity: FloatArray,
    out: FloatArray,
) -> int:
    """One sample of the network into time slot ``t`` of ``ring``, outputs into ``out`` (4, n_dof).

    ``ring`` (period · (n_layers + 1), channels, n_dof) and ``reads``
    (period, 3 · n_layers), the rows of the taps per time slot, are those of
    :class:`~sensorless.thresholds._cnn.CnnState`; the inputs are one sample,
    each (n_dof,). ``out`` rows: centre, width, lower, upper [N m]. Returns
    :data:`OK`, or, having written nothing, :data:`NOT_FINITE`,
    :data:`WRONG_LENGTH` or :data:`WRONG_STATE` (rings of a network of
    another shape than the constants': nothing is indexed past an array).
    """
    n = ring.shape[2]
    channels = ring.shape[1]
    n_layers = reads.shape[1] // 3
    size = 3 * channels * (_N_INPUTS + (n_layers - 1) * channels)
    size += n_layers * n * channels + 2 * channels + _N_ROWS * n + 2
    if (
        constants.shape[0] != size
        or ring.shape[0] != reads.shape[0] * (n_layers + 1)
        or not 0 <= t < reads.shape[0]
    ):
        return WRONG_STATE
    for values in (model_torque, friction, sign, velocity):
        if values.shape[0] != n:
            return WRONG_LENGTH
    for j in range(n):
        if not (
            math.isfinite(model_torque[j])
            and math.isfinite(friction[j])
            and math.isfinite(sign[j])
            and math.isfinite(velocity[j])
        ):
            return NOT_FINITE
    at = 3 * channels * (_N_INPUTS + (n_layers - 1) * channels)
    biases = constants[at : at + n_layers * n * channels].reshape((n_layers, n, channels))
    at += n_layers * n * channels
    head = constants[at : at + 2 * channels].reshape((2, channels))
    at += 2 * channels
    rows = constants[at : at + _N_ROWS * n].reshape((_N_ROWS, n))
    head_bias, floor = constants[at + _N_ROWS * n], constants[at + _N_ROWS * n + 1]

    slot = t * (n_layers + 1)
    _normalise(model_torque, rows, 0, ring[slot])
    _normalise(friction, rows, 1, ring[slot])
    _normalise(sign, rows, 2, ring[slot])
    _normalise(velocity, rows, 3, ring[slot])
    taps = np.empty((n, 3 * channels))
    y = np.empty((n, channels))
    start = 0
    for k in range(n_layers):
        width = _N_INPUTS if k == 0 else channels
        size = 3 * width * channels
        kernel = constants[start : start + size].reshape((channels, 3 * width))
        start += size
        for tap in range(3):
            row = reads[t, 3 * k + tap]
            for c in range(width):
                for j in range(n):
                    taps[j, tap * width + c] = ring[row, c, j]
        for j in range(n):
            for o in range(channels):
                y[j, o] = biases[k, j, o]
        _products(kernel, taps, y, 3 * width)
        for j in range(n):
            for o in range(channels):
                y[j, o] = _tanh(y[j, o])
        for o in range(channels):
            for j in range(n):
                ring[slot + k + 1, o, j] = y[j, o]
    _outputs(ring[slot + n_layers], head, rows, head_bias, floor, out)
    return OK


def _products(kernel: FloatArray, taps: FloatArray, y: FloatArray, m: int) -> None:
    """``y[j] += kernel[:, :m] @ taps[j, :m]`` for every joint j.

    Two joints by two output channels at a time: four sums share each load,
    and the compiler vectorises them along ``m``. An odd last joint or
    channel is paired with itself and its sum added once.
    """
    channels = kernel.shape[0]
    n = y.shape[0]
    for j in range(0, n, 2):
        j1 = min(j + 1, n - 1)
        for o in range(0, channels, 2):
            o1 = min(o + 1, channels - 1)
            a = 0.0
            b = 0.0
            c = 0.0
            d = 0.0
            for i in range(m):
                k0 = kernel[o, i]
                k1 = kernel[o1, i]
                t0 = taps[j, i]
                t1 = taps[j1, i]
                a += k0 * t0
                b += k1 * t0
                c += k0 * t1
                d += k1 * t1
            y[j, o] += a
            if o1 > o:
                y[j, o1] += b
            if j1 > j:
                y[j1, o] += c
                if o1 > o:
                    y[j1, o1] += d


def _outputs(
    last: FloatArray,
    head: FloatArray,
    rows: FloatArray,
    head_bias: float,
    floor: float,
    out: FloatArray,
) -> None:
    """Centre, width and bounds from the last layer's output ``last`` (channels, n_dof)."""
    base = 2 * _N_INPUTS
    for j in range(last.shape[1]):
        centre = 0.0
        spread = head_bias
        for c in range(last.shape[0]):
            centre += head[0, c] * last[c, j]
            spread += head[1, c] * last[c, j]
        centre = centre * rows[base, j] + rows[base + 1, j]
        # softplus(o) + floor = logaddexp(floor, o + floor) of the numpy step
        softplus = max(spread, 0.0) + math.log1p(math.exp(-abs(spread)))
        width = (softplus + floor) * rows[base, j]
        out[0, j] = centre
        out[1, j] = width
        if rows[base + 4, j] > 0.0:
            half = rows[base + 2, j] * width + rows[base + 3, j]
            out[2, j] = centre - half
            out[3, j] = centre + half
        else:
            out[2, j] = -math.inf
            out[3, j] = math.inf


available: bool
try:
    from numba import njit, types
except ImportError:  # _cnn.step_numpy is the fallback
    available = False
else:
    available = True
    _OPTIONS: dict[str, Any] = {"fastmath": _FAST_MATH, "error_model": "numpy", "cache": True}
    # step_into calls these by their global names: compiled first, the calls stay in machine code
    _tanh = njit(**_OPTIONS)(_tanh)
    _normalise = njit(**_OPTIONS)(_normalise)
    _products = njit(**_OPTIONS)(_products)
    _outputs = njit(**_OPTIONS)(_outputs)


@functools.cache
def compiled() -> Any:
    """:func:`step_into` compiled for its one signature (numba required; compiled once, lazily)."""
    inputs = types.Array(types.float64, 1, "A")
    signature = types.intp(
        types.Array(types.float64, 3, "C"),
        types.Array(types.intp, 2, "C"),
        types.intp,
        types.Array(types.float64, 1, "C", readonly=True),
        inputs,
        inputs,
        inputs,
        inputs,
        types.Array(types.float64, 2, "C"),
    )
    return njit(signature, **_OPTIONS)(step_into)
