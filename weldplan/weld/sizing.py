"""How much memory a planning run will take, estimated before the heavy work starts.

Two things grow without bound with the settings and the input:

* the obstacle grid: one voxel per ``pitch`` cube of the joints' bounding box grown by ``margin``
  on every side (:func:`weldplan.geometry.grid.grid_region`). Per voxel the run holds the
  ``occupied`` booleans and their negation ``free`` (1 byte each, :class:`ObstacleGrid`), the
  connected-component labels of the free voxels that the local planner computes once
  (``scipy.ndimage.label``: int32, 4 bytes): 6 bytes, and :data:`GRID_BYTES_PER_VOXEL`, the
  measured slope of peak memory against voxels, is 5.5-5.6 (``scripts/calibrate_sizing.py``;
  docs/sizing.md);
* the pair tables of :mod:`weldplan.weld.pairs`: the ``(n, n)`` pair numbers, cost matrix and its
  copies, the upper-triangle index pairs, seeds and flags. They are ``(n, n)`` even with
  candidate pairs; without candidates the straight check of every pair adds its segment end
  points (``(n (n - 1) / 2, 3)`` twice, float64) at once. :data:`PAIR_BYTES` and
  :data:`PAIR_BYTES_CANDIDATES` are bytes per ``n^2``, measured likewise.

:func:`check_size` refuses, in one line that names the option to change, a run whose estimate
exceeds the memory limit (``--memory-limit`` / ``PlanConfig.memory_limit``, GB; default
:func:`default_memory_limit`).
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from weldplan.errors import ConfigError

log = logging.getLogger(__name__)

#: bytes of peak memory per voxel of the region of interest, planning included: the slope of
#: peak RSS against voxels, 5.5 (car2 50-set, 1.5 M -> 16.7 M voxels) and 5.6 (demo, 0.9 M ->
#: 7.7 M voxels), rounded up (docs/sizing.md)
GRID_BYTES_PER_VOXEL = 6.0
#: bytes of peak memory of a process besides the grid and the pairs: interpreter, numpy, scipy,
#: open3d, python-fcl, the mesh and its BVH (measured intercept: 207-228 MiB; docs/sizing.md)
BASE_BYTES = 240 * 2**20
#: bytes of one local search at its cap (``LocalParams.max_search_voxels``, 2 M voxels): about
#: 0.5 GB (docs/bench-scale.md; not re-measured here), counted once per process that searches
SEARCH_BYTES = 512 * 2**20
#: bytes per n^2 of the pair work when every pair is checked straight up front: the slope of peak
#: RSS against n^2 over 300, 600, 1000 joints (737 B; docs/sizing.md); most of it is the
#: vectorised straight check of all n (n - 1) / 2 segments at once
PAIR_BYTES = 740.0
#: bytes per n^2 with candidate pairs (``--candidates 6``): the (n, n) tables (slope over 300 and
#: 600 joints: 108 B; docs/sizing.md)
PAIR_BYTES_CANDIDATES = 110.0
#: share of the available memory a run may take by default
DEFAULT_MEMORY_FRACTION = 0.8


@dataclass(frozen=True)
class SizeEstimate:
    """What a run will hold at its peak (bytes; ``voxels`` may be ``inf`` for absurd inputs)."""

    voxels: float
    grid_bytes: float
    pair_bytes: float
    base_bytes: float

    @property
    def total_bytes(self) -> float:
        return self.grid_bytes + self.pair_bytes + self.base_bytes


def available_memory() -> float | None:
    """Bytes of memory available to a new process (``MemAvailable`` of /proc/meminfo, else the
    free physical pages); None when the system does not say."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return None


def _process_ceiling() -> float | None:
    """Bytes this process may still take under its own limits: the address-space rlimit (less
    what is mapped already) and a cgroup v2 ``memory.max`` (less ``memory.current``); None when
    neither is set."""
    room: list[float] = []
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft != resource.RLIM_INFINITY:
            mapped = 0.0
            with open("/proc/self/status", encoding="ascii") as f:
                for line in f:
                    if line.startswith("VmSize:"):
                        mapped = float(line.split()[1]) * 1024.0
            room.append(max(float(soft) - mapped, 0.0))
    except (ImportError, OSError, ValueError):  # pragma: no cover - not POSIX
        pass
    try:
        with open("/sys/fs/cgroup/memory.max", encoding="ascii") as f:
            limit = f.read().strip()
        if limit != "max":
            with open("/sys/fs/cgroup/memory.current", encoding="ascii") as f:
                used = float(f.read().strip())
            room.append(max(float(limit) - used, 0.0))
    except (OSError, ValueError):
        pass
    return min(room) if room else None


def default_memory_limit() -> float | None:
    """GB: :data:`DEFAULT_MEMORY_FRACTION` of the memory this run can have: the system's
    :func:`available_memory`, or less where the process runs under an address-space rlimit or a
    cgroup memory limit (``ulimit -v``, a container); None: unknown."""
    avail = available_memory()
    ceiling = _process_ceiling()
    if ceiling is not None:
        avail = ceiling if avail is None else min(avail, ceiling)
    return None if avail is None else DEFAULT_MEMORY_FRACTION * avail / 1e9


def grid_voxels(points: ArrayLike, pitch: float, margin: float) -> float:
    """Voxels of the grid over ``points``' bounding box grown by ``margin`` (mm), as
    :func:`~weldplan.geometry.grid.grid_region` lays it out; computed in floating point, so a
    1e300 mm coordinate gives ``inf`` instead of an overflow."""
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(P) == 0:
        return 0.0
    with np.errstate(over="ignore", invalid="ignore"):
        lo = P.min(axis=0) - margin
        hi = P.max(axis=0) + margin
        per_axis = np.floor(hi / pitch + 1e-9) - np.ceil(lo / pitch - 1e-9) + 1.0
    if not np.all(np.isfinite(per_axis)):
        return math.inf
    return float(np.prod(np.maximum(per_axis, 1.0)))


def estimate(
    points: ArrayLike | None,
    pitch: float,
    margin: float,
    n_joints: int,
    candidates: int | None,
    workers: int = 1,
) -> SizeEstimate:
    """The peak-memory estimate of a run (module docstring); ``points`` None: no grid.

    ``workers`` > 1: local worker processes (``--jobs``, ``--dask local``), each holding the
    cell and running searches, besides this process (counted as one more holder of the grid).
    """
    voxels = 0.0 if points is None else grid_voxels(points, pitch, margin)
    per_pair = PAIR_BYTES if candidates is None else PAIR_BYTES_CANDIDATES
    holders = 1 if workers <= 1 else workers + 1  # this process and each worker hold the cell
    searchers = 1 if workers <= 1 else workers
    return SizeEstimate(
        voxels=voxels,
        grid_bytes=voxels * GRID_BYTES_PER_VOXEL * holders,
        pair_bytes=float(n_joints) ** 2 * per_pair,
        base_bytes=float(BASE_BYTES) * holders + float(SEARCH_BYTES) * searchers,
    )


def _gb(b: float) -> str:
    return "an unbounded amount" if not math.isfinite(b) else f"{b / 1e9:.1f} GB"


def check_size(
    points: ArrayLike | None,
    *,
    pitch: float,
    margin: float,
    n_joints: int,
    candidates: int | None,
    memory_limit: float | None = None,
    cli: bool = False,
    workers: int = 1,
) -> SizeEstimate:
    """Refuse a run whose estimate exceeds ``memory_limit`` GB (None: the default limit).

    Raises :class:`~weldplan.errors.ConfigError` with one line naming what to change: the
    margin or the pitch when the grid dominates, ``candidates`` when the pair checks do and
    candidates would fit, else the number of joints. ``cli`` spells the options as flags.
    ``workers``: see :func:`estimate`.
    """
    est = estimate(points, pitch, margin, n_joints, candidates, workers)
    limit = default_memory_limit() if memory_limit is None else float(memory_limit)
    log.info(
        "size estimate: %.3g voxels (%s), %d joints (%s), limit %s",
        est.voxels,
        _gb(est.grid_bytes),
        n_joints,
        _gb(est.pair_bytes),
        "none" if limit is None else f"{limit:.1f} GB",
    )
    if limit is None or est.total_bytes <= limit * 1e9:
        return est
    opt = (lambda s: "--" + s.replace("_", "-")) if cli else (lambda s: s)
    what = (
        f"needs about {_gb(est.total_bytes)}, over the {limit:.1f} GB limit ({opt('memory_limit')})"
    )
    if est.grid_bytes >= est.pair_bytes:
        vox = "inf" if not math.isfinite(est.voxels) else f"{est.voxels:,.0f}"
        more = f" in each of {workers} worker processes" if workers > 1 else ""
        raise ConfigError(
            f"the grid of {vox} voxels (joints' bounding box + {margin:g} mm margin at "
            f"{pitch:g} mm pitch{more}) {what}: use a smaller {opt('margin')} or a larger "
            f"{opt('pitch')}" + (f" or fewer {opt('jobs')}" if workers > 1 else ""),
            field="margin",
        )
    with_cand = estimate(points, pitch, margin, n_joints, 6, workers)
    if candidates is None and with_cand.total_bytes <= limit * 1e9:
        raise ConfigError(
            f"checking all {n_joints * (n_joints - 1) // 2:,} pairs of {n_joints:,} joints {what}: "
            f"use {opt('candidates')} K (each joint's K nearest pairs up front, e.g. 6)",
            field="candidates",
        )
    raise ConfigError(
        f"the pair tables of {n_joints:,} joints {what}, even with {opt('candidates')}: split "
        "the joints into several runs",
        field="joints",
    )


def check_pair_work(n_joints: int, candidates: int | None, memory_limit: float | None) -> None:
    """The pair part of :func:`check_size` (the grid is already built when
    :func:`~weldplan.weld.pipeline.plan_route` runs)."""
    est = estimate(None, 1.0, 0.0, n_joints, candidates)
    limit = default_memory_limit() if memory_limit is None else float(memory_limit)
    if limit is not None and est.pair_bytes > limit * 1e9:
        check_size(
            None,
            pitch=1.0,
            margin=0.0,
            n_joints=n_joints,
            candidates=candidates,
            memory_limit=memory_limit,
        )
