"""One compiled (numba) function per stream sample: the stream of :mod:`.stream`, fused.

Importing this module requires numba; without it :class:`~sensorless.monitor.CollisionMonitor`
runs its Python stream. For one sample whose types and shapes
:func:`~sensorless._validation.as_sample` has checked, :func:`fused_step` does
what :meth:`CollisionMonitor.step` does with numbers, in the same order and
with the same arithmetic: the time and value rules of :mod:`.policy`; the
velocity cascade of the ``CausalEstimator`` (``_step_outputs``); p, Cᵀq̇ and
g by the O(n) recursion (``terms_at`` of :mod:`sensorless.robots._recursion_numba`)
and the update of ``MomentumObserver._step_checked``; after the settling
window, the drift adapter when the monitor has one
(``FrictionAdapter._step_checked``, by ``advance_rows`` of
:mod:`sensorless.observers._adaptive_kernel`), the bounds of the constant,
time-variant (forms "friction" and "hysteretic") and velocity-based
thresholds (their ``_process_checked``), the events of
``Detector._step_checked`` and the latch. The new state is written
to scratch rows and committed only when the sample was good from end to end:
a fault changes nothing but the time of the last refused sample (``PENDING``,
the gap rule's memory). Joints travel as bit masks (bit j: joint j + 1).
Units SI and radians.

Two flat float64 arrays per stream (packed by :class:`~sensorless.monitor._fused.FusedStream`),
sliced into views by the kernel, since each array argument costs about 0.1 µs per call
(the positions named below are in :mod:`._layout`):

``model`` (read-only)
    The header (``DT`` … ``GUARD``); the velocity sections (n_sections × 6)
    and their unit initial states (n_sections × 2); the velocity bin edges
    [rad/s]; ``const`` (n_dof, ``N_CONST``): per joint ``kernel_constants`` of
    the recursion (columns 0–27), then the columns named below; ``table``
    (3, n_bins, n_dof): τ̂_fme, L and U of the velocity-based threshold [N m];
    the drift adapter's parameters, if any (see ``_adapter_parts``).
``buffers``
    ``flags`` (3, ``N_FLAGS``): committed (0) and scratch (1) scalars, and the
    event that closed at the sample (2); ``state`` (2, n_rows, n_dof):
    committed and scratch rows, the estimator's section states from row
    ``SECTIONS`` on; ``work`` (n_dof, 23): scratch of ``terms_at``; with a
    drift adapter, its committed and scratch state and its temporaries.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit, types

from .._validation import FloatArray
from ..friction._static_kernel import sign, static_torque
from ..robots._numba_views import view
from ..robots._recursion_numba import terms_at
from ._codes import (
    COLLISION,
    EVENT,
    FAULT_BOUNDS,
    FAULT_EARLY,
    FAULT_GAP,
    FAULT_OBSERVER,
    FAULT_Q,
    FAULT_TAU_J,
    FAULT_TAU_M,
    FAULT_TIME,
    FAULT_VELOCITY,
    JOINTS_SHIFT,
    OK,
    SETTLING,
    UNJUDGED,
)
from ._compiled_adapter import adapt, adapter_restart

# isort: off
from ._layout import (
    ADAPT_AT, ADAPT_SIZE, ADAPT_STATE, BIN_POLE, BIN_STATE, BIN_WEIGHT, CENTRE, COEFFICIENT,
    CONST_AT, CONSTANT, COR_GRAVITY, DT, EARLY, EXTRA, FAMILY, FILTERED_FRICTION,
    FILTERED_SIGN, FLOOR, FRICTION, FRICTION_PARAMETERS, FRICTION_TORQUE, GAMMA, GAP, GUARD,
    HALF_RANGE, HAS_DETECTOR, HAS_STREAM, HEADER, HOLD, INSIDE_SINCE, JOINT, LATCHED,
    MIN_DURATION, MODEL_TORQUE, MOMENTUM, MONITORED, N_CONST, N_EDGES, N_FLAGS, N_SECTIONS,
    OPEN, OPEN_END, OPEN_JOINTS, OPEN_PEAK, OPEN_PEAK_RESIDUAL, OPEN_START, OUTSIDE, PENDING,
    POLE, QUIET_FROM, RELEASE, RESIDUAL, SECTIONS, SETTLE, SIGN, SPEED_LIMIT, START, T_LAST,
    TABLE_AT, TERMS, TIME_VARIANT, TORQUE, TORQUE_LIMIT, VELOCITY, VELOCITY_BINS, VISITED_HIGH,
    VISITED_LOW, WEIGHT, WIDTH,
)  # fmt: skip
# isort: on

__all__ = [
    "READ",
    "READ2",
    "SAMPLE_SIGNATURES",
    "SIGNATURE",
    "WRITE",
    "WRITE2",
    "bound",
    "cascade",
    "detect",
    "fused_step",
    "fused_step_sample",
    "observer_update",
    "step",
    "views_of",
]


# the arrays of the signatures: float64, C-contiguous, read-only or writable
READ = types.Array(types.float64, 1, "C", readonly=True)
READ2 = types.Array(types.float64, 2, "C", readonly=True)
WRITE, WRITE2 = types.Array(types.float64, 1, "C"), types.Array(types.float64, 2, "C")
SIGNATURE = types.int64(types.float64, READ, READ, READ, READ, READ, WRITE, WRITE2)
"""Arguments of :func:`fused_step`; writable arrays convert to its read-only types."""
SAMPLE_SIGNATURES = tuple(
    types.int64(types.float64, sample, sample, sample, READ, WRITE, WRITE2)
    for sample in (WRITE, READ)
)
"""Arguments of :func:`fused_step_sample`: writable samples and read-only ones (rows of a
``Log``), each an exact match for numba's dispatcher (a conversion costs it 0.2 µs a call)."""


@njit(cache=True)
def _copy(source: Any, target: Any) -> None:
    """``target[:] = source`` for 1-D arrays of one size, as a plain loop.

    numba's slice assignment goes through its broadcasting code, about three
    times the cost of this loop on the stream's small rows.
    """
    for i in range(source.shape[0]):
        target[i] = source[i]


@njit(cache=True)
def _copy_state(flags: Any, state: Any, source: int, target: int) -> None:
    """Flags and state rows ``source`` to ``target`` (0 committed, 1 scratch), by index.

    Indexing the arrays themselves, not views of their rows: each view costs
    numba a reference count and about 25 ns.
    """
    for i in range(flags.shape[1]):
        flags[target, i] = flags[source, i]
    for row in range(state.shape[1]):
        for j in range(state.shape[2]):
            state[target, row, j] = state[source, row, j]


@njit(cache=True)
def _close(source: FloatArray, min_duration: float, event: FloatArray) -> None:
    """Copy the open event of ``source`` to ``event`` if it lasted ``min_duration`` [s]."""
    if source[OPEN] != 0.0 and source[OPEN_END] - source[OPEN_START] >= min_duration:
        event[OPEN:N_FLAGS] = source[OPEN:N_FLAGS]


@njit(cache=True)
def _bin(model: FloatArray, v: float) -> int:
    """Velocity bin of ``v`` [rad/s] (``searchsorted(edges, v, "right") − 1``, clipped)."""
    n_edges = int(model[N_EDGES])
    base = HEADER + 8 * int(model[N_SECTIONS])  # after the sections and their unit states
    low, high = 0, n_edges
    while low < high:
        middle = (low + high) // 2
        if model[base + middle] <= v:
            low = middle + 1
        else:
            high = middle
    return min(max(low - 1, 0), n_edges - 2)


@njit(cache=True, inline="always")
def cascade(model: FloatArray, y: float, z: Any, first: int, j: int) -> float:
    """The velocity sections on ``y`` = q_j [rad] (state rows ``z[first:]``, column j, updated).

    Returns the cascade's output, the velocity estimate times dt [rad].
    """
    for k in range(int(model[N_SECTIONS])):
        b = HEADER + 6 * k
        z0, z1 = z[first + 2 * k, j], z[first + 2 * k + 1, j]
        out = model[b] * y + z0
        z[first + 2 * k, j] = model[b + 1] * y - model[b + 4] * out + z1
        z[first + 2 * k + 1, j] = model[b + 2] * y - model[b + 5] * out
        y = out
    return y


@njit(cache=True)
def _terms(q: FloatArray, const: FloatArray, s: Any, work: Any) -> None:
    """p, Cᵀq̇ and g at (q, the row ``VELOCITY`` of ``s``) into the rows ``TERMS`` of ``s``."""
    n = q.shape[0]
    velocity = s[VELOCITY : VELOCITY + 1]
    terms_at(0, view(q, (1, n)), velocity, const, work, view(s[TERMS:SECTIONS], (3, 1, n)))


@njit(cache=True)
def _restart(
    q: FloatArray, qd: FloatArray, const: FloatArray, model: FloatArray, s: FloatArray, work: Any
) -> None:
    """Initial estimator and observer states at ``q`` into the rows ``s``.

    The observer starts at the measured velocity ``qd`` when it has n_dof
    entries, else at rest (``MomentumObserver.initial_state``); the estimator
    always starts at rest.
    """
    n = q.shape[0]
    zi_at = HEADER + 6 * int(model[N_SECTIONS])
    kind = int(model[FRICTION])
    for j in range(n):
        s[VELOCITY, j] = qd[j] if qd.shape[0] == n else 0.0
    _terms(q, const, s, work)
    for j in range(n):
        v = s[VELOCITY, j]
        vg = s[TERMS + 1, j] - s[TERMS + 2, j]
        fr = static_torque(kind, const, j, FRICTION_PARAMETERS, v)
        s[MOMENTUM, j], s[COR_GRAVITY, j], s[FRICTION_TORQUE, j] = s[TERMS, j], vg, fr
        s[SIGN, j], s[TORQUE, j] = sign(v), fr - vg
        s[RESIDUAL, j], s[MODEL_TORQUE, j], s[FILTERED_FRICTION, j] = 0.0, -vg, fr
        s[FILTERED_SIGN, j] = sign(v)
        for row in range(2 * int(model[N_SECTIONS])):
            s[SECTIONS + row, j] = model[zi_at + row] * q[j]


@njit(cache=True, inline="always")
def observer_update(
    last: tuple[float, float, float, float, float], new: tuple[float, float, float, float],
    filtered: tuple[float, float, float, float], pole: float, weight: float, dt: float,
) -> tuple[float, float, float, float]:  # fmt: skip
    """The four first-order filters of ``MomentumObserver._step_checked`` for one joint.

    ``last`` is (p [N m s], Cᵀq̇ − g, τ̂_fr [N m], sign, τ [N m]) of the last
    sample, ``new`` the first four of this one, ``filtered`` the filters'
    states (r̂, h, τ̂_fr, sign): returns them updated.
    """
    p0, vg0, fr0, s0, tau0 = last
    p1, vg1, fr1, s1 = new
    r, h_f, f_f, s_f = filtered
    h = (p1 - p0) / dt - 0.5 * (vg0 + vg1)
    f = (fr0 + fr1) * 0.5
    g = (s0 + s1) * 0.5
    e = (h + f) - tau0
    return (
        weight * e + pole * r, weight * h + pole * h_f, weight * f + pole * f_f,
        weight * g + pole * s_f,
    )  # fmt: skip


@njit(cache=True)
def _observe(
    q: FloatArray,
    qd: FloatArray,
    tau: FloatArray,
    const: FloatArray,
    model: FloatArray,
    s: Any,
    work: Any,
    fresh: bool,
) -> bool:
    """Estimator, recursion and observer update in place on the rows ``s``; False if not finite.

    ``fresh``: the second sample of a stream, whose velocity estimate is the
    first one; the observer starts from it (``MomentumObserver.initial_state``).
    A measured velocity ``qd`` with n_dof entries replaces the estimate (the
    estimator still runs, so a stream may switch between the two).
    """
    n = q.shape[0]
    dt = model[DT]
    for j in range(n):
        y = cascade(model, q[j], s, SECTIONS, j)
        s[VELOCITY, j] = qd[j] if qd.shape[0] == n else y / dt
    for j in range(n):
        if not abs(s[VELOCITY, j]) <= const[j, SPEED_LIMIT]:
            return False
    _terms(q, const, s, work)
    kind = int(model[FRICTION])
    for j in range(n):
        v = s[VELOCITY, j]
        p1, vg1 = s[TERMS, j], s[TERMS + 1, j] - s[TERMS + 2, j]
        fr1 = static_torque(kind, const, j, FRICTION_PARAMETERS, v)
        s1 = sign(v)
        if fresh:
            s[MOMENTUM, j], s[COR_GRAVITY, j], s[FRICTION_TORQUE, j] = p1, vg1, fr1
            s[SIGN, j], s[TORQUE, j] = s1, fr1 - vg1
            s[RESIDUAL, j], s[MODEL_TORQUE, j] = 0.0, -vg1
            s[FILTERED_FRICTION, j], s[FILTERED_SIGN, j] = fr1, s1
        last = (s[MOMENTUM, j], s[COR_GRAVITY, j], s[FRICTION_TORQUE, j], s[SIGN, j], s[TORQUE, j])
        filtered = (s[RESIDUAL, j], s[RESIDUAL + 1, j], s[RESIDUAL + 2, j], s[RESIDUAL + 3, j])
        a, w = const[j, POLE], const[j, WEIGHT]
        filtered = observer_update(last, (p1, vg1, fr1, s1), filtered, a, w, dt)
        s[RESIDUAL, j], s[MODEL_TORQUE, j], s[FILTERED_FRICTION, j], s[FILTERED_SIGN, j] = filtered
        s[MOMENTUM, j], s[COR_GRAVITY, j], s[FRICTION_TORQUE, j] = p1, vg1, fr1
        s[SIGN, j], s[TORQUE, j] = s1, tau[j]
    for row in range(RESIDUAL, RESIDUAL + 4):
        for j in range(n):
            if not math.isfinite(s[row, j]):
                return False
    return True


@njit(cache=True, inline="always")
def bound(
    const: FloatArray, table: FloatArray, model: FloatArray, j: int,
    signals: tuple[float, float, float, float], held: float, start: bool,
) -> tuple[float, float, float]:  # fmt: skip
    """Lower and upper bound of joint j [N m], and the velocity-bin filter's new state.

    ``signals`` are joint j's filtered model torque h [N m], velocity [rad/s],
    filtered friction [N m] and filtered sign; ``held`` is the velocity-bin
    filter's state [N m] (returned as it is by the other families).
    """
    family = int(model[FAMILY])
    h, v, filtered_friction, filtered_sign = signals
    if family == CONSTANT:
        upper = const[j, WIDTH]
        lower = -upper
    elif family == VELOCITY_BINS:
        k = _bin(model, v)
        friction = table[0, k, j] if start else held  # start: this bin held since forever
        held = const[j, BIN_WEIGHT] * table[0, k, j] + const[j, BIN_POLE] * friction
        centre = const[j, GAMMA] * h + friction
        lower = table[1, k, j] + centre
        upper = table[2, k, j] + centre
        if model[EXTRA] > 0.0 and (v < const[j, VISITED_LOW] or v >= const[j, VISITED_HIGH]):
            lower = lower - model[EXTRA]
            upper = upper + model[EXTRA]
    else:
        if family == TIME_VARIANT:
            centre = const[j, GAMMA] * h + const[j, COEFFICIENT] * filtered_friction
        else:
            centre = const[j, GAMMA] * h - const[j, COEFFICIENT] * filtered_sign
        lower = centre - const[j, WIDTH]
        upper = centre + const[j, WIDTH]
    if const[j, MONITORED] == 0.0:
        lower, upper = -np.inf, np.inf
    return lower, upper, held


@njit(cache=True)
def _bounds(
    const: FloatArray, table: FloatArray, model: FloatArray, s: Any, start: bool, out: Any
) -> bool:
    """Bounds of the threshold into out[1], out[2]; False if one is NaN."""
    for j in range(s.shape[1]):
        signals = (s[MODEL_TORQUE, j], s[VELOCITY, j], s[FILTERED_FRICTION, j], s[FILTERED_SIGN, j])
        lower, upper, held = bound(const, table, model, j, signals, s[BIN_STATE, j], start)
        s[BIN_STATE, j] = held
        if math.isnan(lower) or math.isnan(upper):
            return False
        out[1, j], out[2, j] = lower, upper
    return True


@njit(cache=True)
def detect(
    time: float, const: FloatArray, model: FloatArray, out: Any, new: Any, event: Any
) -> int:
    """``Detector._step_checked`` and the latch on the flags ``new``: status | joints mask.

    ``out`` (3, n_dof) holds the residual, lower and upper bound [N m] of the sample.
    """
    mask, best, worst = 0, -1, 0.0
    for j in range(out.shape[1]):
        if const[j, MONITORED] != 0.0:
            excursion = max(out[0, j] - out[2, j], out[1, j] - out[0, j])
            if excursion > 0.0:
                mask |= 1 << j
            if best < 0 or excursion > worst:
                best, worst = j, excursion
    if mask:
        if new[OPEN] != 0.0 and (new[OUTSIDE] != 0.0 or time - new[OPEN_END] < model[HOLD]):
            new[OPEN_END] = time
            new[OPEN_JOINTS] = float(int(new[OPEN_JOINTS]) | mask)
            if not worst <= new[OPEN_PEAK]:
                new[OPEN_PEAK], new[OPEN_PEAK_RESIDUAL] = worst, out[0, best]
        else:
            _close(new, model[MIN_DURATION], event)
            new[OPEN], new[OPEN_START], new[OPEN_END] = 1.0, time, time
            new[OPEN_JOINTS], new[OPEN_PEAK], new[OPEN_PEAK_RESIDUAL] = (
                mask,
                worst,
                out[0, best],
            )
    elif new[OPEN] != 0.0 and time - new[OPEN_END] >= model[HOLD]:
        _close(new, model[MIN_DURATION], event)
        new[OPEN] = 0.0
    new[OUTSIDE] = 1.0 if mask else 0.0
    confirmed = mask != 0 and new[OPEN] != 0.0 and time - new[OPEN_START] >= model[MIN_DURATION]
    if confirmed:
        new[LATCHED], new[INSIDE_SINCE] = 1.0, np.nan
        return COLLISION | mask << JOINTS_SHIFT
    if new[LATCHED] != 0.0 and not math.isnan(model[RELEASE]):
        if mask:
            new[INSIDE_SINCE] = np.nan
        elif math.isnan(new[INSIDE_SINCE]):
            new[INSIDE_SINCE] = time
        if time - new[INSIDE_SINCE] >= model[RELEASE]:
            new[LATCHED], new[INSIDE_SINCE] = 0.0, np.nan
    status = COLLISION if new[LATCHED] != 0.0 else OK
    return status | mask << JOINTS_SHIFT


@njit(cache=True)
def views_of(model: FloatArray, buffers: FloatArray, n: int) -> Any:
    """``const``, ``table``, ``flags``, ``state``, ``work``, ``adapter``: views of the two arrays.

    ``adapter``: the drift adapter's committed state, its scratch state and
    the temporaries of ``advance_rows``, all empty without adaptation (see
    :func:`_adapt`).
    """
    n_rows = SECTIONS + 2 * int(model[N_SECTIONS])
    table_at = int(model[TABLE_AT])
    const = view(model[int(model[CONST_AT]) : table_at], (n, N_CONST))
    table_end = int(model[ADAPT_AT]) if model[ADAPT_AT] > 0.0 else model.shape[0]
    table = view(model[table_at:table_end], (3, (table_end - table_at) // (3 * n), n))
    flags = view(buffers[: 3 * N_FLAGS], (3, N_FLAGS))
    end = 3 * N_FLAGS + 2 * n_rows * n
    state = view(buffers[3 * N_FLAGS : end], (2, n_rows, n))
    size = int(model[ADAPT_SIZE])
    adapter_at = int(model[ADAPT_STATE])
    region = buffers[adapter_at:]
    adapter = (region[:size], region[size : 2 * size], region[2 * size :])
    return const, table, flags, state, view(buffers[end : end + 23 * n], (n, 23)), adapter


@njit(cache=True)
def fused_step(
    time: float,
    q: FloatArray,
    qd: FloatArray,
    tau_m: FloatArray,
    tau_j: FloatArray,
    model: FloatArray,
    buffers: FloatArray,
    out: FloatArray,
) -> int:
    """One sample of the stream; returns status | ``EVENT`` | joints mask << ``JOINTS_SHIFT``.

    ``time`` [s] is finite; ``q`` [rad], ``tau_m`` and ``tau_j`` [N m] have
    shape (n_dof,) (``tau_j`` is ``tau_m`` for the motor-torque observer);
    ``qd`` [rad/s] is the measured velocity, shape (n_dof,), or empty to use
    the estimate. ``out`` (3, n_dof) receives the residual and the bounds
    [N m] (NaN bounds while settling).
    """
    return step(time, (q, qd, tau_m, tau_j), model, views_of(model, buffers, q.shape[0]), out)


@njit(cache=True)
def fused_step_sample(
    time: float,
    q: FloatArray,
    tau_m: FloatArray,
    tau_j: FloatArray,
    model: FloatArray,
    buffers: FloatArray,
    out: Any,
) -> int:
    """:func:`fused_step` of a sample without a measured velocity, as the user gave it.

    The stream's common sample, called through numba's dispatcher so that
    its signatures check the types (float64, 1-D, C-contiguous): this
    function checks the rest that :func:`~sensorless._validation.as_sample`
    would, the shapes, and that ``time`` is finite. ``tau_j`` is ``tau_m``
    for the motor-torque observer. It returns ``UNJUDGED``, with nothing
    changed, for a sample it does not judge (the Python side then says
    why); otherwise what :func:`fused_step` returns.
    """
    n = out.shape[1]
    if q.shape[0] != n or tau_m.shape[0] != n or tau_j.shape[0] != n or not math.isfinite(time):
        return UNJUDGED
    return step(time, (q, q[:0], tau_m, tau_j), model, views_of(model, buffers, n), out)


@njit(cache=True)
def step(time: float, sample: Any, model: FloatArray, views: Any, out: FloatArray) -> int:
    """:func:`fused_step` on the ``views`` of its two flat arrays."""
    q, qd, tau_m, tau_j = sample
    const, table, flags, state, work, adapter = views
    n = q.shape[0]
    old = flags[0]
    if time <= old[FLOOR]:
        return FAULT_TIME
    for j in range(n):
        if not abs(q[j] - const[j, CENTRE]) <= const[j, HALF_RANGE]:
            old[PENDING] = time
            return FAULT_Q
    for j in range(n):
        if not abs(tau_m[j]) <= const[j, TORQUE_LIMIT]:
            old[PENDING] = time
            return FAULT_TAU_M
    joint = model[JOINT] != 0.0
    for j in range(n if joint else 0):
        if not abs(tau_j[j]) <= const[j, TORQUE_LIMIT]:
            old[PENDING] = time
            return FAULT_TAU_J
    restart = old[HAS_STREAM] == 0.0
    if not restart:
        step = time - old[T_LAST]
        if step < model[EARLY]:
            return FAULT_EARLY
        if step > model[GAP]:
            if model[EARLY] <= time - old[PENDING] <= model[GAP]:
                restart = True  # the stream resumed after a real gap
            else:
                old[PENDING] = time
                return FAULT_GAP
    new, event, rows = flags[1], flags[2], state[1]
    _copy_state(flags, state, 0, 1)  # scratch = committed; a restart rewrites the rows it uses
    adapting = model[ADAPT_AT] > 0.0
    if adapting:
        _copy(adapter[0], adapter[1])
    event[OPEN] = 0.0
    if restart:
        if old[HAS_STREAM] != 0.0 and old[HAS_DETECTOR] != 0.0:
            _close(old, model[MIN_DURATION], event)
        _restart(q, qd, const, model, rows, work)
        new[HAS_STREAM], new[START], new[HAS_DETECTOR] = 1.0, time, 0.0
        new[QUIET_FROM] = -np.inf
    fresh = not restart and old[T_LAST] == old[START]
    if restart or fresh:  # the adapter's filters start with the observer; what it learned stays
        adapter_restart(model, adapter[1], n)
    if not _observe(q, qd, tau_j if joint else tau_m, const, model, rows, work, fresh):
        old[PENDING] = time
        for j in range(n):
            if not abs(rows[VELOCITY, j]) <= const[j, SPEED_LIMIT]:
                return FAULT_VELOCITY
        return FAULT_OBSERVER
    settling = time - new[START] < model[SETTLE]
    if adapting:
        trusted = not settling and old[LATCHED] == 0.0 and time >= new[QUIET_FROM]
        adapt(model, adapter[1:], rows, trusted, out)
    else:
        for j in range(n):
            out[0, j] = rows[RESIDUAL, j]
    if settling:
        for j in range(n):
            out[1, j], out[2, j] = np.nan, np.nan
        code = SETTLING
    else:
        start = new[HAS_DETECTOR] == 0.0
        if start:
            new[HAS_DETECTOR], new[OUTSIDE], new[OPEN] = 1.0, 0.0, 0.0
        if not _bounds(const, table, model, rows, start, out):
            old[PENDING] = time
            return FAULT_BOUNDS
        code = detect(time, const, model, out, new, event)
    if code >> JOINTS_SHIFT != 0 or code & 15 == COLLISION:
        new[QUIET_FROM] = time + model[GUARD]
    new[T_LAST], new[FLOOR], new[PENDING] = time, time, -np.inf
    _copy_state(flags, state, 1, 0)
    if adapting:
        _copy(adapter[1], adapter[0])
    return code | (EVENT if event[OPEN] != 0.0 else 0)
