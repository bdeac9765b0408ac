"""The study as a table: one row per spot, a verdict column and a reason column per tool and per
(tool, robot) (``weldplan check-spots -o table.csv``).

Columns: ``id, x, y, z`` (mm, part frame), ``surface_mm`` (distance to the part), ``stack``,
``feasible`` (``yes``/``no``), then per tool ``gun:<tool>`` (the verdict word),
``gun:<tool>:free`` (free candidates / candidates) and ``gun:<tool>:reason`` (the closest miss,
where the gun hits), then per tool and robot ``robot:<robot>:<tool>`` and its ``:reason``. A
header comment line says what produced the file and in which frame.
"""

from __future__ import annotations

import csv
import io

from weldplan.study.result import FeasibilityStudy


def table_rows(study: FeasibilityStudy) -> list[list[str]]:
    """The header and one row per spot, as strings."""
    header = ["id", "x", "y", "z", "surface_mm", "stack", "feasible"]
    for t in study.tools:
        header += [f"gun:{t}", f"gun:{t}:free", f"gun:{t}:reason"]
    for t in study.tools:
        for r in study.robots:
            header += [f"robot:{r.name}:{t}", f"robot:{r.name}:{t}:reason"]
    rows = [header]
    for s in study.spots:
        row = [s.id, *(f"{v:.3f}" for v in s.position), f"{s.surface_distance:.2f}", s.stack]
        row.append("yes" if s.feasible else "no")
        for g in s.guns:
            row += [g.status, f"{g.n_free}/{g.n_candidates}", g.reason]
        for v in s.robots:
            row += [v.status, v.reason]
        rows.append(row)
    return rows


def study_csv_text(study: FeasibilityStudy, *, title: str = "weldplan check-spots") -> str:
    """The CSV text (module docstring), ``#`` comment lines first."""
    out = io.StringIO()
    n_ok = int(study.feasible.sum())
    out.write(f"# {title}: {n_ok} / {len(study.spots)} spots feasible; {study.frame} frame, mm\n")
    for r in study.robots:
        x, y, z, yaw = r.xyz_yaw()
        how = f"searched for tool {r.tool}" if r.searched else (r.note or "given")
        out.write(f"# robot {r.name}: base {x:.1f},{y:.1f},{z:.1f},{yaw:.2f} ({how})\n")
    w = csv.writer(out, lineterminator="\n")
    w.writerows(table_rows(study))
    return out.getvalue()
