"""Tests of sensorless.identification.friction with planted parameters."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.friction import Coulomb, CoulombViscous, LuGre, Stribeck
from sensorless.identification.friction import (
    FrictionFit,
    fit_coulomb,
    fit_coulomb_viscous,
    fit_lugre_dynamic,
    fit_stribeck,
    plot_friction_map,
    steady_state_map,
    sweep_velocities,
)

C_POS, C_NEG = 0.2508, -0.2591  # Table 2.2, joint 1


def _map(
    model: Coulomb | CoulombViscous | Stribeck, noise: float = 0.0, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    v = sweep_velocities()
    f = model.torque(v[:, None])[:, 0]
    if noise:
        f = f + np.random.default_rng(seed).normal(0.0, noise, v.size)
    return v, f


def test_sweep_velocities_match_thesis() -> None:
    v = sweep_velocities()
    assert np.all(v != 0.0)
    assert np.all(np.diff(v) > 0.0)
    assert v[0] == -2.0 and v[-1] == 2.0
    np.testing.assert_allclose(np.diff(v[v > 0.11]), 0.16, atol=1e-12)
    slow = v[np.abs(v) <= 0.11 + 1e-12]
    np.testing.assert_allclose(slow[slow > 0], np.arange(1, 12) * 0.01, atol=1e-12)
    assert v.size == 26 + 22 - 2  # +-0.08 lies on both sweeps


def test_sweep_velocities_rejects_bad_range() -> None:
    with pytest.raises(InputValueError, match="step > 0"):
        sweep_velocities(fast=(-2.0, 2.0, 0.0))


def test_fit_coulomb_recovers_table_2_2() -> None:
    fit = fit_coulomb(*_map(Coulomb(C_POS, C_NEG)))
    assert isinstance(fit, FrictionFit) and isinstance(fit.model, Coulomb)
    assert fit.parameters["c_pos"] == pytest.approx(C_POS, abs=1e-6)
    assert fit.parameters["c_neg"] == pytest.approx(C_NEG, abs=1e-6)
    assert fit.rms < 1e-9
    assert fit.to_pandas()["c_pos"] == pytest.approx(C_POS, abs=1e-6)


def test_fit_coulomb_noisy() -> None:
    fit = fit_coulomb(*_map(Coulomb(C_POS, C_NEG), noise=0.01))
    assert fit.parameters["c_pos"] == pytest.approx(C_POS, rel=0.03)
    assert fit.parameters["c_neg"] == pytest.approx(C_NEG, rel=0.03)
    assert fit.rms == pytest.approx(0.01, rel=0.3)


def test_fit_coulomb_viscous_recovers_parameters() -> None:
    planted = CoulombViscous(C_POS, C_NEG, 0.3)
    fit = fit_coulomb_viscous(*_map(planted))
    assert isinstance(fit.model, CoulombViscous)
    for name, value in (("c_pos", C_POS), ("c_neg", C_NEG), ("fv", 0.3)):
        assert fit.parameters[name] == pytest.approx(value, abs=1e-6)
    noisy = fit_coulomb_viscous(*_map(planted, noise=0.01, seed=1))
    for name, value in (("c_pos", C_POS), ("c_neg", C_NEG), ("fv", 0.3)):
        assert noisy.parameters[name] == pytest.approx(value, rel=0.03)


def test_fit_stribeck_recovers_parameters() -> None:
    planted = {"fc": 0.25, "fs": 0.4, "vs": 0.05, "fv": 0.1}
    fit = fit_stribeck(*_map(Stribeck(**planted)))
    assert isinstance(fit.model, Stribeck)
    for name, value in planted.items():
        assert fit.parameters[name] == pytest.approx(value, abs=1e-6)
    noisy = fit_stribeck(*_map(Stribeck(**planted), noise=0.002, seed=2))
    for name, value in planted.items():
        assert noisy.parameters[name] == pytest.approx(value, rel=0.05)


def test_fit_stribeck_exponent_one() -> None:
    planted = {"fc": 0.3, "fs": 0.5, "vs": 0.03, "fv": 0.2}
    fit = fit_stribeck(*_map(Stribeck(**planted, delta=1.0)), delta=1.0)
    for name, value in planted.items():
        assert fit.parameters[name] == pytest.approx(value, abs=1e-6)


def _sweep_log(
    model: LuGre, velocities: np.ndarray, hold: float, dt: float, ramp_time: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ramp = np.linspace(0.0, 1.0, int(ramp_time / dt), endpoint=False)
    pieces, previous = [], 0.0
    for v in velocities:
        pieces += [previous + (v - previous) * ramp, np.full(int(hold / dt), v)]
        previous = v
    qd = np.concatenate(pieces)
    tau, _ = model.torque(qd[:, None], dt)
    return np.arange(qd.size) * dt, qd, tau[:, 0]


VELOCITIES = np.array([-1.2, -0.4, -0.05, -0.01, 0.01, 0.05, 0.4, 1.2, 0.002, -0.001])


def test_steady_state_map_recovers_stribeck_curve() -> None:
    model = LuGre.canudas1995()
    velocities = VELOCITIES
    t, qd, tau = _sweep_log(model, velocities, hold=0.7, dt=1e-3, ramp_time=0.0)
    table = steady_state_map(t, qd, tau, settle=0.5)
    assert isinstance(table, pd.DataFrame)
    assert list(table.columns) == ["velocity", "torque", "torque_std", "n_samples"]
    np.testing.assert_allclose(table["velocity"], np.sort(velocities), rtol=1e-12)
    expected = model.steady_state(table["velocity"].to_numpy()[:, None])[:, 0]
    np.testing.assert_allclose(table["torque"], expected, rtol=1e-9, atol=1e-9)
    assert np.all(table["torque_std"] < 1e-9)
    assert np.all(np.abs(table["n_samples"] - 200) <= 1)  # 0.2 s kept at 1 kHz
    fit = fit_stribeck(table["velocity"], table["torque"])
    assert fit.parameters["fc"] == pytest.approx(1.0, rel=1e-4)
    assert fit.parameters["fv"] == pytest.approx(0.4, rel=1e-4)


def test_steady_state_map_with_ramps_between_plateaus() -> None:
    # Ramp samples within the tolerance join a plateau: small, bounded bias.
    model = LuGre.canudas1995()
    t, qd, tau = _sweep_log(model, VELOCITIES, hold=0.7, dt=1e-3, ramp_time=0.05)
    table = steady_state_map(t, qd, tau)
    np.testing.assert_allclose(table["velocity"], np.sort(VELOCITIES), rtol=2e-3)
    expected = model.steady_state(np.sort(VELOCITIES)[:, None])[:, 0]
    np.testing.assert_allclose(table["torque"], expected, rtol=1e-3)


def test_steady_state_map_errors() -> None:
    t = np.arange(100) * 1e-3
    with pytest.raises(InputValueError, match="no constant-velocity plateau"):
        steady_state_map(t, np.linspace(-1.0, 1.0, 100), np.zeros(100))
    with pytest.raises(InputValueError, match="qd must be finite"):
        steady_state_map(t, np.r_[np.nan, np.ones(99)], np.zeros(100))
    with pytest.raises(DimensionError, match="same length"):
        steady_state_map(t, np.ones(99), np.zeros(100))
    with pytest.raises(InputValueError, match="strictly increasing"):
        steady_state_map(t[::-1], np.ones(100), np.zeros(100))
    with pytest.raises(InputValueError, match="tolerance"):
        steady_state_map(t, np.ones(100), np.zeros(100), tolerance=0.0)
    with pytest.raises(DimensionError, match=r"shape \(n_samples,\)"):
        steady_state_map(t[:, None], np.ones(100), np.zeros(100))


def test_fit_errors() -> None:
    v = np.array([0.1, 0.2, 0.3, 0.4])
    with pytest.raises(InputValueError, match="1 positive and 1 negative"):
        fit_coulomb(v, np.full(4, 0.25))
    with pytest.raises(InputValueError, match="sign of the velocity"):
        fit_coulomb(np.r_[-v, v], np.r_[np.full(4, 0.2), np.full(4, -0.2)])
    with pytest.raises(DimensionError, match="same length"):
        fit_coulomb_viscous(np.r_[-v, v], np.ones(7))
    with pytest.raises(InputValueError, match="f must be finite"):
        fit_stribeck(np.r_[-v, v], np.r_[np.ones(7), np.inf])
    with pytest.raises(InputValueError, match="4 distinct nonzero speeds"):
        fit_stribeck(np.r_[-v[:2], v[:1]], np.r_[-np.ones(2), np.ones(1)])
    with pytest.raises(InputValueError, match="delta"):
        fit_stribeck(np.r_[-v, v], np.r_[-np.ones(4), np.ones(4)], delta=-1.0)


def _presliding(
    model: LuGre, amplitude: float, frequency: float, dt: float = 1e-3
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(0.0, 0.5, dt)
    omega = 2.0 * np.pi * frequency
    qd = amplitude * omega * np.cos(omega * t)
    # Positions consistent with the held-velocity convention of LuGre.step.
    q = np.concatenate([[0.0], np.cumsum(qd * dt)])[:-1]
    tau, _ = model.torque(qd[:, None], dt)
    return t, q, tau[:, 0]


def test_fit_lugre_dynamic_recovers_sigma0_sigma1() -> None:
    planted = LuGre.canudas1995()
    static = Stribeck(fc=1.0, fs=1.5, vs=0.001, fv=0.4)
    amplitude = 0.2 * 1.0 / 1e5  # a fifth of fc / sigma0: presliding
    t, q, tau = _presliding(planted, amplitude, frequency=10.0)
    fit = fit_lugre_dynamic(t, q, tau, static)
    assert isinstance(fit.model, LuGre)
    assert fit.parameters["sigma0"] == pytest.approx(1e5, rel=0.01)
    assert fit.parameters["sigma1"] == pytest.approx(np.sqrt(1e5), rel=0.01)
    noisy_tau = tau + np.random.default_rng(3).normal(0.0, 0.005, tau.size)
    noisy = fit_lugre_dynamic(t, q, noisy_tau, static)
    assert noisy.parameters["sigma0"] == pytest.approx(1e5, rel=0.1)
    assert noisy.parameters["sigma1"] == pytest.approx(np.sqrt(1e5), rel=0.1)


def test_fit_lugre_dynamic_errors() -> None:
    static = Stribeck(fc=1.0, fs=1.5, vs=0.001, fv=0.4)
    t = np.arange(10) * 1e-3
    with pytest.raises(InputTypeError, match="Stribeck"):
        fit_lugre_dynamic(t, np.zeros(10), np.zeros(10), Coulomb(0.1, -0.1))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="uniformly sampled"):
        fit_lugre_dynamic(t**2, np.zeros(10), np.zeros(10), static)
    with pytest.raises(InputValueError, match="fc > 0"):
        fit_lugre_dynamic(t, np.zeros(10), np.zeros(10), Stribeck(fc=0.0, fs=1.0, vs=1e-3))


def test_plot_friction_map() -> None:
    v, f = _map(Coulomb(C_POS, C_NEG), noise=0.01)
    table = pd.DataFrame({"velocity": v, "torque": f, "torque_std": np.full(v.size, 0.01)})
    fit = fit_coulomb(v, f)
    figure = plot_friction_map(table, fit)
    assert isinstance(figure, Figure)
    axes = figure.axes[0]
    assert len(axes.lines) >= 1 and axes.get_xlabel().startswith("joint velocity")
    assert isinstance(plot_friction_map(table, LuGre.canudas1995()), Figure)
    assert isinstance(plot_friction_map(table), Figure)
    with pytest.raises(InputValueError, match="missing"):
        plot_friction_map(table.drop(columns="torque"))
