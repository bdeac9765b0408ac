"""The robot against itself and against the floor (python-fcl judges), for
:class:`~weldplan.robot.collision.RobotCollision`.

Bodies: the link collision meshes and the **whole** tool (no contact zone: the zone is exempt only
against the part it welds), each riding on its link frame; where the cell has a floor, a large box
(:class:`fcl.Box`) whose top face is the floor plane. They are registered, with the part, in one
collision world (:func:`~weldplan.robot.collision.robot_world`,
:class:`~weldplan.geometry.world.CollisionWorld`: named bodies and the allowed pairs as data, as
Pinocchio's ``GeometryModel``), and :class:`SelfCheck` reads its bodies and the pairs it checks
from there (:class:`~weldplan.robot.collision.AllowedCollisions`: that data by body index).

Which pairs are checked is the world's data (:mod:`weldplan.robot.collision.world`: the chain's
pairs, the description's disabled ones, MoveIt's contact rules); every other pair is checked.

The floor: every body except those of the root link (it stands on the floor or on its pedestal:
``"on the floor"``) must stay more than :data:`SELF_GAP_MM` above it. Without a known floor it is
not checked (and the world has no floor): a floor is known when it is given (``plan --floor-z``,
:attr:`weldplan.robot.placement.BaseSearch.floor_z`, ``plan_robot_route(floor_z=)``), not where the
base search assumes one (:func:`cell_floor`).

States: a pair whose bounding spheres are apart cannot touch; FCL collide judges the rest, as the
part's state check does (likewise a body whose bounding sphere stays above the floor).

Motions (linear in joint space): during a motion the points of body ``a`` move relative to the
frame of body ``b`` (the lower link) only through the joints between them, at most ``sum_j |dq_j|
R_j`` mm (``R_j`` bounding their distance to joint j's axis: the checker's motion radii); against
the floor the whole chain counts but A1 when it turns about the vertical (an upright base: it
moves no point up or down). A pair whose bounding spheres, at either end of the motion, are
farther apart than that bound plus the gap is free; the others are advanced conservatively with
FCL distance (from a configuration at distance ``d`` nothing can touch before the bodies have
moved ``d`` relative to each other; closer than :data:`SELF_GAP_MM` counts as a collision), as the
part check does. Against the floor the motion is bisected on the body's height over it, the
lowest vertex of its convex hull (:meth:`SelfCheck._floor_motion`: exact for a mesh and a plane,
with no FCL call); a hit's gap is FCL's. A motion's hit is the pair that meets first.

A hit names the pair ``"tool/link_3"`` (the body on the later link first) or ``"link_2/floor"``.
"""

from __future__ import annotations

import logging
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.checker import advance
from weldplan.geometry.world import CollisionWorld
from weldplan.robot.collision.motionbound import PROBE_AFTER, Carry, touches_ahead
from weldplan.robot.collision.nearpart import fcl_tf
from weldplan.robot.collision.world import (
    FLOOR,
    ROBOT_KINDS,
    SELF_GAP_MM,
    AllowedCollisions,
    FloorBox,
)
from weldplan.robot.collision.world import (
    pair_distance as _pair_distance,  # a name tests count calls of
)

log = logging.getLogger(__name__)

#: conservative-advancement steps per (motion, pair) before a motion is declared blocked
MAX_SELF_STEPS = 400
#: mm: the floor check of a motion splits it until no point moves more than this in a piece
FLOOR_TOL_MM = 0.05
#: pieces examined per (motion, body) against the floor before the motion is declared blocked
MAX_FLOOR_SPLITS = 2000
#: a pair is carried whole (:class:`~weldplan.robot.collision.Carry` keeps sphere subsets)
_WHOLE = np.zeros(1, dtype=np.int64)


def pair_label(a: str, b: str) -> str:
    """The name of a hit between bodies ``a`` (on the later link) and ``b``: ``"tool/link_3"``."""
    return f"{a}/{b}"


def hit_words(body: str) -> str:
    """Words for a hit's ``body``: ``"link_4 touches the part"``, ``"tool/link_3 collide
    (self-collision)"``, ``"link_2/floor collide (the floor)"`` (the body or pair first)."""
    if "/" not in body:
        return f"{body} touches the part"
    why = "the floor" if body.endswith("/" + FLOOR) else "self-collision"
    return f"{body} collide ({why})"


def cell_floor(search: Any, base: Any) -> float | None:
    """mm: the floor (part frame) a base search was told it stands the robot on,
    ``search.floor_z``; ``None`` when no floor is known: a given base, no search, a search along
    a line, or no ``floor_z`` (the search then stands the robot on the part's lowest point,
    :func:`weldplan.robot.placement.candidate_bases`: an assumption about where to put the base,
    not a floor anyone gave; the part may stand on a fixture)."""
    if base is not None or search is None or getattr(search, "line", None) is not None:
        return None
    return None if search.floor_z is None else float(search.floor_z)


class SelfCheck:
    """Self-collision and floor checks of the robot's bodies in a collision world (module
    docstring).

    Parameters
    ----------
    world
        The robot's world (:func:`robot_world`): its link and tool bodies (whose ``data`` are
        :class:`~weldplan.robot.collision.Body`) are the bodies checked, its allowed pairs the
        pairs not checked, its ``"floor"`` body the floor box.
    radii
        ``(6, b)`` mm: ``R[j, b]`` bounds the distance of body b's points from joint j's axis.
    floor_z
        mm: the floor height in the part frame (``None``: not checked; the world then has no
        floor).
    """

    def __init__(
        self, world: CollisionWorld, radii: NDArray[np.float64], floor_z: float | None
    ) -> None:
        self.world = world
        self.bodies = [b.data for b in world.of_kind(*ROBOT_KINDS)]
        self.R = radii
        self.acm = AllowedCollisions.of(world)
        self.floor_z = floor_z
        self.radius = np.array([b.radius for b in self.bodies])
        self.on_floor: list[int] = []
        if floor_z is not None:
            box: FloorBox = world.body(FLOOR).data
            self.side, self.floor = box.side, box.obj
            self.on_floor = [
                b for b, body in enumerate(self.bodies) if world.allowed(body.name, FLOOR) is None
            ]
        # per body the vertices of its convex hull (its link frame): the lowest point of a body
        # is one of them, so its height over the floor is exact with no FCL call
        self.hull = {b: _hull_points(self.bodies[b].vertices) for b in self.on_floor}

    def _height(self, b: int, F: NDArray[np.float64]) -> float:
        """mm: the height of body ``b``'s lowest point over the floor at link frames ``F (7, 4,
        4)`` (negative below it): the least z of its hull's vertices."""
        T = F[self.bodies[b].frame]
        return float(np.min(self.hull[b] @ T[2, :3]) + T[2, 3] - self.floor_z)  # type: ignore[operator]

    def _names(self, i: int, j: int) -> str:
        return pair_label(self.bodies[i].name, FLOOR if j < 0 else self.bodies[j].name)

    def _below(self, robot: Any, b: int, F: NDArray[np.float64], lift: float) -> bool:
        """Whether a point of body ``b`` at link frames ``F (7, 4, 4)`` lies less than ``lift``
        mm above the floor (FCL collide with the floor box raised by ``lift``: a solid box, so a
        body wholly below counts too)."""
        x, y = robot.base[:2, 3]
        z = float(self.floor_z) + lift - self.side / 2  # type: ignore[arg-type]
        self.floor.setTransform(fcl.Transform(np.eye(3), np.array([x, y, z])))
        body = self.bodies[b]
        body.obj.setTransform(fcl_tf(F[body.frame]))
        return bool(
            fcl.collide(body.obj, self.floor, fcl.CollisionRequest(), fcl.CollisionResult())
        )

    def _floor_gap(self, robot: Any, b: int, F: NDArray[np.float64]) -> float:
        """mm: FCL distance of body ``b`` to the floor (0 on contact), for a hit's report."""
        self._below(robot, b, F, 0.0)
        d = fcl.distance(
            self.bodies[b].obj, self.floor, fcl.DistanceRequest(), fcl.DistanceResult()
        )
        return max(float(d), 0.0)

    def distance(self, robot: Any, F: NDArray[np.float64]) -> float:
        """mm: the least FCL distance of the checked pairs, and of the bodies above the floor
        to it when the floor is known, at link frames ``F (7, 4, 4)`` of ``robot``; 0 on
        contact, ``inf`` when nothing is checked."""
        d = min(
            (_pair_distance(self.bodies, i, j, F) for i, j in self.acm.checked), default=np.inf
        )
        if self.floor_z is not None:
            d = min([d] + [self._floor_gap(robot, b, F) for b in self.on_floor])
        return float(d)

    def _use(self, tool: bool) -> NDArray[np.bool_]:
        return np.array([tool or b.name != "tool" for b in self.bodies])

    def _centres(self, F: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n, b, 3)`` mm: the bounding-sphere centres at link frames ``F (n, 7, 4, 4)``."""
        return np.stack(
            [F[:, b.frame, :3, :3] @ b.centre + F[:, b.frame, :3, 3] for b in self.bodies], axis=1
        )

    def states(self, robot: Any, F: NDArray[np.float64], *, tool: bool = True) -> list[str | None]:
        """Per configuration (link frames ``F (n, 7, 4, 4)`` of ``robot``): the first pair that
        touches (FCL collide, as the part's state check: ``"tool/link_3"``, ``"link_2/floor"``),
        ``None`` where none does (``tool=False``: the links only)."""
        out: list[str | None] = [None] * len(F)
        if len(F) == 0:
            return out
        c = self._centres(F)
        use = self._use(tool)
        pairs = [(i, j) for i, j in self.acm.checked if use[i] and use[j]]
        if pairs:
            I, J = np.array(pairs).T
            gap = np.linalg.norm(c[:, I] - c[:, J], axis=2) - self.radius[I] - self.radius[J]
            near = gap <= SELF_GAP_MM  # (n, pairs): bounding spheres meet
            for k in np.flatnonzero(near.any(axis=1)):
                out[k] = self._touching(F[k], [pairs[p] for p in np.flatnonzero(near[k])])
        if self.floor_z is not None:
            for b in self.on_floor:
                near = c[:, b, 2] - self.radius[b] <= self.floor_z
                for k in np.flatnonzero(near & use[b]):
                    if out[k] is None and self._below(robot, b, F[k], 0.0):
                        out[k] = self._names(b, -1)
        return out

    def _touching(self, F: NDArray[np.float64], pairs: list[tuple[int, int]]) -> str | None:
        """The first of ``pairs`` that touches (FCL collide) at link frames ``F (7, 4, 4)``, each
        body placed once."""
        placed: set[int] = set()
        for i, j in pairs:
            for b in (i, j):
                if b not in placed:
                    self.bodies[b].obj.setTransform(fcl_tf(F[self.bodies[b].frame]))
                    placed.add(b)
            req, res = fcl.CollisionRequest(), fcl.CollisionResult()
            if fcl.collide(self.bodies[i].obj, self.bodies[j].obj, req, res):
                return self._names(i, j)
        return None

    def _suspects(
        self, robot: Any, qa: NDArray[np.float64], qb: NDArray[np.float64]
    ) -> tuple[list[list[tuple[int, int, float]]], NDArray[np.float64]]:
        """Per motion ``qa[k] -> qb[k]``: the ``(i, j, rate mm)`` pairs (``j < 0``: the floor)
        whose bounding spheres do not prove it free (module docstring); and ``(n, p)`` mm, the
        bound on the relative motion of each checked pair ``acm.checked[p]`` over each motion."""
        dq = np.abs(qb - qa)
        ca, cb = self._centres(robot.link_frames(qa)), self._centres(robot.link_frames(qb))
        out: list[list[tuple[int, int, float]]] = [[] for _ in range(len(qa))]
        rates = np.zeros((len(qa), len(self.acm.checked)))
        for p, (i, j) in enumerate(self.acm.checked):
            fi, fj = self.bodies[i].frame, self.bodies[j].frame  # fi >= fj
            rate = dq[:, fj:fi] @ self.R[fj:fi, i]  # i's motion in j's frame
            rates[:, p] = rate
            far = np.maximum(
                np.linalg.norm(ca[:, i] - ca[:, j], axis=1),
                np.linalg.norm(cb[:, i] - cb[:, j], axis=1),
            )
            lb = far - self.radius[i] - self.radius[j] - rate
            for k in np.flatnonzero(lb <= SELF_GAP_MM):
                out[k].append((i, j, float(rate[k])))
        if self.floor_z is not None:
            # the vertical motion of a body's points: A1 turning about a vertical axis (an
            # upright base) moves none of them up or down
            up = slice(1, None) if _a1_vertical(robot) else slice(None)
            for b in self.on_floor:
                rate = dq[:, up] @ self.R[up, b]
                lb = np.maximum(ca[:, b, 2], cb[:, b, 2]) - self.radius[b] - self.floor_z - rate
                for k in np.flatnonzero(lb <= SELF_GAP_MM):
                    out[k].append((b, -1, float(rate[k])))
        return out, rates

    def motions(
        self,
        robot: Any,
        Q: NDArray[np.float64],
        seg: NDArray[np.int64],
        *,
        first_only: bool = False,
    ) -> list[tuple[int, float, str, float]]:
        """``(segment, t, pair, distance mm)`` of the pair that meets first on each blocked
        motion ``Q[s] -> Q[s + 1]`` of ``seg`` (none: every one is free; ``first_only``: stop at
        the first blocked motion).

        A pair's FCL distance carries over consecutive motions (``s`` then ``s + 1`` in
        ``seg``; :class:`~weldplan.robot.collision.Carry`, as a body's against the part): its
        *slack*, the distance less :data:`SELF_GAP_MM` less the bounds on the pair's relative
        motion since it was measured, is a lower bound of what is left of it, so a motion whose
        bound is below the slack is free with no FCL call. The per-motion
        advancement would have proven such a motion free in its first step, so the verdicts are
        the same, with fewer calls: a path of short motions (a sampled linear move) asks FCL
        about a pair once, not once per motion.
        """
        seg = np.asarray(seg, dtype=np.int64)
        if len(seg) == 0:
            return []
        qa, qb = Q[seg], Q[seg + 1]
        suspects, rates = self._suspects(robot, qa, qb)
        index = {pair: p for p, pair in enumerate(self.acm.checked)}
        carry = Carry(seg, rates)  # a pair's last distance, as the part check's bodies
        out = []
        for k in range(len(seg)):
            first: tuple[float, float, str] | None = None  # the earliest pair to meet
            for i, j, rate in suspects[k]:
                if j < 0:
                    hit = self._floor_motion(robot, qa[k], qb[k], i, rate)
                else:
                    p = index[(i, j)]
                    if carry.free(k, p, _WHOLE, np.array([rate])):
                        continue  # free: the distance measured before still proves it
                    hit, left = self._advance(robot, qa[k], qb[k], i, j, rate)
                    carry.measured(k, p, _WHOLE, left)
                if hit is not None and (first is None or hit[0] < first[0]):
                    first = (hit[0], hit[1], self._names(i, j))
            if first is not None:
                out.append((int(seg[k]), first[0], first[2], first[1]))
                if first_only:
                    return out
        return out

    def _advance(
        self, robot: Any, qa: NDArray, qb: NDArray, i: int, j: int, rate: float
    ) -> tuple[tuple[float, float] | None, float]:
        """Conservative advancement of pair ``(i, j)`` along ``qa -> qb``, over which they
        move at most ``rate`` mm relative to each other: ``(t, distance)`` where they come
        within :data:`SELF_GAP_MM` (``None`` when they never do), and the slack left at the
        motion's end (mm: a lower bound of their distance there less the gap; ``-inf`` after a
        hit)."""

        def distance(t: float) -> float:
            return _pair_distance(self.bodies, i, j, robot.link_frames(qa + t * (qb - qa))[0])

        def probe(step: int, t: float) -> bool:
            a, b = self.bodies[i], self.bodies[j]
            return step in PROBE_AFTER and touches_ahead(
                robot, a.obj, b.obj, qa, qb, t, a.frame, b.frame
            )

        run = advance(
            distance, rate, gap=SELF_GAP_MM, until_covered=True, max_steps=MAX_SELF_STEPS,
            probe=probe,
        )  # fmt: skip
        if run.free:  # they cannot meet before the motion ends
            return None, run.left
        return (run.t, run.distance), -np.inf

    def _floor_motion(
        self, robot: Any, qa: NDArray, qb: NDArray, b: int, rate: float
    ) -> tuple[float, float] | None:
        """Body ``b`` against the floor along ``qa -> qb``, over which no point of it moves more
        than ``rate`` mm: ``(t, distance)`` where it comes within :data:`SELF_GAP_MM`, ``None``
        when it never does.

        Bisection on the body's height over the floor (:meth:`_height`: the lowest of its hull's
        vertices, exact for a mesh against a plane; before, FCL collide with the floor box, a few
        ms a call and most of an OMPL run's time near a floor): an interval of length ``dt`` is
        free when the body at its middle stands more than ``SELF_GAP_MM + rate dt / 2`` above
        the floor (no point rises or sinks farther than that within it); else it is split, down
        to :data:`FLOOR_TOL_MM` of motion, where a body not yet proven clear counts as a hit
        (its gap measured by FCL). ``rate`` bounds the vertical motion only: a turn about a
        vertical A1 moves no point up or down (:meth:`_suspects`).
        """
        todo = [(0.0, 1.0)]
        for _ in range(MAX_FLOOR_SPLITS):
            if not todo:
                return None
            t0, t1 = todo.pop()
            tc, h = (t0 + t1) / 2, rate * (t1 - t0) / 2
            F = robot.link_frames(qa + tc * (qb - qa))[0]
            d = self._height(b, F)
            if d > SELF_GAP_MM + h:
                continue
            if h <= FLOOR_TOL_MM or d <= SELF_GAP_MM:
                return tc, self._floor_gap(robot, b, F)
            todo.extend([(tc, t1), (t0, tc)])  # the earlier half first
        return todo[-1][0], 0.0


def _hull_points(vertices: NDArray[np.float64]) -> NDArray[np.float64]:
    """The vertices of the convex hull of ``vertices (n, 3)`` (all of them when the hull is
    degenerate: a flat or tiny body)."""
    from scipy.spatial import ConvexHull, QhullError

    v = np.asarray(vertices, dtype=np.float64)
    try:
        return np.ascontiguousarray(v[ConvexHull(v).vertices])
    except (QhullError, ValueError):
        return np.ascontiguousarray(v)


def _a1_vertical(robot: Any) -> bool:
    """Whether ``robot``'s first axis is vertical in the planning frame (its base upright)."""
    z = (robot.base @ robot.origins[0])[:3, :3] @ robot.axes[0]
    return bool(np.linalg.norm(np.cross(z, [0.0, 0.0, 1.0])) < 1e-9)
