"""The papers' path encodings as Problems: any registered optimiser plans on any of them.

* :class:`SplinePathProblem` (paper 000, sec. 4.4): m path nodes between the fixed start and
  goal, cubic-spline interpolation in x and y, fitness eq. 10 ``S = eta1 f1 + eta2 f2``.
* :class:`SegmentPathProblem` (paper 003, sec. 4.1-4.2): the x' axis from start to target split
  into N equal segments, the y' offsets of the N - 1 inner nodes optimised within the map
  (eq. 8-10), feasible and infeasible fitness of eq. 11-16 transcribed into minimisation.
  ``frame="original"`` gives 003's "PSO in the original coordinates": the nodes' (x, y) free.
* :class:`GridPathProblem` (paper 001): 8-connected moves on an occupancy grid between
  waypoint cells joined by digital straight lines.

Every problem decodes a population ``X (P, n_var)`` into polylines ``(P, n, 2)`` with
:meth:`PathProblem.decode`, evaluates the whole population at once, and measures one solution
with :meth:`PathProblem.measure` (length, smoothness, clearance, collisions) against the
scenario's obstacles plus the map frame (:attr:`Scenario.world`).
"""

from __future__ import annotations

import logging
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import WeldplanError
from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.geometry.pathcore import at_fractions
from weldplan.geometry.pathmetrics import PathMetrics, measure, path_length, smoothness
from weldplan.geometry.splines import N_INTERP, cubic_spline_path
from weldplan.optim.core import Problem
from weldplan.planar.scenarios import Scenario

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: paper 000 eq. 10: path-length coefficient eta1 and collision coefficient eta2
ETA1 = 1.0
ETA2 = 1000.0
#: paper 000 Table 2: m = 3 path nodes
SPLINE_NODES = 3
#: deepest penetration (map units) a spline path may graze an obstacle and count as
#: collision-free (see SplinePathProblem.success)
GRAZE_TOL_SPLINE = 0.01
#: roadmap seeding (an off-by-default improvement, not in paper 000): cell size of the coarse
#: occupancy grid, in map units, and the share of the initial population seeded along its A* path
ROADMAP_CELL = 0.25
ROADMAP_SHARE = 1.0 / 3.0


class PathProblem(Problem):
    """Base of the planar encodings: a scenario, a decoder and a measure."""

    scenario: Scenario
    world: Obstacles2D

    def decode(self, X: ArrayLike) -> FloatArray:
        """Polylines ``(P, n, 2)`` from start to goal of solutions ``X (P, n_var)``."""
        raise NotImplementedError

    def path(self, x: ArrayLike) -> FloatArray:
        """The polyline ``(n, 2)`` of one solution ``x (n_var,)``."""
        return self.decode(np.asarray(x, dtype=np.float64).reshape(1, -1))[0]

    def measure(self, x: ArrayLike) -> PathMetrics:
        """Length, smoothness, clearance and collisions of one solution's path."""
        return measure(self.path(x), self.world)

    def success(self, X: ArrayLike) -> NDArray[np.bool_]:
        """Whether each solution's path is collision-free: ``(P,) bool``."""
        P = self.decode(np.atleast_2d(np.asarray(X, dtype=np.float64)))
        return ~np.any(self.world.segments_hit(P[:, :-1], P[:, 1:]), axis=1)

    def roadmap_path(self, cell: float = ROADMAP_CELL) -> FloatArray:
        """A coarse global path ``(n, 2)``: 8-connected A* on the map rasterised at ``cell``.

        A cell is free when its whole square is clear of obstacles (clearance of its centre
        above half its diagonal); start and goal cells are forced free. Octile lengths differ
        from Euclidean ones by up to 8 %, so this picks a corridor (a homotopy class), not
        the any-angle optimum; it is the cheap global planner of the ``roadmap`` seeding, not
        the exact baseline. Cached per cell size.
        """
        from weldplan.planar.exact import astar_grid

        cache = self.__dict__.setdefault("_roadmap", {})
        if cell in cache:
            return cache[cell]
        x0, y0, x1, y1 = (float(v) for v in self.scenario.bounds)
        nx, ny = max(int(np.ceil((x1 - x0) / cell)), 1), max(int(np.ceil((y1 - y0) / cell)), 1)
        ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        centres = np.stack([x0 + (ii + 0.5) * cell, y0 + (jj + 0.5) * cell], axis=-1)
        free = self.world.clearance(centres) > 0.0
        s, g = self.scenario.start, self.scenario.goal
        si = tuple(int(v) for v in np.clip(((s - [x0, y0]) // cell), 0, [nx - 1, ny - 1]))
        gi = tuple(int(v) for v in np.clip(((g - [x0, y0]) // cell), 0, [nx - 1, ny - 1]))
        free[si] = free[gi] = True
        cells = astar_grid(free, si, gi).points_array.astype(np.int64)
        path = np.vstack([s, centres[cells[1:-1, 0], cells[1:-1, 1]], g])
        cache[cell] = path
        return path

    def initial_population(
        self, rng: np.random.Generator, n: int, share: float = ROADMAP_SHARE
    ) -> FloatArray:
        """``n`` starting solutions ``(n, n_var)``: ``ceil(share n)`` seeded along
        :meth:`roadmap_path`, the rest uniform in the box.

        A seeded solution puts node ``k = 1..m`` at the arc-length fraction
        ``(k + u) / (m + 1)`` of the roadmap path, ``u ~ U(-1/2, 1/2)``, plus Gaussian noise of
        one cell, and :meth:`encode_nodes` turns the nodes into variables. Used by optimisers
        built with ``init="problem"`` (the homotopy-aware start of the LRSMA improvement, see
        ``weldplan bench planar``, and of the default pipeline); the faithful algorithms draw
        uniformly. When no roadmap path exists every row is uniform.
        """
        from weldplan.errors import PlanningError

        X = self.lower + rng.random((n, self.n_var)) * (self.upper - self.lower)
        k = min(int(np.ceil(share * n)), n)
        try:
            path = self.roadmap_path()
        except PlanningError:
            log.warning("no roadmap path on %s; uniform initial population", self.scenario.name)
            return X
        if k == 0:
            return X
        m = self.n_seed_nodes
        q = (np.arange(1, m + 1) + rng.uniform(-0.5, 0.5, (k, m))) / (m + 1)
        nodes = at_fractions(path, q)
        nodes += rng.normal(0.0, ROADMAP_CELL, nodes.shape)
        X[:k] = np.clip(self.encode_nodes(nodes, path, rng), self.lower, self.upper)
        return X

    @property
    def n_seed_nodes(self) -> int:
        """Path nodes a seeded solution places (:meth:`initial_population`)."""
        raise NotImplementedError

    def encode_nodes(
        self, nodes: FloatArray, path: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        """Variables ``(k, n_var)`` of solutions through nodes ``(k, m, 2)`` placed along the
        roadmap ``path (p, 2)`` (default: the nodes' coordinates; ``rng`` unused)."""
        return nodes.reshape(len(nodes), -1)


class SplinePathProblem(PathProblem):
    """Paper 000 sec. 4.4: cubic spline through m nodes, ``S = eta1 f1 + eta2 f2`` (eq. 10).

    Variables ``(x_1, y_1, ..., x_m, y_m)``, each within the scenario bounds. The path is the
    polyline through ``n_interp`` points of the cubic spline (uniform parameter, not-a-knot,
    as MATLAB's ``spline``) through start, nodes and goal.

    ``f1`` is the polyline length. ``f2``, "the average distance between all interpolation
    points and all obstacles", positive only when the path enters an obstacle, is read as the
    mean over the interpolation points of their penetration depth ``max(0, -signed
    distance)`` summed over the obstacles (the four frame rectangles of the map included, so
    leaving the map is penalised). It is judged on the interpolation points, so a path can
    cut a thin obstacle between two points with ``f2 = 0``; :meth:`success` checks every
    segment exactly. (Averaging over the obstacles as well would make shallow cuts cheaper
    than going round: most best paths then graze into the circles.)
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        n_nodes: int = SPLINE_NODES,
        n_interp: int = N_INTERP,
        eta1: float = ETA1,
        eta2: float = ETA2,
        graze_tol: float = GRAZE_TOL_SPLINE,
    ) -> None:
        lo = np.tile(scenario.bounds[:2], n_nodes)
        hi = np.tile(scenario.bounds[2:], n_nodes)
        super().__init__(lo, hi, name=f"spline:{scenario.name}")
        self.scenario = scenario
        self.world = scenario.world
        self.n_nodes = int(n_nodes)
        self.n_interp = int(n_interp)
        self.eta1 = float(eta1)
        self.eta2 = float(eta2)
        self.graze_tol = float(graze_tol)

    @property
    def n_seed_nodes(self) -> int:
        return self.n_nodes

    def decode(self, X: ArrayLike) -> FloatArray:
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        P = X.shape[0]
        nodes = np.empty((P, self.n_nodes + 2, 2))
        nodes[:, 0] = self.scenario.start
        nodes[:, -1] = self.scenario.goal
        nodes[:, 1:-1] = X.reshape(P, self.n_nodes, 2)
        return cubic_spline_path(nodes, self.n_interp)

    def _evaluate(self, X: FloatArray) -> FloatArray:
        paths = self.decode(X)
        f1 = path_length(paths)
        f2 = np.mean(self.world.total_penetration(paths), axis=1)
        return self.eta1 * f1 + self.eta2 * f2

    def success(self, X: ArrayLike) -> NDArray[np.bool_]:
        """Collision-free up to ``graze_tol``: no point of the path deeper than that inside.

        Eq. 10 trades a sliver of penetration for length (a depth d at a few of the 100
        samples costs ``eta2 d k / n``, comparable to what cutting the corner saves), so the
        best paths of every optimiser graze obstacles by about 0.01 units or less; the
        polyline is checked at its samples and at the deepest point of each segment
        (segments cut circles between samples too). :meth:`strict_success` allows no depth.
        """
        paths = self.decode(np.atleast_2d(np.asarray(X, dtype=np.float64)))
        o = self.world
        nc = len(o.circles)
        chords = o.inside_length(paths[:, :-1], paths[:, 1:], per_obstacle=True)  # (P, S, O)
        # a chord of length c in a circle of radius r reaches depth r - sqrt(r^2 - c^2 / 4)
        r = o.circles[:, 2]
        c = chords[..., :nc]
        circle_depth = r - np.sqrt(np.maximum(r * r - 0.25 * c * c, 0.0))
        worst = np.max(circle_depth, axis=(1, 2), initial=0.0)
        # samples inside an obstacle (a segment's chord underestimates depth when its ends
        # are inside)
        worst = np.maximum(worst, np.max(o.penetration(paths), axis=(1, 2), initial=0.0))
        # other obstacles (rectangles, polygons, the frame): the length cut inside them
        worst = np.maximum(worst, np.max(chords[..., nc:], axis=(1, 2), initial=0.0))
        return worst <= self.graze_tol

    def strict_success(self, X: ArrayLike) -> NDArray[np.bool_]:
        """No segment of the sampled polyline enters an obstacle (exact)."""
        return super().success(X)


def line_bounds(
    bounds: ArrayLike, points: ArrayLike, direction: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """The range of ``s`` keeping ``points + s * direction`` inside a rectangle.

    The general form of paper 003 eq. 9-10 (which spell out the case of a start in the lower
    left and a target in the upper right): clip each line ``L_i`` against the map.

    Parameters
    ----------
    bounds
        ``(xmin, ymin, xmax, ymax)``.
    points
        ``(n, 2)`` points inside the rectangle.
    direction
        ``(2,)`` unit vector.

    Returns
    -------
    ``(lo (n,), hi (n,))`` with ``lo <= 0 <= hi``.
    """
    b = np.asarray(bounds, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    lo = np.full(len(p), -np.inf)
    hi = np.full(len(p), np.inf)
    for ax in (0, 1):
        if abs(d[ax]) < 1e-15:
            continue
        a = (b[ax] - p[:, ax]) / d[ax]
        c = (b[ax + 2] - p[:, ax]) / d[ax]
        lo = np.maximum(lo, np.minimum(a, c))
        hi = np.minimum(hi, np.maximum(a, c))
    return lo, hi


class SegmentPathProblem(PathProblem):
    """Paper 003 sec. 4.1-4.2: the rotated frame and the feasible/infeasible fitness.

    The x' axis runs from start to target and is split into ``N = n_nodes + 1`` equal
    segments; node i sits on the line ``L_i`` perpendicular to x' through the i-th division
    point, at the offset ``y'_i`` (the variable), bounded so that it stays on the map
    (eq. 9-10, see :func:`line_bounds`). With ``frame="original"`` the variables are instead
    the nodes' ``(x, y)`` within the bounds (003's "PSO (ori)").

    Fitness, minimised (the paper maximises; transcription):

    * feasible path (no segment enters an obstacle): ``G = f1 + k f2`` with f1 the length
      (eq. 11) and f2 the sum of turning angles (the sum in eq. 12), mirroring eq. 13's
      ``1/f1 + k f2 + C``;
    * infeasible path: ``G = B (1 + f3 + f4) + w f1`` with ``f3 = N_inf / N`` (eq. 14) and
      ``f4 = sum d_obs / f1`` (eq. 15), mirroring eq. 16's ``1/(w f1) + 1/(f3 + f4)``; the
      offset ``B`` (N times the map diagonal, more than any feasible path's length) plays the
      reward C of eq. 13: every feasible path beats every infeasible one.

    ``k`` and ``w`` are not given in the paper; defaults ``k = 0`` (tables compare lengths)
    and ``w = 1``. Paper 003 regenerates a path whose node leaves the map; here the bounds
    are the box of the problem and the optimiser's bound handling applies.
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        n_nodes: int | None = None,
        frame: str = "rotated",
        k: float = 0.0,
        w: float = 1.0,
    ) -> None:
        n = int(scenario.nodes if n_nodes is None else n_nodes)
        if frame not in ("rotated", "original"):
            raise WeldplanError(f"frame must be 'rotated' or 'original', got {frame!r}")
        s, g = scenario.start, scenario.goal
        D = float(np.linalg.norm(g - s))
        if D == 0:
            raise WeldplanError("start and goal coincide")
        self.axis = (g - s) / D
        self.normal = np.array([-self.axis[1], self.axis[0]])
        self.base = s + np.outer(np.arange(1, n + 1) / (n + 1), g - s)  # (n, 2) on x'
        if frame == "rotated":
            lo, hi = line_bounds(scenario.bounds, self.base, self.normal)
        else:
            lo = np.tile(scenario.bounds[:2], n)
            hi = np.tile(scenario.bounds[2:], n)
        super().__init__(lo, hi, name=f"segments-{frame}:{scenario.name}")
        self.scenario = scenario
        self.world = scenario.world
        self.frame = frame
        self.n_nodes = n
        self.n_segments = n + 1
        self.k = float(k)
        self.w = float(w)
        b = scenario.bounds
        self.offset = self.n_segments * float(np.hypot(b[2] - b[0], b[3] - b[1]))

    @property
    def n_seed_nodes(self) -> int:
        return self.n_nodes

    def encode_nodes(
        self, nodes: FloatArray, path: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        """Rotated frame: node i's offset is where the roadmap first crosses ``L_i``, plus
        Gaussian noise of one roadmap cell (the arc-length nodes are not on the ``L_i``);
        original frame: the nodes themselves."""
        if self.frame != "rotated":
            return nodes.reshape(len(nodes), -1)
        s = self.scenario.start
        xp, yp = (path - s) @ self.axis, (path - s) @ self.normal
        c = (self.base - s) @ self.axis  # (n,) positions of the L_i on x'
        a, b = xp[None, :-1] - c[:, None], xp[None, 1:] - c[:, None]  # (n, p - 1)
        cross = (a * b <= 0.0) & (a != b)
        j = np.argmax(cross, axis=1)
        t = np.clip(
            -a[np.arange(len(c)), j] / np.where(cross.any(1), (b - a)[np.arange(len(c)), j], 1.0),
            0,
            1,
        )
        off = np.where(cross.any(1), yp[j] + t * (yp[j + 1] - yp[j]), 0.0)
        return off[None] + rng.normal(0.0, ROADMAP_CELL, (len(nodes), self.n_nodes))

    def decode(self, X: ArrayLike) -> FloatArray:
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        P = X.shape[0]
        out = np.empty((P, self.n_nodes + 2, 2))
        out[:, 0] = self.scenario.start
        out[:, -1] = self.scenario.goal
        if self.frame == "rotated":
            out[:, 1:-1] = self.base[None] + X[:, :, None] * self.normal
        else:
            out[:, 1:-1] = X.reshape(P, self.n_nodes, 2)
        return out

    def _evaluate(self, X: FloatArray) -> FloatArray:
        paths = self.decode(X)
        A, B = paths[:, :-1], paths[:, 1:]
        f1 = path_length(paths)
        hit, inside = self.world.segments_hit_length(A, B)  # (P, N) each
        n_inf = np.sum(hit, axis=1)
        feasible = f1 + self.k * smoothness(paths)
        f3 = n_inf / self.n_segments
        f4 = np.sum(np.where(hit, inside, 0.0), axis=1) / np.maximum(f1, 1e-12)
        infeasible = self.offset * (1.0 + f3 + f4) + self.w * f1
        return np.where(n_inf == 0, feasible, infeasible)


class GridPathProblem(PathProblem):
    """Paper 001's grid world: 8-connected moves between cells of an occupancy grid.

    Variables: ``n_waypoints`` cells ``(i, j)`` (rounded) between the start and goal cells.
    Consecutive waypoints are joined by the digital straight line between them (the cells
    ``rint(a + k (b - a) / n)``, ``k = 0..n``, ``n = max(|di|, |dj|)``), which is an 8-connected
    walk of exactly ``min(|di|, |dj|)`` diagonal and ``n - min`` straight moves, so a leg
    costs the octile distance and the path length is the sum over legs.

    Fitness: path length (cells) ``+ penalty x`` (blocked cells entered + diagonal moves that
    cut a blocked corner, counted over the whole walk). ``penalty`` defaults to the number of
    cells of the grid, more than any path is long. A collision-free decoded path is an
    8-connected grid path without corner cutting, so its length is at least the A* optimum
    (:func:`~weldplan.planar.exact.astar_grid`). (Paper 001 moves its fish cell by cell; the
    optimisers here see a continuous box, and this encoding is its grid path.)
    """

    def __init__(
        self, scenario: Scenario, *, n_waypoints: int = 4, penalty: float | None = None
    ) -> None:
        if scenario.grid is None:
            raise WeldplanError(f"scenario {scenario.name!r} has no occupancy grid")
        grid = scenario.grid
        occ = np.asarray(grid.occupied, dtype=bool)
        n_i, n_j = occ.shape
        m = int(n_waypoints)
        lo = np.full(2 * m, -0.5)
        hi = np.tile([n_i - 0.5, n_j - 0.5], m)
        super().__init__(lo, hi, name=f"grid:{scenario.name}")
        self.scenario = scenario
        self.world = scenario.world
        self.grid = grid
        self.occ = occ
        self.n_waypoints = m
        self.s_cell = grid.cell_of(scenario.start)
        self.g_cell = grid.cell_of(scenario.goal)
        self.penalty = float(occ.size if penalty is None else penalty)

    @property
    def n_seed_nodes(self) -> int:
        return self.n_waypoints

    def encode_nodes(
        self, nodes: FloatArray, path: FloatArray, rng: np.random.Generator
    ) -> FloatArray:
        """Cell coordinates (fractional) of the nodes."""
        ij = (nodes - np.asarray(self.grid.origin)) / self.grid.cell - 0.5
        return ij.reshape(len(nodes), -1)

    def waypoints(self, X: ArrayLike) -> NDArray[np.int64]:
        """Waypoint cells ``(P, m + 2, 2)``, start and goal included."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        P = X.shape[0]
        n_i, n_j = self.occ.shape
        W = np.empty((P, self.n_waypoints + 2, 2), dtype=np.int64)
        W[:, 0] = self.s_cell
        W[:, -1] = self.g_cell
        inner = np.rint(X.reshape(P, self.n_waypoints, 2)).astype(np.int64)
        inner[..., 0] = np.clip(inner[..., 0], 0, n_i - 1)
        inner[..., 1] = np.clip(inner[..., 1], 0, n_j - 1)
        W[:, 1:-1] = inner
        return W

    def _walk(self, W: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
        """Cells of every leg ``(P, legs, steps + 1, 2)`` and which steps are real moves."""
        d = W[:, 1:] - W[:, :-1]
        n = np.max(np.abs(d), axis=-1)  # (P, legs)
        nmax = max(int(n.max()), 1)
        k = np.arange(nmax + 1)
        frac = np.minimum(k / np.maximum(n, 1)[..., None], 1.0)  # (P, legs, nmax + 1)
        cells = np.rint(W[:, :-1, None, :] + frac[..., None] * d[:, :, None, :]).astype(np.int64)
        real = (k >= 1) & (k <= n[..., None])
        return cells, real

    def _evaluate(self, X: FloatArray) -> FloatArray:
        W = self.waypoints(X)
        d = np.abs(W[:, 1:] - W[:, :-1])
        length = np.sum(
            d[..., 0] + d[..., 1] + (math.sqrt(2.0) - 2.0) * np.minimum(d[..., 0], d[..., 1]),
            axis=1,
        )
        cells, real = self._walk(W)
        occ = self.occ
        blocked = occ[cells[..., 0], cells[..., 1]] & real
        prev = np.concatenate([cells[..., :1, :], cells[..., :-1, :]], axis=-2)
        diag = real & np.all(cells != prev, axis=-1)
        cut = diag & (occ[prev[..., 0], cells[..., 1]] | occ[cells[..., 0], prev[..., 1]])
        bad = np.sum(blocked, axis=(1, 2)) + np.sum(cut, axis=(1, 2))
        return length + self.penalty * bad

    def cells(self, x: ArrayLike) -> NDArray[np.int64]:
        """The cells ``(n, 2)`` of one solution's walk from the start cell to the goal cell."""
        W = self.waypoints(np.asarray(x, dtype=np.float64).reshape(1, -1))
        cells, real = self._walk(W)
        walk = [W[0, 0]] + [
            c for c, r in zip(cells[0].reshape(-1, 2), real[0].reshape(-1), strict=True) if r
        ]
        return np.array(walk, dtype=np.int64)

    def decode(self, X: ArrayLike) -> FloatArray:
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        paths = [self.grid.centre(self.cells(x)) for x in X]
        n = max(len(p) for p in paths)
        # pad with the goal so that the population stacks (zero-length segments are free)
        return np.stack([np.concatenate([p, np.repeat(p[-1:], n - len(p), 0)]) for p in paths])

    def path(self, x: ArrayLike) -> FloatArray:
        return self.grid.centre(self.cells(x))

    def success(self, X: ArrayLike) -> NDArray[np.bool_]:
        """Collision-free on the grid: no blocked cell, no corner cut."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        return self._evaluate(X) < self.penalty


def population_diversity(X: ArrayLike) -> float:
    """Paper 003 eq. 18: ``DI = (1/NP) sqrt(sum_i ||X_i - mean(X)||^2)`` of ``X (NP, n_var)``."""
    X = np.atleast_2d(np.asarray(X, dtype=np.float64))
    return float(np.sqrt(np.sum((X - X.mean(axis=0)) ** 2)) / X.shape[0])


ENCODERS = {
    "spline": SplinePathProblem,
    "segments": SegmentPathProblem,
    "grid": GridPathProblem,
}


def make_problem(scenario: Scenario, encoding: str | None = None, **params: object) -> PathProblem:
    """The Problem of ``encoding`` (default: the scenario's own) on ``scenario``."""
    enc = encoding or scenario.encoding
    if enc not in ENCODERS:
        raise WeldplanError(f"unknown encoding {enc!r}; choose one of: {', '.join(ENCODERS)}")
    return ENCODERS[enc](scenario, **params)  # type: ignore[arg-type]
