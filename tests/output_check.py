"""An independent check of the poses a run writes: python-fcl on the meshes, nothing else.

Shares no code with weldplan's checkers (tool/verify_*, tool/transitions/sweep*,
robot/collision/checker): the tool's triangles are placed here from the file's position and
quaternion, the part is one BVH of the whole mesh, and a pose is *inside the part* when any tool
triangle that is not wholly inside the contact zone (the sphere of the contact radius about a weld
spot, where the tool touches the sheet by design) collides with the part (``fcl.collide``; touching
counts).
"""

from __future__ import annotations

import csv
from pathlib import Path

import fcl
import numpy as np
from scipy.spatial.transform import Rotation


def _bvh(vertices: np.ndarray, faces: np.ndarray) -> fcl.BVHModel:
    m = fcl.BVHModel()
    m.beginModel(len(vertices), len(faces))
    m.addSubModel(np.asarray(vertices, np.float64), np.asarray(faces, np.int32))
    m.endModel()
    return m


class InsideCheck:
    """``count(poses)``: how many TCP poses ``(k, 4, 4)`` (part frame, mm) put the tool inside
    the part (module docstring)."""

    def __init__(self, part_vertices, part_faces, tool_vertices, tool_faces, spots, radius):
        self.part = fcl.CollisionObject(_bvh(part_vertices, part_faces), fcl.Transform())
        self.tv = np.asarray(tool_vertices, np.float64)
        self.tf = np.asarray(tool_faces, np.int64)
        self.spots = np.asarray(spots, np.float64).reshape(-1, 3)
        self.radius = float(radius)
        self.whole = _bvh(self.tv, self.tf)  # built once: most poses touch nothing at all

    def _collide(self, tool: fcl.CollisionObject) -> bool:
        return bool(fcl.collide(tool, self.part, fcl.CollisionRequest(), fcl.CollisionResult()))

    def inside(self, T: np.ndarray) -> bool:
        if not self._collide(fcl.CollisionObject(self.whole, fcl.Transform(T[:3, :3], T[:3, 3]))):
            return False
        v = self.tv @ T[:3, :3].T + T[:3, 3]
        d = np.linalg.norm(v[:, None, :] - self.spots[None], axis=2)  # (n, welds)
        tri = d[self.tf]  # (m, 3, welds): a triangle is exempt if one zone holds all three
        keep = ~np.any(np.all(tri < self.radius, axis=1), axis=1)
        if not keep.any():
            return False
        return self._collide(fcl.CollisionObject(_bvh(v, self.tf[keep]), fcl.Transform()))

    def count(self, poses: np.ndarray) -> list[int]:
        """The indices of the poses inside the part."""
        return [k for k, T in enumerate(poses) if self.inside(T)]


def csv_poses(path: Path) -> tuple[np.ndarray, list[int]]:
    """The TCP poses ``(k, 4, 4)`` of the rows of a route or tool CSV that carry one (x, y, z
    and a quaternion ``qw..qz``), and their row numbers; ``#`` lines skipped."""
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    poses, rows = [], []
    for k, r in enumerate(csv.DictReader(lines)):
        if not r.get("qw") or not r.get("x"):
            continue
        T = np.eye(4)
        q = [float(r[c]) for c in ("qx", "qy", "qz", "qw")]
        T[:3, :3] = Rotation.from_quat(q).as_matrix()
        T[:3, 3] = [float(r[c]) for c in ("x", "y", "z")]
        poses.append(T)
        rows.append(k)
    return np.array(poses).reshape(-1, 4, 4), rows


def csv_rows(path: Path) -> list[dict[str, str]]:
    """The rows of a CSV weldplan wrote, by column name (its ``#`` comment lines skipped)."""
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def comments(text: str, mark: str = "#") -> list[str]:
    """The comment lines of a file's text (``mark``: ``#`` CSV, ``!`` RAPID, ``;`` KRL), without
    the mark and the indent."""
    return [
        ln.strip()[len(mark) :].strip() for ln in text.splitlines() if ln.strip().startswith(mark)
    ]


def trajectory_q(path: Path) -> np.ndarray:
    """``(m, d)`` rad: the joint rows of a trajectory CSV (``#`` lines skipped)."""
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(lines))[1:]
    return np.array([[float(v) for v in r[2:]] for r in rows])


def trajectory_t(path: Path) -> np.ndarray:
    """``(m,)`` s: the ``t`` column of a trajectory CSV."""
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    return np.array([float(r[0]) for r in list(csv.reader(lines))[1:]])
