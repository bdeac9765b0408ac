"""Whether a robot at its base reaches a free gun pose of each spot, and why not.

A spot's gun poses are the tool stage's verified pose first, then its other free candidates
(:attr:`weldplan.tool.poses.WeldPoses.alternatives`, spread in rotation by
:func:`weldplan.robot.placement.spread` to at most ``poses`` per spot). For all of them at once:
IK (:meth:`~weldplan.robot.model.Robot.ik_all`), the reach rule of
:func:`weldplan.robot.placement.usable` (a branch inside the joint limits, A5 away from its
singularity) and, per pose without a usable branch, :func:`weldplan.robot.placement.classify`'s
reason. The usable (pose, branch) pairs of every spot are then checked in rounds (one batched
call a round, the spot's pairs in the order of its poses): the links and the tool minus its
contact zone against the part, the robot against itself and against the floor
(:meth:`weldplan.robot.collision.RobotCollision.states_blocked`, FCL judges), until one is clear
or ``branches`` pairs of the spot were checked (a work budget, not a clock). A pose other than
the verified one is re-checked for the tool (:class:`weldplan.tool.verify.PoseChecker`:
fresh FCL models of the whole part and tool, clearance measured) before it is reported.

Without a clear pair, the spot's verdict is the reason closest to feasible over its poses:
``collision`` (usable branches exist, each blocked: the body named), then ``singular``, then
``joint_limit`` (the joints and their limits named, :func:`weldplan.robot.placement.posechoice.
joint_limit_reason`), then ``out_of_reach``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from weldplan.robot.collision.selfcollision import hit_words
from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.altreach import spread
from weldplan.robot.placement.posechoice import joint_limit_reason
from weldplan.robot.placement.reach import classify, usable
from weldplan.study.result import (
    COLLISION,
    JOINT_LIMIT,
    OK,
    OUT_OF_REACH,
    SINGULAR,
    RobotVerdict,
)

#: what blocked a pose whose gun fails the independent re-check
TOOL_SHORT = "tool"


@dataclass(frozen=True)
class SpotPoses:
    """The free gun poses of one spot, the verified one first.

    Attributes
    ----------
    position
        ``(3,)`` mm: the spot (the TCP position of every pose).
    quaternions
        ``(k, 4)`` ``(qw, qx, qy, qz)``: TCP orientations, part frame; ``k = 0`` without a free
        pose. Row 0 passed the tool stage's independent re-check.
    """

    position: NDArray[np.float64]
    quaternions: NDArray[np.float64]


@dataclass(frozen=True)
class ReachBudget:
    """The work the robot check may do per spot.

    Attributes
    ----------
    poses
        Free gun poses judged per spot (the verified one and the others spread in rotation).
    branches
        Usable (pose, branch) pairs collision-checked per spot before it is declared blocked.
    singular_deg
        A5 within this many degrees of 0 is near-singular (:func:`weldplan.robot.placement.usable`).
    """

    poses: int = 64
    branches: int = 24
    singular_deg: float = 5.0


def tcp_matrices(position: NDArray[np.float64], quats: NDArray[np.float64]) -> NDArray:
    """``(k, 4, 4)`` mm: TCP poses at ``position (3,)`` with orientations ``quats (k, 4)``
    ``(qw, qx, qy, qz)``."""
    T = np.tile(np.eye(4), (len(quats), 1, 1))
    if len(quats):
        T[:, :3, :3] = Rotation.from_quat(np.roll(quats, -1, axis=1)).as_matrix()
    T[:, :3, 3] = position
    return T


def robot_verdicts(
    robot: Robot,
    checker: object,
    flange_tcp: NDArray[np.float64],
    spots: Sequence[SpotPoses],
    tool_clear: Callable[[NDArray[np.float64]], bool],
    budget: ReachBudget,
    names: tuple[str, str],
) -> list[RobotVerdict | None]:
    """The verdict of ``robot`` (at its base) at every spot that has a free gun pose.

    Parameters
    ----------
    robot
        The robot at its base (part frame).
    checker
        A :class:`~weldplan.robot.collision.RobotCollision` of that robot with the tool.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    spots
        Per spot its free gun poses (:class:`SpotPoses`).
    tool_clear
        ``tool_clear(T (4, 4) mm) -> bool``: the tool's independent re-check of a TCP pose
        (:func:`tool_recheck`).
    budget
        Work per spot (:class:`ReachBudget`).
    names
        ``(tool, robot)``: the names the verdicts carry.

    Returns
    -------
    list
        One :class:`~weldplan.study.result.RobotVerdict` per spot, ``None`` where the spot has
        no free gun pose (the caller gives the gun's verdict).
    """
    quats = [s.quaternions[spread(s.quaternions, budget.poses)] for s in spots]
    owner = np.concatenate(
        [np.full(len(q), i, dtype=np.int64) for i, q in enumerate(quats)]
        or [np.zeros(0, dtype=np.int64)]
    )
    first = np.r_[True, owner[1:] != owner[:-1]] if len(owner) else np.zeros(0, dtype=bool)
    T = np.concatenate(
        [tcp_matrices(s.position, q) for s, q in zip(spots, quats, strict=True)]
        or [np.zeros((0, 4, 4))]
    )
    br = robot.ik_all(T @ np.linalg.inv(flange_tcp)) if len(T) else None
    found = _clear_pairs(robot, checker, br, owner, first, T, tool_clear, budget, len(spots))
    out: list[RobotVerdict | None] = []
    status = classify(br, budget.singular_deg) if br is not None else np.zeros(0, dtype=str)
    for i in range(len(spots)):
        mine = np.flatnonzero(owner == i)
        if len(mine) == 0:
            out.append(None)
            continue
        hit = found.get(i)
        if isinstance(hit, tuple):
            k, q = hit
            quat = tuple(float(v) for v in np.asarray(quats[i])[k - mine[0]])
            v = RobotVerdict(*names, OK, "", quat, tuple(float(a) for a in q), len(mine))  # type: ignore[arg-type]
        else:
            word, why = _why_not(robot, br, status, mine, hit)
            v = RobotVerdict(*names, word, why, None, None, len(mine))
        out.append(v)
    return out


def _clear_pairs(
    robot: Robot,
    checker: object,
    br: object,
    owner: NDArray[np.int64],
    first: NDArray[np.bool_],
    T: NDArray[np.float64],
    tool_clear: Callable[[NDArray[np.float64]], bool],
    budget: ReachBudget,
    n: int,
) -> dict[int, tuple[int, NDArray[np.float64]] | Counter[str]]:
    """Per spot: ``(pose row, q (6,))`` of its first clear usable pair, else a ``Counter`` of
    what blocked the pairs checked (empty: no usable pair). Rounds of one batched check each
    (module docstring). A pair clear of the robot's checks whose pose is not the verified one
    is then re-checked for the tool (``tool_clear(T)``); a pose that fails drops all its pairs,
    and that pair does not count against the spot's ``branches``."""
    out: dict[int, tuple[int, NDArray[np.float64]] | Counter[str]] = {
        i: Counter() for i in range(n)
    }
    if br is None:
        return out
    idx = np.argwhere(usable(br, budget.singular_deg))  # (pairs, 2): pose row, branch
    w = owner[idx[:, 0]]
    left = np.ones(len(idx), dtype=bool)
    spent = np.zeros(n, dtype=np.int64)
    done = np.zeros(n, dtype=bool)
    while True:
        live = np.flatnonzero(left & ~done[w] & (spent[w] < budget.branches))
        if len(live) == 0:
            return out
        pick = live[np.unique(w[live], return_index=True)[1]]  # the next pair of each spot
        left[pick] = False
        spent[w[pick]] += 1
        q = br.q[idx[pick, 0], idx[pick, 1]]  # type: ignore[attr-defined]
        blocked = checker.states_blocked(q, zone=True, tool=True)  # type: ignore[attr-defined]
        for p, qk, b in zip(pick, q, blocked, strict=True):
            i, row = int(w[p]), int(idx[p, 0])
            if b is not None:
                out[i][b] += 1  # type: ignore[index]
            elif first[row] or tool_clear(T[row]):
                out[i] = (row, qk)
                done[i] = True
            else:
                left[idx[:, 0] == row] = False
                spent[i] -= 1
                out[i][TOOL_SHORT] += 1  # type: ignore[index]


def tool_recheck(pose_checker: object) -> Callable[[NDArray[np.float64]], bool]:
    """``tool_clear(T)``: :class:`~weldplan.tool.verify.PoseChecker` ``pose_checker``'s
    verdict on TCP pose ``T (4, 4)`` mm, remembered per pose (a pose's verdict does not depend
    on the robot's base)."""
    memo: dict[bytes, bool] = {}

    def tool_clear(T: NDArray[np.float64]) -> bool:
        key = np.asarray(T, dtype=np.float64).tobytes()
        if key not in memo:
            q = Rotation.from_matrix(T[:3, :3]).as_quat()[[3, 0, 1, 2]]
            memo[key] = bool(pose_checker.check(T[:3, 3], q).ok)  # type: ignore[attr-defined]
        return memo[key]

    return tool_clear


def _why_not(
    robot: Robot,
    br: object,
    status: NDArray[np.str_],
    rows: NDArray[np.int64],
    blocked: Counter[str],
) -> tuple[str, str]:
    """``(word, reason)`` of a spot none of whose poses ``rows`` has a clear usable branch."""
    n = len(rows)
    short = blocked.pop(TOOL_SHORT, 0)
    if blocked:
        body, k = blocked.most_common(1)[0]
        total = sum(blocked.values())
        also = f"; {short} reachable poses fail the gun's re-check" if short else ""
        return COLLISION, f"{hit_words(body)} ({k} of {total} usable branches checked{also})"
    if short:
        return COLLISION, (
            f"the gun: each of the {short} poses the robot can take fails its re-check (short "
            "of the clearance outside the contact zone)"
        )
    st = status[rows]
    counts = Counter(str(s) for s in st)
    tally = ", ".join(f"{w.replace('_', ' ')} {c}" for w, c in counts.most_common())
    if SINGULAR in counts:
        return SINGULAR, f"A5 near 0 on every usable branch ({tally} of {n} poses)"
    if JOINT_LIMIT in counts:
        r = int(rows[np.flatnonzero(st == JOINT_LIMIT)[0]])
        lim = joint_limit_reason(robot, br.q[r], br.exists[r])  # type: ignore[attr-defined]
        return JOINT_LIMIT, f"{lim.replace('joint_limit ', '')} ({tally} of {n} poses)"
    return OUT_OF_REACH, f"the wrist centre is beyond the arm's reach on all {n} poses"
