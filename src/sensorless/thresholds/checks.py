"""Input checks of the threshold families and of the detector.

Hyper-parameters are checked when ``fit`` reads them, signals when a public
entry point receives them: ``fit``, ``bounds``, ``initial_state``, ``step``
and ``process`` of a threshold, ``run``, ``detect`` and ``step`` of a
:class:`~sensorless.detection.Detector`. Past those entry points, functions
take checked arrays and check nothing again.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_joint_array,
    check_finite,
    check_increasing,
    check_type,
    first_irregular_step,
)
from ..exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    ModelMismatchError,
    SensorlessError,
)
from ..signals import ObserverSignals
from .state import ThresholdInputs, ThresholdState

__all__ = [
    "as_inputs",
    "as_runs",
    "as_samples",
    "check_inputs_finite",
    "check_joints",
    "check_runs",
    "check_state",
    "other_model",
    "parameters_differ",
    "regular_period",
    "robot_mismatch",
]

SERIES = ("model_torque", "friction", "sign", "velocity")
"""Signals every family receives besides the residual (the first fields of ThresholdInputs)."""


# --------------------------------------------------------------------------- hyper-parameters


def check_joints(joints: Any, n_dof: int) -> tuple[int, ...]:
    """Return the monitored joints (1-based, sorted) after checking them; None means all."""
    if joints is None:
        return tuple(range(1, n_dof + 1))
    message = (
        f"joints must be distinct joint numbers between 1 and {n_dof} (1-based), "
        f"or None for all; got {joints!r}"
    )
    try:
        values = [operator.index(j) for j in joints]
    except TypeError:
        raise InputValueError(message) from None
    if not values or len(set(values)) != len(values) or not all(1 <= j <= n_dof for j in values):
        raise InputValueError(message)
    return tuple(sorted(values))


# --------------------------------------------------------------------------- runs


def regular_period(t: FloatArray, what: str, rtol: float = 1e-6) -> float:
    """Sample period [s] of regular time stamps; irregular ones are an error, never resampled."""
    if t.shape[0] < 2:
        raise InputValueError(
            f"{what} has {t.shape[0]} sample(s); at least 2 are needed to know the sample period"
        )
    step = np.diff(t)
    median = float(np.median(step))
    k = first_irregular_step(t, median, rtol)
    if k is not None:
        raise InputValueError(
            f"t of {what} is not regularly sampled: t[{k + 1}] - t[{k}] = {step[k]:.9g} s, "
            f"the median step is {median:.9g} s (rtol {rtol:g}); resample the log explicitly "
            "with sensorless.io.resample"
        )
    return median


def as_runs(signals: Any) -> list[ObserverSignals]:
    """The fit runs: one ObserverSignals or a non-empty sequence of them."""
    runs = [signals] if isinstance(signals, ObserverSignals) else signals
    if not isinstance(runs, Sequence) or not all(isinstance(r, ObserverSignals) for r in runs):
        raise InputTypeError(
            "fit takes an ObserverSignals or a sequence of ObserverSignals (collision-free "
            f"runs); got {type(signals).__name__}"
        )
    if not runs:
        raise InputValueError("fit needs at least one collision-free run; got an empty sequence")
    return list(runs)


def other_model(name: str, fingerprint: str, other_name: str, other_fingerprint: str) -> bool:
    """Whether two nominal models differ: by name, or by fingerprint when both are known.

    An empty fingerprint (signals built by hand, a threshold file written
    before fingerprints were saved) is compared by name only.
    """
    return name != other_name or bool(
        fingerprint and other_fingerprint and fingerprint != other_fingerprint
    )


def check_same_residual(first: Any, second: Any, first_name: str, second_name: str) -> None:
    """Raise unless two fitted thresholds bound the residual of one model, kind and gain.

    ``first_name`` and ``second_name`` name them in the messages ("the
    contact threshold", "the steady part").
    """
    if first.n_dof_ != second.n_dof_:
        raise DimensionError(
            f"{first_name} is for {first.n_dof_} joints, {second_name} for {second.n_dof_}; "
            "both watch one robot"
        )
    if other_model(first.robot_, first.fingerprint_, second.robot_, second.fingerprint_):
        raise ModelMismatchError(
            f"{first_name} is for robot {first.robot_!r}, {second_name} for {second.robot_!r} "
            "(or other dynamic parameters); fit both on one model"
        )
    if first.kind_ != second.kind_ or not np.allclose(
        first.gain_, second.gain_, rtol=1e-9, atol=0.0, equal_nan=True
    ):
        raise InputValueError(
            f"both must watch one residual: {first_name} bounds {first.kind_!r} signals with "
            f"K_I = {first.gain_.tolist()} [1/s], {second_name} {second.kind_!r} signals with "
            f"K_I = {second.gain_.tolist()}"
        )


def parameters_differ(fingerprint: str, other_fingerprint: str) -> str:
    """``"; the dynamic parameters differ (…)"`` when both fingerprints are known and differ."""
    if fingerprint and other_fingerprint and fingerprint != other_fingerprint:
        return (
            f"; the dynamic parameters differ (fingerprints {fingerprint} and {other_fingerprint})"
        )
    return ""


def robot_mismatch(message: str, expected_n_dof: int, n_dof: int) -> SensorlessError:
    """The error for signals of another robot model than expected, ``message`` first.

    Joint counts that differ are a :class:`DimensionError`; the same joint
    count with another model (another robot name, or the same name with other
    dynamic parameters: a payload, an identified set; see :func:`other_model`)
    is a :class:`ModelMismatchError`.
    """
    if n_dof != expected_n_dof:
        return DimensionError(message)
    return ModelMismatchError(
        f"{message}: the joint counts match but the robot models differ (another robot, a "
        "payload or other parameters); use signals of one model, or fit again on signals "
        "of the model in use"
    )


def check_runs(runs: list[ObserverSignals]) -> None:
    """Fit runs of one robot, signal kind and gain, with increasing time and finite signals."""
    first = runs[0]
    for i, run in enumerate(runs):
        what = f"fit run {i}"
        if run.t.shape[0] < 2:
            raise InputValueError(
                f"{what} has {run.t.shape[0]} sample(s); a fit needs at least 2 per run "
                "(they define its sample period)"
            )
        if run.n_dof != first.n_dof or other_model(
            run.robot, run.fingerprint, first.robot, first.fingerprint
        ):
            raise robot_mismatch(
                f"all fit runs must come from one robot; run 0 is {first.robot!r} "
                f"({first.n_dof} joints), {what} is {run.robot!r} ({run.n_dof} joints)"
                + parameters_differ(first.fingerprint, run.fingerprint),
                first.n_dof,
                run.n_dof,
            )
        if run.kind != first.kind:
            raise InputValueError(
                f"all fit runs must be of one signal kind; run 0 is {first.kind!r}, "
                f"{what} is {run.kind!r}"
            )
        if not np.allclose(run.gain, first.gain, rtol=1e-9, atol=0.0, equal_nan=True):
            raise InputValueError(
                f"all fit runs must use one observer gain K_I; run 0 has {first.gain.tolist()}, "
                f"{what} has {run.gain.tolist()} [1/s]"
            )
        check_increasing(run.t, what)
        for name in ("residual", *SERIES):
            check_finite(getattr(run, name), f"{name} of {what}")


# --------------------------------------------------------------------------- samples


def as_samples(
    value: ArrayLike, n_dof: int, name: str, *, one_sample: str = "", allow_nonfinite: bool = False
) -> FloatArray:
    """``value`` as an array of shape (n_samples, n_dof).

    ``one_sample`` names the method (``"step"``) that takes exactly one
    sample of shape (n_dof,); ``allow_nonfinite`` skips the NaN/inf check
    (the detector reports such samples as faults instead).
    """
    arr, single = as_joint_array(value, n_dof, name, allow_nonfinite=allow_nonfinite)
    if one_sample and not single:
        raise DimensionError(
            f"{one_sample} takes one sample: {name} of shape ({n_dof},); got shape "
            f"{np.shape(value)}"
        )
    return arr


def as_inputs(
    n_dof: int,
    model_torque: ArrayLike,
    friction: ArrayLike,
    sign: ArrayLike,
    velocity: ArrayLike,
    position: ArrayLike | None,
    acceleration: ArrayLike | None,
    *,
    one_sample: str = "",
    allow_nonfinite: bool = False,
) -> ThresholdInputs:
    """Checked :class:`ThresholdInputs` of a stream; every series has the samples of the first.

    ``one_sample`` and ``allow_nonfinite`` as for :func:`as_samples`.
    """
    counts: list[int] = []

    def convert(value: ArrayLike, name: str) -> FloatArray:
        arr = as_samples(value, n_dof, name, one_sample=one_sample, allow_nonfinite=allow_nonfinite)
        if counts and arr.shape[0] != counts[0]:
            raise DimensionError(f"{name} has {arr.shape[0]} samples; model_torque has {counts[0]}")
        counts.append(arr.shape[0])
        return arr

    return ThresholdInputs(
        convert(model_torque, "model_torque"),
        convert(friction, "friction"),
        convert(sign, "sign"),
        convert(velocity, "velocity"),
        None if position is None else convert(position, "position"),
        None if acceleration is None else convert(acceleration, "acceleration"),
    )


def check_inputs_finite(inputs: ThresholdInputs) -> None:
    """Raise :class:`~sensorless.exceptions.InputValueError` naming the first non-finite input."""
    for name, values in zip(ThresholdInputs._fields, inputs, strict=True):
        if values is not None:
            check_finite(values, name)


def check_state(state: Any, expected: type[ThresholdState] = ThresholdState) -> None:
    """Raise :class:`~sensorless.exceptions.InputTypeError` unless ``state`` is an ``expected``."""
    check_type(state, expected, "state", " from initial_state, step or process")
