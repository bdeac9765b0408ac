"""The swept tool: a conservative clearance check of a rigid tool moving between two poses.

Motion model. Between two TCP poses ``(p0, R0)`` and ``(p1, R1)`` the TCP moves on the straight
segment and the orientation turns at constant rate about one axis (spherical linear
interpolation, :class:`scipy.spatial.transform.Slerp`)::

    p(s) = p0 + s (p1 - p0),   R(s) = R0 exp(s theta k^),   s in [0, 1]

with ``theta`` (rad) the angle between ``R0`` and ``R1``. A tool point ``x`` (TCP frame, mm,
``|x| <= r`` with ``r`` the tool's reach) lands at ``w(s) = R(s) x + p(s)``; its speed in ``s``
is at most ``|p1 - p0| + theta r`` (the rotation moves it at ``theta`` times its distance from
the rotation axis through the TCP, at most ``theta r``). So between two parameters ``s`` and
``s'`` no tool point moves more than ``L |s - s'|`` with the **motion bound**
``L = |p1 - p0| + theta r`` (:func:`motion_bound`).

The check (:meth:`SweepChecker.check`) is conservative advancement on FCL distances: at ``s``
the **slack** (the distance from the tool to the part less the clearance, python-fcl
``distance``) is measured; no point of the tool can use it up before ``s + slack / L``, so the
next sample is taken there. It advances from the start to the middle and from the end back to
the middle (a weld pose may have little slack, which grows as the tool leaves it); FCL's cheap
``collide`` on a grid of the motion goes first (:meth:`SweepChecker.first_touch`): a motion on
which the tool touches the part is blocked there at once. A negative or
zero slack, more than ``2 (L / min_step + 1)`` samples (a motion that grazes the part), or,
from an end that is not a weld pose, a slack below ``min_step``, stops the check: the motion is
reported blocked at ``s``. A passed motion keeps **at least the
clearance from the part at every ``s``**, not only at the samples: that is what the independent
re-check (:mod:`weldplan.tool.verify.sweeps`) tests with its own uniform samples and its own
bound.

The contact zone. At a weld the tool's electrode cap (or wire tip) touches the sheet: the pose
search exempts the tool inside the sphere of ``contact_radius`` about the TCP
(:meth:`~weldplan.tool.model.Tool.outside_zone`) against the whole part. A motion that leaves or
reaches a weld narrows that exemption to pairs of tool-zone and part-zone points: the tool
outside its zone must keep the clearance from the whole part, and the tool inside its zone must
not touch the part outside the sphere of ``contact_radius`` about the weld spot (part frame; no
clearance asked there, because the pose itself may have the electrode cap within the clearance
of the sheet just outside that sphere). So an electrode cap may slide off its spot, but no other
part of the tool may pass through the sheet there (a C-gun's fixed electrode, 47 mm ahead of the
TCP, retracted along the tool axis, hits the sheet it straddles).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.geometry.checker import advance
from weldplan.geometry.world import CollisionWorld, Exemption, WorldBody
from weldplan.tool.model.tool import Tool, bvh, outside_sphere
from weldplan.tool.transitions.sweep_motion import SweepCheck, SweepMotion, SweptChecks

log = logging.getLogger(__name__)

#: mm: a motion of bound ``L`` may take at most ``2 (L / min_step + 1)`` samples (conservative
#: advancement along a motion that grazes the part would never end)
DEFAULT_MIN_STEP = 0.5
#: mm of tool motion between the poses at which a motion is first tested for contact
#: (:meth:`SweepChecker.first_touch`)
TOUCH_GRID_MM = 5.0
#: answers :meth:`SweepChecker.slack` keeps before it starts its memo afresh (about 200 bytes
#: each)
SLACK_MEMO_SIZE = 200_000
#: mm: the zone's distance to the part outside a spot's sphere is measured up to this much
#: (:meth:`SweepChecker.slack`); the zone needs only not touch, so a cap costs only step length
ZONE_CAP_MM = 30.0


def quat_to_matrix(q: ArrayLike) -> NDArray[np.float64]:
    """``(..., 3, 3)`` rotation matrices of unit quaternions ``(..., 4)`` ``(qw, qx, qy, qz)``."""
    q = np.asarray(q, dtype=np.float64)
    return (
        Rotation.from_quat(np.roll(q.reshape(-1, 4), -1, axis=1))
        .as_matrix()
        .reshape((*q.shape[:-1], 3, 3))
    )


def rotation_angle(q0: ArrayLike, q1: ArrayLike) -> float:
    """Radians between two unit quaternions (any sign): ``2 arccos |q0 . q1|``."""
    dot = abs(float(np.dot(np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64))))
    return 2.0 * math.acos(min(1.0, dot))


def interpolate(
    p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, s: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Poses along the motion (module docstring) at parameters ``s (k,)`` in [0, 1].

    Returns
    -------
    positions, rotations
        ``(k, 3)`` mm and ``(k, 3, 3)``.
    """
    return _interpolator(p0, q0, p1, q1)(s)


def _interpolator(
    p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike
) -> Callable[[ArrayLike], tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """:func:`interpolate` for one motion, its end rotations set up once (a check asks for one
    pose at a time; the same arithmetic, so the same poses)."""
    a, b = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    ra = Rotation.from_quat(np.roll(np.asarray(q0, dtype=np.float64), -1))
    rb = Rotation.from_quat(np.roll(np.asarray(q1, dtype=np.float64), -1))
    rel = (ra.inv() * rb).as_rotvec()  # the shortest rotation from a to b, in a's frame

    def at(s: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        pos = a + s[:, None] * (b - a)
        rots = (ra * Rotation.from_rotvec(s[:, None] * rel[None, :])).as_matrix()
        return pos, rots

    return at


def motion_bound(p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, reach: float) -> float:
    """mm: no tool point moves farther than this over the whole motion (module docstring)."""
    dp = float(np.linalg.norm(np.asarray(p1, dtype=np.float64) - np.asarray(p0, dtype=np.float64)))
    return dp + rotation_angle(q0, q1) * float(reach)


def tool_zone(tool: Tool, radius: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The tool's triangles that reach into the sphere of ``radius`` about the TCP (a superset of
    the tool inside it: every triangle whose closest point to the TCP lies within ``radius``).

    Returns ``(vertices (k, 3) mm, faces (j, 3))``, possibly empty.
    """
    tri = tool.vertices[tool.faces]
    closest = trimesh.triangles.closest_point(tri, np.zeros((len(tri), 3)))
    near = np.flatnonzero(np.linalg.norm(closest, axis=1) <= radius)
    f = tool.faces[near]
    used, inv = np.unique(f, return_inverse=True)
    return tool.vertices[used], inv.reshape(-1, 3).astype(np.int64)


class SweepChecker(SweptChecks):
    """The planner's swept-tool checker: python-fcl models of the part and the tool, kept.

    Parameters
    ----------
    part
        The part (mm).
    tool
        The tool (mm, TCP frame).
    clearance
        mm: the least distance the moving tool must keep from the part.
    contact_radius
        mm: the contact zone (module docstring) about the TCP and about the weld spots that a
        motion's ``exempt`` names.
    min_step
        mm: sets the sample budget of a motion (:data:`DEFAULT_MIN_STEP`).
    """

    def __init__(
        self,
        part: trimesh.Trimesh,
        tool: Tool,
        clearance: float,
        contact_radius: float,
        *,
        min_step: float = DEFAULT_MIN_STEP,
    ) -> None:
        if not (clearance >= 0 and contact_radius >= 0 and min_step > 0):
            raise ValueError("clearance and contact_radius >= 0 and min_step > 0 are needed")
        self.part = part
        self.tool = tool
        self.clearance = float(clearance)
        self.contact_radius = float(contact_radius)
        self.min_step = float(min_step)
        self.reach = tool.reach
        # the whole part and the whole tool are built when first asked for (:meth:`_model`):
        # a focused planner whose motions all exempt a weld may need neither
        self._models: dict[str, fcl.CollisionObject] = {}
        # the pose search's BVH of the tool outside its zone (the same mesh, built once a tool)
        self._outside = fcl.CollisionObject(tool.fcl_model(self.contact_radius)[0], fcl.Transform())
        zv, zf = tool_zone(tool, self.contact_radius)
        self._zone = None if len(zf) == 0 else fcl.CollisionObject(bvh(zv, zf), fcl.Transform())
        #: mm: the zone's reach from the TCP, and the radius of the part kept about a spot
        self.zone_reach = float(np.linalg.norm(zv, axis=1).max()) if len(zf) else 0.0
        self.cut_radius = 2 * self.zone_reach + self.contact_radius + ZONE_CAP_MM
        self._cut: dict[tuple[float, ...], fcl.CollisionObject | None] = {}
        tri = np.asarray(part.triangles)
        self._tri_lo, self._tri_hi = tri.min(axis=1), tri.max(axis=1)
        #: the focus (:meth:`focus`): TCP box ``(lo, hi)``, its crop object and faces, a key
        self._focus: tuple[NDArray, NDArray, fcl.CollisionObject | None, NDArray, int] | None = None
        self._n_focus = 0
        #: crops built by :meth:`focus`
        self.crops_built = 0
        #: :meth:`slack`'s answers, by pose, exempt spots and part object (the focus' number)
        self._slack_memo: dict[tuple[bytes, bytes, int], float] = {}

    def _model(self, name: str) -> fcl.CollisionObject:
        """The python-fcl object of the whole ``"part"`` or the whole ``"tool"``, built once."""
        if name not in self._models:
            mesh = self.part if name == "part" else self.tool
            self._models[name] = fcl.CollisionObject(
                bvh(np.asarray(mesh.vertices), np.asarray(mesh.faces)), fcl.Transform()
            )
        return self._models[name]

    @property
    def world(self) -> CollisionWorld:
        """The part and the whole tool as a collision world (:mod:`weldplan.geometry.world`,
        the FCL objects this checker judges with): one pair, checked with the tool's contact
        zone exempt (module docstring), which :meth:`CollisionWorld.describe
        <weldplan.geometry.world.CollisionWorld.describe>` prints. Builds the whole models."""
        part = WorldBody(
            "part", "part", self._model("part"), shape=f"BVH, {len(self.part.faces)} triangles"
        )
        n = len(self.tool.faces)
        tool = WorldBody(
            "tool", "tool", self._model("tool"), None, "the TCP pose", f"BVH, {n} triangles"
        )
        note = f"a sphere of {self.contact_radius:g} mm about the TCP and about the weld spot"
        zone = {("tool", "part"): Exemption("contact zone", note)}
        return CollisionWorld.of([part, tool], zones=zone)

    def focus(self, lo: ArrayLike, hi: ArrayLike) -> None:
        """Check motions whose TCP stays in the box ``[lo, hi] (3,)`` mm against only the part's
        triangles whose bounding boxes come within ``reach + clearance + min_step`` of the box.

        No other triangle can come within the clearance of the tool while its TCP is in the box
        (every tool point lies within ``reach`` of the TCP), so a motion inside the box is free
        against the crop exactly when it is free against the whole part, and its slack there is
        the slack that counts (the farther triangles only add slack beyond the clearance).
        Motions with an end outside the box (the box is convex: a motion with both ends in it
        stays in it) are checked against the whole part, so the focus never changes an answer:
        it only makes FCL's distance queries cheaper. A box inside the current focus keeps it.
        """
        lo = np.asarray(lo, dtype=np.float64).reshape(3)
        hi = np.asarray(hi, dtype=np.float64).reshape(3)
        f = self._focus
        if f is not None and np.all(lo >= f[0]) and np.all(hi <= f[1]):
            return
        pad = self.reach + self.clearance + self.min_step
        gap = np.maximum(self._tri_lo - hi - pad, 0) + np.maximum(lo - pad - self._tri_hi, 0)
        near = np.flatnonzero(~gap.any(axis=1))
        faces = np.asarray(self.part.faces)[near]
        obj = None
        if len(near):
            obj = fcl.CollisionObject(bvh(self.part.vertices, faces), fcl.Transform())
        self._n_focus += 1
        self.crops_built += 1
        self._focus = (lo, hi, obj, faces, self._n_focus)

    def _inside(self, *points: ArrayLike) -> bool:
        f = self._focus
        return f is not None and all(
            bool(np.all(np.asarray(p) >= f[0]) and np.all(np.asarray(p) <= f[1])) for p in points
        )

    def _part_cut(self, spot: NDArray[np.float64]) -> fcl.CollisionObject | None:
        """A BVH of the part near one weld spot, outside its zone: the triangles whose bounding
        boxes come within :attr:`cut_radius` of the spot, cut by :func:`outside_sphere`
        (cached per spot; ``None`` when nothing is left). :meth:`slack` says why near is enough."""
        key = tuple(np.round(spot, 9).tolist())
        if key not in self._cut:
            gap = np.maximum(self._tri_lo - spot, 0) + np.maximum(spot - self._tri_hi, 0)
            near = np.einsum("ij,ij->i", gap, gap) <= self.cut_radius**2
            faces = np.asarray(self.part.faces)[near]
            v, f = outside_sphere(self.part.vertices, faces, spot, self.contact_radius, bisect=True)
            self._cut[key] = (
                None if len(f) == 0 else fcl.CollisionObject(bvh(v, f), fcl.Transform())
            )
        return self._cut[key]

    def slack(
        self,
        p: ArrayLike,
        R: ArrayLike,
        exempt: ArrayLike | None = None,
        focused: bool | None = None,
    ) -> float:
        """mm by which the tool at TCP ``p (3,)``, ``R (3, 3)`` clears what it must (negative: it
        does not): the distance to the part less the clearance; with ``exempt (m, 3)`` weld spots,
        the least of (tool outside its zone to the whole part) less the clearance and (tool in
        its zone to the part outside the spots' zones), which need only not touch.
        ``focused``: measure against the focus' crop (:meth:`focus`; default: when ``p`` lies in
        its box); a crop with nothing in it means nothing within reach (``inf``).

        The zone's distance ``dz`` is a lower bound, found cheaply (``rz`` the zone's reach from
        the TCP, ``r`` the contact radius, ``M`` = :data:`ZONE_CAP_MM`):

        * the zone's distance to the whole part (or the crop) first: when it is not below the
          outside's slack, no exemption can change the least of the two;
        * for a spot ``e`` with ``|p - e| >= rz + r`` the zone cannot reach into e's sphere, so
          its distance to the part outside that sphere is at least its distance to the part;
        * else every point of the zone lies within ``2 rz + r`` of ``e``, so the part beyond
          ``cut_radius = 2 rz + r + M`` of ``e`` is at least ``M`` away: the distance to the part
          near ``e`` outside its sphere (:meth:`_part_cut`), capped at ``M``, is a lower bound.
        """
        p = np.asarray(p, dtype=np.float64)
        if focused is None:
            focused = self._inside(p)
        on_focus = focused and self._focus is not None
        part = self._focus[2] if on_focus else self._model("part")
        if part is None:
            return math.inf
        R = np.ascontiguousarray(R, dtype=np.float64)
        ex = None if exempt is None else np.asarray(exempt, dtype=np.float64).reshape(-1, 3)
        # the same pose, spots and part object: the same FCL answer (a quarter of the demo's
        # samples are asked again: exits re-checked by the transitions, re-plans' paths)
        key = (
            p.tobytes() + R.tobytes(),
            b"" if ex is None else ex.tobytes(),
            self._focus[4] if on_focus else 0,  # type: ignore[index]
        )
        hit = self._slack_memo.get(key)
        if hit is None:
            if len(self._slack_memo) >= SLACK_MEMO_SIZE:
                self._slack_memo.clear()
            hit = self._slack_memo[key] = self._slack(p, R, ex, part)
        return hit

    def _slack(
        self, p: NDArray[np.float64], R: NDArray[np.float64], ex: NDArray | None, part: Any
    ) -> float:
        """:meth:`slack` against the part object ``part``, without the memo."""
        tf = fcl.Transform(R, p)
        req = fcl.DistanceRequest()
        if ex is None or len(ex) == 0:
            whole = self._model("tool")
            whole.setTransform(tf)
            d = float(fcl.distance(whole, part, req, fcl.DistanceResult()))
            return d - self.clearance
        self._outside.setTransform(tf)
        d = float(fcl.distance(self._outside, part, req, fcl.DistanceResult()))
        slack = d - self.clearance
        if self._zone is None:
            return slack
        self._zone.setTransform(tf)
        dz_all = float(fcl.distance(self._zone, part, req, fcl.DistanceResult()))
        if dz_all >= slack:
            return slack
        # the part outside every zone is a subset of the part outside each one, so the
        # largest lower bound of the distances to those is a lower bound of the one that counts
        dz = dz_all
        for e in ex:
            if np.linalg.norm(p - e) >= self.zone_reach + self.contact_radius:
                continue  # dz_all already bounds it
            cut = self._part_cut(e)
            de = math.inf if cut is None else float(
                fcl.distance(self._zone, cut, req, fcl.DistanceResult()))  # fmt: skip
            dz = max(dz, min(de, ZONE_CAP_MM))
        return min(slack, dz)

    def touches(self, p: ArrayLike, R: ArrayLike, focused: bool | None = None) -> bool:
        """Whether the tool outside its zone touches the part at TCP ``p (3,)``, ``R (3, 3)``
        (python-fcl ``collide``, about 40 times cheaper than ``distance`` on the gun near a
        flange): then :meth:`slack` is negative, whatever spots are exempt. ``focused`` as in
        :meth:`slack`. A fast way to show a pose or a motion blocked, never free."""
        p = np.asarray(p, dtype=np.float64)
        if focused is None:
            focused = self._inside(p)
        part = self._focus[2] if focused and self._focus is not None else self._model("part")
        if part is None:
            return False
        self._outside.setTransform(fcl.Transform(np.asarray(R, dtype=np.float64), p))
        req = fcl.CollisionRequest()
        return bool(fcl.collide(self._outside, part, req, fcl.CollisionResult()))

    def first_touch(
        self, at: Callable[[ArrayLike], tuple[NDArray, NDArray]], L: float, focused: bool
    ) -> tuple[float | None, int]:
        """The first parameter, middle first and then halving the gaps (where a blocked motion
        is most often found), of a grid :data:`TOUCH_GRID_MM` of tool motion apart at which the
        tool outside its zone touches the part (:meth:`touches`), or ``None``: no contact there,
        which proves nothing; and the poses tested. ``at``: the motion's poses at parameters
        (:func:`interpolate`), ``L`` its motion bound (mm)."""
        n = max(1, math.ceil(L / TOUCH_GRID_MM))
        s = _bisection_order(n + 1) / n
        P, R = at(s)
        for k in range(len(s)):
            if self.touches(P[k], R[k], focused):
                return float(s[k]), k + 1
        return None, len(s)

    def state_ok(self, p: ArrayLike, q: ArrayLike, exempt: ArrayLike | None = None) -> bool:
        """Whether one pose (TCP ``p (3,)`` mm, ``q`` wxyz) clears (:meth:`slack` >= 0)."""
        return self.slack(p, quat_to_matrix(q), exempt) >= 0.0

    def _motion(
        self, p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, soft: tuple[bool, bool]
    ) -> SweepMotion:
        """The motion ``(p0, q0) -> (p1, q1)`` as :meth:`check` takes it (:class:`SweepMotion`)."""
        L = motion_bound(p0, q0, p1, q1, self.reach)
        soft_range = max(self.contact_radius, 10 * self.min_step)
        if L <= soft_range and any(soft):  # a short motion off a weld pose lies wholly in its
            soft = (True, True)  # soft range: its far end may have a small slack too
        a, b = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
        at = _interpolator(p0, q0, p1, q1)
        return SweepMotion(a, b, at, L, soft, soft_range, self._inside(p0, p1))

    def _advance(
        self, m: SweepMotion, exempt: ArrayLike | None, cap: int | None, deadline: float | None
    ) -> SweepCheck:
        """:meth:`check`'s advancement, one FCL sample at a time (module docstring); ``deadline``
        is a :func:`time.perf_counter` value."""
        L, soft, soft_range, focused, pose_at = m.L, m.soft, m.soft_range, m.focused, m.at
        budget = [max_samples(L, self.min_step)]
        smin = [math.inf]
        late = [False]
        first = budget[0]
        if L > 0 and cap is None and deadline is None:
            # FCL's collide first (tens of times cheaper than a distance): a motion on which
            # the tool touches the part cannot pass, wherever the advancement would stop
            hit, _ = self.first_touch(pose_at, L, focused)
            if hit is not None:
                return SweepCheck(False, 0, -math.inf, hit, L, False, self.min_step)

        def slack_at(s: float) -> float:
            spent = first - budget[0]
            if (cap is not None and spent >= cap) or (
                deadline is not None and time.perf_counter() > deadline
            ):
                late[0] = True
                return -math.inf
            pos, rot = pose_at([s])
            v = self.slack(pos[0], rot[0], exempt, focused)
            budget[0] -= 1
            smin[0] = min(smin[0], v)
            return v

        def blocks_at(start: float, may: bool) -> Callable[[float, float], bool]:
            def blocks(s: float, v: float) -> bool:
                soft_here = may and abs(s - start) * L <= soft_range
                short = v < self.min_step and not soft_here
                return v < 0 or (v == 0 and L > 0) or budget[0] < 0 or (short and L > 0)

            return blocks

        # forward from the start and backward from the end, meeting half-way: the slack at a
        # weld pose may be small, and grows as the tool leaves it
        blocked = float("nan")
        for start, stop, may in ((0.0, 0.5, soft[0]), (1.0, 0.5, soft[1])):
            run = advance(slack_at, L, start=start, stop=stop, blocked=blocks_at(start, may))
            if not run.free:
                blocked = run.t
                break
        n = first - budget[0]
        ok = math.isnan(blocked)
        return SweepCheck(ok, n, smin[0], blocked, L, late[0], self.min_step)

    def last_valid(
        self, a: tuple[ArrayLike, ArrayLike], b: tuple[ArrayLike, ArrayLike], exempt: Any = None
    ) -> float:
        """The last valid parameter of the motion between the TCP poses ``a = (p0, q0)`` and
        ``b = (p1, q1)`` (mm, wxyz)
        (:meth:`~weldplan.geometry.checker.StateChecker.check_motion`): conservative advancement
        from the start only, by :meth:`check`'s rules (a slack below ``min_step`` blocks outside
        the soft range of the start, a weld pose maybe; the same sample budget), so it keeps the
        clearance on ``[0, t]`` and ``1.0`` means all of it. Not the planner's check (that one
        meets in the middle and tries FCL's collide first: it fails faster, and says less)."""
        m = self._motion(a[0], a[1], b[0], b[1], (True, False))
        L, soft_range, pose_at, focused = m.L, m.soft_range, m.at, m.focused

        def slack_at(s: float) -> float:
            pos, rot = pose_at([s])
            return self.slack(pos[0], rot[0], exempt, focused)

        def blocks(s: float, v: float) -> bool:
            short = v < self.min_step and s * L > soft_range
            return v < 0 or (v == 0 and L > 0) or (short and L > 0)

        run = advance(slack_at, L, blocked=blocks, max_steps=max_samples(L, self.min_step))
        return 1.0 if run.free else run.t


class ToolStateChecker:
    """The tool in SE(3) as a :class:`~weldplan.geometry.checker.StateChecker`: a state is a
    TCP pose ``(p (3,) mm, q (4,) wxyz)``, a motion the straight TCP segment with slerp.

    An adapter over :class:`SweepChecker` (whose ``clearance`` is the mm the tool must keep,
    read at two dozen call sites; the protocol's ``clearance(state)`` would clash with it).

    Parameters
    ----------
    checker
        The swept-tool checker.
    exempt
        ``(m, 3)`` mm: weld spots whose contact zones apply (:meth:`SweepChecker.slack`), or
        ``None``: the whole tool keeps the clearance.
    """

    def __init__(self, checker: SweepChecker, exempt: ArrayLike | None = None) -> None:
        self.checker = checker
        self.exempt = exempt

    def is_valid(self, state: tuple[ArrayLike, ArrayLike]) -> bool:
        """Whether the tool at pose ``state`` keeps the clearance
        (:meth:`SweepChecker.state_ok`)."""
        return self.checker.state_ok(state[0], state[1], self.exempt)

    def clearance(self, state: tuple[ArrayLike, ArrayLike]) -> float:
        """mm: the tool's FCL distance to the part at pose ``state``; with weld spots exempt, a
        lower bound of what the contact-zone rule measures (:meth:`SweepChecker.slack` plus the
        clearance)."""
        p, q = state
        return self.checker.slack(p, quat_to_matrix(q), self.exempt) + self.checker.clearance

    def check_motion(self, a: tuple[ArrayLike, ArrayLike], b: tuple[ArrayLike, ArrayLike]) -> float:
        """The last valid parameter of the motion ``a -> b`` (:meth:`SweepChecker.last_valid`)."""
        return self.checker.last_valid(a, b, self.exempt)


def max_samples(bound: float, min_step: float) -> int:
    """Samples one motion of bound ``bound`` mm may take: ``2 (bound / min_step + 1)``."""
    return 2 * (math.ceil(bound / min_step) + 1)


def exempt_for(*spots: Any) -> NDArray[np.float64] | None:
    """``(m, 3)`` from the spots given (``None`` entries dropped), ``None`` when there are none."""
    pts = [np.asarray(s, dtype=np.float64).reshape(3) for s in spots if s is not None]
    return np.array(pts) if pts else None


def _bisection_order(n: int) -> NDArray[np.int64]:
    """The integers ``0..n-1`` in the order of a bisection: the middle, then the quarters, ...
    (the ends last: the motion's ends are states OMPL has checked already)."""
    seen = np.zeros(n, dtype=bool)
    out = []
    step = 1 << max(0, (n - 1).bit_length())
    while step >= 1:
        for k in range(step // 2 if step > 1 else 0, n, step):
            if not seen[k]:
                seen[k] = True
                out.append(k)
        step //= 2
    ends = list(dict.fromkeys(k for k in (0, n - 1) if k in out))
    rest = [k for k in out if k not in ends]
    return np.array(rest + ends, dtype=np.int64)
