"""Measure: the shared gun as one BVH against a convex decomposition (CoACD), on car2 welds.

Usage (from the repository root; needs ``pip install coacd``, which is NOT a weldplan
dependency: the BVH measured faster and exact, docs/tool.md)::

    python scripts/measure_tool_convex.py [--threshold 0.1] [--welds 0,5,12,25,40]

Decomposes the gun outside its 20 mm contact zone once (CoACD, seconds printed), then checks
the 408 default candidates of a few car2_synthetic_50 welds with both bodies against the same
part crop: python-fcl ``collide`` of the BVH, and of the hulls (``fcl.Convex`` in a
``DynamicAABBTreeCollisionManager``). Prints the time per candidate and how often the answers
agree (hulls contain their pieces, so they can only add collisions).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import fcl
import numpy as np

import weldplan
from weldplan.tool import shared_spot_gun
from weldplan.tool.poses import PoseSearch, candidate_rotations, local_candidates

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threshold", type=float, default=0.1, help="CoACD concavity threshold")
    ap.add_argument("--welds", default="0,5,12,25,40", help="indices into car2_synthetic_50")
    args = ap.parse_args()
    try:
        import coacd
    except ImportError:
        raise SystemExit("needs coacd: pip install coacd (not a weldplan dependency)") from None
    gun = shared_spot_gun()
    v, f = gun.outside_zone(20.0)
    t = time.perf_counter()
    parts = coacd.run_coacd(coacd.Mesh(v, f), threshold=args.threshold)
    print(f"CoACD: {len(parts)} hulls in {time.perf_counter() - t:.1f} s")
    hulls = []
    for pv, pf in parts:
        pf = np.asarray(pf, dtype=np.int64)
        flat = np.hstack([np.full((len(pf), 1), 3), pf]).ravel()
        shape = fcl.Convex(np.asarray(pv, dtype=np.float64), len(pf), flat)
        hulls.append(fcl.CollisionObject(shape, fcl.Transform()))
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(hulls)
    manager.setup()
    car2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"
    cell = weldplan.load_cell(car2, ROOT / "assets/car2/car2_synthetic_50.csv", length=4500)
    search = PoseSearch(cell.part, gun, 20.0, 5.0)
    local, _ = local_candidates(15.0, 7.5, 15.0, 8)
    idx = [int(i) for i in args.welds.split(",")]
    rots = candidate_rotations(-np.asarray(cell.joints.directions)[idx], local)
    t_bvh = t_hull = 0.0
    same = hull_only = bvh_only = 0
    for w, i in enumerate(idx):
        p = cell.joints.xyz[i]
        obj, _ = search.part_near(p)
        t = time.perf_counter()
        a = search.collides(obj, p, rots[w])
        t_bvh += time.perf_counter() - t
        t = time.perf_counter()
        b = np.zeros(len(a), dtype=bool)
        for k, R in enumerate(rots[w]):
            tf = fcl.Transform(R, p)
            for h in hulls:
                h.setTransform(tf)
            manager.update()
            data = fcl.CollisionData(request=fcl.CollisionRequest())
            manager.collide(obj, data, fcl.defaultCollisionCallback)
            b[k] = data.result.is_collision
        t_hull += time.perf_counter() - t
        same += int(np.sum(a == b))
        hull_only += int(np.sum(b & ~a))
        bvh_only += int(np.sum(a & ~b))
    n = rots.shape[0] * rots.shape[1]
    print(
        f"{n} candidates on {len(idx)} welds: BVH {1e3 * t_bvh / n:.3f} ms, "
        f"{len(hulls)} hulls {1e3 * t_hull / n:.3f} ms per candidate; same answer {same} / {n} "
        f"(hulls only: {hull_only}, BVH only: {bvh_only}); load {os.getloadavg()}"
    )


if __name__ == "__main__":
    main()
