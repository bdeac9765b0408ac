"""Which welds put one robot in another robot's way: the allocation's conflict table.

Two robots of a station meet where their shares send them into the same space. The planner's
interference check (:mod:`weldplan.multi.interference`) finds it only after every robot is
planned; this module looks before the allocation, on the configurations the feasibility study
found (each robot's ``q`` at each weld it serves, and its home):

* ``at_home (R, W, R)``: robot ``r`` at weld ``i`` comes closer than ``clearance + margin``
  to robot ``s`` standing at its home. A robot stands at its home at the start and the end of
  every cycle, and the whole cycle when it has no weld; a weld that puts another robot there
  can only be welded while it is away, and not at all when it is idle;
* ``pair (R, W, R, W)``: robot ``r`` at weld ``i`` and robot ``s`` at weld ``j`` (``r != s``)
  come that close: the two welds cannot be welded at the same time, and every such pair of an
  allocation is an interlock and a wait (two robots whose shares cross meet at many).

The allocation (:func:`weldplan.multi.allocate`) keeps a weld away from a robot that meets
another at its home when some robot serves it without (:func:`home_forbidden`), and charges
each conflicting pair of welds of two robots (``AllocationSettings.conflict_s``) so that shares
that cross cost more than shares side by side (the pairwise interference cost of Lopes et al.,
EJOR 2017, and Åblad et al., IEEE T-ASE 2022, over rests instead of swept paths).

Every configuration pair is checked (deterministic, bounded: ``(1 + W_r)(1 + W_s)``
configuration pairs per robot pair): the bodies' bounding spheres first, then their sphere
covers, then the FCL distance (python-fcl, :func:`weldplan.multi.interference.pair_distance`)
of the body pairs whose spheres are not ``clearance + margin`` apart, closest first. ``margin``
covers what the table does not see: the planned gun pose is not always the study's, and the
moves between the welds.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ConflictSettings:
    """How close two robots at rest may come before their welds conflict.

    Attributes
    ----------
    clearance
        mm: the station's robot-robot clearance.
    margin
        mm added to it (module docstring: the planned poses and the moves the table does not
        see).
    """

    clearance: float = 5.0
    margin: float = 50.0

    def __post_init__(self) -> None:
        for name in ("clearance", "margin"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"must be a finite number >= 0 mm, got {v!r}", field=name)


@dataclass(frozen=True)
class RestedRobot:
    """One robot with the configurations it rests at.

    Attributes
    ----------
    name
        Its name in the station.
    robot
        :class:`~weldplan.robot.model.Robot` at its base (planning frame, mm).
    home
        ``(6,)`` rad: its home.
    q
        ``(W, 6)`` rad: its configuration at each weld (the study's), NaN where it serves none.
    tool, flange_tcp
        Its tool mesh (TCP frame, mm) and ``(4, 4)`` TCP in the flange frame, or ``None``.
    """

    name: str
    robot: Any
    home: NDArray[np.float64]
    q: NDArray[np.float64]
    tool: Any = None
    flange_tcp: NDArray[np.float64] | None = None


@dataclass(frozen=True, eq=False)
class ConflictTable:
    """What :func:`conflict_table` returns (module docstring).

    Attributes
    ----------
    robots
        ``R`` names.
    at_home
        ``(R, W, R) bool``: robot ``r`` at weld ``i`` meets robot ``s`` at its home.
    pair
        ``(R, W, R, W) bool``, symmetric: robot ``r`` at weld ``i`` meets robot ``s`` at weld
        ``j``.
    home_bodies
        ``{(r, i, s): "link_4/link_1 0.0 mm"}``: where each ``at_home`` conflict was measured.
    threshold
        mm: ``clearance + margin``.
    fcl_calls
        FCL distance queries made.
    """

    robots: tuple[str, ...]
    at_home: NDArray[np.bool_]
    pair: NDArray[np.bool_]
    home_bodies: dict[tuple[int, int, int], str]
    threshold: float
    fcl_calls: int

    def line(self) -> str:
        """One line: the conflicts found."""
        pairs = int(self.pair.sum()) // 2
        return (
            f"rest conflicts (study configurations, {self.threshold:g} mm, {self.fcl_calls} FCL "
            f"distances): {int(self.at_home.sum())} weld-robot pairs meet another robot at its "
            f"home, {pairs} pairs of welds of two robots meet"
        )


def _configs(rr: RestedRobot) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
    """``(weld index per configuration (-1: home), (n, 7, 4, 4) link frames)``."""
    q = np.asarray(rr.q, dtype=np.float64)
    served = np.flatnonzero(np.isfinite(q).all(axis=1))
    Q = np.vstack([np.asarray(rr.home, dtype=np.float64)[None], q[served]])
    return np.concatenate([[-1], served]).astype(np.intp), rr.robot.link_frames(Q)


def conflict_table(
    robots: Sequence[RestedRobot], settings: ConflictSettings | None = None
) -> ConflictTable:
    """Every robot at each of its rests against every other at each of its own (module
    docstring).

    Parameters
    ----------
    robots
        Station order, every ``q`` over the same ``W`` welds.
    settings
        The clearance and margin (mm).

    Returns
    -------
    ConflictTable
    """
    from weldplan.multi.interference import MovingRobot, pair_distance, robot_bodies

    s = settings or ConflictSettings()
    thr = s.clearance + s.margin
    R = len(robots)
    W = int(np.shape(robots[0].q)[0]) if R else 0
    at_home = np.zeros((R, W, R), dtype=bool)
    pair = np.zeros((R, W, R, W), dtype=bool)
    where: dict[tuple[int, int, int], str] = {}
    built = []
    for rr in robots:
        bodies = robot_bodies(MovingRobot(rr.name, rr.robot, None, rr.tool, rr.flange_tcp))
        idx, F = _configs(rr)
        C = np.stack([F[:, b.frame, :3, :3] @ b.centre + F[:, b.frame, :3, 3] for b in bodies], 1)
        built.append((bodies, idx, F, C, np.array([b.radius for b in bodies])))
    calls = 0
    for a in range(R):
        for b in range(a + 1, R):
            (ba, ia, Fa, Ca, ra), (bb, ib, Fb, Cb, rb) = built[a], built[b]
            d = np.linalg.norm(Ca[:, None, :, None, :] - Cb[None, :, None, :, :], axis=-1)
            gaps = d - ra[None, None, :, None] - rb[None, None, None, :]  # (na, nb, Ba, Bb)
            for x, y in np.argwhere((gaps < thr).any(axis=(2, 3))).tolist():
                g = gaps[x, y]
                near = np.argwhere(g < thr)
                for p, q in near[np.argsort(g[near[:, 0], near[:, 1]], kind="stable")]:
                    Ta, Tb = Fa[x, ba[p].frame], Fb[y, bb[q].frame]
                    if _cover_gap(ba[p], Ta, bb[q], Tb) >= thr:
                        continue
                    dist = pair_distance(ba[p].obj, Ta, bb[q].obj, Tb)
                    calls += 1
                    if dist < thr:
                        said = (ba[p].name, bb[q].name, dist)
                        _mark(at_home, pair, where, (a, int(ia[x])), (b, int(ib[y])), said)
                        break
    out = ConflictTable(tuple(r.name for r in robots), at_home, pair, where, thr, calls)
    log.info("%s", out.line())
    return out


def _cover_gap(ba: Any, Ta: NDArray, bb: Any, Tb: NDArray) -> float:
    """mm: the least gap between the sphere covers of two bodies (each
    :class:`~weldplan.robot.collision.bodies.Body`'s union of spheres holds its triangles) at
    link frames ``Ta``, ``Tb`` ``(4, 4)``: a lower bound of their FCL distance."""
    ca = ba.centres @ Ta[:3, :3].T + Ta[:3, 3]
    cb = bb.centres @ Tb[:3, :3].T + Tb[:3, 3]
    d = np.linalg.norm(ca[:, None, :] - cb[None, :, :], axis=-1)
    return float((d - ba.radii[:, None] - bb.radii[None, :]).min())


def _mark(
    at_home: NDArray, pair: NDArray, where: dict, one: tuple[int, int], other: tuple[int, int],
    said: tuple[str, str, float],
) -> None:  # fmt: skip
    """Record that robot ``one[0]`` at weld ``one[1]`` (-1: home) meets ``other`` likewise;
    ``said``: the two bodies and their distance (mm)."""
    (a, i), (b, j) = one, other
    if i >= 0 and j >= 0:
        pair[a, i, b, j] = pair[b, j, a, i] = True
    elif i >= 0:
        at_home[a, i, b] = True
        where[(a, i, b)] = f"{said[0]}/{said[1]} {said[2]:.1f} mm"
    elif j >= 0:
        at_home[b, j, a] = True
        where[(b, j, a)] = f"{said[1]}/{said[0]} {said[2]:.1f} mm"


def home_forbidden(table: ConflictTable, ok: NDArray[np.bool_]) -> dict[tuple[int, int], str]:
    """``{(robot, weld): reason}``: the welds a robot serves that put it in another robot's way
    at its home, where some other robot serves the weld without; the reason names the other
    robot and the bodies. A weld only such robots serve is kept (its conflict is left to the
    interlocks)."""
    ok = np.asarray(ok, dtype=bool)
    meets = table.at_home.any(axis=2) & ok  # (R, W)
    clean = ok & ~meets
    out = {}
    for r, i in np.argwhere(meets & clean.any(axis=0)[None, :]).tolist():
        s = int(np.flatnonzero(table.at_home[r, i])[0])
        out[(r, i)] = (
            f"at this weld it meets {table.robots[s]} at its home "
            f"({table.home_bodies.get((r, i, s), '')}; {table.threshold:g} mm)"
        )
    return out


def without(reach: Any, forbid: dict[tuple[int, int], str]) -> Any:
    """The :class:`~weldplan.multi.problem.ReachMap` ``reach`` with the pairs ``forbid``
    ``{(robot, weld): reason}`` no longer served, each refusal with its reason."""
    import dataclasses

    if not forbid:
        return reach
    ok = np.array(reach.ok, dtype=bool)
    reasons = [list(r) for r in reach.reasons]
    for (r, i), why in forbid.items():
        ok[r, i] = False
        reasons[r][i] = why
    return dataclasses.replace(reach, ok=ok, reasons=tuple(tuple(r) for r in reasons))


def weld_at(ids: dict[int, str], row: int, toward: int) -> str | None:
    """The weld a motion at timed row ``row`` belongs to (``ids``: ``{timed row: weld id}``,
    :meth:`ProgramBuild.weld_ids_by_row
    <weldplan.robot.program.ProgramBuild.weld_ids_by_row>`): the weld at ``row``, else the nearest
    weld row in the direction of ``toward`` (a move's other end), else the nearest on the
    other side (a home leg belongs to the weld it joins); ``None``: no weld."""
    if row in ids:
        return ids[row]
    rows = sorted(ids)
    if not rows:
        return None
    ahead = [k for k in rows if k > row]
    back = [k for k in rows if k < row]
    first, second = (ahead, back[::-1]) if toward >= row else (back[::-1], ahead)
    return ids[(first or second)[0]]


def blamed(
    conflicts: Sequence[Any], motions: Any, ids: Sequence[dict[int, str] | None]
) -> list[tuple[int, str, int, str]]:
    """``(robot, its weld, other robot, its weld)`` per conflict no interlock orders (a
    :class:`~weldplan.multi.interference.Conflict` with motions ``x`` of ``a`` and ``y`` of
    ``b``): the weld each motion belongs to (:func:`weld_at`; ``""`` for a robot with no
    weld or a motion away from any), the moving robot first when the other is at rest."""
    out = []
    for c in conflicts:
        got = []
        for r, m in ((c.a, c.x), (c.b, c.y)):
            mo = motions[r][m]
            w = None if ids[r] is None else weld_at(ids[r], mo.start_row, mo.end_row)
            if mo.kind == "move" and ids[r] is not None and mo.end_row in ids[r]:
                w = ids[r][mo.end_row]
            got.append((r, w or "", mo.kind))
        if got[0][2] == "rest" and got[1][2] == "move":
            got.reverse()
        out.append((got[0][0], got[0][1], got[1][0], got[1][1]))
    return out
