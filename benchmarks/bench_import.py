"""Import cost of long recordings: a Franka-style CSV and a ROS 2 MCAP bag.

Writes into a temporary folder one hour (``--seconds``) of a 7-joint arm
sampled at 1 kHz, twice:

* a CSV of libfranka ``RobotState`` fields (``time`` [s], ``q0..6``,
  ``dq0..6``, ``tau_J0..6``, ``tau_J_d0..6``, ``tau_ext0..6``, ``label``),
  values with 6 decimals as loggers print them;
* a rosbag2 in MCAP storage of ``sensor_msgs/msg/JointState`` (position,
  velocity, effort of 7 named joints), the same samples.

Then imports each in a fresh Python process (``import_franka``,
``import_ros2``) and prints the file size, the wall and CPU time of the
import call (the CPU time stays meaningful on a shared machine) and the peak
resident memory of that process (``VmHWM``, Linux) beside its
resident memory after ``import sensorless`` (``VmRSS``). The goal of issue
11: at most 20 s and 2 GB each.
Run with ``.venv/bin/python benchmarks/bench_import.py``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv

RATE = 1000.0
N_DOF = 7
CHUNK = 360_000
JOINTS = [f"panda_joint{j}" for j in range(1, N_DOF + 1)]
EPOCH_NS = 1_700_000_000 * 10**9

CHILD = """
import json, sys, time
import sensorless.io as sio
def status(key):
    with open("/proc/self/status") as handle:
        return next(int(line.split()[1]) for line in handle if line.startswith(key + ":"))
base = status("VmRSS")
start, cpu = time.perf_counter(), time.process_time()
logs = getattr(sio, sys.argv[1])(sys.argv[2])
wall, cpu = time.perf_counter() - start, time.process_time() - cpu
peak = status("VmHWM")
print(json.dumps({"wall": wall, "cpu": cpu, "peak_kib": peak, "base_kib": base,
                  "segments": len(logs), "samples": sum(log.n_samples for log in logs),
                  "groups": logs[0].groups, "resampled": "resampled" in logs[0].metadata}))
"""


def chunks(n_samples: int) -> Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]:
    """Sample numbers and signals [rad, rad/s, N m] of a smooth 7-joint motion, by chunk."""
    rng = np.random.default_rng(0)
    frequency = 0.05 * np.arange(1, N_DOF + 1)  # Hz
    for first in range(0, n_samples, CHUNK):
        k = np.arange(first, min(first + CHUNK, n_samples))
        phase = 2 * np.pi * np.outer(k / RATE, frequency)
        noise = rng.normal(0.0, 1e-3, (k.size, N_DOF))
        yield (
            k,
            {
                "q": np.sin(phase) + noise,
                "dq": 2 * np.pi * frequency * np.cos(phase),
                "tau_J": 10 * np.sin(phase + 0.3) + noise,
                "tau_J_d": 9 * np.sin(phase + 0.3),
                "tau_ext": noise,
            },
        )


def write_franka_csv(path: Path, n_samples: int) -> None:
    names = ["time"] + [
        f"{p}{j}" for p in ("q", "dq", "tau_J", "tau_J_d", "tau_ext") for j in range(N_DOF)
    ]
    names.append("label")
    options = pa_csv.WriteOptions(quoting_style="none")
    schema = pa.schema([(name, pa.float64()) for name in names[:-1]] + [("label", pa.int64())])
    with pa_csv.CSVWriter(path, schema, write_options=options) as writer:
        for k, signals in chunks(n_samples):
            columns: list[np.ndarray] = [np.round(k / RATE, 6)]
            for values in signals.values():
                columns.extend(np.round(values, 6).T)
            columns.append(np.zeros(k.size, dtype=np.int64))
            writer.write_table(pa.table(columns, schema=schema))


def write_mcap_bag(path: Path, n_samples: int) -> None:
    """A rosbag2 in MCAP storage, messages built from one serialised template."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    state = store.types["sensor_msgs/msg/JointState"]
    header = store.types["std_msgs/msg/Header"]
    stamp = store.types["builtin_interfaces/msg/Time"]
    marks = {name: np.arange(N_DOF) + offset for offset, name in enumerate(["p", "v", "e"], 1)}
    template = bytes(
        store.serialize_cdr(
            state(
                header=header(stamp=stamp(sec=0, nanosec=0), frame_id="base"),
                name=JOINTS,
                position=marks["p"] * 1.5,
                velocity=marks["v"] * 2.5,
                effort=marks["e"] * 3.5,
            ),
            state.__msgtype__,
        )
    )
    offsets = {
        field: template.find((values * scale).astype("<f8").tobytes())
        for field, values, scale in [
            ("q", marks["p"], 1.5),
            ("dq", marks["v"], 2.5),
            ("tau_J", marks["e"], 3.5),
        ]
    }
    base = np.frombuffer(template, dtype=np.uint8)
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        topic = writer.add_connection("/joint_states", state.__msgtype__, typestore=store)
        for k, signals in chunks(n_samples):
            ns = EPOCH_NS + k * 1_000_000
            buffer = np.tile(base, (k.size, 1))
            buffer[:, 4:8] = (ns // 10**9).astype("<i4").view(np.uint8).reshape(-1, 4)
            buffer[:, 8:12] = (ns % 10**9).astype("<u4").view(np.uint8).reshape(-1, 4)
            for field, offset in offsets.items():
                data = np.ascontiguousarray(signals[field], dtype="<f8").view(np.uint8)
                buffer[:, offset : offset + 8 * N_DOF] = data
            for row, received in zip(buffer, ns.tolist(), strict=True):
                writer.write(topic, received, row.tobytes())


def measure(function: str, path: Path) -> dict[str, object]:
    result = subprocess.run(
        [sys.executable, "-c", CHILD, function, str(path)], capture_output=True, text=True
    )
    if result.returncode:
        raise RuntimeError(f"{function}({path}) failed:\n{result.stderr}")
    figures: dict[str, object] = json.loads(result.stdout)
    return figures


def size(path: Path) -> int:
    return sum(p.stat().st_size for p in ([path] if path.is_file() else path.rglob("*")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3600.0, help="recording length [s]")
    args = parser.parse_args()
    n_samples = int(args.seconds * RATE)
    with tempfile.TemporaryDirectory() as folder:
        csv_path, bag_path = Path(folder) / "franka.csv", Path(folder) / "bag"
        start = time.perf_counter()
        write_franka_csv(csv_path, n_samples)
        csv_written = time.perf_counter() - start
        start = time.perf_counter()
        write_mcap_bag(bag_path, n_samples)
        bag_written = time.perf_counter() - start
        print(f"{args.seconds:g} s at {RATE:g} Hz, {N_DOF} joints: {n_samples} samples")
        print(f"(written in {csv_written:.0f} s and {bag_written:.0f} s)")
        print(f"{'file':<20}{'size MB':>9}{'wall s':>8}{'CPU s':>7}{'peak MB':>9}{'base MB':>9}")
        for label, function, path in [
            ("Franka CSV", "import_franka", csv_path),
            ("ROS 2 bag (MCAP)", "import_ros2", bag_path),
        ]:
            figures = measure(function, path)
            if figures["samples"] != n_samples or figures["segments"] != 1:
                raise RuntimeError(f"{label}: imported {figures}, expected one log of {n_samples}")
            print(
                f"{label:<20}{size(path) / 1e6:>9.0f}{figures['wall']:>8.1f}{figures['cpu']:>7.1f}"
                f"{figures['peak_kib'] / 1024:>9.0f}{figures['base_kib'] / 1024:>9.0f}"
            )


if __name__ == "__main__":
    main()
