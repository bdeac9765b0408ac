"""The arm: its URDF chain, OPW inverse kinematics and the tool's payload on the flange.

Modules: ``arm``, ``ik``, ``payload``, ``urdf``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "ELBOW": "ik",
    "IKBranches": "ik",
    "IKSolutions": "ik",
    "OPWParams": "ik",
    "Robot": "arm",
    "RobotLink": "arm",
    "SHOULDER": "ik",
    "UrdfJoint": "urdf",
    "WRIST": "ik",
    "branch_bits": "ik",
    "chain": "urdf",
    "chain_transform": "urdf",
    "joint_limits": "urdf",
    "link_geometry": "urdf",
    "load_opw": "ik",
    "load_robot": "arm",
    "parse_urdf": "urdf",
    "solve": "ik",
    "urdf_payload": "payload",
    "wrap_into_limits": "ik",
}

__all__ = [
    "ELBOW",
    "IKBranches",
    "IKSolutions",
    "OPWParams",
    "Robot",
    "RobotLink",
    "SHOULDER",
    "UrdfJoint",
    "WRIST",
    "branch_bits",
    "chain",
    "chain_transform",
    "joint_limits",
    "link_geometry",
    "load_opw",
    "load_robot",
    "parse_urdf",
    "solve",
    "urdf_payload",
    "wrap_into_limits",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
