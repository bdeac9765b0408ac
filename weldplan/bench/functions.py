"""``weldplan bench functions``: 002 Table 2's protocol for every registered optimiser.

002 section 1.2 (3): population 30, 500 iterations, 30 independent runs on the five 30-d
functions of Table 1; report the mean and standard deviation of the best value. Writes
``functions.md`` (the table, with seconds per run), ``functions.json`` (every run's final value)
and ``convergence-<function>.png`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import logging
import platform
import sys
import time
from pathlib import Path

import numpy as np

from weldplan.errors import WeldplanError
from weldplan.optim.core import minimize
from weldplan.optim.functions import FUNCTIONS, TABLE1, get_function
from weldplan.optim.registry import available, get_optimizer

HELP = "002 Table 2 protocol (pop 30, 500 iterations, 30 runs) for the optimiser registry"
log = logging.getLogger(__name__)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--algorithms", default="all", help="comma list of registry names, or 'all'")
    p.add_argument(
        "--functions", default=",".join(TABLE1), help="comma list (default: 002 Table 1)"
    )
    p.add_argument("--dim", type=int, default=30, help="variables (002: 30)")
    p.add_argument("--pop", type=int, default=30, help="population size (002: 30)")
    p.add_argument("--iters", type=int, default=500, help="iterations per run (002: 500)")
    p.add_argument("--runs", type=int, default=30, help="independent runs (002: 30)")
    p.add_argument("--seed", type=int, default=0, help="first seed; run k uses seed + k")
    p.add_argument(
        "--shift",
        type=float,
        default=0.0,
        help="move the optimum to shift * bound * linspace(-1, 1, dim) (0: as in 002)",
    )


def _names(spec: str, known: list[str], what: str) -> list[str]:
    if spec == "all":
        return known
    names = [s.strip().lower() for s in spec.split(",") if s.strip()]
    bad = [n for n in names if n not in known]
    if bad:
        raise WeldplanError(f"unknown {what}: {', '.join(bad)}; choose from {', '.join(known)}")
    return names


def _fmt(v: float) -> str:
    return "0" if v == 0 else f"{v:.3g}"


def run(args: argparse.Namespace) -> int:
    algos = _names(args.algorithms, available(), "algorithm")
    funcs = _names(args.functions, list(FUNCTIONS), "function")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results: dict[str, dict[str, dict]] = {}
    t_start = time.perf_counter()
    for fn in funcs:
        bound = FUNCTIONS[fn].bound
        shift = args.shift * bound * np.linspace(-1.0, 1.0, args.dim) if args.shift else None
        problem = get_function(fn, args.dim, shift=shift)
        histories: dict[str, list] = {}
        for algo in algos:
            fs, secs, hist = [], [], []
            for k in range(args.runs):
                r = minimize(
                    problem,
                    get_optimizer(algo, pop_size=args.pop),
                    max_iter=args.iters,
                    rng=args.seed + k,
                )
                fs.append(r.f)
                secs.append(r.seconds)
                hist.append(r.history)
            histories[algo] = hist
            results.setdefault(fn, {})[algo] = {
                "f": fs,
                "mean": float(np.mean(fs)),
                "sd": float(np.std(fs, ddof=1)) if len(fs) > 1 else 0.0,
                "seconds_per_run": float(np.mean(secs)),
                "n_eval": r.n_eval,
            }
            print(
                f"{problem.name:>18s} {algo:>8s} mean {_fmt(np.mean(fs)):>9s} "
                f"({np.mean(secs):.3f} s/run)",
                file=sys.stderr,
            )
        from weldplan.viz.convergence import plot_convergence

        plot_convergence(
            histories,
            out / f"convergence-{problem.name}.png",
            title=f"{problem.name}, {args.dim}-d, pop {args.pop}, {args.runs} runs",
        )
    total = time.perf_counter() - t_start
    _write_markdown(out / "functions.md", args, algos, funcs, results, total)
    (out / "functions.json").write_text(json.dumps({"args": _args_dict(args), "results": results}))
    print(f"wrote {out / 'functions.md'} in {total:.1f} s", file=sys.stderr)
    return 0


def _args_dict(args: argparse.Namespace) -> dict:
    return {k: v for k, v in vars(args).items() if not k.startswith("_")}


def _write_markdown(path: Path, args, algos, funcs, results, total: float) -> None:  # type: ignore[no-untyped-def]
    lines = [
        "# Benchmark functions: 002 Table 2 protocol",
        "",
        f"{args.dim}-d, population {args.pop}, {args.iters} iterations, {args.runs} runs "
        f"(seeds {args.seed}..{args.seed + args.runs - 1})"
        + (
            f", optimum shifted by {args.shift} x bound x linspace(-1, 1, dim)"
            if args.shift
            else ""
        )
        + f". Mean and SD of the best value; seconds per run. Total {total:.1f} s on "
        f"{platform.machine()} / Python {platform.python_version()}.",
        "",
        "| algorithm | " + " | ".join(f"{f} mean | {f} SD" for f in funcs) + " | s/run |",
        "|---|" + "---|---|" * len(funcs) + "---|",
    ]
    for a in algos:
        cells = []
        for f in funcs:
            r = results[f][a]
            cells += [_fmt(r["mean"]), _fmt(r["sd"])]
        sec = np.mean([results[f][a]["seconds_per_run"] for f in funcs])
        lines.append(f"| {a} | " + " | ".join(cells) + f" | {sec:.3f} |")
    lines += [
        "",
        "002 Table 2 (MATLAB) reports, SMA / ISMA: Sphere 0 / 0; Schwefel 2.22 3.96e-154 / 0; "
        "Schwefel 2.21 2.38e-150 / 0; Rastrigin 0 / 0; Ackley 4.44e-16 / 4.44e-16 (SD 0 or "
        "2.01e-31).",
        "",
    ]
    path.write_text("\n".join(lines))
