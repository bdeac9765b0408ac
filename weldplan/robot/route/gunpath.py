"""The robot follows the gun: a route in the tool stage's order whose legs are its transitions.

The tool stage (:mod:`weldplan.tool.transitions.reorder`, :mod:`weldplan.tool.transitions.plan`)
orders the welds that have a pose on the tool's own costs and plans, for each pair in that order, a
transition of the whole tool whose every motion passed its swept check (a lift and a slide along the
flange, an axial retract, a side exit, an SE(3) re-plan) or reports it blocked. :func:`gun_route`
turns that :class:`~weldplan.tool.transitions.ToolPath` into the route the robot follows:

* the welds in the tool's order (the welds without a pose are not on it: the tool never reaches
  them);
* each leg the TCP path of its transition, every motion (straight TCP segment, orientation
  slerped: :mod:`weldplan.tool.transitions.sweep`'s model) cut into steps of at most :data:`STEP_MM`
  mm and :data:`STEP_DEG` deg, so that IK along it (:func:`weldplan.robot.route.joint_path`: one
  continuous branch, limits, singularities, flips) puts the TCP on the gun's path at every step;
  a blocked transition's leg is the spot-to-spot segment without steps (one joint motion, which
  the robot's check must prove or the detour replaces);
* the TCP pose at every waypoint (:attr:`GunRoute.tcp`: the transition's own orientations, not
  the point-tip route's slerp by arc length);
* per motion whether the tool's contact zone may be exempt in the robot's check
  (:attr:`GunRoute.zone`): only where both ends of the motion have the TCP within the contact
  radius of the weld spot it leaves or reaches (the lift off the sheet and the lowering onto it,
  as the gun stage exempts only the sphere about each spot); every other motion is checked with
  the whole tool and every link.

The robot's joint path along this route is then checked by the same
:class:`~weldplan.robot.collision.RobotCollision` proof as any robot route; the gun stage's
verdict is a guide, not a proof, for the robot (its joint motion between two steps is not the
gun's Cartesian motion). When the gun stage supplies a transition for a pair that was blocked
(an SE(3) bridge), the robot follows it with no change here.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

log = logging.getLogger(__name__)

#: mm, deg: the largest TCP step between two IK samples along a gun transition (the robot's
#: joint motion between samples leaves the gun's straight segment by a little; the check is of
#: the joint motion itself)
STEP_MM = 20.0
STEP_DEG = 10.0


@dataclass(frozen=True, eq=False)
class GunRoute:
    """The route the robot follows along the gun's transitions (module docstring).

    Attributes
    ----------
    route
        :class:`~weldplan.weld.route.Route` in the tool's order; leg ``k`` the TCP path of
        transition ``k`` (``method`` ``"gun <via>"``).
    poses
        :class:`~weldplan.tool.poses.WeldPoses`: the route's poses, in this route's order.
    tcp
        ``(m, 4, 4)`` mm: the TCP pose at every waypoint of ``route``.
    zone
        ``(m - 1,) bool``: the motions whose contact zone may be exempt.
    via
        Per leg, how the gun goes (:attr:`~weldplan.tool.transitions.Transition.via`).
    exits
        Per route row of a weld, the TCP paths ``(k, 4, 4)`` leaving it that the gun stage
        proved free (:func:`gun_exits`), longest first: a robot detour leaves and reaches the
        weld along them before its own retracts (:meth:`weldplan.robot.route.Detour.leave`).
    """

    route: Any
    poses: Any
    tcp: NDArray[np.float64]
    zone: NDArray[np.bool_]
    via: tuple[str, ...]
    exits: dict[int, tuple[NDArray[np.float64], ...]] = field(default_factory=dict)

    def quaternions(self) -> NDArray[np.float64]:
        """``(m, 4)``: the TCP orientations ``(qw, qx, qy, qz)``, ``qw >= 0``."""
        q = np.roll(Rotation.from_matrix(self.tcp[:, :3, :3]).as_quat(), 1, axis=1)
        return np.where(q[:, :1] < 0, -q, q)

    def to_dict(self) -> dict[str, Any]:
        """The route and its orientations (for the route JSON's robot section)."""
        return {
            "route": self.route.to_dict(),
            "quaternions": self.quaternions().tolist(),
            "zone": self.zone.astype(int).tolist(),
            "via": list(self.via),
        }


def gun_route(
    route: Any,
    poses: Any,
    path: Any,
    *,
    contact_radius: float,
    step_mm: float = STEP_MM,
    step_deg: float = STEP_DEG,
) -> GunRoute:
    """The route along the gun's transitions (module docstring).

    Parameters
    ----------
    route
        The point-tip :class:`~weldplan.weld.route.Route` (its joints and settings are kept).
    poses
        Its :class:`~weldplan.tool.poses.WeldPoses` (route order).
    path
        The tool stage's :class:`~weldplan.tool.transitions.ToolPath` over those poses.
    contact_radius
        mm: the tool's contact zone (:attr:`GunRoute.zone`).
    step_mm, step_deg
        The largest TCP step between IK samples along a free transition.
    """
    import dataclasses

    from weldplan.tool.poses.route_frames import weld_rows
    from weldplan.tool.section import ToolSection
    from weldplan.weld.route import Leg

    if not path.order:
        raise ValueError("the tool path visits no weld")
    by_id = {p.id: p for p in poses.poses}
    legs, P_all, Q_all, via = [], [], [], []
    for t in path.transitions:
        P, Q = np.asarray(t.positions), np.asarray(t.quaternions)
        if t.free:
            P, Q = _steps(*_split_ends(P, Q, contact_radius), step_mm, step_deg)
        else:
            P, Q = P[[0, -1]], Q[[0, -1]]
        legs.append(Leg(t.from_id, t.to_id, P, method=f"gun {t.via}"))
        P_all.append(P if not P_all else P[1:])
        Q_all.append(Q if not Q_all else Q[1:])
        via.append(t.via)
    first = by_id[path.order[0]]
    P = np.concatenate(P_all) if P_all else np.asarray([first.position], dtype=np.float64)
    Q = np.concatenate(Q_all) if Q_all else np.asarray([first.quaternion], dtype=np.float64)
    gr = ToolSection().on(dataclasses.replace(route, order=tuple(path.order), legs=tuple(legs)))
    gposes = dataclasses.replace(poses, poses=tuple(by_id[i] for i in path.order))
    T = np.tile(np.eye(4), (len(P), 1, 1))
    T[:, :3, :3] = Rotation.from_quat(np.roll(Q, -1, axis=1)).as_matrix()
    T[:, :3, 3] = P
    zone = _zone_mask(gr, P, contact_radius)
    rows = weld_rows(gr)
    exits = {
        int(rows[k]): gun_exits(path, w, contact_radius, step_mm, step_deg)
        for k, w in enumerate(path.order)
    }
    return GunRoute(gr, gposes, T, zone, tuple(via), {r: e for r, e in exits.items() if e})


#: kinds of a transition's motions that leave its first weld (its exit), and that reach its
#: last one (its entry, reversed an exit): :mod:`weldplan.tool.transitions.plan`
LEAVING = ("lift", "retract")
REACHING = ("lower", "lift", "approach")
#: mm: an exit whose TCP path is not longer than this is left to the robot's own retracts
#: (:data:`weldplan.robot.route.RETRACT_MM` has the gun's 10 and 20 mm lifts along the axis)
EXIT_MIN_MM = 40.0


def gun_exits(
    path: Any, weld: str, radius: float, step_mm: float = STEP_MM, step_deg: float = STEP_DEG
) -> tuple[NDArray[np.float64], ...]:
    """TCP paths ``(k, 4, 4)`` mm leaving ``weld`` that the gun stage proved free, longest
    first, in IK steps (the first step ends within ``radius`` of the spot):

    * of each free transition out of it, its motions before the move (a lift, a side exit and
      its retract, an axial retract: kinds :data:`LEAVING` or ``exit ...``); of an SE(3)
      re-plan, its first half;
    * of each free transition into it, the same from its end, reversed.

    Exits not longer than :data:`EXIT_MIN_MM` are left out (the robot's retracts try them).
    """
    out: dict[bytes, NDArray[np.float64]] = {}
    for t in path.transitions:
        if not t.free or weld not in (t.from_id, t.to_id):
            continue
        P, Q = np.asarray(t.positions), np.asarray(t.quaternions)
        if t.to_id == weld:
            P, Q, kinds = P[::-1], Q[::-1], t.kinds[::-1]
            keep = REACHING
        else:
            kinds, keep = t.kinds, LEAVING
        n = len(P) // 2 + 1 if t.status == "replanned" else _exit_points(kinds, keep)
        P, Q = P[:n], Q[:n]
        if len(P) < 2 or np.linalg.norm(np.diff(P, axis=0), axis=1).sum() <= EXIT_MIN_MM:
            continue
        P, Q = _steps(*_split_ends(P, Q, radius, ends=(0,)), step_mm, step_deg)
        T = np.tile(np.eye(4), (len(P), 1, 1))
        T[:, :3, :3] = Rotation.from_quat(np.roll(Q, -1, axis=1)).as_matrix()
        T[:, :3, 3] = P
        out.setdefault(np.round(P, 3).tobytes(), T)
    length = {
        k: float(np.linalg.norm(np.diff(T[:, :3, 3], axis=0), axis=1).sum()) for k, T in out.items()
    }
    return tuple(out[k] for k in sorted(out, key=lambda k: -length[k]))


def _exit_points(kinds: tuple[str, ...], keep: tuple[str, ...]) -> int:
    """The number of points of a transition's path before its first motion that is neither of
    ``keep`` nor a side exit (``exit ...``, ``enter ...``): its exit, from its first point."""
    for i, k in enumerate(kinds):
        if not (k in keep or k.startswith(("exit ", "enter "))):
            return i + 1
    return len(kinds) + 1


def _steps(
    P: NDArray[np.float64], Q: NDArray[np.float64], step_mm: float, step_deg: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``P (k, 3)``, ``Q (k, 4)`` with every motion cut into equal steps of at most ``step_mm``
    of TCP travel and ``step_deg`` of turn (straight segment, slerp: the gun's motion model)."""
    outP, outQ = [P[:1]], [Q[:1]]
    for i in range(len(P) - 1):
        R = Rotation.from_quat(np.roll(Q[i : i + 2], -1, axis=1))
        ang = math.degrees((R[0].inv() * R[1]).magnitude())
        n = max(1, math.ceil(np.linalg.norm(P[i + 1] - P[i]) / step_mm), math.ceil(ang / step_deg))
        s = np.linspace(0.0, 1.0, n + 1)[1:]
        outP.append(P[i] + s[:, None] * (P[i + 1] - P[i]))
        q = np.roll(Slerp([0.0, 1.0], R)(s).as_quat(), 1, axis=1)
        q[-1] = Q[i + 1]  # the transition's own end, bit for bit
        outQ.append(q)
    return np.concatenate(outP), np.concatenate(outQ)


def _split_ends(
    P: NDArray[np.float64],
    Q: NDArray[np.float64],
    radius: float,
    ends: tuple[int, ...] = (0, -1),
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``P``, ``Q`` with a point added on the first and the last motion (``ends``) where the
    TCP is ``radius`` from the spot (when that motion goes farther): the contact zone is exempt
    up to there, and the rest of the motion is checked with the whole tool."""
    for end in ends:
        i, j = (0, 1) if end == 0 else (len(P) - 1, len(P) - 2)
        d = float(np.linalg.norm(P[j] - P[i]))
        if radius <= 0 or d <= radius * (1 + 1e-9):
            continue
        f = radius / d
        R = Rotation.from_quat(np.roll(Q[[i, j]], -1, axis=1))
        q = np.roll(Slerp([0.0, 1.0], R)([f]).as_quat()[0], 1)
        at = 1 if end == 0 else len(P) - 1
        P = np.insert(P, at, P[i] + f * (P[j] - P[i]), axis=0)
        Q = np.insert(Q, at, q, axis=0)
    return P, Q


def _zone_mask(route: Any, P: NDArray[np.float64], radius: float) -> NDArray[np.bool_]:
    """``(m - 1,) bool``: motion ``i`` exempts the contact zone when both its ends lie within
    ``radius`` of the spot of the weld its leg leaves or reaches."""
    from weldplan.tool.poses.route_frames import weld_rows

    rows = weld_rows(route)
    zone = np.zeros(max(len(P) - 1, 0), dtype=bool)
    for k in range(len(rows) - 1):
        a, b = int(rows[k]), int(rows[k + 1])
        zone[a:b] = _same_end(P[a : b + 1], P[a], P[b], radius)
    return zone


def _same_end(
    P: NDArray[np.float64], pa: NDArray[np.float64], pb: NDArray[np.float64], radius: float
) -> NDArray[np.bool_]:
    """``(len(P) - 1,) bool``: both ends of each motion near the same spot (not one near ``pa``
    and the other near ``pb``, a jump between two close welds)."""
    na = np.linalg.norm(P - pa, axis=1) <= radius
    nb = np.linalg.norm(P - pb, axis=1) <= radius
    return (na[:-1] & na[1:]) | (nb[:-1] & nb[1:])


def legs_taken(
    via: tuple[str, ...], status: tuple[str, ...], replanned: tuple[int, ...]
) -> list[str]:
    """How the robot went between each two consecutive served welds: ``"gun <via>"`` along the
    gun's transitions (every leg between them free for the gun), ``"detour"`` (retract, transfer,
    approach: :mod:`weldplan.robot.route.replan`), ``"joint"`` (the gun's transition is blocked, the
    robot's own joint motion was proved free)."""
    served = [k for k, s in enumerate(status) if s == "ok"]
    out = []
    for a, b in zip(served[:-1], served[1:], strict=True):
        if a in replanned:
            out.append("detour")
        elif any(v == "blocked" for v in via[a:b]):
            out.append("joint")
        else:
            out.append("gun " + "+".join(dict.fromkeys(via[a:b])))
    return out
