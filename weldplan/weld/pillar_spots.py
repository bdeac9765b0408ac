"""A second held-out thin-feature station: the B-pillar of the generated side frame
(``python -m weldplan.weld.pillar_spots OUT``).

car2's thin wall (:mod:`weldplan.weld.wall_spots`) is one station the robot stage had not seen;
this is another of a different shape, so that what serves the one is not fitted to it. The side
frame of :mod:`weldplan.weld.sheetmetal` (sill, B-pillar and roof rail, each a hat section closed
by an inner panel, real lap joints 1.6-4.2 mm thick) is generated whole, and only the spots on the
**B-pillar's two flanges** are kept: two vertical lines of spots about 1 m tall on two thin
stacks a hat's width apart, standing free between the sill and the roof rail (10 mm clear of
each), the gun closing on each flange from the inner panel's side. Where the wall station's
spots lie along one horizontal edge and the gun slides from one to the next, here the gun must
leave one flange and cross the pillar's crown to reach the other.

Everything is a function of :class:`~weldplan.weld.sheetmetal.SheetFrameSettings` and the seed:
the same call gives the same files. The body is the whole frame (the sill and the roof rail are
obstacles); the spots are synthetic.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
from collections.abc import Sequence
from os import PathLike
from pathlib import Path

import numpy as np

from weldplan.io.joints import Joints
from weldplan.random import RNGLike
from weldplan.weld.sheetmetal import (
    SheetFrameSettings,
    SheetStation,
    generate_side_frame,
    station_texts,
)

log = logging.getLogger(__name__)

#: the member whose flanges carry the station's spots (one of
#: :data:`weldplan.weld.sheetmetal.MEMBERS`)
MEMBER = "bpillar"


def pillar_station(
    settings: SheetFrameSettings | None = None, *, rng: RNGLike = 0, member: str = MEMBER
) -> SheetStation:
    """The side frame of ``settings`` and ``rng`` (:func:`generate_side_frame`, every spot
    drawn) with only the spots on ``member``'s flanges kept, in their order.

    Raises
    ------
    ValueError
        ``member`` carries no spot (not a member of the frame).
    """
    s = dataclasses.replace(settings or SheetFrameSettings(), n_spots=None)
    full = generate_side_frame(s, rng=rng)
    keep = np.array([f.startswith(f"{member}_") for f in full.spot_flange], dtype=bool)
    if not keep.any():
        raise ValueError(f"no spot on a member named {member!r}")
    sp = full.spots
    assert sp.directions is not None
    spots = Joints(
        ids=tuple(i for i, k in zip(sp.ids, keep, strict=True) if k),
        xyz=sp.xyz[keep],
        directions=sp.directions[keep],
    )
    flanges = tuple(f for f, k in zip(full.spot_flange, keep, strict=True) if k)
    return dataclasses.replace(full, spots=spots, spot_flange=flanges)


def pillar_texts(station: SheetStation, member: str = MEMBER) -> dict[str, str]:
    """``body.obj``, ``spots.csv`` and ``truth.json`` of :func:`pillar_station`: those of
    :func:`~weldplan.weld.sheetmetal.station_texts`, the spots' header saying which were kept."""
    texts = station_texts(station)
    note = (
        f"# kept: the {len(station.spots)} spots on the {member}'s two flanges "
        f"(weldplan.weld.pillar_spots.pillar_station(rng={station.seed}))\n"
    )
    first, rest = texts["spots.csv"].split("\n", 1)  # the SYNTHETIC line stays first
    texts["spots.csv"] = f"{first}\n{note}{rest}"
    return texts


def write_pillar_station(station: SheetStation, out: str | PathLike[str]) -> list[Path]:
    """Write :func:`pillar_texts` into folder ``out`` (made if absent), all or none."""
    from weldplan.errors import InputError
    from weldplan.io.outputset import check_outputs, write_outputs

    folder = Path(out)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"cannot make the output folder ({exc.strerror or exc})", path=folder
        ) from exc
    texts = {folder / name: text for name, text in pillar_texts(station).items()}
    check_outputs({p.name: p for p in texts})
    return write_outputs(texts)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m weldplan.weld.pillar_spots OUT [--seed S]``: write the station's files."""
    ap = argparse.ArgumentParser(
        prog="python -m weldplan.weld.pillar_spots", description=__doc__.splitlines()[0]
    )
    ap.add_argument("out", help="folder to write body.obj, spots.csv and truth.json into")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    from weldplan.errors import WeldplanError

    try:
        paths = write_pillar_station(pillar_station(rng=args.seed), args.out)
    except WeldplanError as exc:
        ap.exit(2, f"error: {exc}\n")
    log.info("wrote %s", ", ".join(str(p) for p in paths))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
