"""Built-in robots. Every number below cites its source in the builder's docstring."""

from __future__ import annotations

import importlib.metadata
from collections.abc import Callable
from functools import cache
from pathlib import Path

import numpy as np

from ..exceptions import ModelError
from ..friction import CoulombViscous, Sigmoid
from .lwr4 import lwr4
from .model import LinkInertia, MotorData, RobotModel

__all__ = [
    "BUILTIN",
    "lwr4",
    "panda",
    "panda_gaz",
    "panda_urdf_path",
    "planar2",
    "puma560",
    "ur5",
    "ur10",
    "ur_urdf_path",
]

_HALF_PI = np.pi / 2


def puma560() -> RobotModel:
    """Unimation PUMA 560, the classic standard-DH model.

    Numbers of Corke & Armstrong-Hélouvry, "A search for consensus among model
    parameters reported for the PUMA 560 robot", ICRA 1994 (collecting
    Armstrong, Khatib & Burdick, ICRA 1986), as published in the Robotics
    Toolbox for Python (``roboticstoolbox/models/DH/Puma560.py``): standard DH
    with the toolbox's joint-angle convention (q = 0 is the "L" pose, Paul's
    sign of α), d1 = 0.672 m, masses, centres of mass and principal
    inertias about the centre of mass (products of inertia zero), rotor
    inertias Jm and gear ratios G (armature Jm·G²), motor-side viscous B and
    asymmetric Coulomb Tc referred to the joint side as B·G² and Tc·|G|.
    Joint limits of Wang & Chen (IEEE Trans. RA 7(4), 1991) as in the toolbox.
    Link 1 mass is 0 (Armstrong found none; it does not enter the dynamics).
    """
    deg = np.pi / 180
    table = [
        {"d": 0.672, "a": 0.0, "alpha": _HALF_PI, "theta": 0.0},
        {"d": 0.0, "a": 0.4318, "alpha": 0.0, "theta": 0.0},
        {"d": 0.15005, "a": 0.0203, "alpha": -_HALF_PI, "theta": 0.0},
        {"d": 0.4318, "a": 0.0, "alpha": _HALF_PI, "theta": 0.0},
        {"d": 0.0, "a": 0.0, "alpha": -_HALF_PI, "theta": 0.0},
        {"d": 0.0, "a": 0.0, "alpha": 0.0, "theta": 0.0},
    ]
    masses = [0.0, 17.4, 4.8, 0.82, 0.34, 0.09]
    coms = [
        (0.0, 0.0, 0.0),
        (-0.3638, 0.006, 0.2275),
        (-0.0203, -0.0141, 0.070),
        (0.0, 0.019, 0.0),
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 0.032),
    ]
    principal = [
        (0.0, 0.35, 0.0),
        (0.13, 0.524, 0.539),
        (0.066, 0.086, 0.0125),
        (1.8e-3, 1.3e-3, 1.8e-3),
        (0.3e-3, 0.4e-3, 0.3e-3),
        (0.15e-3, 0.15e-3, 0.04e-3),
    ]
    # The moments of links 1 and 3 break the triangle inequality of a rigid body
    # (link 1: one moment only; link 3: 0.086 > 0.066 + 0.0125): published as is.
    links = [
        LinkInertia(m, c, np.diag(i), f"link{k}", rigid_body=k not in (1, 3))
        for k, (m, c, i) in enumerate(zip(masses, coms, principal, strict=True), start=1)
    ]
    gear = np.array([-62.6111, 107.815, -53.7063, 76.0364, 71.923, 76.686])
    motors = MotorData(rotor_inertia=[200e-6] * 3 + [33e-6] * 3, gear_ratio=gear)
    viscous_motor = np.array([1.48e-3, 0.817e-3, 1.38e-3, 71.2e-6, 82.6e-6, 36.7e-6])
    coulomb_pos = np.array([0.395, 0.126, 0.132, 11.2e-3, 9.26e-3, 3.96e-3])
    coulomb_neg = np.array([-0.435, -0.071, -0.105, -16.9e-3, -14.5e-3, -10.5e-3])
    friction = CoulombViscous(
        c_pos=coulomb_pos * np.abs(gear),
        c_neg=coulomb_neg * np.abs(gear),
        fv=viscous_motor * gear**2,
    )
    lower = np.array([-160, -45, -225, -110, -100, -266]) * deg
    upper = np.array([160, 225, 45, 170, 100, 266]) * deg
    return RobotModel.from_dh(
        table,
        links,
        motors,
        friction=friction,
        name="puma560",
        description="PUMA 560, Corke & Armstrong-Helouvry 1994 (Armstrong, Khatib, Burdick 1986)",
        position_limits=(lower, upper),
    )


# Franka Panda limits, from the URDF of example-robot-data (franka_ros description).
_PANDA_LOWER = [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]
_PANDA_UPPER = [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]
_PANDA_VELOCITY = [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]
_PANDA_EFFORT = [87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0]
_PANDA_JOINTS = [f"panda_joint{i}" for i in range(1, 8)]


def _example_robot_data_file(suffix: str, what: str) -> Path:
    """Path of the file of ``example-robot-data`` whose path ends with ``suffix``."""
    try:
        files = importlib.metadata.files("example-robot-data") or []
    except importlib.metadata.PackageNotFoundError:
        raise ModelError(
            f"the {what} URDF comes from the package example-robot-data; install it "
            "(pip install example-robot-data)"
        ) from None
    for entry in files:
        if str(entry).endswith(suffix):
            return Path(str(entry.locate()))
    raise ModelError(f"example-robot-data is installed but ships no {suffix}")


@cache
def panda_urdf_path() -> Path:
    """Path of ``panda.urdf`` shipped by the PyPI package ``example-robot-data``."""
    return _example_robot_data_file("panda_description/urdf/panda.urdf", "Panda")


@cache
def ur_urdf_path(model: str) -> Path:
    """Path of ``<model>_robot.urdf`` (``"ur5"``, ``"ur10"``) shipped by ``example-robot-data``."""
    return _example_robot_data_file(f"ur_description/urdf/{model}_robot.urdf", model.upper())


def panda() -> RobotModel:
    """Franka Emika Panda, the nominal model of its URDF (arm joints only).

    Source: ``panda_description/urdf/panda.urdf`` of the PyPI package
    ``example-robot-data`` (generated from franka_ros). The tree is cut at the
    flange ``panda_link8``: the hand and fingers are left out, so that the model
    describes the same bare arm as :func:`panda_gaz`. No friction and no
    armature: the URDF has neither (its ``<dynamics>`` tags are not a friction
    model). Joint limits are the URDF's.
    """
    return RobotModel.from_urdf(
        panda_urdf_path(),
        _PANDA_JOINTS,
        tip="panda_link8",
        name="panda",
        description="Franka Panda, URDF of example-robot-data, cut at the flange",
    )


def panda_gaz() -> RobotModel:
    """Franka Emika Panda as identified by Gaz, Cognetti, Oliva, Robuffo Giordano
    and De Luca, "Dynamic identification of the Franka Emika Panda robot with
    retrieval of feasible parameters using penalty-based optimization", IEEE
    RA-L 4(4), 2019.

    Numbers from the authors' repository ``marcocognetti/FrankaEmikaPandaDynModel``
    (``Load_Franka_DH.m``, ``get_FrictionTorque.m``, ``franka_model.h``) and the
    paper's Tables VIII–IX: Craig modified DH, masses, centres of mass and
    inertias about the centre of mass in link axes (xx, xy, xz, yy, yz, zz, the
    order confirmed by the same values in the franka_ros URDF), and the
    per-joint sigmoid friction φ1/(1 + e^{−φ2(q̇+φ3)}) − φ1/(1 + e^{−φ2 φ3}).
    Link-1 Ixx, Iyy do not affect the dynamics of a fixed base. No armature
    (the identified model lumps it into the links). Limits as :func:`panda`.
    This is the "true" robot of the benchmarks, against the nominal :func:`panda`.
    """
    alpha = [0.0, -_HALF_PI, _HALF_PI, _HALF_PI, -_HALF_PI, _HALF_PI, _HALF_PI]
    a = [0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]
    d = [0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]
    table = [
        {"alpha": al, "a": ai, "theta": 0.0, "d": di}
        for al, ai, di in zip(alpha, a, d, strict=True)
    ]
    masses = [4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522]
    coms = [
        (3.875e-3, 2.081e-3, 0.0),
        (-3.141e-3, -2.872e-2, 3.495e-3),
        (2.7518e-2, 3.9252e-2, -6.6502e-2),
        (-5.317e-2, 1.04419e-1, 2.7454e-2),
        (-1.1953e-2, 4.1065e-2, -3.8437e-2),
        (6.0149e-2, -1.4117e-2, -1.0517e-2),
        (1.0517e-2, -4.252e-3, 6.1597e-2),
    ]
    inertias = [
        (0.70337, -1.39e-4, 6.772e-3, 0.70661, 1.9169e-2, 9.117e-3),
        (7.962e-3, -3.925e-3, 1.0254e-2, 2.811e-2, 7.04e-4, 2.5995e-2),
        (3.7242e-2, -4.761e-3, -1.1396e-2, 3.6155e-2, -1.2805e-2, 1.083e-2),
        (2.5853e-2, 7.796e-3, -1.332e-3, 1.9552e-2, 8.641e-3, 2.8323e-2),
        (3.5549e-2, -2.117e-3, -4.037e-3, 2.9474e-2, 2.29e-4, 8.627e-3),
        (1.964e-3, 1.09e-4, -1.158e-3, 4.354e-3, 3.41e-4, 5.433e-3),
        (1.2516e-2, -4.28e-4, -1.196e-3, 1.0027e-2, -7.41e-4, 4.815e-3),
    ]
    links = [LinkInertia(m, c, i) for m, c, i in zip(masses, coms, inertias, strict=True)]
    friction = Sigmoid(
        phi1=[0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489],
        phi2=[5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336],
        phi3=[0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526],
    )
    return RobotModel.from_mdh(
        table,
        links,
        friction=friction,
        name="panda_gaz",
        description="Franka Panda identified by Gaz et al., RA-L 2019",
        position_limits=(_PANDA_LOWER, _PANDA_UPPER),
        velocity_limits=_PANDA_VELOCITY,
        effort_limits=_PANDA_EFFORT,
    )


def planar2(
    lengths: tuple[float, float] = (1.0, 1.0),
    masses: tuple[float, float] = (1.0, 1.0),
    com_ratio: float = 0.5,
) -> RobotModel:
    """Two-link planar arm in a vertical plane, with textbook closed-form dynamics.

    Link *i* is a uniform slender rod of length l_i [m] and mass m_i [kg]: its
    centre of mass lies at ``com_ratio``·l_i along the link and its inertia
    about the centre of mass is m_i l_i²/12 about the joint axis (Spong,
    Hutchinson & Vidyasagar, *Robot Modeling and Control*, §7.4). The joints
    turn about the base z axis; gravity is −9.81 m/s² along the base y axis, so
    q = 0 is the arm stretched horizontally.
    """
    l1 = lengths[0]
    table = [
        {"alpha": 0.0, "a": 0.0, "theta": 0.0, "d": 0.0},
        {"alpha": 0.0, "a": l1, "theta": 0.0, "d": 0.0},
    ]
    links = [
        LinkInertia(
            m, (com_ratio * length, 0.0, 0.0), np.diag([0.0, 1.0, 1.0]) * m * length**2 / 12
        )
        for m, length in zip(masses, lengths, strict=True)
    ]
    return RobotModel.from_mdh(
        table,
        links,
        gravity=(0.0, -9.81, 0.0),
        name="planar2",
        description="two-link planar arm of uniform rods (Spong et al. §7.4)",
    )


# Joint names of the Universal Robots URDFs (ur_description), base to wrist 3.
_UR_JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]


def _ur_from_urdf(model: str) -> RobotModel:
    return RobotModel.from_urdf(
        ur_urdf_path(model),
        _UR_JOINTS,
        tip="tool0",
        name=model,
        description=f"Universal Robots {model.upper()}, URDF of example-robot-data, cut at "
        "the flange",
    )


def ur10() -> RobotModel:
    """Universal Robots UR10 (CB-series), the nominal model of its URDF.

    Source: ``ur_description/urdf/ur10_robot.urdf`` of the PyPI package
    ``example-robot-data`` (from ROS-Industrial's ``universal_robot``
    description: UR's published link masses, with the centres of mass and
    inertias of uniform cylinders along the links). This is the arm of the real
    recordings in ``shared/data/ur10-ext_observer``. The arm is cut at the
    flange ``tool0``. No friction and no armature (the URDF has neither).
    Joint limits are the URDF's.

    **Current-to-torque convention.** A UR joint reports its motor current
    [A] (RTDE ``actual_current``), not a torque. The joint torque [N m] is
    taken as ``gain · current``, one gain [N m/A] per joint lumping the
    motor's torque constant and the gear ratio, in the joint directions of
    this model: a positive current drives its joint towards positive q. The
    importers apply the gains and write the log's ``tau_m`` in N m; the
    UR10's are ``sensorless.io.UR_CURRENT_GAINS["ur10"]`` = (10.0, 10.6956,
    8.4566, 9.0029, 9.48, 10.1232) N m/A, from the MIT-licensed project
    ext_observer (S. Mikhel 2020, ``ur/test.cpp``). On its recording of the
    standing arm (``ur-static.csv``), the mean of ``gain · current`` of the
    shoulder and the elbow matches this model's gravity torque g(q) in sign
    and to within 13 % of the largest entry of g.
    """
    return _ur_from_urdf("ur10")


def ur5() -> RobotModel:
    """Universal Robots UR5 (CB-series), the nominal model of its URDF.

    Source: ``ur_description/urdf/ur5_robot.urdf`` of the PyPI package
    ``example-robot-data`` (from ROS-Industrial's ``universal_robot``
    description, as :func:`ur10`), cut at the flange ``tool0``, without
    friction or armature; joint limits are the URDF's. The current-to-torque
    convention is that of :func:`ur10`, but no published gains are known for
    this arm: give them to the importers (``gains=``).
    """
    return _ur_from_urdf("ur5")


BUILTIN: dict[str, Callable[..., RobotModel]] = {
    "lwr4": lwr4,
    "puma560": puma560,
    "panda": panda,
    "panda_gaz": panda_gaz,
    "planar2": planar2,
    "ur10": ur10,
    "ur5": ur5,
}
