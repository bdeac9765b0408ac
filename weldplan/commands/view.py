"""``weldplan view ROUTE MESH``: the route in meshcat, live, as a static page or as a PNG.

``weldplan view route_station.json``: a station of several robots, its page rebuilt from the
saved files (:meth:`weldplan.multi.saved.SavedStationPlan.page_text`: the station file's part,
robots and tools, each robot's trajectory CSV, the schedule), as ``weldplan plan --html``
writes it; live, the same scene without the Gantt chart."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from weldplan.commands.plan import add_cell_arguments

HELP = (
    "show a route JSON over its part, or a station JSON of several robots, in meshcat (live "
    "server, --html for a static page, --png for a picture)"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "route",
        help="route JSON written by `weldplan plan --json`, or the station JSON of a station "
        "of several robots (route_station.json)",
    )
    p.add_argument(
        "mesh",
        nargs="?",
        help="the part mesh (optional: without it, the route only; not with a station JSON)",
    )
    add_cell_arguments(p)
    p.add_argument("--html", metavar="F", help="write a self-contained page instead of serving")
    p.add_argument(
        "--png", metavar="F", help="write a picture of the page instead of serving (needs Chromium)"
    )
    p.add_argument("--no-browser", action="store_true", help="do not open a browser")
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the live viewer listens on (default 127.0.0.1, this machine only; "
        "0.0.0.0 opens it to the network)",
    )
    p.add_argument("--port", type=int, help="web port of the live viewer (default: 7000 or next)")
    p.add_argument(
        "--station",
        metavar="TOML",
        help="with a station JSON: the station file (default: the one the plan records)",
    )
    from weldplan.commands._tool import add_tool_arguments

    add_tool_arguments(p, search=False)


def run(args: argparse.Namespace) -> int:
    from weldplan.commands._tool import tool_from_args
    from weldplan.io.export import read_route
    from weldplan.multi.saved import is_station_json

    if args.png:  # no Chromium: say so before any work
        from weldplan.viz.png import find_chromium

        find_chromium()
    if is_station_json(args.route):
        return _view_station(args)
    route = read_route(args.route)
    tool = tool_from_args(args)
    if tool is not None:  # draw the route's poses only with the tool they were planned for
        from weldplan.tool.verify.check_route import check_tool_provenance

        check_tool_provenance(route, tool[1], args.route)
    part = None
    if args.mesh:
        from weldplan.cellframe import recorded_pose
        from weldplan.io.mesh import load_part

        part = load_part(args.mesh, units=args.units, scale=args.scale, length=args.length)
        pose = recorded_pose(route.provenance, None, part, path=args.route)
        if pose is not None:  # a route planned in the cell: the part drawn where it stood
            part = pose.mesh_to_cell(part)
    if args.html or args.png:
        from weldplan.viz.viewer import static_html

        mounted = None if tool is None else tool[0]
        return _write_pages(args, lambda: static_html(route, part, tool=mounted))
    from weldplan.viz.viewer import live_view

    vis, server = live_view(
        route, part, host=args.host, port=args.port, tool=None if tool is None else tool[0]
    )
    return _serve(vis, server, args.no_browser)


def _view_station(args: argparse.Namespace) -> int:
    """A station JSON: its page rebuilt from the saved files, written (``--html``, ``--png``)
    or served live (the scene without the chart); its allocate-plan rounds, one line each, on
    stdout first (none for a file written before they were recorded)."""
    from weldplan.errors import WeldplanError
    from weldplan.multi.saved import load_station_plan

    if args.mesh is not None:
        raise WeldplanError(f"{args.route} is a station JSON: give no mesh (its station names it)")
    saved = load_station_plan(args.route)
    for line in saved.rounds_lines():
        print(line)
    if args.station is not None:
        from weldplan.station.load import load_station

        station = load_station(args.station)
    else:
        station = saved.load_station()
    if len(station.robots) != len(saved.robots):
        from weldplan.errors import InputError

        raise InputError(
            f"the station has {len(station.robots)} robots, the plan {len(saved.robots)}",
            path=saved.path, field="robots",
        )  # fmt: skip
    if args.html or args.png:
        return _write_pages(args, lambda: saved.page_text(station=station))
    return _serve_station(args, saved, station)


def _serve_station(args: argparse.Namespace, saved: Any, station: Any) -> int:
    """The station's scene (:func:`weldplan.viz.station_page.build_station_scene`) on a live
    meshcat server until Ctrl-C."""
    import contextlib
    import io

    import meshcat

    from weldplan.viz.live import MeshcatServer
    from weldplan.viz.station_page import (
        build_station_scene,
        saved_station_part,
        saved_station_robots,
    )

    robots = saved_station_robots(saved, station)
    part = saved_station_part(station)
    server = MeshcatServer(args.host, args.port)
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
            vis = meshcat.Visualizer(zmq_url=server.zmq_url)
        build_station_scene(vis, robots, saved.schedule, part=part)
    except BaseException:
        server.close()
        raise
    return _serve(vis, server, args.no_browser)


def _write_pages(args: argparse.Namespace, render: Callable[[], str]) -> int:
    """Write ``--html`` and ``--png`` as one set (both or neither), checked before ``render``
    makes the page's text."""
    from weldplan.io.outputset import check_outputs, write_outputs

    paths = {k: Path(getattr(args, k)) for k in ("html", "png") if getattr(args, k)}
    check_outputs(paths)
    page = render()
    files: dict[Path, str | bytes] = {}
    if "html" in paths:
        files[paths["html"]] = page
    if "png" in paths:
        from weldplan.viz.png import png_bytes

        files[paths["png"]] = png_bytes(page)
    write_outputs(files)
    print("wrote " + ", ".join(str(p) for p in files))
    return 0


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def _serve(vis: Any, server: Any, no_browser: bool) -> int:
    """Keep the viewer up until Ctrl-C or SIGTERM (exit 0) or until its server dies (exit 1);
    the server process is stopped on the way out in every case."""
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        print(f"meshcat viewer at {server.web_url} (Ctrl-C to stop)", flush=True)
        if not no_browser:
            vis.open()
        while server.proc.poll() is None:
            time.sleep(0.2)
        print(
            f"weldplan view: the meshcat server stopped ({server.proc.returncode})", file=sys.stderr
        )
        return 1
    except KeyboardInterrupt:
        return 0
    finally:
        signal.signal(signal.SIGTERM, previous)
        with contextlib.suppress(Exception):
            vis.window.zmq_socket.close(linger=0)
        server.close()
