"""Running ``weldplan bench planar``'s planning runs in worker processes, and the statistics
its tables print (:mod:`weldplan.bench.planar`)."""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor

import numpy as np

log = logging.getLogger(__name__)


def run_one(task: tuple) -> dict:
    """One run in a worker: (scenario, algorithm, encoding, frame, pop, iters, seed[, params,
    label, as_printed]). ``as_printed`` (default ``True``: the papers' tables) runs the
    algorithm alone; ``False`` the default pipeline (``pop``/``iters`` ``None``: its budgets),
    with the free-space mesh built afresh as a ``weldplan planar`` call would."""
    from weldplan.planar.encodings import make_problem
    from weldplan.planar.freespace import _MESH_CACHE
    from weldplan.planar.scenarios import load_scenario
    from weldplan.planar.solve import PlanarSettings, solve

    name, algo, enc, frame, pop, iters, seed = task[:7]
    opt_params = task[7] if len(task) > 7 else {}
    label = task[8] if len(task) > 8 else algo
    as_printed = task[9] if len(task) > 9 else True
    _MESH_CACHE.clear()
    c0 = time.process_time()
    w0 = time.perf_counter()
    sc = load_scenario(name)
    params = {"frame": frame} if enc == "segments" else {}
    prob = make_problem(sc, enc, **params)
    settings = PlanarSettings(encoding=enc, pop_size=pop, max_iter=iters, with_optimum=False,
                              optimizer_params=opt_params, as_printed=as_printed)  # fmt: skip
    r = solve(sc, algo, settings, rng=seed, problem=prob)
    cpu = time.process_time() - c0
    return {
        "map": name,
        "algo": label,
        "cpu": cpu,
        "wall": time.perf_counter() - w0,
        "frame": frame,
        "seed": seed,
        "length": r.length,
        "success": r.success,
        "collisions": r.collisions,
        "seconds": r.seconds,
        "history": list(r.history),
        "diversity": r.diversity,
        "points": r.points,
        "smoothness": r.smoothness,
        "stages": [(s.name, s.length, s.collisions, s.note) for s in r.stages],
    }


def run_all(tasks: list[tuple], jobs: int) -> list[dict]:
    if jobs <= 1:
        return [run_one(t) for t in tasks]
    with ProcessPoolExecutor(max_workers=jobs) as ex:
        return list(ex.map(run_one, tasks, chunksize=1))


def collect_best(rr: list[dict], algo: str, best_paths: dict, hist: dict) -> None:
    """Add ``algo``'s shortest run (successful ones first) and its mean convergence curve."""
    ok = [r for r in rr if r["success"]] or rr
    b = min(ok, key=lambda r: r["length"])
    best_paths[f"{algo.upper()} {b['length']:.3f}"] = b["points"]
    hist[algo.upper()] = np.mean([r["history"] for r in rr], axis=0)


def run_stats(rows: Iterable[dict]) -> dict:
    rows = list(rows)
    L = np.array([r["length"] for r in rows])
    ok = np.array([r["success"] for r in rows])
    T = np.array([r["seconds"] for r in rows])
    Lok = L[ok] if ok.any() else np.array([np.nan])
    return {
        "n": len(rows),
        "min": float(np.min(Lok)),
        "mean": float(np.mean(Lok)),
        "sd": float(np.std(Lok)),
        "worst": float(np.max(Lok)),
        "succ": float(np.mean(ok)),
        "t_mean": float(np.mean(T)),
        "t_max": float(np.max(T)),
        "cpu_mean": float(np.mean([r.get("cpu", np.nan) for r in rows])),
        "mean_all": float(np.mean(L)),
        "di": _nanmean([r["diversity"] for r in rows]),
    }


def _nanmean(values: list[float]) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.mean(v)) if len(v) else float("nan")


def fmt_cell(v: float, nd: int = 3) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v:.{nd}f}"
