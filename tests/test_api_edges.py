"""Issue 10's API edges: each bad argument gives the library's error naming what came."""

from __future__ import annotations

import numpy as np
import pytest

from sensorless.exceptions import (
    InputTypeError,
    InputValueError,
    ModelError,
    NotFittedError,
    SensorlessError,
)
from sensorless.monitor import CollisionMonitor, ObserverSettings, tune
from sensorless.robots import load
from sensorless.robots.base_parameters import base_parameters
from sensorless.robots.model import RobotModel
from sensorless.signals import ObserverSignals
from sensorless.thresholds import ConstantThreshold

ROW = {"alpha": 0.0, "a": 0.0, "d": 0.0, "theta": 0.0}
LINK = {"mass": 1.0, "com": [0.0, 0.0, 0.0], "inertia": [0.01, 0.0, 0.0, 0.01, 0.0, 0.01]}


def _signals(n_samples: int) -> ObserverSignals:
    t = np.arange(n_samples) * 1e-3
    zeros = np.zeros((n_samples, 2))
    return ObserverSignals(
        t=t, residual=zeros, model_torque=zeros, friction=zeros, sign=zeros, velocity=zeros,
        gain=np.full(2, 20.0), kind="motor", robot="planar2",
    )  # fmt: skip


CASES = [
    ("from_mdh table=None", lambda: RobotModel.from_mdh(None, [LINK]), InputTypeError,
     r"DH table must be a DataFrame or a sequence of rows.*got NoneType"),
    ("from_mdh mass 'x'", lambda: RobotModel.from_mdh([ROW], [{**LINK, "mass": "x"}]),
     ModelError, r"link 'link1': mass must be a number \[kg\]; got 'x'"),
    ("from_mdh com 'x'", lambda: RobotModel.from_mdh([ROW], [{**LINK, "com": "x"}]),
     SensorlessError, r"link 'link1': centre of mass"),
    ("from_mdh negative inertia",
     lambda: RobotModel.from_mdh([ROW], [{**LINK, "inertia": [-0.01, 0, 0, 0.01, 0, 0.01]}]),
     ModelError, r"link 'link1': the inertia tensor is not positive semi-definite"),
    ("load(['panda'])", lambda: load(["panda"]), InputTypeError,  # type: ignore[arg-type]
     r"robot name must be a string.*got \['panda'\]"),
    ("inverse_dynamics qdd=1e308",
     lambda: load("planar2").inverse_dynamics(np.zeros(2), np.zeros(2), np.full(2, 1e308)),
     InputValueError, r"the result is not finite at sample 0"),
    ("base_parameters zero=None", lambda: base_parameters(load("planar2"), None),
     InputTypeError, r"zero must be a sequence of parameter names; got None"),
    ("base_parameters n_samples=1", lambda: base_parameters(load("planar2"), n_samples=1),
     InputValueError, r"n_samples must be an integer >= 11; got 1"),
    ("base_parameters n_samples=2.5", lambda: base_parameters(load("planar2"), n_samples=2.5),
     InputValueError, r"n_samples must be an integer >= 11; got 2.5"),
    ("base_parameters seed=-1", lambda: base_parameters(load("planar2"), seed=-1),
     InputValueError, r"seed must be an integer >= 0; got -1"),
    ("base_parameters tolerance=-1", lambda: base_parameters(load("planar2"), tolerance=-1),
     InputValueError, r"tolerance must be a finite number > 0 \[-\]; got -1"),
    ("base_parameters tolerance=nan",
     lambda: base_parameters(load("planar2"), tolerance=float("nan")),
     InputValueError, r"tolerance must be a finite number > 0 \[-\]; got nan"),
    ("fit on 0 samples", lambda: ConstantThreshold().fit(_signals(0)), InputValueError,
     r"fit run 0 has 0 sample\(s\); a fit needs at least 2"),
    ("fit on 1 sample", lambda: ConstantThreshold().fit(_signals(1)), InputValueError,
     r"fit run 0 has 1 sample\(s\); a fit needs at least 2"),
    ("monitor with an unfitted threshold",
     lambda: CollisionMonitor(load("planar2"), ConstantThreshold(), ObserverSettings()),
     NotFittedError, r"not fitted"),
    ("tune on a string", lambda: tune("run.parquet", load("planar2"), "constant"),  # type: ignore[arg-type]
     InputTypeError, r"logs must be a Log or a sequence of Logs; got str"),
]  # fmt: skip


@pytest.mark.parametrize(("name", "call", "error", "message"), CASES, ids=[c[0] for c in CASES])
def test_a_bad_argument_gives_a_clear_error(name, call, error, message) -> None:
    with pytest.raises(error, match=message):
        call()


def test_tune_takes_one_log_as_one_run() -> None:
    from sensorless.simulation.scenario import load_scenario

    log = load_scenario("panda-gaz").with_duration(1.0).run(seed=1, collisions=False).log
    nominal = load_scenario("panda-gaz").robots()[1]
    one, _ = tune(log, nominal, "constant", margin=0.05, folds=None)
    listed, _ = tune([log], nominal, "constant", margin=0.05, folds=None)
    np.testing.assert_array_equal(one.beta_, listed.beta_)


def test_tune_refuses_a_log_in_degrees() -> None:
    from sensorless.simulation.scenario import load_scenario

    scenario = load_scenario("panda-gaz").with_duration(1.0)
    log = scenario.run(seed=1, collisions=False).log
    frame = log.to_pandas()
    # Joint 1 near 0.15 rad, given in degrees: 8.6 "rad", under the log's 4π check but
    # beyond twice the joint's range (±2.9 rad) from its centre.
    frame["q_1"] = np.rad2deg(0.15 + 0.01 * np.sin(frame["t"]))
    degrees = type(log).from_pandas(frame)
    with pytest.raises(InputValueError, match=r"log 0: q of joint \d is .* degrees instead of"):
        tune([degrees], scenario.robots()[1], "constant", margin=0.05, folds=None)
