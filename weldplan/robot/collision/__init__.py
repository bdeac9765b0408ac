"""What touches: the links and the tool against the part, the robot against itself and the floor,
the motion bounds and part tables under them.

Modules: ``checker``, ``distbound``, ``motionbound``, ``nearpart``, ``selfcollision``, ``world``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "AllowedCollisions": "world",
    "AlongMotion": "nearpart",
    "Body": "bodies",
    "Carry": "motionbound",
    "FLOOR": "world",
    "FloorBox": "world",
    "Hit": "bodies",
    "MIN_GAP_MM": "checker",
    "PROBE_AFTER": "motionbound",
    "PartCrops": "nearpart",
    "ROBOT_KINDS": "world",
    "RobotCollision": "checker",
    "SELF_GAP_MM": "world",
    "SPHERE_CELL_MM": "checker",
    "SelfCheck": "selfcollision",
    "WorldSettings": "world",
    "cell_floor": "selfcollision",
    "fcl_distance": "nearpart",
    "fcl_tf": "nearpart",
    "floor_box": "world",
    "hit_words": "selfcollision",
    "pair_distance": "world",
    "robot_world": "world",
    "sphere_groups": "motionbound",
    "touches_ahead": "motionbound",
}

__all__ = [
    "AllowedCollisions",
    "AlongMotion",
    "Body",
    "Carry",
    "FLOOR",
    "FloorBox",
    "Hit",
    "MIN_GAP_MM",
    "PROBE_AFTER",
    "PartCrops",
    "ROBOT_KINDS",
    "RobotCollision",
    "SELF_GAP_MM",
    "SPHERE_CELL_MM",
    "SelfCheck",
    "WorldSettings",
    "cell_floor",
    "fcl_distance",
    "fcl_tf",
    "floor_box",
    "hit_words",
    "pair_distance",
    "robot_world",
    "sphere_groups",
    "touches_ahead",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
