"""Transitions with the whole tool (issue 16, item 3): retract, move, approach; SE(3) where blocked.

For consecutive welds ``a -> b`` (both with a verified pose, in the tool's order) the direct
transition is three motions (:mod:`weldplan.tool.sweep`'s motion model: straight TCP segment,
slerped orientation):

1. ``retract``: from the pose at ``a`` back ``retract`` mm along its TCP axis (orientation kept);
2. ``move``: from that retract point to ``b``'s, the orientation slerped from ``a``'s to ``b``'s;
3. ``approach``: along ``b``'s TCP axis onto its spot.

Each motion is checked for the swept tool by :class:`~weldplan.tool.sweep.SweepChecker`
(conservative advancement on FCL distances: the tool keeps the clearance along the whole motion,
with the contact zones of ``a`` and ``b`` exempt as that module defines). When a motion is
blocked the transition is re-planned in SE(3) with OMPL
(:func:`weldplan.motion.sampling.plan_se3`): between the retract points when both retracts are
free, else between the weld poses themselves; OMPL's states are checked with the same checker
and its motions with the same swept check, and the path it returns is checked again motion by
motion before it is accepted. A transition with no free motion is reported :data:`BLOCKED` with
the reason; it is never silently repaired.

Deviation from a single "TCP path": the move between retract points is the straight segment, not
the point-tip route's leg (whose vias were planned for a 5 mm sphere and say nothing about the
gun); where the straight move is blocked, OMPL plans the whole tool.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.tool.model import Tool
from weldplan.tool.result import WeldPoses
from weldplan.tool.sweep import DEFAULT_MIN_STEP, SweepChecker, quat_to_matrix
from weldplan.tool.transit import BLOCKED, DIRECT, REPLANNED, ToolPath, Transition

log = logging.getLogger(__name__)

#: mm: default retract distance along the TCP axis before leaving a weld (issue 16)
DEFAULT_RETRACT = 50.0
#: default OMPL planner for blocked transitions (stops at its first solution, then simplified)
DEFAULT_SE3_PLANNER = "rrtconnect"
#: mm: lifts along the TCP axis tried before a side exit (:meth:`TransitionPlanner._leave`)
SIDE_LIFTS = (5.0, 10.0, 20.0)
#: mm: default side exit when the axial retract is blocked (a C-gun's jaws round a flange: the
#: shared gun's C back stands 231 mm from its electrode axis)
DEFAULT_SIDE_EXIT = 250.0
#: default seconds OMPL may spend on one transition
DEFAULT_SE3_TIME = 5.0


def _se3_box(a: NDArray, b: NDArray, part: trimesh.Trimesh, pad: float) -> tuple[NDArray, NDArray]:
    """The TCP position box of an SE(3) re-plan: the two ends and the part's box, padded."""
    lo = np.minimum(np.minimum(a, b), np.asarray(part.bounds[0])) - pad
    hi = np.maximum(np.maximum(a, b), np.asarray(part.bounds[1])) + pad
    return lo, hi


class TransitionPlanner:
    """Plans :class:`Transition` s between weld poses with one :class:`SweepChecker`.

    Parameters
    ----------
    part, tool
        The part and the tool (mm).
    clearance, contact_radius
        mm, as in the pose search.
    retract
        mm along the TCP axis (0: no retract/approach motions, the move starts at the spot).
    side_exit
        mm: when the axial retract is blocked, try leaving sideways by this much first
        (:meth:`_leave`; 0: never).
    se3
        Re-plan blocked transitions with OMPL (needs ``weldplan[ompl]``).
    planner, time_s, seed, rot_weight
        OMPL's planner, seconds per transition, seed and metric weight (mm per rad).
    """

    def __init__(
        self,
        part: trimesh.Trimesh,
        tool: Tool,
        *,
        clearance: float,
        contact_radius: float,
        retract: float = DEFAULT_RETRACT,
        se3: bool = True,
        planner: str = DEFAULT_SE3_PLANNER,
        time_s: float = DEFAULT_SE3_TIME,
        seed: int | None = 0,
        rot_weight: float = 200.0,
        min_step: float = DEFAULT_MIN_STEP,
        side_exit: float = DEFAULT_SIDE_EXIT,
    ) -> None:
        if not (np.isfinite(retract) and retract >= 0):
            raise InputError(f"must be a finite number of mm >= 0, got {retract}", field="retract")
        self.part = part
        self.tool = tool
        self.retract = float(retract)
        self.se3 = se3
        self.planner = planner
        self.time_s = float(time_s)
        self.seed = seed
        self.rot_weight = float(rot_weight)
        self.side_exit = float(side_exit)
        self.checker = SweepChecker(part, tool, clearance, contact_radius, min_step=min_step)
        self.samples = 0

    def _motions(
        self,
        P: NDArray,
        Q: NDArray,
        exempt: NDArray,
        soft_first: bool = False,
        soft_last: bool = False,
    ) -> tuple[bool, int, str]:
        """Check consecutive poses; returns (all free, first blocked motion, its description).
        Only a weld pose (the first / last pose when ``soft_first`` / ``soft_last``) may have a
        small slack."""
        for k in range(len(P) - 1):
            soft = (soft_first and k == 0, soft_last and k == len(P) - 2)
            out = self.checker.check(P[k], Q[k], P[k + 1], Q[k + 1], exempt, soft)
            self.samples += out.samples
            if not out.ok:
                return False, k, out.describe()
        return True, -1, ""

    def _leave(self, w: Any, exempt: NDArray) -> tuple[NDArray | None, tuple[str, ...], str]:
        """Positions from weld ``w``'s pose to a clear point, its orientation kept: the retract
        along the TCP axis; when that is blocked and ``side_exit > 0``, a lift of
        :data:`SIDE_LIFTS` mm along the axis, a side exit of ``side_exit`` mm along TCP -x, +x,
        -y or +y, and the rest of the retract (a C-gun leaves the flange it straddles sideways,
        its jaws opened round the sheet). ``None`` and why when all are blocked.
        The same positions, reversed, are the approach (the same swept set)."""
        p = np.asarray(w.position, dtype=np.float64)
        q = np.asarray(w.quaternion, dtype=np.float64)
        if self.retract <= 0:
            return p[None], (), ""
        R = quat_to_matrix(q)
        back = -self.retract * R[:, 2]
        cands: list[tuple[list[NDArray], tuple[str, ...]]] = [([p, p + back], ("retract",))]
        z = R[:, 2]
        dirs = (("-x", -R[:, 0]), ("+x", R[:, 0]), ("-y", -R[:, 1]), ("+y", R[:, 1]))
        for lift in SIDE_LIFTS if self.side_exit > 0 else ():
            lift = min(lift, self.retract)
            for name, d in dirs:
                up = p - lift * z
                side = up + self.side_exit * d
                pts = [p, up, side, p + self.side_exit * d + back]
                cands.append((pts, ("lift", f"exit {name}", "retract")))
        first = ""
        for pts, kinds in cands:
            P = np.array(pts)
            ok, k, why = self._motions(P, np.repeat(q[None], len(P), axis=0), exempt, True)
            if ok:
                return P, kinds, ""
            first = first or f"{kinds[k]} {why}"
        return None, (), first

    def plan(self, a: Any, b: Any) -> Transition:
        """The transition from weld pose ``a`` to ``b`` (:class:`~weldplan.tool.result.WeldPose`,
        both ok)."""
        n0 = self.samples
        pa, pb = (np.asarray(w.position, dtype=np.float64) for w in (a, b))
        qa, qb = (np.asarray(w.quaternion, dtype=np.float64) for w in (a, b))
        exempt = np.array([pa, pb])
        la, ka, why_a = self._leave(a, exempt)
        lb, kb, why_b = self._leave(b, exempt)
        enter = tuple(
            k.replace("retract", "approach").replace("exit", "enter") for k in reversed(kb)
        )
        if la is not None and lb is not None:
            P = np.concatenate([la, lb[::-1]])
            Q = np.array([qa] * len(la) + [qb] * len(lb))
            kinds = ka + ("move",) + enter
            ok, _, why = self._motions(P[len(la) - 1 : len(la) + 1], Q[len(la) - 1 : len(la) + 1],
                                       exempt)  # fmt: skip
            if ok:
                return Transition(a.id, b.id, P, Q, kinds, DIRECT, "", self.samples - n0)
            reason = f"move {why}"
        else:
            P, Q, kinds = np.array([pa, pb]), np.array([qa, qb]), ("move",)
            reason = f"leaving {a.id}: {why_a}" if la is None else f"reaching {b.id}: {why_b}"
        if not self.se3:
            return Transition(a.id, b.id, P, Q, kinds, BLOCKED, reason, self.samples - n0)
        # re-plan between the clear points when both ends have one, else between the welds
        ends = la is not None and lb is not None
        start, goal = ((la[-1], qa), (lb[-1], qb)) if ends else ((pa, qa), (pb, qb))
        path, status = self._se3(start, goal, exempt)
        if path is None:
            return Transition(
                a.id, b.id, P, Q, kinds, BLOCKED, f"{reason}; SE(3): {status}", self.samples - n0
            )
        sp, sq = path[:, :3], path[:, 3:]
        skinds: tuple[str, ...] = ("se3",) * (len(path) - 1)
        if ends:
            assert la is not None and lb is not None
            sp = np.concatenate([la[:-1], sp, lb[::-1][1:]])
            sq = np.concatenate([[qa] * (len(la) - 1), sq, [qb] * (len(lb) - 1)])
            skinds = ka + skinds + enter
        # the planner's answer, checked again (the whole path: the ends are known free)
        ok3, k3, why3 = self._motions(path[:, :3], path[:, 3:], exempt, not ends, not ends)
        if not ok3:
            return Transition(
                a.id, b.id, sp, sq, skinds, BLOCKED,
                f"{reason}; SE(3) path motion {k3} {why3}", self.samples - n0,
            )  # fmt: skip
        return Transition(
            a.id, b.id, sp, sq, skinds, REPLANNED, f"{reason}; SE(3): {status}", self.samples - n0
        )

    def _se3(
        self, start: tuple[NDArray, NDArray], goal: tuple[NDArray, NDArray], exempt: NDArray
    ) -> tuple[NDArray | None, str]:
        """OMPL's SE(3) path ``(n, 7)`` between two poses, or ``None`` and why not."""
        try:
            from weldplan.motion.sampling import plan_se3
        except ImportError as exc:  # the wrapper or OMPL itself is missing
            return None, f"SE(3) re-planning unavailable ({exc})"
        check = self.checker

        def is_valid(p: NDArray, q: NDArray) -> bool:
            return check.state_ok(p, q, exempt)

        ends = np.array([np.r_[start[0], start[1]], np.r_[goal[0], goal[1]]])

        def motion_valid(s: NDArray, t: NDArray) -> bool:
            soft = (
                any(np.allclose(s, e) for e in ends),
                any(np.allclose(t, e) for e in ends),
            )
            out = check.check(s[:3], s[3:], t[:3], t[3:], exempt, soft)
            self.samples += out.samples
            return out.ok

        if not (is_valid(*start) and is_valid(*goal)):
            return None, "an end pose of the re-plan is not free"
        lo, hi = _se3_box(start[0], goal[0], self.part, pad=self.tool.reach)
        res = plan_se3(
            start[0], start[1], goal[0], goal[1], lo, hi, is_valid,
            motion_valid=motion_valid, rot_weight=self.rot_weight, planner=self.planner,
            time_s=self.time_s, seed=self.seed, simplify=True,
        )  # fmt: skip
        if not res.solved:
            return None, f"{res.planner}: {res.status}"
        return np.asarray(res.points, dtype=np.float64), f"{res.planner}: {res.status}"


def plan_transitions(
    part: trimesh.Trimesh,
    tool: Tool,
    poses: WeldPoses,
    *,
    order: list[str] | None = None,
    retract: float = DEFAULT_RETRACT,
    se3: bool = True,
    planner: str = DEFAULT_SE3_PLANNER,
    time_s: float = DEFAULT_SE3_TIME,
    seed: int | None = 0,
    rot_weight: float = 200.0,
    side_exit: float = DEFAULT_SIDE_EXIT,
    stats: dict[str, Any] | None = None,
) -> ToolPath:
    """The whole tool's transitions through the welds with a pose (module docstring).

    Parameters
    ----------
    part, tool
        The part and the tool (mm).
    poses
        The weld poses (:func:`weldplan.tool.poses.plan_weld_poses`); its settings give the
        clearance and the contact radius.
    order
        The welds' visiting order (ids with a pose); default the poses' own order
        (:func:`weldplan.tool.tool_order.tool_order` gives the tool-aware one).
    retract, se3, planner, time_s, seed, rot_weight, side_exit
        :class:`TransitionPlanner`.
    stats
        Extra figures to record (the ordering's costs).

    Returns
    -------
    ToolPath
        Every transition direct, re-planned or blocked; welds without a pose are skipped.
    """
    t0 = time.perf_counter()
    ok_ids = [p.id for p in poses.poses if p.ok]
    order = ok_ids if order is None else [str(i) for i in order]
    if sorted(order) != sorted(ok_ids):
        raise ValueError("the order must visit exactly the welds that have a pose")
    clearance = float(poses.settings["clearance"])
    radius = float(poses.settings["contact_radius"])
    tp = TransitionPlanner(
        part, tool, clearance=clearance, contact_radius=radius, retract=retract, se3=se3,
        planner=planner, time_s=time_s, seed=seed, rot_weight=rot_weight, side_exit=side_exit,
    )  # fmt: skip
    transitions = tuple(
        tp.plan(poses[a], poses[b]) for a, b in zip(order[:-1], order[1:], strict=True)
    )
    result = ToolPath(
        order=tuple(order),
        transitions=transitions,
        skipped=tuple(p.id for p in poses.poses if not p.ok),
        settings={
            "retract": retract,
            "side_exit": side_exit,
            "clearance": clearance,
            "contact_radius": radius,
            "rot_weight": rot_weight,
            "se3": se3,
            "planner": planner,
            "time_s": time_s,
            "seed": seed,
            "min_step": tp.checker.min_step,
        },
        stats={**(stats or {}), "samples": tp.samples, "total_s": time.perf_counter() - t0},
    )
    log.info("%s (%.1f s)", result.summary().splitlines()[0], result.stats["total_s"])
    return result
