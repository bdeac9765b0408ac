"""Which motions of two robots come closer than the clearance: the planner's interference check.

Every robot of a station runs its timed route (:class:`~weldplan.robot.program.TimedTrajectory`)
alone; two robots that share the space around the part may meet. This module finds, per pair of
robots, the pairs of **motions** whose swept robots (every link and the whole tool, their
collision meshes through python-fcl) come closer than the station's clearance, whatever the two
robots' timing: the zones (:mod:`weldplan.multi.zones`) then order each such pair by an
interlock, and the replay (:mod:`weldplan.multi.replay`) proves the result independently.

Motions
-------
A robot's timed route, cut at its stop rows ``s_0 < s_1 < ... < s_S`` (where it is at rest),
is the sequence of :class:`Motion` ``0 .. 2S``: motion ``2i`` is the **rest** at stop ``s_i``
(one configuration, for as long as the robot welds or waits there; the rest at ``s_0`` begins
with the cycle, the rest at ``s_S`` lasts to its end), motion ``2i + 1`` the **move** from
``s_i`` to ``s_{i+1}`` (the timing's dense samples, taken as linear in joint space between two
samples, as :mod:`weldplan.robot.collision.checker` takes the motion between two rows).

What is proven, what is sampled
-------------------------------
A pair of motions is **clear** when every configuration of one is at least ``clearance`` mm
from every configuration of the other: the swept volumes, not a timed alignment, so that it holds
under any timing. It is proven, with no sample-pair left out, by three levels:

1. *Robots.* Each robot lies within its reach sphere (base origin, the chain's link offsets plus
   the largest body extent); two robots whose spheres are ``clearance`` apart have no conflict and
   cost nothing more.
2. *Motion spheres.* Each body (link or tool) over a whole motion lies in its bounding sphere
   at the motion's middle sample grown by how far any of its points can move from there
   (:func:`weldplan.robot.collision.motionbound.sphere_rates` per pair of consecutive samples, a
   bound on the path length of any point of a sphere over a linear joint motion, summed). Two
   motions whose body spheres are all ``clearance`` apart are clear.
3. *FCL, by bisection.* For the bodies that are not, the two sample ranges are halved
   recursively. A node (a range of each motion) is clear when the bodies' spheres at the two
   middle samples, or their FCL distance ``d`` there, exceed the clearance by how far each body
   can be from there over its range (the same bound, conservative advancement's argument). At
   two single samples the range is the half intervals to their neighbours: ``d < clearance``
   there is a **conflict** witnessed at two samples; ``d >= clearance`` without the proof is a
   conflict too, marked *unproven* (the motions pass within the motion bound of each other):
   conservative. Where a tool is one of the two bodies, its small spheres and the other's
   (:mod:`weldplan.multi.sweep`) bound ``d`` from below and above first; a node they settle as
   ``d`` would is not asked to FCL (``InterferenceSettings(prune=False)`` asks every one): the
   conflicts, their distances and bodies are the same.

Timing does not prune: the interlocks come after this check, and under them any robot may be
early or late at any wait, so every motion of one robot may overlap every motion of the other.

The bound is the planner's own (:mod:`weldplan.robot.collision.motionbound`, FK by
:meth:`weldplan.robot.model.Robot.link_frames`); the replay checks with its own FK and bound.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError
from weldplan.geometry.spherecover import sphere_cover
from weldplan.multi.sweep import (
    CLEAR,
    HALVE,
    Cover,
    body_cover,
    cached,
    mesh_key,
    settled,
    worth_asking,
)
from weldplan.robot.collision.bodies import Body
from weldplan.robot.collision.checker import SPHERE_CELL_MM
from weldplan.robot.collision.motionbound import sphere_rates
from weldplan.robot.collision.nearpart import fcl_tf
from weldplan.tool.model.tool import bvh

log = logging.getLogger(__name__)

#: relative slack of a time window when the samples of a move are picked by their times
TIME_EPS = 1e-9


@dataclass(frozen=True)
class InterferenceSettings:
    """How close two robots may come.

    Attributes
    ----------
    clearance
        mm: the smallest distance allowed between any two bodies (links, tools) of two robots.
    prune
        ``True``: skip the FCL queries whose answer the bodies' sphere covers already give
        (:mod:`weldplan.multi.sweep`); ``False``: ask FCL at every node the bounding spheres
        do not settle. The conflicts are the same (tested); only the work differs.
    """

    clearance: float = 5.0
    prune: bool = True

    def __post_init__(self) -> None:
        if not (np.isfinite(self.clearance) and self.clearance >= 0):
            raise ConfigError(f"clearance must be >= 0 mm, got {self.clearance}", field="clearance")


@dataclass(frozen=True, eq=False)
class MovingRobot:
    """One robot of a station with what it runs.

    Attributes
    ----------
    name
        The robot's name in the station.
    robot
        :class:`~weldplan.robot.model.Robot` at its base (part frame, mm).
    timing
        Its :class:`~weldplan.robot.program.TimedTrajectory`.
    tool
        Its tool (``vertices (v, 3)`` mm and ``faces (f, 3)`` in the TCP frame, e.g.
        :class:`weldplan.tool.model.Tool`), or ``None``.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame (ignored without a tool).
    """

    name: str
    robot: Any
    timing: Any
    tool: Any = None
    flange_tcp: NDArray[np.float64] | None = None


@dataclass(frozen=True)
class Motion:
    """One motion of a robot's cycle (module docstring).

    Attributes
    ----------
    index
        In program order: ``2i`` the rest at stop ``i``, ``2i + 1`` the move from stop ``i``.
    kind
        ``"rest"`` or ``"move"``.
    start_row, end_row
        Timed rows: where it starts and ends (equal for a rest).
    start, end
        s: its nominal interval with the robot alone (a rest: the arrival to the departure).
    """

    index: int
    kind: str
    start_row: int
    end_row: int
    start: float
    end: float


@dataclass(frozen=True)
class Conflict:
    """Two motions of two robots whose swept robots are not proven ``clearance`` apart.

    Attributes
    ----------
    a, b
        Robot indices, ``a < b``.
    x, y
        Motion indices of ``a`` and of ``b`` (:class:`Motion`).
    distance
        mm: the smallest FCL distance measured between the two (at samples).
    proven
        ``True``: a sampled distance is below the clearance; ``False``: only not proven clear.
    bodies
        ``"link_3/tool"``: the bodies of ``a`` and of ``b`` where ``distance`` was measured.
    """

    a: int
    x: int
    b: int
    y: int
    distance: float
    proven: bool
    bodies: str = ""


@dataclass(frozen=True, eq=False)
class Interference:
    """What :func:`find_interference` found.

    Attributes
    ----------
    robots
        Robot names, station order.
    clearance
        mm asked.
    motions
        Per robot its motions in program order (empty for an idle robot).
    conflicts
        Every pair of motions not proven clear, by robot pair then motion.
    robot_pairs
        Pairs of robots whose reach spheres are not ``clearance`` apart (the others cost nothing).
    pairs_checked
        Pairs of motions compared (of those robot pairs).
    fcl_calls
        FCL distance queries.
    min_distance
        mm: the smallest distance of a conflict (``inf`` when there is none).
    fcl_skipped
        FCL distance queries whose answer the sphere covers gave (:mod:`weldplan.multi.sweep`).
    """

    robots: tuple[str, ...]
    clearance: float
    motions: tuple[tuple[Motion, ...], ...]
    conflicts: tuple[Conflict, ...]
    robot_pairs: tuple[tuple[int, int], ...]
    pairs_checked: int
    fcl_calls: int
    min_distance: float
    fcl_skipped: int = 0

    def line(self) -> str:
        """One line: what was checked and found."""
        md = "" if np.isinf(self.min_distance) else f", the closest {self.min_distance:.1f} mm"
        return (
            f"{len(self.robot_pairs)} robot pairs within reach, {self.pairs_checked} motion "
            f"pairs checked, {len(self.conflicts)} not proven {self.clearance:g} mm apart "
            f"(FCL{md})"
        )


# ---------------------------------------------------------------------------- one robot
@dataclass(frozen=True, eq=False)
class _Swept:
    """A robot's bodies along its timed route: the planner side's collision model."""

    bodies: tuple[Body, ...]
    frames: NDArray[np.float64]  # (m, 7, 4, 4) link frames per sample
    centres: NDArray[np.float64]  # (m, b, 3) mm body sphere centres per sample
    radii: NDArray[np.float64]  # (b,) mm
    step: NDArray[np.float64]  # (m - 1, b) mm motion bound between consecutive samples
    cum: NDArray[np.float64]  # (m, b) mm its running sum from the first sample
    spans: tuple[tuple[int, int], ...]  # per motion, its samples [i0, i1]
    covers: dict[int, Cover]  # per body asked, its cover spheres (weldplan.multi.sweep)
    origin: NDArray[np.float64]  # (3,) base origin
    reach: float  # mm


def robot_bodies(mover: MovingRobot) -> tuple[Body, ...]:
    """The links and the whole tool of ``mover`` as :class:`~weldplan.robot.collision.Body`
    (meshes in their link frames, the tool on the last link), each with its own FCL object."""
    robot = mover.robot
    out = []
    for link in robot.links:
        out.append(_body(link.name, link.index, link.vertices, link.faces))
    if mover.tool is not None:
        ft = np.eye(4) if mover.flange_tcp is None else np.asarray(mover.flange_tcp, float)
        T6 = robot.tip @ ft
        v = np.asarray(mover.tool.vertices, float) @ T6[:3, :3].T + T6[:3, 3]
        out.append(_body("tool", 6, v, np.asarray(mover.tool.faces)))
    return tuple(out)


#: FCL BVHs of the bodies' meshes, by their digest (weldplan.multi.sweep.mesh_key): built once
#: per process for every robot of one model, each body its own CollisionObject over it (an
#: object is placed by each query; the BVH is read only)
BVHS: dict[str, fcl.BVHModel] = {}


def _body(name: str, frame: int, v: NDArray, f: NDArray) -> Body:
    c, r, g = sphere_cover(v, f, SPHERE_CELL_MM)
    centre = (v.min(axis=0) + v.max(axis=0)) / 2
    radius = float(np.linalg.norm(v - centre, axis=1).max()) * (1 + 1e-9) + 1e-9
    model = cached(BVHS, mesh_key(v, f), lambda: bvh(v, f))
    obj = {(): fcl.CollisionObject(model, fcl.Transform())}
    return Body(name, frame, np.asarray(v), np.asarray(f), c, r, g, centre, radius, obj)


def robot_motions(timing: Any) -> tuple[tuple[Motion, ...], tuple[tuple[int, int], ...]]:
    """``(motions, sample spans)``: the motions of a timed route (module docstring) and, per
    motion, the first and last index of its samples in ``timing.t``."""
    stops = np.flatnonzero(np.asarray(timing.stops))
    rt = np.asarray(timing.row_times)
    welds = set(np.asarray(timing.weld_rows).tolist())
    t = np.asarray(timing.t)
    arrive = rt[stops]
    leave = arrive + np.array([timing.weld_time if int(r) in welds else 0.0 for r in stops])
    motions: list[Motion] = []
    spans: list[tuple[int, int]] = []
    for i, r in enumerate(stops.tolist()):
        at = int(np.searchsorted(t, arrive[i] - TIME_EPS * (1 + arrive[i])))
        motions.append(Motion(2 * i, "rest", r, r, float(arrive[i]), float(leave[i])))
        spans.append((at, at))
        if i + 1 < len(stops):
            nxt = stops[i + 1]
            end = int(np.searchsorted(t, arrive[i + 1] + TIME_EPS * (1 + arrive[i + 1]))) - 1
            motions.append(
                Motion(2 * i + 1, "move", r, int(nxt), float(leave[i]), float(arrive[i + 1]))
            )
            spans.append((at, max(end, at)))
    return tuple(motions), tuple(spans)


def _swept(mover: MovingRobot) -> tuple[tuple[Motion, ...], _Swept]:
    bodies = robot_bodies(mover)
    motions, spans = robot_motions(mover.timing)
    Q = np.asarray(mover.timing.q, dtype=np.float64)
    F = mover.robot.link_frames(Q)
    C = np.stack([F[:, b.frame, :3, :3] @ b.centre + F[:, b.frame, :3, 3] for b in bodies], 1)
    radii = np.array([b.radius for b in bodies])
    dq = np.abs(np.diff(Q, axis=0))
    step = np.zeros((max(len(Q) - 1, 0), len(bodies)))
    if len(Q) > 1:
        for k, b in enumerate(bodies):
            step[:, k] = sphere_rates(F[:-1], b.frame, b.centre[None], np.array([b.radius]), dq)[
                :, 0
            ]
    origin = np.asarray(mover.robot.base)[:3, 3]
    offsets = np.linalg.norm(np.asarray(mover.robot.origins)[:, :3, 3], axis=1).sum()
    extent = max(float(np.linalg.norm(b.vertices, axis=1).max()) for b in bodies)
    cum = np.vstack([np.zeros((1, len(bodies))), np.cumsum(step, axis=0)])
    sw = _Swept(bodies, F, C, radii, step, cum, spans, {}, origin, float(offsets + extent))
    return motions, sw


# ---------------------------------------------------------------------------- spheres
def _cover(sw: _Swept, p: int) -> Cover:
    """Body ``p``'s :class:`~weldplan.multi.sweep.Cover`, made when first asked."""
    if p not in sw.covers:
        sw.covers[p] = body_cover(sw.bodies[p])
    return sw.covers[p]


def _reach(sw: _Swept, span: tuple[int, int], lo: int, hi: int) -> tuple[int, NDArray]:
    """``(mid, (b,) mm)``: the middle sample of ``[lo, hi]`` (inside the motion's ``span``) and,
    per body, how far any of its points can be from where it is at ``mid`` over the samples
    ``lo .. hi`` and the half intervals beyond them that are inside the span."""
    mid = (lo + hi) // 2
    out_lo = sw.step[lo - 1] / 2 if lo > span[0] else 0.0
    out_hi = sw.step[hi] / 2 if hi < span[1] else 0.0
    back = sw.cum[mid] - sw.cum[lo] + out_lo
    ahead = sw.cum[hi] - sw.cum[mid] + out_hi
    return mid, np.maximum(back, ahead)


def _gaps(ca: NDArray, ra: NDArray, cb: NDArray, rb: NDArray) -> NDArray[np.float64]:
    """``(ka, kb, ba, bb)`` mm: sphere-to-sphere gaps of ``(ka, ba)`` and ``(kb, bb)`` spheres."""
    d = np.linalg.norm(ca[:, None, :, None, :] - cb[None, :, None, :, :], axis=-1)
    return d - ra[:, None, :, None] - rb[None, :, None, :]


def pair_distance(
    oa: fcl.CollisionObject, Ta: NDArray, ob: fcl.CollisionObject, Tb: NDArray
) -> float:
    """mm: FCL distance of ``oa`` at ``Ta (4, 4)`` to ``ob`` at ``Tb (4, 4)``; 0 on contact."""
    oa.setTransform(fcl_tf(Ta))
    ob.setTransform(fcl_tf(Tb))
    if fcl.collide(oa, ob, fcl.CollisionRequest(), fcl.CollisionResult()):
        return 0.0
    return max(float(fcl.distance(oa, ob, fcl.DistanceRequest(), fcl.DistanceResult())), 0.0)


# ---------------------------------------------------------------------------- a pair of motions
@dataclass
class _Tally:
    fcl_calls: int = 0
    skipped: int = 0


def _bodies_apart(
    sa: _Swept, span_a: tuple[int, int], p: int, sb: _Swept, span_b: tuple[int, int], q: int,
    s: InterferenceSettings, tally: _Tally,
) -> tuple[float, bool] | None:  # fmt: skip
    """Body ``p`` of ``sa`` over ``span_a`` against body ``q`` of ``sb`` over ``span_b``:
    ``None`` when proven ``clearance`` apart, else ``(distance, proven closer)``.

    Bisection of the two sample ranges: a node (two ranges) is proven by the bounding spheres,
    else by the FCL distance ``d`` at its middle samples less how far each body can be from
    there over its range (:func:`_reach`); else the longer range is halved. Two single samples
    not proven: a conflict (witnessed when ``d < clearance``)."""
    ba, bb = sa.bodies[p], sb.bodies[q]
    ask = s.prune and worth_asking(ba, bb)
    stack = [(span_a[0], span_a[1], span_b[0], span_b[1])]
    worst: tuple[float, bool] | None = None
    while stack:
        a0, a1, b0, b1 = stack.pop()
        ma, ra = _reach(sa, span_a, a0, a1)
        mb, rb = _reach(sb, span_b, b0, b1)
        gap = np.linalg.norm(sa.centres[ma, p] - sb.centres[mb, q]) - ba.radius - bb.radius
        if gap - ra[p] - rb[q] >= s.clearance:
            continue
        Ta, Tb = sa.frames[ma, ba.frame], sb.frames[mb, bb.frame]
        leaf = a0 == a1 and b0 == b1
        known = 0 if not ask else settled(
            _cover(sa, p), Ta, _cover(sb, q), Tb, float(ra[p] + rb[q]), s.clearance, leaf
        )  # fmt: skip
        if known == CLEAR:
            tally.skipped += 1
            continue
        if known == HALVE:
            tally.skipped += 1
        else:
            d = pair_distance(ba.obj, Ta, bb.obj, Tb)
            tally.fcl_calls += 1
            if d < s.clearance:
                return d, True
            if d - ra[p] - rb[q] >= s.clearance:
                continue
        if leaf:
            worst = (d, False) if worst is None or d < worst[0] else worst
        elif b0 == b1 or (a0 < a1 and ra[p] >= rb[q]):
            stack += [(a0, ma, b0, b1), (ma + 1, a1, b0, b1)] if a1 > a0 else []
        else:
            stack += [(a0, a1, b0, mb), (a0, a1, mb + 1, b1)]
    return worst


def _pair(
    sa: _Swept, span_a: tuple[int, int], sb: _Swept, span_b: tuple[int, int],
    near: NDArray, s: InterferenceSettings, tally: _Tally,
) -> tuple[float, bool, str] | None:  # fmt: skip
    """``None`` when the two motions are proven clear, else ``(distance, proven, bodies)``;
    ``near``: the body pairs ``(p, q)`` whose motion spheres are not apart, closest first."""
    worst: tuple[float, bool, str] | None = None
    for p, q in near:
        got = _bodies_apart(sa, span_a, int(p), sb, span_b, int(q), s, tally)
        if got is None:
            continue
        names = f"{sa.bodies[p].name}/{sb.bodies[q].name}"
        if got[1]:
            return got[0], True, names
        if worst is None or got[0] < worst[0]:
            worst = (got[0], False, names)
    return worst


def _motion_spheres(sw: _Swept) -> tuple[NDArray, NDArray]:
    """Per motion, per body, one sphere holding the body over the whole motion:
    ``(motions, b, 3)`` centres, ``(motions, b)`` radii, mm."""
    cs, rs = [], []
    for span in sw.spans:
        mid, r = _reach(sw, span, *span)
        cs.append(sw.centres[mid])
        rs.append(sw.radii + r)
    return np.array(cs), np.array(rs)


def _robot_pair(
    a: int, sa: _Swept, b: int, sb: _Swept, s: InterferenceSettings, tally: _Tally
) -> tuple[list[Conflict], int]:
    """The conflicts of robots ``a`` and ``b`` and the motion pairs compared."""
    ca, ra = _motion_spheres(sa)
    cb, rb = _motion_spheres(sb)
    gaps = _gaps(ca, ra, cb, rb)
    out = []
    for x, y in np.argwhere((gaps < s.clearance).any(axis=(2, 3))).tolist():
        g = gaps[x, y]
        near = np.argwhere(g < s.clearance)
        near = near[np.argsort(g[near[:, 0], near[:, 1]])]
        found = _pair(sa, sa.spans[x], sb, sb.spans[y], near, s, tally)
        if found is not None:
            out.append(Conflict(a, x, b, y, found[0], found[1], found[2]))
    return out, len(ca) * len(cb)


def find_interference(
    robots: list[MovingRobot | None], settings: InterferenceSettings | None = None
) -> Interference:
    """Every pair of motions of two robots not proven ``clearance`` apart (module docstring).

    Parameters
    ----------
    robots
        Per robot of the station its :class:`MovingRobot` (``None``: an idle robot, left out:
        where it stands is not known).
    settings
        The clearance (mm).

    Returns
    -------
    Interference
        The motions of each robot, the conflicts and the counts.
    """
    s = settings or InterferenceSettings()
    names = tuple("" if r is None else r.name for r in robots)
    built = [None if r is None else _swept(r) for r in robots]
    motions = tuple(() if b is None else b[0] for b in built)
    tally = _Tally()
    conflicts: list[Conflict] = []
    pairs: list[tuple[int, int]] = []
    checked = 0
    for a in range(len(robots)):
        for b in range(a + 1, len(robots)):
            if built[a] is None or built[b] is None:
                continue
            sa, sb = built[a][1], built[b][1]  # type: ignore[index]
            if np.linalg.norm(sa.origin - sb.origin) - sa.reach - sb.reach >= s.clearance:
                continue
            pairs.append((a, b))
            found, n = _robot_pair(a, sa, b, sb, s, tally)
            conflicts += found
            checked += n
    log.info("interference: %d robot pairs, %d motion pairs, %d conflicts, %d FCL calls "
             "(%d skipped)", len(pairs), checked, len(conflicts), tally.fcl_calls,
             tally.skipped)  # fmt: skip
    return Interference(
        names, s.clearance, motions, tuple(conflicts), tuple(pairs), checked, tally.fcl_calls,
        min((c.distance for c in conflicts), default=float("inf")), tally.skipped,
    )  # fmt: skip
