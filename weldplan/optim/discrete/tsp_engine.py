"""fast-tsp (MIT, Rust Lin-Kernighan-style local search) wrapped for weld sequencing.

``fast_tsp.find_tour`` solves the *symmetric* closed TSP over a matrix of integers in
``0 .. 65535`` (uint16), within a wall-clock budget. Weld sequencing needs more, and this module
adds it around the solver, each step a standard reduction:

* **every variant as one closed tour**: open paths, fixed first / last nodes and closed tours
  arrive here already reduced to a closed tour over ``A`` through the start node
  (:func:`weldplan.optim.discrete.costs.reduce_to_tour`: the dummy-node reduction of an open path).
* **asymmetric costs**: a reduced ``A`` that is not symmetric (asymmetric input, a single fixed
  end of an open path, both ends of a closed tour) goes through the 2n-node transform of
  Jonker and Volgenant (1983): node ``i`` becomes ``i_in`` and ``i_out``, joined at cost 0;
  ``i_out - j_in`` costs ``A[i, j] + M``; ``in - in`` and ``out - out`` pairs are forbidden.
  Deviation: Jonker and Volgenant's ``M`` is large enough to *prove* that an optimal tour
  alternates twins; with uint16 costs it cannot be (``M`` is one more than the largest scaled
  cost), so the returned tour is *checked*: a tour that does not alternate is reported
  (``feasible=False``), never silently read.
* **float costs**: ``c`` is scaled by ``s`` and rounded, ``round(s c)``. Each edge is off by at
  most ``0.5 / s`` (mm), so any order of ``k`` edges has ``|L_float - L_int / s| <= k / (2 s)``
  (:attr:`EngineResult.rounding_bound`); against the best order under the float costs the
  rounding can cost at most twice that (:attr:`EngineResult.optimality_loss_bound`). Integral
  costs are passed unscaled (``s = 1``, bound 0: TSPLIB's ``nint`` distances as they are)
  whenever the clipping rule below fits under the top finite integer: never scaled by a
  non-integer factor, which would reorder tours one unit apart. To spend the 16 bits where
  tours live, costs above ``cap`` (by default a few times each node's ``CAP_NEIGHBOUR``-th
  nearest cost; :data:`FINITE_MAX` for integral costs) are clipped to the top finite integer;
  the bounds above hold for every order that uses no clipped edge (clipping only lowers a
  cost), and the caller re-solves without clipping when the returned order uses one
  (:func:`solve_fast_tsp` does).
* **unplannable pairs**: ``inf`` becomes the largest integer (a large finite penalty); the
  returned order is checked and ``penalty_edges`` counts the ``inf`` edges it uses (the caller
  raises or repairs).
* **avoided pairs**: an optional mask of edges priced ``AVOID_BASE`` above their own scaled
  cost, so above every edge not avoided and below the penalty ("use only where the other edges
  connect badly"; the pipeline's legs not planned yet). Not above every *tour*: a detour of many
  edges may cost more than one avoided edge, and the caller learns it from ``avoided_edges``.

The budget is wall time for the whole call: the conversion and checks above come out of it
(about 0.15 CPU s at 2,152 nodes, fast-tsp's set-up included) and fast-tsp searches for the
rest, with one thread on each available core (:func:`search_threads`; fast-tsp's own default is
one thread). The returned lengths are always recomputed in floats over the caller's matrix,
never read back from the integers. fast-tsp has no seed and cannot be given one: its Rust core
draws its perturbations from ``fastrand``'s process-wide generator, seeded from fresh entropy in
each process, so even with ``stop_when_converged`` and ``duration_seconds=inf`` (no clock) and
one thread, two runs may return different tours (a280: three runs, three different optimal
tours); with this wrapper's wall-clock budget the length varies too (lin318 at the optimum in
one run, 0.27 % above it in another). It solves up to 20 nodes exactly, in
milliseconds. The sequencer's default is therefore not this engine
(:mod:`weldplan.optim.discrete.sequence`).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)

#: fast-tsp's integer range (uint16)
INT_MAX = 2**16 - 1
#: scaled finite costs lie in ``0 .. FINITE_MAX`` (room above for avoided edges and penalties)
FINITE_MAX = 2**14 - 1
#: the ATSP transform's constant ``M`` (one above every scaled finite cost)
ATSP_M = FINITE_MAX + 1
#: avoided edges cost ``AVOID_BASE + round(s c)``: above every other finite cost (not above
#: every tour), ordered among themselves, below the penalty
AVOID_BASE = 2**15
#: infinite (unplannable) edges and forbidden pairs of the ATSP transform
PENALTY_INT = INT_MAX
#: default clipping: ``cap = CAP_FACTOR x`` the largest ``CAP_NEIGHBOUR``-th nearest cost of a node
CAP_NEIGHBOUR = 10
CAP_FACTOR = 4.0
#: fast-tsp searches at least this long (s), even when the conversion used up the budget
MIN_SEARCH_SECONDS = 0.01
#: a re-solve without clipping gets at least this fraction of the budget
RESOLVE_FRACTION = 0.25


def default_seconds(m: int) -> float:
    """Default budget (s) for ``m`` tour nodes: 1 ms a node, between 0.05 s and 10 s (fast-tsp
    reaches TSPLIB optima up to ~1,000 nodes in about a second on this kind of machine)."""
    return float(np.clip(1e-3 * m, 0.05, 10.0))


@dataclass(frozen=True)
class EngineResult:
    """A closed tour over the reduced matrix and what the integer model cost it.

    Attributes
    ----------
    tour
        ``(m,) int``: closed tour over ``A`` starting at ``start`` (orientation read from ``A``).
    cost
        Its cost recomputed in floats over ``A`` (``inf`` if it uses an ``inf`` edge).
    scale
        ``s``: integers are ``round(s c)`` (1/mm in the weld pipeline).
    cap
        Costs above it were clipped to :data:`FINITE_MAX`; ``inf`` when nothing was clipped.
    rounding_bound
        ``m / (2 s)``: bound on ``|cost - integer cost / s|`` for this order (0 when exact),
        valid as ``clipped_edges == avoided_edges == penalty_edges == 0``.
    clipped_edges, avoided_edges, penalty_edges
        Edges of the tour that were clipped, avoided, or ``inf`` (each a flag for the caller).
    feasible
        False when the ATSP transform's tour did not alternate twins (no order could be read).
    transform
        ``"symmetric"`` or ``"atsp-2n"``.
    seconds
        Wall time, conversion included.
    """

    tour: NDArray[np.intp]
    cost: float
    scale: float
    cap: float
    rounding_bound: float
    clipped_edges: int
    avoided_edges: int
    penalty_edges: int
    feasible: bool
    transform: str
    seconds: float

    @property
    def optimality_loss_bound(self) -> float:
        """How much longer than the float-cost optimum the integer-optimal order can be."""
        return 2.0 * self.rounding_bound


def _import_fast_tsp():
    try:
        import fast_tsp
    except ImportError as exc:  # pragma: no cover - a runtime dependency
        raise WeldplanError(
            "the fast-tsp sequencer needs the 'fast-tsp' package (pip install fast-tsp)"
        ) from exc
    return fast_tsp


def choose_scale(
    A: NDArray[np.float64],
    usable: NDArray[np.bool_],
    cap: float | None,
    *,
    integral: bool | None = None,
) -> tuple[float, float]:
    """``(scale, cap)`` for the finite, usable entries of ``A``.

    Integral costs keep ``scale = 1`` (exact) whenever they can: unclipped when every usable
    cost fits in :data:`FINITE_MAX`, else clipped at :data:`FINITE_MAX` when the default cap
    (below) fits under it (TSPLIB's u1060: costs up to 20,262, tours' edges far below; scaling
    such costs by a non-integer factor would perturb the order of tours one unit apart).
    Otherwise ``cap`` (None: ``CAP_FACTOR`` times the largest ``CAP_NEIGHBOUR``-th nearest usable
    cost of any node, at most the largest usable cost) maps to :data:`FINITE_MAX`.

    Parameters
    ----------
    A
        ``(m, m) float`` costs.
    usable
        ``(m, m) bool``: the finite entries that set the scale.
    cap
        Clip above this cost; None: the rule above.
    integral
        Whether the usable costs are integers (None: checked here).
    """
    if not usable.any():
        return 1.0, np.inf
    top = float(np.max(A, where=usable, initial=-np.inf))
    if integral is None:
        integral = bool(np.all((A == np.rint(A)) | ~usable))
    if cap is None and integral and top <= FINITE_MAX:
        return 1.0, np.inf
    if cap is None:
        cap = _default_cap(A, usable, top)
        if integral and cap <= FINITE_MAX:
            return 1.0, float(FINITE_MAX)
    cap = min(float(cap), top)
    if cap <= 0:
        return 1.0, np.inf
    return FINITE_MAX / cap, (cap if cap < top else np.inf)


def _default_cap(A: NDArray[np.float64], usable: NDArray[np.bool_], top: float) -> float:
    """``CAP_FACTOR`` x the largest ``CAP_NEIGHBOUR``-th nearest usable cost of any node."""
    m = A.shape[0]
    k = min(CAP_NEIGHBOUR, m - 1)
    if k < 1:
        return top
    R = np.where(usable, A, np.inf)
    np.fill_diagonal(R, np.inf)
    kth = np.partition(R, k - 1, axis=1)[:, k - 1]
    kth = kth[np.isfinite(kth)]
    return CAP_FACTOR * float(kth.max()) if len(kth) else top


def _integers(
    A: NDArray[np.float64], avoid: NDArray[np.bool_] | None, cap: float | None
) -> tuple[NDArray[np.uint16], float, float, bool]:
    """``(I, s, cap, exact)``: fast-tsp's ``uint16`` matrix, the scale, the cap (``inf``: no
    clipping) and whether ``I`` is exact (``s = 1`` over integral costs) below the cap."""
    finite = np.isfinite(A)
    all_finite = bool(finite.all())
    off = ~np.eye(A.shape[0], dtype=bool)
    usable = finite if avoid is None else finite & ~avoid
    scaling = usable & off
    if not (scaling & (A > 0)).any():  # nothing but avoided (or zero) edges: scale by those
        scaling = finite & off
    integral = bool(np.all((A == np.rint(A)) | ~finite))
    s, cap_used = choose_scale(A, scaling, cap, integral=integral)
    X = A.copy() if all_finite else np.where(finite, A, 0.0)
    if s != 1.0:
        X *= s
    np.rint(X, out=X)
    np.minimum(X, FINITE_MAX, out=X)
    I = X.astype(np.uint16)
    if not all_finite:
        I[~finite] = PENALTY_INT
    if avoid is not None:
        I[finite & avoid] += AVOID_BASE
    np.fill_diagonal(I, 0)
    return I, s, cap_used, s == 1.0 and integral


def _edge_flags(
    A: NDArray[np.float64], avoid: NDArray[np.bool_] | None, cap: float, a, b
) -> tuple[int, int, int]:
    c = A[a, b]
    pen = ~np.isfinite(c)
    av = np.zeros_like(pen) if avoid is None else avoid[a, b] & ~pen
    clip = (c > cap) & ~pen & ~av
    return int(clip.sum()), int(av.sum()), int(pen.sum())


def search_threads(threads: int | None = None) -> int:
    """fast-tsp's thread count: ``threads``, or every core this process may run on (None).

    fast-tsp's own default is one thread (and its ``None`` one fewer than the cores): on the
    2-core machines this project measures on, that leaves half of the CPU idle
    (docs/bench-sequence.md).
    """
    if threads is not None:
        if threads < 1:
            raise ValueError(f"threads must be >= 1, got {threads}")
        return int(threads)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def fast_tsp_tour(
    A: NDArray[np.float64],
    start: int,
    *,
    seconds: float | None = None,
    avoid: NDArray[np.bool_] | None = None,
    cap: float | None = None,
    threads: int | None = None,
) -> EngineResult:
    """Closed tour over ``A (m, m)`` through ``start`` by fast-tsp (module docstring).

    Parameters
    ----------
    A
        ``(m, m) float``, non-negative, ``inf`` for unreachable pairs; may be asymmetric
        (``A[i, j]``: from ``i`` to ``j``).
    start
        The tour is returned rotated to start here, in the orientation that ``A`` prices
        (for symmetric ``A``: the cheaper of the two).
    seconds
        Wall-clock budget of the whole call, the integer conversion included: fast-tsp searches
        for what is left of it (at least :data:`MIN_SEARCH_SECONDS`; it uses all of it above 20
        nodes). Default :func:`default_seconds` of the solver's node count.
    avoid
        ``(m, m) bool``: edges to use only where no tour avoids them.
    cap
        Clip costs above it (module docstring); None: the default rule.
    threads
        fast-tsp's search threads (:func:`search_threads`; None: every available core).
    """
    t0 = time.perf_counter()
    fast_tsp = _import_fast_tsp()
    A = np.asarray(A, dtype=np.float64)
    m = A.shape[0]
    if m <= 3:
        tour = np.arange(m, dtype=np.intp)
        tour = np.roll(tour, -start)
        return _result(A, tour, avoid, 1.0, np.inf, True, True, "symmetric", t0)
    I, s, cap_used, exact = _integers(A, avoid, cap)
    symmetric = bool(np.array_equal(I, I.T))
    n_solver = m if symmetric else 2 * m
    budget = default_seconds(n_solver) if seconds is None else float(seconds)
    feasible = True

    def search(M: NDArray) -> NDArray[np.intp]:
        left = max(MIN_SEARCH_SECONDS, budget - (time.perf_counter() - t0))
        return np.asarray(
            fast_tsp.find_tour(M, left, max_threads=search_threads(threads)), dtype=np.intp
        )

    if symmetric:
        t = search(I)
        t = np.roll(t, -int(np.flatnonzero(t == start)[0]))
        rev = np.concatenate([t[:1], t[1:][::-1]])
        if _cost(A, rev, avoid) < _cost(A, t, avoid):
            t = rev
        transform = "symmetric"
    else:
        t, feasible = _read_atsp(search(_atsp_matrix(I)), m, start)
        transform = "atsp-2n"
    return _result(A, t, avoid, s, cap_used, exact, feasible, transform, t0)


def _atsp_matrix(I: NDArray[np.uint16]) -> NDArray[np.uint16]:
    """Jonker and Volgenant's symmetric ``(2m, 2m)`` matrix of the asymmetric ``I (m, m)``."""
    m = I.shape[0]
    S = np.full((2 * m, 2 * m), PENALTY_INT, dtype=np.uint16)
    ii = np.arange(m)
    S[ii, ii + m] = S[ii + m, ii] = 0
    I32 = I.astype(np.int32)
    cross = np.where(I32 < PENALTY_INT, I32 + ATSP_M, PENALTY_INT)
    cross = np.minimum(cross, PENALTY_INT).astype(np.uint16)
    S[m:, :m] = cross  # out_i -> in_j costs A[i, j]
    S[:m, m:] = cross.T
    np.fill_diagonal(S[m:, :m], 0)
    np.fill_diagonal(S[:m, m:], 0)
    np.fill_diagonal(S, 0)
    return S


def _read_atsp(t2: NDArray[np.intp], m: int, start: int) -> tuple[NDArray[np.intp], bool]:
    """The ATSP order from a 2m-node tour: it must alternate ``i_in, i_out``; else infeasible."""
    k = int(np.flatnonzero(t2 == start)[0])
    t2 = np.roll(t2, -k)
    if t2[1] != start + m:  # walk the other way round: in, out pairs
        t2 = np.concatenate([t2[:1], t2[1:][::-1]])
    ins, outs = t2[0::2], t2[1::2]
    ok = bool(np.all(ins < m) and np.array_equal(outs, ins + m))
    if not ok:
        log.warning("fast-tsp: the ATSP transform's tour does not alternate twins")
        return np.arange(m, dtype=np.intp), False
    return ins.astype(np.intp), True


def _cost(A: NDArray[np.float64], t: NDArray[np.intp], avoid) -> tuple[int, float]:
    a, b = t, np.roll(t, -1)
    c = A[a, b]
    bad = int((~np.isfinite(c)).sum()) + (0 if avoid is None else int(avoid[a, b].sum()))
    return bad, float(np.where(np.isfinite(c), c, 0.0).sum())


def _result(A, t, avoid, s, cap, exact, feasible, transform, t0) -> EngineResult:
    a, b = t, np.roll(t, -1)
    clip, av, pen = _edge_flags(A, avoid, cap, a, b)
    cost = float(A[a, b].sum()) if len(t) > 1 else 0.0
    return EngineResult(
        tour=t.astype(np.intp),
        cost=cost,
        scale=float(s),
        cap=float(cap),
        rounding_bound=0.0 if exact or len(t) <= 3 else len(t) / (2 * s),
        clipped_edges=clip,
        avoided_edges=av,
        penalty_edges=pen,
        feasible=feasible,
        transform=transform,
        seconds=time.perf_counter() - t0,
    )


def solve_fast_tsp(
    A: NDArray[np.float64],
    start: int,
    *,
    seconds: float | None = None,
    avoid: NDArray[np.bool_] | None = None,
    threads: int | None = None,
) -> EngineResult:
    """:func:`fast_tsp_tour` with the default clipping, re-solved once without clipping when
    the returned tour uses a clipped edge (so the rounding bound holds for the returned order).

    ``seconds`` is the budget of the whole call (None: :func:`default_seconds`); the re-solve
    gets what is left of it but at least ``RESOLVE_FRACTION`` of it, so in that (rare) case the
    call may take up to ``1 + RESOLVE_FRACTION`` times the budget; ``seconds`` of the result
    counts both solves.
    """
    t0 = time.perf_counter()
    res = fast_tsp_tour(A, start, seconds=seconds, avoid=avoid, threads=threads)
    if res.clipped_edges:
        log.info("fast-tsp: %d clipped edges used; re-solving unclipped", res.clipped_edges)
        finite = np.isfinite(A) if avoid is None else np.isfinite(A) & ~avoid
        top = float(A[finite].max()) if finite.any() else 1.0
        budget = default_seconds(A.shape[0]) if seconds is None else float(seconds)
        left = max(RESOLVE_FRACTION * budget, budget - (time.perf_counter() - t0))
        res = fast_tsp_tour(A, start, seconds=left, avoid=avoid, cap=top, threads=threads)
        res = replace(res, seconds=time.perf_counter() - t0)
    return res
