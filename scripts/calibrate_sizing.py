"""Measure peak memory of the cell (grid) and of the pair tables, to calibrate weldplan.weld.sizing.

Each measurement runs in a fresh child process (``python scripts/calibrate_sizing.py child ...``)
and reports its peak RSS (``ru_maxrss``), so imports and earlier runs do not blur it.

    python scripts/calibrate_sizing.py grid car2 150 300 500   # car2 (4500 mm), 50-joint set
    python scripts/calibrate_sizing.py grid demo 150 400
    python scripts/calibrate_sizing.py pairs 1000 2000 3000      # synthetic joints, all straight
    python scripts/calibrate_sizing.py plan demo                 # demo end to end (cell + plan)
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CAR2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"
CAR2_50 = ROOT / "assets" / "car2" / "car2_synthetic_50.csv"


def _peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _cell(which: str, margin: float):
    from weldplan.weld.cell import demo_cell, load_cell

    if which == "demo":
        return demo_cell(margin=margin), None
    return load_cell(CAR2, CAR2_50, length=4500.0, margin=margin), None


def child(kind: str, which: str, arg: float) -> dict:
    import numpy as np

    from weldplan.weld import sizing

    t0 = time.perf_counter()
    base = _peak_mib()
    if kind in ("grid", "plan"):
        import weldplan.weld.local  # noqa: F401 - imports counted in the base, not the grid
        import weldplan.weld.pipeline  # noqa: F401

        base = _peak_mib()
        cell, _ = _cell(which, arg)
        voxels = int(np.prod(cell.grid.shape))
        est = sizing.estimate(cell.joints.xyz, cell.pitch, arg, len(cell.joints.ids), None)
        out = {"voxels": voxels, "estimated_voxels": est.voxels}
        if kind == "plan":
            from weldplan.weld.pipeline import plan_route

            plan_route(cell, rng=0)
        out.update(peak_mib=_peak_mib(), base_mib=base, estimate_mib=est.total_bytes / 2**20)
    else:  # pairs: n joints in free space, every pair straight
        import trimesh

        from weldplan.geometry.collision import CollisionModel
        from weldplan.io.joints import Joints
        from weldplan.weld.pipeline import PlanConfig, plan_route

        n = int(arg)
        rng = np.random.default_rng(0)
        xyz = rng.uniform(0, 1000, size=(n, 3))
        box = trimesh.creation.box(extents=[10, 10, 10])
        box.apply_translation([5000, 5000, 5000])

        class Cell:  # the duck type plan_route needs, no grid
            joints = Joints(ids=tuple(str(k) for k in range(n)), xyz=xyz)
            virtual_xyz = xyz
            collision = CollisionModel(box)
            clearance = 5.0
            pitch = 5.0

        cand = None if which == "all" else 6
        base = _peak_mib()
        plan_route(Cell(), config=PlanConfig(sequencer="nn", candidates=cand), rng=0)
        est = sizing.estimate(xyz, 5.0, 0.0, n, cand)
        out = {
            "joints": n,
            "candidates": cand,
            "peak_mib": _peak_mib(),
            "base_mib": base,
            "pair_estimate_mib": est.pair_bytes / 2**20,
        }
    out["seconds"] = time.perf_counter() - t0
    return out


def main() -> None:
    if sys.argv[1] == "child":
        print(json.dumps(child(sys.argv[2], sys.argv[3], float(sys.argv[4]))))
        return
    kind = sys.argv[1]
    if kind == "pairs":
        which, values = sys.argv[2], sys.argv[3:]
    else:
        which, values = sys.argv[2], sys.argv[3:] or ["150"]
    for v in values:
        r = subprocess.run(
            [sys.executable, __file__, "child", kind, which, v],
            capture_output=True,
            text=True,
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        print(r.stdout.strip() or r.stderr[-2000:], flush=True)


if __name__ == "__main__":
    main()
