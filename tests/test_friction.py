"""Tests of :mod:`sensorless.friction`.

Expected values are written out from the formulas of the thesis and the cited
papers (with :mod:`math`), and the LuGre discretisation is checked against an
independent stiff ODE solver and against the model's physical invariants.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sensorless.exceptions import DimensionError, InputValueError
from sensorless.friction import (
    Coulomb,
    CoulombViscous,
    FrictionModel,
    HystereticError,
    LuGre,
    Sigmoid,
    Stribeck,
    Viscous,
)

# Thesis Table 2.2 (KUKA LWR, effective motor-side friction), joints 1-7.
TABLE_2_2_C_POS = [0.2508, 0.4902, 0.3609, 0.3491, 0.2945, 1.1474, 0.2954]
TABLE_2_2_C_NEG = [-0.2591, -0.4939, -0.3717, -0.3581, -0.3034, -1.1174, -0.2961]

# Gaz et al. 2019, Franka Panda, joints 1-7 (parameters.md).
PANDA_PHI1 = [0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489]
PANDA_PHI2 = [5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336]
PANDA_PHI3 = [0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526]

# Canudas de Wit et al. 1995, Table I.
SIGMA0, SIGMA1, SIGMA2, FC, FS, VS = 1e5, math.sqrt(1e5), 0.4, 1.0, 1.5, 0.001
DT = 1e-3


def gaussian_stribeck(v: float) -> float:
    """Steady-state LuGre friction of the 1995 paper, written from the paper."""
    if v == 0.0:
        return 0.0
    return math.copysign(FC + (FS - FC) * math.exp(-((v / VS) ** 2)), v) + SIGMA2 * v


# --------------------------------------------------------------------------- stateless


def test_coulomb_table_2_2_joint_1() -> None:
    model = Coulomb(c_pos=0.2508, c_neg=-0.2591)
    qd = np.array([[-2.0], [-1e-9], [0.0], [1e-9], [1.5]])
    expected = np.array([[-0.2591], [-0.2591], [0.0], [0.2508], [0.2508]])
    np.testing.assert_array_equal(model.torque(qd), expected)
    assert model.n_dof == 1


def test_coulomb_all_joints_dissipate() -> None:
    model = Coulomb(TABLE_2_2_C_POS, TABLE_2_2_C_NEG)
    assert model.n_dof == 7
    qd = np.array([0.3, -0.2, 1.0, -1.0, 0.0, 2.0, -0.01])
    tau = model.torque(qd)
    expected = [0.2508, -0.4939, 0.3609, -0.3581, 0.0, 1.1474, -0.2961]
    np.testing.assert_array_equal(tau, expected)
    # Dissipated torque has the sign of the velocity (module convention).
    assert np.all(tau * qd >= 0.0)


def test_viscous_hand_values() -> None:
    model = Viscous(fv=[0.5, 2.0])
    np.testing.assert_allclose(model.torque([1.0, -3.0]), [0.5, -6.0], rtol=0, atol=0)
    np.testing.assert_allclose(
        model.torque([[0.0, 0.0], [-0.2, 0.25]]), [[0.0, 0.0], [-0.1, 0.5]], rtol=1e-15
    )


def test_coulomb_viscous_hand_values() -> None:
    model = CoulombViscous(c_pos=0.2508, c_neg=-0.2591, fv=0.1)
    qd = np.array([[-2.0], [0.0], [0.5]])
    expected = np.array([[-0.2591 - 0.2], [0.0], [0.2508 + 0.05]])
    np.testing.assert_allclose(model.torque(qd), expected, rtol=1e-15)


def test_stribeck_gaussian_hand_values() -> None:
    model = Stribeck(fc=FC, fs=FS, vs=VS, fv=SIGMA2)  # delta = 2 by default
    velocities = [0.0, 0.0005, -0.001, 0.002, -0.1, 10.0]
    expected = [
        0.0,
        1.0 + 0.5 * math.exp(-0.25) + 0.4 * 0.0005,
        -(1.0 + 0.5 * math.exp(-1.0)) - 0.4 * 0.001,
        1.0 + 0.5 * math.exp(-4.0) + 0.4 * 0.002,
        -1.0 - 0.04,  # exp(-1e4) underflows to 0
        1.0 + 4.0,
    ]
    tau = model.torque(np.array(velocities)[:, None])
    np.testing.assert_allclose(tau[:, 0], expected, rtol=1e-14)


def test_stribeck_thesis_exponential_form() -> None:
    # eq. (4.22c): s = Fc + (Fs - Fc) exp(-alpha |qd|) is delta = 1, vs = 1 / alpha.
    alpha = 500.0
    model = Stribeck(fc=0.8, fs=1.2, vs=1.0 / alpha, delta=1.0)
    for v in [0.001, -0.004, 0.02]:
        expected = math.copysign(0.8 + 0.4 * math.exp(-alpha * abs(v)), v)
        assert model.torque([v])[0] == pytest.approx(expected, rel=1e-14)


def test_sigmoid_panda_joint_1() -> None:
    phi1, phi2, phi3 = PANDA_PHI1[0], PANDA_PHI2[0], PANDA_PHI3[0]
    model = Sigmoid(phi1, phi2, phi3)
    offset = phi1 / (1.0 + math.exp(-phi2 * phi3))
    assert model.torque([0.0])[0] == 0.0
    assert model.torque([100.0])[0] == pytest.approx(phi1 - offset, rel=1e-12)
    assert model.torque([-100.0])[0] == pytest.approx(-offset, rel=1e-12)
    for v in [0.5, -0.3]:
        expected = phi1 / (1.0 + math.exp(-phi2 * (v + phi3))) - offset
        assert model.torque([v])[0] == pytest.approx(expected, rel=1e-13)


def test_sigmoid_all_panda_joints_dissipate_without_overflow() -> None:
    model = Sigmoid(PANDA_PHI1, PANDA_PHI2, PANDA_PHI3)
    qd = np.outer([-1e6, -1.0, -1e-3, 1e-3, 1.0, 1e6], np.ones(7))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # exp overflow would warn
        tau = model.torque(qd)
    assert np.all(np.isfinite(tau))
    assert np.all(np.sign(tau) == np.sign(qd))


def test_hysteretic_error_eq_5_38() -> None:
    model = HystereticError(c=[0.2678, 0.5654, 0.4367])  # Table 5.7
    np.testing.assert_array_equal(model.torque([2.0, -0.1, 0.0]), [-0.2678, 0.5654, 0.0])


STATELESS = [
    Coulomb(TABLE_2_2_C_POS[:3], TABLE_2_2_C_NEG[:3]),
    Viscous([0.1, 0.2, 0.3]),
    CoulombViscous(TABLE_2_2_C_POS[:3], TABLE_2_2_C_NEG[:3], 0.05),
    Stribeck(fc=[1.0, 0.5, 0.2], fs=1.5, vs=[0.001, 0.01, 0.1], fv=0.4, delta=[2.0, 1.0, 0.5]),
    Sigmoid(PANDA_PHI1[:3], PANDA_PHI2[:3], PANDA_PHI3[:3]),
    HystereticError([0.2678, 0.5654, 0.4367]),
]


@pytest.mark.parametrize("model", STATELESS, ids=lambda m: type(m).__name__)
def test_stateless_sample_equals_series(model: FrictionModel) -> None:
    rng = np.random.default_rng(0)
    qd = rng.normal(scale=0.5, size=(20, 3))
    qd[3] = 0.0
    series = model.torque(qd)
    assert isinstance(model, FrictionModel)
    assert series.shape == qd.shape
    assert model.torque(qd[5]).shape == (3,)
    for k in range(qd.shape[0]):
        np.testing.assert_array_equal(model.torque(qd[k]), series[k])


def test_parameters_broadcast_and_are_immutable() -> None:
    model = Coulomb(c_pos=[0.1, 0.2], c_neg=-0.3)
    assert model.n_dof == 2
    np.testing.assert_array_equal(model.c_neg, [-0.3, -0.3])
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.c_pos = np.zeros(2)  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        model.c_pos[0] = 1.0
    copy = dataclasses.replace(model, c_pos=0.5)
    np.testing.assert_array_equal(copy.c_pos, [0.5, 0.5])


# --------------------------------------------------------------------------- LuGre


def test_canudas1995_parameters() -> None:
    model = LuGre.canudas1995(n_dof=3)
    assert model.n_dof == 3
    for name, value in [
        ("sigma0", 1e5),
        ("sigma1", math.sqrt(1e5)),
        ("sigma2", 0.4),
        ("fc", 1.0),
        ("fs", 1.5),
        ("vs", 0.001),
        ("delta", 2.0),
    ]:
        np.testing.assert_array_equal(getattr(model, name), np.full(3, value))
    np.testing.assert_array_equal(model.initial_state(), np.zeros(3))


def test_lugre_steady_state_is_stribeck_curve() -> None:
    speeds = [0.0005, 0.002, 0.01, 0.1, 1.0]
    velocities = np.array(speeds + [-v for v in speeds])
    model = LuGre.canudas1995(n_dof=velocities.size)
    qd = np.tile(velocities, (2000, 1))  # 2 s; slowest time constant is 28 ms
    tau, z = model.torque(qd, DT)
    expected = np.array([gaussian_stribeck(v) for v in velocities])
    np.testing.assert_allclose(tau[-1], expected, rtol=1e-12)
    np.testing.assert_allclose(model.steady_state(velocities), expected, rtol=1e-14)
    # In steady state the bristles carry the Stribeck level: sigma0 z = s(qd).
    np.testing.assert_allclose(SIGMA0 * z, expected - SIGMA2 * velocities, rtol=1e-12)


def test_lugre_thesis_exponential_steady_state() -> None:
    alpha = 200.0
    model = LuGre(sigma0=1e4, sigma1=50.0, sigma2=0.1, fc=0.3, fs=0.5, vs=1 / alpha, delta=1.0)
    v = -0.004
    tau, _ = model.torque(np.full((3000, 1), v), DT)
    expected = -(0.3 + 0.2 * math.exp(-alpha * abs(v))) + 0.1 * v
    assert tau[-1, 0] == pytest.approx(expected, rel=1e-12)


def test_lugre_presliding_is_a_spring_of_stiffness_sigma0() -> None:
    model = LuGre.canudas1995()
    qd_small = 1e-6  # for 0.1 s: displacement 1e-7 rad << fc / sigma0 = 1e-5 rad
    n = 100
    displacement = qd_small * n * DT
    qd = np.concatenate([np.full((n, 1), qd_small), np.zeros((1, 1))])
    tau, z = model.torque(qd, DT)
    # Last sample at rest: no damping or viscous term, the torque is the spring.
    assert tau[-1, 0] == pytest.approx(SIGMA0 * displacement, rel=0.01)
    assert tau[-1, 0] == pytest.approx(SIGMA0 * z[0], rel=1e-12)
    assert abs(tau[-1, 0]) < 0.01 * FC
    # Moving back by the same amount releases the spring (elastic presliding).
    _, z_back = model.torque(np.full((n, 1), -qd_small), DT, z0=z)
    assert abs(z_back[0]) < 0.02 * displacement


def test_lugre_long_sinusoid_stays_bounded() -> None:
    model = LuGre.canudas1995(n_dof=2)
    t = np.arange(100_000) * DT  # 100 s at 1 kHz
    qd = np.column_stack([0.01, 1.0]) * np.sin(2 * np.pi * 0.5 * t)[:, None]
    z = model.initial_state()
    tau = np.empty_like(qd)
    z_series = np.empty_like(qd)
    for k in range(t.size):
        tau[k], z = model.step(qd[k], DT, z)
        z_series[k] = z
    assert np.all(np.isfinite(tau)) and np.all(np.isfinite(z_series))
    # LuGre invariant: |z(0)| <= Fs / sigma0 implies |z(t)| <= Fs / sigma0.
    assert np.max(np.abs(z_series)) <= FS / SIGMA0 * (1 + 1e-12)
    # With |z| <= Fs/sigma0: |zdot| <= |qd| (1 + Fs / Fc), hence this bound on tau.
    qd_max = np.max(np.abs(qd), axis=0)
    bound = FS + SIGMA1 * (1 + FS / FC) * qd_max + SIGMA2 * qd_max
    assert np.all(np.max(np.abs(tau), axis=0) <= bound)
    # Sliding well above vs the fast bristles follow the steady-state curve.
    sliding = np.abs(qd[:, 1]) > 0.1
    steady = np.array([gaussian_stribeck(v) for v in qd[sliding, 1]])
    np.testing.assert_allclose(tau[sliding, 1], steady, atol=1e-2)


def test_lugre_matches_stiff_ode_solver() -> None:
    model = LuGre.canudas1995(n_dof=2)
    n = 120
    t = np.arange(n) * DT
    qd = np.column_stack(
        [0.004 * np.sin(2 * np.pi * 10 * t), 0.5 * np.sin(2 * np.pi * 10 * t + 0.3)]
    )

    z = model.initial_state()
    z_model = np.empty_like(qd)
    tau_model = np.empty_like(qd)
    for k in range(n):
        tau_model[k], z = model.step(qd[k], DT, z)
        z_model[k] = z

    z_ref = np.empty_like(qd)
    z_now = np.zeros(2)
    for k in range(n):
        v = qd[k]
        level = FC + (FS - FC) * np.exp(-((v / VS) ** 2))
        rate = SIGMA0 * np.abs(v) / level

        def rhs(_t: float, zz: np.ndarray, v: np.ndarray = v, rate: np.ndarray = rate):
            return v - rate * zz

        sol = solve_ivp(
            rhs,
            (0.0, DT),
            z_now,
            method="Radau",
            rtol=1e-12,
            atol=1e-22,
            jac=lambda _t, _z, rate=rate: np.diag(-rate),
        )
        assert sol.success
        z_now = sol.y[:, -1]
        z_ref[k] = z_now

    np.testing.assert_allclose(z_model, z_ref, rtol=1e-9, atol=1e-9 * FS / SIGMA0)
    # eq. (4.22b) at the sample instants, from the reference state.
    level = FC + (FS - FC) * np.exp(-((qd / VS) ** 2))
    zdot_ref = qd - SIGMA0 * np.abs(qd) / level * z_ref
    tau_ref = SIGMA0 * z_ref + SIGMA1 * zdot_ref + SIGMA2 * qd
    np.testing.assert_allclose(tau_model, tau_ref, rtol=1e-6, atol=1e-6)


def _lugre_test_series() -> np.ndarray:
    t = np.arange(1500) * DT
    return np.column_stack([0.003 * np.sin(2 * np.pi * 3 * t), 0.2 * np.cos(2 * np.pi * 2 * t)])


def test_lugre_chunked_equals_whole() -> None:
    model = LuGre.canudas1995(n_dof=2)
    qd = _lugre_test_series()
    tau_whole, z_whole = model.torque(qd, DT)
    parts, z = [], model.initial_state()
    for chunk in np.split(qd, [1, 37, 700, 701]):
        tau_part, z = model.torque(chunk, DT, z0=z)
        parts.append(tau_part)
    assert np.array_equal(np.concatenate(parts), tau_whole)
    assert np.array_equal(z, z_whole)


def test_lugre_step_loop_equals_series() -> None:
    model = LuGre.canudas1995(n_dof=2)
    qd = _lugre_test_series()
    z0 = np.array([5e-6, -1e-5])
    tau_series, z_series_final = model.torque(qd, DT, z0=z0)
    z = z0
    for k in range(qd.shape[0]):
        tau_k, z = model.step(qd[k], DT, z)
        assert np.array_equal(tau_k, tau_series[k])
    assert np.array_equal(z, z_series_final)
    np.testing.assert_array_equal(z0, [5e-6, -1e-5])  # input state not modified


def test_lugre_continuous_time_functions() -> None:
    model = LuGre.canudas1995(n_dof=2)
    qd = np.array([[0.002, -0.5], [0.0, 0.01]])
    z = np.array([[1e-5, -2e-6], [3e-6, 0.0]])
    level = FC + (FS - FC) * np.exp(-((qd / VS) ** 2))
    zdot = qd - SIGMA0 * np.abs(qd) / level * z
    np.testing.assert_allclose(model.bristle_dynamics(qd, z), zdot, rtol=1e-14)
    np.testing.assert_allclose(model.bristle_dynamics(qd[0], z[0]), zdot[0], rtol=1e-14)
    tau = SIGMA0 * z + SIGMA1 * zdot + SIGMA2 * qd
    np.testing.assert_allclose(model.torque_from_state(qd, z), tau, rtol=1e-12)


def test_lugre_step_size_does_not_matter_at_constant_velocity() -> None:
    # The update is the exact solution for held velocity: 1 step of 10 ms = 10 of 1 ms.
    model = LuGre.canudas1995()
    z0 = np.array([-1e-5])
    _, z_coarse = model.step([0.0007], 10 * DT, z0)
    _, z_fine = model.torque(np.full((10, 1), 0.0007), DT, z0=z0)
    np.testing.assert_allclose(z_coarse, z_fine, rtol=1e-12)


# --------------------------------------------------------------------------- bad input


def test_wrong_joint_count() -> None:
    with pytest.raises(DimensionError, match=r"shape \(2,\) or \(n_samples, 2\).*got shape \(3,\)"):
        Viscous([0.1, 0.2]).torque([1.0, 2.0, 3.0])
    model = LuGre.canudas1995(n_dof=2)
    with pytest.raises(DimensionError, match=r"got shape \(4, 3\)"):
        model.torque(np.zeros((4, 3)), DT)
    with pytest.raises(DimensionError, match=r"z0 must have shape \(2,\)"):
        model.torque(np.zeros((4, 2)), DT, z0=np.zeros(3))
    with pytest.raises(DimensionError, match=r"qd must be one sample of shape \(2,\)"):
        model.step(np.zeros((3, 2)), DT, model.initial_state())
    with pytest.raises(DimensionError, match="z must have the shape of qd"):
        model.bristle_dynamics(np.zeros((3, 2)), np.zeros(2))


def test_nan_velocity() -> None:
    with pytest.raises(InputValueError, match="qd must be finite; found nan at sample 1, joint 0"):
        Coulomb(0.2508, -0.2591).torque([[0.1], [np.nan]])
    model = LuGre.canudas1995()
    with pytest.raises(InputValueError, match="qd must be finite"):
        model.step([np.nan], DT, model.initial_state())
    with pytest.raises(InputValueError, match="z must be finite"):
        model.step([0.1], DT, [np.inf])


@pytest.mark.parametrize(
    ("factory", "pattern"),
    [
        (lambda: Viscous(-0.1), r"Viscous: fv must be >= 0 .*got -0.1 at joint 0"),
        (lambda: Coulomb(0.25, 0.26), r"Coulomb: c_neg must be <= 0 .*-0.2591.*got 0.26"),
        (lambda: Coulomb(-0.25, -0.26), r"Coulomb: c_pos must be >= 0"),
        (lambda: CoulombViscous(0.25, -0.26, -1.0), r"CoulombViscous: fv must be >= 0"),
        (lambda: Stribeck(fc=1.0, fs=1.5, vs=0.0), r"Stribeck: vs must be > 0"),
        (lambda: Sigmoid(0.5, -5.0, 0.0), r"Sigmoid: phi2 must be >= 0"),
        (
            lambda: LuGre(-1e5, 316.0, 0.4, 1.0, 1.5, 0.001),
            r"LuGre: sigma0 must be > 0 .*got -100000.0 at joint 0",
        ),
        (lambda: LuGre(1e5, 316.0, [0.4, -0.4], 1.0, 1.5, 0.001), r"sigma2 .*at joint 1"),
        (lambda: Viscous(np.nan), r"Viscous: fv must be finite"),
    ],
)
def test_invalid_parameters(factory: object, pattern: str) -> None:
    with pytest.raises(InputValueError, match=pattern):
        factory()  # type: ignore[operator]


def test_parameter_shapes() -> None:
    with pytest.raises(DimensionError, match=r"one common length n_dof; got shapes"):
        Coulomb([0.1, 0.2], [-0.1, -0.2, -0.3])
    with pytest.raises(DimensionError, match=r"scalar or a non-empty array"):
        Viscous(np.ones((2, 2)))
    with pytest.raises(InputValueError, match="n_dof must be a positive integer; got 0"):
        LuGre.canudas1995(n_dof=0)


@pytest.mark.parametrize("dt", [0.0, -1e-3, np.inf, "fast"])
def test_nonpositive_dt(dt: object) -> None:
    model = LuGre.canudas1995()
    with pytest.raises(InputValueError, match="dt must be a positive"):
        model.torque(np.zeros((2, 1)), dt)
    with pytest.raises(InputValueError, match="dt must be a positive"):
        model.step([0.0], dt, model.initial_state())
