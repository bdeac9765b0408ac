"""Where the robot stands: reach, the base search, alternative tool poses, the pose choice's reach
test, the welds a base can join.

Modules: ``altreach``, ``base``, ``posechoice``, ``reach``, ``roadmaps``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "BaseSearch": "reach",
    "COLLISION": "reach",
    "DEFAULT_SINGULAR_DEG": "reach",
    "JOINT_LIMIT": "reach",
    "LegRoadmap": "roadmaps",
    "NO_POSE": "reach",
    "OK": "reach",
    "OUT_OF_REACH": "reach",
    "PRESELECT": "reach",
    "Placement": "reach",
    "ReachTest": "posechoice",
    "SINGULAR": "reach",
    "alt_free": "altreach",
    "alt_pairs": "reach",
    "alternative_flange_poses": "altreach",
    "arm_reach": "reach",
    "base_pose": "reach",
    "branch_roadmap": "roadmaps",
    "candidate_bases": "reach",
    "classify": "reach",
    "free_branches": "base",
    "join_welds": "roadmaps",
    "joint_limit_reason": "posechoice",
    "may_reach": "reach",
    "parse_base": "reach",
    "place": "base",
    "place_for_poses": "posechoice",
    "rank_bases": "base",
    "search_base": "reach",
    "sight_clear": "reach",
    "spread": "altreach",
    "usable": "reach",
}

__all__ = [
    "BaseSearch",
    "COLLISION",
    "DEFAULT_SINGULAR_DEG",
    "JOINT_LIMIT",
    "LegRoadmap",
    "NO_POSE",
    "OK",
    "OUT_OF_REACH",
    "PRESELECT",
    "Placement",
    "ReachTest",
    "SINGULAR",
    "alt_free",
    "alt_pairs",
    "alternative_flange_poses",
    "arm_reach",
    "base_pose",
    "branch_roadmap",
    "candidate_bases",
    "classify",
    "free_branches",
    "join_welds",
    "joint_limit_reason",
    "may_reach",
    "parse_base",
    "place",
    "place_for_poses",
    "rank_bases",
    "search_base",
    "sight_clear",
    "spread",
    "usable",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
