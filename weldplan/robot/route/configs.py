"""Configurations: one joint vector per route waypoint, continuous in joint space.

The route's waypoints (:meth:`~weldplan.weld.route.Route.waypoints`) carry TCP poses: positions
from the route, orientations from the weld poses, slerped along the legs
(:func:`~weldplan.tool.poses.waypoint_quaternions`). The flange pose of each is
``T_tcp @ inv(T_flange_tcp)``. Every waypoint gets all its IK solutions: the eight OPW branches
and, for joints whose range spans a full turn (KUKA A1, A4, A6), each equivalent inside the
limits (``q + 2 pi k``). Solutions outside the limits or near the wrist singularity
(:func:`~weldplan.robot.placement.usable`) are dropped.

The choice is a shortest path through the layered graph of waypoints (dynamic programming, exact):
the cost of going from one solution to the next is the time the slowest joint needs at its
velocity limit, ``max_j |dq_j| / v_j`` (s; a synchronous PTP move at full speed, ignoring
acceleration), plus :data:`FLIP_PENALTY_S` when the branch changes. So the route keeps one
branch wherever one branch can do it, and a branch change (an elbow, wrist or shoulder flip)
happens only where the route cannot be done without one; each is reported.

A waypoint with no usable solution is left out of the chain: its joint vector is interpolated in
joint space between its neighbours (``exact=False``: that row's FK is not the route's pose), and
a weld there gets the reason (:func:`~weldplan.robot.placement.classify`). Between consecutive rows
the robot moves linearly in joint space; :mod:`weldplan.robot.collision.checker` checks exactly that
motion.
"""

from __future__ import annotations

import itertools
import json
import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.robot.model.arm import Robot
from weldplan.robot.model.ik import IKBranches
from weldplan.robot.placement.reach import (
    COLLISION,
    DEFAULT_SINGULAR_DEG,
    NO_POSE,
    OK,
    classify,
    usable,
)

log = logging.getLogger(__name__)

#: seconds of joint motion a branch change costs in the configuration choice (module docstring):
#: larger than any joint move of a route, so a flip is taken only when nothing else works
FLIP_PENALTY_S = 1000.0


@dataclass(frozen=True, eq=False)
class RobotRoute:
    """The route in joint space.

    Attributes
    ----------
    robot, joint_names
        The robot's name and its joints (URDF names), the columns of :attr:`q`.
    base
        ``(4, 4)`` mm: the robot base in the part frame.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame (the tool transform used).
    q
        ``(k, 6)`` rad: the joint path; the robot moves linearly in joint space between rows.
    row
        ``(k,) int``: the route waypoint (row of :meth:`Route.waypoints`) each row belongs to.
        Without re-planning ``k`` is the number of waypoints and ``row = arange(k)``; a re-planned
        leg's joint-space vias belong to the waypoint the leg leaves from.
    exact
        ``(k,) bool``: ``fk(q) @ flange_tcp`` is the route's TCP pose at that row (False for
        interpolated rows and re-planned vias).
    branch
        ``(k,) int``: the IK branch of each row (:mod:`weldplan.robot.model.ik`).
    weld_ids
        The welds in visiting order.
    weld_index
        ``(n_welds,) int``: the row of :attr:`q` at each weld.
    status
        Per weld: ``ok``, ``out_of_reach``, ``joint_limit``, ``singular``, ``no_pose`` or
        ``collision`` (:mod:`weldplan.robot.placement.reach`).
    flips
        Rows where the branch differs from the previous row's.
    replanned
        Legs re-planned in joint space (their index in the route).
    stats
        Figures of the run (seconds, counts, verification).
    detail
        Per weld: what blocks it when its status is ``collision`` (the body, link name or
        ``tool``, and where: at the weld pose on every branch, or on the leg to it after the
        re-plan failed), else ``""``.
    """

    robot: str
    joint_names: tuple[str, ...]
    base: NDArray[np.float64]
    flange_tcp: NDArray[np.float64]
    q: NDArray[np.float64]
    row: NDArray[np.int64]
    exact: NDArray[np.bool_]
    branch: NDArray[np.int64]
    weld_ids: tuple[str, ...]
    weld_index: NDArray[np.int64]
    status: tuple[str, ...]
    flips: tuple[int, ...] = ()
    replanned: tuple[int, ...] = ()
    stats: dict[str, Any] = field(default_factory=dict)
    detail: tuple[str, ...] = ()

    @property
    def weld_branch(self) -> NDArray[np.int64]:
        """``(n_welds,) int``: the branch at each weld (-1 where the weld is not ok)."""
        b = self.branch[self.weld_index].copy()
        b[np.array([s != OK for s in self.status], dtype=bool)] = -1
        return b

    @property
    def weld_q(self) -> NDArray[np.float64]:
        """``(n_welds, 6)`` rad: the configuration at each weld."""
        return self.q[self.weld_index]

    @property
    def n_ok(self) -> int:
        return sum(s == OK for s in self.status)

    def tcp(self, robot: Robot) -> NDArray[np.float64]:
        """``(k, 4, 4)`` mm: the TCP pose of every row, by FK of the URDF chain."""
        return robot.with_base(self.base).fk(self.q) @ self.flange_tcp

    def to_dict(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "joint_names": list(self.joint_names),
            "base": self.base.tolist(),
            "flange_tcp": self.flange_tcp.tolist(),
            "q": self.q.tolist(),
            "row": self.row.tolist(),
            "exact": self.exact.tolist(),
            "branch": self.branch.tolist(),
            "weld_ids": list(self.weld_ids),
            "weld_index": self.weld_index.tolist(),
            "status": list(self.status),
            "flips": list(self.flips),
            "replanned": list(self.replanned),
            "stats": self.stats,
            "detail": list(self.detail),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RobotRoute:
        return cls(
            robot=str(d["robot"]),
            joint_names=tuple(d["joint_names"]),
            base=np.asarray(d["base"], dtype=np.float64),
            flange_tcp=np.asarray(d["flange_tcp"], dtype=np.float64),
            q=np.asarray(d["q"], dtype=np.float64).reshape(-1, 6),
            row=np.asarray(d["row"], dtype=np.int64),
            exact=np.asarray(d["exact"], dtype=bool),
            branch=np.asarray(d["branch"], dtype=np.int64),
            weld_ids=tuple(d["weld_ids"]),
            weld_index=np.asarray(d["weld_index"], dtype=np.int64),
            status=tuple(d["status"]),
            flips=tuple(int(i) for i in d.get("flips", ())),
            replanned=tuple(int(i) for i in d.get("replanned", ())),
            stats=dict(d.get("stats", {})),
            detail=tuple(d.get("detail", ())),
        )

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> RobotRoute:
        return cls.from_dict(json.loads(text))


def turn_variants(
    br: IKBranches, lower: NDArray[np.float64], upper: NDArray[np.float64], ok: NDArray[np.bool_]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """Every usable solution with its full-turn equivalents inside the limits.

    Parameters
    ----------
    br
        All branches of ``m`` poses.
    lower, upper
        ``(6,)`` rad joint limits.
    ok
        ``(m, 8) bool``: the usable branches.

    Returns
    -------
    Q, branch, valid
        ``(m, K, 6)`` rad, ``(m, K)`` branch labels and ``(m, K)`` validity, ``K = 8 * 3**t``
        with ``t`` the joints whose range spans at least a full turn.
    """
    turn = np.flatnonzero(upper - lower >= 2 * math.pi)
    shifts = np.zeros((3 ** len(turn), 6))
    for k, combo in enumerate(itertools.product((0.0, -1.0, 1.0), repeat=len(turn))):
        shifts[k, turn] = combo
    shifts *= 2 * math.pi
    Q = br.q[:, :, None, :] + shifts[None, None]  # (m, 8, S, 6)
    valid = ok[:, :, None] & np.all((Q >= lower) & (Q <= upper), axis=3)
    m = len(Q)
    branch = np.broadcast_to(np.arange(8)[None, :, None], valid.shape)
    return Q.reshape(m, -1, 6), branch.reshape(m, -1).astype(np.int64), valid.reshape(m, -1)


def motion_cost(
    qa: NDArray[np.float64], qb: NDArray[np.float64], velocity: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(a, b)`` s: ``max_j |qb_j - qa_j| / v_j`` between all rows of ``(a, 6)``, ``(b, 6)``."""
    return (np.abs(qb[None] - qa[:, None]) / velocity).max(axis=2)


def choose_configurations(
    Q: NDArray[np.float64],
    branch: NDArray[np.int64],
    valid: NDArray[np.bool_],
    velocity: NDArray[np.float64],
    *,
    flip_penalty: float = FLIP_PENALTY_S,
) -> NDArray[np.int64]:
    """The shortest path through the layered graph (module docstring).

    Parameters
    ----------
    Q, branch, valid
        From :func:`turn_variants`: ``(m, K, 6)``, ``(m, K)``, ``(m, K)``.
    velocity
        ``(6,)`` rad/s.

    Returns
    -------
    ``(m,) int``
        The chosen column of each layer, -1 for layers without a valid solution (skipped).
    """
    m = len(Q)
    layers = [i for i in range(m) if valid[i].any()]
    choice = np.full(m, -1, dtype=np.int64)
    if not layers:
        return choice
    cols = [np.flatnonzero(valid[i]) for i in layers]
    cost = np.zeros(len(cols[0]))
    back: list[NDArray[np.int64]] = []
    for k in range(1, len(layers)):
        a, b = cols[k - 1], cols[k]
        C = motion_cost(Q[layers[k - 1], a], Q[layers[k], b], velocity)
        C += flip_penalty * (branch[layers[k - 1], a][:, None] != branch[layers[k], b][None])
        tot = cost[:, None] + C
        arg = np.argmin(tot, axis=0)
        back.append(arg)
        cost = tot[arg, np.arange(len(b))]
    j = int(np.argmin(cost))
    for k in range(len(layers) - 1, -1, -1):
        choice[layers[k]] = cols[k][j]
        if k > 0:
            j = int(back[k - 1][j])
    return choice


def joint_path(
    robot: Robot,
    T_flange: ArrayLike,
    *,
    singular_deg: float = DEFAULT_SINGULAR_DEG,
    flip_penalty: float = FLIP_PENALTY_S,
    allowed: ArrayLike | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_], NDArray[np.str_]]:
    """Joint vectors for flange poses ``(m, 4, 4)`` mm (part frame; NaN rows: no pose).

    ``allowed``: ``(m, 8) bool``, the branches a caller lets each row use besides the usable
    ones (the robot check's collision-free branches at the welds); a row whose usable branches
    it all removes gets :data:`~weldplan.robot.placement.COLLISION`.

    Returns
    -------
    q, branch, exact, status
        ``(m, 6)`` rad; ``(m,)`` branch (-1 where skipped); ``(m,)`` True where the row solves
        its pose; ``(m,)`` status (:data:`~weldplan.robot.placement.OK`, a reason, or
        :data:`~weldplan.robot.placement.NO_POSE` for NaN rows).

    Raises
    ------
    PlanningError
        When no row has a usable solution.
    """
    from weldplan.errors import PlanningError

    T = np.asarray(T_flange, dtype=np.float64).reshape(-1, 4, 4)
    m = len(T)
    has_pose = np.all(np.isfinite(T), axis=(1, 2))
    T_ok = np.where(has_pose[:, None, None], T, np.eye(4))
    br = robot.ik_all(T_ok)
    ok = usable(br, singular_deg) & has_pose[:, None]
    status = classify(br, singular_deg).astype(object)
    status[~has_pose] = NO_POSE
    if allowed is not None:
        kept = ok & np.asarray(allowed, dtype=bool).reshape(m, 8)
        status[ok.any(axis=1) & ~kept.any(axis=1)] = COLLISION
        ok = kept
    Q, brn, valid = turn_variants(br, robot.lower, robot.upper, ok)
    choice = choose_configurations(Q, brn, valid, robot.velocity, flip_penalty=flip_penalty)
    solved = choice >= 0
    if not solved.any():
        raise PlanningError(
            f"the robot reaches none of the {m} route poses from its base "
            f"({_reasons(status)}): move the base (--robot-base) or let it be searched"
        )
    q = np.full((m, 6), np.nan)
    idx = np.flatnonzero(solved)
    q[idx] = Q[idx, choice[idx]]
    branch = np.full(m, -1, dtype=np.int64)
    branch[idx] = brn[idx, choice[idx]]
    # rows without a solution: joint-space interpolation between their solved neighbours
    for j in range(6):
        q[:, j] = np.interp(np.arange(m), idx, q[idx, j])
    return q, branch, solved, status.astype(str)


def _reasons(status: NDArray[Any]) -> str:
    words, counts = np.unique(status, return_counts=True)
    return ", ".join(f"{c} {w.replace('_', ' ')}" for w, c in zip(words, counts, strict=True))
