"""The demo part: a sheet-metal sub-assembly built around the 15 weld joints of Wang et al. 2017.

The paper's part (its Figures 1-3) is not published, only its weld joints (Table 1). This module
builds a stand-in from flanged sheet-metal panels (1.5-2 mm sheet, boxes and sheared boxes from
``trimesh.creation``) so that:

* every joint lies exactly on a flange face (distance to the mesh 0 to round-off): each flange is
  a chain of planar strips whose front faces pass through consecutive joints of one seam;
* joints 1-3 sit on an outer flange and joints 4-6 on the inner sheet of the same lap, just below
  the outer flange's edge (the two rows of Table 1 are 2.75 mm apart across the sheets);
* a stiffener bracket stands across the straight line from joint 3 to joint 7 (and the lines of
  several other pairs), so obstacle avoidance matters, but a detour of a few per cent exists
  around its edge, as in the paper (SO-ACO 203.29 mm against a straight 202.91 mm).

Run ``python -m weldplan.weld.demo_part`` to regenerate ``assets/demo/part.stl`` and
``assets/demo/joints.csv``; a test checks that the committed files equal a fresh generation.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)

#: folder of the demo assets (the joints CSV and the generated part)
DEMO_DIR = Path(__file__).resolve().parents[2] / "assets" / "demo"
DEMO_JOINTS = DEMO_DIR / "joints.csv"
DEMO_PART = DEMO_DIR / "part.stl"

#: Wang et al. 2017, Table 1: weld joints 1..15 (mm)
TABLE1_XYZ: NDArray[np.float64] = np.array(
    [
        [1443.60, -53.20, 686.00],
        [1399.56, -60.05, 688.49],
        [1356.00, -66.67, 689.57],
        [1456.36, -48.49, 669.34],
        [1417.70, -54.51, 671.94],
        [1379.31, -60.57, 674.61],
        [1504.91, -126.99, 813.51],
        [1493.74, -109.17, 801.14],
        [1474.16, -111.25, 791.00],
        [1442.88, -117.47, 779.19],
        [1414.82, -122.26, 771.35],
        [1356.71, -132.48, 759.65],
        [1554.17, -94.37, 909.95],
        [1539.25, -99.03, 879.83],
        [1549.76, -8.79, 903.34],
    ]
)

#: bracket width, height and the offset of the 3 -> 7 line from its edge (mm)
BRACKET = (24.0, 20.0, 5.0)
#: side of the square tab carrying joint 7 (mm)
TAB = 24.0

_X = np.array([1.0, 0.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


def _unit(v: ArrayLike) -> NDArray[np.float64]:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _parallelepiped(
    corner: ArrayLike, e1: ArrayLike, e2: ArrayLike, e3: ArrayLike
) -> trimesh.Trimesh:
    """Closed box spanned by edge vectors ``e1, e2, e3`` (3,) from ``corner`` (3,), mm."""
    M = np.column_stack([e1, e2, e3]).astype(np.float64)
    T = np.eye(4)
    T[:3, :3] = M
    T[:3, 3] = np.asarray(corner, dtype=np.float64) + 0.5 * M.sum(axis=1)
    return trimesh.creation.box(extents=(1.0, 1.0, 1.0), transform=T)


def flange(
    seam: ArrayLike,
    *,
    sweep: ArrayLike | None = None,
    front: ArrayLike | None = None,
    look_at: ArrayLike | None = None,
    down: float,
    up: float,
    thickness: float,
    extend: float | tuple[float, float],
    web: float = 0.0,
    web_at: str = "up",
) -> tuple[list[trimesh.Trimesh], NDArray[np.float64]]:
    """A flange whose front face passes exactly through the seam's joints.

    Parameters
    ----------
    seam
        ``(k, 3)`` joints along the seam (mm), in order.
    sweep
        ``(3,)`` direction across the flange (the strip is swept from ``-down`` to ``+up``
        along it); must not be parallel to any seam segment.
    front
        ``(3,)`` a direction the front face should look towards (the torch side).
    look_at
        Instead of ``sweep`` and ``front``: a point (3,) that each strip's front face looks at
        (``up`` is then the side towards +z).
    down, up
        Flange width below and above the seam line (mm, along ``sweep``).
    thickness
        Sheet thickness (mm), laid behind the front face.
    extend
        Length (mm) the flange runs past the first and last joint (one value or a pair).
    web, web_at
        A panel of ``web`` mm leaving the flange's ``"up"`` or ``"down"`` edge backwards (away
        from the front), same thickness: the flanged panel the flange belongs to.

    Returns
    -------
    parts, normals
        The closed boxes, and ``(k - 1, 3)`` unit front normals of the strips.
    """
    P = np.asarray(seam, dtype=np.float64)
    ext = (extend, extend) if np.isscalar(extend) else tuple(extend)
    parts = []
    normals = []
    for i in range(len(P) - 1):
        a, b = P[i].copy(), P[i + 1].copy()
        u = _unit(b - a)
        if look_at is not None:
            t = np.asarray(look_at, dtype=np.float64) - 0.5 * (a + b)
            n = _unit(t - np.dot(t, u) * u)
            v = _unit(np.cross(n, u))
            if v[2] < 0:
                v = -v
        else:
            v = _unit(sweep)
            n = _unit(np.cross(u, v))
            if np.dot(n, front) < 0:
                n = -n
        if i == 0:
            a -= ext[0] * u
        if i == len(P) - 2:
            b += ext[1] * u
        parts.append(_parallelepiped(a - down * v, b - a, (down + up) * v, -thickness * n))
        if web > 0:
            edge = a + up * v if web_at == "up" else a - down * v
            side = -v if web_at == "up" else v
            parts.append(_parallelepiped(edge, b - a, -web * n, thickness * side))
        normals.append(n)
    return parts, np.array(normals)


def bracket(
    a: ArrayLike,
    b: ArrayLike,
    *,
    across: ArrayLike,
    width: float,
    height: float,
    thickness: float,
    offset: float,
) -> trimesh.Trimesh:
    """A plate standing across the straight line from ``a`` to ``b`` (3,) at its midpoint.

    The plate is normal to ``b - a``; it spans ``width`` mm along ``across`` (made normal to the
    line) and ``height`` mm along the third direction, and the line crosses it ``offset`` mm
    from its edge on the ``-across`` side, so the shortest detour goes round that edge.
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    t = _unit(b - a)
    w1 = _unit(np.asarray(across) - np.dot(across, t) * t)
    w2 = np.cross(t, w1)
    mid = 0.5 * (a + b)
    corner = mid - offset * w1 - 0.5 * height * w2 - 0.5 * thickness * t
    return _parallelepiped(corner, width * w1, height * w2, thickness * t)


def tab(centre: ArrayLike, *, normal: ArrayLike, size: float, thickness: float) -> trimesh.Trimesh:
    """A square plate of side ``size`` (mm) whose front face, normal to ``normal``, is centred
    on ``centre`` (3,); the sheet ``thickness`` lies behind the face."""
    n = _unit(normal)
    w1 = _unit(np.cross(n, _Z))
    w2 = np.cross(n, w1)
    corner = np.asarray(centre, dtype=np.float64) - 0.5 * size * (w1 + w2)
    return _parallelepiped(corner, size * w1, size * w2, -thickness * n)


def demo_assets() -> tuple[trimesh.Trimesh, NDArray[np.float64]]:
    """The demo part (mm) and the torch approach direction ``(15, 3)`` of each joint.

    A joint's direction is the mean front normal of the flange strips it lies on (the side the
    torch comes from), rounded to 4 decimals as it is written to the CSV.
    """
    J = TABLE1_XYZ
    inside = np.array([0.0, -1.0, 0.0])  # the lap flanges of joints 1-6 look towards -y
    parts: list[trimesh.Trimesh] = []
    normal_sum = np.zeros_like(J)

    def add(ids: list[int], **kw: object) -> None:
        boxes, normals = flange(J[ids], **kw)  # type: ignore[arg-type]
        parts.extend(boxes)
        for k, n in enumerate(normals):
            normal_sum[ids[k]] += n
            normal_sum[ids[k + 1]] += n

    # outer flange of the lower lap: joints 3-2-1, with its panel leaving the top edge backwards
    add(
        [2, 1, 0],
        sweep=_Z,
        front=inside,
        down=8.0,
        up=14.0,
        thickness=2.0,
        extend=40.0,
        web=60.0,
        web_at="up",
    )
    # inner sheet of the lap: joints 6-5-4, 2.75 mm behind the outer flange's face, panel below
    add(
        [5, 4, 3],
        sweep=_Z,
        front=inside,
        down=14.0,
        up=10.0,
        thickness=1.5,
        extend=40.0,
        web=60.0,
        web_at="down",
    )
    # upper rail flange: joints 12-11-10-9-8 facing the lap (+y), its panel leaving the top edge
    add(
        [11, 10, 9, 8],
        sweep=_Z,
        front=-inside,
        down=10.0,
        up=16.0,
        thickness=2.0,
        extend=(30.0, 0.0),
        web=50.0,
        web_at="up",
    )
    # its last strip (joints 9-8) has no panel above, so joint 7 stays open to the lap rows
    add([8, 7], sweep=_Z, front=-inside, down=4.0, up=16.0, thickness=2.0, extend=0.0)
    # a tab welded to the end of the rail carries joint 7, its face turned towards the lap rows
    look = _unit(J[:6].mean(axis=0) - J[6])
    parts.append(tab(J[6], normal=look, size=TAB, thickness=2.0))
    normal_sum[6] += look
    # roof flange bent at joint 13: riser 14-13 and arm 13-15, both facing into the bend
    add([13, 12], sweep=_X, front=-inside, down=10.0, up=10.0, thickness=1.5, extend=(5.0, 0.0))
    add([12, 14], sweep=_X, front=-_Z, down=10.0, up=10.0, thickness=1.5, extend=(0.0, 10.0))
    # stiffener bracket across the line 3 -> 7
    parts.append(
        bracket(
            J[2],
            J[6],
            across=_X,
            width=BRACKET[0],
            height=BRACKET[1],
            thickness=2.0,
            offset=BRACKET[2],
        )
    )
    mesh = trimesh.util.concatenate(parts)
    directions = np.round(normal_sum / np.linalg.norm(normal_sum, axis=1, keepdims=True), 4)
    return mesh, directions


def demo_part() -> trimesh.Trimesh:
    """The demo part (mm): flanges through Table 1's seams plus the blocking bracket."""
    return demo_assets()[0]


def demo_joints_csv() -> str:
    """Text of ``assets/demo/joints.csv``: Table 1 with the approach directions."""
    _, directions = demo_assets()
    lines = [
        "# The 15 weld joints of Wang et al. 2017, Table 1 (mm), with torch approach directions",
        "# (nx,ny,nz: front normals of the demo part's flanges). Generated by",
        "# python -m weldplan.weld.demo_part",
        "id,x,y,z,nx,ny,nz",
    ]
    for k, (p, d) in enumerate(zip(TABLE1_XYZ, directions, strict=True)):
        lines.append(f"{k + 1},{p[0]:.2f},{p[1]:.2f},{p[2]:.2f},{d[0]:.4f},{d[1]:.4f},{d[2]:.4f}")
    return "\n".join(lines) + "\n"


def write_demo_assets(folder: str | Path = DEMO_DIR) -> tuple[Path, Path]:
    """Generate the demo part (binary STL) and joints CSV into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    part, joints = folder / DEMO_PART.name, folder / DEMO_JOINTS.name
    demo_part().export(str(part), file_type="stl")
    joints.write_text(demo_joints_csv(), encoding="utf-8")
    return part, joints


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="regenerate the demo part and joints")
    parser.add_argument("--out", default=str(DEMO_DIR), help="folder to write into")
    args = parser.parse_args(argv)
    for path in write_demo_assets(args.out):
        log.info("wrote %s", path)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
