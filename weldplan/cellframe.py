"""The cell frame: where the part stands in the welding cell (DESIGN.md, "Frames").

The part frame is where the mesh and the weld joints are given; the *cell frame* is z up, with
the floor at a known height, and is where robots stand. A :class:`PartPose` is the rigid
transform part frame -> cell frame (``(4, 4)``, mm), with the floor and the fixture:

* from an up axis (:meth:`PartPose.from_up`): the rotation that turns the part's ``x``, ``y``,
  ``z``, ``-x``, ``-y`` or ``-z`` axis to the cell's ``+z``. For ``y`` it is the rule of
  ``../shared/data/README.md`` for car2.obj, ``(x, y, z) -> (x, -z, y)`` (a quarter turn about
  x); ``-y`` and ``-z`` turn about x too, ``x`` and ``-x`` about y (the axis not involved stays
  horizontal); ``z`` is the identity;
* from ``x, y, z, rx, ry, rz`` (mm, degrees; :meth:`PartPose.from_xyzrpy`): fixed-axis rotations
  about the cell's x, then y, then z, ``R = Rz(rz) @ Ry(ry) @ Rx(rx)`` (URDF's ``rpy``; KUKA's
  ``A, B, C`` are ``rz, ry, rx`` of the same matrix), then the translation;
* from a ``(4, 4)`` matrix or a text file of 4 rows of 4 numbers (:meth:`PartPose.from_file`).

The fixture: with ``fixture_z`` the part is lifted (or lowered) along the cell's z so that its
lowest point lies ``fixture_z`` mm above the floor (:meth:`PartPose.placed`, on the part's
vertices); without it the matrix's own z stands. ``from_up`` defaults to ``fixture_z = 0`` (the
part on the floor, as car2 on its fixture posts). The floor is at ``floor_z`` in the cell
(default 0).

Every check is an :class:`~weldplan.errors.InputError` of one line naming the option or key:
NaN or infinite numbers, a matrix that is not ``(4, 4)``, whose last row is not ``0, 0, 0, 1``,
or whose rotation is not one (``R^T R = I`` and ``det R = +1`` within :data:`ROTATION_TOL`: a
mirror, a scale or a shear would turn the part inside out or resize it).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.io.joints import Joints

#: largest deviation of ``R^T R`` from the identity, and of ``det R`` from 1, accepted
ROTATION_TOL = 1e-6
#: two part poses agree (:meth:`PartPose.same_as`) within this, mm and rad (entries of R)
MATCH_TOL = 1e-6

_QUARTER = {  # the up axis -> the rotation turning it to the cell's +z (module docstring)
    "z": np.eye(3),
    "-z": np.diag([1.0, -1.0, -1.0]),
    "y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),
    "-y": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),
    "x": np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]),
    "-x": np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]),
}
#: the up axes :meth:`PartPose.from_up` takes
UP_AXES = tuple(_QUARTER)


def check_transform(matrix: Any, *, field: str, path: str | None = None) -> NDArray[np.float64]:
    """``matrix`` as a ``(4, 4) float`` rigid transform (module docstring), else InputError
    naming ``field`` (and ``path``)."""
    try:
        M = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError("must be a 4x4 matrix of numbers", path=path, field=field) from None
    if M.shape != (4, 4):
        raise InputError(f"must be a 4x4 matrix, got shape {M.shape}", path=path, field=field)
    if not np.all(np.isfinite(M)):
        raise InputError("has a NaN or infinite entry", path=path, field=field)
    if not np.allclose(M[3], [0.0, 0.0, 0.0, 1.0], atol=1e-12, rtol=0.0):
        raise InputError(f"last row must be 0 0 0 1, got {M[3].tolist()}", path=path, field=field)
    R = M[:3, :3]
    ortho = float(np.abs(R.T @ R - np.eye(3)).max())
    det = float(np.linalg.det(R))
    if ortho > ROTATION_TOL or abs(det - 1.0) > ROTATION_TOL:
        raise InputError(
            f"the 3x3 block is not a rotation (|R^T R - I| = {ortho:.3g}, det {det:.6g}; a "
            "mirror, scale or shear is not a pose)",
            path=path,
            field=field,
        )
    return M


def _finite(value: Any, field: str, *, minimum: float | None = None) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not math.isfinite(v) or (minimum is not None and v < minimum):
        bound = "" if minimum is None else f" >= {minimum:g}"
        raise InputError(f"must be a finite number{bound} of mm, got {value!r}", field=field)
    return v


@dataclass(frozen=True, eq=False)
class PartPose:
    """The part's pose in the cell (module docstring).

    Attributes
    ----------
    matrix
        ``(4, 4) float``: part frame -> cell frame, mm (a rigid transform).
    floor_z
        mm: the floor's height in the cell frame (default 0).
    fixture_z
        mm above the floor of the part's lowest point (:meth:`placed` sets the matrix's z from
        it); ``None``: the matrix's z stands.
    given
        How the pose was given, for messages and the route JSON (``"--up y"``, ...).
    """

    matrix: NDArray[np.float64]
    floor_z: float = 0.0
    fixture_z: float | None = None
    given: str = "matrix"

    def __post_init__(self) -> None:
        M = check_transform(self.matrix, field="part_pose")
        M.setflags(write=False)
        object.__setattr__(self, "matrix", M)
        object.__setattr__(self, "floor_z", _finite(self.floor_z, "floor_z"))
        if self.fixture_z is not None:
            object.__setattr__(self, "fixture_z", _finite(self.fixture_z, "fixture_z"))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_up(cls, axis: str, *, fixture_z: float | None = 0.0, floor_z: float = 0.0) -> PartPose:
        """The pose turning the part's ``axis`` (:data:`UP_AXES`) to the cell's +z, its lowest
        point ``fixture_z`` mm above the floor (default 0: on the floor)."""
        key = str(axis).strip().lower().replace("+", "")
        if key not in _QUARTER:
            raise InputError(
                f"unknown up axis {axis!r}; use one of {', '.join(UP_AXES)}", field="up"
            )
        M = np.eye(4)
        M[:3, :3] = _QUARTER[key]
        return cls(M, floor_z=floor_z, fixture_z=fixture_z, given=f"up {key}")

    @classmethod
    def from_xyzrpy(
        cls, values: ArrayLike, *, fixture_z: float | None = None, floor_z: float = 0.0
    ) -> PartPose:
        """``x, y, z`` mm and ``rx, ry, rz`` degrees, ``R = Rz(rz) @ Ry(ry) @ Rx(rx)``."""
        from scipy.spatial.transform import Rotation

        try:
            v = np.array(values, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            v = np.full(0, np.nan)
        if v.shape != (6,) or not np.all(np.isfinite(v)):
            raise InputError(
                f"need six finite numbers x,y,z,rx,ry,rz (mm, deg), got {values!r}",
                field="part_pose",
            )
        M = np.eye(4)
        M[:3, :3] = Rotation.from_euler("xyz", v[3:], degrees=True).as_matrix()
        M[:3, 3] = v[:3]
        text = ",".join(f"{x:g}" for x in v)
        return cls(M, floor_z=floor_z, fixture_z=fixture_z, given=f"x,y,z,rx,ry,rz {text}")

    @classmethod
    def from_file(
        cls,
        path: str | PathLike[str],
        *,
        fixture_z: float | None = None,
        floor_z: float = 0.0,
    ) -> PartPose:
        """A ``(4, 4)`` matrix from a text file: 4 rows of 4 numbers (spaces or commas; blank
        and ``#`` lines skipped), translation in mm. InputError naming the file and line."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"cannot read the part pose: {exc}", path=path) from None
        rows = []
        for n, line in enumerate(text.splitlines(), start=1):
            s = line.split("#", 1)[0].replace(",", " ").split()
            if not s:
                continue
            try:
                vals = [float(x) for x in s]
            except ValueError:
                raise InputError(f"not numbers: {line.strip()!r}", path=path, line=n) from None
            if len(vals) != 4 or not all(math.isfinite(x) for x in vals):
                raise InputError(
                    f"need 4 finite numbers a row, got {line.strip()!r}", path=path, line=n
                )
            rows.append(vals)
        if len(rows) != 4:
            raise InputError(f"need 4 rows of 4 numbers, got {len(rows)} rows", path=path)
        M = check_transform(rows, field="part_pose", path=str(path))
        return cls(M, floor_z=floor_z, fixture_z=fixture_z, given=f"matrix {path}")

    # ------------------------------------------------------------------ placement
    def placed(self, points: ArrayLike) -> PartPose:
        """This pose with the matrix's z set so that the lowest of ``points`` (``(n, 3)`` mm,
        part frame: the mesh's vertices) lies ``fixture_z`` above the floor; itself without a
        fixture height."""
        if self.fixture_z is None:
            return self
        z = (np.asarray(points, dtype=np.float64).reshape(-1, 3) @ self.matrix[2, :3]).min()
        M = self.matrix.copy()
        M[2, 3] = self.floor_z + self.fixture_z - float(z)
        return dataclasses.replace(self, matrix=M)

    @property
    def rotation(self) -> NDArray[np.float64]:
        """``(3, 3)``: the part's axes in the cell frame."""
        return self.matrix[:3, :3]

    def to_cell(self, points: ArrayLike) -> NDArray[np.float64]:
        """``(n, 3)`` mm: part-frame points in the cell frame."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return p @ self.rotation.T + self.matrix[:3, 3]

    def to_part(self, points: ArrayLike) -> NDArray[np.float64]:
        """``(n, 3)`` mm: cell-frame points in the part frame (the inverse of :meth:`to_cell`)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return (p - self.matrix[:3, 3]) @ self.rotation

    def mesh_to_cell(self, mesh: trimesh.Trimesh) -> trimesh.Trimesh:
        """A copy of ``mesh`` (part frame) in the cell frame; its ``metadata["weldplan"]`` (the
        loader's provenance) is kept and gains ``part_pose`` (:meth:`to_dict`)."""
        out = trimesh.Trimesh(
            vertices=self.to_cell(mesh.vertices),
            faces=np.asarray(mesh.faces).copy(),
            process=False,
        )
        meta = dict(mesh.metadata.get("weldplan") or {})
        meta["part_pose"] = self.to_dict()
        out.metadata["weldplan"] = meta
        return out

    def joints_to_cell(self, joints: Joints) -> Joints:
        """``joints`` (part frame) in the cell frame: positions moved, approach directions
        turned; ids, source file and lines kept (errors still name them)."""
        d = None if joints.directions is None else joints.directions @ self.rotation.T
        return dataclasses.replace(joints, xyz=self.to_cell(joints.xyz), directions=d)

    def joints_to_part(self, joints: Joints) -> Joints:
        """The inverse of :meth:`joints_to_cell`."""
        d = None if joints.directions is None else joints.directions @ self.rotation
        return dataclasses.replace(joints, xyz=self.to_part(joints.xyz), directions=d)

    # ------------------------------------------------------------------ records
    def to_dict(self) -> dict[str, Any]:
        """Plain data for the route JSON (read back by :meth:`from_dict`, exactly)."""
        return {
            "matrix": [[float(v) for v in row] for row in self.matrix],
            "floor_z": self.floor_z,
            "fixture_z": self.fixture_z,
            "given": self.given,
        }

    @classmethod
    def from_dict(cls, d: Any, *, path: str | PathLike[str] | None = None) -> PartPose:
        """The pose a route JSON records (:meth:`to_dict`); InputError naming the key."""
        if not isinstance(d, dict) or "matrix" not in d:
            raise InputError("part_pose must be an object with a 'matrix'", path=path)
        M = check_transform(d["matrix"], field="part_pose.matrix", path=_str(path))
        try:
            return cls(
                M,
                floor_z=d.get("floor_z", 0.0),
                fixture_z=d.get("fixture_z"),
                given=str(d.get("given", "matrix")),
            )
        except InputError as exc:
            raise InputError(exc.message, path=path, field=f"part_pose.{exc.field}") from None

    def same_as(self, other: PartPose, tol: float = MATCH_TOL) -> bool:
        """Whether two poses place the part alike (matrices within ``tol`` mm / rad, the same
        floor)."""
        return bool(
            np.abs(self.matrix - other.matrix).max() <= tol
            and abs(self.floor_z - other.floor_z) <= tol
        )

    def describe(self) -> str:
        """One line: how it was given, the translation, the floor and the fixture."""
        t = ", ".join(f"{v:.1f}" for v in self.matrix[:3, 3])
        fix = "" if self.fixture_z is None else f", lowest point {self.fixture_z:g} mm above it"
        return f"part pose {self.given}: translation ({t}) mm, floor z {self.floor_z:g} mm{fix}"


def _str(path: str | PathLike[str] | None) -> str | None:
    return None if path is None else str(path)


def parse_part_pose(text: str, *, fixture_z: float | None = None, floor_z: float = 0.0) -> PartPose:
    """``--part-pose``: six numbers ``x,y,z,rx,ry,rz`` (mm, deg) or the path of a 4x4 file
    (:meth:`PartPose.from_file`); InputError naming the option."""
    parts = text.replace(";", ",").split(",")
    if len(parts) == 6:
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            raise InputError(
                f"not six numbers x,y,z,rx,ry,rz: {text!r}", field="--part-pose"
            ) from None
        try:
            return PartPose.from_xyzrpy(vals, fixture_z=fixture_z, floor_z=floor_z)
        except InputError as exc:
            raise InputError(exc.message, field="--part-pose") from None
    if not Path(text).is_file():
        raise InputError(
            f"neither six numbers x,y,z,rx,ry,rz (mm, deg) nor a 4x4 matrix file: {text!r}",
            field="--part-pose",
        )
    return PartPose.from_file(text, fixture_z=fixture_z, floor_z=floor_z)


def place_part(
    part: trimesh.Trimesh, joints: Joints | None, pose: PartPose
) -> tuple[trimesh.Trimesh, Joints | None, PartPose]:
    """The part and its joints (part frame) in the cell frame, and the pose as applied (its
    fixture height resolved on the part's vertices: :meth:`PartPose.placed`)."""
    placed = pose.placed(part.vertices)
    moved = None if joints is None else placed.joints_to_cell(joints)
    return placed.mesh_to_cell(part), moved, placed


def recorded_pose(
    provenance: dict[str, Any],
    given: PartPose | None,
    part: trimesh.Trimesh,
    *,
    path: str | PathLike[str] | None = None,
) -> PartPose | None:
    """The part pose a route was planned with (its provenance's ``part_pose``), checked
    against the one given again (``given``, placed on ``part`` in the part frame, on the
    route's floor); InputError when they differ, or when only ``given`` exists. ``None``:
    planned in the part frame."""
    rec = provenance.get("part_pose")
    pose = None if rec is None else PartPose.from_dict(rec, path=path)
    if given is None:
        return pose
    if pose is None:
        raise InputError(
            f"the route was planned in the part frame (no part pose), not with {given.given}: "
            "leave out --up/--part-pose/--fixture-z",
            path=path,
        )
    now = dataclasses.replace(given, floor_z=pose.floor_z).placed(part.vertices)
    if not now.same_as(pose):
        raise InputError(
            f"the route was planned with {pose.describe()}; the options give "
            f"{now.describe()}: give the planning run's pose or none (the route's own)",
            path=path,
            field="part_pose",
        )
    return pose
