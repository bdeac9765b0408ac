"""The timed joint trajectory as CSV, for any simulator: ``--trajectory F``.

Layout (one row per sample, time increasing)::

    t,step,joint_a1,joint_a2,joint_a3,joint_a4,joint_a5,joint_a6
    0.0000,0,0.00000000,-1.49051235,1.63902105,...
    0.0100,1,...

``t`` in s from the arrival at the first weld; ``step`` the row of the robot's route the robot is
moving to or resting at (:attr:`~weldplan.robot.route.RobotRoute.row`, not a row of the route CSV:
the robot's route is the gun's path, the route JSON's ``tool.robot.follows``, when the robot follows
the tool stage's order, else the point-tip route's waypoints;
:class:`~weldplan.robot.program.TimedTrajectory`; joint-space vias of a re-planned leg belong to the
row the leg leaves from); one column per robot joint, named as in the URDF, in radians. Samples are
:data:`~weldplan.robot.program.timing.DEFAULT_DT` apart plus one at every waypoint arrival and at
both ends of every weld dwell, so a replay that interpolates linearly between rows stays within the
timing's tolerance of the path. ``t`` strictly increases, as written (a regular sample that would
share an arrival's time is not taken, :data:`~weldplan.robot.program.timing.MIN_GAP_DT`; a
trajectory whose written times would repeat is refused, nothing written), so a replay may divide by
the step. The CLI writes it with the other outputs as one set (:mod:`weldplan.io.outputset`): whole
or not at all.
"""

from __future__ import annotations

import csv
import io
import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from weldplan.errors import PlanningError
from weldplan.io.outputset import comment_lines

log = logging.getLogger(__name__)

#: decimals of ``t`` (s) and of the joint values (rad)
T_DECIMALS = 4
Q_DECIMALS = 8


def trajectory_csv_text(
    timing: Any, row: ArrayLike | None = None, header: Sequence[str] = ()
) -> str:
    """The CSV text of a :class:`~weldplan.robot.program.TimedTrajectory` (module docstring);
    ``header``: lines written first as ``#`` comments (what produced it, what was verified).

    ``row`` ``(k,) int`` maps the timing's joint rows to the rows of the robot's route (the
    program's :attr:`~weldplan.robot.program.ProgramBuild.row`: the joint route without the rows
    the program only passes); default: the identity.
    """
    step = np.asarray(timing.step, dtype=np.int64)
    if row is not None:
        step = np.asarray(row, dtype=np.int64)[step]
    times = [f"{t:.{T_DECIMALS}f}" for t in timing.t]
    for k in range(1, len(times)):
        if float(times[k]) <= float(times[k - 1]):
            raise PlanningError(
                f"trajectory samples {k - 1} and {k} both at t {times[k]} s: the written "
                "times would not strictly increase; nothing written"
            )
    buf = io.StringIO()
    buf.write(comment_lines(header, "#"))
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["t", "step", *timing.joint_names])
    for t, s, q in zip(times, step, timing.q, strict=True):
        w.writerow([t, int(s), *(f"{v:.{Q_DECIMALS}f}" for v in q)])
    return buf.getvalue()
