"""Which welds the robot can join at a base: joint-space roadmaps on the welds' IK branch.

A base that reaches every weld may still be one from which the welds cannot be joined (the arm
reaches each, not one from the next). :func:`join_welds` judges a base by the welds it can join:
the route's own free legs and, for the legs that are blocked, the *transfer trial* (the ends'
retracts joined by a straight or tucked-arm joint motion, the detours' own first tries: no
planner) and, when asked, one OMPL roadmap (:mod:`weldplan.motion.roadmap`) on the FCL checks of
the detours (:class:`~weldplan.robot.route.Detour`). The base search ranks its best candidates by
it (:func:`weldplan.robot.placement.rank_bases`, step 4: by default the trial alone), and the
detours ask the chosen base's roadmap before OMPL (:class:`LegRoadmap`,
:meth:`~weldplan.robot.route.Detour.via_roadmap`). Issue 27, item 2; docs/robot-placement.md,
"Joining the welds".
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.motion.roadmap import Roadmap, RoadmapReport, RoadmapSettings, build_roadmap
from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.reach import usable
from weldplan.robot.route.replan import Detour

log = logging.getLogger(__name__)

#: deg: margin about the welds' A1 and wrist angles of the box a weld roadmap samples
#: (:func:`branch_box`)
ROADMAP_MARGIN_DEG = 30.0
#: other retracts a weld outside the largest group tries (:func:`join_welds`; each is a query
#: of the roadmap: ``neighbours`` proven motions)
MORE_RETRACTS = 2


@dataclass(frozen=True)
class WeldJoin:
    """Which welds served at one base one joint-space roadmap joins (:func:`join_welds`).

    Attributes
    ----------
    group
        ``(n,) int`` per weld (route order): the group of welds it is joined with, by the
        route's own free legs or through the roadmap (-1: not served at this base).
    main
        ``(n,) bool``: in the largest group.
    n_joined
        Welds in the largest group.
    blocked_legs
        Legs between consecutive served welds whose own joint motion is blocked.
    report
        The roadmap's figures (``None``: no leg needed it).
    causes
        Per weld left out of the largest group: why (its id-free position, the group).
    branch
        The IK branch of the roadmap (-1: none built).
    roadmap
        The :class:`~weldplan.motion.roadmap.Roadmap` built (``None``: none needed).
    splits
        Per leg between consecutive served welds that stays split (its ends in different
        groups): ``"A -> B: why"`` (the body blocking its own motion, and a missing retract or
        transfer).
    """

    group: NDArray[np.int64]
    main: NDArray[np.bool_]
    n_joined: int
    blocked_legs: int
    report: RoadmapReport | None
    causes: tuple[str, ...]
    branch: int = -1
    roadmap: Any = field(default=None, compare=False, repr=False)
    splits: tuple[str, ...] = ()

    def summary(self) -> dict[str, Any]:
        """JSON-ready figures (the route's ``stats["placement"]["joins"]``)."""
        return {
            "joined": self.n_joined,
            "served": int((self.group >= 0).sum()),
            "blocked_legs": self.blocked_legs,
            "branch": self.branch,
            "roadmap": None if self.report is None else dataclasses.asdict(self.report),
            "left_out": list(self.causes),
            "split_legs": list(self.splits),
        }


def branch_box(
    robot: Robot, Q: NDArray[np.float64], margin_deg: float = ROADMAP_MARGIN_DEG
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(lower (6,), upper (6,))`` rad: the box a weld roadmap samples: the joint limits for A2
    and A3 (the arm folds through them on a transfer), the span of ``Q (k, 6)`` widened by
    ``margin_deg`` for A1 and the wrist (A4 and A6 turn almost twice round: a box over all of
    it would put the roadmap's few milestones a turn apart). A path inside the box is a path:
    the box narrows where milestones are sampled, not what an answer means."""
    lo = np.maximum(Q.min(axis=0) - np.radians(margin_deg), robot.lower)
    hi = np.minimum(Q.max(axis=0) + np.radians(margin_deg), robot.upper)
    lo[1:3], hi[1:3] = robot.lower[1:3], robot.upper[1:3]
    return lo, hi


def branch_roadmap(
    det: Detour,
    Q_ref: NDArray[np.float64],
    keep: int,
    settings: RoadmapSettings,
    seed: int | None,
) -> Roadmap:
    """OMPL's PRM (:class:`~weldplan.motion.roadmap.Roadmap`) for the robot of ``det`` at its
    base on IK branch ``keep``: states on the branch whose links and whole tool are free
    (``det.checker.state_free``: the part, self-collision, the floor when known), motions that
    stay on the branch and are free (:meth:`~weldplan.robot.route.Detour.motion_ok`, the
    detours' own test), in :func:`branch_box` about ``Q_ref (k, 6)``."""
    rb, checker = det.robot, det.checker
    plain = dataclasses.replace(det, roadmap=None)  # OMPL holds the checks: no cycle through it

    def valid(x: NDArray[np.float64]) -> bool:
        return int(rb.branch_bits(x)[0]) == keep and bool(checker.state_free(x))

    lo, hi = branch_box(rb, Q_ref)
    return build_roadmap(
        lo, hi, valid, lambda a, b: plain.motion_ok(a, b, keep), settings, seed=seed
    )


def retracts(det: Detour, q: NDArray, row: int, branch: int) -> list[NDArray[np.float64]]:
    """Every retract configuration of the weld at route row ``row`` (configuration ``q``) that
    :meth:`~weldplan.robot.route.Detour.retract` would accept, in its order (it takes the
    first): :data:`~weldplan.robot.route.RETRACT_DIRS` x
    :data:`~weldplan.robot.route.RETRACT_MM`."""
    from weldplan.robot.route.replan import RETRACT_DIRS, RETRACT_MM

    out = []
    T = det.T_tcp[row]
    for axis, sign in RETRACT_DIRS:
        for d in RETRACT_MM:
            qr = det.offset(q, T, branch, sign * d * T[:3, axis])
            if (
                qr is not None
                and det.checker.state_free(qr)
                and det.checker.motion_free(q, qr, zone=True)
            ):
                out.append(qr)
    return out


def join_welds(
    det: Detour,
    q: NDArray[np.float64],
    branch: NDArray[np.int64],
    rows: NDArray[np.int64],
    served: NDArray[np.bool_],
    settings: RoadmapSettings | None,
    seed: int | None = 0,
    alts: list[NDArray[np.float64]] | None = None,
    ids: tuple[str, ...] | None = None,
) -> WeldJoin:
    """Which served welds (``served (n,)``, route order, at route rows ``rows``; ``ids`` name
    them, default their positions) the robot of ``det`` can join, on the route's joint path
    ``q (m, 6)`` rad / ``branch (m,)``, as the detours would: consecutive served welds whose own
    leg is free (``path_hits``, the contact zone exempt as on a point-tip route) are joined; so
    are the ends of a blocked leg whose retracts (:meth:`~weldplan.robot.route.Detour.retract`)
    a straight or tucked-arm motion joins (:meth:`~weldplan.robot.route.Detour.direct`): the
    *transfer trial*, no planner. With roadmap ``settings`` (``None``: the trial alone) the
    retracts of the legs still blocked go into one roadmap on the welds' branch
    (:func:`branch_roadmap`; built only for them): welds whose retracts share a component are
    joined. A weld still outside the largest group tries up to :data:`MORE_RETRACTS` other
    retracts (:func:`retracts`) and, with ``alts`` (per weld, ``(k, 4, 4)`` mm flange poses, the
    chosen one first: :mod:`weldplan.robot.placement.altreach`), the retracts of its other poses
    usable on the branch with no link in the part (a weld joined by another pose counts, as in
    :func:`~weldplan.robot.placement.alt_free`: the pose stage picks it). Issue 27, item 2: a
    base is scored by the welds it can join, not only by those it reaches."""
    n = len(rows)
    g = _Groups(n)
    idx = np.flatnonzero(served)
    keep = int(np.bincount(branch[rows[idx]]).argmax()) if len(idx) else -1
    trial = _trial(det, q, branch, rows, idx, keep, g)
    rm, report = None, None
    if trial.pending and settings is not None:
        ends = sorted({k for leg in trial.pending for k in leg})
        pairs = [(k, trial.first[k]) for k in ends if trial.first[k] is not None]
        ref = np.vstack([q[rows[idx]], *(x for _, x in pairs)])
        rm = branch_roadmap(det, ref, keep, settings, seed)
        _unite(rm, pairs, g, [])
        for k in ends:  # welds outside the largest group: their other retracts, other poses
            r = int(rows[k])
            for more in (
                lambda: retracts(det, q[r], r, keep)[1 : 1 + MORE_RETRACTS],  # noqa: B023
                lambda: [] if alts is None else _alt_retracts(det, alts[k][1:], keep),  # noqa: B023
            ):
                if not g.in_main(k, served):
                    got = [(k, x) for x in more()]
                    _unite(rm, got, g, pairs)
                    pairs += got
        report = rm.report()
    return _weld_join(g, served, trial, report, keep if rm else -1, rm, ids)


class _Groups:
    """Union-find over the welds of one route (route order)."""

    def __init__(self, n: int) -> None:
        self.parent = np.arange(n)

    def find(self, k: int) -> int:
        while self.parent[k] != k:
            self.parent[k] = self.parent[self.parent[k]]
            k = int(self.parent[k])
        return k

    def join(self, a: int, b: int) -> None:
        self.parent[self.find(b)] = self.find(a)

    def in_main(self, k: int, served: NDArray[np.bool_]) -> bool:
        """Whether weld ``k`` is in the largest group now."""
        roots = [self.find(j) for j in np.flatnonzero(served)]
        vals, counts = np.unique(roots, return_counts=True)
        return self.find(k) == int(vals[np.argmax(counts)])


@dataclass
class _Trial:
    """What the transfer trial (:func:`_trial`) found: blocked legs, the legs left for the
    roadmap, each weld's first retract (``None``: none), the cause of each leg not joined."""

    legs: int
    pending: list[tuple[int, int]]
    first: dict[int, NDArray[np.float64] | None]
    cuts: dict[tuple[int, int], str]


def _trial(
    det: Detour,
    q: NDArray[np.float64],
    branch: NDArray[np.int64],
    rows: NDArray[np.int64],
    idx: NDArray[np.int64],
    keep: int,
    g: _Groups,
) -> _Trial:
    """The transfer trial of :func:`join_welds` over the consecutive served welds ``idx``:
    joins in ``g`` the legs whose own motion is free (one ``path_hits`` of the whole path: the
    sphere bound, then FCL) or whose ends' first retracts on branch ``keep`` a straight or
    tucked-arm joint motion joins; the others are kept with their cause."""
    zone = np.ones(max(len(q) - 1, 0), dtype=bool)
    hits = det.checker.path_hits(q, zone) if len(idx) > 1 else []
    segs = np.array(sorted({h.segment for h in hits}), dtype=np.int64)
    body = {h.segment: h.body for h in hits}
    out = _Trial(0, [], {}, {})

    def leave(k: int) -> NDArray[np.float64] | None:
        if k not in out.first:
            r = int(rows[k])
            got = det.retract(q[r], det.T_tcp[r], keep) if branch[r] == keep else None
            out.first[k] = None if got is None else got[0]
        return out.first[k]

    for a, b in zip(idx[:-1], idx[1:], strict=True):
        on = segs[(segs >= rows[a]) & (segs < rows[b])]
        if len(on) == 0:
            g.join(int(a), int(b))
            continue
        out.legs += 1
        la, lb = leave(int(a)), leave(int(b))
        own = f"its own motion blocked ({body[int(on[0])]})"
        if la is None or lb is None:
            end = "start" if la is None else "end"
            out.cuts[(int(a), int(b))] = f"{own}, no free retract at its {end}"
        elif det.direct(la, lb, keep) is not None:
            g.join(int(a), int(b))
        else:
            out.pending.append((int(a), int(b)))
            out.cuts[(int(a), int(b))] = f"{own}, no straight or tucked transfer"
    return out


def _weld_join(
    g: _Groups,
    served: NDArray[np.bool_],
    trial: _Trial,
    report: RoadmapReport | None,
    branch: int,
    rm: Any,
    ids: tuple[str, ...] | None,
) -> WeldJoin:
    """The :class:`WeldJoin` of the groups ``g``: the largest, why each other served weld is
    not in it, and the legs that stay split (:attr:`WeldJoin.splits`)."""
    n = len(served)
    name = (lambda k: ids[k]) if ids is not None else (lambda k: f"weld {k + 1} of the route order")
    group = np.array([g.find(k) if served[k] else -1 for k in range(n)], dtype=np.int64)
    counts = np.bincount(group[group >= 0], minlength=n) if served.any() else np.zeros(n, int)
    top = int(np.argmax(counts)) if served.any() else -1
    main = (group == top) & served
    causes = tuple(
        f"{name(int(k))}: in a group of {counts[group[k]]} weld(s), not the largest "
        f"({counts[top]}): no free leg, straight or tucked transfer nor roadmap component "
        "joins them"
        for k in np.flatnonzero(served & ~main)
    )
    splits = tuple(
        f"{name(a)} -> {name(b)}: {why}"
        + ("" if report is None else "; not in one roadmap component")
        for (a, b), why in trial.cuts.items()
        if g.find(a) != g.find(b)
    )
    return WeldJoin(
        group, main, int(main.sum()), trial.legs, report, causes, branch, rm, splits=splits
    )


def _alt_retracts(det: Detour, T_fl: NDArray[np.float64], keep: int) -> list[NDArray]:
    """The first retract configuration of each flange pose of ``T_fl (k, 4, 4)`` mm usable on
    branch ``keep`` with no link or tool (outside its contact zone) in the part."""
    if len(T_fl) == 0:
        return []
    br = det.robot.ik_all(T_fl)
    ok = np.flatnonzero(usable(br, det.singular_deg)[:, keep])
    if len(ok) == 0:
        return []
    Q = br.q[ok, keep]
    out = []
    for i, qk, b in zip(ok, Q, det.checker.states_blocked(Q, zone=True), strict=True):
        got = None if b is not None else det.retract(qk, T_fl[i] @ det.flange_tcp, keep)
        if got is not None:
            out.append(got[0])
    return out


def _unite(
    rm: Roadmap,
    new: list[tuple[int, NDArray[np.float64]]],
    g: _Groups,
    old: list[tuple[int, NDArray[np.float64]]],
) -> None:
    """Add the configurations of ``new`` ``(weld, q)`` to the roadmap and join the welds whose
    configurations (with those of ``old``, added before) share a component."""
    if not new:
        return
    keys = [k for k, _ in new] + [k for k, _ in old]
    comp = rm.connect(np.array([x for _, x in new]))
    if old:
        comp = np.r_[comp, rm.component_of(np.array([x for _, x in old]))]
    by: dict[int, int] = {}
    for k, c in zip(keys, comp, strict=True):
        if c < 0:
            continue
        if c in by:
            g.join(by[c], k)
        else:
            by[int(c)] = k


class LegRoadmap:
    """The detours' roadmaps at one base, one per IK branch, built on first use
    (:meth:`weldplan.robot.route.Detour.via_roadmap`): a leg whose two ends one of them joins
    is its path; a leg it does not join is reported at once with the components of its ends.

    Parameters
    ----------
    q_weld
        ``(n, 6)`` rad: the welds' configurations (the sampled box is about those on the leg's
        branch, :func:`branch_box`; the ends of a leg are named by the weld nearest them).
    ids
        The welds' ids, as ``q_weld``.
    settings, seed
        The roadmap's work and seed (:class:`~weldplan.motion.roadmap.RoadmapSettings`).
    built
        Roadmaps already built at this base, by branch (the base search's, :class:`WeldJoin`).
    """

    def __init__(
        self,
        q_weld: NDArray[np.float64],
        ids: tuple[str, ...],
        settings: RoadmapSettings,
        seed: int | None = 0,
        built: dict[int, Roadmap] | None = None,
    ) -> None:
        self.q_weld = np.asarray(q_weld, dtype=np.float64).reshape(-1, 6)
        self.ids = tuple(ids)
        self.settings = settings
        self.seed = seed
        self.maps: dict[int, Roadmap] = dict(built or {})

    def close(self) -> None:
        """Release every roadmap's OMPL objects (:meth:`~weldplan.motion.roadmap.Roadmap.close`)."""
        for rm in self.maps.values():
            rm.close()

    def join(
        self, det: Detour, qa: NDArray, qb: NDArray, keep: int
    ) -> tuple[NDArray[np.float64] | None, str]:
        """``(path (p, 6) rad or None, why not)`` from ``qa`` to ``qb`` on branch ``keep``."""
        if keep not in self.maps:
            on = det.robot.branch_bits(self.q_weld) == keep
            ref = np.vstack([self.q_weld[on], qa, qb])
            self.maps[keep] = branch_roadmap(det, ref, keep, self.settings, self.seed)
        rm = self.maps[keep]
        ca, cb = rm.connect(np.array([qa, qb]))
        if ca >= 0 and ca == cb:
            P = rm.path(qa, qb)
            if P is not None:
                P[0], P[-1] = qa, qb
                return P, ""
        comp = rm.graph()[2]

        def where(c: int, x: NDArray) -> str:
            w = self.ids[int(np.argmin(np.abs(self.q_weld - x).sum(axis=1)))] if self.ids else "?"
            if c < 0:
                return f"near weld {w}: outside the roadmap's box or not free"
            return f"near weld {w}: component {c} ({int((comp == c).sum())} vertices)"

        rep = rm.report()
        return None, (
            f"roadmap ({rep.milestones} milestones, branch {keep}) does not join the leg: its "
            f"start {where(int(ca), qa)}, its end {where(int(cb), qb)}"
        )
