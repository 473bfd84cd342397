"""Tests of :mod:`sensorless.filters`.

Each estimator is checked against something computed another way: analytic
derivatives of sinusoids and polynomials, ``np.diff``, the closed-form
frequency response of the continuous prototype mapped by the bilinear
transform, the closed-form group delay of an analog Butterworth filter, and
the frequency response of the designed sections (``freqz_sos``) against the
steady-state amplitude and phase of the time-domain output.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy import signal

from sensorless.exceptions import DimensionError, InputValueError, SensorlessError
from sensorless.filters import (
    Butterworth,
    CausalEstimator,
    Delays,
    Derivatives,
    DirtyDerivative,
    FilterState,
    FiniteDifference,
    SavitzkyGolay,
)

DT = 1e-3  # 1 kHz
FS = 1.0 / DT
F_SINE = 0.5  # [Hz]
CAUSAL = [
    pytest.param(FiniteDifference(DT), id="finite-difference"),
    pytest.param(DirtyDerivative(DT, cutoff=20.0), id="dirty-derivative"),
    pytest.param(Butterworth(DT, cutoff=20.0), id="butterworth-5"),
    pytest.param(Butterworth(DT, cutoff=35.0, order=2), id="butterworth-2"),
]


def _time(n_samples: int) -> np.ndarray:
    return np.arange(n_samples)[:, None] * DT


def _sines(t: np.ndarray) -> np.ndarray:
    """Two joints: q = sin(2π f t) and 0.3 cos(2π f t) + 1 [rad]."""
    w = 2 * np.pi * F_SINE
    return np.hstack([np.sin(w * t), 0.3 * np.cos(w * t) + 1.0])


def _sines_velocity(t: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * F_SINE
    return np.hstack([w * np.cos(w * t), -0.3 * w * np.sin(w * t)])


def _sines_acceleration(t: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * F_SINE
    return np.hstack([-(w**2) * np.sin(w * t), -0.3 * w**2 * np.cos(w * t)])


def _noisy_record(n_samples: int = 600) -> np.ndarray:
    rng = np.random.default_rng(0)
    return _sines(_time(n_samples)) + 1e-3 * rng.standard_normal((n_samples, 2))


# --------------------------------------------------------------------------- accuracy


@pytest.mark.parametrize("est", CAUSAL)
def test_sine_velocity_matches_analytic_derivative_delayed(est: CausalEstimator) -> None:
    t = _time(3000)
    y, _ = est.filter(_sines(t))
    after = t[:, 0] > 1.0  # start-up over
    # Residual error after removing the delay: amplitude droop and phase
    # curvature, both O((f / cutoff)^2) relative; backward differences O((ω dt)^2).
    velocity_ref = _sines_velocity(t - est.delays.velocity)
    acceleration_ref = _sines_acceleration(t - est.delays.acceleration)
    w = 2 * np.pi * F_SINE
    np.testing.assert_allclose(y.velocity[after], velocity_ref[after], rtol=0, atol=2e-3 * w)
    np.testing.assert_allclose(
        y.acceleration[after], acceleration_ref[after], rtol=0, atol=4e-3 * w**2
    )
    np.testing.assert_allclose(
        y.position[after], _sines(t - est.delays.position)[after], rtol=0, atol=1e-3
    )
    # Without the delay correction the error is larger: the delay is real.
    if est.delay > 5e-3:
        assert np.abs(y.velocity[after] - _sines_velocity(t)[after]).max() > 2e-3 * w


@pytest.mark.parametrize("est", CAUSAL)
def test_steady_sine_response_matches_freqz_of_designed_sections(est: CausalEstimator) -> None:
    f = 12.5  # [Hz]: 80 samples per period, near the cut-off so the filter matters
    t = _time(4000)
    x = np.sin(2 * np.pi * f * t)
    y, _ = est.filter(x)
    tail = slice(-800, None)  # ten whole periods, after the start-up
    basis = np.hstack([np.sin(2 * np.pi * f * t[tail]), np.cos(2 * np.pi * f * t[tail])])
    for out, sos, power in [
        (y.position, est.sos_position, 0),
        (y.velocity, est.sos_velocity, 1),
        (y.acceleration, est.sos_acceleration, 2),
    ]:
        (a, b), *_ = np.linalg.lstsq(basis, out[tail, 0], rcond=None)
        measured = a + 1j * b  # sin(ωt) in, Im(H e^{jωt}) = Re H sin + Im H cos out
        _, h = signal.freqz_sos(sos, worN=[f], fs=FS)
        expected = h[0] / DT**power
        assert abs(measured - expected) <= 1e-9 * max(1.0, abs(expected))


def test_dirty_derivative_is_tustin_of_continuous_prototype() -> None:
    cutoff = 30.0
    est = DirtyDerivative(DT, cutoff)
    tau = 1 / (2 * np.pi * cutoff)
    f = np.array([0.1, 1.0, 10.0, 30.0, 100.0, 400.0])
    _, h_velocity = signal.freqz_sos(est.sos_velocity, worN=f, fs=FS)
    _, h_acceleration = signal.freqz_sos(est.sos_acceleration, worN=f, fs=FS)
    s = 1j * (2 / DT) * np.tan(np.pi * f * DT)  # bilinear frequency warping
    prototype = s / (tau * s + 1)
    np.testing.assert_allclose(h_velocity / DT, prototype, rtol=1e-9)
    np.testing.assert_allclose(h_acceleration / DT**2, prototype**2, rtol=1e-9)
    assert est.tau == pytest.approx(tau, rel=1e-15)


@pytest.mark.parametrize("order", [1, 2, 5, 8])
def test_butterworth_magnitude_matches_closed_form(order: int) -> None:
    cutoff = 40.0
    est = Butterworth(DT, cutoff, order=order)
    f = np.array([1.0, 20.0, 40.0, 80.0, 300.0])
    _, h = signal.freqz_sos(est.sos_position, worN=f, fs=FS)
    ratio = np.tan(np.pi * f * DT) / np.tan(np.pi * cutoff * DT)
    np.testing.assert_allclose(np.abs(h), 1 / np.sqrt(1 + ratio ** (2 * order)), rtol=1e-9)
    _, h_velocity = signal.freqz_sos(est.sos_velocity, worN=f, fs=FS)
    difference = 1 - np.exp(-2j * np.pi * f * DT)
    np.testing.assert_allclose(h_velocity, h * difference, rtol=1e-9)


# --------------------------------------------------------------------------- delays


def test_delays_closed_forms() -> None:
    assert FiniteDifference(DT).delays == Delays(0.0, DT / 2, DT)
    dirty = DirtyDerivative(DT, 15.0)
    np.testing.assert_allclose(dirty.delays, [0.0, dirty.tau, 2 * dirty.tau], rtol=1e-9)
    for order, cutoff in [(5, 20.0), (2, 10.0), (3, 5.0)]:
        est = Butterworth(DT, cutoff, order=order)
        analog = 1 / (2 * np.pi * cutoff * math.sin(np.pi / (2 * order)))
        assert est.delays.position == pytest.approx(analog, rel=1e-2)
        assert est.delays.velocity == pytest.approx(est.delays.position + DT / 2, rel=1e-12)
        assert est.delays.acceleration == pytest.approx(est.delays.position + DT, rel=1e-12)
        assert est.delay == est.delays.velocity


@pytest.mark.parametrize("est", CAUSAL)
def test_polynomial_inputs_reveal_the_delays(est: CausalEstimator) -> None:
    # For an LTI filter with unit DC gain a ramp comes out shifted by exactly
    # the DC group delay; so does the derivative of a parabola / cubic.
    t = _time(2500)
    after = slice(1500, None)
    ramp, _ = est.filter(0.7 * t)
    np.testing.assert_allclose(ramp.position[after], 0.7 * (t - est.delays.position)[after])
    np.testing.assert_allclose(ramp.velocity[after], 0.7, rtol=1e-9)
    parabola, _ = est.filter(0.5 * 1.3 * t**2)
    np.testing.assert_allclose(
        parabola.velocity[after], 1.3 * (t - est.delays.velocity)[after], rtol=1e-9
    )
    np.testing.assert_allclose(parabola.acceleration[after], 1.3, rtol=1e-7)
    cubic, _ = est.filter(2.0 * t**3 / 6)
    np.testing.assert_allclose(
        cubic.acceleration[after], 2.0 * (t - est.delays.acceleration)[after], rtol=1e-6
    )


# --------------------------------------------------------------------------- exactness


def test_finite_difference_is_exactly_np_diff() -> None:
    x = _noisy_record()
    y, _ = FiniteDifference(DT).filter(x)
    assert np.array_equal(y.position, x)
    assert np.array_equal(y.velocity[1:], np.diff(x, axis=0) / DT)
    np.testing.assert_allclose(
        y.acceleration[2:], np.diff(np.diff(x, axis=0) / DT, axis=0) / DT, rtol=1e-12, atol=1e-6
    )
    assert np.array_equal(y.acceleration[2:], np.diff(x, n=2, axis=0) / DT**2)
    assert not y.velocity[0].any() and not y.acceleration[:1].any()


@pytest.mark.parametrize("est", CAUSAL)
def test_robot_at_rest_gives_exactly_zero_derivatives(est: CausalEstimator) -> None:
    x0 = np.array([0.3, -1.7, 2.9])
    x = np.tile(x0, (200, 1))
    for state in (None, est.initial_state(x0)):
        y, _ = est.filter(x, state)
        assert not y.velocity.any()
        assert not y.acceleration.any()
        np.testing.assert_allclose(y.position, x, rtol=1e-13)
    y1, _ = est.step(x0, est.initial_state(x0))
    assert not y1.velocity.any() and not y1.acceleration.any()


def test_savitzky_golay_exact_on_cubic() -> None:
    t = np.arange(300)[:, None] * 2e-3
    coef = np.array([[0.4, -1.0], [1.5, 0.2], [-2.0, 3.0], [0.7, -0.9]])  # c0..c3 per joint
    q = coef[0] + coef[1] * t + coef[2] * t**2 + coef[3] * t**3
    qd = coef[1] + 2 * coef[2] * t + 3 * coef[3] * t**2
    qdd = 2 * coef[2] + 6 * coef[3] * t
    y = SavitzkyGolay(2e-3, window=21, polyorder=3).filter(q)
    assert isinstance(y, Derivatives)
    np.testing.assert_allclose(y.position, q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y.velocity, qd, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y.acceleration, qdd, rtol=0, atol=1e-9)


def test_savitzky_golay_is_zero_phase_on_sine() -> None:
    t = _time(3000)
    y = SavitzkyGolay(DT, window=101, polyorder=3).filter(_sines(t))
    inner = slice(100, -100)
    w = 2 * np.pi * F_SINE
    np.testing.assert_allclose(y.velocity[inner], _sines_velocity(t)[inner], atol=1e-5 * w)
    # The second derivative of a cubic fit is that of a quadratic: droop O((ω window dt)^2).
    np.testing.assert_allclose(
        y.acceleration[inner], _sines_acceleration(t)[inner], atol=3e-3 * w**2
    )


def test_savitzky_golay_is_offline_only() -> None:
    est = SavitzkyGolay(DT, window=11)
    assert not isinstance(est, CausalEstimator)
    assert not hasattr(est, "step") and not hasattr(est, "initial_state")


# --------------------------------------------------------------------------- streaming = batch


@pytest.mark.parametrize("est", CAUSAL)
def test_step_loop_equals_filter(est: CausalEstimator) -> None:
    x = _noisy_record(300)
    whole, final = est.filter(x)
    state = est.initial_state(x[0])
    rows = []
    for sample in x:
        y, state = est.step(sample, state)
        assert y.velocity.shape == (2,)
        rows.append(y)
    for name in Derivatives._fields:
        stepped = np.array([getattr(r, name) for r in rows])
        np.testing.assert_allclose(stepped, getattr(whole, name), rtol=1e-12, atol=1e-12)
    for name in ("position", "velocity", "acceleration"):
        np.testing.assert_allclose(getattr(state, name), getattr(final, name), rtol=1e-12)


@pytest.mark.parametrize("est", CAUSAL)
def test_chunked_equals_whole(est: CausalEstimator) -> None:
    x = _noisy_record(600)
    whole, final = est.filter(x)
    state = est.initial_state(x[0])
    parts = []
    for lo, hi in [(0, 1), (1, 1), (1, 97), (97, 98), (98, 400), (400, 600)]:
        y, state = est.filter(x[lo:hi], state)
        parts.append(y)
    for name in Derivatives._fields:
        chunked = np.concatenate([getattr(p, name) for p in parts])
        np.testing.assert_allclose(chunked, getattr(whole, name), rtol=1e-12, atol=1e-12)
    for name in ("position", "velocity", "acceleration"):
        np.testing.assert_allclose(getattr(state, name), getattr(final, name), rtol=1e-12)


def test_state_is_immutable_and_replayable() -> None:
    est = Butterworth(DT, 20.0)
    x = _noisy_record(100)
    state = est.initial_state(x[0])
    first, _ = est.filter(x, state)
    again, _ = est.filter(x, state)
    assert np.array_equal(first.velocity, again.velocity)
    assert state.n_dof == 2
    with pytest.raises(ValueError, match="read-only"):
        state.velocity[0, 0, 0] = 1.0
    sos = est.sos_velocity
    sos[:] = 0.0  # a copy: the estimator keeps its design
    assert est.sos_velocity.any()


def test_designed_sections_reproduce_output_with_plain_scipy() -> None:
    est = DirtyDerivative(DT, 25.0)
    x = _noisy_record(200)
    y, _ = est.filter(x, est.initial_state(np.zeros(2)))  # zero state = sosfilt default
    np.testing.assert_allclose(y.velocity, signal.sosfilt(est.sos_velocity, x, axis=0) / DT)
    np.testing.assert_allclose(
        y.acceleration, signal.sosfilt(est.sos_acceleration, x, axis=0) / DT**2
    )
    assert repr(est) == "DirtyDerivative(dt=0.001, cutoff=25.0)"
    assert repr(Butterworth(DT, 20)) == "Butterworth(dt=0.001, cutoff=20.0, order=5)"
    assert repr(SavitzkyGolay(DT, 11)) == "SavitzkyGolay(dt=0.001, window=11, polyorder=3)"


# --------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("factory", "match"),
    [
        (lambda: FiniteDifference(0.0), "dt must be a positive"),
        (lambda: FiniteDifference("fast"), "dt must be a positive"),  # type: ignore[arg-type]
        (lambda: DirtyDerivative(DT, 0.0), r"0 < cutoff < Nyquist"),
        (lambda: DirtyDerivative(DT, float("nan")), "cutoff"),
        (lambda: DirtyDerivative(DT, None), "cutoff must be a frequency in Hz"),  # type: ignore[arg-type]
        (lambda: DirtyDerivative(DT, 500.0), "= 500 Hz"),
        (lambda: Butterworth(DT, 600.0), r"Nyquist frequency 1/\(2 dt\) = 500 Hz"),
        (lambda: Butterworth(DT, -1.0), "got -1.0"),
        (lambda: Butterworth(DT, 20.0, order=0), "order must be an integer >= 1; got 0"),
        (lambda: Butterworth(DT, 20.0, order=2.5), "order must be an integer >= 1; got 2.5"),  # type: ignore[arg-type]
        (lambda: Butterworth(DT, 20.0, order=True), "order must be an integer"),
        (lambda: SavitzkyGolay(DT, 10), "window must be an odd number"),
        (lambda: SavitzkyGolay(DT, 3, polyorder=3), "window must be an integer >= 4; got 3"),
        (lambda: SavitzkyGolay(DT, 11, polyorder=1), "polyorder must be an integer >= 2"),
        (lambda: SavitzkyGolay(-DT, 11), "dt must be a positive"),
    ],
)
def test_bad_hyper_parameters(factory: Callable[[], object], match: str) -> None:
    with pytest.raises(InputValueError, match=match):
        factory()


def test_bad_signals() -> None:
    est = Butterworth(DT, 20.0)
    good = np.zeros((5, 2))
    state = est.initial_state(good[0])
    with pytest.raises(InputValueError, match=r"x must be finite; found nan at sample 2, joint 1"):
        bad = good.copy()
        bad[2, 1] = np.nan
        est.filter(bad)
    with pytest.raises(DimensionError, match=r"shape \(n_samples, n_dof\).*got \(5, 2, 1\)"):
        est.filter(np.zeros((5, 2, 1)))
    with pytest.raises(DimensionError, match=r"x must have shape \(n_samples, n_dof\)"):
        est.filter(np.zeros(4))
    with pytest.raises(DimensionError, match="x has no samples"):
        est.filter(np.zeros((0, 2)))
    with pytest.raises(DimensionError, match=r"robot with 2 joints; got shape \(5, 3\)"):
        est.filter(np.zeros((5, 3)), state)
    with pytest.raises(DimensionError, match="use step for one sample"):
        est.filter(np.zeros(2), state)
    with pytest.raises(DimensionError, match=r"step takes one sample x of shape \(2,\)"):
        est.step(good, state)
    with pytest.raises(DimensionError, match=r"shape \(2,\) or \(n_samples, 2\)"):
        est.step(np.zeros(3), state)
    with pytest.raises(InputValueError, match="x must be finite"):
        est.step([np.inf, 0.0], state)
    with pytest.raises(DimensionError, match=r"x0 must have shape \(n_dof,\)"):
        est.initial_state(good)
    with pytest.raises(InputValueError, match="x0 must be finite"):
        est.initial_state([np.nan, 0.0])
    with pytest.raises(TypeError, match=r"state must be a FilterState.*got ndarray"):
        est.step(good[0], np.zeros((3, 2, 2)))  # type: ignore[arg-type]
    other = FiniteDifference(DT).initial_state(good[0])
    with pytest.raises(DimensionError, match="another estimator"):
        est.filter(good, other)
    with pytest.raises(DimensionError, match=r"FilterState.velocity must have shape"):
        FilterState(np.zeros((1, 2, 2)), np.zeros((1, 2)), np.zeros((1, 2, 2)))
    with pytest.raises(DimensionError, match="is for 3 joints"):
        FilterState(np.zeros((1, 2, 2)), np.zeros((1, 2, 3)), np.zeros((1, 2, 2)))
    sg = SavitzkyGolay(DT, 11)
    with pytest.raises(DimensionError, match="needs at least 11 samples; x has 5"):
        sg.filter(good)
    with pytest.raises(InputValueError, match="x must be finite"):
        sg.filter(np.full((20, 2), np.inf))
    with pytest.raises(SensorlessError):
        sg.filter(np.zeros(20))


def test_empty_chunk_with_state_is_a_no_op() -> None:
    est = DirtyDerivative(DT, 20.0)
    state = est.initial_state([0.1, 0.2])
    y, same = est.filter(np.zeros((0, 2)), state)
    assert y.velocity.shape == (0, 2)
    assert same is state


@pytest.mark.parametrize("est", CAUSAL)
def test_step_outputs_computes_only_the_selected_outputs(est: CausalEstimator) -> None:
    # The internal path of CollisionMonitor: velocity alone, bit for bit as step.
    x = _noisy_record(50)
    state = est.initial_state(x[0])
    zis = (state.position, state.velocity, state.acceleration)
    for sample in x:
        y, state = est.step(sample, state)
        outputs, new = est._step_outputs(sample, zis, (False, True, False))
        assert outputs[0] is None and outputs[2] is None
        np.testing.assert_array_equal(outputs[1], y.velocity)
        np.testing.assert_array_equal(new[1], state.velocity)
        assert new[0] is zis[0] and new[2] is zis[2]  # not selected: left as they were
        zis = (state.position, new[1], state.acceleration)
