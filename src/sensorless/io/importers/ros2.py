"""ROS 2 bags and MCAP files of ``sensor_msgs/msg/JointState``, without a ROS installation.

The bag (a rosbag2 folder, or one ``.mcap`` or ``.db3`` file) is read with
the pure-Python package ``rosbags``. One topic of type
``sensor_msgs/msg/JointState`` is imported (the only one, or the one
named); each message is one row, named in errors by its number on the
topic (from 0):

===============  ===========  ============================================
message field    log group    note
===============  ===========  ============================================
``header.stamp`` ``t``        or the bag's receive time (``stamp="receive"``)
``position``     ``q``        [rad]
``velocity``     ``qd``       [rad/s], when the messages carry it
``effort``       ``tau_m``    [N m] (or ``tau_j``, see ``effort``); times
                              ``effort_gains`` if the driver publishes
                              motor currents
===============  ===========  ============================================

Joints are picked by name, in the order asked (by default all the joints of
the first message, in its order); messages that name none of them (another
part of the robot on the same topic) are skipped and counted.

Messages are decoded in chunks: all messages with the byte layout of the
first one (same joint names, same field lengths, little-endian CDR) are
decoded at once with numpy; any other message goes through ``rosbags``'s
own deserialiser.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._validation import FloatArray, per_joint
from ...exceptions import InputValueError, LogFormatError, MissingFileError, one_line
from ..columns import ANGLE_LIMIT, show_value
from ..log import Log
from ._pipeline import Provenance, Recording, RowBuffer, Timebase, regularize, timebase_doc

if TYPE_CHECKING:
    from typing import Unpack

    from rosbags.interfaces import Connection
    from rosbags.typesys.store import Typestore

__all__ = ["EFFORT_GROUPS", "JOINT_STATE", "STAMPS", "import_ros2"]

IMPORTER_VERSION = 1
"""Version of the conversion rules of this importer, recorded in the metadata."""

JOINT_STATE = "sensor_msgs/msg/JointState"
"""The message type read."""

STAMPS: tuple[str, ...] = ("header", "receive")
"""Time of a message: its ``header.stamp``, or the time the bag received it."""

EFFORT_GROUPS: tuple[str, ...] = ("tau_m", "tau_j")
"""Log groups the ``effort`` field can fill."""

CHUNK_MESSAGES = 1 << 14
"""Messages decoded at once."""

_FIELDS = ("position", "velocity", "effort")
_CDR_LE = b"\x00\x01"
_NS = 1_000_000_000


@dataclass(frozen=True)
class _Layout:
    """Byte layout of one JointState message in little-endian CDR."""

    names: tuple[str, ...]
    fields: dict[str, tuple[int, int]]  # field -> (offset in the message, count)
    length: int
    # Runs [start, stop) of the bytes that are neither the stamp nor a value (encapsulation,
    # frame, names, counts), and the first message's bytes: equal runs, equal layout.
    runs: tuple[tuple[int, int], ...]
    reference: NDArray[np.uint8]


def _align(offset: int, size: int) -> int:
    return (offset + size - 1) // size * size


def _layout(raw: bytes) -> _Layout | None:
    """Walk a JointState message; None if it is not little-endian CDR or is truncated."""
    if raw[:2] != _CDR_LE:
        return None
    data = memoryview(raw)[4:]
    try:
        pos = 8  # header.stamp: int32 sec, uint32 nanosec
        (size,) = struct.unpack_from("<I", data, pos)
        pos = _align(pos + 4 + size, 4)  # header.frame_id
        (count,) = struct.unpack_from("<I", data, pos)
        pos += 4
        names = []
        for _ in range(count):
            pos = _align(pos, 4)
            (size,) = struct.unpack_from("<I", data, pos)
            names.append(bytes(data[pos + 4 : pos + 3 + size]).decode("utf-8"))
            pos += 4 + size
        fields = {}
        for name in _FIELDS:
            pos = _align(pos, 4)
            (count,) = struct.unpack_from("<I", data, pos)
            pos += 4
            if count:
                pos = _align(pos, 8)
            fields[name] = (4 + pos, count)
            pos += 8 * count
    except (struct.error, UnicodeDecodeError):
        return None
    if 4 + pos != len(raw):
        return None
    values = np.zeros(len(raw), dtype=bool)
    values[4:12] = True
    for offset, count in fields.values():
        values[offset : offset + 8 * count] = True
    structure = np.flatnonzero(~values)
    breaks = np.flatnonzero(np.diff(structure) != 1)
    starts = [int(structure[0]), *(structure[breaks + 1]).tolist()]
    stops = [*(structure[breaks] + 1).tolist(), int(structure[-1]) + 1]
    runs = tuple(zip(starts, stops, strict=True))
    return _Layout(tuple(names), fields, len(raw), runs, np.frombuffer(raw, dtype=np.uint8))


class _Decoder:
    """Decode JointState messages of one topic into the chosen joints' values."""

    def __init__(
        self,
        source: Path,
        topic: str,
        typestore: Typestore,
        first: bytes,
        joints: Sequence[str] | None,
        stamp: str,
    ) -> None:
        self.source, self.topic, self.typestore, self.stamp = source, topic, typestore, stamp
        message = self._deserialize(first, 0)
        names = list(message.name)
        self.joints = list(names if joints is None else joints)
        if not self.joints:
            if joints is not None:
                raise InputValueError("joints must name at least one joint, or be None for all")
            raise LogFormatError(
                f"{source}: topic {topic!r}, field 'name', message 0: names no joint; the first "
                f"message sets the joints of the log"
            )
        missing = [joint for joint in self.joints if joint not in names]
        if missing:
            raise InputValueError(
                f"{source}: topic {topic!r} has no joint(s) {missing} in its first message; "
                f"its joints are {names}"
            )
        self.fields = [
            name for name in _FIELDS if name == "position" or len(getattr(message, name)) > 0
        ]
        for name in self.fields:
            self._check_count(message, name, names, 0)
        layout = _layout(first)
        self.layout = (
            layout if layout is not None and self._agrees(layout, first, message) else None
        )
        columns = [names.index(joint) for joint in self.joints]
        # All joints in their own order: a slice, so that decoding copies no column.
        self.columns: list[int] | slice = (
            slice(None) if columns == list(range(len(names))) else columns
        )

    def row_buffer(self, capacity: int) -> RowBuffer:
        """A buffer for ``capacity`` decoded rows: message number, stamp [ns], the fields."""
        widths = {"row": 0, "stamp": 0} | {name: len(self.joints) for name in self.fields}
        return RowBuffer(capacity, widths, {"row": np.int64, "stamp": np.int64})

    def _deserialize(self, raw: bytes, row: int) -> Any:
        from rosbags.serde import SerdeError

        try:
            return self.typestore.deserialize_cdr(raw, JOINT_STATE)
        except (SerdeError, ValueError, IndexError, struct.error) as exc:
            raise LogFormatError(
                f"{self.source}: topic {self.topic!r}, message {row}: not a valid {JOINT_STATE} "
                f"({type(exc).__name__}: {one_line(exc)})"
            ) from None

    def _check_count(self, message: Any, field: str, names: list[str], row: int) -> None:
        count = len(getattr(message, field))
        if count != len(names):
            raise LogFormatError(
                f"{self.source}: topic {self.topic!r}, field {field!r}, message {row}: holds "
                f"{count} values for {len(names)} joint names {names}"
            )

    def _agrees(self, layout: _Layout, raw: bytes, message: Any) -> bool:
        """The byte layout decodes the first message as rosbags does (a cross-check)."""
        buffer = np.frombuffer(raw, dtype=np.uint8)[None, :]
        decoded, _ = self._fast(layout, buffer)
        return all(
            np.array_equal(decoded[name][0], np.asarray(getattr(message, name), dtype=float))
            for name in self.fields
        )

    def _fast(
        self, layout: _Layout, buffer: NDArray[np.uint8]
    ) -> tuple[dict[str, FloatArray], NDArray[np.int64]]:
        """Decode messages of the layout ``layout``, one per row of ``buffer``."""
        out = {}
        for name in self.fields:
            offset, count = layout.fields[name]
            out[name] = buffer[:, offset : offset + 8 * count].copy().view("<f8")
        sec = buffer[:, 4:8].copy().view("<i4")[:, 0].astype(np.int64)
        nanosec = buffer[:, 8:12].copy().view("<u4")[:, 0].astype(np.int64)
        return out, sec * _NS + nanosec

    def _matching(self, raws: Sequence[bytes]) -> tuple[NDArray[np.intp], NDArray[np.uint8]]:
        """Indices of the messages laid out as the first one, and their bytes, one per row."""
        layout = self.layout
        if layout is None:
            return np.zeros(0, dtype=np.intp), np.zeros((0, 0), dtype=np.uint8)
        lengths = np.fromiter(map(len, raws), dtype=np.int64, count=len(raws))
        same = np.flatnonzero(lengths == layout.length)
        chosen = raws if same.size == len(raws) else [raws[i] for i in same.tolist()]
        buffer = np.frombuffer(b"".join(chosen), dtype=np.uint8).reshape(same.size, layout.length)
        match = np.ones(same.size, dtype=bool)
        for start, stop in layout.runs:
            match &= (buffer[:, start:stop] == layout.reference[start:stop]).all(axis=1)
        if match.all():
            return same, buffer
        return same[match], buffer[match]

    def decode(
        self, raws: Sequence[bytes], received: Sequence[int], first_row: int, into: RowBuffer
    ) -> int:
        """Decode one chunk of messages, append the kept rows to ``into``; return the skipped.

        ``into`` has the columns ``row`` (message number), ``stamp`` [ns] and one
        per field of :attr:`fields`.
        """
        n = len(raws)
        matched, buffer = self._matching(raws)
        layout = self.layout
        if layout is not None and matched.size == n:
            # The common case, every message laid out as the first: no per-message work.
            decoded, stamps = self._fast(layout, buffer)
            rows = into.take(n)
            for name in self.fields:
                rows[name][:] = decoded[name][:, self.columns]
            rows["row"][:] = np.arange(first_row, first_row + n)
            rows["stamp"][:] = np.asarray(received) if self.stamp == "receive" else stamps
            return 0
        fast = np.zeros(n, dtype=bool)
        values = {name: np.empty((n, len(self.joints))) for name in self.fields}
        stamps = np.empty(n, dtype=np.int64)
        if layout is not None and matched.size:
            fast[matched] = True
            decoded, stamps[matched] = self._fast(layout, buffer)
            for name in self.fields:
                values[name][matched] = decoded[name][:, self.columns]
        keep = np.ones(n, dtype=bool)
        for index in np.flatnonzero(~fast).tolist():
            row = first_row + index
            message = self._deserialize(raws[index], row)
            names = list(message.name)
            if not any(joint in names for joint in self.joints):
                keep[index] = False
                continue
            missing = [joint for joint in self.joints if joint not in names]
            if missing:
                raise LogFormatError(
                    f"{self.source}: topic {self.topic!r}, field 'name', message {row}: has no "
                    f"joint(s) {missing}; its joints are {names}"
                )
            columns = [names.index(joint) for joint in self.joints]
            for name in self.fields:
                self._check_count(message, name, names, row)
                values[name][index] = np.asarray(getattr(message, name), dtype=float)[columns]
            header = message.header.stamp
            stamps[index] = header.sec * _NS + header.nanosec
        if self.stamp == "receive":
            stamps = np.asarray(received, dtype=np.int64)
        out: dict[str, NDArray[Any]] = {name: values[name][keep] for name in self.fields}
        out |= {"row": first_row + np.flatnonzero(keep), "stamp": stamps[keep]}
        into.extend(out)
        return int(n - np.count_nonzero(keep))


def _check_values(
    source: Path, topic: str, field: str, joints: list[str], values: FloatArray, rows: NDArray[Any]
) -> None:
    bad = ~np.isfinite(values)
    if field == "position":
        bad |= np.abs(values) > ANGLE_LIMIT
    if bad.any():
        row, joint = (int(i) for i in np.argwhere(bad)[0])
        raise LogFormatError(
            f"{source}: topic {topic!r}, field '{field}' of joint {joints[joint]!r}, message "
            f"{int(rows[row])}: holds {show_value(values[row, joint])}; values must be finite"
            + (" and positions within ±4π rad" if field == "position" else "")
        )


def _choose_topic(source: Path, connections: list[Connection], topic: str | None) -> str:
    topics = sorted({c.topic for c in connections if c.msgtype == JOINT_STATE})
    if topic is None:
        if len(topics) == 1:
            return topics[0]
        if not topics:
            found = sorted({f"{c.topic} ({c.msgtype})" for c in connections})
            raise LogFormatError(f"{source}: no topic of type {JOINT_STATE}; its topics: {found}")
        raise InputValueError(f"{source}: several {JOINT_STATE} topics {topics}; pass topic=")
    if topic not in topics:
        raise InputValueError(
            f"{source}: no {JOINT_STATE} topic {topic!r}; its {JOINT_STATE} topics: {topics}"
        )
    return topic


@dataclass
class _Messages:
    """What :func:`_read` found: the topic, its decoder, the decoded rows, the skipped."""

    topic: str
    decoder: _Decoder
    rows: dict[str, NDArray[Any]]
    skipped: int


def _read(source: Path, topic: str | None, joints: Sequence[str] | None, stamp: str) -> _Messages:
    from rosbags.rosbag2 import Reader, ReaderError
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_HUMBLE)
    try:
        with Reader(source) as reader:
            name = _choose_topic(source, list(reader.connections), topic)
            wanted = [c for c in reader.connections if c.topic == name]
            messages = reader.messages(connections=wanted)
            first = next(messages, None)
            if first is None:
                raise LogFormatError(f"{source}: topic {name!r} holds no message")
            decoder = _Decoder(source, name, typestore, first[2], joints, stamp)
            buffer = decoder.row_buffer(sum(c.msgcount for c in wanted))
            skipped = done = 0
            # Only bytes and ints are kept between chunks: they are not tracked by the
            # garbage collector, which would otherwise walk every retained message tuple.
            raws, received = [first[2]], [first[1]]
            for _, timestamp, raw in messages:
                raws.append(raw)
                received.append(timestamp)
                if len(raws) == CHUNK_MESSAGES:
                    skipped += decoder.decode(raws, received, done, buffer)
                    done += len(raws)
                    raws, received = [], []
            if raws:
                skipped += decoder.decode(raws, received, done, buffer)
    except (ReaderError, UnicodeDecodeError) as exc:
        # A metadata.yaml that is not UTF-8 is not wrapped by rosbags.
        raise LogFormatError(f"{source}: cannot be read as a ROS 2 bag: {one_line(exc)}") from None
    except (MemoryError, OverflowError):
        # rosbags allocates the length a record header claims before reading it (beyond
        # 2**63 bytes that is an OverflowError).
        raise LogFormatError(
            f"{source}: cannot be read as a ROS 2 bag: a record claims more bytes than memory "
            "holds (a corrupt length field, or a bag too large for this machine)"
        ) from None
    return _Messages(name, decoder, buffer.arrays(), skipped)


@timebase_doc
def import_ros2(
    path: str | Path,
    *,
    topic: str | None = None,
    joints: Sequence[str] | None = None,
    stamp: str = "header",
    effort: str | None = "tau_m",
    effort_gains: ArrayLike | None = None,
    robot: str | None = None,
    **timebase: Unpack[Timebase],
) -> list[Log]:
    """Import the ``sensor_msgs/msg/JointState`` messages of a ROS 2 bag or MCAP file.

    Parameters
    ----------
    path : str or Path
        A rosbag2 folder, or one ``.mcap`` or ``.db3`` file.
    topic : str, optional
        The JointState topic; needed only if the bag has several.
    joints : sequence of str, optional
        Joint names to import, in the order of the log's columns; by
        default every joint of the first message, in its order.
    stamp : {"header", "receive"}
        Time of each row: the message's ``header.stamp`` or the bag's receive time.
    effort : {"tau_m", "tau_j"} or None
        Log group filled by the ``effort`` field (motor torques or
        joint-torque sensors), or None to leave it out.
    effort_gains : float or array-like of shape (n_dof,), optional
        Factor [N m per effort unit] applied to ``effort``, e.g. current-to-torque
        gains if the driver publishes motor currents [A] (default 1: N m).
    robot : str, optional
        Robot name, stored as ``metadata["robot"]``.
    {timebase}

    Raises
    ------
    LogFormatError
        The bag cannot be read, has no JointState topic, or a message is
        malformed or holds a bad value (the message names the file, the
        topic, the field and joint, and the message number).
    InputValueError
        An invalid option, an unknown topic or joint.
    FileNotFoundError
        ``path`` does not exist.
    """
    source = Path(path)
    if stamp not in STAMPS:
        raise InputValueError(f"stamp must be one of {list(STAMPS)}; got {stamp!r}")
    if effort is not None and effort not in EFFORT_GROUPS:
        raise InputValueError(
            f"effort must be one of {list(EFFORT_GROUPS)} or None; got {effort!r}"
        )
    if not source.exists():
        raise MissingFileError(f"{source} does not exist")
    messages = _read(source, topic, joints, stamp)
    name, decoder = messages.topic, messages.decoder
    rows, stamps = messages.rows.pop("row"), messages.rows.pop("stamp")
    if stamp == "header" and not np.any(stamps):
        raise LogFormatError(
            f"{source}: topic {name!r}: every header.stamp is zero; pass stamp='receive' to "
            "use the bag's receive times"
        )
    targets = {"position": "q", "velocity": "qd", "effort": effort}
    groups: dict[str, FloatArray] = {}
    conversions: dict[str, Any] = {}
    for field in decoder.fields:
        values = messages.rows.pop(field)
        _check_values(source, name, field, decoder.joints, values, rows)
        group = targets[field]
        if group is None:
            continue
        if field == "effort" and effort_gains is not None:
            gains = per_joint(effort_gains, len(decoder.joints), "effort_gains", "N m", "positive")
            with np.errstate(over="ignore"):  # checked again below
                values *= gains
            _check_values(source, name, "effort (times effort_gains)", decoder.joints, values, rows)
            conversions[group] = {"effort_gains": gains.tolist()}
        groups[group] = values
    units = {"t": "s", "q": "rad", "qd": "rad/s"}
    for group in EFFORT_GROUPS:
        units[group] = "effort unit (× effort_gains)" if group in conversions else "N m"
    fields = {group: field for field, group in targets.items() if group in groups}
    columns: dict[str, Any] = {
        "t": "header.stamp" if stamp == "header" else "receive time",
        "topic": name,
        "joints": decoder.joints,
    }
    columns |= {group: f"{field}[joints]" for group, field in fields.items()}
    provenance = Provenance(
        format="ros2",
        source=source.resolve(),
        importer=__name__,
        importer_version=IMPORTER_VERSION,
        source_units={group: units[group] for group in ["t", *groups]},
        columns=columns,
        conversions=conversions,
        robot=robot,
        report={"messages_skipped": messages.skipped},
    )
    # Integer nanoseconds from the first message: exact, where seconds since 1970 in
    # float64 would keep only a quarter of a microsecond.
    origin = int(stamps[0])
    recording = Recording(
        t=(stamps - origin).astype(np.float64) * 1e-9,
        groups=groups,
        time_origin=origin // _NS + (origin % _NS) * 1e-9,
    )
    return regularize(recording, provenance, **timebase)
