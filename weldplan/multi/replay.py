"""The independent replay: no two robots closer than the clearance, under any timing.

The planner (:mod:`weldplan.multi.interference`, :mod:`weldplan.multi.zones`) chose interlocks
so that conflicting motions never overlap. This module checks the result with none of its code:

* **Kinematics.** Its own reading of each robot's URDF (``xml.etree``: the joints' origins and
  axes from the root of the arm's chain to the flange link, the links' collision meshes with
  their origins and scales), its own forward kinematics (scipy rotations, composed joint by
  joint), its own meshes (trimesh) and FCL objects (python-fcl BVH models it builds); the tool's
  mesh (TCP frame) hangs on the flange link through the flange-to-TCP transform.
* **Motions.** Each robot's timed program cut at its stop rows: the rest at each stop (one
  configuration) and the move between two stops (the dense samples of the timed trajectory,
  taken as linear in joint space between two samples).
* **Happens-before**, from the programs' semantics alone: each robot's motions in program order;
  an interlock puts the releasing robot's arrival at ``release_row`` before the waiting robot's
  departure from ``wait_row``. Two motions of two robots *may overlap* when neither's end
  reaches the other's start in this graph (networkx reachability): some timing (any robot early
  or late at any wait) runs them at once. Every such pair is checked, all other pairs are not.
* **Distance.** Per pair that may overlap and per pair of bodies, the two motions (continuous:
  linear in joint space between samples) are halved until each piece is proven: the bodies'
  bounding spheres, else their FCL distance, at the middle of each piece, less how far each
  body can be from there over its piece, at least the clearance. The motion bound is its own,
  static: a point of a body riding on link ``k`` moves at most ``sum_j |dq_j| rho_j`` over a
  linear joint motion, ``rho_j`` the sum of the chain's offsets from joint ``j`` to the link plus
  the body's extent. A distance below the clearance, or pieces of :data:`MIN_PIECE` of a sample
  interval still not proven, fail the pair.

:func:`replay_station` returns a :class:`~weldplan.multi.schedule.ReplayVerdict`; its
``min_distance`` is the smallest distance found over the pairs that may overlap (FCL at samples,
or the sphere gap, a lower bound, where the spheres settled a pair).
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import fcl
import networkx as nx
import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from weldplan.errors import InputError
from weldplan.multi.schedule import Interlock, ReplayVerdict

log = logging.getLogger(__name__)

#: mm per URDF metre
MM = 1000.0
#: failures named in the verdict
MAX_FAILURES = 5
#: the finest piece of a sample interval the replay halves a motion into before it gives up
#: proving a pair (1/16 of 10 ms at 100 Hz sampling)
MIN_PIECE = 1.0 / 16


@dataclass(frozen=True, eq=False)
class ReplayRobot:
    """One robot as the replay reads it.

    Attributes
    ----------
    name
        Its name in the station.
    urdf
        The robot's URDF file (metres; link meshes beside it).
    base
        ``(4, 4)`` mm: the root of the arm's chain (the parent link of its first revolute
        joint) in the part frame.
    timing
        Its :class:`~weldplan.robot.program.TimedTrajectory` (``None``: an idle robot, left out).
    tool_vertices, tool_faces
        The tool's mesh in its TCP frame (mm), or ``None``.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange link's frame.
    flange
        The flange link (default ``tool0`` when the URDF has it, else the last revolute joint's
        child).
    """

    name: str
    urdf: Path
    base: NDArray[np.float64]
    timing: Any
    tool_vertices: NDArray[np.float64] | None = None
    tool_faces: NDArray[np.int64] | None = None
    flange_tcp: NDArray[np.float64] | None = None
    flange: str | None = None


# ---------------------------------------------------------------------------- the URDF, again
def _rot(el: ET.Element | None) -> NDArray[np.float64]:
    rpy = [0.0, 0.0, 0.0] if el is None else [float(v) for v in el.get("rpy", "0 0 0").split()]
    return Rotation.from_euler("xyz", rpy).as_matrix()


def _origin(el: ET.Element | None) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] = _rot(el)
    if el is not None:
        T[:3, 3] = [float(v) * MM for v in el.get("xyz", "0 0 0").split()]
    return T


@dataclass(frozen=True, eq=False)
class _Chain:
    """The arm from its root link to the flange: per joint its origin, axis (``None``: fixed)
    and child link; the bodies (link meshes, the tool) with their FCL objects."""

    joints: tuple[tuple[NDArray, NDArray | None, str], ...]
    bodies: tuple[tuple[str, int, fcl.CollisionObject, NDArray, float, NDArray], ...]
    # (name, frame index: 0 the root, k after joint k-1, centre, radius, rho per revolute joint)


def _read_chain(rr: ReplayRobot) -> _Chain:
    path = Path(rr.urdf)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"the replay cannot read the URDF: {exc}", path=path) from None
    joints = {j.find("child").get("link"): j for j in root.findall("joint")}  # type: ignore[union-attr]
    names = {lk.get("name") for lk in root.findall("link")}
    tip = rr.flange or ("tool0" if "tool0" in names else None)
    if tip is None:
        revs = [j for j in root.findall("joint") if j.get("type") in ("revolute", "continuous")]
        tip = revs[-1].find("child").get("link")  # type: ignore[union-attr]
    up = []
    link = tip
    while link in joints:
        up.append(joints[link])
        link = joints[link].find("parent").get("link")  # type: ignore[union-attr]
    up.reverse()
    first = next(i for i, j in enumerate(up) if j.get("type") in ("revolute", "continuous"))
    chain = []
    for j in up[first:]:
        axis = None
        if j.get("type") in ("revolute", "continuous"):
            ax = j.find("axis")
            axis = np.array(
                [float(v) for v in (ax.get("xyz") if ax is not None else "1 0 0").split()]
            )
            axis = axis / np.linalg.norm(axis)
        chain.append((_origin(j.find("origin")), axis, str(j.find("child").get("link"))))  # type: ignore[union-attr]
    root_link = up[first].find("parent").get("link")  # type: ignore[union-attr]
    return _Chain(tuple(chain), _bodies(rr, root, path, str(root_link), chain))


def _bodies(rr: ReplayRobot, root: ET.Element, path: Path, root_link: str, chain: list) -> tuple:
    """Every link of the chain with a mesh, and the tool on the flange (the last frame)."""
    links = [root_link] + [c for _, _, c in chain]
    out = []
    for k, name in enumerate(links):
        el = root.find(f"link[@name='{name}']")
        node = None if el is None else el.find("collision")
        if node is None and el is not None:
            node = el.find("visual")
        mesh = None if node is None else node.find("geometry/mesh")
        if mesh is None:
            continue
        fname = (mesh.get("filename") or "").replace("file://", "")
        if fname.startswith("package://"):
            fname = fname.split("/", 3)[-1]
        tm = trimesh.load(path.parent / fname, force="mesh", process=False)
        scale = np.array([float(v) for v in mesh.get("scale", "1 1 1").split()]) * MM
        T = _origin(node.find("origin"))  # type: ignore[union-attr]
        v = (np.asarray(tm.vertices) * scale) @ T[:3, :3].T + T[:3, 3]
        out.append((name, k, v, np.asarray(tm.faces)))
    if rr.tool_vertices is not None:
        ft = np.eye(4) if rr.flange_tcp is None else np.asarray(rr.flange_tcp, float)
        v = np.asarray(rr.tool_vertices, float) @ ft[:3, :3].T + ft[:3, 3]
        out.append(("tool", len(links) - 1, v, np.asarray(rr.tool_faces)))
    return tuple(_body(name, k, v, f, chain) for name, k, v, f in out)


def _body(name: str, k: int, v: NDArray, f: NDArray, chain: list) -> tuple:
    m = fcl.BVHModel()
    m.beginModel(len(v), len(f))
    m.addSubModel(np.asarray(v, float), np.asarray(f, np.int32))
    m.endModel()
    centre = (v.min(axis=0) + v.max(axis=0)) / 2
    radius = float(np.linalg.norm(v - centre, axis=1).max()) + 1e-6
    extent = float(np.linalg.norm(v, axis=1).max())
    # rho per revolute joint before frame k: the chain's offsets after it up to frame k
    offs = [float(np.linalg.norm(o[:3, 3])) for o, _, _ in chain]
    rho = []
    for j, (_, axis, _) in enumerate(chain[:k]):
        if axis is not None:
            rho.append(sum(offs[j + 1 : k]) + extent)
    rho += [0.0] * (6 - len(rho))
    return (name, k, fcl.CollisionObject(m, fcl.Transform()), centre, radius, np.array(rho))


def _fk(chain: _Chain, base: NDArray, Q: NDArray) -> NDArray[np.float64]:
    """``(n, L + 1, 4, 4)`` mm: the root and every chain link's frame per configuration."""
    n = len(Q)
    T = np.broadcast_to(np.asarray(base, float), (n, 4, 4)).copy()
    out = [T]
    j = 0
    for origin, axis, _ in chain.joints:
        T = T @ origin
        if axis is not None:
            R = np.tile(np.eye(4), (n, 1, 1))
            R[:, :3, :3] = Rotation.from_rotvec(Q[:, j, None] * axis[None]).as_matrix()
            T = T @ R
            j += 1
        out.append(T)
    return np.stack(out, axis=1)


# ---------------------------------------------------------------------------- motions and order
def _motions(timing: Any) -> tuple[NDArray[np.int64], list[tuple[int, int]]]:
    """``(stop rows, per motion its sample range [i0, i1])``: motion ``2i`` rests at stop ``i``,
    ``2i + 1`` moves from stop ``i`` to stop ``i + 1`` (the samples between the two arrivals)."""
    stops = np.flatnonzero(np.asarray(timing.stops))
    t = np.asarray(timing.t)
    at = [int(np.argmin(np.abs(t - timing.row_times[r]))) for r in stops]
    spans: list[tuple[int, int]] = []
    for i in range(len(stops)):
        spans.append((at[i], at[i]))
        if i + 1 < len(stops):
            spans.append((at[i], at[i + 1]))
    return stops, spans


def _order(stops: list[NDArray | None], interlocks: tuple[Interlock, ...]) -> nx.DiGraph:
    """The events ``(robot, e)``: ``2i`` arrival at stop ``i``, ``2i + 1`` departure (the last:
    the cycle's end); program order and the interlocks' edges."""
    g = nx.DiGraph()
    for r, st in enumerate(stops):
        if st is None:
            continue
        n = 2 * len(st)
        g.add_nodes_from((r, e) for e in range(n))
        g.add_edges_from(((r, e), (r, e + 1)) for e in range(n - 1))
    for lock in interlocks:
        sa, sb = stops[lock.first], stops[lock.second]
        if sa is None or sb is None:
            raise InputError(f"interlock {lock.name} names an idle robot", field="interlocks")
        i = np.flatnonzero(sa == lock.release_row)
        j = np.flatnonzero(sb == lock.wait_row)
        if not len(i) or not len(j):
            raise InputError(f"interlock {lock.name}: a row that is not a stop", field="interlocks")
        g.add_edge((lock.first, 2 * int(i[0])), (lock.second, 2 * int(j[0]) + 1))
    return g


def overlapping(
    stops: list[NDArray | None], interlocks: tuple[Interlock, ...]
) -> list[tuple[int, int, int, int]]:
    """``(a, x, b, y)``, ``a < b``: every pair of motions that some timing runs at once (no
    path from the end of either to the start of the other)."""
    g = _order(stops, interlocks)
    if not nx.is_directed_acyclic_graph(g):
        raise InputError("the interlocks wait on each other in a circle", field="interlocks")
    R = len(stops)
    # reach[r][e, s]: the first event of robot s after event e of robot r (a suffix: program order)
    reach = [
        None if st is None else np.full((2 * len(st), R), np.iinfo(np.int64).max) for st in stops
    ]
    for r, e in g.nodes:
        for s, f in nx.descendants(g, (r, e)):
            reach[r][e, s] = min(reach[r][e, s], f)  # type: ignore[index]
    out = []
    for a, sa in enumerate(stops):
        for b in range(a + 1, R):
            if sa is None or stops[b] is None:
                continue
            nx_, ny = 2 * len(sa) - 1, 2 * len(stops[b]) - 1  # type: ignore[arg-type]
            x_first = reach[a][1 : nx_ + 1, b][:, None] <= np.arange(ny)[None]  # type: ignore[index]
            y_first = reach[b][1 : ny + 1, a][None, :] <= np.arange(nx_)[:, None]  # type: ignore[index]
            out += [(a, int(x), b, int(y)) for x, y in np.argwhere(~x_first & ~y_first)]
    return out


# ---------------------------------------------------------------------------- distances
@dataclass(frozen=True, eq=False)
class _Run:
    """One robot replayed: its bodies, per sample their frames, the motion bound between
    consecutive samples, its stops and motions."""

    name: str
    chain: _Chain
    frames: NDArray[np.float64]  # (n, L + 1, 4, 4)
    radii: NDArray[np.float64]  # (B,)
    step: NDArray[np.float64]  # (n - 1, B)
    stops: NDArray[np.int64]
    spans: list[tuple[int, int]]
    q: NDArray[np.float64]  # (n, 6) rad
    base: NDArray[np.float64]  # (4, 4) mm
    cum: NDArray[np.float64]  # (n, B) mm: the step bound summed from the first sample
    between: dict[float, NDArray[np.float64]]  # frames at parameters between samples


def _run(rr: ReplayRobot) -> _Run:
    chain = _read_chain(rr)
    Q = np.asarray(rr.timing.q, dtype=np.float64)
    F = _fk(chain, rr.base, Q)
    rho = np.array([b[5] for b in chain.bodies])  # (B, 6)
    step = np.abs(np.diff(Q, axis=0)) @ rho.T
    stops, spans = _motions(rr.timing)
    radii = np.array([b[4] for b in chain.bodies])
    cum = np.vstack([np.zeros((1, len(radii))), np.cumsum(step, axis=0)])
    base = np.asarray(rr.base, float)
    return _Run(rr.name, chain, F, radii, step, stops, spans, Q, base, cum, {})


def _bound(run: _Run, u: float) -> NDArray[np.float64]:
    """``(B,)`` mm: the motion bound summed from the first sample to parameter ``u`` (sample
    units; the motion between two samples is linear in joint space)."""
    if len(run.cum) == 1:
        return run.cum[0]
    k = min(int(u), len(run.cum) - 2)
    return run.cum[k] + (u - k) * run.step[k]


def _frames(run: _Run, u: float) -> NDArray[np.float64]:
    """``(L + 1, 4, 4)``: the chain's frames at parameter ``u``."""
    if u == int(u):
        return run.frames[int(u)]
    if u not in run.between:
        k = int(u)
        q = run.q[k] + (u - k) * (run.q[k + 1] - run.q[k])
        run.between[u] = _fk(run.chain, run.base, q[None])[0]
    return run.between[u]


@dataclass
class _Found:
    low: float = float("inf")
    where: tuple[int, int, int, int] | None = None
    calls: int = 0


def _distance(oa: Any, Ta: NDArray, ob: Any, Tb: NDArray) -> float:
    oa.setTransform(fcl.Transform(Ta[:3, :3], Ta[:3, 3]))
    ob.setTransform(fcl.Transform(Tb[:3, :3], Tb[:3, 3]))
    if fcl.collide(oa, ob, fcl.CollisionRequest(), fcl.CollisionResult()):
        return 0.0
    return max(float(fcl.distance(oa, ob, fcl.DistanceRequest(), fcl.DistanceResult())), 0.0)


def _check_pair(
    ra: _Run, x: int, rb: _Run, y: int, clearance: float, found: _Found
) -> tuple[float, str] | None:
    """``None`` when motions ``x`` of ``ra`` and ``y`` of ``rb`` are proven ``clearance``
    apart, else ``(distance, bodies)`` where they are not."""
    sx, sy = ra.spans[x], rb.spans[y]
    for p in range(len(ra.radii)):
        for q in range(len(rb.radii)):
            bad = _apart(ra, sx, p, rb, sy, q, clearance, found)
            if bad is not None:
                return bad, f"{ra.chain.bodies[p][0]}/{rb.chain.bodies[q][0]}"
    return None


def _apart(
    ra: _Run, sx: tuple[int, int], p: int, rb: _Run, sy: tuple[int, int], q: int,
    clearance: float, found: _Found,
) -> float | None:  # fmt: skip
    """Body ``p`` over motion ``sx`` (sample range) against body ``q`` over ``sy``: the two
    parameter ranges are halved, the longer reach first, until the bodies' spheres or their FCL
    distance at the middles, less how far each body can be from there over its range, prove
    the clearance. ``None`` when proven, else the distance where a piece of at most
    :data:`MIN_PIECE` of a sample interval on each side is not (below the clearance: met)."""
    oa, ob = ra.chain.bodies[p], rb.chain.bodies[q]
    todo = [(float(sx[0]), float(sx[1]), float(sy[0]), float(sy[1]))]
    while todo:
        a0, a1, b0, b1 = todo.pop()
        ua, ub = (a0 + a1) / 2, (b0 + b1) / 2
        ca, cb, cu = _bound(ra, a0)[p], _bound(ra, a1)[p], _bound(ra, ua)[p]
        da = max(cu - ca, cb - cu)
        ca, cb, cu = _bound(rb, b0)[q], _bound(rb, b1)[q], _bound(rb, ub)[q]
        db = max(cu - ca, cb - cu)
        Fa, Fb = _frames(ra, ua)[oa[1]], _frames(rb, ub)[ob[1]]
        centre = np.linalg.norm(
            (Fa[:3, :3] @ oa[3] + Fa[:3, 3]) - (Fb[:3, :3] @ ob[3] + Fb[:3, 3])
        ) - oa[4] - ob[4]  # fmt: skip
        if centre - da - db >= clearance:
            found.low = min(found.low, float(centre - da - db))
            continue
        dist = _distance(oa[2], Fa, ob[2], Fb)
        found.calls += 1
        found.low = min(found.low, dist)
        if dist - da - db >= clearance:
            continue
        if dist < clearance or max(a1 - a0, b1 - b0) <= MIN_PIECE:
            return dist
        if b1 - b0 <= MIN_PIECE or (a1 - a0 > MIN_PIECE and da >= db):
            todo += [(a0, ua, b0, b1), (ua, a1, b0, b1)]
        else:
            todo += [(a0, a1, b0, ub), (a0, a1, ub, b1)]
    return None


def _where(run: _Run, m: int) -> str:
    if m % 2 == 0:
        return f"{run.name} at rest at row {int(run.stops[m // 2])}"
    return f"{run.name} moving rows {int(run.stops[m // 2])} -> {int(run.stops[m // 2 + 1])}"


def replay_station(
    robots: list[ReplayRobot], interlocks: tuple[Interlock, ...], clearance: float
) -> ReplayVerdict:
    """Replay the timed programs under ``interlocks`` and worst-case timing (module docstring).

    Parameters
    ----------
    robots
        Station order (an idle robot: ``timing`` ``None``).
    interlocks
        The programs' interlocks (rows: timed stop rows).
    clearance
        mm: the smallest robot-robot distance allowed.

    Returns
    -------
    ReplayVerdict
        ``ok`` when every pair of motions that may overlap is proven ``clearance`` apart.
    """
    runs = [None if r.timing is None else _run(r) for r in robots]
    pairs = overlapping([None if r is None else r.stops for r in runs], interlocks)
    found = _Found()
    failures: list[str] = []
    for a, x, b, y in pairs:
        ra, rb = runs[a], runs[b]
        before = found.low
        bad = _check_pair(ra, x, rb, y, clearance, found)  # type: ignore[arg-type]
        if found.low < before:
            found.where = (a, _row(ra, x), b, _row(rb, y))  # type: ignore[arg-type]
        if bad is not None and len(failures) < MAX_FAILURES:
            failures.append(
                f"{_where(ra, x)} and {_where(rb, y)}: {bad[0]:.1f} mm ({bad[1]}), "  # type: ignore[arg-type]
                f"not proven {clearance:g} mm apart"
            )
    method = (
        f"replay: own URDF FK and FCL meshes, {len(pairs)} motion pairs that may overlap under "
        f"any timing (networkx happens-before of the programs and {len(interlocks)} interlocks), "
        f"both motions halved down to 1/16 of a sample: bounding spheres or FCL less a static "
        f"motion bound, "
        f"{found.calls} FCL distances"
    )
    log.info("%s; failures: %s", method, failures)
    return ReplayVerdict(
        not failures, float(clearance), found.low, found.where, len(pairs), tuple(failures), method
    )


def _row(run: _Run, m: int) -> int:
    """The timed row motion ``m`` moves to or rests at."""
    return int(run.stops[(m + 1) // 2])
