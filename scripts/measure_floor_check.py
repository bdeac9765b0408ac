"""Measure the robot's floor check on random motions: CPU seconds and verdicts.

The shared KR 150 with the shared spot gun on the floor (base at the origin, floor z = 0), a part
far away (tests/robot/test_robot_selfcollision.py's), ``N`` seeded random motions between free
configurations inside the joint limits: each motion's verdict (``RobotCollision.path_hits``) and
the CPU seconds of them all. Run it on two commits to compare verdicts and cost::

    PYTHONPATH=. .venv/bin/python scripts/measure_floor_check.py [N] [--out verdicts.json]
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    from tests.robot.test_robot_selfcollision import FAR_PART
    from weldplan.robot import load_robot
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.route import tool_flange_tcp
    from weldplan.tool import shared_spot_gun
    from weldplan.tool.model import SHARED_GUN_DIR

    n = int(argv[0]) if argv and not argv[0].startswith("--") else 150
    out = Path(argv[argv.index("--out") + 1]) if "--out" in argv else None
    data = ROOT.parent / "shared" / "data" / "robots" / "kuka_kr150r3100_2"
    robot = load_robot(data / "kr150r3100_2.urdf")
    flange_tcp = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    chk = RobotCollision(robot, FAR_PART, shared_spot_gun(), flange_tcp, floor_z=0.0)
    rng = np.random.default_rng(0)
    motions = []
    while len(motions) < n:
        qa, qb = rng.uniform(robot.lower, robot.upper), rng.uniform(robot.lower, robot.upper)
        if chk.state_free(qa) and chk.state_free(qb):
            motions.append((qa, qb))
    t = time.process_time()
    verdicts = [[h.body for h in chk.path_hits(np.array(m))] for m in motions]
    cpu = time.process_time() - t
    floor = sum(any(b.endswith("/floor") for b in v) for v in verdicts)
    print(f"{n} motions: {sum(not v for v in verdicts)} free, {floor} through the floor; "
          f"{cpu:.1f} CPU s")  # fmt: skip
    if out is not None:
        out.write_text(json.dumps(verdicts))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
