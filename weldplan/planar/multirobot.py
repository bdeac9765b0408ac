"""Several robots (paper 001, section 3): the expansion logic strategy and the scoring function.

:func:`simulate_robots` runs the paper's case: each robot follows its global path (HAFSA on
the grid encoding, A* where HAFSA's best path collides) and replans locally around the others:
of the safe neighbouring cells it takes the one closest to its goal, ties to the higher eq. 15
score (001 sec. 3, after eq. 15).

How the collision probabilities enter that choice (001 gives them for the three rings but does
not say how they are used; this is our reading, named): a move into a cell with collision
probability ``p`` (:func:`collision_probability` over the expansion zones of the map's
obstacles and of the other robots' cells) succeeds with probability ``1 - p``; a failed move
leaves the robot where it is. The robot takes the cell of least *expected* distance to its
goal, ``(1 - p) |G - c| + p |G - x|`` (``x`` its cell), ties to the higher score. With
``p = 0`` everywhere this is the paper's rule exactly; otherwise, of two cells with about the
same progress, the one farther from obstacles wins, and a risky cell is taken only for
proportionally more progress. ``risk=False`` gives the rule without the probabilities. (A
sampled collision event per move would make the run stochastic for no gain in the paper's
case; an expected-cost penalty would need a collision cost the paper does not give.)

Expansion logic (001 eqs. 12-14): for a polygonal obstacle with vertices ``p_i``, the vertex
pair at the largest distance ``d_max = max d_ij`` (eq. 13) defines a range circle centred on
their midpoint with diameter ``d_max`` (eq. 14, the "endpoint connection method", chosen by
the paper over the minimum circumscribed circle for speed). Two concentric circles of diameter
``1.2 d_max`` and ``1.4 d_max`` follow; the collision probability is 0.85 inside the first
circle (outside the obstacle), 0.65 between it and the 1.2 circle, 0.45 between the 1.2 and
1.4 circles. We take it as 1 inside the obstacle and 0 beyond the last circle (the paper does
not say).

Scoring (001 eq. 15): ``score = 100 - ceil(dist / l)`` with ``dist`` the start-to-goal
distance and ``l`` the start-to-current-position distance.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: diameters of the expansion circles as multiples of d_max (001 sec. 3)
EXPANSION_FACTORS = (1.0, 1.2, 1.4)
#: collision probabilities in the three rings (001 sec. 3)
COLLISION_PROBABILITIES = (0.85, 0.65, 0.45)
#: the top score of eq. 15
SCORE_TOP = 100


@dataclass(frozen=True)
class ExpansionZone:
    """The expansion circles of one polygonal obstacle.

    Attributes
    ----------
    center
        ``(2,)``: midpoint of the farthest vertex pair (eq. 14).
    d_max
        Largest vertex-to-vertex distance (eq. 13).
    radii
        ``(3,)``: radii of the circles of diameter ``d_max``, ``1.2 d_max``, ``1.4 d_max``.
    vertices
        ``(n, 2)``: the obstacle.
    """

    center: tuple[float, float]
    d_max: float
    radii: tuple[float, float, float]
    vertices: tuple[tuple[float, float], ...]


def expansion_zone(vertices: ArrayLike) -> ExpansionZone:
    """The expansion circles of the polygon ``vertices (n, 2)`` (001 eqs. 12-14)."""
    V = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    if len(V) < 2:
        raise ValueError("an obstacle needs at least two vertices")
    d = np.linalg.norm(V[:, None] - V[None], axis=-1)  # eq. 12
    i, j = np.unravel_index(int(np.argmax(d)), d.shape)
    d_max = float(d[i, j])  # eq. 13
    c = 0.5 * (V[i] + V[j])  # eq. 14
    radii = tuple(0.5 * f * d_max for f in EXPANSION_FACTORS)
    return ExpansionZone(
        center=(float(c[0]), float(c[1])),
        d_max=d_max,
        radii=(float(radii[0]), float(radii[1]), float(radii[2])),
        vertices=tuple((float(x), float(y)) for x, y in V),
    )


def collision_probability(zones: list[ExpansionZone], points: ArrayLike) -> NDArray[np.float64]:
    """Collision probability ``(...)`` of points ``(..., 2)``: the largest over the zones of
    1 inside the obstacle, 0.85 / 0.65 / 0.45 in the three rings, 0 outside them."""
    from matplotlib.path import Path as MplPath

    P = np.asarray(points, dtype=np.float64)
    flat = P.reshape(-1, 2)
    out = np.zeros(len(flat))
    for z in zones:
        r = np.linalg.norm(flat - np.asarray(z.center), axis=1)
        p = np.select(
            [r <= z.radii[0], r <= z.radii[1], r <= z.radii[2]],
            list(COLLISION_PROBABILITIES),
            0.0,
        )
        inside = MplPath(np.asarray(z.vertices)).contains_points(flat)
        p[inside] = 1.0
        out = np.maximum(out, p)
    return out.reshape(P.shape[:-1])


def local_choice(
    here: ArrayLike, goal: ArrayLike, start: ArrayLike, cells: ArrayLike, p: ArrayLike
) -> int:
    """The local step of 001 sec. 3 with collision probabilities (module docstring): the index
    of the cell of ``cells (c, 2)`` with the least expected distance to ``goal``,
    ``(1 - p) |goal - cell| + p |goal - here|``, ties to the higher eq. 15 score (``dist`` the
    start-goal distance, ``l`` the start-cell distance). With ``p = 0`` it is the paper's rule:
    the cell closest to the goal, ties to the higher score."""
    C = np.asarray(cells, dtype=np.float64).reshape(-1, 2)
    g = np.asarray(goal, dtype=np.float64)
    s0 = np.asarray(start, dtype=np.float64)
    pc = np.broadcast_to(np.asarray(p, dtype=np.float64), (len(C),))
    here_d = float(np.linalg.norm(g - np.asarray(here, dtype=np.float64)))
    expect = (1.0 - pc) * np.linalg.norm(g - C, axis=1) + pc * here_d
    d0 = float(np.linalg.norm(g - s0))
    l = np.maximum(np.linalg.norm(C - s0, axis=1), 1e-9)  # noqa: E741 - the paper's name
    sc = score(d0, l)
    return min(range(len(C)), key=lambda m: (float(expect[m]), -int(sc[m])))


def obstacle_zones(obstacles) -> list[ExpansionZone]:
    """The expansion zones of a map's polygonal obstacles (rectangles and polygons; an
    occupancy grid's obstacles are its rectangles)."""
    out = [expansion_zone(p) for p in obstacles.polygons]
    for x0, y0, x1, y1 in np.asarray(obstacles.rectangles).reshape(-1, 4):
        out.append(expansion_zone([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    return out


def score(dist: ArrayLike, l: ArrayLike) -> NDArray[np.int64]:  # noqa: E741 - the paper's name
    """001 eq. 15: ``100 - ceil(dist / l)`` (``l > 0``)."""
    d = np.asarray(dist, dtype=np.float64)
    ll = np.asarray(l, dtype=np.float64)
    if np.any(ll <= 0):
        raise ValueError("l (distance from the start to the current position) must be > 0")
    return (SCORE_TOP - np.ceil(d / ll - 1e-12)).astype(np.int64)


# ------------------------------------------------------------------------------ simulation
#: paper 001's three-robot case on the 20 x 20 grid: start cells and goal cells
PAPER_STARTS = ((1, 1), (1, 5), (1, 9))
PAPER_GOALS = ((10, 14), (17, 1), (18, 13))
#: robots must stay strictly farther apart than this (cells): no shared or edge-adjacent cells
SAFETY_RADIUS = 1.0

_MOVES = np.array([(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1)], dtype=np.int64)


@dataclass(frozen=True)
class RobotsRun:
    """A time-stepped run of several robots on a grid (cells as ``(i, j)``, one move a step).

    Attributes
    ----------
    paths
        Per robot, the cells occupied at steps 0, 1, ... (the goal repeated after arrival).
    global_paths
        Per robot, the global path planned before the start (by ``planner``).
    arrival
        Per robot, the first step at the goal (``-1``: not reached within ``max_steps``).
    min_distance
        Per step, the smallest distance between two robots (cells; half steps included).
    safety
        The safety radius the run kept (``min(min_distance) > safety``).
    replans
        Local replanning events per robot.
    planner
        What planned the global paths (``"hafsa"``, or ``"astar"`` where HAFSA's path collided).
    """

    paths: tuple[tuple[tuple[int, int], ...], ...]
    global_paths: tuple[tuple[tuple[int, int], ...], ...]
    arrival: tuple[int, ...]
    min_distance: tuple[float, ...]
    safety: float
    replans: tuple[int, ...]
    planner: tuple[str, ...]

    @property
    def all_arrived(self) -> bool:
        return all(a >= 0 for a in self.arrival)


def _global_path(scenario, free, s, g, algorithm, rng) -> tuple[NDArray[np.int64], str]:
    """A global path of cells from ``s`` to ``g``: the optimiser on the grid encoding (paper
    001's HAFSA by default), or A* when its best path collides."""
    from dataclasses import replace

    from weldplan.optim.core import minimize
    from weldplan.optim.registry import get_optimizer
    from weldplan.planar.encodings import make_problem
    from weldplan.planar.exact import astar_grid

    if algorithm != "astar":
        grid = scenario.grid
        sc = replace(scenario, start=grid.centre(np.array(s)), goal=grid.centre(np.array(g)))
        prob = make_problem(sc, "grid")
        res = minimize(prob, get_optimizer(algorithm, pop_size=50), max_iter=100, rng=rng)
        if bool(prob.success(res.x_array[None])[0]):
            return np.asarray(prob.cells(res.x_array), dtype=np.int64), algorithm
    ex = astar_grid(free, tuple(s), tuple(g))
    return np.asarray(ex.points, dtype=np.int64), "astar"


def _step_ok(free: NDArray[np.bool_], a: NDArray[np.int64], b: NDArray[np.int64]) -> bool:
    nx, ny = free.shape
    if not (0 <= b[0] < nx and 0 <= b[1] < ny) or not free[b[0], b[1]]:
        return False
    d = b - a
    if d[0] and d[1]:  # no corner cutting
        return bool(free[a[0] + d[0], a[1]] and free[a[0], a[1] + d[1]])
    return True


def simulate_robots(
    scenario,
    starts=PAPER_STARTS,
    goals=PAPER_GOALS,
    *,
    algorithm: str = "hafsa",
    safety: float = SAFETY_RADIUS,
    max_steps: int = 200,
    risk: bool = True,
    rng=None,
) -> RobotsRun:
    """Robots follow their global paths; a robot whose next move would bring it within
    ``safety`` of another (at the end of the step or halfway) replans locally (001 sec. 3): of
    the free neighbouring cells (and staying) that keep the distance, it takes the one of least
    expected distance to its goal under the expansion zones' collision probabilities (module
    docstring; ``risk=False``: the one closest to its goal), ties to the higher eq. 15 score,
    then re-plans its global path from there with A*. Robots move in index order each step
    (lower index has priority).

    Parameters
    ----------
    scenario
        A planar scenario with an occupancy grid (e.g. ``grid20``).
    starts, goals
        Cells ``(i, j)`` per robot; the paper's case by default.
    """
    from weldplan.planar.exact import astar_grid
    from weldplan.random import as_generator

    gen = as_generator(rng)
    if scenario.grid is None:
        raise ValueError("simulate_robots needs a scenario with an occupancy grid")
    free = ~scenario.grid.occupied
    S = np.asarray(starts, dtype=np.int64)
    G = np.asarray(goals, dtype=np.int64)
    n = len(S)
    plans, planner = [], []
    for k in range(n):
        p, who = _global_path(scenario, free, S[k], G[k], algorithm, gen)
        plans.append(p)
        planner.append(who)
    glob = [tuple((int(a), int(b)) for a, b in p) for p in plans]
    risk_of = _risk_model(scenario, free, risk)
    pos = S.copy()
    idx = [0] * n
    hist = [[tuple(int(v) for v in s)] for s in S]
    arrival = [0 if (S[k] == G[k]).all() else -1 for k in range(n)]
    replans = [0] * n
    dmin = [_min_pair(pos.astype(float))]
    for t in range(1, max_steps + 1):
        new = pos.copy()
        for k in range(n):
            if arrival[k] >= 0:
                continue
            want = plans[k][idx[k] + 1] if idx[k] + 1 < len(plans[k]) else G[k]
            step = _step(free, pos, new, k, want, S[k], G[k], safety, risk_of)
            if step == "follow":
                idx[k] += 1
            elif step == "replan":
                replans[k] += 1
                start = tuple(int(v) for v in new[k])
                plans[k] = np.asarray(astar_grid(free, start, tuple(G[k])).points, dtype=np.int64)
                idx[k] = 0
            if (new[k] == G[k]).all():
                arrival[k] = t
        mids = 0.5 * (pos + new)
        pos = new
        for k in range(n):
            hist[k].append((int(pos[k, 0]), int(pos[k, 1])))
        dmin.append(min(_min_pair(pos.astype(float)), _min_pair(mids)))
        if all(a >= 0 for a in arrival):
            break
    return RobotsRun(
        paths=tuple(tuple(h) for h in hist),
        global_paths=tuple(glob),
        arrival=tuple(arrival),
        min_distance=tuple(float(v) for v in dmin),
        safety=float(safety),
        replans=tuple(replans),
        planner=tuple(planner),
    )


def _risk_model(
    scenario, free: NDArray[np.bool_], risk: bool
) -> Callable[[NDArray[np.int64], NDArray[np.int64]], NDArray[np.float64]]:
    """``risk_of(cells (c, 2), others (r, 2))``: collision probability of moving into each
    cell under the obstacles' expansion zones and those of the other robots' cells (unit
    squares); all zeros when ``risk`` is False."""
    grid = scenario.grid
    zones = obstacle_zones(scenario.obstacles) if risk else []
    p_static = np.zeros(free.shape)
    if zones:  # collision probability of every cell centre under the obstacles' zones
        ij = np.argwhere(np.ones(free.shape, dtype=bool))
        p_static[ij[:, 0], ij[:, 1]] = collision_probability(zones, grid.centre(ij))

    def risk_of(cells: NDArray[np.int64], others: NDArray[np.int64]) -> NDArray[np.float64]:
        p = p_static[cells[:, 0], cells[:, 1]]
        if not risk or not len(others):
            return p
        h = 0.5 * grid.cell
        sq = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
        rz = [expansion_zone(grid.centre(o) + sq) for o in others]
        return np.maximum(p, collision_probability(rz, grid.centre(cells)))

    return risk_of


def _step(
    free: NDArray[np.bool_],
    pos: NDArray[np.int64],
    new: NDArray[np.int64],
    k: int,
    want: NDArray[np.int64],
    start: NDArray[np.int64],
    goal: NDArray[np.int64],
    safety: float,
    risk_of: Callable[[NDArray[np.int64], NDArray[np.int64]], NDArray[np.float64]],
) -> str:
    """Robot ``k``'s move this step, written into ``new[k]`` (``pos``: every robot at the start
    of the step; ``new``: lower indices already moved). ``"follow"``: the next cell of its
    path ``want``; ``"replan"``: the local choice (a different cell: re-plan from there);
    ``"stay"``: the local choice kept it, or nowhere was safe."""
    here = pos[k]
    others_now = np.delete(pos, k, axis=0).astype(float)
    moved = np.delete(new, k, axis=0).astype(float)

    def clear(c: NDArray[np.int64]) -> bool:
        mid = 0.5 * (here + c)
        mids = 0.5 * (others_now + moved)
        return bool(
            np.all(np.linalg.norm(moved - c, axis=1) > safety)
            and np.all(np.linalg.norm(mids - mid, axis=1) > safety)
        )

    if _step_ok(free, here, want) and clear(want):
        new[k] = want
        return "follow"
    cand = [here + m for m in _MOVES]
    cand = [c for c in cand if (c == here).all() or _step_ok(free, here, c)]
    cand = [c for c in cand if clear(c)]
    if not cand:  # nowhere safe: stay (checked again at the end of the step)
        return "stay"
    C = np.array(cand)
    pc = risk_of(C, np.delete(new, k, axis=0))
    best = C[local_choice(here, goal, start, C, pc)]
    new[k] = best
    return "stay" if (best == here).all() else "replan"


def _min_pair(P: NDArray[np.float64]) -> float:
    d = np.linalg.norm(P[:, None] - P[None], axis=-1)
    d[np.diag_indices(len(P))] = np.inf
    return float(d.min())
