"""Tuning: observer settings, threshold families by name, fit on collision-free logs, files.

:func:`tune` fits a threshold family on collision-free logs, cross-validates
it on the same logs to say what false-alarm rate to expect, and can set the
margin for a stated rate (:mod:`.calibration`); observer settings and that
calibration travel with the fitted threshold in one YAML file
(:func:`save_tuned`, :func:`load_tuned`), so a threshold is never applied to
residuals computed differently from those it was fitted on. Units SI and
radians; time along axis 0; rates per hour.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._validation import check_dt, check_scalar
from ..exceptions import FileFormatError, InputTypeError, InputValueError, UnknownNameError
from ..filters import Butterworth, CausalEstimator, DirtyDerivative, FiniteDifference
from ..io import Log
from ..io.file_schema import read_yaml_mapping
from ..observers import default_estimator, observe
from ..robots.model import RobotModel
from ..signals import ObserverSignals
from ..thresholds import (
    ConstantThreshold,
    LearnedThreshold,
    ModelBasedThreshold,
    PayloadThreshold,
    Threshold,
    TimeVariantThreshold,
    VelocityThreshold,
)
from ..thresholds.files import OLD_NAMES, threshold_from_dict
from .calibration import (
    DEFAULT_HOLD,
    DEFAULT_MIN_DURATION,
    Calibration,
    attach_calibration,
    calibration_of,
    cross_validate,
    margin_for_rate,
    with_stated,
)
from .policy import StreamPolicy

__all__ = [
    "DEFAULT_MARGIN_FRACTION",
    "METHOD_NAMES",
    "ObserverSettings",
    "load_tuned",
    "make_threshold",
    "save_tuned",
    "tune",
]

#: Threshold families by their one name (files, CLI, API, reports), with the observer each
#: one watches.
METHOD_NAMES: dict[str, str] = {
    "constant": "motor",
    "time-variant": "motor",
    "hysteretic": "motor",
    "velocity": "motor",
    "model": "acceleration",
    "learned": "motor",
}
_FILTERS = ("default", "finite_difference", "dirty_derivative", "butterworth")

DEFAULT_MARGIN_FRACTION = 0.1
"""Default margin of :func:`tune`: this fraction of the constant band β_j of each joint."""


@dataclass(frozen=True)
class ObserverSettings:
    """How residuals are computed from a log or a stream.

    Parameters
    ----------
    kind : {"motor", "joint", "acceleration"}
        r̂ from motor torques (eq. 4.4), r̂_s from joint torque sensors (eq. 4.9),
        or the acceleration-based τ̂_c (eq. 3.16).
    gain : float
        Observer gain K_I [1/s] (momentum observers; §5.4 uses 20).
    filter : {"default", "finite_difference", "dirty_derivative", "butterworth"}
        Velocity/acceleration estimator; "default" is
        :func:`sensorless.observers.default_estimator`.
    cutoff : float
        Cut-off [Hz] of the dirty derivative or Butterworth filter.
    order : int
        Butterworth order (the thesis used 5).
    """

    kind: str = "motor"
    gain: float = 20.0
    filter: str = "default"
    cutoff: float = 20.0
    order: int = 5

    def __post_init__(self) -> None:
        if self.kind not in ("motor", "joint", "acceleration"):
            raise InputValueError(
                f"observer kind must be motor, joint or acceleration; got {self.kind!r}"
            )
        if self.filter not in _FILTERS:
            raise InputValueError(f"filter must be one of {list(_FILTERS)}; got {self.filter!r}")
        if not np.isfinite(self.gain) or self.gain <= 0:
            raise InputValueError(f"observer gain K_I must be > 0 [1/s]; got {self.gain}")

    def estimator(self, dt: float) -> CausalEstimator:
        """The velocity/acceleration estimator for sample period ``dt`` [s]."""
        period = check_dt(dt)
        if self.filter == "finite_difference":
            return FiniteDifference(period)
        if self.filter == "dirty_derivative":
            return DirtyDerivative(period, self.cutoff)
        if self.filter == "butterworth":
            return Butterworth(period, self.cutoff, self.order)
        return default_estimator(period, self.kind)

    def settle_time(self, dt: float) -> float:
        """Start-up time [s] after which the residual has forgotten its start.

        A momentum observer's residual decays as exp(−K_I t) from its start
        (eq. 3.6): 5/K_I leaves less than 1 % of a start-up error. The
        acceleration-based estimate has no memory but the estimator's: five
        times its delay. At least ten samples either way.
        """
        period = check_dt(dt)
        if self.kind == "acceleration":
            memory = 5.0 * max(self.estimator(period).delays.acceleration, period)
        else:
            memory = 5.0 / self.gain
        return max(memory, 10.0 * period)

    def observe(self, log: Log, robot: RobotModel) -> ObserverSignals:
        """Residual signals of a whole log (see :func:`sensorless.observers.observe`)."""
        return observe(log, robot, kind=self.kind, gain=self.gain, estimator=self.estimator(log.dt))

    def to_dict(self) -> dict[str, Any]:
        """Plain values for a YAML file."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ObserverSettings:
        """Inverse of :meth:`to_dict`; unknown keys are a TypeError listing the valid ones."""
        valid = set(cls.__dataclass_fields__)
        unknown = set(data) - valid
        if unknown:
            raise InputTypeError(
                f"unknown observer settings {sorted(unknown)}; valid: {sorted(valid)}"
            )
        return cls(**data)


def _check_method(method: Any) -> str:
    if method in METHOD_NAMES:
        return str(method)
    renamed = OLD_NAMES.get(method) if isinstance(method, str) else None
    hint = f" (the family is called {renamed!r})" if renamed in METHOD_NAMES else ""
    raise UnknownNameError(
        f"unknown threshold method {method!r}{hint}; options: {sorted(METHOD_NAMES)}"
    )


def make_threshold(method: str, robot: RobotModel, **options: Any) -> Threshold:
    """An unfitted threshold of the family ``method`` (one of :data:`METHOD_NAMES`)."""
    method = _check_method(method)
    if method == "constant":
        return ConstantThreshold(**options)
    if method == "time-variant":
        return TimeVariantThreshold(form="friction", **options)
    if method == "hysteretic":
        return TimeVariantThreshold(form="hysteretic", **options)
    if method == "velocity":
        return VelocityThreshold(**options)
    if method == "model":
        return ModelBasedThreshold(robot, **options)
    if method == "learned":
        return LearnedThreshold(**options)
    raise UnknownNameError(f"no threshold family for method {method!r}")  # pragma: no cover


def _check_angles(logs: Sequence[Log], robot: RobotModel) -> None:
    """Refuse a log whose positions leave the robot's range by more than the range itself.

    Such a log is in degrees (or of another robot): 90° reads as 90 rad. A
    small overshoot of the limits (a simulated trajectory, a real arm at its
    stop) passes; samples beyond the limits are the monitor's faults.
    """
    limits = StreamPolicy().limits(robot)
    for i, log in enumerate(logs):
        q = np.asarray(log.q)
        if q.shape[1] != robot.n_dof:
            return  # observe says so, with the joint counts
        over = np.nanmax(np.abs(q - limits.centre), axis=0) - 2.0 * limits.half_range
        if (over > 0.0).any():
            j = int(np.argmax(over))
            k = int(np.nanargmax(np.abs(q[:, j] - limits.centre[j])))
            low = limits.centre[j] - limits.half_range[j]
            high = limits.centre[j] + limits.half_range[j]
            raise InputValueError(
                f"log {i}: q of joint {j + 1} is {q[k, j]:.6g} at t = {log.t[k]:.6g} s, far "
                f"outside the robot's range [{low:.4g}, {high:.4g}] rad: degrees instead of "
                f"radians? Convert with numpy.deg2rad (robot {robot.name!r})"
            )


def tune(
    logs: Sequence[Log],
    robot: RobotModel,
    method: str,
    settings: ObserverSettings | None = None,
    *,
    false_alarm_rate: float | None = None,
    folds: str | int | None = "runs",
    min_duration: float = DEFAULT_MIN_DURATION,
    hold: float = DEFAULT_HOLD,
    confidence: float = 0.95,
    seed: int = 0,
    margin_fraction: float | None = None,
    payload: dict[str, Any] | None = None,
    **options: Any,
) -> tuple[Threshold, ObserverSettings]:
    """Fit a threshold family on collision-free logs and say what false-alarm rate to expect.

    Parameters
    ----------
    logs : Log or sequence of Log
        Collision-free runs of the robot.
    robot : RobotModel
        The nominal model the observer uses.
    method : str
        One of :data:`METHOD_NAMES`.
    settings : ObserverSettings, optional
        Observer settings; by default the observer the method watches, K_I = 20.
    false_alarm_rate : float, optional
        Stated false alarms per hour for the robot [1/h]: the margin is set
        by :func:`~sensorless.monitor.margin_for_rate` on held-out folds, then
        the family is refitted on all logs with it. Not together with ``margin``.
    folds : "runs", int or None
        Cross-validation folds: every log held out once ("runs"; one log:
        two time blocks), or k folds (k time blocks of a single log). None
        skips the cross-validation (quick fits in tests and benchmarks): the
        threshold then carries no calibration and makes no promise.
    min_duration, hold : float
        Detector settings [s] the false alarms are counted with; the
        defaults are those of :class:`~sensorless.monitor.CollisionMonitor`.
    confidence : float
        Level of the intervals.
    seed : int
        Seed of the bootstrap behind the stated rate's interval.
    margin_fraction : float, optional
        Margin added to the fitted bounds of joint j, as a fraction of the
        constant band β_j = max |r_j| of the same residual on the same samples
        (eq. 5.32) [-]; :data:`DEFAULT_MARGIN_FRACTION` (10 %, the demo's)
        when neither ``margin`` nor ``false_alarm_rate`` is given. Every
        family then gets the same margin in N m, so none runs with margin 0.
    payload : dict, optional
        A payload the arm may grip that ``robot`` lacks, as the keywords of
        :class:`~sensorless.thresholds.PayloadThreshold`: ``max_mass`` [kg],
        ``center``, ``radius`` or ``half_widths`` [m] in the end-link frame,
        ``velocity_error`` [rad/s]. The family is fitted on ``logs`` (without
        the payload) and wrapped, so that a gripped object up to that mass is
        no collision; the cross-validation judges the wrapped threshold. Not
        with ``false_alarm_rate``. Such a threshold runs on the Python path
        and has no file format yet.
    **options
        Hyper-parameters of the threshold (``margin``, ``joints``, ``transient``...).
        ``margin`` [N m], a number or one per joint, is the absolute form (not
        with ``margin_fraction``).
        ``transient`` [s], the start of each log left out of the fit, defaults to
        the observer's :meth:`ObserverSettings.settle_time`: a log that begins in
        motion starts with a residual excursion that is the observer's, not the
        robot's, and the live monitor does not judge that start either.

    Returns
    -------
    threshold : Threshold
        Fitted on all logs, with the cross-validated false alarms per hour
        (a :class:`~sensorless.monitor.Calibration`: rate, interval, warnings,
        the stated rate's margin) as ``threshold.calibration_``
        (:func:`~sensorless.monitor.calibration_of`) unless ``folds`` is None.
    settings : ObserverSettings
        The settings used (save them with the threshold: :func:`save_tuned`).
    """
    method = _check_method(method)
    if isinstance(logs, Log):
        logs = [logs]  # one run
    if not isinstance(logs, Sequence) or not all(isinstance(log, Log) for log in logs):
        raise InputTypeError(f"logs must be a Log or a sequence of Logs; got {type(logs).__name__}")
    if not logs:
        raise InputValueError("tune needs at least one collision-free log")
    if false_alarm_rate is not None and (
        "margin" in options or margin_fraction is not None or folds is None
    ):
        raise InputValueError(
            "false_alarm_rate sets the margin from held-out folds: give no margin, and folds "
            f"'runs' or an integer; got margin={options.get('margin')!r}, "
            f"margin_fraction={margin_fraction!r}, folds={folds!r}"
        )
    if payload is not None and false_alarm_rate is not None:
        raise InputValueError(
            "a declared payload widens the bounds beyond any margin: give it with a margin "
            "(margin or margin_fraction), not with false_alarm_rate"
        )
    if margin_fraction is not None:
        if "margin" in options:
            raise InputValueError(
                "give the margin as a fraction of the band (margin_fraction) or in N m "
                f"(margin), not both; got margin_fraction={margin_fraction!r}, "
                f"margin={options['margin']!r}"
            )
        margin_fraction = check_scalar(margin_fraction, "margin_fraction", "-", "nonnegative")
    settings = settings or ObserverSettings(kind=METHOD_NAMES[method])
    needed = METHOD_NAMES[method]
    if (needed == "acceleration") != (settings.kind == "acceleration"):
        raise InputValueError(
            f"method {method!r} watches the {needed!r} residual; observer kind is {settings.kind!r}"
        )
    _check_angles(logs, robot)
    signals = [settings.observe(log, robot) for log in logs]
    options.setdefault("transient", settings.settle_time(signals[0].dt))
    if false_alarm_rate is None and "margin" not in options:
        fraction = DEFAULT_MARGIN_FRACTION if margin_fraction is None else margin_fraction
        options["margin"] = _band_margin(signals, fraction, options)
    detector: dict[str, Any] = {"folds": folds, "min_duration": min_duration, "hold": hold}
    stated = None

    def shape() -> Threshold:
        family = make_threshold(method, robot, **options)
        return family if payload is None else PayloadThreshold(family, robot, **payload)

    if false_alarm_rate is not None:
        stated = margin_for_rate(
            signals, shape(), false_alarm_rate, confidence=confidence, seed=seed, **detector
        )
        options["margin"] = list(stated.margin)
    threshold = shape().fit(signals)
    if folds is None:
        return threshold, settings
    calibration = cross_validate(
        signals, threshold, confidence=confidence, target_rate=false_alarm_rate, **detector
    )
    if stated is not None:
        calibration = with_stated(calibration, stated)
    return attach_calibration(threshold, calibration), settings


def _band_margin(
    signals: Sequence[ObserverSignals], fraction: float, options: dict[str, Any]
) -> list[float]:
    """``fraction`` × the constant band β_j of the residual, on the samples the fit uses [N m]."""
    if fraction == 0.0:
        return [0.0] * signals[0].residual.shape[1]
    band = ConstantThreshold(joints=options.get("joints"), transient=options["transient"])
    return [float(fraction * beta) for beta in band.fit(list(signals)).beta_]


def save_tuned(path: str | Path, threshold: Threshold, settings: ObserverSettings) -> Path:
    """Write a fitted threshold, its observer settings and its calibration to one YAML file.

    The calibration (cross-validated false alarms per hour, see :func:`tune`)
    is written under ``calibration`` when the threshold has one.
    """
    data = threshold.to_dict()
    data["observer"] = settings.to_dict()
    calibration = calibration_of(threshold)
    if calibration is not None:
        data["calibration"] = calibration.to_dict()
    out = Path(path)
    out.write_text(
        "# sensorless fitted collision threshold (edit with care)\n"
        + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100),
        encoding="utf-8",
    )
    return out


def load_tuned(
    path: str | Path, robot: RobotModel | None = None
) -> tuple[Threshold, ObserverSettings]:
    """Read a file written by :func:`save_tuned` (or a bare threshold file: default settings).

    A saved calibration comes back as the threshold's ``calibration_``;
    ``robot`` is the nominal model, for a threshold that needs it (``payload``,
    see :func:`~sensorless.thresholds.load_threshold`).
    """
    data = read_yaml_mapping(path, "threshold")
    settings_data = data.pop("observer", None)
    calibration_data = data.pop("calibration", None)
    try:
        threshold = threshold_from_dict(
            data, Threshold, source=f"threshold file {path}", robot=robot
        )
        if calibration_data is not None:
            attach_calibration(threshold, Calibration.from_dict(calibration_data))
    except (InputValueError, InputTypeError) as exc:
        raise FileFormatError(f"{path}: {exc}") from None
    if settings_data is None:
        settings = ObserverSettings(kind=threshold.kind_, gain=float(threshold.gain_[0]))
    else:
        settings = ObserverSettings.from_dict(settings_data)
    return threshold, settings
