"""The swept check's one entry point, shared by the exact checker
(:class:`~weldplan.tool.transitions.SweepChecker`, one FCL sample at a time) and the fast one
(:class:`~weldplan.tool.transitions.FastSweep`, the sphere bound first).

Both take a motion the same way (:meth:`SweptChecks.check`), set it up the same way
(:class:`SweepMotion`: its motion bound, poses, soft ends and focus,
:mod:`weldplan.tool.transitions.sweep`'s module docstring) and answer the same way
(:class:`SweepCheck`); only their conservative advancement over it differs (``_advance``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.checker import CheckVerdict


@dataclass(frozen=True)
class SweepCheck:
    """Outcome of one motion's check.

    Attributes
    ----------
    ok
        The tool keeps ``clearance`` from the part along the whole motion.
    samples
        FCL distance samples taken.
    min_slack
        mm: the least :meth:`~weldplan.tool.transitions.SweepChecker.slack` measured at a sample
        (``inf``: nothing near).
    blocked_at
        The motion parameter in [0, 1] where the check stopped (NaN when ``ok``).
    bound
        mm: the motion bound ``L``.
    out_of_budget
        The caller's cap or deadline (:meth:`SweptChecks.check`) stopped the check.
    min_step
        mm: the checker's least step away from a weld pose (a slack below it blocks there).
    """

    ok: bool
    samples: int
    min_slack: float
    blocked_at: float = float("nan")
    bound: float = 0.0
    out_of_budget: bool = False
    min_step: float = 0.0

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (the place: where
        it was blocked, as a share of the motion)."""
        fails = () if self.ok else ((f"{100 * self.blocked_at:.0f} %", self.describe()),)
        return CheckVerdict.of("tool motion", 1, fails, ok=self.ok)

    def describe(self) -> str:
        if self.ok:
            return f"free ({self.samples} samples, least slack {self.min_slack:.1f} mm)"
        if self.out_of_budget:
            return f"not shown free at {100 * self.blocked_at:.0f} %: the caller's budget ran out"
        if self.min_slack < 0:
            how = "collides or lacks clearance"
        elif self.min_slack < self.min_step:
            how = f"within {self.min_step:g} mm of lacking clearance away from a weld pose"
        else:
            how = "grazes: sample budget spent"
        return f"blocked at {100 * self.blocked_at:.0f} % of the motion ({how})"


@dataclass(frozen=True)
class SweepMotion:
    """One TCP motion as the swept checks take it (:mod:`weldplan.tool.transitions.sweep`).

    Attributes
    ----------
    p0, p1
        ``(3,)`` mm: the TCP at the start and at the end.
    at
        The motion's poses at parameters ``s (k,)``: ``(positions (k, 3) mm, rotations
        (k, 3, 3))`` (:func:`~weldplan.tool.transitions.interpolate`).
    L
        mm: the motion bound (:func:`~weldplan.tool.transitions.motion_bound`).
    soft
        Whether the advancement from the start (from the end) may take steps shorter than
        ``min_step``; both when the whole motion lies in the soft range of a soft end.
    soft_range
        mm of tool motion from a soft end over which it may: ``max(contact_radius,
        10 min_step)``.
    focused
        Whether both ends lie in the checker's focus box, so its crop of the part answers for
        the whole motion (:meth:`~weldplan.tool.transitions.SweepChecker.focus`).
    """

    p0: NDArray[np.float64]
    p1: NDArray[np.float64]
    at: Callable[[ArrayLike], tuple[NDArray[np.float64], NDArray[np.float64]]]
    L: float
    soft: tuple[bool, bool]
    soft_range: float
    focused: bool


class SweptChecks:
    """A swept-tool checker's :meth:`check`: a subclass sets the motion up (``_motion``) and
    advances over it (``_advance``)."""

    def check(
        self,
        p0: ArrayLike,
        q0: ArrayLike,
        p1: ArrayLike,
        q1: ArrayLike,
        exempt: ArrayLike | None = None,
        soft: tuple[bool, bool] = (True, True),
        *,
        cap: int | None = None,
        deadline: float | None = None,
    ) -> SweepCheck:
        """Check the motion ``(p0, q0) -> (p1, q1)`` (TCP mm, wxyz) by conservative advancement
        (:mod:`weldplan.tool.transitions.sweep`'s module docstring) on the checker's slack. ``exempt
        (m, 3)``: the weld spots whose zones apply. ``soft``: whether the advancement from the start
        (from the end) may take steps shorter than ``min_step`` over its first
        ``max(contact_radius, 10 min_step)`` mm of tool motion (a weld pose's slack may be
        small; a motion that short from a weld pose is soft at both ends); elsewhere a slack
        below ``min_step`` blocks the motion at once (fail fast: OMPL asks about many motions).
        Softness changes only where the check gives up early, never what it shows: a passed
        motion keeps the clearance throughout.

        ``cap`` (samples; the fast checker counts its FCL samples only) and ``deadline`` (a
        :func:`time.perf_counter` value for the exact checker, a :func:`time.process_time`
        value, the SE(3) re-plan's CPU budget, for the fast one) bound the check's own work:
        when either is spent before the motion is shown free, the motion is reported not free
        (``out_of_budget``), never free. The SE(3) re-plan uses them so that its time budget
        holds for the gun (one motion of a large turn may ask for thousands of samples)."""
        return self._advance(self._motion(p0, q0, p1, q1, soft), exempt, cap, deadline)

    def _motion(
        self, p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, soft: tuple[bool, bool]
    ) -> SweepMotion:
        raise NotImplementedError

    def _advance(
        self, m: SweepMotion, exempt: ArrayLike | None, cap: int | None, deadline: float | None
    ) -> SweepCheck:
        raise NotImplementedError
