"""The drift adapter inside the compiled stream: its parameters and state in the flat arrays.

:func:`adapt` runs ``FrictionAdapter._step_checked`` (by ``compiled_rows`` of
:mod:`sensorless.observers._adaptive_kernel`) on one sample of
:mod:`sensorless.monitor._compiled`; :func:`adapter_restart` restarts its
filters with the observer. Units SI and radians.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from .._validation import FloatArray
from ..observers._adaptive_kernel import compiled_rows as adapter_rows
from ..robots._numba_views import view
from ._layout import ADAPT_AT, MODEL_TORQUE, RESIDUAL, VELOCITY

__all__ = ["adapt", "adapter_restart"]


@njit(cache=True)
def _adapter_parts(model: FloatArray, region: FloatArray, n: int) -> Any:
    """The drift adapter's parameters (read from ``model``) and state (views of ``region``).

    At ``model[ADAPT_AT]``: λ, max_trace and the number of columns m (the
    ``scalars`` of the adapter), then pole, weight, v_s, max_correction and
    rate·dt (n each), the norm weights and the box (n × m each). ``region``
    (one copy of the state): θ and the RLS estimate (n × m each), P
    (n × m × m), φ (n × 3), ψ (n × m), δτ, F(δτ), the update counts (n each)
    and the started flag. These are the arguments of
    :func:`sensorless.observers._adaptive_kernel.advance_block`.
    """
    at = int(model[ADAPT_AT])
    m = int(model[at + 2])
    scalars = model[at : at + 3]
    p = at + 3
    pole, weight, v_s = model[p : p + n], model[p + n : p + 2 * n], model[p + 2 * n : p + 3 * n]
    max_corr, step_bound = model[p + 3 * n : p + 4 * n], model[p + 4 * n : p + 5 * n]
    p += 5 * n
    norm_w = view(model[p : p + n * m], (n, m))
    box = view(model[p + n * m : p + 2 * n * m], (n, m))
    theta = view(region[: n * m], (n, m))
    estimate = view(region[n * m : 2 * n * m], (n, m))
    r = 2 * n * m
    cov = view(region[r : r + n * m * m], (n, m, m))
    r += n * m * m
    reg = view(region[r : r + 3 * n], (n, 3))
    freg = view(region[r + 3 * n : r + (3 + m) * n], (n, m))
    r += (3 + m) * n
    corr, fcorr = region[r : r + n], region[r + n : r + 2 * n]
    updates, started = region[r + 2 * n : r + 3 * n], region[r + 3 * n : r + 3 * n + 1]
    state = (theta, estimate, cov, reg, freg, corr, fcorr)
    params = (pole, weight, v_s, max_corr, norm_w, box, step_bound)
    return state, started, updates, params, scalars


@njit(cache=True)
def adapter_restart(model: FloatArray, region: FloatArray, n: int) -> None:
    """``FrictionAdapter.restart`` in place: φ, ψ, δτ, F(δτ) and the started flag to zero."""
    if model[ADAPT_AT] == 0.0:
        return
    state, started, _, _, _ = _adapter_parts(model, region, n)
    _, _, _, reg, freg, corr, fcorr = state
    reg[:] = 0.0
    freg[:] = 0.0
    corr[:] = 0.0
    fcorr[:] = 0.0
    started[0] = 0.0


@njit(cache=True)
def adapt(model: FloatArray, region: Any, rows: Any, trusted: bool, out: Any) -> None:
    """The drift adapter on this sample: the corrected residual into ``out[0]``.

    ``FrictionAdapter._step_checked`` on the observer's r̂, the velocity
    and the filtered model torque h of ``rows``, learning only if ``trusted``;
    ``region`` is (the scratch copy of the adapter's state, the temporaries
    of ``advance_rows``).
    """
    n = rows.shape[1]
    state, started, updates, params, scalars = _adapter_parts(model, region[0], n)
    trust = np.full((1, n), trusted)
    adapter_rows(
        rows[RESIDUAL : RESIDUAL + 1], rows[VELOCITY : VELOCITY + 1],
        rows[MODEL_TORQUE : MODEL_TORQUE + 1], trust, state, started, updates, params,
        scalars, out[0:1], region[1],
    )  # fmt: skip
