"""Blocked legs of a joint route: detours through retract poses, re-planned with OMPL.

:func:`assemble` walks the welds the robot serves (status ``ok``) in route order. The leg from
one served weld ``a`` to the next ``b`` is first the route's own: its waypoints' configurations,
checked with the tool's contact zone exempt (the TCP is on the verified route). When that is
blocked, the leg becomes a detour:

0. *gun exit*: when the caller gives the gun stage's proven exits of ``a``
   (:attr:`Detour.exits`: a side exit and its retract, an axial retract, half an SE(3) re-plan;
   :func:`weldplan.robot.gunpath.gun_exits`), ``a`` is first left along one of them, longest
   first, by IK at each TCP step on ``a``'s branch (:meth:`Detour.follow`: the first motion
   checked with the contact zone exempt, the rest and the end with the whole tool); ``b`` is
   reached the same way reversed. Else:
1. *retract*: from ``a``'s configuration to ``a``'s pose moved ``d`` mm (orientation kept)
   back along its TCP axis or, failing that, sideways along its x or y axis
   (:data:`RETRACT_DIRS` x :data:`RETRACT_MM`, the first that works), on the same IK branch and
   the turn nearest ``a``'s; that motion checked with the contact zone exempt, the retract
   configuration with the *whole* tool. Deviation from the tool stage's retract (issue 16):
   with the zone exempt, the electrode caps may slide along the sheet while they leave it
   sideways (a real servo gun opens first); the tool stage narrows its exemption further;
2. *transfer*: from ``a``'s retract configuration to ``b``'s approach configuration (its retract
   pose), straight in joint space when that is free, else through a tucked arm (A2, A3 set to
   :data:`TUCK_A2_A3`: fold at ``a``, turn folded, unfold at ``b``, three straight joint
   motions), else planned in joint space by OMPL
   (:func:`weldplan.motion.sampling.plan_rn`, ``rrtconnect``) with the whole tool and every link
   checked by :class:`~weldplan.robot.collision.RobotCollision` (states and motions): one run of
   ``time_s`` and, while that does not solve it, retries of :data:`RETRY_TIME_S` with the next
   seeds, while the route's retries stay within :data:`RETRY_TOTAL_S` (rrtconnect stops at its
   first solution, so only a leg that needs the time spends it);
3. *approach*: ``b``'s approach configuration to ``b``'s, contact zone exempt.

When no detour is found, ``b`` is dropped (status ``collision``, its ``detail`` naming the body
that blocked the leg) and the next served weld is tried from ``a``. When that one cannot be
reached from ``a`` either, ``a`` is taken for the weld the robot cannot leave: ``a`` is dropped
instead (``cannot be left``), its leg taken off the path, and both are tried again from the weld
before ``a`` (once: that weld is not dropped in turn). Before, every weld after a weld that could
not be left was tried from it, one OMPL run each, and dropped (car2_200 from one base: 190).
Welds the path passes without serving keep a row on it that is not exact (the program passes
them without welding):
the detour's joint polyline is subdivided where it has fewer inner rows than such welds (points
on its own segments: the motion is unchanged). The motions of the route's own legs are checked
with the contact zone exempt where the caller says (``zone=``: every one on the point-tip route;
only near the spots on a route along the gun's transitions, :mod:`weldplan.robot.gunpath`), those
of the retract/approach with it exempt, those of the transfer without (``zone`` in the result).
The caller checks the assembled path again (the verification).

The head (route rows before the first served weld) and the tail (after the last) are the route's
own rows; a blocked tail is replaced by the retract from the last served weld (subdivided, one
point per route row after it, the last the retract configuration), or, with no retract, by the
last served configuration held (the program ends at that weld).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.robot.collision import RobotCollision
from weldplan.robot.model import Robot
from weldplan.robot.reach import COLLISION, OK, usable

log = logging.getLogger(__name__)

#: mm: retract distances tried, in order (the longer first: it leaves the transfer more room;
#: 20 and 10 mm for a C-gun whose only exit is a short lift off its flange, as the gun stage's
#: exit test finds for the demo's welds 1-6: on the demo 9 -> 11 of 15 welds served, robot stage
#: 21 s -> 205 s, most of it OMPL from the tighter start)
RETRACT_MM = (150.0, 60.0, 20.0, 10.0)
#: retract directions tried, in order, as (axis of the TCP frame, sign): back along the TCP axis
#: first (a torch), then sideways (a C-gun straddles its sheet: its fixed electrode, ahead of the
#: TCP, would hit the sheet on a retract along the axis)
RETRACT_DIRS = ((2, -1.0), (0, -1.0), (0, 1.0), (1, -1.0), (1, 1.0))


#: deg: (A2, A3) of the tucked arm a transfer may pass through (KUKA convention: A2 = -90 deg the
#: upper arm upright, A3 = 90 deg the forearm level; -120/120 keeps the wrist lower and nearer
#: the base): the arm folds there, A1 and the wrist turn folded, and it unfolds at the goal
TUCK_A2_A3 = ((-90.0, 90.0), (-120.0, 120.0))

#: s: a transfer OMPL did not solve in its first budget gets more runs of this long (the next
#: seeds) while the route's retries last: rrtconnect stops at its first solution, so only the
#: legs that need it pay for it
RETRY_TIME_S = 30.0
#: s: the most all the retries of one route may take together (then a leg gets one run only)
RETRY_TOTAL_S = 120.0


@dataclass
class JointPath:
    """A joint route being assembled: rows and, per row, the zone flag of the motion leaving it."""

    q: list[NDArray[np.float64]] = field(default_factory=list)
    row: list[int] = field(default_factory=list)
    exact: list[bool] = field(default_factory=list)
    branch: list[int] = field(default_factory=list)
    zone: list[bool] = field(default_factory=list)

    def add(self, q: NDArray, row: int, exact: bool, branch: int, zone: bool = True) -> None:
        self.q.append(np.asarray(q, dtype=np.float64))
        self.row.append(int(row))
        self.exact.append(bool(exact))
        self.branch.append(int(branch))
        self.zone.append(bool(zone))

    def arrays(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """``q (k, 6)``, ``row (k,)``, ``exact (k,)``, ``branch (k,)``, ``zone (k - 1,)``."""
        return (
            np.array(self.q).reshape(-1, 6),
            np.array(self.row, dtype=np.int64),
            np.array(self.exact, dtype=bool),
            np.array(self.branch, dtype=np.int64),
            np.array(self.zone[:-1], dtype=bool),
        )


@dataclass(frozen=True)
class Detour:
    """What :func:`assemble` needs besides the joint route (see the module docstring)."""

    robot: Robot
    checker: RobotCollision
    T_tcp: NDArray[np.float64]  # (m, 4, 4) mm: the route's TCP poses
    flange_tcp: NDArray[np.float64]  # (4, 4) mm
    singular_deg: float
    planner: str
    time_s: float
    rng: int | None
    tuck: tuple[tuple[float, float], ...] = TUCK_A2_A3
    retry_time_s: float = RETRY_TIME_S
    retry_total_s: float = RETRY_TOTAL_S
    #: per route row of a weld, TCP paths ``(k, 4, 4)`` mm that leave it (the first pose the
    #: weld's own) which the gun stage proved free for the tool: tried before :meth:`retract`
    #: (:func:`weldplan.robot.gunpath.gun_exits`)
    exits: dict[int, tuple[NDArray[np.float64], ...]] = field(default_factory=dict)
    #: figures of the transfers planned with OMPL (runs, solved, retries, seconds)
    ompl: dict[str, float] = field(default_factory=dict, compare=False)
    #: how each weld was left or reached by a detour: ``"gun exit"`` or ``"retract"``
    left_by: dict[str, int] = field(default_factory=dict, compare=False)

    def offset(self, q: NDArray, T: NDArray, branch: int, move: NDArray) -> NDArray | None:
        """The configuration of pose ``T`` moved by ``move (3,)`` mm (part frame, orientation
        kept) on branch ``branch``, at the turn nearest ``q``; ``None`` when not usable."""
        Tr = T.copy()
        Tr[:3, 3] = T[:3, 3] + move
        br = self.robot.ik_all(Tr @ np.linalg.inv(self.flange_tcp))
        if branch < 0 or not usable(br, self.singular_deg)[0, branch]:
            return None
        qr = q + np.angle(np.exp(1j * (br.q[0, branch] - q)))  # the turn nearest q
        return qr if self.robot.in_limits(qr[None])[0] else br.q[0, branch]

    def retract(self, q: NDArray, T: NDArray, branch: int) -> tuple[NDArray, NDArray] | None:
        """The first retract of :data:`RETRACT_DIRS` x :data:`RETRACT_MM` from configuration ``q``
        at TCP pose ``T`` that works (module docstring): ``(q_retract, move (3,) mm)``."""
        for axis, sign in RETRACT_DIRS:
            for d in RETRACT_MM:
                move = sign * d * T[:3, axis]
                qr = self.offset(q, T, branch, move)
                if (
                    qr is not None
                    and self.checker.state_free(qr)
                    and self.checker.motion_free(q, qr, zone=True)
                ):
                    return qr, move
        return None

    def leave(self, q: NDArray, row: int, branch: int) -> NDArray | None:
        """``(p, 6)`` rad from the weld at route row ``row`` (configuration ``q``, not included)
        to a clear configuration (the last row): along one of the gun's proven exits
        (:attr:`exits`, :meth:`follow`), else by :meth:`retract`; ``None`` when neither works.
        The same rows reversed approach the weld."""
        for T in self.exits.get(row, ()):
            P = self.follow(q, T, branch)
            if P is not None:
                self.left_by["gun exit"] = self.left_by.get("gun exit", 0) + 1
                return P
        got = self.retract(q, self.T_tcp[row], branch)
        if got is None:
            return None
        self.left_by["retract"] = self.left_by.get("retract", 0) + 1
        return got[0][None]

    def follow(self, q: NDArray, T: NDArray, branch: int) -> NDArray | None:
        """``(k - 1, 6)`` rad: IK along the TCP poses ``T[1:]`` (``T (k, 4, 4)`` mm, ``T[0]`` the
        weld's) on ``branch``, each at the turn nearest the previous, from configuration ``q``;
        the first motion checked with the contact zone exempt (the lift off the sheet), every
        later one and the last configuration with the whole tool. ``None`` where a step is not
        usable or a motion is blocked."""
        out: list[NDArray] = []
        prev = np.asarray(q, dtype=np.float64)
        for Tk in T[1:]:
            qk = self.offset(prev, Tk, branch, np.zeros(3))
            if qk is None or not self.checker.motion_free(prev, qk, zone=not out):
                return None
            out.append(qk)
            prev = qk
        if not out or not self.checker.state_free(prev):
            return None
        return np.array(out)

    def transfer(self, qa: NDArray, qb: NDArray) -> NDArray | None:
        """``(p, 6)`` rad from ``qa`` to ``qb`` (ends included), whole tool and links free:
        straight, else through a tucked arm (``tuck``, default :data:`TUCK_A2_A3`), else OMPL."""
        if self.checker.motion_free(qa, qb):
            return np.vstack([qa, qb])
        for a2, a3 in self.tuck:
            P = np.array([qa, qa, qb, qb])
            P[1:3, 1:3] = np.radians([a2, a3])
            if not self.robot.in_limits(P[1:3]).all():
                continue
            if all(self.checker.motion_free(x, y) for x, y in zip(P[:-1], P[1:], strict=True)):
                return P
        return self._ompl(qa, qb)

    def _ompl(self, qa: NDArray, qb: NDArray) -> NDArray | None:
        """OMPL in joint space (:func:`~weldplan.motion.sampling.plan_rn`), ``time_s``; while
        that is not enough, more runs of ``retry_time_s`` with the next seeds as long as the
        route's retries have spent less than ``retry_total_s`` (the first leg that needs them
        may take them all: on a route along the gun's order, a leg that cannot be detoured is
        a bridge between two groups of welds, and every later weld of the far group would be
        tried from the same weld across the same gap)."""
        from weldplan.motion.sampling import plan_rn

        k = 0
        while True:
            if k and (
                self.retry_time_s <= 0 or self.ompl.get("retry_s", 0.0) >= self.retry_total_s
            ):
                if k == 1:
                    log.info("joint-space transfer: no retry (%.0f s spent)", self.retry_total_s)
                return None
            res = plan_rn(
                qa,
                qb,
                self.robot.lower,
                self.robot.upper,
                self.checker.state_free,
                motion_valid=self.checker.motion_free,
                planner=self.planner,
                time_s=self._run_time(k),
                seed=None if self.rng is None else self.rng + k,
            )
            log.info("joint-space transfer%s: %s", f" (retry {k})" if k else "", res.status)
            for key, v in (("runs", 1), ("retries", k > 0), ("solved", res.solved)):
                self.ompl[key] = self.ompl.get(key, 0) + float(v)
            self.ompl["s"] = self.ompl.get("s", 0.0) + res.time_s
            if k:
                self.ompl["retry_s"] = self.ompl.get("retry_s", 0.0) + res.time_s
            if res.solved:
                return np.asarray(res.points, dtype=np.float64)
            k += 1

    def _run_time(self, k: int) -> float:
        """s of OMPL run ``k`` of a transfer: the first ``time_s``, a retry ``retry_time_s`` or
        what is left of the route's ``retry_total_s``, whichever is less."""
        if not k:
            return self.time_s
        left = self.retry_total_s - self.ompl.get("retry_s", 0.0)
        return max(min(self.retry_time_s, left), 1e-3)


def subdivide(P: NDArray[np.float64], inner: int) -> NDArray[np.float64]:
    """``P (p, 6)`` with points added on its longest segments (halving them) until it has at
    least ``inner`` rows strictly between its ends; the polyline itself is unchanged."""
    P = np.asarray(P, dtype=np.float64)
    while len(P) - 2 < inner:
        seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
        i = int(np.argmax(seg))
        P = np.insert(P, i + 1, (P[i] + P[i + 1]) / 2, axis=0)
    return P


def assemble(
    det: Detour,
    q: NDArray[np.float64],
    exact: NDArray[np.bool_],
    branch: NDArray[np.int64],
    rows: NDArray[np.int64],
    status: list[str],
    detail: list[str],
    ids: tuple[str, ...],
    zone: NDArray[np.bool_] | None = None,
    blocked: set[int] | None = None,
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, list[int]]:
    """The joint route with blocked legs detoured (module docstring).

    Parameters
    ----------
    q, exact, branch
        ``(m, 6)`` rad, ``(m,)``, ``(m,)``: one row per route waypoint.
    rows
        ``(n,)``: the route rows of the welds, in route order.
    status, detail
        Per weld; updated in place for the welds dropped.
    ids
        The welds' ids (for the details).
    zone
        ``(m - 1,) bool``: the route's own motions on which the contact zone is exempt (default
        every one; a route along the gun's transitions exempts it only near the spots).
    blocked
        The route's own motions the caller's check of ``q`` (same checker, same ``zone``) found
        blocked, every one: a leg with none of them is not checked again. ``None``: each leg is
        checked here.

    Returns
    -------
    q, row, exact, branch, zone, replanned
        The assembled route (``zone (k - 1,)`` per motion) and the legs detoured (the position
        in ``rows`` of the weld each leaves).
    """
    served = [k for k in range(len(rows)) if status[k] == OK]
    own = np.ones(max(len(q) - 1, 0), dtype=bool) if zone is None else np.asarray(zone, bool)
    own = np.append(own, True)  # own[i]: the motion leaving route row i (the last: none)
    out = JointPath()
    served_exact = np.zeros(len(q), dtype=bool)
    served_exact[rows[served]] = True
    # a weld row that is not served is passed, never exact
    ex = exact & (served_exact | ~np.isin(np.arange(len(q)), rows))
    if not served:
        for i in range(len(q)):
            out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
        return (*out.arrays(), [])
    for i in range(int(rows[served[0]]) + 1):
        out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
    a, replanned = _legs(det, out, q, ex, branch, rows, served, status, detail, ids, own, blocked)
    _tail(det, out, q, ex, branch, int(rows[a]), own, blocked)
    return (*out.arrays(), replanned)


def _legs(
    det: Detour,
    out: JointPath,
    q: NDArray,
    ex: NDArray,
    branch: NDArray,
    rows: NDArray[np.int64],
    served: list[int],
    status: list[str],
    detail: list[str],
    ids: tuple[str, ...],
    own: NDArray[np.bool_],
    blocked: set[int] | None,
) -> tuple[int, list[int]]:
    """Every leg between served welds onto ``out`` (from the first served weld's row on),
    detoured where blocked; ``(the last weld kept, the legs detoured)``. A weld with no detour
    to it is dropped, and the next is tried from the same weld ``a``; when a second weld in a
    row cannot be reached from ``a``, ``a`` is the weld that cannot be left: it is dropped
    instead (its leg taken off ``out``) and the welds dropped after it are tried again from
    the weld before it, once (a weld reached that way is not dropped for being stuck)."""
    replanned: list[int] = []
    kept = [(served[0], len(out.q), 0)]  # (weld, rows of out and legs detoured before its leg)
    lost: list[int] = []  # welds dropped in a row from the last kept one
    todo = list(served[1:])
    backed = -1  # the weld the route was taken back to (not dropped for being stuck)
    while todo:
        a, b = kept[-1][0], todo.pop(0)
        ia, ib = int(rows[a]), int(rows[b])
        hits = _leg_hits(det, q, own, ia, ib, blocked)
        start = (b, len(out.q), len(replanned))
        if not hits:
            out.zone[-1] = bool(own[ia])
            for i in range(ia + 1, ib + 1):
                out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
            kept.append(start)
            lost = []
            continue
        path = _detour(det, q, branch, ia, ib)
        if path is not None:
            _add_detour(out, det.robot, path, ia, ib, rows, q, branch)
            replanned.append(a)
            kept.append(start)
            lost = []
            continue
        why = f"{hits[0].body} on the leg from weld {ids[a]}; no detour through retract poses found"
        if lost and len(kept) > 1 and a != backed:  # a cannot be left: drop it instead
            _, n_rows, n_rep = kept.pop()
            del out.q[n_rows:], out.row[n_rows:], out.exact[n_rows:], out.branch[n_rows:]
            del out.zone[n_rows:], replanned[n_rep:]
            status[a] = COLLISION
            detail[a] = (
                f"cannot be left: {hits[0].body} on the legs to welds {ids[lost[0]]} and "
                f"{ids[b]}, no detour through retract poses found (dropped instead of them)"
            )
            log.info("weld %s dropped: %s", ids[a], detail[a])
            for k in lost:
                status[k], detail[k] = OK, ""
            todo[:0] = [*lost, b]
            lost, backed = [], kept[-1][0]
            continue
        status[b], detail[b] = COLLISION, why
        log.info("weld %s dropped: %s", ids[b], detail[b])
        lost.append(b)
    return kept[-1][0], replanned


def _leg_hits(
    det: Detour, q: NDArray, own: NDArray, ia: int, ib: int, blocked: set[int] | None
) -> list[Any]:
    """The first blocked motion of the route's own rows ``ia..ib`` (``[]``: free), from the
    caller's ``blocked`` motions when given, else checked here."""
    if blocked is None:
        return det.checker.path_hits(q[ia : ib + 1], own[ia:ib], first_only=True)
    at = sorted(s for s in blocked if ia <= s < ib)
    if not at:
        return []
    return det.checker.path_hits(q[at[0] : at[0] + 2], own[at[0] : at[0] + 1])


def _detour(det: Detour, q: NDArray, branch: NDArray, ia: int, ib: int) -> NDArray | None:
    """``[leave a ..., transfer ..., approach b ...]`` (rad), else ``None``."""
    la = det.leave(q[ia], ia, int(branch[ia]))
    lb = None if la is None else det.leave(q[ib], ib, int(branch[ib]))
    if la is None or lb is None:
        return None
    mid = det.transfer(la[-1], lb[-1])
    if mid is None:
        return None
    return np.vstack([la[:-1], mid, lb[:-1][::-1]])


def _add_detour(
    out: JointPath,
    robot: Robot,
    path: NDArray,
    ia: int,
    ib: int,
    rows: NDArray[np.int64],
    q: NDArray,
    branch: NDArray,
) -> None:
    """Rows of a detour from the weld at route row ``ia`` to the one at ``ib``: the retract
    (labelled ``ia``), inner points (labelled ``ia``, then one per weld passed between), the
    approach (labelled ``ib``) and the weld ``ib`` itself."""
    passed = [int(r) for r in rows if ia < r < ib]
    P = subdivide(path, len(passed))
    pb = robot.branch_of(P)
    labels = [ia] * len(P)
    labels[-1] = ib
    for j, r in enumerate(passed):  # the last inner points stand for the welds passed
        labels[len(P) - 1 - len(passed) + j] = r
    out.zone[-1] = True  # weld -> retract: contact zone exempt
    for p, lab, b in zip(P, labels, pb, strict=True):
        out.add(p, lab, False, int(b), zone=False)
    out.zone[-1] = True  # approach -> weld
    out.add(q[ib], ib, True, int(branch[ib]))


def _tail(
    det: Detour,
    out: JointPath,
    q: NDArray,
    ex: NDArray,
    branch: NDArray,
    ia: int,
    own: NDArray[np.bool_],
    blocked: set[int] | None = None,
) -> None:
    """The route's rows after the last served weld (module docstring); ``own[i]``: the contact
    zone is exempt on the route's own motion leaving row ``i``."""
    m = len(q)
    if ia + 1 >= m:
        return
    if not _leg_hits(det, q, own, ia, m - 1, blocked):
        out.zone[-1] = bool(own[ia])
        for i in range(ia + 1, m):
            out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
        return
    got = det.retract(q[ia], det.T_tcp[ia], int(branch[ia]))
    out.zone[-1] = True  # weld -> retract (or no motion): contact zone exempt, as checked
    if got is None:
        # no way off the last served weld: the robot stays there (zero motions), the route's
        # later welds are passed without welding; before, the route's own blocked rows were
        # kept and the final check refused the whole route
        log.info("no retract from the last served weld: the program ends there")
        for i in range(ia + 1, m):
            out.add(q[ia], i, False, int(branch[ia]))
        return
    # the rest of the route's rows as points on the retract from the last served weld (a motion
    # retract() checked), the last of them the retract configuration itself
    P = subdivide(np.vstack([q[ia], got[0]]), m - 2 - ia)[1:]
    pb = det.robot.branch_of(P)
    for j, i in enumerate(range(ia + 1, m)):
        out.add(P[j], i, False, int(pb[j]))
