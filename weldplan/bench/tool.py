"""``weldplan bench tool``: the gun's planning time against the point tip's, and its reach.

Target (issue 16): a 200-joint car2 station planned with the gun in at most 2 x the point-tip
planning time on 2 cores. For each station, from one run:

- point tip: building the cell and planning the verified point-tip route (``plan_route``);
- gun: the same plus the pose search (:func:`~weldplan.tool.poses.plan_weld_poses`, which
  re-checks every chosen pose), the independent re-check of all poses
  (:func:`~weldplan.tool.verify.verify_poses`), the order on the tool's costs
  (:func:`~weldplan.tool.transitions.tool_order`), the transitions of the swept gun
  (:func:`~weldplan.tool.transitions.plan_transitions`) and their independent re-check
  (:func:`~weldplan.tool.verify.verify_sweeps`): what ``weldplan plan --tool`` runs
  (``--no-transitions``: the poses only);
- the ratio of the two, welds with a verified pose / total (and how many of those are turned
  over), transitions free / total by how they go (axial retract, slide along the flange, side
  exit, SE(3) re-plan), the tool path's length and orientation change against the point-tip
  route's length and the orientation change of its welds' poses in the point-tip order.

car2 is ``../shared/data/bodies/car2.obj`` scaled to 4500 mm with the committed synthetic
stations ``assets/car2/car2_synthetic_{50,200}.csv`` (docs/bench-scale.md). Writes ``tool.md``
into ``--out`` (and each station's poses as JSON with ``--json``). Timings are wall clock on
whatever machine runs it; the load average is recorded beside them, and the process's CPU
seconds (``time.process_time``: less sensitive to other sessions on a shared machine; the gun's
include the point tip's and the tool order's) with their ratio.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import time
from pathlib import Path
from typing import Any

from weldplan.tool.settings import DEFAULT_SE3_TIME

HELP = (
    "gun poses and transitions vs point-tip planning time (target <= 2x on car2 200), "
    "reach per station"
)

ROOT = Path(__file__).resolve().parents[2]
#: the car2 body in the shared data (../shared/data relative to the repository root)
CAR2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"
#: car2's length in the stations (mm), as docs/bench-scale.md
CAR2_LENGTH_MM = 4500.0
#: the target of issue 16: gun time / point-tip time on a 200-joint station
TARGET_RATIO = 2.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--stations", default="demo,car2_50,car2_200", help="comma list: demo, car2_50, car2_200"
    )
    p.add_argument(
        "--one-side",
        action="store_true",
        help="do not try the gun turned over (the reach before issue 16's second round)",
    )
    p.add_argument(
        "--whole-part",
        action="store_true",
        help="check against one BVH of the whole part instead of a crop per weld",
    )
    p.add_argument("--json", action="store_true", help="also write each station's poses JSON")
    p.add_argument(
        "--no-transitions", action="store_true", help="time the poses only (no transitions)"
    )
    p.add_argument(
        "--se3-time",
        type=float,
        default=DEFAULT_SE3_TIME,
        help="OMPL CPU seconds per blocked transition (default 10; 0: off)",
    )
    p.add_argument(
        "--no-exit-check",
        dest="exit_check",
        action="store_false",
        help="choose the poses without the exit test (weldplan.tool.poses.exits; the choice before "
        "it)",
    )
    p.add_argument(
        "--exits",
        default="lift,axial,side",
        help="the exits the exit test counts, in the order tried (weldplan.tool.poses.exits)",
    )
    p.add_argument(
        "--order-axial",
        action="store_true",
        help="price every leg of the tool order as the axial retract, also where the exit test "
        "found a lift (the estimate before the exit test)",
    )


def _load() -> str:
    try:
        return " ".join(f"{v:.1f}" for v in os.getloadavg())
    except OSError:  # pragma: no cover
        return "n/a"


def _cell(name: str) -> Any:
    import weldplan

    if name == "demo":
        return weldplan.demo_cell()
    size = name.split("_", 1)[1]
    joints = ROOT / "assets" / "car2" / f"car2_synthetic_{size}.csv"
    if not CAR2.is_file():
        raise SystemExit(f"weldplan bench tool: {CAR2} not found (the shared data)")
    return weldplan.load_cell(CAR2, joints, length=CAR2_LENGTH_MM)


def _station(name: str, gun: Any, args: argparse.Namespace) -> dict[str, Any]:
    import weldplan
    from weldplan.tool import plan_weld_poses, verify_poses
    from weldplan.tool.settings import PoseSearchSettings

    load0 = _load()
    t0, c0 = time.perf_counter(), time.process_time()
    cell = _cell(name)
    route = weldplan.plan_route(cell, rng=0)
    t_point, c_point = time.perf_counter() - t0, time.process_time() - c0
    t1 = time.perf_counter()
    exits = _exit_test(cell, route, gun, args)
    search = PoseSearchSettings(both_sides=not args.one_side, crop=not args.whole_part)
    poses = plan_weld_poses(cell, route, gun, search, accept=exits)
    if exits is not None:
        poses = dataclasses.replace(poses, stats={**poses.stats, **exits.stats()})
    t_poses = time.perf_counter() - t1
    t2 = time.perf_counter()
    ver = verify_poses(poses, cell.part, gun)
    t_verify = time.perf_counter() - t2
    reuse = None if exits is None else exits.planner
    tr = {} if args.no_transitions else _transitions(cell, route, poses, gun, args, reuse)
    gun_s = t_point + t_poses + t_verify + tr.get("transitions_s", 0.0) + tr.get("sweeps_s", 0.0)
    c_gun = time.process_time() - c0  # everything since the point tip's start, CPU
    misses = [p.miss for p in poses.poses if not p.ok and p.miss is not None]
    if args.json:
        out = Path(args.out)
        (out / f"tool-{name}.json").write_text(poses.to_json(), encoding="utf-8")
    return {
        **tr,
        "name": name,
        "n": len(poses.poses),
        "ok": poses.n_ok,
        "flipped": sum(p.ok and p.flipped for p in poses.poses),
        "misses_ahead": sum(m.contacts > 0 and m.tool_point[2] > 0 for m in misses),
        "misses_short": sum(m.contacts == 0 for m in misses),
        "no_miss": sum(not p.ok and p.miss is None for p in poses.poses),
        "rotation": poses.total_rotation,
        "verified": f"{'ok' if ver.ok else 'FAILED'} ({ver.checked})",
        "point_s": t_point,
        "poses_s": t_poses,
        "verify_s": t_verify,
        "gun_s": gun_s,
        "ratio": gun_s / t_point,
        "cpu": f"{c_point:.1f} / {c_gun:.1f} ({c_gun / c_point:.2f})",
        "stats": poses.stats,
        "notes": [(p.id, p.note) for p in poses.poses if p.note],
        "load": f"{load0} / {_load()}",
    }


def _transition_settings(args: Any) -> Any:
    """The transitions' settings of the bench, the same for the exit test's planner and the
    transitions (the defaults, seed 0, and ``--se3-time``)."""
    from weldplan.tool.settings import TransitionSettings

    return TransitionSettings(se3=args.se3_time > 0, time_s=max(args.se3_time, 1e-3), seed=0)


def _exit_test(cell: Any, route: Any, gun: Any, args: Any) -> Any:
    """The exit test (:class:`~weldplan.tool.poses.ExitTest`) with the planner the transitions
    use (same settings: :func:`_transitions`), or ``None`` with ``--no-exit-check``."""
    if not args.exit_check:
        return None
    from weldplan.tool.poses.exits import ExitTest
    from weldplan.tool.settings import DEFAULT_CONTACT_RADIUS
    from weldplan.tool.transitions.plan import TransitionPlanner

    planner = TransitionPlanner(
        cell.part, gun, _transition_settings(args), clearance=float(cell.clearance),
        contact_radius=DEFAULT_CONTACT_RADIUS,
    )  # fmt: skip
    return ExitTest(planner, route.order, tuple(e.strip() for e in args.exits.split(",")))


def _transitions(
    cell: Any, route: Any, poses: Any, gun: Any, args: Any, reuse: Any = None
) -> dict[str, Any]:
    """Order, transitions (re-ordered round blocked pairs, :mod:`weldplan.tool.transitions.reorder`)
    and their re-check for one station (timed together); ``reuse``: the exit test's planner."""
    from weldplan.tool.settings import OrderSettings
    from weldplan.tool.transitions.reorder import plan_ordered_transitions
    from weldplan.tool.verify.sweeps import verify_sweeps

    t0 = time.perf_counter()
    path = plan_ordered_transitions(
        cell.part, gun, poses, _transition_settings(args),
        OrderSettings(price_lifts=not args.order_axial), reuse=reuse,
    )  # fmt: skip
    t1 = time.perf_counter()
    sweeps = verify_sweeps(path, poses, cell.part, gun)
    t2 = time.perf_counter()
    free = [t for t in path.transitions if t.free]
    return {
        "transitions": len(path.transitions),
        "via": path.by_via(),
        "free_length": sum(t.length for t in free),
        "free_rotation": sum(t.rotation for t in free),
        "blocked": [f"{t.from_id}->{t.to_id}: {t.reason}" for t in path.blocked],
        "order_rounds": path.stats.get("order_rounds", 1),
        "sweeps": f"{'ok' if sweeps.ok else 'FAILED'} ({sweeps.checked})",
        "point_length": route.length,
        "transitions_s": t1 - t0,
        "sweeps_s": t2 - t1,
    }


def _transition_row(r: dict[str, Any]) -> str:
    v = r["via"]
    n = r["transitions"]
    return (
        f"| {r['name']} | {r['ok']} / {r['n']} | {n - v['blocked']} / {n} | {v['axial']} "
        f"| {v['slide']} | {v['side']} | {v['se3']} | {r['free_length']:.1f} "
        f"| {r['free_rotation']:.1f} | {r['point_length']:.1f} | {r['rotation']:.1f} "
        f"| {r['sweeps']} | {r['poses_s'] + r['verify_s']:.1f} | {r['transitions_s']:.1f} "
        f"| {r['sweeps_s']:.1f} |"
    )


def run(args: argparse.Namespace) -> int:
    from weldplan.tool import shared_spot_gun

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    gun = shared_spot_gun()
    side = "one side" if args.one_side else "both sides (turned over where needed)"
    side += f"; exit test: {args.exits}" if args.exit_check else "; no exit test"
    part = "whole-part BVH" if args.whole_part else "part cropped per weld"
    lines = [
        "# weldplan bench tool",
        "",
        f"{platform.node()} ({os.cpu_count()} CPUs); tool {gun.name}, {len(gun.faces)} "
        f"triangles, reach {gun.reach:.0f} mm; {side}; {part}.",
        f"Target: gun / point tip <= {TARGET_RATIO:g} on car2_200 (issue 16).",
        "",
        "| station | welds ok / total (turned over) | point tip s | gun s (poses + re-check; "
        "with transitions: + transitions + their re-check) "
        "| ratio | rotation deg | re-check | pose stages s: setup, crop, collide, choose, miss "
        "| CPU s point tip / gun (ratio) | load before / after |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    print("\n".join(lines), flush=True)
    notes: list[str] = []
    rows: list[str] = []
    for name in args.stations.split(","):
        r = _station(name.strip(), gun, args)
        s = r["stats"]
        stages = ", ".join(
            f"{s.get(k, float('nan')):.1f}"
            for k in ("setup_s", "broad_phase_s", "collide_s", "choose_s", "miss_s")
        )
        parts = [r["poses_s"], r["verify_s"]] + (
            [r["transitions_s"], r["sweeps_s"]] if "via" in r else []
        )
        row = (
            f"| {r['name']} | {r['ok']} / {r['n']} ({r['flipped']}) | {r['point_s']:.1f} "
            f"| {r['gun_s']:.1f} ({' + '.join(f'{x:.1f}' for x in parts)}) | {r['ratio']:.2f} "
            f"| {r['rotation']:.1f} | {r['verified']} | {stages} | {r['cpu']} | {r['load']} |"
        )
        lines.append(row)
        print(row, flush=True)
        if "via" in r:
            rows.append(_transition_row(r))
            notes += [f"- {r['name']} blocked {b}" for b in r["blocked"]]
            if r["order_rounds"] > 1:
                notes.append(
                    f"- {r['name']}: {r['order_rounds']} orders (re-ordered round blocked pairs)"
                )
        notes.append(
            f"- {r['name']}: {r['n'] - r['ok']} misses: {r['misses_ahead']} hit ahead of the TCP "
            f"(fixed electrode / lower arm: structure behind the sheet), {r['misses_short']} only "
            f"short of the clearance, {r['no_miss']} without a miss (must be 0); "
            f"{s['collision_queries']} collide, {s['distance_queries']} distance queries"
            + (
                f"; exit test: {s['exit_calls']} picks judged, {s['exit_vetoes']} vetoed, "
                f"{s['exit_samples']} samples, {s['accept_exhausted']} welds kept a pose "
                f"without an exit; vetoes by weld {s['exit_vetoed']}"
                if "exit_calls" in s
                else "; no exit test"
            )
        )
        notes += [f"- {r['name']} weld {w}: {note}" for w, note in r["notes"]]
    if rows:
        head = [
            "",
            "Transitions (shared gun, tool order, retract 50 mm, slide lifts 4/10/20 mm, side exit "
            f"250 mm, SE(3) {args.se3_time:g} CPU s each, one process): free / total "
            "by how they go; the free "
            "transitions' TCP length and rotation against the point-tip route's length and its "
            "welds' poses' rotation in the point-tip order; seconds for poses (+ re-check), "
            "transitions, their re-check.",
            "",
            "| station | welds ok | transitions free / total | axial | slide | side | SE(3) "
            "| tool path mm | tool rotation deg | point-tip mm | point-order rotation deg "
            "| re-check | poses s | transitions s | re-check s |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        lines += head + rows
        print("\n".join(head + rows))
    lines += [""] + notes
    print("\n".join(notes))
    (out / "tool.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return 0
