"""One walk up a weld pose's TCP axis for all its lifts (weldplan.tool.transitions.axis_walk),
judged against the independent swept re-check (weldplan.tool.verify.sweeps) and the planner's
own check of each lift."""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from weldplan.tool import Tool, TransitionSettings
from weldplan.tool.transitions import TransitionPlanner, quat_to_matrix
from weldplan.tool.transitions.axis_walk import AxisWalk
from weldplan.tool.verify.sweeps import _Sweeps

LIFTS = (4.0, 5.0, 10.0, 20.0, 50.0)


def _box(extents, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents).apply_translation(centre)


def _stick() -> Tool:
    """A 10 mm square stick 200 mm long behind the TCP (along TCP -z), its tip face at the TCP."""
    m = _box((10, 10, 200), (0, 0, -100))
    return Tool("stick", np.asarray(m.vertices), np.asarray(m.faces))


def _part() -> trimesh.Trimesh:
    """A plate (top z = 0), caps 208-218 and 230-240 mm above it, and a wall beside the spots:
    lifts end in the caps at different lengths, tilted sticks graze the wall."""
    return trimesh.util.concatenate([
        _box((600, 600, 2), (0, 0, -1)),
        _box((40, 40, 10), (0, 0, 213)),
        _box((40, 40, 10), (60, 0, 235)),
        _box((10, 300, 150), (-45, 0, 75)),
    ])


def _poses(n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``n`` TCP poses on the plate: spots near the caps and the wall, the axis tilted up to
    25 deg off the plate's normal, any spin."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        p = np.array([rng.uniform(-30, 90), rng.uniform(-30, 30), 0.0])
        tilt, az, spin = np.radians(rng.uniform(0, 25)), rng.uniform(0, 2 * np.pi), rng.uniform(
            0, 2 * np.pi)  # fmt: skip
        # TCP z points into the plate (the tool stands above it along -z)
        R = Rotation.from_euler("zyz", [az, np.pi - tilt, spin]).as_matrix()
        out.append((p, R))
    return out


def test_the_walk_never_says_free_where_the_independent_re_check_finds_the_lift_blocked():
    part, tool = _part(), _stick()
    clearance, radius = 5.0, 20.0
    planner = TransitionPlanner(
        part, tool, TransitionSettings(retract=50.0, side_exit=0.0, se3=False),
        clearance=clearance, contact_radius=radius,
    )  # fmt: skip
    sweeps = _Sweeps(part, tool, clearance, radius)
    agree = free = blocked_by_both = 0
    for p, R in _poses(40, seed=3):
        q = Rotation.from_matrix(R).as_quat()[[3, 0, 1, 2]]
        R = quat_to_matrix(q)
        walk = AxisWalk(planner.checker, p, R, max(LIFTS))
        seen = []
        for L in LIFTS:
            got = walk.lift(L)
            end = p - L * R[:, 2]
            sweeps.crop(np.array([p, end]))
            why = sweeps.motion(p, q, end, q, p[None], 4.0)
            own = planner.checker.check(p, q, end, q, p[None], (True, False))
            if got.ok:
                free += 1
                # the independent re-check (its own samples and bound) finds it free
                assert why == "", (p, L, why)
            elif why:
                blocked_by_both += 1
            agree += got.ok == own.ok
            seen.append(got.ok)
        # the lifts are one motion cut at other lengths: a free lift frees every shorter one
        assert seen == sorted(seen, reverse=True), seen
    n = 40 * len(LIFTS)
    assert free > 0 and blocked_by_both > 0  # both answers occur on this part
    assert agree >= 0.9 * n  # the lift's own check gives up early elsewhere at most rarely


def test_the_walk_answers_a_shorter_lift_from_the_samples_a_longer_one_took():
    part, tool = _part(), _stick()
    planner = TransitionPlanner(
        part, tool, TransitionSettings(retract=50.0, side_exit=0.0, se3=False),
        clearance=5.0, contact_radius=20.0,
    )  # fmt: skip
    p = np.array([150.0, 100.0, 0.0])  # open sky above: every lift free
    R = quat_to_matrix(np.array([0.0, 1.0, 0.0, 0.0]))  # TCP z down into the plate
    walk = AxisWalk(planner.checker, p, R, 50.0)
    long = walk.lift(50.0)
    assert long.ok and long.samples > 0
    for L in (4.0, 10.0, 20.0):
        short = walk.lift(L)
        assert short.ok and short.samples == 0
    # a fresh walk asked for the short lift first takes no more samples for it than the long
    fresh = AxisWalk(planner.checker, p, R, 50.0)
    assert fresh.lift(4.0).samples <= long.samples
