"""Which legs of a route are known, and the rounds that plan just the legs an order needs.

:class:`PairPlanning` holds the state of one run of :func:`weldplan.weld.pipeline.plan_route`
between the cell and the route: the straight checks of pairs of virtual joints, the local paths of
blocked pairs, the cost matrix, and the lazy plan-then-sequence rounds (the pipeline's module
docstring says why and how). It was the body of ``plan_route`` (359 lines of closures sharing
state); as a class, each step is one method with one job.

Pairs are numbered along the upper triangle: pair ``p`` joins joints ``iu[p] < ju[p]``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError, PlanningError, UnreachableJointsError

log = logging.getLogger(__name__)

#: most pairs in one task sent to the executor. With 4 batches per worker, the 4000-joint
#: station's 4,905 blocked candidates went out in 8 batches of 614 on 2 workers, and one worker
#: sat idle for the last batch of the other (about 4 min of a 23 min stage at load 15); pairs
#: carry their own seeds, so the batching never changes a route
PAIR_BATCH_MAX = 64


class PairPlanning:
    """The pairs of one planning run: checked, free, known, planned; costs; the rounds.

    Parameters
    ----------
    cell
        The cell (joints, virtual joints, collision model, grid).
    config
        The run's :class:`~weldplan.weld.pipeline.PlanConfig`.
    gen
        The run's only random generator (pair seeds, then the sequencer).
    executor
        Where blocked pairs are planned (None: serially in this process).
    report
        ``report(stage, done, total)`` progress callback.
    exact_max
        Joints up to which Held-Karp is cheap (the pipeline's ``LOWER_BOUND_EXACT_MAX``).
    subset
        Indices of the cell's joints to plan (None: all). The local paths are still planned
        in ``cell`` (so workers keep the cell they hold); joint ``k`` here is
        ``subset[k]`` there.
    leg_cost
        ``(N, N)`` over the cell's joints: what the sequencer minimises instead of the legs'
        lengths (``--cost time``: seconds, :func:`weldplan.robot.route.leg_times`). A leg
        whose local path failed stays infinite; the lazy rounds still plan exactly the legs an
        order uses. ``self.C`` stays in mm (the route's length and its proved length bounds);
        the order's own cost over ``leg_cost`` and its proved bound are the caller's to state.
        None: lengths (the default).
    """

    def __init__(
        self,
        cell: Any,
        config: Any,
        gen: np.random.Generator,
        executor: Executor | None,
        report: Callable[[str, int, int], None],
        exact_max: int,
        subset: NDArray[np.intp] | None = None,
        leg_cost: NDArray[np.float64] | None = None,
    ) -> None:
        self.cell = cell
        self.config = config
        self.gen = gen
        self.executor = executor
        self.report = report
        self.exact_max = exact_max
        ids = tuple(str(i) for i in cell.joints.ids)
        self.index = np.arange(len(ids)) if subset is None else np.asarray(subset, dtype=np.intp)
        self.ids = tuple(ids[k] for k in self.index)
        self.P = np.asarray(cell.joints.xyz, dtype=float).reshape(-1, 3)[self.index]
        self.V = np.asarray(cell.virtual_xyz, dtype=float).reshape(-1, 3)[self.index]
        directions = getattr(cell.joints, "directions", None)
        self.directions = None if directions is None else np.asarray(directions)[self.index]
        self.n = n = len(self.ids)
        self.clearance = float(cell.clearance)
        if n == 0:
            raise PlanningError("the cell has no weld joints")
        self.approach = np.linalg.norm(self.V - self.P, axis=1)
        self.iu, self.ju = np.triu_indices(n, 1)
        self.n_pairs = len(self.iu)
        self.pair_index = -np.ones((n, n), dtype=np.intp)
        self.pair_index[self.iu, self.ju] = np.arange(self.n_pairs)
        self.pair_index[self.ju, self.iu] = np.arange(self.n_pairs)
        self.checked = np.zeros(self.n_pairs, dtype=bool)
        self.free = np.zeros(self.n_pairs, dtype=bool)
        self.paths: dict[int, Any] = {}
        self.t_local = 0.0
        self.t_seq = 0.0
        self.n_failed = 0
        self.rounds = 0
        self.gap_rounds: Any = None  # converge.GapRounds when close_gap ran
        self._shared: Any = None  # the cell as the executor's tasks carry it, made on first use
        self.pso: Any = None
        self.known_first = False
        self.leg_cost = None if leg_cost is None else self._leg_cost(leg_cost, len(ids))

    def _leg_cost(self, leg_cost: Any, n_cell: int) -> NDArray[np.float64]:
        M = np.asarray(leg_cost, dtype=np.float64)
        if M.shape != (n_cell, n_cell) or np.isnan(M).any() or (M < 0).any():
            raise ConfigError(
                f"leg_cost must be a ({n_cell}, {n_cell}) matrix of costs >= 0, got shape "
                f"{M.shape}",
                field="leg_cost",
            )
        return M[np.ix_(self.index, self.index)]

    # ------------------------------------------------------------------ straight checks
    def check(self, pairs: NDArray[np.intp]) -> None:
        """Straight capsule checks of ``pairs`` (one vectorised call); sets checked / free."""
        pairs = pairs[~self.checked[pairs]]
        if not len(pairs):
            return
        a, b = self.V[self.iu[pairs]], self.V[self.ju[pairs]]
        ok = np.all(a == b, axis=1)
        if (~ok).any():
            ok[~ok] = self.cell.collision.segments_free(a[~ok], b[~ok], self.clearance)
        self.free[pairs] = ok
        self.checked[pairs] = True

    def straight_stage(self) -> float:
        """Check the up-front pairs (all, or the candidates), cost every pair by its estimate
        (the straight polyline spot -> virtual -> virtual -> spot, a lower bound of any leg),
        draw one seed per pair. Returns the seconds taken."""
        from weldplan.weld import pairtasks

        t0 = time.perf_counter()
        config, n, iu, ju = self.config, self.n, self.iu, self.ju
        if config.candidates is None or config.candidates >= n - 1:
            self.upfront = np.arange(self.n_pairs)
        else:
            self.upfront = pairtasks.candidate_pairs(
                self.P, config.candidates, self.pair_index, config.candidate_radius
            )
        self.report("straight", 0, len(self.upfront))
        self.check(self.upfront)
        self.report("straight", len(self.upfront), len(self.upfront))
        V, approach = self.V, self.approach
        self.est = approach[iu] + np.linalg.norm(V[iu] - V[ju], axis=1) + approach[ju]
        self.C = np.zeros((n, n))
        self.C[iu, ju] = self.est
        self.C[ju, iu] = self.est
        self.known = self.free.copy()
        self.pair_seeds = self.gen.integers(0, 2**63 - 1, size=self.n_pairs)
        self.blocked = np.flatnonzero(self.checked & ~self.free)
        log.info(
            "%d joints, %d pairs, %d checked, %d blocked at %g mm",
            n,
            self.n_pairs,
            len(self.upfront),
            len(self.blocked),
            self.clearance,
        )
        return time.perf_counter() - t0

    # ------------------------------------------------------------------ local paths
    def plan(self, pairs: list[int]) -> None:
        """Make ``pairs`` known: the straight check first where not done, then a local path
        for each blocked one (through the executor); the costs follow."""
        from weldplan.weld import pairtasks

        t = time.perf_counter()
        config, iu, ju = self.config, self.iu, self.ju
        fresh = np.array([p for p in pairs if not self.checked[p]], dtype=np.intp)
        if len(fresh):  # on demand: the straight segment first (timed with the local stage)
            self.check(fresh)
            self.known[fresh] = self.free[fresh]
        todo = [p for p in pairs if not self.known[p]]
        total = len(self.paths) + len(todo)
        self.report("local", len(self.paths), total)
        cell_index = self.index
        args = [
            (
                int(cell_index[iu[p]]),
                int(cell_index[ju[p]]),
                config.planner,
                dict(config.aco),
                int(self.pair_seeds[p]),
            )
            for p in todo
        ]
        if self.executor is None:
            results: Any = (
                pairtasks._plan_pair_task(self.cell, i, j, m, prm, s, config.local_time_budget)
                for i, j, m, prm, s in args
            )
        else:
            results = self._submit(args)
        for p, lp in zip(todo, results, strict=True):
            self._record(p, lp)
            self.report("local", len(self.paths), total)
        self.t_local += time.perf_counter() - t

    def _submit(self, args: list[tuple]) -> Any:
        """The local paths of ``args`` from the executor, in order (batches of pairs)."""
        from weldplan.weld import pairtasks
        from weldplan.weld.parallel import batches, n_workers, share_cell

        if self._shared is None:
            self._shared = share_cell(self.cell, self.executor)
        budget = self.config.local_time_budget
        futures = [
            self.executor.submit(pairtasks._plan_pairs_task, self._shared, batch, budget)  # type: ignore[union-attr]
            for batch in batches(args, n_workers(self.executor), PAIR_BATCH_MAX)
        ]
        return (lp for f in futures for lp in f.result())

    def _record(self, p: int, lp: Any) -> None:
        """Store the local path of pair ``p``; its cost, infinite when the search failed."""
        self.paths[int(p)] = lp
        self.known[p] = True
        i, j = self.iu[p], self.ju[p]
        ok = bool(getattr(lp, "success", True)) and np.isfinite(lp.length)
        if not ok:
            self.n_failed += 1
            log.info(
                "no local path %s -> %s: %s", self.ids[i], self.ids[j], getattr(lp, "reason", "")
            )
        self.C[i, j] = self.C[j, i] = lp.length if ok else np.inf

    # ------------------------------------------------------------------ sequencing
    def _stranded_check(self) -> None:
        """Raise when a joint has no finite leg to any other joint."""
        n, C, ids = self.n, self.C, self.ids
        off = ~np.eye(n, dtype=bool)
        stranded = [ids[k] for k in range(n) if n > 1 and not np.isfinite(C[k][off[k]]).any()]
        if stranded:
            raise UnreachableJointsError(
                f"no collision-free path from joint(s) {', '.join(stranded)} to any other joint "
                f"at {self.clearance:g} mm clearance (planner {self.config.planner}); failed "
                "pairs: "
                + ", ".join(
                    f"{ids[self.iu[p]]}-{ids[self.ju[p]]}"
                    for p in sorted(self.paths)
                    if not np.isfinite(C[self.iu[p], self.ju[p]])
                ),
                stranded=stranded,
            )

    def cost_matrix(self) -> NDArray[np.float64]:
        """The matrix the sequencer minimises: ``C`` (mm), or ``leg_cost`` where ``C`` is finite
        (a failed leg stays infinite)."""
        if self.leg_cost is None:
            return self.C
        return np.where(np.isfinite(self.C), self.leg_cost, np.inf)

    def _sequencing_costs(self, method: str) -> NDArray[np.float64]:
        """The cost matrix the sequencer sees: with ``known_first``, an unknown leg costs its
        estimate plus a penalty larger than any route over known legs."""
        base = self.cost_matrix()
        if not (self.known_first and method not in ("exact", "fast-tsp")):
            return base  # fast-tsp avoids unknown legs instead (``sequence``)
        iu, ju, n = self.iu, self.ju, self.n
        off = ~self.known
        finite = base[iu[self.known], ju[self.known]]
        finite = finite[np.isfinite(finite)]
        est = self.est if self.leg_cost is None else base[iu, ju][np.isfinite(base[iu, ju])]
        penalty = (n - 1) * float(finite.max() if len(finite) else est.max(initial=0.0)) + 1.0
        Cs = base.copy()
        Cs[iu[off], ju[off]] += penalty
        Cs[ju[off], iu[off]] += penalty
        return Cs

    def sequence(
        self, round_: int, method: str, initial: list[int] | None = None, kicks: int = 0
    ) -> Any:
        """One run of the sequencer over the current costs (warm from ``initial`` if given)."""
        from weldplan.optim.discrete.costs import order_cost
        from weldplan.optim.discrete.local_search import PolishParams
        from weldplan.optim.discrete.sequence import SequenceSettings, solve_sequence

        t = time.perf_counter()
        self._stranded_check()
        self.report("sequence", round_, round_ + 1)
        config = self.config
        try:
            settings = SequenceSettings(
                method=method,
                polish=config.polish,
                pso=self.pso,
                polish_params=None if initial is None else PolishParams(kicks=kicks),
                time_budget=config.sequence_time_budget,
            )
            avoid = None
            if self.known_first and method == "fast-tsp":
                avoid = ~self.known[self.pair_index] & (self.pair_index >= 0)
            Cs = self._sequencing_costs(method)
            seq = solve_sequence(Cs, settings, rng=self.gen, initial=initial, avoid=avoid)
            if Cs is not self.C:
                seq = replace(seq, cost=float(order_cost(self.C, np.asarray(seq.order), False)))
        except PlanningError as exc:
            raise explain_no_order(
                exc, self.C, self.known, self.iu, self.ju, self.paths, self.ids
            ) from exc
        self.t_seq += time.perf_counter() - t
        self.report("sequence", round_ + 1, round_ + 1)
        return seq

    def settle(self, method: str) -> Any:
        """Sequence, plan the unknown legs of the order, repeat until it uses known legs only."""
        from weldplan.optim.discrete.sequence import resolve_method

        config, n = self.config, self.n
        method = resolve_method(method, n)
        warm = (
            config.warm_rounds
            and config.polish
            and method not in ("exact", "fast-tsp")  # fast-tsp has no warm start
            and n > self.exact_max
        )
        full_kicks = n if config.warm_kicks is None else int(config.warm_kicks)
        previous = None
        kicks = full_kicks
        while True:
            seq = self.sequence(self.rounds, method, previous, kicks)
            self.rounds += 1
            order = list(seq.order)
            needed = [
                int(self.pair_index[a, b]) for a, b in zip(order[:-1], order[1:], strict=True)
            ]
            unknown = [p for p in needed if not self.known[p]]
            if warm:
                if not unknown and previous is not None and kicks < full_kicks:
                    # settled with descents only: one polish with kicks before accepting it
                    previous, kicks = order, full_kicks
                    continue
                previous, kicks = order, 0
            if not unknown:
                return seq
            if self.rounds >= config.max_rounds and config.candidates is None:
                log.warning("lazy planning: %d rounds, planning every blocked pair", self.rounds)
                unknown = [int(p) for p in self.blocked]
            elif config.demand_neighbours and n > self.exact_max:
                unknown = sorted(set(unknown) | set(self.near_unknown(unknown)))
            self.plan(unknown)

    def near_unknown(self, pairs: list[int]) -> list[int]:
        """The unknown pairs of each end of ``pairs`` to its ``demand_neighbours`` nearest joints
        by current cost (the moves the sequencer's polish tries next)."""
        iu, ju, n = self.iu, self.ju, self.n
        ends = np.unique(np.concatenate([iu[pairs], ju[pairs]]))
        k = min(int(self.config.demand_neighbours), n - 1)
        near = np.argsort(self.C[ends], axis=1, kind="stable")[:, : k + 1]
        cand = self.pair_index[np.repeat(ends, k + 1), near.ravel()]
        cand = cand[cand >= 0]
        return [int(p) for p in np.unique(cand) if not self.known[p]]

    def run(self) -> Any:
        """The rounds after the straight stage: the up-front plans, Held-Karp discovery rounds
        on small cells, then the configured sequencer until its order uses known legs only.
        Returns the final ``Sequence``."""
        from weldplan.optim.discrete.tsp_pso import PSOParams

        config, n = self.config, self.n
        self.pso = PSOParams(**config.pso) if config.pso else None
        self.known_first = (
            config.known_first and config.candidates is not None and n > self.exact_max
        )
        if config.pairs == "all" or config.candidates is not None:
            self.plan([int(p) for p in self.blocked])
        if config.sequencer != "exact" and n <= self.exact_max and not self.known.all():
            # discovery rounds with Held-Karp (fast at this size) find the legs good orders use,
            # so the configured (slower) sequencer usually runs once
            self.settle("exact")
        seq = self.settle(config.sequencer)
        return self.close_gap(seq)

    def close_gap(self, seq: Any) -> Any:
        """With fast-tsp or nn above Held-Karp size in the lazy mode: plan the legs that optimistic
        orders use until the route is within ``config.gap_target`` of one
        (:func:`weldplan.weld.converge.close_gap`); ``self.gap_rounds`` records the rounds."""
        from weldplan.optim.discrete.sequence import (
            SequenceSettings,
            resolve_method,
            solve_sequence,
        )
        from weldplan.weld.converge import close_gap

        config = self.config
        if (
            config.gap_target is None
            or self.leg_cost is not None  # its optimistic orders are over lengths
            or resolve_method(config.sequencer, self.n) not in ("fast-tsp", "nn")
            or config.pairs != "lazy"
            or self.n <= self.exact_max
        ):
            return seq
        settings = SequenceSettings(
            method=resolve_method(config.sequencer, self.n),
            time_budget=config.sequence_time_budget,
        )
        seq, self.gap_rounds = close_gap(
            seq,
            self.C,
            self.known,
            self.pair_index,
            optimistic=lambda Cb: solve_sequence(Cb, settings, rng=self.gen),
            plan=self.plan,
            resequence=lambda: self.settle(config.sequencer),
            near=self.near_unknown,
            target=config.gap_target,
            max_rounds=config.gap_rounds,
        )
        return seq


def explain_no_order(
    exc: Exception,
    C: NDArray[np.float64],
    known: NDArray[np.bool_],
    iu: NDArray[np.intp],
    ju: NDArray[np.intp],
    paths: dict[int, Any],
    ids: tuple[str, ...],
) -> PlanningError:
    """An error a user can act on when no order of finite cost exists.

    When the joints fall into groups with no collision-free path between them (typically spots
    on both sides of a panel, or one enclosed), an :class:`UnreachableJointsError` names the
    groups (largest first); else a :class:`PlanningError` lists the failed pairs.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(ids)
    reach = ~known | np.isfinite(C[iu, ju])  # unknown pairs might still be reachable
    A = coo_matrix((np.ones(int(reach.sum())), (iu[reach], ju[reach])), shape=(n, n))
    k, label = connected_components(A, directed=False)
    if k > 1:
        members = [np.flatnonzero(label == g) for g in range(k)]
        groups_text = ["{" + ", ".join(ids[v] for v in m) + "}" for m in members]
        # largest group first; ties keep the group of the earlier joint first
        by_size = sorted(members, key=lambda m: (-len(m), int(m[0])))
        return UnreachableJointsError(
            f"the joints fall into {k} groups with no collision-free path between them at this "
            f"clearance (spots on both sides of a panel, or enclosed?): {' '.join(groups_text)}",
            groups=[[ids[v] for v in m] for m in by_size],
        )
    failed = [f"{ids[iu[p]]}-{ids[ju[p]]}" for p in paths if not np.isfinite(C[iu[p], ju[p]])]
    return PlanningError(f"{exc}; local planning failed for pairs {', '.join(failed) or 'none'}")
