"""``weldplan bench grid``: time and peak memory of the 5 mm obstacle grid.

Measures :func:`weldplan.geometry.grid.build_grid` on ../shared/data/bodies/car2.obj scaled to a
4500 mm body, over the whole body and over a 600 mm cube (the densest one, where the most
surface lies), and, side by side in the same run, trimesh's ``voxelized(pitch=5)`` against
weldplan on ../shared/data/bodies/car5.obj. Every measurement runs in its own process so that
the peak memory figures are separate.

The two voxelisers answer different questions: trimesh marks the voxels the surface passes
through; weldplan marks every voxel centre of the box closer to the surface than the clearance
(the paper's obstacle rule), which is the grid the planners need.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from weldplan.bench.common import CHILD_PRELUDE, conditions, run_child, shared_path, table

HELP = "5 mm obstacle grid: whole car2, a 600 mm cube, and trimesh's voxeliser on car5"

log = logging.getLogger(__name__)

_OURS = (
    CHILD_PRELUDE
    + """
import numpy as np
from weldplan.io.mesh import load_part
from weldplan.geometry.grid import build_grid
from weldplan.geometry.distance import SurfaceDistance
mesh = load_part({path!r}, length={length!r})
region = {region!r}
if region == "cube":
    # the 600 mm cube holding the most surface, centred on one of 400 sampled face centres
    rng = np.random.default_rng(0)
    c = mesh.triangles_center
    cand = c[rng.choice(len(c), 400, replace=False)]
    inside = np.all(np.abs(c[None, :, :] - cand[:, None, :]) <= 300.0, axis=2)
    best = cand[np.argmax(inside @ mesh.area_faces)]
    region = np.stack([best - 300.0, best + 300.0]).tolist()
SurfaceDistance(mesh)  # import open3d before the clock starts
rss0 = rss_mib()
t = time.perf_counter()
grid = build_grid(mesh, pitch=5.0, clearance=5.0, region=region, margin=0.0)
dt = time.perf_counter() - t
print(json.dumps(dict(seconds=dt, peak_mib=peak_mib(), before_mib=rss0, shape=list(grid.shape),
                      obstacle=grid.n_obstacle, voxels=int(np.prod(grid.shape)),
                      region=region if isinstance(region, str) else np.round(region, 1).tolist(),
                      faces=len(mesh.faces), extents=np.round(mesh.extents, 1).tolist())))
"""
)

_TRIMESH = (
    CHILD_PRELUDE
    + """
import trimesh
mesh = trimesh.load({path!r}, force="mesh")
rss0 = rss_mib()
t = time.perf_counter()
vox = mesh.voxelized(pitch=5.0)
dt = time.perf_counter() - t
print(json.dumps(dict(seconds=dt, peak_mib=peak_mib(), before_mib=rss0,
                      shape=[int(s) for s in vox.shape], filled=int(vox.filled_count))))
"""
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--skip-trimesh",
        action="store_true",
        help="skip trimesh's voxelized(pitch=5) on car5 (about 214 s on a 2-core machine)",
    )


def run(args: argparse.Namespace) -> int:
    car2 = str(shared_path("bodies", "car2.obj"))
    car5 = str(shared_path("bodies", "car5.obj"))
    before = conditions()
    rows = []
    results = {}
    for name, path, length, region in (
        ("car2 (4500 mm), whole body", car2, 4500.0, "all"),
        ("car2 (4500 mm), densest 600 mm cube", car2, 4500.0, "cube"),
        ("car5 (mm), whole body", car5, None, "all"),
    ):
        r = run_child(_OURS.format(path=path, length=length, region=region))
        results[name] = r
        log.info("%s: %.2f s", name, r["seconds"])
        rows.append(
            [
                f"weldplan build_grid: {name}",
                " x ".join(map(str, r["shape"])),
                f"{r['voxels']:,}",
                f"{r['obstacle']:,} obstacle",
                f"{r['seconds']:.2f}",
                f"{r['peak_mib']:.0f} ({r['peak_mib'] - r['before_mib']:+.0f})",
            ]
        )
    if not args.skip_trimesh:
        r = run_child(_TRIMESH.format(path=car5))
        results["trimesh"] = r
        rows.append(
            [
                "trimesh voxelized(pitch=5): car5 (mm), surface voxels",
                " x ".join(map(str, r["shape"])),
                f"{r['shape'][0] * r['shape'][1] * r['shape'][2]:,}",
                f"{r['filled']:,} filled",
                f"{r['seconds']:.2f}",
                f"{r['peak_mib']:.0f} ({r['peak_mib'] - r['before_mib']:+.0f})",
            ]
        )
    lines = [
        "# Obstacle grid at 5 mm pitch, 5 mm clearance",
        "",
        f"Before: {before}  ",
        f"After: {conditions()}",
        "",
        table(
            ["what", "grid", "voxels", "marked", "seconds", "peak RSS MiB (+ over imports)"],
            rows,
        ),
        "",
    ]
    cube = results["car2 (4500 mm), densest 600 mm cube"]
    lines.append(f"600 mm cube bounds (mm): {cube['region']}.")
    if "trimesh" in results:
        ratio = results["trimesh"]["seconds"] / results["car5 (mm), whole body"]["seconds"]
        lines.append(
            f"On car5, weldplan's grid (every centre of the box classified by the exact "
            f"clearance rule) took 1/{ratio:.0f} of the time of trimesh's surface voxeliser "
            f"(ratio {ratio:.1f}, same run)."
        )
    lines += [
        "",
        "Each row is a separate process; peak RSS includes the interpreter, numpy, trimesh and "
        "open3d (the figure in brackets is the growth during the build).",
        "",
    ]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "grid.md").write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))
    return 0
