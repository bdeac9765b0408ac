"""The summary of a plan: the table ``weldplan plan`` prints at the end of a run, the rows of
each stage, and the lines of a partial plan."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any


def _tool_route(route: Any) -> Any:
    """The route's tool section, typed (:class:`~weldplan.robot.program.ToolRoute`)."""
    from weldplan.robot.program.toolroute import ToolRoute

    return ToolRoute.of(route)


def _gap_rounds(g: Any) -> str:
    """The converging rounds of the lazy costs (:func:`weldplan.weld.converge.close_gap`)."""
    if not g:
        return ""
    return f"; {g['rounds']} gap round(s) planned {g['pairs_planned']} more pair(s) ({g['reason']})"


def _gaps(route: Any) -> str:
    """The gap to the straight-line bound, and to the tighter bounds that the reader can use."""
    if len(route.joint_ids) < 2 or not route.lower_bound > 0:
        return "n/a"
    parts = [
        f"{100 * route.gap:.2f} % over the straight-line bound",
    ]
    b = route.stats.get("bound_virtual")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.inner_length / b - 1):.2f} % between virtual joints over their own "
            f"straight-line bound ({b:.2f} mm)"
        )
    b = route.stats.get("bound_with_approaches")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound with approaches ({b:.2f} mm)"
        )
    b = route.stats.get("bound_planned")
    if b is not None and b == b and b > 0:
        how = route.stats.get("bound_planned_method", "")
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound of the planned legs "
            f"({b:.2f} mm, {how})"
        )
    return "; ".join(parts)


def _skipped_rows(route: Any) -> list[tuple[str, str]]:
    """One row per joint left out by ``--skip-unreachable``."""
    skipped = route.stats.get("skipped") or []
    if not skipped:
        return []
    rows = [("skipped", f"{len(skipped)} joint(s), not in the route (exit code 3)")]
    rows += [(f"  {s['id']}", s["reason"]) for s in skipped]
    return rows


def smooth_rows(route: Any) -> list[tuple[str, str]]:
    """The smoothing's totals (``--smooth``), and one row per leg whose polyline was kept."""
    sm = route.stats.get("smooth")
    if not sm:
        return []
    c = sm["clearance"]
    k = sm["max_curvature"]
    line = (
        f"{sm['smoothed']} of {sm['curved']} curved legs smoothed ({len(route.legs)} legs, "
        f"{len(route.legs) - sm['curved']} straight between their virtual joints)"
    )
    if sm["smoothed"]:
        radius = f", radius {1 / k:.2f} mm" if k > 0 else ""
        m = sm["min_clearance_margin"]
        line += (
            f"; max curvature {k:.4f} 1/mm{radius}; min clearance {c + m:.3f}"
            f" mm (margin {m:.3f} mm over {c:g}); smooth length "
            f"{sm['length']:.2f} mm ({sm['length'] - route.length:+.2f}); spacing <= "
            f"{sm['spacing']:g} mm"
        )
    rows = [("smooth", line)]
    rows += [
        (f"  leg {f['leg']}", f"{f['from_id']} -> {f['to_id']}: {f['status']}")
        for f in sm["legs"]
        if f["curved"] and not f["smoothed"]
    ]
    return rows


def clock_caps(route: Any) -> list[str]:
    """What in this run depended on the clock or on an unseeded search, so that the same
    command may write other files (empty: every search was budgeted by work and seeded).

    Read from the route's figures: the sequencer (fast-tsp has no seed; a ``--sequence-time``
    budget), a clock budget of the local planner, the route stage's CPU-time safety nets that
    were spent (a pair's refinement, the 1-tree bounds: ``stats["clock_stops"]``), the gun's
    SE(3) re-plans and the robot's joint-space transfers that the clock safety net stopped."""
    s, cfg = route.stats, route.settings
    caps = []
    if str(s.get("sequence_method", "")).startswith("fast-tsp"):
        caps.append("the weld order came from fast-tsp (no seed)")
    for key, what in (("sequence_time_budget", "sequencer"), ("local_time_budget", "local paths")):
        if cfg.get(key) is not None:
            caps.append(f"the {what} had a clock budget ({cfg[key]:g} s)")
    if cfg.get("planner") == "ompl" and cfg.get("local_time_budget") is None and s.get(
        "pairs_planned"
    ):  # BIT* runs for its time, not for a count of states
        from weldplan.weld.local_ompl import DEFAULT_TIME_S

        caps.append(f"the local paths of --planner ompl had a clock budget ({DEFAULT_TIME_S:g} s)")
    caps += _route_clock_stops(s.get("clock_stops") or {})
    tr = _tool_route(route)
    runs = (tr.transitions.stats.get("se3_runs") or []) if tr.transitions is not None else []
    n = sum(bool(r.get("clock")) for r in runs)
    if n:
        caps.append(f"{n} SE(3) re-plan(s) of the gun stopped by the clock")
    ompl = (tr.robot.route.stats.get("ompl") or {}) if tr.robot is not None else {}
    if ompl.get("clock"):
        caps.append(f"{int(ompl['clock'])} joint-space transfer(s) stopped by the clock")
    return caps


def _route_clock_stops(stops: dict[str, Any]) -> list[str]:
    """The route stage's CPU-time safety nets that were spent (``Route.stats["clock_stops"]``)."""
    caps = []
    pairs = stops.get("refine_pairs") or []
    if pairs:
        shown = ", ".join(pairs[:5]) + (", ..." if len(pairs) > 5 else "")
        caps.append(f"{len(pairs)} local path refinement(s) stopped by their CPU cap ({shown})")
    for key, what in (("lower_bound", "straight-line"), ("bound_planned", "planned-leg")):
        if stops.get(key):
            caps.append(f"the {what} 1-tree bound stopped by its CPU cap")
    return caps


def _reproducible(route: Any) -> str:
    caps = clock_caps(route)
    if not caps:
        return "yes: every search seeded and budgeted by work"
    return "NOT reproducible, the same command may write other files: " + "; ".join(caps)


def summary_table(
    route: Any,
    times: dict[str, float],
    outputs: dict[str, Path],
    *,
    title: str,
    report: Any,
    note: str | None = None,
    extra: list[tuple[str, str]] | None = None,
) -> str:
    """The table printed at the end of a run (``extra``: rows after ``verified``)."""
    s = route.stats
    rows = [
        (
            "joints",
            f"{len(route.joint_ids)}"
            + (
                f" ({len(route.order)} in the route)"
                if len(route.order) < len(route.joint_ids)
                else ""
            ),
        ),
        ("pairs", f"{s['pairs']} ({s['pairs_straight']} straight, {s['pairs_blocked']} blocked)"),
        (
            "pairs planned",
            f"{s['pairs_planned']} of {s['pairs_blocked']} blocked "
            f"({route.settings['planner']}, {s['rounds']} sequencing rounds"
            + (f", {s['pairs_failed']} failed" if s["pairs_failed"] else "")
            + ")",
        ),
        ("sequencer", f"{s['sequence_method']}" + _gap_rounds(s.get("gap_rounds"))),
        (
            "route length",
            f"{route.length:.2f} mm ({route.inner_length:.2f} mm between virtual joints "
            f"+ {route.approach_length:.2f} mm of approaches to the weld spots)",
        ),
        ("lower bound", f"{route.lower_bound:.2f} mm ({route.lower_bound_method})"),
        ("gap", _gaps(route)),
        ("order", "-".join(route.order)),
        *_skipped_rows(route),
        *smooth_rows(route),
        ("verified", report.describe()),
        *(extra or []),
        ("reproducible", _reproducible(route)),
        (
            "time",
            ", ".join(f"{k} {v:.2f} s" for k, v in times.items()),
        ),
        ("written", ", ".join(str(p) for p in outputs.values())),
    ]
    w = max(len(k) for k, _ in rows)
    lines = [title, "-" * len(title)] + [f"{k:<{w}}  {v}" for k, v in rows]
    if note:
        lines.append(note)
    return "\n".join(lines)


def plan_rows(plan: Any) -> list[tuple[str, str]]:
    """The rows of the tool and robot stages of ``plan`` (after ``verified``)."""
    if plan.poses is None:
        return []
    from weldplan.station.toolstage import tool_checks

    rows = pose_rows(plan.route, tool_checks(plan.poses, plan.transitions))
    if plan.robot is None:
        return rows
    joint, build = plan.robot, plan.program
    rr = joint.robot_route
    rows += robot_rows(rr, build) + order_rows(plan.route, joint.gun, rr)
    rows += reach_rows(joint.reach) + cost_rows(plan.route, build.timing.total)
    return rows


def partial_lines(plan: Any) -> list[str]:
    """One line per cause of a partial plan: joints skipped, welds without a free tool pose,
    tool transitions blocked, welds not in the robot program."""
    route = plan.route

    def listed(ids: list[str]) -> str:
        return ", ".join(ids[:10]) + (", ..." if len(ids) > 10 else "")

    out = []
    skipped = [s["id"] for s in route.stats.get("skipped") or []]
    if skipped:
        out.append(f"partial route: {len(skipped)} joint(s) skipped ({listed(skipped)})")
    if plan.poses is not None:
        missed = [str(p.id) for p in plan.poses.poses.poses if not p.ok]
        if missed:
            out.append(f"{len(missed)} weld(s) without a free tool pose ({listed(missed)})")
    if plan.transitions is not None:
        blocked = [f"{t.from_id}->{t.to_id}" for t in plan.transitions.path.blocked]
        if blocked:
            out.append(
                f"{len(blocked)} tool transition(s) blocked for the swept tool ({listed(blocked)})"
            )
    if plan.robot is not None and not out:
        gun = plan.robot.gun
        unposed = () if gun is None else tuple(i for i in route.order if i not in gun.route.order)
        left = (*plan.program.skipped, *unposed)
        if left:
            out.append(f"{len(left)} weld(s) not in the robot program")
    return out


def transition_rows(path: Any, check: Any) -> list[tuple[str, str]]:
    """Summary rows of the transitions (:class:`~weldplan.tool.transitions.ToolPath`, None: none):
    free / total, re-planned, length and rotation versus the point-tip order, and each blocked
    transition."""
    if path is None:
        return []
    sweeps = getattr(check, "sweeps", None)
    n = len(path.transitions)
    est = path.stats.get("point_order")
    rows = [
        (
            "tool transitions",
            f"{n - len(path.blocked)} / {n} free for the swept tool ("
            + ", ".join(f"{k} {v}" for k, v in path.by_via().items() if k != "blocked")
            + f"); retract {path.settings['retract']:g} mm, side exit "
            f"{path.settings.get('side_exit', 0):g} mm"
            + (f"; re-checked: {sweeps.describe()}" if sweeps is not None else ""),
        ),
        (
            "tool path",
            f"{path.length:.1f} mm, orientation change {path.rotation:.1f} deg, order "
            f"{path.stats.get('order_from', '?')}"
            + (
                f" (estimated on direct transitions: point-tip order {est['length']:.1f} mm, "
                f"{est['rotation_deg']:.1f} deg; tool order "
                f"{path.stats['tool_order']['length']:.1f} mm, "
                f"{path.stats['tool_order']['rotation_deg']:.1f} deg)"
                if est
                else ""
            ),
        ),
    ]
    rows += [(f"  {t.from_id}->{t.to_id}", f"blocked; {t.reason}") for t in path.blocked]
    return rows


def pose_rows(route: Any, check: Any) -> list[tuple[str, str]]:
    """Summary rows of the pose stage: the tool, welds reached, and each miss."""
    tr = _tool_route(route)
    poses = tr.poses
    n = len(poses.poses)
    rows = [
        ("tool", f"{poses.tool}, sha256 {tr.provenance['file_sha256'][:12]}"),
        (
            "tool poses",
            f"{poses.n_ok} / {n} welds with a free pose (re-checked: {check.checked} ok poses, "
            f"fresh FCL models); total orientation change {poses.total_rotation:.1f} deg"
            + ("" if poses.n_ok == n else "; exit code 3"),
        ),
    ]
    rows += [
        (f"  weld {p.id}", f"no free pose; {p.miss.describe()}" if p.miss else "no free pose")
        for p in poses.poses
        if not p.ok
    ]
    return rows + transition_rows(tr.transitions, check)


def robot_rows(rr: Any, build: Any) -> list[tuple[str, str]]:
    """Summary rows of the robot stage: the robot and its base, the route, each weld left out,
    the cycle time, the program."""
    tt = build.timing
    x, y, z, yaw = rr.stats.get("placement", {}).get("base_xyz_yaw", [math.nan] * 4)
    legs = tt.leg_times()
    miss = [
        (f"  weld {w}", f"not welded: {s.replace('_', ' ')}" + (f"; {d}" if d else ""))
        for w, s, d in zip(rr.weld_ids, rr.status, rr.detail or [""] * len(rr.status), strict=True)
        if s != "ok"
    ]
    targets = build.program.targets
    return [
        ("robot", f"{rr.robot}, base ({x:.0f}, {y:.0f}, {z:.0f}) mm yaw {yaw:.1f} deg"),
        (
            "robot route",
            f"{rr.n_ok} / {len(rr.status)} welds, {len(rr.flips)} branch flip(s), "
            f"{len(rr.replanned)} leg(s) re-planned in joint space, collision-free "
            f"{rr.stats.get('collision_free', 'not checked')} ({floor_words(rr.stats)})"
            + (f"; {len(miss)} weld(s) not in the program (exit code 3)" if miss else ""),
        ),
        *miss,
        *_walk_rows(rr),
        (
            "cycle time",
            f"{tt.total:.2f} s ({tt.motion_time:.2f} s moving, {tt.weld_time:g} s a weld; legs "
            f"{', '.join(f'{v:.2f}' for v in legs[:6])}{' ...' if len(legs) > 6 else ''} s); "
            f"at a constant {build.tcp_speed:g} mm/s TCP: {build.constant_speed_time:.2f} s",
        ),
        (
            "program",
            f"{sum(t.move == 'linear' for t in targets)} linear and "
            f"{sum(t.move == 'joint' for t in targets)} joint moves, "
            f"{sum(t.blend >= 0.3 for t in targets)} fly-by points; the timed path "
            f"within {tt.deviation:.1e} rad of the joint path, its TCP up to "
            f"{build.tcp_deviation:.2f} mm off the linear moves' lines",
        ),
    ]


def floor_words(stats: dict[str, Any]) -> str:
    """What the robot route was checked against, the floor said: the floor it names
    (``stats["floor_z"]``, mm), or that none was given. A searched base without a floor stands on
    the part's lowest point, where the part may not stand on the floor (a fixture): no floor is
    known there and none is checked (docs/robot-route.md, "The robot against itself and the
    floor"); ``--floor-z`` or the station's ``floor_z`` gives one."""
    z = stats.get("floor_z")
    if z is None:
        return "part, self-collision; no floor given, none checked: --floor-z gives one"
    return f"part, self-collision, the floor at z {z:.0f} mm"


def _walk_rows(rr: Any) -> list[tuple[str, str]]:
    """The summary row of the walk over the welds: its work and the welds it left out, by
    cause (:class:`weldplan.robot.route.WalkStats`)."""
    from weldplan.robot.route.walkstats import WalkStats

    walk = rr.stats.get("walk")
    return [("robot walk", WalkStats.from_dict(walk).describe())] if walk else []


def _ends(rr: Any) -> str:
    """How the detours left and reached their welds (``stats["detour_ends"]``), as
    ``"; welds left or reached: 2 by a gun exit, 4 by a retract"``."""
    ends = rr.stats.get("detour_ends") or {}
    if not ends:
        return ""
    return "; welds left or reached: " + ", ".join(f"{v} by a {k}" for k, v in ends.items())


def _legs(rr: Any, gun: Any) -> list[tuple[str, str, str]]:
    """``(from, to, how)`` of each leg between consecutive served welds."""
    from weldplan.robot.route.gunpath import legs_taken

    served = [w for w, s in zip(rr.weld_ids, rr.status, strict=True) if s == "ok"]
    taken = legs_taken(gun.via, rr.status, rr.replanned)
    return [(a, b, k) for a, b, k in zip(served[:-1], served[1:], taken, strict=True)]


def _legs_line(rr: Any, gun: Any) -> str:
    """How each leg between served welds goes, in one line."""
    from collections import Counter

    legs_by = _legs(rr, gun)
    taken = Counter(k for _, _, k in legs_by)
    gun_legs = {k[4:]: v for k, v in taken.items() if k.startswith("gun ")}
    detoured = [f"{a}->{b}" for a, b, k in legs_by if k == "detour"]
    return (
        f"{sum(gun_legs.values())} along the gun's transitions"
        + (f" ({', '.join(f'{k} {v}' for k, v in gun_legs.items())})" if gun_legs else "")
        + f", {taken['detour']} detoured (leave, joint-space transfer, approach"
        + (f": {', '.join(detoured)}" if detoured else "")
        + _ends(rr)
        + f"), {taken['joint']} by one joint motion where the gun's transition is blocked"
    )


def order_rows(route: Any, gun: Any, rr: Any) -> list[tuple[str, str]]:
    """Summary rows: the order the program follows (and why, when it is not the point-tip
    route's), how each leg between served welds goes, and the welds the tool never reaches."""
    if gun is None:
        return []
    order = gun.route.order
    pt = tuple(i for i in route.order if i in set(order))
    why = (
        "the tool stage's order, the same as the point-tip route's"
        if pt == order
        else f"the tool stage's order, not the point-tip route's ({'-'.join(pt)}): the gun's "
        "transitions were planned and checked between consecutive welds of the tool order, "
        "which avoids the pairs found blocked for the gun"
    )
    rows = [("robot order", f"{'-'.join(order)}: {why}"), ("robot legs", _legs_line(rr, gun))]
    rows += [
        (f"  weld {i}", "not welded: no tool pose (the tool never reaches it)")
        for i in route.order
        if i not in order
    ]
    return rows


def reach_rows(reach: Any) -> list[tuple[str, str]]:
    """The summary row of the robot's reach test in the pose choice."""
    if reach is None:
        return []
    t = reach.accept
    why = ", ".join(f"{k} {v}" for k, v in t.vetoes.most_common())
    base = "searched on the poses chosen without the robot" if reach.placement else "given"
    return [
        (
            "robot reach test",
            f"{t.calls} gun pose(s) judged, {sum(t.vetoes.values())} vetoed"
            + (f" ({why})" if why else "")
            + f"; base {base} ({reach.seconds:.1f} s)",
        )
    ] + base_trial_rows(reach.placement)


def base_trial_rows(placement: Any) -> list[tuple[str, str]]:
    """Per base the search's transfer trial judged, what it leaves out and why
    (:class:`weldplan.robot.placement.base.BaseVerdict`), under a row that says whether any
    of them joins every weld."""
    verdicts = () if placement is None else placement.verdicts
    if not verdicts:
        return []
    judged = [v for v in verdicts if v.joined >= 0]
    n = verdicts[0].served + len(verdicts[0].unserved)  # the welds of the search's route
    whole = [v for v in judged if v.joined == n]
    head = (
        f"{len(whole)} of the {len(judged)} base(s) judged join all {n} welds"
        if whole
        else f"none of the {len(judged)} base(s) judged joins all {n} welds"
    )
    rows = [
        (
            "base trial",
            f"{head} (free legs, straight or tucked transfers between retracts; on the poses "
            "chosen without the robot: the detours still try a split leg)",
        )
    ]
    for v in verdicts:
        x, y, z, yaw = v.base
        rows.append((f"  base {x:.0f},{y:.0f},{z:.0f},{yaw:.1f}", v.line()))
    return rows


def cost_rows(route: Any, cycle: float | None) -> list[tuple[str, str]]:
    """The summary row of ``cost = "time"``: seconds of the order, the proved bound, the gap of
    the timed cycle (``cycle``, s) to it."""
    st = route.stats.get("cost_time")
    if not st:
        return []
    b = st["time_bound"]
    timed = (
        f"; timed cycle {cycle:.2f} s, {100 * (cycle / b - 1):.1f} % over the bound"
        if cycle is not None and b > 0 and math.isfinite(cycle)
        else ""
    )
    return [
        (
            "cost time",
            f"order {st['time_cost']:.2f} s (rest-to-rest bounds on IK branch "
            f"{st['station_branch']}, {st['weld_time']:g} s a weld); proved bound {b:.2f} s "
            f"({st['time_bound_method']}, any order and configuration){timed}",
        )
    ]


def station_rows(splan: Any, plans: tuple[Any, ...]) -> list[tuple[str, str]]:
    """The rows of a station of several robots (:class:`weldplan.multi.station.StationPlan`;
    ``plans``: each robot's plan as written, :func:`weldplan.multi.saved.robot_plans`): per
    robot its welds, timed cycle, utilisation, waiting and interlocks; the station's cycle
    beside the allocation's, its lower bound and the baselines; the interference line."""
    a, s = splan.allocation, splan.schedule
    rows = []
    for r, name in enumerate(a.robots):
        p = plans[r]
        if p is None:
            rows.append((f"robot {name}", "idle: no weld allocated"))
            continue
        build = p.program
        sets = sum(x.action == "set" for x in build.program.signals)
        waits = len(build.program.signals) - sets
        left = len(p.partial())
        busy = f", utilisation {s.utilisation[r]:.0%}, waiting {s.waiting[r]:.2f} s" if s else ""
        gone = f" ({left} cause(s) of welds left out)" if left else ""
        cycle = build.timing.total if s is None else s.cycle_times[r]
        rows.append((
            f"robot {name}",
            f"{len(a.shares[r].order)} welds{gone}, cycle {cycle:.2f} s{busy}; "
            f"interlocks: {sets} set, {waits} wait",
        ))  # fmt: skip
    top = splan.cycle_time if s is None else s.cycle_time
    rows.append(("station cycle", f"{top:.2f} s timed (the last robot's end, waits counted)"))
    rows.append(("allocation", "the cycles of the leg-time model it minimised, beside its bound:"))
    rows += [("", line) for line in splan.report.lines()]
    rows.append(("interference", interference_line(splan)))
    return rows


def interference_line(splan: Any) -> str:
    """What the station plan says of robot-robot interference: the replay's verdict, or that
    it was not checked."""
    v = splan.replay
    if v is None:
        return splan.interference
    dist = "no motions overlap" if v.min_distance == float("inf") else (
        f"min robot-robot distance {v.min_distance:.1f} mm"
    )  # fmt: skip
    state = "ok" if v.ok else "FAILED"
    return (
        f"replay {state}: {v.pairs} overlapping motion pairs, {dist} (clearance {v.clearance:g} mm)"
    )


def station_partial(splan: Any, plans: tuple[Any, ...]) -> list[str]:
    """One line per cause of exit 3: welds no robot reaches, welds a robot's plan left out,
    a replay that found robots too close."""
    out = []
    un = splan.allocation.unreached
    if un:
        out.append(f"{len(un)} weld(s) no robot reaches ({', '.join(u.weld for u in un[:10])})")
    for name, p in zip(splan.allocation.robots, plans, strict=True):
        out += [] if p is None else [f"{name}: {line}" for line in p.partial()]
    if splan.replay is not None and not splan.replay.ok:
        out.append(f"the replay found robots too close: {interference_line(splan)}")
    return out
