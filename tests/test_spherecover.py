"""The sphere cover's grouping: the same groups and the same bits as numpy's row unique and
unbuffered ``ufunc.at`` (weldplan.geometry.spherecover)."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.geometry.spherecover import cell_groups, group_reduce, sphere_cover


@pytest.mark.parametrize("spread", [3, 1000, 2**40])
def test_cell_groups_number_rows_as_numpy_unique(spread: int) -> None:
    rng = np.random.default_rng(7)
    key = rng.integers(-spread, spread, size=(2000, 3), dtype=np.int64)
    key[::5] = key[1::5]  # repeated rows
    want = np.unique(key, axis=0, return_inverse=True)[1].ravel()
    assert np.array_equal(cell_groups(key), want)


@pytest.mark.parametrize("ufunc", [np.minimum, np.maximum])
def test_group_reduce_is_ufunc_at(ufunc: np.ufunc) -> None:
    rng = np.random.default_rng(3)
    group = rng.integers(0, 50, size=3000)
    group[:50] = np.arange(50)  # every group non-empty
    values = rng.normal(size=(3000, 3)) * 1e3
    want = np.full((50, 3), np.inf if ufunc is np.minimum else -np.inf)
    ufunc.at(want, group, values)
    got = group_reduce(ufunc, values, group, 50)
    assert got.tobytes() == want.tobytes()


def test_cover_holds_every_vertex() -> None:
    rng = np.random.default_rng(1)
    v = rng.uniform(-200, 200, size=(600, 3))
    f = rng.integers(0, 600, size=(400, 3))
    c, r, g = sphere_cover(v, f, 25.0)
    # every triangle's corners lie in its own sphere
    d = np.linalg.norm(v[f] - c[g][:, None, :], axis=2)
    assert np.all(d <= r[g][:, None])
    # and the groups are the triangles' centroid cells
    key = np.floor(v[f].mean(axis=1) / 25.0).astype(np.int64)
    assert np.array_equal(g, np.unique(key, axis=0, return_inverse=True)[1].ravel())
