"""The compiled stream over a whole log: runs of plain samples by phases, the rest sample by sample.

:func:`fused_block` gives, for every row of a log, what
:func:`~sensorless.monitor._compiled.fused_step` gives on a fresh stream, bit for
bit. Most samples of a log are *plain*: the stream is running (neither its
first nor its second sample), the time step is inside the ``early``/``gap``
rules and q, τ_m, τ_J inside their limits.
A run of up to ``chunk`` plain samples goes through :func:`_plain_run` in
phases, each a tight loop over the run with the stream's own arithmetic:

1. the velocity cascade, sample by sample, and its limit;
2. p, Cᵀq̇ and g of the whole run by the O(n) recursion (``terms_at``);
3. the momentum observer and the threshold's bounds, joint by joint over the
   run (the observer's four filters are first-order recursions,
   r_k = a·r_{k−1} + b·u_k, and so is the velocity-bin filter), and their
   finiteness;
4. detector and latch, sample by sample, with a verdict per sample.

The state is committed once, at the last sample of the run, instead of
being copied to scratch rows and back at every sample. A sample a phase
refuses (a velocity beyond its limit, a non-finite observer output, a NaN
bound) ends the run before it; that sample and every sample that is not
plain (faults, restarts, the drift adapter) go through the per-sample kernel,
which judges them as the stream does. Units SI and radians.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit, types

from .._validation import FloatArray
from ..friction._static_kernel import sign, static_torque
from ..robots._recursion_numba import terms_at
from ._codes import COLLISION, EVENT, FAULT, FAULT_VELOCITY, JOINTS_SHIFT, SETTLING
from ._compiled import (
    READ,
    READ2,
    WRITE,
    WRITE2,
    bound,
    cascade,
    detect,
    observer_update,
    step,
    views_of,
)
from ._layout import (
    ADAPT_AT,
    BIN_STATE,
    CENTRE,
    COR_GRAVITY,
    DT,
    EARLY,
    FILTERED_FRICTION,
    FILTERED_SIGN,
    FLOOR,
    FRICTION,
    FRICTION_PARAMETERS,
    FRICTION_TORQUE,
    GAP,
    GUARD,
    HALF_RANGE,
    HAS_DETECTOR,
    HAS_STREAM,
    JOINT,
    MODEL_TORQUE,
    MOMENTUM,
    N_FLAGS,
    N_SECTIONS,
    OPEN,
    OPEN_START,
    OUTSIDE,
    PENDING,
    POLE,
    QUIET_FROM,
    RESIDUAL,
    SECTIONS,
    SETTLE,
    SIGN,
    SPEED_LIMIT,
    START,
    T_LAST,
    TERMS,
    TORQUE,
    TORQUE_LIMIT,
    VELOCITY,
    WEIGHT,
)

__all__ = ["BLOCK_SIGNATURE", "CHUNK", "fused_block"]

CHUNK = 128
"""Longest run of plain samples done by phases (its p, Cᵀq̇, g stay in cache)."""
BLOCK_SIGNATURE = types.void(
    READ, READ2, READ2, READ2, READ2, READ, WRITE,
    types.Array(types.float64, 3, "C"), types.Array(types.int64, 1, "C"),
    WRITE2, types.int64,
)  # fmt: skip
"""Arguments of :func:`fused_block`."""


@njit(cache=True)
def fused_block(
    t: FloatArray,
    q: FloatArray,
    qd: FloatArray,
    tau_m: FloatArray,
    tau_j: FloatArray,
    model: FloatArray,
    buffers: FloatArray,
    series: FloatArray,
    codes: Any,
    events: FloatArray,
    chunk: int,
) -> None:
    """:func:`fused_step` over the rows of a block: the batch monitor is the stream.

    ``t`` (n_samples,) [s]; ``q``, ``tau_m``, ``tau_j`` (n_samples, n_dof);
    ``qd`` (n_samples, n_dof) measured [rad/s] or (n_samples, 0). Per sample,
    ``codes`` receives the return code, ``series`` (7, n_samples, n_dof) the
    residual, lower and upper bounds, and the observer's filtered model
    torque, friction, sign and velocity (NaN left at faults but the velocity
    of a ``FAULT_VELOCITY``), and ``events``
    (n_samples, 5) the event closed there (start, end, joints mask, peak,
    peak residual) when the code has ``EVENT``. ``chunk``: the longest run
    of plain samples done by phases; 0 runs every sample through the
    per-sample kernel (the same results).
    """
    n = q.shape[1]
    views = views_of(model, buffers, n)
    flags, state = views[2], views[3]
    out = np.empty((3, n))
    terms = np.empty((3, max(chunk, 1), n))
    held = np.empty((max(chunk, 1), n))
    sections = np.empty((2 * int(model[N_SECTIONS]), n))
    phased = chunk > 0 and model[ADAPT_AT] == 0.0
    k = 0
    while k < t.shape[0]:
        old = flags[0]
        if phased and old[HAS_STREAM] != 0.0 and old[T_LAST] != old[START]:
            done = _plain_run(
                k, (t, q, qd, tau_m, tau_j), model, views, (series, codes, events),
                (terms, sections, held, out),
            )  # fmt: skip
            if done:
                k += done
                continue
        code = step(t[k], (q[k], qd[k], tau_m[k], tau_j[k]), model, views, out)
        codes[k] = code
        if code == FAULT_VELOCITY:  # the estimate its message names
            series[6, k] = state[1, VELOCITY]
        if code & 15 < FAULT:
            for j in range(n):  # loops: numba's slice assignment costs more than the copies
                series[0, k, j], series[1, k, j] = out[0, j], out[1, j]
                series[2, k, j] = out[2, j]
                series[3, k, j] = state[0, MODEL_TORQUE, j]
                series[4, k, j] = state[0, FILTERED_FRICTION, j]
                series[5, k, j] = state[0, FILTERED_SIGN, j]
                series[6, k, j] = state[0, VELOCITY, j]
            if code & EVENT:
                events[k] = flags[2, OPEN_START:N_FLAGS]
        k += 1


@njit(cache=True)
def _plain_run(k0: int, log: Any, model: FloatArray, views: Any, results: Any, scratch: Any) -> int:
    """The plain samples from ``k0`` on (at most ``chunk``), by phases; returns how many.

    ``log`` is (t, q, qd, tau_m, tau_j), ``results`` (series, codes, events)
    of :func:`fused_block`, ``scratch`` (terms (3, chunk, n), section states
    (2 n_sections, n), velocity-bin filter states (chunk, n), one sample's
    residual and bounds (3, n)). The committed
    state is that after the last sample done; 0 done changes nothing.
    """
    t, q, qd, tau_m, tau_j = log
    series = results[0]
    terms, sections, held, out = scratch
    const, table, flags, state, work, _ = views
    old, rows = flags[0], state[0]
    n, n_rows = q.shape[1], sections.shape[0]
    plain = _phase_rules(k0, min(k0 + terms.shape[1], t.shape[0]), log, model, const, old)
    for row in range(n_rows):
        for j in range(n):
            sections[row, j] = rows[SECTIONS + row, j]
    velocity = series[6]
    stop = reach = _phase_velocity(k0, plain, q, qd, model, const, sections, velocity)
    if stop == k0:
        return 0
    run_q, run_velocity = q[k0:stop], velocity[k0:stop]
    for i in range(stop - k0):
        terms_at(i, run_q, run_velocity, const, work, terms)
    tau = tau_j if model[JOINT] != 0.0 else tau_m
    stop = _phase_observer(
        k0, stop, (t, tau), model, (const, table), (old, rows), terms, series, held
    )
    _phase_detector(k0, stop, t, model, const, (old, flags[2]), results, out)
    valid = stop - k0
    if valid == 0:
        _forget(k0, reach, series)
        return 0
    last = stop - 1
    kind = int(model[FRICTION])
    for j in range(n):
        v = velocity[last, j]
        rows[VELOCITY, j] = v
        p1, vg1 = terms[0, valid - 1, j], terms[1, valid - 1, j] - terms[2, valid - 1, j]
        rows[TERMS, j], rows[TERMS + 1, j] = p1, terms[1, valid - 1, j]
        rows[TERMS + 2, j] = terms[2, valid - 1, j]
        rows[MOMENTUM, j], rows[COR_GRAVITY, j] = p1, vg1
        rows[FRICTION_TORQUE, j] = static_torque(kind, const, j, FRICTION_PARAMETERS, v)
        rows[SIGN, j], rows[TORQUE, j] = sign(v), tau[last, j]
        rows[RESIDUAL, j], rows[MODEL_TORQUE, j] = series[0, last, j], series[3, last, j]
        rows[FILTERED_FRICTION, j], rows[FILTERED_SIGN, j] = series[4, last, j], series[5, last, j]
        rows[BIN_STATE, j] = held[valid - 1, j]
    if stop == plain:  # phase 1 ended there
        for row in range(n_rows):
            for j in range(n):
                rows[SECTIONS + row, j] = sections[row, j]
    else:  # a later sample was refused: the sections after the last one done, run again
        for k in range(k0, stop):
            for j in range(n):
                cascade(model, q[k, j], rows, SECTIONS, j)
    _forget(stop, reach, series)
    return valid


@njit(cache=True)
def _phase_rules(
    k0: int, stop: int, log: Any, model: FloatArray, const: FloatArray, old: FloatArray
) -> int:
    """The first sample of [k0, stop) that is not plain for the time and value rules."""
    t, q, _, tau_m, tau_j = log
    n = q.shape[1]
    joint = model[JOINT] != 0.0
    last, floor = old[T_LAST], old[FLOOR]
    for k in range(k0, stop):
        time = t[k]
        if not time > floor:
            return k
        for j in range(n):
            if not abs(q[k, j] - const[j, CENTRE]) <= const[j, HALF_RANGE]:
                return k
            if not abs(tau_m[k, j]) <= const[j, TORQUE_LIMIT]:
                return k
            if joint and not abs(tau_j[k, j]) <= const[j, TORQUE_LIMIT]:
                return k
        step = time - last
        if not (step >= model[EARLY] and step <= model[GAP]):
            return k
        last = floor = time
    return stop


@njit(cache=True)
def _phase_velocity(
    k0: int, stop: int, q: FloatArray, qd: FloatArray, model: FloatArray, const: FloatArray,
    sections: Any, velocity: Any,
) -> int:  # fmt: skip
    """Phase 1: the velocity of [k0, stop) into ``velocity``; the first beyond its limit."""
    n = q.shape[1]
    dt = model[DT]
    measured = qd.shape[1] == n
    for k in range(k0, stop):
        for j in range(n):
            y = cascade(model, q[k, j], sections, 0, j)
            velocity[k, j] = qd[k, j] if measured else y / dt
        for j in range(n):
            if not abs(velocity[k, j]) <= const[j, SPEED_LIMIT]:
                for i in range(n):
                    velocity[k, i] = np.nan
                return k
    return stop


@njit(cache=True)
def _phase_observer(
    k0: int, stop: int, log: Any, model: FloatArray, parameters: Any, state: Any, terms: Any,
    series: Any, held: Any,
) -> int:  # fmt: skip
    """Phase 3: ``MomentumObserver._step_checked`` and the bounds of [k0, stop), joint by joint.

    ``log`` is (t, τ), ``parameters`` (const, table), ``state`` the committed
    (flags, rows), read and not written. The residual, the filtered model
    torque, friction and sign and the bounds go to ``series`` (rows 0, 3, 4,
    5 and 1, 2; NaN bounds while settling), the velocity-bin filter's state
    after each sample to ``held``. Returns the first sample with a non-finite
    observer output or a NaN bound (``stop`` if none).
    """
    t, tau = log
    const, table = parameters
    old, rows = state
    dt, settle = model[DT], old[START] + 0.0
    kind = int(model[FRICTION])
    velocity = series[6]
    for j in range(rows.shape[1]):
        p0, vg0 = rows[MOMENTUM, j], rows[COR_GRAVITY, j]
        fr0, s0, tau0 = rows[FRICTION_TORQUE, j], rows[SIGN, j], rows[TORQUE, j]
        r, h_f = rows[RESIDUAL, j], rows[MODEL_TORQUE, j]
        f_f, s_f = rows[FILTERED_FRICTION, j], rows[FILTERED_SIGN, j]
        bin_state, judged = rows[BIN_STATE, j], old[HAS_DETECTOR] != 0.0
        a, w = const[j, POLE], const[j, WEIGHT]
        for k in range(k0, stop):
            i = k - k0
            v = velocity[k, j]
            p1, vg1 = terms[0, i, j], terms[1, i, j] - terms[2, i, j]
            fr1 = static_torque(kind, const, j, FRICTION_PARAMETERS, v)
            s1 = sign(v)
            last = (p0, vg0, fr0, s0, tau0)
            r, h_f, f_f, s_f = observer_update(
                last, (p1, vg1, fr1, s1), (r, h_f, f_f, s_f), a, w, dt
            )
            series[0, k, j], series[3, k, j], series[4, k, j], series[5, k, j] = r, h_f, f_f, s_f
            finite = math.isfinite(r) and math.isfinite(h_f)
            if not (finite and math.isfinite(f_f) and math.isfinite(s_f)):
                stop = k
                break
            if t[k] - settle < model[SETTLE]:
                lower = upper = np.nan
            else:
                signals = (h_f, v, f_f, s_f)
                lower, upper, bin_state = bound(
                    const, table, model, j, signals, bin_state, not judged
                )
                judged = True
                if math.isnan(lower) or math.isnan(upper):
                    stop = k
                    break
            series[1, k, j], series[2, k, j], held[i, j] = lower, upper, bin_state
            p0, vg0, fr0, s0, tau0 = p1, vg1, fr1, s1, tau[k, j]
    return stop


@njit(cache=True)
def _phase_detector(
    k0: int, stop: int, t: FloatArray, model: FloatArray, const: FloatArray, flags: Any,
    results: Any, out: Any,
) -> None:  # fmt: skip
    """Phase 4: detector and latch of [k0, stop), sample by sample, on the committed flags.

    ``flags`` is (the committed flags, the kernel's row of the event closed
    at a sample); writes the codes and the closed events. ``out`` (3, n) is
    scratch for one sample's residual and bounds.
    """
    old, event = flags
    series, codes, events = results
    for k in range(k0, stop):
        time = t[k]
        event[OPEN] = 0.0
        if time - old[START] < model[SETTLE]:
            code = SETTLING
        else:
            if old[HAS_DETECTOR] == 0.0:
                old[HAS_DETECTOR], old[OUTSIDE], old[OPEN] = 1.0, 0.0, 0.0
            for j in range(out.shape[1]):
                out[0, j], out[1, j], out[2, j] = series[0, k, j], series[1, k, j], series[2, k, j]
            code = detect(time, const, model, out, old, event)
        if code >> JOINTS_SHIFT != 0 or code & 15 == COLLISION:
            old[QUIET_FROM] = time + model[GUARD]
        old[T_LAST], old[FLOOR], old[PENDING] = time, time, -np.inf
        if event[OPEN] != 0.0:
            code |= EVENT
            for c in range(N_FLAGS - OPEN_START):
                events[k, c] = event[OPEN_START + c]
        codes[k] = code


@njit(cache=True)
def _forget(k0: int, stop: int, series: Any) -> None:
    """NaN in every series of samples [k0, stop): a later phase refused them."""
    for row in range(series.shape[0]):
        for k in range(k0, stop):
            for j in range(series.shape[2]):
                series[row, k, j] = np.nan
