"""The Python side of the compiled stream: pack a monitor's parts, read the verdict back.

:class:`FusedStream` lays the constants of a
:class:`~sensorless.monitor.CollisionMonitor` (estimator, observer, threshold,
limits, policy) into the flat arrays :func:`~sensorless.monitor._compiled.fused_step`
reads, holds its state buffers and turns its return code into a status,
joints and an event; each call costs about 0.1 µs per array argument, hence
two flat arrays. :func:`unsupported` says which monitors it covers.
Importing this module requires numba. Units SI and radians.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ..detection import TIME_TOLERANCE
from ..friction._kinds import STATIC_KINDS, static_parameters
from ..observers._adaptive_kernel import temporaries_size
from ..signals import Event
from ..thresholds import ConstantThreshold, Threshold, TimeVariantThreshold, VelocityThreshold
from . import _compiled as kernel
from . import _layout as layout
from ._codes import EVENT, StreamCodes, event_of, refusal
from ._compiled_block import BLOCK_SIGNATURE, CHUNK, fused_block

if TYPE_CHECKING:
    from .stream import CollisionMonitor

__all__ = ["FusedStream", "unsupported"]

_FAMILIES = (ConstantThreshold, TimeVariantThreshold, VelocityThreshold)
# Bound once: each attribute lookup on the module costs as much as a line of arithmetic.
_fused_step, _fused_block = kernel.fused_step, fused_block
_fused_step_sample = kernel.fused_step_sample
_THRESHOLD_ROWS = [layout.MODEL_TORQUE, layout.FILTERED_FRICTION, layout.FILTERED_SIGN,
                   layout.VELOCITY]  # fmt: skip


def unsupported(monitor: CollisionMonitor) -> str:
    """Why the compiled stream cannot run ``monitor`` ("" when it can)."""
    friction = getattr(monitor._observer, "friction_model", None)
    if friction is not None and type(friction) not in STATIC_KINDS:
        return f"the friction model {type(friction).__name__} runs on the Python path only"
    return refusal(monitor, _FAMILIES, "compiled stream")


class FusedStream(StreamCodes):
    """The two arrays of one monitor's compiled stream, and what reads them.

    The kernel's return codes are read as :class:`~._codes.StreamCodes` reads them.

    Parameters
    ----------
    monitor : CollisionMonitor
        A monitor :func:`unsupported` accepts; its estimator, momentum
        observer, fitted threshold, detector, limits, policy and settling
        window are read once.
    """

    def __init__(self, monitor: CollisionMonitor) -> None:
        observer, policy, detector = monitor._observer, monitor.policy, monitor.detector
        n, dt = observer.n_dof, observer.dt
        sos = monitor.estimator.sos_velocity
        zi_unit = monitor.estimator._zi_unit[1]  # the velocity cascade's sosfilt_zi
        friction, parameters = static_parameters(observer.friction_model, n)
        family, const, table, edges, extra = _threshold(monitor.threshold, dt, n)
        limits = monitor.limits
        const[:, :28] = observer._kernel.kernel_constants
        const[:, layout.CENTRE], const[:, layout.HALF_RANGE] = limits.centre, limits.half_range
        const[:, layout.SPEED_LIMIT], const[:, layout.TORQUE_LIMIT] = limits.velocity, limits.torque
        const[:, layout.POLE], const[:, layout.WEIGHT] = observer._pole, observer._weight
        const[:, layout.FRICTION_PARAMETERS : layout.MONITORED] = parameters
        const[np.asarray(detector.monitored_joints) - 1, layout.MONITORED] = 1.0
        release = math.nan if policy.release is None else policy.release - TIME_TOLERANCE
        const_at = layout.HEADER + 8 * sos.shape[0] + edges.size
        table_at = const_at + const.size
        adapter, self._adapter_start = _adapter(monitor, n)
        flags, rows = 3 * layout.N_FLAGS, 2 * (layout.SECTIONS + 2 * sos.shape[0]) * n
        adapter_state = flags + rows + 23 * n
        header = [
            # durations compared up to the Detector's tolerance on time differences
            dt, policy.early * dt, policy.gap * dt, monitor.settle - TIME_TOLERANCE, release,
            detector.min_duration - TIME_TOLERANCE, detector.hold - TIME_TOLERANCE,
            observer.torque == "joint", friction, family,
            extra, sos.shape[0], edges.size, const_at, table_at,
            table_at + table.size if adapter.size else 0, adapter_state,
            self._adapter_start.size, monitor._guard,
        ]  # fmt: skip
        parts = [np.array(header, dtype=np.float64), sos, zi_unit, edges, const, table, adapter]
        self._model = np.concatenate([np.ravel(part) for part in parts])
        self._model.setflags(write=False)
        temporaries = 0 if adapter.size == 0 else temporaries_size(n, int(adapter[2]))
        self._buffers = self._fresh(
            np.zeros(adapter_state + 2 * self._adapter_start.size + temporaries)
        )
        self._flags = self._buffers[:flags].reshape(3, layout.N_FLAGS)
        self._state = self._buffers[flags : flags + rows].reshape(2, -1, n)
        self._decode_masks(n)
        for function, signatures in (
            (_fused_step, (kernel.SIGNATURE,)),
            (_fused_block, (BLOCK_SIGNATURE,)),
            (_fused_step_sample, kernel.SAMPLE_SIGNATURES),
        ):
            for signature in signatures:
                if signature.args not in function.signatures:
                    # These versions only, loaded from numba's cache after the first run:
                    # without more, other inputs would compile other versions.
                    function.compile(signature)
            function.disable_compile()
        self.sample = (_fused_step_sample, self._model, self._buffers)
        """:func:`~sensorless.monitor._compiled.fused_step_sample` and this stream's two arrays.

        Called as ``function(time, q, tau_m, tau_j, model, buffers, out)``
        with whatever the user gave (``tau_j`` is ``tau_m`` for the
        motor-torque observer); numba's dispatcher refuses (TypeError) what
        its signatures do not take, and the function returns ``UNJUDGED`` for
        the rest of what it does not judge.
        """
        self.step = _entry_point(_fused_step, kernel.SIGNATURE)
        """:func:`~sensorless.monitor._compiled.fused_step` without numba's type dispatch.

        Callable as ``step(time, q, qd, tau_m, tau_j, model, buffers, out)``
        only with float64 C-contiguous 1-D samples (what
        :func:`~sensorless._validation.as_sample` returns): it skips the
        dispatcher's type resolution (0.7 µs of the 1.5 µs a call costs at
        8 arguments) and unboxes the arrays as its signature says.
        """

    def reset(self) -> None:
        """Forget the stream, the latch and what the drift adapter learned."""
        self._fresh(self._buffers)

    def _fresh(self, buffers: FloatArray) -> FloatArray:
        """``buffers`` as a stream that saw no sample (no time floor, nothing latched)."""
        flags = buffers[: layout.N_FLAGS]
        flags[:] = 0.0
        flags[[layout.FLOOR, layout.PENDING]] = -np.inf
        flags[layout.INSIDE_SINCE] = np.nan
        size = self._adapter_start.size
        if size:
            start = int(self._model[layout.ADAPT_STATE])
            buffers[start : start + 2 * size].reshape(2, size)[:] = self._adapter_start
        return buffers

    def run(
        self,
        time: float,
        sample: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
        out: FloatArray,
        method: str,
    ) -> tuple[str, tuple[int, ...], Event | None]:
        """:func:`~sensorless.monitor._compiled.fused_step` on this stream's arrays.

        ``sample`` is (q, qd, tau_m, tau_j), ``qd`` empty without a measured
        velocity. Returns the status ("ok", "collision", "settling") or, for a
        fault, what was refused (an entry of ``REASONS`` in :mod:`._codes`);
        the joints outside their bounds; the event that closed at the sample
        (found by ``method``), if any.
        """
        q, qd, tau_m, tau_j = sample
        code = self.step(time, q, qd, tau_m, tau_j, self._model, self._buffers, out)
        return self.decoded(code, method)

    def closed(self, method: str) -> Event:
        """The event that closed at the last sample run (its code has ``EVENT``)."""
        return event_of(self._flags[2, layout.OPEN_START :].tolist(), method)

    def block(
        self,
        t: FloatArray,
        sample: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
        method: str,
        chunk: int = CHUNK,
    ) -> tuple[np.ndarray, FloatArray, list[Event]]:
        """A whole log as a fresh stream, by :func:`._compiled_block.fused_block`.

        ``t`` (n_samples,) [s]; ``sample`` is (q, qd, tau_m, tau_j), each
        (n_samples, n_dof), ``qd`` (n_samples, 0) without a measured velocity;
        ``chunk``: the longest run of plain samples done by phases (0: every
        sample by the per-sample kernel, the same results).
        The live stream's state is left alone. Returns the codes per sample,
        the series (7, n_samples, n_dof) of :func:`fused_block` (NaN at faults)
        and the events, the one still open at the end included.
        """
        q, qd, tau_m, tau_j = sample
        n_samples, n = q.shape
        buffers = self._fresh(np.zeros_like(self._buffers))
        series = np.full((7, n_samples, n), np.nan)
        codes = np.zeros(n_samples, dtype=np.int64)
        closed = np.zeros((n_samples, 5))
        _fused_block(t, q, qd, tau_m, tau_j, self._model, buffers, series, codes, closed, chunk)
        flags = buffers[: 3 * layout.N_FLAGS].reshape(3, layout.N_FLAGS)
        events = [event_of(row, method) for row in closed[np.flatnonzero(codes & EVENT)].tolist()]
        last = self._finish(flags[0], method)
        return codes, series, events if last is None else [*events, last]

    @property
    def floor(self) -> float:
        """No sample may come at or before this time [s]."""
        return float(self._flags[0, layout.FLOOR])

    @property
    def last(self) -> float:
        """Time of the last accepted sample [s]."""
        return float(self._flags[0, layout.T_LAST])

    @property
    def latched(self) -> bool:
        """Whether a collision is latched."""
        return bool(self._flags[0, layout.LATCHED])

    @property
    def velocity(self) -> FloatArray:
        """The velocity estimate of the last sample run, accepted or not [rad/s]."""
        return self._state[1, layout.VELOCITY].copy()

    def threshold_rows(self) -> FloatArray:
        """The observer's model torque, filtered friction and sign [N m, N m, -] and the
        velocity [rad/s] of the last accepted sample, shape (4, n_dof): what a threshold
        reads besides the residual (a copy)."""
        return self._state[0, _THRESHOLD_ROWS]

    def refuse(self, time: float) -> None:
        """Record a sample refused before :meth:`run` (the gap rule's pending time)."""
        self._flags[0, layout.PENDING] = time

    def finish(self, method: str) -> Event | None:
        """Close the open event at the end of the stream, as ``Detector.finish``."""
        return self._finish(self._flags[0], method)

    def _finish(self, flags: FloatArray, method: str) -> Event | None:
        if not (flags[layout.HAS_STREAM] and flags[layout.HAS_DETECTOR]):
            return None
        lasted = (
            flags[layout.OPEN_END] - flags[layout.OPEN_START] >= self._model[layout.MIN_DURATION]
        )
        event = (
            event_of(flags[layout.OPEN_START :].tolist(), method)
            if flags[layout.OPEN] and lasted
            else None
        )
        flags[layout.OPEN] = flags[layout.OUTSIDE] = 0.0
        return event


def _entry_point(function: Any, signature: Any) -> Any:
    """The compiled ``signature`` version of ``function`` itself, else the dispatcher."""
    overload = function.overloads.get(signature.args)
    return getattr(overload, "entry_point", function)


def _adapter(monitor: CollisionMonitor, n: int) -> tuple[FloatArray, FloatArray]:
    """The drift adapter's parameters and initial state, flat, as ``_adapter_parts`` reads them.

    Both empty without adaptation.
    """
    adapter = monitor._adapter
    if adapter is None:
        return np.zeros(0), np.zeros(0)
    pole, weight, v_s, max_corr, norm_w, box, step_bound = adapter._params
    per_joint = [np.broadcast_to(v, (n,)) for v in (pole, weight, v_s, max_corr, step_bound)]
    parameters = np.concatenate([adapter._scalars, *per_joint, np.ravel(norm_w), np.ravel(box)])
    state = adapter.initial_state()
    fields = (
        state.theta, state.estimate, state.covariance, state.regressor,
        state.filtered_regressor, state.correction, state.filtered_correction,
        state.updates.astype(np.float64), [float(state.started)],
    )  # fmt: skip
    return parameters, np.concatenate([np.ravel(field) for field in fields])


def _threshold(
    threshold: Threshold, dt: float, n: int
) -> tuple[int, FloatArray, FloatArray, FloatArray, float]:
    """Family, per-joint constants, bin table (3, n_bins, n), bin edges, extrapolation margin."""
    const = np.zeros((n, layout.N_CONST))
    if isinstance(threshold, ConstantThreshold):
        const[:, layout.WIDTH] = threshold.beta_
        return layout.CONSTANT, const, np.zeros((3, 1, n)), np.zeros(0), 0.0
    if isinstance(threshold, TimeVariantThreshold):
        hysteretic = threshold.form == "hysteretic"
        const[:, layout.WIDTH], const[:, layout.GAMMA] = threshold.alpha_, threshold.gamma_
        const[:, layout.COEFFICIENT] = threshold.c_ if hysteretic else threshold.eps_fr_
        family = layout.HYSTERETIC_FORM if hysteretic else layout.TIME_VARIANT
        return family, const, np.zeros((3, 1, n)), np.zeros(0), 0.0
    assert isinstance(threshold, VelocityThreshold)  # unsupported() admits these three
    edges = np.asarray(threshold.bin_edges_, dtype=np.float64)
    step = np.broadcast_to(threshold.gain_, (n,)) * dt  # the filter of first_order
    const[:, layout.GAMMA] = threshold.gamma_
    const[:, layout.BIN_POLE], const[:, layout.BIN_WEIGHT] = np.exp(-step), -np.expm1(-step)
    visited = threshold.counts_ > 0
    first = np.argmax(visited, axis=0)
    last = visited.shape[0] - 1 - np.argmax(visited[::-1], axis=0)
    const[:, layout.VISITED_LOW], const[:, layout.VISITED_HIGH] = edges[first], edges[last + 1]
    table = np.stack([threshold.tau_fme_, threshold.lower_, threshold.upper_])
    return layout.VELOCITY_BINS, const, table, edges, float(threshold.extrapolation_margin)
