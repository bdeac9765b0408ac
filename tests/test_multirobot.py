"""Paper 001 sec. 3 building blocks: expansion circles, collision probabilities, eq. 15."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.planar.multirobot import collision_probability, expansion_zone, score


def test_expansion_zone_of_a_rectangle():
    z = expansion_zone([[0, 0], [4, 0], [4, 3], [0, 3]])
    assert z.d_max == pytest.approx(5.0)  # the diagonal
    assert z.center == pytest.approx((2.0, 1.5))
    assert z.radii == pytest.approx((2.5, 3.0, 3.5))


def test_collision_probabilities_by_ring():
    z = expansion_zone([[0, 0], [4, 0], [4, 3], [0, 3]])
    c = np.array(z.center)
    pts = [c, c + [0, 2.4], c + [0, 2.8], c + [0, 3.2], c + [0, 3.6]]
    np.testing.assert_allclose(collision_probability([z], pts), [1.0, 0.85, 0.65, 0.45, 0.0])


def test_score_eq15():
    assert score(10.0, 5.0) == 98
    assert score(10.0, 3.0) == 96  # ceil(3.33) = 4
    np.testing.assert_array_equal(score([10.0, 10.0], [10.0, 20.0]), [99, 99])
    with pytest.raises(ValueError):
        score(1.0, 0.0)
