"""The fish, bee, ParaPA, lion and sparrow optimisers on benchmark functions, and ABC/SSA beside
mealpy (figures first made for issue 6 part B).

Part ``own``: every algorithm with its paper defaults on the 10-d Sphere and the 30-d Rastrigin
at one evaluation budget (15,000 = 002's population 30 x 500 iterations), median final value and
wall time per run over seeded runs.

Part ``mealpy``: ABC and SSA against mealpy 3.0.2's OriginalABC and OriginalSSA (the bench
extra) at the same population and iterations on the 30-d Sphere, Rastrigin and Ackley, side by
side in one run: wall-time ratio and median final value over the seeds. The populations are
matched by food sources / sparrows: ours ``ABC(pop_size=2 * P)`` has ``P`` sources and ``P``
onlookers like mealpy's ``OriginalABC(pop_size=P)``.

Usage::

    python scripts/bench_swarm_optimizers.py own [--seeds 5]
    python scripts/bench_swarm_optimizers.py mealpy [--seeds 10] [--iters 500] [--pop 30]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from weldplan.optim.core import minimize
from weldplan.optim.functions import FUNCTIONS, get_function
from weldplan.optim.registry import get_optimizer

OURS = ("afsa", "hafsa", "abc", "mabc", "parapa", "lso", "ssa")


def load() -> str:
    a, b, c = os.getloadavg()
    return f"load average {a:.2f} {b:.2f} {c:.2f}"


def own(seeds: int, budget: int) -> None:
    print(f"# fish, bee, ParaPA, lion, sparrow: paper defaults, {budget} evaluations")
    print(f"# seeds 0..{seeds - 1}")
    print(f"# {load()}")
    print(
        "| algorithm | Sphere 10-d median | Rastrigin 30-d median"
        " | s/run (Sphere) | s/run (Rast.) |"
    )
    print("|---|---|---|---|---|")
    cases = (("sphere", 10), ("rastrigin", 30))
    for name in OURS:
        cells, secs = [], []
        for fn, dim in cases:
            p = get_function(fn, dim)
            vals, ts = [], []
            for s in range(seeds):
                t = time.perf_counter()
                r = minimize(p, get_optimizer(name), max_evals=budget, rng=s)
                ts.append(time.perf_counter() - t)
                vals.append(r.f)
            cells.append(f"{statistics.median(vals):.3g}")
            secs.append(f"{statistics.median(ts):.3f}")
        print(f"| {name} | {cells[0]} | {cells[1]} | {secs[0]} | {secs[1]} |")
    print(f"# {load()}")


def peer(seeds: int, iters: int, pop: int) -> None:
    try:
        from mealpy import FloatVar
        from mealpy.swarm_based.ABC import OriginalABC
        from mealpy.swarm_based.SSA import OriginalSSA
    except ImportError as exc:  # pragma: no cover - optional peer
        raise SystemExit("mealpy is a benchmark extra: pip install 'weldplan[bench]'") from exc

    pairs = (
        ("abc", {"pop_size": 2 * pop}, OriginalABC, {"pop_size": pop}),
        ("ssa", {"pop_size": pop}, OriginalSSA, {"pop_size": pop}),
    )
    print(f"# ours vs mealpy 3.0.2, population {pop}, {iters} iterations, seeds 0..{seeds - 1}")
    print(f"# {load()}")
    print(
        "| algorithm | function (30-d) | ours median | mealpy median | ours s/run | mealpy s/run |"
        " time ratio (mealpy/ours) | ours evals | mealpy evals |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for ours, okw, cls, mkw in pairs:
        for fn in ("sphere", "rastrigin", "ackley"):
            p = get_function(fn, 30)
            func = FUNCTIONS[fn].func
            o_vals, o_ts, m_vals, m_ts = [], [], [], []
            o_ev = m_ev = 0
            for s in range(seeds):
                t = time.perf_counter()
                r = minimize(p, get_optimizer(ours, **okw), max_iter=iters, rng=s)
                o_ts.append(time.perf_counter() - t)
                o_vals.append(r.f)
                o_ev = r.n_eval
                count = [0]

                def obj(x, func=func, count=count):  # type: ignore[no-untyped-def]
                    count[0] += 1
                    return float(func(np.asarray(x)[None])[0])

                problem = {
                    "bounds": FloatVar(lb=p.lower.tolist(), ub=p.upper.tolist()),
                    "minmax": "min",
                    "obj_func": obj,
                    "log_to": None,
                }
                model = cls(epoch=iters, **mkw)
                t = time.perf_counter()
                g = model.solve(problem, seed=s)
                m_ts.append(time.perf_counter() - t)
                m_vals.append(float(g.target.fitness))
                m_ev = count[0]
            om, mm = statistics.median(o_ts), statistics.median(m_ts)
            print(
                f"| {ours} | {fn} | {statistics.median(o_vals):.3g} |"
                f" {statistics.median(m_vals):.3g} | {om:.3f} | {mm:.3f} | {mm / om:.1f} |"
                f" {o_ev} | {m_ev} |"
            )
    print(f"# {load()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", choices=["own", "mealpy"])
    ap.add_argument("--seeds", type=int, default=None)
    ap.add_argument("--budget", type=int, default=15_000)
    ap.add_argument("--iters", type=int, default=500)
    ap.add_argument("--pop", type=int, default=30)
    a = ap.parse_args()
    if a.part == "own":
        own(a.seeds or 5, a.budget)
    else:
        peer(a.seeds or 10, a.iters, a.pop)


if __name__ == "__main__":
    main()
