"""Issue 15's length targets on every blocked pair `bench local --peers --pairs 8` leaves out.

`weldplan bench local --peers --pairs 8` measures 32 pairs (8 spread over each cell's list). This
runs the other blocked pairs of the same cells (demo, car2 Z3L/Z4L/Z4R) with the default column
(exact + refine) and OMPL BIT* at 0.1 s and 10 s only (no SO-ACO columns), split round-robin
over processes, and summarises them::

    python scripts/bench_local_all_pairs.py run PART NPARTS OUT.json   # one process
    python scripts/bench_local_all_pairs.py summary OUT.json [...]

Run one ``run`` per core (BIT*'s budget is wall time: give each process a core of its own).
"""

from __future__ import annotations

import json
import sys

import numpy as np

from weldplan.bench.local_peers import (
    DEFAULT_COLUMN,
    STATION_SIZE,
    blocked_pairs,
    build_cells,
    planners,
)
from weldplan.motion.local import TorchChecks

B01, B10 = "OMPL BIT* 0.1 s", "OMPL BIT* 10 s"


def run(part: int, nparts: int, out: str) -> None:
    cols = planners([0.1, 10.0], ["bitstar"])
    cols = {k: v for k, v in cols.items() if k in (DEFAULT_COLUMN, B01, B10)}
    recs, k = [], 0
    for cname, cell in build_cells("demo,car2", STATION_SIZE):
        seen = set(blocked_pairs(cell, 8))
        checks = TorchChecks(cell)
        ids = [str(v) for v in cell.joints.ids]
        for idx, (i, j) in enumerate(blocked_pairs(cell, None)):
            if (i, j) in seen:
                continue
            k += 1
            if k % nparts != part:
                continue
            rec = {"cell": cname, "pair": [ids[i], ids[j]]}
            for col, fn in cols.items():
                lp = fn(cell, i, j, idx, checks)
                ok = bool(lp.success)
                rec[col] = {
                    "ok": ok,
                    "len": float(lp.inner_length) if ok else None,
                    "wall": float(lp.seconds),
                    "cpu": float(lp.cpu_seconds),
                }
            recs.append(rec)
            print(cname, rec["pair"], {c: rec[c]["len"] for c in cols}, flush=True)
            with open(out, "w") as fh:
                json.dump(recs, fh)


def summary(files: list[str]) -> None:
    recs = [r for f in files for r in json.load(open(f))]
    print(f"pairs {len(recs)}")
    for c in (DEFAULT_COLUMN, B01, B10):
        wall = np.median([r[c]["wall"] for r in recs])
        print(f"{c}: solved {sum(r[c]['ok'] for r in recs)}, median wall {wall:.3f} s")
    both = [r for r in recs if r[DEFAULT_COLUMN]["ok"] and r[B10]["ok"]]
    for cell in sorted({r["cell"] for r in both}) + ["all"]:
        x = np.array(
            [r[DEFAULT_COLUMN]["len"] / r[B10]["len"] for r in both if cell in ("all", r["cell"])]
        )
        print(f"{cell}: {len(x)} pairs, default / BIT* 10 s mean {x.mean():.4f} max {x.max():.4f}")
    worst = sorted(both, key=lambda r: -r[DEFAULT_COLUMN]["len"] / r[B10]["len"])[:5]
    for r in worst:
        print("worst", r["cell"], r["pair"], round(r[DEFAULT_COLUMN]["len"] / r[B10]["len"], 4))


if __name__ == "__main__":
    if sys.argv[1:2] == ["run"]:
        run(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
    elif sys.argv[1:2] == ["summary"]:
        summary(sys.argv[2:])
    else:
        sys.exit(__doc__)
