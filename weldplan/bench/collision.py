"""``weldplan bench collision``: segment checks per second on car2.

Random segments near ../shared/data/bodies/car2.obj scaled to 4500 mm: each starts 5-50 mm
from a point sampled uniformly on the surface, in a random direction, and runs 50-300 mm in
another random direction; the torch-tip radius is 5 mm. ``segments_free`` (sphere tracing on
open3d distances, fcl for the rest) is timed against pure python-fcl on the same segments, and
their answers are compared.
"""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

import numpy as np
import trimesh

from weldplan.bench.common import conditions, shared_path, table
from weldplan.geometry.collision import CollisionModel
from weldplan.io.mesh import load_part

HELP = "segments_free throughput on car2 (random 50-300 mm segments near the surface)"

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--segments", type=int, default=20000, help="segments (default 20000)")
    parser.add_argument(
        "--fcl-segments", type=int, default=5000, help="of which checked by pure fcl too"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--repeat", type=int, default=3, help="timed repetitions (best kept)")


def random_segments(
    mesh: trimesh.Trimesh, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``(n, 3)`` starts 5-50 mm off the surface and ends 50-300 mm away (mm)."""
    S, _ = trimesh.sample.sample_surface(mesh, n, seed=int(rng.integers(2**31)))
    u = rng.normal(size=(n, 3))
    v = rng.normal(size=(n, 3))
    A = S + u / np.linalg.norm(u, axis=1, keepdims=True) * rng.uniform(5, 50, (n, 1))
    B = A + v / np.linalg.norm(v, axis=1, keepdims=True) * rng.uniform(50, 300, (n, 1))
    return A, B


def run(args: argparse.Namespace) -> int:
    mesh = load_part(shared_path("bodies", "car2.obj"), length=4500)
    rng = np.random.default_rng(args.seed)
    A, B = random_segments(mesh, args.segments, rng)
    model = CollisionModel(mesh)
    model.segments_free(A[:100], B[:100], 5.0)  # build the open3d scene and warm up
    before = conditions()
    best = np.inf
    for _ in range(args.repeat):
        t = time.perf_counter()
        fast = model.segments_free(A, B, 5.0)
        best = min(best, time.perf_counter() - t)
    status = model._trace(A, B, 5.0)
    m = min(args.fcl_segments, args.segments)
    t = time.perf_counter()
    ref = model.segments_free(A[:m], B[:m], 5.0, method="fcl")
    t_fcl = time.perf_counter() - t
    agree = int(np.sum(ref == fast[:m]))
    rate, rate_fcl = args.segments / best, m / t_fcl
    rows = [
        [
            "segments_free (rays, sphere tracing, fcl for the rest)",
            f"{args.segments:,}",
            f"{best:.3f}",
            f"{rate:,.0f}",
        ],
        ["pure python-fcl capsules", f"{m:,}", f"{t_fcl:.3f}", f"{rate_fcl:,.0f}"],
    ]
    lines = [
        "# Segment checks on car2 (4500 mm), torch-tip radius 5 mm",
        "",
        f"Before: {before}  ",
        f"After: {conditions()}",
        "",
        table(["method", "segments", "seconds", "segments / s"], rows),
        "",
        f"Speed-up over pure fcl: {rate / rate_fcl:.1f}x (same run). Free: "
        f"{fast.mean():.1%} of the segments. Decided without fcl: "
        f"{np.mean(status != 0):.2%}. Agreement with pure fcl: {agree} / {m}.",
        "",
    ]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "collision.md").write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))
    return 0
