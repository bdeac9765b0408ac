"""``weldplan bench local --peers``: weldplan's local planners beside OMPL on every blocked pair.

Issue 15 item 5. On each cell, every pair of joints whose straight segment between the virtual
joints is blocked (the FCL capsule at the clearance) is planned by

- ours (``--ours``): SO-ACO as the paper prints it (``plan_pair(method="so-aco")``), alone and
  followed by the continuous refinement (:func:`weldplan.weld.refine.refine_local_path`); exact
  (26-connected A* + the secondary optimisation, ``method="exact"``) alone, with the refinement
  on one grid route ("one class"), and with the refinement and the second-class stage
  (:mod:`weldplan.weld.homotopy`), the local stage of ``weldplan plan`` (the default column);
- OMPL (:mod:`weldplan.weld.local_ompl`): BIT* and RRT* for each of ``--budgets`` seconds, then
  OMPL's simplifier, with weldplan's own FCL checks as the validity checker (the sphere at the
  clearance + closed-solid test for states, the ``method="fcl"`` capsule for motions);

``--pairs all`` (the default) measures every blocked pair, ``--pairs N`` at most N a cell;
``--jobs N`` shares the pairs among N processes (give each a core: OMPL's budgets are wall time).

Every length is the inner length between the two virtual joints (the same for every planner).
Per pair, the best known length is the shortest successful path any planner found; the issue's
reference, BIT* at the largest budget + simplify, is reported beside it. Times are wall seconds
of the whole call (OMPL: planning + simplification) and CPU seconds of this process. OMPL's
budgets are wall-clock, so on a loaded machine it gets fewer samples in its budget: the load
average is in the report.

Cells: the demo (:func:`weldplan.weld.cell.demo_cell`) and the car2 stations the repo generates
(``assets/car2/car2_synthetic_1000.csv``, stations by joint id prefix ``Z{zone}{L|R}``): for each
station with at least ``--station-size`` joints, the ``--station-size`` joints nearest its
centroid (as :func:`weldplan.weld.synthetic.select_set` picks a set around the home station),
on car2 scaled to 4500 mm (../shared/data).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

#: the OMPL planners of the comparison (names of :data:`weldplan.motion.sampling.PLANNERS`)
OMPL_PLANNERS = ("bitstar", "rrtstar")
#: OMPL budgets, s (the issue's 0.1 / 1 / 10)
BUDGETS = (0.1, 1.0, 10.0)
#: joints per car2 station
STATION_SIZE = 12
#: the synthetic car2 joint set whose stations are the car2 cells
CAR2_SET = Path(__file__).resolve().parents[2] / "assets" / "car2" / "car2_synthetic_1000.csv"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of the peers mode (added to ``weldplan bench local``)."""
    parser.add_argument(
        "--peers",
        action="store_true",
        help="issue 15: our planners beside OMPL BIT*/RRT* on every blocked pair of the demo "
        "and the car2 stations (writes local-peers.md/json)",
    )
    parser.add_argument(
        "--budgets",
        default=",".join(f"{b:g}" for b in BUDGETS),
        help="--peers: OMPL time budgets in s, comma-separated (0.1,1,10)",
    )
    parser.add_argument(
        "--pairs",
        default="all",
        help="--peers: 'all' (default: every blocked pair) or at most this many blocked pairs a "
        "cell, spread evenly over its list",
    )
    parser.add_argument(
        "--ours",
        default=",".join(OURS_DEFAULT),
        help="--peers: our columns, comma-separated, of "
        + ", ".join(OURS)
        + f" ({','.join(OURS_DEFAULT)})",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="--peers: worker processes, pairs shared among them (1). OMPL's budgets are wall "
        "time: give each job a core of its own",
    )
    parser.add_argument(
        "--cells",
        default="demo,car2",
        help="--peers: demo, car2 (every car2 station) or car2:STATION, comma-separated",
    )
    parser.add_argument(
        "--station-size", type=int, default=STATION_SIZE, help="--peers: joints a car2 station"
    )
    parser.add_argument(
        "--ompl-planners",
        default=",".join(OMPL_PLANNERS),
        help="--peers: OMPL planners, comma-separated (bitstar,rrtstar)",
    )


def _floats(text: str, name: str) -> list[float]:
    from weldplan.errors import ConfigError

    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        vals = []
    if not vals or not all(math.isfinite(v) and v > 0 for v in vals):
        raise ConfigError(f"{name} must be positive numbers, comma-separated; got {text!r}")
    return sorted(set(vals))


# --------------------------------------------------------------------------- cells and pairs


def car2_stations(size: int) -> dict[str, Any]:
    """Station name -> Joints: the ``size`` joints of each car2 station nearest its centroid."""
    from weldplan.io.joints import Joints, read_joints

    j = read_joints(CAR2_SET)
    station = np.array([str(i).rsplit("-", 1)[0] for i in j.ids])
    out = {}
    for name in sorted(set(station)):
        sel = np.flatnonzero(station == name)
        if len(sel) < size:
            continue
        c = j.xyz[sel].mean(axis=0)
        pick = np.sort(
            sel[np.argsort(np.linalg.norm(j.xyz[sel] - c, axis=1), kind="stable")[:size]]
        )
        dirs = None if j.directions is None else j.directions[pick]
        out[name] = Joints(ids=tuple(j.ids[k] for k in pick), xyz=j.xyz[pick], directions=dirs)
    return out


def build_cells(spec: str, size: int) -> list[tuple[str, Any]]:
    """``(name, Cell)`` for each entry of ``--cells``."""
    from weldplan.bench.common import shared_path
    from weldplan.errors import ConfigError
    from weldplan.weld.cell import build_cell, demo_cell

    cells: list[tuple[str, Any]] = []
    part = stations = None
    for item in (s.strip() for s in spec.split(",") if s.strip()):
        if item == "demo":
            cells.append(("demo", demo_cell()))
            continue
        if not (item == "car2" or item.startswith("car2:")):
            raise ConfigError(f"unknown cell {item!r}: demo, car2 or car2:STATION", field="cells")
        if part is None:
            from weldplan.io.mesh import load_part
            from weldplan.weld.synthetic import CAR2_LENGTH_MM

            part = load_part(shared_path("bodies", "car2.obj"), length=CAR2_LENGTH_MM)
            stations = car2_stations(size)
        assert stations is not None
        names = list(stations) if item == "car2" else [item.split(":", 1)[1]]
        for name in names:
            if name not in stations:
                raise ConfigError(
                    f"no car2 station {name!r} with {size} joints; have {', '.join(stations)}",
                    field="cells",
                )
            cells.append((f"car2 {name}", build_cell(part, stations[name])))
    return cells


def blocked_pairs(cell: Any, limit: int | None) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, ``i < j``, whose straight segment between virtual joints collides (the
    FCL capsule at the clearance); ``limit`` of them spread evenly over the list when given."""
    n = cell.n_joints
    iu, ju = np.triu_indices(n, 1)
    V = np.asarray(cell.virtual_xyz)
    free = cell.collision.segments_free(V[iu], V[ju], cell.clearance, method="fcl")
    pairs = [(int(a), int(b)) for a, b in zip(iu[~free], ju[~free], strict=True)]
    if limit is not None and len(pairs) > limit:
        keep = np.unique(np.linspace(0, len(pairs) - 1, limit).round().astype(int))
        pairs = [pairs[k] for k in keep]
    return pairs


# --------------------------------------------------------------------------- planners


#: the column of weldplan's default pipeline (``weldplan plan``'s local stage: exact A* + SO,
#: the refinement and the second-class stage, :mod:`weldplan.weld.homotopy`)
DEFAULT_COLUMN = "exact + refine + 2nd class (default)"
#: the same with one grid route only (the default before the second-class stage)
ONE_CLASS_COLUMN = "exact + refine, one class"
#: one class, the refinement's vertex stage as one-vertex sweeps (the default until the joint
#: vertex optimisation, :mod:`weldplan.weld.taut`)
SWEEPS_COLUMN = "exact + refine, sweeps"
#: ``--ours`` key -> column
OURS = {
    "paper": "SO-ACO (paper)",
    "paper+refine": "SO-ACO + refine",
    "exact": "exact (A* + SO)",
    "sweeps": SWEEPS_COLUMN,
    "one-class": ONE_CLASS_COLUMN,
    "default": DEFAULT_COLUMN,
}
#: the columns of ours measured unless ``--ours`` says otherwise
OURS_DEFAULT = ("paper", "paper+refine", "exact", "one-class", "default")


def _refine_hook(taut: bool = True) -> Callable[[Any, Any], Any]:
    """``refine(cell, local_path) -> LocalPath``: the pipeline's own continuous refinement
    (:func:`weldplan.weld.refine.refine_local_path`, python-fcl checks) applied to a planned
    pair, with its CPU time added; ``taut=False``: its vertex stage as one-vertex sweeps (the
    refinement before the joint vertex optimisation)."""
    from weldplan.weld.refine import refine_local_path

    def refine(cell: Any, lp: Any) -> Any:
        c0 = time.process_time()
        out = refine_local_path(cell, lp, taut=taut)
        if out is lp:
            return lp
        return replace(out, cpu_seconds=lp.cpu_seconds + time.process_time() - c0)

    return refine


def planners(
    budgets: list[float], ompl: list[str], ours: list[str] | None = None
) -> dict[str, Callable[..., Any]]:
    """Column name -> ``f(cell, i, j, seed, checks) -> LocalPath``; ``ours``: keys of
    :data:`OURS` (default :data:`OURS_DEFAULT`), then the OMPL columns.

    The default column is the pipeline's own local stage (``plan_pair(method="exact",
    params={"refine": True})``: A* + SO, the refinement, the second-class stage, all inside one
    timed call); "one class" the same with ``second_class=False``.
    """
    from weldplan.weld.local import plan_pair
    from weldplan.weld.local_ompl import plan_pair_ompl

    refine = _refine_hook()
    sweeps = _refine_hook(taut=False)
    one = {"refine": True, "second_class": False}
    every: dict[str, Callable[..., Any]] = {
        "paper": lambda c, i, j, s, ch: plan_pair(c, i, j, method="so-aco", rng=s),
        "paper+refine": lambda c, i, j, s, ch: refine(
            c, plan_pair(c, i, j, method="so-aco", rng=s)
        ),
        "exact": lambda c, i, j, s, ch: plan_pair(c, i, j, method="exact"),
        "sweeps": lambda c, i, j, s, ch: sweeps(c, plan_pair(c, i, j, method="exact")),
        "one-class": lambda c, i, j, s, ch: plan_pair(c, i, j, method="exact", params=one),
        "default": lambda c, i, j, s, ch: plan_pair(
            c, i, j, method="exact", params={"refine": True}
        ),
    }
    cols = {OURS[k]: every[k] for k in (OURS_DEFAULT if ours is None else ours)}
    label = {"bitstar": "BIT*", "rrtstar": "RRT*"}
    for name in ompl:
        for b in budgets:
            cols[f"OMPL {label.get(name, name)} {b:g} s"] = lambda c, i, j, s, ch, name=name, b=b: (
                plan_pair_ompl(c, i, j, planner=name, time_s=b, rng=s, checks=ch)
            )
    return cols


def _measure_pair(
    cname: str, cell: Any, i: int, j: int, cols: dict[str, Callable[..., Any]], seed: int,
    checks: Any,
) -> dict[str, Any]:  # fmt: skip
    """One record: every column's length, success, wall and CPU seconds on pair ``(i, j)``."""
    ids = [str(v) for v in cell.joints.ids]
    rec: dict[str, Any] = {"cell": cname, "pair": [ids[i], ids[j]], "runs": {}}
    for col, fn in cols.items():
        try:
            lp = fn(cell, i, j, seed, checks)
            ok = bool(lp.success)
            run = {
                "length": float(lp.inner_length) if ok else None,
                "success": ok,
                "wall_s": float(lp.seconds),
                "cpu_s": float(lp.cpu_seconds),
                "reason": "" if ok else str(lp.reason),
            }
        except Exception as exc:  # a planner error is a failed pair in the table
            run = {"length": None, "success": False, "wall_s": math.nan,
                   "cpu_s": math.nan, "reason": f"{type(exc).__name__}: {exc}"}  # fmt: skip
        rec["runs"][col] = run
    done = [v["length"] for v in rec["runs"].values() if v["success"]]
    rec["best"] = min(done) if done else None
    short = " ".join(f"{v['length']:.1f}" if v["success"] else "FAIL" for v in rec["runs"].values())
    print(f"  {cname} {ids[i]} -> {ids[j]}: {short}", flush=True)
    return rec


def _warm(cell: Any, pairs: list[tuple[int, int]]) -> None:
    """Build a cell's per-grid caches (padded array, components, move tables, open3d scene)
    once, untimed, as a pipeline that plans many pairs of one cell does."""
    from weldplan.weld.local import plan_pair

    if pairs:
        plan_pair(cell, *pairs[0], method="exact", params={"refine": True})


#: a worker process's cells, columns and checks (:func:`_init_worker`)
_WORKER: dict[str, Any] = {}


def _init_worker(spec: str, size: int, budgets: list[float], ompl: list[str],
                 ours: list[str], limit: int | None) -> None:  # fmt: skip
    from weldplan.weld.local_ompl import TorchChecks

    cells = build_cells(spec, size)
    for _, cell in cells:
        _warm(cell, blocked_pairs(cell, limit))
    _WORKER.update(
        cells=cells, cols=planners(budgets, ompl, ours),
        checks=[TorchChecks(cell) for _, cell in cells],
    )  # fmt: skip


def _work(task: tuple[int, int, int, int]) -> dict[str, Any]:
    c, i, j, seed = task
    cname, cell = _WORKER["cells"][c]
    return _measure_pair(cname, cell, i, j, _WORKER["cols"], seed, _WORKER["checks"][c])


def _tasks(cells: list[tuple[str, Any]], limit: int | None, seed: int) -> list[tuple[int, ...]]:
    """``(cell index, i, j, seed)`` for every measured pair; seeds count up over the cells."""
    tasks = []
    for c, (cname, cell) in enumerate(cells):
        pairs = blocked_pairs(cell, limit)
        print(f"{cname}: {cell.n_joints} joints, {len(pairs)} blocked pairs measured")
        tasks += [(c, i, j, seed + len(tasks) + k) for k, (i, j) in enumerate(pairs)]
    return tasks


# --------------------------------------------------------------------------- summary


def summarise(records: list[dict[str, Any]], cols: list[str], ref: str | None) -> dict[str, Any]:
    """Per column: success, length / best known (mean, max, within 1 %), length / ``ref``
    (mean, max, over pairs both solved), wall and CPU seconds (median, mean)."""
    out: dict[str, Any] = {}
    for col in cols:
        runs = [(r["runs"][col], r["best"], r["runs"].get(ref) if ref else None) for r in records]
        ok = [(v, b, rf) for v, b, rf in runs if v["success"] and b]
        rb = np.array([v["length"] / b for v, b, _ in ok]) if ok else np.zeros(0)
        rr = np.array([v["length"] / rf["length"] for v, _, rf in ok if rf and rf["success"]])
        wall = np.array([v["wall_s"] for v, _, _ in runs if math.isfinite(v["wall_s"])])
        cpu = np.array([v["cpu_s"] for v, _, _ in runs if math.isfinite(v["cpu_s"])])
        out[col] = {
            "pairs": len(runs),
            "solved": len(ok),
            "best_mean": float(rb.mean()) if len(rb) else None,
            "best_max": float(rb.max()) if len(rb) else None,
            "within_1pct": int((rb <= 1.01).sum()),
            "ref_mean": float(rr.mean()) if len(rr) else None,
            "ref_max": float(rr.max()) if len(rr) else None,
            "ref_pairs": len(rr),
            "wall_median": float(np.median(wall)) if len(wall) else None,
            "wall_mean": float(wall.mean()) if len(wall) else None,
            "cpu_median": float(np.median(cpu)) if len(cpu) else None,
        }
    return out


def _f(x: float | None, fmt: str = ".4f") -> str:
    return "-" if x is None else format(x, fmt)


def markdown(
    records: list[dict[str, Any]],
    summary: dict[str, dict[str, dict[str, Any]]],
    ref: str | None,
    fast: str | None,
    meta: dict[str, Any],
) -> str:
    """The report: one table per cell and one over all cells, then the issue's targets."""
    lines = [
        "# Local planners beside OMPL on every blocked pair (issue 15 item 5)",
        "",
        f"Cells: {', '.join(meta['cells'])}; {len(records)} blocked pairs"
        + (f" (at most {meta['pairs_limit']} a cell)" if meta["pairs_limit"] else "")
        + f"; seeds from {meta['seed']} (one a pair).",
        f"Machine: {meta['before']} before; load {meta['load_after']} after; "
        f"{meta['wall_s']:.0f} s in all.",
        "Length: between the virtual joints (mm), the same end points for every planner. "
        "Best known: the shortest successful path any column found for that pair. "
        f"Reference: {ref or '(none)'} (the issue's BIT* 10 s + simplify when 10 is a budget).",
        "OMPL: weldplan's FCL checks as its validity checker (sphere + closed solids per state, "
        "FCL capsule per motion); budgets are wall-clock; time includes OMPL's simplifier.",
        meta["refine_note"],
        "",
    ]
    header = (
        "| planner | solved | length / best: mean | max | within 1 % | length / reference: "
        "mean | max | median wall s | mean wall s | median CPU s |"
    )
    for scope, table in summary.items():
        lines += [f"## {scope}", "", header, "|---|---|---|---|---|---|---|---|---|---|"]
        for col, s in table.items():
            lines.append(
                f"| {col} | {s['solved']}/{s['pairs']} | {_f(s['best_mean'])} | "
                f"{_f(s['best_max'])} | {s['within_1pct']}/{s['solved']} | {_f(s['ref_mean'])} | "
                f"{_f(s['ref_max'])} | {_f(s['wall_median'], '.3f')} | "
                f"{_f(s['wall_mean'], '.3f')} | {_f(s['cpu_median'], '.3f')} |"
            )
        lines.append("")
    allc = summary["all cells"]
    ours = allc.get(DEFAULT_COLUMN)
    lines += [f"## Targets (issue 15, {DEFAULT_COLUMN} vs OMPL)", ""]
    if ours:
        lines.append(
            f"- Every blocked pair solved: {ours['solved']}/{ours['pairs']} "
            f"({'met' if ours['solved'] == ours['pairs'] else 'NOT met'})."
        )
        if ref and ours["ref_mean"] is not None:
            mean_ok = ours["ref_mean"] <= 1.002
            max_ok = ours["ref_max"] <= 1.01
            lines.append(
                f"- Mean length <= 1.002 x {ref}: {ours['ref_mean']:.4f} "
                f"({'met' if mean_ok else 'NOT met'}); max <= 1.01: {ours['ref_max']:.4f} "
                f"({'met' if max_ok else 'NOT met'}), over {ours['ref_pairs']} pairs both solved."
            )
        if fast and allc[fast]["wall_median"] is not None:
            t, tf = ours["wall_median"], allc[fast]["wall_median"]
            lines.append(
                f"- Median time a pair <= {fast}: {t:.3f} s vs {tf:.3f} s "
                f"({'met' if t <= tf else 'NOT met'})."
            )
    lines.append("")
    return "\n".join(lines)


def _pairs_limit(text: str | int | None) -> int | None:
    from weldplan.errors import ConfigError

    if text is None or str(text).strip().lower() == "all":
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise ConfigError(f"--pairs must be 'all' or a positive integer, got {text!r}")
    return n


def _options(args: argparse.Namespace) -> tuple[list[float], list[str], list[str], int | None]:
    """Validated ``--budgets``, ``--ompl-planners``, ``--ours`` and ``--pairs``."""
    from weldplan.errors import ConfigError
    from weldplan.motion.sampling import PLANNERS, ompl_available

    if not ompl_available():
        raise ConfigError("bench local --peers needs OMPL: pip install 'weldplan[ompl]'")
    budgets = _floats(args.budgets, "--budgets")
    ompl = [p.strip() for p in args.ompl_planners.split(",") if p.strip()]
    bad = [p for p in ompl if p not in PLANNERS]
    if bad:
        raise ConfigError(f"unknown OMPL planner(s) {bad}; choose from {', '.join(PLANNERS)}")
    ours = [k.strip() for k in getattr(args, "ours", ",".join(OURS_DEFAULT)).split(",")]
    ours = [k for k in ours if k]
    bad = [k for k in ours if k not in OURS]
    if bad:
        raise ConfigError(f"unknown --ours column(s) {bad}; choose from {', '.join(OURS)}")
    if getattr(args, "jobs", 1) < 1:
        raise ConfigError(f"--jobs must be a positive integer, got {args.jobs}")
    return budgets, ompl, ours, _pairs_limit(args.pairs)


def run(args: argparse.Namespace) -> int:
    """Measure, print a line a pair, write ``local-peers.md`` and ``local-peers.json``.

    With ``--jobs N > 1`` the pairs are shared among N worker processes (each builds the cells
    once); the report is written when every pair is done. With one job it is written after every
    cell, so a long run that is stopped keeps what it measured.
    """
    from concurrent.futures import ProcessPoolExecutor

    from weldplan.bench.common import conditions
    from weldplan.weld.local_ompl import TorchChecks

    budgets, ompl, ours, limit = _options(args)
    jobs = int(getattr(args, "jobs", 1))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    before = conditions()
    t0 = time.perf_counter()
    cells = build_cells(args.cells, args.station_size)
    cols = planners(budgets, ompl, ours)
    names = list(cols)
    ref = f"OMPL BIT* {max(budgets):g} s" if "bitstar" in ompl else None
    fast = f"OMPL BIT* {min(budgets):g} s" if "bitstar" in ompl else None
    tasks = _tasks(cells, limit, args.seed)

    def write(records: list[dict[str, Any]], upto: int) -> None:
        done = cells[:upto]
        summary = {"all cells": summarise(records, names, ref)}
        for cname, _ in done:
            summary[cname] = summarise([r for r in records if r["cell"] == cname], names, ref)
        load = os.getloadavg()
        meta = {
            "cells": [c for c, _ in done],
            "pairs_limit": limit,
            "seed": args.seed,
            "budgets": budgets,
            "ompl_planners": ompl,
            "jobs": jobs,
            "before": before,
            "load_after": f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
            "wall_s": time.perf_counter() - t0,
            "refine_note": REFINE_NOTE,
        }
        (out / "local-peers.md").write_text(markdown(records, summary, ref, fast, meta))
        (out / "local-peers.json").write_text(
            json.dumps({"meta": meta, "summary": summary, "records": records}, indent=1)
        )

    records: list[dict[str, Any]] = []
    if jobs > 1:
        init = (args.cells, args.station_size, budgets, ompl, ours, limit)
        with ProcessPoolExecutor(jobs, initializer=_init_worker, initargs=init) as pool:
            records = list(pool.map(_work, tasks))
        write(records, len(cells))
    else:
        for c, (cname, cell) in enumerate(cells):
            mine = [t for t in tasks if t[0] == c]
            _warm(cell, [(i, j) for _, i, j, _ in mine])
            checks = TorchChecks(cell)
            records += [_measure_pair(cname, cell, i, j, cols, sd, checks) for _, i, j, sd in mine]
            write(records, c + 1)
    print(f"wrote {out / 'local-peers.md'}, {out / 'local-peers.json'}")
    return 0


REFINE_NOTE = (
    "+ refine: weldplan.weld.refine (the pipeline's continuous refinement, FCL-checked: "
    "shortcuts, then the joint vertex optimisation); '+ 2nd class': the second-class stage "
    "(weldplan.weld.homotopy: a second A* route outside the first's corridor, refined when its "
    "grid path is within the slack, the shorter kept); 'one class': without it; 'sweeps': "
    "one-vertex sweeps instead of the joint optimisation (the refinement as it was)."
)
