"""Which robot welds which weld: a min-max assignment, then a seeded local search.

:func:`allocate` minimises the station's cycle time, the slowest robot's (weld times plus its
route over its welds), over every assignment of the served welds to robots that serve them:

1. **start**: the min-max assignment on per-weld costs ``weld_time + tour share``
   (:func:`weldplan.multi.problem.tour_shares`) as a MILP solved by HiGHS
   (:func:`scipy.optimize.milp`, budgeted by branch-and-bound nodes); a greedy
   longest-first assignment when HiGHS finds no integer point within its budget;
2. each robot's order by the sequencer (:func:`weldplan.optim.discrete.solve_sequence`:
   Held-Karp up to 13 welds, seeded nearest neighbour + 2-opt/Or-opt above);
3. **iterated local search** (seeded, budgeted by candidate evaluations and kicks): from
   the bottleneck robot,
   move one weld to another robot that serves it, or swap one with another robot's. Candidates
   are ranked by their insertion estimate (removal from the current order, cheapest insertion
   into the other: the cost of an actual order, so an estimate that lowers the maximum is a
   move that does); a few that do not are re-sequenced in full before the search gives up. A
   move is kept when it lowers the sorted vector of cycle times lexicographically (the maximum
   first: with several robots at the maximum, relieving one of them counts); the search ends
   when no candidate does, or the budget is spent (``stats["budget_spent"]``). Then a kick
   moves a few random welds to random robots that serve them and the descent runs again
   from there, keeping the best answer (``AllocationSettings.kicks`` times: on move times
   without the triangle inequality, one descent stalls in poor local optima);
4. each robot's final order by the sequencer with its full polish.

The approach follows the "allocate, sequence, re-balance" loop of the station-balancing
literature (Spensieri et al., IEEE T-ASE 2016; Åblad et al., IEEE T-ASE 2022) with the leg
times of :mod:`weldplan.robot.route.legtime` in place of their path-planned ones; a planned
station puts the timed legs of its plans back and allocates again
(:mod:`weldplan.multi.calibrate`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.multi.problem import AllocationProblem, AllocationSettings, ReachMap
from weldplan.multi.result import Allocation, RobotShare, Unreached
from weldplan.random import RNGLike, as_generator, seed_of

log = logging.getLogger(__name__)

#: a cycle must drop by more than this (s) to count as lower
EPS = 1e-9


@dataclass(frozen=True, eq=False)
class PairCost:
    """Pairs of welds of two robots that must not be welded at the same time, and what each
    pair costs the search (:mod:`weldplan.multi.conflicts`: two robots at rest that meet).

    Attributes
    ----------
    pair
        ``(R, W, R, W) bool``, symmetric: robot ``r`` at weld ``i`` meets robot ``s`` at ``j``.
    seconds
        s charged to each of the two robots' cycles per such pair of the assignment: the wait
        an interlock of the two costs at least (the other's weld), so that crossing shares
        cost more than shares side by side.
    """

    pair: NDArray[np.bool_]
    seconds: float

    def loads(self, assign: NDArray[np.intp], R: int) -> NDArray[np.float64]:
        """``(R,)`` s: per robot, the conflicting pairs of ``assign`` it is in, times
        :attr:`seconds`."""
        idx = np.flatnonzero(assign >= 0)
        a = assign[idx]
        M = self.pair[a[:, None], idx[:, None], a[None, :], idx[None, :]]
        M &= a[:, None] != a[None, :]
        return self.seconds * np.bincount(a, weights=M.sum(axis=1), minlength=R)[:R]

    def count(self, assign: NDArray[np.intp]) -> int:
        """The conflicting pairs ``assign`` keeps."""
        R = self.pair.shape[0]
        return int(round(self.loads(np.asarray(assign), R).sum() / self.seconds / 2)) if (
            self.seconds > 0) else 0  # fmt: skip


def allocate(
    reach: ReachMap | ArrayLike,
    weld_time: ArrayLike,
    travel: Sequence[ArrayLike] | ArrayLike,
    *,
    rng: RNGLike = None,
    settings: AllocationSettings | None = None,
    conflicts: PairCost | None = None,
) -> Allocation:
    """Assign every served weld to one robot and order each robot's welds (module docstring).

    Parameters
    ----------
    reach
        A :class:`~weldplan.multi.problem.ReachMap`, or an ``(R, W) bool`` array.
    weld_time
        ``(R, W)`` s: each weld's dwell on each robot.
    travel
        ``R`` matrices ``(W, W)`` s: each robot's move times between the welds it serves.
    rng
        Seed or Generator (the local search's tie-breaks and the sequencer's kicks).
    settings
        :class:`~weldplan.multi.problem.AllocationSettings` (the route kind and the budgets).
    conflicts
        :class:`PairCost`: pairs of welds of two robots that meet, each charged to both
        robots' cycles in the search (``None``: none). The shares' cycle times reported stay
        the model's; ``stats["conflict_pairs"]`` counts the pairs the answer keeps.

    Returns
    -------
    Allocation
        ``method="ours"``; the welds no robot serves in ``unreached`` with every robot's reason.

    Raises
    ------
    ConfigError
        Inputs of the wrong shape or negative times (naming the field).
    """
    settings = settings or AllocationSettings()
    problem = AllocationProblem.build(reach, weld_time, travel, settings.closed)
    gen = as_generator(rng)
    assign, stats = initial_assignment(problem, settings)
    state = _State.start(problem, assign, gen, settings.search_kicks, conflicts)
    stats["start_cycle_time"] = float(state.cyc.max(initial=0.0))
    stats.update(_iterated_search(problem, state, settings, gen))
    state.polish(settings.final_kicks)
    if conflicts is not None:
        stats["conflict_pairs"] = conflicts.count(state.assign)
    stats["settings"] = asdict(settings)
    out = make_allocation(problem, "ours", state.assign, state.orders, seed_of(rng), stats)
    log.info(
        "allocated %d welds to %d robots: cycle %.3f s (start %.3f s, %d moves applied)",
        int(problem.served.sum()),
        len(problem.reach.robots),
        out.cycle_time,
        stats["start_cycle_time"],
        stats["applied"],
    )
    return out


def initial_assignment(
    problem: AllocationProblem, settings: AllocationSettings
) -> tuple[NDArray[np.intp], dict]:
    """``(W,) int`` robot per weld (-1: none serves it) from the min-max MILP of step 1, and
    its figures (``milp_status``, ``milp_value``: the MILP's objective in s, ``start``)."""

    from weldplan.multi.bound import assignment_model

    ok = problem.ok
    assign = np.full(ok.shape[1], -1, dtype=np.intp)
    if not ok.any():
        return assign, {"start": "none", "milp_status": "no weld served"}
    cost = problem.weld_time + problem.share
    m = assignment_model(problem, cost, bound=False)
    rob, weld, K = m.rob, m.weld, len(m.rob)
    res = m.milp(
        {
            "node_limit": settings.milp_nodes,
            "mip_rel_gap": settings.milp_gap,
            "time_limit": settings.milp_seconds,
            "presolve": True,
        }
    )
    stats = {"milp_status": str(res.message)}
    if res.x is None:
        stats["start"] = "greedy"
        return _greedy(cost, ok), stats
    x = res.x[:K]
    best = np.full(ok.shape[1], -1.0)
    for k in np.argsort(-x, kind="stable"):  # each weld to its largest x
        if best[weld[k]] < 0:
            best[weld[k]] = x[k]
            assign[weld[k]] = rob[k]
    stats.update(start="milp", milp_value=float(res.fun))
    return assign, stats


def _greedy(cost: NDArray[np.float64], ok: NDArray[np.bool_]) -> NDArray[np.intp]:
    """Longest processing time first: welds by decreasing cheapest cost, each to the serving
    robot whose load ends lowest (deterministic)."""
    R, W = ok.shape
    load = np.zeros(R)
    assign = np.full(W, -1, dtype=np.intp)
    c = np.where(ok, cost, np.inf)
    served = np.flatnonzero(ok.any(axis=0))
    for i in served[np.argsort(-c[:, served].min(axis=0), kind="stable")]:
        r = int(np.argmin(load + c[:, i]))
        assign[i] = r
        load[r] += c[r, i]
    return assign


def sequence_share(
    problem: AllocationProblem, r: int, welds: ArrayLike, seed: int, kicks: int | None
) -> tuple[int, ...]:
    """Robot ``r``'s order over ``welds`` (indices) by the sequencer (exact up to 13 welds,
    nearest neighbour + polish with ``kicks`` above; ``None``: its default)."""
    from weldplan.optim.discrete.local_search import PolishParams
    from weldplan.optim.discrete.sequence import solve_sequence

    w = np.sort(np.asarray(welds, dtype=np.intp))
    if len(w) < 3:
        if len(w) == 2 and problem.route_time(r, w[::-1]) < problem.route_time(r, w):
            w = w[::-1]
        return tuple(int(v) for v in w)
    seq = solve_sequence(
        problem.travel[r][np.ix_(w, w)],
        closed=problem.closed,
        rng=seed,
        polish_params=PolishParams(kicks=kicks),
    )
    return tuple(int(w[k]) for k in seq.order)


def make_allocation(
    problem: AllocationProblem,
    method: str,
    assign: NDArray[np.intp],
    orders: Sequence[Sequence[int]],
    seed: int | None,
    stats: dict,
) -> Allocation:
    """The :class:`~weldplan.multi.result.Allocation` of ``assign`` and per-robot ``orders``;
    the welds with no robot (-1) listed with every robot's reason."""
    rm = problem.reach
    shares = tuple(
        RobotShare(
            rm.robots[r],
            tuple(int(v) for v in o),
            float(problem.weld_time[r, list(o)].sum()),
            problem.route_time(r, o),
        )
        for r, o in enumerate(orders)
    )
    unreached = tuple(
        Unreached(
            rm.welds[i],
            tuple(f"{rm.robots[r]}: {rm.reasons[r][i] or 'served'}" for r in range(len(rm.robots))),
        )
        for i in np.flatnonzero(np.asarray(assign) < 0)
    )
    return Allocation(
        method=method,
        robots=rm.robots,
        welds=rm.welds,
        assignment=tuple(int(v) for v in assign),
        shares=shares,
        unreached=unreached,
        closed=problem.closed,
        seed=seed,
        stats=stats,
    )


def removal_deltas(T: NDArray[np.float64], o: NDArray[np.intp], closed: bool) -> NDArray:
    """``(n,)`` s: the change of the route time of order ``o`` when its ``k``-th weld is
    removed (the neighbours joined), over move times ``T (W, W)`` (zero diagonal)."""
    n = len(o)
    if n < 2:
        return np.zeros(n)
    if closed:
        a, b = np.concatenate((o[-1:], o[:-1])), np.concatenate((o[1:], o[:1]))
        return T[a, b] - T[a, o] - T[o, b]
    d = np.empty(n)
    d[0], d[-1] = -T[o[0], o[1]], -T[o[-2], o[-1]]
    a, m, b = o[:-2], o[1:-1], o[2:]
    d[1:-1] = T[a, b] - T[a, m] - T[m, b]
    return d


def insertion(
    T: NDArray[np.float64], o: NDArray[np.intp], closed: bool, new: NDArray[np.intp]
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """``(m,)`` s and ``(m,)`` positions: the cheapest insertion of each weld of ``new`` into
    order ``o`` (inserted at position ``p``: ``o[:p] + [i] + o[p:]``) and where."""
    n = len(o)
    if n == 0:
        return np.zeros(len(new)), np.zeros(len(new), dtype=np.intp)
    if closed:
        a, b = o, np.concatenate((o[1:], o[:1]))  # between o[p - 1] and o[p]: p = 1..n
        d = T[a][:, new] + T[new][:, b].T - T[a, b][:, None]
        k = np.argmin(d, axis=0)
        return d[k, np.arange(len(new))], (k + 1).astype(np.intp)
    first = T[new, o[0]][None]
    last = T[o[-1], new][None]
    mid = T[o[:-1]][:, new] + T[new][:, o[1:]].T - T[o[:-1], o[1:]][:, None]
    d = np.concatenate([first, mid, last])  # position 0, 1..n-1, n
    k = np.argmin(d, axis=0)
    return d[k, np.arange(len(new))], k.astype(np.intp)


def _edit(T, o: tuple[int, ...], closed: bool, out: int | None, new: int | None) -> tuple[int, ...]:
    """Order ``o`` without weld ``out`` and with weld ``new`` at its cheapest place."""
    kept = [v for v in o if v != out]
    if new is None:
        return tuple(kept)
    _, p = insertion(T, np.asarray(kept, dtype=np.intp), closed, np.array([new]))
    return tuple(kept[: p[0]] + [new] + kept[p[0] :])


def lex_lower(new: NDArray[np.float64], old: NDArray[np.float64]) -> bool:
    """Whether the cycle times ``new`` sorted from the largest are lexicographically lower
    than ``old``'s by more than :data:`EPS` at the first entry that differs."""
    for x, y in zip(np.sort(new)[::-1], np.sort(old)[::-1], strict=True):
        if x < y - EPS:
            return True
        if x > y + EPS:
            return False
    return False


@dataclass
class _State:
    """The search's mutable state: the assignment, each robot's order and cycle."""

    problem: AllocationProblem
    assign: NDArray[np.intp]
    orders: list[tuple[int, ...]]
    cyc: NDArray[np.float64]
    gen: np.random.Generator
    kicks: int
    conflicts: PairCost | None = None
    charge: NDArray[np.float64] | None = None  # (R,) s: the charges of ``assign``
    _next: NDArray[np.float64] | None = None  # the last trial's charges

    @classmethod
    def start(cls, problem, assign, gen, kicks, conflicts=None) -> _State:
        R = problem.ok.shape[0]
        if conflicts is not None and not conflicts.pair.any():
            conflicts = None  # nothing to charge: the plain search
        s = cls(problem, assign.copy(), [()] * R, np.zeros(R), gen, kicks, conflicts)
        for r in range(R):
            s.orders[r] = sequence_share(problem, r, np.flatnonzero(assign == r), s.seed(), kicks)
            s.cyc[r] = problem.cycle(r, s.orders[r])
        s.charge = s.charges(s.assign)
        s.cyc += s.charge
        return s

    def charges(self, assign: NDArray[np.intp]) -> NDArray[np.float64]:
        """``(R,)`` s: the conflicting pairs' charge per robot (0 without conflicts)."""
        R = len(self.cyc)
        return np.zeros(R) if self.conflicts is None else self.conflicts.loads(assign, R)

    def trial(self, pair: dict[int, tuple[int, ...]]) -> NDArray[np.float64]:
        """``(R,)`` s: the cycles (charges included) if ``pair``'s orders replaced theirs."""
        new = self.cyc.copy()
        if self.conflicts is None:
            for r, o in pair.items():
                new[r] = self.problem.cycle(r, o)
            return new
        assign = self.assign.copy()
        for r, o in pair.items():
            assign[list(o)] = r
        self._next = self.charges(assign)
        new = new - self.charge
        for r, o in pair.items():
            new[r] = self.problem.cycle(r, o)
        return new + self._next

    def seed(self) -> int:
        return int(self.gen.integers(2**31))

    def resequence(self, r: int, o: tuple[int, ...], kicks: int | None) -> tuple[int, ...]:
        """The better of ``o`` and the sequencer's order over the same welds (the same welds:
        the same charges)."""
        q = sequence_share(self.problem, r, o, self.seed(), kicks)
        return q if self.problem.cycle(r, q) < self.problem.cycle(r, o) - EPS else o

    def apply(self, pairs: dict[int, tuple[int, ...]]) -> None:
        self.cyc = self.trial(pairs)
        for r, o in pairs.items():
            self.orders[r] = o
            self.assign[list(o)] = r
        if self.conflicts is not None:
            self.charge = self._next

    def polish(self, kicks: int | None) -> None:
        self.apply({r: self.resequence(r, o, kicks) for r, o in enumerate(self.orders)})


def _candidates(problem: AllocationProblem, st: _State, b: int) -> NDArray[np.float64]:
    """Rows ``(estimated max, estimated sum, tie-break, r, i, j)`` of every move (``j = -1``)
    of a weld ``i`` of robot ``b`` to robot ``r``, and every swap with a weld ``j`` of ``r``,
    whose estimate does not raise the pair's maximum above ``b``'s cycle; best first."""
    ok, w, T = problem.ok, problem.weld_time, problem.travel
    ob = np.asarray(st.orders[b], dtype=np.intp)
    rem_b = removal_deltas(T[b], ob, problem.closed)
    rows = []
    for r in range(ok.shape[0]):
        if r == b:
            continue
        orr = np.asarray(st.orders[r], dtype=np.intp)
        movable = ok[r, ob]
        if not movable.any():
            continue
        ib = ob[movable]
        ins_r, _ = insertion(T[r], orr, problem.closed, ib)
        nb = st.cyc[b] - w[b, ib] + rem_b[movable]
        nr = st.cyc[r] + w[r, ib] + ins_r
        rows.append(
            np.c_[np.maximum(nb, nr), nb + nr, np.full(len(ib), r), ib, np.full(len(ib), -1)]
        )
        back = ok[b, orr]
        if not back.any():
            continue
        jr = orr[back]
        ins_b, _ = insertion(T[b], ob, problem.closed, jr)
        rem_r = removal_deltas(T[r], orr, problem.closed)[back]
        sb = nb[:, None] + (w[b, jr] + ins_b)[None, :]
        sr = nr[:, None] - (w[r, jr] - rem_r)[None, :]
        keep = np.maximum(sb, sr) <= st.cyc[b] + EPS
        ii, jj = np.nonzero(keep)
        rows.append(
            np.c_[np.maximum(sb, sr)[keep], (sb + sr)[keep], np.full(len(ii), r), ib[ii], jr[jj]]
        )
    if not rows:
        return np.zeros((0, 6))
    C = np.concatenate(rows)
    C = np.c_[C[:, :2], st.gen.random(len(C)), C[:, 2:]]
    return C[np.lexsort((C[:, 2], C[:, 1], C[:, 0]))]


def _iterated_search(
    problem: AllocationProblem, st: _State, settings: AllocationSettings, gen: np.random.Generator
) -> dict:
    """Step 3 of the module docstring on ``st`` (left at the best answer); its figures."""
    stats = _descent(problem, st, settings.moves, settings.resequence)
    ok = problem.ok
    movable = np.flatnonzero(ok.sum(axis=0) >= 2)
    best = (st.assign.copy(), list(st.orders), st.cyc.copy())
    kicks = improved = 0
    while kicks < settings.kicks and stats["tried"] < settings.moves and len(movable):
        kicks += 1
        for i in gen.choice(movable, size=min(settings.kick_size, len(movable)), replace=False):
            others = np.flatnonzero(ok[:, i] & (np.arange(len(ok)) != st.assign[i]))
            r, b = int(gen.choice(others)), int(st.assign[i])
            st.apply({b: _edit(problem.travel[b], st.orders[b], problem.closed, int(i), None)})
            st.apply({r: _edit(problem.travel[r], st.orders[r], problem.closed, None, int(i))})
        more = _descent(problem, st, settings.moves - stats["tried"], settings.resequence)
        for k in ("tried", "applied", "rounds"):
            stats[k] += more[k]
        if lex_lower(st.cyc, best[2]):
            best = (st.assign.copy(), list(st.orders), st.cyc.copy())
            improved += 1
        else:
            st.assign, st.orders, st.cyc = best[0].copy(), list(best[1]), best[2].copy()
            st.charge = st.charges(st.assign)
    stats.update(
        kicks=kicks, kicks_improved=improved, budget_spent=stats["tried"] >= settings.moves
    )
    return stats


def _descent(problem: AllocationProblem, st: _State, moves: int, resequence: int) -> dict:
    """The descent of step 3 on ``st`` with at most ``moves`` candidate evaluations."""
    tried = applied = rounds = 0
    T = problem.travel
    while tried < moves:
        rounds += 1
        b = int(np.argmax(st.cyc))
        improved, left = False, resequence
        for _, _, _, r, i, j in _candidates(problem, st, b):
            if tried >= moves:
                break
            tried += 1
            r, i, j = int(r), int(i), int(j)
            jj = None if j < 0 else j
            pair = {
                b: _edit(T[b], st.orders[b], problem.closed, i, jj),
                r: _edit(T[r], st.orders[r], problem.closed, jj, i),
            }
            new = st.trial(pair)
            if not lex_lower(new, st.cyc):
                if left == 0:
                    break  # candidates are best first: the rest estimate no better
                left -= 1
                pair = {k: st.resequence(k, o, st.kicks) for k, o in pair.items()}
                new = st.trial(pair)
                if not lex_lower(new, st.cyc):
                    continue
            else:
                pair = {k: st.resequence(k, o, st.kicks) for k, o in pair.items()}
            st.apply(pair)
            applied += 1
            improved = True
            break
        if not improved:
            break
    return {"tried": tried, "applied": applied, "rounds": rounds}
