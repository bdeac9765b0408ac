"""Results of the transition planning: the whole tool's path from weld to weld.

A :class:`Transition` is the motion of the tool from one weld pose to the next, as TCP poses
``(positions (k, 3) mm, quaternions (k, 4) qw, qx, qy, qz)``; between consecutive poses the TCP
moves on the straight segment and the orientation turns by spherical linear interpolation
(:mod:`weldplan.tool.transitions.sweep`). A :class:`ToolPath` gathers the transitions of a route, in
the order the tool visits the welds (which may differ from the point-tip route's order:
:mod:`weldplan.tool.transitions.order`). Both are frozen and round-trip through JSON.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.pathcore import polyline_length

#: a transition that retracts, moves and approaches on the TCP path, its sweeps all free
DIRECT = "direct"
#: a transition re-planned in SE(3) (OMPL), its sweeps all free
REPLANNED = "replanned"
#: a transition for which no free motion was found (reported, never verified)
BLOCKED = "blocked"
#: statuses of a transition whose every motion passed the planner's swept-tool check
FREE_STATUSES = (DIRECT, REPLANNED)
#: how a free transition leaves and reaches its welds (:attr:`Transition.via`): retract along
#: the axis, slide along the flange, side exit, SE(3) re-plan
VIAS = ("axial", "slide", "side", "se3")


def path_length(positions: NDArray[np.float64]) -> float:
    """mm: the TCP polyline's length."""
    return polyline_length(np.asarray(positions, dtype=np.float64).reshape(-1, 3))


def path_rotation(quaternions: NDArray[np.float64]) -> float:
    """Degrees: the summed rotation angle between consecutive orientations ``(k, 4)``."""
    Q = np.asarray(quaternions, dtype=np.float64).reshape(-1, 4)
    if len(Q) < 2:
        return 0.0
    dot = np.abs(np.einsum("ij,ij->i", Q[:-1], Q[1:]))
    return float(np.degrees(2.0 * np.arccos(np.clip(dot, 0.0, 1.0))).sum())


@dataclass(frozen=True, eq=False)
class Transition:
    """The tool's motion from weld ``from_id``'s pose to weld ``to_id``'s pose.

    Attributes
    ----------
    from_id, to_id
        The welds (both with a verified pose).
    positions
        ``(k, 3)`` mm: TCP positions, the first the from-weld's spot and the last the to-weld's.
    quaternions
        ``(k, 4)``: TCP orientations ``(qw, qx, qy, qz)`` in the part frame.
    kinds
        ``(k - 1,)`` what each motion is: ``"retract"``, ``"move"``, ``"approach"`` or ``"se3"``.
    status
        :data:`DIRECT`, :data:`REPLANNED` or :data:`BLOCKED`.
    reason
        The exits tried before the one taken (all of them for a blocked transition) and where
        each was blocked, and OMPL's status and counts for an SE(3) re-plan; empty when the
        first exit tried was free.
    samples
        FCL distance samples the planner's swept check took.
    """

    from_id: str
    to_id: str
    positions: NDArray[np.float64]
    quaternions: NDArray[np.float64]
    kinds: tuple[str, ...]
    status: str
    reason: str = ""
    samples: int = 0

    def __post_init__(self) -> None:
        P = np.array(self.positions, dtype=np.float64).reshape(-1, 3)
        Q = np.array(self.quaternions, dtype=np.float64).reshape(-1, 4)
        if len(P) != len(Q) or len(P) < 2 or len(self.kinds) != len(P) - 1:
            raise ValueError(
                f"transition {self.from_id}->{self.to_id}: {len(P)} positions, {len(Q)} "
                f"quaternions and {len(self.kinds)} motions do not fit"
            )
        P.setflags(write=False)
        Q.setflags(write=False)
        object.__setattr__(self, "positions", P)
        object.__setattr__(self, "quaternions", Q)
        object.__setattr__(self, "kinds", tuple(str(k) for k in self.kinds))

    @property
    def free(self) -> bool:
        return self.status in FREE_STATUSES

    @property
    def via(self) -> str:
        """How the tool goes (:data:`VIAS`, from the motions' kinds), ``"blocked"`` when not
        free: ``"se3"`` re-planned, ``"slide"`` along the flange, ``"side"`` when a weld is left
        or reached by a side exit, else ``"axial"``."""
        if not self.free:
            return "blocked"
        if self.status == REPLANNED:
            return "se3"
        if "slide" in self.kinds:
            return "slide"
        if any(k.startswith(("exit ", "enter ")) for k in self.kinds):
            return "side"
        return "axial"

    @property
    def length(self) -> float:
        """mm of TCP path."""
        return path_length(self.positions)

    @property
    def rotation(self) -> float:
        """Degrees of orientation change along the transition."""
        return path_rotation(self.quaternions)

    def to_dict(self) -> dict[str, Any]:
        return {
            "from": self.from_id,
            "to": self.to_id,
            "status": self.status,
            "reason": self.reason,
            "samples": self.samples,
            "kinds": list(self.kinds),
            "positions": self.positions.tolist(),
            "quaternions": self.quaternions.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Transition:
        return cls(
            from_id=str(d["from"]),
            to_id=str(d["to"]),
            positions=np.asarray(d["positions"], dtype=np.float64),
            quaternions=np.asarray(d["quaternions"], dtype=np.float64),
            kinds=tuple(d["kinds"]),
            status=str(d["status"]),
            reason=str(d.get("reason", "")),
            samples=int(d.get("samples", 0)),
        )


@dataclass(frozen=True)
class ToolPath:
    """The tool's transitions through the welds that have a pose, in visiting order.

    Attributes
    ----------
    order
        The welds with a pose, in the order the tool visits them.
    transitions
        ``len(order) - 1`` transitions, transition ``k`` from ``order[k]`` to ``order[k + 1]``.
    skipped
        Welds without a free pose (not visited by the tool; their closest miss is in the poses).
    settings
        ``retract`` (mm), ``clearance``, ``contact_radius``, ``rot_weight`` (mm per rad), the
        SE(3) planner and its time, the order's source.
    stats
        Figures: costs of the point-tip order and of the chosen order, seconds, samples.
    """

    order: tuple[str, ...]
    transitions: tuple[Transition, ...]
    skipped: tuple[str, ...] = ()
    settings: dict[str, Any] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if len(self.transitions) != max(len(self.order) - 1, 0):
            raise ValueError("a tool path over k welds has k - 1 transitions")
        for k, t in enumerate(self.transitions):
            if (t.from_id, t.to_id) != (self.order[k], self.order[k + 1]):
                raise ValueError(f"transition {k} runs {t.from_id}->{t.to_id}, not in the order")

    @property
    def length(self) -> float:
        """mm: the TCP path's total length."""
        return float(sum(t.length for t in self.transitions))

    @property
    def rotation(self) -> float:
        """Degrees: the total orientation change."""
        return float(sum(t.rotation for t in self.transitions))

    @property
    def n_replanned(self) -> int:
        return sum(t.status == REPLANNED for t in self.transitions)

    @property
    def blocked(self) -> tuple[Transition, ...]:
        return tuple(t for t in self.transitions if not t.free)

    def by_via(self) -> dict[str, int]:
        """Transitions per :attr:`Transition.via` (every kind of :data:`VIAS` and ``blocked``)."""
        counts = dict.fromkeys((*VIAS, "blocked"), 0)
        for t in self.transitions:
            counts[t.via] += 1
        return counts

    def waypoints(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(m, 3)`` positions and ``(m, 4)`` quaternions of the whole path (shared weld poses
        not repeated)."""
        if not self.transitions:
            return np.zeros((0, 3)), np.zeros((0, 4))
        P = [self.transitions[0].positions[:1]] + [t.positions[1:] for t in self.transitions]
        Q = [self.transitions[0].quaternions[:1]] + [t.quaternions[1:] for t in self.transitions]
        return np.concatenate(P), np.concatenate(Q)

    def summary(self) -> str:
        n = len(self.transitions)
        via = self.by_via()
        text = (
            f"{n - len(self.blocked)} / {n} transitions free for the swept tool "
            f"(axial {via['axial']}, slide {via['slide']}, side {via['side']}, re-planned in "
            f"SE(3) {via['se3']}); TCP path {self.length:.1f} mm, "
            f"orientation change {self.rotation:.1f} deg"
        )
        for t in self.blocked:
            text += f"\n  {t.from_id}->{t.to_id}: blocked; {t.reason}"
        return text

    def to_dict(self) -> dict[str, Any]:
        return {
            "order": list(self.order),
            "skipped": list(self.skipped),
            "settings": self.settings,
            "stats": self.stats,
            "length": self.length,
            "rotation": self.rotation,
            "transitions": [t.to_dict() for t in self.transitions],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ToolPath:
        return cls(
            order=tuple(str(i) for i in d["order"]),
            transitions=tuple(Transition.from_dict(t) for t in d["transitions"]),
            skipped=tuple(str(i) for i in d.get("skipped", ())),
            settings=dict(d.get("settings", {})),
            stats=dict(d.get("stats", {})),
        )


def finite(x: float) -> float | None:
    """JSON-safe float (None for NaN/inf)."""
    return float(x) if math.isfinite(x) else None
