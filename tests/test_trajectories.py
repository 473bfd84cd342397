"""Tests of :mod:`sensorless.trajectories`.

Independent checks: the via-point quintics are compared with the closed-form
rest-to-rest quintic and with a per-segment 6x6 linear solve of the boundary
conditions; velocities and accelerations are compared with central finite
differences of the positions; the thesis tables give the expected via points.
"""

from __future__ import annotations

import io
import itertools

import numpy as np
import pandas as pd
import pytest

from sensorless.exceptions import DimensionError, InputValueError, LogFormatError
from sensorless.trajectories import (
    FourierSeries,
    QuinticViaPoints,
    RandomPointToPoint,
    Trajectory,
)

# Thesis Table 5.1 (simulated PUMA 560), tab separated as printed; angles [deg].
TABLE_5_1 = """time(s)\tq1\tq2\tq3\tq4\tq5\tq6
0\t0\t-90\t90\t0\t0\t0
1.25\t0\t-90\t90\t0\t0\t0
2.5\t45\t-90\t135\t0\t90\t135
3.75\t0\t-45\t90\t180\t0\t0
5\t0\t-90\t90\t0\t0\t0
"""

# Thesis Table 5.8 (KUKA LWR), angles [deg].
TABLE_5_8 = np.array(
    [
        [0, 0, 0, 0],
        [3, 25, 25, 25],
        [15, -168, -6, 88],
        [27, 27, -70, -70],
        [36, 0, 100, 44],
        [47, 168, -37, -88],
        [56, 0, 115, -168],
        [69, 168, 6, -88],
        [83, -55, 4, 1],
        [96, 34, -4, -1],
        [107, -165, -115, 169],
        [122, 165, 115, -169],
        [133, -165, -85, -169],
        [146, 165, -85, 169],
        [160, 27, -70, -70],
    ],
    dtype=float,
)


def random_via_points() -> QuinticViaPoints:
    rng = np.random.default_rng(7)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 2.0, size=5))])
    positions = rng.uniform(-np.pi, np.pi, size=(6, 3))
    velocities = rng.uniform(-1.0, 1.0, size=(6, 3))
    accelerations = rng.uniform(-2.0, 2.0, size=(6, 3))
    return QuinticViaPoints(times, positions, velocities, accelerations)


def interior_times(breaks: np.ndarray, per_segment: int = 7) -> np.ndarray:
    """Times strictly inside every segment, away from the breakpoints."""
    fractions = np.linspace(0.05, 0.95, per_segment)
    return np.concatenate([a + fractions * (b - a) for a, b in itertools.pairwise(breaks)])


def check_finite_differences(traj: Trajectory, t: np.ndarray, h: float = 1e-5) -> None:
    q_plus, qd_plus, _ = traj.evaluate(t + h)
    q_minus, qd_minus, _ = traj.evaluate(t - h)
    _, qd, qdd = traj.evaluate(t)
    np.testing.assert_allclose(qd, (q_plus - q_minus) / (2 * h), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(qdd, (qd_plus - qd_minus) / (2 * h), rtol=1e-6, atol=1e-6)


def quintic_segment(t0, t1, start, end):
    """Coefficients of q(t) = Σ c_k (t - t0)^k from the six boundary conditions."""
    T = t1 - t0
    rows = []
    for tau in (0.0, T):
        rows.append([tau**k for k in range(6)])
        rows.append([k * tau ** (k - 1) if k >= 1 else 0.0 for k in range(6)])
        rows.append([k * (k - 1) * tau ** (k - 2) if k >= 2 else 0.0 for k in range(6)])
    rhs = np.array([*start, *end])
    return np.linalg.solve(np.array(rows), rhs)


# --------------------------------------------------------------------- quintic


def test_passes_through_via_points_with_prescribed_derivatives():
    traj = random_via_points()
    q, qd, qdd = traj.evaluate(traj.times)
    np.testing.assert_allclose(q, traj.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(qd, traj.velocities, rtol=0, atol=1e-12)
    np.testing.assert_allclose(qdd, traj.accelerations, rtol=0, atol=1e-12)


def test_matches_independent_linear_solve_per_segment():
    traj = random_via_points()
    for k in range(traj.times.size - 1):
        t0, t1 = traj.times[k], traj.times[k + 1]
        t = np.linspace(t0, t1, 9)[1:-1]
        q, qd, qdd = traj.evaluate(t)
        for j in range(traj.n_dof):
            c = quintic_segment(
                t0,
                t1,
                (traj.positions[k, j], traj.velocities[k, j], traj.accelerations[k, j]),
                (traj.positions[k + 1, j], traj.velocities[k + 1, j], traj.accelerations[k + 1, j]),
            )
            tau = t - t0
            np.testing.assert_allclose(q[:, j], np.polyval(c[::-1], tau), atol=1e-10)
            dc = np.polyder(c[::-1])
            np.testing.assert_allclose(qd[:, j], np.polyval(dc, tau), atol=1e-10)
            np.testing.assert_allclose(qdd[:, j], np.polyval(np.polyder(dc), tau), atol=1e-9)


def test_rest_to_rest_closed_form():
    traj = QuinticViaPoints([0.0, 2.0], [[0.2, -1.0], [1.2, 0.5]])
    t = np.linspace(0.0, 2.0, 11)
    s = t / 2.0
    delta = np.array([1.0, 1.5])
    q, qd, _ = traj.evaluate(t)
    shape = 10 * s**3 - 15 * s**4 + 6 * s**5
    np.testing.assert_allclose(q, np.array([0.2, -1.0]) + np.outer(shape, delta), atol=1e-13)
    np.testing.assert_allclose(np.abs(qd).max(axis=0), 15 / 8 * delta / 2.0, rtol=1e-12)


def test_velocity_and_acceleration_are_finite_differences():
    traj = random_via_points()
    check_finite_differences(traj, interior_times(traj.times))


def test_continuity_across_segment_boundaries():
    traj = random_via_points()
    eps = 1e-9
    interior = traj.times[1:-1]
    before = traj.evaluate(interior - eps)
    after = traj.evaluate(interior + eps)
    for left, right, tol in zip(before, after, (1e-8, 1e-7, 1e-6), strict=True):
        np.testing.assert_allclose(left, right, rtol=0, atol=tol)


def test_default_velocities_follow_slope_heuristic():
    times = [0.0, 1.0, 2.0, 3.0, 4.0, 6.0]
    # joint 0 slopes: 1, 2, -1, 0, 0.5 -> same sign only at t = 1
    # joint 1 slopes: -1, -3, -1, -1, -0.5 -> always the same sign
    positions = np.array(
        [[0.0, 3.0], [1.0, 2.0], [3.0, -1.0], [2.0, -2.0], [2.0, -3.0], [3.0, -4.0]]
    )
    traj = QuinticViaPoints(times, positions)
    expected = np.array(
        [[0.0, 0.0], [1.5, -2.0], [0.0, -2.0], [0.0, -1.0], [0.0, -0.75], [0.0, 0.0]]
    )
    np.testing.assert_array_equal(traj.velocities, expected)
    np.testing.assert_array_equal(traj.accelerations, np.zeros((6, 2)))
    _, qd, qdd = traj.evaluate(traj.times)
    np.testing.assert_allclose(qd, expected, atol=1e-12)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)


def test_via_point_arrays_are_read_only():
    traj = random_via_points()
    for arr in (traj.times, traj.positions, traj.velocities, traj.accelerations):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0


def test_from_degrees_converts_to_radians():
    traj = QuinticViaPoints.from_degrees([0.0, 1.0, 3.0], [[0.0, 10.0], [90.0, -45.0], [0.0, 0]])
    np.testing.assert_allclose(traj.positions, np.deg2rad([[0, 10], [90, -45], [0, 0]]))
    q, _, _ = traj.evaluate(1.0)
    np.testing.assert_allclose(q, np.deg2rad([90.0, -45.0]), atol=1e-12)


# ----------------------------------------------------------------- thesis tables


@pytest.mark.parametrize("kind", ["tab-text", "csv-file", "dataframe"])
def test_table_5_1(kind, tmp_path):
    if kind == "tab-text":
        source = io.StringIO(TABLE_5_1)
    elif kind == "csv-file":
        source = tmp_path / "table_5_1.csv"
        source.write_text(TABLE_5_1.replace("\t", ","))
    else:
        source = pd.read_csv(io.StringIO(TABLE_5_1), sep="\t")
    traj = QuinticViaPoints.from_table(source, degrees=True)
    assert traj.n_dof == 6
    assert traj.duration == 5.0
    q, qd, _ = traj.evaluate(2.5)
    np.testing.assert_allclose(q, np.deg2rad([45, -90, 135, 0, 90, 135]), atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, atol=1e-12)
    # 0 -> 1.25 s is a dwell: both ends equal with zero default velocity
    q_dwell, _, _ = traj.evaluate(np.linspace(0.0, 1.25, 6))
    np.testing.assert_allclose(q_dwell, np.deg2rad([[0, -90, 90, 0, 0, 0]] * 6), atol=1e-12)


def test_table_5_1_repeated_twelve_times_is_periodic():
    single = QuinticViaPoints.from_table(io.StringIO(TABLE_5_1))
    traj = QuinticViaPoints.from_table(io.StringIO(TABLE_5_1), repeat=12)
    assert traj.duration == pytest.approx(60.0, abs=1e-12)
    assert traj.times.size == 4 * 12 + 1
    t = np.linspace(0.0, 5.0, 101)
    reference = single.evaluate(t)
    for k in range(12):
        for got, want in zip(traj.evaluate(t + 5.0 * k), reference, strict=True):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-10)
    check_finite_differences(traj, interior_times(traj.times, per_segment=3))


def test_repeat_is_seamless_where_default_velocity_at_junction_would_not_be_zero():
    # slopes keep their sign across the junction; each period still starts at rest
    text = "time,q\n0,0\n1,10\n2,30\n3,0\n"
    traj = QuinticViaPoints.from_table(io.StringIO(text), repeat=3)
    q0 = traj.evaluate(np.linspace(0.0, 3.0, 31))
    for k in (1, 2):
        for got, want in zip(traj.evaluate(np.linspace(0.0, 3.0, 31) + 3.0 * k), q0, strict=True):
            np.testing.assert_allclose(got, want, atol=1e-10)
    eps = 1e-9
    for junction in (3.0, 6.0):
        for left, right in zip(
            traj.evaluate(junction - eps), traj.evaluate(junction + eps), strict=True
        ):
            np.testing.assert_allclose(left, right, atol=1e-6)


def test_table_5_8_via_points():
    frame = pd.DataFrame(TABLE_5_8, columns=["time", "q1", "q2", "q3"])
    traj = QuinticViaPoints.from_table(frame)
    assert traj.duration == 160.0
    q, _, _ = traj.evaluate(TABLE_5_8[:, 0])
    np.testing.assert_allclose(np.rad2deg(q), TABLE_5_8[:, 1:], atol=1e-10)


def test_from_table_in_radians():
    text = "time [s],q1,q2\n0,0.1,-0.2\n2,1.5,0.3\n"
    traj = QuinticViaPoints.from_table(io.StringIO(text), degrees=False)
    np.testing.assert_allclose(traj.positions, [[0.1, -0.2], [1.5, 0.3]])


# ------------------------------------------------------------- common behaviour


@pytest.fixture(
    params=["quintic", "random", "fourier"],
)
def trajectory(request) -> Trajectory:
    if request.param == "quintic":
        return random_via_points()
    if request.param == "random":
        return RandomPointToPoint(2, 8.0, -1.0, 1.0, 0.8, seed=11, rest=(0.1, 0.5))
    return FourierSeries(0.2, a=[[0.3, -0.2], [0.1, 0.4]], b=[[0.2, 0.1], [-0.3, 0.0]], q0=[0, 1])


def test_scalar_evaluation_equals_array_rows(trajectory):
    t = np.linspace(-1.0, trajectory.duration + 1.0, 23)
    batch = trajectory.evaluate(t)
    for i, ti in enumerate(t):
        single = trajectory.evaluate(float(ti))
        for got, rows in zip(single, batch, strict=True):
            assert got.shape == (trajectory.n_dof,)
            # numpy's vectorised sin/cos may round the last bit differently from the
            # one-element path (numpy 2.4 on this machine: 1 ulp), so: to 1e-15.
            np.testing.assert_allclose(got, rows[i], rtol=1e-15, atol=1e-15)


def test_holds_end_points_outside_time_range(trajectory):
    q_start, _, _ = trajectory.evaluate(0.0)
    q_end, _, _ = trajectory.evaluate(trajectory.duration)
    q, qd, qdd = trajectory.evaluate([-5.0, -1e-3, trajectory.duration + 1e-3, 1e6])
    np.testing.assert_array_equal(q, [q_start, q_start, q_end, q_end])
    np.testing.assert_array_equal(qd, 0.0)
    np.testing.assert_array_equal(qdd, 0.0)


def test_sample_grid(trajectory):
    t, q, qd, qdd = trajectory.sample(0.01)
    n = t.size
    assert q.shape == qd.shape == qdd.shape == (n, trajectory.n_dof)
    np.testing.assert_allclose(np.diff(t), 0.01, rtol=1e-9)
    assert t[0] == 0.0 and trajectory.duration - 0.01 < t[-1] <= trajectory.duration
    for got, want in zip((q, qd, qdd), trajectory.evaluate(t), strict=True):
        np.testing.assert_array_equal(got, want)


def test_sample_ends_on_duration_when_dt_divides_it():
    traj = QuinticViaPoints([0.0, 0.3], [[0.0], [1.0]])
    t, _, _, _ = traj.sample(0.1)
    np.testing.assert_allclose(t, [0.0, 0.1, 0.2, 0.3], atol=1e-15)
    assert t[-1] == 0.3
    t, _, _, _ = traj.sample(0.07)
    np.testing.assert_allclose(t, 0.07 * np.arange(5))


# ------------------------------------------------------------- random moves


def make_random(seed: int = 5, **kwargs) -> RandomPointToPoint:
    options = {
        "n_dof": 3,
        "duration": 20.0,
        "lower": [-2.0, -1.0, 0.5],
        "upper": [2.0, 1.5, 2.5],
        "max_velocity": [1.0, 1.5, 2.0],
        "seed": seed,
        "segment_time": (0.1, 0.5),
        "rest": (0.2, 0.6),
    }
    options.update(kwargs)
    return RandomPointToPoint(**options)


def test_random_stays_within_limits_and_velocity_bound():
    traj = make_random()
    _, q, qd, _ = traj.sample(1e-3)
    assert (q >= traj.lower - 1e-12).all() and (q <= traj.upper + 1e-12).all()
    peak = np.abs(qd).max(axis=0)
    assert (peak <= traj.max_velocity * (1 + 1e-12) + 1e-12).all()
    # the segment times (0.1-0.5 s) are short, so the velocity limit is what binds
    assert np.isclose(peak, traj.max_velocity, rtol=1e-4).any()


def test_random_moves_are_rest_to_rest_and_respect_timing():
    traj = make_random()
    via = traj.via_points
    np.testing.assert_array_equal(via.velocities, 0.0)
    np.testing.assert_array_equal(via.accelerations, 0.0)
    assert via.times[0] == 0.0 and traj.duration == 20.0
    steps = np.diff(via.times)
    moving = np.any(np.diff(via.positions, axis=0) != 0.0, axis=1)
    assert (steps[moving] >= 0.1 - 1e-12).all()
    assert (steps[~moving][:-1] >= 0.2 - 1e-12).all()  # rests, except the final hold
    assert moving.sum() >= 3
    _, qd, qdd = traj.evaluate(traj.duration)
    np.testing.assert_allclose(qd, 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)


def test_random_is_reproducible_from_seed():
    first = make_random(seed=42).sample(0.01)
    second = make_random(seed=42).sample(0.01)
    for a, b in zip(first, second, strict=True):
        assert a.tobytes() == b.tobytes()
    other = make_random(seed=43).sample(0.01)
    assert not np.array_equal(first[1], other[1])


def test_random_start_and_derivatives():
    traj = make_random(start=[0.0, 0.0, 1.0], rest=(0.0, 0.0))
    q, _, _ = traj.evaluate(0.0)
    np.testing.assert_array_equal(q, [0.0, 0.0, 1.0])
    check_finite_differences(traj, interior_times(traj.via_points.times, per_segment=3))


# ------------------------------------------------------------------- Fourier


def fourier() -> FourierSeries:
    rng = np.random.default_rng(3)
    return FourierSeries(
        0.1,
        a=rng.normal(0, 0.3, size=(5, 3)),
        b=rng.normal(0, 0.3, size=(5, 3)),
        q0=[0.1, -0.5, 1.0],
        duration=30.0,
    )


def test_fourier_closed_form_at_zero():
    traj = fourier()
    omega = 2 * np.pi * 0.1 * np.arange(1, 6)
    q, qd, qdd = traj.evaluate(0.0)
    np.testing.assert_allclose(q, traj.q0 - (traj.b / omega[:, None]).sum(axis=0), atol=1e-14)
    np.testing.assert_allclose(qd, traj.a.sum(axis=0), atol=1e-14)
    np.testing.assert_allclose(qdd, (traj.b * omega[:, None]).sum(axis=0), atol=1e-14)


def test_fourier_derivatives_are_finite_differences():
    traj = fourier()
    check_finite_differences(traj, np.linspace(0.01, 29.99, 97))


def test_fourier_is_periodic():
    traj = fourier()
    assert traj.n_harmonics == 5
    t = np.linspace(0.0, 20.0, 57)
    for got, want in zip(traj.evaluate(t + 10.0), traj.evaluate(t), strict=True):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_fourier_default_duration_is_one_period():
    traj = FourierSeries(0.25, a=[[1.0]], b=[[0.0]], q0=[0.0])
    assert traj.duration == 4.0


# ------------------------------------------------------------------ bad input


@pytest.mark.parametrize(
    ("times", "positions", "error", "match"),
    [
        ([0.0, 1.0, 1.0], np.zeros((3, 2)), InputValueError, "strictly increasing"),
        ([0.0, 2.0, 1.0], np.zeros((3, 2)), InputValueError, r"times\[1\] = 2"),
        ([0.5, 1.0], np.zeros((2, 2)), InputValueError, "start at 0"),
        ([0.0], np.zeros((1, 2)), DimensionError, "at least 2 via points"),
        ([0.0, 1.0, 2.0], np.zeros((2, 2)), DimensionError, r"\(3, n_dof\).*\(2, 2\)"),
        ([0.0, 1.0, 2.0], np.zeros(3), DimensionError, "positions must have shape"),
        ([0.0, np.nan, 2.0], np.zeros((3, 2)), InputValueError, "times must be finite"),
        ([0.0, 1.0], [[0.0, np.nan], [0.0, 0.0]], InputValueError, "positions must be finite"),
        ([0.0, 1.0], [[0.0, 90.0], [0.0, 0.0]], InputValueError, "looks like degrees"),
        ([0.0, 1.0], [["a", 0.0], [0.0, 0.0]], DimensionError, "numeric"),
    ],
)
def test_quintic_rejects_bad_via_points(times, positions, error, match):
    with pytest.raises(error, match=match):
        QuinticViaPoints(times, positions)


def test_quintic_rejects_bad_derivatives():
    with pytest.raises(DimensionError, match="velocities must have the shape of positions"):
        QuinticViaPoints([0.0, 1.0], np.zeros((2, 2)), velocities=np.zeros((2, 3)))
    with pytest.raises(InputValueError, match="accelerations must be finite"):
        QuinticViaPoints([0.0, 1.0], np.zeros((2, 1)), accelerations=[[0.0], [np.inf]])


def test_from_table_rejects_bad_tables():
    with pytest.raises(InputValueError, match="looks like degrees"):
        QuinticViaPoints.from_table(io.StringIO(TABLE_5_1), degrees=False)
    with pytest.raises(InputValueError, match="repeat=2 needs the last via point equal"):
        QuinticViaPoints.from_table(io.StringIO("time,q\n0,0\n1,10\n"), repeat=2)
    with pytest.raises(InputValueError, match="repeat must be a positive integer"):
        QuinticViaPoints.from_table(io.StringIO(TABLE_5_1), repeat=0)
    with pytest.raises(LogFormatError, match=r"first column .* must be 'time'"):
        QuinticViaPoints.from_table(io.StringIO(TABLE_5_1.replace("time(s)", "t")))
    with pytest.raises(LogFormatError, match=r"first column .* must be 'time'"):
        QuinticViaPoints.from_table(pd.DataFrame({"q1": [0.0, 1.0], "time": [0.0, 1.0]}))
    with pytest.raises(LogFormatError, match="at least one joint column"):
        QuinticViaPoints.from_table(io.StringIO("time\n0\n1\n"))
    with pytest.raises(LogFormatError, match="numeric"):
        QuinticViaPoints.from_table(io.StringIO("time,q\n0,0\n1,ten\n"))
    with pytest.raises(LogFormatError, match="could not read"):
        QuinticViaPoints.from_table(io.StringIO(""))
    with pytest.raises(InputValueError, match="strictly increasing"):
        QuinticViaPoints.from_table(io.StringIO("time,q\n0,0\n0,10\n"))


def test_evaluate_and_sample_reject_bad_time():
    traj = random_via_points()
    with pytest.raises(DimensionError, match=r"shape \(n_samples,\)"):
        traj.evaluate(np.zeros((2, 2)))
    with pytest.raises(InputValueError, match="t must be finite"):
        traj.evaluate([0.0, np.nan])
    with pytest.raises(InputValueError, match="dt must be a positive"):
        traj.sample(0.0)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"lower": [0.0, 1.0, 3.0]}, InputValueError, "joint 2 has lower = 3 rad > upper"),
        ({"max_velocity": [1.0, 0.0, 1.0]}, InputValueError, "max_velocity must be positive"),
        ({"max_velocity": -1.0}, InputValueError, "max_velocity must be positive"),
        ({"lower": [0.0, 0.0]}, DimensionError, r"lower must be a scalar or have shape \(3,\)"),
        ({"upper": 100.0}, InputValueError, "looks like degrees"),
        ({"duration": 0.0}, InputValueError, "duration must be a positive"),
        ({"segment_time": (0.0, 1.0)}, InputValueError, "segment_time must be a pair"),
        ({"segment_time": (2.0, 1.0)}, InputValueError, "min <= max"),
        ({"rest": (-1.0, 1.0)}, InputValueError, "rest must be a pair"),
        ({"rest": (1.0, 2.0, 3.0)}, DimensionError, "rest must be a pair"),
        ({"seed": -1}, InputValueError, "seed must be a non-negative integer"),
        ({"seed": 1.5}, InputValueError, "seed must be a non-negative integer"),
        ({"n_dof": 0}, InputValueError, "n_dof must be a positive integer"),
        ({"start": [0.0, np.nan, 1.0]}, InputValueError, "start must be finite"),
    ],
)
def test_random_rejects_bad_input(kwargs, error, match):
    with pytest.raises(error, match=match):
        make_random(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"base_frequency": 0.0}, InputValueError, "base_frequency must be a positive"),
        ({"b": [[0.0, 0.0], [0.0, 0.0]]}, DimensionError, r"b must have the shape of a"),
        ({"a": [1.0, 2.0]}, DimensionError, r"a must have shape \(n_harmonics, n_dof\)"),
        ({"q0": [0.0]}, DimensionError, r"q0 must have shape \(n_dof,\) = \(2,\)"),
        ({"a": [[np.nan, 0.0]]}, InputValueError, "a must be finite"),
        ({"duration": -1.0}, InputValueError, "duration must be a positive"),
    ],
)
def test_fourier_rejects_bad_input(kwargs, error, match):
    options = {"base_frequency": 1.0, "a": [[0.1, 0.2]], "b": [[0.0, 0.1]], "q0": [0.0, 0.0]}
    options.update(kwargs)
    with pytest.raises(error, match=match):
        FourierSeries(**options)
