"""Column names and units of the log format, shared by every reader and writer.

The table layout is described in the :mod:`sensorless.io` docstring. This
module holds the names, units and limits in one place, together with the
helpers that spell column names and values in error messages, so that the
validation, the :class:`~sensorless.io.Log` object and every file reader or
importer use the same ones.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

__all__ = [
    "ANGLE_GROUPS",
    "ANGLE_LIMIT",
    "COLUMN_PATTERN",
    "JOINT_GROUPS",
    "KNOWN_COLUMNS",
    "OPTIONAL_GROUPS",
    "UNITS",
    "abbreviate",
    "column_name",
    "show_value",
]

JOINT_GROUPS: tuple[str, ...] = (
    "q",
    "qd",
    "tau_m",
    "tau_j",
    "tau_ext",
    "q_true",
    "qd_true",
    "tau_c",
)
"""Per-joint column groups in table order; ``q`` is required, the others optional."""

OPTIONAL_GROUPS: tuple[str, ...] = JOINT_GROUPS[1:]
"""Per-joint column groups a log may leave out."""

UNITS: dict[str, str] = {
    "t": "s",
    "q": "rad",
    "qd": "rad/s",
    "tau_m": "N m",
    "tau_j": "N m",
    "tau_ext": "N m",
    "q_true": "rad",
    "qd_true": "rad/s",
    "tau_c": "N m",
    "collision_id": "1",
}
"""Unit of each column group (``"1"``: dimensionless)."""

ANGLE_LIMIT = 4.0 * math.pi
"""Largest |angle| [rad] accepted in ``q``/``q_true``; beyond it the log looks like degrees."""

ANGLE_GROUPS: tuple[str, ...] = ("q", "q_true")
"""Per-joint groups that hold angles [rad] and are checked against :data:`ANGLE_LIMIT`."""

COLUMN_PATTERN = re.compile(rf"({'|'.join(JOINT_GROUPS)})_([1-9][0-9]*)")
"""A per-joint column name: group ``[1]`` and 1-based joint number ``[2]``."""

KNOWN_COLUMNS = (
    "'t', 'q_<j>', 'qd_<j>', 'tau_m_<j>', 'tau_j_<j>', 'tau_ext_<j>', 'q_true_<j>', "
    "'qd_true_<j>', 'tau_c_<j>', 'collision_id' (joint numbers j = 1..n_dof)"
)
"""The valid column names, as error messages list them."""


def column_name(group: str, joint: int) -> str:
    """Column name of 1-based ``joint`` in ``group``, e.g. ``column_name("q", 1) == "q_1"``."""
    return f"{group}_{joint}"


def show_value(x: Any) -> str:
    """``repr`` of a value with numpy scalars shown as plain Python numbers."""
    return repr(x.item() if isinstance(x, np.generic) else x)


def abbreviate(names: list[Any], limit: int = 12) -> str:
    """List at most ``limit`` names so that messages stay readable for wide tables."""
    shown = ", ".join(repr(name) for name in names[:limit])
    more = f", ... ({len(names) - limit} more)" if len(names) > limit else ""
    return f"[{shown}{more}]"
