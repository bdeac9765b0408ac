"""``weldplan bench scale --joints N``: a whole-body station on Dask (issue #18 item 3).

Targets: the 4000-joint car2 station (``assets/car2/car2_synthetic_4000.csv``, the synthetic
generator's ``whole-body`` profile) end to end in at most 10 min and 8 GB on 2 cores; pair
planning that scales with Dask worker processes (1, 2, 4).

Two measurements, each in a fresh child process (so its figures are its own):

throughput
    The cell of the station, its candidate pairs (each joint's ``--candidates`` nearest), their
    straight checks, then ``--pairs`` of the blocked ones (spread evenly over the list) planned
    on a Dask ``LocalCluster`` of ``w`` single-threaded worker processes for each ``w`` in
    ``--workers``: wall seconds (the cell's scatter to the workers included), the workers' CPU
    seconds, the peak RSS summed over the whole process tree, and whether every ``w`` gave the
    same paths as the first.
end to end
    The product path: :func:`~weldplan.weld.cell.load_cell`, then
    :func:`~weldplan.weld.pipeline.plan_route` with ``PlanConfig(candidates=k)`` on a Dask
    cluster of ``w`` workers (``--e2e-workers``), then the independent verification; wall and
    CPU seconds per stage, the peak RSS of the whole tree, the route, its proved bound
    (``bound_planned``: 1-tree over planned lengths and straight-polyline lower bounds, never an
    optimistic estimate) and the gap.

The peak RSS of the tree is sampled every :data:`SAMPLE_S` seconds (psutil, which Dask brings):
the sum over the process and all its descendants, so a peak shorter than the interval can be
missed. CPU seconds come from ``getrusage`` (the process, and its reaped descendants: the Dask
nannies and workers once the cluster is closed). The load average is written beside each figure:
on a shared 2-core machine wall time alone says little.
"""

from __future__ import annotations

import json
import os
import resource
import threading
import time
from pathlib import Path
from typing import Any

from weldplan.bench.common import table

#: seconds between two samples of the process tree's memory
SAMPLE_S = 0.5


class TreeMemory:
    """Peak RSS (bytes) summed over this process and all its descendants, sampled in a thread.

    Use as a context manager; ``peak`` is the largest sum seen, ``mark()`` starts a new interval
    whose peak is ``since_mark``.
    """

    def __init__(self, interval: float = SAMPLE_S) -> None:
        try:
            import psutil
        except ImportError as exc:  # pragma: no cover - comes with the dask extra
            from weldplan.errors import WeldplanError

            raise WeldplanError(
                "the whole-body bench needs psutil: pip install 'weldplan[dask]'"
            ) from exc
        self._psutil = psutil
        self.interval = interval
        self.peak = 0
        self.since_mark = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def now(self) -> int:
        """RSS of the tree now (bytes)."""
        me = self._psutil.Process()
        total = 0
        for p in [me, *me.children(recursive=True)]:
            try:
                total += p.memory_info().rss
            except self._psutil.Error:  # ended between listing and reading
                pass
        return total

    def mark(self) -> None:
        self.since_mark = self.now()

    def _run(self) -> None:
        while not self._stop.is_set():
            rss = self.now()
            self.peak = max(self.peak, rss)
            self.since_mark = max(self.since_mark, rss)
            self._stop.wait(self.interval)

    def __enter__(self) -> TreeMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def _cpu() -> tuple[float, float]:
    """CPU seconds (user + system) of this process and of its reaped descendants."""
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime, c.ru_utime + c.ru_stime


def _workers_cpu(psutil: Any) -> float:
    """CPU seconds of the live descendants of this process (the Dask nannies and workers)."""
    total = 0.0
    for p in psutil.Process().children(recursive=True):
        try:
            t = p.cpu_times()
            total += t.user + t.system
        except psutil.Error:
            pass
    return total


MIB = 2**20


def throughput_child(spec: dict[str, Any]) -> dict[str, Any]:
    """The throughput measurement (module docstring), run in a child process."""
    import logging

    import numpy as np

    from weldplan.weld.cell import load_cell
    from weldplan.weld.pairtasks import _plan_pairs_task, candidate_pairs
    from weldplan.weld.parallel import batches, dask_executor, share_cell

    logging.disable(logging.WARNING)
    out: dict[str, Any] = {"load_before": os.getloadavg(), "runs": []}
    with TreeMemory() as mem:
        t0 = time.perf_counter()
        cell = load_cell(spec["mesh"], spec["joints"], length=4500.0)
        out["cell"] = time.perf_counter() - t0
        n = len(cell.joints.ids)
        iu, ju = np.triu_indices(n, 1)
        pair_index = -np.ones((n, n), dtype=np.intp)
        pair_index[iu, ju] = np.arange(len(iu))
        cand = candidate_pairs(np.asarray(cell.joints.xyz), spec["k"], pair_index)
        V = cell.virtual_xyz
        free = cell.collision.segments_free(V[iu[cand]], V[ju[cand]], cell.clearance)
        blocked = cand[~free]
        step = max(1, len(blocked) // spec["pairs"])
        todo = blocked[::step][: spec["pairs"]]
        args = default_pair_args(iu, ju, todo)
        out.update(
            n=n,
            candidates=len(cand),
            blocked=len(blocked),
            pairs=len(args),
            planner=default_planner(),
        )
        first = None
        for w in spec["workers"]:
            l0 = os.getloadavg()
            with dask_executor("local", workers=w) as ex:
                for f in [ex.submit(int, 0) for _ in range(w)]:
                    f.result()  # the workers are up
                c0 = _workers_cpu(mem._psutil)
                mem.mark()
                t = time.perf_counter()
                shared = share_cell(cell, ex)
                fs = [ex.submit(_plan_pairs_task, shared, b, None) for b in batches(args, w)]
                got = [lp for f in fs for lp in f.result()]
                wall = time.perf_counter() - t
                cpu = _workers_cpu(mem._psutil) - c0
                peak = mem.since_mark
            first = first or got
            same = all(np.array_equal(a.points, b.points) for a, b in zip(first, got, strict=True))
            out["runs"].append(
                dict(workers=w, wall=wall, cpu=cpu, peak_mib=peak / MIB, same=same,
                     load_before=l0, load_after=os.getloadavg())
            )  # fmt: skip
    out["peak_mib"] = mem.peak / MIB
    return out


def end_to_end_child(spec: dict[str, Any]) -> dict[str, Any]:
    """The end-to-end measurement (module docstring), run in a child process."""
    import logging

    from weldplan.errors import PlanningError
    from weldplan.weld.cell import load_cell
    from weldplan.weld.parallel import dask_executor
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.verify import verify_route

    logging.disable(logging.WARNING)
    w = spec["workers"]
    out: dict[str, Any] = {"workers": w, "load_before": os.getloadavg()}
    with TreeMemory() as mem:
        t0 = time.perf_counter()
        cell = load_cell(spec["mesh"], spec["joints"], length=4500.0)
        out["cell"] = time.perf_counter() - t0
        cfg = PlanConfig(candidates=spec["k"])
        t1 = time.perf_counter()
        try:
            with dask_executor("local", workers=w) as ex:
                route = plan_route(cell, config=cfg, rng=0, executor=ex)
        except PlanningError as exc:  # a row of the table, not a crash of the bench
            out.update(error=str(exc)[:300], plan=time.perf_counter() - t1)
            route = None
        else:
            out["plan"] = time.perf_counter() - t1
        if route is not None:
            t2 = time.perf_counter()
            rep = verify_route(route, cell.part, joints=cell.joints)
            out["verify"] = time.perf_counter() - t2
            s = route.stats
            out.update(
                length=route.length,
                bound_planned=s["bound_planned"],
                bound_method=s["bound_planned_method"],
                gap=s["gap_planned"],
                ok=bool(rep.ok),
                violations=len(rep.violations),
                seconds=s["seconds"],
                gap_rounds=s["gap_rounds"],
                rounds=s["rounds"],
                pairs={k: s[k] for k in s if k.startswith("pairs")},
            )
        out["wall"] = time.perf_counter() - t0
    out["cpu_self"], out["cpu_children"] = _cpu()
    out.update(n=len(cell.joints.ids), peak_mib=mem.peak / MIB, load_after=os.getloadavg())
    return out


def child_code(kind: str, spec: dict[str, Any]) -> str:
    """Source for :func:`~weldplan.bench.common.run_child`: one measurement, printed as JSON."""
    return (
        "import json\n"
        f"from weldplan.bench.scale_body import {kind}_child\n"
        f"print(json.dumps({kind}_child(json.loads({json.dumps(spec)!r}))))\n"
    )


def default_planner() -> str:
    """The pipeline's default local planner (``PlanConfig()``), as the tables name it."""
    from weldplan.weld.pipeline import PlanConfig

    cfg = PlanConfig()
    return cfg.planner + (" + refine" if cfg.aco.get("refine") else "")


def default_pair_args(iu: Any, ju: Any, todo: Any) -> list[tuple]:
    """``_plan_pairs_task`` arguments planning pairs ``todo`` as the pipeline does by default:
    ``PlanConfig().planner`` with ``PlanConfig().aco`` (which carries ``refine``), seed = pair."""
    from weldplan.weld.pipeline import PlanConfig

    cfg = PlanConfig()
    return [(int(iu[p]), int(ju[p]), cfg.planner, dict(cfg.aco), int(p)) for p in todo]


def _load(v: list[float]) -> str:
    return " ".join(f"{x:.2f}" for x in v)


def throughput_table(r: dict[str, Any]) -> list[str]:
    base = r["runs"][0]
    return [
        f"Pair planning on Dask ({r['n']}-joint station: {r['candidates']} candidate pairs, "
        f"{r['blocked']} blocked; {r['pairs']} of them, spread over the list, planner "
        f"{r['planner']} (the pipeline's default); "
        f"cell {r['cell']:.1f} s). Wall includes scattering the cell to the workers; CPU is the "
        "workers' (nannies included); peak RSS is summed over the whole process tree.",
        "",
        table(
            ["workers", "wall s", "speed-up", "CPU s", "peak tree MiB", "same paths", "load"],
            [
                [
                    x["workers"],
                    f"{x['wall']:.1f}",
                    f"**{base['wall'] / x['wall']:.2f}x**",
                    f"{x['cpu']:.1f}",
                    f"{x['peak_mib']:.0f}",
                    x["same"],
                    f"{_load(x['load_before'])} / {_load(x['load_after'])}",
                ]
                for x in r["runs"]
            ],
        ),
        "",
    ]


def end_to_end_rows(runs: list[dict[str, Any]]) -> list[str]:
    rows = []
    for r in runs:
        cpu = r["cpu_self"] + r["cpu_children"]
        if "error" in r:
            rows.append(
                [r["workers"], f"{r['cell']:.0f}", "", "", "", f"{r['wall']:.0f}", f"{cpu:.0f}",
                 f"{r['peak_mib']:.0f}", r["error"], "", "", "", "no",
                 f"{_load(r['load_before'])} / {_load(r['load_after'])}"]
            )  # fmt: skip
            continue
        sec, p = r["seconds"], r["pairs"]
        gr = r["gap_rounds"] or {}
        rows.append(
            [
                r["workers"],
                f"{r['cell']:.0f}",
                f"{sec['local']:.0f}",
                f"{sec['sequence']:.0f}",
                f"{r['verify']:.0f}",
                f"**{r['wall']:.0f}**",
                f"{cpu:.0f}",
                f"**{r['peak_mib']:.0f}**",
                f"{p['pairs_checked']} / {p['pairs_planned']} ({p['pairs_failed']} failed); "
                f"{r['rounds']} rounds, gap rounds {gr.get('rounds', 0)} "
                f"(+{gr.get('pairs_planned', 0)} pairs)",
                f"{r['length']:.0f}",
                f"{r['bound_planned']:.0f} ({r['bound_method']})",
                f"{100 * r['gap']:.2f} %",
                "yes" if r["ok"] else f"no ({r['violations']})",
                f"{_load(r['load_before'])} / {_load(r['load_after'])}",
            ]
        )
    return [
        "End to end (`load_cell`, `plan_route(PlanConfig(candidates=k))` on a Dask local "
        "cluster, `verify_route`), seed 0. Seconds are wall clock; CPU is the whole tree's; "
        "peak is the RSS summed over the whole process tree (MiB); bound: proved lower bound "
        "of any route of this planner's legs (planned lengths, straight-polyline bounds for "
        "legs not planned).",
        "",
        table(
            [
                "workers",
                "cell s",
                "local s",
                "sequence s",
                "verify s",
                "wall s",
                "CPU s",
                "peak tree MiB",
                "pairs checked / planned",
                "length mm",
                "bound mm",
                "gap",
                "verified",
                "load",
            ],
            rows,
        ),  # fmt: skip
        "",
    ]


def run_body(args: Any, mesh: str, out: Path, before: str, run_child: Any) -> int:
    """``--joints N``: the throughput and end-to-end measurements, written as
    ``scale-{N}.md`` / ``.json``."""
    from weldplan.bench.common import conditions

    joints = Path(__file__).resolve().parents[2] / "assets" / "car2"
    joints = joints / f"car2_synthetic_{args.joints}.csv"
    if not joints.exists():
        from weldplan.errors import InputError

        raise InputError(
            f"no synthetic set of {args.joints} joints: write it with python -m "
            "weldplan.weld.synthetic --profile whole-body --sizes N --out assets/car2",
            path=str(joints),
            field="--joints",
        )
    spec = {"mesh": mesh, "joints": str(joints), "k": args.candidates}
    raw: dict[str, Any] = {}
    md = [f"# weldplan bench scale --joints {args.joints}: car2 (4500 mm), synthetic", ""]
    md += [f"Before: {before}  ", ""]
    if not args.e2e_only:
        thr = run_child(
            child_code("throughput", {**spec, "pairs": args.pairs, "workers": args.workers})
        )
        raw["throughput"] = thr
        md += throughput_table(thr)
    if not args.throughput_only:
        raw["end_to_end"] = [
            run_child(child_code("end_to_end", {**spec, "workers": w})) for w in args.e2e_workers
        ]
        md += end_to_end_rows(raw["end_to_end"])
    md += [f"After: {conditions()}", ""]
    (out / f"scale-{args.joints}.md").write_text("\n".join(md), encoding="utf-8")
    (out / f"scale-{args.joints}.json").write_text(json.dumps(raw, indent=1), encoding="utf-8")
    print("\n".join(md))  # noqa: T201
    return 0
