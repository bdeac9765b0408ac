"""The allocate-plan-interference passes of a station of several robots (issue 30, item 4).

:func:`weldplan.multi.station.plan_station` builds, after the robots' studies, the conflict
table of their rests (:mod:`weldplan.multi.conflicts`) and hands over to
:func:`plan_and_repair`:

1. the allocation serves no weld from a robot that meets another robot at its home there when
   another robot serves it (:func:`weldplan.multi.conflicts.home_forbidden`), and charges every
   pair of welds of two robots that meet at rest (:class:`~weldplan.multi.allocate.PairCost`,
   :data:`CONFLICT_S`), so that shares that cross cost more than shares side by side;
2. the shares are planned and calibrated over rounds (:func:`allocate_and_plan`,
   :mod:`weldplan.multi.calibrate`);
3. the interference stage (:func:`weldplan.multi.station.interfere`) orders every conflict it
   can by interlocks; the conflicts no interlock orders (e.g. a robot's move through another
   robot's column, which it holds at every weld) are mapped to their welds
   (:func:`weldplan.multi.conflicts.blamed`), each kept away from the robot that met the other
   there (the moving one's first, when another robot serves it), and steps 1-3 run again, at
   most :data:`REPAIRS` times; a share planned in any pass is not planned again.

A conflict neither ordered nor re-allocated is said in the interference line, naming the
robots and the welds; the replay then fails and says where (the plan is kept whole).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from weldplan.multi.inputs import StudyInputs
from weldplan.multi.problem import AllocationSettings
from weldplan.multi.result import AllocationReport
from weldplan.multi.schedule import ReplayVerdict, StationSchedule

log = logging.getLogger(__name__)

#: re-allocations after the interference stage: each keeps the welds of the conflicts no
#: interlock orders away from the robot that met the other there, and plans again
REPAIRS = 2
#: s charged to each of two robots per pair of their welds that meet at rest (the allocation's
#: :class:`~weldplan.multi.allocate.PairCost`): at least the other's weld as a wait
CONFLICT_S = 0.5


@dataclass(eq=False)
class Context:
    """What the allocate-plan-interference passes of :func:`plan_station` share: the inputs,
    the settings, the clocks and the plans made so far (``cache``: per ``(robot, sorted weld
    ids)``, so that a share planned in one pass is not planned again in the next)."""

    station: Any
    robots: list[Any]
    inp: StudyInputs
    seed: int | None
    settings: AllocationSettings
    executor: Any
    progress: Callable[[str, int, int], None] | None
    seconds: dict[str, float]
    table: Any
    interfere: Callable[..., tuple[Any, ...]]
    cache: dict[tuple[int, tuple[str, ...]], Any] = field(default_factory=dict)
    cpu: dict[str, float] = field(default_factory=dict)
    ran: list[str] = field(default_factory=list)
    bound: Any = None


@dataclass(frozen=True, eq=False)
class _Passed:
    """The pass :func:`_plan_and_repair` keeps."""

    plans: list[Any]
    report: AllocationReport
    rounds: tuple[Any, ...]
    schedule: StationSchedule
    replay: ReplayVerdict
    line: str
    conflicts: dict[str, Any]


def rested(robots: list[Any], studies: list[Any], homes: list[Any]) -> list[Any]:
    """Per robot its :class:`~weldplan.multi.conflicts.RestedRobot`: at its study base, its
    home and the study's configuration at each weld it serves (NaN elsewhere)."""
    from weldplan.multi.conflicts import RestedRobot

    out = []
    for k, ((_, mounted, robot), study) in enumerate(zip(robots, studies, strict=True)):
        q = np.full((len(study.spots), 6), np.nan)
        for i, spot in enumerate(study.spots):
            v = spot.robots[0]
            if v.ok and v.q is not None:
                q[i] = v.q
        placed = robot.with_base(study.robots[0].base_matrix())
        out.append(RestedRobot(f"robot{k + 1}", placed, np.radians(homes[k]), q,
                               mounted.tool, mounted.flange_tcp))  # fmt: skip
    return out


def plan_and_repair(ctx: Context) -> _Passed:
    """Allocate and plan (:func:`_allocate_and_plan`), check the interference
    (``ctx.interfere``: :func:`weldplan.multi.station.interfere`), and while conflicts no
    interlock orders are left (at most :data:`REPAIRS` times) keep each one's weld away from
    the robot that met the other there (the moving robot's first, where another robot serves
    it) and again; the pass with the fewest such conflicts is kept (the later on a tie). A
    conflict neither ordered nor re-allocated is said in the interference line, naming the
    robots and the welds. A robot's share that has no plan (:class:`~weldplan.multi.shares.
    ShareFailed`: e.g. none of its welds joined to its home) costs that robot those welds, not
    the station: they are kept from it, with the pipeline's words, and the station allocated
    again (at most once per robot); the interference line names it."""
    from weldplan.multi.allocate import PairCost
    from weldplan.multi.conflicts import home_forbidden
    from weldplan.multi.shares import ShareFailed

    ok = np.asarray(ctx.inp.reach.ok, dtype=bool)
    forbid = home_forbidden(ctx.table, ok)
    at_home = len(forbid)
    cost = PairCost(ctx.table.pair, CONFLICT_S)
    best: tuple[Any, ...] | None = None
    failed: list[str] = []
    k = n_failed = 0
    while True:
        try:
            plans, report, rounds = _allocate_and_plan(ctx, forbid, cost)
        except ShareFailed as exc:  # that robot's share has no plan: its welds go elsewhere
            new = _share_failed(exc, ctx, forbid)
            if not new or len(failed) >= len(ctx.robots):
                raise
            failed.append(f"robot{exc.k + 1} ({len(new)} welds: {exc.message})")
            log.warning("station: robot %d's share failed, re-allocated: %s", exc.k + 1, exc)
            forbid, n_failed = {**forbid, **new}, n_failed + len(new)
            continue
        names = report.ours.robots
        (ctx.progress or (lambda *a: None))("interference", 0, len(ctx.robots))
        got = ctx.interfere(ctx.station, plans, names, ctx.seconds)
        if best is None or len(got[4]) <= len(best[1][4]):
            best = (report, got, rounds, dict(forbid))
        new = _repairs(got[4], ok, forbid, report.ours.welds, names)
        if not got[4] or not new or k == REPAIRS:
            break
        log.info("station: re-allocation %d keeps %d welds away from a robot", k + 1, len(new))
        forbid = {**forbid, **new}
        k += 1
    report, (plans, schedule, replay, line, left), rounds, forbid = best
    said = [
        ctx.table.line(), f"{at_home} kept from a robot that meets another at its home",
        f"{len(forbid) - at_home - n_failed} re-allocated after the interference ({k + 1} passes)",
    ]  # fmt: skip
    if failed:
        said.append(f"shares with no plan, re-allocated: {'; '.join(failed)}")
    if left:
        said.append(f"NOT ordered nor re-allocated: {_left_line(left, names)}")
    stats = {"at_home": at_home, "repaired": len(forbid) - at_home - n_failed, "passes": k + 1,
             "pairs_kept": report.ours.stats.get("conflict_pairs", 0),
             "left": [list(x) for x in left], "failed": failed}  # fmt: skip
    return _Passed(plans, report, rounds, schedule, replay, f"{line}; {'; '.join(said)}", stats)


def _share_failed(
    exc: Any, ctx: Context, forbid: dict[tuple[int, int], str]
) -> dict[tuple[int, int], str]:
    """``{(robot, weld): reason}``: every weld of the share ``exc``
    (:class:`~weldplan.multi.shares.ShareFailed`) kept from its robot, the pipeline's words
    as the reason (a weld no other robot serves is then listed unreached with them)."""
    pos = {w: i for i, w in enumerate(ctx.inp.reach.welds)}
    why = f"its share had no plan: {exc.message}"
    return {(exc.k, pos[w]): why for w in exc.welds if w in pos and (exc.k, pos[w]) not in forbid}


def _repairs(
    left: list[tuple[int, str, int, str]], ok: Any, forbid: dict[tuple[int, int], str],
    welds: tuple[str, ...], names: tuple[str, ...],
) -> dict[tuple[int, int], str]:  # fmt: skip
    """``{(robot, weld): reason}``: per conflict of ``left`` (the robot listed first moved),
    its weld kept away from that robot where another robot serves it and is not kept from
    it, else the other robot's weld likewise; none for a conflict neither can give away."""
    pos = {w: i for i, w in enumerate(welds)}
    new: dict[tuple[int, int], str] = {}
    for a, wa, b, wb in left:
        for r, w, other, wo in ((a, wa, b, wb), (b, wb, a, wa)):
            i = pos.get(w)
            if i is None or (r, i) in forbid or (r, i) in new:
                continue
            takers = [s for s in range(len(ok)) if s != r and ok[s, i] and (s, i) not in forbid]
            if takers:
                at = f" at weld {wo}" if wo else " at its home"
                new[(r, i)] = f"at this weld it meets {names[other]}{at}: no interlock orders it"
                break
    return new


def _left_line(left: list[tuple[int, str, int, str]], names: tuple[str, ...]) -> str:
    """One line naming the robots and welds of the conflicts left (at most 5)."""
    said = [f"{names[a]} at {wa or 'home'} / {names[b]} at {wb or 'home'}"
            for a, wa, b, wb in dict.fromkeys(left)]  # fmt: skip
    more = f" and {len(said) - 5} more" if len(said) > 5 else ""
    return "; ".join(said[:5]) + more


def _tcp_bounds(robots: list[Any], inp: StudyInputs) -> tuple[Any, Any]:
    """``((R, W, W) s, (R, W) s)``: per robot the pose-free bounds of its legs between the
    welds and between its home and each weld (:func:`weldplan.multi.bound.pose_free_legs`:
    the TCP's distance and axis 1's turn, whatever gun poses the plans pick); each robot's
    home is its settings' (``multi.station.with_homes`` gave every robot one)."""
    from weldplan.multi.bound import pose_free_legs

    legs = [
        pose_free_legs(
            robot, mounted.flange_tcp, inp.reach.positions, np.radians(spec.settings.home)
        )  # fmt: skip
        for spec, mounted, robot in robots
    ]
    return np.stack([g.travel for g in legs]), np.stack([g.home for g in legs])


def _allocate_and_plan(
    ctx: Context, forbid: dict[tuple[int, int], str], cost: Any
) -> tuple[list[Any], AllocationReport, tuple[Any, ...]]:
    """Steps 4-5 of the module docstring, iterated (:func:`weldplan.multi.calibrate.
    allocate_and_plan`, ``settings.rounds``): ``(plans, the best round's report, the rounds)``;
    each round's new shares planned by :func:`weldplan.multi.shares.plan_shares` (a share
    planned before, in any pass, is taken from ``ctx.cache``). The allocation serves no pair
    of ``forbid`` (``{(robot, weld): reason}``: :mod:`weldplan.multi.conflicts`) and charges
    ``cost`` (:class:`~weldplan.multi.allocate.PairCost`) per pair of welds that meet.
    The bound is computed once, over every pair the study serves and the pose-free leg bounds
    (:func:`_tcp_bounds`: true of the timed cycle whatever gun poses the robots' plans choose),
    with the bound over the study's poses beside it (``LowerBound.at_study_poses``: the planned
    gun poses may differ from the study's, and then beat it leg by leg)."""
    from weldplan.multi.baselines import allocation_report
    from weldplan.multi.calibrate import allocate_and_plan
    from weldplan.multi.conflicts import without

    settings, seconds, inp = ctx.settings, ctx.seconds, ctx.inp
    say = ctx.progress or (lambda stage, done, total: None)
    if ctx.bound is None:
        ctx.bound = _bound(ctx)
    reach = without(inp.reach, forbid)
    calls = [0]

    def allocate_once(travel: Any) -> AllocationReport:
        say("allocation", calls[0], settings.rounds)
        calls[0] += 1
        t = time.perf_counter()
        out = allocation_report(reach, inp.weld_time, travel, rng=ctx.seed, settings=settings,
                                bound=ctx.bound, conflicts=cost)  # fmt: skip
        seconds["allocation"] += time.perf_counter() - t
        return out

    got = allocate_and_plan(allocate_once, lambda shares: _plan_fresh(ctx, shares), inp.model,
                            settings.rounds)  # fmt: skip
    return list(got.plans), got.report, got.rounds


def _bound(ctx: Context) -> Any:
    """The station's :class:`~weldplan.multi.result.LowerBound` (:func:`_allocate_and_plan`)."""
    from weldplan.multi.bound import lower_bound
    from weldplan.multi.problem import AllocationProblem

    t = time.perf_counter()
    bounds = []
    free, home = _tcp_bounds(ctx.robots, ctx.inp)
    for travel in (free, ctx.inp.bound):
        problem = AllocationProblem.build(ctx.inp.reach, ctx.inp.weld_time, travel,
                                          ctx.settings.closed)  # fmt: skip
        bounds.append(lower_bound(problem, nodes=ctx.settings.milp_nodes,
                                  seconds=ctx.settings.milp_seconds, home=home))  # fmt: skip
    ctx.seconds["allocation"] = ctx.seconds.get("allocation", 0.0) + time.perf_counter() - t
    return dataclasses.replace(bounds[0], at_study_poses=bounds[1].value)


def _plan_fresh(ctx: Context, shares: dict[int, tuple[str, ...]]) -> dict[int, Any]:
    """A round's new shares, in turn or side by side (:func:`weldplan.multi.shares.
    plan_shares`), those planned in an earlier pass taken from ``ctx.cache``."""
    from weldplan.multi.shares import plan_shares

    key = {k: (k, tuple(sorted(ids))) for k, ids in shares.items()}
    todo = {k: ids for k, ids in shares.items() if key[k] not in ctx.cache}
    if todo:
        names = tuple(f"robot{k + 1}" for k in range(len(ctx.robots)))
        got = plan_shares(ctx.station, _Shares(names, todo), seed=ctx.seed,
                          executor=ctx.executor, progress=ctx.progress)  # fmt: skip
        for name, v in got.seconds.items():
            ctx.seconds[name] = ctx.seconds.get(name, 0.0) + v
        for name, v in got.cpu.items():
            ctx.cpu[name] = round(ctx.cpu.get(name, 0.0) + v, 2)
        ctx.ran.append(got.ran)
        for k in todo:
            ctx.cache[key[k]] = got.plans[k]
    return {k: ctx.cache[key[k]] for k in shares}


@dataclass(frozen=True)
class _Shares:
    """The shares one allocate-plan round plans (:func:`weldplan.multi.shares.plan_shares`
    reads ``robots`` and ``welds_of``): the robots whose share is new, none for the others."""

    robots: tuple[str, ...]
    shares: dict[int, tuple[str, ...]]

    def welds_of(self, k: int) -> tuple[str, ...]:
        return self.shares.get(k, ())
