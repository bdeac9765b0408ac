"""Results of a weld allocation: each robot's share, the station cycle, the bound, the baselines.

Every class is frozen and round-trips through JSON (``to_dict`` / ``from_dict``). Times are in
seconds; welds are named by their ids and indexed in the reach map's order.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class RobotShare:
    """One robot's welds in visiting order and its cycle time.

    Attributes
    ----------
    robot
        Its name.
    order
        Weld indices (reach-map order) in visiting order.
    weld_time
        s: the sum of its weld times.
    route_time
        s: its moves along ``order`` (the closing move included for a closed tour).
    """

    robot: str
    order: tuple[int, ...]
    weld_time: float
    route_time: float

    @property
    def cycle_time(self) -> float:
        """s: weld time plus route time."""
        return self.weld_time + self.route_time

    def to_dict(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "order": list(self.order),
            "weld_time": self.weld_time,
            "route_time": self.route_time,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RobotShare:
        return cls(
            str(d["robot"]),
            tuple(int(v) for v in d["order"]),
            float(d["weld_time"]),
            float(d["route_time"]),
        )


@dataclass(frozen=True)
class Unreached:
    """A weld no robot serves, with every robot's reason (never dropped silently).

    Attributes
    ----------
    weld
        Its id.
    reasons
        ``"robot: reason"`` per robot, in robot order.
    """

    weld: str
    reasons: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"weld": self.weld, "reasons": list(self.reasons)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Unreached:
        return cls(str(d["weld"]), tuple(str(v) for v in d["reasons"]))


@dataclass(frozen=True)
class LowerBound:
    """A proved lower bound of the station cycle time of *any* allocation and orders.

    Attributes
    ----------
    value
        s: ``max(integer, lp, unique)``.
    name
        What it is, in words (the binding term first).
    lp
        s: the LP relaxation of the min-max assignment with tour shares
        (:func:`weldplan.multi.bound.lower_bound`).
    unique
        s: the largest unavoidable time of the welds only one robot serves.
    unique_robot
        The robot of ``unique`` (empty when no weld has a single robot).
    unique_method
        How ``unique``'s route part was bounded: ``"held-karp"``, ``"1-tree"`` or
        ``"shares"``.
    integer
        s: HiGHS's dual bound of the same assignment in integers (0 when it found none).
    status
        HiGHS's word on that integer search (optimal, node limit, time limit).
    at_study_poses
        s: the same bound over the all-branch leg times of the study's weld poses, when the
        bound itself is over pose-free times (:func:`weldplan.multi.bound.tcp_leg_bound`);
        ``None`` otherwise. It bounds the timed cycle only where the plans weld with the
        study's poses.
    """

    value: float
    name: str
    lp: float
    unique: float
    unique_robot: str = ""
    unique_method: str = ""
    integer: float = 0.0
    status: str = ""
    at_study_poses: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> LowerBound:
        return cls(
            float(d["value"]),
            str(d["name"]),
            float(d["lp"]),
            float(d["unique"]),
            str(d.get("unique_robot", "")),
            str(d.get("unique_method", "")),
            float(d.get("integer", 0.0)),
            str(d.get("status", "")),
            None if d.get("at_study_poses") is None else float(d["at_study_poses"]),
        )


@dataclass(frozen=True)
class Allocation:
    """Which robot welds which weld, in which order: what :func:`weldplan.multi.allocate`
    and the baselines return.

    Attributes
    ----------
    method
        ``"ours"``, ``"nearest-robot"`` or ``"one-robot"``.
    robots, welds
        Names and ids, in the reach map's order.
    assignment
        Per weld the robot index that welds it, -1 for a weld no robot serves.
    shares
        One :class:`RobotShare` per robot, in robot order (an idle robot has an empty order).
    unreached
        The welds no robot serves (or, for a baseline that cannot serve some, that it does
        not serve), each with the reasons.
    closed
        Tours are closed.
    seed
        The integer seed, when one was given.
    stats
        Figures of the run (MILP status and value, moves tried and applied, the start's cycle).
    """

    method: str
    robots: tuple[str, ...]
    welds: tuple[str, ...]
    assignment: tuple[int, ...]
    shares: tuple[RobotShare, ...]
    unreached: tuple[Unreached, ...] = ()
    closed: bool = False
    seed: int | None = None
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def cycle_time(self) -> float:
        """s: the station's cycle, the slowest robot's."""
        return max((s.cycle_time for s in self.shares), default=0.0)

    @property
    def cycle_times(self) -> tuple[float, ...]:
        """s per robot."""
        return tuple(s.cycle_time for s in self.shares)

    @property
    def bottleneck(self) -> str:
        """The slowest robot's name (the first on ties)."""
        c = self.cycle_times
        return self.robots[c.index(max(c))] if c else ""

    @property
    def utilisation(self) -> tuple[float, ...]:
        """Per robot, its cycle over the station's (1 for the bottleneck; 0 when idle)."""
        top = self.cycle_time
        return tuple(c / top if top > 0 else 0.0 for c in self.cycle_times)

    def welds_of(self, robot: str | int) -> tuple[str, ...]:
        """The ids ``robot`` welds, in its visiting order."""
        r = robot if isinstance(robot, int) else self.robots.index(robot)
        return tuple(self.welds[i] for i in self.shares[r].order)

    def to_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "robots": list(self.robots),
            "welds": list(self.welds),
            "assignment": list(self.assignment),
            "shares": [s.to_dict() for s in self.shares],
            "unreached": [u.to_dict() for u in self.unreached],
            "closed": self.closed,
            "seed": self.seed,
            "stats": self.stats,
            "cycle_time": self.cycle_time,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Allocation:
        return cls(
            method=str(d["method"]),
            robots=tuple(str(v) for v in d["robots"]),
            welds=tuple(str(v) for v in d["welds"]),
            assignment=tuple(int(v) for v in d["assignment"]),
            shares=tuple(RobotShare.from_dict(s) for s in d["shares"]),
            unreached=tuple(Unreached.from_dict(u) for u in d.get("unreached", ())),
            closed=bool(d.get("closed", False)),
            seed=None if d.get("seed") is None else int(d["seed"]),
            stats=dict(d.get("stats", {})),
        )


@dataclass(frozen=True)
class AllocationReport:
    """Our allocation beside its lower bound and the baselines (issue 30, item 2).

    Attributes
    ----------
    ours
        :func:`weldplan.multi.allocate`'s answer.
    bound
        The :class:`LowerBound` printed beside it.
    nearest
        Each weld to the nearest robot (by base) that serves it; ``None`` without bases and
        weld positions.
    one_robot
        The best single robot that serves every weld some robot serves; ``None`` when none
        does.
    """

    ours: Allocation
    bound: LowerBound
    nearest: Allocation | None = None
    one_robot: Allocation | None = None

    @property
    def gap(self) -> float:
        """Our cycle over the bound, minus 1 (0: proved optimal; nan without a bound)."""
        b = self.bound.value
        return self.ours.cycle_time / b - 1.0 if b > 0 else float("nan")

    def clock_caps(self) -> list[str]:
        """Which HiGHS call its wall-clock safety net stopped (empty: every MILP ended on its
        node budget or optimal, so the same inputs and seed give the same report anywhere)."""
        runs = [(a.stats.get("milp_status", ""), f"the {what} assignment MILP")
                for what, a in (("allocation's", self.ours), ("nearest robot's", self.nearest))
                if a is not None]  # fmt: skip
        runs.append((self.bound.status, "the lower bound's MILP"))
        return [f"{what} stopped by its clock" for status, what in runs
                if "time limit" in str(status).lower()]  # fmt: skip

    def rows(self) -> list[tuple[str, float | None, float | None]]:
        """``(what, cycle s or None, over the bound or None)`` for the table a run prints:
        one robot, nearest robot, ours, the bound (:attr:`LowerBound.name` says which)."""
        b = self.bound.value
        out: list[tuple[str, float | None, float | None]] = []
        for name, a in (("one robot", self.one_robot), ("nearest robot", self.nearest)):
            c = None if a is None else a.cycle_time
            out.append((name, c, None if c is None or b <= 0 else c / b - 1.0))
        out.append(("ours", self.ours.cycle_time, self.gap if b > 0 else None))
        out.append(("lower bound", b, None))
        return out

    def lines(self) -> list[str]:
        """The table as text lines (the library never prints; the CLI does)."""
        out = [f"{'allocation':<16} {'cycle s':>9} {'vs bound':>9}"]
        for name, c, g in self.rows():
            cs = "-" if c is None else f"{c:9.2f}"
            gs = "" if g is None else f"{100 * g:+8.1f}%"
            out.append(f"{name:<16} {cs:>9} {gs:>9}")
        out.append(f"bound: {self.bound.name}")
        if self.bound.at_study_poses is not None:
            out.append(f"bound at the study's gun poses: {self.bound.at_study_poses:.2f} s "
                       "(holds where the plans weld with those poses)")  # fmt: skip
        if self.ours.unreached:
            out.append(f"{len(self.ours.unreached)} welds no robot reaches:")
            out += [f"  {u.weld}: {'; '.join(u.reasons)}" for u in self.ours.unreached]
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "ours": self.ours.to_dict(),
            "bound": self.bound.to_dict(),
            "nearest": None if self.nearest is None else self.nearest.to_dict(),
            "one_robot": None if self.one_robot is None else self.one_robot.to_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AllocationReport:
        return cls(
            Allocation.from_dict(d["ours"]),
            LowerBound.from_dict(d["bound"]),
            None if d.get("nearest") is None else Allocation.from_dict(d["nearest"]),
            None if d.get("one_robot") is None else Allocation.from_dict(d["one_robot"]),
        )

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> AllocationReport:
        return cls.from_dict(json.loads(text))
