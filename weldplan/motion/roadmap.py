"""A probabilistic roadmap in R^n, built once and queried many times (OMPL's PRM).

Where :func:`weldplan.motion.sampling.plan_rn` plans one path per call, a :class:`Roadmap` is
built once for a scene (a robot at one base, on one IK branch) and answers many questions about
it: which of a set of configurations lie in one connected component (:meth:`Roadmap.connect`), and
a path between two of them (:meth:`Roadmap.path`). It is OMPL's PRM (Kavraki, Svestka, Latombe,
Overmars, IEEE T-RA 1996; ``starStrategy=True``: PRM*, Karaman and Frazzoli, IJRR 2011) with the
caller's validity checks, so every edge of the roadmap is a motion the caller's ``motion_valid``
proved free, and a path read from it is exactly as trustworthy as that check.

Conventions (those of :mod:`weldplan.motion.sampling`)
-------------------------------------------------------
- States are numpy arrays ``(d,)``; the roadmap samples the box ``[lower, upper]``.
- **Budgeted by work**, not by the clock: the roadmap grows (OMPL's ``growRoadmap``: a valid
  sample, then its ``neighbours`` nearest milestones connected where ``motion_valid`` says so)
  until it holds :attr:`RoadmapSettings.milestones` milestones or its state checks reach
  :attr:`RoadmapSettings.max_checks`; :attr:`RoadmapSettings.wall_s` is a safety net whose firing
  :attr:`RoadmapReport.stopped` reports (the result then depends on the machine).
- **Seeded**: OMPL's process-wide seed generator is reset with the seed before the planner and
  its sampler are made, so the same seed and checks give the same roadmap (single-threaded:
  ``growRoadmap`` runs in the caller's thread).
- **Queries** are added as milestones by OMPL's own connection strategy (PRM's ``solve`` with
  the queries as start states and a termination condition that is already true: the starts are
  connected, nothing is grown, no solution thread runs). They stay in the roadmap: later queries
  may connect through them.
- **Not a proof of disconnection.** Two states in different components of a roadmap built on a
  finite sample may still be joined by a path the sample missed; only "same component" is an
  answer (a path, each edge checked).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.motion.ompl_base import (
    MotionCheck,
    SamplingArgumentError,
    StateCheck,
    _check_box,
    _import_ompl,
    _motion_validator,
    _ompl_seed,
    _vector,
)

log = logging.getLogger(__name__)

#: why the roadmap stopped growing (:attr:`RoadmapReport.stopped`)
STOP_MILESTONES = "milestones"
STOP_CHECKS = "checks"
STOP_CLOCK = "clock"


@dataclass(frozen=True)
class RoadmapSettings:
    """The work a roadmap may do (module docstring).

    Attributes
    ----------
    milestones
        Milestones grown before the queries (the queries add their own).
    neighbours
        PRM's ``k``: nearest milestones a new one tries to connect to (OMPL's default 10).
    query_neighbours
        ``k`` while queries are added (:meth:`Roadmap.connect`): a query is where the caller
        needs an answer, often near an obstacle where the nearest few motions are blocked.
    max_checks
        State validity checks during growth at most (a scene where valid samples are rare stops
        here instead of sampling on).
    star
        PRM* (``k`` grows with ``log n``) instead of PRM's fixed ``neighbours``.
    wall_s
        s: the clock's safety net (reported when it fires).
    """

    milestones: int = 60
    neighbours: int = 8
    query_neighbours: int = 16
    max_checks: int = 20000
    star: bool = False
    wall_s: float = 600.0

    def __post_init__(self) -> None:
        for name in ("milestones", "neighbours", "query_neighbours", "max_checks"):
            v = getattr(self, name)
            if not (isinstance(v, (int, np.integer)) and v >= 1):
                raise ConfigError(f"{name} must be a positive integer, got {v!r}", field=name)
        if not (np.isfinite(self.wall_s) and self.wall_s > 0):
            raise ConfigError(f"wall_s must be positive seconds, got {self.wall_s}", field="wall_s")


@dataclass(frozen=True)
class RoadmapReport:
    """What a roadmap did (a snapshot: :meth:`Roadmap.report`).

    Attributes
    ----------
    milestones, edges
        Vertices (queries included) and undirected edges of the roadmap.
    queries
        Query states added (:meth:`Roadmap.connect`).
    state_checks, motion_checks
        Calls of the caller's ``is_valid`` / ``motion_valid`` so far.
    components
        Sizes of the components that hold queries, largest first (queries counted).
    stopped
        Why growth stopped: :data:`STOP_MILESTONES`, :data:`STOP_CHECKS` or :data:`STOP_CLOCK`
        (the safety net: not reproducible).
    grow_s
        Wall seconds of the growth.
    seed
        The seed it was grown with.
    """

    milestones: int
    edges: int
    queries: int
    state_checks: int
    motion_checks: int
    components: tuple[int, ...]
    stopped: str
    grow_s: float
    seed: int | None

    def line(self) -> str:
        """One line for logs and summaries."""
        comp = ", ".join(str(c) for c in self.components[:5]) or "none"
        return (
            f"{self.milestones} milestones ({self.queries} queries), {self.edges} edges, query "
            f"components {comp}; {self.state_checks} state and {self.motion_checks} motion "
            f"checks; stopped by {self.stopped} ({self.grow_s:.1f} s)"
        )


class Roadmap:
    """OMPL's PRM over the box ``[lower, upper]`` of R^d, grown on construction (module
    docstring).

    Parameters
    ----------
    lower, upper
        ``(d,)`` the box sampled (rad for joints).
    is_valid
        ``is_valid(x (d,)) -> bool``: whether a state is free.
    motion_valid
        ``motion_valid(a, b) -> bool``: whether the straight motion ``a -> b`` (ends included)
        is free; every edge is one it accepted.
    settings
        The work allowed (:class:`RoadmapSettings`).
    seed
        Seeds OMPL's process-wide generator before the planner is made (``None``: left alone,
        not reproducible).
    """

    def __init__(
        self,
        lower: ArrayLike,
        upper: ArrayLike,
        is_valid: StateCheck,
        motion_valid: MotionCheck,
        settings: RoadmapSettings | None = None,
        *,
        seed: int | np.random.Generator | None = 0,
    ) -> None:
        self.lower = _vector("lower", lower)
        self.d = len(self.lower)
        self.upper = _vector("upper", upper, self.d)
        _check_box(self.lower, self.upper, {})
        self.settings = settings or RoadmapSettings()
        checks = self._checks = [0, 0]  # state, motion; the closures OMPL holds must not hold
        # self: a cycle through C++ is one Python's collector cannot see

        def valid(x: NDArray[np.float64]) -> bool:
            checks[0] += 1
            return bool(is_valid(x))

        def motion(a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
            checks[1] += 1
            return bool(motion_valid(a, b))

        self._valid = valid
        self._queries: list[NDArray[np.float64]] = []
        self._seed = _ompl_seed(seed)
        self._setup(motion)
        self._grow()

    # ------------------------------------------------------------------ OMPL objects
    def _setup(self, motion: MotionCheck) -> None:
        ob, og, ou = _import_ompl()
        space = ob.RealVectorStateSpace(self.d)
        bounds = ob.RealVectorBounds(self.d)
        for i in range(self.d):
            bounds.setLow(i, float(self.lower[i]))
            bounds.setHigh(i, float(self.upper[i]))
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        d, valid = self.d, self._valid

        def read(state: Any) -> NDArray[np.float64]:
            return np.array([state[i] for i in range(d)], dtype=np.float64)

        si.setStateValidityChecker(lambda state: valid(read(state)))
        si.setMotionValidator(_motion_validator(si, read, motion))
        si.setup()
        if self._seed is not None:  # before the planner: its sampler and neighbour structure
            level = ou.getLogLevel()  # draw their seeds from the generator (OMPL complains
            ou.setLogLevel(ou.LOG_NONE)  # on stderr when it was used before: it resets anyway)
            ou.RNG.setSeed(self._seed)
            ou.setLogLevel(level)
        prm = og.PRM(si, bool(self.settings.star))
        if not self.settings.star:
            prm.setMaxNearestNeighbors(int(self.settings.neighbours))
        pdef = ob.ProblemDefinition(si)
        prm.setProblemDefinition(pdef)
        self._ob, self._space, self._si, self._prm, self._pdef = ob, space, si, prm, pdef
        self._read = read

    def _grow(self) -> None:
        ob, ou = self._ob, _import_ompl()[2]
        s, checks, prm = self.settings, self._checks, self._prm

        def enough() -> bool:
            return prm.milestoneCount() >= s.milestones or checks[0] >= s.max_checks

        ptc = ob.plannerOrTerminationCondition(
            ob.timedPlannerTerminationCondition(float(s.wall_s)),
            ob.PlannerTerminationCondition(enough),
        )
        level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_DEBUG if log.isEnabledFor(logging.DEBUG) else ou.LOG_NONE)
        t0 = time.perf_counter()
        try:
            self._prm.growRoadmapPtc(ptc)
        finally:
            ou.setLogLevel(level)
        self._grow_s = time.perf_counter() - t0
        self._milestones = int(prm.milestoneCount())
        if self._milestones >= s.milestones:
            self._stopped = STOP_MILESTONES
        elif checks[0] >= s.max_checks:
            self._stopped = STOP_CHECKS
        else:
            self._stopped = STOP_CLOCK
            log.warning("roadmap: the clock's safety net (%.0f s) stopped its growth", s.wall_s)
        self._graph: tuple[NDArray, list[tuple[int, int]], NDArray] | None = None

    # ------------------------------------------------------------------ queries
    def connect(self, Q: ArrayLike) -> NDArray[np.int64]:
        """Add the states ``Q (n, d)`` as milestones (each connected to its nearest ones by
        OMPL's strategy, motions checked) and return, per state, the index of its component
        (:meth:`components`; -1 for a state that is invalid or outside the box: not added)."""
        if self._prm is None:
            raise PlanningError("the roadmap was closed: it takes no more queries")
        Q = np.asarray(Q, dtype=np.float64).reshape(-1, self.d)
        inside = np.all((Q >= self.lower) & (Q <= self.upper), axis=1)
        ok = np.array([bool(inside[i]) and self._valid(Q[i]) for i in range(len(Q))], dtype=bool)
        new = [q for q, k in zip(Q, ok, strict=True) if k and not self._known(q)]
        if new:
            self._add(new)
        comp = self.component_of(Q)
        comp[~ok] = -1
        return comp

    def _known(self, q: NDArray[np.float64]) -> bool:
        return any(np.array_equal(q, x) for x in self._queries)

    def _add(self, new: list[NDArray[np.float64]]) -> None:
        """PRM's ``solve`` with ``new`` as start states (the last also the goal) and a
        termination condition that is already true: OMPL adds and connects them, grows nothing
        (module docstring)."""
        ob, ou = self._ob, _import_ompl()[2]
        self._prm.clearQuery()
        self._pdef.clearStartStates()
        self._pdef.clearGoal()
        for q in new[:-1]:
            self._pdef.addStartState(self._state(q))
        self._pdef.setGoalState(self._state(new[-1]))
        if len(new) == 1:
            self._pdef.addStartState(self._state(new[-1]))
        level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_NONE)
        star = self.settings.star
        if not star:
            self._prm.setMaxNearestNeighbors(int(self.settings.query_neighbours))
        try:  # a C++ condition: PRM's solution thread must not call into Python
            self._prm.solve(ob.timedPlannerTerminationCondition(0.0))
        finally:
            ou.setLogLevel(level)
            if not star:
                self._prm.setMaxNearestNeighbors(int(self.settings.neighbours))
        self._queries.extend(np.array(q, copy=True) for q in new)
        self._graph = None

    def _state(self, q: NDArray[np.float64]) -> Any:
        st = self._space.allocState()
        for i in range(self.d):
            st[i] = float(q[i])
        return st

    def graph(self) -> tuple[NDArray[np.float64], list[tuple[int, int]], NDArray[np.int64]]:
        """``(states (v, d), edges [(i, j)], component (v,))`` of the roadmap as OMPL holds it
        (``getPlannerData``; vertices with no edge that are not queries are left out)."""
        if self._graph is None:
            from scipy.sparse import coo_matrix
            from scipy.sparse.csgraph import connected_components

            pd = self._ob.PlannerData(self._si)
            self._prm.getPlannerData(pd)
            n = pd.numVertices()
            X = np.array([self._read(pd.getVertex(i).getState()) for i in range(n)])
            X = X.reshape(n, self.d)
            if n == 0:
                self._graph = (X, [], np.zeros(0, dtype=np.int64))
                return self._graph
            edges = [(i, j) for i in range(n) for j in pd.getEdges(i) if i < j]
            e = np.array(edges, dtype=np.int64).reshape(-1, 2)
            adj = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
            _, comp = connected_components(adj, directed=False)
            self._graph = (X, edges, comp.astype(np.int64))
        return self._graph

    def _index(self, Q: NDArray[np.float64]) -> NDArray[np.int64]:
        """Vertex index of each state of ``Q (n, d)`` (-1: not a vertex)."""
        X = self.graph()[0]
        out = np.full(len(Q), -1, dtype=np.int64)
        for k, q in enumerate(Q):
            hit = np.flatnonzero(np.all(X == q, axis=1))
            if len(hit):
                out[k] = int(hit[0])
        return out

    def component_of(self, Q: ArrayLike) -> NDArray[np.int64]:
        """Component index of each state of ``Q (n, d)`` that is a vertex (-1 otherwise)."""
        Q = np.asarray(Q, dtype=np.float64).reshape(-1, self.d)
        idx = self._index(Q)
        comp = self.graph()[2]
        if len(comp) == 0:
            return np.full(len(Q), -1, dtype=np.int64)
        return np.where(idx >= 0, comp[np.maximum(idx, 0)], -1)

    def path(self, qa: ArrayLike, qb: ArrayLike) -> NDArray[np.float64] | None:
        """``(p, d)``: the shortest path (Euclidean edge lengths, Dijkstra) along the roadmap
        from vertex ``qa`` to vertex ``qb``, ends included; ``None`` when they are not vertices
        of one component. Each motion of it is an edge ``motion_valid`` accepted."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import dijkstra

        ia, ib = self._index(np.array([qa, qb], dtype=np.float64).reshape(2, self.d))
        X, edges, comp = self.graph()
        if ia < 0 or ib < 0 or comp[ia] != comp[ib]:
            return None
        if ia == ib:
            return X[[ia, ib]]
        e = np.array(edges, dtype=np.int64).reshape(-1, 2)
        w = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1) + 1e-12
        adj = coo_matrix((w, (e[:, 0], e[:, 1])), shape=(len(X), len(X)))
        _, pred = dijkstra(adj, directed=False, indices=int(ia), return_predecessors=True)
        chain = [int(ib)]
        while chain[-1] != ia:
            chain.append(int(pred[chain[-1]]))
        return X[chain[::-1]]

    def close(self) -> None:
        """Release OMPL's objects (the graph read so far stays: :meth:`graph`, :meth:`path`,
        :meth:`report` still answer; :meth:`connect` no longer does). A roadmap still alive
        when the interpreter exits makes nanobind report its objects as leaked on stderr."""
        if self._prm is not None:
            self.graph()
            self._milestones = int(self._prm.milestoneCount())
        self._ob = self._space = self._si = self._prm = self._pdef = self._read = None

    def report(self) -> RoadmapReport:
        """The roadmap's figures now (:class:`RoadmapReport`)."""
        X, edges, comp = self.graph()
        qc = self.component_of(np.array(self._queries).reshape(-1, self.d))
        qc = qc[qc >= 0]
        sizes = sorted(np.bincount(qc).tolist(), reverse=True) if len(qc) else []
        if self._prm is not None:
            self._milestones = int(self._prm.milestoneCount())
        return RoadmapReport(
            milestones=self._milestones,
            edges=len(edges),
            queries=len(self._queries),
            state_checks=int(self._checks[0]),
            motion_checks=int(self._checks[1]),
            components=tuple(int(s) for s in sizes if s > 0),
            stopped=self._stopped,
            grow_s=round(self._grow_s, 3),
            seed=self._seed,
        )


def build_roadmap(
    lower: ArrayLike,
    upper: ArrayLike,
    is_valid: StateCheck,
    motion_valid: MotionCheck,
    settings: RoadmapSettings | None = None,
    *,
    seed: int | np.random.Generator | None = 0,
) -> Roadmap:
    """A :class:`Roadmap` grown in ``[lower, upper]`` (the arguments are its own).

    Raises
    ------
    SamplingArgumentError
        Bad bounds or seed.
    weldplan.errors.ConfigError
        OMPL not installed, or bad settings.
    """
    return Roadmap(lower, upper, is_valid, motion_valid, settings, seed=seed)


__all__ = [
    "Roadmap",
    "RoadmapReport",
    "RoadmapSettings",
    "SamplingArgumentError",
    "build_roadmap",
]
