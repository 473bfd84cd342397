"""The stream of :mod:`.stream` without numba: one sample in a few vectorised numpy calls.

:class:`NumpyStream` has the interface of :class:`~sensorless.monitor._fused.FusedStream`
and does, for one sample, what :func:`~sensorless.monitor._compiled.fused_step`
specifies (time rules, value limits, velocity cascade, p, Cᵀq̇ and g, the
momentum observer, settling, bounds, detector events, latch; commit only when
the whole sample was good), with numpy over the joints instead of compiled
loops. A small numpy call costs 0.2–0.6 µs, so the sample is laid out to need
few of them:

* all per-joint state lives in two row buffers (n_rows, n_dof), the committed
  one and the scratch one; a sample reads the committed buffer, writes the
  scratch one and commits by swapping the two (a fault swaps nothing);
* the velocity estimate of backward differences is one subtraction; any
  other filter runs through the estimator's own ``sos_sample``;
* the value limits of q, τ_m, τ_J and of the velocity estimate are one check
  on a block of rows;
* p + g is ``pin.rnea`` at zero velocity and acceleration q̇ (M q̇ + g, armature
  included), Cᵀq̇ is q̇ · ``computeCoriolisMatrix`` and g ``computeGeneralizedGravity``,
  all on one model and data (a second model's memory costs more than it saves);
  the observer's product takes p as the difference of the two rows;
* the observer's update (increments of p, trapezoid of Cᵀq̇ − g and τ̂_fr,
  held τ, the four first-order filters) is one matrix product over the rows
  (this sample's terms, last sample's terms and filter states) when every
  joint has the same gain; the same product gives ±r̂ for the constant bounds,
  and the filter of τ_fme and copies of this sample's bin entries (one
  ``searchsorted`` and one ``take``) for the velocity bins;
* the time-variant bounds (forms "friction" and "hysteretic") and those of
  the velocity bins, with the detector's excursions, are one elementwise
  product and one matrix product; the constant ones one subtraction;
* the detector reads the excursions as one list; a joint outside costs one
  comparison more (:mod:`._numpy_rules`).

The results equal the compiled stream's to rounding (the sums run in another
order). Needs no numba. Units SI and radians.
"""

from __future__ import annotations

import copy
import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .._validation import FloatArray
from ..detection import TIME_TOLERANCE
from ..filters._sos import sections, sos_sample
from ..signals import Event
from ..thresholds import ConstantThreshold, TimeVariantThreshold, VelocityThreshold
from ._codes import (
    COLLISION,
    EVENT,
    FAULT,
    FAULT_BOUNDS,
    FAULT_EARLY,
    FAULT_GAP,
    FAULT_OBSERVER,
    FAULT_TIME,
    FAULT_VELOCITY,
    OK,
    SETTLING,
    UNJUDGED,
    StreamCodes,
    event_of,
    refusal,
)
from ._numpy_parts import (
    BIN,
    FME,
    LC,
    ONE,
    SG,
    TJ,
    TM,
    UC,
    Bounds,
    F,
    H,
    P,
    R,
    V,
    block_views,
    friction_basis,
    layout,
    limits_check,
    observer_matrix,
    start_rows,
)  # fmt: skip
from ._numpy_rules import EventRules, Flags, refused

if TYPE_CHECKING:
    from .stream import CollisionMonitor

__all__ = ["NumpyStream", "unsupported"]

_FAMILIES = (ConstantThreshold, TimeVariantThreshold, VelocityThreshold)


def unsupported(monitor: CollisionMonitor) -> str:
    """Why the numpy stream cannot run ``monitor`` ("" when it can)."""
    if monitor._adapter is not None:
        return "drift adaptation runs on the Python and numba paths only"
    return refusal(monitor, _FAMILIES, "numpy stream")


class NumpyStream(StreamCodes):
    """One monitor's stream in numpy: the interface of :class:`~._fused.FusedStream`.

    Its return codes are the compiled kernel's (:class:`~._codes.StreamCodes`).

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
        self._n = n
        estimator = monitor.estimator
        sos = np.asarray(estimator.sos_velocity, dtype=np.float64)
        self._sections = sections(sos)
        self._zi = np.asarray(estimator._zi_unit[1], dtype=np.float64).reshape(-1, 1)
        self._backward = sos.tolist() == [[1.0, -1.0, 0.0, 1.0, 0.0, 0.0]]
        self._scale = np.full(n, float(estimator._scale[1]))  # arrays divide faster than floats
        self._joint = observer.torque == "joint"
        self._tau = TJ if self._joint else TM  # the torque the observer integrates
        check = 4 if self._joint else 3  # rows V … TM (… TJ)
        self._centre, self._check = limits_check(monitor.limits, check)
        monitored = np.zeros(n, dtype=bool)
        monitored[np.asarray(detector.monitored_joints) - 1] = True
        self._monitored = np.flatnonzero(monitored).tolist()
        self._bounds = bounds = Bounds(monitor.threshold, dt, monitored)
        self._velocity, self._constant = bounds.velocity, bounds.constant
        uniform = bool(np.all(observer.gain == observer.gain[0]))
        pole, weight = observer._pole, observer._weight
        kind = "velocity" if bounds.velocity else "constant" if bounds.constant else ""
        self._observe = observer_matrix(
            dt, float(weight[0]) if uniform else 1.0, float(pole[0]) if uniform else 0.0, self._tau,
            bounds.bins, bounds.constant,
        )  # fmt: skip
        self._gains = None if uniform else (weight[None, :].copy(), pole[None, :].copy())
        self._bin_gains = bounds.bin_gains  # per-joint filters after the product
        self._per_joint = self._gains is not None or self._bin_gains is not None
        self._friction, self._friction_kind, self._basis = friction_basis(observer)
        self._friction_on = self._friction_kind != "none"
        model, self._zero = observer.robot.pinocchio_model, np.zeros(n)
        self._pin = (model, model.createData(), self._zero)  # rnea, Coriolis and g on one data
        # Durations compared up to the Detector's tolerance on time differences.
        self._early, self._gap = policy.early * dt, policy.gap * dt
        self._settle = monitor.settle - TIME_TOLERANCE
        self._release = math.nan if policy.release is None else policy.release - TIME_TOLERANCE
        self._rules = EventRules(
            self._monitored, detector.min_duration - TIME_TOLERANCE,
            detector.hold - TIME_TOLERANCE, self._release, bounds.pair,
        )  # fmt: skip
        self._decode_masks(n)
        m = 2 * sos.shape[0]  # section states, rows 0 … m − 1; the observer block after them
        self._buffers = (np.zeros((m + BIN + 1, n)), np.zeros((m + BIN + 1, n)))
        self._views = tuple(layout(buffer, m, check, kind) for buffer in self._buffers)
        self._start = np.zeros((BIN + 1, n))  # observer block of a (re)start or second sample
        self._start_views = block_views(self._start, kind)
        self._shape = (n,)
        self.sample = (self._sample_step, None, None)
        """The entry point of the common sample, as the compiled stream's ``sample``:
        ``function(time, q, tau_m, tau_j, model, buffers, out)`` (model and buffers
        unused) returns the code of :meth:`_step`, or ``UNJUDGED`` for what it does not
        judge (see :meth:`_sample_step`)."""
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the stream and the latch."""
        for block in (*self._buffers, self._start):
            block[:] = 0.0
            block[-BIN - 1 + ONE] = 1.0
            if self._constant:
                block[-BIN - 1 + LC : -BIN - 1 + UC + 1] = self._bounds.low_up
        self._committed, self._scratch = self._views
        self._velocity_row = self._scratch[1]
        self._flags = Flags()
        self._closed: tuple[float, ...] = ()

    def _save(self) -> tuple[Any, ...]:
        """A copy of the whole state (:meth:`block` runs a fresh stream, then restores it)."""
        first = self._committed is self._views[0]
        velocity = 0 if self._velocity_row is self._views[0][1] else 1
        return [b.copy() for b in self._buffers], first, copy.copy(self._flags), velocity

    def _restore(self, saved: tuple[Any, ...]) -> None:
        buffers, first, flags, velocity = saved
        for buffer, copied in zip(self._buffers, buffers, strict=True):
            buffer[:] = copied
        self._committed, self._scratch = self._views if first else self._views[::-1]
        self._flags, self._velocity_row = flags, self._views[velocity][1]

    # ------------------------------------------------------------------ sample
    def _step(
        self, time: float, q: FloatArray, qd: FloatArray, tau_m: FloatArray, tau_j: FloatArray,
        out: FloatArray,
    ) -> int:  # fmt: skip
        """One sample; returns its code (:mod:`._codes`)."""
        fl = self._flags
        if time <= fl.floor:
            return FAULT_TIME
        restart, time_fault = not fl.has_stream, 0
        if not restart:
            step = time - fl.t_last
            if step < self._early:
                time_fault = FAULT_EARLY
            elif step > self._gap:
                if self._early <= time - fl.pending <= self._gap:
                    restart = True  # the stream resumed after a real gap
                else:
                    time_fault = FAULT_GAP
        committed, scratch = self._committed, self._scratch
        written = scratch[12]  # the views of the scratch buffer a sample writes
        s_v, s_q, s_tau_m, s_tau_j, s_check, s_out, s_update, s_rows, s_filters, s_block = written
        if self._backward:  # backward differences: y = q − q_prev
            _subtract(q, q if restart else committed[2], s_v)  # out positional: faster
        else:
            z = self._zi * q if restart else committed[0]  # rows: the sections' two states each
            y, z_next = sos_sample(self._sections, q, z.reshape(-1, 2, q.shape[0]))
            scratch[0][...] = z_next.reshape(z.shape)
            s_v[...] = y
        _divide(s_v, self._scale, s_v)
        if len(qd):
            s_v[...] = qd  # the measured velocity replaces the estimate
        self._velocity_row = s_v
        s_q[...] = q
        s_tau_m[...] = tau_m
        if self._joint:
            s_tau_j[...] = tau_j
        difference, low, high, all_inside, inside = self._check
        _subtract(s_check, self._centre, difference)
        _less_equal(low, high, inside)
        if time_fault or inside.tobytes() != all_inside:
            return refused(fl, inside, time, time_fault)
        fresh = not restart and fl.t_last == fl.start
        views = self._start_views if restart or fresh else committed[11]
        self._terms(q, s_v, views)
        if restart:
            self._initial(q, qd if len(qd) else self._zero, views[-1])
        elif fresh:  # the observer starts at the first velocity estimate
            start_rows(views[-1], views[-1], self._tau)
        settling = time - (time if restart else fl.start) < self._settle
        bounds = self._bounds
        if self._velocity and not settling:  # this sample's bin entries (Bounds.lookup_parts)
            edges, base, index, table = bounds.lookup_parts
            _add(edges.searchsorted(s_v, "right"), base, index)
            table.take(index, 1, views[9], "clip")  # positional: faster
            if restart or not fl.has_detector:  # the filter of τ_fme starts at τ_fme
                views[-1][BIN] = views[-1][FME]
            elif fresh:
                views[-1][BIN] = committed[10][BIN]
        self._observe.dot(views[-2], s_update)  # the method: no dispatch
        if self._per_joint:
            self._per_joint_gains(s_update, s_block, views[-1])
        if settling:  # else a non-finite filter shows in the excursions
            if not math.isfinite(sum(s_filters.tolist())) and not _finite(s_filters).all():
                fl.pending = time
                return FAULT_OBSERVER
            out[0] = s_block[R]
            out[1:] = math.nan
        elif self._constant:  # [−r̂, r̂] − [−L, U]; the verdict's rows r̂, L, U are the block's
            negated, pair, flat = bounds.constant_parts
            _subtract(s_rows, negated, pair)
            out[...] = s_out
            excursions = flat.tolist()  # L − r̂, then r̂ − U, per joint
            if not sum(excursions) < math.inf:  # NaN or +∞ only from a non-finite r̂
                fl.pending = time
                return FAULT_OBSERVER
        else:  # S @ (G ∘ x) of Bounds; the verdict's rows and the excursions
            gains, scaled, sums, rows, bounds_rows, whole, flat = bounds.parts
            _multiply(gains, s_rows, scaled)
            sums.dot(scaled, rows)
            if whole:
                out[...] = bounds_rows
            else:
                out[0] = s_block[R]
                out[1:] = bounds_rows
            excursions = flat.tolist()  # r̂ − U, then L − r̂, per joint
            total = sum(excursions)  # NaN or +inf: a non-finite filter or bound
            if not total < math.inf:
                if not _finite(s_filters).all():
                    fl.pending = time
                    return FAULT_OBSERVER
                if _isnan(out[1:]).any():
                    fl.pending = time
                    return FAULT_BOUNDS
        # The sample was good from end to end: commit.
        closed: tuple[float, ...] = ()
        if restart:
            if fl.has_stream and fl.has_detector:
                closed = self._rules.lasted(fl)
            fl.has_stream, fl.start, fl.has_detector = True, time, False
        if settling:
            code = SETTLING
        else:
            if not fl.has_detector:
                fl.has_detector, fl.outside, fl.open = True, False, False
            worst = max(excursions)
            if worst > 0.0 or fl.open or (fl.latched and self._release == self._release):
                code, closed = self._rules(fl, time, worst, excursions, out, closed)
            else:  # inside the bounds, nothing open, no release to watch
                fl.outside = False
                code = COLLISION if fl.latched else OK
        fl.t_last = fl.floor = time
        fl.pending = -math.inf
        self._committed, self._scratch = scratch, committed
        self._closed = closed
        return code | EVENT if closed else code

    def _per_joint_gains(
        self, s_update: FloatArray, s_block: FloatArray, block: FloatArray
    ) -> None:
        """The filters y′ = w · input + a · y of per-joint gains (the product gave the inputs):
        the observer's (rows R … SG) and the bins' (BIN) when not all joints have the same."""
        if self._gains is not None:
            weight, pole = self._gains
            filtered = s_update[R - P : SG - P + 1]
            filtered *= weight
            filtered += pole * block[R : SG + 1]
        if self._bin_gains is not None:
            weight, pole = self._bin_gains
            s_block[BIN] *= weight
            s_block[BIN] += pole * block[BIN]

    def _sample_step(
        self, time: float, q: Any, tau_m: Any, tau_j: Any, model: Any, buffers: Any, out: FloatArray
    ) -> int:
        """:meth:`_step` of a sample without a measured velocity, as the user gave it.

        As ``fused_step_sample`` of the compiled stream: ``UNJUDGED``, with
        nothing changed, unless ``time`` is finite and the samples are float64
        arrays of shape (n_dof,), contiguous (``tau_j`` is ``tau_m`` for the
        motor-torque observer); the caller's checks then say why.
        """
        shape = self._shape
        if (
            tau_j is tau_m and type(q) is _ndarray and type(tau_m) is _ndarray
            and q.dtype is _FLOAT and tau_m.dtype is _FLOAT and q.shape == shape == tau_m.shape
            and q.strides == _STRIDES == tau_m.strides and time - time == 0.0
        ):  # fmt: skip
            return self._step(time, q, _EMPTY, tau_m, tau_j, out)  # the common sample
        for x in (q, tau_m) if tau_j is tau_m else (q, tau_m, tau_j):
            # ``is`` first: an unpickled array's dtype is an equal copy, not the same object
            if not (
                type(x) is _ndarray and (x.dtype is _FLOAT or x.dtype == _FLOAT)
                and x.shape == shape and x.strides == _STRIDES
            ):  # fmt: skip
                return UNJUDGED
        if not math.isfinite(time):
            return UNJUDGED
        return self._step(time, q, _EMPTY, tau_m, tau_j, out)

    def _terms(self, q: FloatArray, v: FloatArray, views: tuple[FloatArray, ...]) -> None:
        """p + g, Cᵀq̇, g, sign and the friction rows at (q, ``v``) into the rows P1 … FC.

        ``views`` are those of an observer block (:func:`_block_views`).
        """
        model, data, zero = self._pin
        views[0][...] = _rnea(model, data, q, zero, v)  # p + g
        _coriolis(model, data, q, v).T.dot(v, views[1])
        views[2][...] = _gravity(model, data, q)
        _sign(v, views[3])
        if self._friction_on:
            self._friction_rows(v, views)

    def _friction_rows(self, v: FloatArray, views: tuple[FloatArray, ...]) -> None:
        """The rows FA … FC (their sum is τ̂_fr(``v``)) and the sign² and q̇ rows they use."""
        if self._friction_kind == "basis":  # views: sign, sign², q̇, the basis, the friction rows
            _multiply(views[3], views[3], views[4])
            views[5][...] = v
            _multiply(views[6], self._basis, views[7])
        elif self._friction_kind == "model":
            views[8][...] = self._friction(v)

    def _initial(self, q: FloatArray, v: FloatArray, block: FloatArray) -> None:
        """The observer's state at a (re)start at (q, ``v``) into the rows P … SG of ``block``."""
        terms = np.zeros_like(block)
        self._terms(q, v, block_views(terms))
        start_rows(terms, block, self._tau)

    # ------------------------------------------------------------------ interface
    def run(
        self,
        time: float,
        sample: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
        out: FloatArray,
        method: str,
    ) -> tuple[str, tuple[int, ...], Event | None]:
        """One sample of the stream, as :meth:`~._fused.FusedStream.run`.

        ``sample`` is (q, qd, tau_m, tau_j), ``qd`` empty without a measured
        velocity; ``out`` (3, n_dof) receives the residual and the bounds [N m]
        (NaN bounds while settling). Returns the status ("ok", "collision",
        "settling") or, for a fault, what was refused (an entry of
        :data:`~._codes.REASONS`); the joints outside their bounds; the event that
        closed at the sample (found by ``method``), if any.
        """
        return self.decoded(self._step(time, *sample, out), method)

    def closed(self, method: str) -> Event:
        """The event that closed at the last sample run (its code has ``EVENT``)."""
        return event_of(self._closed, method)

    def block(
        self,
        t: FloatArray,
        sample: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
        method: str,
    ) -> tuple[np.ndarray, FloatArray, list[Event]]:
        """A whole log as a fresh stream, sample by sample, as :meth:`~._fused.FusedStream.block`.

        ``t`` (n_samples,) [s]; ``sample`` is (q, qd, tau_m, tau_j), each
        (n_samples, n_dof), ``qd`` (n_samples, 0) without a measured velocity.
        Returns the codes per sample; the series (7, n_samples, n_dof): the
        residual, lower and upper bounds [N m], the filtered model torque,
        friction [N m] and sign, and the velocity [rad/s] (NaN at faults, but
        the velocity of a "qd" fault); the events, the one still open at the
        end included. The live stream's state is left alone.
        """
        q, qd, tau_m, tau_j = sample
        n_samples, n = q.shape
        saved = self._save()
        self.reset()
        try:
            series = np.full((7, n_samples, n), np.nan)
            codes = np.zeros(n_samples, dtype=np.int64)
            events: list[Event] = []
            out = np.empty((3, n))
            for k in range(n_samples):
                code = self._step(float(t[k]), q[k], qd[k], tau_m[k], tau_j[k], out)
                codes[k] = code
                if code == FAULT_VELOCITY:  # the estimate its message names
                    series[6, k] = self._velocity_row
                if code & 15 >= FAULT:
                    continue
                series[:3, k] = out
                series[3:, k] = self.threshold_rows()
                if code & EVENT:
                    events.append(event_of(self._closed, method))
            last = self.finish(method)
        finally:
            self._restore(saved)
        return codes, series, events if last is None else [*events, last]

    @property
    def floor(self) -> float:
        """No sample may come at or before this time [s]."""
        return self._flags.floor

    @property
    def last(self) -> float:
        """Time of the last accepted sample [s]."""
        return self._flags.t_last

    @property
    def latched(self) -> bool:
        """Whether a collision is latched."""
        return self._flags.latched

    @property
    def velocity(self) -> FloatArray:
        """The velocity estimate of the last sample run, accepted or not [rad/s]."""
        return self._velocity_row.copy()

    def threshold_rows(self) -> FloatArray:
        """The observer's model torque, filtered friction and sign [N m, N m, -] and the
        velocity [rad/s] of the last accepted sample, shape (4, n_dof) (a copy)."""
        return self._committed[10][[H, F, SG, V]]

    def refuse(self, time: float) -> None:
        """Record a sample refused before :meth:`run` (the gap rule's pending time)."""
        self._flags.pending = time

    def finish(self, method: str) -> Event | None:
        """Close the open event at the end of the stream, as ``Detector.finish``."""
        fl = self._flags
        if not (fl.has_stream and fl.has_detector):
            return None
        fields = self._rules.lasted(fl)
        fl.open = fl.outside = False
        return event_of(fields, method) if fields else None


# Bound once: each module attribute lookup costs as much as a line of arithmetic.
_subtract, _divide, _less_equal, _add = np.subtract, np.divide, np.less_equal, np.add
_multiply, _sign = np.multiply, np.sign
_finite, _isnan = np.isfinite, np.isnan
_ndarray, _FLOAT, _STRIDES, _EMPTY = np.ndarray, np.dtype(np.float64), (8,), np.empty(0)
_rnea, _coriolis, _gravity = pin.rnea, pin.computeCoriolisMatrix, pin.computeGeneralizedGravity
