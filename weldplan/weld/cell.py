"""The welding cell: part, joints, obstacle grid, collision model and virtual weld joints.

This is section 3 of Wang et al. 2017 (3D environment modelling) put together:

1. the part is a triangle mesh (mm);
2. a voxel grid of 5 mm cubes covers the region of interest; a cube centre is an obstacle when
   the part is closer than the clearance (:func:`weldplan.geometry.grid.build_grid`);
3. the other centres are free: the torch tip may stand there;
4. each weld joint lies on the surface, hence on an obstacle centre: its *virtual weld joint* is
   the nearest free centre, and planning runs between virtual joints; the offset (joint to virtual
   joint) is recorded. A joint with no free centre within ``search_radius`` is an error naming it.

The python-fcl :class:`~weldplan.geometry.collision.CollisionModel` is the judge every route
passes before it leaves weldplan.

Input checks at this boundary (each an :class:`~weldplan.errors.InputError`, a ValueError):
``pitch`` and ``clearance`` positive and finite, ``margin`` finite and >= 0; every joint within
``max_joint_distance`` of the part's surface (default :func:`default_max_joint_distance`): a
joint 10 m away, a joints CSV in metres beside a mesh in mm, or a wrong ``scale`` is named with
its distance instead of planning a station that is not the one meant. Two joints at the same
coordinates are a warning (logged, and counted in :meth:`Cell.summary`), as are the degenerate
faces the loader removed.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Unpack

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.cellframe import PartPose, place_part
from weldplan.errors import InputError
from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.grid import ObstacleGrid, build_grid
from weldplan.geometry.solids import ClosedSolids
from weldplan.io.joints import COINCIDENT_MM, Joints, coincident_joints, read_joints
from weldplan.io.mesh import geometry_hash, load_part
from weldplan.options import laid_over
from weldplan.weld.cellsettings import (  # noqa: F401 - their home was this module
    JOINT_DISTANCE_MIN_MM,
    CellBuildOptions,
    CellBuildSettings,
    default_max_joint_distance,
)
from weldplan.weld.virtual import (  # noqa: F401 - virtual_joints' home was this module
    _SEARCH_FACTOR,
    APPROACH_CONE_DEG,
    APPROACH_TRIES,
    virtual_joints,
)

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class Cell:
    """Everything the planners need about one welding station.

    Attributes
    ----------
    part
        The part mesh (mm).
    joints
        The weld joints (mm).
    grid
        The obstacle grid over the region of interest.
    collision
        The python-fcl collision judge of the part.
    virtual_index
        ``(n, 3) int64``: grid index of each joint's virtual weld joint (a free voxel).
    virtual_xyz
        ``(n, 3) float``: world position (mm) of each virtual weld joint (a voxel centre).
    offsets
        ``(n,) float``: distance (mm) from each joint to its virtual joint.
    clearance
        Torch-tip clearance (mm) used by the grid and the collision checks.
    pitch
        Voxel side (mm).
    diagnostics
        What the input checks found and let pass: ``repairs`` (faces the loader removed),
        ``coincident_joints`` (pairs of joint ids closer than ``COINCIDENT_MM``),
        ``closed_solids`` (closed components of the part), ``joint_distance_max_mm`` (the
        farthest joint from the surface) and ``max_joint_distance_mm`` (the limit it passed).
    part_pose
        The part's pose in the cell (:class:`~weldplan.cellframe.PartPose`, its fixture height
        resolved): ``part``, ``joints`` and everything planned are then in the cell frame;
        ``None``: in the part frame (the part frame is taken as the cell's).
    spot_depth
        mm below the surface the weld spots lie along their approach (a spot on the faying
        surface of a sheet stack); the approach cone starts that far out
        (:func:`weldplan.weld.verify.approach_pieces`). 0: spots on the surface.
    """

    part: trimesh.Trimesh
    joints: Joints
    grid: ObstacleGrid
    collision: CollisionModel
    virtual_index: NDArray[np.int64]
    virtual_xyz: NDArray[np.float64]
    offsets: NDArray[np.float64]
    clearance: float
    pitch: float
    diagnostics: dict[str, Any] = field(default_factory=dict)
    part_pose: PartPose | None = None
    spot_depth: float = 0.0

    def __post_init__(self) -> None:
        for name, dtype in (
            ("virtual_index", np.int64),
            ("virtual_xyz", np.float64),
            ("offsets", np.float64),
        ):
            arr = np.array(getattr(self, name), dtype=dtype)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def frame(self) -> str:
        """``"cell"`` when the part was placed by a :attr:`part_pose`, else ``"part"``: the
        frame of every coordinate planned on this cell."""
        return "part" if self.part_pose is None else "cell"

    @property
    def provenance(self) -> dict[str, Any]:
        """Where the cell came from, for the route JSON (``Route.provenance``): the geometry
        hash of the part in mm (in :attr:`frame`), the mesh file and its sha256, the units and
        scale applied when loading (None for a mesh built in memory), the faces the loader
        removed, the clearance and the pitch; the frame of the route's coordinates and the part
        pose (:meth:`~weldplan.cellframe.PartPose.to_dict`, ``None`` in the part frame)."""
        meta = dict(self.part.metadata.get("weldplan") or {})
        return {
            "frame": self.frame,
            "part_pose": None if self.part_pose is None else self.part_pose.to_dict(),
            "mesh": {
                "geometry_sha256": geometry_hash(self.part),
                "file": meta.get("file"),
                "file_sha256": meta.get("file_sha256"),
                "units": meta.get("units"),
                "scale": meta.get("scale"),
                "repairs": meta.get("repairs", {"degenerate_faces": 0, "duplicate_faces": 0}),
            },
            "joints": {
                "source": None if self.joints.source is None else str(self.joints.source),
                "coincident": len(self.diagnostics.get("coincident_joints", ())),
            },
            "clearance": self.clearance,
            "pitch": self.pitch,
        }

    def summary(self) -> dict[str, Any]:
        """Plain-data description: part bounds, joints, grid size, free/obstacle counts, offsets."""
        g = self.grid
        return {
            "part": {
                "vertices": int(len(self.part.vertices)),
                "faces": int(len(self.part.faces)),
                "bounds_mm": np.round(self.part.bounds, 3).tolist(),
                "extents_mm": np.round(self.part.extents, 3).tolist(),
            },
            "joints": {
                "count": self.n_joints,
                "ids": list(self.joints.ids),
                "source": None if self.joints.source is None else str(self.joints.source),
            },
            "grid": {
                "shape": list(g.shape),
                "voxels": int(np.prod(g.shape)),
                "pitch_mm": g.pitch,
                "clearance_mm": g.clearance,
                "bounds_mm": np.round(g.bounds, 3).tolist(),
                "free": g.n_free,
                "obstacle": g.n_obstacle,
            },
            "checks": {
                "faces_removed": dict(
                    self.diagnostics.get("repairs")
                    or (self.part.metadata.get("weldplan") or {}).get("repairs")
                    or {"degenerate_faces": 0, "duplicate_faces": 0}
                ),
                "coincident_joints": [
                    list(p) for p in self.diagnostics.get("coincident_joints", ())
                ],
                "closed_solids": int(self.diagnostics.get("closed_solids", 0)),
                "joint_distance_max_mm": self.diagnostics.get("joint_distance_max_mm"),
                "max_joint_distance_mm": self.diagnostics.get("max_joint_distance_mm"),
            },
            "virtual_joints": [
                {
                    "id": jid,
                    "joint_mm": np.round(self.joints.xyz[k], 3).tolist(),
                    "virtual_mm": np.round(self.virtual_xyz[k], 3).tolist(),
                    "offset_mm": round(float(self.offsets[k]), 3),
                }
                for k, jid in enumerate(self.joints.ids)
            ],
        }

    def format_summary(self) -> str:
        """:meth:`summary` as a few lines of text for a terminal."""
        s = self.summary()
        p, g = s["part"], s["grid"]
        lo, hi = (np.asarray(b) for b in p["bounds_mm"])
        lines = [
            f"part: {p['vertices']} vertices, {p['faces']} faces, "
            f"bounds {_fmt(lo)} .. {_fmt(hi)} mm (extents {_fmt(p['extents_mm'])} mm)",
            f"joints: {s['joints']['count']}"
            + (f" from {s['joints']['source']}" if s["joints"]["source"] else ""),
            f"grid: {' x '.join(map(str, g['shape']))} voxels of {g['pitch_mm']:g} mm, "
            f"clearance {g['clearance_mm']:g} mm, {g['free']:,} free / {g['obstacle']:,} obstacle",
        ]
        if self.part_pose is not None:
            lines.append(f"frame: cell (z up); {self.part_pose.describe()}")
        c = s["checks"]
        removed = c["faces_removed"]
        if removed.get("degenerate_faces") or removed.get("duplicate_faces"):
            lines.append(
                f"warning: the loader removed {removed.get('degenerate_faces', 0)} degenerate "
                f"and {removed.get('duplicate_faces', 0)} duplicate faces"
            )
        if c["coincident_joints"]:
            shown = ", ".join("=".join(p) for p in c["coincident_joints"][:5])
            lines.append(
                f"warning: {len(c['coincident_joints'])} pairs of joints at the same "
                f"coordinates: {shown}"
            )
        if c["closed_solids"]:
            lines.append(f"closed solids: {c['closed_solids']} (their interior is obstacle)")
        lines.append("virtual joints (joint -> nearest free voxel centre, offset):")
        for v in s["virtual_joints"]:
            lines.append(
                f"  {v['id']:>4}: {_fmt(v['joint_mm'])} -> {_fmt(v['virtual_mm'])}"
                f"  {v['offset_mm']:6.2f} mm"
            )
        off = self.offsets
        lines.append(f"offsets: min {off.min():.2f}, mean {off.mean():.2f}, max {off.max():.2f} mm")
        return "\n".join(lines)


def _fmt(v: ArrayLike) -> str:
    return "(" + ", ".join(f"{x:.2f}" for x in np.asarray(v, dtype=float)) + ")"


def build_cell(
    part: trimesh.Trimesh,
    joints: Joints,
    settings: CellBuildSettings | None = None,
    *,
    part_pose: PartPose | None = None,
    **options: Unpack[CellBuildOptions],
) -> Cell:
    """Model a welding cell (Wang et al. 2017, section 3).

    Parameters
    ----------
    part
        The part (mm).
    joints
        The weld joints (mm); their approach directions, when given, restrict each virtual
        joint to a cone of ``approach_cone`` degrees around them.
    settings
        :class:`~weldplan.weld.cellsettings.CellBuildSettings`: the grid (pitch, clearance,
        margin, region; see :func:`weldplan.geometry.grid.build_grid`: the interior of the
        part's closed components is obstacle too, :mod:`weldplan.geometry.solids`), the
        virtual joints' search (:func:`virtual_joints`), the largest joint-to-part distance and
        the spots' depth; ``None``: the defaults.
    part_pose
        The part's pose in the cell (:class:`~weldplan.cellframe.PartPose`): ``part`` and
        ``joints`` are given in the part frame and moved into the cell frame (the fixture
        height resolved on the part) before anything else; every stage then plans in the cell
        frame. ``None``: the part frame is the planning frame.
    **options
        Any :class:`~weldplan.weld.cellsettings.CellBuildSettings` field by name (``pitch=2.0``,
        ``clearance=3.0``...), laid over ``settings``; an unknown keyword is a ``TypeError``.

    Returns
    -------
    Cell

    Raises
    ------
    InputError
        A setting is not a finite number in range, or a joint lies farther than
        ``max_joint_distance`` from the part (the message names the joint, its line and the
        distance).
    PlanningError
        A joint has no free voxel centre near it (:func:`virtual_joints`).
    """
    st = laid_over(CellBuildSettings, settings, options, "build_cell")
    pitch, clearance, spot_depth = st.pitch, st.clearance, st.spot_depth
    max_joint_distance = st.joint_distance_limit
    if not isinstance(joints, Joints):
        raise InputError(f"joints must be weldplan Joints, got {type(joints).__name__}")
    if not isinstance(part, trimesh.Trimesh) or len(part.faces) == 0:
        raise InputError("the part must be a trimesh.Trimesh with at least one triangle")
    if part_pose is not None:
        if not isinstance(part_pose, PartPose):
            raise InputError(
                f"part_pose must be a weldplan PartPose, got {type(part_pose).__name__}",
                field="part_pose",
            )
        part, moved, part_pose = place_part(part, joints, part_pose)
        assert moved is not None
        joints = moved
    collision = CollisionModel(part)
    far = check_joint_distances(collision, joints, max_joint_distance)
    pairs = _coincident(joints)
    solids = ClosedSolids.of(part)
    grid = build_grid(
        part,
        pitch=pitch,
        clearance=clearance,
        region=st.region,
        points=joints.xyz,
        margin=st.margin,
        distance=collision.distance,
        solids=solids,
    )
    from weldplan.weld.verify import approach_free

    vidx, vxyz, off = virtual_joints(
        grid,
        joints.xyz,
        ids=joints.ids,
        search_radius=st.search_radius,
        directions=joints.directions,
        approach_cone=st.approach_cone,
        approach_free=lambda p, c: approach_free(collision, p, c, clearance, depth=spot_depth),
    )
    return Cell(
        part=part,
        joints=joints,
        grid=grid,
        collision=collision,
        virtual_index=vidx,
        virtual_xyz=vxyz,
        offsets=off,
        clearance=float(clearance),
        pitch=float(pitch),
        diagnostics=_diagnostics(part, joints, pairs, len(solids), far, max_joint_distance),
        part_pose=part_pose,
        spot_depth=float(spot_depth),
    )


def _diagnostics(
    part: trimesh.Trimesh,
    joints: Joints,
    pairs: list[tuple[int, int]],
    n_solids: int,
    far: float,
    max_joint_distance: float,
) -> dict[str, Any]:
    """:attr:`Cell.diagnostics`: the loader's repairs, coincident joints (by id), closed
    solids, and the largest joint-to-part distance against its limit (mm)."""
    meta = part.metadata.get("weldplan") or {}
    return {
        "repairs": dict(meta.get("repairs") or {"degenerate_faces": 0, "duplicate_faces": 0}),
        "coincident_joints": [(joints.ids[i], joints.ids[j]) for i, j in pairs],
        "closed_solids": n_solids,
        "joint_distance_max_mm": round(far, 6),
        "max_joint_distance_mm": max_joint_distance,
    }


def _coincident(joints: Joints) -> list[tuple[int, int]]:
    """The pairs of joints at the same coordinates (:func:`coincident_joints`), each logged as
    a warning with its lines."""
    pairs = coincident_joints(joints)
    for i, j in pairs:
        log.warning(
            "%s and %s are at the same coordinates %s mm (within %g mm)",
            joints.where(i),
            joints.where(j),
            _fmt(joints.xyz[i]),
            COINCIDENT_MM,
        )
    return pairs


def check_joint_distances(
    collision: CollisionModel, joints: Joints, max_joint_distance: float
) -> float:
    """Largest distance (mm) from a joint to the part; InputError naming the farthest joint
    beyond ``max_joint_distance`` (with its line and distance, and a hint at units and scale)."""
    if len(joints) == 0:
        return 0.0
    d = collision.distance(joints.xyz)
    far = np.flatnonzero(d > max_joint_distance)
    if len(far):
        k = int(far[np.argmax(d[far])])
        raise InputError(
            f"joint {joints.ids[k]!r} at {_fmt(joints.xyz[k])} mm is {d[k]:.1f} mm from the part's "
            f"surface ({len(far)} of {len(joints)} joints farther than {max_joint_distance:g} mm):"
            " are the mesh and the joints in the same units and scale? (check --units, --scale"
            " or --length; --max-joint-distance raises the limit)",
            path=joints.source,
            line=None if joints.lines is None else joints.lines[k],
        )
    return float(d.max())


def load_cell(
    mesh_path: str | PathLike[str],
    joints_path: str | PathLike[str],
    *,
    units: str = "mm",
    scale: float | None = None,
    length: float | None = None,
    joint_units: str | None = None,
    part_pose: PartPose | None = None,
    **kw: Any,
) -> Cell:
    """Load a part and its joints from files and model the cell.

    Parameters
    ----------
    mesh_path, joints_path
        The part mesh (see :func:`weldplan.io.mesh.load_part`) and the joints CSV (see
        :func:`weldplan.io.joints.read_joints`).
    units, scale, length
        Units of the mesh file, and its extra scale or target length (mm).
    joint_units
        Units of the joints CSV (default: ``units``). ``scale``/``length`` do not apply to joints.
    part_pose
        The part's pose in the cell (:class:`~weldplan.cellframe.PartPose`; see
        :func:`build_cell`): the mesh and the joints CSV are in the part frame (the mesh after
        ``units``/``scale``/``length``), the cell is in the cell frame.
    **kw
        Passed to :func:`build_cell`: ``settings`` (a
        :class:`~weldplan.weld.cellsettings.CellBuildSettings`) and any of its fields by name
        (``pitch``, ``clearance``, ``margin``, ``region``, ``search_radius``,
        ``approach_cone``, ``max_joint_distance``, ``spot_depth``).

    Raises
    ------
    InputError
        Bad files, settings, or a joint too far from the part (see :func:`build_cell`).
    """
    for name, value in (("mesh_path", mesh_path), ("joints_path", joints_path)):
        if not isinstance(value, (str, PathLike)):
            raise InputError(
                f"{name} must be a file path (str or os.PathLike), got {type(value).__name__}",
                field=name,
            )
    part = load_part(mesh_path, units=units, scale=scale, length=length)
    joints = read_joints(joints_path, units=joint_units or units)
    return build_cell(part, joints, part_pose=part_pose, **kw)


def demo_cell(**kw: Any) -> Cell:
    """The embedded demo cell: the 15 joints of Wang et al. 2017, Table 1, on the demo part.

    Reads ``assets/demo/part.stl`` and ``assets/demo/joints.csv``; where they are not installed
    (a wheel carries only the package), the same part and joints are generated in memory.
    ``**kw`` go to :func:`build_cell` (``pitch``, ``clearance``, ``margin``, ...).
    """
    from weldplan.weld import demo_part

    if demo_part.DEMO_PART.exists() and demo_part.DEMO_JOINTS.exists():
        return load_cell(demo_part.DEMO_PART, demo_part.DEMO_JOINTS, **kw)
    part, directions = demo_part.demo_assets()
    joints = Joints(
        ids=tuple(str(k + 1) for k in range(len(demo_part.TABLE1_XYZ))),
        xyz=demo_part.TABLE1_XYZ,
        directions=directions,
    )
    return build_cell(part, joints, **kw)
