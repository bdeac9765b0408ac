"""``weldplan planar multimodal SCENARIO --k 3``: ParaPA's k distinct paths in one run (003).

Prints each path's length, gap to the exact optimum (visibility graph), success and swarm,
then the pairwise distinctness (different homology class, eq. 17 crossings, Hausdorff
distance); ``--plot`` writes a PNG of the k paths over the map, ``--json`` the result.
"""

from __future__ import annotations

import argparse
import sys

from weldplan.errors import WeldplanError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("planar multimodal")
    g.add_argument("--k", type=int, default=3, help="multimodal: distinct paths wanted")
    g.add_argument(
        "--swarms",
        type=int,
        default=None,
        help="multimodal: swarms (default 4; --pop is per swarm, default 50)",
    )
    g.add_argument(
        "--iterations", type=int, default=None, help="multimodal: iterations (default 200)"
    )
    g.add_argument(
        "--no-repair", action="store_true", help="multimodal: no reverse planning (Algorithm 2)"
    )


def run(args: argparse.Namespace) -> int:
    from weldplan.planar.multimodal import (
        DEFAULT_SWARMS,
        PAPER_ITERATIONS,
        PAPER_NP,
        check_k,
        plan_multimodal,
    )
    from weldplan.planar.scenarios import load_scenario

    if len(args.more) != 1:
        raise WeldplanError("usage: weldplan planar multimodal SCENARIO [--k K] [options]")
    swarms = DEFAULT_SWARMS if args.swarms is None else args.swarms
    check_k(args.k, swarms)
    iterations = args.iterations or args.iters or PAPER_ITERATIONS
    if iterations < 1:
        raise WeldplanError(f"--iterations must be >= 1, got {iterations}")
    pop = PAPER_NP if args.pop is None else args.pop
    if pop < 2:
        raise WeldplanError(f"--pop (particles per swarm) must be >= 2, got {pop}")
    sc = load_scenario(args.more[0])
    r = plan_multimodal(
        sc,
        args.k,
        n_swarms=swarms,
        pop_per_swarm=pop,
        iterations=iterations,
        repair=not args.no_repair,
        rng=args.seed,
    )
    sys.stdout.write(r.to_json() + "\n" if args.json else _summary(r))
    if args.plot:
        _plot(args.plot, sc, r)
    ok = r.n_success == r.k and r.all_distinct
    return 0 if ok else 1


def _summary(r: object) -> str:
    """The run's text summary: each path's length, gap and verdict, each pair's distinctness."""
    out = [
        f"scenario   {r.scenario}: {r.k} paths from one ParaPA run "
        f"({r.n_swarms} swarms x {r.pop_per_swarm}, {r.iterations} iterations, "
        f"{r.n_eval} evaluations, seed {r.seed}, {r.seconds:.2f} s)",
        f"optimum    {r.optimum:.4f} (exact, visibility graph)",
    ]
    for i in range(len(r.paths)):
        out.append(
            f"path {i + 1}     length {r.lengths[i]:.4f}  gap {100 * r.gaps[i]:+.2f} %  "
            f"{'collision-free' if r.success[i] else 'COLLIDES'}  (swarm {r.swarm[i]})"
        )
    for i in range(len(r.paths)):
        for j in range(i + 1, len(r.paths)):
            out.append(
                f"paths {i + 1}-{j + 1}  "
                f"{'distinct' if r.distinct[i][j] else 'NOT distinct'} (homology class), "
                f"{r.crossings[i][j]} segment crossings, Hausdorff {r.hausdorff[i][j]:.3f}"
            )
    out.append(
        f"repairs    {r.repairs} abandoned hosts and {r.final_repairs} elites repaired by "
        "reverse planning (Algorithm 2)"
    )
    return "\n".join(out) + "\n"


def _plot(path: str, sc: object, r: object) -> None:
    """The k paths beside the exact optimum, as a figure at ``path``."""
    from weldplan.planar.solve import exact_optimum
    from weldplan.viz.planar import plot_paths

    ex = exact_optimum(sc, "segments")
    plot_paths(
        sc,
        {
            f"path {i + 1} (swarm {r.swarm[i]}) {r.lengths[i]:.3f}"
            + ("" if r.success[i] else " collides"): r.path_array(i)
            for i in range(len(r.paths))
        },
        path,
        exact=ex.points_array,
        title=f"{sc.name}: {r.k} multimodal ParaPA paths, optimum {ex.length:.3f}",
    )
