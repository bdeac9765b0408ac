"""Configuration data of a joint vector: ABB ``confdata`` and KUKA ``Status`` / ``Turn``.

Both controllers reach a Cartesian target in one of up to eight arm configurations (and several
turns of the wrist axes); the program names the one the route's joint vector is in.

Arm flags (:func:`arm_flags`, one row per joint vector, from the joint values and the robot):

* ``overhead``: the wrist centre lies behind axis 1, i.e. its x in the A1 frame is negative
  (KUKA Status bit 0, "overhead area"; ABB ``cfx``: wrist centre "behind" axis 1).
* ``elbow``: axis 3 at or beyond ``phi``, the angle where A2, A3 and the wrist centre are in line
  (KUKA Status bit 1, ``A3 >= phi``; the usual elbow-up arm of a floor robot);
  ``phi = -atan2(a2, c3)`` in OPW terms.
* ``wrist``: KUKA Status bit 2, set for ``-180 <= A5 < 0`` or ``A5 >= 180`` degrees (ABB
  ``cfx``: axis 5 negative).

KUKA ``Turn``: bit ``i`` set when axis ``i + 1`` is negative. ABB ``confdata [cf1, cf4, cf6,
cfx]``: ``cf1``, ``cf4``, ``cf6`` are the quadrants ``floor(angle / 90 deg)`` of axes 1, 4 and 6
(-1 for -90..0 deg), and ``cfx = 4 overhead + 2 (not elbow) + wrist`` (RAPID reference manual,
``confdata``: wrist centre relative to axis 1, to the lower arm, sign of axis 5).

Named deviation: both controllers define these on their own axis directions; weldplan writes
the joint values as the URDF gives them (for the shared KUKA the URDF's angles are KUKA's own
A1-A6, so Status/Turn are KUKA's; a RAPID program for it describes the same joint values in
ABB's bit layout).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)


def elbow_phi(opw: Any) -> float:
    """rad: the joint value of axis 3 where A2, A3 and the wrist centre are in line: OPW
    ``theta3 = -atan2(a2, c3)`` turned into the robot's joint value ``sign3 * (theta3 +
    offset3)`` (``opw``: :class:`~weldplan.robot.model.OPWParams`)."""
    return float(opw.signs[2] * (-np.arctan2(opw.a2, opw.c3) + opw.offsets[2]))


def arm_flags(robot: Any, q: ArrayLike) -> NDArray[np.bool_]:
    """``(n, 3) bool``: ``overhead``, ``elbow``, ``wrist`` of joint vectors ``q (n, 6)`` rad.

    ``overhead`` comes from the URDF chain (:meth:`~weldplan.robot.model.Robot.link_frames`: the
    wrist centre, the origin of the fourth joint's child link, expressed in the first joint's
    child link, has a negative x), ``elbow`` from :func:`elbow_phi`, ``wrist`` from A5.
    """
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    F = robot.link_frames(Q)  # (n, 7, 4, 4)
    wc = F[:, 4, :3, 3]
    a1 = F[:, 1]
    x_a1 = np.einsum("ni,ni->n", a1[:, :3, 0], wc - a1[:, :3, 3])
    overhead = x_a1 < 0
    elbow = Q[:, 2] >= elbow_phi(robot.opw)
    a5 = np.degrees(Q[:, 4])
    wrist = ((a5 >= -180) & (a5 < 0)) | (a5 >= 180)
    return np.column_stack([overhead, elbow, wrist])


def kuka_status(flags: ArrayLike) -> NDArray[np.int64]:
    """``(n,)`` KUKA ``Status``: bit 0 overhead, bit 1 elbow (``A3 >= phi``), bit 2 wrist."""
    F = np.asarray(flags, dtype=bool).reshape(-1, 3)
    return (F[:, 0] * 1 + F[:, 1] * 2 + F[:, 2] * 4).astype(np.int64)


def kuka_turn(q: ArrayLike) -> NDArray[np.int64]:
    """``(n,)`` KUKA ``Turn``: bit ``i`` set when axis ``i + 1`` is negative."""
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    return ((Q < 0) * (1 << np.arange(6))).sum(axis=1).astype(np.int64)


def abb_confdata(q: ArrayLike, flags: ArrayLike) -> NDArray[np.int64]:
    """``(n, 4)`` ABB ``confdata [cf1, cf4, cf6, cfx]`` (module docstring)."""
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    F = np.asarray(flags, dtype=bool).reshape(-1, 3)
    quad = np.floor(np.degrees(Q[:, [0, 3, 5]]) / 90.0).astype(np.int64)
    cfx = 4 * F[:, 0] + 2 * (~F[:, 1]) + F[:, 2]
    return np.column_stack([quad, cfx]).astype(np.int64)


def quadrant_interval(cf: int) -> tuple[float, float]:
    """rad: the half-open interval ``[lo, hi)`` of axis angles in ABB quadrant ``cf``."""
    return float(np.radians(90.0 * cf)), float(np.radians(90.0 * (cf + 1)))
