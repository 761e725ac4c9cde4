"""Bit-parallel jump point search (JPS-B: Harabor & Grastien 2014, "Improving
jump point search", §3 "block-based symmetry breaking").

The padded map is kept twice as rows of 64-bit words, bit x of line l set when
the cell is blocked: ``rows[r]`` holds row r (bit = column) and ``cols[c]``
holds column c (bit = row), the transposed map for vertical scans. A straight
jump along a line then tests 64 cells per word instead of one per step. For a
scan towards larger positions, with L the scanned line and A, B the lines on
either side of it, the stops in one word are

    stop = L | (~A & (A << 1)) | (~B & (B << 1))        (JPS-B §3, Fig. 2)

— a blocked cell, or a cell whose side cell is free while the side cell one
step behind it is blocked (the forced-neighbour rule without corner cutting,
as in ``_jps_kernel._jump_straight``). The first stop is the lowest set bit
(count trailing zeros); for scans towards smaller positions the shifts turn
round and the highest set bit is taken (count leading zeros). A stop on a
blocked cell means no jump point; the goal stops the scan where it lies.

The scans find exactly the jump points of the plain byte-by-byte scans
(tests/planner/test_jps_bits.py checks every cell and move on random grids).
Diagonal runs step cell by cell and call the two straight scans, now cheap.
The search also prunes intermediate jump points (JPS-B §5): a diagonal jump
point is not queued but expanded on the spot, its straight jumps generated
with it as their parent, and the diagonal run goes on — on random512 this
cuts the expansions from 7317 to 4498 (median) at the same optimal lengths.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from ._grid_search import H_OCTILE, SQRT2, _h

_U1 = np.uint64(1)
_U63 = np.uint64(63)
_ALL = np.uint64(0xFFFFFFFFFFFFFFFF)
_ZERO = np.uint64(0)


# ---- open list: 4-ary heap with lazy deletion ---------------------------------
# Ordered by (f ascending, g descending). A node whose g improves is pushed
# again instead of moved (no slot index per node, so a sift touches only the
# contiguous heap arrays); the stale entry is dropped when it comes out after
# the node was closed. With a consistent heuristic the first entry of a node
# to come out carries its final g. Four children per slot halve the depth of
# the binary heap; a pop compares them in one pass over adjacent slots.


@njit(cache=True)
def _before(f1, g1, f2, g2):
    return f1 < f2 or (f1 == f2 and g1 > g2)


@njit(cache=True)
def heap_push(hn, hf, hg, size, node, fv, gv):
    """Insert (node, f, g) into the heap of ``size`` entries; returns the new
    size. The arrays must have room."""
    i = size
    while i > 0:
        p = (i - 1) >> 2
        if _before(fv, gv, hf[p], hg[p]):
            hn[i] = hn[p]
            hf[i] = hf[p]
            hg[i] = hg[p]
            i = p
        else:
            break
    hn[i] = node
    hf[i] = fv
    hg[i] = gv
    return size + 1


@njit(cache=True)
def heap_pop(hn, hf, hg, size):
    """Remove the first entry; returns (node, g, new size)."""
    top = hn[0]
    gtop = hg[0]
    size -= 1
    if size > 0:
        n = hn[size]
        fv = hf[size]
        gv = hg[size]
        i = 0
        while True:
            c = 4 * i + 1
            if c >= size:
                break
            best = c
            e = min(c + 4, size)
            for k in range(c + 1, e):
                if _before(hf[k], hg[k], hf[best], hg[best]):
                    best = k
            if _before(hf[best], hg[best], fv, gv):
                hn[i] = hn[best]
                hf[i] = hf[best]
                hg[i] = hg[best]
                i = best
            else:
                break
        hn[i] = n
        hf[i] = fv
        hg[i] = gv
    return top, gtop, size


@intrinsic
def _cttz(typingctx, x):
    """Count trailing zeros of a nonzero uint64 (LLVM cttz)."""
    sig = types.uint64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.cttz(args[0], ir.Constant(ir.IntType(1), 1))

    return sig, codegen


@intrinsic
def _ctlz(typingctx, x):
    """Count leading zeros of a nonzero uint64 (LLVM ctlz)."""
    sig = types.uint64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.ctlz(args[0], ir.Constant(ir.IntType(1), 1))

    return sig, codegen


def pack_lines(gp2d: np.ndarray) -> np.ndarray:
    """(L, n) uint8 map (1 = blocked) → (L, ceil(n/64)) uint64 words, bit i of
    word k = position 64·k + i; positions past n count as blocked."""
    n_lines, n = gp2d.shape
    nw = (n + 63) // 64
    buf = np.ones((n_lines, nw * 64), dtype=np.uint8)
    buf[:, :n] = gp2d
    packed = np.packbits(buf, axis=1, bitorder="little")
    return np.ascontiguousarray(packed).view("<u8").astype(np.uint64, copy=False)


@njit(cache=True)
def scan_fwd(bits, line, x, gl, gx):
    """First stop after position x along ``line`` towards larger positions:
    the jump point's position, or -1 when a blocked cell comes first. The goal
    (gl, gx) ends the scan where it lies. The line must have a blocked cell
    after x (the padding guarantees it)."""
    y = x + 1
    wi = y >> 6
    if wi > 0:
        pa = bits[line - 1, wi - 1]
        pb = bits[line + 1, wi - 1]
    else:
        pa = _ZERO
        pb = _ZERO
    mask = _ALL << np.uint64(y & 63)
    while True:
        a = bits[line - 1, wi]
        b = bits[line + 1, wi]
        sa = (a << _U1) | (pa >> _U63)
        sb = (b << _U1) | (pb >> _U63)
        m = (bits[line, wi] | (~a & sa) | (~b & sb)) & mask
        if m != _ZERO:
            p = (wi << 6) + np.int64(_cttz(m))
            break
        pa = a
        pb = b
        wi += 1
        mask = _ALL
    if gl == line and x < gx <= p:
        return gx
    if (bits[line, p >> 6] >> np.uint64(p & 63)) & _U1:
        return -1
    return p


@njit(cache=True)
def scan_bwd(bits, line, x, gl, gx):
    """As :func:`scan_fwd` towards smaller positions: there a cell is forced
    when its side cell is free and the side cell at position + 1 is blocked,
    so the side lines shift right and the highest stop bit is the first."""
    nw = bits.shape[1]
    y = x - 1
    wi = y >> 6
    if wi + 1 < nw:
        na = bits[line - 1, wi + 1]
        nb = bits[line + 1, wi + 1]
    else:
        na = _ALL
        nb = _ALL
    mask = _ALL >> np.uint64(63 - (y & 63))
    while True:
        a = bits[line - 1, wi]
        b = bits[line + 1, wi]
        sa = (a >> _U1) | (na << _U63)
        sb = (b >> _U1) | (nb << _U63)
        m = (bits[line, wi] | (~a & sa) | (~b & sb)) & mask
        if m != _ZERO:
            p = (wi << 6) + 63 - np.int64(_ctlz(m))
            break
        na = a
        nb = b
        wi -= 1
        mask = _ALL
    if gl == line and p <= gx < x:
        return gx
    if (bits[line, p >> 6] >> np.uint64(p & 63)) & _U1:
        return -1
    return p


@njit(cache=True)
def _straight(rows, cols, r, c, dr, dc, gr, gc):
    """Straight jump from (r, c) along (dr, dc), one of them 0: the position
    (row or column) of the jump point along the move, or -1."""
    if dr == 0:
        if dc > 0:
            return scan_fwd(rows, r, c, gr, gc)
        return scan_bwd(rows, r, c, gr, gc)
    if dr > 0:
        return scan_fwd(cols, c, r, gc, gr)
    return scan_bwd(cols, c, r, gc, gr)


@njit(cache=True)
def _diag(gp, rows, cols, w, r, c, dr, dc, gr, gc):
    """Diagonal jump: steps while the move is allowed (both orthogonal cells
    free, no corner cutting); a cell is a jump point when it is the goal or a
    straight scan from it along either component finds one. Returns the
    number of steps, 0 when the run hits a wall first."""
    cur = r * w + c
    dv = dr * w
    k = 0
    while True:
        if gp[cur + dv] or gp[cur + dc] or gp[cur + dv + dc]:
            return 0
        cur += dv + dc
        r += dr
        c += dc
        k += 1
        if r == gr and c == gc:
            return k
        if dr > 0:
            if scan_fwd(cols, c, r, gc, gr) >= 0:
                return k
        elif scan_bwd(cols, c, r, gc, gr) >= 0:
            return k
        if dc > 0:
            if scan_fwd(rows, r, c, gr, gc) >= 0:
                return k
        elif scan_bwd(rows, r, c, gr, gc) >= 0:
            return k


@njit(cache=True)
def _jump(gp, rows, cols, w, cur, r, c, dr, dc, gr, gc):
    """Jump from node cur = (r, c) along (dr, dc): (jump point, steps) or
    (-1, 0)."""
    if dr != 0 and dc != 0:
        k = _diag(gp, rows, cols, w, r, c, dr, dc, gr, gc)
        if k == 0:
            return -1, 0
        return cur + k * (dr * w + dc), k
    p = _straight(rows, cols, r, c, dr, dc, gr, gc)
    if p < 0:
        return -1, 0
    if dr == 0:
        return r * w + p, abs(p - c)
    return p * w + c, abs(p - r)


# ---- per-node search state, one 16-byte record per node -----------------------------
# rec[node, 0] packs the generation stamp (bits 37–62: the query that wrote the
# record; older ones count as untouched), the closed flag (bit 36), the move
# that reached the node (bits 32–35, coded (dr + 1) * 3 + (dc + 1)) and the
# parent (bits 0–31, all ones = none); recf[node, 1] is g, a float64 view of
# the same memory. One cache line per touched node instead of one per array.

GEN_BITS = 26
_NOPAR = 0xFFFFFFFF
_CLOSED_BIT = np.int64(1) << 36


@njit(cache=True)
def _rec_touch(rec, recf, j, gen):
    m = rec[j, 0]
    if (m >> 37) != gen:
        m = (gen << 37) | _NOPAR
        rec[j, 0] = m
        recf[j, 1] = np.inf
    return m


@njit(cache=True)
def _relax(rec, recf, hn, hf, hg, size, j, ng, par, kin, gen, w, gr, gc):
    """Offer g = ng via par to node j; queue it when that improves its g.
    Returns the heap size, -1 when the heap arrays are full."""
    m = _rec_touch(rec, recf, j, gen)
    if (m & _CLOSED_BIT) or not (ng < recf[j, 1] - 1e-9):
        return size
    if size == len(hn):
        return -1
    recf[j, 1] = ng
    rec[j, 0] = (gen << 37) | (kin << 32) | par
    return heap_push(hn, hf, hg, size, j, ng + _h(H_OCTILE, j, w, gr, gc, 1.0), ng)


@njit(cache=True)
def trace_rec(rec, goal, w):
    """The cell path from the packed parents, each jump filled step by step;
    (row, col) in the padded frame."""
    count = 1
    cur = goal
    while (rec[cur, 0] & _NOPAR) != _NOPAR:
        p = rec[cur, 0] & _NOPAR
        r, c = cur // w, cur % w
        pr, pc = p // w, p % w
        count += max(abs(r - pr), abs(c - pc))
        cur = p
    out = np.empty((count, 2), dtype=np.int64)
    i = count - 1
    cur = goal
    out[i, 0] = cur // w
    out[i, 1] = cur % w
    while (rec[cur, 0] & _NOPAR) != _NOPAR:
        p = rec[cur, 0] & _NOPAR
        r, c = cur // w, cur % w
        pr, pc = p // w, p % w
        dr = (pr > r) - (pr < r)
        dc = (pc > c) - (pc < c)
        while r != pr or c != pc:
            r += dr
            c += dc
            i -= 1
            out[i, 0] = r
            out[i, 1] = c
        cur = p
    return out


@njit(cache=True, _nrt=False)
def jps_bits_kernel(gp, rows, cols, w, s, goal, gen, rec, recf, hn, hf, hg, mv):
    """Jump point search with bit-parallel straight scans: the successor rules
    of ``_jps_kernel.jps_kernel`` with intermediate diagonal jump points pruned
    (recorded, not queued), the scans of this module, a lazy 4-ary heap and
    packed node records. Same optimal lengths as the plain search; fewer
    expansions, and the path may differ among equally short ones. gp: padded
    flat uint8 grid of width w; rows, cols: its packed lines; gen: this query's stamp (1 ≤ gen <
    2**GEN_BITS); mv: an (8, 2) int64 scratch array for the moves to follow.
    Compiled without the runtime's reference counting (nothing is allocated
    here), so its helpers' array arguments (LLVM inlines the small helpers)
    cost no atomic counter updates in the loop. Returns (status, expanded): 1
    goal reached (the path: :func:`trace_rec`), 0 no path, -1 the heap arrays were too small (lazy
    deletion can queue a node more than once; the caller grows them and runs
    the query again)."""
    gr = goal // w
    gc = goal - gr * w
    _rec_touch(rec, recf, s, gen)
    recf[s, 1] = 0.0
    size = heap_push(hn, hf, hg, 0, s, _h(H_OCTILE, s, w, gr, gc, 1.0), 0.0)
    expanded = 0
    while size > 0:
        cur, gq, size = heap_pop(hn, hf, hg, size)
        m = rec[cur, 0]
        if m & _CLOSED_BIT:
            continue  # a stale entry: the node came out earlier with its final g
        rec[cur, 0] = m | _CLOSED_BIT
        expanded += 1
        if cur == goal:
            return 1, expanded
        r = cur // w
        c = cur - r * w
        # the moves to follow, in jps_kernel's order (natural, then forced)
        nm = 0
        if (m & _NOPAR) == _NOPAR:
            for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1)):
                mv[nm, 0] = dr
                mv[nm, 1] = dc
                nm += 1
        else:
            kin = (m >> 32) & 15
            dr = kin // 3 - 1
            dc = kin % 3 - 1
            if dr != 0 and dc != 0:
                mv[0, 0] = dr
                mv[0, 1] = dc
                mv[1, 0] = dr
                mv[1, 1] = 0
                mv[2, 0] = 0
                mv[2, 1] = dc
                nm = 3
            elif dr == 0:
                mv[0, 0] = 0
                mv[0, 1] = dc
                nm = 1
                for sv in (-1, 1):
                    if gp[cur + sv * w] == 0 and gp[cur + sv * w - dc] != 0:
                        mv[nm, 0] = sv
                        mv[nm, 1] = 0
                        mv[nm + 1, 0] = sv
                        mv[nm + 1, 1] = dc
                        nm += 2
            else:
                mv[0, 0] = dr
                mv[0, 1] = 0
                nm = 1
                for sh in (-1, 1):
                    if gp[cur + sh] == 0 and gp[cur + sh - dr * w] != 0:
                        mv[nm, 0] = 0
                        mv[nm, 1] = sh
                        mv[nm + 1, 0] = dr
                        mv[nm + 1, 1] = sh
                        nm += 2
        gcur = recf[cur, 1]
        for i in range(nm):
            dr = mv[i, 0]
            dc = mv[i, 1]
            kin = (dr + 1) * 3 + (dc + 1)
            if dr == 0 or dc == 0:
                j, k = _jump(gp, rows, cols, w, cur, r, c, dr, dc, gr, gc)
                if j >= 0:
                    ng = gcur + k
                    size = _relax(rec, recf, hn, hf, hg, size, j, ng, cur, kin, gen, w, gr, gc)
                    if size < 0:
                        return -1, expanded
                continue
            # Diagonal run with intermediate jump points pruned (JPS-B §5): a
            # diagonal jump point other than the goal is one only because a
            # straight scan from it finds a jump point. Instead of queueing it,
            # record it (g, parent, move) and generate at once what its
            # expansion would (the two straight jumps, then the diagonal run
            # on); it enters the open list only if reached again otherwise.
            base = cur
            rb = r
            cb = c
            gb = gcur
            while True:
                k = _diag(gp, rows, cols, w, rb, cb, dr, dc, gr, gc)
                if k == 0:
                    break
                d = base + k * (dr * w + dc)
                gd = gb + k * SQRT2
                if d == goal:
                    size = _relax(rec, recf, hn, hf, hg, size, d, gd, base, kin, gen, w, gr, gc)
                    if size < 0:
                        return -1, expanded
                    break
                md = _rec_touch(rec, recf, d, gen)
                if (md & _CLOSED_BIT) or not (gd < recf[d, 1] - 1e-9):
                    break  # d is settled or reached as cheaply: its successors are covered
                recf[d, 1] = gd
                rec[d, 0] = (gen << 37) | (kin << 32) | base
                rb += k * dr
                cb += k * dc
                for sr, sc in ((dr, 0), (0, dc)):
                    j, kk = _jump(gp, rows, cols, w, d, rb, cb, sr, sc, gr, gc)
                    if j >= 0:
                        ks = (sr + 1) * 3 + (sc + 1)
                        ng = gd + kk
                        size = _relax(rec, recf, hn, hf, hg, size, j, ng, d, ks, gen, w, gr, gc)
                        if size < 0:
                            return -1, expanded
                base = d
                gb = gd
    return 0, expanded
