"""Bounds on how far a robot's bodies move along a joint motion, and what they let the
collision proof skip (:mod:`weldplan.robot.collision.checker`,
:mod:`weldplan.robot.collision.selfcollision`).

- :func:`sphere_rates`: per cover sphere, a bound on how far any of its points moves over a
  linear joint motion.
- :func:`sphere_groups`: the cover spheres in groups, each group inside one sphere, asked first.
- :class:`Carry`: a body's last conservative-advancement distance still proves the next motions
  of a path while their bounds stay below it.
- :func:`touches_ahead`: a probe of the rest of a motion for a contact, which ends a blocked
  motion's advancement early.

Each one only saves FCL or distance queries whose answer it already knows: the verdicts are
those of the plain proof.
"""

from __future__ import annotations

from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.robot.collision.nearpart import fcl_tf

#: mm: cell of the groups of cover spheres asked first (:func:`sphere_groups`)
GROUP_CELL_MM = 150.0
#: conservative advancement never steps into the gap, so on a blocked motion it creeps towards
#: the contact until its step cap; after these steps the rest of the motion is probed for a
#: contact (:func:`touches_ahead`: FCL collide at PROBE_STATES states), and one found ends the
#: advancement as blocked at once (against the part, and for a pair of bodies)
PROBE_AFTER = frozenset({12, 48, 160})
PROBE_STATES = 24


def sphere_rates(
    F: NDArray[np.float64],
    frame: int,
    centres: NDArray[np.float64],
    radii: NDArray[np.float64],
    dq: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``(n, s)`` mm: bounds on how far any point of each sphere moves during each motion.

    Parameters
    ----------
    F
        ``(n, 7, 4, 4)``: the link frames at each motion's start.
    frame
        The link the spheres ride on.
    centres, radii
        ``(s, 3)`` mm in that link's frame, ``(s,)`` mm.
    dq
        ``(n, 6)`` rad: each motion's absolute joint change.

    A point's distance to joint j's axis changes only through the joints after j, so, from the
    wrist down, ``R_j = |p - o_j| + r + sum_{i > j} |dq_i| R_i`` bounds it over the whole motion
    (``o_j`` the start position of a point on the axis: link j+1's origin), and the point moves at
    most ``sum_j |dq_j| R_j``. (The distance to the axis line itself, the lever arm, is smaller
    and also a bound; it is not used: it changes the advancement's steps, and with them the
    verdict on a motion that stays just outside the gap until the step cap.)
    """
    p = np.einsum("nij,sj->nsi", F[:, frame, :3, :3], centres) + F[:, None, frame, :3, 3]
    inner = np.zeros(p.shape[:2])
    for j in range(frame - 1, -1, -1):
        R = np.linalg.norm(p - F[:, None, j + 1, :3, 3], axis=2) + radii[None] + inner
        inner = inner + dq[:, j, None] * R
    return inner


def sphere_groups(
    centres: NDArray[np.float64], radii: NDArray[np.float64], cell: float = GROUP_CELL_MM
) -> tuple[NDArray, ...]:
    """Cover spheres ``centres (s, 3)`` mm, ``radii (s,)`` mm in groups (their centres in cells
    of ``cell`` mm), each group inside one sphere.

    Returns
    -------
    member, centres, radii, order, starts
        ``(s,)`` each sphere's group; ``(g, 3)`` mm, ``(g,)`` mm the groups' spheres (in the
        body's link frame) holding their members' spheres; ``order (s,)`` the spheres sorted by
        group and ``starts (g,)`` where each group begins in that order.
    """
    key = np.floor(centres / cell).astype(np.int64)
    _, member = np.unique(key, axis=0, return_inverse=True)
    member = member.ravel()
    g = int(member.max()) + 1
    counts = np.bincount(member, minlength=g)
    gc = np.zeros((g, 3))
    np.add.at(gc, member, centres)
    gc /= counts[:, None]
    gr = np.zeros(g)
    np.maximum.at(gr, member, np.linalg.norm(centres - gc[member], axis=1) + radii)
    gr = gr * (1 + 1e-9) + 1e-9
    order = np.argsort(member, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    return member, gc, gr, order, starts


def touches_ahead(
    robot: Any,
    obj: fcl.CollisionObject,
    other: fcl.CollisionObject,
    qa: NDArray[np.float64],
    qb: NDArray[np.float64],
    t: float,
    frame: int | None = None,
    other_frame: int | None = None,
) -> bool:
    """Whether ``obj`` (riding on link ``frame``; default the last) touches ``other`` (fixed,
    or riding on link ``other_frame``: a pair of bodies) (FCL collide) at one of
    :data:`PROBE_STATES` states evenly spaced on the rest ``(t, 1]`` of the joint motion
    ``qa -> qb`` (rad). Conservative advancement never steps into the gap, so on a blocked
    motion it creeps towards the contact until its step cap; after the steps of
    :data:`PROBE_AFTER` the rest of the motion is probed (the ``probe`` of
    :func:`weldplan.geometry.checker.advance`).

    A contact there makes the motion blocked whatever conservative advancement would have done:
    it cannot step past a state where the body touches, so it would have ended blocked too (at
    its step cap, if not before). So a probe changes no verdict; it only ends a blocked
    motion's advancement early (where it stands, ``t``), instead of creeping towards the
    contact for hundreds of steps. Finding no contact proves nothing: the advancement goes on.
    """
    f = 6 if frame is None else frame
    ts = t + (1.0 - t) * np.arange(1, PROBE_STATES + 1) / PROBE_STATES
    F = robot.link_frames(qa + ts[:, None] * (qb - qa))
    for Fk in F:
        obj.setTransform(fcl_tf(Fk[f]))
        if other_frame is not None:
            other.setTransform(fcl_tf(Fk[other_frame]))
        if fcl.collide(obj, other, fcl.CollisionRequest(), fcl.CollisionResult()):
            return True
    return False


class Carry:
    """What a body's (or a pair of bodies') last FCL distance still proves on the motions after
    it (:meth:`~weldplan.robot.collision.RobotCollision.path_hits`,
    :meth:`~weldplan.robot.collision.SelfCheck.motions`).

    The conservative advancement of a motion ends with the FCL distance ``d`` of the triangles
    of some spheres of a body at the motion's end; on the next motions of the path no point of
    the body moves more than their bounds (``D``, mm). While the bounds summed since stay below
    ``d`` less the gap, the same triangles (or any subset of them: a subset is never closer)
    cannot come within the gap (:data:`~weldplan.robot.collision.MIN_GAP_MM`) of the part, so
    such a motion is free with no FCL call. The advancement itself would have proven it free in
    its first step, so the verdicts are the same; a path of short motions (a sampled linear
    move) costs one advancement per body instead of one per motion.

    Parameters
    ----------
    seg
        ``(s,)``: the path's motions checked, increasing.
    D
        ``(s, b)`` mm: each motion's bound on how far any point of each body moves (of a pair:
        relative to each other).
    """

    def __init__(self, seg: NDArray[np.int64], D: NDArray[np.float64]) -> None:
        self.seg = seg
        self.cum = np.vstack([np.zeros((1, D.shape[1])), np.cumsum(D, axis=0)])
        self.last: dict[int, tuple[int, NDArray[np.int64], float]] = {}

    def free(self, s_i: int, b: int, spheres: NDArray[np.int64], rates: NDArray) -> bool:
        """Whether motion ``seg[s_i]`` is free for ``spheres`` of body ``b`` by the distance
        measured last (class docstring)."""
        if b not in self.last:
            return False
        k, measured, left = self.last[b]
        if k >= s_i or self.seg[s_i] - self.seg[k] != s_i - k:  # not the same run of motions
            return False
        moved = self.cum[s_i, b] - self.cum[k + 1, b]  # motions k + 1 .. s_i - 1
        return left - moved - float(np.max(rates)) > 0.0 and bool(np.isin(spheres, measured).all())

    def measured(self, s_i: int, b: int, spheres: NDArray[np.int64], left: float) -> None:
        """Motion ``seg[s_i]``'s advancement of ``spheres`` of body ``b`` left ``left`` mm."""
        self.last[b] = (s_i, spheres, left)
