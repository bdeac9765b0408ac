"""The allocation's inputs from a feasibility study: reach, weld times and leg times per robot.

:func:`study_inputs` turns a :class:`~weldplan.study.FeasibilityStudy` (robots at their study
bases) into what :func:`weldplan.multi.allocate` takes:

* the :class:`~weldplan.multi.problem.ReachMap` of the study (:meth:`ReachMap.from_study`:
  a free gun pose on a usable branch with the links clear, else the study's reason);
* ``weld_time (R, W)``: each robot's dwell per spot;
* per robot, leg times between the spots it reaches (:mod:`weldplan.robot.route.legtime`): the
flange
  pose of the configuration the study found (forward kinematics of ``RobotVerdict.q``), every
  usable IK configuration of that pose (:func:`~weldplan.robot.route.weld_configurations`),
  and the rest-to-rest times between them (:func:`~weldplan.robot.route.leg_times`):
  ``cost`` (on the station branch, what the sequencer minimises) or ``bound`` (over every
  branch: a proved lower bound of any timed leg, so that the allocation's bound is a bound of
  the timed cycle of that pose choice);
* ``approach (R, W)`` s (:func:`approach_times`): the rest-to-rest time from each weld's
  configuration to the one with the TCP at the weld's virtual joint (orientation kept), where
  the timed programs stop as they leave a weld and again as they reach the next (every demo
  program stops there: no blend fits so near the part). The allocation's *model* of a leg
  ``i -> j`` is ``approach_i + cost_ij + approach_j`` (:attr:`StudyInputs.model`); its bound
  stays ``bound`` alone (a program that blends there, or a gun pose other than the study's,
  may beat the approach term).

Why the model adds the approach (measured on the demo two-robot station, docs/station.md): a
timed leg is a sequence of rest-to-rest pieces (lift to the virtual joint, the transfer in
pieces of the route's rows, lower), 2 to 3 times the single rest-to-rest move between the two
weld configurations; the approach ends are the part of that a leg always has. What depends on
the planned path (its pieces, an OMPL detour) is learnt from the timed programs by the
allocate-plan rounds (:mod:`weldplan.multi.calibrate`).

Only the study's configuration at each spot is checked against the part; the other
configurations of the same pose are not (as for the single robot's ``--cost time``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError
from weldplan.multi.problem import ReachMap


@dataclass(frozen=True, eq=False)
class StudyInputs:
    """What :func:`study_inputs` returns.

    Attributes
    ----------
    reach
        The :class:`~weldplan.multi.problem.ReachMap`.
    weld_time
        ``(R, W)`` s.
    cost, bound
        ``(R, W, W)`` s: each robot's leg times on its station branch, and their lower bound
        over every branch (0 where the robot does not reach both spots).
    branch
        ``(R,)``: each robot's station branch (-1: it reaches no spot).
    approach
        ``(R, W)`` s: :func:`approach_times` per robot (0 where not served or not given).
    """

    reach: ReachMap
    weld_time: NDArray[np.float64]
    cost: NDArray[np.float64]
    bound: NDArray[np.float64]
    branch: tuple[int, ...]
    approach: NDArray[np.float64] | None = None

    @property
    def model(self) -> NDArray[np.float64]:
        """``(R, W, W)`` s: the allocation's leg model, ``approach_i + cost_ij + approach_j``
        off the diagonal (module docstring; ``cost`` without approach times)."""
        if self.approach is None:
            return self.cost
        a = self.approach
        out = self.cost + a[:, :, None] + a[:, None, :]
        W = out.shape[1]
        out[:, np.arange(W), np.arange(W)] = 0.0
        return out


def study_inputs(
    study: object,
    robots: Sequence[object],
    weld_time: Sequence[float],
    *,
    tool: str | int = 0,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    lift: ArrayLike | None = None,
) -> StudyInputs:
    """The allocation's inputs from ``study`` (module docstring).

    Parameters
    ----------
    study
        A :class:`~weldplan.study.FeasibilityStudy` with ``R`` robots.
    robots
        The ``R`` :class:`~weldplan.robot.model.Robot` models of the study, in its order
        (placed here at the study's bases).
    weld_time
        ``R`` s: each robot's dwell per spot.
    tool
        The study's tool whose reach is allocated.
    velocity_scale, acceleration_scale
        Factors on the robots' joint limits (as the robot stage's settings).
    lift
        ``(W, 3)`` mm: each weld's virtual joint less the weld (the cell's ``virtual_xyz -
        joints.xyz``), for :attr:`StudyInputs.approach`; ``None``: no approach term.

    Raises
    ------
    ConfigError
        Lists of the wrong length, or a negative weld time.
    """
    from weldplan.robot.route.legtime import leg_times, weld_configurations

    infos = study.robots  # type: ignore[attr-defined]
    R = len(infos)
    if not (len(robots) == len(weld_time) == R):
        raise ConfigError(
            f"the study has {R} robots: give {R} robots and weld times", field="robots"
        )
    W = len(study.spots)  # type: ignore[attr-defined]
    tools = tuple(study.tools)  # type: ignore[attr-defined]
    t = tool if isinstance(tool, int) else tools.index(tool) if tool in tools else -1
    if not 0 <= t < len(tools):
        raise ConfigError(
            f"no tool {tool!r} in the study (it has {', '.join(tools)})", field="tool"
        )
    reach = ReachMap.from_study(study, t)
    cost, bound, branch = np.zeros((R, W, W)), np.zeros((R, W, W)), []
    wt, approach = np.zeros((R, W)), np.zeros((R, W))
    from weldplan.robot.program.timing import check_weld_time

    for r, (robot, info) in enumerate(zip(robots, infos, strict=True)):
        wt[r] = check_weld_time(weld_time[r])
        placed = robot.with_base(info.base_matrix())  # type: ignore[attr-defined]
        idx = np.flatnonzero(reach.ok[r])
        if not len(idx):
            branch.append(-1)
            continue
        q = np.array([study.spots[i].robots[t * R + r].q for i in idx])  # type: ignore[attr-defined]
        configs = weld_configurations(placed, placed.fk(q))  # the study's flange poses
        v = np.asarray(placed.velocity) * velocity_scale  # type: ignore[attr-defined]
        a = np.asarray(placed.acceleration) * acceleration_scale  # type: ignore[attr-defined]
        legs = leg_times(configs, v, a)
        cost[r][np.ix_(idx, idx)] = legs.cost
        bound[r][np.ix_(idx, idx)] = legs.bound
        branch.append(legs.branch)
        if lift is not None:
            approach[r, idx] = approach_times(placed, q, np.asarray(lift)[idx], v, a)
    return StudyInputs(reach, wt, cost, bound, tuple(branch), approach)


def approach_times(
    robot: object, q: ArrayLike, lift: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike
) -> NDArray[np.float64]:
    """``(n,)`` s: the straight rest-to-rest joint move (:func:`weldplan.robot.program.
    pair_time`, the time law of a two-row segment of the timed program) from each
    configuration ``q (n, 6)`` rad to the IK solution nearest it (wrapped joint differences)
    of its flange pose translated by ``lift (n, 3)`` mm, orientation kept; 0 where no solution
    exists (the model then has no approach term there).

    ``robot``: the placed :class:`~weldplan.robot.model.Robot`."""
    from weldplan.robot.program.timing import pair_time

    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    T = robot.fk(Q)  # type: ignore[attr-defined]
    T[:, :3, 3] += np.asarray(lift, dtype=np.float64).reshape(-1, 3)
    br = robot.ik_all(T)  # type: ignore[attr-defined]
    d = np.angle(np.exp(1j * (br.q - Q[:, None, :])))  # (n, 8, 6) wrapped differences
    err = np.where(br.exists, np.abs(d).max(axis=2), np.inf)
    k = np.argmin(err, axis=1)
    dq = d[np.arange(len(Q)), k]
    t = pair_time(dq, velocity, acceleration)
    return np.where(np.isfinite(err.min(axis=1, initial=np.inf)), t, 0.0)


def stack_inputs(parts: Sequence[StudyInputs], names: Sequence[str]) -> StudyInputs:
    """One :class:`StudyInputs` of the robots of ``parts`` (each over the same welds, e.g.
    one study per robot with its own tool), the robots renamed ``names``."""
    if not parts or len(names) != sum(len(p.reach.robots) for p in parts):
        raise ConfigError("give one name per robot of the parts", field="robots")
    welds = parts[0].reach.welds
    if any(p.reach.welds != welds for p in parts):
        raise ConfigError("the parts are over different welds", field="welds")
    bases = [p.reach.bases for p in parts]
    reach = ReachMap(
        np.vstack([p.reach.ok for p in parts]),
        tuple(r for p in parts for r in p.reach.reasons),
        tuple(names),
        welds,
        None if any(b is None for b in bases) else np.vstack(bases),  # type: ignore[arg-type]
        parts[0].reach.positions,
    )
    return StudyInputs(
        reach,
        np.vstack([p.weld_time for p in parts]),
        np.concatenate([p.cost for p in parts]),
        np.concatenate([p.bound for p in parts]),
        tuple(b for p in parts for b in p.branch),
        np.vstack(
            [np.zeros(p.weld_time.shape) if p.approach is None else p.approach for p in parts]
        ),  # fmt: skip
    )
