"""The log format that every tool of :mod:`sensorless` reads and writes.

A log is one simulated or recorded robot run: a table with time along axis 0,
SI units and angles in radians. Its columns are (joint numbers ``j`` start at
1 and run to ``n_dof``):

=================  ==========  ====================================================
column             unit        meaning
=================  ==========  ====================================================
``t``              s           time stamp, strictly increasing
``q_j``            rad         measured joint position (required)
``qd_j``           rad/s       measured joint velocity, as the robot reports it (optional)
``tau_m_j``        N m         motor / commanded joint torque (optional)
``tau_j_j``        N m         joint-torque-sensor torque (optional)
``tau_ext_j``      N m         the robot vendor's own external-torque estimate, kept as a
                               baseline to compare with (optional)
``q_true_j``       rad         ground-truth joint position (optional)
``qd_true_j``      rad/s       ground-truth joint velocity (optional)
``tau_c_j``        N m         ground-truth external joint torque (optional)
``collision_id``   1           integer label, 0 = no collision (optional)
=================  ==========  ====================================================

An optional group is either present for every joint or absent. Any other
column is an error, so that a typo such as ``tau_M_1`` cannot be silently
ignored. Rows are counted from 0 in error messages (the position in the
table, as ``df.iloc``; the CSV header is not a row).

On disk a log is a Parquet or CSV table plus a JSON sidecar
``<path>.meta.json`` with ``n_dof``, the column list, the units, the sample
rate [Hz] and the user metadata. Both formats keep float64 values exactly.

:func:`validate_table` is the single validation routine: :func:`read_log`,
:meth:`Log.from_pandas` and the :class:`Log` constructor all go through it,
so a :class:`Log` cannot hold an inconsistent run. Irregular time stamps are
an error on read; :func:`resample` is the explicit way to put a jittery log
on a regular grid, and it refuses to interpolate across a gap (a step of more
than a few periods) unless asked: :func:`split_at_gaps` cuts a log into the
regular stretches between its gaps instead.

Recordings of real robots in other formats come in through the importers of
:mod:`sensorless.io.importers` (:func:`import_log` and one function per
format: a column-mapping CSV described by a YAML spec, Franka, UR RTDE and
ROS 2 bags), which return the segments of a recording as logs and record
where each value came from in the metadata.

The package keeps one concern per module: :mod:`~sensorless.io.columns`
(column names, units and limits), :mod:`~sensorless.io.validate`
(:func:`validate_table`), :mod:`~sensorless.io.log` (:class:`Log`),
:mod:`~sensorless.io.timebase` (:func:`resample`, :func:`split_at_gaps`),
:mod:`~sensorless.io.files` (the Parquet/CSV files and their sidecar) and
:mod:`~sensorless.io.importers` (foreign formats). A reader of another file
format builds a :class:`Log` (or a table with the column names of
:mod:`~sensorless.io.columns` for :meth:`Log.from_pandas`), so that it goes
through the same validation.

>>> import numpy as np
>>> t = np.arange(5) * 0.001
>>> log = Log(t=t, q=np.zeros((5, 2)), tau_m=np.ones((5, 2)))
>>> list(log.to_pandas().columns)
['t', 'q_1', 'q_2', 'tau_m_1', 'tau_m_2']
>>> log.n_dof, log.n_samples, round(log.dt, 9)
(2, 5, 0.001)
"""

from __future__ import annotations

from .columns import ANGLE_LIMIT, JOINT_GROUPS, UNITS
from .files import FORMATS, read_log, sidecar_path, write_log
from .importers import (
    IMPORT_FORMATS,
    UR_CURRENT_GAINS,
    CsvSpec,
    import_csv,
    import_franka,
    import_log,
    import_ros2,
    import_ur_rtde,
    load_csv_spec,
)
from .log import Log
from .timebase import DEFAULT_MAX_GAP, resample, split_at_gaps
from .validate import validate_table

__all__ = [
    "ANGLE_LIMIT",
    "DEFAULT_MAX_GAP",
    "FORMATS",
    "IMPORT_FORMATS",
    "JOINT_GROUPS",
    "UNITS",
    "UR_CURRENT_GAINS",
    "CsvSpec",
    "Log",
    "import_csv",
    "import_franka",
    "import_log",
    "import_ros2",
    "import_ur_rtde",
    "load_csv_spec",
    "read_log",
    "resample",
    "sidecar_path",
    "split_at_gaps",
    "validate_table",
    "write_log",
]
