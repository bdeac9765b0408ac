"""``weldplan bench mealpy``: ours against mealpy 3.0.2 at equal population and iterations.

For each pair (ours, mealpy's ``Original*``) and each 30-d function (Sphere, Rastrigin, Ackley),
both run the same seeds one after the other in one process, on the same vectorised function
(mealpy calls it one solution at a time, which is how mealpy works). Reported: the wall-time
ratio (mealpy total / ours total) and the median final value over the seeds. Writes
``mealpy.md`` and ``mealpy.json`` into ``--out``.

mealpy is a benchmark-only dependency: ``pip install "weldplan[bench]"`` (pins mealpy==3.0.2;
3.0.3 requires numpy <= 1.26).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.errors import WeldplanError
from weldplan.optim.core import minimize
from weldplan.optim.functions import get_function
from weldplan.optim.registry import available, get_optimizer

HELP = "ours vs mealpy 3.0.2 (SMA, WOA, GWO, PSO, ABC): wall-time ratio and median final value"
log = logging.getLogger(__name__)

#: ours -> (mealpy module, class, mealpy kwargs, our kwargs), settings matched where both exist
PAIRS: dict[str, tuple[str, str, dict[str, Any], dict[str, Any]]] = {
    "sma": ("SMA", "OriginalSMA", {"p_t": 0.03}, {"z": 0.03}),
    "woa": ("WOA", "OriginalWOA", {}, {}),
    "gwo": ("GWO", "OriginalGWO", {}, {}),
    # mealpy's OriginalPSO: constant w = 0.4, c1 = c2 = 2.05, initial |v| <= 0.5 (ub - lb)
    "pso": (
        "PSO",
        "OriginalPSO",
        {"c1": 2.05, "c2": 2.05, "w": 0.4},
        {"w_start": 0.4, "w_end": 0.4, "c1": 2.05, "c2": 2.05, "v_max": 0.5},
    ),
    # mealpy's pop_size counts food sources (employed bees; as many onlookers), ours counts bees
    "abc": ("ABC", "OriginalABC", {"n_limits": 25}, {"limit": 25}),
}
#: our pop_size = factor * mealpy's, so both evaluate the same number of solutions an iteration
POP_FACTOR: dict[str, int] = {"abc": 2}
FUNCS = ("sphere", "rastrigin", "ackley")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--algorithms", default=",".join(PAIRS), help="comma list of " + ", ".join(PAIRS)
    )
    p.add_argument("--functions", default=",".join(FUNCS), help="comma list of function names")
    p.add_argument("--dim", type=int, default=30)
    p.add_argument("--pop", type=int, default=30)
    p.add_argument("--iters", type=int, default=500, help="iterations = mealpy epochs")
    p.add_argument("--seeds", type=int, default=10)


def _import_mealpy():  # type: ignore[no-untyped-def]
    try:
        import mealpy
    except ImportError as exc:
        raise WeldplanError(
            'mealpy is not installed; install the benchmark extra: pip install "weldplan[bench]"'
        ) from exc
    return mealpy


def run(args: argparse.Namespace) -> int:
    mealpy = _import_mealpy()
    algos = [a.strip().lower() for a in args.algorithms.split(",") if a.strip()]
    unknown = [a for a in algos if a not in PAIRS]
    if unknown:
        raise WeldplanError(
            f"no mealpy pair for: {', '.join(unknown)}; choose from {', '.join(PAIRS)}"
        )
    skipped = [a for a in algos if a not in available()]
    algos = [a for a in algos if a in available()]
    for a in skipped:
        print(f"skipping {a}: not in this registry", file=sys.stderr)
    funcs = [f.strip() for f in args.functions.split(",") if f.strip()]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for fn in funcs:
        problem = get_function(fn, args.dim)

        def obj(x: np.ndarray, _f=problem.func) -> float:  # one solution: mealpy's interface
            return float(_f(x[None, :])[0])

        for algo in algos:
            mod, cls, mkw, okw = PAIRS[algo]
            Model = getattr(getattr(mealpy, mod), cls)
            ours_t, peer_t, ours_f, peer_f = 0.0, 0.0, [], []
            for seed in range(args.seeds):
                t = time.perf_counter()
                r = minimize(
                    problem,
                    get_optimizer(algo, pop_size=POP_FACTOR.get(algo, 1) * args.pop, **okw),
                    max_iter=args.iters,
                    rng=seed,
                )
                ours_t += time.perf_counter() - t
                ours_f.append(r.f)
                spec = {
                    "obj_func": obj,
                    "bounds": mealpy.FloatVar(lb=problem.lower.tolist(), ub=problem.upper.tolist()),
                    "minmax": "min",
                    "log_to": None,
                }
                t = time.perf_counter()
                model = Model(epoch=args.iters, pop_size=args.pop, **mkw)
                g = model.solve(spec, seed=seed)
                peer_t += time.perf_counter() - t
                peer_f.append(float(g.target.fitness))
            row = {
                "function": fn,
                "ours": algo,
                "mealpy": cls,
                "ours_seconds": ours_t,
                "mealpy_seconds": peer_t,
                "speedup": peer_t / ours_t,
                "ours_median": float(np.median(ours_f)),
                "mealpy_median": float(np.median(peer_f)),
                "ours_f": ours_f,
                "mealpy_f": peer_f,
                "ours_n_eval": r.n_eval,
                "mealpy_n_eval": int(getattr(model, "nfe_counter", -1)),
            }
            rows.append(row)
            print(
                f"{fn:>10s} {algo:>4s} vs {cls:<12s} speedup {row['speedup']:7.1f}x  median "
                f"{row['ours_median']:.3g} vs {row['mealpy_median']:.3g}",
                file=sys.stderr,
            )
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    _write_markdown(out / "mealpy.md", args, rows, skipped, load)
    (out / "mealpy.json").write_text(json.dumps({"rows": rows, "load": load}))
    return 0


def _write_markdown(path: Path, args, rows, skipped, load) -> None:  # type: ignore[no-untyped-def]
    lines = [
        "# weldplan vs mealpy 3.0.2",
        "",
        f"{args.dim}-d, population {args.pop}, {args.iters} iterations (= mealpy epochs), seeds "
        f"0..{args.seeds - 1}; both on the same function code, one after the other per seed. "
        f"Speedup = mealpy wall time / ours. Load average after the run "
        f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {platform.machine()}.",
        "",
        "| function | ours | mealpy | ours s | mealpy s | speedup | ours median | mealpy median "
        "| evals ours / mealpy |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['function']} | {r['ours']} | {r['mealpy']} | {r['ours_seconds']:.2f} | "
            f"{r['mealpy_seconds']:.2f} | {r['speedup']:.1f}x | {r['ours_median']:.3g} | "
            f"{r['mealpy_median']:.3g} | {r['ours_n_eval']} / {r['mealpy_n_eval']} |"
        )
    if skipped:
        lines += ["", f"Not run (not in this registry): {', '.join(skipped)}."]
    lines.append("")
    path.write_text("\n".join(lines))
