"""The search box of a pair grows stepwise and never past its voxel cap (issue 9): a pair whose
first box does not connect it still gets its path, a cap too small gives a clear error, and the
pipeline records such a pair as unreachable instead of dying."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _boxcell import box_cell

from weldplan.errors import PlanningError
from weldplan.geometry.collision import CollisionModel
from weldplan.weld.local import LocalParams, SearchLimitError, plan_local_path, plan_pair
from weldplan.weld.pipeline import _plan_pair_task

QUICK = {"n_iterations": 10, "n_ants": 10}
A = np.array([10.0, 0.0, 0.0])
B = np.array([90.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def holed_wall():
    """A wall at x = 50 mm across the whole region, with its only hole at y = 40..80 mm: the
    pair A, B (y = 0) is connected only through a box at least ~45 mm wider than the pair's."""
    wall = [
        (np.array([48.0, -100.0, -100.0]), np.array([52.0, 40.0, 100.0])),
        (np.array([48.0, 80.0, -100.0]), np.array([52.0, 200.0, 100.0])),
    ]
    return box_cell(wall, np.array([0.0, -20.0, -30.0]), np.array([100.0, 100.0, 30.0]))


def _plan(cell, method="so-aco", **prm):
    return plan_local_path(
        cell.grid, cell.collision, A, B, cell.virtual(A), cell.virtual(B), method=method,
        params={**QUICK, **prm}, rng=0,
    )  # fmt: skip


@pytest.mark.parametrize("method", ["so-aco", "aco"])
def test_a_pair_that_needs_a_larger_box_still_gets_its_path(holed_wall, method):
    n_grid = int(np.prod(holed_wall.grid.shape))
    lp = _plan(holed_wall, method, crop_margin=10.0)
    assert lp.success, lp.reason
    assert lp.search_boxes > 1  # the first box (10 mm around the pair) did not connect it
    assert 0 < lp.search_voxels < n_grid  # and the box that did is still not the whole grid
    judge = CollisionModel(holed_wall.collision.mesh.copy())
    assert judge.path_free(lp.points[1:-1], holed_wall.grid.clearance)
    assert lp.points[1:-1, 1].max() >= 40.0  # through the hole
    # the box grew by x2 steps: 10 -> 20 -> 40 -> 80 mm
    wide = _plan(holed_wall, method, crop_margin=80.0)
    assert wide.search_boxes == 1 and wide.search_voxels == lp.search_voxels


def _smallest_connecting_box(cell) -> int:
    """Voxels of the smallest box (the pair's box grown by m voxels) that connects A and B,
    found by trying every m (brute force, independent of the growth schedule)."""
    from scipy import ndimage

    s, g = cell.virtual(A), cell.virtual(B)
    shape = np.asarray(cell.grid.shape)
    for m in range(int(shape.max())):
        lo = np.maximum(np.minimum(s, g) - m, 0)
        hi = np.minimum(np.maximum(s, g) + m + 1, shape)
        lab, _ = ndimage.label(cell.grid.free[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]])
        if lab[tuple(s - lo)] == lab[tuple(g - lo)]:
            return int(np.prod(hi - lo))
    raise AssertionError("never connected")


def test_a_cap_too_small_is_a_clear_error(holed_wall):
    need = _smallest_connecting_box(holed_wall)
    with pytest.raises(SearchLimitError, match="max_search_voxels") as err:
        _plan(holed_wall, crop_margin=10.0, max_search_voxels=need - 1)
    assert isinstance(err.value, PlanningError)
    assert err.value.cap == need - 1 and err.value.voxels > need - 1
    # the largest box within the cap is tried before giving up: a cap of exactly the smallest
    # connecting box succeeds although the x2 steps (10, 20, 40, 80 mm) jump past it
    ok = _plan(holed_wall, crop_margin=10.0, max_search_voxels=need)
    assert ok.success and ok.search_voxels == need


def test_the_whole_grid_over_the_cap_is_never_searched(holed_wall):
    n_grid = int(np.prod(holed_wall.grid.shape))
    whole = _plan(holed_wall, crop_margin=None)
    assert whole.success and whole.search_voxels == n_grid and whole.search_boxes == 0
    # without a margin, a grid over the cap is searched in boxes grown from the pair's own
    need = _smallest_connecting_box(holed_wall)
    with pytest.raises(SearchLimitError):
        _plan(holed_wall, crop_margin=None, max_search_voxels=need - 1)
    # the exact search on a grid over the cap runs on the growing boxes too
    lp = _plan(holed_wall, "exact", crop_margin=10.0, max_search_voxels=n_grid - 1)
    assert lp.success and lp.search_boxes > 1 and lp.search_voxels < n_grid
    whole = _plan(holed_wall, "exact")
    assert whole.search_voxels == n_grid and whole.search_boxes == 0
    assert lp.inner_length >= whole.inner_length - 1e-9  # exact within its box only


def test_memory_stays_bounded_by_the_cap(holed_wall):
    for cap in (20_000, 40_000, None):
        lp = _plan(holed_wall, crop_margin=5.0, max_search_voxels=cap)
        assert lp.success
        assert cap is None or lp.search_voxels <= cap


def test_the_pipeline_records_a_pair_over_the_cap_as_unreachable(holed_wall):
    g = holed_wall
    cell = SimpleNamespace(
        grid=g.grid,
        collision=g.collision,
        joints=SimpleNamespace(xyz=np.stack([A, B]), ids=("a", "b")),
        virtual_index=np.stack([g.virtual(A), g.virtual(B)]),
    )
    prm = {**QUICK, "crop_margin": 10.0, "max_search_voxels": 1000}
    with pytest.raises(SearchLimitError, match="joints a -> b"):
        plan_pair(cell, 0, 1, params=prm, rng=0)
    lp = _plan_pair_task(cell, 0, 1, "so-aco", prm, 0, None)
    assert not lp.success and np.isinf(lp.length) and "max_search_voxels" in lp.reason


def test_params_are_checked():
    with pytest.raises(ValueError, match="crop_growth"):
        LocalParams(crop_growth=1.0)
    with pytest.raises(ValueError, match="max_search_voxels"):
        LocalParams(max_search_voxels=0)
    assert LocalParams.coerce({"max_search_voxels": 5}).max_search_voxels == 5
