"""The compiled search loop of :mod:`weldplan.planar.polyanya` (numba, cached on disk).

Why compiled: the same loop in Python costs about 20 us a node expansion and aurora's long
queries expand 20-30 thousand nodes (0.4 s a query, measured with cProfile on aurora); numba
brings an expansion to well under a microsecond. Without numba the functions run as plain
Python on the same arrays (slow, same answers).

Node storage is two growing arrays: ``NF (cap, 8) float`` = ``f, g, rx, ry, lx, ly, qx, qy``
(root ``r``, interval ``L = (lx, ly)``, ``R = (qx, qy)``) and ``NI (cap, 4) int`` = ``root
record, root vertex (-1: the start), polygon, entry edge`` (``L`` is the polygon's vertex
``j``, ``R`` its vertex ``j + 1``, up to the cuts of the projection). The final node has
polygon ``-2``, its turning point (if any) in ``lx, ly`` and ``j`` = -1/0/1 for through ``L``,
straight, through ``R``. Root records ``(x, y, parent)`` give the path back.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

try:  # pragma: no cover - exercised when numba is installed (a runtime dependency)
    from numba import njit
except ImportError:  # pragma: no cover

    def njit(*args: Any, **kwargs: Any) -> Any:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f


@njit(cache=True)
def heuristic(rx, ry, lx, ly, qx, qy, tx, ty):  # type: ignore[no-untyped-def]
    """The paper's h-value ("Evaluating Search Nodes"): the shortest ``|r x| + |x t|`` for
    ``x`` in the interval ``[L, R]``, the goal reflected across the interval's line when it is
    on the root's side. Returns ``(h, via)``: ``via`` 0 when the straight segment crosses the
    interval, -1 through ``L``, 1 through ``R``. A root on the interval's line gets the nearer
    endpoint's detour."""
    dx = qx - lx
    dy = qy - ly
    sr = dx * (ry - ly) - dy * (rx - lx)
    st = dx * (ty - ly) - dy * (tx - lx)
    if sr * st > 0.0:
        k = 2.0 * st / (dx * dx + dy * dy)
        tx = tx + k * dy
        ty = ty - k * dx
    if sr != 0.0:
        cr = (qx - rx) * (ty - ry) - (qy - ry) * (tx - rx)
        cl = (lx - rx) * (ty - ry) - (ly - ry) * (tx - rx)
        if cr >= 0.0 and cl <= 0.0:
            return math.hypot(tx - rx, ty - ry), 0
    hl = math.hypot(lx - rx, ly - ry) + math.hypot(tx - lx, ty - ly)
    hr = math.hypot(qx - rx, qy - ry) + math.hypot(tx - qx, ty - qy)
    if hl <= hr:
        return hl, -1
    return hr, 1


@njit(cache=True)
def _push(NF, NI, nn, g, rx, ry, rec, rv, lx, ly, qx, qy, poly, j, tx, ty, eps, prune, nexits,
          is_goal):  # type: ignore[no-untyped-def]  # fmt: skip
    """Store a successor unless it is empty or enters an obstacle or a cul-de-sac (the paper's
    pruning); returns the new node count."""
    if poly < 0:
        return nn
    if abs(lx - qx) + abs(ly - qy) <= eps:
        return nn
    if prune and nexits[poly] <= 1 and not is_goal[poly]:
        return nn
    h, _ = heuristic(rx, ry, lx, ly, qx, qy, tx, ty)
    NF[nn, 0] = g + h
    NF[nn, 1] = g
    NF[nn, 2] = rx
    NF[nn, 3] = ry
    NF[nn, 4] = lx
    NF[nn, 5] = ly
    NF[nn, 6] = qx
    NF[nn, 7] = qy
    NI[nn, 0] = rec
    NI[nn, 1] = rv
    NI[nn, 2] = poly
    NI[nn, 3] = j
    return nn + 1


@njit(cache=True)
def _expand(k, NF, NI, nn, RT, RP, nr, best, vx, vy, ptr, pv, pnb, pop, corner, nexits, is_goal,
            tx, ty, eps, prune, px, py):  # type: ignore[no-untyped-def]  # fmt: skip
    """Expand node ``k`` (the paper's "Successors", Fig. 3): observable successors between the
    rays through ``R`` and ``L``, non-observable ones rooted at ``R``'s or ``L``'s vertex when
    it is a corner, only the final node when the polygon holds the goal. Returns
    ``(node count, root count)``."""
    g = NF[k, 1]
    rx, ry = NF[k, 2], NF[k, 3]
    lx, ly, qx, qy = NF[k, 4], NF[k, 5], NF[k, 6], NF[k, 7]
    rec, rv, poly, j = NI[k, 0], NI[k, 1], NI[k, 2], NI[k, 3]
    if is_goal[poly]:  # the final node
        h, via = heuristic(rx, ry, lx, ly, qx, qy, tx, ty)
        NF[nn, 0] = g + h
        NF[nn, 1] = g
        NF[nn, 2] = rx
        NF[nn, 3] = ry
        NF[nn, 4] = lx if via == -1 else qx
        NF[nn, 5] = ly if via == -1 else qy
        NI[nn, 0] = rec
        NI[nn, 1] = rv
        NI[nn, 2] = -2
        NI[nn, 3] = via
        return nn + 1, nr
    b0 = ptr[poly]
    n = ptr[poly + 1] - b0
    # far boundary: vertex i = poly's vertex j + 1 + i (i = 0: R's vertex, n - 1: L's vertex);
    # far edge i runs from far vertex i to i + 1 and is poly's edge j + 1 + i
    for i in range(n):
        v = pv[b0 + (j + 1 + i) % n]
        px[i] = vx[v]
        py[i] = vy[v]
    dRx, dRy = qx - rx, qy - ry
    dLx, dLy = lx - rx, ly - ry
    nR = math.hypot(dRx, dRy)
    nL = math.hypot(dLx, dLy)
    if dRx * dLy - dRy * dLx <= eps * max(nR, nL):
        # the root is on the interval's line, at an end of the edge: it sees all of poly
        for i in range(n - 1):
            e = b0 + (j + 1 + i) % n
            nn = _push(NF, NI, nn, g, rx, ry, rec, rv, px[i + 1], py[i + 1], px[i], py[i],
                       pnb[e], pop[e], tx, ty, eps, prune, nexits, is_goal)  # fmt: skip
        return nn, nr
    tR = eps * nR
    tL = eps * nL
    i = 1
    while i < n - 1 and dRx * (py[i] - ry) - dRy * (px[i] - rx) <= tR:
        i += 1
    ir = i - 1  # the right ray leaves poly on far edge ir
    i = n - 2
    while i > 0 and dLx * (py[i] - ry) - dLy * (px[i] - rx) >= -tL:
        i -= 1
    il = max(i, ir)  # the left ray leaves poly on far edge il
    c0 = dRx * (py[ir] - ry) - dRy * (px[ir] - rx)
    c1 = dRx * (py[ir + 1] - ry) - dRy * (px[ir + 1] - rx)
    if -tR <= c0 <= tR:
        xrx, xry = px[ir], py[ir]
    else:
        s = c0 / (c0 - c1)
        xrx, xry = px[ir] + s * (px[ir + 1] - px[ir]), py[ir] + s * (py[ir + 1] - py[ir])
    c0 = dLx * (py[il] - ry) - dLy * (px[il] - rx)
    c1 = dLx * (py[il + 1] - ry) - dLy * (px[il + 1] - rx)
    if -tL <= c1 <= tL:
        xlx, xly = px[il + 1], py[il + 1]
    else:
        s = c0 / (c0 - c1)
        xlx, xly = px[il] + s * (px[il + 1] - px[il]), py[il] + s * (py[il + 1] - py[il])
    for i in range(ir, il + 1):  # observable: same root
        ax, ay = (xrx, xry) if i == ir else (px[i], py[i])
        bx, by = (xlx, xly) if i == il else (px[i + 1], py[i + 1])
        e = b0 + (j + 1 + i) % n
        nn = _push(NF, NI, nn, g, rx, ry, rec, rv, bx, by, ax, ay, pnb[e], pop[e], tx, ty, eps,
                   prune, nexits, is_goal)  # fmt: skip
    v = pv[b0 + (j + 1) % n]
    if corner[v] and abs(qx - px[0]) + abs(qy - py[0]) <= eps:
        g2 = g + nR
        if not (prune and g2 > best[v] + eps):
            if g2 < best[v]:
                best[v] = g2
            RT[nr, 0], RT[nr, 1] = px[0], py[0]
            RP[nr] = rec
            nr += 1
            for i in range(ir + 1):
                bx, by = (xrx, xry) if i == ir else (px[i + 1], py[i + 1])
                e = b0 + (j + 1 + i) % n
                nn = _push(NF, NI, nn, g2, px[0], py[0], nr - 1, v, bx, by, px[i], py[i],
                           pnb[e], pop[e], tx, ty, eps, prune, nexits, is_goal)  # fmt: skip
    v = pv[b0 + j]
    if corner[v] and abs(lx - px[n - 1]) + abs(ly - py[n - 1]) <= eps:
        g2 = g + nL
        if not (prune and g2 > best[v] + eps):
            if g2 < best[v]:
                best[v] = g2
            RT[nr, 0], RT[nr, 1] = px[n - 1], py[n - 1]
            RP[nr] = rec
            nr += 1
            for i in range(il, n - 1):
                ax, ay = (xlx, xly) if i == il else (px[i], py[i])
                e = b0 + (j + 1 + i) % n
                nn = _push(NF, NI, nn, g2, px[n - 1], py[n - 1], nr - 1, v, px[i + 1],
                           py[i + 1], ax, ay, pnb[e], pop[e], tx, ty, eps, prune, nexits,
                           is_goal)  # fmt: skip
    return nn, nr


@njit(cache=True)
def _heap_push(hf, hi, size, f, k):  # type: ignore[no-untyped-def]
    """Binary min-heap on arrays (keys ``hf``, node indices ``hi``): add ``(f, k)``."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if hf[p] <= f:
            break
        hf[i] = hf[p]
        hi[i] = hi[p]
        i = p
    hf[i] = f
    hi[i] = k
    return size + 1


@njit(cache=True)
def _heap_pop(hf, hi, size):  # type: ignore[no-untyped-def]
    """Remove the smallest key; returns ``(its node index, new size)``."""
    k = hi[0]
    size -= 1
    f = hf[size]
    x = hi[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and hf[c + 1] < hf[c]:
            c += 1
        if hf[c] >= f:
            break
        hf[i] = hf[c]
        hi[i] = hi[c]
        i = c
    if size > 0:
        hf[i] = f
        hi[i] = x
    return k, size


@njit(cache=True)
def search(vx, vy, ptr, pv, pnb, pop, corner, nexits, max_sides, spolys, gpolys, sx, sy, tx, ty,
           eps, prune):  # type: ignore[no-untyped-def]  # fmt: skip
    """A* over Polyanya search nodes from ``(sx, sy)`` (in the polygons ``spolys``) to
    ``(tx, ty)`` (in ``gpolys``). Returns ``(length, path (k, 2), expanded, generated)``;
    length ``inf`` and an empty path when the goal cannot be reached."""
    best = np.full(vx.shape[0], np.inf)
    is_goal = np.zeros(nexits.shape[0], dtype=np.bool_)
    for p in gpolys:
        is_goal[p] = True
    px = np.empty(max_sides)  # the far boundary of the polygon being expanded
    py = np.empty(max_sides)
    cap = 4096
    NF = np.empty((cap, 8))
    NI = np.empty((cap, 4), dtype=np.int64)
    RT = np.empty((cap, 2))
    RP = np.empty(cap, dtype=np.int64)
    RT[0, 0], RT[0, 1], RP[0] = sx, sy, -1
    nr = 1
    nn = 0
    room = 3 * max_sides + 4
    for p in spolys:  # the start's polygons: every edge not through the start
        b0 = ptr[p]
        n = ptr[p + 1] - b0
        if nn + n + 1 > cap:
            cap *= 2
            NF2 = np.empty((cap, 8))
            NF2[:nn] = NF[:nn]
            NF = NF2
            NI2 = np.empty((cap, 4), dtype=np.int64)
            NI2[:nn] = NI[:nn]
            NI = NI2
        for k in range(n):
            a = pv[b0 + k]
            b = pv[b0 + (k + 1) % n]
            ex, ey = vx[b] - vx[a], vy[b] - vy[a]
            if ex * (sy - vy[a]) - ey * (sx - vx[a]) <= eps * math.hypot(ex, ey):
                continue
            nn = _push(NF, NI, nn, 0.0, sx, sy, 0, -1, vx[b], vy[b], vx[a], vy[a], pnb[b0 + k],
                       pop[b0 + k], tx, ty, eps, prune, nexits, is_goal)  # fmt: skip
    hf = np.empty(cap)
    hi = np.empty(cap, dtype=np.int64)
    hs = 0
    for i in range(nn):
        hs = _heap_push(hf, hi, hs, NF[i, 0], i)
    expanded = 0
    while hs > 0:
        k, hs = _heap_pop(hf, hi, hs)
        if NI[k, 2] == -2:
            return _result(k, NF, NI, RT, RP, tx, ty), expanded, nn
        rv = NI[k, 1]
        if prune and rv >= 0 and NF[k, 1] > best[rv] + eps:
            continue  # root-level pruning at pop time
        while True:
            if nn + room > cap or nr + 2 > RT.shape[0]:
                cap *= 2
                NF2 = np.empty((cap, 8))
                NF2[:nn] = NF[:nn]
                NF = NF2
                NI2 = np.empty((cap, 4), dtype=np.int64)
                NI2[:nn] = NI[:nn]
                NI = NI2
                RT2 = np.empty((cap, 2))
                RT2[:nr] = RT[:nr]
                RT = RT2
                RP2 = np.empty(cap, dtype=np.int64)
                RP2[:nr] = RP[:nr]
                RP = RP2
                hf2 = np.empty(cap)
                hf2[:hs] = hf[:hs]
                hf = hf2
                hi2 = np.empty(cap, dtype=np.int64)
                hi2[:hs] = hi[:hs]
                hi = hi2
            first = nn
            nn, nr = _expand(k, NF, NI, nn, RT, RP, nr, best, vx, vy, ptr, pv, pnb, pop, corner,
                             nexits, is_goal, tx, ty, eps, prune, px, py)  # fmt: skip
            expanded += 1
            if prune and nn - first == 1 and NI[first, 2] != -2:
                k = first  # intermediate pruning: expand the lone successor at once
                continue
            for i in range(first, nn):
                hs = _heap_push(hf, hi, hs, NF[i, 0], i)
            break
    length = np.inf
    return (length, np.empty((0, 2))), expanded, nn


@njit(cache=True)
def _result(k, NF, NI, RT, RP, tx, ty):  # type: ignore[no-untyped-def]
    """The final node's length and waypoints (start, turning points, goal)."""
    m = 2 if NI[k, 3] != 0 else 1
    rec = NI[k, 0]
    while rec >= 0:
        m += 1
        rec = RP[rec]
    out = np.empty((m, 2))
    out[m - 1, 0], out[m - 1, 1] = tx, ty
    i = m - 2
    if NI[k, 3] != 0:
        out[i, 0], out[i, 1] = NF[k, 4], NF[k, 5]
        i -= 1
    rec = NI[k, 0]
    while rec >= 0:
        out[i, 0], out[i, 1] = RT[rec, 0], RT[rec, 1]
        i -= 1
        rec = RP[rec]
    return NF[k, 0], out
