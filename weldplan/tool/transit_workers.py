"""Transitions and their re-check over worker processes, in runs of consecutive transitions.

Planning a transition (:mod:`weldplan.tool.transitions`) and re-checking one
(:mod:`weldplan.tool.verify_sweeps`) depend only on the part, the tool and the two weld poses,
so a route's transitions split into ``workers`` runs of consecutive ones, each done in its own
process with its own python-fcl models (built there: FCL objects do not cross processes), and
joined in order. Consecutive runs keep most of the planner's per-weld reuse (a weld's exits are
checked once per process that meets it). The answers are those of one process; only the
seconds change (measured in ``weldplan bench tool``).
"""

from __future__ import annotations

import dataclasses
import logging
import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any, TypeVar

import numpy as np
import trimesh

log = logging.getLogger(__name__)

T = TypeVar("T")


def split(items: Sequence[Any], parts: int) -> list[list[Any]]:
    """``items`` cut into at most ``parts`` runs of consecutive items, as even as can be."""
    parts = max(1, min(int(parts), len(items)))
    bounds = np.linspace(0, len(items), parts + 1).round().astype(int)
    return [list(items[a:b]) for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]


def _portable(x: Any) -> Any:
    """A copy that crosses a process boundary: a tool without its cached FCL models, a part as
    a plain mesh."""
    if isinstance(x, trimesh.Trimesh):
        return trimesh.Trimesh(np.asarray(x.vertices), np.asarray(x.faces), process=False)
    if dataclasses.is_dataclass(x) and hasattr(x, "_cache"):
        return dataclasses.replace(x, _cache={})
    return x


def run_chunks(
    fn: Callable[..., T], items: Sequence[Any], shared: tuple[Any, ...], workers: int
) -> list[T]:
    """``[fn(run, *shared) for run in split(items, workers)]``, in worker processes when
    ``workers > 1`` and there are at least two runs (forked where the platform allows)."""
    runs = split(items, workers) if items else []
    if len(runs) <= 1:
        return [fn(run, *shared) for run in runs]
    shared = tuple(_portable(x) for x in shared)
    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("fork" if "fork" in methods else None)
    with ProcessPoolExecutor(max_workers=len(runs), mp_context=ctx) as ex:
        futures = [ex.submit(fn, run, *shared) for run in runs]
        return [f.result() for f in futures]
