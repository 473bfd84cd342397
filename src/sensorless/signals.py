"""Data shared by observers, thresholds, detection and evaluation.

:class:`ObserverSignals` is what an observer produces over a run and what
thresholds are fitted on and applied to; :class:`Event` is one detected
collision. Units SI and radians; arrays have time along axis 0 and shape
``(n_samples, n_dof)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ._validation import FloatArray
from .exceptions import DimensionError

__all__ = ["Event", "ObserverSignals"]

_SERIES = ("residual", "model_torque", "friction", "sign", "velocity")


@dataclass(frozen=True, eq=False)
class ObserverSignals:
    """Signals of a collision observer over a run.

    Attributes
    ----------
    t : ndarray of shape (n_samples,)
        Time [s].
    residual : ndarray of shape (n_samples, n_dof)
        Residual r̂ (eq. 4.4) or r̂_s (eq. 4.9), or the estimate τ̂_c (eq. 3.16) [N m].
    model_torque : ndarray of shape (n_samples, n_dof)
        h(t) = K_I/(s+K_I)·(M q̈ + C q̇ + g) of the nominal model (eq. 4.26, 5.30) [N m].
    friction : ndarray of shape (n_samples, n_dof)
        K_I/(s+K_I)·τ̂_fr, the filtered nominal friction (eq. 5.29) [N m].
    sign : ndarray of shape (n_samples, n_dof)
        K_I/(s+K_I)·sign(q̇), the filtered velocity sign (eq. 5.39) [-].
    velocity : ndarray of shape (n_samples, n_dof)
        Joint velocity the observer used [rad/s].
    gain : ndarray of shape (n_dof,)
        Observer gain K_I [1/s].
    kind : str
        ``"motor"`` (r̂, motor torques), ``"joint"`` (r̂_s, joint torque sensors)
        or ``"acceleration"`` (τ̂_c).
    robot : str
        Name of the nominal model.
    position : ndarray of shape (n_samples, n_dof) or None
        Joint positions the observer used [rad] (needed by model-based thresholds).
    acceleration : ndarray of shape (n_samples, n_dof) or None
        Estimated joint accelerations [rad/s²] (acceleration-based estimate only).
    metadata : dict
        Anything else (log metadata, filter settings).
    fingerprint : str
        Fingerprint of the nominal model's dynamic parameters
        (:attr:`sensorless.robots.RobotModel.fingerprint`); empty when unknown.
    """

    t: FloatArray
    residual: FloatArray
    model_torque: FloatArray
    friction: FloatArray
    sign: FloatArray
    velocity: FloatArray
    gain: FloatArray
    kind: str = "motor"
    robot: str = ""
    position: FloatArray | None = None
    acceleration: FloatArray | None = None
    metadata: dict[str, Any] = field(default_factory=dict)
    fingerprint: str = ""

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        shape = np.shape(self.residual)
        if t.ndim != 1 or len(shape) != 2 or shape[0] != t.shape[0]:
            raise DimensionError(
                f"t must have shape (n_samples,) and residual (n_samples, n_dof); got "
                f"{t.shape} and {shape}"
            )
        for name in _SERIES:
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != shape:
                raise DimensionError(f"{name} must have shape {shape}; got {value.shape}")
            object.__setattr__(self, name, value)
        for name in ("position", "acceleration"):
            value = getattr(self, name)
            if value is not None:
                value = np.asarray(value, dtype=float)
                if value.shape != shape:
                    raise DimensionError(f"{name} must have shape {shape}; got {value.shape}")
                object.__setattr__(self, name, value)
        gain = np.broadcast_to(np.asarray(self.gain, dtype=float), (shape[1],)).copy()
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "gain", gain)

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.residual.shape[1])

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.residual.shape[0])

    @property
    def dt(self) -> float:
        """Median sample period [s]."""
        return float(np.median(np.diff(self.t))) if self.n_samples > 1 else float("nan")

    def to_pandas(self) -> pd.DataFrame:
        """Table with ``t`` and ``<signal>_<joint>`` columns (joints 1-based)."""
        columns: dict[str, FloatArray] = {"t": self.t}
        for name in _SERIES:
            values = getattr(self, name)
            for j in range(self.n_dof):
                columns[f"{name}_{j + 1}"] = values[:, j]
        return pd.DataFrame(columns)


@dataclass(frozen=True)
class Event:
    """A detected collision: an interval during which some residual left its bounds.

    Attributes
    ----------
    start, end : float
        First and last time [s] the residual was outside its bounds.
    joints : tuple of int
        Joints (1-based) that left their bounds during the event.
    peak : float
        Largest excursion beyond a bound during the event [N m] (residual minus
        upper bound, or lower bound minus residual).
    peak_residual : float
        Residual value [N m] at the joint and time of the peak excursion.
    method : str
        Name of the threshold family that detected it.
    level : str
        Reaction level from a two-level detector (``LevelledDetector``):
        ``"contact"`` or ``"collision"``; empty from a one-level detector.
    """

    start: float
    end: float
    joints: tuple[int, ...]
    peak: float
    peak_residual: float
    method: str = ""
    level: str = ""

    @property
    def duration(self) -> float:
        """end − start [s]."""
        return self.end - self.start
