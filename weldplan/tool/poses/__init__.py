"""One verified collision-free tool pose per weld: candidate orientations, the FCL search, the
least-rotation choice, the exit test, the result, and the route's orientations between welds.

Modules: ``bound``, ``choice``, ``exits``, ``orient``, ``plan``, ``result``, ``route_frames``,
``search``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "Accept": "choice",
    "Candidates": "choice",
    "ChoiceState": "choice",
    "DEFAULT_CONTACT_RADIUS": "plan",
    "ExitTest": "exits",
    "MISS_PROBE_CONTACTS": "search",
    "Miss": "result",
    "NO_FREE_POSE": "result",
    "OK": "result",
    "PoseBound": "bound",
    "PoseSearch": "search",
    "Rechecks": "plan",
    "ToolPieces": "bound",
    "WeldPose": "result",
    "WeldPoses": "result",
    "all_of": "choice",
    "candidate_rotations": "orient",
    "choose": "choice",
    "least_rotation_choice": "orient",
    "leave_distances": "exits",
    "local_candidates": "orient",
    "plan_weld_poses": "plan",
    "probe_positions": "search",
    "quat_wxyz": "result",
    "rotation_angles": "orient",
    "route_poses": "route_frames",
    "route_tool_path": "route_frames",
    "surface_approach": "plan",
    "waypoint_quaternions": "route_frames",
    "weld_rows": "route_frames",
}

__all__ = [
    "Accept",
    "Candidates",
    "ChoiceState",
    "DEFAULT_CONTACT_RADIUS",
    "ExitTest",
    "MISS_PROBE_CONTACTS",
    "Miss",
    "NO_FREE_POSE",
    "OK",
    "PoseBound",
    "PoseSearch",
    "Rechecks",
    "ToolPieces",
    "WeldPose",
    "WeldPoses",
    "all_of",
    "candidate_rotations",
    "choose",
    "least_rotation_choice",
    "leave_distances",
    "local_candidates",
    "plan_weld_poses",
    "probe_positions",
    "quat_wxyz",
    "rotation_angles",
    "route_poses",
    "route_tool_path",
    "surface_approach",
    "waypoint_quaternions",
    "weld_rows",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
