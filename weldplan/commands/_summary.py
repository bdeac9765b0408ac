"""The table ``weldplan plan`` and ``weldplan demo`` print at the end of a run."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def _gap_rounds(g: Any) -> str:
    """The converging rounds of the lazy costs (:func:`weldplan.weld.converge.close_gap`)."""
    if not g:
        return ""
    return f"; {g['rounds']} gap round(s) planned {g['pairs_planned']} more pair(s) ({g['reason']})"


def _gaps(route: Any) -> str:
    """The gap to the straight-line bound, and to the tighter bounds that the reader can use."""
    if len(route.joint_ids) < 2 or not route.lower_bound > 0:
        return "n/a"
    parts = [
        f"{100 * route.gap:.2f} % over the straight-line bound",
    ]
    b = route.stats.get("bound_virtual")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.inner_length / b - 1):.2f} % between virtual joints over their own "
            f"straight-line bound ({b:.2f} mm)"
        )
    b = route.stats.get("bound_with_approaches")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound with approaches ({b:.2f} mm)"
        )
    b = route.stats.get("bound_planned")
    if b is not None and b == b and b > 0:
        how = route.stats.get("bound_planned_method", "")
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound of the planned legs "
            f"({b:.2f} mm, {how})"
        )
    return "; ".join(parts)


def _skipped_rows(route: Any) -> list[tuple[str, str]]:
    """One row per joint left out by ``--skip-unreachable``."""
    skipped = route.stats.get("skipped") or []
    if not skipped:
        return []
    rows = [("skipped", f"{len(skipped)} joint(s), not in the route (exit code 3)")]
    rows += [(f"  {s['id']}", s["reason"]) for s in skipped]
    return rows


def smooth_rows(route: Any) -> list[tuple[str, str]]:
    """The smoothing's totals (``--smooth``), and one row per leg whose polyline was kept."""
    sm = route.stats.get("smooth")
    if not sm:
        return []
    c = sm["clearance"]
    k = sm["max_curvature"]
    line = (
        f"{sm['smoothed']} of {sm['curved']} curved legs smoothed ({len(route.legs)} legs, "
        f"{len(route.legs) - sm['curved']} straight between their virtual joints)"
    )
    if sm["smoothed"]:
        radius = f", radius {1 / k:.2f} mm" if k > 0 else ""
        m = sm["min_clearance_margin"]
        line += (
            f"; max curvature {k:.4f} 1/mm{radius}; min clearance {c + m:.3f}"
            f" mm (margin {m:.3f} mm over {c:g}); smooth length "
            f"{sm['length']:.2f} mm ({sm['length'] - route.length:+.2f}); spacing <= "
            f"{sm['spacing']:g} mm"
        )
    rows = [("smooth", line)]
    rows += [
        (f"  leg {f['leg']}", f"{f['from_id']} -> {f['to_id']}: {f['status']}")
        for f in sm["legs"]
        if f["curved"] and not f["smoothed"]
    ]
    return rows


def clock_caps(route: Any) -> list[str]:
    """What in this run depended on the clock or on an unseeded search, so that the same
    command may write other files (empty: every search was budgeted by work and seeded).

    Read from the route's figures: the sequencer (fast-tsp has no seed; a ``--sequence-time``
    budget), a clock budget of the local planner, the gun's SE(3) re-plans and the robot's
    joint-space transfers that the clock safety net stopped."""
    s, cfg = route.stats, route.settings
    caps = []
    if str(s.get("sequence_method", "")).startswith("fast-tsp"):
        caps.append("the weld order came from fast-tsp (no seed)")
    for key, what in (("sequence_time_budget", "sequencer"), ("local_time_budget", "local paths")):
        if cfg.get(key) is not None:
            caps.append(f"the {what} had a clock budget ({cfg[key]:g} s)")
    tr = (route.tool or {}).get("transitions") or {}
    n = sum(bool(r.get("clock")) for r in (tr.get("stats") or {}).get("se3_runs") or [])
    if n:
        caps.append(f"{n} SE(3) re-plan(s) of the gun stopped by the clock")
    ompl = (((route.tool or {}).get("robot") or {}).get("stats") or {}).get("ompl") or {}
    if ompl.get("clock"):
        caps.append(f"{int(ompl['clock'])} joint-space transfer(s) stopped by the clock")
    return caps


def _reproducible(route: Any) -> str:
    caps = clock_caps(route)
    if not caps:
        return "yes: every search seeded and budgeted by work"
    return "NOT reproducible, the same command may write other files: " + "; ".join(caps)


def summary_table(
    route: Any,
    times: dict[str, float],
    outputs: dict[str, Path],
    *,
    title: str,
    report: Any,
    note: str | None = None,
    extra: list[tuple[str, str]] | None = None,
) -> str:
    """The table printed at the end of a run (``extra``: rows after ``verified``)."""
    s = route.stats
    rows = [
        (
            "joints",
            f"{len(route.joint_ids)}"
            + (
                f" ({len(route.order)} in the route)"
                if len(route.order) < len(route.joint_ids)
                else ""
            ),
        ),
        ("pairs", f"{s['pairs']} ({s['pairs_straight']} straight, {s['pairs_blocked']} blocked)"),
        (
            "pairs planned",
            f"{s['pairs_planned']} of {s['pairs_blocked']} blocked "
            f"({route.settings['planner']}, {s['rounds']} sequencing rounds"
            + (f", {s['pairs_failed']} failed" if s["pairs_failed"] else "")
            + ")",
        ),
        ("sequencer", f"{s['sequence_method']}" + _gap_rounds(s.get("gap_rounds"))),
        (
            "route length",
            f"{route.length:.2f} mm ({route.inner_length:.2f} mm between virtual joints "
            f"+ {route.approach_length:.2f} mm of approaches to the weld spots)",
        ),
        ("lower bound", f"{route.lower_bound:.2f} mm ({route.lower_bound_method})"),
        ("gap", _gaps(route)),
        ("order", "-".join(route.order)),
        *_skipped_rows(route),
        *smooth_rows(route),
        ("verified", report.describe()),
        *(extra or []),
        ("reproducible", _reproducible(route)),
        (
            "time",
            ", ".join(f"{k} {v:.2f} s" for k, v in times.items()),
        ),
        ("written", ", ".join(str(p) for p in outputs.values())),
    ]
    w = max(len(k) for k, _ in rows)
    lines = [title, "-" * len(title)] + [f"{k:<{w}}  {v}" for k, v in rows]
    if note:
        lines.append(note)
    return "\n".join(lines)
