"""Tests of :mod:`sensorless.simulation.sensors`.

Quantisation and the play operator are checked against their defining
bounds (error <= res/2, |y - x| <= w, loop width 2w), noise against its
standard deviation over 100k seeded samples, and the streaming form against
the batch form.
"""

from __future__ import annotations

import numpy as np
import pytest

from sensorless.exceptions import DimensionError, InputValueError
from sensorless.simulation.sensors import SensorModel, SensorState

N_DOF = 3


def _state_of(rng: np.random.Generator) -> dict:
    return rng.bit_generator.state


def _triangle(amplitude: float, n_periods: int, n_per_period: int) -> np.ndarray:
    """Triangle wave starting at 0 and rising, ``n_per_period`` samples per period."""
    phase = np.arange(n_periods * n_per_period) / n_per_period
    return amplitude * (2 / np.pi) * np.arcsin(np.sin(2 * np.pi * phase))


def test_perfect_model_is_identity_and_leaves_rng_alone() -> None:
    model = SensorModel.perfect()
    assert model.is_perfect and model == SensorModel()
    rng = np.random.default_rng(1)
    before = _state_of(rng)
    q = np.random.default_rng(2).normal(size=(50, N_DOF))
    np.testing.assert_array_equal(model.measure_position(q, rng), q)
    np.testing.assert_array_equal(model.measure_motor_torque(q, rng), q)
    reading, state = model.measure_joint_torque(q, model.initial_state(N_DOF), rng)
    np.testing.assert_array_equal(reading, q)
    np.testing.assert_array_equal(state.torque_sensor_output, q[-1])
    np.testing.assert_array_equal(model.measure_position(q[0]), q[0])  # no rng needed
    assert _state_of(rng) == before


def test_quantisation_error_is_at_most_half_a_step() -> None:
    res = 2 * np.pi / 2**17
    model = SensorModel(encoder_resolution=res)
    assert not model.is_perfect
    q = np.random.default_rng(0).uniform(-3, 3, (10_000, N_DOF))
    q_meas = model.measure_position(q)
    assert np.max(np.abs(q_meas - q)) <= res / 2 * (1 + 1e-9)
    np.testing.assert_allclose(q_meas / res, np.round(q_meas / res), atol=1e-6)
    per_joint = SensorModel(encoder_resolution=[0.0, 0.1, 0.5])
    np.testing.assert_allclose(per_joint.measure_position([0.123, 0.123, 0.123]), [0.123, 0.1, 0.0])


@pytest.mark.parametrize(
    ("field", "method"),
    [
        ("position_noise", "measure_position"),
        ("motor_torque_noise", "measure_motor_torque"),
        ("torque_sensor_noise", "measure_joint_torque"),
    ],
)
def test_noise_standard_deviation(field: str, method: str) -> None:
    std = np.array([0.01, 0.5, 2.0])
    model = SensorModel(**{field: std})
    x = np.zeros((100_000, N_DOF))
    args = (model.initial_state(N_DOF),) if method == "measure_joint_torque" else ()
    out = getattr(model, method)(x, *args, np.random.default_rng(5))
    error = out[0] if isinstance(out, tuple) else out
    # the standard error of a sample std over 100k samples is std / sqrt(2e5) ≈ 0.22 %
    np.testing.assert_allclose(error.std(axis=0), std, rtol=0.01)
    assert np.all(np.abs(error.mean(axis=0)) <= 4 * std / np.sqrt(1e5))


def test_gain_error_and_bias() -> None:
    tau = np.array([[10.0, -4.0, 2.0], [1.0, 0.0, -1.0]])
    model = SensorModel(motor_torque_gain_error=[0.1, -0.2, 0.0], torque_sensor_bias=0.3)
    np.testing.assert_allclose(model.measure_motor_torque(tau), tau * [1.1, 0.8, 1.0])
    reading, _ = model.measure_joint_torque(tau, model.initial_state(N_DOF))
    np.testing.assert_allclose(reading, tau + 0.3)


def test_play_operator_loop_width_and_lag() -> None:
    w, amplitude, n_per_period = 0.5, 2.0, 400
    model = SensorModel(torque_sensor_hysteresis=w)
    x = _triangle(amplitude, n_periods=3, n_per_period=n_per_period)
    reading, _ = model.measure_joint_torque(x[:, None], model.initial_state(1))
    y = reading[:, 0]
    assert np.max(np.abs(y - x)) == pytest.approx(w, abs=1e-12)
    # loop width 2w: where x crosses 0 going up the output is -w, going down +w
    up = np.arange(1, 3) * n_per_period  # x = 0, rising (after the first period)
    down = up - n_per_period // 2  # x = 0, falling
    np.testing.assert_allclose(x[up], 0.0, atol=1e-12)
    np.testing.assert_allclose(y[up], -w, atol=1e-12)
    np.testing.assert_allclose(y[down], +w, atol=1e-12)
    # lag: after each peak of x the output holds at A - w until x has fallen by 2w
    slope = 4 * amplitude / n_per_period  # input change per sample
    hold = round(2 * w / slope)
    for peak in np.arange(3) * n_per_period + n_per_period // 4:
        np.testing.assert_allclose(y[peak : peak + hold + 1], amplitude - w, atol=1e-12)
        assert y[peak + hold + 1] < amplitude - w


def test_play_operator_ignores_small_inputs() -> None:
    model = SensorModel(torque_sensor_hysteresis=[0.5, 1.0])
    x = 0.45 * np.sin(np.linspace(0, 20, 500))[:, None] * [1.0, 2.0]
    reading, state = model.measure_joint_torque(x, model.initial_state(2))
    np.testing.assert_array_equal(reading, 0.0)
    np.testing.assert_array_equal(state.torque_sensor_output, 0.0)
    started, _ = model.measure_joint_torque([0.0, 0.0], model.initial_state(2, [0.3, -0.2]))
    np.testing.assert_array_equal(started, [0.3, -0.2])  # within ±w of 0: kept


def test_batch_equals_step_loop_and_chunks() -> None:
    model = SensorModel(
        torque_sensor_hysteresis=0.3, torque_sensor_bias=[0.1, -0.1, 0.0], torque_sensor_noise=0.05
    )
    x = np.random.default_rng(9).normal(size=(200, N_DOF)).cumsum(axis=0) * 0.1
    batch, final = model.measure_joint_torque(
        x, model.initial_state(N_DOF), np.random.default_rng(4)
    )
    rng = np.random.default_rng(4)
    state = model.initial_state(N_DOF)
    steps = []
    for sample in x:
        reading, state = model.measure_joint_torque(sample, state, rng)
        steps.append(reading)
    np.testing.assert_array_equal(np.array(steps), batch)
    np.testing.assert_array_equal(state.torque_sensor_output, final.torque_sensor_output)
    rng = np.random.default_rng(4)
    first, mid = model.measure_joint_torque(x[:77], model.initial_state(N_DOF), rng)
    second, _ = model.measure_joint_torque(x[77:], mid, rng)
    np.testing.assert_array_equal(np.vstack([first, second]), batch)


def test_same_seed_same_output() -> None:
    model = SensorModel(position_noise=1e-3, encoder_resolution=1e-4, motor_torque_noise=0.2)
    q = np.linspace(0, 1, 30).reshape(10, N_DOF)
    a = model.measure_position(q, np.random.default_rng(11))
    b = model.measure_position(q, np.random.default_rng(11))
    c = model.measure_position(q, np.random.default_rng(12))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_dict_round_trip_and_unknown_key() -> None:
    model = SensorModel(position_noise=1e-4, torque_sensor_bias=[0.1, 0.2, 0.3])
    data = model.to_dict()
    assert data["torque_sensor_bias"] == [0.1, 0.2, 0.3] and data["encoder_resolution"] == 0.0
    assert SensorModel.from_dict(data) == model
    with pytest.raises(TypeError, match=r"unknown SensorModel parameter\(s\) \['noise'\]; valid"):
        SensorModel.from_dict({"noise": 0.1})
    with pytest.raises(TypeError, match=r"expects a mapping"):
        SensorModel.from_dict([("position_noise", 0.1)])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"position_noise": -0.1}, InputValueError, r"position_noise must be >= 0"),
        ({"encoder_resolution": np.nan}, InputValueError, r"encoder_resolution must be finite"),
        ({"torque_sensor_hysteresis": [0.1, -1]}, InputValueError, r"hysteresis must be >= 0"),
        ({"motor_torque_gain_error": -1.0}, InputValueError, r"gain_error must be > -1"),
        ({"torque_sensor_bias": np.inf}, InputValueError, r"torque_sensor_bias must be finite"),
        ({"motor_torque_noise": "loud"}, InputValueError, r"must be a number or an array"),
        ({"torque_sensor_noise": [[0.1]]}, DimensionError, r"got shape \(1, 1\)"),
    ],
)
def test_model_validation(kwargs, error, match) -> None:
    with pytest.raises(error, match=match):
        SensorModel(**kwargs)


def test_measurement_errors() -> None:
    model = SensorModel(position_noise=[0.1, 0.2], torque_sensor_noise=0.1)
    with pytest.raises(TypeError, match=r"position_noise is on, so a numpy.random.Generator"):
        model.measure_position([0.0, 0.0])
    with pytest.raises(DimensionError, match=r"position_noise has 2 per-joint values; .* 3 joints"):
        model.measure_position([0.0, 0.0, 0.0], np.random.default_rng(0))
    with pytest.raises(DimensionError, match=r"state is for 3 joints; tau_j has 2"):
        model.measure_joint_torque([0.0, 0.0], model.initial_state(3), np.random.default_rng(0))
    with pytest.raises(TypeError, match=r"state must be a SensorState"):
        model.measure_joint_torque([0.0, 0.0], None, np.random.default_rng(0))  # type: ignore[arg-type]
    with pytest.raises(DimensionError, match=r"q must have shape \(n_dof,\) or"):
        model.measure_position(np.zeros((2, 2, 2)))
    with pytest.raises(InputValueError, match=r"q must be finite"):
        SensorModel().measure_position([0.0, np.nan])
    with pytest.raises(InputValueError, match=r"n_dof must be a positive integer"):
        model.initial_state(0)
    with pytest.raises(DimensionError, match=r"tau_j0 must have shape \(2,\)"):
        model.initial_state(2, [1.0, 2.0, 3.0])
    assert isinstance(model.initial_state(2), SensorState)
