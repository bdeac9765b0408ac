"""Checked linear (Cartesian) moves: where a program may say ``MoveL`` / ``LIN``.

A controller executes ``MoveL`` / ``LIN`` by moving the TCP on the straight line between the two
targets (position interpolated, orientation slerped), solving the inverse kinematics on the way
in the configuration it started in. The robot route (:mod:`weldplan.robot.route.plan`) was verified
along the *joint-space* line between rows, a different path. :func:`check_linear_moves` checks
the Cartesian move itself:

1. samples along the line at most :data:`LIN_STEP_MM` mm and :data:`LIN_STEP_DEG` degrees
   apart (both ends included);
2. IK of every sample (:meth:`~weldplan.robot.model.Robot.ik_all`) on the start row's branch,
   each joint unwrapped to the turn nearest the previous sample: the configuration the
   controller follows;
3. refused (``reason``): a sample the branch cannot reach (``no_ik``), a wrist closer to its
   singularity than ``singular_deg`` (``singular``), a joint outside its limits
   (``joint_limit``), a joint step between samples over :data:`MAX_STEP_RAD` (``flip``), an end
   configuration other than the target's (``turn``: the controller would arrive in another
   configuration than the one programmed), and a collision of the robot's links plus the tool
   along the sampled joint path (``collision``: :class:`weldplan.robot.collision.RobotCollision`,
   robotcol's checker, its proof of each joint-space motion between samples).

Named deviation: between two samples the collision proof covers the joint-space interpolation
of the samples, not the controller's exact Cartesian path; at 5 mm / 2 deg spacing the two
differ by a fraction of a millimetre (:func:`weldplan.robot.program.joint_line_deviation`
measures it for whole moves), below the checker's 1 mm collision margin.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation, Slerp

log = logging.getLogger(__name__)

#: mm and degrees: the largest distance and turn between two samples of a linear move
LIN_STEP_MM = 5.0
LIN_STEP_DEG = 2.0
#: rad: the largest joint step between two samples: more is a flip (a configuration change the
#: controller would not make on a LIN, or a near-singular swing)
MAX_STEP_RAD = 0.2
#: rad: the end of the sampled path must be the target's joint vector within this
END_TOL_RAD = 1e-6

OK = "ok"


@dataclass(frozen=True)
class LinearChecks:
    """What :func:`check_linear_moves` found, per move.

    Attributes
    ----------
    ok
        ``(m,) bool``: the linear move is verified.
    reason
        ``(m,)``: :data:`OK` or why not (module docstring).
    samples
        ``(m,) int``: samples checked per move.
    """

    ok: NDArray[np.bool_]
    reason: tuple[str, ...]
    samples: NDArray[np.int64]


def line_poses(Ta: NDArray, Tb: NDArray, step_mm: float, step_deg: float) -> NDArray:
    """``(s, 4, 4)``: poses from ``Ta`` to ``Tb`` (both included) on the straight line, the
    orientation slerped, at most ``step_mm`` / ``step_deg`` apart."""
    d = float(np.linalg.norm(Tb[:3, 3] - Ta[:3, 3]))
    R = Rotation.from_matrix(np.stack([Ta[:3, :3], Tb[:3, :3]]))
    ang = math.degrees((R[0].inv() * R[1]).magnitude())
    n = max(1, math.ceil(max(d / step_mm, ang / step_deg)))
    f = np.linspace(0.0, 1.0, n + 1)
    out = np.tile(np.eye(4), (n + 1, 1, 1))
    out[:, :3, :3] = Slerp([0.0, 1.0], R)(f).as_matrix()
    out[:, :3, 3] = Ta[:3, 3] + f[:, None] * (Tb[:3, 3] - Ta[:3, 3])
    return out


def _follow(robot: Any, T_fl: NDArray, qa: NDArray, b: int, singular: float) -> tuple[Any, str]:
    """The joint path along flange poses ``T_fl (s, 4, 4)`` on branch ``b`` from ``qa``."""
    br = robot.ik_all(T_fl)
    if not br.exists[:, b].all():
        return None, "no_ik"
    with np.errstate(invalid="ignore"):
        if not (np.nan_to_num(br.wrist[:, b]) >= singular).all():
            return None, "singular"
    Q = np.unwrap(np.vstack([qa[None], br.q[:, b]]), axis=0)[1:]
    if np.abs(Q[0] - qa).max() > END_TOL_RAD:
        return None, "turn"
    if not robot.in_limits(Q).all():
        return None, "joint_limit"
    if len(Q) > 1 and np.abs(np.diff(Q, axis=0)).max() > MAX_STEP_RAD:
        return None, "flip"
    return Q, OK


def check_linear_moves(
    robot: Any,
    flange_tcp: ArrayLike,
    qa: ArrayLike,
    qb: ArrayLike,
    *,
    checker: Any = None,
    singular_deg: float | None = None,
    step_mm: float = LIN_STEP_MM,
    step_deg: float = LIN_STEP_DEG,
) -> LinearChecks:
    """Check the linear moves from ``qa (m, 6)`` to ``qb (m, 6)`` rad (module docstring).

    Parameters
    ----------
    robot
        The placed :class:`~weldplan.robot.model.Robot`.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    checker
        A :class:`~weldplan.robot.collision.RobotCollision` (robot + tool against the part);
        ``None`` fails every move that is kinematically fine with ``"collision"`` (no move is
        emitted linear unchecked).
    singular_deg
        Default :data:`weldplan.robot.placement.DEFAULT_SINGULAR_DEG`.
    """
    from weldplan.robot.placement.reach import DEFAULT_SINGULAR_DEG

    sd = DEFAULT_SINGULAR_DEG if singular_deg is None else float(singular_deg)
    singular = math.sin(math.radians(sd))
    F = np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4)
    A = np.asarray(qa, dtype=np.float64).reshape(-1, 6)
    B = np.asarray(qb, dtype=np.float64).reshape(-1, 6)
    m = len(A)
    if m == 0:
        return LinearChecks(np.zeros(0, bool), (), np.zeros(0, np.int64))
    Ta, Tb = robot.fk(A) @ F, robot.fk(B) @ F
    branch = robot.branch_of(A)
    Finv = np.linalg.inv(F)
    reasons: list[str] = []
    samples = np.zeros(m, dtype=np.int64)
    paths: dict[int, NDArray] = {}  # the moves whose kinematics hold: their sampled joint path
    for i in range(m):
        T = line_poses(Ta[i], Tb[i], step_mm, step_deg) @ Finv
        samples[i] = len(T)
        Q, why = _follow(robot, T, A[i], int(branch[i]), singular)
        if Q is not None and np.abs(Q[-1] - B[i]).max() > END_TOL_RAD:
            Q, why = None, "turn"
        if Q is not None:
            paths[i] = Q
        reasons.append(why)
    for i in _blocked(checker, paths):
        reasons[i] = "collision"
    ok = np.array([why == OK for why in reasons], dtype=bool)
    log.info("linear moves: %d of %d verified", int(ok.sum()), m)
    return LinearChecks(ok, tuple(reasons), samples)


def _blocked(checker: Any, paths: dict[int, NDArray]) -> set[int]:
    """The moves of ``paths`` (move -> ``(s, 6)`` rad sampled joint path) whose path the
    checker does not prove free (all of them without a checker): every path in one
    :meth:`~weldplan.robot.collision.RobotCollision.path_hits` call, the motions joining one
    path to the next left out (each motion's verdict is its own, so the same verdicts as one
    call per move, with the per-call work done once)."""
    if checker is None or not paths:
        return set(paths)
    moves = list(paths)
    Q = np.concatenate([paths[i] for i in moves])
    ends = np.cumsum([len(paths[i]) for i in moves])  # one past each path's last row
    inner = np.ones(len(Q) - 1, dtype=bool)
    inner[ends[:-1] - 1] = False  # the motion from one path's last row to the next one's first
    hits = checker.path_hits(Q, np.ones(len(Q) - 1, bool), only=inner)
    owner = np.searchsorted(ends, [h.segment for h in hits], side="right")
    return {moves[int(k)] for k in owner}
