"""``weldplan bench route``: the demo cell end to end, against the exact pipeline and the paper.

Targets (issue 5): the demo cell (15 joints) with SO-ACO at N = M = 10 and the paper's TSP-PSO,
end to end within 5 s on a 2-core machine, route length within 2 % of the exact local planner +
Held-Karp; both beside the paper's 599.72 mm and the straight-line lower bound (595.10 mm).

Writes ``route.md`` into ``--out``. Timings are wall clock on whatever machine runs it; the
machine's load average is recorded beside them.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HELP = "demo cell end to end: SO-ACO + PSO vs exact + Held-Karp, vs the paper's 599.72 mm"

#: Wang et al. 2017: the collision-free route through the 15 joints (mm)
PAPER_ROUTE_MM = 599.72
#: Held-Karp open-path optimum over straight-line distances of Table 1 (mm)
PAPER_LOWER_BOUND_MM = 595.10


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--runs", type=int, default=5, help="seeds of the stochastic pipeline (5)")
    p.add_argument("--quick", action="store_true", help="2 runs, no CLI timing")


def _load() -> str:
    try:
        return " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:  # pragma: no cover
        return "n/a"


def _timed(f, *a, **k):
    t = time.perf_counter()
    out = f(*a, **k)
    return out, time.perf_counter() - t


def run(args: argparse.Namespace) -> int:
    from weldplan.weld.cell import demo_cell

    runs = 2 if args.quick else max(1, args.runs)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    load_before = _load()

    cell, t_cell = _timed(demo_cell)
    configs = _configs()
    rows = []
    results = {}
    for name, cfg in configs.items():
        seeds = [0] if cfg.planner == "exact" and cfg.sequencer == "exact" else range(runs)
        row, results[name] = _run_config(name, cell, cfg, seeds, t_cell)
        rows.append(row)
    cli_s = None if args.quick else _cli_seconds()
    text = _report(list(results.values()), rows, load_before, t_cell, cli_s)
    (out / "route.md").write_text(text)
    print(text)
    return 0


def _configs() -> dict:
    """The three pipelines of the table, by name: the paper's, the paper's with every blocked
    pair planned, and the exact one (the first and the last are compared)."""
    from weldplan.weld.pipeline import PlanConfig

    return {
        "SO-ACO N=M=10 + TSP-PSO (paper) + polish": PlanConfig(
            planner="so-aco", sequencer="pso", aco={"n_iterations": 10, "n_ants": 10}
        ),
        "SO-ACO N=M=10 + TSP-PSO, every blocked pair planned": PlanConfig(
            planner="so-aco", sequencer="pso", pairs="all", aco={"n_iterations": 10, "n_ants": 10}
        ),
        "exact grid search + Held-Karp": PlanConfig(planner="exact", sequencer="exact"),
    }


def _run_config(name: str, cell, cfg, seeds, t_cell: float) -> tuple[tuple, tuple]:
    """Plan, verify and render the demo with ``cfg`` once per seed.

    Returns
    -------
    row, result
        The table row (lengths mm, mean timings s, pairs planned, verified, last order) and
        ``(lengths (runs,) mm, the last route, lengths between virtual joints (runs,) mm)``.
    """
    from weldplan.viz.viewer import static_html
    from weldplan.weld.pipeline import plan_route
    from weldplan.weld.verify import verify_route

    lengths, inner, plan_s, verify_s, html_s, planned, ok = [], [], [], [], [], [], True
    route = None
    for seed in seeds:
        route, tp = _timed(plan_route, cell, config=cfg, rng=seed)
        rep, tv = _timed(verify_route, route, cell.part, joints=cell.joints)
        _, th = _timed(static_html, route, cell.part)
        ok &= rep.ok
        lengths.append(route.length)
        inner.append(route.inner_length)
        plan_s.append(tp)
        verify_s.append(tv)
        html_s.append(th)
        planned.append(route.stats["pairs_planned"])
    e2e = t_cell + np.array(plan_s) + np.array(verify_s) + np.array(html_s)
    row = (
        name,
        len(lengths),
        f"{np.mean(lengths):.2f} [{np.min(lengths):.2f}, {np.max(lengths):.2f}]",
        f"{np.mean(inner):.2f} [{np.min(inner):.2f}, {np.max(inner):.2f}]",
        f"{np.mean(plan_s):.2f}",
        f"{np.mean(verify_s):.2f}",
        f"{np.mean(html_s):.2f}",
        f"{np.mean(e2e):.2f} (max {np.max(e2e):.2f})",
        f"{np.mean(planned):.1f} of {route.stats['pairs_blocked']}",
        "yes" if ok else "NO",
        "-".join(route.order),
    )
    return row, (np.array(lengths), route, np.array(inner))


def _cli_seconds() -> float:
    """Wall seconds of ``weldplan demo --quiet`` in a new process, in a scratch folder."""
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "weldplan", "demo", "--quiet"],
            cwd=tmp,
            check=True,
            env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])},
        )
        return time.perf_counter() - t


def _report(
    results: list[tuple], rows: list[tuple], load_before: str, t_cell: float, cli_s: float | None
) -> str:
    """``route.md``: the table and the comparisons of the paper's pipeline (``results[0]``)
    with the exact one (``results[2]``), the bound and the paper."""
    so, exact = results[0][0], results[2][0]
    so_in, exact_in = results[0][2], results[2][2]
    lb = results[2][1].lower_bound
    paper_gap = 100 * (PAPER_ROUTE_MM / PAPER_LOWER_BOUND_MM - 1)
    lines = [
        "# Demo cell end to end (weldplan bench route)",
        "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; "
        f"load average {load_before} before, {_load()} after. Python {platform.python_version()}.",
        f"Cell build (grid, collision model, virtual joints): {t_cell:.2f} s.",
        "",
        "| pipeline | runs | length mm mean [min, max] | between virtual joints mm "
        "| plan s | verify s | html s | end to end s (cell + plan + verify + html) "
        "| pairs planned | verified | order |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    lines += [
        "",
        f"- SO-ACO + PSO vs exact + Held-Karp: mean {np.mean(so) / exact[0]:.4f}, "
        f"worst {np.max(so) / exact[0]:.4f} (target <= 1.02)",
        f"- straight-line lower bound (Held-Karp over the weld spots): {lb:.2f} mm "
        f"(the paper's {PAPER_LOWER_BOUND_MM})",
        f"- between virtual joints (the paper's measure, no approach segments): SO-ACO + PSO "
        f"{np.mean(so_in):.2f} mm ({100 * (np.mean(so_in) / lb - 1):+.2f} % over the bound), "
        f"exact {exact_in[0]:.2f} mm ({100 * (exact_in[0] / lb - 1):+.2f} %); the paper "
        f"{PAPER_ROUTE_MM} mm ({paper_gap:+.2f} %). Our part is generated, not the paper's.",
        f"- whole route with the approaches to the weld spots: SO-ACO + PSO {np.mean(so):.2f} mm, "
        f"exact {exact[0]:.2f} mm ({100 * (exact[0] / lb - 1):+.2f} % over the bound)",
    ]
    if cli_s is not None:
        lines.append(
            f"- `weldplan demo` as a user runs it (new process: imports, cell, plan, verify, "
            f"route.csv + route.html): {cli_s:.2f} s wall"
        )
    return "\n".join(lines) + "\n"
