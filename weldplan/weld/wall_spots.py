"""Synthetic spots along car2's thin free-standing wall (``python -m weldplan.weld.wall_spots``).

car2 is a slab model (issue 29: its walls are 35 / 68 / 322 mm thick at the 5th / 50th / 95th
percentile), so a C-gun closes on almost none of its sheet-metal spots. It has one wall thin
enough for the shared gun to straddle: a transverse bulkhead about 9 mm thick (8-11 mm), standing
across the body at ``x`` about -1100 mm (scaled to 4500 mm), its top edge free. This module finds
it and writes a station of spots along its top edge, labelled *synthetic*:

1. **Thin samples.** The surface is sampled (a point per :data:`SAMPLE_SPACING_MM` squared,
   ``rng``); from each sample a ray goes inwards along the face normal, and the sample is
   *thin* when it leaves the slab through an antiparallel face (``cos`` at least
   :data:`PARALLEL_COS`) between :data:`THICKNESS_MM` apart.
2. **The wall.** Thin samples within :data:`LINK_MM` of each other form groups; the wall is the
   largest group and the groups of at least :data:`PART_SHARE` of its size whose top edge lies
   within :data:`TOP_TOL_MM` of its own (the mesh's height axis is ``y``: car2 is y-up); its top
   edge is where a line down through the slab's middle at the highest thin sample meets it.
3. **Spots.** Candidate positions every :data:`CANDIDATE_STEP_MM` along the wall's width, each
   :data:`EDGE_INSET_MM` below the top edge; a candidate is kept when a ray across the wall
   there (along the wall's normal, the body's length axis ``x``) crosses exactly one slab whose
   thickness lies in :data:`THICKNESS_MM`. ``n`` spots are taken from the kept candidates
   evenly by rank (so evenly along the wall where it qualifies), each shifted by a seeded
   jitter of at most :data:`JITTER_MM`; the spot lies on the wall's face towards ``-x`` (the
   face the line along +x meets first) and its approach is that face's outward normal.

Everything is a function of the mesh, ``n`` and ``seed``: the same call gives the same spots.
The wall is found by this module's own ray test, not by
:func:`weldplan.geometry.flanges.find_flanges`: car2 models this wall as two separate open
surfaces (two connected components, each face's normal pointing out of the slab) about 9 mm
apart, which that finder reads as two zero-thickness single skins (a wall there is one closed
body, and two sheets are a stack only within ``max_gap`` = 4 mm).
"""

from __future__ import annotations

import argparse
import logging
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.io.joints import Joints
from weldplan.random import RNGLike, as_generator

log = logging.getLogger(__name__)

#: mm: surface samples of step 1 lie about this far apart (600k samples on car2's 33 m^2)
SAMPLE_SPACING_MM = 7.5
#: mm: a thin sample's slab thickness range (the issue's "8-11 mm", with half a mm each way for
#: the slab's slight taper)
THICKNESS_MM = (7.5, 11.5)
#: the exit face is antiparallel to the entry face within this cosine
PARALLEL_COS = 0.9
#: mm: thin samples nearer than this belong to one group
LINK_MM = 20.0
#: a group of thin samples belongs to the wall when it holds at least this share of the largest
#: group's samples and its top lies within TOP_TOL_MM of that group's (car2's bulkhead reads as
#: three groups: its two halves and the piece between them)
PART_SHARE = 0.1
TOP_TOL_MM = 10.0
#: mm: the candidate spacing along the wall's width (step 3)
CANDIDATE_STEP_MM = 2.0
#: mm: spots lie this far below the wall's free top edge
EDGE_INSET_MM = 20.0
#: mm: the largest seeded shift of a spot along the wall
JITTER_MM = 4.0
#: the mesh's height axis (car2.obj is y-up) and the wall's normal axis (the body's length)
UP_AXIS = 1
NORMAL_AXIS = 0
#: mm: a ray leaves its surface point this far inside, so as not to hit its own face
_START_MM = 0.01
#: the station label of every spot
STATION = "WALL"


@dataclass(frozen=True)
class Wall:
    """The thin wall of step 2 (part frame, mm).

    ``top`` is the height of its free top edge (along :data:`UP_AXIS`); ``width`` the
    ``(lo, hi)`` range it spans along the third axis; ``x_range`` its extent along
    :data:`NORMAL_AXIS` (the wall is curved in plan); ``thickness`` the median of its samples;
    ``samples`` how many thin samples it holds.
    """

    top: float
    width: tuple[float, float]
    x_range: tuple[float, float]
    thickness: float
    samples: int


def find_wall(mesh: trimesh.Trimesh, *, rng: RNGLike = 0) -> Wall:
    """The largest thin wall of ``mesh`` (module docstring, steps 1-2).

    Raises ``ValueError`` when the mesh has no thin sample.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    gen = as_generator(rng)
    count = max(int(np.ceil(mesh.area / SAMPLE_SPACING_MM**2)), 1)
    P, face = trimesh.sample.sample_surface(mesh, count, seed=int(gen.integers(2**31)))
    N = np.asarray(mesh.face_normals)[face]
    t, cos = _inward_hits(mesh, np.asarray(P, np.float64), N)
    lo, hi = THICKNESS_MM
    thin = (t >= lo) & (t <= hi) & (cos >= PARALLEL_COS)
    X, T = np.asarray(P)[thin], t[thin]
    if len(X) == 0:
        raise ValueError(f"no wall {lo:g}-{hi:g} mm thick on this mesh")
    pairs = cKDTree(X).query_pairs(LINK_MM, output_type="ndarray")
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(X),) * 2)
    _, label = connected_components(g, directed=False)
    count = np.bincount(label)
    first = int(np.argmax(count))
    top = np.full(len(count), -np.inf)
    np.maximum.at(top, label, X[:, UP_AXIS])
    parts = (count >= PART_SHARE * count[first]) & (np.abs(top - top[first]) <= TOP_TOL_MM)
    big = parts[label]
    W, across = X[big], 3 - UP_AXIS - NORMAL_AXIS
    return Wall(
        top=_top_edge(mesh, X, N[thin], T, big),
        width=(float(W[:, across].min()), float(W[:, across].max())),
        x_range=(float(W[:, NORMAL_AXIS].min()), float(W[:, NORMAL_AXIS].max())),
        thickness=float(np.median(T[big])),
        samples=int(big.sum()),
    )


def _top_edge(
    mesh: trimesh.Trimesh, X: NDArray, N: NDArray, T: NDArray, mask: NDArray[np.bool_]
) -> float:
    """The height (mm) of the wall's top face above its highest thin sample: a line down through
    the slab's middle there, from above the sample, meets the mesh first at the top face."""
    k = int(np.flatnonzero(mask)[np.argmax(X[mask, UP_AXIS])])
    mid = X[k] - 0.5 * T[k] * N[k]
    up = np.zeros(3)
    up[UP_AXIS] = 1.0
    loc, _, _ = mesh.ray.intersects_location([mid + LINK_MM * up], [-up])
    above = loc[loc[:, UP_AXIS] >= X[k, UP_AXIS] - 1e-6, UP_AXIS]
    return float(above.max()) if len(above) else float(X[k, UP_AXIS])


def _inward_hits(
    mesh: trimesh.Trimesh, P: NDArray[np.float64], N: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per point ``(n, 3)``: the distance (mm) to the first face hit inwards along ``-N`` and the
    cosine between that face's normal and the ray (``inf`` and ``nan`` where nothing is hit)."""
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32))
    rays = np.hstack([P - _START_MM * N, -N]).astype(np.float32)
    r = scene.cast_rays(rays)
    t = r["t_hit"].numpy().astype(np.float64) + _START_MM
    hit = np.isfinite(t)
    f = r["primitive_ids"].numpy().astype(np.int64)
    cos = np.full(len(P), np.nan)
    cos[hit] = np.einsum("ij,ij->i", np.asarray(mesh.face_normals)[f[hit]], -N[hit])
    return t, cos


def _crossing(mesh: trimesh.Trimesh, wall: Wall, c: NDArray[np.float64]) -> NDArray | None:
    """The wall's two faces crossed by the line along the normal axis at across-position ``c``
    (``(m,)`` mm) at the spot height: ``(m, 2)`` coordinates of the entry and exit (nan where the
    line does not cross exactly one slab of the thickness range)."""
    across = 3 - UP_AXIS - NORMAL_AXIS
    margin = 100.0
    O = np.zeros((len(c), 3))
    O[:, UP_AXIS] = wall.top - EDGE_INSET_MM
    O[:, across] = c
    O[:, NORMAL_AXIS] = wall.x_range[0] - margin
    D = np.zeros((len(c), 3))
    D[:, NORMAL_AXIS] = 1.0
    loc, ray, _ = mesh.ray.intersects_location(O, D, multiple_hits=True)
    out = np.full((len(c), 2), np.nan)
    lo, hi = THICKNESS_MM
    for k in range(len(c)):
        x = loc[ray == k, NORMAL_AXIS]
        x = np.unique(np.round(x[x <= wall.x_range[1] + margin], 4))
        if len(x) == 2 and lo <= x[1] - x[0] <= hi:
            out[k] = x
    return out


def wall_spots(
    mesh: trimesh.Trimesh, n: int, *, rng: RNGLike = 0, wall: Wall | None = None
) -> Joints:
    """``n`` spots along the top edge of ``mesh``'s thin wall (module docstring, step 3).

    Returns
    -------
    Joints
        ``W-1 .. W-n`` along the wall's width, ``xyz (n, 3)`` mm on the wall's ``-x`` face,
        ``directions (n, 3)`` that face's outward unit normal.
    """
    gen = as_generator(rng)
    wall = find_wall(mesh, rng=gen) if wall is None else wall
    c = np.arange(wall.width[0], wall.width[1], CANDIDATE_STEP_MM)
    faces = _crossing(mesh, wall, c)
    ok = np.isfinite(faces[:, 0])
    if ok.sum() < n:
        raise ValueError(f"the wall has {int(ok.sum())} spot positions, fewer than {n}")
    cand, x_front = c[ok], faces[ok, 0]
    # n candidates evenly spread by rank (the kept candidates are CANDIDATE_STEP_MM apart
    # where the wall qualifies), each moved by a seeded jitter of whole candidate steps
    rank = np.linspace(0, len(cand) - 1, n + 2)[1:-1]
    shift = np.rint(gen.uniform(-JITTER_MM, JITTER_MM, size=n) / CANDIDATE_STEP_MM)
    pick = np.clip(np.rint(rank) + shift, 0, len(cand) - 1).astype(np.int64)
    pick_a = np.unique(pick)
    if len(pick_a) < n:
        raise ValueError(f"{n} spots do not fit on the wall's {len(cand)} positions")
    across = 3 - UP_AXIS - NORMAL_AXIS
    xyz = np.zeros((n, 3))
    xyz[:, NORMAL_AXIS] = x_front[pick_a]
    xyz[:, UP_AXIS] = wall.top - EDGE_INSET_MM
    xyz[:, across] = cand[pick_a]
    # the outward normal of the face each spot lies on
    _, _, tri = trimesh.proximity.closest_point(mesh, xyz)
    nrm = np.asarray(mesh.face_normals)[tri]
    nrm *= np.where(nrm[:, NORMAL_AXIS] > 0, -1.0, 1.0)[:, None]
    ids = tuple(f"W-{k + 1}" for k in range(n))
    return Joints(ids=ids, xyz=xyz, directions=nrm)


def car2_wall_spots(n: int = 40, seed: int = 0, mesh: trimesh.Trimesh | None = None) -> Joints:
    """The ``n``-spot wall station on car2 scaled to 4500 mm (requires ../shared/data)."""
    from weldplan.weld.synthetic import car2_part

    return wall_spots(car2_part() if mesh is None else mesh, n, rng=seed)


def write_wall_set(path: str | PathLike[str], joints: Joints, wall: Wall, *, seed: int) -> None:
    """Write ``id,x,y,z,nx,ny,nz,station`` with a ``# SYNTHETIC`` header saying how it was made."""
    from weldplan.weld.synthetic import CAR2_LENGTH_MM

    assert joints.directions is not None
    lines = [
        f"# SYNTHETIC weld spots ({len(joints)}): not measured; generated by "
        f"weldplan.weld.wall_spots.car2_wall_spots(n={len(joints)}, seed={seed}) on car2.obj "
        f'scaled to {CAR2_LENGTH_MM:g} mm (part frame, y up: stand it upright with up = "y"); '
        f"along the top edge of its thin free-standing wall ({wall.thickness:.1f} mm median, "
        f"{THICKNESS_MM[0]:g}-{THICKNESS_MM[1]:g} mm; top edge at y = {wall.top:.1f}), "
        f"{EDGE_INSET_MM:g} mm below the edge on the wall's -x face, approach = its normal",
        "id,x,y,z,nx,ny,nz,station",
    ]
    for k, jid in enumerate(joints.ids):
        vals = [f"{v:.3f}" for v in joints.xyz[k]] + [f"{v:.6f}" for v in joints.directions[k]]
        lines.append(",".join([jid, *vals, STATION]))
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m weldplan.weld.wall_spots",
        description="Write the synthetic spots along car2's thin wall (labelled synthetic).",
    )
    p.add_argument("-n", type=int, default=40, help="spots (default 40)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="assets/car2/car2_wall_40.csv", help="the CSV to write")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    from weldplan.weld.synthetic import car2_part

    mesh = car2_part()
    gen = as_generator(args.seed)
    wall = find_wall(mesh, rng=gen)
    joints = wall_spots(mesh, args.n, rng=gen, wall=wall)
    write_wall_set(args.out, joints, wall, seed=args.seed)
    log.info("%s: %d spots on the wall %s", args.out, args.n, wall)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
