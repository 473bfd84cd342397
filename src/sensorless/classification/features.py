"""Features of one event's residual: rise rate, duration, high-frequency fraction, power.

An :class:`EventFeatures` describes the residual r̂ of one detected event from
its first sample (time ``start``, residual ``b``) to its last:

* ``rise_rate`` [N m/s]: the steepest rise of ``e(t) = ‖r̂(t) - b‖`` over a
  lag of ``lag`` seconds, max over the event of ``(e_k - e_{k-L}) / (t_k - t_{k-L})``
  for ``k >= L = round(lag / dt)`` samples; an event of at most ``L``
  samples has its peak change over its duration (0 for a single sample);
* ``duration`` [s]: ``end - start``;
* ``hf_fraction`` [-]: the share of the energy of ``r̂ - b`` that a causal
  second-order Butterworth high-pass at ``highpass`` Hz lets through,
  ``Σ‖hp(r̂ - b)‖² / Σ‖r̂ - b‖²`` (0 while r̂ has not moved), started at rest
  at the event's first sample;
* ``mean_power`` [W]: the mean of τ̂_cᵀq̇ = r̂ᵀq̇ over the event's samples;
  positive when the external force pushes the arm the way it moves (energy
  flows into the robot);
* ``peak_change`` [N m]: the largest ``e(t)``.

Everything is a running sum or a running maximum, so the features of a
stream and of a recorded event are one computation (:func:`_update`, over a
chunk of any length): a stream feeds one sample at a time, a batch the whole
event, with the same arithmetic in the same order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from scipy import signal as sps

from .._validation import FloatArray
from ..exceptions import InputValueError

__all__ = ["FEATURE_NAMES", "EventFeatures"]

#: The features the rules use, in the order of :class:`EventFeatures`.
FEATURE_NAMES: tuple[str, ...] = ("rise_rate", "duration", "hf_fraction", "mean_power")


@dataclass(frozen=True)
class EventFeatures:
    """Features of the residual over one event (or its first part).

    Attributes
    ----------
    start, end : float
        First and last time of the samples used [s].
    rise_rate : float
        Steepest rise of ‖r̂ - r̂(start)‖ over the lag [N m/s].
    duration : float
        ``end - start`` [s].
    hf_fraction : float
        High-frequency share of the energy of r̂ - r̂(start) [-].
    mean_power : float
        Mean of r̂ᵀq̇ [W].
    peak_change : float
        Largest ‖r̂ - r̂(start)‖ [N m].
    n_samples : int
        Number of samples used.
    """

    start: float
    end: float
    rise_rate: float
    duration: float
    hf_fraction: float
    mean_power: float
    peak_change: float
    n_samples: int

    def as_dict(self) -> dict[str, Any]:
        """The attributes as a plain dict (for tables)."""
        return {
            "start": self.start,
            "end": self.end,
            "rise_rate": self.rise_rate,
            "duration": self.duration,
            "hf_fraction": self.hf_fraction,
            "mean_power": self.mean_power,
            "peak_change": self.peak_change,
            "n_samples": self.n_samples,
        }


class _Sums(NamedTuple):
    """Running sums and maxima of one event; immutable, replaced by :func:`_update`."""

    start: float
    baseline: FloatArray  # r̂ at the first sample [N m]
    zi: FloatArray  # high-pass state, (n_sections, 2, n_dof)
    tail_t: FloatArray  # times of the last `lag` samples [s]
    tail_e: FloatArray  # their ‖r̂ - b‖ [N m]
    n: int  # samples so far
    last: float
    energy: float  # Σ‖r̂ - b‖² [N² m²]
    high: float  # Σ‖hp(r̂ - b)‖² [N² m²]
    power: float  # Σ r̂ᵀq̇ [W]
    rate: float  # running max of the lagged rise [N m/s]
    peak: float  # running max of ‖r̂ - b‖ [N m]


class _Design(NamedTuple):
    """What a classifier fixes before the first sample: the high-pass and the lag."""

    sos: FloatArray
    lag: int


def _design(highpass: float, lag: float, dt: float) -> _Design:
    """Second-order Butterworth high-pass at ``highpass`` Hz and the lag in samples at ``dt``."""
    nyquist = 0.5 / dt
    if not highpass < nyquist:
        raise InputValueError(
            f"highpass must be below the Nyquist frequency 1/(2 dt) = {nyquist:g} Hz; "
            f"got {highpass:g} Hz"
        )
    sos = np.asarray(sps.butter(2, highpass, "highpass", fs=1.0 / dt, output="sos"))
    return _Design(sos, max(1, round(lag / dt)))


def _open(design: _Design, start: float, residual: FloatArray) -> _Sums:
    """Sums before the first sample of an event starting at ``start`` with ``residual``."""
    n_dof = residual.shape[0]
    zi = np.zeros((design.sos.shape[0], 2, n_dof))
    empty = np.empty(0)
    return _Sums(start, residual.copy(), zi, empty, empty, 0, start, 0.0, 0.0, 0.0, 0.0, 0.0)


def _running(prior: float, values: FloatArray) -> float:
    """``prior + values[0] + values[1] + ...`` added left to right (as a stream adds them)."""
    if values.size == 1:  # the stream's case: one addition, as cumsum would do it
        return prior + float(values[0])
    return float(np.cumsum(np.concatenate([[prior], values]))[-1])


def _sos_one(sos: FloatArray, zi: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`scipy.signal.sosfilt` of one sample ``x`` (n_dof,) from the state ``zi``.

    The transposed direct form II of scipy's own loop, in its order of
    operations, without its per-call checks (they cost a stream ~60 µs a sample).
    """
    state = np.empty_like(zi)
    current = x
    for k in range(sos.shape[0]):
        b0, b1, b2, _, a1, a2 = sos[k]
        out = b0 * current + zi[k, 0]
        state[k, 0] = b1 * current - a1 * out + zi[k, 1]
        state[k, 1] = b2 * current - a2 * out
        current = out
    return current[None, :], state


def _update(
    design: _Design, sums: _Sums, t: FloatArray, residual: FloatArray, velocity: FloatArray
) -> _Sums:
    """Sums after the samples ``t`` (m,), ``residual`` and ``velocity`` (m, n_dof) of one event."""
    change = residual - sums.baseline
    squares = np.sum(change**2, axis=1)
    e = np.sqrt(squares)
    if t.size == 1:
        high, zi = _sos_one(design.sos, sums.zi, change[0])
    else:
        high, zi = sps.sosfilt(design.sos, change, axis=0, zi=sums.zi)
    times = np.concatenate([sums.tail_t, t])
    norms = np.concatenate([sums.tail_e, e])
    # Global sample index g of every new sample and its lag partner g - L, as
    # positions in `times` (which starts at global index n - len(tail)); a
    # rise over fewer than L samples would be a difference of two noisy samples.
    first = sums.n - sums.tail_t.size
    g = sums.n + np.arange(t.size)
    full = g[g >= design.lag]
    rate = sums.rate
    if full.size:
        here, partner = full - first, full - design.lag - first
        rises = (norms[here] - norms[partner]) / (times[here] - times[partner])
        rate = max(rate, float(rises.max()))
    keep = min(design.lag, times.size)
    return _Sums(
        start=sums.start,
        baseline=sums.baseline,
        zi=zi,
        tail_t=times[times.size - keep :],
        tail_e=norms[norms.size - keep :],
        n=sums.n + t.size,
        last=float(t[-1]) if t.size else sums.last,
        energy=_running(sums.energy, squares),
        high=_running(sums.high, np.sum(high**2, axis=1)),
        power=_running(sums.power, np.sum(residual * velocity, axis=1)),
        rate=rate,
        peak=max(sums.peak, float(e.max())) if e.size else sums.peak,
    )


def _mean_rise(sums: _Sums) -> float:
    """Rise rate of an event shorter than the lag: its peak change over its duration [N m/s]."""
    span = sums.last - sums.start
    return sums.peak / span if span > 0.0 else 0.0


def _features(sums: _Sums, lag: int) -> EventFeatures:
    """The features the sums describe, with the lag of the rise rate in samples."""
    return EventFeatures(
        start=sums.start,
        end=sums.last,
        rise_rate=sums.rate if sums.n > lag else _mean_rise(sums),
        duration=sums.last - sums.start,
        hf_fraction=sums.high / sums.energy if sums.energy > 0.0 else 0.0,
        mean_power=sums.power / sums.n if sums.n else math.nan,
        peak_change=sums.peak,
        n_samples=sums.n,
    )
