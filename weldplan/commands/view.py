"""``weldplan view ROUTE MESH``: the route in meshcat, live or as a static page."""

from __future__ import annotations

import argparse
import time

from weldplan.commands.plan import add_cell_arguments

HELP = "show a route JSON over its part in meshcat (live server, or --html for a static page)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("route", help="route JSON written by `weldplan plan --json`")
    p.add_argument("mesh", nargs="?", help="the part mesh (optional: without it, the route only)")
    add_cell_arguments(p)
    p.add_argument("--html", metavar="F", help="write a self-contained page instead of serving")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser")


def run(args: argparse.Namespace) -> int:
    from weldplan.io.export import read_route

    route = read_route(args.route)
    part = None
    if args.mesh:
        from weldplan.io.mesh import load_part

        part = load_part(args.mesh, units=args.units, scale=args.scale, length=args.length)
    if args.html:
        from weldplan.viz.viewer import write_html

        write_html(route, part, args.html)
        print(f"wrote {args.html}")
        return 0
    from weldplan.viz.viewer import view_route

    vis = view_route(route, part)
    print(f"meshcat viewer at {vis.url()} (Ctrl-C to stop)")
    if not args.no_browser:
        vis.open()
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        return 0
