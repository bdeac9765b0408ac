"""The inputs of a weld allocation among several robots, checked once.

An allocation (issue 30, item 2) assigns every weld to one robot of a station so that the
slowest robot finishes first. It sees three things, all indexed by robot ``r`` and weld ``i``:

* :class:`ReachMap`: ``ok (R, W) bool`` (robot ``r`` serves weld ``i`` from its base: a free
  gun pose on a usable IK branch, links clear; :meth:`weldplan.study.FeasibilityStudy.reach_matrix`)
  with the reason of every refusal, the robots' bases and the welds' positions (mm, part frame;
  the nearest-robot baseline uses them);
* ``weld_time (R, W)`` s: the dwell of weld ``i`` on robot ``r``;
* ``travel``: per robot a ``(W, W)`` matrix of joint-space move times (s) between the welds it
  serves (:func:`weldplan.robot.route.leg_times`, or any estimator); the entries of welds it
  does not serve are ignored.

:class:`AllocationProblem` holds them checked (a bad shape or a negative time is a
:class:`~weldplan.errors.ConfigError` naming the field) with the per-robot quantities the
allocation, its bound and its baselines share: the *tour share* of each weld
(:func:`tour_shares`) and the exact cost of a given visiting order
(:meth:`AllocationProblem.cycle`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError


@dataclass(frozen=True, eq=False)
class ReachMap:
    """Which robot serves which weld, and why not.

    Attributes
    ----------
    ok
        ``(R, W) bool``: robot ``r`` serves weld ``i``.
    reasons
        ``R`` tuples of ``W`` words: why robot ``r`` does not serve weld ``i`` (empty where it
        does; a study's verdict and reason, e.g. ``"collision: link_3 hits the part"``).
    robots
        ``R`` names.
    welds
        ``W`` weld ids.
    bases
        ``(R, 3)`` mm: each robot's base position (part frame), or ``None``.
    positions
        ``(W, 3)`` mm: each weld's position (part frame), or ``None``.
    """

    ok: NDArray[np.bool_]
    reasons: tuple[tuple[str, ...], ...]
    robots: tuple[str, ...]
    welds: tuple[str, ...]
    bases: NDArray[np.float64] | None = None
    positions: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        ok = np.asarray(self.ok)
        if ok.ndim != 2 or ok.dtype != bool:
            raise ConfigError(
                f"must be an (R, W) bool array, got {ok.dtype} {ok.shape}", field="reach"
            )
        R, W = ok.shape
        if len(self.robots) != R or len(self.welds) != W:
            raise ConfigError(
                f"{len(self.robots)} robot names and {len(self.welds)} weld ids for a "
                f"{R} x {W} reach map",
                field="reach",
            )
        if len(set(self.robots)) != R:
            raise ConfigError("two robots share a name", field="robots")
        if len(self.reasons) != R or any(len(r) != W for r in self.reasons):
            raise ConfigError(f"reasons must be {R} tuples of {W} words", field="reasons")
        for name, arr, n in (("bases", self.bases, R), ("positions", self.positions, W)):
            if arr is not None and np.shape(arr) != (n, 3):
                raise ConfigError(f"must be ({n}, 3) mm, got {np.shape(arr)}", field=name)

    @property
    def shape(self) -> tuple[int, int]:
        return (len(self.robots), len(self.welds))

    @classmethod
    def of(
        cls,
        ok: ArrayLike,
        *,
        robots: Sequence[str] | None = None,
        welds: Sequence[str] | None = None,
        bases: ArrayLike | None = None,
        positions: ArrayLike | None = None,
        reason: str = "not reached",
    ) -> ReachMap:
        """A reach map from a bare ``(R, W)`` bool array: robots named ``r0, r1, ...``, welds
        ``0, 1, ...``, every refusal with the one word ``reason``."""
        a = np.asarray(ok, dtype=bool)
        if a.ndim != 2:
            raise ConfigError(f"must be an (R, W) bool array, got shape {a.shape}", field="reach")
        R, W = a.shape
        why = tuple(tuple("" if a[r, i] else reason for i in range(W)) for r in range(R))
        return cls(
            a,
            why,
            tuple(robots) if robots is not None else tuple(f"r{r}" for r in range(R)),
            tuple(welds) if welds is not None else tuple(str(i) for i in range(W)),
            None if bases is None else np.asarray(bases, dtype=np.float64),
            None if positions is None else np.asarray(positions, dtype=np.float64),
        )

    @classmethod
    def from_study(cls, study: object, tool: str | int | None = None) -> ReachMap:
        """The reach map of a :class:`~weldplan.study.FeasibilityStudy` (robots at their
        study bases; ``tool``: one tool's reach, ``None``: any tool's; a refusal's reason is
        every tool's verdict, ``"gun/robot: status reason"``)."""
        ok = study.reach_matrix(tool).T  # type: ignore[attr-defined]
        names = tuple(r.name for r in study.robots)  # type: ignore[attr-defined]
        tools = study.tools  # type: ignore[attr-defined]
        R = len(names)
        reasons = []
        for r in range(R):
            row = []
            for i, s in enumerate(study.spots):  # type: ignore[attr-defined]
                if ok[r, i]:
                    row.append("")
                    continue
                vs = [s.robots[k * R + r] for k in range(len(tools))]
                row.append("; ".join(f"{v.tool}: {v.status} {v.reason}".strip() for v in vs))
            reasons.append(tuple(row))
        bases = np.array([r.base_matrix()[:3, 3] for r in study.robots])  # type: ignore[attr-defined]
        return cls(
            ok,
            tuple(reasons),
            names,
            study.ids,  # type: ignore[attr-defined]
            bases if R else None,
            np.array([s.position for s in study.spots], dtype=np.float64).reshape(-1, 3),  # type: ignore[attr-defined]
        )


@dataclass(frozen=True)
class AllocationSettings:
    """How :func:`weldplan.multi.allocate` searches, budgeted by work (../shared/DESIGN.md).

    Attributes
    ----------
    closed
        Each robot's route returns to its first weld (a closed tour) instead of ending at its
        last (an open path, the single-robot pipeline's route).
    moves
        Candidate moves (one weld to another robot, or a swap of two welds) the local search
        evaluates exactly, in all.
    kicks
        Kicks of the iterated search: each moves ``kick_size`` random welds to random robots
        that serve them, then descends again; the best answer is kept.
    kick_size
        Welds a kick moves.
    resequence
        Per round, candidates whose insertion estimate does not lower the maximum but that are
        re-sequenced in full by the sequencer before the search gives up.
    milp_nodes
        Branch-and-bound nodes of the initial min-max assignment (HiGHS ``node_limit``).
    milp_gap
        Relative gap at which HiGHS stops the initial assignment (it is only a start).
    milp_seconds
        Wall-clock safety net of that assignment (a clock cap that fires is reported in
        ``Allocation.stats["milp_status"]``; the node budget is the real limit).
    search_kicks
        Kicks of the sequencer's polish when the search re-sequences a robot
        (:class:`~weldplan.optim.discrete.local_search.PolishParams`; 0: plain 2-opt/Or-opt
        descent). Up to 13 welds the sequencer is exact whatever this says.
    final_kicks
        Kicks of the final sequencing of every robot's share (``None``: the sequencer's
        default, 10 a weld).
    rounds
        Allocate-plan rounds of a planned station (:mod:`weldplan.multi.calibrate`: after
        each, the planned legs' timed values replace their model times and the station is
        allocated and planned again while its timed cycle drops; 1: allocate and plan once).
    """

    closed: bool = False
    moves: int = 4000
    kicks: int = 30
    kick_size: int = 2
    resequence: int = 4
    milp_nodes: int = 500
    milp_gap: float = 0.01
    milp_seconds: float = 60.0
    search_kicks: int = 0
    final_kicks: int | None = None
    rounds: int = 3

    def __post_init__(self) -> None:
        if self.final_kicks is not None and not (
            isinstance(self.final_kicks, int) and self.final_kicks >= 0
        ):
            raise ConfigError(
                f"must be None or an integer >= 0, got {self.final_kicks!r}", field="final_kicks"
            )
        if not (isinstance(self.rounds, int) and not isinstance(self.rounds, bool)
                and self.rounds >= 1):  # fmt: skip
            raise ConfigError(f"must be an integer >= 1, got {self.rounds!r}", field="rounds")
        for name in ("moves", "kicks", "kick_size", "resequence", "milp_nodes", "search_kicks"):
            v = getattr(self, name)
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= 0):
                raise ConfigError(f"must be an integer >= 0, got {v!r}", field=name)
        for name in ("milp_gap", "milp_seconds"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ConfigError(f"must be a finite number >= 0, got {v!r}", field=name)


def tour_shares(
    travel: NDArray[np.float64], served: NDArray[np.bool_]
) -> tuple[NDArray[np.float64], float, float]:
    """Each served weld's share of any tour, and the correction that keeps it a lower bound.

    Every leg ``i -> j`` of a route is counted half at ``i`` (its way out) and half at ``j``
    (its way in), so a route over welds ``S`` costs ``sum_{i in S} (out_i + in_i) / 2``. With
    ``min_out_i`` / ``min_in_i`` the cheapest leg out of / into ``i`` over the welds the robot
    serves, ``share_i = (min_out_i + min_in_i) / 2`` (the "half its two cheapest travel edges"
    of issue 30; in and out separately, so it holds for asymmetric times and for ``|S| = 2``):

    * a closed tour over ``|S| >= 2`` welds costs at least ``sum_S share_i``; over one weld it
      costs 0, at least ``share_i - max_S share``;
    * an open path lacks the way in of its first weld and the way out of its last, so it costs
      at least ``sum_S share_i - (max min_in + max min_out) / 2``, for any ``|S|``.

    Parameters
    ----------
    travel
        ``(W, W)`` s: the robot's move times (only served rows and columns are read).
    served
        ``(W,) bool``: the welds it serves.

    Returns
    -------
    share, closed_slack, open_slack
        ``(W,)`` s (0 where not served), and the corrections above (s) for a closed tour and
        an open path.
    """
    W = len(served)
    share = np.zeros(W)
    idx = np.flatnonzero(served)
    if len(idx) < 2:
        return share, 0.0, 0.0
    M = travel[np.ix_(idx, idx)].astype(np.float64, copy=True)
    np.fill_diagonal(M, np.inf)
    out_, in_ = M.min(axis=1), M.min(axis=0)
    share[idx] = (out_ + in_) / 2.0
    return share, float(share[idx].max()), float((in_.max() + out_.max()) / 2.0)


@dataclass(frozen=True, eq=False)
class AllocationProblem:
    """The checked inputs of an allocation (module docstring) and what its stages share.

    Attributes
    ----------
    reach
        The :class:`ReachMap`.
    weld_time
        ``(R, W)`` s (0 where not served).
    travel
        ``(R, W, W)`` s (0 where either weld is not served by the robot, and on the diagonal).
    closed
        Closed tours instead of open paths.
    share
        ``(R, W)`` s: :func:`tour_shares` per robot.
    slack
        ``(R,)`` s: the correction of :func:`tour_shares` for the route kind (closed or open).
    """

    reach: ReachMap
    weld_time: NDArray[np.float64]
    travel: NDArray[np.float64]
    closed: bool
    share: NDArray[np.float64]
    slack: NDArray[np.float64]

    @classmethod
    def build(
        cls, reach: ReachMap | ArrayLike, weld_time: ArrayLike, travel: object, closed: bool
    ) -> AllocationProblem:
        """Check the inputs (:class:`~weldplan.errors.ConfigError` naming the field)."""
        rm = reach if isinstance(reach, ReachMap) else ReachMap.of(reach)
        R, W = rm.shape
        ok = np.asarray(rm.ok, dtype=bool)
        wt = np.asarray(weld_time, dtype=np.float64)
        if wt.shape != (R, W):
            raise ConfigError(f"must be ({R}, {W}) s, got {wt.shape}", field="weld_time")
        wt = np.where(ok, wt, 0.0)
        if not (np.all(np.isfinite(wt)) and np.all(wt >= 0)):
            raise ConfigError(
                "must be finite and >= 0 where the robot serves the weld", field="weld_time"
            )
        mats = [np.asarray(t, dtype=np.float64) for t in travel]  # type: ignore[attr-defined]
        T = np.stack(mats) if mats else np.zeros((0, W, W))
        if T.shape != (R, W, W):
            raise ConfigError(f"must be {R} matrices ({W}, {W}) s, got {T.shape}", field="travel")
        both = ok[:, :, None] & ok[:, None, :]
        T = np.where(both, T, 0.0)
        T[:, np.arange(W), np.arange(W)] = 0.0
        if not (np.all(np.isfinite(T)) and np.all(T >= 0)):
            raise ConfigError(
                "move times must be finite and >= 0 between welds the robot serves", field="travel"
            )
        shares, slacks = [], []
        for r in range(R):
            s, sc, so = tour_shares(T[r], ok[r])
            shares.append(s)
            slacks.append(sc if closed else so)
        share = np.array(shares).reshape(R, W)
        return cls(rm, wt, T, bool(closed), share, np.asarray(slacks, dtype=np.float64))

    @property
    def ok(self) -> NDArray[np.bool_]:
        return np.asarray(self.reach.ok, dtype=bool)

    @property
    def served(self) -> NDArray[np.bool_]:
        """``(W,) bool``: some robot serves the weld."""
        return self.ok.any(axis=0)

    def route_time(self, r: int, order: Sequence[int]) -> float:
        """s: robot ``r``'s move time along ``order`` (weld indices; closed when the problem
        is)."""
        o = np.asarray(order, dtype=np.intp)
        if len(o) < 2:
            return 0.0
        t = float(self.travel[r, o[:-1], o[1:]].sum())
        return t + float(self.travel[r, o[-1], o[0]]) if self.closed else t

    def cycle(self, r: int, order: Sequence[int]) -> float:
        """s: robot ``r``'s cycle along ``order``: its weld times plus its route time."""
        o = np.asarray(order, dtype=np.intp)
        return float(self.weld_time[r, o].sum()) + self.route_time(r, o)
