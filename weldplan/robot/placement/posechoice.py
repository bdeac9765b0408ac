"""Gun poses the robot can reach: the robot's acceptance test for the pose choice (issue 17).

The tool stage chooses one free pose per weld, least rotation along the route
(:func:`weldplan.tool.plan_weld_poses`). Without the robot it may pick a pose the robot cannot
take (the demo's welds 13 and 15 needed A5 = 165 deg, limit 125) or can take only with its arm
through the body (car2: link_3 at the weld pose on every branch). :class:`ReachTest` is the
``accept(i, T)`` of that choice (:mod:`weldplan.tool.poses.choice`): a TCP pose is accepted when,
from the robot's base, at least one IK branch is **usable** (inside the joint limits and away
from the wrist singularity: the rule of :func:`weldplan.robot.placement.usable`) and on at least one
usable branch **no link touches the part** at that configuration
(:meth:`weldplan.robot.collision.RobotCollision.states_blocked`, FCL judges). The tool is left
out: the tool stage has checked it at the pose, minus its contact zone, before ``accept`` runs.
A veto names its cause: ``out_of_reach``, ``joint_limit A5 165 deg (limits -125..125)``,
``singular``, ``link_3 in the part``. :meth:`ReachTest.verdicts` judges many poses in one
call (one IK for all, one FCL pass over their usable branches): the pose choice uses it to veto
the rest of a weld's candidates at once when its pick is vetoed (batch vetoes,
:mod:`weldplan.tool.poses.choice`), and a C-gun whose approach side is all vetoed is then tried
turned over (the demo's welds 13 and 15: every approach-side pose needs A5 141-160 deg from the
searched base, turned over 47-61 deg). The test is a preference of the pose choice, not a
verification: the robot route (:func:`weldplan.robot.route.plan_robot_route`) re-checks the links
and the tool on every branch it uses, and the whole joint path.

**The base** (:func:`place_for_poses`). With a given base the test uses it. A searched base
needs the poses, and the robot-aware poses need the base. The choice made here: plan the poses
without the test (the tool stage's answer as before), search the base for those poses exactly
as the robot route would (:func:`weldplan.robot.placement.place`: floor candidates ranked by
usable welds and manipulability, re-ranked by the welds served without a link in the part, the
best few solved along the whole route), then choose the poses again with the test at that base,
and plan the robot route at that base. Why this and not a base searched on the nominal approach
axes first: the base search scores whole routes of concrete poses (branch continuity, the links
at each weld) and the first-pass poses are free for the gun, so the base it finds is one where
most of the gun's least-rotation poses are already served; the second pass then re-chooses only
where the robot vetoes (the DP's first round is the first pass's answer, so welds the robot
accepts keep their poses unless a neighbour's change makes another pose cheaper). A base
searched over nominal axes would score poses the gun may not be able to take. On request
(``place_for_poses(alternatives=True)``, not the CLI's default) the search scores each weld with
its other free poses too (the first pass's
:attr:`~weldplan.tool.poses.WeldPoses.alternatives`, :mod:`weldplan.robot.placement.altreach`): a
weld whose least-rotation pose a base cannot take, but another of its free poses it can, counts
there, since the second pass will pick that one. The cost is one more pose choice (the tool's
collision table is built again; docs/robot-placement.md, "Tool poses the arm reaches";
``weldplan bench robot`` measures it). The
base is not searched again after the second pass (one round: a second round could move the base
to where the re-chosen poses do better, and then the poses again; not measured to converge).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.robot.collision.checker import RobotCollision
from weldplan.robot.collision.selfcollision import hit_words
from weldplan.robot.model.arm import Robot
from weldplan.robot.placement.reach import (
    DEFAULT_SINGULAR_DEG,
    JOINT_LIMIT,
    OK,
    BaseSearch,
    Placement,
    classify,
    usable,
)
from weldplan.robot.settings import PlacementSettings, ToolOnRobot

log = logging.getLogger(__name__)

#: the suffix of a veto for a link in the part (``"link_3 in the part"``)
IN_PART = "in the part"


class ReachTest:
    """``accept(i, T)`` for :func:`weldplan.tool.plan_weld_poses`: the robot at its base reaches
    the TCP pose ``T`` on a usable IK branch whose links are clear of the part (module
    docstring).

    Parameters
    ----------
    robot
        The robot at its base (part frame).
    flange_tcp
        ``(4, 4)`` mm: the TCP in the robot's flange frame.
    checker
        A :class:`~weldplan.robot.collision.RobotCollision` of that robot against the part (its
        tool is not used), or ``None`` to test the kinematics only.
    singular_deg
        A5 within this many degrees of 0 is near-singular (:func:`weldplan.robot.placement.usable`).

    Attributes
    ----------
    calls
        Poses judged.
    vetoes
        ``Counter`` of the veto reasons' first words (``joint_limit``, ``link_3``...).
    """

    def __init__(
        self,
        robot: Robot,
        flange_tcp: ArrayLike,
        checker: RobotCollision | None = None,
        *,
        singular_deg: float = DEFAULT_SINGULAR_DEG,
    ) -> None:
        self.robot = robot
        self.tcp_flange = np.linalg.inv(np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4))
        self.checker = checker
        self.singular_deg = float(singular_deg)
        self.calls = 0
        self.vetoes: Counter[str] = Counter()

    def __call__(self, i: int, T: NDArray[np.float64]) -> str | None:
        """``None`` when the robot reaches TCP pose ``T (4, 4)`` mm (part frame) of weld ``i``,
        else the reason it does not."""
        return self.verdicts(np.asarray(T, dtype=np.float64)[None])[0]

    def verdicts(self, T_tcp: ArrayLike) -> list[str | None]:
        """Per TCP pose of ``T_tcp (n, 4, 4)`` mm: ``None`` (reached) or the reason (module
        docstring). IK of every pose at once; one FCL pass over every usable branch."""
        T = np.asarray(T_tcp, dtype=np.float64).reshape(-1, 4, 4)
        self.calls += len(T)
        br = self.robot.ik_all(T @ self.tcp_flange)
        ok = usable(br, self.singular_deg)
        status = classify(br, self.singular_deg)
        out: list[str | None] = [None] * len(T)
        for k in np.flatnonzero(status != OK):
            out[k] = (
                joint_limit_reason(self.robot, br.q[k], br.exists[k])
                if status[k] == JOINT_LIMIT
                else str(status[k])
            )
        if self.checker is not None and ok.any():
            idx = np.argwhere(ok)
            blocked = self.checker.states_blocked(br.q[idx[:, 0], idx[:, 1]], zone=True, tool=False)
            first: dict[int, str] = {}
            free = np.zeros(len(T), dtype=bool)
            for (k, _), b in zip(idx, blocked, strict=True):
                if b is None:
                    free[k] = True
                else:
                    first.setdefault(int(k), b)
            for k, b in first.items():
                if not free[k]:
                    out[k] = f"{b} {IN_PART}" if "/" not in b else hit_words(b)
        for r in out:
            if r is not None:
                self.vetoes[r.split(" ")[0]] += 1
        return out


def joint_limit_reason(robot: Robot, q: NDArray[np.float64], exists: NDArray[np.bool_]) -> str:
    """``"joint_limit A5 165 deg (limits -125..125)"``: the joints outside their limits on the
    existing branch of ``q (8, 6)`` rad that breaks the fewest of them, by the least excess.

    Joints are named ``A1``..``A6`` in chain order (the URDF's own names may be anything)."""
    lo, hi = robot.lower, robot.upper
    Q = q[exists]
    excess = np.maximum(lo - Q, 0.0) + np.maximum(Q - hi, 0.0)  # (b, 6) rad
    bad = excess > 0
    key = np.lexsort((excess.sum(axis=1), bad.sum(axis=1)))
    b = int(key[0])
    parts = [
        f"A{j + 1} {math.degrees(Q[b, j]):.0f} deg (limits "
        f"{math.degrees(lo[j]):.0f}..{math.degrees(hi[j]):.0f})"
        for j in np.flatnonzero(bad[b])
    ]
    return f"{JOINT_LIMIT} {', '.join(parts)}"


def place_for_poses(
    robot: Robot,
    route: Any,
    poses: Any,
    tool: ToolOnRobot,
    part: Any,
    checker: RobotCollision | None = None,
    search: BaseSearch | None = None,
    *,
    settings: PlacementSettings | None = None,
    alternatives: bool = False,
) -> Placement:
    """The base the robot route would search for ``route`` with weld ``poses`` (module
    docstring): :func:`weldplan.robot.placement.place` over the route's waypoint poses (mm,
    ``part`` the mesh for the base column and the floor, ``tool`` the tool on the flange), with
    the links-at-the-welds re-ranking when ``checker`` is given. A weld counts at a base when its
    pose or, with ``alternatives``, one of the other free poses ``poses`` carries for it
    (:attr:`~weldplan.tool.poses.WeldPoses.alternatives`) serves there: the reach test then
    picks that pose (:mod:`weldplan.robot.placement.altreach`). Off by default: on car2_200 the
    bases it finds serve every weld pose but the robot route from them cannot leave the first welds
    (docs/robot-placement.md). ``settings``: the robot route's
    (:class:`~weldplan.robot.settings.PlacementSettings`; its ``joins``, the roadmap of a last
    step that re-ranks the best candidates by the welds one joint-space roadmap joins, e.g.
    :data:`~weldplan.robot.settings.ROADMAP`; ``None``, the default: not re-ranked).

    Raises
    ------
    PlanningError
        No base candidate reaches a weld (collision-free, with a checker).
    """
    from weldplan.robot.placement.altreach import alternative_flange_poses
    from weldplan.robot.placement.base import place
    from weldplan.robot.route.plan import tcp_waypoint_poses
    from weldplan.tool.poses.route_frames import weld_rows

    F = tool.flange_tcp
    T_fl = tcp_waypoint_poses(route, poses) @ np.linalg.inv(F)
    checker_for = None if checker is None else checker.with_robot
    placement, _ = place(
        robot,
        T_fl,
        weld_rows(route),
        part,
        None,
        search or BaseSearch(),
        checker_for,
        PlacementSettings() if settings is None else settings,
        alternative_flange_poses(poses, route.order, F) if alternatives else None,
        tuple(route.order),
    )
    if placement.join is not None and placement.join.roadmap is not None:
        placement.join.roadmap.close()  # the robot route builds its own for the new poses
    return placement
