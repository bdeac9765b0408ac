"""The least-rotation choice of one pose per weld among the free candidates, with an optional
acceptance test that knows what comes after the weld.

:func:`choose` runs the dynamic programme of :func:`~weldplan.tool.poses.least_rotation_choice`
over the candidates not known to fail, measuring clearances lazily (:func:`_first_free`), and
re-checks every pick independently (:class:`~weldplan.tool.verify.PoseChecker`).

**Acceptance** (``accept``): a free pose can still be a poor one: no exit may leave it (the gun
cannot retract, slide or step sideways off the weld), or the robot cannot reach it (joint limit,
links in the part). ``accept(i, T)`` judges weld ``i``'s pick with TCP pose ``T (4, 4)`` (mm,
part frame) after it has passed the re-check, and returns ``None`` to accept it or a short reason
to veto it. A vetoed candidate leaves its weld's set and the choice is made again, so the answer
is the least-rotation choice over the free *accepted* candidates. The test is a preference, not a
constraint: a weld whose free candidates are all vetoed, or that reaches ``max_vetoes`` vetoes,
is **exhausted**: its vetoes are lifted, it takes the least-rotation free pose as without the
test, and the reasons are kept (:attr:`ChoiceState.veto_reasons`) for its report. ``accept`` is
called only on picks (never on every candidate) and at most once per candidate.

**Batch vetoes** (optional): a test that is cheap on many poses at once (the robot's reach: one
vectorised IK) may carry ``accept.verdicts(T (m, 4, 4)) -> list[str | None]``. When a weld's
pick is vetoed for the first time, every other candidate of that weld still in the running is
judged by it in one call, and those it vetoes leave the weld's set at once (without a DP round
each, and without counting against ``max_vetoes``); those it passes are still judged by
``accept`` when picked. Without it a weld whose first few hundred least-rotation poses all fail
(the demo's welds 13 and 15: every approach-side pose needs A5 > 125 deg) would only take
``max_vetoes`` of them before the test is lifted. :func:`all_of` keeps the ``verdicts`` of the
tests that have one (a veto of any test is a veto of all).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.tool.poses.orient import least_rotation_choice, rotation_angles
from weldplan.tool.poses.search import PoseSearch
from weldplan.tool.settings import DEFAULT_MAX_VETOES
from weldplan.tool.verify.poses import PoseCheck

log = logging.getLogger(__name__)

#: ``accept(i, T)``: ``None`` accepts weld ``i``'s candidate with TCP pose ``T (4, 4)`` mm, a
#: string vetoes it and says why
Accept = Callable[[int, NDArray[np.float64]], "str | None"]


class Recheck(Protocol):
    """The independent re-check of one pose (:class:`~weldplan.tool.verify.PoseChecker`,
    or :class:`~weldplan.tool.poses.Rechecks` that keeps its verdicts)."""

    def check(self, position: NDArray[np.float64], quaternion: NDArray[np.float64]) -> PoseCheck:
        """The verdict on the TCP at ``position (3,)`` mm, ``quaternion`` wxyz."""
        ...


#: candidates of one weld judged at once while looking for its first free one: the first chunk
#: and the largest (each chunk twice the last: most welds find one among their first few)
MEASURE_CHUNK = (2, 32)


def _first_free(
    i: int,
    ref: NDArray[np.float64],
    dists: NDArray[np.float64],
    allowed: NDArray[np.bool_],
    rots: NDArray[np.float64],
    quats: NDArray[np.float64],
    search: PoseSearch,
    obj: fcl.CollisionObject | None,
    p: NDArray[np.float64],
) -> int:
    """Measure weld ``i``'s unmeasured candidates in order of their summed rotation to ``ref
    (r, 4)`` (the neighbours' current picks) until one keeps the clearance; returns the count.

    The order only decides which measurements come first: the DP that runs next still sees every
    candidate not known to fail, so the final choice is the same optimum (see :func:`choose`).
    The candidates are judged by :meth:`PoseSearch.clearances` in chunks of growing size
    (:data:`MEASURE_CHUNK`; its sphere bounds are vectorised over a chunk), and only up to the
    first free one, as one at a time would: what the choice learns is the same.
    """
    todo = np.flatnonzero(np.isnan(dists[i]) & allowed[i])
    cost = rotation_angles(quats[i, todo], ref).sum(axis=1)
    todo = todo[np.argsort(cost, kind="stable")]
    n = start = 0
    size = MEASURE_CHUNK[0]
    while start < len(todo):
        ks = todo[start : start + size]
        start, size = start + size, min(2 * size, MEASURE_CHUNK[1])
        vals = search.clearances(
            [obj] * len(ks), np.tile(p, (len(ks), 1)), rots[i, ks], first_free=True
        )
        got = ~np.isnan(vals)
        dists[i, ks[got]] = vals[got]
        n += int(got.sum())
        if np.any(vals[got] >= search.clearance):
            break
    return n


@dataclass(frozen=True)
class Candidates:
    """The welds of one pose search and their candidate orientations.

    Attributes
    ----------
    xyz
        ``(n, 3)`` mm: the weld spots, in route order.
    ids
        The welds' names (for the log).
    rots, quats
        ``(n, c, 3, 3)`` and ``(n, c, 4)`` (wxyz): each weld's candidate TCP orientations.
    own
        ``(n, c, 4)``: the same orientations in the part's own frame, whose rotation angles the
        choice minimises (``None``: ``quats``, the part frame is the planning frame). The
        angles do not depend on the frame, but their rounding does: measured in the part frame,
        the choice among equal rotations is the same wherever the part stands in the cell.
    """

    xyz: NDArray[np.float64]
    ids: tuple[str, ...]
    rots: NDArray[np.float64]
    quats: NDArray[np.float64]
    own: NDArray[np.float64] | None = None


class ChoiceState:
    """What :func:`choose` learns that stays true across calls: poses the re-check rejected or
    passed, the acceptance test's verdicts, and counts."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.rejected = np.zeros(shape, dtype=bool)
        self.passed: set[tuple[int, int]] = set()
        #: candidates the acceptance test vetoed (lifted for exhausted welds)
        self.vetoed = np.zeros(shape, dtype=bool)
        #: candidates the acceptance test accepted
        self.accepted: set[tuple[int, int]] = set()
        #: weld -> the reasons its vetoed candidates were given, in the order tried
        self.veto_reasons: dict[int, list[str]] = {}
        #: welds for which the test was lifted (every free candidate vetoed, or too many vetoes)
        self.exhausted: set[int] = set()
        self.counts = {
            "distance_queries": 0,
            "recheck_rejected": 0,
            "choice_rounds": 0,
            "accept_calls": 0,
            "vetoed": 0,
            "batch_judged": 0,
            "batch_vetoed": 0,
        }
        #: weld -> vetoes it had when it was reopened (its budget counts from there)
        self.veto_base: dict[int, int] = {}
        self._lifted: dict[int, NDArray[np.bool_]] = {}
        #: per pair of welds: each candidate's row and column in the cached angle matrix
        #: (``(c,)``, -1 where not cached) and the matrix
        self._angles: dict[tuple[int, int], tuple[NDArray, NDArray, NDArray]] = {}
        #: per pair of welds: the sets of the last cut from that matrix, and the cut
        self._cut: dict[tuple[int, int], tuple[NDArray, NDArray, NDArray]] = {}
        #: welds whose candidates ``accept.verdicts`` has judged in one batch (module docstring)
        self.batched: set[int] = set()

    def angles(
        self, quats: NDArray, i: int, ci: NDArray[np.int64], j: int, cj: NDArray[np.int64]
    ) -> NDArray[np.float64]:
        """``(len(ci), len(cj))`` degrees between candidates ``ci`` of weld ``i`` and ``cj`` of
        weld ``j``, cut from a matrix cached per pair of welds (the DP's rounds shrink the
        candidate sets; the angles do not change)."""
        hit = self._angles.get((i, j))
        if hit is not None:
            a, b, m = hit
            pa, pb = a[ci], b[cj]  # positions in the cached matrix (-1: not cached)
            if len(pa) and len(pb) and pa.min() >= 0 and pb.min() >= 0:
                if len(pa) == len(m) and len(pb) == m.shape[1]:
                    return m  # the same sets (subsets of the cached ones, as many)
                last = self._cut.get((i, j))
                if last is not None and np.array_equal(last[0], ci) and np.array_equal(last[1], cj):
                    return last[2]  # the sets of the last round: most welds' do not change
                cut = m[np.ix_(pa, pb)]
                self._cut[(i, j)] = (ci.copy(), cj.copy(), cut)
                return cut
        m = rotation_angles(quats[i, ci], quats[j, cj])
        a = np.full(quats.shape[1], -1, dtype=np.int64)
        b = np.full(quats.shape[1], -1, dtype=np.int64)
        a[ci], b[cj] = np.arange(len(ci)), np.arange(len(cj))
        self._angles[(i, j)] = (a, b, m)
        return m

    def exhaust(self, i: int) -> None:
        """Lift the acceptance test for weld ``i``."""
        self.exhausted.add(i)
        self._lifted[i] = self.vetoed[i] | self._lifted.get(i, False)
        self.vetoed[i] = False

    def reopen(self, i: int) -> None:
        """Put the acceptance test back on exhausted weld ``i`` (more candidates joined it: a
        C-gun's turned-over poses): its vetoes return and it may take ``max_vetoes`` more."""
        self.exhausted.discard(i)
        if i in self._lifted:
            self.vetoed[i] |= self._lifted.pop(i)
        self.veto_base[i] = len(self.veto_reasons.get(i, []))
        self.batched.discard(i)


def _pose(p: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def _batch(
    i: int,
    live: NDArray[np.bool_],
    xyz: NDArray[np.float64],
    rots: NDArray[np.float64],
    verdicts: Callable[[NDArray[np.float64]], list],
    state: ChoiceState,
) -> None:
    """Judge weld ``i``'s candidates still in the running (``live (c,)``) with
    ``accept.verdicts`` in one call; veto those it vetoes (module docstring)."""
    state.batched.add(i)
    cand = np.flatnonzero(live & ~state.vetoed[i])
    if len(cand) == 0:
        return
    T = np.tile(np.eye(4), (len(cand), 1, 1))
    T[:, :3, :3] = rots[i, cand]
    T[:, :3, 3] = xyz[i]
    out = verdicts(T)
    bad = cand[[r is not None for r in out]]
    state.vetoed[i, bad] = True
    # kept for the weld's note, not counted against max_vetoes
    state.veto_reasons.setdefault(i, []).extend(str(r) for r in out if r is not None)
    state.veto_base[i] = state.veto_base.get(i, 0) + len(bad)
    state.counts["batch_judged"] += len(cand)
    state.counts["batch_vetoed"] += len(bad)


def _judge(
    choice: dict[int, int],
    xyz: NDArray[np.float64],
    rots: NDArray[np.float64],
    accept: Accept,
    state: ChoiceState,
    max_vetoes: int,
    live: NDArray[np.bool_],
) -> bool:
    """Run ``accept`` on the picks it has not judged; True when any was vetoed. ``live (n, c)``:
    the candidates still in the running (for a batch, module docstring)."""
    vetoed = False
    verdicts = getattr(accept, "verdicts", None)
    for i, k in choice.items():
        if i in state.exhausted or (i, k) in state.accepted:
            continue
        state.counts["accept_calls"] += 1
        reason = accept(i, _pose(xyz[i], rots[i, k]))
        if reason is None:
            state.accepted.add((i, k))
            continue
        state.counts["vetoed"] += 1
        state.vetoed[i, k] = vetoed = True
        reasons = state.veto_reasons.setdefault(i, [])
        reasons.append(str(reason))
        if len(reasons) - state.veto_base.get(i, 0) >= max_vetoes:
            state.exhaust(i)
        elif verdicts is not None and i not in state.batched:
            _batch(i, live[i], xyz, rots, verdicts, state)
    return vetoed


def choose(
    cands: Candidates,
    dists: NDArray[np.float64],
    allowed: NDArray[np.bool_],
    search: PoseSearch,
    objs: list[fcl.CollisionObject | None],
    checker: Recheck,
    state: ChoiceState,
    *,
    accept: Accept | None = None,
    max_vetoes: int = DEFAULT_MAX_VETOES,
) -> tuple[dict[int, int], float]:
    """The least-rotation choice over the free (and accepted) candidates, measuring clearances
    lazily.

    ``cands``: the welds and their candidate rotations (:class:`Candidates`). ``dists (n, c)``
    holds 0 for colliding candidates and NaN where the clearance is not measured yet; it is
    filled in place, with :meth:`PoseSearch.clearances` (at least the clearance exactly where a
    candidate keeps it; a bound, not the distance). Only ``allowed (n, c)`` candidates take
    part. The DP runs over every candidate not known to fail; each chosen candidate whose
    clearance is unknown is measured (all of them at once), and a weld whose choice falls short
    has its other candidates measured, least rotation from its neighbours' picks first, up to
    the first that keeps the clearance (:func:`_first_free`),
    before the DP runs again. When every chosen candidate is known to be free, each passes the
    independent re-check or is dropped and the DP runs again; then each must pass ``accept``
    (module docstring) or is vetoed and the DP runs again. The answer is the DP's optimum over
    the truly free, accepted candidates (exhausted welds: over their free ones): every candidate
    it picks has been measured, and the candidates it passed over can only make the optimum over
    a superset no worse. Every round that does not return measures, rejects or vetoes at least
    one candidate, so the rounds are bounded.

    Returns the chosen candidate per weld index (welds with none free are absent) and the summed
    rotation (deg); counts go to ``state``.
    """
    xyz, ids, rots, quats = cands.xyz, cands.ids, cands.rots, cands.quats
    own = quats if cands.own is None else cands.own  # the DP's angles (Candidates)
    clearance = search.clearance
    counts = state.counts
    for _ in range(3 * dists.size + 1):
        counts["choice_rounds"] += 1
        free = allowed & ~state.rejected & ~(dists == 0) & ~(dists < clearance)  # NaN: kept
        for i in np.flatnonzero(free.any(axis=1) & ~(free & ~state.vetoed).any(axis=1)):
            state.exhaust(int(i))  # every candidate left was vetoed: lift the test
        ok = free & ~state.vetoed
        welds_ok = [i for i in range(len(dists)) if ok[i].any()]
        cand = [np.flatnonzero(ok[i]) for i in welds_ok]
        pick, total = least_rotation_choice(
            [own[i, c] for i, c in zip(welds_ok, cand, strict=True)],
            lambda k, w=welds_ok, c=cand: state.angles(own, w[k - 1], c[k - 1], w[k], c[k]),
        )
        choice = {i: int(c[j]) for i, c, j in zip(welds_ok, cand, pick, strict=True)}
        todo = [(i, k) for i, k in choice.items() if np.isnan(dists[i, k])]
        if todo:
            wi, ki = np.array(todo).T
            dists[wi, ki] = search.clearances([objs[i] for i in wi], xyz[wi], rots[wi, ki])
            counts["distance_queries"] += len(todo)
        short = [i for i, k in todo if dists[i, k] < clearance]
        if short:
            chain = list(choice)  # the welds with a pick, in route order
            for i in short:
                j = chain.index(i)
                nbrs = [chain[m] for m in (j - 1, j + 1) if 0 <= m < len(chain)]
                ref = own[nbrs, [choice[m] for m in nbrs]] if nbrs else own[i, [choice[i]]]
                counts["distance_queries"] += _first_free(
                    i, ref, dists, allowed, rots, own, search, objs[i], xyz[i]
                )
            continue
        if _recheck(choice, xyz, ids, quats, checker, state):
            continue
        live = allowed & ~state.rejected & ~(dists < clearance)  # NaN: kept
        if accept is not None and _judge(choice, xyz, rots, accept, state, max_vetoes, live):
            continue
        return choice, total
    raise RuntimeError("the pose choice did not settle: the re-check keeps rejecting poses (a bug)")


def _recheck(
    choice: dict[int, int],
    xyz: NDArray[np.float64],
    ids: tuple[str, ...] | list[str],
    quats: NDArray[np.float64],
    checker: Recheck,
    state: ChoiceState,
) -> bool:
    """Re-check the picks not yet passed; True when any was rejected (dropped for good)."""
    bad = False
    for i, k in choice.items():
        if (i, k) in state.passed:
            continue
        out = checker.check(xyz[i], quats[i, k])
        if out.ok:
            state.passed.add((i, k))
        else:
            log.warning("weld %s: the re-check rejected a pose: %s", ids[i], out.reason)
            state.rejected[i, k] = True
            state.counts["recheck_rejected"] += 1
            bad = True
    return bad


def all_of(*tests: Accept | None) -> Accept | None:
    """One acceptance test that vetoes with the first of ``tests`` that vetoes (``None``s are
    skipped; put the cheap tests first). ``None`` when no test is given."""
    kept = [t for t in tests if t is not None]
    if not kept:
        return None
    if len(kept) == 1:
        return kept[0]

    def accept(i: int, T: NDArray[np.float64]) -> str | None:
        for t in kept:
            reason = t(i, T)
            if reason is not None:
                return reason
        return None

    batch = [v for v in (getattr(t, "verdicts", None) for t in kept) if v is not None]
    if batch:

        def verdicts(T: NDArray[np.float64]) -> list[str | None]:
            out: list[str | None] = [None] * len(T)
            for v in batch:
                todo = [k for k, r in enumerate(out) if r is None]
                if not todo:
                    break
                for k, r in zip(todo, v(T[todo]), strict=True):
                    out[k] = r
            return out

        accept.verdicts = verdicts  # type: ignore[attr-defined]
    return accept
