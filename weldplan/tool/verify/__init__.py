"""The independent re-checks of the tool stage: fresh FCL models, the whole part, a different test
(poses, transitions, a saved route).

Modules: ``check_route``, ``poses``, ``sweeps``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "PoseCheck": "poses",
    "PoseChecker": "poses",
    "PosesVerification": "poses",
    "RoutePosesCheck": "check_route",
    "SweepsVerification": "sweeps",
    "check_tool_provenance": "check_route",
    "triangle_crossings": "poses",
    "verify_poses": "poses",
    "verify_route_poses": "check_route",
    "verify_route_sweeps": "check_route",
    "verify_sweeps": "sweeps",
}

__all__ = [
    "PoseCheck",
    "PoseChecker",
    "PosesVerification",
    "RoutePosesCheck",
    "SweepsVerification",
    "check_tool_provenance",
    "triangle_crossings",
    "verify_poses",
    "verify_route_poses",
    "verify_route_sweeps",
    "verify_sweeps",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
