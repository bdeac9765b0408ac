"""The robot's links and its tool against the part, along a joint-space path (python-fcl judges).

Bodies. Each link's collision mesh rides on its link frame; the tool's mesh rides on the last
link (``tip @ flange_tcp``). The tool touches the part at a weld by design, and its poses were
verified without its contact zone (:func:`weldplan.tool.plan_weld_poses`): paths are checked with
the tool minus that zone (a sphere of ``contact_radius`` mm about the TCP,
:meth:`weldplan.tool.model.Tool.outside_zone`); ``zone=False`` checks the whole tool. Between
welds the TCP point itself is the route's (verified with the cell's clearance).

The motion between two rows is linear in joint space. It is proven free conservatively, with no
shortcut shared with any planner:

1. *Bound.* During a motion no point of a sphere (centre ``p``, radius ``r``) moves farther than
   ``sum_j |dq_j| R_j`` mm, where ``R_j = |p - o_j| + r + sum_{i > j} |dq_i| R_i`` bounds its
   distance to joint j's axis over the whole motion (:func:`sphere_rates`); a static bound per
   body (chain offsets plus the body's extent) caps it and sets the number of samples.
2. *Spheres.* Each body is covered by spheres (its triangles grouped by a grid on their centroids,
   each group inside one sphere), and by one bounding sphere checked first. At every sample the
   bounding sphere's (else, at that sample, each cover sphere's) centre distance to the part
   (exact point-triangle distance, open3d) must exceed its radius plus half its motion between
   samples plus :data:`MIN_GAP_MM`: then no point of it comes closer than :data:`MIN_GAP_MM` to
   the part over the half intervals on both sides of the sample, so over the whole motion.
   Whether a centre is that far is answered by the part's distance table where its
   Lipschitz lower bound decides, by open3d's exact distance elsewhere
   (:class:`~weldplan.geometry.distbound.DistanceBound`: the same answers, several times cheaper).
3. *FCL.* The triangles of the spheres that fail, together, are advanced along the motion with
   python-fcl against the part, when any of it lies within their reach on that motion
   (conservative advancement: from a configuration at distance ``d`` they cannot touch the part
   before they have moved ``d``; collide at every step). Closer than :data:`MIN_GAP_MM` counts as a
   collision. Each step's FCL distance is asked of the part's triangles near the body
   (:class:`~weldplan.robot.collision.AlongMotion`: a crop taken again when the body may have
   left it), and only used where the crop's answer is provably the whole part's: the same
   distances, and so the same steps, as against the whole part, several times cheaper.

The part is a surface (sheet metal): a body wholly inside a closed solid is not seen here.

The robot against itself and against the floor (:mod:`weldplan.robot.collision.selfcollision`):
every state and motion checked here is also checked for the pairs of bodies its allowed collision
matrix does not exempt (the whole tool against the links away from its mount, links against
links not adjacent in the chain) and, when the cell's floor is known (``floor_z``), for every body
but the root link against the floor; with the same proof (bounding spheres, then FCL
conservative advancement, closer than 1 mm counts). A hit names the pair (``"tool/link_3"``,
``"link_2/floor"``). The links, the whole tool, the part and the floor are one collision world of
named bodies with the exempt pairs as data (:attr:`RobotCollision.world`,
:mod:`weldplan.robot.collision.world`), which the self check reads.
"""

from __future__ import annotations

import copy
import logging

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.checker import advance
from weldplan.geometry.distbound import DistanceBound
from weldplan.geometry.spherecover import sphere_cover
from weldplan.geometry.world import CollisionWorld, WorldBody
from weldplan.robot.collision.bodies import Body, Hit, of_part
from weldplan.robot.collision.motionbound import (
    PROBE_AFTER,
    Carry,
    sphere_groups,
    sphere_rates,
    touches_ahead,
)
from weldplan.robot.collision.nearpart import AlongMotion, PartCrops, fcl_distance, fcl_tf
from weldplan.robot.collision.selfcollision import SelfCheck
from weldplan.robot.collision.world import WorldSettings, floor_box, robot_world
from weldplan.robot.model.arm import Robot
from weldplan.tool.model.tool import Tool, bvh

log = logging.getLogger(__name__)

#: mm: a body closer than this to the part counts as colliding (the conservative check's floor)
MIN_GAP_MM = 1.0
#: mm: the most any body point moves between the first-level samples
SAMPLE_MM = 20.0
#: mm: grid cell of the sphere cover (triangles whose centroids share a cell share a sphere);
#: finer for the tool, which works close to the part
SPHERE_CELL_MM = 60.0
TOOL_SPHERE_CELL_MM = 25.0
#: conservative-advancement steps per (motion, body) before a motion is declared blocked
MAX_ADVANCE_STEPS = 400
#: the advancement asks a crop of the part (:mod:`weldplan.robot.collision.nearpart`) for a body of
#: at least this many triangles: the tool after its contact zone's cut (15k, 17 ms a distance to
#: the car body, 2.6 ms to a crop); for a link (at most 1000) FCL on the whole part took 0.6 ms a
#: distance, less than a crop costs to build
CROP_MIN_TRIANGLES = 2000
#: mm: the finest cell of the part's distance table (:attr:`RobotCollision.bound`). Its answers
#: do not depend on the cell (a point its bound does not clear gets open3d's exact distance), only
#: its cost does: the demo part at 5.6 mm filled 1.4 M nodes (about 1.8 s of open3d) for the
#: robot's sphere queries; at 10 mm a sixth of that, and the extra exact queries cost less than
#: the fill saves. A large part's table is coarser than this anyway (the car body's: 24 mm, its
#: node cap :data:`~weldplan.geometry.distbound.MAX_NODES`), so there nothing changes
TABLE_CELL_MM = 10.0


class RobotCollision:
    """Collision checks of a robot (and its tool) against a part (module docstring).

    Parameters
    ----------
    robot
        The robot, at its base.
    part
        The part mesh (mm, part frame).
    tool
        The tool (mesh in its TCP frame), or ``None``.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    contact_radius
        mm: the tool's contact zone exempt on motions that end at a weld.
    floor_z
        mm: the floor height in the part frame (``None``: no floor known, not checked).
    """

    def __init__(
        self,
        robot: Robot,
        part: trimesh.Trimesh,
        tool: Tool | None = None,
        flange_tcp: ArrayLike | None = None,
        *,
        contact_radius: float = 20.0,
        floor_z: float | None = None,
    ) -> None:
        from weldplan.geometry.distance import SurfaceDistance

        self.robot = robot
        self.part = part
        self.floor_z = None if floor_z is None else float(floor_z)
        self.contact_radius = float(contact_radius)
        by_part = of_part(part)
        if "distance" not in by_part:
            by_part["distance"] = SurfaceDistance(part)
        self.distance = by_part["distance"]
        # the part's derived structures, shared with every with_robot copy (made before or after
        # they are built): the distance table is filled lazily, and a table per copy refilled
        # the same blocks once for each base candidate of a search
        self._shared: dict[str, object] = {}
        self.part_obj = fcl.CollisionObject(bvh(part.vertices, part.faces), fcl.Transform())
        self.crops = PartCrops(part.vertices, part.faces, self.part_obj)
        self.flange_tcp = np.eye(4) if flange_tcp is None else np.asarray(flange_tcp, float)
        # the bodies depend on the robot model and the tool alone: built once for every checker
        # of them (kept on the robot's and the tool's caches; a with_robot copy shares them too)
        if "collision_links" not in robot._cache:
            robot._cache["collision_links"] = [
                self._body(lk.name, lk.index, lk.vertices, lk.faces) for lk in robot.links
            ]
        links = robot._cache["collision_links"]
        self.zone_bodies = list(links)
        self._links = links
        self._tool = tool
        if tool is not None:
            key = ("robot_zone_body", self._mount_key(), float(contact_radius))
            if key not in tool._cache:
                vz, fz = tool.outside_zone(contact_radius)
                tool._cache[key] = self._body(
                    "tool", 6, self._on_link6(vz), fz, TOOL_SPHERE_CELL_MM
                )
            self.zone_bodies.append(tool._cache[key])
        self.radii_zone = self._motion_radii(self.zone_bodies)

    @property
    def bound(self) -> DistanceBound:
        """The part's distance table (:class:`~weldplan.geometry.distbound.DistanceBound`, built on
        first use and shared by all :meth:`with_robot` copies and every other checker of the same
        part (:func:`~weldplan.robot.collision.bodies.of_part`): it depends on the part alone,
        and a station's reach test, joint route and program each filled the same blocks of their
        own)."""
        if "bound" not in self._shared:
            by_part = of_part(self.part)
            if "bound" not in by_part:
                lo, hi = np.asarray(self.part.bounds, dtype=np.float64)
                by_part["bound"] = DistanceBound(self.distance, lo, hi, min_cell=TABLE_CELL_MM)
            self._shared["bound"] = by_part["bound"]
        return self._shared["bound"]  # type: ignore[return-value]

    def _clear(self, points: NDArray[np.float64], need: ArrayLike) -> NDArray[np.bool_]:
        """``(n,) bool``: whether each point ``(n, 3)`` mm is farther than ``need`` (mm, scalar
        or ``(n,)``) from the part: :meth:`DistanceBound.clear
        <weldplan.geometry.distbound.DistanceBound.clear>`, asked only of the points that the
        distance to the part's bounding box (a lower bound it takes too) does not clear, so that
        a link far from the part fills no block of the table for nothing. The same answers."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        need = np.broadcast_to(np.asarray(need, dtype=np.float64), (len(P),))
        bound = self.bound
        box = np.linalg.norm(np.maximum(np.maximum(bound.lo - P, P - bound.hi), 0.0), axis=1)
        ok = box - bound.tol > need
        rest = np.flatnonzero(~ok)
        if len(rest):
            ok[rest] = bound.clear(P[rest], need[rest])
        return ok

    @property
    def world(self) -> CollisionWorld:
        """The collision world (:func:`~weldplan.robot.collision.robot_world`): the links,
        the whole tool, the part and, when known, the floor, with the allowed pairs and the
        tool's contact zone against the part as data; built on first use, once per robot, tool
        and floor (shared by every :meth:`with_robot` copy)."""
        key = ("world", self.floor_z)
        if key not in self._shared:
            bodies = self.bodies
            t = np.linalg.norm(self.robot.origins[:, :3, 3], axis=1)
            reach = float(t[0] + self.radii_full[0].max())
            n = len(self.part.faces)
            part = WorldBody("part", "part", self.part_obj, shape=f"BVH, {n} triangles")
            settings = WorldSettings(
                part=part,
                floor=None if self.floor_z is None else floor_box(reach),
                floor_z=self.floor_z,
                contact_radius=None if self._tool is None else self.contact_radius,
            )
            self._shared[key] = robot_world(self.robot, bodies, settings)
        return self._shared[key]  # type: ignore[return-value]

    @property
    def selfcheck(self) -> SelfCheck:
        """The self-collision and floor checks of the links and the whole tool
        (:class:`~weldplan.robot.collision.SelfCheck`), reading its bodies and the pairs it
        checks from :attr:`world`."""
        key = ("self", self.floor_z)
        if key not in self._shared:
            self._shared[key] = SelfCheck(self.world, self.radii_full, self.floor_z)
        return self._shared[key]  # type: ignore[return-value]

    def with_robot(self, robot: Robot) -> RobotCollision:
        """The same checker for ``robot`` at another base (part structures and link covers are
        shared: they do not depend on the base)."""
        other = copy.copy(self)
        other.robot = robot
        return other

    def _mount_key(self) -> bytes:
        """The tool's mounting on the last link (``tip @ flange_tcp``), for the tool's cache."""
        return (self.robot.tip @ self.flange_tcp).tobytes()

    def _on_link6(self, v: NDArray[np.float64]) -> NDArray[np.float64]:
        """Tool vertices (TCP frame, mm) in the last link's frame."""
        T6 = self.robot.tip @ self.flange_tcp
        return v @ T6[:3, :3].T + T6[:3, 3]

    @property
    def bodies(self) -> list[Body]:
        """The links and the whole tool (built on first use)."""
        if not hasattr(self, "_bodies"):
            full = list(self._links)
            if self._tool is not None:
                key = ("robot_whole_body", self._mount_key())
                if key not in self._tool._cache:
                    v = self._on_link6(self._tool.vertices)
                    self._tool._cache[key] = self._body(
                        "tool", 6, v, self._tool.faces, TOOL_SPHERE_CELL_MM
                    )
                full.append(self._tool._cache[key])
            self._bodies = full
            self.radii_full = self._motion_radii(full)
        return self._bodies

    @staticmethod
    def _body(name: str, frame: int, v: NDArray, f: NDArray, cell: float = SPHERE_CELL_MM) -> Body:
        c, r, g = sphere_cover(v, f, cell)
        centre = (v.min(axis=0) + v.max(axis=0)) / 2
        radius = float(np.linalg.norm(v - centre, axis=1).max()) * (1 + 1e-9) + 1e-9
        return Body(name, frame, np.asarray(v), np.asarray(f), c, r, g, centre, radius)

    def _motion_radii(self, bodies: list[Body]) -> NDArray[np.float64]:
        """``(6, b)`` mm: ``R[j, b]`` bounds the distance of body b's points from joint j's axis
        (0 for joints that do not move it)."""
        t = np.linalg.norm(self.robot.origins[:, :3, 3], axis=1)  # link offsets
        R = np.zeros((6, len(bodies)))
        for b, body in enumerate(bodies):
            rho = float(np.linalg.norm(body.vertices, axis=1).max())
            for j in range(body.frame):  # joint j (0-based) moves frames j+1..6
                R[j, b] = t[j + 1 : body.frame].sum() + rho
        return R

    # ---------------------------------------------------------------------------- one state
    def state_free(self, q: ArrayLike, *, zone: bool = False) -> bool:
        """Whether no body (FCL collide) touches the part at configuration ``q (6,)`` rad, nor
        another body or the floor (:attr:`selfcheck`)."""
        F = self.robot.link_frames(np.asarray(q, dtype=np.float64))[0]
        bodies = self.zone_bodies if zone else self.bodies
        c = np.array([F[b.frame, :3, :3] @ b.centre + F[b.frame, :3, 3] for b in bodies])
        clear = self._clear(c, np.array([b.radius for b in bodies]) + 1e-3)
        for body, far in zip(bodies, clear, strict=True):
            if far:  # its bounding sphere does not reach the part
                continue
            body.obj.setTransform(fcl_tf(F[body.frame]))
            if fcl.collide(body.obj, self.part_obj, fcl.CollisionRequest(), fcl.CollisionResult()):
                return False
        return self.selfcheck.states(self.robot, F[None])[0] is None

    def states_blocked(
        self, Q: ArrayLike, *, zone: bool = True, tool: bool = True
    ) -> list[str | None]:
        """Per configuration of ``Q (n, 6)`` rad: the first body (link name or ``tool``) that
        touches the part (FCL collide), else the first pair that touches (``"tool/link_3"``,
        ``"link_2/floor"``: :attr:`selfcheck`, the whole tool), ``None`` where none does
        (``tool=False``: links only).

        Broad phase, vectorised: a body whose bounding sphere is farther from the part than its
        radius (exact point-surface distance, open3d) cannot touch it; FCL judges the rest.
        """
        Q = np.asarray(Q, dtype=np.float64).reshape(-1, 6)
        out: list[str | None] = [None] * len(Q)
        if len(Q) == 0:
            return out
        bodies = self.zone_bodies if zone else self.bodies
        if not tool:
            bodies = [b for b in bodies if b.name != "tool"]
        F = self.robot.link_frames(Q)  # (n, 7, 4, 4)
        c = np.stack(
            [F[:, b.frame, :3, :3] @ b.centre + F[:, b.frame, :3, 3] for b in bodies], axis=1
        )  # (n, b, 3)
        radius = np.array([b.radius for b in bodies])
        need = np.broadcast_to(radius + 1e-3, c.shape[:2]).ravel()
        near = ~self._clear(c.reshape(-1, 3), need).reshape(len(Q), -1)
        for i, b in np.argwhere(near):
            if out[i] is not None:
                continue
            body = bodies[b]
            body.obj.setTransform(fcl_tf(F[i, body.frame]))
            if fcl.collide(body.obj, self.part_obj, fcl.CollisionRequest(), fcl.CollisionResult()):
                out[i] = body.name
        rest = [i for i in range(len(Q)) if out[i] is None]
        for i, b in zip(rest, self.selfcheck.states(self.robot, F[rest], tool=tool), strict=True):
            out[i] = b
        return out

    def body_distance(self, body: Body, F: NDArray[np.float64]) -> float:
        """mm: FCL distance of ``body`` at link frames ``F (7, 4, 4)`` to the part; 0 on contact."""
        return fcl_distance(body.obj, F[body.frame], self.part_obj)

    # ---------------------------------------------------------------------------- a path
    def path_hits(
        self,
        Q: ArrayLike,
        zone: ArrayLike | None = None,
        *,
        first_only: bool = False,
        only: ArrayLike | None = None,
    ) -> list[Hit]:
        """The blocked motions of the joint path ``Q (k, 6)`` rad (module docstring).

        Parameters
        ----------
        Q
            ``(k, 6)`` rad: rows; the motion ``i`` is ``Q[i] -> Q[i + 1]``.
        zone
            ``(k - 1,) bool``: motions checked with the tool's contact zone exempt.
        first_only
            Stop at the first blocked motion.
        only
            ``(k - 1,) bool``: the motions to check (default all); several paths are checked in
            one call as one array of rows with the motions joining them left out.

        Returns
        -------
        list of Hit
            One per blocked motion (none: the whole path is free).
        """
        Q = np.asarray(Q, dtype=np.float64).reshape(-1, 6)
        ns = len(Q) - 1
        if ns < 1:
            if len(Q) == 1 and not self.state_free(Q[0]):
                return [Hit(0, 0.0, "?", 0.0)]
            return []
        Z = np.zeros(ns, dtype=bool) if zone is None else np.asarray(zone, dtype=bool)
        use = np.ones(ns, dtype=bool) if only is None else np.array(only, dtype=bool)
        # motions this checker proved free before (the final path's check repeats the first
        # check's free motions and the detours' own): the same motion, the same verdict
        memo = self._free_motions()
        keys = [Q[i].tobytes() + Q[i + 1].tobytes() + bytes([bool(Z[i])]) for i in range(ns)]
        use &= np.array([k not in memo for k in keys], dtype=bool)
        dq = np.abs(np.diff(Q, axis=0))  # (ns, 6)
        hits: list[Hit] = []
        for zflag in (False, True):
            seg = np.flatnonzero((Z == zflag) & use)
            if len(seg) == 0:
                continue
            bodies = self.zone_bodies if zflag else self.bodies
            Rm = self.radii_zone if zflag else self.radii_full  # set by .bodies
            D = dq[seg] @ Rm  # (s, b) mm: motion bound per body
            suspects = self._sphere_level(Q, seg, D, bodies)
            carry = Carry(seg, D)
            for s_i, b, spheres, rates in suspects:
                if any(h.segment == int(seg[s_i]) for h in hits):
                    continue
                if carry.free(s_i, b, spheres, rates):
                    continue
                hit, left = self._advance(Q, int(seg[s_i]), bodies[b], spheres, rates)
                carry.measured(s_i, b, spheres, left)
                if hit is not None and not any(h.segment == hit.segment for h in hits):
                    hits.append(hit)
                    if first_only:
                        return hits
        # the robot against itself and the floor (the whole tool), on the motions still free
        free = np.setdiff1d(np.flatnonzero(use), [h.segment for h in hits])
        for s, t, pair, d in self.selfcheck.motions(self.robot, Q, free, first_only=first_only):
            hits.append(Hit(s, t, pair, d))
        if not first_only:  # every motion asked was checked: the ones not hit are free
            memo.update(keys[i] for i in np.setdiff1d(free, [h.segment for h in hits]))
        return sorted(hits, key=lambda h: h.segment)

    def _free_motions(self) -> set[bytes]:
        """The motions :meth:`path_hits` proved free at this checker's base (rows' bytes and the
        zone flag; kept with the shared structures, one set per base: a :meth:`with_robot`
        copy at another base has its own)."""
        key = ("free_motions", self.robot.base.tobytes())
        if key not in self._shared:
            self._shared[key] = set()
        return self._shared[key]  # type: ignore[return-value]

    def _sphere_level(
        self, Q: NDArray, seg: NDArray[np.int64], D: NDArray, bodies: list[Body]
    ) -> list[tuple[int, int, NDArray[np.int64], NDArray[np.float64]]]:
        """(motion position in ``seg``, body, spheres, their motion bounds in mm) that the
        sphere test cannot prove free."""
        n = np.maximum(np.ceil(D.max(axis=1) / SAMPLE_MM).astype(np.int64), 1) + 1  # samples
        t = np.concatenate([np.linspace(0.0, 1.0, k) for k in n])
        owner = np.repeat(np.arange(len(seg)), n)
        qs = Q[seg[owner]] + t[:, None] * (Q[seg[owner] + 1] - Q[seg[owner]])
        F = self.robot.link_frames(qs)  # (N, 7, 4, 4)
        out = []
        for b, body in enumerate(bodies):
            Fb = F[:, body.frame]
            delta = D[owner, b] / (n[owner] - 1)  # (N,) mm a point moves between samples
            # the body's bounding sphere first, its cover only where that is not enough
            c0 = Fb[:, :3, :3] @ body.centre + Fb[:, :3, 3]
            near = ~self._clear(c0, body.radius + delta / 2 + MIN_GAP_MM + 1e-3)
            # a sample whose bounding sphere is clear covers the half intervals on both sides of
            # it; only the others need the cover
            pick = np.flatnonzero(near)
            if len(pick) == 0:
                continue
            near_seg = np.unique(owner[pick])
            Fp = Fb[pick]
            c = body.centres @ np.swapaxes(Fp[:, :3, :3], 1, 2) + Fp[:, None, :3, 3]
            # each sphere's own motion bound, no larger than the body's
            first = np.searchsorted(owner, near_seg)  # the t = 0 sample of each near motion
            dq = np.abs(Q[seg[near_seg] + 1] - Q[seg[near_seg]])
            rates = sphere_rates(F[first], body.frame, body.centres, body.radii, dq)
            rates = np.minimum(rates, D[near_seg, b][:, None])  # (near motions, spheres)
            k = np.searchsorted(near_seg, owner[pick])
            step = rates[k] / (n[owner[pick]] - 1)[:, None]
            bad = self._bad_spheres(body, Fp, c, step)
            # per near motion (its samples are consecutive in ``pick``), the spheres bad anywhere
            motions, starts = np.unique(owner[pick], return_index=True)
            bad_seg = np.logical_or.reduceat(bad, starts, axis=0)
            for m in np.flatnonzero(bad_seg.any(axis=1)):
                spheres = np.flatnonzero(bad_seg[m])
                r_i = rates[int(np.searchsorted(near_seg, motions[m])), spheres]
                out.append((int(motions[m]), b, spheres, r_i))
        return out

    def _bad_spheres(
        self, body: Body, Fp: NDArray, c: NDArray[np.float64], step: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """``(p, s) bool``: the cover spheres of ``body`` not proven clear at each sample (link
        frame ``Fp (p, 4, 4)``, centres ``c (p, s, 3)`` mm, motion ``step (p, s)`` mm between
        samples): a sphere is clear when its centre is farther from the part than its radius,
        half its step and the gap.

        The spheres are asked in groups first (:func:`sphere_groups`): a group's sphere holds
        each of its spheres, so when its centre is farther than its radius, its members' largest
        half step and the gap, every member's centre is farther than the member's own need, and
        the members are not asked: the same answers, for a few dozen queries a sample instead
        of the tool's 800.
        """
        need = body.radii[None] + step / 2 + MIN_GAP_MM + 1e-3
        if not body.groups:
            body.groups.append(sphere_groups(body.centres, body.radii))
        member, gc, gr, order, starts = body.groups[0]
        g_step = np.maximum.reduceat(step[:, order], starts, axis=1)  # (p, g)
        g_c = gc @ np.swapaxes(Fp[:, :3, :3], 1, 2) + Fp[:, None, :3, 3]
        g_need = gr[None] + g_step / 2 + MIN_GAP_MM + 1e-3
        g_clear = self._clear(g_c.reshape(-1, 3), g_need.ravel()).reshape(g_need.shape)
        ask = ~g_clear[:, member]  # (p, s): spheres whose group is not clear
        bad = np.zeros(need.shape, dtype=bool)
        bad[ask] = ~self._clear(c[ask], need[ask])
        return bad

    def _advance(
        self,
        Q: NDArray,
        s: int,
        body: Body,
        spheres: NDArray[np.int64],
        rates: NDArray[np.float64],
    ) -> tuple[Hit | None, float]:
        """Conservative advancement along motion ``s`` of the triangles of ``spheres`` of
        ``body`` together (one FCL object), no point of which moves more than ``max(rates)`` mm
        over the whole motion (module docstring): the hit, else ``None``; and the slack at the
        motion's end (mm: the FCL distance of those triangles there less :data:`MIN_GAP_MM`;
        ``-inf`` where none was measured)."""
        qa, qb = Q[s], Q[s + 1]
        obj = body.union(spheres)
        rate = float(np.max(rates))
        obj.setTransform(fcl_tf(self.robot.link_frames(qa)[0, body.frame]))
        if fcl.collide(obj, self.part_obj, fcl.CollisionRequest(), fcl.CollisionResult()):
            # blocked at its start: no need to crop the part
            return Hit(s, 0.0, body.name, 0.0), -np.inf
        if not self._near_part(qa, body, spheres, rates):
            return None, -np.inf  # no part triangle within reach of these spheres
        crop = np.count_nonzero(np.isin(body.group, spheres)) >= CROP_MIN_TRIANGLES
        along = AlongMotion(
            self.crops, obj, body.centres[spheres], body.radii[spheres], rate, crop=crop
        )

        def distance(t: float) -> float:
            return along.distance(self.robot.link_frames(qa + t * (qb - qa))[0, body.frame], t)

        def probe(step: int, t: float) -> bool:
            return step in PROBE_AFTER and touches_ahead(
                self.robot, obj, self.part_obj, qa, qb, t, body.frame
            )

        run = advance(distance, rate, gap=MIN_GAP_MM, max_steps=MAX_ADVANCE_STEPS, probe=probe)
        if run.free:
            return None, run.left
        return Hit(s, run.t, body.name, run.distance), -np.inf

    def _near_part(
        self, qa: NDArray, body: Body, spheres: NDArray[np.int64], rates: NDArray[np.float64]
    ) -> bool:
        """Whether the spheres can reach the part on the motion: a point of sphere ``i`` stays
        within ``r_i + rates_i`` of its start centre, so when every start centre is farther than
        that (plus :data:`MIN_GAP_MM`) from the part (exact distance, open3d) nothing can touch
        it."""
        F = self.robot.link_frames(qa)[0, body.frame]
        c = body.centres[spheres] @ F[:3, :3].T + F[:3, 3]
        reach = body.radii[spheres] + rates + MIN_GAP_MM
        return not np.all(self._clear(c, reach + 1e-3))

    # ------------------------------------------ the StateChecker protocol (geometry.checker)
    def is_valid(self, state: ArrayLike) -> bool:
        """Whether configuration ``state (6,)`` rad is free (:meth:`state_free`)."""
        return self.state_free(state)

    def clearance(self, state: ArrayLike) -> float:
        """mm: the least FCL distance at configuration ``state (6,)`` rad between a body (the
        links and the whole tool) and the part, another body it is checked against, or the
        floor when known (:meth:`SelfCheck.distance
        <weldplan.robot.collision.SelfCheck.distance>`); 0 in contact."""
        F = self.robot.link_frames(np.asarray(state, dtype=np.float64))[0]
        d = min(self.body_distance(b, F) for b in self.bodies)
        return min(d, self.selfcheck.distance(self.robot, F))

    def check_motion(self, a: ArrayLike, b: ArrayLike, *, zone: bool = False) -> float:
        """The last valid parameter of the joint-space motion ``a -> b`` (6,) rad: 1.0 when it
        is free (:meth:`path_hits`), else the earliest of where a body came within
        :data:`MIN_GAP_MM` of the part and where a pair (or a body and the floor) met: the
        motion is free before it (a floor hit is placed within
        :data:`~weldplan.robot.collision.selfcollision.FLOOR_TOL_MM` of motion)."""
        Q = np.vstack([np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)])
        hits = self.path_hits(Q, np.array([zone]))
        if not hits:
            return 1.0
        t = hits[0].t
        if "/" not in hits[0].body:  # a part hit: path_hits did not check the pairs then
            rest = self.selfcheck.motions(self.robot, Q, np.array([0]))
            t = min([t] + [h[1] for h in rest])
        return float(t)

    def motion_free(self, qa: ArrayLike, qb: ArrayLike, *, zone: bool = False) -> bool:
        """Whether the joint-space motion ``qa -> qb`` (ends included) is free."""
        Q = np.vstack([np.asarray(qa, float), np.asarray(qb, float)])
        return not self.path_hits(Q, np.array([zone]), first_only=True)
