"""A dense-sampling oracle for the gun pose search, and its completeness figures (issue 29, item 5).

``weldplan bench gun-oracle --spots 200 --out DIR`` generates a sheet-metal side frame
(:mod:`weldplan.weld.sheetmetal`), asks the oracle and weldplan's pose search
(:func:`weldplan.tool.poses.plan_weld_poses`) which spots the shared C-gun closes on, and
writes the table (``gun_oracle.md``): spots the oracle closes on, spots the search finds a
verified pose for, the spots where they disagree, and the seconds per spot of each.

The oracle
----------
For each spot and its approach axis ``a`` (the joints CSV's direction reversed: into the part),
every orientation of a dense grid is tried until one is free:

* tilts of the tool's axis off ``a`` every :attr:`OracleSettings.tilt_step` (5 deg) up to the
  cone (15 deg), in :attr:`OracleSettings.azimuth_step` (15 deg) directions per ring,
* spins about the tilted axis every :attr:`OracleSettings.spin_step` (5 deg),
* on both sides of the sheet (the axis ``-a``) for a tool that straddles it (a C-gun):
  ``72 x (1 + 3 x 24) x 2 = 10,512`` orientations a spot.

Free means what the pose search means (docs/tool.md, "A pose for every weld"): the tool less
its part inside the contact sphere (``contact_radius`` about the spot) is at least
``clearance`` from the part. The oracle shares none of the search's machinery: its own
orientation grid (scipy rotations, not :mod:`weldplan.tool.poses.orient`), its own cut of the tool
by the sphere (:func:`tool_outside_sphere`: triangles reaching into the sphere subdivided to
0.5 mm edges, those wholly inside dropped; the search's cut uses 1 mm), its own python-fcl
BVHs of the **whole** part (no cropping, no BVH shared between spots), and for every candidate
an ``fcl.collide`` then, where that is clear, an exact ``fcl.distance`` (no lazy distances).
It stops at the first free orientation: it answers whether a spot is closable, not which pose
is best.
"""

from __future__ import annotations

import argparse
import logging
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

log = logging.getLogger(__name__)

#: the edge length (mm) sub-triangles of the tool reaching into the contact sphere are cut to
ORACLE_EDGE_MM = 0.5


@dataclass(frozen=True)
class OracleSettings:
    """The oracle's grid (degrees) and the pose search's definition of free (mm).

    ``contact_radius``, ``clearance`` and ``cone`` default to those of
    :func:`~weldplan.tool.poses.plan_weld_poses`.
    """

    spin_step: float = 5.0
    tilt_step: float = 5.0
    azimuth_step: float = 15.0
    cone: float = 15.0
    contact_radius: float = 20.0
    clearance: float = 5.0
    both_sides: bool = True


@dataclass(frozen=True)
class OracleAnswer:
    """The oracle's answer for one spot.

    ``free`` is whether some orientation of the grid is free; ``rotation`` its ``(3, 3)`` TCP
    frame (columns: TCP axes in the part frame) or ``None``; ``flipped`` whether it is on the
    other side of the sheet; ``tried`` the orientations checked; ``seconds`` the wall time.
    """

    free: bool
    rotation: NDArray[np.float64] | None
    flipped: bool
    tried: int
    seconds: float


def tool_outside_sphere(
    vertices: ArrayLike, faces: ArrayLike, radius: float, edge: float = ORACLE_EDGE_MM
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The tool mesh ``(TCP frame, mm)`` less its part inside the sphere of ``radius`` about
    the TCP: triangles that come within ``radius`` of the TCP (trimesh's closest point on each)
    are subdivided to edges below ``edge`` mm, and those whose three corners lie inside the
    sphere (convex: the whole triangle is inside) are dropped. Returns vertices, faces."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    tri = V[F]
    closest = trimesh.triangles.closest_point(tri, np.zeros((len(tri), 3)))
    reach = np.linalg.norm(closest, axis=1) < radius
    keep_v, keep_f = V, F[~reach]
    sv, sf = trimesh.remesh.subdivide_to_size(V, F[reach], max_edge=edge)
    inside = np.all(np.linalg.norm(sv[sf], axis=2) <= radius, axis=1)
    sf = sf[~inside] + len(keep_v)
    return np.vstack([keep_v, sv]), np.vstack([keep_f, sf])


def _bvh(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> fcl.BVHModel:
    m = fcl.BVHModel()
    m.beginModel(len(vertices), len(faces))
    m.addSubModel(np.asarray(vertices, np.float64), np.asarray(faces, np.int32))
    m.endModel()
    return m


def orientation_grid(axis: ArrayLike, s: OracleSettings) -> NDArray[np.float64]:
    """``(k, 3, 3)`` TCP frames whose +z is ``axis (3,)`` tilted by 0, ``tilt_step``, ... up to
    ``cone`` deg towards every ``azimuth_step`` deg, each spun every ``spin_step`` deg about
    its own +z; untilted first."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    helper = np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, a)
    x /= np.linalg.norm(x)
    base = np.column_stack([x, np.cross(a, x), a])
    spins = np.arange(0.0, 360.0, s.spin_step)
    tilts = np.arange(s.tilt_step, s.cone + 1e-9, s.tilt_step)
    azim = np.arange(0.0, 360.0, s.azimuth_step)
    angles = [(0.0, 0.0, sp) for sp in spins]
    angles += [(az, t, sp) for t in tilts for az in azim for sp in spins]
    # R = base * Rz(azimuth) * Ry(tilt) * Rz(spin - azimuth): tool +z = tilted axis
    e = np.array([[az, t, sp - az] for az, t, sp in angles])
    local = Rotation.from_euler("ZYZ", e, degrees=True).as_matrix()
    return np.einsum("ij,kjl->kil", base, local)


class GunOracle:
    """The dense-sampling oracle (module docstring) for one part and one tool.

    Parameters
    ----------
    part
        The part, mm (the whole of it).
    tool
        A :class:`~weldplan.tool.model.Tool` (its mesh in the TCP frame, mm).
    settings
        :class:`OracleSettings`.
    """

    def __init__(self, part: trimesh.Trimesh, tool: object, settings: OracleSettings | None = None):
        self.s = settings or OracleSettings()
        self._part = fcl.CollisionObject(
            _bvh(np.asarray(part.vertices), np.asarray(part.faces)), fcl.Transform()
        )
        v, f = tool_outside_sphere(tool.vertices, tool.faces, self.s.contact_radius)  # type: ignore[attr-defined]
        self._tool = fcl.CollisionObject(_bvh(v, f), fcl.Transform())
        self.straddles = bool(getattr(tool, "straddles", False)) and self.s.both_sides

    def free(self, position: ArrayLike, R: NDArray[np.float64]) -> bool:
        """Whether the TCP frame ``R (3, 3)`` at ``position (3,)`` is free."""
        self._tool.setTransform(fcl.Transform(R, np.asarray(position, np.float64)))
        if fcl.collide(self._tool, self._part, fcl.CollisionRequest(), fcl.CollisionResult()):
            return False
        if self.s.clearance <= 0:
            return True
        d = fcl.distance(self._tool, self._part, fcl.DistanceRequest(), fcl.DistanceResult())
        return d >= self.s.clearance

    def closes(self, position: ArrayLike, axis: ArrayLike) -> OracleAnswer:
        """Search the grid about ``axis (3,)`` (into the part) at ``position``, then about
        ``-axis`` for a straddling tool; stop at the first free orientation."""
        t0 = time.perf_counter()
        tried = 0
        sides = (False, True) if self.straddles else (False,)
        for flipped in sides:
            for R in orientation_grid(-np.asarray(axis) if flipped else axis, self.s):
                tried += 1
                if self.free(position, R):
                    return OracleAnswer(True, R, flipped, tried, time.perf_counter() - t0)
        return OracleAnswer(False, None, False, tried, time.perf_counter() - t0)


@dataclass(frozen=True)
class Completeness:
    """Oracle against search on a set of spots; times in seconds (wall, and the process's CPU
    seconds of all spots: less sensitive to other work on a shared machine)."""

    ids: tuple[str, ...]
    oracle: tuple[bool, ...]
    search: tuple[bool, ...]
    oracle_s: tuple[float, ...]
    search_s: float
    oracle_cpu_s: float = float("nan")
    search_cpu_s: float = float("nan")

    @property
    def misses(self) -> tuple[str, ...]:
        """Spots the oracle closes on and the search does not."""
        return tuple(
            i for i, o, s in zip(self.ids, self.oracle, self.search, strict=True) if o and not s
        )

    @property
    def extra(self) -> tuple[str, ...]:
        """Spots the search closes on and the oracle does not (its grid is no superset)."""
        return tuple(
            i for i, o, s in zip(self.ids, self.oracle, self.search, strict=True) if s and not o
        )


def completeness(
    part: trimesh.Trimesh, joints: object, tool: object, settings: OracleSettings | None = None
) -> Completeness:
    """Run the oracle and :func:`~weldplan.tool.poses.plan_weld_poses` (its defaults: the same
    cone, contact radius and clearance as :class:`OracleSettings`) on the same spots."""
    from weldplan.tool.poses.plan import plan_weld_poses
    from weldplan.tool.settings import PoseSearchSettings

    s = settings or OracleSettings()
    t0, c0 = time.perf_counter(), time.process_time()
    search = PoseSearchSettings(cone=s.cone, contact_radius=s.contact_radius, clearance=s.clearance)
    poses = plan_weld_poses(part, joints, tool, search)
    search_s, search_cpu = time.perf_counter() - t0, time.process_time() - c0
    by_id = {p.id: p.ok for p in poses.poses}
    oracle = GunOracle(part, tool, s)
    axes = -np.asarray(joints.directions)  # type: ignore[attr-defined]
    c0 = time.process_time()
    answers = [oracle.closes(p, a) for p, a in zip(joints.xyz, axes, strict=True)]  # type: ignore[attr-defined]
    ids = tuple(joints.ids)  # type: ignore[attr-defined]
    return Completeness(
        ids=ids,
        oracle=tuple(a.free for a in answers),
        search=tuple(by_id[i] for i in ids),
        oracle_s=tuple(a.seconds for a in answers),
        search_s=search_s,
        oracle_cpu_s=time.process_time() - c0,
        search_cpu_s=search_cpu,
    )


#: the hat profiles of the "deep" frame of the figures: deep, nearly upright walls beside the
#: flanges (the fixed electrode passes close to them), where the gun needs its tilts
DEEP_PROFILES: dict[str, tuple[float, float, float]] = {
    "sill": (110.0, 120.0, 90.0),
    "pillar": (90.0, 100.0, 100.0),
    "rail": (70.0, 80.0, 70.0),
}


def frame_settings(kind: str, n_spots: int | None) -> object:
    """The side frame of the figures: ``"default"`` (:class:`SheetFrameSettings`) or
    ``"deep"`` (:data:`DEEP_PROFILES`)."""
    from weldplan.weld.sheetmetal import HatProfile, SheetFrameSettings

    if kind == "default":
        return SheetFrameSettings(n_spots=n_spots)
    if kind == "deep":
        hats = {k: HatProfile(*v) for k, v in DEEP_PROFILES.items()}
        return SheetFrameSettings(n_spots=n_spots, **hats)
    raise ValueError(f"unknown frame {kind!r}: default or deep")


def _table(name: str, c: Completeness) -> list[str]:
    n, no, ns = len(c.ids), sum(c.oracle), sum(c.search)
    both = sum(o and s for o, s in zip(c.oracle, c.search, strict=True))
    share = 100.0 * both / no if no else float("nan")
    return [
        f"| {name} | {n} | {no} | {ns} | {both} ({share:.1f} %) | "
        f"{', '.join(c.misses) or '-'} | {', '.join(c.extra) or '-'} | "
        f"{np.mean(c.oracle_s):.3f} (max {np.max(c.oracle_s):.2f}; CPU {c.oracle_cpu_s / n:.3f}) | "
        f"{c.search_s / n:.3f} (CPU {c.search_cpu_s / n:.3f}) |"
    ]


HELP = "the gun pose search against a dense independent oracle on sheet-metal side frames"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--frames", nargs="+", default=["default", "deep"], help="default, deep")
    p.add_argument("--seed", type=int, default=0, help="the side frame's seed (default 0)")
    p.add_argument("--spots", type=int, default=None, help="spots per frame (default: all)")


def run(args: argparse.Namespace) -> int:
    """The completeness table of the shared gun's pose search, written to ``args.out``."""
    from weldplan.tool import shared_spot_gun
    from weldplan.weld.sheetmetal import generate_side_frame

    gun = shared_spot_gun()
    rows = [
        "| frame | spots | oracle closes | search ok | both (of oracle) | search misses | "
        "search only | oracle s/spot | search s/spot |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for kind in args.frames:
        st = generate_side_frame(frame_settings(kind, args.spots), rng=args.seed)  # type: ignore[arg-type]
        c = completeness(st.combined(), st.spots, gun)
        rows += _table(f"{kind} (seed {args.seed})", c)
        log.info("%s", rows[-1])
    load = os.getloadavg()
    text = "\n".join(
        ["# Gun pose search against the dense oracle (shared C-gun, sheet-metal side frame)", ""]
        + rows
        + ["", f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}, {os.cpu_count()} CPUs", ""]
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "gun_oracle.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m weldplan.bench.gun_oracle [--frames default deep] [--seed 0] [--spots N]
    [--out DIR]`` (= ``weldplan bench gun-oracle``)."""
    ap = argparse.ArgumentParser(prog="python -m weldplan.bench.gun_oracle", description=HELP)
    ap.add_argument("--out", type=Path, default=Path("."))
    add_arguments(ap)
    return run(ap.parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
