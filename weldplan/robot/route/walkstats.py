"""What the robot's walk over its welds (:func:`weldplan.robot.route.assemble`) returns: the
assembled joint route, the walk's work and what it gave up, as the robot stage reports them
(``RobotRoute.stats["walk"]``, the CLI's summary).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: why the walk left a weld out (:attr:`WalkStats.dropped`; the weld's ``detail`` names the
#: weld and the body): the weld the leg starts from has no free gun exit or retract; the weld
#: has none (no way in); no transfer joined the two (the straight move blocked, no tucked arm,
#: OMPL unsolved); its transfers were spent (:data:`weldplan.robot.route.TRANSFERS_PER_WELD`);
#: the robot cannot go on from it (a trap, :func:`weldplan.robot.route.assemble`)
NO_EXIT = "no exit from the weld before"
NO_APPROACH = "no approach"
NO_TRANSFER = "no transfer"
BUDGET = "transfers spent"
TRAP = "cannot go on from it"
CAUSES = (NO_EXIT, NO_APPROACH, NO_TRANSFER, BUDGET, TRAP)


@dataclass(frozen=True)
class WalkStats:
    """The work of :func:`assemble`'s walk and what it gave up (module docstring).

    Attributes
    ----------
    transfers, transfers_found
        Transfers tried (:meth:`~weldplan.robot.route.Detour.transfer` calls: a straight
        move, a tucked arm, OMPL runs) and those that found a way.
    per_weld
        :data:`TRANSFERS_PER_WELD`: the most transfers tried towards one weld.
    retraces, retraces_found
        Tries to go back along the path to a hub, and those that reached their weld.
    trap_tests, traps
        Tests of a weld as the trap, and the welds set aside as one.
    ompl_runs, ompl_solved, ompl_cpu_s
        The transfers' OMPL runs (:attr:`~weldplan.robot.route.Detour.ompl`), those solved,
        and their CPU s.
    dropped
        ``(weld id, cause)`` of every weld the walk left out, in route order; the cause one
        of :data:`CAUSES` (the weld's ``detail`` says the rest: which end, which body).
    legs_blocked, split_legs
        The transfer trial before the walk (:mod:`weldplan.robot.route.legtrial`): the legs
        between served welds whose own motion is blocked, and ``"A -> B: why"`` for each that no
        gun exit or retract and straight or tucked transfer joins (left to OMPL).
    retry_share
        The OMPL retry checks one leg may take (its share of the route's).
    other_ways
        Legs joined without a planner by another pair of the welds' ways off than their first
        (:meth:`~weldplan.robot.route.Detour.ways_off`), in the trial and the walk.
    """

    transfers: int = 0
    transfers_found: int = 0
    per_weld: int = 0
    retraces: int = 0
    retraces_found: int = 0
    trap_tests: int = 0
    traps: int = 0
    ompl_runs: int = 0
    ompl_solved: int = 0
    ompl_cpu_s: float = 0.0
    dropped: tuple[tuple[str, str], ...] = ()
    other_ways: int = 0
    legs_blocked: int = 0
    split_legs: tuple[str, ...] = ()
    retry_share: int = 0

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["dropped"] = [list(x) for x in self.dropped]
        d["split_legs"] = list(self.split_legs)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> WalkStats:
        d = dict(d)
        d["dropped"] = tuple((str(w), str(c)) for w, c in d.get("dropped", ()))
        d["split_legs"] = tuple(str(x) for x in d.get("split_legs", ()))
        return cls(**{k: v for k, v in d.items() if k in cls.__dataclass_fields__})

    def describe(self) -> str:
        """One line: the work and the welds left out, grouped by cause."""
        line = (
            f"{self.transfers} transfer(s) tried ({self.transfers_found} found, at most "
            f"{self.per_weld} a weld), {self.ompl_runs} OMPL run(s) ({self.ompl_solved} solved, "
            f"{self.ompl_cpu_s:.1f} CPU s), {self.retraces} tries back along the path "
            f"({self.retraces_found} found), {self.trap_tests} trap test(s) "
            f"({self.traps} weld(s) set aside)"
        )
        if self.split_legs:
            line += (
                f"; {len(self.split_legs)} of {self.legs_blocked} blocked leg(s) split before the "
                f"walk, left to OMPL ({'; '.join(self.split_legs[:3])}"
                f"{' ...' if len(self.split_legs) > 3 else ''})"
            )
        by: dict[str, list[str]] = {}
        for w, c in self.dropped:
            by.setdefault(c, []).append(w)
        if by:
            line += "; left out: " + "; ".join(
                f"{len(ws)} {c} ({', '.join(ws[:8])}{' ...' if len(ws) > 8 else ''})"
                for c, ws in by.items()
            )
        return line


@dataclass(frozen=True, eq=False)
class Assembled:
    """What :func:`assemble` returns.

    Attributes
    ----------
    q, row, exact, branch
        ``(k, 6)`` rad, ``(k,)``, ``(k,)``, ``(k,)``: the assembled joint route.
    zone
        ``(k - 1,) bool``: the motions checked with the tool's contact zone exempt.
    replanned
        The legs detoured (the position in ``rows`` of the weld each leaves).
    stats
        The walk's work and what it left out.
    """

    q: NDArray[np.float64]
    row: NDArray[np.int64]
    exact: NDArray[np.bool_]
    branch: NDArray[np.int64]
    zone: NDArray[np.bool_]
    replanned: tuple[int, ...]
    stats: WalkStats
