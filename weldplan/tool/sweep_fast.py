"""The swept check of :mod:`weldplan.tool.sweep`, fast where the tool is not near the part: its
conservative advancement takes the sphere bound's slack (:mod:`weldplan.tool.sweep_bound`) and
asks FCL only where the bound does not decide.

Why. The SE(3) re-plan's OMPL asks hundreds of states and motions; with an exact FCL distance of
the gun at every advancement step (about 5 ms near a flange) it saw a few dozen in 10 s.

The advancement. At a sample ``s`` of the motion (the checker's motion model) the bound gives
each sphere of the tool a slack ``sl_i`` (its centre's distance less its radius and what it must
keep), and its centre moves at most ``V_i = |dp| + theta |c_i|`` per unit of ``s``, so the sphere
keeps ``sl_i - V_i |s' - s|`` at ``s'``. The finest spheres whose bound is below the floor are
left to FCL: the exact slack ``v`` (:meth:`SweepChecker.slack`) bounds every tool point, which
moves at most ``|dp| + theta (|c_i| + r_i)`` per unit of ``s``, and no point more than the
motion bound ``L``. The next sample is where the first of these could reach the margin
(``min_step`` away from a weld pose, 0 within the soft range of one, as the exact check's
rules), but never nearer than the exact check's own step ``v / L`` where FCL was asked (which
keeps the clearance: a ``min_step`` margin held there made the advancement creep towards a dip
below ``min_step`` without ever sampling it). A sample is blocked by the exact check's own rules
on ``v`` (negative, zero, or below ``min_step`` outside the soft range); the motion's sample
budget is the exact check's. So a passed motion keeps the clearance everywhere, as the exact
check's do. Only the step lengths differ, so on a motion that grazes the part the two may
disagree: the re-plan's path is given to the exact check again
(:func:`weldplan.tool.se3_replan.replan`).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.tool.sweep import (
    SweepCheck,
    SweepChecker,
    _interpolator,
    max_samples,
    motion_bound,
    quat_to_matrix,
)
from weldplan.tool.sweep_bound import THETA_PAD, Interpolator, SweepBound

#: mm of tool motion between the poses at which a motion is first tested for contact
TOUCH_GRID_MM = 5.0
#: mm: a sphere whose bound is below the margin plus this asks FCL (a sphere just above the
#: margin would make tiny steps)
FLOOR_MM = 2.0


class FastSweep:
    """:class:`~weldplan.tool.sweep.SweepChecker`'s state and motion checks with the sphere
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

    def check(
        self,
        p0: ArrayLike,
        q0: ArrayLike,
        p1: ArrayLike,
        q1: ArrayLike,
        exempt: NDArray | None = None,
        soft: tuple[bool, bool] = (True, True),
        *,
        cap: int | None = None,
        deadline: float | None = None,
    ) -> SweepCheck:
        """:meth:`SweepChecker.check`'s contract (``cap`` counts FCL samples only; ``deadline``
        is a :func:`time.process_time` value, the SE(3) re-plan's CPU budget): free only when
        the tool keeps the clearance along the whole motion (module docstring)."""
        chk = self.checker
        L = motion_bound(p0, q0, p1, q1, chk.reach)
        ex = exempt is not None and len(exempt) > 0
        if self.bound.motion_clear(p0, q0, p1, q1, ex, chk.min_step):
            return SweepCheck(True, 0, math.inf, bound=L, min_step=chk.min_step)
        at = _interpolator(p0, q0, p1, q1)
        # the checker's crop answers for the whole motion only when both ends lie in its box
        # (the box is convex); a sample's own position in it is not enough for a step
        focused = chk._inside(p0, p1)
        hit = self._touch_at(at, L, focused)
        if hit is not None:  # the tool touches the part there: the exact check cannot pass it
            return SweepCheck(False, 0, -math.inf, hit, L, False, chk.min_step)
        soft_range = max(chk.contact_radius, 10 * chk.min_step)
        if L <= soft_range and any(soft):
            soft = (True, True)
        dp = float(np.linalg.norm(np.asarray(p1, dtype=np.float64) - np.asarray(p0, np.float64)))
        R0, R1 = at([0.0])[1][0], at([1.0])[1][0]
        theta = math.acos(min(1.0, max(-1.0, (np.trace(R0.T @ R1) - 1) / 2))) + THETA_PAD
        state = {"budget": max_samples(L, chk.min_step), "exact": 0, "smin": math.inf}
        late = False
        blocked = float("nan")
        for start, stop, sign, may in ((0.0, 0.5, 1.0, soft[0]), (1.0, 0.5, -1.0, soft[1])):
            s = start
            while True:
                if (cap is not None and state["exact"] >= cap) or (
                    deadline is not None and time.process_time() > deadline
                ):
                    late, blocked = True, s
                    break
                soft_here = may and abs(s - start) * L <= soft_range
                step = self._step(at(s), exempt, ex, dp, theta, soft_here, state, focused)
                state["budget"] -= 1
                if step is None or step[0] <= 0 or state["budget"] < 0:
                    blocked = s
                    break
                if soft_here:  # margin 0 may hold only up to the soft range's end
                    edge = soft_range / L - abs(s - start) if L > 0 else math.inf
                    step = max(min(step[0], edge), step[1])
                else:
                    step = step[1]
                if L <= 0 or sign * (stop - s) <= 0:
                    break
                s = s + sign * min(step, sign * (stop - s))
            if not math.isnan(blocked):
                break
        self.exact_samples += state["exact"]
        n = max_samples(L, chk.min_step) - state["budget"]
        self.bound_samples += n - state["exact"]
        return SweepCheck(
            math.isnan(blocked), state["exact"], state["smin"], blocked, L, late, chk.min_step
        )

    def _touch_at(self, at: Interpolator, L: float, focused: bool) -> float | None:
        """The first parameter, middle first and then halving the gaps (where a blocked motion
        is most often found), of a grid :data:`TOUCH_GRID_MM` of tool motion apart at which the
        tool outside its zone touches the part (FCL ``collide``); ``None``: no contact there,
        which proves nothing."""
        n = max(1, math.ceil(L / TOUCH_GRID_MM))
        order = _bisection_order(n + 1)
        s = order / n
        P, R = at(s)
        for k in range(len(s)):
            self.touch_tests += 1
            if self.checker.touches(P[k], R[k], focused):
                return float(s[k])
        return None

    def _step(
        self,
        pose: tuple[NDArray[np.float64], NDArray[np.float64]],
        exempt: NDArray | None,
        ex: bool,
        dp: float,
        theta: float,
        soft_here: bool,
        state: dict[str, Any],
        focused: bool,
    ) -> tuple[float, float] | None:
        """At one sample: ``None`` when blocked (the exact check's rules on FCL's slack), else
        the parameter steps ``(with margin 0, with margin min_step)`` that keep the margin."""
        chk = self.checker
        P, R = pose[0][0], pose[1][0]
        margin = 0.0 if soft_here else chk.min_step
        sl, lever, open_lever = self.bound.spheres(P, R, ex, margin + FLOOR_MM)
        V = dp + theta * lever
        steps: list[float] = []
        exact = math.inf
        if open_lever >= 0:  # the bound does not decide: FCL's slack bounds every point
            state["exact"] += 1
            exact = chk.slack(P, R, exempt, focused)
            state["smin"] = min(state["smin"], exact)
            if exact < 0 or (exact == 0 and dp + theta > 0) or exact < margin:
                return None
        else:
            state["smin"] = min(state["smin"], float(sl.min()))
        for m in (0.0, chk.min_step):
            t = float(np.min((sl - m) / np.maximum(V, 1e-12), initial=math.inf))
            if open_lever >= 0:  # FCL's slack also bounds every point, at the motion bound L
                t = min(t, (exact - m) / max(dp + theta * open_lever, 1e-12))
                t = max(t, exact / max(dp + theta * chk.reach, 1e-12))  # the exact check's step
            steps.append(t)
        return steps[0], steps[1]


def _bisection_order(n: int) -> NDArray[np.int64]:
    """The integers ``0..n-1`` in the order of a bisection: the middle, then the quarters, ...
    (the ends last: the motion's ends are states OMPL has checked already)."""
    seen = np.zeros(n, dtype=bool)
    out = []
    step = 1 << max(0, (n - 1).bit_length())
    while step >= 1:
        for k in range(step // 2 if step > 1 else 0, n, step):
            if not seen[k]:
                seen[k] = True
                out.append(k)
        step //= 2
    ends = list(dict.fromkeys(k for k in (0, n - 1) if k in out))
    rest = [k for k in out if k not in ends]
    return np.array(rest + ends, dtype=np.int64)
