"""One collision vocabulary: a state and motion checker in OMPL's shape, the conservative
advancement under every swept check, and the verdict every re-check returns.

:class:`StateChecker` is OMPL's ``base::StateValidityChecker`` (``isValid``, ``clearance``) and
``base::MotionValidator`` (``checkMotion(s1, s2, lastValid)``) in one protocol. It is implemented
by the tool's SE(3) checker (:class:`weldplan.tool.transitions.SweepChecker`: a state is a TCP pose
``(p (3,) mm, q (4,) wxyz)``), the robot's joint-space checker
(:class:`weldplan.robot.collision.RobotCollision`: a state is ``q (6,) rad``) and the point-tip
checker (:class:`PointChecker`: a state is a point ``(3,) mm``).

:func:`advance` is conservative advancement (Mirtich 1996, as FCL's ``continuousCollide`` and
OMPL's discrete motion validators use it): at motion parameter ``t`` the distance ``d`` to the
obstacles is measured; when no point of the moving body moves more than ``bound`` mm over the
whole motion (the **motion bound**), none can use up the slack ``d - gap`` before
``t + (d - gap) / bound``, so the next measurement is taken there. The motion bound is the
caller's: :func:`weldplan.tool.transitions.motion_bound` for a rigid tool in SE(3) (TCP displacement
plus the turn times the tool's reach), :func:`weldplan.robot.collision.motionbound.sphere_rates` for
the robot's links in joint space (each joint's turn times the lever of the points it carries), the
relative bound of two links for a self-collision pair, the segment's length for a point. One
loop serves them all; the rules that end it (what slack blocks, a step cap, a probe ahead) are
parameters.

:class:`CheckVerdict` is the one outcome of a check: ok, what was checked, how many, the first
failures with their place and cause, the least clearance measured. Every re-check's report
(:mod:`weldplan.weld.verify`, :mod:`weldplan.tool.verify.poses`,
:mod:`weldplan.tool.verify.sweeps`, :mod:`weldplan.tool.verify.check_route`,
:mod:`weldplan.robot.program.routejson`) exposes one as ``.verdict``;
:class:`weldplan.station.recheck.Verdict` collects them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "Advance",
    "CheckVerdict",
    "Failure",
    "PointChecker",
    "StateChecker",
    "advance",
    "touching",
]


@runtime_checkable
class StateChecker(Protocol):
    """A state and motion checker in OMPL's shape (module docstring).

    A state is whatever the checker's planner moves: a TCP pose, a joint vector, a point. A
    motion ``a -> b`` is the checker's own interpolation of the two (straight TCP segment with
    slerp, linear in joint space, a straight segment).
    """

    def is_valid(self, state: Any) -> bool:
        """Whether ``state`` keeps what the checker asks (OMPL ``isValid``)."""
        ...

    def clearance(self, state: Any) -> float:
        """mm: the distance from ``state`` to the nearest obstacle, or a lower bound of it
        where the checker says so (OMPL ``clearance``); 0 in contact."""
        ...

    def check_motion(self, a: Any, b: Any) -> float:
        """The last valid motion parameter in [0, 1] of the motion ``a -> b`` (OMPL
        ``checkMotion(s1, s2, lastValid)``): the motion is shown free on ``[0, t)``, and
        ``1.0`` means the whole motion, ends included, is free. A lower bound of the first
        contact: what lies beyond ``t`` was not shown free."""
        ...


def touching(t: float, slack: float) -> bool:
    """The plain blocking rule of :func:`advance`: a slack of 0 or less blocks (``t`` unused)."""
    return slack <= 0.0


@dataclass(frozen=True)
class Advance:
    """Where :func:`advance` stopped.

    Attributes
    ----------
    free
        The motion from ``start`` to ``stop`` was shown free.
    t
        Free: the parameter of the last measurement (``stop``, or earlier where the slack
        covered the rest). Blocked: where it was blocked (the last measurement's parameter; at
        the step cap, the next step's, not measured).
    distance
        mm: the last distance measured (``nan``: none).
    left
        mm: free: a lower bound of the slack at ``stop``, ``distance - gap - bound |stop - t|``
        (what a next motion may use up: :class:`weldplan.robot.collision.Carry`);
        ``-inf`` when blocked.
    steps
        Distances measured.
    """

    free: bool
    t: float
    distance: float
    left: float
    steps: int


def advance(
    distance: Callable[[float], float],
    bound: float,
    *,
    start: float = 0.0,
    stop: float = 1.0,
    gap: float = 0.0,
    blocked: Callable[[float, float], bool] = touching,
    until_covered: bool = False,
    max_steps: int | None = None,
    probe: Callable[[int, float], bool] | None = None,
) -> Advance:
    """Conservative advancement along one motion, from ``start`` towards ``stop`` (module
    docstring).

    Parameters
    ----------
    distance
        ``distance(t)`` mm: the moving body's distance to the obstacles at motion parameter
        ``t`` (or a lower bound of it; the caller may count or cap its own work there).
    bound
        mm: no point of the body moves more than this over the whole motion (``t`` 0 to 1).
    start, stop
        Parameters in [0, 1]; ``stop < start`` advances backwards (a check that meets in the
        middle advances from both ends).
    gap
        mm: the distance the body must keep; the **slack** is ``distance - gap``.
    blocked
        ``blocked(t, slack)``: whether the slack measured at ``t`` blocks the motion there
        (default :func:`touching`: a slack of 0 or less). A caller that refuses small slacks
        away from a weld pose, or whose work budget ran out, says so here.
    until_covered
        Stop as free as soon as the slack covers the rest of the motion
        (``bound |stop - t| <= slack``) instead of measuring at ``stop``.
    max_steps
        Measurements before the motion is declared blocked (a motion that grazes the obstacle
        would never end); ``None``: no cap here.
    probe
        ``probe(step, t)``, asked after the measurement ``step`` (0-based) when it neither
        blocked nor finished: ``True`` declares the motion blocked at ``t`` (a contact found
        ahead, which the advancement could not have passed).

    Returns
    -------
    Advance

    Notes
    -----
    The step ``t + (slack / bound)`` is clipped to ``stop``. A passed motion keeps the slack
    at every parameter, not only at the measurements: between two of them no point moves more
    than the slack measured at the first.
    """
    sign = 1.0 if stop >= start else -1.0
    t = start
    d = math.nan
    steps = 0
    while max_steps is None or steps < max_steps:
        d = distance(t)
        steps += 1
        slack = d - gap
        if blocked(t, slack):
            return Advance(False, t, d, -math.inf, steps)
        rest = sign * (stop - t)
        if bound <= 0 or rest <= 0 or (until_covered and bound * rest <= slack):
            return Advance(True, t, d, slack - bound * rest, steps)
        if probe is not None and probe(steps - 1, t):
            return Advance(False, t, d, -math.inf, steps)
        t = t + sign * min(slack / bound, rest)
    return Advance(False, t, d, -math.inf, steps)


class PointChecker:
    """The point-tip checker: a sphere of ``radius`` mm (the torch tip) against the part, in
    the :class:`StateChecker` shape.

    Parameters
    ----------
    model
        :class:`weldplan.geometry.collision.CollisionModel` of the part (mm).
    radius
        mm: the tip's radius, the cell's clearance.
    max_steps
        Measurements a motion may take before it is declared blocked at the step cap.
    """

    def __init__(self, model: Any, radius: float, *, max_steps: int = 1000) -> None:
        self.model = model
        self.radius = float(radius)
        self.max_steps = int(max_steps)

    def is_valid(self, state: ArrayLike) -> bool:
        """Whether the tip at ``state (3,)`` mm keeps off the part (python-fcl)."""
        p = np.asarray(state, dtype=np.float64).reshape(1, 3)
        return bool(self.model.segments_free(p, p, self.radius, method="fcl")[0])

    def clearance(self, state: ArrayLike) -> float:
        """mm: the distance of the point ``state (3,)`` to the part's surface (python-fcl)."""
        return float(self.model.clearance(np.reshape(state, (1, 3)), method="fcl")[0])

    def check_motion(self, a: ArrayLike, b: ArrayLike) -> float:
        """The last valid parameter of the straight motion ``a -> b`` (3,) mm: conservative
        advancement on python-fcl point distances, the motion bound the segment's length."""
        a = np.asarray(a, dtype=np.float64).reshape(3)
        b = np.asarray(b, dtype=np.float64).reshape(3)
        run = advance(
            lambda t: self.clearance(a + t * (b - a)),
            float(np.linalg.norm(b - a)),
            gap=self.radius,
            max_steps=self.max_steps,
        )
        return 1.0 if run.free else run.t


@dataclass(frozen=True)
class Failure:
    """One failure of a check: where, and why.

    Attributes
    ----------
    place
        What failed, as a user finds it: ``"weld 7"``, ``"12->13"``, ``"motion 4"``.
    cause
        Why, in words (the check's own line).
    """

    place: str
    cause: str

    def __str__(self) -> str:
        return f"{self.place}: {self.cause}" if self.place else self.cause


@dataclass(frozen=True)
class CheckVerdict:
    """The outcome of one check, whichever stage's (module docstring).

    Attributes
    ----------
    ok
        Everything checked passed.
    what
        What was checked, in words (``"tool poses"``, ``"tool transitions"``, ...).
    checked
        How many items were checked (poses, transitions, segments, joint rows).
    failures
        The failures found, first first (a check may stop at its first).
    min_clearance
        mm: the least distance measured between what was checked and the obstacles, or a lower
        bound of it (``nan``: the check measures none, only whether they touch).
    left_out
        What the plan leaves out that the check found (welds with no pose, blocked
        transitions): not a failure, a partial plan.
    """

    ok: bool
    what: str
    checked: int
    failures: tuple[Failure, ...] = ()
    min_clearance: float = math.nan
    left_out: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        what: str,
        checked: int,
        failures: Any = (),
        *,
        place: str = "{}",
        ok: bool | None = None,
        min_clearance: float = math.nan,
        left_out: Any = (),
    ) -> CheckVerdict:
        """The verdict of ``checked`` items with ``failures``: :class:`Failure` or ``(key,
        cause)`` pairs, the place ``place.format(key)`` (``"weld {}"``; a key ``""`` or ``"-"``
        names no place). ``ok`` defaults to "no failure"."""
        fails = tuple(
            f
            if isinstance(f, Failure)
            else Failure("" if str(f[0]) in ("", "-") else place.format(f[0]), str(f[1]))
            for f in failures
        )
        return cls(
            not fails if ok is None else bool(ok),
            what,
            int(checked),
            fails,
            float(min_clearance),
            tuple(str(x) for x in left_out),
        )

    def describe(self, limit: int = 3) -> str:
        """One line: what was checked and found, the first ``limit`` failures named."""
        if self.ok:
            near = (
                f", least clearance {self.min_clearance:.2f} mm"
                if math.isfinite(self.min_clearance)
                else ""
            )
            left = f"; left out: {', '.join(self.left_out)}" if self.left_out else ""
            return f"{self.what}: {self.checked} checked, ok{near}{left}"
        shown = "; ".join(str(f) for f in self.failures[:limit])
        more = len(self.failures) - limit
        tail = f"; ... {more} more" if more > 0 else ""
        return f"{self.what}: {len(self.failures)} failure(s) of {self.checked}: {shown}{tail}"
