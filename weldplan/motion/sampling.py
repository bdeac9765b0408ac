"""OMPL's sampling-based planners in R^n and SE(3), with the caller's validity checks.

This is weldplan's one wrapper of OMPL (``pip install 'weldplan[ompl]'``, OMPL 2's official
nanobind bindings). OMPL samples and searches; whether a state or a motion is free is always
decided by the caller's callables (for the torch: weldplan's FCL sphere and capsule checks), so a
path from here is exactly as trustworthy as those callables, and is re-verified downstream like
any other.

Conventions
-----------
- States are numpy arrays: R^n states ``(d,)``; SE(3) states ``(7,)`` as ``x, y, z, qw, qx, qy,
  qz`` (positions in mm, unit quaternion scalar first).
- Motions: when ``motion_valid`` is ``None``, OMPL's discrete motion validator checks states along
  each motion every ``resolution`` x (the space's maximum extent) and calls ``is_valid`` on them;
  otherwise ``motion_valid(a, b)`` alone decides whether the straight motion a -> b (SE(3):
  linear position, slerp rotation) is free, and it must check both ends as well as the inside.
- Seeds: OMPL has one process-wide seed generator (``ompl.util.RNG.setSeed``), which seeds every
  RNG that OMPL creates afterwards. A call with ``seed`` resets it, so a planner that stops on its
  own (``rrtconnect`` stops at its first solution) and ``simplify`` give the same path for the
  same seed. Anytime planners (``bitstar``, ``rrtstar``...) stop on a budget: with
  ``max_checks`` (below) the result is the same on any machine; with the clock alone how far they
  improve depends on the machine's speed (the seed fixes the sample sequence, not the result).
  Because the seed generator is process-wide, run parallel plans in processes, not threads.
- Budgets by work: ``max_checks`` counts the calls the caller's ``is_valid`` and
  ``motion_valid`` receive and becomes OMPL's termination condition, evaluated in the planner's
  own thread (:mod:`weldplan.motion.budget`): with a seed, the same run stops after the same
  check on any machine and at any load. ``time_s`` stays as a wall-clock safety net;
  :attr:`SampledPath.ended` says what ended a run (``"clock"``: the run is not reproducible).
- "No path found" is a result (``solved=False``), never an exception;
  :class:`SamplingArgumentError` is raised only for bad arguments.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.pathcore import polyline_length
from weldplan.motion.budget import Checks

# the OMPL plumbing shared with roadmap.py; its public names are re-exported from here
from weldplan.motion.ompl_base import (
    QUAT_NORM_TOL,  # noqa: F401 - re-exported
    MotionCheck,
    SamplingArgumentError,  # noqa: F401 - re-exported
    StateCheck,
    _check_box,
    _import_ompl,
    _motion_validator,
    _ompl_seed,
    _unit_quat,
    _vector,
    ompl_available,  # noqa: F401 - re-exported
)
from weldplan.motion.settings import (
    DEFAULT_RESOLUTION,  # noqa: F401 - re-exported
    PLANNERS,
    SamplingOptions,
    SamplingSettings,
    resolve_options,
)

log = logging.getLogger(__name__)

#: OMPL's own wall-clock limit where a caller budgets work (``max_checks`` or its own ``stop``),
#: in seconds per second of the run's expected time: a safety net only (the gun's SE(3)
#: re-plan, the robot's joint-space transfers)
WALL_FACTOR = 10.0


@dataclass(frozen=True)
class SampledPath:
    """A path found by an OMPL planner.

    Attributes
    ----------
    points
        ``(n, d)`` float, read-only: the path's vertices, start first and goal last (mm for
        positions; SE(3): columns ``x, y, z, qw, qx, qy, qz``). ``(0, d)`` when not solved.
    length
        Path length: R^n, the Euclidean length (mm for positions); SE(3), the sum over segments of
        the position distance (mm) plus ``rot_weight`` x the rotation angle (rad). ``inf`` when
        not solved.
    solved
        True when OMPL found an exact solution (the path reaches the goal).
    planner
        The planner's name in :data:`PLANNERS`.
    time_s
        Wall time of the call (planning and simplification), s.
    status
        One line: OMPL's status, vertex count, length, simplification.
    checks
        Calls the caller's ``is_valid`` and ``motion_valid`` received (simplification included).
    ended
        What ended the run: ``"solved"``, ``"checks"`` (the ``max_checks`` work budget),
        ``"stop"`` (the caller's ``stop``), ``"clock"`` (the wall-clock safety net ``time_s``:
        the result depends on the machine) or ``"planner"`` (the planner gave up by itself).
    """

    points: NDArray[np.float64]
    length: float
    solved: bool
    planner: str
    time_s: float
    status: str
    checks: int = 0
    ended: str = "solved"

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=np.float64, copy=True)
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (``points`` as nested lists; an unsolved length as ``None``)."""
        return {
            "points": self.points.tolist(),
            "dim": int(self.points.shape[1]) if self.points.ndim == 2 else 0,
            "length": float(self.length) if np.isfinite(self.length) else None,
            "solved": bool(self.solved),
            "planner": self.planner,
            "time_s": float(self.time_s),
            "status": self.status,
            "checks": int(self.checks),
            "ended": self.ended,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SampledPath:
        """Inverse of :meth:`to_dict`."""
        length = data["length"]
        points = np.asarray(data["points"], dtype=np.float64)
        if points.size == 0:  # an unsolved path: keep its state dimension, (0, d)
            points = points.reshape(0, int(data.get("dim", 0)))
        return cls(
            points=points.reshape(len(data["points"]), -1) if points.size else points,
            length=float("inf") if length is None else float(length),
            solved=bool(data["solved"]),
            planner=str(data["planner"]),
            time_s=float(data["time_s"]),
            status=str(data["status"]),
            checks=int(data.get("checks", 0)),
            ended=str(data.get("ended", "solved" if data["solved"] else "planner")),
        )


# --------------------------------------------------------------------------- the shared solve


def _solve(
    ss: Any,
    *,
    read: Callable[[Any], NDArray[np.float64]],
    motion_valid: MotionCheck | None,
    settings: SamplingSettings,
    seed: int | np.random.Generator | None,
    measure: Callable[[NDArray[np.float64]], float],
    dim: int,
    checks: Checks,
) -> SampledPath:
    """Run ``settings.planner`` on the prepared SimpleSetup ``ss`` and read the path back; it
    stops at ``settings.time_s`` seconds or as soon as ``checks`` is spent or its caller's
    ``stop()`` is true (OMPL asks in its own thread between its steps:
    :mod:`weldplan.motion.budget`). ``settings.reach``: the planner's ``range`` (the longest
    motion it adds in one step, in the space's metric), where the planner has one; ``None``:
    OMPL's default."""
    planner, time_s, reach = settings.planner, settings.time_s, settings.reach
    ob, og, ou = _import_ompl()
    si = ss.getSpaceInformation()
    if motion_valid is None:
        si.setStateValidityCheckingResolution(settings.resolution)
    else:
        si.setMotionValidator(_motion_validator(si, read, motion_valid))
    ss.setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
    algo = getattr(og, PLANNERS[planner])(si)
    if reach is not None and hasattr(algo, "setRange"):
        algo.setRange(float(reach))
    ss.setPlanner(algo)

    ompl_seed = _ompl_seed(seed)
    level = ou.getLogLevel()
    # OMPL logs to stderr by itself; the library never prints, so OMPL stays quiet unless this
    # module's logger is at DEBUG.
    ou.setLogLevel(ou.LOG_DEBUG if log.isEnabledFor(logging.DEBUG) else ou.LOG_NONE)
    t0 = time.perf_counter()
    try:
        if ompl_seed is not None:
            ou.RNG.setSeed(ompl_seed)
        status = ss.solve(checks.termination(ob, time_s))
        used = checks.n
        solved = bool(ss.haveExactSolutionPath())
        simplified = False
        if solved and settings.simplify:
            ss.simplifySolution(0.0)  # 0: simplifyMax, deterministic and complete
            simplified = True
        if solved:
            path = ss.getSolutionPath()
            pts = np.array([read(path.getState(i)) for i in range(path.getStateCount())])
        else:
            pts = np.zeros((0, dim))
    finally:
        ou.setLogLevel(level)
    wall = time.perf_counter() - t0
    length = measure(pts) if solved else float("inf")
    ended = checks.ended(solved, used, wall >= time_s)
    line = (
        f"{planner}: {status.asString()}, {len(pts)} vertices, length {length:.6g}"
        + (", simplified" if simplified else "")
        + f", {used} checks"
        + ("" if ended in ("solved", "planner") else f", ended by {ended}")
    )
    log.debug("%s, %.3g s", line, wall)
    return SampledPath(pts, length, solved, planner, wall, line, checks.n, ended)


# --------------------------------------------------------------------------- R^n


def plan_rn(
    start: ArrayLike,
    goal: ArrayLike,
    lower: ArrayLike,
    upper: ArrayLike,
    is_valid: StateCheck,
    *,
    motion_valid: MotionCheck | None = None,
    settings: SamplingSettings | None = None,
    **options: Unpack[SamplingOptions],
) -> SampledPath:
    """Plan a path from ``start`` to ``goal`` in the box ``[lower, upper]`` of R^d with OMPL.

    Parameters
    ----------
    start, goal
        ``(d,)`` float, inside the box (mm for positions, rad for joints).
    lower, upper
        ``(d,)`` float, the box the planner samples; ``upper > lower`` on every axis.
    is_valid
        ``is_valid(x (d,)) -> bool``: whether a state is free.
    motion_valid
        ``motion_valid(a (d,), b (d,)) -> bool``: whether the straight segment a -> b (ends
        included) is free, e.g. weldplan's FCL capsule check. ``None``: OMPL's discrete check of
        ``is_valid`` every ``settings.resolution`` x the box's diagonal.
    settings
        How the run searches (:class:`~weldplan.motion.settings.SamplingSettings`: planner,
        ``time_s``, resolution, simplification, ``max_checks`` work budget, reach); ``None``:
        the defaults (BIT*, 1 s, no work budget).
    **options
        ``seed``: seeds OMPL's process-wide RNG (see the module notes); ``None`` (the default)
        leaves it alone. ``stop``: ``stop() -> bool``, planning also ends as soon as it is true
        (OMPL asks between its own steps); ``time_s`` stays the wall-clock limit. And any field
        of :class:`~weldplan.motion.settings.SamplingSettings` by name (``planner="rrtconnect"``,
        ``max_checks=400``...), laid over ``settings``.

    Returns
    -------
    SampledPath
        ``solved=False`` (and no points) when no exact solution was found in time.

    Raises
    ------
    SamplingArgumentError
        For bad shapes, bounds, planner names, times or seeds.
    TypeError
        For a keyword that is neither ``seed``, ``stop`` nor a settings field.
    weldplan.errors.ConfigError
        When OMPL is not installed.
    """
    cfg, seed, stop = resolve_options("plan_rn", settings, dict(options))
    s = _vector("start", start)
    d = s.shape[0]
    g = _vector("goal", goal, d)
    lo = _vector("lower", lower, d)
    hi = _vector("upper", upper, d)
    _check_box(lo, hi, {"start": s, "goal": g})
    ob, og, _ = _import_ompl()
    checks = Checks(cfg.max_checks, stop)
    is_valid = checks.state(is_valid)

    space = ob.RealVectorStateSpace(d)
    bounds = ob.RealVectorBounds(d)
    for i in range(d):
        bounds.setLow(i, float(lo[i]))
        bounds.setHigh(i, float(hi[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)

    def read(state: Any) -> NDArray[np.float64]:
        return np.array([state[i] for i in range(d)], dtype=np.float64)

    ss.setStateValidityChecker(lambda state: bool(is_valid(read(state))))
    a = space.allocState()
    b = space.allocState()
    for i in range(d):
        a[i] = float(s[i])
        b[i] = float(g[i])
    ss.setStartAndGoalStates(a, b)

    return _solve(
        ss,
        read=read,
        motion_valid=checks.motion(motion_valid),
        settings=cfg,
        seed=seed,
        measure=polyline_length,
        dim=d,
        checks=checks,
    )


# --------------------------------------------------------------------------- SE(3)


def se3_length(points: ArrayLike, rot_weight: float) -> float:
    """Length of an SE(3) polyline: sum of position steps (mm) + ``rot_weight`` x rotation angles.

    Parameters
    ----------
    points
        ``(n, 7)`` rows ``x, y, z, qw, qx, qy, qz`` (unit quaternions).
    rot_weight
        mm per rad of rotation.

    Returns
    -------
    float
        mm; the rotation angle between q1 and q2 is ``2 acos(|q1 . q2|)`` (q and -q are one
        rotation).
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 7)
    if len(p) < 2:
        return 0.0
    trans = np.linalg.norm(np.diff(p[:, :3], axis=0), axis=1)
    dots = np.abs(np.einsum("ij,ij->i", p[:-1, 3:], p[1:, 3:]))
    angles = 2.0 * np.arccos(np.clip(dots, 0.0, 1.0))
    return float(trans.sum() + rot_weight * angles.sum())


def plan_se3(
    start_pos: ArrayLike,
    start_quat_wxyz: ArrayLike,
    goal_pos: ArrayLike,
    goal_quat: ArrayLike,
    lower: ArrayLike,
    upper: ArrayLike,
    is_valid: Callable[[NDArray[np.float64], NDArray[np.float64]], bool],
    *,
    motion_valid: MotionCheck | None = None,
    settings: SamplingSettings | None = None,
    **options: Unpack[SamplingOptions],
) -> SampledPath:
    """Plan a rigid-body path (a torch or a gun) between two poses with OMPL in SE(3).

    Parameters
    ----------
    start_pos, goal_pos
        ``(3,)`` positions, mm, inside ``[lower, upper]``.
    start_quat_wxyz, goal_quat
        ``(4,)`` unit quaternions ``w, x, y, z`` (norm within 1e-6 of 1, then normalised).
    lower, upper
        ``(3,)`` the position box, mm; rotations are unbounded.
    is_valid
        ``is_valid(pos (3,), quat_wxyz (4,)) -> bool``: whether the body is free at that pose.
    motion_valid
        ``motion_valid(a (7,), b (7,)) -> bool`` on rows ``x, y, z, qw, qx, qy, qz``: whether the
        motion a -> b (position linear, rotation slerp, ends included) is free, e.g. a swept FCL
        check. ``None``: OMPL's discrete check of ``is_valid`` every ``settings.resolution`` x
        the space's maximum extent.
    settings
        As in :func:`plan_rn`; here ``rot_weight`` (mm per rad) makes the metric position
        distance + ``rot_weight`` x rotation angle (OMPL's SO(3) distance is half the rotation
        angle, so its subspace weight is ``2 rot_weight``), and ``reach`` is in the metric's mm:
        shorter motions are cheaper to check and pass more often near the part.
    **options
        As in :func:`plan_rn`: ``seed``, ``stop`` (a caller's own budget, e.g. of collision
        samples) and any settings field by name.

    Returns
    -------
    SampledPath
        ``points (n, 7)``; the first row is the start pose and the last the goal pose as given
        (normalised); ``length`` by :func:`se3_length`.

    Raises
    ------
    SamplingArgumentError
        For bad shapes, bounds, quaternions, weights, planner names, times or seeds.
    TypeError
        For a keyword that is neither ``seed``, ``stop`` nor a settings field.
    """
    cfg, seed, stop = resolve_options("plan_se3", settings, dict(options))
    p0 = _vector("start_pos", start_pos, 3)
    p1 = _vector("goal_pos", goal_pos, 3)
    q0 = _unit_quat("start_quat_wxyz", start_quat_wxyz)
    q1 = _unit_quat("goal_quat", goal_quat)
    lo = _vector("lower", lower, 3)
    hi = _vector("upper", upper, 3)
    _check_box(lo, hi, {"start_pos": p0, "goal_pos": p1})
    checks = Checks(cfg.max_checks, stop)
    ss, read = _se3_setup(
        lo, hi, cfg.rot_weight, checks.state(is_valid), np.r_[p0, q0], np.r_[p1, q1]
    )
    return _solve(
        ss,
        read=read,
        motion_valid=checks.motion(motion_valid),
        settings=cfg,
        seed=seed,
        measure=lambda pts: se3_length(pts, cfg.rot_weight),
        dim=7,
        checks=checks,
    )


def _se3_setup(
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    rot_weight: float,
    is_valid: Callable[[NDArray[np.float64], NDArray[np.float64]], bool],
    start: NDArray[np.float64],
    goal: NDArray[np.float64],
) -> tuple[Any, Callable[[Any], NDArray[np.float64]]]:
    """OMPL's SE(3) problem of :func:`plan_se3`: the SimpleSetup (position box ``lo``..``hi``
    mm, SO(3) subspace weight ``2 rot_weight``, ``is_valid`` as state checker, start and goal
    rows ``(7,)`` = ``x, y, z, qw, qx, qy, qz``) and ``read(state) -> (7,)``, its inverse."""
    ob, og, _ = _import_ompl()
    space = ob.SE3StateSpace()
    bounds = ob.RealVectorBounds(3)
    for i in range(3):
        bounds.setLow(i, float(lo[i]))
        bounds.setHigh(i, float(hi[i]))
    space.setBounds(bounds)
    space.setSubspaceWeight(1, 2.0 * float(rot_weight))
    ss = og.SimpleSetup(space)

    def read(state: Any) -> NDArray[np.float64]:
        r = state.rotation()
        return np.array(
            [state.getX(), state.getY(), state.getZ(), r.w, r.x, r.y, r.z], dtype=np.float64
        )

    def state_valid(state: Any) -> bool:
        x = read(state)
        return bool(is_valid(x[:3], x[3:]))

    ss.setStateValidityChecker(state_valid)
    a = space.allocState()
    b = space.allocState()
    for st, row in ((a, start), (b, goal)):
        st.setXYZ(float(row[0]), float(row[1]), float(row[2]))
        r = st.rotation()
        r.w, r.x, r.y, r.z = (float(v) for v in row[3:])
    ss.setStartAndGoalStates(a, b)
    return ss, read
