"""The run's measured times, apart from the route JSON (../shared/DESIGN.md, reproducibility).

The route JSON is a deliverable: the same inputs and seed must give the same bytes on any
machine and at any load. The figures a run measures (wall and CPU seconds of each stage, search
and solver times) differ from run to run, so :func:`route_json_texts` moves them out of it into
a separate timings JSON (``route.timings.json`` beside ``route.json``: the same nesting with
only those figures); :func:`split_timings` says which keys they are. The CLI's summary prints
the stage times as before.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

from weldplan.weld.route import Route

#: keys inside a ``stats`` mapping that hold a measured time (s): ``seconds`` and ``seconds_*``,
#: ``*_s`` (``total_s``, ``wall_s``...), ``s`` (the robot's OMPL CPU seconds) and ``time_s``
_TIMING_KEY = re.compile(r"^(seconds(_\w+)?|\w+_s|s)$")


def _is_timing(key: str, in_stats: bool) -> bool:
    return in_stats and bool(_TIMING_KEY.match(key))


def split_timings(d: Any, in_stats: bool = False) -> tuple[Any, Any]:
    """``(deliverable, timings)`` of a route's JSON-ready dict ``d``.

    ``timings`` mirrors the nesting of ``d`` with only the measured times: the keys of every
    ``stats`` mapping (at any depth) named ``seconds``, ``seconds_*``, ``*_s`` or ``s``, whole
    subtrees included (``stats.seconds`` is a mapping of stage times). Settings such as the
    SE(3) re-plan's ``time_s`` lie outside ``stats`` and stay. Lists are searched item by item.
    ``deliverable`` is ``d`` without them; ``timings`` is ``None`` where nothing was moved.
    """
    if isinstance(d, dict):
        keep: dict[str, Any] = {}
        moved: dict[str, Any] = {}
        for k, v in d.items():
            if _is_timing(str(k), in_stats):
                moved[k] = v
                continue
            kept, t = split_timings(v, in_stats or k == "stats")
            keep[k] = kept
            if t is not None:
                moved[k] = t
        return keep, (moved or None)
    if isinstance(d, list):
        pairs = [split_timings(v, in_stats) for v in d]
        times = [t for _, t in pairs]
        return [k for k, _ in pairs], (times if any(t is not None for t in times) else None)
    return d, None


def timings_path(json_path: str | PathLike[str]) -> Path:
    """Where the timings of ``route.json`` go: ``route.timings.json`` beside it."""
    p = Path(json_path)
    return p.with_name(p.stem + ".timings.json")


def route_json_texts(route: Route, producer: Mapping[str, Any] | None = None) -> tuple[str, str]:
    """``(route JSON, timings JSON)``: the route without its measured times (the same bytes
    for the same inputs and seed), and those times (module docstring). :func:`read_route`
    reads the first alone. ``producer``: the route JSON's ``"producer"`` entry (what produced
    it and what was verified, :func:`weldplan.station.outputs.producer`)."""
    d, t = split_timings(json.loads(route.to_json()))
    if producer is not None:
        d = {"producer": dict(producer), **d}
    text = json.dumps(d, indent=1, allow_nan=False) + "\n"
    return text, json.dumps(t or {}, indent=1, allow_nan=False) + "\n"
