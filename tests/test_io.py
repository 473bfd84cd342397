"""Tests of :mod:`sensorless.io`.

Round trips are checked bit for bit (``np.array_equal``) against the arrays
the log was built from; the table layout and the sidecar are checked against
the column names and units written out here, not against the module's own
constants. Every validation branch has a ``pytest.raises(..., match=...)``.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pandas as pd
import pytest

from sensorless.exceptions import DimensionError, InputValueError, LogFormatError
from sensorless.io import (
    Log,
    read_log,
    resample,
    sidecar_path,
    split_at_gaps,
    validate_table,
    write_log,
)

N_DOF = 3
N_SAMPLES = 50
DT = 0.001

GROUPS = ("q", "tau_m", "tau_j", "q_true", "qd_true", "tau_c")
EXPECTED_COLUMNS = [
    "t",
    *[f"{group}_{joint}" for group in GROUPS for joint in (1, 2, 3)],
    "collision_id",
]


def make_log(seed: int = 0) -> Log:
    """A full log with awkward floats (0.1 steps, 1/3, random 53-bit mantissas)."""
    rng = np.random.default_rng(seed)
    t = 0.1 + DT * np.arange(N_SAMPLES)
    q = rng.uniform(-3.0, 3.0, (N_SAMPLES, N_DOF))
    q[0, 0] = 1.0 / 3.0
    q[1, 1] = -0.0
    q[2, 2] = 5e-324  # smallest subnormal
    q[3, 0] = 4.0 * math.pi  # the largest accepted angle
    collision_id = np.zeros(N_SAMPLES, dtype=np.int64)
    collision_id[20:30] = 2
    return Log(
        t=t,
        q=q,
        tau_m=rng.normal(0.0, 50.0, (N_SAMPLES, N_DOF)),
        tau_j=rng.normal(0.0, 50.0, (N_SAMPLES, N_DOF)) * 1e-7,
        q_true=q + rng.normal(0.0, 1e-4, (N_SAMPLES, N_DOF)),
        qd_true=rng.normal(0.0, 2.0, (N_SAMPLES, N_DOF)),
        tau_c=rng.normal(0.0, 1e6, (N_SAMPLES, N_DOF)),
        collision_id=collision_id,
        metadata={
            "scenario": "unit test",
            "seed": seed,
            "robot": "planar3",
            "nominal_robot": "planar3-nominal",
            "sample_rate": 1000.0,
            "collisions": [{"id": 2, "link": 3, "t_start": 0.12, "t_end": 0.13}],
            "nested": {"gain": 0.1, "flags": [True, False, None]},
        },
    )


def small_table(n: int = 5, n_dof: int = 2) -> pd.DataFrame:
    """A valid minimal table: time, positions and motor torques."""
    data: dict[str, np.ndarray] = {"t": DT * np.arange(n)}
    for joint in range(1, n_dof + 1):
        data[f"q_{joint}"] = 0.1 * joint + 0.01 * np.arange(n)
    for joint in range(1, n_dof + 1):
        data[f"tau_m_{joint}"] = np.full(n, float(joint))
    return pd.DataFrame(data)


def assert_logs_equal(a: Log, b: Log) -> None:
    for name in ("t", *GROUPS, "collision_id"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert x.dtype == y.dtype, name
            assert np.array_equal(x, y), name
            # -0.0 == 0.0, so compare the bits as well
            assert x.tobytes() == y.tobytes(), name
    assert a.metadata == b.metadata


# --------------------------------------------------------------------------- Log object


def test_log_properties_and_columns() -> None:
    log = make_log()
    assert log.n_dof == N_DOF
    assert log.n_samples == N_SAMPLES
    assert log.dt == pytest.approx(DT, rel=1e-12)
    assert log.duration == pytest.approx(DT * (N_SAMPLES - 1), rel=1e-12)
    df = log.to_pandas()
    assert list(df.columns) == EXPECTED_COLUMNS
    assert log.columns == EXPECTED_COLUMNS
    assert df["collision_id"].dtype == np.int64
    assert all(df[name].dtype == np.float64 for name in EXPECTED_COLUMNS[:-1])
    assert np.array_equal(df["tau_c_2"].to_numpy(), log.tau_c[:, 1])
    assert np.array_equal(df["q_true_3"].to_numpy(), log.q_true[:, 2])


def test_to_pandas_only_present_groups() -> None:
    log = Log(t=[0.0, 0.5, 1.0], q=np.zeros((3, 2)), tau_j=np.ones((3, 2)))
    assert list(log.to_pandas().columns) == ["t", "q_1", "q_2", "tau_j_1", "tau_j_2"]
    assert log.tau_m is None and log.collision_id is None
    assert log.metadata == {}


def test_from_pandas_round_trip_and_column_order() -> None:
    log = make_log()
    df = log.to_pandas()
    shuffled = df[df.columns[::-1]]
    again = Log.from_pandas(shuffled, metadata=log.metadata, n_dof=N_DOF)
    assert_logs_equal(log, again)


def test_log_copies_and_is_read_only() -> None:
    t = np.array([0.0, 0.1, 0.2])
    q = np.zeros((3, 1))
    log = Log(t=t, q=q)
    q[0, 0] = 1.0
    assert log.q[0, 0] == 0.0
    with pytest.raises(ValueError, match="read-only"):
        log.q[0, 0] = 2.0
    with pytest.raises(AttributeError):
        log.q = q  # type: ignore[misc]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"t": np.zeros((3, 1)), "q": np.zeros((3, 2))}, r"t must have shape \(n_samples,\)"),
        ({"t": [0.0, 1.0, 2.0], "q": np.zeros((4, 2))}, r"q must have shape .*got shape \(4, 2\)"),
        ({"t": [0.0, 1.0, 2.0], "q": np.zeros(3)}, r"q must have shape .*got shape \(3,\)"),
        ({"t": [0.0, 1.0, 2.0], "q": np.zeros((3, 0))}, r"n_dof >= 1"),
        (
            {"t": [0.0, 1.0, 2.0], "q": np.zeros((3, 7)), "tau_m": np.zeros((3, 6))},
            r"tau_m must have the shape of q, .*\(3, 7\); got shape \(3, 6\)",
        ),
        (
            {"t": [0.0, 1.0, 2.0], "q": np.zeros((3, 2)), "collision_id": np.zeros(2)},
            r"collision_id must have shape \(n_samples,\) = \(3,\); got shape \(2,\)",
        ),
    ],
)
def test_log_shape_mismatch(kwargs: dict, match: str) -> None:
    with pytest.raises(DimensionError, match=match):
        Log(**kwargs)


def test_log_constructor_validates_values() -> None:
    q = np.zeros((4, 2))
    q[2, 1] = np.nan
    with pytest.raises(LogFormatError, match=r"column 'q_2' must be finite; row 2 holds nan"):
        Log(t=[0.0, 1.0, 2.0, 3.0], q=q)
    with pytest.raises(LogFormatError, match=r"goes backwards at row 2"):
        Log(t=[0.0, 1.0, 0.5], q=np.zeros((3, 1)))
    with pytest.raises(LogFormatError, match=r"at least 2 samples"):
        Log(t=[0.0], q=np.zeros((1, 1)))
    with pytest.raises(LogFormatError, match=r"'collision_id' must hold non-negative integers"):
        Log(t=[0.0, 1.0], q=np.zeros((2, 1)), collision_id=[0.0, 1.5])
    # The constructor accepts an irregular time base (for resample), the reader does not.
    assert Log(t=[0.0, 1.0, 3.0], q=np.zeros((3, 1))).n_samples == 3


def test_metadata_is_json_normalised() -> None:
    log = Log(
        t=[0.0, 1.0],
        q=np.zeros((2, 1)),
        metadata={"seed": np.int64(3), "gain": np.float64(0.5), "v": np.arange(2), "k": (1, 2)},
    )
    assert log.metadata == {"seed": 3, "gain": 0.5, "v": [0, 1], "k": [1, 2]}
    assert type(log.metadata["seed"]) is int
    with pytest.raises(InputValueError, match="JSON-serialisable"):
        Log(t=[0.0, 1.0], q=np.zeros((2, 1)), metadata={"f": object()})
    with pytest.raises(InputValueError, match="JSON-serialisable"):
        Log(t=[0.0, 1.0], q=np.zeros((2, 1)), metadata={"x": math.nan})
    with pytest.raises(InputValueError, match="metadata must be a dict; got list"):
        Log(t=[0.0, 1.0], q=np.zeros((2, 1)), metadata=[1])  # type: ignore[arg-type]


def test_slice_by_time() -> None:
    log = make_log()
    part = log.slice(0.110, 0.120)
    # 0.1 + 0.001 k is not exact in binary; compute the expected rows the same way.
    expected = (log.t >= 0.110) & (log.t < 0.120)
    assert np.array_equal(part.t, log.t[expected])
    assert np.array_equal(part.tau_c, log.tau_c[expected])
    assert np.array_equal(part.collision_id, log.collision_id[expected])
    assert part.metadata == log.metadata
    assert np.array_equal(log.slice(stop=0.105).t, log.t[log.t < 0.105])
    assert np.array_equal(log.slice(start=0.145).t, log.t[log.t >= 0.145])
    with pytest.raises(InputValueError, match="stop must be after start"):
        log.slice(0.2, 0.1)
    with pytest.raises(InputValueError, match=r"holds 1 sample\(s\)"):
        log.slice(0.1, 0.1005)
    with pytest.raises(InputValueError, match="start must be a time"):
        log.slice(math.nan, 0.2)


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_round_trip_exact(tmp_path, suffix: str) -> None:
    log = make_log()
    path = write_log(log, tmp_path / f"run{suffix}")
    assert path == tmp_path / f"run{suffix}"
    again = read_log(path, n_dof=N_DOF)
    assert_logs_equal(log, again)


def test_parquet_and_csv_agree(tmp_path) -> None:
    log = make_log(seed=7)
    from_parquet = read_log(write_log(log, tmp_path / "a.parquet"))
    from_csv = read_log(write_log(log, tmp_path / "a.csv"))
    assert_logs_equal(from_parquet, from_csv)


def test_csv_is_deterministic_and_full_precision(tmp_path) -> None:
    log = make_log()
    first = write_log(log, tmp_path / "one.csv")
    second = write_log(log, tmp_path / "two.csv")
    assert first.read_bytes() == second.read_bytes()
    assert sidecar_path(first).read_bytes() == sidecar_path(second).read_bytes()
    lines = first.read_text().splitlines()
    assert lines[0].split(",") == EXPECTED_COLUMNS
    assert lines[1].split(",")[1] == "0.33333333333333331"  # %.17g of 1/3
    assert len(lines) == N_SAMPLES + 1


def test_parquet_is_deterministic(tmp_path) -> None:
    log = make_log()
    first = write_log(log, tmp_path / "one.parquet")
    second = write_log(log, tmp_path / "two.parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(first), pd.read_parquet(second), check_exact=True)
    assert sidecar_path(first).read_bytes() == sidecar_path(second).read_bytes()
    table = pd.read_parquet(first)
    assert list(table.columns) == EXPECTED_COLUMNS
    assert np.array_equal(table[["q_1", "q_2", "q_3"]].to_numpy(), log.q)


def test_sidecar_contents(tmp_path) -> None:
    log = make_log()
    path = write_log(log, tmp_path / "run.csv")
    meta_path = tmp_path / "run.csv.meta.json"
    assert sidecar_path(path) == meta_path
    text = meta_path.read_text()
    assert text.startswith("{\n  ")  # pretty-printed
    sidecar = json.loads(text)
    assert sidecar["format"] == "csv"
    assert sidecar["n_dof"] == N_DOF
    assert sidecar["n_samples"] == N_SAMPLES
    assert sidecar["columns"] == EXPECTED_COLUMNS
    assert sidecar["units"] == {
        "t": "s",
        "q": "rad",
        "tau_m": "N m",
        "tau_j": "N m",
        "q_true": "rad",
        "qd_true": "rad/s",
        "tau_c": "N m",
        "collision_id": "1",
    }
    assert sidecar["sample_rate"] == pytest.approx(1.0 / DT, rel=1e-9)
    assert sidecar["metadata"] == log.metadata
    assert isinstance(sidecar["sensorless_version"], str)


def test_units_only_for_present_groups(tmp_path) -> None:
    log = Log(t=[0.0, 0.5, 1.0], q=np.zeros((3, 1)), qd_true=np.ones((3, 1)))
    path = write_log(log, tmp_path / "run.parquet")
    units = json.loads(sidecar_path(path).read_text())["units"]
    assert units == {"t": "s", "q": "rad", "qd_true": "rad/s"}


def test_read_without_sidecar(tmp_path) -> None:
    path = tmp_path / "hand.csv"
    small_table().to_csv(path, index=False)
    log = read_log(path)
    assert log.metadata == {}
    assert log.n_dof == 2
    assert np.array_equal(log.tau_m[:, 1], np.full(5, 2.0))


def test_format_selection(tmp_path) -> None:
    log = make_log()
    # Unknown suffix: Parquet by default, and the reader finds the format in the sidecar.
    path = write_log(log, tmp_path / "run.dat")
    assert path.read_bytes()[:4] == b"PAR1"
    assert_logs_equal(log, read_log(path))
    # Explicit format wins over the suffix.
    path = write_log(log, tmp_path / "run.txt", format="csv")
    assert path.read_text().startswith("t,q_1,")
    assert_logs_equal(log, read_log(path))
    assert_logs_equal(log, read_log(path, format="csv"))
    with pytest.raises(InputValueError, match=r"format must be one of \['parquet', 'csv'\]"):
        write_log(log, tmp_path / "run.csv", format="xlsx")
    sidecar_path(path).unlink()
    with pytest.raises(LogFormatError, match=r"cannot tell the format of .*run\.txt"):
        read_log(path)


def test_read_errors(tmp_path) -> None:
    with pytest.raises(FileNotFoundError):
        read_log(tmp_path / "missing.csv")
    broken = tmp_path / "broken.parquet"
    broken.write_text("not parquet")
    with pytest.raises(LogFormatError, match=r"cannot read .* as parquet"):
        read_log(broken)


def test_sidecar_mismatch(tmp_path) -> None:
    log = make_log()
    path = write_log(log, tmp_path / "run.csv")
    meta_path = sidecar_path(path)
    sidecar = json.loads(meta_path.read_text())
    sidecar["n_dof"] = 6
    meta_path.write_text(json.dumps(sidecar))
    with pytest.raises(LogFormatError, match=r"says n_dof = 6, but the table .* has 3 joints"):
        read_log(path)
    sidecar["n_dof"] = 3
    sidecar["columns"] = sidecar["columns"][:-1]
    meta_path.write_text(json.dumps(sidecar))
    with pytest.raises(LogFormatError, match="lists columns"):
        read_log(path)
    meta_path.write_text("{not json")
    with pytest.raises(LogFormatError, match="is not valid JSON"):
        read_log(path)
    meta_path.write_text("[1, 2]")
    with pytest.raises(LogFormatError, match="must hold a JSON object"):
        read_log(path)


def test_read_log_n_dof_mismatch(tmp_path) -> None:
    log = Log(t=DT * np.arange(4), q=np.zeros((4, 7)))
    path = write_log(log, tmp_path / "run.parquet")
    with pytest.raises(DimensionError, match="robot has 6 joints, log has 7"):
        read_log(path, n_dof=6)
    assert read_log(path, n_dof=7).n_dof == 7


# --------------------------------------------------------------------------- corrupt files


def test_nan_in_csv_names_column_and_row(tmp_path) -> None:
    df = small_table(n=10)
    df.loc[6, "tau_m_2"] = np.nan
    path = tmp_path / "nan.csv"
    df.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=r"column 'tau_m_2' must be finite; row 6 holds nan"):
        read_log(path)


def test_inf_names_column_and_row() -> None:
    df = small_table(n=10)
    df.loc[3, "q_1"] = -np.inf
    with pytest.raises(LogFormatError, match=r"column 'q_1' must be finite; row 3 holds -inf"):
        validate_table(df)


def test_non_numeric_in_csv(tmp_path) -> None:
    path = tmp_path / "text.csv"
    path.write_text("t,q_1\n0.0,0.1\n0.001,0.2\n0.002,abc\n0.003,0.4\n")
    with pytest.raises(
        LogFormatError,
        match=r"column 'q_1' must be numeric; row 2 holds the non-numeric value 'abc'",
    ):
        read_log(path)


def test_non_numeric_dtype() -> None:
    df = small_table()
    df["q_2"] = [True, False, True, False, True]
    with pytest.raises(LogFormatError, match=r"column 'q_2' must be numeric; it has dtype bool"):
        validate_table(df)


def test_missing_value_in_object_column() -> None:
    df = small_table().astype({"tau_m_1": object})
    df.loc[4, "tau_m_1"] = None
    with pytest.raises(LogFormatError, match=r"column 'tau_m_1' must be finite; row 4 holds nan"):
        validate_table(df)


@pytest.mark.parametrize(
    ("drop", "match"),
    [
        (["t"], r"needs the time column 't' .*missing 't'; found columns \['q_1'"),
        (["q_1", "q_2"], r"missing 'q_1'\.\.'q_<n_dof>'; found columns \['t', 'tau_m_1'"),
    ],
)
def test_missing_required_columns(drop: list[str], match: str) -> None:
    with pytest.raises(LogFormatError, match=match):
        validate_table(small_table().drop(columns=drop))


def test_missing_q_with_n_dof_says_expected() -> None:
    with pytest.raises(LogFormatError, match=r"missing 'q_1'\.\.'q_2'"):
        validate_table(small_table().drop(columns=["q_1", "q_2"]), n_dof=2)


def test_inconsistent_groups_name_missing_column() -> None:
    df = small_table(n_dof=7).drop(columns=["tau_m_7"])
    with pytest.raises(
        LogFormatError, match=r"inconsistent joint counts \(q: 7, tau_m: 6\).*'tau_m_7'"
    ):
        validate_table(df)
    gap = small_table(n_dof=3).drop(columns=["q_2"])
    with pytest.raises(LogFormatError, match=r"missing column\(s\) \['q_2'\]"):
        validate_table(gap)


def test_n_dof_mismatch_is_dimension_error() -> None:
    df = small_table(n_dof=7)
    with pytest.raises(DimensionError, match="robot has 6 joints, log has 7"):
        validate_table(df, n_dof=6)
    assert validate_table(df, n_dof=7) == 7
    with pytest.raises(InputValueError, match="n_dof must be a positive integer"):
        validate_table(df, n_dof=0)


@pytest.mark.parametrize("name", ["tau_M_1", "q_0", "q_01", "torque", "Unnamed: 0"])
def test_unknown_column(name: str) -> None:
    df = small_table()
    df[name] = 0.0
    with pytest.raises(
        LogFormatError,
        match=rf"unknown column\(s\) \[{re.escape(repr(name))}\]; known columns are 't', 'q_<j>'",
    ):
        validate_table(df)


def test_duplicate_column() -> None:
    df = pd.concat([small_table(), small_table()[["q_1"]]], axis=1)
    with pytest.raises(LogFormatError, match=r"duplicate column\(s\) \['q_1'\]"):
        validate_table(df)


@pytest.mark.parametrize("n", [0, 1])
def test_fewer_than_two_samples(n: int) -> None:
    with pytest.raises(LogFormatError, match=f"at least 2 samples .*got {n}"):
        validate_table(small_table(n=n))


def test_time_goes_backwards() -> None:
    df = small_table(n=6)
    df.loc[4, "t"] = 0.0025
    with pytest.raises(
        LogFormatError,
        match=r"strictly increasing; it goes backwards at row 4: t = 0\.0025 s at row 4 "
        r"after t = 0\.003 s at row 3",
    ):
        validate_table(df)


def test_time_repeats() -> None:
    df = small_table(n=6)
    df.loc[2, "t"] = df.loc[1, "t"]
    with pytest.raises(LogFormatError, match=r"it repeats at row 2: t = 0\.001 s at row 2"):
        validate_table(df)


def test_irregular_time() -> None:
    df = small_table(n=8)
    df.loc[5, "t"] += 2e-4
    with pytest.raises(
        LogFormatError,
        match=r"not regularly sampled: the step from row 4 to row 5 .* is 0\.0012 s, "
        r"the median step is 0\.001 s; .*resample",
    ):
        validate_table(df)
    assert validate_table(df, check_regular=False) == 2
    assert validate_table(df, rtol=0.5) == 2
    with pytest.raises(InputValueError, match="rtol must be a finite, non-negative number"):
        validate_table(df, rtol=-1.0)


def test_regular_time_far_from_zero() -> None:
    # Unix-time stamps at 1 kHz: the float spacing of the stamps is not jitter.
    df = small_table(n=100)
    df["t"] = 1.7e9 + DT * np.arange(100)
    assert validate_table(df) == 2


def test_irregular_time_in_file_and_resample(tmp_path) -> None:
    log = Log(t=[0.0, 0.001, 0.0021, 0.003], q=np.zeros((4, 1)))
    path = write_log(log, tmp_path / "jitter.csv")
    with pytest.raises(LogFormatError, match="not regularly sampled"):
        read_log(path)
    jittery = read_log(path, check_regular=False)
    regular = resample(jittery, 0.001)
    assert validate_table(regular.to_pandas()) == 1


def test_degrees_detected() -> None:
    df = small_table(n=6, n_dof=3)
    df["q_3"] = np.array([0.0, 10.0, 20.0, 30.0, 40.0, 50.0])
    with pytest.raises(
        LogFormatError,
        match=r"column 'q_3' looks like degrees, but angles must be radians: row 2 holds 20\.0",
    ):
        validate_table(df)
    df["q_3"] = 0.0
    df["q_true_1"], df["q_true_2"], df["q_true_3"] = 0.0, 0.0, 0.0
    df.loc[4, "q_true_2"] = -90.0
    with pytest.raises(LogFormatError, match=r"column 'q_true_2' looks like degrees.*row 4"):
        validate_table(df)


def test_torques_are_not_angles() -> None:
    df = small_table()
    df["tau_m_1"] = 300.0
    assert validate_table(df) == 2


def test_collision_id_checks() -> None:
    df = small_table()
    df["collision_id"] = [0, 0, -1, 0, 0]
    with pytest.raises(LogFormatError, match=r"non-negative integers .*row 2 holds -1\.0"):
        validate_table(df)


def test_validate_table_rejects_other_types() -> None:
    with pytest.raises(LogFormatError, match="must be a pandas DataFrame or a mapping"):
        validate_table([1, 2, 3])  # type: ignore[arg-type]


# --------------------------------------------------------------------------- resample


def test_resample_linear_ramp_exact() -> None:
    rng = np.random.default_rng(3)
    # Jittery time base on [0, 1] s with both end points kept.
    t = np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0.0, 1.0, 200)]))
    slopes = np.array([0.5, -1.25])
    offsets = np.array([0.1, 2.0])
    q = offsets + np.outer(t, slopes)
    tau_m = 3.0 * q - 1.0
    collision_id = (t > 0.5).astype(np.int64)
    log = Log(t=t, q=q, tau_m=tau_m, collision_id=collision_id, metadata={"robot": "x"})
    with pytest.raises(LogFormatError, match="not regularly sampled"):
        validate_table(log.to_pandas())

    new = resample(log, 0.01)
    grid = 0.01 * np.arange(101)
    assert new.n_samples == 101
    np.testing.assert_allclose(new.t, grid, rtol=0, atol=1e-15)
    np.testing.assert_allclose(new.q, offsets + np.outer(grid, slopes), rtol=0, atol=1e-14)
    np.testing.assert_allclose(new.tau_m, 3.0 * new.q - 1.0, rtol=0, atol=1e-13)
    # Zero-order hold: the label of the latest original sample at or before each grid time.
    previous = np.searchsorted(t, new.t, side="right") - 1
    assert np.array_equal(new.collision_id, collision_id[previous])
    assert new.collision_id.dtype == np.int64
    assert validate_table(new.to_pandas(), n_dof=2) == 2
    assert new.metadata["robot"] == "x"
    assert new.metadata["sample_rate"] == pytest.approx(100.0)
    assert new.metadata["resampled"]["n_samples_before"] == log.n_samples


def test_resample_errors() -> None:
    log = Log(t=[0.0, 0.1, 0.25], q=np.zeros((3, 1)))
    with pytest.raises(InputValueError, match="dt must be a positive, finite number"):
        resample(log, -0.1)
    with pytest.raises(InputValueError, match=r"dt = 0\.3 s is longer than the log"):
        resample(log, 0.3)


def test_resample_refuses_a_gap() -> None:
    # 100 Hz with the 0.194 s hole of a real recording after t = 1 s.
    t = np.concatenate([0.01 * np.arange(101), 1.194 + 0.01 * np.arange(50)])
    log = Log(t=t, q=np.outer(t, [1.0, -1.0]), metadata={"robot": "x"})
    with pytest.raises(
        LogFormatError,
        match=(
            r"refuses to interpolate across a gap: the log has no sample from t = 1\.0 s "
            r"\(row 100\) to t = 1\.194 s \(row 101\), 0\.194 s = 19\.4 periods of 0\.01 s; "
            r".*max_gap = 3 periods\. .*split_at_gaps.*allow_gaps=True"
        ),
    ):
        resample(log, 0.01)
    # The period is the longer of dt and the log's step: at 10 Hz the hole is 1.9 periods.
    assert resample(log, 0.1).n_samples == 17
    assert resample(log, 0.01, max_gap=20).n_samples == 169
    forced = resample(log, 0.01, allow_gaps=True)
    np.testing.assert_allclose(forced.q[:, 0], forced.t, rtol=0, atol=1e-12)
    assert forced.metadata["resampled"]["interpolated_gaps"] == [
        {"t_start": 1.0, "t_end": 1.194, "duration": pytest.approx(0.194)}
    ]
    assert forced.metadata["resampled"]["max_gap"] == 3.0
    with pytest.raises(LogFormatError, match=r"\(the first of 2 gaps\)"):
        resample(Log(t=[0.0, 0.01, 0.5, 0.51, 1.0, 1.01], q=np.zeros((6, 1))), 0.01)
    with pytest.raises(InputValueError, match=r"max_gap must be a finite number > 0"):
        resample(log, 0.01, max_gap=0.0)
    with pytest.raises(TypeError, match="allow_gaps must be True or False"):
        resample(log, 0.01, allow_gaps="yes")  # type: ignore[arg-type]


def test_split_at_gaps() -> None:
    t = np.array([0.0, 0.01, 0.02, 0.5, 0.9, 0.91, 0.92, 0.93])
    collision_id = np.arange(8)
    log = Log(t=t, q=np.outer(t, [2.0]), collision_id=collision_id, metadata={"seed": 1})
    first, second = split_at_gaps(log)  # 3 median steps of 0.01 s
    assert first.t.tolist() == [0.0, 0.01, 0.02]
    assert second.t.tolist() == [0.9, 0.91, 0.92, 0.93]
    assert second.collision_id.tolist() == [4, 5, 6, 7]
    np.testing.assert_array_equal(second.q[:, 0], 2.0 * second.t)
    segment = second.metadata["segment"]
    assert segment["index"] == 1 and segment["count"] == 2 and segment["first_row"] == 4
    assert segment["isolated_samples_dropped"] == 1  # the sample at 0.5 s
    assert [gap["t_start"] for gap in segment["gaps"]] == [0.02, 0.5]
    assert second.metadata["seed"] == 1
    # Segments share the log's memory instead of copying it.
    assert np.shares_memory(second.q, log.q)
    [whole] = split_at_gaps(log, tolerance=1.0)
    assert np.array_equal(whole.t, log.t) and whole.metadata["segment"]["count"] == 1
    with pytest.raises(LogFormatError, match=r"no two consecutive samples .* tolerance = 0\.001 s"):
        split_at_gaps(log, tolerance=0.001)
    with pytest.raises(InputValueError, match="tolerance must be a finite number > 0"):
        split_at_gaps(log, tolerance=-1.0)


# --------------------------------------------------------------------------- measured velocity


def test_measured_velocity_and_vendor_estimate_groups(tmp_path) -> None:
    rng = np.random.default_rng(4)
    t = DT * np.arange(20)
    q = rng.uniform(-1.0, 1.0, (20, 2))
    qd = rng.normal(0.0, 30.0, (20, 2))  # large velocities are not angles
    log = Log(t=t, q=q, qd=qd, tau_m=-q, tau_ext=rng.normal(size=(20, 2)), qd_true=qd + 1.0)
    assert log.groups == ["q", "qd", "tau_m", "tau_ext", "qd_true"]
    assert log.columns[:5] == ["t", "q_1", "q_2", "qd_1", "qd_2"]
    assert log.columns[7:9] == ["tau_ext_1", "tau_ext_2"]
    for suffix in (".parquet", ".csv"):
        path = write_log(log, tmp_path / f"measured{suffix}")
        sidecar = json.loads(sidecar_path(path).read_text())
        assert sidecar["units"]["qd"] == "rad/s" and sidecar["units"]["tau_ext"] == "N m"
        again = read_log(path)
        assert np.array_equal(again.qd, log.qd) and np.array_equal(again.tau_ext, log.tau_ext)
        assert again.columns == log.columns
    # A log without them is unchanged: no column, no attribute value.
    plain = Log(t=t, q=q)
    assert plain.qd is None and plain.tau_ext is None and plain.columns == ["t", "q_1", "q_2"]
    sliced = log.slice(0.005)
    assert np.array_equal(sliced.qd, log.qd[5:])
    assert np.array_equal(resample(log, 2 * DT).qd, log.qd[::2])


def test_measured_velocity_checks() -> None:
    df = small_table()
    df["qd_1"] = 0.0
    with pytest.raises(LogFormatError, match=r"qd: 1.*missing column\(s\) \['qd_2'\]"):
        validate_table(df)
    df["qd_2"] = [0.0, 0.0, math.inf, 0.0, 0.0]
    with pytest.raises(LogFormatError, match=r"column 'qd_2' must be finite; row 2 holds inf"):
        validate_table(df)
    with pytest.raises(DimensionError, match=r"qd must have the shape of q"):
        Log(t=[0.0, 1.0], q=np.zeros((2, 2)), qd=np.zeros((2, 3)))
    # The new groups are keyword-only: positional arguments keep their meaning.
    positional = Log([0.0, 1.0], np.zeros((2, 1)), np.ones((2, 1)))
    assert positional.tau_m is not None and positional.qd is None


def test_log_shares_read_only_arrays() -> None:
    log = make_log()
    again = Log(t=log.t, q=log.q, tau_m=log.tau_m)
    assert np.shares_memory(again.q, log.q)
    view = np.zeros((N_SAMPLES, N_DOF))
    frozen = view[:]
    frozen.setflags(write=False)  # read-only view of a writable array: still copied
    copied = Log(t=log.t, q=frozen)
    assert not np.shares_memory(copied.q, view)


def test_a_file_with_time_in_milliseconds_is_refused(tmp_path) -> None:
    """A log file sampled at 1 kHz but stamped in ms reads as 1 s steps: refused, with the fix."""
    t = np.arange(200) * 1.0  # ms
    frame = pd.DataFrame({"t": t, "q_1": np.sin(t / 100.0), "q_2": np.cos(t / 100.0)})
    frame.to_csv(tmp_path / "ms.csv", index=False)
    with pytest.raises(
        LogFormatError,
        match=r"looks like milliseconds.*median step is 1 s.*/ *1000|divide t by 1000",
    ):
        read_log(tmp_path / "ms.csv")
    frame["t"] = t / 1000.0
    frame.to_csv(tmp_path / "s.csv", index=False)
    assert read_log(tmp_path / "s.csv").dt == pytest.approx(1e-3)
