"""C++ reference figures of one momentum-observer step, beside the project's numba path (issue 22).

For the 7-dof Panda and the 6-dof UR10 (URDFs of ``example-robot-data``, cut
at the flange as :func:`sensorless.robots.load` builds them), this script

1. writes smooth samples (q [rad], q̇ [rad/s], τ [N m], time along the rows,
   τ = inverse dynamics minus a short external-torque pulse) and the arm's URDF
   to ``benchmarks/cpp/build/``;
2. compiles ``benchmarks/cpp/observer_bench.cpp`` with g++ ``-O3`` against the
   Pinocchio headers and libraries of the ``pin`` wheel when the binary is
   missing or older than its source (or the command changed), and runs it:
   per sample, the median of ``--repeat`` passes over all samples, the
   variants taking turns, of (a) the three standard calls ``crba`` +
   ``computeCoriolisMatrix`` + ``computeGeneralizedGravity``, (b) those + the
   update of :class:`~sensorless.observers.MomentumObserver`, (c) ext_observer's
   MomentumObserver on the same calls, when its sources are given, (d) a
   dedicated O(n) recursion + the update;
3. checks that the C++ residuals of (b) and (d) equal the Python
   ``MomentumObserver`` residual (numpy and numba backends) to 1e-9 N m, and
   exits 1 if not;
4. times, in the same process and on the same motion (torques without the
   pulse: free motion, no detection), the three Pinocchio calls in a Python
   loop, the numpy stream's ``CollisionMonitor.step`` and its batch
   ``CollisionMonitor.run`` over arrays (``backend="numpy"``, what runs without
   numba), ``MomentumTerms.terms_one`` (numba) in a Python loop, the fused
   stream step ``CollisionMonitor.step`` (numba, time-variant threshold), the
   same step called from a numba-compiled loop
   (``CollisionMonitor.compiled_step``),
   ``MomentumTerms.terms`` (numba) over the whole array and the fused batch
   ``CollisionMonitor.run`` (numba; by phases, and every sample through the
   stream step's kernel), and prints one table.

Every figure is a loop over all samples divided by their number [µs per
sample], one thread: the median over ``--rounds`` rounds, each of which runs
the C++ binary and then the Python loops, of the median of ``--repeat`` loops;
the ratios of the fused step (from Python and from a compiled loop) to
ext_observer's, and of the numpy step to the three calls in a Python loop,
are taken per round, then their median. Without g++, the headers or the
libraries, it says what is missing and exits 0. The headers the wheels leave
out are two header-only wheels: ``pip install cmeel-eigen cmeel-urdfdom-headers``.

ext_observer (S. Mikhel, MIT licence) is not part of this repository: pass a
checkout of it, or a git directory of it, with ``--ext-observer PATH`` (or the
environment variable ``EXT_OBSERVER``); its ``lib/`` is exported to
``benchmarks/cpp/build/ext_observer`` once and used from there on.

    .venv/bin/python benchmarks/bench_cpp.py [--samples 20000] [--repeat 3] [--rounds 5]
        [--ext-observer PATH]
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tarfile
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np
import pinocchio as pin

import sensorless as sl
from sensorless.io import Log
from sensorless.monitor import CollisionMonitor, ObserverSettings, tune
from sensorless.observers import MomentumObserver
from sensorless.robots.builders import _prune_urdf
from sensorless.robots.builtin import panda_urdf_path, ur_urdf_path
from sensorless.robots.recursion import MomentumTerms, numba_available
from sensorless.trajectories import RandomPointToPoint

if TYPE_CHECKING:
    from sensorless.monitor._fused import FusedStream

HERE = Path(__file__).resolve().parent / "cpp"
SOURCE = HERE / "observer_bench.cpp"
BUILD = HERE / "build"
BINARY = BUILD / "observer_bench"
DT = 1e-3  # sample period [s]
GAIN = 50.0  # observer gain K_I [1/s], as in issue 22
TOLERANCE = 1e-9  # C++ residual = Python residual [N m]
# Robot name -> (URDF path, flange link), as sensorless.robots builds them.
ROBOTS: dict[str, tuple[Callable[[], Path], str]] = {
    "panda": (panda_urdf_path, "panda_link8"),
    "ur10": (lambda: ur_urdf_path("ur10"), "tool0"),
}
# Defines of the wheel's CMake targets pinocchio::pinocchio_default and
# pinocchio::pinocchio_parsers (lib/cmake/pinocchio/pinocchioTargets.cmake).
DEFINES = [
    "PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION",
    "PINOCCHIO_WITH_URDFDOM",
    "PINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3",
    "PINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0",
    "PINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0",
    "BOOST_MPL_LIMIT_LIST_SIZE=30",
    "BOOST_MPL_LIMIT_VECTOR_SIZE=30",
    "BOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
    "BOOST_FUSION_INVOKE_MAX_ARITY=12",
]
UPDATE = "C++ (b) standard calls + observer update"
EXT = "C++ (c) ext_observer MomentumObserver on the standard calls"
STEP = "numba: CollisionMonitor.step (fused stream step)"
LOOP = "numba: the same step in a compiled loop (compiled_step)"
PINOCCHIO = "Python: the three Pinocchio calls, loop"
NUMPY_STEP = "numpy: CollisionMonitor.step (numpy stream)"
# the per-round ratios printed under the table: a row over its reference row
RATIOS = {STEP: EXT, LOOP: EXT, NUMPY_STEP: PINOCCHIO}


# ---------------------------------------------------------------- build
def cmeel_prefix() -> Path | None:
    """The ``cmeel.prefix`` folder of the installed ``pin`` wheel, if any."""
    spec = importlib.util.find_spec("pinocchio")
    origin = Path(spec.origin) if spec is not None and spec.origin else None
    while origin is not None and origin != origin.parent:
        if origin.name == "cmeel.prefix":
            return origin
        origin = origin.parent
    return None


def include_dir(prefix: Path, relative: str, system: str) -> Path | None:
    """The folder under which ``relative`` exists: the wheel's first, then the system's."""
    for base in (prefix / "include" / Path(relative).parts[0], Path(system)):
        if (base / Path(*Path(relative).parts[1:])).exists():
            return base
    return None


def ext_observer_lib(given: str | None) -> Path | None:
    """ext_observer's ``lib/`` folder: from ``given`` (checkout or git dir) or the build cache."""
    cached = BUILD / "ext_observer" / "lib"
    if given:
        source = Path(given)
        if (source / "lib" / "momentum_observer.h").is_file():
            return source / "lib"
        git = shutil.which("git")
        if git is None:
            print(f"ext_observer: {source} is not a checkout and git is missing: (c) skipped")
            return None
        archive = subprocess.run(
            [git, f"--git-dir={source}", "archive", "HEAD", "lib"], capture_output=True
        )
        if archive.returncode != 0:
            print(f"ext_observer: {source} is neither a checkout nor a git directory: (c) skipped")
            return None
        shutil.rmtree(cached.parent, ignore_errors=True)
        with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
            tar.extractall(cached.parent, filter="data")
    return cached if (cached / "momentum_observer.h").is_file() else None


def compile_command(compiler: str, prefix: Path, ext_lib: Path | None) -> list[str] | str:
    """The g++ command, or why it cannot be built."""
    eigen = include_dir(prefix, "eigen3/Eigen/Core", "/usr/include/eigen3")
    urdf = include_dir(prefix, "urdfdom_headers/urdf_model/model.h", "/usr/include")
    missing = [
        what
        for what, found in (
            (
                "Pinocchio headers (pin wheel)",
                (prefix / "include/pinocchio/multibody.hpp").exists(),
            ),
            ("Eigen headers (pip install cmeel-eigen)", eigen is not None),
            ("urdfdom headers (pip install cmeel-urdfdom-headers)", urdf is not None),
            ("libpinocchio_default.so", (prefix / "lib/libpinocchio_default.so").exists()),
            ("libpinocchio_parsers.so", (prefix / "lib/libpinocchio_parsers.so").exists()),
        )
        if not found
    ]
    if missing or eigen is None or urdf is None:
        return "missing: " + "; ".join(missing)
    lib = prefix / "lib"
    command = [compiler, "-std=c++17", "-O3", "-DNDEBUG", *(f"-D{d}" for d in DEFINES)]
    command += [f"-I{prefix / 'include'}", f"-I{eigen}", f"-I{urdf}"]
    if ext_lib is not None:
        command += ["-DWITH_EXT_OBSERVER", f"-I{ext_lib}"]
    command += [str(SOURCE), "-o", str(BINARY), f"-L{lib}", f"-Wl,-rpath,{lib}"]
    return [*command, "-lpinocchio_parsers", "-lpinocchio_default"]


def build(command: list[str]) -> float | None:
    """Compile when needed; the compile's wall time [s], or None when the binary was up to date."""
    stamp = BUILD / "observer_bench.cmd"
    line = shlex.join(command)
    if (
        BINARY.exists()
        and BINARY.stat().st_mtime >= SOURCE.stat().st_mtime
        and stamp.exists()
        and stamp.read_text() == line
    ):
        return None
    BUILD.mkdir(parents=True, exist_ok=True)
    print(f"compiling: {line}", flush=True)
    start = time.perf_counter()
    subprocess.run(command, check=True)
    elapsed = time.perf_counter() - start
    stamp.write_text(line)
    return elapsed


# ---------------------------------------------------------------- samples
def pruned_urdf(path: Path, tip: str) -> str:
    """The URDF text of ``tip`` and its ancestors only (the arm cut at the flange, as the
    library's builders cut it)."""
    root = ET.parse(path).getroot()
    _prune_urdf(root, tip)
    return ET.tostring(root, encoding="unicode")


def motion(
    robot: sl.robots.RobotModel, n_samples: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """t (n_samples,), and q, q̇, inverse-dynamics τ (n_samples, n_dof) of random smooth moves."""
    lower, upper = robot.position_limits
    centre, half = (lower + upper) / 2, np.minimum(0.4 * (upper - lower), 1.2)
    trajectory = RandomPointToPoint(
        robot.n_dof,
        (n_samples - 1) * DT,
        centre - half,
        centre + half,
        max_velocity=0.5 * robot.velocity_limits,
        seed=seed,
        segment_time=(1.0, 2.5),
    )
    t, q, qd, qdd = trajectory.sample(DT)
    return t, q, qd, robot.inverse_dynamics(q, qd, qdd)


def contact_pulse(t: np.ndarray, n_dof: int) -> np.ndarray:
    """External torque τ_c (n_samples, n_dof) [N m]: a 0.2 s half-sine of 5 N m, joints 2 and 4."""
    start = t[int(0.6 * (t.shape[0] - 1))]
    phase = (t - start) / 0.2
    shape = np.where((phase > 0) & (phase < 1), np.sin(np.pi * phase), 0.0)
    tau_c = np.zeros((t.shape[0], n_dof))
    tau_c[:, [1, 3]] = 5.0 * shape[:, None]
    return tau_c


# ---------------------------------------------------------------- timings
def median_us(run: Callable[[], object], n_samples: int, repeat: int) -> float:
    """Median over ``repeat`` runs of the wall time per sample [µs], after one warm-up run."""
    run()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times) / n_samples * 1e6


def run_cpp(urdf: Path, samples: Path, repeat: int) -> tuple[dict[str, float], dict[str, str]]:
    """Timings [µs per sample] and checks printed by the C++ binary."""
    out = subprocess.run(
        [str(BINARY), str(urdf), str(samples), str(BUILD), repr(DT), repr(GAIN), str(repeat)],
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise SystemExit(f"observer_bench failed ({out.returncode}): {out.stderr.strip()}")
    times, checks = {}, {}
    for line in out.stdout.splitlines():
        kind, label, value = line.split("\t")
        if kind == "time":
            times[label] = float(value)
        else:
            checks[label] = value
    return times, checks


def python_loops(
    robot: sl.robots.RobotModel,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    tau_free: np.ndarray,
) -> dict[str, Callable[[], object]]:
    """The project's per-sample loops on the same samples, by row label (numba rows need numba)."""
    n = t.shape[0]
    model = robot.pinocchio_model
    data = model.createData()

    def pinocchio_loop() -> None:
        for k in range(n):
            pin.crba(model, data, q[k])
            pin.computeCoriolisMatrix(model, data, q[k], qd[k])
            pin.computeGeneralizedGravity(model, data, q[k])

    loops: dict[str, Callable[[], object]] = {PINOCCHIO: pinocchio_loop}
    free = Log(t[: n // 2], q[: n // 2], tau_m=tau_free[: n // 2])
    settings = ObserverSettings(gain=GAIN)
    threshold, settings = tune([free], robot, "time-variant", settings, margin=0.05, folds=None)
    stream = list(zip(t.tolist(), q, tau_free, strict=True))
    log = Log(t, q, tau_m=tau_free)

    def stepping(monitor: CollisionMonitor) -> Callable[[], None]:
        def step_loop() -> None:
            monitor.reset()
            for tk, qk, tauk in stream:
                monitor.step(tk, qk, tauk)

        return step_loop

    numpy_monitor = CollisionMonitor(robot, threshold, settings, backend="numpy")
    loops[NUMPY_STEP] = stepping(numpy_monitor)
    loops["numpy: CollisionMonitor.run (batch over arrays)"] = lambda: numpy_monitor.run(log)
    if not numba_available():
        return loops
    terms = MomentumTerms(model, backend="numba")
    out = np.empty((3, robot.n_dof))
    samples = list(zip(q, qd, strict=True))

    def terms_loop() -> None:
        for qk, qdk in samples:
            terms.terms_one(qk, qdk, out)

    loops["numba: MomentumTerms.terms_one, Python loop"] = terms_loop
    monitor = CollisionMonitor(robot, threshold, settings, backend="numba")
    loops[STEP] = stepping(monitor)
    user_loop, codes = compiled_loop(), np.zeros(n, dtype=np.int64)

    def step_in_a_compiled_loop() -> None:
        monitor.reset()
        user_loop(*monitor.compiled_step(), t, q, tau_free, codes)

    loops[LOOP] = step_in_a_compiled_loop
    loops["numba: MomentumTerms.terms, whole array"] = lambda: terms.terms(q, qd)
    loops["numba: CollisionMonitor.run (fused batch, by phases)"] = lambda: monitor.run(log)
    columns = (t, (q, np.empty((n, 0)), tau_free, tau_free))
    fused = cast("FusedStream", monitor._fused)
    loops["numba: the same batch, every sample by the step's kernel"] = lambda: fused.block(
        *columns, "batch", 0
    )
    return loops


def compiled_loop() -> Callable[..., None]:
    """A user's numba loop of the stream step over arrays (t, q, τ_m), as
    :class:`~sensorless.monitor.CompiledStep` describes it; the codes go to ``codes``."""
    from numba import njit

    @njit
    def loop(function, model, buffers, t, q, tau, codes):  # type: ignore[no-untyped-def]
        out = np.empty((3, q.shape[1]))
        for k in range(t.shape[0]):
            codes[k] = function(t[k], q[k], tau[k], tau[k], model, buffers, out)

    return loop


def residual_check(
    robot: sl.robots.RobotModel, t: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray
) -> dict[str, float]:
    """Largest |C++ residual − Python MomentumObserver residual| [N m], per variant and backend."""
    backends = ["numpy", "numba"] if numba_available() else ["numpy"]
    python = {
        b: MomentumObserver(robot, DT, GAIN, friction=None, backend=b)
        .run(t, q, qd, tau)[0]
        .residual
        for b in backends
    }
    out = {}
    for variant in ("standard", "recursion", "ext_observer"):
        path = BUILD / f"residual_{variant}.csv"
        if not path.exists():
            continue
        cpp = np.loadtxt(path, delimiter=",", ndmin=2)
        for backend, reference in python.items():
            out[f"{variant} vs Python {backend}"] = float(np.max(np.abs(cpp - reference)))
        path.unlink()
    return out


# ---------------------------------------------------------------- one robot, the table
def robot_column(
    name: str, n_samples: int, repeat: int, rounds: int
) -> tuple[str, dict[str, float], dict[str, list[float]], bool]:
    """Column label, {row label: µs per sample}, the per-round ratios of the fused stream step
    (from Python, from a compiled loop) to ext_observer's step, and whether the residual check
    passed.

    Each of ``rounds`` rounds runs the C++ binary (median of ``repeat`` passes per variant)
    and then every Python loop (median of ``repeat``); a row's figure is the median over the
    rounds. Taking turns this way, a change of the machine's speed during the run (a shared
    VM's varies by up to 2×) touches C++ and Python alike.
    """
    robot = sl.robots.load(name)
    urdf_path, tip = ROBOTS[name]
    urdf = BUILD / f"{name}.urdf"
    urdf.write_text(pruned_urdf(urdf_path(), tip))
    t, q, qd, tau_free = motion(robot, n_samples, seed=1)
    tau = tau_free - contact_pulse(t, robot.n_dof)
    samples = BUILD / f"{name}_samples.csv"
    header = ",".join(f"{g}{j + 1}" for g in ("q", "qd", "tau") for j in range(robot.n_dof))
    np.savetxt(samples, np.hstack([q, qd, tau]), fmt="%.17g", delimiter=",", header=header)
    loops = python_loops(robot, t, q, qd, tau_free)
    per_round: dict[str, list[float]] = {}
    ratios: dict[str, list[float]] = {label: [] for label in RATIOS}
    ok = True
    for index in range(rounds):
        times, checks = run_cpp(urdf, samples, repeat)
        if index == 0:
            ok = check_residuals(name, robot, checks, residual_check(robot, t, q, qd, tau))
        for path in BUILD.glob("residual_*.csv"):
            path.unlink()
        row = {f"C++ {k}": v for k, v in times.items()}
        row.update({label: median_us(loop, n_samples, repeat) for label, loop in loops.items()})
        for label, cost in row.items():
            per_round.setdefault(label, []).append(cost)
        for label, ratio in ratios.items():
            if RATIOS[label] in row and label in row:
                ratio.append(row[label] / row[RATIOS[label]])
    column = {label: statistics.median(costs) for label, costs in per_round.items()}
    return f"{name} ({robot.n_dof} dof)", column, ratios, ok


def check_residuals(
    name: str, robot: sl.robots.RobotModel, checks: dict[str, str], errors: dict[str, float]
) -> bool:
    """Print the residual checks of one robot; whether the C++ observers match Python's."""
    if int(checks["n_dof"]) != robot.n_dof:
        raise SystemExit(f"{name}: the C++ model has {checks['n_dof']} joints, not {robot.n_dof}")
    relative = float(checks["recursion relative error"])
    print(f"\n{name}: (d) against the standard calls, relative error {relative:.1e}")
    ok = True
    for label, error in errors.items():
        if label.startswith("ext_observer"):
            verdict = "(its own discretisation)"
        else:
            verdict = "ok" if error <= TOLERANCE else f"FAIL > {TOLERANCE:g}"
            ok &= error <= TOLERANCE
        print(f"  max |C++ {label}| residual difference: {error:.2e} N m {verdict}")
    return ok


def print_table(
    columns: dict[str, dict[str, float]],
    ratios: dict[str, dict[str, list[float]]],
    n_samples: int,
    repeat: int,
    rounds: int,
) -> None:
    """One row per path, one column pair (µs per sample, ratio to (b)) per robot."""
    names = list(columns)
    labels = list(dict.fromkeys(label for column in columns.values() for label in column))
    print(
        f"\nµs per sample over {n_samples} samples: median over {rounds} rounds of the median "
        f"of {repeat} loops"
    )
    print(f"× = ratio to {UPDATE!r}")
    print(f"{'path':62s}" + "".join(f"{n:>16s}{'×':>7s}" for n in names))
    for label in labels:
        row = f"{label:62s}"
        for n in names:
            cost = columns[n].get(label, float("nan"))
            row += f"{cost:16.3f}{cost / columns[n][UPDATE]:7.2f}"
        print(row)
    for n in names:
        for label, per_round in ratios[n].items():
            if per_round:
                each = " ".join(f"{r:.2f}" for r in per_round)
                reference = "ext_observer step" if RATIOS[label] == EXT else "three calls"
                print(
                    f"{n}: {label} / {reference} = "
                    f"{statistics.median(per_round):.2f} (median; per round {each})"
                )


# ---------------------------------------------------------------- main
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20_000, help="samples per robot")
    parser.add_argument("--repeat", type=int, default=3, help="timed loops per round (median)")
    parser.add_argument("--rounds", type=int, default=5, help="rounds of C++ then Python (median)")
    parser.add_argument("--ext-observer", default=os.environ.get("EXT_OBSERVER"))
    args = parser.parse_args()

    wanted = os.environ.get("CXX") or "g++"
    compiler = shutil.which(wanted)
    prefix = cmeel_prefix()
    if compiler is None or prefix is None:
        reason = f"no {wanted} on PATH" if compiler is None else "no pin wheel (cmeel.prefix)"
        print(f"C++ benchmark skipped: {reason}")
        return
    ext_lib = ext_observer_lib(args.ext_observer)
    if ext_lib is None:
        print(
            "ext_observer not given (--ext-observer PATH, a checkout of "
            "github.com/mikhel1984/ext_observer): row (c) left out"
        )
    command = compile_command(compiler, prefix, ext_lib)
    if isinstance(command, str):
        print(f"C++ benchmark skipped, {command}")
        return
    seconds = build(command)
    print("binary up to date" if seconds is None else f"compiled in {seconds:.1f} s (wall)")

    print("load average (1, 5, 15 min) at the start: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    columns, ratios = {}, {}
    failed = False
    for name in ROBOTS:
        label, column, ratios[label], ok = robot_column(
            name, args.samples, args.repeat, args.rounds
        )
        columns[label] = column
        failed |= not ok
    print_table(columns, ratios, args.samples, args.repeat, args.rounds)
    print("load average (1, 5, 15 min) at the end: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    if failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
