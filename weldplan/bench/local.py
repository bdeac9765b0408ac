"""``weldplan bench local``: Table 3 of Wang et al. 2017 (ACO vs SO-ACO, joint 3 to joint 7).

For every (N, M) in the paper's list, ``--runs`` seeded runs of SO-ACO on the demo cell; the ACO
figures are the same runs' colony routes before the secondary optimisation, with the time at which
the colony finished (the paper's SO-ACO time is likewise its ACO time plus the SO). The exact
26-connected baseline (A* + the same secondary optimisation) and the straight-line lower bound are
extra columns. Writes ``local.md``, ``local.json`` and ``local-convergence.png`` into ``--out``.

``--peers`` runs the other comparison instead (:mod:`weldplan.bench.local_peers`): our planners
beside OMPL BIT* and RRT* on every blocked pair of the demo and the car2 stations.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

HELP = "Table 3 of Wang et al. 2017: ACO and SO-ACO between joints 3 and 7 of the demo cell"

#: (N, M) of Table 3
SIZES = ((5, 5), (10, 10), (20, 20), (30, 30), (40, 40), (50, 50), (60, 60))
QUICK_SIZES = ((5, 5), (10, 10), (20, 20))

#: Table 3 of the paper: (N, M) -> (ACO mean, SO-ACO mean length mm, SO-ACO mean time s)
PAPER = {
    (5, 5): (681.000, 206.326, 1.242),
    (10, 10): (579.500, 203.085, 4.369),
    (20, 20): (460.500, 203.219, 13.511),
    (30, 30): (361.000, 203.039, 25.152),
    (40, 40): (330.500, 202.930, 43.332),
    (50, 50): (330.000, 203.120, 56.340),
    (60, 60): (330.000, 202.800, 76.492),
}
STRAIGHT_3_7 = 202.91  # mm, real joints 3 and 7 (Table 1)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--runs", type=int, default=20, help="seeded runs per (N, M) (20)")
    parser.add_argument(
        "--quick", action="store_true", help="(N, M) up to 20 and 3 runs: a smoke test"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the first run")
    parser.add_argument("--from", dest="src", default="3", help="start joint id (3)")
    parser.add_argument("--to", dest="dst", default="7", help="goal joint id (7)")
    from weldplan.bench import local_peers

    local_peers.add_arguments(parser)


def _cell() -> tuple[Any, str]:
    from weldplan.weld.cell import demo_cell

    return demo_cell(), "demo cell (weldplan.weld.cell.demo_cell)"


def _calibrate() -> tuple[float, float]:
    """Wall and CPU seconds of a plain 10^6-iteration Python loop: how fast this machine is now
    (an idle modern core takes a few hundredths of a second)."""
    t, c = time.perf_counter(), time.process_time()
    x = 0
    for k in range(1_000_000):
        x += k
    return time.perf_counter() - t, time.process_time() - c


def _stats(x: list[float]) -> dict[str, float]:
    a = np.asarray(x, dtype=float)
    return {
        "mean": float(a.mean()),
        "sd": float(a.std(ddof=1)) if len(a) > 1 else 0.0,
        "min": float(a.min()),
        "max": float(a.max()),
    }


@dataclass(frozen=True)
class Table3Run:
    """The figures of one ``weldplan bench local`` run: what ``local.md`` and ``local.json``
    report.

    Attributes
    ----------
    cell, pair, runs
        The cell's note, the joint ids of the pair (start, goal) and the seeded runs per row.
    exact, first
        The exact baseline's :class:`~weldplan.weld.localpath.LocalPath` (its last repeat) and
        the first call on the cell (which builds the per-grid caches).
    exact_times, exact_cpu
        Wall and CPU seconds of the exact baseline's repeats.
    straight_virtual, straight_real
        mm between the virtual joints and between the real joints.
    rows
        Per (N, M) and method (ACO, SO-ACO): lengths (mm), times and CPU (s) with their stats.
    load_before, load_after
        The load average (1, 5, 15 min) before and after the runs.
    calibration
        Wall and CPU seconds of a 10^6-iteration Python loop before and after the runs.
    """

    cell: str
    pair: tuple[str, str]
    runs: int
    exact: Any
    first: Any
    exact_times: tuple[float, ...]
    exact_cpu: tuple[float, ...]
    straight_virtual: float
    straight_real: float
    rows: tuple[dict[str, Any], ...]
    load_before: tuple[float, ...]
    load_after: tuple[float, ...]
    calibration: tuple[tuple[float, float], tuple[float, float]]

    def to_dict(self) -> dict[str, Any]:
        """``local.json``'s content (its keys in the order the file has always had them)."""
        return {
            "cell": self.cell,
            "pair": list(self.pair),
            "exact": self.exact.to_dict(),
            "exact_first_call": [self.first.seconds, self.first.cpu_seconds],
            "exact_times": list(self.exact_times),
            "exact_cpu": list(self.exact_cpu),
            "straight_virtual": self.straight_virtual,
            "straight_real": self.straight_real,
            "rows": list(self.rows),
            "load_before": self.load_before,
            "load_after": self.load_after,
            "loop_1e6_wall_cpu": list(self.calibration),
        }


def run(args: argparse.Namespace) -> int:
    if getattr(args, "peers", False):  # issue 15: beside OMPL on every blocked pair
        from weldplan.bench import local_peers

        return local_peers.run(args)
    from weldplan.weld.local import plan_pair

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = QUICK_SIZES if args.quick else SIZES
    runs = min(args.runs, 3) if args.quick else args.runs
    load0 = os.getloadavg()
    cal0 = _calibrate()
    cell, cell_note = _cell()
    ids = [str(v) for v in cell.joints.ids]
    i, j = ids.index(args.src), ids.index(args.dst)
    g = cell.grid
    vs, vg = g.index_to_world(cell.virtual_index[i]), g.index_to_world(cell.virtual_index[j])
    straight_virtual = float(np.linalg.norm(vg - vs))
    straight_real = float(np.linalg.norm(cell.joints.xyz[j] - cell.joints.xyz[i]))

    # the exact baseline: deterministic, timed over a few repeats
    # the first call builds per-grid caches (padded array, components, move tables): timed apart
    first = plan_pair(cell, i, j, method="exact")
    print(f"exact, first call: {first.seconds:.3f} s, {first.cpu_seconds:.3f} s CPU")
    ex_times, ex_cpu, exact = [], [], None
    for _ in range(3 if args.quick else 5):
        exact = plan_pair(cell, i, j, method="exact")
        ex_times.append(exact.seconds)
        ex_cpu.append(exact.cpu_seconds)
    assert exact is not None
    print(f"exact: {exact.inner_length:.3f} mm, {min(ex_times):.4f} s, {min(ex_cpu):.4f} s CPU")

    rows: list[dict[str, Any]] = []
    curves: dict[tuple[int, int], np.ndarray] = {}
    for n, m in sizes:
        so_len, so_t, aco_len, aco_t, hist = [], [], [], [], []
        so_c, aco_c = [], []
        for r in range(runs):
            marks: list[float] = []

            def mark(it: int, best: float, marks: list[float] = marks) -> None:
                marks.append((time.perf_counter(), time.process_time()))

            t0, c0 = time.perf_counter(), time.process_time()
            lp = plan_pair(
                cell, i, j, method="so-aco", params={"n_iterations": n, "n_ants": m},
                rng=args.seed + r, callback=mark,
            )  # fmt: skip
            if not lp.success:
                print(f"N={n} M={m} run {r}: failed ({lp.reason})")
                continue
            so_len.append(lp.inner_length)
            so_t.append(lp.seconds)
            aco_len.append(lp.raw_length)
            aco_t.append((marks[-1][0] if marks else t0) - t0)
            so_c.append(lp.cpu_seconds)
            aco_c.append((marks[-1][1] if marks else c0) - c0)
            hist.append(lp.history[-n:])
        curves[(n, m)] = np.asarray(hist, dtype=float)
        for name, L, T, C in (("ACO", aco_len, aco_t, aco_c), ("SO-ACO", so_len, so_t, so_c)):
            rows.append(
                {"N": n, "M": m, "method": name, "runs": len(L), "length": _stats(L),
                 "time": _stats(T), "cpu": _stats(C), "lengths": L, "times": T, "cpus": C}
            )  # fmt: skip
        print(
            f"N={n:2d} M={m:2d}: ACO {np.mean(aco_len):7.2f} mm {np.mean(aco_t):.3f} s | "
            f"SO-ACO {np.mean(so_len):7.3f} mm {np.mean(so_t):.3f} s {np.mean(so_c):.3f} s CPU "
            f"(x{np.mean(so_len) / exact.inner_length:.4f} of exact)"
        )
    load1 = os.getloadavg()
    cal1 = _calibrate()

    table = Table3Run(
        cell=cell_note, pair=(args.src, args.dst), runs=runs, exact=exact, first=first,
        exact_times=tuple(ex_times), exact_cpu=tuple(ex_cpu), straight_virtual=straight_virtual,
        straight_real=straight_real, rows=tuple(rows), load_before=load0, load_after=load1,
        calibration=(cal0, cal1),
    )  # fmt: skip
    (out / "local.md").write_text(_markdown(table))
    (out / "local.json").write_text(json.dumps(table.to_dict(), indent=1))
    _plot(curves, exact.inner_length, out / "local-convergence.png")
    print(f"wrote {out / 'local.md'}, {out / 'local.json'}, {out / 'local-convergence.png'}")
    return 0


def _markdown(t3: Table3Run) -> str:
    """``local.md``: the run's setting, the exact baseline, the table and the targets."""
    rows, exact, first, runs = t3.rows, t3.exact, t3.first, t3.runs
    ex_times, ex_cpu, cell_note = t3.exact_times, t3.exact_cpu, t3.cell
    straight_virtual, straight_real = t3.straight_virtual, t3.straight_real
    load0, load1, cal = t3.load_before, t3.load_after, t3.calibration
    ex = exact.inner_length
    lines = [
        "# Table 3 reproduction: ACO and SO-ACO, joint 3 to joint 7",
        "",
        f"Cell: {cell_note}.",
        f"{runs} seeded runs per row. Lengths between the virtual joints (mm), as in the paper.",
        f"Load average (1, 5, 15 min) before: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}; "
        f"after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f} (2-core machine shared with others).",
        "Times: wall clock (t) and processor time of this process (CPU); on a loaded machine the "
        "CPU time is the better estimate of the wall time on an idle core (in a VM it still "
        "includes time stolen by the host).",
        f"Machine speed: a 10^6-iteration Python loop took {cal[0][0]:.3f} s wall / "
        f"{cal[0][1]:.3f} s CPU before the runs and {cal[1][0]:.3f} s / {cal[1][1]:.3f} s after "
        "(an idle modern core: about 0.03-0.05 s).",
        "",
        f"- Exact baseline (26-connected A* + the same SO): **{ex:.3f} mm** (grid route "
        f"{exact.raw_length:.3f} mm), wall {min(ex_times):.4f} s min / {np.mean(ex_times):.4f} s "
        f"mean, CPU {min(ex_cpu):.4f} s min / {np.mean(ex_cpu):.4f} s mean of {len(ex_times)}; "
        f"{exact.evaluations} expansions, {exact.repairs} repair(s). The first call on the cell "
        f"took {first.seconds:.3f} s wall / {first.cpu_seconds:.3f} s CPU: it builds the per-grid "
        "caches every later pair shares (padded array, connected components, move tables).",
        f"- Straight line between the virtual joints: {straight_virtual:.3f} mm; between the real "
        f"joints: {straight_real:.3f} mm (paper: 202.91 mm).",
        "",
        "| N | M | method | mean L | SD | min | max | mean t (s) | SD | min | max "
        "| mean CPU (s) | min CPU | mean L / exact | paper mean L | paper mean t (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        L, T, C = r["length"], r["time"], r["cpu"]
        paper = PAPER.get((r["N"], r["M"]))
        pl = "" if paper is None else f"{paper[0 if r['method'] == 'ACO' else 1]:.3f}"
        pt = "" if paper is None or r["method"] == "ACO" else f"{paper[2]:.3f}"
        lines.append(
            f"| {r['N']} | {r['M']} | {r['method']} | {L['mean']:.3f} | {L['sd']:.3f} | "
            f"{L['min']:.3f} | {L['max']:.3f} | {T['mean']:.4f} | {T['sd']:.4f} | "
            f"{T['min']:.4f} | {T['max']:.4f} | {C['mean']:.4f} | {C['min']:.4f} | "
            f"{L['mean'] / ex:.4f} | {pl} | {pt} |"
        )
    so10 = [r for r in rows if r["method"] == "SO-ACO" and r["N"] == 10 and r["M"] == 10]
    big = [r for r in rows if r["method"] == "SO-ACO" and min(r["N"], r["M"]) >= 10]
    lines += ["", "## Targets", ""]
    if so10:
        t = so10[0]["time"]["mean"]
        c = so10[0]["cpu"]["mean"]
        lines.append(
            f"- SO-ACO N = M = 10 within 0.25 s a pair: mean {t:.3f} s wall "
            f"({'met' if t <= 0.25 else 'NOT met'}), {c:.3f} s CPU "
            f"({'met' if c <= 0.25 else 'NOT met'}); paper 4.369 s in MATLAB."
        )
    if big:
        worst = max(max(r["lengths"]) / ex for r in big)
        mean = max(r["length"]["mean"] / ex for r in big)
        lines.append(
            f"- SO-ACO within 2% of exact for N = M >= 10: worst mean ratio {mean:.4f}, worst "
            f"single run {worst:.4f} ({'met' if mean <= 1.02 else 'NOT met'} on the mean)."
        )
    c = min(ex_cpu)
    lines.append(
        f"- Exact baseline within 0.05 s a pair: {min(ex_times):.4f} s wall min "
        f"({'met' if min(ex_times) <= 0.05 else 'NOT met'}), {c:.4f} s CPU min "
        f"({'met' if c <= 0.05 else 'NOT met'})."
    )
    lines.append("")
    return "\n".join(lines)


def _plot(curves: dict[tuple[int, int], np.ndarray], exact: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (n, m), H in curves.items():
        if H.size == 0:
            continue
        H = np.where(np.isfinite(H), H, np.nan)
        x = np.arange(1, H.shape[1] + 1)
        ax.plot(x, np.nanmean(H, axis=0), label=f"ACO N={n}, M={m} (mean of {len(H)})")
    ax.axhline(exact, color="k", ls="--", lw=1, label=f"exact + SO {exact:.1f} mm")
    ax.set_xlabel("iteration")
    ax.set_ylabel("best route so far (mm)")
    ax.set_title("Ant colony convergence, joint 3 to joint 7")
    ax.legend(fontsize=8)
    ax.set_ylim(bottom=0.0 if math.isfinite(exact) else None)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
