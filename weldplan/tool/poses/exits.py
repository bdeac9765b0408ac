"""The exit test of the pose search (issue 16): accept a weld pose only when the tool can leave it.

The least-rotation choice of :func:`~weldplan.tool.poses.plan_weld_poses` looks only at the
poses themselves. A free pose can still leave the tool no way out: on the demo cell, weld 7 is
reachable only turned over, and from the pose picked there every lift, the axial retract and
every side exit is blocked (the transition 7 -> 1 stays blocked even for OMPL with 10 s). The
exit test is an acceptance test (:mod:`weldplan.tool.poses.choice`, ``accept(i, T)``) that asks a
:class:`~weldplan.tool.transitions.TransitionPlanner` whether the tool can leave the pose
(:meth:`~weldplan.tool.transitions.TransitionPlanner.exit_free`), so a pose with no exit gives
way to the next least-rotation free pose that has one. Leaving and approaching are the same
swept set run the other way, so a pose the tool can leave it can also approach.

**Which exits count** (cheapest first; each is checked with only the weld's own contact zone
exempt, stricter than a transition's two zones):

* ``lift``, for a tool that straddles the sheet (a C-gun) with slides on: a lift of 4, 10 or
  20 mm off the sheet along the tool axis. This is how the transitions leave such a tool's welds
  on the measured stations (every free transition of car2_50 and car2_200, and 10 of the demo's
  14, is a slide: lift, slide, lower), and the lifted pose is where an SE(3) re-plan starts when
  the slide to the next weld is blocked. It is the first motion of every exit, so a pose whose
  lifts are all blocked (demo weld 7's pick) has no slide and no lifted SE(3) start;
* ``axial``: the retract along the tool axis (``retract`` mm, 50 by default);
* ``side``: a lift of 5-20 mm, a side exit of ``side_exit`` mm, the rest of the retract.

A lift does not prove that the slide to the neighbour is free (the neighbour's pose is not
chosen yet when a pick is judged): a free lift is a necessary condition of a slide and a start
for SE(3), not a whole transition. The transitions are still planned and re-checked in full
afterwards (:func:`~weldplan.tool.transitions.plan_transitions`,
:func:`~weldplan.tool.verify.verify_sweeps`); the test only steers the choice.

The planner's checks are cached per pose, so handing the same planner to
:func:`~weldplan.tool.transitions.plan_transitions` (``reuse=``) reuses every exit the test
checked for the poses that were kept.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.poses.result import quat_wxyz
from weldplan.tool.transitions.plan import TransitionPlanner

log = logging.getLogger(__name__)

#: the exits that count, cheapest first (module docstring)
DEFAULT_EXITS = ("lift", "axial", "side")


@dataclass(frozen=True)
class _Pose:
    """The fields of a weld pose the planner's exit checks read."""

    id: str
    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]


class ExitTest:
    """``accept(i, T)``: ``None`` when the tool can leave weld ``ids[i]`` at TCP pose ``T (4, 4)``
    (mm, part frame) by one of ``exits``, else the reason (module docstring).

    Parameters
    ----------
    planner
        The transition planner whose checks (and cache) decide; hand it to
        :func:`~weldplan.tool.transitions.plan_transitions` afterwards.
    ids
        The weld ids in the order the pose search sees them (a Route's order).
    exits
        The exits that count, in the order tried (:data:`DEFAULT_EXITS`).

    Attributes
    ----------
    calls, vetoes, samples
        Poses judged, poses vetoed, and the FCL samples the judging took.
    vetoed
        ``weld id -> poses of that weld vetoed``.
    how
        ``weld id -> exit`` of the last pose of that weld the test accepted.
    """

    def __init__(
        self,
        planner: TransitionPlanner,
        ids: Sequence[str],
        exits: tuple[str, ...] = DEFAULT_EXITS,
    ) -> None:
        self.planner = planner
        self.ids = [str(i) for i in ids]
        self.exits = tuple(exits)
        self.calls = 0
        self.vetoes = 0
        self.samples = 0
        self.how: dict[str, str] = {}
        self.vetoed: dict[str, int] = {}

    def __call__(self, i: int, T: NDArray[np.float64]) -> str | None:
        T = np.asarray(T, dtype=np.float64)
        q = quat_wxyz(T[None, :3, :3])[0]
        w = _Pose(self.ids[i], tuple(T[:3, 3].tolist()), tuple(q.tolist()))  # type: ignore[arg-type]
        n0 = self.planner.samples
        ok, how = self.planner.exit_free(w, self.exits)
        self.samples += self.planner.samples - n0
        self.calls += 1
        if ok:
            self.how[w.id] = how
            return None
        self.vetoes += 1
        self.vetoed[w.id] = self.vetoed.get(w.id, 0) + 1
        log.debug("weld %s: no exit: %s", w.id, how)
        return f"no exit: {how}"

    def stats(self) -> dict[str, Any]:
        """The test's counts, for a result's stats."""
        return {"exit_calls": self.calls, "exit_vetoes": self.vetoes,
                "exit_samples": self.samples, "exit_vetoed": dict(self.vetoed)}  # fmt: skip


def leave_distances(planner: TransitionPlanner, poses: Any) -> dict[str, float]:
    """``weld id -> mm``: the lift each ok pose of ``poses`` is left by where its first free exit
    (:meth:`~weldplan.tool.transitions.TransitionPlanner.exit_free`, cached for the poses the
    test judged) is a lift, for the tool order's leg costs
    (:mod:`weldplan.tool.transitions.order`)."""
    out: dict[str, float] = {}
    for p in poses.poses:
        if p.ok:
            ok, how = planner.exit_free(p)
            if ok and how.startswith("lift "):
                out[p.id] = float(how.split()[1])
    return out
