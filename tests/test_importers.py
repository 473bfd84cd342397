"""Tests of :mod:`sensorless.io.importers`.

Each format gets a simulated run written the way a real recorder would write
it, with that format's quirks (duplicated and out-of-order rows, jittered or
millisecond time stamps, motor currents, degrees, a gap), and must come back
to the same signals within the precision of the file. Jittered time stamps
carry the values of the simulated (piecewise-linear) signals at those times;
resampling them back onto a regular grid then errs by less than the largest
second difference of each signal (a chord over at most 1.6 periods spans at
most two kinks, each of which moves it by at most |Δ²x|/dt · L/4). Malformed
files must be refused with an error naming the file, the column and the row.
The real UR10 recordings of ``shared/data`` must import.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

import sensorless as sl
from sensorless.exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    LogFormatError,
    UnknownNameError,
)
from sensorless.io import (
    UR_CURRENT_GAINS,
    Log,
    import_csv,
    import_franka,
    import_log,
    import_ros2,
    import_ur_rtde,
    load_csv_spec,
    read_log,
    write_log,
)
from sensorless.io.importers._pipeline import RowBuffer
from sensorless.simulation.scenario import load_scenario

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"
UR10_FILES = ("link4", "ur-static", "no_torque", "3times")
GAINS = np.array(UR_CURRENT_GAINS["ur10"])


@pytest.fixture(scope="module")
def recorded() -> Log:
    """A simulated Panda run as a real arm records it: measured q̇, three torque signals."""
    sim = load_scenario("panda-gaz").with_duration(2).run(seed=1).log
    return Log(
        t=sim.t,
        q=sim.q,
        qd=sim.qd_true,
        tau_m=sim.tau_m,
        tau_j=sim.tau_m - 0.1 * sim.qd_true,
        tau_ext=sim.tau_c,
        collision_id=sim.collision_id,
    )


@pytest.fixture(scope="module")
def panda() -> sl.RobotModel:
    return sl.robots.load("panda")


# --------------------------------------------------------------------------- quirks
def with_duplicates(table: pd.DataFrame, rows: list[int]) -> pd.DataFrame:
    """Each of ``rows`` written twice in a row."""
    order = np.sort(np.concatenate([np.arange(len(table)), rows]), kind="stable")
    return table.iloc[order].reset_index(drop=True)


def with_swaps(table: pd.DataFrame, rows: list[int]) -> pd.DataFrame:
    """Row ``r`` and ``r + 1`` exchanged for each of ``rows``."""
    order = np.arange(len(table))
    for row in rows:
        order[[row, row + 1]] = order[[row + 1, row]]
    return table.iloc[order].reset_index(drop=True)


def jittered(log: Log, rng: np.random.Generator, fraction: float) -> tuple[np.ndarray, Log]:
    """Time stamps moved by up to ``fraction`` periods, values taken at the moved times."""
    t = log.t.copy()
    t[1:-1] += rng.uniform(-fraction, fraction, t.size - 2) * log.dt
    changes = {group: resampled(getattr(log, group), log.t, t) for group in log.groups}
    assert log.collision_id is not None
    previous = np.searchsorted(log.t, t, side="right") - 1
    return t, Log(t=t, collision_id=log.collision_id[previous], **changes)


def resampled(values: np.ndarray, t: np.ndarray, at: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(at, t, column) for column in values.T])


def assert_within_resampling(segment: Log, log: Log, groups: tuple[str, ...]) -> None:
    """Each group of ``segment`` is ``log`` at the segment's times, to the resampling bound."""
    for group in groups:
        expected = resampled(getattr(log, group), log.t, segment.t)
        bound = np.abs(np.diff(getattr(log, group), 2, axis=0)).max(axis=0)
        error = np.abs(getattr(segment, group) - expected).max(axis=0)
        assert np.all(error <= bound), (group, error, bound)


# --------------------------------------------------------------------------- Franka
def franka_table(log: Log, panda: sl.RobotModel, time_scale: float = 1.0) -> pd.DataFrame:
    data: dict[str, np.ndarray] = {"time": log.t * time_scale}
    commanded = log.tau_m - panda.gravity(log.q)
    for prefix, values in [
        ("q", log.q),
        ("dq", log.qd),
        ("tau_J", log.tau_j),
        ("tau_J_d", commanded),
        ("tau_ext", log.tau_ext),
    ]:
        for joint in range(log.n_dof):
            data[f"{prefix}{joint}"] = values[:, joint]
    data["label"] = log.collision_id
    return pd.DataFrame(data)


def test_franka_round_trip_ms_stamps_duplicates_out_of_order(
    recorded: Log, panda: sl.RobotModel, tmp_path: Path
) -> None:
    table = franka_table(recorded, panda, time_scale=1000.0)
    table["time"] = np.round(table["time"]).astype(np.int64)  # libfranka counts ms
    table = with_swaps(with_duplicates(table, [5, 6, 500, 1999]), [100, 900, 901 + 2])
    path = tmp_path / "franka.csv"
    table.to_csv(path, index=False, float_format="%.17g")

    [log] = import_franka(path, time_unit="ms", gravity_model=panda)
    assert log.groups == ["q", "qd", "tau_m", "tau_j", "tau_ext"]
    np.testing.assert_allclose(log.t, recorded.t, rtol=0, atol=1e-12)
    for group in ("q", "qd", "tau_j", "tau_ext"):
        assert np.array_equal(getattr(log, group), getattr(recorded, group)), group
    np.testing.assert_allclose(log.tau_m, recorded.tau_m, rtol=0, atol=1e-12)
    assert np.array_equal(log.collision_id, recorded.collision_id)
    report = log.metadata["import"]["report"]
    assert report["rows_read"] == recorded.n_samples + 4
    assert report["duplicate_rows_dropped"] == 4
    assert report["duplicates_with_other_values"] == 0
    assert report["out_of_order_rows"] == 3
    assert report["gaps"] == [] and report["segments"] == 1
    assert "resampled" not in log.metadata
    meta = log.metadata["import"]
    assert meta["format"] == "franka" and meta["source"] == str(path.resolve())
    assert meta["source_units"]["t"] == "ms"
    assert "g(q)" in meta["conversions"]["tau_m"]
    # Without a gravity model there is no commanded torque, and the log stays valid.
    [plain] = import_franka(path, time_unit="ms")
    assert plain.groups == ["q", "qd", "tau_j", "tau_ext"]
    # The Franka baseline survives the project's own file format.
    again = read_log(write_log(log, tmp_path / "franka.parquet"))
    assert np.array_equal(again.tau_ext, log.tau_ext) and np.array_equal(again.qd, log.qd)


def test_franka_malformed(recorded: Log, panda: sl.RobotModel, tmp_path: Path) -> None:
    table = franka_table(recorded, panda).astype(object)
    table.loc[17, "dq3"] = "oops"
    path = tmp_path / "bad.csv"
    table.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(path))}: column 'dq3', row 17: "):
        import_franka(path)
    table = franka_table(recorded, panda).drop(columns=["tau_J4"])
    table.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=r"bad\.csv: has 6 of the 7 columns .*\['tau_J4'\]"):
        import_franka(path)
    table = franka_table(recorded, panda)
    table.loc[3, "q2"] = 90.0
    table.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=r"column 'q2', row 3: .*degrees"):
        import_franka(path)
    with pytest.raises(DimensionError, match=r"has 6 joints, the file .* has 7"):
        import_franka(path, gravity_model=sl.robots.load("ur5"))
    with pytest.raises(InputValueError, match="time_unit must be one of"):
        import_franka(path, time_unit="min")


# --------------------------------------------------------------------------- UR RTDE
def ur_table(t: np.ndarray, log: Log) -> pd.DataFrame:
    data: dict[str, np.ndarray] = {"timestamp": t}
    for prefix, values in [
        ("actual_q_", log.q),
        ("actual_qd_", log.qd),
        ("actual_current_", log.tau_m / GAINS),
        ("target_moment_", log.tau_j),
    ]:
        for joint in range(6):
            data[f"{prefix}{joint}"] = values[:, joint]
    return pd.DataFrame(data)


@pytest.fixture(scope="module")
def ur_sized(recorded: Log) -> Log:
    """The first six joints of the run, a UR-sized arm."""
    groups = {group: getattr(recorded, group)[:, :6] for group in recorded.groups}
    return Log(t=recorded.t, collision_id=recorded.collision_id, **groups)


def test_ur_rtde_round_trip_jitter_currents_gap(ur_sized: Log, tmp_path: Path) -> None:
    t, jitter = jittered(ur_sized, np.random.default_rng(5), 0.3)
    table = ur_table(t, jitter)
    table = table[(t < 0.8) | (t >= 1.0)]  # a 0.2 s hole in the recording
    path = tmp_path / "rtde.csv"
    table.to_csv(path, index=False, sep=" ", float_format="%.17g")  # as UR's record.py

    # With jitter this strong the median step is the nominal period only to 0.3 %: give it.
    first, second = import_ur_rtde(path, robot="ur10", dt=0.001)
    assert first.t[0] == pytest.approx(0.0, abs=1e-15)
    assert first.t[-1] < 0.8 <= 1.0 <= second.t[0]
    for segment in (first, second):
        assert segment.dt == pytest.approx(0.001, rel=1e-9)
        assert segment.groups == ["q", "qd", "tau_m"]
        assert_within_resampling(segment, ur_sized, ("q", "qd", "tau_m"))
        assert segment.metadata["robot"] == "ur10"
        assert segment.metadata["resampled"]["dt"] == 0.001
    report = first.metadata["import"]["report"]
    assert report["segments"] == 2 and len(report["gaps"]) == 1
    gap = report["gaps"][0]
    assert gap["t_start"] < 0.8 <= 1.0 <= gap["t_end"]
    assert gap["duration"] == pytest.approx(gap["t_end"] - gap["t_start"])
    assert 0.0002 < report["max_jitter"] <= 0.0006 + 1e-12
    assert first.metadata["import"]["conversions"]["tau_m"]["gains"] == list(GAINS)
    assert first.metadata["import"]["source_units"]["tau_m"] == "A"
    # A tolerance longer than the hole interpolates across it, as asked.
    [whole] = import_ur_rtde(path, robot="ur10", dt=0.001, gap_tolerance=0.5)
    assert whole.metadata["import"]["report"]["gaps"] == []
    # RTDE's target torque as the motor torque, and gains given by hand.
    [target] = import_ur_rtde(path, torque="target_moment", dt=0.001, gap_tolerance=0.5)
    np.testing.assert_allclose(target.t, whole.t, rtol=0, atol=1e-12)
    moments = Log(t=ur_sized.t, q=ur_sized.q, tau_m=ur_sized.tau_j)
    assert_within_resampling(target.slice(stop=0.8), moments, ("tau_m",))
    [doubled] = import_ur_rtde(path, gains=2 * GAINS, dt=0.001, gap_tolerance=0.5)
    np.testing.assert_allclose(doubled.tau_m, 2 * whole.tau_m, rtol=1e-14)


def test_ur_rtde_gains_and_options(ur_sized: Log, tmp_path: Path) -> None:
    path = tmp_path / "rtde.csv"
    ur_table(ur_sized.t, ur_sized).to_csv(path, index=False)
    with pytest.raises(InputValueError, match=r"needs the current-to-torque gains"):
        import_ur_rtde(path)
    with pytest.raises(InputValueError, match=r"no published .* for robot 'ur5'.*pass gains="):
        import_ur_rtde(path, robot="ur5")
    with pytest.raises(InputValueError, match=r"gains must be finite and > 0"):
        import_ur_rtde(path, gains=[1.0, 2.0, 3.0, 4.0, 5.0, -6.0])
    with pytest.raises(InputValueError, match=r"torque must be one of"):
        import_ur_rtde(path, torque="currents")
    [log] = import_ur_rtde(path, robot="ur5", torque=None)
    assert log.groups == ["q", "qd"] and log.metadata["robot"] == "ur5"


def test_ur_rtde_malformed(ur_sized: Log, tmp_path: Path) -> None:
    table = ur_table(ur_sized.t, ur_sized)
    path = tmp_path / "bad.csv"
    table.drop(columns=["timestamp"]).to_csv(path, index=False)
    with pytest.raises(LogFormatError, match=r"bad\.csv: missing column 'timestamp'"):
        import_ur_rtde(path, robot="ur10")
    broken = table.astype(object)
    broken.loc[5, "actual_current_2"] = ""
    broken.to_csv(path, index=False)
    with pytest.raises(
        LogFormatError, match=r"bad\.csv: column 'actual_current_2', row 5: holds nan"
    ):
        import_ur_rtde(path, robot="ur10")
    table.to_csv(path, index=False)
    text = path.read_text(encoding="utf-8")
    path.write_text(text + "3.0,0.1\n", encoding="utf-8")  # a row cut short
    with pytest.raises(LogFormatError, match=r"bad\.csv: column 'actual_q_1', row 2001: holds nan"):
        import_ur_rtde(path, robot="ur10")
    path.write_text(text + "3.0" + ",0.1" * 25 + "\n", encoding="utf-8")  # one field too many
    with pytest.raises(LogFormatError, match=r"bad\.csv: cannot be parsed as CSV: .*line 2003"):
        import_ur_rtde(path, robot="ur10")


# --------------------------------------------------------------------------- column mapping
MAPPING_SPEC = {
    "description": "a UR-style logger: no header, semicolons, ms, degrees, currents",
    "robot": "ur10",
    "header": False,
    "delimiter": ";",
    "time": {"column": 2, "unit": "ms"},
    "q": {"columns": [4, 5, 6, 7, 8, 9], "unit": "deg"},
    "qd": {"columns": [10, 11, 12, 13, 14, 15], "unit": "deg/s"},
    "tau_m": {"columns": [16, 17, 18, 19, 20, 21], "unit": "A", "gains": GAINS.tolist()},
    "label": {"column": 1},
}


def mapping_table(log: Log, rng: np.random.Generator) -> pd.DataFrame:
    """Columns: label, time [ms], an undocumented one, q [deg], q̇ [deg/s], currents, noise."""
    columns: list[np.ndarray] = [log.collision_id, log.t * 1000.0, rng.normal(size=log.n_samples)]
    columns += list(np.rad2deg(log.q).T) + list(np.rad2deg(log.qd).T)
    columns += list((log.tau_m / GAINS).T) + list(rng.normal(size=(3, log.n_samples)))
    return pd.DataFrame(np.column_stack(columns))


def test_mapping_round_trip_degrees_currents_duplicates(ur_sized: Log, tmp_path: Path) -> None:
    table = with_duplicates(mapping_table(ur_sized, np.random.default_rng(2)), [0, 1000, 1001])
    path = tmp_path / "logger.txt"
    table.to_csv(path, index=False, header=False, sep=";", float_format="%.9g")

    [log] = import_csv(path, MAPPING_SPEC)
    np.testing.assert_allclose(log.t, ur_sized.t, rtol=0, atol=1e-12)
    for group in ("q", "qd", "tau_m"):
        expected = getattr(ur_sized, group)
        # 9 significant digits in the file.
        np.testing.assert_allclose(getattr(log, group), expected, rtol=1e-8, atol=1e-12)
    assert np.array_equal(log.collision_id, ur_sized.collision_id)
    assert log.metadata["robot"] == "ur10"
    meta = log.metadata["import"]
    assert meta["source_units"] == {"t": "ms", "q": "deg", "qd": "deg/s", "tau_m": "A"}
    assert meta["columns"]["q"] == [4, 5, 6, 7, 8, 9]
    assert meta["report"]["duplicate_rows_dropped"] == 3
    # The same file through the dispatcher, with the spec as a YAML file.
    spec_path = tmp_path / "spec.yaml"
    spec_path.write_text(yaml.safe_dump(MAPPING_SPEC), encoding="utf-8")
    [again] = import_log("csv", [path], spec=spec_path)
    assert np.array_equal(again.q, log.q)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (
            {"q": {"columns": [4, 5], "unit": "degrees"}},
            r"q\.unit: Input should be 'rad' or 'deg'; got 'degrees'",
        ),
        (
            {"tau_m": {"columns": [16, 17, 18, 19, 20, 21], "unit": "A"}},
            r"tau_m: currents \(unit 'A'\) need gains",
        ),
        (
            {"tau_m": {"columns": [16], "unit": "N m", "gains": 2.0}},
            r"tau_m: gains convert currents",
        ),
        (
            {"tau_m": {"columns": [16, 17], "unit": "A", "gains": [1, 2, 3]}},
            r"tau_m: gains has 3 values for 2 columns",
        ),
        (
            {"tau_m": {"columns": [16], "unit": "A", "gains": [-1]}},
            r"tau_m\.gains\.0: Input should be greater than 0",
        ),
        ({"qd": {"columns": [10, 11]}}, r"qd\.columns has 2 columns but q\.columns has 6"),
        (
            {"time": {"column": 0}},
            r"time\.column: with header: false, columns are numbers from 1; got 0",
        ),
        ({"label": {"column": 4}}, r"column 4 is used by both q\.columns and label\.column"),
        ({"delimiter": "|"}, r"delimiter: Input should be"),
        ({"tau": {"columns": [1]}}, r"tau: Extra inputs are not permitted"),
        ({"q": {"columns": [True]}}, r"q\.columns\.0: a column is a header name .*got True"),
        ({"header": True}, r"time\.column: with header: true, columns are named; got 2"),
    ],
)
def test_mapping_spec_errors_name_the_field(change: dict, match: str) -> None:
    with pytest.raises(InputValueError, match=r"invalid CSV import spec \(a mapping\): " + match):
        load_csv_spec(MAPPING_SPEC | change)


def test_mapping_spec_sources(tmp_path: Path) -> None:
    assert "ur10_ext_observer" in sl.io.importers.available_csv_specs()
    assert load_csv_spec("ur10_ext_observer").robot == "ur10"
    with pytest.raises(
        UnknownNameError, match=r"unknown CSV import spec 'ur11'.*ur10_ext_observer"
    ):
        load_csv_spec("ur11")
    path = tmp_path / "list.yaml"
    path.write_text("- 1\n- 2\n", encoding="utf-8")
    with pytest.raises(InputValueError, match=r"list\.yaml\): a YAML mapping is needed; got list"):
        load_csv_spec(path)
    with pytest.raises(InputValueError, match=r"\(a mapping\): time: Field required"):
        load_csv_spec({"q": {"columns": ["a"]}})


def test_mapping_malformed(ur_sized: Log, tmp_path: Path) -> None:
    path = tmp_path / "logger.txt"
    table = mapping_table(ur_sized, np.random.default_rng(2)).astype(object)
    table.loc[40, 3] = "oops"  # spec column 4 (the first joint's position)
    table.to_csv(path, index=False, header=False, sep=";")
    with pytest.raises(LogFormatError, match=r"logger\.txt: column 4, row 40: holds 'oops'"):
        import_csv(path, MAPPING_SPEC)
    table = mapping_table(ur_sized, np.random.default_rng(2))
    table.to_csv(path, index=False, header=False, sep=";")
    radians = MAPPING_SPEC | {"q": {"columns": [4, 5, 6, 7, 8, 9], "unit": "rad"}}
    with pytest.raises(LogFormatError, match=r"column [4-9], row \d+: holds the angle .*'deg'"):
        import_csv(path, radians)
    beyond = MAPPING_SPEC | {"label": {"column": 99}}
    with pytest.raises(LogFormatError, match=r"row 0 has 24 columns .* column 99 is needed"):
        import_csv(path, beyond)
    table[0] = 0.5  # a fractional label
    table.to_csv(path, index=False, header=False, sep=";")
    with pytest.raises(LogFormatError, match=r"column 1, row 0: holds 0\.5; labels must be"):
        import_csv(path, MAPPING_SPEC)


# --------------------------------------------------------------------------- ROS 2
JOINTS = [f"panda_joint{j}" for j in range(1, 8)]


def write_bag(
    path: Path, messages: list[tuple], storage: str, topics: int = 1, little_endian: bool = True
) -> None:
    """Write JointState messages (receive time [ns], names, position, velocity, effort, stamp).

    An entry (receive time [ns], bytes) is written as it is.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    state = store.types["sensor_msgs/msg/JointState"]
    header = store.types["std_msgs/msg/Header"]
    time = store.types["builtin_interfaces/msg/Time"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        topic = writer.add_connection("/joint_states", state.__msgtype__, typestore=store)
        writer.add_connection("/other", "std_msgs/msg/String", typestore=store)
        for index in range(1, topics):
            writer.add_connection(f"/joint_states_{index}", state.__msgtype__, typestore=store)
        for entry in messages:
            if isinstance(entry[1], bytes):
                writer.write(topic, *entry)
                continue
            received, names, position, velocity, effort, stamp = entry
            message = state(
                header=header(
                    stamp=time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="base"
                ),
                name=names,
                position=position,
                velocity=velocity,
                effort=effort,
            )
            raw = store.serialize_cdr(message, state.__msgtype__, little_endian=little_endian)
            writer.write(topic, received, raw)


def bag_messages(log: Log) -> list[tuple]:
    stamps = np.round(log.t * 1e9).astype(np.int64) + 1_700_000_000 * 10**9
    return [
        (int(stamps[k]) + 20_000, JOINTS, log.q[k], log.qd[k], log.tau_m[k] / 2.0, int(stamps[k]))
        for k in range(log.n_samples)
    ]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_ros2_round_trip(recorded: Log, tmp_path: Path, storage: str) -> None:
    messages = bag_messages(recorded)
    # Another part of the robot on the same topic, a duplicate, two messages stamped early.
    gripper = (
        messages[10][0] + 1,
        ["finger"],
        np.zeros(1),
        np.zeros(1),
        np.zeros(1),
        messages[10][5],
    )
    messages.insert(11, gripper)
    messages.insert(300, messages[299])
    messages[500], messages[501] = messages[501], messages[500]
    messages[501] = (messages[500][0] + 1, *messages[501][1:])
    path = tmp_path / "bag"
    write_bag(path, messages, storage)
    bag = path / "bag.mcap" if storage == "mcap" else path

    [log] = import_ros2(bag, effort_gains=2.0, robot="panda")
    np.testing.assert_allclose(log.t, recorded.t, rtol=0, atol=1e-12)
    assert log.metadata["import"]["report"]["time_origin"] == 1.7e9
    assert log.dt == pytest.approx(0.001, rel=1e-9)
    assert np.array_equal(log.q, recorded.q)
    assert np.array_equal(log.qd, recorded.qd)
    assert np.array_equal(log.tau_m, recorded.tau_m)
    report = log.metadata["import"]["report"]
    assert report["messages_skipped"] == 1
    assert report["duplicate_rows_dropped"] == 1
    assert report["out_of_order_rows"] == 1
    assert log.metadata["import"]["columns"]["joints"] == JOINTS
    # Joints picked by name and order; effort as joint-torque sensors; receive times.
    write_bag(tmp_path / "plain", bag_messages(recorded), storage)
    [part] = import_ros2(tmp_path / "plain", joints=JOINTS[3:0:-1], effort="tau_j", stamp="receive")
    assert part.metadata["import"]["report"]["time_origin"] == pytest.approx(1.7e9 + 2e-5)
    assert np.array_equal(part.q, recorded.q[:, 3:0:-1])
    np.testing.assert_allclose(part.tau_j, recorded.tau_m[:, 3:0:-1] / 2.0, rtol=1e-15)
    assert part.groups == ["q", "qd", "tau_j"]


def test_ros2_big_endian_messages_decode_one_by_one(recorded: Log, tmp_path: Path) -> None:
    messages = bag_messages(recorded)[:300]
    write_bag(tmp_path / "big", messages, "mcap", little_endian=False)
    [log] = import_ros2(tmp_path / "big", effort_gains=2.0)
    assert np.array_equal(log.q, recorded.q[:300])
    assert np.array_equal(log.tau_m, recorded.tau_m[:300])


def test_row_buffer_grows_past_its_estimate() -> None:
    buffer = RowBuffer(2, {"t": 0, "q": 2}, {"t": np.int64})
    for start in (0, 3, 6):
        buffer.extend({"t": np.arange(start, start + 3), "q": np.ones((3, 2)) * start})
    columns = buffer.arrays()
    assert columns["t"].tolist() == list(range(9)) and columns["t"].dtype == np.int64
    assert columns["q"][:, 1].tolist() == [0, 0, 0, 3, 3, 3, 6, 6, 6]


def test_ros2_malformed(recorded: Log, tmp_path: Path) -> None:
    messages = bag_messages(recorded)[:50]
    k = 17
    messages[k] = (*messages[k][:2], messages[k][2][:6], *messages[k][3:])
    write_bag(tmp_path / "short", messages, "mcap")
    with pytest.raises(
        LogFormatError,
        match=r"short\.mcap: topic '/joint_states', field 'position', message 17: holds 6 values",
    ):
        import_ros2(tmp_path / "short" / "short.mcap")
    messages = bag_messages(recorded)[:50]
    velocity = messages[k][3].copy()
    velocity[2] = np.nan
    messages[k] = (*messages[k][:3], velocity, *messages[k][4:])
    write_bag(tmp_path / "nan", messages, "mcap")
    with pytest.raises(
        LogFormatError,
        match=r"'/joint_states', field 'velocity' of joint 'panda_joint3', message 17: holds nan",
    ):
        import_ros2(tmp_path / "nan")
    with pytest.raises(InputValueError, match=r"no joint\(s\) \['elbow'\]"):
        import_ros2(tmp_path / "nan", joints=["elbow"])
    with pytest.raises(InputValueError, match=r"no sensor_msgs/msg/JointState topic '/js'"):
        import_ros2(tmp_path / "nan", topic="/js")
    messages = bag_messages(recorded)[:50]
    messages[k] = (messages[k][0], b"\x00\x01\x00\x00" + b"\xff" * 40)
    write_bag(tmp_path / "garbage", messages, "mcap", topics=2)
    with pytest.raises(InputValueError, match=r"several sensor_msgs/msg/JointState topics"):
        import_ros2(tmp_path / "garbage")
    with pytest.raises(
        LogFormatError, match=r"garbage: topic '/joint_states', message 17: not a valid sensor_msgs"
    ):
        import_ros2(tmp_path / "garbage", topic="/joint_states")
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 40)
    with pytest.raises(LogFormatError, match=r"broken\.mcap: cannot be read as a ROS 2 bag"):
        import_ros2(broken)


# --------------------------------------------------------------------------- dispatcher
def test_import_log_dispatch(recorded: Log, panda: sl.RobotModel, tmp_path: Path) -> None:
    paths = [tmp_path / "a.csv", tmp_path / "b.csv"]
    franka_table(recorded, panda).to_csv(paths[0], index=False)
    franka_table(recorded.slice(1.0), panda).to_csv(paths[1], index=False)
    logs = import_log("franka", paths)
    origins = [log.metadata["import"]["report"]["time_origin"] for log in logs]
    assert origins == [0.0, pytest.approx(1.0)]
    assert [log.t[0] for log in logs] == [0.0, 0.0]
    with pytest.raises(
        UnknownNameError,
        match=r"unknown import format 'rtde'; formats: \['csv', 'franka', 'ur-rtde', 'ros2'\]",
    ):
        import_log("rtde", paths)
    with pytest.raises(
        InputTypeError, match=r"unknown option\(s\) \['gains'\] for format 'franka'"
    ):
        import_log("franka", paths, gains=1.0)
    with pytest.raises(InputTypeError, match="at least one file"):
        import_log("franka", [])
    with pytest.raises(FileNotFoundError):
        import_log("franka", tmp_path / "missing.csv")


# --------------------------------------------------------------------------- real UR10 data
@pytest.fixture(scope="module")
def ur10_logs() -> dict[str, list[Log]]:
    if not DATA.is_dir():
        pytest.skip(f"the real UR10 recordings are not here: {DATA} does not exist")
    return {name: import_csv(DATA / f"{name}.csv", "ur10_ext_observer") for name in UR10_FILES}


def test_real_ur10_recordings_import(ur10_logs: dict[str, list[Log]]) -> None:
    expected_rows = {"link4": 1896, "ur-static": 4259, "no_torque": 531, "3times": 65}
    for name, logs in ur10_logs.items():
        for log in logs:
            assert log.n_dof == 6 and log.groups == ["q", "qd", "tau_m"]
            assert log.dt == pytest.approx(0.01, rel=1e-9)
            assert log.metadata["sample_rate"] == pytest.approx(100.0)
            assert log.metadata["robot"] == "ur10"
            assert log.metadata["import"]["source_units"]["tau_m"] == "A"
            report = log.metadata["import"]["report"]
            assert report["rows_read"] == expected_rows[name]
            assert report["nominal_dt"] == 0.01
            # The README's jitter: steps of 8 to 12 ms.
            assert 0.0 < report["max_jitter"] <= 0.002 + 1e-9
        assert (
            sum(log.metadata["import"]["segment"]["n_samples_before"] for log in logs)
            == (expected_rows[name])
        )
    assert [len(logs) for logs in ur10_logs.values()] == [1, 1, 1, 2]
    gap = ur10_logs["3times"][0].metadata["import"]["report"]["gaps"]
    assert len(gap) == 1 and gap[0]["duration"] == pytest.approx(1.114, abs=1e-9)


def test_real_ur10_current_convention(ur10_logs: dict[str, list[Log]]) -> None:
    """gain · current of the standing arm is the URDF model's gravity torque (sign and size)."""
    [log] = ur10_logs["ur-static"]
    assert np.abs(log.qd).max() < 0.05
    gravity = sl.robots.load("ur10").gravity(log.q).mean(axis=0)
    measured = log.tau_m.mean(axis=0)
    assert np.all(np.sign(measured[1:3]) == np.sign(gravity[1:3]))
    # Measured: 13 % of max |g| on the shoulder (a payload or an offset the model lacks).
    assert np.abs(measured[1:3] - gravity[1:3]).max() <= 0.15 * np.abs(gravity).max()
