"""``sensorless plan``: the file it writes reads back, mistakes end in one line and a code.

The fuzz feeds arbitrary text to every option of the command: whatever comes,
the command ends with exit code 0 (a plan) or a user-error code (2 bad
argument, 3 file, 4 file content), never with a traceback or an internal error (1).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.metric import load_plan

runner = CliRunner()


def plan_args(tmp: Path, *extra: str) -> list[str]:
    return ["plan", "--robot", "planar2", "--from", "0,0", "--to", "1,-0.5", "--duration", "2",
            "-o", str(tmp / "traj.yaml"), *extra]  # fmt: skip


def test_plan_writes_a_file_and_a_figure(tmp_path: Path) -> None:
    figure = tmp_path / "plan.png"
    result = runner.invoke(app, plan_args(tmp_path, "--plot", str(figure)))
    assert result.exit_code == 0, result.output
    assert "% lower" in result.output and figure.stat().st_size > 10_000
    trajectory = load_plan(tmp_path / "traj.yaml")
    q, qd, _ = trajectory.evaluate(np.array([0.0, 2.0]))
    np.testing.assert_allclose(q, [[0.0, 0.0], [1.0, -0.5]], atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, atol=1e-9)


def test_plan_in_degrees_through_a_via_point(tmp_path: Path) -> None:
    args = ["plan", "--robot", "planar2", "--from", "0,0", "--to", "57.29577951308232,0",
            "--duration", "2", "--degrees", "--via", "1:20,10",
            "-o", str(tmp_path / "t.yml")]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    trajectory = load_plan(tmp_path / "t.yml")
    np.testing.assert_allclose(trajectory.evaluate(1.0)[0], np.deg2rad([20.0, 10.0]), atol=1e-9)
    np.testing.assert_allclose(trajectory.evaluate(2.0)[0], [1.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    ("change", "code", "message"),
    [
        (["--from", "0,0,0"], 2, "--from has 3 value(s); robot planar2 has 2 joints"),
        (["--to", "1,nan"], 2, "--to must be comma-separated finite numbers"),
        (["--duration", "0"], 2, "--duration must be one number of seconds > 0"),
        (["--duration", "two"], 2, "--duration must be comma-separated finite numbers"),
        (["--robot", "r2d2"], 2, "r2d2"),
        (["--via", "1,2"], 2, "--via must be TIME:q1,q2"),
        (["--via", "3:0,0"], 2, "via_times must be strictly increasing inside"),
        (["-o", "out.txt"], 2, "must end in one of"),
        (["--plot", "out.gif"], 2, "must end in one of"),
    ],
)
def test_user_mistakes_end_in_one_line(
    tmp_path: Path, change: list[str], code: int, message: str
) -> None:
    args = plan_args(tmp_path)
    for key, value in zip(change[::2], change[1::2], strict=True):
        if key in args:
            args[args.index(key) + 1] = value
        else:
            args += [key, value]
    result = runner.invoke(app, args)
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0]


_TEXT = st.one_of(
    st.text(max_size=12),
    st.sampled_from(["0,0", "1,-0.5", "nan,0", "1e400,0", "0.5", "-0,-0", "3,3", "1e-9"]),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=3).map(
        lambda xs: ",".join(str(x) for x in xs)
    ),
)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    robot=st.sampled_from(["planar2", "puma", "", "scenario:nothing", "x.urdf"]),
    start=_TEXT,
    end=_TEXT,
    duration=st.one_of(_TEXT, st.sampled_from(["0.01", "1e9", "-1", "inf", "0.002"])),
    via=st.one_of(st.none(), _TEXT, st.sampled_from(["1:0.5,0", ":", "0.5:"])),
)
def test_fuzzed_arguments_never_give_a_traceback(
    tmp_path: Path, robot: str, start: str, end: str, duration: str, via: str | None
) -> None:
    args = ["plan", "--robot", robot, "--from", start, "--to", end, "--duration", duration,
            "-o", str(tmp_path / "fuzz.yaml"), "--max-iterations", "20"]  # fmt: skip
    if via is not None:
        args += ["--via", via]
    result = runner.invoke(app, args)
    assert result.exit_code in (0, 2, 3, 4), (args, result.output)
    assert result.exception is None or isinstance(result.exception, SystemExit), args
    assert "Traceback" not in result.output
