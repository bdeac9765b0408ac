"""A weld's alternative tool poses in the base search (issue 17).

The tool stage chooses one pose per weld among the free candidates of its cone (spins and tilts
about the approach axis, :mod:`weldplan.tool.poses.plan`), without the robot; the robot's reach test
then re-chooses the poses at the searched base (:mod:`weldplan.robot.placement.posechoice`). A base
search that scores only the chosen pose of each weld counts a weld as lost at a base where that one
pose is out of the joint limits even when another free pose of the same weld is reachable there, and
may prefer a base from which no pose of the weld is reachable at all (car2_200: Z4L-1 and Z4L-2,
``joint_limit`` on every pose in the torch's cone at the base chosen, reachable from others).

Here a weld counts at a base when its chosen pose **or one of its alternatives** is usable
(:func:`~weldplan.robot.placement.usable`; in the search, with its shoulder-wrist chord clear of the
part as for the chosen pose), and, where the search ranks by collisions, when one of them has a
usable branch with no link in the part. The alternatives are the tool stage's candidates not known
to fail for the tool (:attr:`weldplan.tool.poses.WeldPoses.alternatives`), spread to at most
:data:`SCORE_ALTS` per weld (:func:`spread`: farthest-point in rotation angle from the chosen
one), and they are tried only where the chosen pose fails, so a base whose chosen poses all
serve costs what it did. The score is a ranking: the pose actually welded at the chosen base is
the reach test's pick over every free candidate, and the robot route verifies it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.reach import alt_pairs, usable

#: alternative poses per weld that the base search scores (the chosen one included)
SCORE_ALTS = 16


def spread(quats: ArrayLike, k: int) -> NDArray[np.int64]:
    """Indices of at most ``k`` of the unit quaternions ``(m, 4)``: the first, then each time the
    one farthest (rotation angle) from those taken (ties: the lower index)."""
    q = np.asarray(quats, dtype=np.float64).reshape(-1, 4)
    m = len(q)
    if m <= k:
        return np.arange(m, dtype=np.int64)
    take = [0]
    gap = np.full(m, np.inf)
    for _ in range(k - 1):
        dot = np.clip(np.abs(q @ q[take[-1]]), 0.0, 1.0)
        gap = np.minimum(gap, 2.0 * np.arccos(dot))
        gap[take[-1]] = -1.0
        take.append(int(np.argmax(gap)))
    return np.array(take, dtype=np.int64)


def alternative_flange_poses(
    poses: Any, ids: Sequence[str], flange_tcp: ArrayLike, k: int = SCORE_ALTS
) -> list[NDArray[np.float64]] | None:
    """Per weld of ``ids`` (route order), ``(k_i, 4, 4)`` mm: the flange poses of its alternative
    TCP poses (the chosen one first, spread to ``k``); ``None`` when ``poses`` carries none
    (:attr:`~weldplan.tool.poses.WeldPoses.alternatives`, not kept in JSON)."""
    alts = getattr(poses, "alternatives", ())
    if not alts:
        return None
    inv = np.linalg.inv(np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4))
    by_id = {p.id: (p, a) for p, a in zip(poses.poses, alts, strict=True)}
    out: list[NDArray[np.float64]] = []
    for wid in ids:
        p, a = by_id.get(wid, (None, np.zeros((0, 4))))
        a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
        a = a[spread(a, k)]
        T = np.tile(np.eye(4), (len(a), 1, 1))
        if len(a):
            T[:, :3, :3] = Rotation.from_quat(np.roll(a, -1, axis=1)).as_matrix()
            T[:, :3, 3] = p.position
        out.append(T @ inv)
    return out


def alt_free(
    robot: Robot,
    checker: Any,
    alts: Sequence[NDArray[np.float64]],
    need: NDArray[np.bool_],
    singular_deg: float,
    by_first: NDArray[np.bool_] | None = None,
) -> NDArray[np.bool_]:
    """``(n,) bool``: for the welds of ``need (n,)``, whether one of their alternative flange
    poses has a usable branch from ``robot``'s base on which no link touches the part (``checker``
    a :class:`~weldplan.robot.collision.RobotCollision` at that base; ``None``: usable is
    enough). In rounds: each round checks the next usable (pose, branch) of every weld not yet
    served, in the order of ``alts`` (the chosen pose first), so a weld costs one FCL query when
    its first branch is free. ``by_first (n,) bool``, when given, is set where the weld is served
    by its first pose (all its branches are tried before its other poses)."""
    ok = np.zeros(len(need), dtype=bool)
    _, weld, T = alt_pairs(alts, need[None] & np.array([len(a) > 0 for a in alts])[None])
    if len(T) == 0:
        return ok
    br = robot.ik_all(T)
    idx = np.argwhere(usable(br, singular_deg))
    w = weld[idx[:, 0]]
    first = np.r_[True, weld[1:] != weld[:-1]][idx[:, 0]]  # the weld's first pose
    if checker is None:
        ok[w] = True
        if by_first is not None:
            by_first[w[first]] = True
        return ok
    left = np.ones(len(idx), dtype=bool)
    while True:
        live = np.flatnonzero(left & ~ok[w])
        if len(live) == 0:
            return ok
        pick = live[np.unique(w[live], return_index=True)[1]]  # the first of each weld
        left[pick] = False
        blocked = checker.states_blocked(br.q[idx[pick, 0], idx[pick, 1]], zone=True, tool=False)
        free = pick[[b is None for b in blocked]]
        ok[w[free]] = True
        if by_first is not None:
            by_first[w[free[first[free]]]] = True
