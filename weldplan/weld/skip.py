"""Partial plans (``--skip-unreachable``): leave out the joints that cannot be reached.

When some joints have no collision-free path to the others (spots facing into a volume the body
closes, or on the far side of a panel that spans the region of interest), the pipeline finds the
groups and raises :class:`~weldplan.errors.UnreachableJointsError`. With
``PlanConfig(skip_unreachable=True)`` it keeps the largest group instead (ties: the group of the
earlier joint in the file), plans it, and lists every joint left out, with the reason, in
``route.stats["skipped"]`` as ``[{"id": ..., "reason": ...}]``. The route's joint table keeps every
joint of the cell, so ``weldplan verify --joints`` still compares the whole file; verification
accepts a joint that is never visited only when the route lists it as skipped.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import PlanningError, UnreachableJointsError


def reachable_subset(
    cell: Any,
    subset: NDArray[np.intp] | None,
    exc: UnreachableJointsError,
    clearance: float,
) -> tuple[NDArray[np.intp], list[dict[str, str]]]:
    """The joints to plan next after ``exc``, and the ones left out with their reasons.

    Parameters
    ----------
    cell
        The cell; ``subset`` indexes its joints (None: all of them).
    exc
        The error of the last attempt: its ``stranded`` joints have no path to any joint, its
        ``groups`` (largest first) have none between them.
    clearance
        mm, for the reasons.

    Returns
    -------
    subset, skipped
        Sorted cell indices of the joints kept; ``[{"id", "reason"}]`` of those left out.
    """
    ids = [str(i) for i in cell.joints.ids]
    current = np.arange(len(ids)) if subset is None else np.asarray(subset, dtype=np.intp)
    names = [ids[k] for k in current]
    drop: dict[str, str] = {}
    for jid in exc.stranded:
        drop[jid] = f"no collision-free path to any other joint at {clearance:g} mm clearance"
    if not drop and len(exc.groups) > 1:
        main = exc.groups[0]
        for group in exc.groups[1:]:
            for jid in group:
                drop[jid] = (
                    f"no collision-free path at {clearance:g} mm clearance between its group "
                    f"({len(group)} joint{'s' if len(group) > 1 else ''}: "
                    f"{', '.join(group[:5])}{', ...' if len(group) > 5 else ''}) and the "
                    f"{len(main)} joints planned (enclosed, or behind a panel?)"
                )
    if not drop:  # nothing to leave out: the error is not about reachability after all
        raise exc
    keep = np.array([k for k, jid in zip(current, names, strict=True) if jid not in drop])
    if len(keep) == 0:
        raise PlanningError(f"every joint is unreachable: {exc}") from exc
    return np.sort(keep).astype(np.intp), [
        {"id": jid, "reason": drop[jid]} for jid in names if jid in drop
    ]


def with_skipped(route: Any, cell: Any, skipped: list[dict[str, str]]) -> Any:
    """``route`` (planned over part of the cell) with the cell's whole joint table and the
    ``skipped`` list in its stats."""
    joints = cell.joints
    directions = getattr(joints, "directions", None)
    stats = dict(route.stats)
    stats["skipped"] = list(skipped)
    return replace(
        route,
        joint_ids=tuple(str(i) for i in joints.ids),
        joint_xyz=np.asarray(joints.xyz, dtype=float).reshape(-1, 3),
        directions=None if directions is None else np.asarray(directions, dtype=float),
        virtual_xyz=np.asarray(cell.virtual_xyz, dtype=float).reshape(-1, 3),
        stats=stats,
    )
