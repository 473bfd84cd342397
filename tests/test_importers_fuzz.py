"""Fuzzing the log importers and the log reader: a bad file is refused, never a crash.

Each entry point starts from a small valid file written the way the
example-based tests of ``test_importers.py`` and ``test_io.py`` write theirs;
hypothesis then truncates it, flips, inserts or deletes bytes, deletes,
repeats or swaps lines, puts NaN, inf, 1e999, words or a very long string in
a cell, renames, drops or reorders columns, adds a byte-order mark, Windows
line endings or bytes that are not UTF-8; for ROS 2 bags it corrupts the
bag's bytes, its ``metadata.yaml`` and the payload of single messages. The
outcome must be one of two:

- an error of the library (:class:`~sensorless.exceptions.SensorlessError`)
  whose message is one non-empty line and names the file; or
- logs that are valid by an independent recount: time finite, strictly
  increasing and regular, every group of shape (n_samples, n_dof), every
  value finite (the importers and the reader refuse NaN), positions within
  ±4π rad, labels non-negative integers, JSON metadata.

Any other exception (KeyError, OverflowError, struct.error, sqlite3 and
pandas errors, ...) fails the test. ``SENSORLESS_FUZZ_EXAMPLES=5000`` runs a
deeper search than CI's.
"""

from __future__ import annotations

import io
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.exceptions import (
    InputTypeError,
    InputValueError,
    LogFormatError,
    MissingFileError,
    SensorlessError,
)
from sensorless.io import (
    Log,
    import_csv,
    import_franka,
    import_log,
    import_ros2,
    import_ur_rtde,
    load_csv_spec,
    read_log,
    sidecar_path,
    write_log,
)
from test_importers import MAPPING_SPEC

DEEP = int(os.environ.get("SENSORLESS_FUZZ_EXAMPLES", "0"))
N_ROWS = 60
DT = 0.001
ANGLE_LIMIT = 4.0 * math.pi  # written out, not taken from the module under test


def fuzz(examples: int) -> Any:
    """Reproducible settings: the same examples on every run, ``examples`` of them."""
    return settings(
        max_examples=DEEP or examples,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[
            HealthCheck.too_slow,
            HealthCheck.data_too_large,
            HealthCheck.function_scoped_fixture,
        ],
    )


@pytest.fixture(scope="module")
def folder() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="sensorless-fuzz-") as name:
        yield Path(name)


# --------------------------------------------------------------------------- valid files
def signals(n_dof: int, n: int = N_ROWS) -> np.ndarray:
    """Smooth joint signals, shape (n, n_dof), within ±1."""
    k = np.arange(n)[:, None]
    return np.sin(0.05 * k + np.arange(n_dof)[None, :])


def franka_bytes() -> bytes:
    data: dict[str, Any] = {"time": DT * np.arange(N_ROWS)}
    for prefix, scale in [("q", 1.0), ("dq", 0.5), ("tau_J", 20.0), ("tau_ext", 2.0)]:
        for joint in range(3):
            data[f"{prefix}{joint}"] = scale * signals(3)[:, joint]
    data["label"] = (np.arange(N_ROWS) // 20 == 1).astype(np.int64)
    return pd.DataFrame(data).to_csv(index=False, float_format="%.17g").encode()


def ur_bytes(sep: str) -> bytes:
    data: dict[str, Any] = {"timestamp": 1234.5 + 0.002 * np.arange(N_ROWS)}
    for prefix, scale in [
        ("actual_q_", 1.0),
        ("actual_qd_", 0.5),
        ("actual_current_", 2.0),
        ("target_moment_", 30.0),
    ]:
        for joint in range(6):
            data[f"{prefix}{joint}"] = scale * signals(6)[:, joint]
    return pd.DataFrame(data).to_csv(index=False, sep=sep, float_format="%.17g").encode()


def mapping_bytes() -> bytes:
    """The layout of ``MAPPING_SPEC``: label, time [ms], noise, q [deg], q̇ [deg/s], currents."""
    columns = [(np.arange(N_ROWS) // 25).astype(float), 10.0 * np.arange(N_ROWS)]
    columns += [np.cos(np.arange(N_ROWS))]
    columns += list(60.0 * signals(6).T) + list(20.0 * signals(6).T) + list(signals(6).T)
    columns += [np.zeros(N_ROWS)] * 3
    table = pd.DataFrame(np.column_stack(columns))
    return table.to_csv(index=False, header=False, sep=";", float_format="%.9g").encode()


HEADER_SPEC = {
    "header": True,
    "delimiter": ",",
    "time": {"column": "stamp", "unit": "us"},
    "q": {"columns": ["a", "b"], "unit": "rad"},
    "tau_m": {"columns": ["ia", "ib"], "unit": "A", "gains": [2.0, 3.0]},
    "label": {"column": "hit"},
}


def header_mapping_bytes() -> bytes:
    data: dict[str, Any] = {"stamp": 1_000_000 + 500 * np.arange(N_ROWS)}
    data |= {"extra": np.ones(N_ROWS), "a": signals(2)[:, 0], "b": signals(2)[:, 1]}
    data |= {"ia": signals(2)[:, 1], "ib": signals(2)[:, 0], "hit": np.zeros(N_ROWS, int)}
    return pd.DataFrame(data).to_csv(index=False, float_format="%.17g").encode()


# --------------------------------------------------------------------------- mutations
TOKENS = [
    b"",
    b"nan",
    b"NaN",
    b"inf",
    b"-inf",
    b"1e999",
    b"-1e999",
    b"1e308",
    b"-1e308",
    b"1e300",
    b"5e-324",
    b"-0",
    b"oops",
    b"True",
    b"NA",
    b"null",
    b"0x1F",
    b"1,5",
    b'"',
    b"9223372036854775808",
    b"-9223372036854775809",
    b"123456789012345678901234567890",
    b"\xff\xfe",
    b" ",
    b"x" * 5000,
    b"1" * 400,
]
cell_text = st.one_of(
    st.sampled_from(TOKENS),
    st.floats(allow_nan=True, allow_infinity=True).map(lambda x: repr(x).encode()),
    st.integers(-(2**70), 2**70).map(lambda x: str(x).encode()),
    st.binary(max_size=12),
)


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


def _cells(line: bytes, sep: bytes) -> list[bytes]:
    return line.split(sep)


def _truncate(draw: Any, data: bytes, sep: bytes) -> bytes:
    return data[: draw(st.integers(0, len(data)))]


def _replace_bytes(draw: Any, data: bytes, sep: bytes) -> bytes:
    buffer = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        if buffer:
            buffer[draw(st.integers(0, len(buffer) - 1))] = draw(st.integers(0, 255))
    return bytes(buffer)


def _insert_bytes(draw: Any, data: bytes, sep: bytes) -> bytes:
    at = draw(st.integers(0, len(data)))
    extra = draw(st.one_of(st.binary(min_size=1, max_size=8), st.sampled_from([*TOKENS, sep])))
    return data[:at] + extra + data[at:]


def _delete_bytes(draw: Any, data: bytes, sep: bytes) -> bytes:
    at = draw(st.integers(0, len(data)))
    return data[:at] + data[at + draw(st.integers(1, 40)) :]


def _line_index(draw: Any, lines: list[bytes]) -> int:
    # The header and the first rows matter most (they set the layout): draw them often.
    return draw(st.one_of(st.integers(0, 2), st.integers(0, len(lines) - 1))) % len(lines)


def _edit_lines(draw: Any, data: bytes, sep: bytes) -> bytes:
    lines = _lines(data)
    i, j = _line_index(draw, lines), _line_index(draw, lines)
    how = draw(st.sampled_from(["delete", "repeat", "swap", "move"]))
    if how == "delete":
        del lines[i]
    elif how == "repeat":
        lines.insert(i, lines[i])
    elif how == "swap":
        lines[i], lines[j] = lines[j], lines[i]
    else:
        lines.insert(j, lines.pop(i))
    return b"\n".join(lines)


def _replace_cell(draw: Any, data: bytes, sep: bytes) -> bytes:
    lines = _lines(data)
    i = _line_index(draw, lines)
    cells = _cells(lines[i], sep)
    j = draw(st.integers(0, len(cells) - 1))
    cells[j] = draw(cell_text)
    lines[i] = sep.join(cells)
    return b"\n".join(lines)


def _rename_header(draw: Any, data: bytes, sep: bytes) -> bytes:
    lines = _lines(data)
    cells = _cells(lines[0], sep)
    j = draw(st.integers(0, len(cells) - 1))
    cells[j] = draw(
        st.one_of(
            st.sampled_from(cells),  # a name twice
            st.sampled_from([b" " + cells[j], cells[j] + b" ", cells[j].upper(), b'"' + cells[j]]),
            cell_text,
        )
    )
    lines[0] = sep.join(cells)
    return b"\n".join(lines)


def _drop_column(draw: Any, data: bytes, sep: bytes) -> bytes:
    lines = _lines(data)
    j = draw(st.integers(0, len(_cells(lines[0], sep)) - 1))
    kept = []
    for line in lines:
        cells = _cells(line, sep)
        kept.append(sep.join(cells[:j] + cells[j + 1 :]))
    return b"\n".join(kept)


def _reorder_columns(draw: Any, data: bytes, sep: bytes) -> bytes:
    lines = _lines(data)
    width = len(_cells(lines[0], sep))
    order = draw(st.permutations(range(width)))
    out = []
    for line in lines:
        cells = _cells(line, sep)
        out.append(sep.join([cells[k] for k in order]) if len(cells) == width else line)
    return b"\n".join(out)


def _whole_file(draw: Any, data: bytes, sep: bytes) -> bytes:
    how = draw(st.sampled_from(["crlf", "bom", "empty", "header", "blank", "tail", "latin"]))
    if how == "crlf":
        return data.replace(b"\n", b"\r\n")
    if how == "bom":
        return b"\xef\xbb\xbf" + data
    if how == "empty":
        return b""
    if how == "header":
        return _lines(data)[0] + b"\n"
    if how == "blank":
        return b"\n" + data
    if how == "tail":
        return data.rstrip(b"\n")
    return data.replace(b"e", "é".encode("latin-1"))


MUTATIONS: list[Callable[[Any, bytes, bytes], bytes]] = [
    _truncate,
    _replace_bytes,
    _insert_bytes,
    _delete_bytes,
    _edit_lines,
    _replace_cell,
    _rename_header,
    _drop_column,
    _reorder_columns,
    _whole_file,
]


@st.composite
def mutated(draw: Any, data: bytes, sep: bytes = b",", max_steps: int = 3) -> bytes:
    """``data`` after 1 to ``max_steps`` mutations drawn from :data:`MUTATIONS`."""
    for mutation in draw(st.lists(st.sampled_from(MUTATIONS), min_size=1, max_size=max_steps)):
        data = mutation(draw, data, sep) if data else data
    return data


def binary_mutated(data: bytes) -> st.SearchStrategy[bytes]:
    """Byte-level mutations only (for Parquet, MCAP and SQLite files)."""
    steps = [_truncate, _replace_bytes, _insert_bytes, _delete_bytes]

    @st.composite
    def strategy(draw: Any) -> bytes:
        out = data
        for mutation in draw(st.lists(st.sampled_from(steps), min_size=1, max_size=3)):
            out = mutation(draw, out, b"")
        return out

    return strategy()


# --------------------------------------------------------------------------- the outcome
def assert_valid_log(log: Log, regular: bool = True) -> None:
    """Recount what a valid log is, without trusting the library's own checks."""
    assert isinstance(log, Log)
    t = np.asarray(log.t)
    assert t.dtype == np.float64 and t.ndim == 1 and t.size >= 2
    assert np.all(np.isfinite(t))
    steps = np.diff(t)
    assert np.all(steps > 0.0)
    median = float(np.median(steps))
    slack = 1e-6 * median + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    assert not regular or np.all(np.abs(steps - median) <= slack), "time is not regular"
    q = np.asarray(log.q)
    assert q.ndim == 2 and q.shape[0] == t.size and q.shape[1] >= 1
    for group in ("q", "qd", "tau_m", "tau_j", "tau_ext", "q_true", "qd_true", "tau_c"):
        values = getattr(log, group)
        if values is None:
            continue
        values = np.asarray(values)
        assert values.shape == q.shape and values.dtype == np.float64, group
        assert np.all(np.isfinite(values)), group
        if group in ("q", "q_true"):
            assert np.all(np.abs(values) <= ANGLE_LIMIT), group
    if log.collision_id is not None:
        labels = np.asarray(log.collision_id)
        assert labels.shape == t.shape and labels.dtype == np.int64
        assert np.all(labels >= 0)
    json.dumps(log.metadata, allow_nan=False)


def assert_clear_error(error: BaseException, path: Path | None) -> None:
    """A library error in one non-empty line that names the file."""
    assert isinstance(error, SensorlessError), f"{type(error).__name__}: {error}"
    message = str(error)
    assert message.strip(), f"empty message of {type(error).__name__}"
    assert "\n" not in message.strip(), f"more than one line: {message!r}"
    if path is not None:
        assert path.name in message, f"the message does not name {path.name}: {message!r}"


def outcome(
    run: Callable[[], list[Log] | Log], path: Path | None, regular: bool = True
) -> list[Log] | None:
    """Run an import: its logs are valid (``regular``: in time), or it raises a clear error."""
    try:
        result = run()
    except SensorlessError as error:
        assert_clear_error(error, path)
        return None
    logs = result if isinstance(result, list) else [result]
    assert logs, "an import returned no log and no error"
    for log in logs:
        assert_valid_log(log, regular)
    return logs


def write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


# --------------------------------------------------------------------------- CSV importers
FRANKA = franka_bytes()
UR_SPACE = ur_bytes(" ")
UR_COMMA = ur_bytes(",")
MAPPED = mapping_bytes()
HEADER_MAPPED = header_mapping_bytes()


def test_valid_files_import(folder: Path) -> None:
    """The unmutated files are valid: what the fuzz mutates is accepted as it is."""
    [franka] = import_franka(write(folder / "franka.csv", FRANKA))
    assert franka.groups == ["q", "qd", "tau_j", "tau_ext"] and franka.n_samples == N_ROWS
    for data in (UR_SPACE, UR_COMMA):
        [ur] = import_ur_rtde(write(folder / "rtde.csv", data), robot="ur10")
        assert ur.groups == ["q", "qd", "tau_m"] and ur.n_dof == 6
    [mapped] = import_csv(write(folder / "mapped.txt", MAPPED), MAPPING_SPEC)
    assert mapped.n_samples == N_ROWS and mapped.dt == pytest.approx(0.01)
    [named] = import_csv(write(folder / "named.csv", HEADER_MAPPED), HEADER_SPEC)
    assert named.n_samples == N_ROWS and named.dt == pytest.approx(5e-4)
    for log in (franka, ur, mapped, named):
        assert_valid_log(log)


def test_a_byte_order_mark_is_read_as_nothing(folder: Path) -> None:
    """A spreadsheet's UTF-8 byte-order mark before the header changes nothing; a missing
    file is the library's MissingFileError (a FileNotFoundError)."""
    bom = b"\xef\xbb\xbf"
    cases = [
        ("franka.csv", FRANKA, import_franka),
        ("rtde.csv", UR_SPACE, lambda path: import_ur_rtde(path, robot="ur10")),
        ("named.csv", HEADER_MAPPED, lambda path: import_csv(path, HEADER_SPEC)),
    ]
    for name, data, read in cases:
        [plain] = read(write(folder / name, data))
        [marked] = read(write(folder / f"bom-{name}", bom + data))
        assert marked.groups == plain.groups
        for group in ["t", *plain.groups]:
            np.testing.assert_array_equal(getattr(marked, group), getattr(plain, group))
        with pytest.raises(MissingFileError, match="does not exist"):
            read(folder / f"missing-{name}")
    with pytest.raises(MissingFileError, match="does not exist"):
        import_ros2(folder / "no-such-bag")


@fuzz(150)
@given(data=mutated(FRANKA))
def test_fuzz_franka(folder: Path, data: bytes) -> None:
    path = write(folder / "franka.csv", data)
    outcome(lambda: import_franka(path), path)


@fuzz(120)
@given(
    sep_data=st.one_of(
        mutated(UR_SPACE, b" ").map(lambda d: (" ", d)),
        mutated(UR_COMMA, b",").map(lambda d: (",", d)),
    )
)
def test_fuzz_ur_rtde(folder: Path, sep_data: tuple[str, bytes]) -> None:
    _, data = sep_data
    path = write(folder / "rtde.csv", data)
    outcome(lambda: import_ur_rtde(path, robot="ur10"), path)


@fuzz(120)
@given(data=mutated(MAPPED, b";"))
def test_fuzz_column_mapping_without_header(folder: Path, data: bytes) -> None:
    path = write(folder / "mapped.txt", data)
    outcome(lambda: import_csv(path, MAPPING_SPEC), path)


@fuzz(120)
@given(data=mutated(HEADER_MAPPED))
def test_fuzz_column_mapping_with_header(folder: Path, data: bytes) -> None:
    path = write(folder / "named.csv", data)
    outcome(lambda: import_csv(path, HEADER_SPEC), path)


@fuzz(60)
@given(text=mutated(yaml.safe_dump(HEADER_SPEC).encode(), b": "))
def test_fuzz_column_mapping_spec_file(folder: Path, text: bytes) -> None:
    """A mangled YAML spec is an error of the spec (it names the spec file) or a valid import."""
    spec = write(folder / "spec.yaml", text)
    path = write(folder / "named.csv", HEADER_MAPPED)
    try:
        logs = import_csv(path, spec)
    except SensorlessError as error:
        assert_clear_error(error, None)
        assert spec.name in str(error) or path.name in str(error), str(error)
        return
    for log in logs:
        assert_valid_log(log)


# --------------------------------------------------------------------------- the dispatcher
CSV_FILES = {
    "franka": (FRANKA, b","),
    "ur-rtde": (UR_SPACE, b" "),
    "csv": (MAPPED, b";"),
}
OPTIONS: dict[str, dict[str, Any]] = {
    "franka": {},
    "ur-rtde": {"robot": "ur10"},
    "csv": {"spec": MAPPING_SPEC},
}


@fuzz(80)
@given(
    format=st.sampled_from(sorted(OPTIONS)),
    kind=st.sampled_from(sorted(CSV_FILES)),
    data=st.data(),
    dt=st.one_of(st.none(), st.sampled_from([0.001, 0.002, 1e-7, 0.5])),
)
def test_fuzz_import_log_dispatch(
    folder: Path, format: str, kind: str, data: st.DataObject, dt: float | None
) -> None:
    """Any of the CSV formats, given any of the files (mutated or not), by name."""
    content, sep = CSV_FILES[kind]
    if data.draw(st.booleans()):
        content = data.draw(mutated(content, sep))
    path = write(folder / "file.csv", content)
    options = OPTIONS[format] | ({} if dt is None else {"dt": dt})
    outcome(lambda: import_log(format, [path], **options), path)


# --------------------------------------------------------------------------- the log reader
def small_log() -> Log:
    t = 0.25 + DT * np.arange(N_ROWS)
    labels = (np.arange(N_ROWS) // 20 == 1).astype(np.int64)
    return Log(
        t=t,
        q=signals(2),
        qd=0.5 * signals(2),
        tau_m=30.0 * signals(2),
        collision_id=labels,
        metadata={"robot": "planar2", "note": "fuzz"},
    )


@pytest.fixture(scope="module")
def written(folder: Path) -> dict[str, tuple[bytes, bytes]]:
    """The table and sidecar bytes of a small log in each format."""
    out = {}
    for suffix in ("csv", "parquet"):
        path = write_log(small_log(), folder / f"source.{suffix}")
        out[suffix] = (path.read_bytes(), sidecar_path(path).read_bytes())
    return out


def _read(path: Path, **checks: Any) -> Callable[[], Log]:
    return lambda: read_log(path, **checks)


@fuzz(100)
@given(data=st.data(), regular=st.booleans())
def test_fuzz_read_log_csv(
    folder: Path, written: dict[str, tuple[bytes, bytes]], data: st.DataObject, regular: bool
) -> None:
    table, sidecar = written["csv"]
    path = write(folder / "run.csv", data.draw(mutated(table)))
    write(sidecar_path(path), sidecar)
    outcome(_read(path, check_regular=regular), path, regular)


@fuzz(80)
@given(data=st.data())
def test_fuzz_read_log_parquet(
    folder: Path, written: dict[str, tuple[bytes, bytes]], data: st.DataObject
) -> None:
    table, sidecar = written["parquet"]
    path = write(folder / "run.parquet", data.draw(binary_mutated(table)))
    write(sidecar_path(path), sidecar)
    outcome(_read(path), path)


@fuzz(100)
@given(data=st.data(), suffix=st.sampled_from(["csv", "parquet"]))
def test_fuzz_read_log_sidecar(
    folder: Path, written: dict[str, tuple[bytes, bytes]], data: st.DataObject, suffix: str
) -> None:
    """A mangled sidecar: an error that names the sidecar or the table, or a valid log."""
    table, sidecar = written[suffix]
    path = write(folder / f"side.{suffix}", table)
    write(sidecar_path(path), data.draw(mutated(sidecar, b": ")))
    outcome(_read(path), path)


# --------------------------------------------------------------------------- ROS 2 bags
JOINT_NAMES = ["j1", "j2", "j3"]
STAMP0 = 1_700_000_000 * 10**9
_STORE: list[Any] = []


def typestore() -> Any:
    if not _STORE:
        from rosbags.typesys import Stores, get_typestore

        _STORE.append(get_typestore(Stores.ROS2_HUMBLE))
    return _STORE[0]


def joint_state(
    stamp: int,
    names: list[str],
    position: np.ndarray,
    velocity: np.ndarray,
    effort: np.ndarray,
    little_endian: bool = True,
) -> bytes:
    store = typestore()
    state = store.types["sensor_msgs/msg/JointState"]
    header = store.types["std_msgs/msg/Header"]
    time = store.types["builtin_interfaces/msg/Time"]
    message = state(
        header=header(stamp=time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="base"),
        name=names,
        position=np.asarray(position, dtype=np.float64),
        velocity=np.asarray(velocity, dtype=np.float64),
        effort=np.asarray(effort, dtype=np.float64),
    )
    return bytes(store.serialize_cdr(message, state.__msgtype__, little_endian=little_endian))


def write_raw_bag(path: Path, messages: list[tuple[int, bytes]], storage: str) -> None:
    """A rosbag2 folder with one JointState topic holding ``messages`` (receive ns, bytes)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = typestore()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    shutil.rmtree(path, ignore_errors=True)
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        topic = writer.add_connection(
            "/joint_states", "sensor_msgs/msg/JointState", typestore=store
        )
        for received, raw in messages:
            writer.write(topic, received, raw)


def valid_messages(n: int = 40) -> list[dict[str, Any]]:
    values = signals(3, n)
    return [
        {
            "stamp": STAMP0 + k * 10**6,
            "received": STAMP0 + k * 10**6 + 20_000,
            "names": list(JOINT_NAMES),
            "position": values[k],
            "velocity": 0.5 * values[k],
            "effort": 10.0 * values[k],
            "little_endian": True,
        }
        for k in range(n)
    ]


FLOATS = [math.nan, math.inf, -math.inf, 1e308, -1e308, 20.0, -0.0, 5e-324]


@st.composite
def message_edits(draw: Any) -> list[tuple[int, bytes]]:
    """Valid JointState messages with a few of them changed, serialised, some bytes mangled."""
    messages = valid_messages()
    for _ in range(draw(st.integers(1, 3))):
        k = draw(st.integers(0, len(messages) - 1))
        message = messages[k]
        how = draw(
            st.sampled_from(
                ["value", "stamp", "names", "length", "empty", "endian", "drop", "repeat"]
            )
        )
        if how == "value":
            field = draw(st.sampled_from(["position", "velocity", "effort"]))
            values = np.array(message[field])
            if values.size:
                values[draw(st.integers(0, 2)) % values.size] = draw(st.sampled_from(FLOATS))
            message[field] = values
        elif how == "stamp":
            message["stamp"] = draw(
                st.one_of(
                    st.sampled_from([0, STAMP0, STAMP0 - 10**9, 2**31 * 10**9 - 1]),
                    st.integers(0, 2**31 * 10**9 - 1),
                )
            )
        elif how == "names":
            message["names"] = draw(
                st.sampled_from(
                    [["j1", "j2"], ["x"], ["j3", "j2", "j1"], ["j1", "j2", "j3", "j4"], []]
                )
            )
            size = len(message["names"])
            for field in ("position", "velocity", "effort"):
                message[field] = np.resize(message[field], size)
        elif how == "length":
            field = draw(st.sampled_from(["position", "velocity", "effort"]))
            message[field] = message[field][: draw(st.integers(0, 2))]
        elif how == "empty":
            message["velocity"] = np.zeros(0)
        elif how == "endian":
            message["little_endian"] = False
        elif how == "drop":
            del messages[k]
        else:
            messages.insert(k, dict(message))
    raws = [
        [
            m["received"],
            joint_state(
                m["stamp"],
                m["names"],
                m["position"],
                m["velocity"],
                m["effort"],
                m["little_endian"],
            ),
        ]
        for m in messages
    ]
    if raws and draw(st.booleans()):
        k = draw(st.integers(0, len(raws) - 1))
        raws[k][1] = draw(binary_mutated(raws[k][1]))
    return [(received, raw) for received, raw in raws]


@fuzz(25)
@given(messages=message_edits(), storage=st.sampled_from(["mcap", "sqlite3"]))
def test_fuzz_ros2_messages(folder: Path, messages: list[tuple[int, bytes]], storage: str) -> None:
    bag = folder / "messages"
    if not messages:
        return
    write_raw_bag(bag, messages, storage)
    outcome(lambda: import_ros2(bag), bag)


@pytest.fixture(scope="module")
def bags(folder: Path) -> dict[str, dict[str, bytes]]:
    """The files of a valid bag in each storage, by name."""
    raws = [
        (
            m["received"],
            joint_state(m["stamp"], m["names"], m["position"], m["velocity"], m["effort"]),
        )
        for m in valid_messages()
    ]
    out = {}
    for storage in ("mcap", "sqlite3"):
        path = folder / f"valid-{storage}"
        write_raw_bag(path, raws, storage)
        [log] = import_ros2(path)
        assert_valid_log(log)
        out[storage] = {item.name: item.read_bytes() for item in path.iterdir()}
    return out


@fuzz(60)
@given(storage=st.sampled_from(["mcap", "sqlite3"]), data=st.data())
def test_fuzz_ros2_bag_bytes(
    folder: Path, bags: dict[str, dict[str, bytes]], storage: str, data: st.DataObject
) -> None:
    """The storage file or ``metadata.yaml`` of a bag mangled; the folder or the file imported."""
    files = bags[storage]
    bag = folder / "bytes"
    shutil.rmtree(bag, ignore_errors=True)
    bag.mkdir()
    target = data.draw(st.sampled_from(sorted(files)))
    for name, content in files.items():
        if name == target:
            if name.endswith(".yaml"):
                content = data.draw(mutated(content, b": "))
            else:
                content = data.draw(binary_mutated(content))
        (bag / name).write_bytes(content)
    storage_file = next(bag / name for name in files if not name.endswith(".yaml"))
    path = data.draw(st.sampled_from([bag, storage_file]))
    outcome(lambda: import_ros2(path), path)


# --------------------------------------------------------------------------- the CLI
runner = CliRunner()


@fuzz(25)
@given(
    format=st.sampled_from(["franka", "ur-rtde", "csv"]),
    data=st.data(),
)
def test_fuzz_cli_import(folder: Path, format: str, data: st.DataObject) -> None:
    """``sensorless import`` on a mangled file: exit 0, 2, 3 or 4; an error is one line."""
    content, sep = CSV_FILES[format]
    path = write(folder / "cli.csv", data.draw(mutated(content, sep)))
    spec = folder / "cli-spec.yaml"
    spec.write_text(yaml.safe_dump(MAPPING_SPEC), encoding="utf-8")
    args = ["import", format, str(path), "-o", str(folder / "cli-out.parquet")]
    args += {"franka": [], "ur-rtde": ["--robot", "ur10"], "csv": ["--spec", str(spec)]}[format]
    for old in folder.glob("cli-out*"):
        old.unlink()
    result = runner.invoke(app, args)
    assert result.exit_code in (0, 2, 3, 4), (result.exit_code, result.output)
    assert "Traceback" not in result.output
    if result.exit_code:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
        assert path.name in lines[0], lines[0]
    else:
        outputs = sorted(folder.glob("cli-out*.parquet"))
        assert outputs
        for output in outputs:
            assert_valid_log(read_log(output))


# --------------------------------------------------------------------------- regressions
# Inputs the fuzz found (or that the same reading of the code found next to them); each
# once raised another exception than the library's, or let a bad value through.
def franka_lines() -> list[str]:
    return FRANKA.decode().splitlines()


def test_header_names_with_spaces_are_read(folder: Path) -> None:
    """Was KeyError 'time': the header's names were stripped, the parser's were not."""
    lines = franka_lines()
    lines[0] = lines[0].replace("time,", "time ,").replace(",q1,", ", q1 ,")
    path = write(folder / "spaced.csv", ("\n".join(lines) + "\n").encode())
    [log] = import_franka(path)
    [plain] = import_franka(write(folder / "plain.csv", FRANKA))
    assert np.array_equal(log.q, plain.q) and np.array_equal(log.t, plain.t)


def test_time_beyond_the_float_range(folder: Path) -> None:
    """Was OverflowError: -1e308 then 1e308 s made an infinite time from the first row."""
    lines = franka_lines()
    lines[1] = "-1e308" + lines[1][lines[1].index(",") :]
    lines[6] = "1e308" + lines[6][lines[6].index(",") :]
    path = write(folder / "span.csv", ("\n".join(lines) + "\n").encode())
    with pytest.raises(LogFormatError, match=r"span\.csv: column 'time', row 5: is inf s from"):
        import_franka(path)


def test_huge_labels_are_refused(folder: Path) -> None:
    """Was a LogFormatError on an int64 overflow: 'row 0 holds -9.2e+18', without the file."""
    lines = franka_lines()
    lines[4] = lines[4].rsplit(",", 1)[0] + ",1e300"
    path = write(folder / "labels.csv", ("\n".join(lines) + "\n").encode())
    with pytest.raises(
        LogFormatError,
        match=r"labels\.csv: column 'label', row 3: holds 1e\+300; labels must be non-negative "
        r"integers up to 2\*\*53",
    ):
        import_franka(path)
    table = small_log().to_pandas()
    table["collision_id"] = table["collision_id"].astype(float)
    table.loc[7, "collision_id"] = 2.0**63
    table.to_csv(folder / "ids.csv", index=False)
    with pytest.raises(
        LogFormatError, match=r"ids\.csv: column 'collision_id' .* up to 2\*\*53; row 7 holds"
    ):
        read_log(folder / "ids.csv")


def test_import_log_passes_the_time_base_options(folder: Path) -> None:
    """Was InputTypeError "unknown option(s) ['dt']": the options were read from the signature."""
    path = write(folder / "dispatch.csv", FRANKA)
    [log] = import_log("franka", path, dt=0.002, gap_tolerance=0.01)
    assert log.dt == pytest.approx(0.002) and log.t[-1] <= DT * (N_ROWS - 1)
    with pytest.raises(InputTypeError, match=r"its options: .*'dt', 'gap_tolerance'\]"):
        import_log("franka", path, gains=1.0)
    result = runner.invoke(
        app, ["import", "franka", str(path), "--dt", "0.002", "-o", str(folder / "dt.parquet")]
    )
    assert result.exit_code == 0, result.output
    assert read_log(folder / "dt.parquet").dt == pytest.approx(0.002)


def test_spec_file_that_is_not_yaml(folder: Path) -> None:
    """Was yaml.ScannerError and UnicodeDecodeError out of load_csv_spec."""
    path = write(folder / "broken.yaml", b"time: {column: [\n")
    with pytest.raises(
        InputValueError, match=r"invalid CSV import spec \(.*broken\.yaml\): not a readable YAML"
    ) as error:
        load_csv_spec(path)
    assert "\n" not in str(error.value)
    write(path, b"time: \xff\n")
    with pytest.raises(InputValueError, match=r"broken\.yaml\): not a readable YAML file: 'utf-8'"):
        load_csv_spec(path)


def test_corrupt_parquet(folder: Path, written: dict[str, tuple[bytes, bytes]]) -> None:
    """Was OSError "Couldn't deserialize thrift" (pyarrow's, without errno)."""
    path = write(folder / "shifted.parquet", b"\x00" + written["parquet"][0])
    with pytest.raises(LogFormatError, match=r"cannot read .*shifted\.parquet as parquet: "):
        read_log(path)


def test_read_log_errors_name_the_file(folder: Path) -> None:
    """The table's errors name the file; a sidecar's 'columns' that is not a list was TypeError."""
    table = small_log().to_pandas()
    table.loc[3, "q_2"] = math.inf
    table.to_csv(folder / "inf.csv", index=False)
    with pytest.raises(LogFormatError, match=r"inf\.csv: column 'q_2' must be finite; row 3"):
        read_log(folder / "inf.csv")
    path = write_log(small_log(), folder / "listed.csv")
    sidecar = json.loads(sidecar_path(path).read_text(encoding="utf-8"))
    sidecar["columns"] = 3
    sidecar_path(path).write_text(json.dumps(sidecar), encoding="utf-8")
    with pytest.raises(LogFormatError, match=r"listed\.csv\.meta\.json lists columns 3, but"):
        read_log(path)
    with pytest.raises(MissingFileError, match=r"log file .*absent\.csv does not exist"):
        read_log(folder / "absent.csv")


def test_ros2_first_message_without_joints(folder: Path) -> None:
    """Was ValueError (a broadcast into zero columns): the first message named no joint."""
    messages = valid_messages(5)
    raws = [(m["received"], joint_state(m["stamp"], [], [], [], [])) for m in messages[:1]]
    raws += [
        (m["received"], joint_state(m["stamp"], m["names"], m["position"], [], []))
        for m in messages[1:]
    ]
    write_raw_bag(folder / "nameless", raws, "mcap")
    with pytest.raises(LogFormatError, match=r"field 'name', message 0: names no joint"):
        import_ros2(folder / "nameless")
    with pytest.raises(InputValueError, match=r"joints must name at least one joint"):
        import_ros2(folder / "nameless", joints=[])


def test_ros2_unreadable_metadata_and_record_lengths(
    folder: Path, bags: dict[str, dict[str, bytes]]
) -> None:
    """Were UnicodeDecodeError, a many-line YAML message and MemoryError out of rosbags."""
    bag = folder / "meta"
    shutil.rmtree(bag, ignore_errors=True)
    bag.mkdir()
    for name, content in bags["mcap"].items():
        (bag / name).write_bytes(b"\x80" + content if name == "metadata.yaml" else content)
    with pytest.raises(LogFormatError, match=r"meta: cannot be read as a ROS 2 bag: 'utf-8'"):
        import_ros2(bag)
    (bag / "metadata.yaml").write_bytes(b"{rosbag2_bagfile_information:\n  - [\n")
    with pytest.raises(LogFormatError, match=r"meta: cannot be read as a ROS 2 bag: ") as error:
        import_ros2(bag)
    assert "\n" not in str(error.value)
    content = bytearray(next(v for k, v in bags["mcap"].items() if k.endswith(".mcap")))
    content[9:17] = (2**62).to_bytes(8, "little")  # the length of the header record
    path = write(folder / "long.mcap", bytes(content))
    with pytest.raises(LogFormatError, match=r"long\.mcap: .*a record claims more bytes"):
        import_ros2(path)


def test_time_stamps_too_far_apart_for_float64(folder: Path) -> None:
    """Was ValueError (math domain error): a stray stamp made the others equal once shifted."""
    lines = franka_lines()
    lines[2] = "-17592186044416" + lines[2][lines[2].index(",") :]  # -2**44 s: ulp 4 ms
    path = write(folder / "stray.csv", ("\n".join(lines) + "\n").encode())
    with pytest.raises(
        LogFormatError, match=r"stray\.csv: the time stamps run from -17592186044416\.0 to "
    ):
        import_franka(path)


def test_integer_beyond_the_float_range(folder: Path) -> None:
    """Was OverflowError out of pandas.to_numeric: a 400-digit integer in a column."""
    lines = franka_lines()
    lines[4] = lines[4].rsplit(",", 1)[0] + "," + "1" * 400
    path = write(folder / "digits.csv", ("\n".join(lines) + "\n").encode())
    with pytest.raises(
        LogFormatError, match=r"digits\.csv: column 'label', row 3: holds 1111.*beyond the range"
    ):
        import_franka(path)


def test_gain_times_value_beyond_the_float_range(folder: Path) -> None:
    """Was a LogFormatError without the file: a current of 1e308 A times its gain is inf."""
    lines = MAPPED.decode().splitlines()
    cells = lines[7].split(";")
    cells[15] = "1e308"  # spec column 16, the first current
    lines[7] = ";".join(cells)
    path = write(folder / "gains.txt", ("\n".join(lines) + "\n").encode())
    with pytest.raises(
        LogFormatError, match=r"gains\.txt: column 16, row 7: holds 1e\+308, which times its factor"
    ):
        import_csv(path, MAPPING_SPEC)


def test_resampling_that_overflows(folder: Path) -> None:
    """Was a LogFormatError without the file: interpolating from 1e308 to -1e308 gives -inf."""
    table = pd.read_csv(io.BytesIO(FRANKA))
    table.loc[3, "time"] = 0.0031  # jitter: the segment is resampled
    table["dq0"] = np.where(np.arange(N_ROWS) % 2, 1e308, -1e308)
    path = folder / "extreme.csv"
    table.to_csv(path, index=False, float_format="%.17g")
    with pytest.raises(
        LogFormatError, match=r"extreme\.csv: qd holds values too large to resample"
    ):
        import_franka(path)


def test_ros2_record_length_beyond_any_size(
    folder: Path, bags: dict[str, dict[str, bytes]]
) -> None:
    """Was OverflowError ("cannot fit 'int' into an index-sized integer") out of rosbags."""
    content = bytearray(next(v for k, v in bags["mcap"].items() if k.endswith(".mcap")))
    content[9:17] = (2**64 - 1).to_bytes(8, "little")
    path = write(folder / "endless.mcap", bytes(content))
    with pytest.raises(LogFormatError, match=r"endless\.mcap: .*a record claims more bytes"):
        import_ros2(path)
