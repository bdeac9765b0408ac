"""The robot against itself and against the floor (python-fcl judges), for
:class:`~weldplan.robot.collision.RobotCollision`.

Bodies: the link collision meshes and the **whole** tool (no contact zone: the zone is exempt only
against the part it welds), each riding on its link frame; where the cell has a floor, a large box
(:class:`fcl.Box`) whose top face is the floor plane.

Allowed collision matrix (:func:`allowed_collisions`, computed once per robot + tool and cached).
A pair of bodies is not checked when it is

1. *adjacent*: on the same link frame or on consecutive ones (the tool rides on the last link
   through the fixed mount, so it is adjacent to the last link and to the one before it, as
   MoveIt's setup assistant merges links joined by fixed joints);
2. *in contact at the zero pose* (every joint 0, clamped into its limits): closer than
   :data:`SELF_GAP_MM` there (MoveIt's "default" pairs);
3. *in contact at every one of* :data:`ACM_SAMPLES` *random configurations* (uniform inside the
   joint limits, seed :data:`ACM_SEED`; MoveIt's "always" pairs).

MoveIt's fourth rule ("never" in contact over the samples) is not used: a sample proves nothing
about the configurations it missed, and the tool folded into the upper arm is exactly such a
rare configuration. Every other pair is checked; on the shared KUKA with the gun only rule 1
applies (no other pair touches at the zero pose, none touches at every sample): 20 of its 28
pairs are checked.

The floor: every body except those of the root link (it stands on the floor or on its pedestal)
must stay more than :data:`SELF_GAP_MM` above it. Without a known floor it is not checked: a floor
is known when it is given (``plan --floor-z``, :attr:`weldplan.robot.reach.BaseSearch.floor_z`,
``plan_robot_route(floor_z=)``), not where the base search assumes one (:func:`cell_floor`).

States: a pair whose bounding spheres are apart cannot touch; FCL collide judges the rest, as the
part's state check does (likewise a body whose bounding sphere stays above the floor).

Motions (linear in joint space): during a motion the points of body ``a`` move relative to the
frame of body ``b`` (the lower link) only through the joints between them, at most ``sum_j |dq_j|
R_j`` mm (``R_j`` bounding their distance to joint j's axis: the checker's motion radii); against
the floor the whole chain counts. A pair whose bounding spheres, at either end of the motion, are
farther apart than that bound plus the gap is free; the others are advanced conservatively with
FCL distance (from a configuration at distance ``d`` nothing can touch before the bodies have
moved ``d`` relative to each other; closer than :data:`SELF_GAP_MM` counts as a collision), as the
part check does. Against the floor the motion is bisected on FCL collide instead
(:meth:`SelfCheck._floor_motion`: FCL's distance to a box is slow). A motion's hit is the pair
that meets first.

A hit names the pair ``"tool/link_3"`` (the body on the later link first) or ``"link_2/floor"``.
"""

from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.checker import advance
from weldplan.robot.motionbound import PROBE_AFTER, Carry, touches_ahead
from weldplan.robot.nearpart import fcl_distance, fcl_tf

log = logging.getLogger(__name__)

#: mm: two bodies (or a body and the floor) closer than this count as colliding (as the part's)
SELF_GAP_MM = 1.0
#: random configurations of the allowed-collision-matrix's "always in contact" rule, and their seed
ACM_SAMPLES = 1000
ACM_SEED = 0
#: conservative-advancement steps per (motion, pair) before a motion is declared blocked
MAX_SELF_STEPS = 400
#: mm: the floor check of a motion splits it until no point moves more than this in a piece
FLOOR_TOL_MM = 0.05
#: pieces examined per (motion, body) against the floor before the motion is declared blocked
MAX_FLOOR_SPLITS = 2000
#: the floor's name in a hit
FLOOR = "floor"
#: a pair is carried whole (:class:`~weldplan.robot.motionbound.Carry` keeps sphere subsets)
_WHOLE = np.zeros(1, dtype=np.int64)
#: allowed collision matrices already computed (key: the bodies' names, frames and meshes)
_ACM_CACHE: dict[str, AllowedCollisions] = {}


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


@dataclass(frozen=True)
class AllowedCollisions:
    """Which body pairs are never checked, and why (module docstring).

    Attributes
    ----------
    names
        The bodies, in the checker's order.
    reasons
        ``{(i, j): "adjacent" | "zero pose" | "always"}`` for the allowed pairs ``i < j``.
    checked
        The pairs ``(i, j)`` that are checked, ``i`` on the later (or same) link.
    samples
        Random configurations of the "always" rule.
    """

    names: tuple[str, ...]
    reasons: dict[tuple[int, int], str]
    checked: tuple[tuple[int, int], ...]
    samples: int

    def allowed(self, a: str, b: str) -> str | None:
        """Why the pair of bodies named ``a`` and ``b`` is not checked (``None``: it is)."""
        i, j = sorted((self.names.index(a), self.names.index(b)))
        return self.reasons.get((i, j))

    def describe(self) -> list[str]:
        """One line per allowed pair: ``"link_5/tool: adjacent"``."""
        return [f"{self.names[i]}/{self.names[j]}: {w}" for (i, j), w in self.reasons.items()]


def _pair_distance(bodies: list[Any], i: int, j: int, F: NDArray[np.float64]) -> float:
    """mm: FCL distance of bodies ``i`` and ``j`` at link frames ``F (7, 4, 4)``; 0 on contact."""
    a, b = bodies[i], bodies[j]
    b.obj.setTransform(fcl_tf(F[b.frame]))
    return fcl_distance(a.obj, F[a.frame], b.obj)


def _key(bodies: list[Any], robot: Any, samples: int, seed: int, gap: float) -> str:
    h = hashlib.sha1()
    h.update(repr((samples, seed, gap, robot.lower.tolist(), robot.upper.tolist())).encode())
    h.update(np.ascontiguousarray(robot.origins).tobytes())
    for b in bodies:
        h.update(f"{b.name}:{b.frame}".encode())
        h.update(np.ascontiguousarray(b.vertices).tobytes())
        h.update(np.ascontiguousarray(b.faces).tobytes())
    return h.hexdigest()


def allowed_collisions(
    robot: Any,
    bodies: list[Any],
    *,
    samples: int = ACM_SAMPLES,
    seed: int = ACM_SEED,
    gap: float = SELF_GAP_MM,
) -> AllowedCollisions:
    """The allowed collision matrix of ``bodies`` (``name``, ``frame``, ``obj``, ``centre``,
    ``radius``, ``vertices``, ``faces``: :class:`~weldplan.robot.collision.Body`) on ``robot``
    (module docstring: adjacent, in contact at the zero pose, in contact at every sample).
    Cached per robot chain + limits + meshes."""
    key = _key(bodies, robot, samples, seed, gap)
    if key in _ACM_CACHE:
        return _ACM_CACHE[key]
    n = len(bodies)
    reasons: dict[tuple[int, int], str] = {}
    rest = []
    at = robot.with_base(np.eye(4))
    F0 = at.link_frames(np.clip(np.zeros(6), robot.lower, robot.upper))[0]
    for i in range(n):
        for j in range(i + 1, n):
            if abs(bodies[i].frame - bodies[j].frame) <= 1:
                reasons[(i, j)] = "adjacent"
            elif _pair_distance(bodies, i, j, F0) <= gap:
                reasons[(i, j)] = "zero pose"
            else:
                rest.append((i, j))
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (samples, 6))
    F = at.link_frames(Q)
    for i, j in rest:
        # "always": stops at the first sample where the pair is apart (bounding spheres first)
        for k in range(samples):
            ci = F[k, bodies[i].frame, :3, :3] @ bodies[i].centre + F[k, bodies[i].frame, :3, 3]
            cj = F[k, bodies[j].frame, :3, :3] @ bodies[j].centre + F[k, bodies[j].frame, :3, 3]
            far = np.linalg.norm(ci - cj) > bodies[i].radius + bodies[j].radius + gap
            if far or _pair_distance(bodies, i, j, F[k]) > gap:
                break
        else:
            reasons[(i, j)] = "always"
    checked = tuple(
        (j, i) if bodies[j].frame >= bodies[i].frame else (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if (i, j) not in reasons
    )
    acm = AllowedCollisions(tuple(b.name for b in bodies), reasons, checked, samples)
    log.info(
        "allowed collision matrix: %d of %d body pairs checked; allowed: %s",
        len(checked),
        n * (n - 1) // 2,
        ", ".join(acm.describe()),
    )
    _ACM_CACHE[key] = acm
    return acm


def cell_floor(search: Any, base: Any) -> float | None:
    """mm: the floor (part frame) a base search was told it stands the robot on,
    ``search.floor_z``; ``None`` when no floor is known: a given base, no search, a search along
    a line, or no ``floor_z`` (the search then stands the robot on the part's lowest point,
    :func:`weldplan.robot.reach.candidate_bases`: an assumption about where to put the base,
    not a floor anyone gave; the part may stand on a fixture)."""
    if base is not None or search is None or getattr(search, "line", None) is not None:
        return None
    return None if search.floor_z is None else float(search.floor_z)


class SelfCheck:
    """Self-collision and floor checks of a checker's bodies (module docstring).

    Parameters
    ----------
    bodies
        The links and the whole tool (:class:`~weldplan.robot.collision.Body`).
    radii
        ``(6, b)`` mm: ``R[j, b]`` bounds the distance of body b's points from joint j's axis.
    acm
        The pairs to check (:func:`allowed_collisions`).
    floor_z
        mm: the floor height in the part frame (``None``: not checked).
    reach
        mm: no body point is farther than this from the robot's base origin.
    """

    def __init__(
        self,
        bodies: list[Any],
        radii: NDArray[np.float64],
        acm: AllowedCollisions,
        floor_z: float | None,
        reach: float,
    ) -> None:
        self.bodies = bodies
        self.R = radii
        self.acm = acm
        self.floor_z = floor_z
        self.radius = np.array([b.radius for b in bodies])
        self.on_floor = [b for b, body in enumerate(bodies) if body.frame >= 1]
        # a box whose top face is the floor, wider and deeper than anything the robot reaches:
        # within the robot's reach it is the half-space below the floor (FCL's Halfspace crashed
        # python-fcl's distance)
        self.side = 2.0 * (reach + 1000.0)
        self.floor = fcl.CollisionObject(fcl.Box(self.side, self.side, self.side), fcl.Transform())

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
            for b in self.on_floor:
                rate = dq @ self.R[:, b]
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
        ``seg``; :class:`~weldplan.robot.motionbound.Carry`, as a body's against the part): its
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

        Bisection on FCL collide with the floor box (FCL's box distance is slow, tens of ms
        against the tool): an interval of length ``dt`` is free when the body at its middle is
        clear of the floor raised by ``SELF_GAP_MM + rate dt / 2`` (no point moves farther than
        that within it); else it is split, down to :data:`FLOOR_TOL_MM` of motion, where a body
        not yet proven clear counts as a hit.
        """
        todo = [(0.0, 1.0)]
        for _ in range(MAX_FLOOR_SPLITS):
            if not todo:
                return None
            t0, t1 = todo.pop()
            tc, h = (t0 + t1) / 2, rate * (t1 - t0) / 2
            F = robot.link_frames(qa + tc * (qb - qa))[0]
            if not self._below(robot, b, F, SELF_GAP_MM + h):
                continue
            if h <= FLOOR_TOL_MM or self._below(robot, b, F, SELF_GAP_MM):
                return tc, self._floor_gap(robot, b, F)
            todo.extend([(tc, t1), (t0, tc)])  # the earlier half first
        return todo[-1][0], 0.0
