"""Layout of the compiled stream's two flat arrays: indices into ``model`` and ``buffers``.

:class:`~sensorless.monitor._fused.FusedStream` packs a monitor into these
positions and :mod:`sensorless.monitor._compiled` reads them (its docstring
describes the two arrays). Plain integers, no numba.
"""

from __future__ import annotations

# model header
DT, EARLY, GAP, SETTLE, RELEASE, MIN_DURATION, HOLD, JOINT = range(8)
FRICTION, FAMILY, EXTRA, N_SECTIONS, N_EDGES, CONST_AT, TABLE_AT = range(8, 15)
ADAPT_AT, ADAPT_STATE, ADAPT_SIZE, GUARD = range(15, 19)  # drift adaptation; ADAPT_AT 0: none
HEADER = 19
# const columns after the recursion's 28; FRICTION_PARAMETERS has five
CENTRE, HALF_RANGE, SPEED_LIMIT, TORQUE_LIMIT, POLE, WEIGHT, FRICTION_PARAMETERS = range(28, 35)
MONITORED, WIDTH, GAMMA, COEFFICIENT, BIN_POLE, BIN_WEIGHT = range(39, 45)
VISITED_LOW, VISITED_HIGH, N_CONST = 45, 46, 47
# state rows: the ObserverState fields, the threshold's filter state, q̂̇, p/Cᵀq̇/g, sections
MOMENTUM, COR_GRAVITY, FRICTION_TORQUE, SIGN, TORQUE = range(5)
RESIDUAL, MODEL_TORQUE, FILTERED_FRICTION, FILTERED_SIGN = range(5, 9)
BIN_STATE, VELOCITY, TERMS, SECTIONS = 9, 10, 11, 14
# flags; row 2 holds a closed event in the OPEN... fields
HAS_STREAM, START, T_LAST, FLOOR, PENDING, LATCHED, INSIDE_SINCE, HAS_DETECTOR = range(8)
QUIET_FROM = 8  # the drift adapter may learn from this time on [s]
OUTSIDE, OPEN, OPEN_START, OPEN_END, OPEN_JOINTS, OPEN_PEAK, OPEN_PEAK_RESIDUAL = range(9, 16)
N_FLAGS = 16
# threshold families (friction kinds: sensorless.friction._kinds)
CONSTANT, TIME_VARIANT, HYSTERETIC_FORM, VELOCITY_BINS = range(4)
