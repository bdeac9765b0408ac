"""weldplan.motion.roadmap: OMPL's PRM built once, queried many times, against exact answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("ompl")

from weldplan.errors import ConfigError  # noqa: E402
from weldplan.motion.roadmap import (  # noqa: E402
    STOP_CHECKS,
    STOP_MILESTONES,
    Roadmap,
    RoadmapSettings,
)

# The 10 x 10 square of test_motion_sampling with its wall x in (4, 6), y < 8, and a closed
# pocket: the ring 1 < |x - (8, 8)|_inf < 1.5 is blocked, so (8, 8) is reached from nowhere else.
LO, HI = np.zeros(2), np.full(2, 10.0)
LEFT, RIGHT, POCKET = np.array([1.0, 1.0]), np.array([9.0, 1.0]), np.array([8.0, 8.0])


def blocked(x: np.ndarray) -> bool:
    wall = 4.0 < x[0] < 6.0 and x[1] < 8.0
    ring = 1.0 < np.abs(x - POCKET).max() < 1.5
    return bool(wall or ring)


def valid(x: np.ndarray) -> bool:
    return not blocked(x)


def motion(a: np.ndarray, b: np.ndarray) -> bool:
    """Dense sampling every 0.01: thinner than the wall (2) and the ring (0.5)."""
    n = max(2, int(math.ceil(np.linalg.norm(b - a) / 0.01)) + 1)
    return all(valid(a + t * (b - a)) for t in np.linspace(0.0, 1.0, n))


def test_the_roadmap_joins_round_the_wall_and_never_into_the_closed_pocket():
    rm = Roadmap(LO, HI, valid, motion, RoadmapSettings(milestones=80, neighbours=8), seed=1)
    assert not motion(LEFT, RIGHT)  # the straight motion is blocked
    comp = rm.connect(np.array([LEFT, RIGHT, POCKET]))
    assert comp[0] == comp[1] >= 0
    assert comp[2] != comp[0]  # exact: no path exists into the pocket
    P = rm.path(LEFT, RIGHT)
    np.testing.assert_array_equal(P[0], LEFT)
    np.testing.assert_array_equal(P[-1], RIGHT)
    # independent check: every edge of the path is free at a finer step
    for a, b in zip(P[:-1], P[1:], strict=True):
        assert all(valid(a + t * (b - a)) for t in np.linspace(0.0, 1.0, 4001))
    # no path can be shorter than the exact shortest one round the wall's two top corners
    assert np.linalg.norm(np.diff(P, axis=0), axis=1).sum() >= 2 * math.hypot(3, 7) + 2 - 1e-9
    assert rm.path(LEFT, POCKET) is None
    rep = rm.report()
    assert rep.stopped == STOP_MILESTONES and rep.queries == 3
    assert rep.milestones == 83 and rep.components[0] == 2


def test_the_same_seed_gives_the_same_roadmap_and_another_seed_another():
    s = RoadmapSettings(milestones=40, neighbours=6)
    a, b, c = (Roadmap(LO, HI, valid, motion, s, seed=k) for k in (7, 7, 8))
    for rm in (a, b, c):
        rm.connect(np.array([LEFT, RIGHT]))
    Xa, Ea, _ = a.graph()
    Xb, Eb, _ = b.graph()
    np.testing.assert_array_equal(Xa, Xb)
    assert Ea == Eb
    assert a.report().motion_checks == b.report().motion_checks
    assert not np.array_equal(Xa, c.graph()[0][: len(Xa)])


def test_growth_stops_at_its_state_check_budget_and_bad_settings_are_refused():
    rm = Roadmap(LO, HI, lambda x: False, motion, RoadmapSettings(max_checks=500), seed=0)
    rep = rm.report()
    assert rep.stopped == STOP_CHECKS and rep.milestones == 0
    assert 500 <= rep.state_checks < 1000  # OMPL asks the budget between batches of samples
    assert (rm.connect(np.array([LEFT])) == -1).all()  # invalid: not added
    with pytest.raises(ConfigError, match="milestones"):
        RoadmapSettings(milestones=0)
