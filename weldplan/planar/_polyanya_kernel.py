"""The compiled search loop of :mod:`weldplan.planar.polyanya` (numba, cached on disk).

Why compiled: the same loop in Python costs about 20 us a node expansion and aurora's long
queries expand 20-30 thousand nodes (0.4 s a query, measured with cProfile on aurora); numba
brings an expansion to about 0.35 us of CPU (aurora, 2,990 queries: 12.5 s of CPU in all,
with loading; the hot loop is one function, see :func:`_search`). Without numba the functions
run as plain Python on the same arrays (slow, same answers).

Node storage is two arrays of fixed room per search (:func:`search` reruns a search that
outgrows it): ``NF (cap, 8) float`` = ``f, g, rx, ry, lx, ly, qx, qy``
(root ``r``, interval ``L = (lx, ly)``, ``R = (qx, qy)``) and ``NI (cap, 4) int`` = ``root
record, root vertex (-1: the start), polygon, entry edge`` (``L`` is the polygon's vertex
``j``, ``R`` its vertex ``j + 1``, up to the cuts of the projection). The final node has
polygon ``-2``, its turning point (if any) in ``lx, ly`` and ``j`` = -1/0/1 for through ``L``,
straight, through ``R``. Root records ``(x, y, parent)`` give the path back.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

try:  # pragma: no cover - exercised when numba is installed (a runtime dependency)
    from numba import njit
except ImportError:  # pragma: no cover

    def njit(*args: Any, **kwargs: Any) -> Any:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f


@njit(cache=True)
def _norm(x, y):  # type: ignore[no-untyped-def]
    """``sqrt(x^2 + y^2)``: the ordering key's distances. ``math.hypot`` (libm, correctly
    rounded, guarded against overflow) was 16 % of the search's ``perf`` samples on aurora;
    this one is an instruction and differs from it by about an ulp. Lengths (``g`` and the
    final node's ``h``) keep ``math.hypot``."""
    return math.sqrt(x * x + y * y)


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
            return _norm(tx - rx, ty - ry), 0
    hl = _norm(lx - rx, ly - ry) + _norm(tx - lx, ty - ly)
    hr = _norm(qx - rx, qy - ry) + _norm(tx - qx, ty - qy)
    if hl <= hr:
        return hl, -1
    return hr, 1


@njit(cache=True)
def _heap_push(H, size, f, k):  # type: ignore[no-untyped-def]
    """Binary min-heap on one ``(cap, 2)`` array (key, node index as a float: exact below
    2**53): add ``(f, k)``."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if H[p, 0] <= f:
            break
        H[i, 0] = H[p, 0]
        H[i, 1] = H[p, 1]
        i = p
    H[i, 0] = f
    H[i, 1] = k
    return size + 1


@njit(cache=True)
def _heap_pop(H, size):  # type: ignore[no-untyped-def]
    """Remove the smallest key; returns ``(its node index, new size)``."""
    k = int(H[0, 1])
    size -= 1
    f = H[size, 0]
    x = H[size, 1]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and H[c + 1, 0] < H[c, 0]:
            c += 1
        if H[c, 0] >= f:
            break
        H[i, 0] = H[c, 0]
        H[i, 1] = H[c, 1]
        i = c
    if size > 0:
        H[i, 0] = f
        H[i, 1] = x
    return k, size


class KernelMesh(NamedTuple):
    """The mesh as the kernels read it, built once per mesh (:class:`weldplan.planar.polyanya.
    Polyanya`): vertices ``vx, vy (n_v,) float``; polygon ``p``'s vertex and edge slots
    ``ptr[p]:ptr[p + 1]`` into ``pv`` (vertex), ``pnb`` (the polygon across the edge, -1 an
    obstacle) and ``pop`` (the edge's slot in that polygon); ``corner (n_v,) bool`` (where a path
    may turn); ``nexits (n_p,) int`` (edges that are not obstacles); ``max_sides`` (the most
    sides of a polygon); ``eps`` (the mesh's tolerance)."""

    vx: NDArray[np.float64]
    vy: NDArray[np.float64]
    ptr: NDArray[np.int64]
    pv: NDArray[np.int64]
    pnb: NDArray[np.int64]
    pop: NDArray[np.int64]
    corner: NDArray[np.bool_]
    nexits: NDArray[np.int64]
    max_sides: int
    eps: float


class Query(NamedTuple):
    """One query: from ``(sx, sy)`` (in the polygons ``spolys``) to ``(tx, ty)`` (in
    ``gpolys``), with or without the paper's pruning (``prune``)."""

    sx: float
    sy: float
    tx: float
    ty: float
    spolys: NDArray[np.int64]
    gpolys: NDArray[np.int64]
    prune: bool


@njit(cache=True)
def search(mesh, query, cap=1 << 15):  # type: ignore[no-untyped-def]
    """A* over Polyanya search nodes for one :class:`Query` on a :class:`KernelMesh`. Returns
    ``(length, path (k, 2), expanded, generated)``; length ``inf`` and an empty path when the
    goal cannot be reached.

    The node arrays have a fixed capacity during one search (:func:`_search`); a search that
    outgrows it is run again with four times the room (rare: 32768 nodes hold every aurora
    query but a few). Growing the arrays inside the loop made numba update the reference
    counts of all five arrays on every expansion. ``cap``: the first room (nodes).
    """
    while True:
        done, res, expanded, generated = _search(mesh, query, cap)
        if done:
            return res, expanded, generated
        cap *= 4


@njit(cache=True)
def _search(mesh, query, cap):  # type: ignore[no-untyped-def]
    """One search with room for ``cap`` nodes and root records; returns ``(done, (length,
    path), expanded, generated)``, ``done`` False when the room ran out.

    Expanding a node (the paper's "Successors", Fig. 3: observable successors between the
    rays through ``R`` and ``L``, non-observable ones rooted at ``R``'s or ``L``'s vertex when it
    is a corner, only the final node when the polygon holds the goal) is written inside the
    loop rather than in functions of its own: numba increments and decrements the reference
    count of every array a compiled function receives (locked atomic updates), and with the
    expansion and the push as functions taking 16 and 4 arrays, ``perf`` put 34-53 % of the
    query loop's samples on NRT_incref/NRT_decref (aurora, 1.0 us of CPU a node expansion;
    0.57 us inlined, same nodes, same lengths). A node's successors are first listed in the
    scratch arrays ``SC`` (interval: ``(bx, by)`` its ``L``, ``(ax, ay)`` its ``R``) and ``SE``
    (mesh edge slot; root: 0 the node's, 1 ``R``'s vertex, 2 ``L``'s vertex), then stored in
    one place. The start's intervals (:func:`_start_edges`) and the final node
    (:func:`_final_node`) are functions: they run a few times a query, not per expansion.
    Splitting the expansion itself into functions inlined by numba (``inline="always"``) kept
    the nodes but cost 0.60 us of CPU a node expansion against 0.35 (aurora, 2,990 queries)
    and 98 s of compilation: the inlined arguments still carry reference counts. Tried again
    with the arrays in namedtuples: helpers taking the tuples as calls made the
    aurora queries 4x slower (every member of a tuple argument is incref'd and decref'd per
    call, unpruned where a helper calls another, has a raise path or uses an array last in a
    branch); with ``error_model="numpy"`` and the arrays taken out of the tuples in the entry
    block the helpers carry no reference counts, yet as calls they cost +50 % of CPU and
    inlined into this loop +11-20 % (same nodes and lengths, bench on 2 loaded cores). So the
    loop stays one function.
    """
    vx, vy, ptr, pv, pnb, pop, corner, nexits, max_sides, eps = mesh
    sx, sy, tx, ty, spolys, gpolys, prune = query
    best = np.full(vx.shape[0], np.inf)
    is_goal = np.zeros(nexits.shape[0], dtype=np.bool_)
    for p in gpolys:
        is_goal[p] = True
    px = np.empty(max_sides)  # the far boundary of the polygon being expanded
    py = np.empty(max_sides)
    SC = np.empty((2 * max_sides + 2, 4))  # one node's successors before they are stored
    SE = np.empty((2 * max_sides + 2, 2), dtype=np.int64)
    NF = np.empty((cap, 8))
    NI = np.empty((cap, 4), dtype=np.int64)
    RT = np.empty((cap, 2))
    RP = np.empty(cap, dtype=np.int64)
    H = np.empty((cap, 2))
    RT[0, 0], RT[0, 1], RP[0] = sx, sy, -1
    nr = 1
    nn = 0
    hs = 0
    room = 3 * max_sides + 4
    expanded = 0
    gR = gL = 0.0  # the new roots' g, records and vertices (set when used)
    recR = rvR = recL = rvL = -1
    # the start (root record 0) is "expanded" in each of its polygons: every edge not
    # through it; then the loop pops nodes (k < 0: none to expand yet)
    ip = 0
    k = -1
    while True:
        if nn + room > cap or nr + 2 > cap:
            return False, (np.inf, np.empty((0, 2))), expanded, nn
        first = nn
        ns = 0
        if k < 0:  # the start's polygons, one at a time
            if ip == spolys.shape[0]:
                if hs == 0:
                    break
                k, hs = _heap_pop(H, hs)
                if NI[k, 2] == -2:
                    return True, _result(k, NF, NI, RT, RP, tx, ty), expanded, nn
                if prune and NI[k, 1] >= 0 and NF[k, 1] > best[NI[k, 1]] + eps:
                    k = -1  # root-level pruning at pop time
                continue
            p = spolys[ip]
            ip += 1
            n = ptr[p + 1] - ptr[p]
            g, rx, ry, rec, rv = 0.0, sx, sy, 0, -1
            ns = _start_edges(SC, SE, p, ptr, pv, vx, vy, sx, sy, eps)
        else:
            expanded += 1
            g = NF[k, 1]
            rx, ry = NF[k, 2], NF[k, 3]
            lx, ly, qx, qy = NF[k, 4], NF[k, 5], NF[k, 6], NF[k, 7]
            rec, rv, poly, j = NI[k, 0], NI[k, 1], NI[k, 2], NI[k, 3]
            if is_goal[poly]:  # the final node
                hs = _final_node(NF, NI, H, k, nn, hs, tx, ty)
                nn += 1
                k = -1
                continue
            b0 = ptr[poly]
            n = ptr[poly + 1] - b0
            # far boundary: vertex i = poly's vertex j + 1 + i (i = 0: R's vertex, n - 1: L's
            # vertex); far edge i runs from far vertex i to i + 1 and is poly's edge j + 1 + i
            for i in range(n):
                v = pv[b0 + (j + 1 + i) % n]
                px[i] = vx[v]
                py[i] = vy[v]
            dRx, dRy = qx - rx, qy - ry
            dLx, dLy = lx - rx, ly - ry
            nR = _norm(dRx, dRy)  # tolerances; a new root's g takes math.hypot
            nL = _norm(dLx, dLy)
            if dRx * dLy - dRy * dLx <= eps * max(nR, nL):
                # the root is on the interval's line, at an end of the edge: it sees all of poly
                for i in range(n - 1):
                    SC[ns, 0], SC[ns, 1], SC[ns, 2], SC[ns, 3] = px[i + 1], py[i + 1], px[i], py[i]
                    SE[ns, 0], SE[ns, 1] = b0 + (j + 1 + i) % n, 0
                    ns += 1
            else:
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
                    t = c0 / (c0 - c1)
                    xrx = px[ir] + t * (px[ir + 1] - px[ir])
                    xry = py[ir] + t * (py[ir + 1] - py[ir])
                c0 = dLx * (py[il] - ry) - dLy * (px[il] - rx)
                c1 = dLx * (py[il + 1] - ry) - dLy * (px[il + 1] - rx)
                if -tL <= c1 <= tL:
                    xlx, xly = px[il + 1], py[il + 1]
                else:
                    t = c0 / (c0 - c1)
                    xlx = px[il] + t * (px[il + 1] - px[il])
                    xly = py[il] + t * (py[il + 1] - py[il])
                for i in range(ir, il + 1):  # observable: same root
                    SC[ns, 0], SC[ns, 1] = (xlx, xly) if i == il else (px[i + 1], py[i + 1])
                    SC[ns, 2], SC[ns, 3] = (xrx, xry) if i == ir else (px[i], py[i])
                    SE[ns, 0], SE[ns, 1] = b0 + (j + 1 + i) % n, 0
                    ns += 1
                # non-observable, rooted at R's vertex (kind 1) and at L's (kind 2) when it is
                # a corner the node's root reached no more cheaply before (root-level pruning)
                v = pv[b0 + (j + 1) % n]
                if corner[v] and abs(qx - px[0]) + abs(qy - py[0]) <= eps:
                    gR = g + math.hypot(dRx, dRy)
                    if not (prune and gR > best[v] + eps):
                        if gR < best[v]:
                            best[v] = gR
                        RT[nr, 0], RT[nr, 1] = px[0], py[0]
                        RP[nr] = rec
                        recR, rvR = nr, v
                        nr += 1
                        for i in range(ir + 1):
                            SC[ns, 0], SC[ns, 1] = (xrx, xry) if i == ir else (px[i + 1], py[i + 1])
                            SC[ns, 2], SC[ns, 3] = px[i], py[i]
                            SE[ns, 0], SE[ns, 1] = b0 + (j + 1 + i) % n, 1
                            ns += 1
                v = pv[b0 + j]
                if corner[v] and abs(lx - px[n - 1]) + abs(ly - py[n - 1]) <= eps:
                    gL = g + math.hypot(dLx, dLy)
                    if not (prune and gL > best[v] + eps):
                        if gL < best[v]:
                            best[v] = gL
                        RT[nr, 0], RT[nr, 1] = px[n - 1], py[n - 1]
                        RP[nr] = rec
                        recL, rvL = nr, v
                        nr += 1
                        for i in range(il, n - 1):
                            SC[ns, 0], SC[ns, 1] = px[i + 1], py[i + 1]
                            SC[ns, 2], SC[ns, 3] = (xlx, xly) if i == il else (px[i], py[i])
                            SE[ns, 0], SE[ns, 1] = b0 + (j + 1 + i) % n, 2
                            ns += 1
        # store the listed successors, dropping empty intervals, obstacles and cul-de-sacs
        for s in range(ns):
            e = SE[s, 0]
            q = pnb[e]
            if q < 0:
                continue
            bx, by, ax, ay = SC[s, 0], SC[s, 1], SC[s, 2], SC[s, 3]
            if abs(bx - ax) + abs(by - ay) <= eps:
                continue
            if prune and nexits[q] <= 1 and not is_goal[q]:
                continue
            kind = SE[s, 1]
            if kind == 0:
                g2, r2x, r2y, rec2, rv2 = g, rx, ry, rec, rv
            elif kind == 1:
                g2, r2x, r2y, rec2, rv2 = gR, px[0], py[0], recR, rvR
            else:
                g2, r2x, r2y, rec2, rv2 = gL, px[n - 1], py[n - 1], recL, rvL
            h, _ = heuristic(r2x, r2y, bx, by, ax, ay, tx, ty)
            NF[nn, 0] = g2 + h
            NF[nn, 1] = g2
            NF[nn, 2] = r2x
            NF[nn, 3] = r2y
            NF[nn, 4] = bx
            NF[nn, 5] = by
            NF[nn, 6] = ax
            NF[nn, 7] = ay
            NI[nn, 0] = rec2
            NI[nn, 1] = rv2
            NI[nn, 2] = q
            NI[nn, 3] = pop[e]
            nn += 1
        if prune and k >= 0 and nn - first == 1:
            k = first  # intermediate pruning: expand the lone successor at once
            continue
        for i in range(first, nn):
            hs = _heap_push(H, hs, NF[i, 0], i)
        k = -1
    return True, (np.inf, np.empty((0, 2))), expanded, nn


@njit(cache=True)
def _start_edges(SC, SE, p, ptr, pv, vx, vy, sx, sy, eps):  # type: ignore[no-untyped-def]
    """List in ``SC``/``SE`` the edges of the start's polygon ``p`` that do not pass through
    the start ``(sx, sy)`` (the start's intervals, rooted at it); returns their count."""
    ns = 0
    b0 = ptr[p]
    n = ptr[p + 1] - b0
    for i in range(n):
        a = pv[b0 + i]
        b = pv[b0 + (i + 1) % n]
        ex, ey = vx[b] - vx[a], vy[b] - vy[a]
        if ex * (sy - vy[a]) - ey * (sx - vx[a]) <= eps * math.hypot(ex, ey):
            continue
        SC[ns, 0], SC[ns, 1], SC[ns, 2], SC[ns, 3] = vx[b], vy[b], vx[a], vy[a]
        SE[ns, 0], SE[ns, 1] = b0 + i, 0
        ns += 1
    return ns


@njit(cache=True)
def _final_node(NF, NI, H, k, nn, hs, tx, ty):  # type: ignore[no-untyped-def]
    """Store node ``nn``: the final node of node ``k``, whose polygon holds the goal ``(tx,
    ty)`` (polygon -2, its turning point in ``lx, ly``, ``j`` the side it turns to), and push
    it on the heap ``H``; returns the heap's new size."""
    g, rx, ry = NF[k, 1], NF[k, 2], NF[k, 3]
    lx, ly, qx, qy = NF[k, 4], NF[k, 5], NF[k, 6], NF[k, 7]
    _, via = heuristic(rx, ry, lx, ly, qx, qy, tx, ty)
    if via == 0:  # the final length in math.hypot (see _norm)
        h = math.hypot(tx - rx, ty - ry)
    else:
        ex, ey = (lx, ly) if via == -1 else (qx, qy)
        h = math.hypot(ex - rx, ey - ry) + math.hypot(tx - ex, ty - ey)
    NF[nn, 0] = g + h
    NF[nn, 1] = g
    NF[nn, 2] = rx
    NF[nn, 3] = ry
    NF[nn, 4] = lx if via == -1 else qx
    NF[nn, 5] = ly if via == -1 else qy
    NI[nn, 0] = NI[k, 0]
    NI[nn, 1] = NI[k, 1]
    NI[nn, 2] = -2
    NI[nn, 3] = via
    return _heap_push(H, hs, g + h, nn)


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
