"""A plan as a saved, re-loadable, re-checkable result: :func:`save_plan`, :func:`load_plan`.

The route JSON is the plan's saved form (docs/outputs.md): the point-tip route and, in its
``tool`` section (:class:`~weldplan.robot.program.ToolRoute`), the weld poses, the tool path
and the robot route. :func:`save_plan` writes it with its measured times beside it
(``route.timings.json``, :func:`weldplan.io.timings.route_json_texts`) as one set, whole or not
at all (:func:`weldplan.io.outputset.write_outputs`, as :func:`~weldplan.station.outputs.write_plan`
does). :func:`load_plan` reads it back into a frozen :class:`SavedPlan` holding the same objects
typed; saving that again gives the same bytes. :meth:`SavedPlan.verify` re-checks it
(:func:`weldplan.station.recheck.recheck`), which is what ``weldplan verify`` runs::

    plan = weldplan.plan(station, rng=0)
    plan.save("route.json")
    saved = weldplan.load_plan("route.json", mesh="part.stl")
    saved.verify(tool=plan.tool).ok
"""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

from weldplan.robot.program.toolroute import ToolRoute


def save_route(route: Any, path: str | PathLike[str]) -> Path:
    """Write ``route`` (a :class:`~weldplan.weld.route.Route`) to the route JSON ``path`` and
    its measured times to ``route.timings.json`` beside it, both or neither.

    Raises
    ------
    InputError
        When ``path`` cannot be written (its folder missing, a folder in its place...), before
        anything is written.
    """
    from weldplan.io.outputset import check_outputs, write_outputs
    from weldplan.io.timings import route_json_texts, timings_path

    path = Path(path)
    paths = {"json": path, "timings": timings_path(path)}
    check_outputs(paths)
    text, timings = route_json_texts(route)
    write_outputs({paths["json"]: text, paths["timings"]: timings})
    return path


@dataclass(frozen=True, eq=False)
class SavedPlan:
    """A plan read back from its route JSON (:func:`load_plan`).

    Attributes
    ----------
    path
        The route JSON.
    route
        The :class:`~weldplan.weld.route.Route` (the point-tip route, in the frame it was planned
        in: the cell frame with a part pose).
    tool_route
        The :class:`~weldplan.robot.program.ToolRoute`: weld poses, tool path, robot route
        (all None for a point-tip route).
    part
        The part mesh (trimesh, mm) in the route's frame; None when none was given.
    joints
        The :class:`~weldplan.io.joints.Joints` the route must visit (None: not checked).
    part_pose
        The :class:`~weldplan.cellframe.PartPose` the route was planned with (None: the part
        frame).
    """

    path: Path
    route: Any
    tool_route: ToolRoute
    part: Any = None
    joints: Any = None
    part_pose: Any = None

    @property
    def poses(self) -> Any:
        """The :class:`~weldplan.tool.poses.WeldPoses` (None without a tool)."""
        return self.tool_route.poses

    @property
    def tool_path(self) -> Any:
        """The :class:`~weldplan.tool.transitions.ToolPath` (None without transitions)."""
        return self.tool_route.transitions

    @property
    def robot_route(self) -> Any:
        """The :class:`~weldplan.robot.route.RobotRoute` (None without a robot)."""
        return None if self.tool_route.robot is None else self.tool_route.robot.route

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the plan back (:func:`save_route`), the route carrying :attr:`tool_route`."""
        return save_route(self.tool_route.on(self.route), path)

    def verify(self, *, tool: Any = None, robot: Any = None, clearance: float | None = None) -> Any:
        """Re-check the saved plan against :attr:`part`
        (:func:`weldplan.station.recheck.recheck`; ``tool``: ``(Tool, provenance)`` or a
        :class:`~weldplan.station.mount.MountedTool`, ``robot``: a Robot or
        :class:`~weldplan.station.recheck.RobotFiles`).

        Returns
        -------
        :class:`~weldplan.station.recheck.Verdict`
        """
        from weldplan.errors import InputError
        from weldplan.station.recheck import recheck

        if self.part is None:
            raise InputError("no part to check the plan against: load_plan(path, mesh=...)")
        return recheck(
            self.route, self.part, tool=tool, robot=robot, joints=self.joints,
            clearance=clearance, part_pose=_pose_check(self.part_pose), path=self.path,
        )  # fmt: skip


@dataclass(frozen=True)
class PartFiles:
    """How to read the part and the welds of a saved plan (as ``weldplan plan`` read them).

    ``units``, ``scale``, ``length``: :func:`weldplan.io.mesh.load_part`; ``joints``: the joints
    CSV the route must visit exactly (None: not checked); ``part_pose``: the
    :class:`~weldplan.cellframe.PartPose` given again (None: the route's own).
    """

    units: str = "mm"
    scale: float | None = None
    length: float | None = None
    joints: str | PathLike[str] | None = None
    part_pose: Any = None


def load_plan(
    path: str | PathLike[str],
    *,
    mesh: str | PathLike[str] | None = None,
    part: PartFiles | None = None,
) -> SavedPlan:
    """Read the route JSON ``path`` (and the part ``mesh``, placed by the route's part pose;
    ``part``: how to read it, :class:`PartFiles`).

    Raises
    ------
    InputError
        The file is not a route JSON (naming it, and the line of a JSON error), its tool section
        is not readable (naming the field), the mesh or the joints cannot be read, or the part
        pose given differs from the route's.
    """
    from weldplan.cellframe import recorded_pose
    from weldplan.errors import InputError
    from weldplan.io.export import read_route

    part = part or PartFiles()
    route = read_route(path)
    try:
        tool_route = ToolRoute.of(route)
    except (KeyError, TypeError, ValueError) as exc:
        why = f"missing field {exc}" if isinstance(exc, KeyError) else str(exc)
        raise InputError(f"the tool section is not valid: {why}", path=path, field="tool") from None
    if mesh is None:
        return SavedPlan(Path(path), route, tool_route)
    from weldplan.io.mesh import load_part

    mesh_part = load_part(mesh, units=part.units, scale=part.scale, length=part.length)
    pose = recorded_pose(route.provenance, part.part_pose, mesh_part, path=path)
    joints = None
    if part.joints is not None:
        from weldplan.io.joints import read_joints

        joints = read_joints(part.joints, units=part.units)
    if pose is not None:  # re-applied from the route: the checks run in its cell frame
        mesh_part = pose.mesh_to_cell(mesh_part)
        joints = None if joints is None else pose.joints_to_cell(joints)
    return SavedPlan(Path(path), route, tool_route, mesh_part, joints, pose)


def _pose_check(pose: Any) -> Any:
    from weldplan.station.recheck import CheckResult

    text = "planned in the part frame" if pose is None else pose.describe()
    return CheckResult("part pose", True, text)
