"""Tests of :mod:`sensorless.observers.adaptive` (the friction/offset adapter).

Independent checks:

* the synthetic residual is the observer's filter applied to a known δτ,
  computed with :func:`scipy.signal.lfilter` (not the adapter's recursion);
  with no limit active, the adapter's θ equals the exponentially weighted
  least-squares solution of :func:`scipy.linalg.lstsq` on the same data, and
  is close to the true θ;
* step = run = chunked, bit for bit;
* untrusted and non-finite samples leave θ and P exactly unchanged;
* the rate limit holds at every velocity of its range, and a push ramped over
  2 s, of the size of the demo's pushes, moves the correction by at most
  rate_limit × 2 s and stays in the corrected residual.
"""

from __future__ import annotations

import doctest
import importlib
from typing import Any

import numpy as np
import pytest
from scipy import linalg, signal

from sensorless import robots
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.observers import MomentumObserver
from sensorless.observers.adaptive import AdapterState, FrictionAdapter
from sensorless.simulation.collisions import Contact, Push

DT = 1e-3
GAIN = np.array([20.0, 30.0])
V_S = 0.02


def _filtered(x: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """The observer's K_I/(s+K_I): y_0 = 0, y_k+1 = a y_k + (1 - a)(x_k + x_k+1)/2."""
    out = np.zeros_like(x)
    for j, k_i in enumerate(gain):
        pole = np.exp(-k_i * DT)
        trapezoid = 0.5 * (x[:-1, j] + x[1:, j])
        out[1:, j] = signal.lfilter([1.0 - pole], [1.0, -pole], trapezoid)
    return out


def _regressor(qd: np.ndarray) -> np.ndarray:
    return np.stack([np.tanh(qd / V_S), qd, np.ones_like(qd)], axis=-1)


def _motion(n: int, seed: int = 0) -> np.ndarray:
    """Joint velocities [rad/s] with reversals, rests and varied speed: (n, 2)."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    qd = np.stack(
        [
            1.2 * np.sin(2 * np.pi * 0.7 * t) * (0.5 + 0.5 * np.sin(2 * np.pi * 0.11 * t)),
            0.8 * np.sin(2 * np.pi * 0.45 * t + 1.0) + 0.3 * np.sin(2 * np.pi * 1.3 * t),
        ],
        axis=1,
    )
    return qd + 0.001 * rng.standard_normal(qd.shape)


def _unlimited(**options: Any) -> FrictionAdapter:
    settings = {
        "rate_limit": np.inf, "max_correction": np.inf, "max_trace": np.inf,
        "smooth_velocity": V_S, "forgetting_time": 2.0, "initial_covariance": 1e3,
    }  # fmt: skip
    settings.update(options)
    return FrictionAdapter(2, DT, GAIN, **settings)


THETA = np.array([[1.5, 0.8, -0.3], [-0.6, 2.0, 0.25]])  # θ_c [N m], θ_v [N m s/rad], θ_0 [N m]


def test_rls_equals_weighted_least_squares_and_recovers_theta() -> None:
    n = 6000
    qd = _motion(n)
    phi = _regressor(qd)
    delta = np.einsum("knc,nc->kn", phi, THETA)
    rng = np.random.default_rng(1)
    r_hat = _filtered(delta, GAIN) + 0.01 * rng.standard_normal(delta.shape)
    adapter = _unlimited()
    _, state = adapter.run(r_hat, qd, np.ones(n, dtype=bool))

    lam = adapter.forgetting_factor
    psi = np.stack([_filtered(phi[:, :, c], GAIN) for c in range(3)], axis=-1)
    for j in range(2):
        # Updates at samples 1..n-1 (sample 0 has ψ = 0); prior θ_0 = 0, P_0 = 1e3 I.
        weight = np.sqrt(lam ** (n - 1 - np.arange(1, n)))
        rows = np.vstack([weight[:, None] * psi[1:, j], np.sqrt(lam ** (n - 1) / 1e3) * np.eye(3)])
        target = np.concatenate([weight * r_hat[1:, j], np.zeros(3)])
        expected = linalg.lstsq(rows, target)[0]
        np.testing.assert_allclose(state.theta[j], expected, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(state.theta[j], THETA[j], atol=0.02)
    np.testing.assert_array_equal(state.theta, state.estimate)  # no limit: applied = estimate
    assert state.updates.tolist() == [n - 1, n - 1]


def test_corrected_residual_vanishes_once_learned() -> None:
    n = 6000
    qd = _motion(n, seed=2)
    r_hat = _filtered(np.einsum("knc,nc->kn", _regressor(qd), THETA), GAIN)
    adapter = _unlimited(forgetting_time=np.inf)
    out, _ = adapter.run(r_hat, qd, np.ones(n, dtype=bool))
    assert np.abs(r_hat[-1000:]).max() > 1.0
    assert np.abs(out[-1000:]).max() < 1e-3 * np.abs(r_hat[-1000:]).max()


def _inputs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    qd = _motion(n, seed)
    r_hat = _filtered(np.einsum("knc,nc->kn", _regressor(qd), THETA), GAIN)
    r_hat += 0.05 * rng.standard_normal(r_hat.shape)
    trusted = rng.random((n, 2)) > 0.2
    r_hat[n // 3, 1] = np.nan
    qd[n // 2, 0] = np.inf
    return r_hat, qd, trusted


def test_step_equals_run_equals_chunks() -> None:
    r_hat, qd, trusted = _inputs(1500, 3)
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=5.0, max_correction=3.0, max_trace=50.0)
    whole, state = adapter.run(r_hat, qd, trusted)
    stepped = adapter.initial_state()
    rows = []
    for k in range(r_hat.shape[0]):
        row, stepped = adapter.step(stepped, r_hat[k], qd[k], trusted[k])
        rows.append(row)
    np.testing.assert_array_equal(np.array(rows), whole)
    chunked_state = None
    parts = []
    for block in np.array_split(np.arange(r_hat.shape[0]), [1, 400, 401, 1111]):
        part, chunked_state = adapter.run(r_hat[block], qd[block], trusted[block], chunked_state)
        parts.append(part)
    np.testing.assert_array_equal(np.concatenate(parts), whole)
    for name in ("theta", "covariance", "filtered_regressor", "filtered_correction", "updates"):
        np.testing.assert_array_equal(getattr(stepped, name), getattr(state, name))
        assert chunked_state is not None
        np.testing.assert_array_equal(getattr(chunked_state, name), getattr(state, name))


def test_untrusted_samples_leave_theta_and_covariance_unchanged() -> None:
    r_hat, qd, _ = _inputs(1200, 4)
    r_hat, qd = np.nan_to_num(r_hat), np.nan_to_num(qd, posinf=0.0)
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=5.0, max_correction=3.0)
    trusted = np.ones(1200, dtype=bool)
    _, first = adapter.run(r_hat[:600], qd[:600], trusted[:600])
    out, second = adapter.run(r_hat[600:], qd[600:], ~trusted[600:], first)
    np.testing.assert_array_equal(second.theta, first.theta)
    np.testing.assert_array_equal(second.estimate, first.estimate)
    np.testing.assert_array_equal(second.covariance, first.covariance)
    np.testing.assert_array_equal(second.updates, first.updates)
    # The filters go on: the correction is F(δτ) of the frozen θ, continued from `first`.
    delta = np.vstack([first.correction, adapter.correction(first, qd[600:])])
    for j, k_i in enumerate(GAIN):
        pole = np.exp(-k_i * DT)
        trapezoid = 0.5 * (delta[:-1, j] + delta[1:, j])
        zi = [pole * first.filtered_correction[j]]
        expected = signal.lfilter([1.0 - pole], [1.0, -pole], trapezoid, zi=zi)[0]
        np.testing.assert_allclose(r_hat[600:, j] - out[:, j], expected, rtol=1e-9, atol=1e-12)
    # Per joint: joint 1 untrusted learns nothing, joint 0 learns.
    mask = np.column_stack([np.ones(600, dtype=bool), np.zeros(600, dtype=bool)])
    _, third = adapter.run(r_hat[600:], qd[600:], mask, first)
    np.testing.assert_array_equal(third.theta[1], first.theta[1])
    assert not np.array_equal(third.theta[0], first.theta[0])


def test_rate_limit_holds_at_every_velocity_of_its_range() -> None:
    rate, v_max = 0.05, 1.5
    adapter = FrictionAdapter(
        2, DT, GAIN, rate_limit=rate, max_correction=20.0, max_velocity=v_max, smooth_velocity=V_S
    )
    n = 3000
    qd = _motion(n, 5)
    r_hat = 10.0 + _filtered(np.einsum("knc,nc->kn", _regressor(qd), THETA), GAIN)
    state = adapter.initial_state()
    grid = np.linspace(-v_max, v_max, 301)[:, None] * np.ones((1, 2))
    before = adapter.correction(state, grid)
    weight = np.array([1.0, v_max, 1.0])
    limited = 0
    for k in range(n):
        _, new_state = adapter.step(state, r_hat[k], qd[k], True)
        after = adapter.correction(new_state, grid)
        assert np.abs(after - before).max() <= rate * DT * (1 + 1e-9)
        size = np.abs(new_state.theta - state.theta) @ weight
        limited += int((size >= rate * DT * (1 - 1e-9)).all())
        before, state = after, new_state
    # The 10 N m error is far from learned in 3 s: the limit was active nearly throughout,
    # while the RLS estimate itself has the offset long since.
    assert limited > 0.9 * n
    np.testing.assert_allclose(state.estimate[:, 2], THETA[:, 2] + 10.0, atol=0.2)
    assert (np.abs(state.theta[:, 2]) < rate * n * DT).all()


def test_slow_push_moves_the_correction_by_at_most_rate_times_duration() -> None:
    # The demo's slow push: 40 N at the PUMA 560's flange (puma560-thesis contacts
    # are 10-60 N), ramped over 2 s; joint torques from the contact Jacobian.
    puma = robots.load("puma560")
    q0 = np.radians([0.0, 90.0, -90.0, 0.0, 0.0, 0.0])
    push = Contact(1, 6, (0.0, 0.0, 0.1), (1.0, 0.0, 0.0), Push(20.0, 2.0, 1.0, 0.5, 40.0))
    t = np.arange(24000) * DT
    tau_c_full = push.joint_torque(puma, np.tile(q0, (t.size, 1)), t)
    joints = np.argsort(-np.abs(tau_c_full).max(axis=0))[:2]
    tau_c = tau_c_full[:, joints]
    assert np.abs(tau_c).max() > 5.0

    rate = 0.05
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=rate, max_correction=10.0)
    qd = _motion(t.size, 6)
    friction_error = np.einsum("knc,nc->kn", _regressor(qd), THETA)
    r_hat = _filtered(friction_error + tau_c, GAIN)
    trusted = np.ones(t.size, dtype=bool)  # worst case: the detector never fires
    start, end = int(20.0 / DT), int(22.0 / DT)
    out, before = adapter.run(r_hat[:start], qd[:start], trusted[:start])
    out_push, after = adapter.run(r_hat[start:end], qd[start:end], trusted[start:end], before)
    grid = np.linspace(-2.0, 2.0, 81)[:, None] * np.ones((1, 2))
    change = np.abs(adapter.correction(after, grid) - adapter.correction(before, grid))
    assert change.max() <= rate * 2.0 * (1 + 1e-9)
    # The corrected residual still shows the push: the filtered push at the end of
    # the ramp, less at most what was learned during it, less the pre-push error.
    pushed = _filtered(tau_c, GAIN)[end - 1]
    residual_before = np.abs(out[-2000:]).max(axis=0)
    assert (np.abs(out_push[-1]) >= np.abs(pushed) - rate * 2.0 - residual_before).all()
    assert (np.abs(out_push[-1]) > 0.9 * np.abs(pushed)).all()


def test_covariance_stays_bounded_without_excitation() -> None:
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=5.0, max_trace=40.0,
                              forgetting_time=0.5)  # fmt: skip
    n = 5000
    _, state = adapter.run(np.zeros((n, 2)), np.zeros((n, 2)), np.ones(n, dtype=bool))
    trace = np.einsum("nii->n", state.covariance)
    assert (trace <= 40.0 * (1 + 1e-12)).all()
    assert (np.linalg.eigvalsh(state.covariance) > 0).all()
    unbounded = FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=5.0,
                                max_trace=np.inf, forgetting_time=0.5)  # fmt: skip
    _, wound = unbounded.run(np.zeros((n, 2)), np.zeros((n, 2)), np.ones(n, dtype=bool))
    assert np.einsum("nii->n", wound.covariance).min() > 1e3


def test_correction_is_bounded() -> None:
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=np.inf, max_correction=0.5)
    n = 3000
    qd = _motion(n, 7)
    r_hat = _filtered(np.einsum("knc,nc->kn", _regressor(qd), 10 * THETA), GAIN)
    out, state = adapter.run(r_hat, qd, np.ones(n, dtype=bool))
    assert (np.abs(state.correction) <= 0.5).all()
    assert (np.abs(adapter.correction(state, qd)) <= 0.5).all()
    assert (np.abs(r_hat - out) <= 0.5 + 1e-12).all()
    assert np.abs(state.theta[:, 0]).max() <= 0.5 and np.abs(state.theta[:, 2]).max() <= 0.5


@pytest.mark.parametrize(
    ("r_value", "qd_value"),
    [(np.nan, 0.1), (0.2, np.nan), (0.2, np.inf), (np.inf, 0.1), (-np.inf, -np.inf)],
)
def test_nonfinite_input_changes_nothing(r_value: float, qd_value: float) -> None:
    r_hat, qd, _ = _inputs(300, 8)
    r_hat, qd = np.nan_to_num(r_hat), np.nan_to_num(qd, posinf=0.0)
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=5.0, max_correction=3.0)
    _, state = adapter.run(r_hat, qd, np.ones(300, dtype=bool))
    out, after = adapter.step(state, [r_value, 0.3], [qd_value, 0.2], True)
    for name in AdapterState.__slots__:
        np.testing.assert_array_equal(getattr(after, name), getattr(state, name))
    expected = np.array([r_value, 0.3]) - state.filtered_correction
    np.testing.assert_array_equal(out, expected)
    # And the stream goes on as if the sample had not come.
    resumed, _ = adapter.step(after, [0.1, 0.1], [0.2, 0.2], True)
    reference, _ = adapter.step(state, [0.1, 0.1], [0.2, 0.2], True)
    np.testing.assert_array_equal(resumed, reference)


def test_first_sample_passes_and_filters_start_at_zero() -> None:
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=5.0)
    state = adapter.initial_state(theta=[[1.0, 0.0, 0.5], [0.0, 0.0, 0.0]])
    out, state = adapter.step(state, [0.4, -0.2], [1.0, 0.0], True)
    np.testing.assert_array_equal(out, [0.4, -0.2])
    assert state.started
    np.testing.assert_array_equal(state.filtered_correction, [0.0, 0.0])
    out, state = adapter.step(state, [0.4, -0.2], [1.0, 0.0], False)
    delta = np.tanh(1.0 / 0.02) + 0.5
    pole = np.exp(-GAIN[0] * DT)
    np.testing.assert_allclose(out[0], 0.4 - (1 - pole) * delta, rtol=1e-14)


def test_restart_keeps_what_was_learned_and_restarts_the_filters() -> None:
    r_hat, qd, _ = _inputs(800, 9)
    r_hat, qd = np.nan_to_num(r_hat), np.nan_to_num(qd, posinf=0.0)
    adapter = FrictionAdapter(2, DT, GAIN, rate_limit=0.5, max_correction=3.0)
    _, learned = adapter.run(r_hat, qd, np.ones(800, dtype=bool))
    again = adapter.restart(learned)
    for name in ("theta", "estimate", "covariance", "updates"):
        np.testing.assert_array_equal(getattr(again, name), getattr(learned, name))
    assert not again.started
    np.testing.assert_array_equal(again.filtered_correction, [0.0, 0.0])
    # Restarted = a fresh run of the same inputs from the learned θ, estimate and P.
    out_restart, _ = adapter.run(r_hat[:50], qd[:50], np.zeros(50, dtype=bool), again)
    fresh = adapter.initial_state(learned.theta, learned.covariance)
    out_fresh, _ = adapter.run(r_hat[:50], qd[:50], np.zeros(50, dtype=bool), fresh)
    np.testing.assert_array_equal(out_restart, out_fresh)


def test_from_observer_takes_joints_period_and_gain() -> None:
    observer = MomentumObserver(robots.load("planar2"), dt=2e-3, gain=[15.0, 25.0])
    adapter = FrictionAdapter.from_observer(observer, rate_limit=0.1, max_correction=2.0)
    assert adapter.n_dof == 2 and adapter.dt == 2e-3
    np.testing.assert_array_equal(adapter.gain, [15.0, 25.0])
    assert adapter.forgetting_factor == pytest.approx(np.exp(-2e-3 / 120.0))
    assert "FrictionAdapter(n_dof=2" in repr(adapter)


def test_validation() -> None:
    def make(**options: Any) -> FrictionAdapter:
        settings = {"rate_limit": 1.0, "max_correction": 1.0}
        settings.update(options)
        return FrictionAdapter(2, DT, GAIN, **settings)

    with pytest.raises(InputValueError, match="rate_limit must be"):
        make(rate_limit=0.0)
    with pytest.raises(InputValueError, match="max_correction must be"):
        make(max_correction=-1.0)
    with pytest.raises(InputValueError, match="forgetting_time"):
        make(forgetting_time=0.0)
    with pytest.raises(InputValueError, match="max_trace"):
        make(max_trace=-1.0)
    with pytest.raises(InputValueError, match="dt must be"):
        FrictionAdapter(2, 0.0, rate_limit=1.0, max_correction=1.0)
    with pytest.raises(InputValueError, match="n_dof must be"):
        FrictionAdapter(0, DT, rate_limit=1.0, max_correction=1.0)
    adapter = make()
    with pytest.raises(InputValueError, match="box"):
        adapter.initial_state(theta=[[2.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(DimensionError, match="theta must have shape"):
        adapter.initial_state(theta=[1.0, 0.0, 0.0])
    with pytest.raises(InputValueError, match="positive definite"):
        adapter.initial_state(covariance=np.zeros((2, 3, 3)))
    state = adapter.initial_state()
    with pytest.raises(InputTypeError, match="trusted must be booleans"):
        adapter.step(state, [0.0, 0.0], [0.0, 0.0], 1)
    with pytest.raises(DimensionError, match="trusted must have shape"):
        adapter.run(np.zeros((5, 2)), np.zeros((5, 2)), np.ones(4, dtype=bool))
    with pytest.raises(DimensionError, match="qd must have the shape"):
        adapter.run(np.zeros((5, 2)), np.zeros((4, 2)), np.ones(5, dtype=bool))
    with pytest.raises(DimensionError, match="r_hat must have shape"):
        adapter.step(state, np.zeros((2, 2)), [0.0, 0.0], True)
    with pytest.raises(InputTypeError, match="AdapterState"):
        adapter.step(None, [0.0, 0.0], [0.0, 0.0], True)  # type: ignore[arg-type]
    other = FrictionAdapter(3, DT, rate_limit=1.0, max_correction=1.0).initial_state()
    with pytest.raises(DimensionError, match="state is for 3 joints"):
        adapter.step(other, [0.0, 0.0], [0.0, 0.0], True)
    with pytest.raises(InputTypeError, match="observer must be"):
        FrictionAdapter.from_observer(object(), rate_limit=1.0, max_correction=1.0)  # type: ignore[arg-type]


def test_doctests() -> None:
    module = importlib.import_module("sensorless.observers.adaptive")
    assert doctest.testmod(module).failed == 0


# ------------------------------------------------------------------ the model-torque term

EPS_H = np.array([0.08, -0.05])  # relative model error θ_h [-]


def _model_torque(n: int, seed: int) -> np.ndarray:
    """A filtered model torque h [N m]: slow gravity-like swings plus inertial bursts."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    h = np.stack([12.0 * np.sin(2 * np.pi * 0.3 * t), 30.0 + 8.0 * np.cos(2 * np.pi * 0.9 * t)], 1)
    return h + 0.5 * rng.standard_normal(h.shape)


def test_model_torque_term_equals_weighted_least_squares() -> None:
    """θ = (θ_c, θ_v, θ_0, θ_h): r̂ = F(φᵀθ_fr) + θ_h·h, h already filtered."""
    n = 6000
    qd, h = _motion(n, 7), _model_torque(n, 7)
    phi = _regressor(qd)
    rng = np.random.default_rng(8)
    r_hat = _filtered(np.einsum("knc,nc->kn", phi, THETA), GAIN) + EPS_H * h
    r_hat += 0.01 * rng.standard_normal(r_hat.shape)
    adapter = _unlimited(max_model_torque=100.0)
    assert adapter.columns == 4
    out, state = adapter.run(r_hat, qd, np.ones(n, dtype=bool), model_torque=h)

    lam = adapter.forgetting_factor
    psi = np.concatenate(
        [np.stack([_filtered(phi[:, :, c], GAIN) for c in range(3)], -1), h[:, :, None]], -1
    )
    for j in range(2):
        weight = np.sqrt(lam ** (n - 1 - np.arange(1, n)))
        rows = np.vstack([weight[:, None] * psi[1:, j], np.sqrt(lam ** (n - 1) / 1e3) * np.eye(4)])
        target = np.concatenate([weight * r_hat[1:, j], np.zeros(4)])
        np.testing.assert_allclose(state.theta[j], linalg.lstsq(rows, target)[0], rtol=1e-7)
        np.testing.assert_allclose(state.theta[j, :3], THETA[j], atol=0.05)
        np.testing.assert_allclose(state.theta[j, 3], EPS_H[j], atol=2e-3)
    # Once learned, the model error leaves the residual with the friction error.
    assert np.abs(out[-1000:]).max() < 0.1 * np.abs(r_hat[-1000:]).max()
    # The friction-only adapter cannot remove the θ_h·h part.
    rest, _ = _unlimited().run(r_hat, qd, np.ones(n, dtype=bool))
    assert np.abs(rest[-1000:]).max() > 5 * np.abs(out[-1000:]).max()


def test_model_torque_term_step_equals_run_and_honours_the_rate_limit() -> None:
    r_hat, qd, trusted = _inputs(1500, 9)
    h = _model_torque(1500, 9)
    h[700, 1] = np.nan
    r_hat = r_hat + EPS_H * np.nan_to_num(h)
    rate, h_max = 0.5, 50.0
    adapter = FrictionAdapter(
        2, DT, GAIN, rate_limit=rate, max_correction=3.0, max_model_torque=h_max
    )
    whole, state = adapter.run(r_hat, qd, trusted, model_torque=h)
    stepped = adapter.initial_state()
    weight = np.array([1.0, adapter._max_velocity[0], 1.0, h_max])
    rows = []
    for k in range(r_hat.shape[0]):
        row, new = adapter.step(stepped, r_hat[k], qd[k], trusted[k], h[k])
        assert (np.abs(new.theta - stepped.theta) @ weight <= rate * DT * (1 + 1e-9)).all()
        if not np.isfinite(h[k]).all():  # a non-finite h changes nothing
            np.testing.assert_array_equal(new.theta, stepped.theta)
            np.testing.assert_array_equal(new.covariance, stepped.covariance)
        rows.append(row)
        stepped = new
    np.testing.assert_array_equal(np.array(rows), whole)
    np.testing.assert_array_equal(stepped.theta, state.theta)
    # |θ_h| stays in the box max_correction / max_model_torque.
    assert (np.abs(state.theta[:, 3]) <= 3.0 / h_max + 1e-12).all()


def test_model_torque_is_required_exactly_when_the_term_is_on() -> None:
    on = FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=1.0, max_model_torque=10.0)
    off = FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=1.0)
    with pytest.raises(InputValueError, match="pass model_torque"):
        on.step(on.initial_state(), [0.0, 0.0], [0.0, 0.0], True)
    with pytest.raises(InputValueError, match="no model-torque term"):
        off.step(off.initial_state(), [0.0, 0.0], [0.0, 0.0], True, [1.0, 1.0])
    with pytest.raises(DimensionError, match="3 parameters per joint; this adapter learns 4"):
        on.step(off.initial_state(), [0.0, 0.0], [0.0, 0.0], True, [1.0, 1.0])
    with pytest.raises(DimensionError, match="model_torque must have shape"):
        on.run(np.zeros((5, 2)), np.zeros((5, 2)), True, model_torque=np.zeros((4, 2)))
    with pytest.raises(InputValueError, match="max_model_torque"):
        FrictionAdapter(2, DT, GAIN, rate_limit=1.0, max_correction=1.0, max_model_torque=-1.0)


@pytest.mark.parametrize("max_model_torque", [None, 60.0])
def test_compiled_kernel_equals_the_numpy_recursion(
    monkeypatch: pytest.MonkeyPatch, max_model_torque: float | None
) -> None:
    """The numba kernel (step and run) against FrictionAdapter._advance, to rounding."""
    from sensorless.observers import _adaptive_kernel

    if _adaptive_kernel.compiled is None:
        pytest.skip("numba is not installed: the numpy recursion is the only path")
    r_hat, qd, trusted = _inputs(2500, 11)
    h = _model_torque(2500, 11)
    h[900, 0] = np.inf
    r_hat = r_hat + EPS_H * np.nan_to_num(h, posinf=0.0)
    adapter = FrictionAdapter(
        2, DT, GAIN, rate_limit=2.0, max_correction=3.0, max_trace=50.0,
        max_model_torque=max_model_torque,
    )  # fmt: skip
    given = None if max_model_torque is None else h
    compiled, state = adapter.run(r_hat, qd, trusted, model_torque=given)
    monkeypatch.setattr(_adaptive_kernel, "compiled", None)
    reference, expected = adapter.run(r_hat, qd, trusted, model_torque=given)
    np.testing.assert_allclose(compiled, reference, rtol=1e-12, atol=1e-12)
    for name in ("theta", "estimate", "covariance", "filtered_regressor", "filtered_correction"):
        np.testing.assert_allclose(
            getattr(state, name), getattr(expected, name), rtol=1e-10, atol=1e-12
        )
    np.testing.assert_array_equal(state.updates, expected.updates)
    assert state.started == expected.started
