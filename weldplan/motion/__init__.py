"""Sampling-based motion planning through OMPL (the ``ompl`` extra): one wrapper for every stage
that needs it (the torch's local planner peer, SE(3) gun transitions, joint-space replanning).

The validity check is always the caller's (weldplan's FCL checks); OMPL only samples and searches.
"""

from weldplan.motion.sampling import (
    PLANNERS,
    SampledPath,
    SamplingArgumentError,
    ompl_available,
    plan_rn,
    plan_se3,
)
from weldplan.motion.settings import SamplingSettings

__all__ = [
    "PLANNERS",
    "SampledPath",
    "SamplingArgumentError",
    "SamplingSettings",
    "ompl_available",
    "plan_rn",
    "plan_se3",
]
