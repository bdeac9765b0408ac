"""Blocked legs of a joint route: detours through retract poses, re-planned with OMPL.

:func:`weldplan.robot.route.assemble` walks the welds the robot serves in route order; where
the route's own leg from one served weld ``a`` to the next ``b`` is blocked, it asks
:class:`Detour` for a detour:

0. *gun exit*: when the caller gives the gun stage's proven exits of ``a``
   (:attr:`Detour.exits`: a side exit and its retract, an axial retract, half an SE(3) re-plan;
   :func:`weldplan.robot.route.gun_exits`), ``a`` is first left along one of them, longest
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
   :data:`TRANSFER_CHECKS` checks and, while that does not solve it, retries of
   :data:`RETRY_CHECKS` with the next seeds, at most :data:`RETRY_LEG_CHECKS` for one leg and
   :data:`RETRY_TOTAL_CHECKS` for the route (rrtconnect stops at its first solution, so only a
   leg that needs the checks spends them). Budgets count checks (states and motions), so the
   same seed gives the same detours on any machine; ``time_s`` is a wall-clock safety net. When
   both ends are on one IK branch (they are: the welds' branches are chosen continuous), every
   step of the transfer stays on it (:meth:`Detour.on_branch`; tucks that would flip the elbow
   or shoulder are skipped, OMPL's states and motions off the branch are invalid): a detour
   passes no wrist, elbow or shoulder flip (before, car2_200's one OMPL detour passed A5
   through 0 and back, two flips in the program);
3. *approach*: ``b``'s approach configuration to ``b``'s, contact zone exempt.

The walk over the welds that uses these detours is :mod:`weldplan.robot.route.walk`.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.motion.sampling import WALL_FACTOR, SampledPath
from weldplan.robot.collision.checker import RobotCollision
from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.reach import usable

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

#: checks (calls of the state and motion checks) of a transfer's first OMPL run
#: (:func:`~weldplan.motion.sampling.plan_rn`'s ``max_checks``): measured 60-70 checks a CPU
#: second with the KR 150 and a torch (rrtconnect and the simplifier), so about the 5 CPU s
#: the first run had before
TRANSFER_CHECKS = 400
#: checks of each further run (the next seed) of a transfer the first run did not solve (the
#: 30 CPU s a retry had): rrtconnect stops at its first solution, so only the legs that need
#: it pay for it
RETRY_CHECKS = 2_000
#: the most checks the retries of one leg may take together (two retries): a leg that cannot
#: be joined does not take the whole route's retries from the legs after it
RETRY_LEG_CHECKS = 4_000
#: the most checks all the retries of one route may take together (the 120 CPU s before;
#: then a leg gets one run)
RETRY_TOTAL_CHECKS = 8_000
#: factor by which each further retry of one transfer grows its checks (a restart with a fresh
#: seed and twice the work: the work-budgeted form of restarts for heavy-tailed run lengths;
#: car2_200 seed 1's leg Z4L-134 -> Z4L-3 took rrtconnect 2,921 checks, more than a retry's
#: 2,000)
RETRY_GROWTH = 2
#: ways off one weld (:meth:`Detour.ways_off`) whose pairs the walk joins by a straight or
#: tucked-arm transfer before it asks OMPL (the first, :meth:`Detour.leave`'s, included): a leg
#: whose first retracts no straight transfer joins may be joined from another side, for a few
#: checks instead of an OMPL run
WAYS_OFF = 4
#: configurations on a joint motion at which a transfer's IK branch is checked
#: (:meth:`Detour.on_branch`)
BRANCH_SAMPLES = 9


@dataclass(frozen=True)
class Detour:
    """What :func:`weldplan.robot.route.assemble` needs besides the joint route (see the
    module docstring)."""

    robot: Robot
    checker: RobotCollision
    T_tcp: NDArray[np.float64]  # (m, 4, 4) mm: the route's TCP poses
    flange_tcp: NDArray[np.float64]  # (4, 4) mm
    singular_deg: float
    planner: str
    #: s: about what a first OMPL run of ``checks`` takes; OMPL's wall-clock limit, a safety
    #: net, is :data:`WALL_FACTOR` times it (a retry's in proportion to its checks); a run it
    #: ends is counted in ``ompl["clock"]`` and the route is not reproducible
    time_s: float
    rng: int | None
    tuck: tuple[tuple[float, float], ...] = TUCK_A2_A3
    checks: int = TRANSFER_CHECKS
    retry_checks: int = RETRY_CHECKS
    retry_leg_checks: int = RETRY_LEG_CHECKS
    retry_total_checks: int = RETRY_TOTAL_CHECKS
    #: per route row of a weld, TCP paths ``(k, 4, 4)`` mm that leave it (the first pose the
    #: weld's own) which the gun stage proved free for the tool: tried before :meth:`retract`
    #: (:func:`weldplan.robot.route.gun_exits`)
    exits: dict[int, tuple[NDArray[np.float64], ...]] = field(default_factory=dict)
    #: figures of the transfers planned with OMPL (runs, solved, retries, checks, retry_checks,
    #: clock: runs the safety net ended; CPU and wall seconds)
    ompl: dict[str, float] = field(default_factory=dict, compare=False)
    #: how each weld was left or reached by a detour: ``"gun exit"`` or ``"retract"``
    left_by: dict[str, int] = field(default_factory=dict, compare=False)
    #: a transfer between two configurations on one IK branch stays on it (:meth:`transfer`)
    keep_branch: bool = True
    #: the joint-space roadmaps at this base (:class:`weldplan.robot.placement.LegRoadmap`), asked
    #: before OMPL (:meth:`via_roadmap`); ``None``: OMPL with its retries, as before
    roadmap: Any = field(default=None, compare=False)
    #: the legs the roadmap did not join, each with its cause (:meth:`via_roadmap`)
    roadmap_misses: list[str] = field(default_factory=list, compare=False)

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

    def ways_off(
        self, q: NDArray, row: int, branch: int, first: NDArray | None = None
    ) -> list[NDArray]:
        """Up to :data:`WAYS_OFF` ways off the weld at route row ``row``, each as
        :meth:`leave` returns one (``(p, 6)`` rad, its last row clear): :meth:`leave`'s first
        (``first`` when the caller has it), then the other gun exits that work, then the first
        working retract (of :data:`RETRACT_MM`) of each other direction of
        :data:`RETRACT_DIRS`."""
        first = self.leave(q, row, branch) if first is None else first
        if first is None:
            return []
        out = [first]
        for T in self.exits.get(row, ()):
            P = self.follow(q, T, branch) if len(out) < WAYS_OFF else None
            if P is not None and not any(np.array_equal(P, x) for x in out):
                out.append(P)
        Tw = self.T_tcp[row]
        for axis, sign in RETRACT_DIRS:
            for d in RETRACT_MM:
                if len(out) >= WAYS_OFF:
                    return out
                qr = self.offset(q, Tw, branch, sign * d * Tw[:3, axis])
                if (
                    qr is not None
                    and self.checker.state_free(qr)
                    and self.checker.motion_free(q, qr, zone=True)
                ):
                    if not any(np.array_equal(qr[None], x) for x in out):
                        out.append(qr[None])
                    break  # the first distance of this direction that works
        return out

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
        straight, else through a tucked arm (``tuck``, default :data:`TUCK_A2_A3`), else OMPL.
        With :attr:`keep_branch` and both ends on one IK branch, every step stays on it
        (:meth:`on_branch`): the detour passes no wrist, elbow or shoulder flip."""
        keep = self._kept_branch(qa, qb)
        P = self.direct(qa, qb, keep)
        if P is not None:
            return P
        if self.roadmap is not None and keep is not None:
            return self.via_roadmap(qa, qb, keep)
        return self._ompl(qa, qb, keep)

    def direct(self, qa: NDArray, qb: NDArray, keep: int | None) -> NDArray | None:
        """The transfers that need no planner (:meth:`transfer`): the straight joint motion,
        else through a tucked arm; ``None`` when neither is free (on branch ``keep``)."""
        if self._motion_ok(qa, qb, keep):
            return np.vstack([qa, qb])
        for a2, a3 in self.tuck:
            P = np.array([qa, qa, qb, qb])
            P[1:3, 1:3] = np.radians([a2, a3])
            if not self.robot.in_limits(P[1:3]).all():
                continue
            if all(self._motion_ok(x, y, keep) for x, y in zip(P[:-1], P[1:], strict=True)):
                return P
        return None

    def joins_directly(self, qa: NDArray, qb: NDArray) -> NDArray | None:
        """:meth:`direct` on the branch :meth:`transfer` keeps: the transfer ``qa -> qb`` that
        needs no planner, ``None`` when there is none (the walk's trial,
        :func:`weldplan.robot.route.legtrial.leg_trial`)."""
        return self.direct(qa, qb, self._kept_branch(qa, qb))

    def via_roadmap(self, qa: NDArray, qb: NDArray, keep: int) -> NDArray | None:
        """``(p, 6)`` rad from ``qa`` to ``qb`` along :attr:`roadmap`'s branch ``keep`` when one
        of its components holds both (every edge a motion :meth:`motion_ok` proved free). Else
        the cause (the components of the two ends) goes to :attr:`roadmap_misses` and the log at
        once, and OMPL gets one run of ``checks`` with no retries: a roadmap grown on a finite
        sample proves no disconnection (:mod:`weldplan.motion.roadmap`), so a small bounded
        attempt stays, not the minutes of retries."""
        P, why = self.roadmap.join(self, qa, qb, keep)
        self.ompl["roadmap_legs"] = self.ompl.get("roadmap_legs", 0) + 1.0
        if P is not None:
            self.ompl["roadmap_joined"] = self.ompl.get("roadmap_joined", 0) + 1.0
            return np.asarray(P, dtype=np.float64)
        self.roadmap_misses.append(why)
        log.info("joint-space transfer: %s; one bounded OMPL run", why)
        return dataclasses.replace(self, retry_checks=0)._ompl(qa, qb, keep)

    def _kept_branch(self, qa: NDArray, qb: NDArray) -> int | None:
        """The IK branch a transfer ``qa -> qb`` keeps: both ends' when they share one and
        :attr:`keep_branch` is set, else ``None`` (no constraint)."""
        if not self.keep_branch:
            return None
        ba, bb = self.robot.branch_bits(np.array([qa, qb]))
        return int(ba) if ba == bb else None

    def on_branch(self, qa: NDArray, qb: NDArray, keep: int | None) -> bool:
        """Whether the straight joint motion ``qa -> qb`` stays on branch ``keep`` (``None``:
        any), judged at :data:`BRANCH_SAMPLES` evenly spaced configurations (ends included)
        by :meth:`~weldplan.robot.model.Robot.branch_bits`. Exact for the wrist and elbow bits
        (linear in A5, A3 between the ends); the shoulder bit, a sine of A2 and A3, could in
        principle cross and come back between two samples, which the final flip count (IK of FK
        at every row) would show."""
        if keep is None:
            return True
        t = np.linspace(0.0, 1.0, BRANCH_SAMPLES)[:, None]
        return bool(np.all(self.robot.branch_bits(qa + t * (qb - qa)) == keep))

    def motion_ok(self, qa: NDArray, qb: NDArray, keep: int | None) -> bool:
        """The detours' test of a straight joint motion (on branch ``keep``, ``None``: any;
        free for the whole tool and every link), for a roadmap's edges
        (:func:`weldplan.robot.placement.branch_roadmap`)."""
        return self._motion_ok(qa, qb, keep)

    def _motion_ok(self, qa: NDArray, qb: NDArray, keep: int | None) -> bool:
        """The straight joint motion ``qa -> qb`` stays on branch ``keep`` and is free for the
        whole tool and every link."""
        return self.on_branch(qa, qb, keep) and bool(self.checker.motion_free(qa, qb))

    def _ompl(self, qa: NDArray, qb: NDArray, keep: int | None = None) -> NDArray | None:
        """OMPL in joint space (:func:`~weldplan.motion.sampling.plan_rn`): a first run of
        ``checks`` checks (states and motions); while that is not enough, more runs of
        ``retry_checks`` with the next seeds, at most ``retry_leg_checks`` for this leg and
        ``retry_total_checks`` for the route (:meth:`_run_checks`): budgets of work, so the
        same seed gives the same detour on any machine and at any load (before, CPU seconds:
        the answer changed with the machine, and the first leg that needed retries took the
        route's whole retry budget). OMPL's own wall-clock limit, :data:`WALL_FACTOR` times
        ``time_s`` (a retry's scaled by its checks), is a safety net: a run it ends is counted
        in ``ompl["clock"]``. ``keep``: the states and motions must stay on that IK branch
        (:meth:`on_branch`)."""
        from weldplan.motion.sampling import plan_rn

        def valid(x: NDArray) -> bool:
            return (keep is None or int(self.robot.branch_bits(x)[0]) == keep) and bool(
                self.checker.state_free(x)
            )

        leg = {"retry_checks": 0}
        k = 0
        while True:
            budget = self._run_checks(k, leg["retry_checks"])
            if budget <= 0:
                if k == 1:
                    log.info("joint-space transfer: no retry left (%s)", self._retry_left())
                return None
            cpu0 = time.process_time()
            res = plan_rn(
                qa,
                qb,
                self.robot.lower,
                self.robot.upper,
                valid,
                motion_valid=lambda x, y: self._motion_ok(x, y, keep),
                planner=self.planner,
                time_s=WALL_FACTOR * self.time_s * max(1.0, budget / self.checks),
                seed=None if self.rng is None else self.rng + k,
                max_checks=budget,
            )
            log.info("joint-space transfer%s: %s", f" (retry {k})" if k else "", res.status)
            self._count(res, k, time.process_time() - cpu0)
            if k:
                leg["retry_checks"] += res.checks
            if res.solved:
                return np.asarray(res.points, dtype=np.float64)
            k += 1

    def _count(self, res: SampledPath, k: int, cpu: float) -> None:
        """Add one OMPL run to :attr:`ompl` (the seconds are figures for the report only)."""
        for key, v in (
            ("runs", 1),
            ("retries", k > 0),
            ("solved", res.solved),
            ("checks", res.checks),
            ("retry_checks", res.checks if k else 0),
            ("clock", res.ended == "clock"),
            ("s", cpu),
            ("wall_s", res.time_s),
        ):
            self.ompl[key] = self.ompl.get(key, 0) + float(v)

    def _retry_left(self) -> str:
        used = int(self.ompl.get("retry_checks", 0))
        return f"{used} of the route's {self.retry_total_checks} retry checks spent"

    def _run_checks(self, k: int, leg_retry: int) -> int:
        """Checks of OMPL run ``k`` of a transfer whose retries have spent ``leg_retry``: the
        first ``checks``; retry ``k`` ``retry_checks`` x 2^(k - 1) (each fresh seed gets twice
        the last one's work: a leg that needs more than one retry's checks gets them in few
        restarts, :data:`RETRY_GROWTH`) or what is left of this leg's ``retry_leg_checks`` or
        of the route's ``retry_total_checks``, whichever is least (0: no run)."""
        if not k:
            return int(self.checks)
        left = min(
            self.retry_leg_checks - leg_retry,
            self.retry_total_checks - int(self.ompl.get("retry_checks", 0)),
        )
        grown = int(self.retry_checks) * RETRY_GROWTH ** (k - 1)
        return max(0, min(grown, int(left)))
