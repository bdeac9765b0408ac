"""Where the robots of a station of several stand: the planning frame, given and searched bases.

A station of several robots is planned in one frame, as one robot's is (docs/station.md,
:mod:`weldplan.cellframe`): the part frame, or the cell frame when the station places the part
in a cell (``part_pose``). The cell stage moves the part and the welds into it; every robot's
``base`` is given in it, every study, the allocation's reach and leg times and every robot's
sub-station plan (which keeps the part pose) are in it, so all robots' forward kinematics share
one frame.

:func:`place_robots` fixes every robot's base before the studies:

* a **given** base is checked against the part: its base link (the URDF's root link at the
  base pose) must not touch the part (FCL, the link's and the part's meshes) and its origin must
  not lie inside a closed part (else it stands "in the part's solid"), and its origin must lie
  outside the part's footprint on the floor (the part's bounding box in x, y: a robot cannot
  stand under the part). Two given bases
  closer than the sum of their footprint radii (:func:`footprint_radius`; or
  :attr:`LayoutSettings.spacing`) are refused by :func:`check_apart` before anything is loaded
  but the robots;
* a **searched** base (a robot without ``base``), in station order, after every given one: the
  single-robot study's base search (:func:`weldplan.study.check_spots` with a searched
  :class:`~weldplan.study.StudyRobot`: :func:`weldplan.robot.placement.search_base` on the robot's
  ``[robot.search]`` region, then the best few judged by the study itself, links and tool
  checked) on the welds its tool has a free pose at, the footprints of the robots already placed
  kept out (:attr:`weldplan.robot.placement.BaseSearch.keep_out`). It takes the base serving most
  welds; a region where no base serves any weld is a :class:`~weldplan.errors.ConfigError`
  naming the robot. Greedy and deterministic: no random draw, the search budgeted by its grid
  and pool (robot-robot interference along the routes is the station's later stage).

Every refusal is one :class:`~weldplan.errors.ConfigError` naming the robot and the key.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError, InputError, PlanningError
from weldplan.multi.bases import base_link_hits

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LayoutSettings:
    """How far apart the robots of a station stand.

    Attributes
    ----------
    spacing
        mm: least distance in x, y between two robots' bases; ``None``: the sum of their
        footprint radii (:func:`footprint_radius`: their base columns do not overlap).
    """

    spacing: float | None = None

    def __post_init__(self) -> None:
        if self.spacing is not None and not (math.isfinite(self.spacing) and self.spacing >= 0):
            raise ConfigError(f"spacing must be >= 0 mm, got {self.spacing!r}", field="spacing")

    def apart(self, r1: float, r2: float) -> float:
        """mm: the least distance between bases of footprint radii ``r1`` and ``r2``."""
        return r1 + r2 if self.spacing is None else float(self.spacing)


@dataclass(frozen=True, eq=False)
class Layout:
    """What :func:`place_robots` returns.

    Attributes
    ----------
    robots
        Per robot ``(spec, MountedTool, Robot)``: a searched robot's spec with its ``base``
        (``x, y, z, yaw`` in the planning frame) and no search, its robot at that base.
    studies
        Per robot the :class:`~weldplan.study.FeasibilityStudy` its base search made (at the
        chosen base, the same as a study there), ``None`` for a given base.
    """

    robots: tuple[tuple[Any, Any, Any], ...]
    studies: tuple[Any, ...]


def planning_floor(station: Any) -> float | None:
    """mm: the floor's height in the planning frame: the station's ``floor_z``, else the cell's
    floor when the part is placed in a cell (:attr:`weldplan.cellframe.PartPose.floor_z`), else
    ``None`` (not known)."""
    if station.floor_z is not None:
        return float(station.floor_z)
    pose = station.part_pose
    return None if pose is None else float(pose.floor_z)


def study_settings(station: Any) -> Any:
    """The :class:`~weldplan.study.StudySettings` of a station's robots: the tool stage's cone
    and contact radius, the planning frame's floor."""
    from weldplan.study import StudySettings

    ts = station.tool
    return StudySettings(
        cone=ts.cone, contact_radius=ts.contact_radius, floor_z=planning_floor(station)
    )


def footprint_radius(robot: Any) -> float:
    """mm: the radius about A1 of the robot's base column in x, y (its base and A1 links; the
    radius the base search's :func:`weldplan.robot.placement.reach.column_free` keeps clear of the
    part)."""
    return max(float(np.linalg.norm(lk.vertices[:, :2], axis=1).max()) for lk in robot.links[:2])


def check_apart(robots: Any, settings: LayoutSettings | None = None, source: Any = None) -> None:
    """Refuse two robots whose given bases stand closer in x, y than
    :meth:`LayoutSettings.apart` (a ConfigError ``base`` naming both; with the station file
    ``source``, an :class:`~weldplan.errors.InputError` naming it, the line of the second
    robot's ``base`` and the key ``robot.base``)."""
    settings = settings or LayoutSettings()
    given = [
        (k, s.base, footprint_radius(r)) for k, (s, _, r) in enumerate(robots) if s.base is not None
    ]
    for j, (kb, b, rb) in enumerate(given):
        for ka, a, ra in given[:j]:
            d = math.hypot(b[0] - a[0], b[1] - a[1])
            need = settings.apart(ra, rb)
            if d < need:
                same = "at the same base" if d < 1e-6 else f"{d:.1f} mm apart"
                raise _base_error(
                    f"robots {ka + 1} and {kb + 1} stand {same}: two bases must be at least "
                    f"{need:.0f} mm apart in x, y (their footprints)",
                    source,
                    kb,
                )


def _base_error(message: str, source: Any, k: int) -> ConfigError | InputError:
    """The refusal of robot ``k``'s base: located in the station file ``source`` when there
    is one (its line of ``robot.base``), else a ConfigError ``base``."""
    if source is None:
        return ConfigError(message, field="base")
    from weldplan.station.load import key_line

    line = key_line(source, ("robot", k, "base")) or key_line(source, ("robot", k))
    return InputError(message, path=source, line=line, field="robot.base")


def check_in_part(part: Any, k: int, spec: Any, robot: Any, source: Any = None) -> None:
    """Refuse robot ``k``'s given base when it stands in the part's solid or inside its
    footprint on the floor (module docstring; ConfigError ``base``, located in the station
    file ``source`` as :func:`check_apart` does)."""
    p = np.asarray([spec.base[:3]], dtype=np.float64)
    where = ", ".join(f"{v:.0f}" for v in spec.base[:3])
    hit = base_link_hits(part, robot)
    if hit or (part.is_watertight and bool(part.contains(p)[0])):
        what = f"its base link {robot.links[0].name!r} meets the part" if hit else "inside it"
        raise _base_error(
            f"robot {k + 1}'s base ({where}) stands in the part's solid: {what}", source, k
        )
    lo, hi = np.asarray(part.bounds)[:, :2]
    if np.all(p[0, :2] >= lo) and np.all(p[0, :2] <= hi):
        raise _base_error(
            f"robot {k + 1}'s base ({where}) lies inside the part's footprint on the floor "
            f"(its bounding box x {lo[0]:.0f}..{hi[0]:.0f}, y {lo[1]:.0f}..{hi[1]:.0f} mm): a "
            "robot cannot stand under the part",
            source,
            k,
        )


def xyz_yaw(B: NDArray[np.float64]) -> tuple[float, float, float, float]:
    """``(x, y, z mm, yaw deg)`` of a base pose ``B (4, 4)`` turned about z only."""
    yaw = math.degrees(math.atan2(B[1, 0], B[0, 0]))
    return (float(B[0, 3]), float(B[1, 3]), float(B[2, 3]), yaw)


def place_robots(
    cell: Any,
    station: Any,
    robots: Any,
    seconds: dict[str, float] | None = None,
    settings: LayoutSettings | None = None,
) -> Layout:
    """Every robot's base fixed and checked (module docstring).

    Parameters
    ----------
    cell
        The station's :class:`~weldplan.weld.cell.Cell` (part and welds in the planning frame).
    station
        The :class:`~weldplan.station.model.Station`.
    robots
        Per robot ``(spec, MountedTool, Robot)`` (:func:`weldplan.multi.station._robots`).
    seconds
        Where each search's wall seconds go (``"bases robotK"``), if given.
    settings
        :class:`LayoutSettings`.

    Raises
    ------
    ConfigError
        A given base in the part (``base``); a region with no base serving any weld
        (``search``), each naming the robot.
    """
    settings = settings or LayoutSettings()
    for k, (spec, _, robot) in enumerate(robots):
        if spec.base is not None:
            check_in_part(cell.part, k, spec, robot, station.source)
    out, studies = list(robots), [None] * len(robots)
    for k, (spec, mounted, robot) in enumerate(robots):
        if spec.base is not None:
            continue
        t = time.perf_counter()
        others = [out[j] for j in range(len(out)) if j != k and out[j][0].base is not None]
        study = _search(cell, station, k, (spec, mounted, robot), others, settings)
        B = study.robots[0].base_matrix()
        placed = dataclasses.replace(spec, base=xyz_yaw(B), search={})
        out[k] = (placed, mounted, robot.with_base(B))
        studies[k] = study
        if seconds is not None:
            seconds[f"bases robot{k + 1}"] = time.perf_counter() - t
        log.info("station: robot %d's base searched: %s", k + 1, np.round(placed.base, 1))
    return Layout(tuple(out), tuple(studies))


def _search(
    cell: Any, station: Any, k: int, entry: Any, others: list[Any], settings: LayoutSettings
) -> Any:
    """Robot ``k``'s study with its base searched in its region, ``others``' footprints kept
    out (module docstring)."""
    from weldplan.study import StudyRobot, StudyTool, check_spots

    spec, mounted, robot = entry
    r = footprint_radius(robot)
    discs = tuple(
        (float(s.base[0]), float(s.base[1]), settings.apart(r, footprint_radius(rb)))
        for s, _, rb in others
    )
    opts = dataclasses.replace(spec.base_search(planning_floor(station)), keep_out=discs)
    tool = StudyTool(f"tool{k + 1}", mounted.tool, mounted.spec)
    name = f"robot{k + 1}"
    try:
        study = check_spots(
            cell.part, cell.joints, [tool], [StudyRobot(name, robot, True, search=opts)],
            study_settings(station), frame=cell.frame,
        )  # fmt: skip
    except PlanningError as exc:
        raise ConfigError(
            f"robot {k + 1}: no base in its search region serves any weld ({exc})", field="search"
        ) from None
    if not study.robots[0].searched:
        raise ConfigError(
            f"robot {k + 1}: no weld has a free pose of its tool, nothing to search its base on",
            field="search",
        )
    served = int(study.reach_matrix()[:, 0].sum())
    if served == 0:
        raise ConfigError(
            f"robot {k + 1}: no base in its search region serves any weld (the best judged, "
            f"{np.round(xyz_yaw(study.robots[0].base_matrix()), 1).tolist()}, serves none)",
            field="search",
        )
    return study
