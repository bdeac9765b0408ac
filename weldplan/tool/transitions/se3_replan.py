"""SE(3) re-planning of a blocked transition with OMPL (:mod:`weldplan.tool.transitions.plan`, exit
4).

OMPL (:func:`weldplan.motion.sampling.plan_se3`) plans the whole tool between the two welds'
clear points (both exits free, the move between them blocked) or else between the weld poses.
Its states and motions are judged by the transition planner's swept check with the sphere bound
first (:class:`~weldplan.tool.transitions.FastSweep`: the bound where it proves a pose or a motion
free, FCL's ``collide`` where it shows one blocked, FCL's distance in between) within a budget
of work that holds (:func:`se3_path`: checks and FCL samples, so the same seed gives the same
path on any machine), and the path it returns is checked again, motion by motion, by the exact
check (:class:`~weldplan.tool.transitions.SweepChecker`) before it is taken.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.motion.sampling import WALL_FACTOR
from weldplan.tool.transitions.result import BLOCKED, REPLANNED, Transition

#: the CPU-seconds safety net of one re-plan, in units of the planner's ``time_s``: reached only
#: when the work budget takes far longer than usual (a run it stops is marked ``clock``)
CLOCK_SAFETY = 3.0


def _se3_box(a: NDArray, b: NDArray, part: trimesh.Trimesh, pad: float) -> tuple[NDArray, NDArray]:
    """The TCP position box of an SE(3) re-plan: the two ends and the part's box, padded."""
    lo = np.minimum(np.minimum(a, b), np.asarray(part.bounds[0])) - pad
    hi = np.maximum(np.maximum(a, b), np.asarray(part.bounds[1])) + pad
    return lo, hi


def entering(kind: str) -> str:
    """The name of a leaving motion run backwards (a retract is an approach, an exit an entry)."""
    return kind.replace("retract", "approach").replace("exit", "enter")


def replan(
    tp: Any,
    a: Any,
    b: Any,
    ends: tuple[NDArray, NDArray] | None,
    legs: tuple[NDArray, tuple[str, ...], NDArray, tuple[str, ...]] | None,
    tried: list[str],
    done: Any,
    fallback: tuple[NDArray, NDArray, tuple[str, ...]],
) -> Transition:
    """OMPL in SE(3) between the clear points ``ends`` (both weld exits free, the move
    blocked) or else between the weld poses; its path checked again motion by motion."""
    pa, pb = (np.asarray(w.position, dtype=np.float64) for w in (a, b))
    qa, qb = (np.asarray(w.quaternion, dtype=np.float64) for w in (a, b))
    exempt = np.array([pa, pb])
    start, goal = ((ends[0], qa), (ends[1], qb)) if ends is not None else ((pa, qa), (pb, qb))
    path, status, proven = se3_path(tp, start, goal, exempt)
    if path is None:
        tried.append(f"SE(3): {status}")
        return done(*fallback, BLOCKED)
    sp, sq = path[:, :3], path[:, 3:]
    skinds: tuple[str, ...] = ("se3",) * (len(path) - 1)
    if legs is not None:
        la, ka, lb, kb = legs
        sp = np.concatenate([la[:-1], sp, lb[::-1][1:]])
        sq = np.concatenate([[qa] * (len(la) - 1), sq, [qb] * (len(lb) - 1)])
        skinds = (*ka, *skinds, *(entering(k) for k in reversed(kb)))
    # the planner's answer, checked again by the exact check where the fast one did not prove
    # it free during the run (the ends are known free; soft at the ends as OMPL's checks were:
    # softness changes only where a check gives up early)
    last = len(path) - 2
    for k in range(len(path) - 1):
        if _motion_key(path[k], path[k + 1]) in proven:
            continue
        ok3, _, why3 = tp._motions(path[k : k + 2, :3], path[k : k + 2, 3:], exempt, k == 0,
                                   k == last)  # fmt: skip
        if not ok3:
            tried.append(f"SE(3) path motion {k} {why3}")
            return done(sp, sq, skinds, BLOCKED)
    tried.append(f"SE(3): {status}")
    return done(sp, sq, skinds, REPLANNED)


def _motion_key(s: NDArray, t: NDArray) -> bytes:
    """The key of the motion between states ``s`` and ``t`` ``(7,)``, either way round (the
    same swept set, the same soft ends)."""
    a, b = np.asarray(s, dtype=np.float64).tobytes(), np.asarray(t, dtype=np.float64).tobytes()
    return min(a, b) + max(a, b)


def se3_path(
    tp: Any, start: tuple[NDArray, NDArray], goal: tuple[NDArray, NDArray], exempt: NDArray
) -> tuple[NDArray | None, str, set[bytes]]:
    """OMPL's SE(3) path ``(n, 7)`` between two poses, or ``None`` and why not; and the motions
    the fast check proved free during the run (:func:`_motion_key`), which :func:`replan` does
    not ask the exact check again: both keep the clearance everywhere on a motion they pass
    (:mod:`weldplan.tool.transitions.sweep_fast`), and the independent re-check
    (:mod:`weldplan.tool.verify.sweeps`) tests every motion of the path with its own samples.

    The budget is work and holds: OMPL stops after ``se3_checks`` state and motion checks
    (:func:`~weldplan.motion.sampling.plan_se3`'s ``max_checks``), every check after
    ``se3_samples`` FCL samples answers "not free" at once, and one motion may take at most
    ``se3_motion_cap`` samples: the same seed gives the same answer on any machine. A safety
    net of :data:`CLOCK_SAFETY` x ``time_s`` CPU seconds of this process
    (:func:`time.process_time`) does the same; a run it reaches is marked ``clock`` in its
    figures (the route is then not reproducible)."""
    try:
        from weldplan.motion.sampling import plan_se3
    except ImportError as exc:  # the wrapper or OMPL itself is missing
        return None, f"SE(3) re-planning unavailable ({exc})", set()
    check = tp.fast
    run = {"states": 0, "motions": 0, "refused": 0, "samples": 0, "bound_states": 0,
           "bound_motions": 0, "clock": False}  # fmt: skip
    tp.se3_runs.append(run)
    st = tp.settings
    deadline = time.process_time() + CLOCK_SAFETY * st.time_s
    cap = st.se3_samples

    def spent() -> bool:
        if cap is not None and run["samples"] >= cap:
            return True
        if time.process_time() > deadline:
            run["clock"] = True
            return True
        return False

    def is_valid(p: NDArray, q: NDArray) -> bool:
        run["states"] += 1
        if spent():
            run["refused"] += 1
            return False
        n0, b0 = check.exact_samples, check.bound_samples
        ok = check.state_ok(p, q, exempt)  # the bound where it proves it, else FCL
        run["samples"] += check.exact_samples - n0
        tp.samples += check.exact_samples - n0
        run["bound_states"] += check.bound_samples - b0
        return ok

    ends = np.array([np.r_[start[0], start[1]], np.r_[goal[0], goal[1]]])
    near = 1e-8 + 1e-5 * np.abs(ends)  # np.allclose's tolerances about each end, once

    def at_end(x: NDArray) -> bool:
        """Whether state ``x (7,)`` is one of the ends (``np.allclose`` to either)."""
        return bool(np.any(np.all((np.abs(x - ends) <= near) | (x == ends), axis=1)))

    def motion_valid(s: NDArray, t: NDArray) -> bool:
        run["motions"] += 1
        if spent():
            run["refused"] += 1
            return False
        soft = (at_end(s), at_end(t))
        left = st.se3_motion_cap if cap is None else min(
            st.se3_motion_cap, cap - run["samples"])  # fmt: skip
        out = check.check(s[:3], s[3:], t[:3], t[3:], exempt, soft, cap=left,
                          deadline=deadline)  # fmt: skip
        run["clock"] = run["clock"] or time.process_time() > deadline
        run["samples"] += out.samples
        tp.samples += out.samples
        run["refused"] += out.out_of_budget
        run["bound_motions"] += out.samples == 0 and out.ok
        if out.ok:
            proven.add(_motion_key(s, t))
        return out.ok

    proven: set[bytes] = set()
    if not (check.state_ok(*start, exempt) and check.state_ok(*goal, exempt)):
        return None, "an end pose of the re-plan is not free", proven
    lo, hi = _se3_box(start[0], goal[0], tp.part, pad=tp.tool.reach)
    res = plan_se3(
        start[0], start[1], goal[0], goal[1], lo, hi, is_valid,
        motion_valid=motion_valid, rot_weight=st.rot_weight, planner=st.planner,
        time_s=WALL_FACTOR * st.time_s, seed=st.seed, simplify=True, stop=spent, reach=st.se3_range,
        max_checks=st.se3_checks,
    )  # fmt: skip
    run["checks"] = res.checks
    run["clock"] = run["clock"] or res.ended == "clock"
    if run["clock"]:
        res_note = "; stopped by the clock safety net (not reproducible)"
    else:
        res_note = ""
    tally = (
        f"{run['states']} states, {run['motions']} motions checked ({run['refused']} "
        f"refused: budget spent; {run['bound_states']} states and {run['bound_motions']} "
        f"motions shown free by the sphere bound alone), {run['samples']} FCL samples{res_note}"
    )
    if not res.solved:
        return None, f"{res.planner}: {res.status}; {tally}", proven
    return np.asarray(res.points, dtype=np.float64), f"{res.planner}: {res.status}; {tally}", proven
