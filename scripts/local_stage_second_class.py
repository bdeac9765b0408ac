"""The cost of the second-class stage at scale: one car2 joint set planned end to end with the
local planner's second-class stage on or off (``LocalParams.second_class``), everything else
the defaults of ``weldplan plan car2.obj SET --length 4500 --candidates 6``. One setting a
process (the first plan in a process also builds the cell's caches, so two settings in one
process do not compare)::

    python scripts/local_stage_second_class.py assets/car2/car2_synthetic_200.csv off
    python scripts/local_stage_second_class.py assets/car2/car2_synthetic_200.csv on

Prints, per setting: the local stage's wall seconds (and the whole plan's CPU seconds, one
process), the pairs planned, the sum of the planned
local paths' lengths, the route length, its gap over the bound of the planned legs, and the
independent re-check (``verify_route``).
"""

from __future__ import annotations

import sys
import time

from weldplan.bench.common import conditions, shared_path
from weldplan.weld.cell import load_cell
from weldplan.weld.pipeline import DEFAULT_ACO, PlanConfig, plan_route
from weldplan.weld.synthetic import CAR2_LENGTH_MM
from weldplan.weld.verify import verify_route


def main(joints: str, setting: str) -> None:
    print(conditions())
    t = time.perf_counter()
    cell = load_cell(shared_path("bodies", "car2.obj"), joints, length=CAR2_LENGTH_MM)
    print(f"cell {time.perf_counter() - t:.1f} s, {cell.n_joints} joints")
    for second in (setting == "on",):
        aco = {**DEFAULT_ACO, "refine": True, "second_class": second}
        c0 = time.process_time()
        route = plan_route(cell, config=PlanConfig(aco=aco, candidates=6), rng=0)
        cpu = time.process_time() - c0
        st = route.stats
        planned = sum(v["length"] for v in st["local_paths"].values())
        rep = verify_route(route, cell)
        print(
            f"second_class={second}: local {st['seconds']['local']:.1f} s (whole plan "
            f"{cpu:.1f} CPU s), "
            f"{st['pairs_planned']} pairs planned ({planned:.1f} mm), route "
            f"{route.length:.2f} mm, gap {100 * st['gap_planned']:.2f} % over the planned "
            f"legs' bound, verify {'ok' if rep.ok else 'FAILED'}"
        )
    print(conditions())


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[2] not in ("on", "off"):
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
