"""weldplan.motion.sampling: OMPL planners with the caller's checks, against exact answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("ompl")

from weldplan.errors import PlanningError  # noqa: E402
from weldplan.motion import (  # noqa: E402
    PLANNERS,
    SampledPath,
    SamplingArgumentError,
    SamplingSettings,
    plan_rn,
    plan_se3,
)
from weldplan.motion.sampling import se3_length  # noqa: E402

# A 10 x 10 square with a wall x in (4, 6), y < 8 (open set: its boundary is free). From (1, 1) to
# (9, 1) the shortest path wraps the wall's two top corners: exact length 2 sqrt(3^2 + 7^2) + 2.
LO, HI = np.zeros(2), np.full(2, 10.0)
START, GOAL = np.array([1.0, 1.0]), np.array([9.0, 1.0])
WALL_LO, WALL_HI = np.array([4.0, -1.0]), np.array([6.0, 8.0])
DETOUR = 2.0 * math.hypot(3.0, 7.0) + 2.0


def in_wall(x: np.ndarray) -> bool:
    return bool(np.all(x[:2] > WALL_LO) and np.all(x[:2] < WALL_HI))


def segment_hits_wall(a: np.ndarray, b: np.ndarray) -> bool:
    """Exact: does the segment a-b meet the open box (Liang-Barsky clipping)?"""
    a, b = np.asarray(a[:2], float), np.asarray(b[:2], float)
    d = b - a
    t0, t1 = 0.0, 1.0
    for k in range(2):
        if abs(d[k]) < 1e-15:
            if not (WALL_LO[k] < a[k] < WALL_HI[k]):
                return False
            continue
        ta, tb = (WALL_LO[k] - a[k]) / d[k], (WALL_HI[k] - a[k]) / d[k]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    # an open box is met only when the clipped interval has positive length inside it
    return t1 - t0 > 1e-12


def test_free_space_is_the_straight_line():
    start, goal = np.array([1.0, 2.0, 3.0]), np.array([8.0, -4.0, 5.5])
    path = plan_rn(start, goal, [-10] * 3, [10] * 3, lambda x: True, time_s=0.5, seed=1)
    assert path.solved and path.planner == "bitstar"
    assert path.points.shape == (2, 3)
    np.testing.assert_array_equal(path.points[0], start)
    np.testing.assert_array_equal(path.points[-1], goal)
    assert path.length == pytest.approx(np.linalg.norm(goal - start), rel=1e-12)


@pytest.mark.parametrize("planner", ["bitstar", "rrtstar"])
def test_wall_detour_is_never_shorter_than_exact_and_close_to_it(planner):
    calls = []

    def motion_valid(a, b):
        calls.append(1)
        return not segment_hits_wall(a, b)

    path = plan_rn(
        START,
        GOAL,
        LO,
        HI,
        lambda x: not in_wall(x),
        motion_valid=motion_valid,
        planner=planner,
        time_s=0.5,
        seed=7,
    )
    assert path.solved, path.status
    assert calls, "the caller's motion check must be the one used"
    np.testing.assert_array_equal(path.points[[0, -1]], [START, GOAL])
    edges = zip(path.points[:-1], path.points[1:], strict=True)
    assert all(not segment_hits_wall(a, b) for a, b in edges)
    assert path.length >= DETOUR - 1e-9
    assert path.length <= DETOUR * 1.05
    lengths = np.linalg.norm(np.diff(path.points, axis=0), axis=1).sum()
    assert path.length == pytest.approx(lengths, rel=1e-12)


def test_discrete_motion_check_uses_is_valid_at_the_resolution():
    seen = []

    def is_valid(x):
        seen.append(x.copy())
        return not in_wall(x)

    # rrtconnect stops at its first solution (time_s is only a cap) and the simplifier runs to
    # convergence, so with a seed the result does not depend on the machine's load
    path = plan_rn(
        START, GOAL, LO, HI, is_valid, resolution=0.002, planner="rrtconnect", time_s=30.0, seed=3
    )
    assert path.solved
    assert len(seen) > 100
    # states along every edge at the resolution are free; the detour holds up to one step
    step = 0.002 * np.linalg.norm(HI - LO)
    assert path.length >= DETOUR - 2 * step
    assert path.length <= DETOUR * 1.05


def test_same_seed_same_path_other_seed_other_path():
    def run(seed):
        return plan_rn(
            START,
            GOAL,
            LO,
            HI,
            lambda x: not in_wall(x),
            planner="rrtconnect",
            seed=seed,
            simplify=False,
            time_s=2.0,
        )

    a, b, c = run(11), run(11), run(12)
    assert a.solved and b.solved and c.solved
    np.testing.assert_array_equal(a.points, b.points)
    assert a.points.shape != c.points.shape or not np.array_equal(a.points, c.points)


def test_no_path_is_a_result_not_an_exception():
    # a wall across the whole square: the goal cannot be reached
    path = plan_rn(
        START,
        GOAL,
        LO,
        HI,
        lambda x: not (4 < x[0] < 6),
        planner="rrtconnect",
        time_s=0.1,
        seed=1,
    )
    assert not path.solved
    assert path.points.shape == (0, 2)
    assert path.length == math.inf
    assert "rrtconnect" in path.status


def test_invalid_start_is_unsolved():
    path = plan_rn([5, 1], GOAL, LO, HI, lambda x: not in_wall(x), time_s=0.05, seed=1)
    assert not path.solved


@pytest.mark.parametrize(
    "kwargs",
    [
        {"planner": "astar"},
        {"time_s": 0.0},
        {"resolution": 0.0},
        {"goal": [9.0, 1.0, 0.0]},
        {"start": [11.0, 1.0]},
        {"upper": [10.0, 0.0]},
        {"seed": 1.5},
    ],
)
def test_bad_arguments_raise_a_planning_and_value_error(kwargs):
    args = {"start": START, "goal": GOAL, "lower": LO, "upper": HI}
    args.update({k: v for k, v in kwargs.items() if k in args})
    rest = {k: v for k, v in kwargs.items() if k not in args}
    with pytest.raises(SamplingArgumentError) as info:
        plan_rn(args["start"], args["goal"], args["lower"], args["upper"], lambda x: True, **rest)
    assert isinstance(info.value, PlanningError) and isinstance(info.value, ValueError)


def test_every_registered_planner_runs_with_a_python_motion_check():
    for planner in PLANNERS:
        path = plan_rn(
            START,
            GOAL,
            LO,
            HI,
            lambda x: not in_wall(x),
            motion_valid=lambda a, b: not segment_hits_wall(a, b),
            planner=planner,
            time_s=0.5,
            seed=5,
        )
        assert path.solved, path.status
        assert path.length >= DETOUR - 1e-9


def test_sampled_path_round_trips_json_and_is_read_only():
    # rrtconnect stops on its own, so the run is the same at any load (BIT* stops on the clock)
    path = plan_rn(
        START, GOAL, LO, HI, lambda x: not in_wall(x), planner="rrtconnect", time_s=30, seed=2
    )
    assert path.solved
    again = SampledPath.from_dict(path.to_dict())
    np.testing.assert_array_equal(again.points, path.points)
    assert (again.length, again.solved, again.planner) == (path.length, path.solved, path.planner)
    with pytest.raises(ValueError):
        path.points[0, 0] = 3.0


def test_an_unsolved_path_round_trips_json_with_its_dimension():
    blocked = plan_rn(
        START, GOAL, LO, HI, lambda x: not 4.0 < x[0] < 6.0, planner="rrtconnect", time_s=0.2
    )
    assert not blocked.solved and blocked.points.shape[0] == 0
    again = SampledPath.from_dict(blocked.to_dict())
    assert again.points.shape == blocked.points.shape
    assert again.length == blocked.length == float("inf")


# --------------------------------------------------------------------------- SE(3)

Q_START = np.array([1.0, 0.0, 0.0, 0.0])
ANGLE = 1.2  # rad about z
Q_GOAL = np.array([math.cos(ANGLE / 2), 0.0, 0.0, math.sin(ANGLE / 2)])


def test_se3_free_space_is_one_motion_with_the_weighted_length():
    p0, p1 = np.array([1.0, 2.0, 3.0]), np.array([7.0, 5.0, 9.0])
    path = plan_se3(
        p0,
        Q_START,
        p1,
        Q_GOAL,
        [0] * 3,
        [10] * 3,
        lambda p, q: True,
        rot_weight=25.0,
        time_s=0.5,
        seed=1,
    )
    assert path.solved and path.points.shape == (2, 7)
    np.testing.assert_allclose(path.points[0], np.r_[p0, Q_START], atol=1e-12)
    np.testing.assert_allclose(path.points[-1], np.r_[p1, Q_GOAL], atol=1e-12)
    assert path.length == pytest.approx(np.linalg.norm(p1 - p0) + 25.0 * ANGLE, rel=1e-9)


def test_se3_around_a_wall_keeps_the_poses_and_the_lower_bound():
    def valid(p, q):
        assert p.shape == (3,) and q.shape == (4,)
        return not in_wall(p)

    def motion(a, b):
        assert a.shape == (7,) and b.shape == (7,)
        return not segment_hits_wall(a, b)

    p0, p1 = np.r_[START, 5.0], np.r_[GOAL, 5.0]
    path = plan_se3(
        p0,
        Q_START,
        p1,
        Q_GOAL,
        [0] * 3,
        [10] * 3,
        valid,
        motion_valid=motion,
        rot_weight=2.0,
        time_s=1.0,
        seed=3,
    )
    assert path.solved, path.status
    np.testing.assert_allclose(path.points[0], np.r_[p0, Q_START], atol=1e-12)
    np.testing.assert_allclose(path.points[-1], np.r_[p1, Q_GOAL], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(path.points[:, 3:], axis=1), 1.0, atol=1e-9)
    # positions must wrap the wall; rotations must turn by ANGLE at least (triangle inequality)
    assert path.length >= DETOUR + 2.0 * ANGLE - 1e-9
    assert path.length == pytest.approx(se3_length(path.points, 2.0), rel=1e-12)


def test_se3_rejects_a_quaternion_that_is_not_unit():
    with pytest.raises(SamplingArgumentError, match="unit quaternion"):
        plan_se3([1] * 3, [1, 0, 0, 0.1], [2] * 3, Q_GOAL, [0] * 3, [10] * 3, lambda p, q: True)
    with pytest.raises(SamplingArgumentError, match="rot_weight"):
        plan_se3(
            [1] * 3, Q_START, [2] * 3, Q_GOAL, [0] * 3, [10] * 3, lambda p, q: True, rot_weight=0
        )


def test_se3_length_counts_q_and_minus_q_as_one_rotation():
    pts = np.array([[0, 0, 0, *Q_GOAL], [3, 4, 0, *(-Q_GOAL)]])
    assert se3_length(pts, 10.0) == pytest.approx(5.0)


def _bitstar_checks(seed, max_checks, planner="bitstar"):
    return plan_rn(
        START,
        GOAL,
        LO,
        HI,
        lambda x: not in_wall(x),
        motion_valid=lambda a, b: not segment_hits_wall(a, b),
        planner=planner,
        seed=seed,
        time_s=60.0,  # the safety net only: the work budget ends these runs
        max_checks=max_checks,
    )


def test_an_anytime_planner_on_a_work_budget_gives_the_same_path_for_the_same_seed():
    # BIT* keeps improving until a limit: on the clock its path depends on the machine's speed,
    # on a budget of checks it is the same on every run
    a, b, c = (_bitstar_checks(s, 3000) for s in (5, 5, 6))
    assert a.solved and b.solved and c.solved
    assert a.ended == b.ended == "solved" and a.checks >= 3000
    np.testing.assert_array_equal(a.points, b.points)
    assert a.checks == b.checks
    assert a.points.shape != c.points.shape or not np.array_equal(a.points, c.points)
    assert DETOUR - 1e-6 <= a.length <= DETOUR * 1.05


def test_a_starved_work_budget_gives_up_and_says_so():
    path = _bitstar_checks(5, 3, planner="rrtconnect")
    assert not path.solved and path.ended == "checks"
    assert 3 <= path.checks < 50  # a step in progress finishes first
    assert "ended by checks" in path.status
    full = _bitstar_checks(5, 100_000, planner="rrtconnect")
    assert full.solved and full.ended == "solved" and full.checks > 3


def test_a_run_ended_by_the_clock_says_so():
    # a wall across the whole square: only the clock can end it
    path = plan_rn(
        START, GOAL, LO, HI, lambda x: not (4 < x[0] < 6), planner="rrtconnect",
        time_s=0.05, seed=1, max_checks=10**9,
    )  # fmt: skip
    assert not path.solved and path.ended == "clock"


def test_se3_on_a_work_budget_is_reproducible():
    def run(seed):
        return plan_se3(
            np.r_[START, 5.0], Q_START, np.r_[GOAL, 5.0], Q_GOAL, [0] * 3, [10] * 3,
            lambda p, q: not in_wall(p), motion_valid=lambda a, b: not segment_hits_wall(a, b),
            rot_weight=2.0, planner="bitstar", time_s=60.0, seed=seed, max_checks=2000,
        )  # fmt: skip

    a, b = run(3), run(3)
    assert a.solved and a.checks == b.checks
    np.testing.assert_array_equal(a.points, b.points)


# --------------------------------------------------------------------------- settings


def test_a_settings_object_and_its_keyword_conveniences_are_one_call():
    # rrtconnect on a work budget: the same seed gives the same path, whichever way it is asked
    settings = SamplingSettings(planner="rrtconnect", time_s=60.0, max_checks=5000)
    a = plan_rn(START, GOAL, LO, HI, lambda x: not in_wall(x), settings=settings, seed=4)
    b = plan_rn(
        START, GOAL, LO, HI, lambda x: not in_wall(x),
        planner="rrtconnect", time_s=60.0, max_checks=5000, seed=4,
    )  # fmt: skip
    # a keyword overrides its field of the settings given
    c = plan_rn(
        START, GOAL, LO, HI, lambda x: not in_wall(x),
        settings=SamplingSettings(planner="bitstar"), planner="rrtconnect", time_s=60.0,
        max_checks=5000, seed=4,
    )  # fmt: skip
    assert a.solved and a.planner == b.planner == c.planner == "rrtconnect"
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.points, c.points)
    assert a.checks == b.checks == c.checks


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("planner", "astar"),
        ("time_s", float("nan")),
        ("resolution", 1.5),
        ("max_checks", 0),
        ("reach", -1.0),
        ("rot_weight", 0.0),
    ],
)
def test_bad_settings_fail_once_when_made_naming_the_field(field, value):
    with pytest.raises(SamplingArgumentError, match=field):
        SamplingSettings(**{field: value})


def test_an_unknown_keyword_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="'planer'"):
        plan_rn(START, GOAL, LO, HI, lambda x: True, planer="rrtconnect")
