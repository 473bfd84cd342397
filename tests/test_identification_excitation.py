"""Tests of :mod:`sensorless.identification.excitation` and the Fourier file format.

The optimisations are kept small (planar arm, 3 harmonics; a 2-harmonic
Panda) so that each runs in about a second on one core.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import sensorless as sl
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.identification.excitation import (
    ExcitationResult,
    load_excitation,
    optimize_excitation,
)
from sensorless.identification.regression import identify_base_parameters
from sensorless.trajectories import FourierSeries

PLANAR_OPTIONS = {
    "n_harmonics": 3,
    "base_frequency": 0.2,
    "n_samples": 60,
    "position_limits": ([-2.0, -1.5], [2.0, 2.5]),
    "velocity_limits": [1.5, 2.0],
    "acceleration_limits": [4.0, 5.0],
}
#: Dense-grid tolerance, relative to each limit: the check grid (10 × n_samples)
#: holds exactly; between its points a harmonic of N f overshoots its sampled
#: peak by at most 1 − cos(π N / (10 n_samples)) ≈ 1.2e-4 of its amplitude here.
DENSE_TOLERANCE = 1e-3


@pytest.fixture(scope="module")
def planar2() -> sl.RobotModel:
    return sl.robots.load("planar2")


@pytest.fixture(scope="module")
def planar_result(planar2: sl.RobotModel) -> ExcitationResult:
    return optimize_excitation(planar2, seed=0, n_restarts=2, max_iterations=150, **PLANAR_OPTIONS)


def stacked_condition(base: sl.BaseParameters, trajectory: FourierSeries, n_samples: int) -> float:
    """cond of the base regressor stacked over ``n_samples`` instants of one period."""
    t = np.arange(n_samples) * trajectory.duration / n_samples
    q, qd, qdd = trajectory.evaluate(t)
    return float(np.linalg.cond(base.regressor(q, qd, qdd).reshape(-1, base.count)))


def assert_within_limits(result: ExcitationResult, trajectory: FourierSeries, n: int) -> None:
    # An irrational offset keeps the dense grid off the optimisation and check grids.
    t = (np.arange(n) + 1 / np.sqrt(2)) * trajectory.duration / n
    q, qd, qdd = trajectory.evaluate(t)
    span = result.upper_limit - result.lower_limit
    assert (q >= result.lower_limit - DENSE_TOLERANCE * span).all()
    assert (q <= result.upper_limit + DENSE_TOLERANCE * span).all()
    assert (np.abs(qd) <= result.velocity_limit * (1 + DENSE_TOLERANCE)).all()
    assert (np.abs(qdd) <= result.acceleration_limit * (1 + DENSE_TOLERANCE)).all()


# ---------------------------------------------------------------------- optimisation


def test_limits_hold_on_a_dense_grid(planar_result: ExcitationResult) -> None:
    assert planar_result.within_limits
    assert 0.0 < planar_result.amplitude_scale <= 1.0
    assert_within_limits(planar_result, planar_result.trajectory, 40 * planar_result.n_samples)
    np.testing.assert_array_equal(planar_result.lower_limit, [-2.0, -1.5])
    np.testing.assert_array_equal(planar_result.acceleration_limit, [4.0, 5.0])
    # The reported extremes are those of the trajectory (check grid ⊂ dense truth).
    t = np.linspace(0.0, planar_result.trajectory.duration, 4001)
    q, qd, _ = planar_result.trajectory.evaluate(t)
    np.testing.assert_allclose(planar_result.max_position, q.max(axis=0), rtol=1e-3)
    np.testing.assert_allclose(planar_result.max_velocity, np.abs(qd).max(axis=0), rtol=1e-3)


def test_condition_number_improves_on_the_random_start(
    planar2: sl.RobotModel, planar_result: ExcitationResult
) -> None:
    base = sl.base_parameters(planar2)
    n = planar_result.n_samples
    final = stacked_condition(base, planar_result.trajectory, n)
    start = stacked_condition(base, planar_result.initial_trajectory, n)
    assert planar_result.condition_number == pytest.approx(final, rel=1e-9)
    assert planar_result.initial_condition_number == pytest.approx(start, rel=1e-9)
    assert final < 0.5 * start
    assert planar_result.success and planar_result.n_iterations > 0
    assert planar_result.base_names == base.names
    assert planar_result.trajectory.duration == pytest.approx(5.0)


def test_same_seed_gives_identical_coefficients(planar2: sl.RobotModel) -> None:
    options = {**PLANAR_OPTIONS, "n_restarts": 1, "max_iterations": 15}
    first = optimize_excitation(planar2, seed=3, **options)
    again = optimize_excitation(planar2, seed=3, **options)
    other = optimize_excitation(planar2, seed=4, **options)
    for name in ("a", "b", "q0"):
        np.testing.assert_array_equal(
            getattr(first.trajectory, name), getattr(again.trajectory, name)
        )
    assert first.condition_number == again.condition_number
    assert not np.array_equal(first.trajectory.a, other.trajectory.a)


def test_start_at_rest(planar2: sl.RobotModel) -> None:
    result = optimize_excitation(
        planar2, seed=1, n_restarts=1, max_iterations=30, start_at_rest=True, **PLANAR_OPTIONS
    )
    _, qd, qdd = result.trajectory.evaluate(0.0)
    np.testing.assert_allclose(qd, 0.0, atol=1e-9)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-9)
    np.testing.assert_allclose(result.initial_trajectory.evaluate(0.0)[1], 0.0, atol=1e-12)
    assert result.condition_number < result.initial_condition_number
    assert result.within_limits


def test_coarse_grid_is_shrunk_into_the_limits(planar2: sl.RobotModel) -> None:
    """With 7 instants per period the optimum overshoots between them; a, b are shrunk."""
    options = {**PLANAR_OPTIONS, "n_samples": 7}
    result = optimize_excitation(planar2, seed=0, n_restarts=1, max_iterations=40, **options)
    assert result.amplitude_scale < 1.0
    assert result.within_limits
    assert_within_limits(result, result.trajectory, 4000)
    base = sl.base_parameters(planar2)
    assert result.condition_number == pytest.approx(
        stacked_condition(base, result.trajectory, 7), rel=1e-9
    )


def test_panda_identification_along_optimised_trajectory() -> None:
    """Noise-free torques of panda_gaz along the optimised trajectory give θ exactly."""
    robot = sl.robots.load("panda_gaz")
    result = optimize_excitation(
        robot, n_harmonics=2, n_samples=40, n_restarts=1, max_iterations=15, seed=0
    )
    assert result.condition_number < result.initial_condition_number
    assert result.within_limits
    lower, upper = robot.position_limits
    assert (result.lower_limit > lower).all() and (result.upper_limit < upper).all()
    np.testing.assert_allclose(result.velocity_limit, 0.8 * robot.velocity_limits)
    assert np.isinf(result.acceleration_limit).all()
    _, q, qd, qdd = result.trajectory.sample(result.trajectory.duration / 200)
    tau = robot.inverse_dynamics(q, qd, qdd)
    base, fit = identify_base_parameters(robot, q, qd, qdd, tau, friction=None)
    truth = base.values
    np.testing.assert_allclose(fit.estimates, truth, rtol=1e-6, atol=1e-6 * np.abs(truth).max())


# ---------------------------------------------------------------------- files


def test_fourier_dict_round_trip_is_exact(planar_result: ExcitationResult) -> None:
    trajectory = planar_result.trajectory
    spec = trajectory.to_dict()
    assert spec["type"] == "fourier"
    assert np.shape(spec["a"]) == (3, 2) and len(spec["offset"]) == 2
    again = FourierSeries.from_dict(spec)
    for name in ("a", "b", "q0"):
        np.testing.assert_array_equal(getattr(again, name), getattr(trajectory, name))
    assert again.base_frequency == trajectory.base_frequency
    assert again.duration == trajectory.duration
    # Without the optional keys: one period.
    short = FourierSeries.from_dict({k: spec[k] for k in ("base_frequency", "offset", "a", "b")})
    assert short.duration == 1 / spec["base_frequency"]


def test_yaml_round_trip_is_exact(planar_result: ExcitationResult, tmp_path: Path) -> None:
    path = planar_result.to_yaml(tmp_path / "excitation.yaml")
    text = path.read_text(encoding="utf-8")
    assert text.startswith("# Excitation trajectory")
    assert "type: fourier" in text and "base_frequency: 0.2" in text
    loaded = load_excitation(path)
    t = np.linspace(0.0, 5.0, 11)
    for got, want in zip(loaded.evaluate(t), planar_result.trajectory.evaluate(t), strict=True):
        np.testing.assert_array_equal(got, want)
    data = yaml.safe_load(text)
    assert data["condition_number"] == planar_result.condition_number
    assert data["joints"]["velocity_limit"] == [1.5, 2.0]
    # A bare specification file is read too.
    bare = tmp_path / "bare.yaml"
    bare.write_text(yaml.safe_dump(planar_result.trajectory.to_dict()), encoding="utf-8")
    np.testing.assert_array_equal(load_excitation(bare).b, planar_result.trajectory.b)


def test_result_tables(planar_result: ExcitationResult) -> None:
    table = planar_result.to_pandas()
    assert list(table.index) == ["joint1", "joint2"]
    assert table.shape == (2, 9)
    np.testing.assert_array_equal(table["offset"], planar_result.trajectory.q0)
    data = planar_result.to_dict()
    assert data["robot"] == "planar2" and data["success"] is True
    assert data["trajectory"] == planar_result.trajectory.to_dict()


@pytest.mark.parametrize(
    ("spec", "error", "match"),
    [
        ([1, 2], InputTypeError, "must be a mapping"),
        (
            {"base_frequency": 1.0, "offset": [0.0], "a": [[0.0]], "b": [[0.0]], "q0": [0.0]},
            InputTypeError,
            r"unknown keys \['q0'\].*valid keys",
        ),
        (
            {"base_frequency": 1.0, "a": [[0.0]], "b": [[0.0]]},
            InputValueError,
            r"missing \['offset'\]",
        ),
        (
            {
                "type": "via_points",
                "base_frequency": 1.0,
                "offset": [0.0],
                "a": [[0.0]],
                "b": [[0.0]],
            },
            InputValueError,
            "type must be 'fourier'",
        ),
        (
            {"base_frequency": 1.0, "offset": [0.0, 0.0], "a": [[0.0]], "b": [[0.0]]},
            DimensionError,
            r"q0 must have shape \(n_dof,\) = \(1,\)",
        ),
    ],
)
def test_from_dict_rejects_bad_specifications(spec, error, match) -> None:
    with pytest.raises(error, match=match):
        FourierSeries.from_dict(spec)


def test_load_excitation_rejects_bad_files(tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("a: [1, 2\n", encoding="utf-8")
    with pytest.raises(InputValueError, match="is not a YAML file"):
        load_excitation(broken)
    listing = tmp_path / "list.yaml"
    listing.write_text("- 1\n- 2\n", encoding="utf-8")
    with pytest.raises(InputValueError, match="holds no trajectory specification"):
        load_excitation(listing)
    with pytest.raises(FileNotFoundError):
        load_excitation(tmp_path / "missing.yaml")


# ---------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"n_harmonics": 0}, InputValueError, "n_harmonics must be an integer >= 1; got 0"),
        (
            {"n_harmonics": 1, "start_at_rest": True},
            InputValueError,
            "start_at_rest needs n_harmonics >= 2",
        ),
        (
            {"base_frequency": 0.0},
            InputValueError,
            r"base_frequency must be a positive number \[Hz\]",
        ),
        ({"base_frequency": "fast"}, InputValueError, "base_frequency must be a positive"),
        ({"n_samples": 6}, InputValueError, r"n_samples must be an integer >= 7; got 6"),
        (
            {"n_harmonics": 1, "n_samples": 3},
            InputValueError,
            r"n_samples · n_dof must exceed the 7",
        ),
        ({"seed": -1}, InputValueError, "seed must be an integer >= 0"),
        ({"n_restarts": 0}, InputValueError, "n_restarts must be an integer >= 1"),
        ({"max_iterations": 1.5}, InputValueError, "max_iterations must be an integer"),
        ({"limit_margin": 0.5}, InputValueError, r"limit_margin must lie in \[0, 0.5\)"),
        (
            {"position_limits": None},
            InputValueError,
            r"position limits of robot 'planar2' must be finite.*Pass position_limits",
        ),
        ({"position_limits": (-1.0,)}, DimensionError, r"position_limits must be a pair"),
        (
            {"position_limits": ([0.0, 0.0], [1.0, -1.0])},
            InputValueError,
            r"lower < upper; joint 1 has 0 >= -1",
        ),
        (
            {"position_limits": ([0.0, 0.0, 0.0], 1.0)},
            DimensionError,
            r"position_limits lower must be a scalar or have shape \(2,\)",
        ),
        (
            {"velocity_limits": None},
            InputValueError,
            r"robot 'planar2' has no finite velocity limits.*pass velocity_limits",
        ),
        (
            {"velocity_limits": [1.0, -1.0]},
            InputValueError,
            r"velocity_limits must be positive \[rad/s\]; joint 1 has -1",
        ),
        ({"velocity_limits": np.inf}, InputValueError, "velocity_limits must be finite"),
        ({"velocity_limits": np.nan}, InputValueError, "velocity_limits must not contain NaN"),
        (
            {"acceleration_limits": [1.0, 1.0, 1.0]},
            DimensionError,
            r"acceleration_limits must be a scalar or have shape \(2,\)",
        ),
        ({"acceleration_limits": 0.0}, InputValueError, "acceleration_limits must be positive"),
        ({"zero": ["mY1"], "base": "use"}, InputValueError, "zero=.* applies only without base"),
    ],
)
def test_optimize_rejects_bad_options(planar2: sl.RobotModel, options, error, match) -> None:
    arguments = {**PLANAR_OPTIONS, **options}
    if arguments.get("base") == "use":
        arguments["base"] = sl.base_parameters(planar2)
    with pytest.raises(error, match=match):
        optimize_excitation(planar2, **arguments)


def test_optimize_rejects_bad_models(planar2: sl.RobotModel) -> None:
    with pytest.raises(InputTypeError, match="robot must be a RobotModel; got str"):
        optimize_excitation("planar2")  # type: ignore[arg-type]
    with pytest.raises(InputTypeError, match="base must be a BaseParameters; got dict"):
        optimize_excitation(planar2, base={}, **PLANAR_OPTIONS)  # type: ignore[arg-type]
    puma_base = sl.base_parameters(sl.robots.load("puma560"))
    with pytest.raises(DimensionError, match="base belongs to a robot with 6 joints"):
        optimize_excitation(planar2, base=puma_base, **PLANAR_OPTIONS)
    with pytest.raises(TypeError, match="unexpected keyword argument 'harmonics'"):
        optimize_excitation(planar2, harmonics=3)  # type: ignore[call-arg]
