"""``weldplan bench sequence``: the sequencer against TSPLIB optima, OR-Tools and the paper.

Four tables, one run, written as markdown to ``OUT/sequence.md``:

0. Engines at equal budgets (issue #18): ours (the default, fast-tsp through the engine wrapper),
   the paper's PSO + polish, fast-tsp called directly, LKH-3 (elkai, if installed) and OR-Tools
   at each of ``--budgets`` seconds on the shared TSPLIB set up to u2152
   (:mod:`weldplan.bench.tsp_peers`); budgets above 10 s only on ``--long-instances``. Lengths
   recomputed from the returned tours. fast-tsp has no seed, so ``--repeats R`` runs each cell
   R times (solvers interleaved) and adds the distribution (min, median, max, runs within the
   target).
1. TSPLIB (closed tours, TSPLIB integer distances): gap to the known optimum and wall time of
   the paper's TSP-PSO alone (Table 4 parameters), PSO + polish and nearest neighbour + polish
   within ``--budget`` seconds each, OR-Tools (its default first solution plus
   ``--ortools-time`` s of guided local search, when ``ortools`` is importable: the ``bench``
   extra) and PSO + polish given OR-Tools' measured wall time ("equal time").
2. The paper check (Wang et al. 2017, 15 joints of Table 1, straight-line costs, open path):
   Held-Karp's optimum and order, and how often the paper-parameter PSO reaches it over
   ``--paper-seeds`` seeds, alone and with polish.
3. Held-Karp time and table memory as the station grows, to show where exact stops being
   reasonable.

The machine's load average is recorded beside the figures.
"""

from __future__ import annotations

import argparse
import logging
import os
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from weldplan.io.tsplib import read_best_solutions, read_tour, read_tsplib, tour_length
from weldplan.optim.discrete.costs import cost_matrix
from weldplan.optim.discrete.held_karp import held_karp_tour
from weldplan.optim.discrete.sequence import solve_sequence
from weldplan.weld.demo_part import TABLE1_XYZ

log = logging.getLogger(__name__)

HELP = "weld sequencer: TSP-PSO, polish, Held-Karp vs TSPLIB optima and OR-Tools"

INSTANCES = ("eil51", "berlin52", "st70", "att48", "kroA100", "ch130", "a280", "lin318")
#: every shared TSPLIB instance with a known optimum, up to u2152 (../shared/data/tsplib)
ENGINE_INSTANCES = INSTANCES + ("rat783", "u1060", "d1291", "u2152")
#: issue #18's target: every shared instance within this gap of its optimum at 10 s
TARGET_GAP = 0.001
DEFAULT_DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "tsplib"

# Wang et al. 2017, Table 1: the 15 weld joints (mm); joint id = row + 1 (one copy, in demo_part).
PAPER_JOINTS = TABLE1_XYZ
PAPER_ORDER = (15, 13, 14, 7, 8, 9, 10, 11, 12, 3, 6, 2, 5, 1, 4)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", type=Path, default=DEFAULT_DATA, help="TSPLIB folder")
    p.add_argument("--instances", default=",".join(INSTANCES), help="comma-separated names")
    p.add_argument("--seed", type=int, default=0, help="seed of the stochastic runs")
    p.add_argument("--budget", type=float, default=2.0, help="seconds for each +polish run")
    p.add_argument("--ortools-time", type=float, default=1.0, help="OR-Tools GLS seconds")
    p.add_argument("--paper-seeds", type=int, default=20, help="seeds for the paper check")
    p.add_argument("--hk-sizes", default="11,13,15,17,19", help="Held-Karp node counts")
    p.add_argument(
        "--skip", default="", help="comma list of parts to skip: engines,tsplib,paper,hk"
    )
    p.add_argument(
        "--engine-instances", default=",".join(ENGINE_INSTANCES), help="engines table instances"
    )
    p.add_argument(
        "--solvers",
        default="ours,pso+polish,fast-tsp,lkh3,ortools",
        help="engines table solvers (ours, ours-1t, pso+polish, fast-tsp, lkh3, ortools)",
    )
    p.add_argument("--budgets", default="1,10,60", help="engines table budgets (s)")
    p.add_argument(
        "--repeats",
        type=int,
        default=1,
        help="engines table: runs of each cell (median, range and a distribution table)",
    )
    p.add_argument(
        "--long-instances",
        default="u2152",
        help="instances that also run the budgets above 10 s (the CPU is shared)",
    )


def _load() -> str:
    try:
        a, b, c = os.getloadavg()
        return f"load average {a:.2f}, {b:.2f}, {c:.2f}"
    except OSError:  # pragma: no cover
        return "load average unavailable"


def _gap(cost: float, opt: float) -> str:
    return f"{100.0 * (cost / opt - 1.0):.2f}%"


def tsplib_table(args: argparse.Namespace) -> list[str]:
    best = read_best_solutions(args.data / "bestSolutions.txt")
    try:
        import ortools  # noqa: F401

        has_ortools = True
    except ImportError:
        has_ortools = False
    rows = [
        "## TSPLIB (closed tours)",
        "",
        f"Seed {args.seed}; +polish runs get {args.budget:g} s in all (PSO included); OR-Tools: "
        f"default first solution + {args.ortools_time:g} s guided local search; "
        "'equal time' = the run given OR-Tools' measured wall time; 'vs OR-Tools' = its cost "
        "relative to OR-Tools' cost. Cells: gap to the "
        "optimum / seconds.",
        "",
        "| instance | n | optimum | opt.tour length | PSO alone | PSO + polish | NN + polish "
        "| OR-Tools | PSO + polish, equal time | vs OR-Tools | NN + polish, equal time "
        "| vs OR-Tools |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    if not has_ortools:
        rows.insert(3, "OR-Tools is not importable here (`pip install weldplan[bench]`): skipped.")
    for name in [s for s in args.instances.split(",") if s]:
        prob = read_tsplib(args.data / f"{name}.tsp")
        D = prob.matrix()
        opt = best.get(name, float("nan"))
        tour_file = args.data / f"{name}.opt.tour"
        opt_len = f"{tour_length(D, read_tour(tour_file)):.0f}" if tour_file.exists() else "-"
        pso = solve_sequence(D, method="pso", closed=True, polish=False, rng=args.seed)
        pp = solve_sequence(D, method="pso", closed=True, rng=args.seed, time_budget=args.budget)
        nn = solve_sequence(D, method="nn", closed=True, rng=args.seed, time_budget=args.budget)
        cells = [
            name,
            str(prob.dimension),
            f"{opt:.0f}",
            opt_len,
            f"{_gap(pso.cost, opt)} / {pso.seconds:.2f}",
            f"{_gap(pp.cost, opt)} / {pp.seconds:.2f}",
            f"{_gap(nn.cost, opt)} / {nn.seconds:.2f}",
        ]
        if has_ortools:
            from weldplan.bench.tsp_peers import ortools_tour

            res = ortools_tour(D, args.ortools_time)
            assert res is not None
            ot, osec = res
            oc = tour_length(D, ot)
            cells.append(f"{_gap(oc, opt)} / {osec:.2f}")
            for method in ("pso", "nn"):
                eq = solve_sequence(D, method=method, closed=True, rng=args.seed, time_budget=osec)
                cells += [
                    f"{_gap(eq.cost, opt)} / {eq.seconds:.2f}",
                    f"{100.0 * (eq.cost / oc - 1.0):+.2f}%",
                ]
        else:
            cells += ["skipped", "-", "-", "-", "-"]
        log.info("%s done", name)
        rows.append("| " + " | ".join(cells) + " |")
    return rows


def engines_table(args: argparse.Namespace) -> list[str]:
    """Gap to the optimum / wall seconds of each solver at each budget (module docstring); with
    ``--repeats`` R > 1 each cell is the median of R runs (solvers interleaved run by run, so
    they share the machine's load) with the range, and a distribution table follows."""
    from weldplan.bench.tsp_peers import SOLVERS, available

    best = read_best_solutions(args.data / "bestSolutions.txt")
    budgets = [float(b) for b in args.budgets.split(",") if b]
    long = set(args.long_instances.split(","))
    names = [s for s in args.solvers.split(",") if s]
    unknown = [s for s in names if s not in SOLVERS]
    if unknown:
        raise ValueError(f"unknown solvers {unknown}; choose from {sorted(SOLVERS)}")
    missing = [s for s in names if not available(s)]
    run = [s for s in names if s not in missing]
    cols = [(s, b) for b in budgets for s in run]
    R = max(1, int(getattr(args, "repeats", 1)))
    rows = [
        "## TSPLIB: engines at equal budgets (closed tours)",
        "",
        "Cells: gap to the optimum (length recomputed from the returned tour) / wall seconds / "
        "CPU seconds of this process (the budgets are wall time: on a loaded machine a solver "
        "gets a fraction of a core; OR-Tools' and LKH-3's threads are counted; ours runs "
        "fast-tsp on every core, ours-1t on one). "
        f"Budgets above 10 s only on {', '.join(sorted(long))}. LKH-3 (elkai): RUNS = 1 and "
        "TIME_LIMIT = budget (its preprocessing is outside the limit; see the seconds). "
        f"Target (issue #18): ours within {100 * TARGET_GAP:g} % of every optimum at 10 s.",
        "",
    ]
    if R > 1:
        rows += [f"{R} runs a cell: median gap [min-max] / median wall s / median CPU s.", ""]
    if missing:
        rows += [f"Not importable here, skipped: {', '.join(missing)}.", ""]
    rows += [
        "| instance | n | optimum | " + " | ".join(f"{s} {b:g} s" for s, b in cols) + " |",
        "|---|---|---|" + "---|" * len(cols),
    ]
    dist: list[tuple[str, str, float, NDArray]] = []
    for name in [s for s in args.engine_instances.split(",") if s]:
        D = read_tsplib(args.data / f"{name}.tsp").matrix()
        opt = best[name]
        todo = [(s, b) for s, b in cols if b <= 10 or name in long]
        runs = _engine_runs(D, opt, todo, R, name)
        cells = [name, str(D.shape[0]), f"{opt:.0f}"]
        for solver, b in cols:
            if (solver, b) not in runs:
                cells.append("-")
                continue
            g, w, c = runs[solver, b].T
            if R == 1:
                cells.append(f"{100 * g[0]:.3f}% / {w[0]:.1f} / {c[0]:.1f}")
            else:
                cells.append(
                    f"{100 * np.median(g):.3f}% [{100 * g.min():.3f}-{100 * g.max():.3f}] "
                    f"/ {np.median(w):.1f} / {np.median(c):.1f}"
                )
            dist.append((name, solver, b, runs[solver, b]))
        rows.append("| " + " | ".join(cells) + " |")
    rows += _target_lines(dist, R)
    return rows


def _engine_runs(
    D: NDArray, opt: float, cols: list[tuple[str, float]], R: int, name: str
) -> dict[tuple[str, float], NDArray]:
    """``{(solver, budget): (R, 3) [gap, wall s, CPU s]}``, the solvers interleaved run by run."""
    from weldplan.bench.tsp_peers import SOLVERS, checked_length

    out: dict[tuple[str, float], list[list[float]]] = {c: [] for c in cols}
    for r in range(R):
        for solver, b in cols:
            cpu0 = time.process_time()
            tour, sec = SOLVERS[solver][0](D, b)
            cpu = time.process_time() - cpu0
            gap = checked_length(D, tour) / opt - 1.0
            out[solver, b].append([gap, sec, cpu])
            log.info("%s %s %g s run %d: %.3f %% in %.1f s", name, solver, b, r, 100 * gap, sec)
    return {k: np.asarray(v) for k, v in out.items()}


def _target_lines(dist: list[tuple[str, str, float, NDArray]], R: int) -> list[str]:
    """The target check of ours at 10 s and, with repeats, the distribution of every cell."""
    rows: list[str] = []
    ours10 = [r for n, s, b, r in dist if s == "ours" and b == 10]
    if ours10:
        worst = max(float(r[:, 0].max()) for r in ours10)
        hits = sum(int((r[:, 0] <= TARGET_GAP).all()) for r in ours10)
        met = "MET" if worst <= TARGET_GAP else "NOT met"
        rows += [
            "",
            f"Ours at 10 s: worst gap {100 * worst:.3f} % over {R} run(s) an instance; "
            f"{hits} / {len(ours10)} instances within {100 * TARGET_GAP:g} % in every run "
            f"({met}).",
        ]
    if R > 1:
        rows += [
            "",
            f"Distribution over {R} runs (gap %; within: runs at most {100 * TARGET_GAP:g} %):",
            "",
            "| instance | solver | budget s | min | median | max | within | CPU s min-max |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for name, solver, b, r in dist:
            g, c = 100 * r[:, 0], r[:, 2]
            rows.append(
                f"| {name} | {solver} | {b:g} | {g.min():.3f} | {np.median(g):.3f} | "
                f"{g.max():.3f} | {int((r[:, 0] <= TARGET_GAP).sum())} / {R} | "
                f"{c.min():.1f}-{c.max():.1f} |"
            )
    return rows


def paper_table(args: argparse.Namespace) -> list[str]:
    C = cost_matrix(PAPER_JOINTS)
    exact = solve_sequence(C, method="exact")
    opt = exact.cost
    histories = []
    found = {"alone": 0, "polish": 0}
    costs: dict[str, list[float]] = {"alone": [], "polish": []}
    secs: dict[str, list[float]] = {"alone": [], "polish": []}
    for seed in range(args.paper_seeds):
        for key, pol in (("alone", False), ("polish", True)):
            s = solve_sequence(C, method="pso", rng=seed, polish=pol)
            if not pol:
                histories.append(s.history)
            found[key] += int(abs(s.cost - opt) < 1e-9 * opt)
            costs[key].append(s.cost)
            secs[key].append(s.seconds)
    order = "-".join(str(v + 1) for v in exact.order)
    match = "yes" if tuple(v + 1 for v in exact.order) == PAPER_ORDER else "NO"
    k = args.paper_seeds
    rows = [
        "## Paper check (Wang et al. 2017, 15 joints, straight-line costs, open path)",
        "",
        f"Held-Karp: {opt:.2f} mm in {exact.seconds * 1000:.1f} ms, order {order} "
        f"(the paper's order: {match}; the paper states 595.10 mm).",
        "",
        "| PSO (Table 4 parameters) | found the optimum | mean cost (mm) | worst (mm) "
        "| mean seconds |",
        "|---|---|---|---|---|",
    ]
    for key, label in (("alone", "alone"), ("polish", "+ polish")):
        c = np.asarray(costs[key])
        rows.append(
            f"| {label} | {found[key]} / {k} | {c.mean():.2f} | {c.max():.2f} "
            f"| {np.mean(secs[key]):.3f} |"
        )
    png = _convergence_plot(histories, opt, Path(args.out) / "sequence-convergence.png")
    if png is not None:
        rows += ["", f"Convergence of the swarm alone (best cost per iteration): `{png.name}`."]
    return rows


def _convergence_plot(histories: list[tuple[float, ...]], opt: float, path: Path) -> Path | None:
    """Best cost per iteration of each seed, with the optimum; ``None`` without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover
        return None
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for h in histories:
        ax.plot(h, color="tab:blue", alpha=0.3, lw=0.8)
    ax.plot(np.mean(np.asarray(histories), axis=0), color="tab:blue", lw=2, label="PSO, mean")
    ax.axhline(opt, color="k", ls="--", lw=1, label=f"optimum {opt:.2f} mm")
    ax.set_xlabel("iteration")
    ax.set_ylabel("open path length (mm)")
    ax.set_title("TSP-PSO (Table 4 parameters) on the paper's 15 joints")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def held_karp_table(args: argparse.Namespace) -> list[str]:
    rows = [
        "## Held-Karp: where exact stops being reasonable",
        "",
        "Open path over n random points (n + 1 tour nodes with the dummy), float64 table "
        "of 8 n 2^n bytes.",
        "",
        "| n | seconds | DP table (MB) |",
        "|---|---|---|",
    ]
    rng = np.random.default_rng(args.seed)
    for n in [int(v) for v in args.hk_sizes.split(",") if v]:
        C = cost_matrix(rng.uniform(0, 1000, size=(n, 2)))
        t0 = time.perf_counter()
        solve_sequence(C, method="exact")
        dt = time.perf_counter() - t0
        rows.append(f"| {n} | {dt:.3f} | {8 * n * 2**n / 1e6:.1f} |")
    _ = held_karp_tour  # the solver behind method='exact'
    return rows


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    skip = set(args.skip.split(","))
    lines = ["# weldplan bench sequence", "", f"Before: {_load()}.", ""]
    t0 = time.perf_counter()
    if "engines" not in skip:
        lines += engines_table(args) + [f"({_load()})", ""]
    if "tsplib" not in skip:
        lines += tsplib_table(args) + [""]
    if "paper" not in skip:
        lines += paper_table(args) + [""]
    if "hk" not in skip:
        lines += held_karp_table(args) + [""]
    lines += [f"After: {_load()}; total {time.perf_counter() - t0:.0f} s.", ""]
    path = out / "sequence.md"
    path.write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"written {path}")
    return 0
