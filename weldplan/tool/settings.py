"""The settings of the tool stage's searches: one frozen, validated object a search.

:class:`PoseSearchSettings` (the weld poses, :func:`weldplan.tool.plan_weld_poses`),
:class:`TransitionSettings` (the transitions, :class:`~weldplan.tool.transitions.TransitionPlanner`
and :func:`~weldplan.tool.transitions.plan_transitions`) and :class:`OrderSettings` (the weld
order they are planned in, :func:`weldplan.tool.transitions.plan_ordered_transitions`). A search
takes its inputs and one of these (../shared/DESIGN.md: "a stage takes its inputs and one frozen,
validated settings object"); each is checked once, when it is made, and a bad field is a
:class:`~weldplan.errors.ConfigError` naming it. A station's
:class:`~weldplan.station.settings.ToolSettings` maps onto them in one place,
:mod:`weldplan.station.toolstage`.

The defaults are the module's constants below, each with its reason (issue 16 for the pose
search and the transitions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from weldplan.errors import ConfigError
from weldplan.weld.validate import flag, integer

#: default half-angle (deg) of the tilt cone about the approach axis (issue 16)
DEFAULT_CONE = 15.0
#: default tilt ring spacing (deg)
DEFAULT_TILT_STEP = 7.5
#: default spin spacing about the approach axis (deg)
DEFAULT_SPIN_STEP = 15.0
#: default tilt directions per ring
DEFAULT_AZIMUTHS = 8
#: default contact-zone radius about the weld spot (mm, issue 16)
DEFAULT_CONTACT_RADIUS = 20.0
#: default clearance (mm) when neither the call nor a cell gives one: the cell's torch-tip default
DEFAULT_CLEARANCE = 5.0
#: vetoes a weld may take before the test is lifted for it (each costs one more DP round,
#: :mod:`weldplan.tool.poses.choice`)
DEFAULT_MAX_VETOES = 12

#: mm: default retract distance along the TCP axis before leaving a weld (issue 16)
DEFAULT_RETRACT = 50.0
#: default OMPL planner for blocked transitions (stops at its first solution, then simplified)
DEFAULT_SE3_PLANNER = "rrtconnect"
#: mm: default side exit when the axial retract is blocked (a C-gun's jaws round a flange: the
#: shared gun's C back stands 231 mm from its electrode axis)
DEFAULT_SIDE_EXIT = 250.0
#: default CPU seconds of one transition's SE(3) re-plan, a safety net only (the CLI's and the
#: bench's too): the work budget is :data:`DEFAULT_SE3_CHECKS`; the clock stops a re-plan only
#: at :data:`~weldplan.tool.transitions.se3_replan.CLOCK_SAFETY` times this, and says so (not
#: reproducible)
DEFAULT_SE3_TIME = 10.0
#: state and motion checks one SE(3) re-plan may make (OMPL's ``max_checks``): the demo's three
#: re-plans took 191, 291 and about 1,900 (the last at 5 CPU s a thousand, cut by the old 10 CPU s
#: budget), so the same work as before on a quiet machine, now the same on any machine
DEFAULT_SE3_CHECKS = 2_000
#: FCL samples one motion of an SE(3) re-plan may take (a conservative advancement that needs
#: more grazes the part, or turns a 0.7 m gun far; OMPL tries a shorter motion instead)
DEFAULT_SE3_MOTION_CAP = 200
#: the SE(3) planner's range (mm of the metric, ``rot_weight`` mm per rad): OMPL's default, a
#: fifth of the space's extent, gave motions of 1-1.6 m of gun travel on the demo, each checked
#: near a flange for hundreds of FCL samples and nearly always blocked
DEFAULT_SE3_RANGE = 150.0
#: mm per rad: default weight of the orientation change in the leg costs (a turn of 1 rad costs
#: as much as 200 mm of TCP travel: about what a 0.7 m gun's far end sweeps through); also the
#: SE(3) planner's metric weight
DEFAULT_ROT_WEIGHT = 200.0
#: orders tried when transitions are found blocked (:mod:`weldplan.tool.transitions.reorder`)
REORDER_ROUNDS = 3


def _at_least(name: str, v: Any, lo: float, *, lo_open: bool = False) -> float:
    """``v`` as a finite float ``>= lo`` (``> lo`` when ``lo_open``), else a ConfigError."""
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    if not (ok and (v > lo if lo_open else v >= lo)):
        raise ConfigError(
            f"{name} must be a finite number {'>' if lo_open else '>='} {lo:g}, got {v!r}",
            field=name,
        )
    return float(v)


def _put(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class PoseSearchSettings:
    """How :func:`~weldplan.tool.poses.plan_weld_poses` searches a pose per weld.

    Attributes
    ----------
    cone, tilt_step, spin_step, azimuths
        The candidate orientations (degrees; :func:`~weldplan.tool.poses.local_candidates`):
        tilts up to ``cone`` off the approach axis in rings ``tilt_step`` apart, ``azimuths``
        directions a ring, spins ``spin_step`` apart.
    contact_radius
        mm: the contact zone about the weld spot, exempt from the check.
    clearance
        mm: least distance between the tool outside the zone and the part; ``None``: the cell's
        clearance, else :data:`DEFAULT_CLEARANCE`.
    both_sides
        Also try every candidate turned over (the approach axis reversed), after those on the
        approach side; ``None``: the tool's :attr:`~weldplan.tool.model.Tool.straddles`.
    crop
        Check against a BVH per weld of the part cropped to the tool's reach (default), or
        against one BVH of the whole part (the same answers).
    max_vetoes
        Vetoes of the acceptance test a weld may take before the test is lifted for it
        (:mod:`weldplan.tool.poses.choice`).
    """

    cone: float = DEFAULT_CONE
    tilt_step: float = DEFAULT_TILT_STEP
    spin_step: float = DEFAULT_SPIN_STEP
    azimuths: int = DEFAULT_AZIMUTHS
    contact_radius: float = DEFAULT_CONTACT_RADIUS
    clearance: float | None = None
    both_sides: bool | None = None
    crop: bool = True
    max_vetoes: int = DEFAULT_MAX_VETOES

    def __post_init__(self) -> None:
        _at_least("cone", self.cone, 0.0)
        _at_least("tilt_step", self.tilt_step, 0.0, lo_open=True)
        _at_least("spin_step", self.spin_step, 0.0, lo_open=True)
        integer("azimuths", self.azimuths, 1)
        _at_least("contact_radius", self.contact_radius, 0.0)
        if self.clearance is not None:
            _at_least("clearance", self.clearance, 0.0)
        if self.both_sides is not None:
            flag("both_sides", self.both_sides)
        flag("crop", self.crop)
        integer("max_vetoes", self.max_vetoes, 0)


@dataclass(frozen=True)
class TransitionSettings:
    """How the :class:`~weldplan.tool.transitions.TransitionPlanner` leaves, joins and reaches
    the welds (the clearance and the contact radius are the poses': they travel with the poses,
    not here).

    Attributes
    ----------
    retract
        mm along the TCP axis (0: no retract/approach motions, the move starts at the spot).
    side_exit
        mm: when the axial retract is blocked, try leaving sideways by this much (0: never).
    slide
        Try the slide (:data:`~weldplan.tool.transitions.SLIDE_LIFTS`) before the side exits.
    se3
        Re-plan blocked transitions with OMPL (needs ``weldplan[ompl]``).
    planner, time_s, seed
        OMPL's planner, its CPU seconds a transition (a safety net: the budget is
        ``se3_checks``) and its seed (the tool order's sequencer takes it too).
    rot_weight
        mm per rad: the SE(3) planner's metric weight on rotation (> 0).
    min_step
        mm: the swept check's least step (None:
        :data:`weldplan.tool.transitions.sweep.DEFAULT_MIN_STEP`).
    se3_samples
        FCL distance samples one SE(3) re-plan may take in all (``None``: no cap but the
        checks): its state and motion checks answer "not free" once it is spent, so OMPL stops.
    se3_motion_cap
        Samples one motion of an SE(3) re-plan may take (a longer motion is "not free").
    se3_checks
        State and motion checks one SE(3) re-plan may make (its work budget).
    se3_range
        mm: the SE(3) planner's range (:func:`weldplan.motion.sampling.plan_se3`'s ``reach``;
        None: OMPL's own).
    """

    retract: float = DEFAULT_RETRACT
    side_exit: float = DEFAULT_SIDE_EXIT
    slide: bool = True
    se3: bool = True
    planner: str = DEFAULT_SE3_PLANNER
    time_s: float = DEFAULT_SE3_TIME
    seed: int | None = 0
    rot_weight: float = DEFAULT_ROT_WEIGHT
    min_step: float | None = None
    se3_samples: int | None = None
    se3_motion_cap: int = DEFAULT_SE3_MOTION_CAP
    se3_checks: int = DEFAULT_SE3_CHECKS
    se3_range: float | None = DEFAULT_SE3_RANGE

    def __post_init__(self) -> None:
        for name in ("retract", "side_exit"):
            _put(self, name, _at_least(name, getattr(self, name), 0.0))
        for name in ("time_s", "rot_weight"):
            _put(self, name, _at_least(name, getattr(self, name), 0.0, lo_open=True))
        for name in ("min_step", "se3_range"):
            if getattr(self, name) is not None:
                _put(self, name, _at_least(name, getattr(self, name), 0.0, lo_open=True))
        flag("slide", self.slide)
        flag("se3", self.se3)
        if not (isinstance(self.planner, str) and self.planner):
            raise ConfigError(f"planner must be an OMPL planner's name, got {self.planner!r}",
                              field="planner")  # fmt: skip
        integer("seed", self.seed, 0, optional=True)
        integer("se3_samples", self.se3_samples, 1, optional=True)
        integer("se3_motion_cap", self.se3_motion_cap, 1)
        integer("se3_checks", self.se3_checks, 1)


@dataclass(frozen=True)
class OrderSettings:
    """The weld order the transitions are planned in (:mod:`weldplan.tool.transitions.reorder`).

    Attributes
    ----------
    rot_weight
        mm per rad: the order's leg costs weigh the orientation change by this
        (:func:`~weldplan.tool.transitions.tool_order`; 0: TCP length only).
    keep_order
        Keep the poses' own order (the point-tip route's) and never re-order.
    price_lifts
        With the exit test's planner: a weld that planner leaves by a lift is priced at the
        lift, not the axial retract (:func:`weldplan.tool.poses.leave_distances`).
    rounds
        At most this many orders, each pricing out the pairs found blocked before.
    """

    rot_weight: float = DEFAULT_ROT_WEIGHT
    keep_order: bool = False
    price_lifts: bool = True
    rounds: int = REORDER_ROUNDS

    def __post_init__(self) -> None:
        _put(self, "rot_weight", _at_least("rot_weight", self.rot_weight, 0.0))
        flag("keep_order", self.keep_order)
        flag("price_lifts", self.price_lifts)
        integer("rounds", self.rounds, 1)
