"""The independent re-checks of a plan, saved or just planned: one :class:`Verdict`.

:func:`recheck` runs, in order, the checks that share none of the planner's shortcuts
(../shared/DESIGN.md, "verified"), each on what the route JSON carries:

``part pose``
    the pose the route was planned with (its provenance) against the one given again
    (:func:`weldplan.cellframe.recorded_pose`; done by the caller that loads the part, which
    reports it here);
``route``
    the point-tip route, every segment by FCL at the clearance, every joint once
    (:func:`weldplan.weld.verify.verify_route`);
``tool poses``
    the weld poses belong to the route and each pose reported free is free, fresh FCL models of
    the whole part and tool (:func:`weldplan.tool.verify.verify_route_poses`), after the
    tool's provenance is matched (a route planned with another tool is bad input; two spellings
    of one TCP, a joint's name and none for a URDF's last fixed joint, are one tool:
    :func:`same_tcp_spelling`);
``tool transitions``
    the swept tool along every transition (:func:`weldplan.tool.verify.verify_route_sweeps`);
``robot route``
    forward kinematics of the URDF chain on every exact row, the joint limits, robot and tool
    against the part, themselves and the floor
    (:func:`weldplan.robot.program.verify_robot_route`).

A check that fails stops the run (the later ones are listed in :attr:`Verdict.not_run`): a later
check reads what the earlier one vouched for. A weld left out (no pose, a blocked transition, not
in the program) is not a failure: the verdict is ``ok`` and :attr:`Verdict.partial`.
``weldplan verify`` prints the checks' lines and exits :attr:`Verdict.exit_code`.
"""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from weldplan.errors import EXIT_PARTIAL
from weldplan.geometry.checker import CheckVerdict

#: the checks, in the order they run
CHECKS = ("part pose", "route", "tool poses", "tool transitions", "robot route")
#: exit code of a failed check (``weldplan verify``)
EXIT_FAILED = 1
#: mm: two spellings of a TCP are one TCP when the tool's vertices in their frames agree to this
SAME_TCP_MM = 1e-6


@dataclass(frozen=True)
class CheckResult:
    """One re-check.

    Attributes
    ----------
    name
        One of :data:`CHECKS`.
    ok
        It passed.
    text
        One line: what was checked and found (the report's ``describe()``).
    left_out
        Welds (or transitions) the plan leaves out, found by this check: a partial plan.
    report
        The check's own report (:class:`~weldplan.weld.verify.VerifyReport`,
        :class:`~weldplan.tool.verify.RoutePosesCheck`,
        :class:`~weldplan.tool.verify.SweepsVerification`,
        :class:`~weldplan.robot.program.RobotCheck`; None for the part pose); each exposes
        the one verdict type, :attr:`verdict`.
    """

    name: str
    ok: bool
    text: str
    left_out: tuple[str, ...] = ()
    report: Any = None

    @property
    def verdict(self) -> CheckVerdict:
        """The check's :class:`~weldplan.geometry.checker.CheckVerdict`: its report's
        (``report.verdict``), else one made of this line (the part pose)."""
        own = getattr(self.report, "verdict", None)
        if isinstance(own, CheckVerdict):
            return own
        fails = () if self.ok else (("", self.text),)
        return CheckVerdict.of(self.name, 1, fails, left_out=self.left_out, ok=self.ok)


@dataclass(frozen=True)
class Verdict:
    """What :func:`recheck` found.

    Attributes
    ----------
    checks
        The checks run, in order (:class:`CheckResult`).
    not_run
        ``(check, why)`` of each check the plan carries something for that was not run: the
        caller gave no tool, or an earlier check failed.
    """

    checks: tuple[CheckResult, ...]
    not_run: tuple[tuple[str, str], ...] = ()

    @property
    def ok(self) -> bool:
        """Every check run passed (a partial plan can be ok)."""
        return all(c.ok for c in self.checks)

    @property
    def failures(self) -> tuple[CheckResult, ...]:
        return tuple(c for c in self.checks if not c.ok)

    @property
    def verdicts(self) -> tuple[CheckVerdict, ...]:
        """The checks run, in order, each as its
        :class:`~weldplan.geometry.checker.CheckVerdict`."""
        return tuple(c.verdict for c in self.checks)

    @property
    def left_out(self) -> tuple[str, ...]:
        """Everything the checks found left out, in check order."""
        return tuple(x for c in self.checks for x in c.left_out)

    @property
    def partial(self) -> bool:
        return self.ok and bool(self.left_out)

    @property
    def exit_code(self) -> int:
        """0 ok, 1 a check failed, 3 (:data:`weldplan.errors.EXIT_PARTIAL`) ok but partial."""
        if not self.ok:
            return EXIT_FAILED
        return EXIT_PARTIAL if self.left_out else 0

    def __getitem__(self, name: str) -> CheckResult:
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(f"no {name!r} check was run (run: {[c.name for c in self.checks]})")

    def describe(self) -> str:
        """One line: ok (and what was left out), or the first failure named."""
        if not self.ok:
            first = self.failures[0]
            return f"{first.name} failed: {first.text}"
        names = ", ".join(c.name for c in self.checks)
        left = f"; left out: {', '.join(self.left_out)}" if self.left_out else ""
        return f"ok ({names}){left}"


@dataclass(frozen=True)
class RobotFiles:
    """The robot of a saved plan's robot route, by file (``urdf`` None: the file the route
    names; ``opw``: the OPW parameters, None: beside the URDF)."""

    urdf: str | PathLike[str] | None = None
    opw: str | PathLike[str] | None = None


def recheck(
    route: Any,
    part: Any,
    *,
    tool: Any = None,
    robot: Any = None,
    joints: Any = None,
    clearance: float | None = None,
    part_pose: CheckResult | None = None,
    path: str | PathLike[str] | None = None,
) -> Verdict:
    """Run the re-checks of the module docstring on ``route``.

    Parameters
    ----------
    route
        :class:`~weldplan.weld.route.Route`, with its ``tool`` section (read as a
        :class:`~weldplan.robot.program.ToolRoute`).
    part
        The part mesh (trimesh, mm) in the route's frame (the cell frame when it was planned
        with a part pose).
    tool
        ``(Tool, provenance)`` or a :class:`~weldplan.station.mount.MountedTool`; None: the tool
        checks are not run (listed in :attr:`Verdict.not_run`).
    robot
        A :class:`~weldplan.robot.model.Robot`, or :class:`RobotFiles` (default: the URDF the
        route names), loaded only when the earlier checks passed.
    joints
        :class:`~weldplan.io.joints.Joints`: the route must visit exactly these.
    clearance
        mm: the torch-tip radius (default: the route's own).
    part_pose
        The part pose's check, done by the caller that placed ``part`` (listed first).
    path
        The route file, for the messages.

    Raises
    ------
    InputError
        The route was planned with another tool, or its tool section (the robot's route
        included) is unreadable.
    """
    from weldplan.tool.verify.check_route import check_tool_provenance
    from weldplan.weld.verify import verify_route

    tool_obj = provenance = None
    if tool is not None:  # another tool is bad input, whatever the route
        tool_obj, provenance = (tool.tool, tool.provenance) if hasattr(tool, "tool") else tool
        check_tool_provenance(route, same_tcp_spelling(route, provenance, tool_obj), path)
    run = _Run([] if part_pose is None else [part_pose], _carried(route, path))
    if part_pose is not None and not part_pose.ok:
        return run.verdict("an earlier check failed")
    rep = verify_route(route, part, clearance=clearance, joints=joints)
    run.add(CheckResult("route", rep.ok, rep.describe(limit=20 if not rep.ok else 5), (), rep))
    if not rep.ok:
        return run.verdict("an earlier check failed")
    if tool is None:
        return run.verdict("no tool given")
    if not _tool_checks(run, route, part, tool_obj):
        return run.verdict("an earlier check failed")
    _robot_check(run, route, part, tool_obj, robot, path)
    return run.verdict("an earlier check failed")


def same_tcp_spelling(route: Any, provenance: dict[str, Any], tool: Any) -> dict[str, Any]:
    """``provenance`` with the route's spelling of the TCP when both spellings name one TCP.

    A provenance records the TCP as it was written: ``None`` (a URDF's last fixed joint), a
    joint or link name, or six numbers. ``--tcp nozzle_tip`` and no ``--tcp`` name the same joint
    of the shared gun, and are one tool. So, when the route and ``provenance`` differ in the
    ``tcp`` only, the route's spelling is resolved again in the given files
    (:func:`weldplan.tool.model.load_tool`) and the tool it gives is compared with ``tool``: the
    same triangles in the TCP frame to :data:`SAME_TCP_MM` is the same TCP transform, and the
    route's spelling is returned. Otherwise ``provenance`` is returned unchanged (and
    :func:`weldplan.tool.verify.check_tool_provenance` names the difference).

    Parameters
    ----------
    route
        The route, with the provenance of the tool it was planned with (its
        :attr:`~weldplan.tool.section.ToolSection.provenance`).
    provenance
        The given tool's provenance.
    tool
        The given :class:`~weldplan.tool.model.Tool` (mm, TCP frame).
    """
    from weldplan.errors import InputError
    from weldplan.tool.model.load import PROVENANCE_KEYS, load_tool
    from weldplan.tool.section import ToolSection

    try:
        planned = ToolSection.of(route).provenance
    except (KeyError, TypeError, ValueError):  # check_tool_provenance names what is wrong
        return provenance
    if planned.get("tcp") == provenance.get("tcp") or not provenance.get("file"):
        return provenance
    if any(planned.get(k) != provenance.get(k) for k in PROVENANCE_KEYS if k != "tcp"):
        return provenance
    units = None if provenance.get("units") == "urdf" else provenance.get("units")
    try:
        again, _ = load_tool(
            provenance["file"], tcp=planned.get("tcp"), units=units, mesh=provenance.get("mesh")
        )
    except InputError:  # the route's TCP is not in the given files: another tool
        return provenance
    v0, v1 = np.asarray(again.vertices), np.asarray(tool.vertices)
    if v0.shape == v1.shape and np.allclose(v0, v1, rtol=0.0, atol=SAME_TCP_MM):
        return {**provenance, "tcp": planned.get("tcp")}
    return provenance


class _Run:
    """The checks run so far."""

    def __init__(self, checks: list[CheckResult], carried: set[str]) -> None:
        self.checks = checks
        self.carried = carried

    def add(self, c: CheckResult) -> bool:
        self.checks.append(c)
        return c.ok

    def verdict(self, why: str) -> Verdict:
        done = {c.name for c in self.checks}
        rest = tuple((n, why) for n in CHECKS if n in self.carried and n not in done)
        return Verdict(tuple(self.checks), rest)


def _carried(route: Any, path: str | PathLike[str] | None) -> set[str]:
    """The checks ``route`` carries something for (its tool section read typed:
    :class:`InputError` naming ``path`` when it is not readable)."""
    from weldplan.robot.program.routejson import tool_route

    tool = tool_route(route, path)
    carried = {
        "tool poses": tool.poses is not None,
        "tool transitions": tool.transitions is not None,
        "robot route": tool.robot is not None,
    }
    return {"route"} | {name for name, has in carried.items() if has}


def _tool_checks(run: _Run, route: Any, part: Any, tool: Any) -> bool:
    """The poses, then the transitions; False when one fails."""
    from weldplan.tool.verify.check_route import verify_route_poses, verify_route_sweeps

    check = verify_route_poses(route, part, tool)
    if not run.add(CheckResult("tool poses", check.ok, check.describe(), check.missing, check)):
        return False
    sweeps = verify_route_sweeps(route, part, tool)
    if sweeps is None:
        return True
    blocked = tuple(sweeps.blocked)
    return run.add(CheckResult("tool transitions", sweeps.ok, sweeps.describe(), blocked, sweeps))


def _robot_check(run: _Run, route: Any, part: Any, tool: Any, robot: Any, path: Any) -> None:
    """The robot route, when the route carries one."""
    from weldplan.robot.program.routejson import (
        robot_route_of,
        saved_robot_route,
        verify_robot_route,
    )

    rr = robot_route_of(route, path)
    if rr is None:
        return
    if robot is None or isinstance(robot, RobotFiles):
        from weldplan.robot import load_robot

        files = robot or RobotFiles()
        urdf = files.urdf or saved_robot_route(route, path).urdf
        robot = load_robot(urdf, files.opw)
    check = verify_robot_route(route, rr, robot, part, tool)
    run.add(CheckResult("robot route", check.ok, check.describe(), check.left_out, check))
