"""The pair-planning tasks that executors run: one local path, a batch of them in a worker, and
the candidate pairs planned up front on large stations.

Module-level functions so process pools and Dask can pickle them; kept apart from
:mod:`weldplan.weld.pipeline` and :mod:`weldplan.weld.pairs` so both can use them without importing
each other.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def _plan_pair_task(
    cell: Any, i: int, j: int, method: str, params: dict, seed: int, budget: float | None
) -> Any:
    """One local path (module-level so process pools can pickle it); ``method="ompl"`` runs
    OMPL's BIT* for ``budget`` seconds (1 s without one). A pair whose search would
    exceed the voxel cap (:class:`~weldplan.weld.local.SearchLimitError`) comes back as a failed
    path with the reason: the sequencer then treats it as unreachable."""
    from weldplan.weld.local import LocalPath, SearchLimitError, plan_pair

    if method == "ompl":  # OMPL's BIT* on the same FCL checks (weldplan.weld.local_ompl)
        from weldplan.weld.local_ompl import DEFAULT_TIME_S, plan_pair_ompl

        return plan_pair_ompl(cell, i, j, rng=seed, time_s=budget or DEFAULT_TIME_S)
    try:
        return plan_pair(cell, i, j, method=method, params=params, rng=seed, time_budget=budget)
    except SearchLimitError as exc:
        return LocalPath(
            points=np.zeros((0, 3)),
            length=np.inf,
            inner_length=np.inf,
            method=method,
            success=False,
            reason=str(exc),
        )


def _plan_pairs_task(cell: Any, batch: list[tuple], budget: float | None) -> list[Any]:
    """A batch of local paths in one worker task; ``cell`` arrives as a
    :func:`weldplan.weld.parallel.share_cell` reference (built once per worker)."""
    from weldplan.weld.parallel import resolve

    cell = resolve(cell)
    return [_plan_pair_task(cell, i, j, m, prm, s, budget) for i, j, m, prm, s in batch]


def candidate_pairs(
    xyz: NDArray[np.float64],
    k: int,
    pair_index: NDArray[np.intp] | None = None,
    radius: float | None = None,
) -> NDArray[np.intp]:
    """Indices (into the upper-triangle pair list) of each joint with its ``k`` nearest joints.

    Parameters
    ----------
    xyz
        ``(n, 3)`` weld spots (mm); nearness is the straight-line distance between them.
    k
        Neighbours per joint (ties broken by joint order).
    pair_index
        ``(n, n)`` pair number of ``(i, j)``, as built by :func:`plan_route`; built when None.
    radius
        mm: a neighbour farther than this is not a candidate (None: no limit).

    Returns
    -------
    ``(m,) intp``, sorted, unique.
    """
    from scipy.spatial import cKDTree

    n = len(xyz)
    if pair_index is None:
        iu, ju = np.triu_indices(n, 1)
        pair_index = -np.ones((n, n), dtype=np.intp)
        pair_index[iu, ju] = pair_index[ju, iu] = np.arange(len(iu))
    k = min(int(k), n - 1)
    if k < 1:
        return np.zeros(0, dtype=np.intp)
    bound = np.inf if radius is None else float(radius)
    _, nb = cKDTree(xyz).query(xyz, k=k + 1, distance_upper_bound=bound)
    rows = np.repeat(np.arange(n), k + 1)
    cols = nb.reshape(-1)
    keep = (rows != cols) & (cols < n)  # cols == n: no neighbour within the radius
    return np.unique(pair_index[rows[keep], cols[keep]])
