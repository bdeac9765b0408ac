"""One walk along a weld pose's TCP axis, shared by every lift and the axial retract.

A weld pose is left along its TCP axis, orientation kept, in several ways: the lifts of a slide
(:data:`~weldplan.tool.transitions.plan.SLIDE_LIFTS`, 4, 10 and 20 mm), the lifts before a side
exit (:data:`~weldplan.tool.transitions.plan.SIDE_LIFTS`, 5, 10 and 20 mm) and the axial retract
(50 mm by default). Each is the same motion cut at another length: the tool at ``x`` mm up the
axis is the same pose whatever the lift. Checked one by one, every lift walked the same first
millimetres again from the weld, where the slack is least and the steps shortest; a pose with
no exit (the exit test's vetoes, :mod:`weldplan.tool.poses.exits`) walked them five times.

:class:`AxisWalk` walks the axis once, by conservative advancement (Mirtich 1996; the rule of
:mod:`weldplan.tool.transitions.sweep`), and extends the walk only as far as the longest lift
asked so far: the sample at ``x`` mm measures the slack ``v`` (:meth:`SweepChecker.slack
<weldplan.tool.transitions.SweepChecker.slack>`, the weld's own zone exempt); no tool point can
use it up before the TCP has moved ``v`` mm more (the motion is a pure translation, so its bound
is the TCP's travel), so the whole axis from 0 to ``x + v`` keeps the clearance and the next
sample is taken there. A lift of ``L`` mm is **free** once the walk has covered ``L``; it is
**blocked** where the walk is blocked before ``L``:

* FCL's ``collide`` (tens of times cheaper than a distance) on the grid of
  :data:`~weldplan.tool.transitions.TOUCH_GRID_MM` along the axis, and at ``L`` itself, goes
  first: a pose up the axis where the tool outside its zone touches the part blocks every lift
  that passes it;
* a negative or zero slack blocks there, as does a slack below ``min_step`` farther from the
  weld than the soft range ``max(contact_radius, 10 min_step)`` (the swept check's fail-fast
  rule away from a weld pose): every longer lift passes that sample too;
* a lift of ``L`` mm may take :func:`~weldplan.tool.transitions.max_samples` ``(L, min_step)``
  samples in all (a walk that grazes the part would never end); a lift that runs out is blocked,
  and a longer one, with a larger budget, walks on.

What a free lift guarantees is what the swept check's does (the clearance kept at every point
of the motion, not only at the samples); the independent re-check of the transitions
(:mod:`weldplan.tool.verify.sweeps`) tests the lifts they use with its own samples and bound.
Where the walk and a lift's own check differ is only where they give up early (the lift's own
check advances from both ends and meets in the middle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.transitions.sweep import TOUCH_GRID_MM, SweepChecker, max_samples
from weldplan.tool.transitions.sweep_motion import SweepCheck


@dataclass(frozen=True)
class AxisStop:
    """Where a walk stopped for good (every longer lift passes it).

    Attributes
    ----------
    x
        mm up the axis.
    slack
        mm: the slack measured there (``-inf``: the tool touches the part there, FCL collide).
    """

    x: float
    slack: float


class AxisWalk:
    """Conservative advancement up the TCP axis of one weld pose (module docstring).

    Parameters
    ----------
    checker
        The swept check whose slack, rules and focus the walk uses.
    p
        ``(3,)`` mm: the TCP at the weld.
    R
        ``(3, 3)``: the TCP orientation (its third column the axis; the walk goes to ``-z``).
    extent
        mm: the longest lift the walk will be asked for (the focus, :meth:`SweepChecker.focus
        <weldplan.tool.transitions.SweepChecker.focus>`, answers for the walk only when the
        axis up to here lies in its box).

    Attributes
    ----------
    samples
        FCL distance samples taken so far.
    """

    def __init__(
        self, checker: SweepChecker, p: NDArray[np.float64], R: NDArray[np.float64], extent: float
    ) -> None:
        self.checker = checker
        self.p = np.asarray(p, dtype=np.float64)
        self.R = np.ascontiguousarray(R, dtype=np.float64)
        self.up = -self.R[:, 2]
        self.extent = float(extent)
        self.exempt = self.p[None]
        self.soft_range = max(checker.contact_radius, 10 * checker.min_step)
        self.samples = 0
        self.least = math.inf
        #: mm: the next sample's place; the axis below it is shown free once a sample is taken
        self.next_x = 0.0
        self.sampled = False
        #: mm: the collide grid is probed up to here
        self.probed = -1.0
        self.stop: AxisStop | None = None

    def at(self, x: float) -> NDArray[np.float64]:
        """``(3,)`` mm: the TCP ``x`` mm up the axis."""
        return self.p + x * self.up

    def covered(self) -> float:
        """mm: the axis from the weld to here is shown to keep the clearance (0: nothing yet)."""
        return self.next_x if self.sampled else 0.0

    def lift(self, L: float) -> SweepCheck:
        """The verdict on the lift of ``L`` mm (``0 < L <= extent``), as the swept check's
        :class:`~weldplan.tool.transitions.sweep_motion.SweepCheck` (its ``samples``: those
        this call took)."""
        n0 = self.samples
        got = self._walk(float(L))
        n = self.samples - n0
        if got is None:
            return SweepCheck(True, n, self.least, bound=L, min_step=self.checker.min_step)
        x, least = got
        return SweepCheck(False, n, least, min(x / L, 1.0), L, False, self.checker.min_step)

    def _walk(self, L: float) -> tuple[float, float] | None:
        """``None`` when the lift of ``L`` mm is free, else where it is blocked (mm) and the
        least slack that says why (``-inf``: a touch)."""
        if self.sampled and self.next_x >= L:
            return None
        if self.stop is not None and self.stop.x <= L:
            return self.stop.x, min(self.stop.slack, self.least)
        touch = self._probe(L)
        if touch is not None:
            self.stop = AxisStop(touch, -math.inf)
            return touch, -math.inf
        budget = max_samples(L, self.checker.min_step)
        c = self.checker
        while not (self.sampled and self.next_x >= L):
            if self.samples >= budget:
                return self.next_x, self.least  # a longer lift walks on
            x = self.next_x
            focused = c._inside(self.p, self.at(self.extent))
            v = c.slack(self.at(x), self.R, self.exempt, focused)
            self.samples += 1
            self.sampled = True
            self.least = min(self.least, v)
            if v <= 0 or (v < c.min_step and x > self.soft_range):
                self.stop = AxisStop(x, v)
                return x, v
            self.next_x = x + v
        return None

    def _probe(self, L: float) -> float | None:
        """The first place (mm) on the grid of :data:`TOUCH_GRID_MM` up to ``L``, and ``L``
        itself, not probed yet, where the tool outside its zone touches the part (FCL collide),
        or ``None``."""
        grid = np.arange(math.floor(L / TOUCH_GRID_MM) + 1) * TOUCH_GRID_MM
        xs = [float(x) for x in grid if x > self.probed]
        if L > self.probed and (not xs or xs[-1] != L):
            xs.append(L)
        focused = self.checker._inside(self.p, self.at(self.extent))
        for x in xs:
            if self.checker.touches(self.at(x), self.R, focused):
                return x
            self.probed = x
        return None
