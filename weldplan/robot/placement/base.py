"""Choosing the robot base for a route: kinematics first, then collisions at the welds, then the
whole route (:func:`place`, used by :func:`weldplan.robot.route.plan_robot_route`).

1. :func:`weldplan.robot.placement.search_base` ranks floor (or line) candidates, at every pedestal
   height and yaw of its :class:`~weldplan.robot.placement.BaseSearch`, by the welds they make
   usable (reach, limits, wrist singularity), then by manipulability; the best
   :data:`POOL` go on.
2. With a collision checker, each of those is re-ranked by the welds it serves *collision-free*:
   a weld counts when at least one usable branch has no link touching the part at the weld pose
   (:meth:`~weldplan.robot.collision.RobotCollision.states_blocked`, FCL judges). The tool is
   left out of this ranking: at a weld it is where the weld pose puts it whatever the base, and
   the tool stage verified it there; the final check of the route includes it.
3. The best ``top`` are solved along the whole route (:func:`~weldplan.robot.route.joint_path`
   with the collision-free branches at the welds) and ranked by welds ok, then the smallest
   manipulability of the chosen configurations over every solved waypoint.
4. With a checker, those are re-ranked by the welds the robot can **join** in one group (issue
   27, item 2), then by step 3's key (:func:`rank_bases`,
   :func:`~weldplan.robot.placement.join_welds`).
   By default (``PlacementSettings.trial``) the *transfer trial* alone: consecutive served welds
   whose own leg is free are joined, and so are the ends of a blocked leg when a straight or
   tucked-arm joint motion joins their retracts (the detours' own first tries, FCL: no
   planner, the same work on any machine); each leg that stays split is named with its cause
   (:attr:`~weldplan.robot.placement.roadmaps.WeldJoin.splits`). With roadmap settings
   (``PlacementSettings.joins``) the ends of the legs still blocked go into one joint-space
   roadmap on their IK branch (OMPL's PRM, :mod:`weldplan.motion.roadmap`, on the same FCL
   checks as the detours: part, self-collision, floor) and are joined where it puts their
   retracts in one component; a weld left out tries its other retracts and alternative poses
   first; the chosen base's roadmap goes on to the detours
   (:class:`~weldplan.robot.placement.LegRoadmap`). Best first, a candidate that serves no more
   welds than the best joined so far is skipped, so where the first candidate joins all it
   serves, it is the only one judged. With the trial (or a roadmap) to come, step 2 hands on one
   candidate per floor position before a second of any (:func:`_by_stand`), so the trial judges
   different stands; each judged base's verdict (the welds it does not serve, the served welds it
   leaves out of the largest group, the legs that stay split) is kept
   (:attr:`~weldplan.robot.placement.Placement.verdicts`, :class:`BaseVerdict`).

With each weld's **alternative poses** (the tool's other free poses,
:mod:`weldplan.robot.placement.altreach`; on request of the pose stage's search,
``place_for_poses(alternatives=True)``) a weld counts at every step when its pose or one of them
serves: in the full score of step 1, in step 2 (a weld's poses checked in rounds, the chosen one
first; the best by the given poses alone are handed on too), and in step 3 (a weld the route's
pose loses counts when another of its poses is free there, and each leg whose joint path takes a
link through the part counts against the base). Reach over-promises where the arm would pass
through the part, so step 2 then takes the candidates best first by reach until :data:`POOL` are
checked **and** the next one's reach count is below the best count served (every
:data:`~weldplan.robot.placement.PRESELECT` candidate at most), instead of a fixed :data:`POOL`:
car2_200 had 78 candidates reaching all 200 welds, and the 48 with the best manipulability among
them served at most 193 without a link in the body. The CLI does not ask for it: from the bases
it finds on car2_200 (every weld pose served) the robot route served 7 of 200 when it was
measured; why it is off: docs/robot-placement.md, "Tool poses the arm reaches" (*Alternative
poses*).
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.altreach import alt_free
from weldplan.robot.placement.reach import (
    OK,
    PRESELECT,
    TIE_DECIMALS,
    BaseSearch,
    Placement,
    search_base,
    usable,
)
from weldplan.robot.placement.roadmaps import join_welds
from weldplan.robot.route.configs import joint_path
from weldplan.robot.route.replan import Detour
from weldplan.robot.settings import PlacementSettings

log = logging.getLogger(__name__)

#: kinematically best candidates re-ranked by the collision test at the welds
POOL = 48
#: split legs a base's log line names (all of them are in its :class:`WeldJoin`)
SPLITS_LOGGED = 3


@dataclass(frozen=True)
class BaseVerdict:
    """What step 4 found at one of the best bases: the welds it leaves out and why.

    Judged on the poses and order the search was given (before the pose stage re-chooses the
    poses at the chosen base, and before the tool stage's order): a weld left out here is a
    doubt, not a verdict on the program, whose detours still try the split legs.

    Attributes
    ----------
    base
        ``(x, y, z, yaw)`` mm and deg (the ``--robot-base`` form).
    served
        Welds with a usable IK branch and no link in the part at their pose (step 3).
    joined
        Served welds in the largest group the transfer trial joins; ``-1``: not judged (it
        serves no more welds than a base judged before it joins: it cannot do better).
    unserved
        The welds (by id) not served there: the reach verdict.
    left_out
        The served welds (by id) outside the largest group: the transfer verdict.
    splits
        The legs that stay split, ``"A -> B: why"``
        (:attr:`~weldplan.robot.placement.roadmaps.WeldJoin.splits`).
    """

    base: tuple[float, float, float, float]
    served: int
    joined: int
    unserved: tuple[str, ...]
    left_out: tuple[str, ...]
    splits: tuple[str, ...] = ()

    def summary(self) -> dict[str, Any]:
        """JSON-ready (the route's ``stats["placement"]["bases"]``)."""
        return dataclasses.asdict(self)

    def line(self) -> str:
        """One line: ``"served S, joined J; not served: ...; left out: ...; split A -> B: ..."``."""
        if self.joined < 0:
            return f"serves {self.served}: not judged (no more than a base judged before joins)"
        out = f"{self.joined} of {self.served} served welds joined"
        for label, ids in (("not served", self.unserved), ("left out", self.left_out)):
            if ids:
                out += f"; {label}: {_id_list(ids)}"
        return out + "".join(f"; split {s}" for s in self.splits[:SPLITS_LOGGED])


def _id_list(ids: tuple[str, ...], most: int = 12) -> str:
    """``"a, b, c"``, or the first ``most`` and how many more."""
    more = len(ids) - most
    return ", ".join(ids[:most]) + (f" and {more} more" if more > 0 else "")


def free_branches(
    robot: Robot,
    checker: Any,
    T_weld: NDArray[np.float64],
    singular_deg: float,
    *,
    tool: bool = True,
) -> tuple[NDArray[np.bool_], list[str | None]]:
    """The usable IK branches of each weld pose that do not touch the part.

    Parameters
    ----------
    robot
        The robot at its base.
    checker
        A :class:`~weldplan.robot.collision.RobotCollision` for that base.
    T_weld
        ``(n, 4, 4)`` mm: flange poses (NaN: no pose).
    tool
        Check the tool (minus its contact zone) as well as the links.

    Returns
    -------
    free, blame
        ``(n, 8) bool``; per weld the body that blocks its first usable branch (``None`` when a
        branch is free or none is usable).
    """
    has = np.all(np.isfinite(T_weld), axis=(1, 2))
    br = robot.ik_all(np.where(has[:, None, None], T_weld, np.eye(4)))
    ok = usable(br, singular_deg) & has[:, None]
    idx = np.argwhere(ok)
    blocked = checker.states_blocked(br.q[idx[:, 0], idx[:, 1]], zone=True, tool=tool)
    free = np.zeros_like(ok)
    blame: list[str | None] = [None] * len(T_weld)
    for (i, j), b in zip(idx, blocked, strict=True):
        if b is None:
            free[i, j] = True
        elif blame[i] is None:
            blame[i] = b
    for i in np.flatnonzero(free.any(axis=1)):
        blame[i] = None
    return free, blame


def place(
    robot: Robot,
    T_fl: NDArray[np.float64],
    rows: NDArray[np.int64],
    part: Any,
    base: ArrayLike | None,
    search: BaseSearch | None,
    checker_for: Any,
    settings: PlacementSettings,
    alternatives: list[NDArray[np.float64]] | None = None,
    ids: tuple[str, ...] | None = None,
) -> tuple[Placement, NDArray[np.bool_] | None]:
    """The base (given, the robot's own, or searched: module docstring) and, for a searched one,
    the allowed-branch mask of its weld rows (``None`` for a given base: the caller computes it).

    ``checker_for(robot_at_base)`` builds the collision checker (``None``: no collision test;
    give it the tool for step 4 to check it on the legs). ``settings``: the singular threshold,
    the flip penalty, the candidates re-scored along the route (``top``) and, with a checker,
    step 4 (``trial``, ``joins``): the candidates of step 3 re-ranked by the welds joined in one
    group (:func:`join_welds`; the placement's :attr:`~weldplan.robot.placement.Placement.join`).
    ``alternatives``: per weld row, ``(k, 4, 4)`` mm flange poses of the weld's other free tool
    poses (:mod:`weldplan.robot.placement.altreach`); a weld counts at a base when its pose or
    one of them serves there, at every step. ``ids``: the welds' names (route order) in the
    reports of step 4.
    """
    T_weld = T_fl[rows]
    if base is not None or search is None:
        B = robot.base if base is None else np.asarray(base, dtype=np.float64)
        return Placement(B, -1, len(T_weld), float("nan"), 0, False), None
    sd, top = settings.singular_deg, settings.top
    ok = np.all(np.isfinite(T_weld), axis=(1, 2))
    alts = alternatives
    pool = POOL if checker_for is not None else top
    if alts is not None and checker_for is not None:
        pool = PRESELECT  # every fully scored candidate: the re-rank stops by its bound
    cands = search_base(
        robot, T_weld[ok], part, search, singular_deg=sd, top=pool,
        alternatives=None if alts is None else [a for a, k in zip(alts, ok, strict=True) if k],
    )  # fmt: skip
    masks: list[NDArray[np.bool_] | None] = [None] * len(cands)
    if checker_for is not None:
        judged = settings.trial or settings.joins is not None
        cands, masks = _rerank(robot, cands, T_weld, checker_for, sd, top, alts, judged)
    return rank_bases(robot, cands, masks, T_fl, rows, checker_for, settings, alts, ids)


def rank_bases(
    robot: Robot,
    cands: list[Placement],
    masks: list[NDArray[np.bool_] | None],
    T_fl: NDArray[np.float64],
    rows: NDArray[np.int64],
    checker_for: Any,
    settings: PlacementSettings,
    alts: list[NDArray[np.float64]] | None = None,
    ids: tuple[str, ...] | None = None,
) -> tuple[Placement, NDArray[np.bool_] | None]:
    """Steps 3 and 4 of the module docstring: the best of ``cands`` (with their allowed-branch
    masks, ``None``: every branch) along the whole route (flange poses ``T_fl (m, 4, 4)`` mm,
    welds at ``rows``, named ``ids``), then, with a checker and ``settings.trial`` or
    ``settings.joins``, by the welds joined in one group
    (:func:`~weldplan.robot.placement.join_welds`); ties keep the order of ``cands``."""
    scored = []
    for pl, mask in zip(cands, masks, strict=True):
        rb = robot.with_base(pl.base)
        got = _route_score(
            rb, T_fl, rows, mask, checker_for, settings.singular_deg, settings.flip_penalty, alts
        )
        if got is not None:
            scored.append((got[0], dataclasses.replace(pl, min_manipulability=got[0][1]), mask,
                           got[1]))  # fmt: skip
    if not scored:
        raise PlanningError(
            f"no base among the {len(cands)} best candidates reaches a weld collision-free"
        )
    scored.sort(key=lambda s: s[0], reverse=True)  # stable: ties keep the search's order
    if checker_for is None or (settings.joins is None and not settings.trial):
        return scored[0][1], scored[0][2]
    return _by_joins(robot, scored, T_fl, rows, checker_for, settings, alts, ids)


def _by_joins(
    robot: Robot,
    scored: list[tuple[tuple[int, float], Placement, Any, Any]],
    T_fl: NDArray[np.float64],
    rows: NDArray[np.int64],
    checker_for: Any,
    settings: PlacementSettings,
    alts: list[NDArray[np.float64]] | None = None,
    ids: tuple[str, ...] | None = None,
) -> tuple[Placement, NDArray[np.bool_] | None]:
    """Step 4: the candidates of step 3 (best first) by the welds they join in one group
    (:func:`~weldplan.robot.placement.join_welds`: the transfer trial, and the roadmap of
    ``settings.joins`` when given; with each weld's alternative poses ``alts``), then their
    step-3 key (welds served, then manipulability).
    A candidate serving no more welds than the best joined count so far cannot beat it and is
    not judged (the welds it serves bound those it joins): when the first candidate joins every
    weld it serves, one is judged."""
    best: tuple[tuple[int, tuple[int, float]], Placement, Any] | None = None
    names = ids if ids is not None else tuple(f"weld {k + 1}" for k in range(len(rows)))
    verdicts: list[BaseVerdict] = []
    for key, pl, mask, (q, branch, status) in scored:
        served = np.array([status[r] == OK for r in rows], dtype=bool)
        unserved = tuple(names[k] for k in np.flatnonzero(~served))
        if best is not None and served.sum() <= best[0][0]:
            verdicts.append(BaseVerdict(pl.xyz_yaw(), int(served.sum()), -1, unserved, ()))
            continue
        rb = robot.with_base(pl.base)
        checker = checker_for(rb)
        det = Detour(rb, checker, T_fl @ checker.flange_tcp, checker.flange_tcp,
                     settings.singular_deg, "rrtconnect", 1.0, 0)  # fmt: skip
        wj = join_welds(det, q, branch, rows, served, settings.joins, alts=alts, ids=ids)
        x, y, z, yaw = pl.xyz_yaw()
        log.info(
            "base %.0f,%.0f,%.0f,%.1f: %d/%d served welds joined (%d blocked legs%s%s)",
            x, y, z, yaw, wj.n_joined, int(served.sum()), wj.blocked_legs,
            "" if wj.report is None else "; roadmap " + wj.report.line(),
            "".join(f"; split {s}" for s in wj.splits[:SPLITS_LOGGED]),
        )  # fmt: skip
        verdicts.append(BaseVerdict(
            pl.xyz_yaw(), int(served.sum()), wj.n_joined, unserved,
            tuple(names[k] for k in np.flatnonzero(served & ~wj.main)), wj.splits,
        ))  # fmt: skip
        if best is None or (wj.n_joined, key) > best[0]:
            best = ((wj.n_joined, key), dataclasses.replace(pl, join=wj), mask)
    assert best is not None
    return dataclasses.replace(best[1], verdicts=tuple(verdicts)), best[2]


def _route_score(
    rb: Robot,
    T_fl: NDArray[np.float64],
    rows: NDArray[np.int64],
    mask: NDArray[np.bool_] | None,
    checker_for: Any,
    singular_deg: float,
    flip_penalty: float,
    alts: list[NDArray[np.float64]] | None,
) -> tuple[tuple[int, float], tuple[NDArray, NDArray, NDArray]] | None:
    """Step 3 for the robot at one base: ``(welds ok along the route, the smallest
    manipulability of its solved waypoints)`` and the route's joint path ``(q (m, 6), branch
    (m,), status (m,))``, ``None`` when it reaches none. With ``alts`` a
    weld the route's pose loses counts when another of its poses is free there, and, with a
    checker, each leg between welds on which the route's joint path puts a link through the part
    (:meth:`~weldplan.robot.collision.RobotCollision.path_hits`) counts against it: it needs a
    detour, which may not exist (module docstring)."""
    allowed = _allowed(len(T_fl), rows, mask)
    try:
        q, branch, exact, status = joint_path(
            rb, T_fl, singular_deg=singular_deg, flip_penalty=flip_penalty, allowed=allowed
        )
    except PlanningError:  # no weld pose reached: only their alternatives may serve
        if alts is None:
            return None
        q, exact = np.zeros((0, 6)), np.zeros(0, dtype=bool)
        branch = np.zeros(0, dtype=np.int64)
        status = np.full(len(T_fl), "", dtype=object)
    lost = np.array([status[r] != OK for r in rows], dtype=bool)
    n_ok = int((~lost).sum())
    checker = None if checker_for is None or alts is None else checker_for(rb)
    if alts is not None and lost.any():  # served at this base by another of their poses
        n_ok += int(alt_free(rb, checker, alts, lost, singular_deg).sum())
        if n_ok == 0:
            return None
    n_legs, legs_said = 0, ""
    if alts is not None and checker is not None and len(q) > 1:
        segs = sorted({h.segment for h in checker.path_hits(q)})
        legs = np.searchsorted(rows, segs, side="right") - 1  # the weld each leaves
        n_legs = len(set(legs[(legs >= 0) & (legs < len(rows) - 1)].tolist()))
        legs_said = f", {n_legs} legs with a link through the part"
    m = float(rb.manipulability(q[exact]).min()) if exact.any() else -np.inf
    m = round(m, TIE_DECIMALS)  # bases equal but for round-off tie: the search's order decides
    x, y, z = rb.base[:3, 3]
    yaw = np.degrees(np.arctan2(rb.base[1, 0], rb.base[0, 0]))
    log.info(
        "base %.0f,%.0f,%.0f,%.1f along the route: %d/%d welds served%s, min manipulability %.4f",
        x, y, z, yaw, n_ok, len(rows), legs_said, m,
    )  # fmt: skip
    return (n_ok - n_legs, m), (q, branch, status)


def _rerank(
    robot: Robot,
    cands: list[Placement],
    T_weld: NDArray[np.float64],
    checker_for: Any,
    singular_deg: float,
    top: int,
    alts: list[NDArray[np.float64]] | None,
    spread: bool = False,
) -> tuple[list[Placement], list[NDArray[np.bool_] | None]]:
    """The ``top`` of ``cands`` by the welds they serve without a link in the part at the weld
    pose, then manipulability; with their free-branch masks of the given poses. With ``alts``
    (module docstring) a weld counts when one of its poses serves, and the candidates (best
    first by reach) are checked until :data:`POOL` are and the next one's reach count is below
    the best count served. With ``spread`` (step 4 follows) each floor position gives one
    candidate before any gives a second (:func:`_by_stand`)."""
    keys: list[tuple[int, float]] = []
    given: list[tuple[int, float]] = []
    masks: list[NDArray[np.bool_] | None] = []
    for pl in cands:
        rb = robot.with_base(pl.base)
        checker = checker_for(rb)
        if alts is None:
            free, _ = free_branches(rb, checker, T_weld, singular_deg, tool=False)
            masks.append(free)
            keys.append((int(free.any(axis=1).sum()), pl.min_manipulability))
            continue
        if len(keys) >= POOL and pl.n_usable < max(keys)[0]:
            break
        first = np.zeros(len(alts), dtype=bool)
        served = alt_free(rb, checker, alts, np.ones(len(alts), dtype=bool), singular_deg, first)
        masks.append(None)
        keys.append((int(served.sum()), pl.min_manipulability))
        given.append((int(first.sum()), pl.min_manipulability))
    order = sorted(range(len(keys)), key=lambda c: keys[c], reverse=True)
    order = _by_stand(cands, order)[:top] if spread else order[:top]
    if alts is not None:  # and the best by the given poses alone (module docstring)
        by_given = sorted(range(len(given)), key=lambda c: given[c], reverse=True)[:top]
        order += [c for c in by_given if c not in order]
    log.info(
        "base search: %d candidates re-ranked by collisions at the welds; best serves %d/%d",
        len(keys),
        keys[order[0]][0],
        len(T_weld),
    )
    out = [cands[c] for c in order]
    if alts is not None:  # the masks of the few that go on
        masks = [None] * len(keys)
        for c, pl in zip(order, out, strict=True):
            rb = robot.with_base(pl.base)
            masks[c] = free_branches(rb, checker_for(rb), T_weld, singular_deg, tool=False)[0]
    return out, [masks[c] for c in order]


def _by_stand(cands: list[Placement], order: list[int]) -> list[int]:
    """``order`` (indices of ``cands``, best first) with the first candidate of each floor
    position ``(x, y)`` ahead of the others, each part in its order. The pedestal heights and
    yaws of one stand mostly serve the same welds and split the same legs (the trial tells
    them apart rarely: on car2_200 every one of the top five, one stand turned five ways,
    split at the same leg), so step 4 judges different stands first."""
    seen: set[tuple[float, float]] = set()
    first, rest = [], []
    for c in order:
        xy = (round(float(cands[c].base[0, 3]), 3), round(float(cands[c].base[1, 3]), 3))
        (rest if xy in seen else first).append(c)
        seen.add(xy)
    return first + rest


def _allowed(m: int, rows: NDArray[np.int64], mask: NDArray[np.bool_] | None) -> NDArray | None:
    """``(m, 8) bool``: every branch allowed except at the weld rows, where ``mask`` says."""
    if mask is None:
        return None
    allowed = np.ones((m, 8), dtype=bool)
    allowed[rows] = mask
    return allowed
