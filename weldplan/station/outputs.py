"""The files of a plan, rendered in memory and written as one set.

:func:`output_paths` names every file an :class:`~weldplan.station.model.OutputSpec` asks for
and checks them before any work (:func:`weldplan.io.outputset.check_outputs`);
:func:`render_outputs` renders each in memory; :func:`write_plan` writes them as one set
(:func:`weldplan.io.outputset.write_outputs`: temporaries, then renames, rolled back on
failure), so a failed run leaves existing files exactly as they were.

With a robot the program is rendered by its post (``rapid``: ABB ``.mod``; ``krl``: KUKA ``.src``
and ``.dat``) and parsed back (:func:`check_program`): every target is re-solved by forward
kinematics of the URDF chain (<= 0.01 mm, 0.01 deg), so what is written is what was planned.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import PlanningError, WeldplanError
from weldplan.station.model import OutputSpec

#: the round trip of an emitted program must close within these (mm, deg)
CHECK_MM = 0.01
CHECK_DEG = 0.01


def output_paths(out: OutputSpec, *, robot: bool, tool: bool) -> dict[str, Path]:
    """Every file the run will write, by kind, checked before any work is done."""
    from weldplan.io.export import POSTS

    if out.csv is None:
        raise WeldplanError("no route CSV to write: give -o (or [output] csv in the station)")
    paths = {"csv": out.csv}
    for kind in ("json", "html"):
        if getattr(out, kind) is not None:
            paths[kind] = getattr(out, kind)
    if out.json is not None:  # the run's measured times, apart from the deliverable
        from weldplan.io.timings import timings_path

        paths["timings"] = timings_path(out.json)
    if out.post:
        paths["post"] = out.post_file or out.csv.with_suffix(POSTS[out.post].suffix)
    elif out.post_file:
        raise WeldplanError("--post-file needs --post rapid|krl")
    if robot and out.post == "krl":  # KRL's data list beside the .src
        paths["post_dat"] = paths["post"].with_suffix(".dat")
    if out.tool_csv is not None:
        if not tool:
            raise WeldplanError("--tool-csv needs --tool")
        paths["tool_csv"] = out.tool_csv
    for kind in ("trajectory", "robot_html", "png"):
        if getattr(out, kind) is not None:
            paths[kind] = getattr(out, kind)
    if out.png is not None:  # no Chromium: say so before any work
        from weldplan.viz.png import find_chromium

        find_chromium()
    seen: dict[Path, str] = {}
    for kind, path in paths.items():
        key = path.resolve()
        if key in seen:
            raise WeldplanError(f"{path}: given for both {seen[key]} and {kind}")
        seen[key] = kind
    from weldplan.io.outputset import check_outputs

    check_outputs(paths)
    return paths


def producer(plan: Any) -> dict[str, Any]:
    """What produced ``plan``'s files and which independent re-checks it passed (issue 28:
    each file says so): weldplan's version, the station's name, one line per check. No
    command line and no time: the same station gives the same files, by file, options or
    library. A plan exists only once its checks passed (:func:`weldplan.station.plan` raises
    otherwise), so each named check passed."""
    from weldplan._version import __version__

    v = plan.verification
    checks = [
        f"route: {v.segments_checked} segments free at {v.clearance:g} mm clearance "
        "(FCL capsules, weldplan.weld.verify)"
    ]
    if plan.poses is not None:
        checks.append(
            f"tool poses: {plan.poses.check.checked} weld poses free outside the contact zone "
            "(FCL, weldplan.tool.verify.poses)"
        )
    if plan.transitions is not None:
        checks.append(
            f"tool transitions: {plan.transitions.sweeps.checked} swept-tool motions free "
            "(FCL, weldplan.tool.verify.sweeps)"
        )
    if plan.robot is not None:
        checks.append(
            "robot: FK of the URDF chain puts the TCP on every exact route row; links and "
            "tool clear of the part along the joint path (FCL, weldplan.robot.route.plan)"
        )
    name = plan.station.name or "weldplan_route"
    return {"weldplan": __version__, "station": name, "verified": checks}


def header_lines(prod: dict[str, Any]) -> list[str]:
    """The comment lines a file starts with, from :func:`producer`."""
    head = f"produced by weldplan {prod['weldplan']} for station '{prod['station']}'"
    return [head, *(f"verified: {c}" for c in prod["verified"])]


def post_name_option(post: str, name: str | None) -> dict[str, str]:
    """The point-tip post's name option (RAPID's ``module``, KRL's ``program``) set to the
    station's ``name``, as the robot's programs are named; empty without a name (the post's
    default, ``weldplan_route``) or for a post that takes none."""
    import inspect

    from weldplan.io.export import POSTS

    if not name:
        return {}
    params = inspect.signature(POSTS[post].render).parameters
    return next(({k: name} for k in ("module", "program") if k in params), {})


def render_outputs(plan: Any, kinds: set[str], post: str | None) -> dict[str, str | bytes]:
    """The text of each output kind of ``plan`` (``post``: ``"rapid"`` or ``"krl"``); each file
    says what produced it and what was verified (:func:`producer`)."""
    from weldplan.io.export import render_post, to_csv_text
    from weldplan.viz.viewer import static_html

    route, prod = plan.route, producer(plan)
    head = header_lines(prod)
    texts = {"csv": to_csv_text(route, head)}
    if "json" in kinds:
        from weldplan.io.timings import route_json_texts

        texts["json"], texts["timings"] = route_json_texts(route, prod)
    if "html" in kinds:
        texts["html"] = static_html(route, plan.cell.part, tool=plan.tool and plan.tool.tool)
    if "tool_csv" in kinds:
        from weldplan.io.tool_csv import route_tool_csv

        texts["tool_csv"] = route_tool_csv(route, head)
    if plan.robot is not None:
        texts.update(_robot_texts(plan, kinds, post, head))
    elif "post" in kinds:
        name = post_name_option(post, plan.station.name)
        texts["post"] = render_post(route, post, plan.cell, header=head, **name)
    if "png" in kinds:  # the robot cell's page with a robot, else the route's
        from weldplan.viz.png import png_bytes

        page = texts.get("robot_html") if plan.robot is not None else texts.get("html")
        if page is None:
            kind = "robot_html" if plan.robot is not None else "html"
            page = render_outputs(plan, {kind}, post)[kind]
        texts["png"] = png_bytes(page)
    return texts


def write_plan(plan: Any, paths: dict[str, Path]) -> None:
    """Render every output of ``paths`` (kind -> path, :func:`output_paths`), then write them as
    one set."""
    from weldplan.io.outputset import write_outputs

    texts = render_outputs(plan, set(paths), plan.station.outputs.post)
    write_outputs({path: texts[kind] for kind, path in paths.items()})


def _robot_texts(plan: Any, kinds: set[str], post: str | None, head: list[str]) -> dict[str, str]:
    """The robot's program (checked by :func:`check_program`), trajectory and 3D page
    (``head``: their comment lines, :func:`header_lines`)."""
    from weldplan.io.trajectory import trajectory_csv_text

    build, joint = plan.program, plan.robot
    texts: dict[str, str] = {}
    if "post" in kinds:
        # written only when the round trip below closes
        prog = [*head, f"verified: program: every target re-solved by FK of its joint values "
                f"within {CHECK_MM:g} mm, {CHECK_DEG:g} deg (parsed back)"]  # fmt: skip
        if post == "rapid":
            from weldplan.io.posts.rapid import render_rapid

            texts["post"] = render_rapid(build.program, header=prog)
        else:
            from weldplan.io.posts.krl import render_krl

            texts["post"], texts["post_dat"] = render_krl(build.program, header=prog)
        check_program(str(post), texts, build.program, joint.robot)
    if "trajectory" in kinds:
        texts["trajectory"] = trajectory_csv_text(build.timing, build.row, head)
    if "robot_html" in kinds:
        from weldplan.viz.robot_scene import robot_html

        texts["robot_html"] = robot_html(
            joint.robot, build.timing, joint.robot_route.flange_tcp, part=plan.cell.part,
            tool=plan.tool.tool, route_points=joint.follow.waypoints(),
            weld_ids=build.welded_ids(),
        )  # fmt: skip
    return texts


def check_program(post: str, texts: dict[str, str], program: Any, robot: Any) -> float:
    """Parse the emitted program and re-solve every target by FK of the URDF chain (a target
    written as axis values, the home, by FK of the values read back).

    Returns the largest position error (mm); raises :class:`PlanningError` past
    :data:`CHECK_MM` / :data:`CHECK_DEG`.
    """
    from weldplan.io.posts.parse import parse_krl, parse_rapid

    if post == "rapid":
        mod = parse_rapid(texts["post"])
        frame, tool, points, axes = mod.wobj, mod.tool, mod.targets, mod.joints
    else:
        prog = parse_krl(texts["post"], texts["post_dat"])
        frame, tool, points, axes = prog.base, prog.tool, prog.points, prog.axes
    names = [m[1] for m in (mod.moves if post == "rapid" else prog.moves)]

    def flange(name: str) -> NDArray[np.float64]:  # in the robot base frame
        if name in axes:
            return np.linalg.solve(robot.base, robot.fk(np.radians(axes[name])[None])[0])
        return frame @ points[name][0] @ np.linalg.inv(tool)

    Q = np.array([t.q for t in program.targets])
    T_fk = np.linalg.solve(robot.base, robot.fk(Q))  # flange in the robot base frame
    T_prog = np.array([flange(n) for n in names])
    mm = float(np.linalg.norm(T_fk[:, :3, 3] - T_prog[:, :3, 3], axis=1).max())
    c = (np.einsum("nij,nij->n", T_fk[:, :3, :3], T_prog[:, :3, :3]) - 1.0) / 2.0
    deg = float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))).max())
    if mm > CHECK_MM or deg > CHECK_DEG:
        raise PlanningError(
            f"the emitted {post} program misses FK of its joint values by {mm:.3g} mm, "
            f"{deg:.3g} deg; nothing written"
        )
    return mm
