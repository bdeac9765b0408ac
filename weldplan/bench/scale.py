"""``weldplan bench scale``: station scale on car2 (issue 9), written as ``scale.md``.

Targets: 200 joints end to end within 60 s and 1000 within 10 min on a 2-core machine, peak
memory under 6 GB; pair-planning throughput at least 1.7x from one worker to two; route length
within 2 % of the reference route on the 200-joint set.

Every size runs in a fresh child process (so peak memory is its own): car2 scaled to 4500 mm, the
synthetic joint set of that size (``assets/car2``, labelled SYNTHETIC), the cell, then
:func:`~weldplan.weld.pipeline.plan_route` with candidate pairs, then verification.

The reference route for the length ratio (``--reference``, sizes up to ``--reference-max``):

``lazy``
    every pair checked straight (no candidates), blocked pairs planned when an order uses them
    (serial); quick, but it shares the candidates' blind spot: a blocked pair is costed by its
    straight-line estimate until an order uses it.
``all``
    every blocked pair searched (planned) up front on ``--jobs`` workers, the dense matrix the
    paper builds: the all-pairs route of the issue's target (on the 200-joint set: 17,884
    searches).
``none``
    no reference.

With a heuristic sequencer both routes are heuristic, so the ratio compares two runs of the same
seed. Throughput (``--workers``, default 1 and 2; ``--throughput-only`` skips the end-to-end runs)
plans the same batch of blocked pairs serially and on pools holding the cell. Timings are wall
clock on whatever machine runs it; the load average is written beside every figure.

``--joints N`` (issue #18 item 3) is the whole-body mode instead: the ``N``-joint set (4000:
the synthetic generator's ``whole-body`` profile), pair planning on Dask with each of
``--workers`` and the product path end to end with each of ``--e2e-workers``, with CPU seconds
and the peak RSS of the whole process tree (:mod:`weldplan.bench.scale_body`).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from weldplan.bench.common import CHILD_PRELUDE, conditions, run_child, shared_path, table
from weldplan.bench.scale_body import default_planner
from weldplan.weld.pipeline import SEQUENCERS

REFERENCES = ("lazy", "all", "none")

HELP = (
    "car2 station scale: 50/200/1000 synthetic joints end to end, 1 vs 2 workers; --joints "
    "4000: the whole-body station on Dask"
)

ASSETS = Path(__file__).resolve().parents[2] / "assets" / "car2"

_CHILD = (
    CHILD_PRELUDE
    + """
import logging, os, numpy as np
from weldplan.weld.cell import load_cell
from weldplan.weld.pipeline import PlanConfig, plan_route
from weldplan.weld.verify import verify_route
from weldplan.errors import PlanningError
logging.disable(logging.WARNING)
load0 = os.getloadavg()
t0 = time.perf_counter()
cell = load_cell({mesh!r}, {joints!r}, length=4500.0)
t_cell = time.perf_counter() - t0
cfg = PlanConfig(candidates={k}, candidate_radius={radius}, sequencer={seq!r},
    sequence_time_budget={sbud})
from weldplan.weld.parallel import process_pool
executor = None
if {jobs} > 1:
    executor = process_pool(cell, {jobs})
t1 = time.perf_counter()
try:
    route = plan_route(cell, config=cfg, rng=0, executor=executor)
except PlanningError as exc:  # e.g. joints no collision-free path reaches: a row, not a crash
    if executor is not None:
        executor.shutdown()
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(json.dumps(dict(n=len(cell.joints.ids), cell=t_cell, error=str(exc)[:300],
        plan=time.perf_counter() - t1, peak_mib=peak_mib(), child_peak_mib=kids,
        load_before=load0, load_after=os.getloadavg())))
    raise SystemExit(0)
t_plan = time.perf_counter() - t1
if executor is not None:
    executor.shutdown()
t2 = time.perf_counter()
rep = verify_route(route, cell.part, joints=cell.joints)
t_ver = time.perf_counter() - t2
load1 = os.getloadavg()
ref_len = float('nan')
ref_plan = float('nan')
ref_stats = {{}}
ref_ok = None
if {reference!r} != 'none':
    ref_cfg = PlanConfig(sequencer={seq!r}, sequence_time_budget={sbud},
        pairs='all' if {reference!r} == 'all' else 'lazy')
    ref_ex = None
    if {reference!r} == 'all' and {jobs} > 1:
        ref_ex = process_pool(cell, {jobs})
    t3 = time.perf_counter()
    ref = plan_route(cell, config=ref_cfg, rng=0, executor=ref_ex)
    ref_plan = time.perf_counter() - t3
    if ref_ex is not None:
        ref_ex.shutdown()
    ref_len = ref.length
    ref_stats = {{k: ref.stats[k] for k in ref.stats if k.startswith('pairs')}}
    ref_ok = bool(verify_route(ref, cell.part, joints=cell.joints).ok)
kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
s = route.stats
print(json.dumps(dict(n=len(cell.joints.ids), cell=t_cell, plan=t_plan, verify=t_ver,
    total=t_cell + t_plan + t_ver, length=route.length, lower_bound=route.lower_bound,
    ok=bool(rep.ok), violations=len(rep.violations), ref_length=ref_len, ref_plan=ref_plan,
    ref_stats=ref_stats, ref_ok=ref_ok, reference={reference!r}, load_before=load0,
    load_after=load1, load_ref=os.getloadavg(),
    peak_mib=peak_mib(), child_peak_mib=kids, grid=list(cell.grid.occupied.shape),
    stats={{k: s[k] for k in s if k.startswith('pairs') or k == 'rounds'}},
    seconds=s['seconds'])))
"""
)

_THROUGHPUT = (
    CHILD_PRELUDE
    + """
import logging, os, numpy as np
from weldplan.weld.cell import load_cell
from weldplan.weld.pipeline import _plan_pairs_task, candidate_pairs
from weldplan.weld.parallel import process_pool, share_cell, batches
from weldplan.bench.scale_body import default_pair_args, default_planner
logging.disable(logging.WARNING)
cell = load_cell({mesh!r}, {joints!r}, length=4500.0)
n = len(cell.joints.ids)
iu, ju = np.triu_indices(n, 1)
V = cell.virtual_xyz
cand = candidate_pairs(np.asarray(cell.joints.xyz), 6)
free = cell.collision.segments_free(V[iu[cand]], V[ju[cand]], cell.clearance)
todo = cand[~free][:{pairs}]
args = default_pair_args(iu, ju, todo)
res = dict(pairs=len(args), runs=[], planner=default_planner())
serial = None
for w in {workers}:
    l0 = os.getloadavg()
    if w == 1:
        c0 = resource.getrusage(resource.RUSAGE_SELF)
        t = time.perf_counter()
        got = _plan_pairs_task(cell, args, None)
        wall = time.perf_counter() - t
        c1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu = c1.ru_utime - c0.ru_utime + c1.ru_stime - c0.ru_stime
    else:
        k0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        with process_pool(cell, w) as ex:
            for f in [ex.submit(int, 0) for _ in range(w)]:
                f.result()  # workers started and holding the cell
            t = time.perf_counter()
            shared = share_cell(cell, ex)
            fs = [ex.submit(_plan_pairs_task, shared, b, None) for b in batches(args, w)]
            got = [lp for f in fs for lp in f.result()]
            wall = time.perf_counter() - t
        k1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # the workers, after shutdown
        cpu = k1.ru_utime - k0.ru_utime + k1.ru_stime - k0.ru_stime
    serial = serial or got
    same = all(np.array_equal(a.points, b.points) for a, b in zip(serial, got))
    res['runs'].append(dict(workers=w, wall=wall, cpu=cpu, same=same, load_before=l0,
        load_after=os.getloadavg()))
print(json.dumps(res))
"""
)


def _ints(text: str) -> list[int]:
    try:
        vals = [int(v) for v in text.split(",") if v.strip()]
    except ValueError as exc:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated integers, got {text!r}"
        ) from exc
    if not vals or min(vals) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers, got {text!r}")
    return vals


def _load(v: list[float]) -> str:
    return " ".join(f"{x:.2f}" for x in v)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--sizes", type=int, nargs="*", default=[50, 200, 1000], help="none: throughput only"
    )
    p.add_argument("--candidates", type=int, default=6, help="k nearest pairs per joint (6)")
    p.add_argument(
        "--candidate-radius", type=float, default=None, help="mm; farther neighbours on demand"
    )
    p.add_argument("--jobs", type=int, default=2, help="workers of the end-to-end runs (2)")
    p.add_argument("--sequencer", default="auto", choices=SEQUENCERS)
    p.add_argument(
        "--sequence-budget", type=float, default=None, help="seconds per sequencer polish run"
    )
    p.add_argument(
        "--reference",
        default="lazy",
        choices=REFERENCES,
        help="reference route of the length ratio: lazy (every pair checked straight, blocked "
        "ones planned when used), all (every blocked pair searched up front on --jobs workers; "
        "long), none",
    )
    p.add_argument(
        "--reference-max", type=int, default=200, help="largest size given a reference (200)"
    )
    p.add_argument("--pairs", type=int, default=120, help="pairs in the throughput batch (120)")
    p.add_argument(
        "--workers",
        type=_ints,
        default=[1, 2],
        help="throughput: worker counts to compare, comma-separated (1,2)",
    )
    p.add_argument(
        "--throughput-only",
        action="store_true",
        help="only the pair-planning throughput (1 vs 2 workers on the 200-joint set)",
    )
    p.add_argument("--quick", action="store_true", help="50 and 200 joints, 40 throughput pairs")
    p.add_argument(
        "--joints",
        type=int,
        default=None,
        help="whole-body mode (weldplan.bench.scale_body): the N-joint set (4000), pair planning "
        "on Dask with each of --workers, then end to end with each of --e2e-workers",
    )
    p.add_argument(
        "--e2e-workers",
        type=_ints,
        default=[2],
        help="with --joints: Dask worker processes of the end-to-end runs, comma-separated (2)",
    )
    p.add_argument(
        "--e2e-only", action="store_true", help="with --joints: skip the throughput runs"
    )


def run(args: argparse.Namespace) -> int:
    mesh = str(shared_path("bodies", "car2.obj"))
    sizes = [50, 200] if args.quick else args.sizes
    if args.throughput_only:
        sizes = []
    n_pairs = 40 if args.quick else args.pairs
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    before = conditions()
    if args.joints is not None:
        from weldplan.bench.scale_body import run_body

        return run_body(args, mesh, out, before, run_child)
    rows, raw = [], {}
    for n in sizes:
        reference = args.reference if n <= args.reference_max else "none"
        r = run_child(_size_code(args, mesh, n, reference))
        raw[n] = r
        rows += _size_rows(args, n, reference, r)
    thr = None
    if args.throughput_only or 200 in sizes or not sizes:
        code = _THROUGHPUT.format(
            mesh=mesh,
            joints=str(ASSETS / "car2_synthetic_200.csv"),
            pairs=n_pairs,
            workers=list(args.workers),
        )
        thr = run_child(code)
        raw["throughput"] = thr
    after = conditions()
    md = [
        "# weldplan bench scale: car2 (4500 mm), synthetic weld-joint sets",
        "",
        f"Before: {before}  ",
        f"After: {after}",
        "",
    ]
    if rows:
        md += _sizes_table(args, rows)
    if thr is not None:
        md += _throughput_table(thr)
    (out / "scale.md").write_text("\n".join(md), encoding="utf-8")
    (out / "scale.json").write_text(json.dumps(raw, indent=1), encoding="utf-8")
    print("\n".join(md))  # noqa: T201
    print(f"wrote {out / 'scale.md'} ({time.strftime('%H:%M:%S')})")  # noqa: T201
    return 0


def _size_code(args: argparse.Namespace, mesh: str, n: int, reference: str) -> str:
    """The child program of the end-to-end run on the ``n``-joint set."""
    return _CHILD.format(
        mesh=mesh,
        joints=str(ASSETS / f"car2_synthetic_{n}.csv"),
        k=args.candidates,
        radius=args.candidate_radius,
        seq=args.sequencer,
        sbud=args.sequence_budget,
        jobs=args.jobs,
        reference=reference,
    )


def _size_rows(args: argparse.Namespace, n: int, reference: str, r: dict) -> list[list]:
    """The table rows of one size from its child's result ``r``: the run (or its failure) and,
    when a reference ran, the reference's row."""
    if "error" in r:
        return [
            [n, f"{r['cell']:.1f}", "", "", "", "", f"failed after {r['plan']:.1f}",
             f"{max(r['peak_mib'], r['child_peak_mib']):.0f}", r["error"], "", "", "no",
             f"{_load(r['load_before'])} / {_load(r['load_after'])}"]
        ]  # fmt: skip
    s = r["stats"]
    ratio = r["length"] / r["ref_length"] if r["ref_length"] == r["ref_length"] else None
    rows = [
        [
            n,
            f"{r['cell']:.1f}",
            f"{r['seconds']['straight']:.1f}",
            f"{r['seconds']['local']:.1f}",
            f"{r['seconds']['sequence']:.1f}",
            f"{r['verify']:.1f}",
            f"**{r['total']:.1f}**",
            f"{max(r['peak_mib'], r['child_peak_mib']):.0f}",
            f"{s['pairs_checked']} / {s['pairs_straight']} / {s['pairs_planned']}"
            + (f" ({s['pairs_failed']} failed)" if s.get("pairs_failed") else ""),
            f"{r['length']:.0f}",
            "-" if ratio is None else f"{ratio:.4f}",
            "yes" if r["ok"] else f"no ({r['violations']})",
            f"{_load(r['load_before'])} / {_load(r['load_after'])}",
        ]
    ]
    if ratio is not None:
        rs = r["ref_stats"]
        how = "lazy, serial" if reference == "lazy" else f"all searched, {args.jobs} workers"
        rows.append(
            [
                f"{n} (ref: {how})",
                "",
                "",
                "",
                "",
                "",
                f"plan {r['ref_plan']:.1f}",
                "",
                f"{rs['pairs_checked']} / {rs['pairs_straight']} / {rs['pairs_planned']}"
                + (f" ({rs['pairs_failed']} failed)" if rs.get("pairs_failed") else ""),
                f"{r['ref_length']:.0f}",
                "1",
                "yes" if r["ref_ok"] else "no",
                f"- / {_load(r['load_ref'])}",
            ]
        )
    return rows


def _sizes_table(args: argparse.Namespace, rows: list[list]) -> list[str]:
    """``scale.md``'s end-to-end table with the paragraph that says how it was measured."""
    return [
        f"Candidates k = {args.candidates} (radius {args.candidate_radius} mm), "
        f"{args.jobs} worker processes, sequencer "
        f"{args.sequencer}, local planner {default_planner()} (the pipeline's default), "
        "seed 0. Seconds are wall clock; memory is "
        "the peak RSS of the run's process or of its largest worker (MiB). Pairs: checked "
        "straight / free / searched. Length ratio: against the reference route "
        f"(--reference {args.reference}), same seed. Load: 1/5/15-minute load average "
        "before / after the run.",
        "",
        table(
            [
                "joints",
                "cell s",
                "straight s",
                "local s",
                "sequence s",
                "verify s",
                "total s",
                "peak MiB",
                "pairs chk/free/searched",
                "length mm",
                "len / ref",
                "verified",
                "load",
            ],
            rows,
        ),
        "",
    ]


def _throughput_table(thr: dict) -> list[str]:
    """``scale.md``'s pair-planning throughput table from the throughput child's result."""
    runs = thr["runs"]
    base = runs[0]
    return [
        f"Pair-planning throughput (200-joint set, {thr['pairs']} blocked candidate pairs, "
        f"planner {thr['planner']}, the pipeline's default `PlanConfig().planner`; CPU "
        "seconds of the planning process or of the pool's workers, "
        "worker start-up excluded from the wall time but included in the pool's CPU "
        "seconds: imports, cell unpickling and collision model in each worker):",
        "",
        table(
            ["workers", "wall s", "speed-up", "CPU s", "CPU / first", "same paths", "load"],
            [
                [
                    r["workers"],
                    f"{r['wall']:.2f}",
                    f"**{base['wall'] / r['wall']:.2f}x**",
                    f"{r['cpu']:.2f}",
                    f"{r['cpu'] / base['cpu']:.2f}" if base["cpu"] else "-",
                    r["same"],
                    f"{_load(r['load_before'])} / {_load(r['load_after'])}",
                ]
                for r in runs
            ],
        ),
        "",
        "The wall speed-up is bound by the cores free on the machine: compare it with the "
        "load average beside it (on 2 cores, a load of 1 already leaves one core to share).",
        "",
    ]
