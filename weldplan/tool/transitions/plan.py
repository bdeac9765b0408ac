"""Transitions with the whole tool (issue 16, item 3): axial, slide, side exit; SE(3) where blocked.

For consecutive welds ``a -> b`` (both with a verified pose, in the tool's order) the planner
tries, in order, and takes the first whose every motion is free
(:mod:`weldplan.tool.transitions.sweep`'s motion model: straight TCP segment, slerped orientation;
:class:`TransitionPlanner`):

1. **axial**: ``retract`` mm back along a's TCP axis (orientation kept), ``move`` to b's retract
   point (orientation slerped), ``approach`` along b's axis;
2. **slide**: ``lift`` off a's sheet by one of :data:`SLIDE_LIFTS` mm along its axis, ``slide``
   to b's spot lifted as much along b's axis (orientation slerped), ``lower`` onto b. A C-gun
   welding a row of spots on one flange stays straddled over it: the sheet passes through its
   opening (46.5 mm between the shared gun's electrode faces; a lift of 20 mm leaves the
   moving electrode ~19 mm off the sheet and the fixed one ~27 mm less the sheet's thickness
   off its far side). The slide is checked like every motion, and **conservatively**: the
   contact zone does not follow the TCP; only the zones about ``a`` and ``b`` are exempt, so
   away from the two spots the whole gun, electrodes included, keeps the clearance from the
   sheet it straddles. A slide passes only where the opening holds the sheet plus twice the
   clearance; an electrode that must rub along the sheet is not accepted;
3. **side**: a weld whose axial retract is blocked (a C-gun's fixed electrode, behind the sheet,
   would be pulled through it) is left by a lift of :data:`SIDE_LIFTS` mm, a side exit of
   ``side_exit`` mm along TCP -x, +x, -y or +y, and the rest of the retract; the move joins the
   two welds' exits (an axial retract where it is free);
4. **SE(3)**: OMPL (:func:`weldplan.motion.sampling.plan_se3`) between the clear points when
   both welds have one and the move between them is blocked, else between the weld poses; its
   states and motions judged by the same swept check within a budget that holds
   (:mod:`weldplan.tool.transitions.se3_replan`), and the path it returns checked again motion by
   motion.

A transition none of these frees is reported :data:`~weldplan.tool.transitions.BLOCKED`, its reason
listing every exit tried and where it was blocked; it is never silently repaired.

Each weld's axial and side exits are checked once (with only its own contact zone exempt,
stricter than a transition's two zones) and reused by the transitions into and out of it; its
lifts and its axial retract are one walk up its TCP axis, extended as far as the longest asked
(:mod:`weldplan.tool.transitions.axis_walk`). The
checker is focused on the part near the two welds
(:meth:`~weldplan.tool.transitions.SweepChecker.focus`: the same answers, cheaper distance queries).

Deviation from a single "TCP path": the move between clear points is the straight segment, not
the point-tip route's leg (whose vias were planned for a 5 mm sphere and say nothing about the
gun); where the straight move is blocked, OMPL plans the whole tool.
"""

from __future__ import annotations

import logging
import time
from dataclasses import fields
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.tool.model.tool import Tool
from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.settings import TransitionSettings
from weldplan.tool.transitions.axis_walk import AxisWalk
from weldplan.tool.transitions.result import BLOCKED, DIRECT, ToolPath, Transition
from weldplan.tool.transitions.se3_replan import entering, replan
from weldplan.tool.transitions.sweep import SweepChecker, quat_to_matrix
from weldplan.tool.transitions.sweep_bound import SweepBound
from weldplan.tool.transitions.sweep_fast import FastSweep

log = logging.getLogger(__name__)

#: mm: lifts along the TCP axis tried before a side exit (:meth:`TransitionPlanner._side`)
SIDE_LIFTS = (5.0, 10.0, 20.0)
#: mm: lifts off the sheet tried for a slide, the middle of the shared gun's 46.5 mm opening
#: first (0.8 to 47.3 mm ahead of the TCP), then nearer either electrode
SLIDE_LIFTS = (4.0, 10.0, 20.0)


class TransitionPlanner:
    """Plans :class:`Transition` s between weld poses with one :class:`SweepChecker`.

    The exits tried, in this order (module docstring), the first free one taken (a tool that
    straddles the sheet, :attr:`~weldplan.tool.model.Tool.straddles`, tries the slide first:
    its axial retract would pull its jaw behind the sheet through it):

    1. ``axial``: retract along a's TCP axis, move, approach along b's axis;
    2. ``slide``: lift off the sheet by one of :data:`SLIDE_LIFTS` mm, slide to b's lifted pose,
       lower onto b (a C-gun stays straddled over the flange it welds);
    3. ``side``: leave each weld sideways (a lift, a side exit along TCP -x, +x, -y or +y, the rest
       of the retract; :meth:`_side`), move, enter the same way;
    4. ``se3``: OMPL between the clear points (or the weld poses), within its budget.

    Every motion of every exit passes the same swept check (:class:`SweepChecker`); a weld's
    axial and side exits are checked once and reused by both its transitions. A blocked
    transition's reason lists every exit tried and why it failed.

    Parameters
    ----------
    part, tool
        The part and the tool (mm).
    settings
        The exits, the SE(3) re-plan and its budget
        (:class:`~weldplan.tool.settings.TransitionSettings`; default its defaults).
    clearance, contact_radius
        mm, as in the pose search (the poses'
        :attr:`~weldplan.tool.poses.WeldPoses.settings`).
    """

    def __init__(
        self,
        part: trimesh.Trimesh,
        tool: Tool,
        settings: TransitionSettings | None = None,
        *,
        clearance: float,
        contact_radius: float,
    ) -> None:
        self.part = part
        self.tool = tool
        self.settings = s = settings if settings is not None else TransitionSettings()
        step = {} if s.min_step is None else {"min_step": s.min_step}
        self.checker = SweepChecker(part, tool, clearance, contact_radius, **step)
        self._fast: FastSweep | None = None
        self.samples = 0
        #: per SE(3) re-plan: states and motions asked, motions refused for the budget, samples
        self.se3_runs: list[dict[str, Any]] = []
        # per weld pose (:func:`_pose_key`: a weld's candidate poses each have their own entry)
        self._axial: dict[tuple[Any, ...], tuple[NDArray | None, tuple[str, ...], str]] = {}
        self._sides: dict[tuple[Any, ...], tuple[NDArray | None, tuple[str, ...], str]] = {}
        self._lifts: dict[tuple[Any, ...], tuple[NDArray, str]] = {}
        self._walks: dict[tuple[Any, ...], AxisWalk] = {}
        self._planned: dict[tuple[Any, ...], Transition] = {}

    @property
    def fast(self) -> FastSweep:
        """The checker with the sphere bound first (:mod:`weldplan.tool.transitions.sweep_fast`),
        which the SE(3) re-plan's states and motions ask; built at the first re-plan (car2 has
        none)."""
        if self._fast is None:
            c = self.checker
            bound = SweepBound(self.part, self.tool, c.clearance, c.contact_radius)
            bound.table.fill_all()  # before any re-plan's clock starts: OMPL roams the box
            self._fast = FastSweep(c, bound)
        return self._fast

    def _pad(self) -> float:
        """mm about the welds the checker focuses on: every exit stays inside."""
        return self.settings.retract + self.settings.side_exit + max(SIDE_LIFTS + SLIDE_LIFTS) + 1.0

    def _sideways(self) -> bool:
        """Whether side exits are tried (a side exit and a retract to finish them)."""
        return self.settings.side_exit > 0 and self.settings.retract > 0

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

    def _leave_axial(self, w: Any) -> tuple[NDArray | None, tuple[str, ...], str]:
        """Weld ``w``'s retract along its TCP axis (cached per weld; the approach is the same
        positions reversed, the same swept set)."""
        key = _pose_key(w)
        if key not in self._axial:
            p = np.asarray(w.position, dtype=np.float64)
            if self.settings.retract <= 0:
                self._axial[key] = (p[None], (), "")
            else:
                P, why = self._lift(w, self.settings.retract)
                self._axial[key] = (P, ("retract",), "") if not why else (
                    None, (), f"retract: retract {why}")  # fmt: skip
        return self._axial[key]

    def _lift(self, w: Any, lift: float) -> tuple[NDArray, str]:
        """Weld ``w``'s pose and the pose ``lift`` mm back along its TCP axis ``(2, 3)``, and why
        that motion is blocked ('' when free; cached per weld and lift; only w's zone exempt,
        stricter than a transition's two zones; lowering is the same swept set)."""
        key = (*_pose_key(w), float(lift))
        if key not in self._lifts:
            walk = self._walk(w)
            out = walk.lift(lift)
            self.samples += out.samples
            self._lifts[key] = (np.array([walk.p, walk.at(lift)]), "" if out.ok else out.describe())
        return self._lifts[key]

    def _walk(self, w: Any) -> AxisWalk:
        """Weld ``w``'s walk up its TCP axis (:mod:`weldplan.tool.transitions.axis_walk`), shared
        by its lifts and its axial retract (one per pose)."""
        key = _pose_key(w)
        if key not in self._walks:
            p = np.asarray(w.position, dtype=np.float64)
            R = quat_to_matrix(np.asarray(w.quaternion, dtype=np.float64))
            extent = max(*SIDE_LIFTS, *SLIDE_LIFTS, self.settings.retract)
            self._walks[key] = AxisWalk(self.checker, p, R, extent)
        return self._walks[key]

    def _side(self, w: Any) -> tuple[NDArray | None, tuple[str, ...], str]:
        """Weld ``w``'s side exits (cached): a lift of :data:`SIDE_LIFTS` mm along the axis, a
        side exit of ``side_exit`` mm along TCP -x, +x, -y or +y, and the rest of the retract
        (a C-gun leaves the flange it straddles sideways, its jaws opened round the sheet). A
        blocked lift is tried once, not once per direction."""
        key = _pose_key(w)
        if key not in self._sides:
            p = np.asarray(w.position, dtype=np.float64)
            q = np.asarray(w.quaternion, dtype=np.float64)
            R = quat_to_matrix(q)
            back = -self.settings.retract * R[:, 2]
            dirs = (("-x", -R[:, 0]), ("+x", R[:, 0]), ("-y", -R[:, 1]), ("+y", R[:, 1]))
            fails: list[str] = []
            found: tuple[NDArray | None, tuple[str, ...], str] | None = None
            for lift in SIDE_LIFTS:
                lift = min(lift, self.settings.retract)
                (_, up), why = self._lift(w, lift)
                if why:
                    fails.append(f"lift {lift:g}: lift {why}")
                    continue
                for name, d in dirs:
                    side = self.settings.side_exit * d
                    P = np.array([up, up + side, p + side + back])
                    ok, k, why = self._motions(P, np.repeat(q[None], 3, axis=0), p[None])
                    if ok:
                        found = (np.vstack([p, P]), ("lift", f"exit {name}", "retract"), "")
                        break
                    kind = (f"exit {name}", "retract")[k]
                    fails.append(f"lift {lift:g} exit {name}: {kind} {why}")
                if found is not None:
                    break
            self._sides[key] = found or (None, (), "; ".join(fails))
        return self._sides[key]

    def _joined(
        self, a: Any, b: Any, la: NDArray, ka: tuple[str, ...], lb: NDArray, kb: tuple[str, ...]
    ) -> tuple[NDArray, NDArray, tuple[str, ...], bool, str]:
        """a's exit, the move between the clear points, b's exit reversed; whether the move is
        free and why not."""
        qa, qb = (np.asarray(w.quaternion, dtype=np.float64) for w in (a, b))
        exempt = np.array([a.position, b.position], dtype=np.float64)
        P = np.concatenate([la, lb[::-1]])
        Q = np.array([qa] * len(la) + [qb] * len(lb))
        enter = tuple(entering(k) for k in reversed(kb))
        i = len(la) - 1
        ok, _, why = self._motions(P[i : i + 2], Q[i : i + 2], exempt)
        return P, Q, (*ka, "move", *enter), ok, why

    def _slide(self, a: Any, b: Any) -> tuple[NDArray | None, NDArray | None, str]:
        """Lift off a's sheet, slide to b's lifted pose, lower onto b: the first of
        :data:`SLIDE_LIFTS` whose three motions are free (the contact zones of a and b only are
        exempt, as for every motion: the tool keeps the clearance from the sheet it straddles)."""
        pa, pb = (np.asarray(w.position, dtype=np.float64) for w in (a, b))
        qa, qb = (np.asarray(w.quaternion, dtype=np.float64) for w in (a, b))
        exempt = np.array([pa, pb])
        Q = np.array([qa, qa, qb, qb])
        fails = []
        for lift in SLIDE_LIFTS:
            (_, ua), why_a = self._lift(a, lift)
            (_, ub), why_b = self._lift(b, lift) if not why_a else ((pb, pb), "")
            if why_a or why_b:
                fails.append(f"lift {lift:g}: " + (f"lift off {a.id} {why_a}" if why_a
                                                   else f"lower onto {b.id} {why_b}"))  # fmt: skip
                continue
            ok, _, why = self._motions(np.array([ua, ub]), Q[1:3], exempt)
            if ok:
                return np.array([pa, ua, ub, pb]), Q, ""
            fails.append(f"lift {lift:g}: slide {why}")
        return None, None, "; ".join(fails)

    def _clear_point(self, w: Any) -> NDArray | None:
        """``(2, 3)``: weld ``w`` and its first free lift of :data:`SLIDE_LIFTS` (checked by the
        slides already), or ``None``: where an SE(3) re-plan without exits starts or ends."""
        for lift in SLIDE_LIFTS:
            P, why = self._lift(w, lift)
            if not why:
                return P
        return None

    def plan(self, a: Any, b: Any) -> Transition:
        """The transition from weld pose ``a`` to ``b`` (:class:`~weldplan.tool.poses.WeldPose`,
        both ok): the first free exit of the class docstring, or blocked with every exit's
        failure in the reason. Planned once per pair of poses: asked again (a re-ordered route,
        :mod:`weldplan.tool.transitions.reorder`), the planner returns the same transition."""
        key = (_pose_key(a), _pose_key(b))
        if key not in self._planned:
            self._planned[key] = self._plan(a, b)
        return self._planned[key]

    def _plan(self, a: Any, b: Any) -> Transition:
        n0 = self.samples
        pa, pb = (np.asarray(w.position, dtype=np.float64) for w in (a, b))
        qa, qb = (np.asarray(w.quaternion, dtype=np.float64) for w in (a, b))
        pad = self._pad()
        self.checker.focus(np.minimum(pa, pb) - pad, np.maximum(pa, pb) + pad)
        tried: list[str] = []
        ends: tuple[NDArray, NDArray] | None = None  # clear points of a and b for SE(3)
        legs: tuple[NDArray, tuple[str, ...], NDArray, tuple[str, ...]] | None = None
        shown: tuple[NDArray, NDArray, tuple[str, ...]] | None = None

        def done(P: NDArray, Q: NDArray, kinds: tuple[str, ...], status: str) -> Transition:
            reason = "; ".join(tried)
            return Transition(a.id, b.id, P, Q, kinds, status, reason, self.samples - n0)

        # a tool that straddles the sheet (a C-gun) slides first: its axial retract pulls the
        # jaw behind the sheet through it, so trying that first costs a check per weld
        slide_first = self.settings.slide and self.tool.straddles
        for kind in ("slide", "axial", "side") if slide_first else ("axial", "slide", "side"):
            if kind == "slide":
                if not self.settings.slide:
                    continue
                P, Q, why = self._slide(a, b)
                if P is not None:
                    return done(P, Q, ("lift", "slide", "lower"), DIRECT)
                tried.append(f"slide: {why}")
                continue
            if kind == "side" and not (self._sideways() and legs is None):
                continue
            leave = self._leave_axial if kind == "axial" else self._leave
            got = self._via(a, b, kind, leave, tried)
            if got is None:
                continue
            P, Q, kinds, ok, ends, legs = got
            if ok:
                return done(P, Q, kinds, DIRECT)
            shown = shown or (P, Q, kinds)
        # a blocked transition shows its first joined path tried, else the spot-to-spot segment
        shown = shown or (np.array([pa, pb]), np.array([qa, qb]), ("move",))
        if not self.settings.se3:
            return done(*shown, BLOCKED)
        if ends is None:  # no clear exits: from the lifted poses where the lifts are free
            ca, cb = self._clear_point(a), self._clear_point(b)
            if ca is not None and cb is not None:
                ends, legs = (ca[-1], cb[-1]), (ca, ("lift",), cb, ("lift",))
        return replan(self, a, b, ends, legs, tried, done, shown)

    def _via(
        self, a: Any, b: Any, label: str, leave: Any, tried: list[str]
    ) -> tuple[NDArray, NDArray, tuple[str, ...], bool, Any, Any] | None:
        """Both welds' exits by ``leave`` (axial or side), joined by the move: ``(P, Q, kinds,
        free, ends, legs)``; ``None`` when an exit is blocked. Failures go to ``tried``."""
        la, ka, why_a = leave(a)
        lb, kb, why_b = leave(b) if la is not None else (None, (), "")
        if la is None or lb is None:
            w, why = (a, why_a) if la is None else (b, why_b)
            tried.append(f"{label}: {'leaving' if w is a else 'reaching'} {w.id}: {why}")
            return None
        P, Q, kinds, ok, why = self._joined(a, b, la, ka, lb, kb)
        if not ok:
            tried.append(f"{label}: move {why}")
        return P, Q, kinds, ok, (la[-1], lb[-1]), (la, ka, lb, kb)

    def _leave(self, w: Any) -> tuple[NDArray | None, tuple[str, ...], str]:
        """Weld ``w``'s axial retract when free, else its first free side exit (both cached)."""
        out = self._leave_axial(w)
        return out if out[0] is not None else self._side(w)

    def exit_free(
        self, w: Any, kinds: tuple[str, ...] = ("lift", "axial", "side")
    ) -> tuple[bool, str]:
        """Whether the tool can leave weld pose ``w`` (and, the same swept set reversed, approach
        it) by one of ``kinds``, cheapest first: ``(True, how)`` or ``(False, why each failed)``.

        ``lift``: one of :data:`SLIDE_LIFTS` off the sheet (only a tool that
        :attr:`~weldplan.tool.model.Tool.straddles` it, with the slide on: the start of a slide,
        or of an SE(3) re-plan from the lifted pose); ``axial``: the retract; ``side``: a side
        exit (:meth:`_side`). Each is checked with only ``w``'s zone exempt and cached per pose,
        so the transitions into and out of ``w`` reuse the answer (:meth:`plan`).
        ``w`` needs ``id``, ``position`` (mm) and ``quaternion`` (qw, qx, qy, qz).
        """
        p = np.asarray(w.position, dtype=np.float64)
        pad = self._pad()
        self.checker.focus(p - pad, p + pad)
        fails: list[str] = []
        for kind in kinds:
            if kind == "lift" and self.settings.slide and self.tool.straddles:
                for lift in SLIDE_LIFTS:
                    _, why = self._lift(w, lift)
                    if not why:
                        return True, f"lift {lift:g}"
                    fails.append(f"lift {lift:g}: {why}")
            elif kind == "axial":
                la, _, why = self._leave_axial(w)
                if la is not None:
                    return True, "axial retract"
                fails.append(f"axial {why}")
            elif kind == "side" and self._sideways():
                sa, how, why = self._side(w)
                if sa is not None:
                    return True, f"side {how[1]}"
                fails.append(f"side: {why}")
        return False, "; ".join(fails) or "no exit tried"


def _pose_key(w: Any) -> tuple[Any, ...]:
    """The cache key of a weld pose: its id, position and quaternion (rounded to 1e-9: the same
    pose rebuilt from a 4x4 matrix hits the entry its :class:`WeldPose` made)."""
    return (
        str(w.id),
        *np.round(np.asarray(w.position, dtype=np.float64), 9).tolist(),
        *np.round(np.asarray(w.quaternion, dtype=np.float64), 9).tolist(),
    )


def _planner_for(
    part: trimesh.Trimesh,
    tool: Tool,
    settings: TransitionSettings | None,
    zone: tuple[float, float],
    reuse: TransitionPlanner | None,
) -> TransitionPlanner:
    """``reuse`` when it was built for this part, tool, settings (``None``: its own) and
    ``zone`` (clearance, contact radius in mm), else a ``ValueError`` naming what differs; a new
    planner without ``reuse``."""
    if reuse is None:
        return TransitionPlanner(part, tool, settings, clearance=zone[0], contact_radius=zone[1])
    mine, theirs = (reuse.settings if settings is None else settings), reuse.settings
    diff = [f.name for f in fields(mine) if getattr(mine, f.name) != getattr(theirs, f.name)]
    if (reuse.checker.clearance, reuse.checker.contact_radius) != zone:
        diff.insert(0, "clearance or contact radius")
    if reuse.part is not part or reuse.tool is not tool:
        diff.insert(0, "part or tool")
    if diff:
        raise ValueError(f"the planner's settings differ from this call's: {', '.join(diff)}")
    return reuse


def plan_transitions(
    part: trimesh.Trimesh,
    tool: Tool,
    poses: WeldPoses,
    settings: TransitionSettings | None = None,
    *,
    order: list[str] | None = None,
    stats: dict[str, Any] | None = None,
    reuse: TransitionPlanner | None = None,
) -> ToolPath:
    """The whole tool's transitions through the welds with a pose (module docstring).

    Parameters
    ----------
    part, tool
        The part and the tool (mm).
    poses
        The weld poses (:func:`weldplan.tool.poses.plan_weld_poses`); its settings give the
        clearance and the contact radius.
    settings
        :class:`~weldplan.tool.settings.TransitionSettings`; default those of ``reuse``, else
        the defaults.
    order
        The welds' visiting order (ids with a pose); default the poses' own order
        (:func:`weldplan.tool.transitions.tool_order` gives the tool-aware one).
    stats
        Extra figures to record (the ordering's costs).
    reuse
        A :class:`TransitionPlanner` to plan with, keeping the exits it has checked already
        (the pose search's exit test, :mod:`weldplan.tool.poses.exits`, reuses its cache here). Its
        part, tool, settings and the poses' clearance and contact radius must be this call's
        (``ValueError`` otherwise).

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
    tp = _planner_for(part, tool, settings, (clearance, radius), reuse)
    s = tp.settings
    n0, c0, r0 = tp.samples, tp.checker.crops_built, len(tp.se3_runs)
    transitions = tuple(
        tp.plan(poses[a], poses[b]) for a, b in zip(order[:-1], order[1:], strict=True)
    )
    result = ToolPath(
        order=tuple(order),
        transitions=transitions,
        skipped=tuple(p.id for p in poses.poses if not p.ok),
        settings={
            "retract": s.retract,
            "side_exit": s.side_exit,
            "slide": s.slide,
            "slide_lifts": list(SLIDE_LIFTS),
            "se3_samples": s.se3_samples,
            "se3_motion_cap": s.se3_motion_cap,
            "se3_checks": s.se3_checks,
            "clearance": clearance,
            "contact_radius": radius,
            "rot_weight": s.rot_weight,
            "se3": s.se3,
            "planner": s.planner,
            "time_s": s.time_s,
            "seed": s.seed,
            "min_step": tp.checker.min_step,
        },
        stats={
            **(stats or {}),
            "samples": tp.samples - n0,
            "crops_built": tp.checker.crops_built - c0,
            "se3_runs": tp.se3_runs[r0:],
            "total_s": time.perf_counter() - t0,
        },
    )
    log.info("%s (%.1f s)", result.summary().splitlines()[0], result.stats["total_s"])
    return result
