"""Write the planar scenarios under assets/scenarios/ (run once; the JSON files are the data).

The papers publish figures, not coordinates, so these maps are ours, made to match the papers'
setups: paper 000's three circle scenarios (paths of about 28-35 units), paper 003's seven
20 x 20 maps of different obstacle shapes (map 4 an S-shaped corridor), two 50 x 50 maps of
random rectangles and a 100 x 100 building layout with 003's starts and targets, and paper
001's 20 x 20 and 40 x 40 occupancy grids. Random maps use fixed seeds, so rerunning this
script rewrites identical files.

    python scripts/make_scenarios.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "assets" / "scenarios"


def circle(x: float, y: float, r: float) -> dict:
    return {"type": "circle", "center": [x, y], "radius": r}


def rect(x0: float, y0: float, x1: float, y1: float) -> dict:
    return {"type": "rectangle", "min": [x0, y0], "max": [x1, y1]}


def poly(*pts: tuple[float, float]) -> dict:
    return {"type": "polygon", "vertices": [list(p) for p in pts]}


def write(name: str, data: dict) -> None:
    data = {"name": name, **data}
    text = json.dumps(data, indent=1)
    (OUT / f"{name}.json").write_text(text + "\n")


def circle_maps() -> None:
    common = {"bounds": [-1, -1, 21, 21], "start": [0, 0], "goal": [20, 20], "encoding": "spline"}
    write(
        "circles-1",
        {
            "description": "Paper 000 scenario 1 style: three circles near the diagonal.",
            **common,
            "obstacles": [circle(6, 7, 2.0), circle(13, 12, 2.5), circle(16, 5, 1.5)],
        },
    )
    write(
        "circles-2",
        {
            "description": "Paper 000 scenario 2 style: six circles, the diagonal blocked twice.",
            **common,
            "obstacles": [
                circle(4, 5, 1.8),
                circle(10, 10, 3.0),
                circle(14, 15, 2.2),
                circle(15, 8, 1.8),
                circle(7, 15, 2.0),
                circle(18, 12, 1.2),
            ],
        },
    )
    write(
        "circles-3",
        {
            "description": "Paper 000 scenario 3 style: ten circles, no straight corridor.",
            **common,
            "obstacles": [
                circle(3, 4, 1.5),
                circle(7, 2, 1.3),
                circle(9, 9, 3.2),
                circle(4, 12, 2.0),
                circle(13, 6, 2.0),
                circle(13.5, 13.5, 2.4),
                circle(17, 10, 1.6),
                circle(8, 17, 1.8),
                circle(16, 17, 1.8),
                circle(19, 15, 1.0),
            ],
        },
    )


S20 = {"bounds": [0, 0, 20, 20], "start": [0.5, 0.5], "goal": [19.5, 19.5], "nodes": 12}


def maps20() -> None:
    enc = {"encoding": "segments"}
    write(
        "map20-1",
        {
            "description": "Paper 003 map 1 style: axis-aligned rectangles.",
            **S20,
            **enc,
            "obstacles": [
                rect(3, 2, 6, 7),
                rect(8, 8, 12, 11),
                rect(13, 3, 16, 6),
                rect(4, 12, 7, 16),
                rect(14, 13, 17, 17),
            ],
        },
    )
    write(
        "map20-2",
        {
            "description": "Paper 003 map 2 style: convex polygons (triangles, a pentagon).",
            **S20,
            **enc,
            "obstacles": [
                poly((4, 3), (9, 4), (6, 8)),
                poly((11, 9), (15, 10), (14, 14), (10, 13), (9.5, 11)),
                poly((3, 12), (7, 11), (5, 17)),
                poly((14, 2), (18, 4), (15, 6)),
            ],
        },
    )
    write(
        "map20-3",
        {
            "description": "Paper 003 map 3 style: circles of different sizes.",
            **S20,
            **enc,
            "obstacles": [
                circle(5, 5, 2.2),
                circle(10, 10, 2.8),
                circle(15, 15, 2.2),
                circle(14, 5, 2.0),
                circle(5, 14, 2.0),
                circle(10, 17, 1.2),
                circle(17, 10, 1.2),
            ],
        },
    )
    write(
        "map20-4",
        {
            "description": "Paper 003 map 4 style: an S-shaped corridor of three transverse walls.",
            **S20,
            **enc,
            "obstacles": [rect(0, 5, 15, 6.5), rect(5, 10, 20, 11.5), rect(0, 15, 15, 16.5)],
        },
    )
    write(
        "map20-5",
        {
            "description": "Paper 003 map 5 style: concave polygons (U and L shapes).",
            **S20,
            **enc,
            "obstacles": [
                poly((3, 4), (9, 4), (9, 9), (7.5, 9), (7.5, 5.5), (4.5, 5.5), (4.5, 9), (3, 9)),
                poly((11, 11), (17, 11), (17, 12.5), (12.5, 12.5), (12.5, 17), (11, 17)),
                poly((12, 2), (17, 2), (17, 7), (15.5, 7), (15.5, 3.5), (12, 3.5)),
                poly((2, 12), (3.5, 12), (3.5, 16), (8, 16), (8, 17.5), (2, 17.5)),
            ],
        },
    )
    write(
        "map20-6",
        {
            "description": "Paper 003 map 6 style: rotated rectangles and circles mixed.",
            **S20,
            **enc,
            "obstacles": [
                poly((3, 6), (7, 2), (8.5, 3.5), (4.5, 7.5)),
                poly((9, 12), (13, 8), (14.5, 9.5), (10.5, 13.5)),
                poly((14, 17), (18, 13), (19, 14), (15, 18)),
                circle(6, 13, 2.0),
                circle(14, 4, 1.8),
            ],
        },
    )
    rects = []
    rng = np.random.default_rng(2027)
    for i in range(2, 18, 4):
        for j in range(2, 18, 4):
            dx, dy = rng.uniform(-0.8, 0.8, 2)
            rects.append(rect(i + dx, j + dy, i + dx + 1.6, j + dy + 1.6))
    write(
        "map20-7",
        {
            "description": "Paper 003 map 7 style: a lattice of sixteen small jittered squares.",
            **S20,
            **enc,
            "obstacles": rects,
        },
    )


def random_rects(seed: int, size: float, n: int, start: list, goal: list) -> list[dict]:
    rng = np.random.default_rng(seed)
    out: list[dict] = []
    while len(out) < n:
        w, h = rng.uniform(2, 8, 2)
        x, y = rng.uniform(0, size - w), rng.uniform(0, size - h)
        r = [x, y, x + w, y + h]
        # keep 2 units of room around start and goal
        if any(r[0] - 2 < p[0] < r[2] + 2 and r[1] - 2 < p[1] < r[3] + 2 for p in (start, goal)):
            continue
        out.append(rect(*(round(float(v), 2) for v in r)))
    return out


def maps50() -> None:
    for k, seed in ((1, 50_001), (2, 50_002)):
        start, goal = [0.5, 0.5], [49.5, 49.5]
        write(
            f"map50-{k}",
            {
                "description": f"Paper 003 scenario 2 style: 24 random rectangles (seed {seed}).",
                "bounds": [0, 0, 50, 50],
                "start": start,
                "goal": goal,
                "encoding": "segments",
                "nodes": 20,
                "obstacles": random_rects(seed, 50, 24, start, goal),
            },
        )


def building() -> None:
    walls = [
        # outer rooms: vertical walls with doors
        rect(30, 0, 31, 40),
        rect(30, 46, 31, 75),
        rect(30, 81, 31, 100),
        rect(65, 0, 66, 22),
        rect(65, 28, 66, 62),
        rect(65, 68, 66, 100),
        # horizontal walls with doors
        rect(0, 50, 12, 51),
        rect(18, 50, 30, 51),
        rect(66, 45, 85, 46),
        rect(91, 45, 100, 46),
        rect(31, 85, 45, 86),
        rect(51, 85, 65, 86),
        # exhibition stands and stage props
        rect(8, 10, 20, 16),
        rect(8, 25, 20, 31),
        rect(40, 10, 55, 18),
        rect(40, 30, 55, 38),
        rect(40, 55, 55, 70),
        rect(75, 10, 90, 30),
        rect(75, 60, 88, 72),
        rect(80, 80, 95, 90),
        rect(10, 65, 22, 85),
    ]
    write(
        "building100",
        {
            "description": "Paper 003 scenario 3 style: a 100 x 100 building (a small cultural "
            "complex: rooms with doors, exhibition stands, a stage).",
            "bounds": [0, 0, 100, 100],
            "start": [3.5, 3.5],
            "goal": [99.5, 99.5],
            "encoding": "segments",
            "nodes": 30,
            "obstacles": walls,
        },
    )


def grid_map(n: int, seed: int, blocks: list[tuple[int, int, int, int]]) -> list[str]:
    occ = np.zeros((n, n), dtype=bool)  # [row from top, column]
    for r0, c0, r1, c1 in blocks:
        occ[r0:r1, c0:c1] = True
    rng = np.random.default_rng(seed)
    extra = rng.random((n, n)) < 0.04
    occ |= extra
    occ[-2:, :2] = False  # start (bottom-left) and goal (top-right) corners free
    occ[:2, -2:] = False
    return ["".join("#" if v else "." for v in row) for row in occ]


def grids() -> None:
    rows20 = grid_map(
        20, 20, [(2, 3, 5, 8), (8, 10, 12, 13), (13, 2, 16, 7), (4, 14, 7, 18), (15, 12, 18, 16)]
    )
    write(
        "grid20",
        {
            "description": "Paper 001 style 20 x 20 occupancy grid (blocks and scattered cells).",
            "bounds": [0, 0, 20, 20],
            "start": [0.5, 0.5],
            "goal": [19.5, 19.5],
            "encoding": "grid",
            "obstacles": [{"type": "grid", "origin": [0, 0], "cell": 1, "rows": rows20}],
        },
    )
    rows40 = grid_map(
        40,
        40,
        [
            (3, 5, 9, 15),
            (12, 18, 20, 24),
            (25, 3, 30, 14),
            (6, 28, 13, 36),
            (30, 22, 36, 32),
            (18, 30, 26, 34),
            (20, 8, 23, 16),
        ],
    )
    write(
        "grid40",
        {
            "description": "Paper 001 style 40 x 40 occupancy grid (blocks and scattered cells).",
            "bounds": [0, 0, 40, 40],
            "start": [0.5, 0.5],
            "goal": [39.5, 39.5],
            "encoding": "grid",
            "obstacles": [{"type": "grid", "origin": [0, 0], "cell": 1, "rows": rows40}],
        },
    )


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    circle_maps()
    maps20()
    maps50()
    building()
    grids()
    print(f"wrote {len(list(OUT.glob('*.json')))} scenarios to {OUT}")
