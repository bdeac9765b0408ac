"""The swept check of :mod:`weldplan.tool.transitions.sweep`, fast where the tool is not near the
part: its conservative advancement takes the sphere bound's slack
(:mod:`weldplan.tool.transitions.sweep_bound`) and asks FCL only where the bound does not decide.

Why. The SE(3) re-plan's OMPL asks hundreds of states and motions; with an exact FCL distance of
the gun at every advancement step (about 5 ms near a flange) it saw a few dozen in 10 s.

The advancement, coarse to fine (:meth:`FastSweep._cover`). The motion (the checker's motion
model) is sampled on a grid of :data:`COVER_GRID_MM` of tool motion, and every sample of a batch
is judged in one vectorised call of the bound (:meth:`SweepBound.rates
<weldplan.tool.transitions.SweepBound.rates>`): each sphere of the tool has a slack bound
``sl_i`` (its centre's distance less its radius and what it must keep) and its centre moves at
most ``V_i = |dp| + theta |c_i|`` per unit of ``s``, so the sphere keeps slack over
``|s' - s| <= sl_i / V_i``. The finest spheres whose bound stays below ``min_step`` +
:data:`FLOOR_MM` are left to FCL at that sample only: its exact slack ``v``
(:meth:`SweepChecker.slack`) bounds every tool point, whose lever is at most theirs, and no
point moves more than the motion bound ``L`` (so ``v / L`` holds however the bound fared, the
exact check's own step). A sample's **radius** is the least of these; a gap between two
samples whose radii do not meet is halved, and the new midpoints form the next batch, until no
gap is left: then the tool keeps slack >= 0 all along the motion, not only at the samples.
Before the first FCL distance of a motion, FCL's cheap ``collide`` on a grid of
:data:`TOUCH_GRID_MM` (:meth:`FastSweep._touch_at`) shows most blocked motions at once.

A sample is blocked by the exact check's own rules on ``v`` (negative, zero, or below
``min_step`` outside the soft range of a weld pose); the motion's sample budget is the exact
check's (:func:`~weldplan.tool.transitions.max_samples`). So a passed motion keeps the clearance
everywhere, as the exact check's do; only the places sampled differ, so on a motion that
grazes the part the two may disagree: the re-plan's path is given to the exact check again
(:func:`weldplan.tool.transitions.replan`). On the demo the three re-plans make the same OMPL
decisions as with the one-sample-at-a-time advancement (the same states, motions and paths),
with 1,625 FCL samples instead of 3,967.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.tool.transitions.sweep import (
    TOUCH_GRID_MM,
    SweepCheck,
    SweepChecker,
    _bisection_order,
    max_samples,
    quat_to_matrix,
)

__all__ = ["COVER_GRID_MM", "FLOOR_MM", "TOUCH_GRID_MM", "FastSweep", "_bisection_order"]
from weldplan.tool.transitions.sweep_bound import THETA_PAD, Interpolator, SweepBound
from weldplan.tool.transitions.sweep_motion import SweepMotion, SweptChecks

#: mm: a sphere whose bound is below ``min_step`` plus this asks FCL (a sphere just above it
#: would make tiny steps)
FLOOR_MM = 2.0
#: mm of tool motion between the samples of a motion's first batch (:meth:`FastSweep._cover`)
COVER_GRID_MM = 40.0


@dataclass
class _Cover:
    """One motion's advancement (:meth:`FastSweep._cover`): its poses, speeds and rules, and
    what it has done: samples taken, FCL samples, least slack seen, where it stopped."""

    at: Interpolator
    L: float
    speed: tuple[float, float]
    exempt: NDArray | None
    soft: tuple[bool, bool]
    soft_range: float
    focused: bool
    cap: int | None
    deadline: float | None
    taken: int = 0
    exact: int = 0
    smin: float = math.inf
    blocked: float = math.nan
    late: bool = False
    touched: bool = False

    def soft_at(self, s: float) -> bool:
        """Whether parameter ``s`` lies within the soft range of a soft end (a slack below
        ``min_step`` may hold there, not elsewhere)."""
        return (self.soft[0] and s * self.L <= self.soft_range) or (
            self.soft[1] and (1.0 - s) * self.L <= self.soft_range
        )


class FastSweep(SweptChecks):
    """:class:`~weldplan.tool.transitions.SweepChecker`'s state and motion checks with the sphere
    bound first (module docstring); the same guarantees, FCL asked far less often.

    Attributes
    ----------
    exact_samples, bound_samples, touch_tests
        Samples decided by FCL's distance, by the bound alone, and poses tested for contact by
        FCL's ``collide`` (motions and states shown blocked cheaply).
    """

    def __init__(self, checker: SweepChecker, bound: SweepBound) -> None:
        self.checker = checker
        self.bound = bound
        self.exact_samples = 0
        self.bound_samples = 0
        self.touch_tests = 0

    def state_ok(self, p: ArrayLike, q: ArrayLike, exempt: NDArray | None) -> bool:
        """Whether one pose clears (:meth:`SweepChecker.state_ok`): the bound when it proves
        it, FCL otherwise (the same answer: the bound is a lower bound of FCL's slack)."""
        R = quat_to_matrix(q)
        if self.bound.state_clear(p, R, exempt is not None and len(exempt) > 0):
            self.bound_samples += 1
            return True
        if self.checker.touches(p, R):  # slack < 0: FCL's distance would say so too
            self.touch_tests += 1
            return False
        self.exact_samples += 1
        return self.checker.slack(p, R, exempt) >= 0.0

    def _motion(
        self, p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, soft: tuple[bool, bool]
    ) -> SweepMotion:
        """The checker's own set-up of the motion (its crop answers for the whole motion only
        when both ends lie in its box: the box is convex; a sample's own position in it is not
        enough for a step)."""
        return self.checker._motion(p0, q0, p1, q1, soft)

    def _advance(
        self, m: SweepMotion, exempt: ArrayLike | None, cap: int | None, deadline: float | None
    ) -> SweepCheck:
        """:meth:`check`'s advancement, coarse to fine (:meth:`_cover`): free only when the tool
        keeps the clearance along the whole motion (module docstring). ``cap`` counts FCL
        samples only; ``deadline`` is a :func:`time.process_time` value."""
        chk, L, at = self.checker, m.L, m.at
        dp = float(np.linalg.norm(m.p1 - m.p0))
        R0, R1 = at([0.0, 1.0])[1]  # one call: scipy's rotations are the same bits batched
        theta = math.acos(min(1.0, max(-1.0, (np.trace(R0.T @ R1) - 1) / 2))) + THETA_PAD
        run = _Cover(at, L, (dp, theta), exempt, m.soft, m.soft_range, m.focused, cap, deadline)
        self._cover(run)
        self.exact_samples += run.exact
        self.bound_samples += run.taken - run.exact
        return SweepCheck(
            math.isnan(run.blocked), run.exact, run.smin, run.blocked, L, run.late, chk.min_step
        )

    def _cover(self, run: _Cover) -> None:
        """The coarse-to-fine advancement of the module docstring: samples on a grid of
        :data:`COVER_GRID_MM` of tool motion, each judged at once by :meth:`_radii`; every gap
        its two samples' radii do not cover is halved, until none is left (free), a sample is
        blocked, or the sample budget (:func:`~weldplan.tool.transitions.max_samples`) is spent."""
        budget = max_samples(run.L, self.checker.min_step)
        n = max(2, math.ceil(run.L / COVER_GRID_MM) + 1) if run.L > 0 else 1
        new = _bisection_order(n) / max(n - 1, 1)  # the middle first: where blocks are found
        S, rad = np.zeros(0), np.zeros(0)
        while True:
            if run.taken + len(new) > budget:  # grazes: the exact check's budget spent too
                run.blocked = float(new[0])
                return
            got = self._radii(run, new)
            if got is None:
                return
            S, rad = np.concatenate([S, new]), np.concatenate([rad, got])
            order = np.argsort(S, kind="stable")
            S, rad = S[order], rad[order]
            open_ = np.flatnonzero(rad[:-1] + rad[1:] < np.diff(S))
            if len(open_) == 0:
                return
            new = (S[open_] + S[open_ + 1]) / 2

    def _radii(self, run: _Cover, s: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """The parameter radius about each sample ``s (k,)`` over which the tool keeps slack
        >= 0 (module docstring), the bound's for all of them in one call and FCL's where the
        bound does not decide; ``None`` when a sample is blocked or the budget ran out (then
        ``run.blocked`` says where)."""
        chk = self.checker
        P, Rs = run.at(s)
        dp, theta = run.speed
        ex = run.exempt is not None and len(run.exempt) > 0
        rate, least, lever = self.bound.rates(P, Rs, ex, chk.min_step + FLOOR_MM, run.speed)
        run.taken += len(s)
        run.smin = min(run.smin, float(np.min(least[lever < 0], initial=math.inf)))
        ask = np.flatnonzero(lever >= 0)
        if len(ask) and run.deadline is not None and time.process_time() > run.deadline:
            run.late, run.blocked = True, float(s[ask[0]])  # the safety net, once a batch
            return None
        if len(ask) and not run.touched:  # FCL's collide first: cheap, and shows most blocks
            run.touched = True
            hit = self._touch_at(run.at, run.L, run.focused)
            if hit is not None:  # the tool touches the part there: slack < 0
                run.smin, run.blocked = -math.inf, hit
                return None
        for j in ask:
            if run.cap is not None and run.exact >= run.cap:
                run.late, run.blocked = True, float(s[j])
                return None
            run.exact += 1
            v = chk.slack(P[j], Rs[j], run.exempt, run.focused)
            run.smin = min(run.smin, v)
            if v < 0 or (v == 0 and dp + theta > 0) or (v < chk.min_step and not run.soft_at(s[j])):
                run.blocked = float(s[j])
                return None
            # FCL's slack bounds every point: those of the undecided spheres move at most
            # dp + theta lever, any point at most the motion bound L
            rate[j] = min(rate[j], v / max(dp + theta * lever[j], 1e-12))
            rate[j] = max(rate[j], v / max(dp + theta * chk.reach, 1e-12))
        return rate

    def _touch_at(self, at: Interpolator, L: float, focused: bool) -> float | None:
        """:meth:`SweepChecker.first_touch`, counted."""
        hit, tests = self.checker.first_touch(at, L, focused)
        self.touch_tests += tests
        return hit
