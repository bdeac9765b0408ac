"""The feasibility study's stack column from the mesh: :func:`flange_stacks`.

The study's ``stacks`` hook (:data:`weldplan.study.feasibility.StackFinder`) filled by the flange
detector (:func:`weldplan.geometry.flanges.snap_spots`): for each spot, the sheets of the stack it
sits on, their gauges and gaps, the overlap and the distance to the free edge, or why there is no
stack a gun can close on (no sheet near, a single skin, a stack too thick or too narrow, no free
edge). A spot joins two sheets; slab models such as car2 are judged with ``walls=True``, where
a body thin enough for a gun to straddle near a free edge counts as a ``wall``
(``weldplan check-spots --walls``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray


def stack_words(snap: Any) -> str:
    """One cell of the table for a :class:`~weldplan.geometry.flanges.SpotSnap`: ``"stack
    b1+b2 (1.00+1.20 mm, gap 0.20 mm; overlap 20 mm, edge 8 mm)"`` or ``"none: <reason>"``."""
    st = snap.stack
    if st is None or not snap.ok:
        return f"none: {snap.verdict}: {snap.reason}"
    gauges = "+".join(f"{g:.2f}" for g in st.gauges)
    gaps = ", ".join(f"{g:.2f}" for g in st.gaps)
    overlap = "wide" if not np.isfinite(st.overlap) else f"{st.overlap:.0f} mm"
    edge = "none near" if st.edge_distance is None else f"{st.edge_distance:.0f} mm"
    return (
        f"{st.kind} {'+'.join(st.bodies)} ({gauges} mm"
        + (f", gap {gaps} mm" if gaps else "")
        + f"; overlap {overlap}, edge {edge})"
    )


def flange_stacks(walls: bool = False) -> Any:
    """The study's stack hook (``stacks(part, xyz) -> words``) backed by
    :func:`~weldplan.geometry.flanges.snap_spots` (``walls``: slab walls count, module
    docstring)."""
    from weldplan.geometry.flanges import snap_spots
    from weldplan.geometry.stacks import FlangeSettings

    settings = FlangeSettings(walls=walls)

    def stacks(part: Any, xyz: NDArray[np.float64]) -> Sequence[str]:
        return [stack_words(s) for s in snap_spots(part, xyz, settings)]

    return stacks
