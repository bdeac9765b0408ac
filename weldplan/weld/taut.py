"""Joint vertex optimisation of a refined path: all vertices at once, the shortest polyline
through them whose segments keep the clearance (issue 15 item 1, "local optimisation of the
vertices toward the clearance surface").

The vertex sweeps of :func:`weldplan.weld.refine.tighten_path` move one vertex at a time toward
its chord; on a rounded or curved surface a vertex held by the clearance on both of its segments
cannot move in any of those directions although the path is not taut (it should slide *along*
the surface), so such paths stay longer than OMPL BIT* 10 s finds in the same homotopy class
(docs/bench-local-peers.md). :func:`tauten_path` moves every vertex together, by
sequential linearised programs (the trust-region scheme of sequential convex planners such as
TrajOpt, Schulman et al., IJRR 2014, section IV; here with exact separating planes instead of
signed-distance gradients):

1. **Contacts.** Every segment is sampled every ``SAMPLE_STEP * radius``; each sample within
   ``radius * (1 + CONTACT_BAND)`` of the obstacle gives its closest surface point ``c``, moved
   once more to the surface point closest to the point of the segment nearest ``c`` (so ``c``
   is the closest approach, not a sample's).
2. **Separating planes.** For a contact ``c`` of segment ``k`` (ends ``v_k``, ``v_k+1``) and the
   point ``p`` of the segment nearest ``c``, ``n = (p - c) / |p - c|``: the constraint
   ``n . (v - c) >= radius + margin`` on both ends keeps the whole segment (convex) in the
   half-space, so ``c`` stays at least that far from it. The current path satisfies every
   plane (``p`` is the segment's closest point to ``c``), so each round starts feasible.
3. **One program a round.** Minimise the length ``sum |v_k+1 - v_k|`` over the interior
   vertices, subject to the planes and a box trust region of half-width ``delta`` around the
   current vertices: a second-order cone program (one cone ``|v_k+1 - v_k| <= t_k`` a segment,
   minimise ``sum t_k``), convex, solved to optimality by Clarabel (interior point; its own
   sparse factorisation, no BLAS threads to fight over on a loaded machine).
4. **The judge.** Every segment the round changed is checked with ``free`` (the refinement's
   check, at the clearance + margin). Pass: the round is taken and ``delta`` doubles (up to
   :data:`TRUST_MAX` radii), and the contacts are sampled again on the new path. Fail: the
   failing segments are sampled densely for more contacts, kept for every later round, and
   ``delta`` is quartered. Stop when a round gains less than ``tol`` of the length, ``delta``
   falls under :data:`TRUST_MIN` radii, after ``max_rounds`` rounds or at the deadline.

Before the rounds, every segment that passes within the contact band is split into pieces no
longer than ``SPACING * radius``, so the polyline can follow a rounded edge; straight runs are
dropped afterwards. The result is never longer than the input and every segment of it that
differs from the input's passed ``free``; :func:`weldplan.weld.refine.refine_path` still re-checks
the whole path at the clearance with python-fcl before anything leaves it.

Deviation from TrajOpt, named: the constraints are exact separating planes through the contact
points (a sufficient condition per contact), not the linearised signed distance, and there is no
penalty method (every iterate is feasible for the planes, so no merit function is needed).

Measured (docs/bench-local-peers.md): on the 32 blocked pairs of ``weldplan bench local --peers``
the refinement with this stage ends at 0.995 x the length of OMPL BIT* 10 s + simplify on average
(the sweeps: 1.006), 0.03 % over the exact optimum around a 100 mm cube (the sweeps, three
levels: 0.13 %), in 4 rounds (median) of a few milliseconds each. scipy's SLSQP on the same
programs took 0.3-0.7 s a round (about 185 quasi-Newton iterations on the non-smooth length).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

import clarabel
import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from weldplan.geometry.pathcore import polyline_length

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
SegmentsCheck = Callable[[FloatArray, FloatArray], NDArray[np.bool_]]

__all__ = ["CONTACT_BAND", "SPACING", "closest_points", "tauten_path"]

#: split segments near the obstacle into pieces no longer than this many radii
SPACING = 1.0
#: sample spacing along a segment when looking for contacts, in radii
SAMPLE_STEP = 0.25
#: a sample within ``radius * (1 + CONTACT_BAND)`` of the obstacle gives a contact
CONTACT_BAND = 1.0
#: extra clearance of the planes beyond the check's radius, in radii: room for the surface
#: between contacts (a sharp edge crossed between two contacts comes closer than both)
PLANE_EXTRA = 0.002
#: first, largest and smallest trust-region half-width, in radii
TRUST0, TRUST_MAX, TRUST_MIN = 0.5, 2.0, 1e-3
#: rounds of linearised programs (a guard; the gain falls under ``tol`` first)
MAX_ROUNDS = 30
#: Clarabel's gap and feasibility tolerances (its default; 1e-6 measured no faster on the
#: bench's pairs and left vertices off their chords that 1e-8 puts on them, to be dropped)
SOLVER_TOL = 1e-8
#: contacts are merged when they agree to this fraction of the radius (on the same segment)
_MERGE = 0.05
#: finite-difference step of the distance gradient for obstacles without ``closest_points``,
#: as a fraction of the largest distance queried (at least 1 unit)
_FD_STEP = 1e-3


def closest_points(obstacle: object, X: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(C (m, d), D (m,))``: the obstacle surface point closest to each point of ``X (m, d)``
    and its distance. Uses ``obstacle.closest_points`` when it has one (the 3D part: open3d);
    otherwise ``c = x - d(x) grad d(x)`` with a central-difference gradient of
    ``obstacle.distance`` (2D maps)."""
    f = getattr(obstacle, "closest_points", None)
    if f is not None:
        C = np.asarray(f(X), dtype=np.float64)
        return C, np.linalg.norm(X - C, axis=1)
    dist = obstacle.distance  # type: ignore[attr-defined]
    m, d = X.shape
    D = np.asarray(dist(X), dtype=np.float64)
    h = _FD_STEP * max(1.0, float(np.abs(D).max(initial=1.0)))
    E = np.eye(d) * h
    plus = np.asarray(dist((X[:, None, :] + E[None]).reshape(-1, d))).reshape(m, d)
    minus = np.asarray(dist((X[:, None, :] - E[None]).reshape(-1, d))).reshape(m, d)
    G = (plus - minus) / (2 * h)
    G /= np.maximum(np.linalg.norm(G, axis=1, keepdims=True), 1e-12)
    return X - D[:, None] * G, np.abs(D)


def _nearest_on_segments(V: FloatArray, K: NDArray, C: FloatArray) -> FloatArray:
    """``(m, d)``: the point of segment ``V[K] -> V[K + 1]`` nearest each ``C``."""
    a, ab = V[K], V[K + 1] - V[K]
    L2 = np.einsum("ij,ij->i", ab, ab)
    t = np.divide(np.einsum("ij,ij->i", C - a, ab), L2, out=np.zeros(len(K)), where=L2 > 0)
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def _contacts(
    V: FloatArray, obstacle: object, radius: float, step: float, segs: NDArray | None = None
) -> tuple[NDArray, FloatArray]:
    """Contacts ``(K (m,), C (m, d))`` of the segments ``segs`` (default all) of ``V``: samples
    every ``step`` within the band, each moved to the closest approach (module docstring)."""
    segs = np.arange(len(V) - 1) if segs is None else np.asarray(segs)
    if len(segs) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, V.shape[1]))
    L = np.linalg.norm(V[segs + 1] - V[segs], axis=1)
    cnt = np.maximum(2, np.ceil(L / step).astype(np.int64) + 1)
    K = np.repeat(segs, cnt)
    start = np.repeat(np.cumsum(cnt) - cnt, cnt)
    t = (np.arange(len(K)) - start) / np.repeat(cnt - 1, cnt)
    X = V[K] + t[:, None] * (V[K + 1] - V[K])
    C, D = closest_points(obstacle, X)
    near = D < radius * (1.0 + CONTACT_BAND)
    K, C = K[near], C[near]
    if len(K):
        C, _ = closest_points(obstacle, _nearest_on_segments(V, K, C))
    return K, C


def _merge(K: NDArray, C: FloatArray, K2: NDArray, C2: FloatArray, radius: float):
    """The union of two contact sets, one contact per segment and cell of ``_MERGE * radius``."""
    K = np.concatenate([K, K2])
    C = np.concatenate([C, C2])
    key = np.column_stack([K, np.floor(C / (_MERGE * radius)).astype(np.int64)])
    _, first = np.unique(key, axis=0, return_index=True)
    first = np.sort(first)
    return K[first], C[first]


def _densify(V: FloatArray, obstacle: object, radius: float) -> FloatArray:
    """Split every segment with a contact into pieces of at most ``SPACING * radius``."""
    K, _ = _contacts(V, obstacle, radius, SAMPLE_STEP * radius)
    near = np.zeros(len(V) - 1, dtype=bool)
    near[K] = True
    out = [V[:1]]
    for k in range(len(V) - 1):
        a, b = V[k], V[k + 1]
        n = int(np.ceil(np.linalg.norm(b - a) / (SPACING * radius))) if near[k] else 1
        if n > 1:
            t = np.arange(1, n)[:, None] / n
            out.append(a + t * (b - a))
        out.append(b[None])
    return np.concatenate(out)


def _planes(V: FloatArray, K: NDArray, C: FloatArray, level: float, delta: float):
    """The separating planes as ``G x >= h`` over the interior vertices ``x``: ``G`` as sparse
    triplets ``(rows, cols, vals)``, and ``h``. A plane farther than ``sqrt(d) delta`` from
    both ends of its segment cannot bind inside the trust region and is left out."""
    m, d = len(V) - 2, V.shape[1]
    P = _nearest_on_segments(V, K, C)
    N = P - C
    nn = np.linalg.norm(N, axis=1)
    ok = (nn > 1e-9) & (nn - level < np.sqrt(d) * delta * 1.01)
    K, C, N = K[ok], C[ok], N[ok] / nn[ok, None]
    rows, cols, vals, hs = [], [], [], []
    r0 = 0
    for end in (K, K + 1):
        mv = np.flatnonzero((end >= 1) & (end <= m))
        rows.append(np.repeat(r0 + np.arange(len(mv)), d))
        cols.append(((end[mv] - 1)[:, None] * d + np.arange(d)).ravel())
        vals.append(N[mv].ravel())
        hs.append(np.einsum("ij,ij->i", N[mv], C[mv]) + level)
        r0 += len(mv)
    return (np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)), np.concatenate(hs)


def _cone_program(V: FloatArray, G: tuple, h: FloatArray, delta: float):
    """``(A, b, cones)`` of the program of :func:`_solve` in Clarabel's form ``A z + s = b``,
    ``s`` in the cones, over ``z = (x, t)``: the planes, the trust region, then one second-order
    cone ``(t_k, v_k+1 - v_k)`` a segment."""
    n, d = V.shape
    m, ns, nh = (n - 2) * d, n - 1, len(h)
    x0 = V[1:-1].ravel()
    gr, gc, gv = G
    ar = np.arange(m)
    # v_k+1 - v_k: +x at vertex k+1 (interior when k + 1 <= n - 2), -x at vertex k (when k >= 1)
    k, j = np.divmod(np.arange(ns * d), d)
    soc0 = nh + 2 * m  # first cone row
    row_of = soc0 + k * (d + 1) + 1 + j
    up = k + 1 <= n - 2
    lo = k >= 1
    rows = [gr, nh + ar, nh + m + ar, soc0 + np.arange(ns) * (d + 1), row_of[up], row_of[lo]]
    cols = [gc, ar, ar, m + np.arange(ns), k[up] * d + j[up], (k[lo] - 1) * d + j[lo]]
    vals = [-gv, np.ones(m), -np.ones(m), -np.ones(ns), -np.ones(int(up.sum())),
            np.ones(int(lo.sum()))]  # fmt: skip
    A = sparse.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(soc0 + ns * (d + 1), m + ns),
    )
    const = np.zeros((ns, d + 1))
    const[0, 1:] -= V[0]
    const[-1, 1:] += V[-1]
    b = np.concatenate([-h, x0 + delta, delta - x0, const.ravel()])
    cones = [clarabel.NonnegativeConeT(nh + 2 * m)] + [clarabel.SecondOrderConeT(d + 1)] * ns
    return A, b, cones


def _solve(V: FloatArray, G: tuple, h: FloatArray, delta: float) -> FloatArray | None:
    """One linearised program (module docstring, step 3) as a second-order cone program:
    minimise ``sum t_k`` subject to ``|v_k+1 - v_k| <= t_k``, the planes ``G x >= h`` and the
    trust region, solved to optimality by Clarabel (an interior-point conic solver; its own
    sparse factorisation, no BLAS threads). ``None`` when it does not solve."""
    n, d = V.shape
    m, ns = (n - 2) * d, n - 1
    A, b, cones = _cone_program(V, G, h, delta)
    q = np.concatenate([np.zeros(m), np.ones(ns)])
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_threads = 1
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = SOLVER_TOL
    solver = clarabel.DefaultSolver(sparse.csc_matrix((m + ns, m + ns)), q, A, b, cones, settings)
    sol = solver.solve()
    if str(sol.status) not in ("Solved", "AlmostSolved"):
        log.debug("tauten_path: cone program %s", sol.status)
        return None
    W = V.copy()
    W[1:-1] = np.asarray(sol.x[:m]).reshape(-1, d)
    return W


def tauten_path(
    points: FloatArray,
    obstacle: object,
    radius: float,
    free: SegmentsCheck,
    *,
    margin: float = 0.0,
    max_rounds: int = MAX_ROUNDS,
    tol: float = 1e-4,
    time_budget: float | None = None,
) -> tuple[FloatArray, int]:
    """The joint vertex optimisation (module docstring).

    Parameters
    ----------
    points
        ``(n, d) float`` a path whose segments pass ``free`` (mm in 3D).
    obstacle
        A :class:`~weldplan.geometry.pathcore.PathObstacle` (``distance``; ``closest_points``
        when it has one).
    radius
        The clearance (mm).
    free
        ``free(A (m, d), B (m, d)) -> (m,) bool``: the judge of every changed segment (the
        refinement passes its check at ``radius + margin``).
    margin
        The check's margin over ``radius``; the planes keep ``radius + margin +
        PLANE_EXTRA * radius``.
    max_rounds, tol, time_budget
        Guards: rounds, the gain (a fraction of the length) under which a round ends the loop,
        seconds after which no round starts. The clock starts after the first contact query,
        so that the one-time set-up of the obstacle's distance queries (open3d builds its
        scene on first use: seconds on a car body) is not charged to the first pair.

    Returns
    -------
    (points, rounds)
        The path (never longer than the input; the same end points) and the rounds run.
    """
    V = np.asarray(points, dtype=np.float64)
    if len(V) < 3:
        return V.copy(), 0
    level = radius + margin + PLANE_EXTRA * radius
    V = _densify(V, obstacle, radius)
    K, C = _contacts(V, obstacle, radius, SAMPLE_STEP * radius)
    deadline = None if time_budget is None else time.thread_time() + time_budget  # CPU s
    # contacts found where a round's path failed the check: kept for every later round
    Ks, Cs = np.zeros(0, dtype=np.int64), np.zeros((0, V.shape[1]))
    delta, L = TRUST0 * radius, polyline_length(V)
    rounds = 0
    while rounds < max_rounds and delta >= TRUST_MIN * radius:
        if deadline is not None and time.thread_time() >= deadline:
            break
        rounds += 1
        G, h = _planes(V, *_merge(K, C, Ks, Cs, radius), level, delta)
        W = _solve(V, G, h, delta)
        if W is None:
            break
        Lw = polyline_length(W)
        if not Lw < L:
            break
        moved = np.flatnonzero(np.any(W[1:] != V[1:], axis=1) | np.any(W[:-1] != V[:-1], axis=1))
        ok = free(W[moved], W[moved + 1])
        log.debug(
            "round %d: %d planes, delta %.3g, gain %.4g, %d of %d changed segments free",
            rounds, len(h), delta, L - Lw, int(ok.sum()), len(ok),
        )  # fmt: skip
        if ok.all():
            V, L, gain = W, Lw, L - Lw
            if gain <= tol * L:
                break
            delta = min(2.0 * delta, TRUST_MAX * radius)
            K, C = _contacts(V, obstacle, radius, SAMPLE_STEP * radius)
        else:
            bad = moved[~ok]
            Ks, Cs = _merge(Ks, Cs, *_contacts(W, obstacle, radius, 0.1 * radius, bad), radius)
            delta *= 0.25
    log.debug("tauten_path: %d rounds, %.4f -> %.4f", rounds, polyline_length(points), L)
    return V, rounds
