"""The result of friction identification from a sweep log: maps and fitted models per joint."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from ..exceptions import InputValueError
from ._friction_models import FrictionFit
from ._friction_plots import plot_friction_identification

__all__ = ["FrictionIdentification"]

#: Units of the map columns and of every fitted parameter, for ``to_dict``.
_UNITS = {
    "velocity": "rad/s",
    "torque": "N m",
    "torque_std": "N m",
    "c_pos": "N m",
    "c_neg": "N m",
    "fv": "N m s/rad",
    "fc": "N m",
    "fs": "N m",
    "vs": "rad/s",
    "rms": "N m",
    "settle": "s",
    "rest_velocity": "rad/s",
    "max_acceleration": "rad/s^2",
    "window": "s",
}


@dataclass(frozen=True)
class FrictionIdentification:
    """Friction maps and fitted models of the joints swept in one log.

    Returned by :func:`~sensorless.identification.friction.identify_friction`.

    Attributes
    ----------
    maps : DataFrame
        Steady-state maps of all identified joints: columns ``joint``
        (numbered from 1), ``velocity`` [rad/s], ``torque`` [N m],
        ``torque_std`` [N m] and ``n_samples``, as :func:`steady_state_map`.
    fits : dict of int to dict of str to FrictionFit
        ``fits[joint][model]`` for each identified joint and requested model
        (``"coulomb"``, ``"coulomb_viscous"``, ``"stribeck"``).
    torque : {"motor", "joint"}
        Torque the friction was computed from: ``tau_m - g(q)`` (eq. (2.6)
        at constant velocity) or ``tau_j - g(q)`` (eq. (2.10), link side).
    settle : float
        Transient dropped at the start of each plateau [s].
    tolerance : float
        Relative velocity tolerance of a plateau [-].
    rest_velocity : float
        Speed [rad/s] under which a joint counted as resting.
    max_acceleration : float
        Largest acceleration [rad/s²] of a steady-state sample.
    window : float
        Length of the Savitzky-Golay velocity window [s].
    """

    maps: pd.DataFrame
    fits: dict[int, dict[str, FrictionFit]]
    torque: str
    settle: float
    tolerance: float
    rest_velocity: float
    max_acceleration: float
    window: float

    @property
    def joints(self) -> tuple[int, ...]:
        """Identified joints, numbered from 1, in increasing order."""
        return tuple(sorted(self.fits))

    def joint_map(self, joint: int) -> pd.DataFrame:
        """Steady-state map of one identified joint (columns of :func:`steady_state_map`)."""
        if joint not in self.fits:
            raise InputValueError(
                f"joint {joint!r} was not identified; identified joints: {list(self.joints)}"
            )
        rows = self.maps[self.maps["joint"] == joint].drop(columns="joint")
        return rows.reset_index(drop=True)

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint and model: ``joint``, ``model``, the parameters, ``rms``.

        Parameters a model does not have are NaN; ``n_plateaus`` counts the
        points of the joint's map.
        """
        counts = self.maps.groupby("joint").size()
        rows = [
            {
                "joint": joint,
                "model": name,
                **fit.parameters,
                "rms": fit.rms,
                "n_plateaus": int(counts[joint]),
            }
            for joint in self.joints
            for name, fit in self.fits[joint].items()
        ]
        parameters = dict.fromkeys(
            key for row in rows for key in row if key not in ("joint", "model", "rms", "n_plateaus")
        )
        return pd.DataFrame(rows, columns=["joint", "model", *parameters, "rms", "n_plateaus"])

    def to_dict(self) -> dict[str, Any]:
        """Plain Python values (lists, floats, str) for a YAML or JSON file, SI units.

        Returns
        -------
        dict
            ``torque``, ``settle``, ``tolerance``, ``rest_velocity``,
            ``max_acceleration``, ``window``, a ``units`` entry naming the unit of every number, and
            ``joints``: a list with, per joint, its number, its map (lists
            ``velocity``, ``torque``, ``torque_std``, ``n_samples``) and its
            fitted ``models`` (parameters and ``rms`` by model name).
        """
        joints = []
        for joint in self.joints:
            table = self.joint_map(joint)
            joints.append(
                {
                    "joint": int(joint),
                    "map": {
                        column: [float(v) for v in table[column]]
                        for column in ("velocity", "torque", "torque_std")
                    }
                    | {"n_samples": [int(v) for v in table["n_samples"]]},
                    "models": {
                        name: {**{k: float(v) for k, v in fit.parameters.items()}, "rms": fit.rms}
                        for name, fit in self.fits[joint].items()
                    },
                }
            )
        return {
            "torque": self.torque,
            "settle": float(self.settle),
            "tolerance": float(self.tolerance),
            "rest_velocity": float(self.rest_velocity),
            "max_acceleration": float(self.max_acceleration),
            "window": float(self.window),
            "units": dict(_UNITS),
            "joints": joints,
        }

    def plot(self) -> Figure:
        """Friction map and fitted curves, one panel per joint (Fig. 2.2).

        Returns
        -------
        figure : matplotlib.figure.Figure
        """
        return plot_friction_identification(self)
