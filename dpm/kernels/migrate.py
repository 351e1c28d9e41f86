"""Message packing for migration and gather: rows of body, element and contact arrays
into the flat float64 and int64 buffers of the MPI backend's buffer-call messages
(mpi4py's ``Ialltoallv`` at a list rebuild, ``Iallgatherv`` at a whole-state gather), and back
(:mod:`dpm.parallel.messages` lays the messages out; :mod:`dpm.parallel.backend` sends
them).

A message is a run of *sections* (its bodies, its elements, its pair entries, its
boundary entries). A section of ``n`` rows and ``width`` columns takes the ``n * width``
values of a buffer from ``start`` on, row after row; a field (an array with one row per
body, element or entry) takes ``w`` consecutive columns of every row from column ``col``
on. Floats go to the float64 buffer, integers (ids, indices, counts, flags) to the int64
buffer, so that every value arrives exactly. A received buffer holds the same section of
several ranks one message after another: the ``*_segments`` kernels read a section of
every message (``starts``, ``counts``: where each one's section begins and its rows) in
one call, in rank order.

Unlike the other library kernels these are cached on disk (numba's ``cache=True``): they
call no function of another file (numba #1833, :mod:`dpm.kernels.config`), so a cached
copy cannot go stale, and every rank of every run would otherwise compile them at its
first rebuild and call end (about a second on a loaded 2-core machine).
"""

from numba import njit

from .config import JIT, inline_jit

#: the compile options of these kernels: dpm's, cached
jit = njit(**dict(JIT, cache=True))


@jit
def pack_rows(rows, src, buf, start, width, col):
    """Row k of the section at ``start`` takes src[rows[k]] in columns col, col + 1, ...
    (as many as ``src`` has)."""
    w = src.shape[1]
    for k in range(rows.shape[0]):
        r = rows[k]
        o = start + k * width + col
        for c in range(w):
            buf[o + c] = src[r, c]


@jit
def take_segments(buf, starts, counts, width, col, out):
    """out[m] = columns col, col + 1, ... of the m-th row of the segments (segment s:
    ``counts[s]`` rows from ``starts[s]`` on), in segment order."""
    w = out.shape[1]
    if col == 0 and w == width:  # whole rows: each segment is one block
        flat = out.reshape(out.size)
        m = 0
        for s in range(starts.shape[0]):
            n = counts[s] * w
            flat[m:m + n] = buf[starts[s]:starts[s] + n]  # (a slice copy: 4x the loop's speed)
            m += n
        return
    m = 0
    for s in range(starts.shape[0]):
        for k in range(counts[s]):
            o = starts[s] + k * width + col
            for c in range(w):
                out[m, c] = buf[o + c]
            m += 1


@jit
def put_segments(buf, starts, counts, width, col, rows, dst):
    """dst[rows[m]] = what :func:`take_segments` reads as row m (the rows of ``dst`` a
    gathered field lands in)."""
    w = dst.shape[1]
    m = 0
    for s in range(starts.shape[0]):
        for k in range(counts[s]):
            o = starts[s] + k * width + col
            r = rows[m]
            for c in range(w):
                dst[r, c] = buf[o + c]
            m += 1


@inline_jit
def reported_entry(i, j, gel, ne_own, pair):
    """Whether a rank reports entry (i, j) in a whole-state gather: a pair by the rank owning the
    element that comes first in host numbering, a boundary entry by its element's."""
    if pair:
        first = i if gel[i] < gel[j] else j
        return first < ne_own
    return i < ne_own


@jit
def count_reported(start, key, gel, ne_own, pair):
    """How many entries of a contact list (rows ``start``, keys ``key``) this rank
    reports (:func:`reported_entry`)."""
    n = 0
    for i in range(start.shape[0] - 1):
        for q in range(start[i], start[i + 1]):
            if reported_entry(i, key[q], gel, ne_own, pair):
                n += 1
    return n


@jit
def pack_reported(start, key, history, active, gel, ne_own, pair, fbuf, fstart, ibuf,
                  istart):
    """The entries :func:`count_reported` counts, in list order, in host numbering: ints
    (host element of i, host element of j or the boundary key, touching flag), floats
    the history row."""
    w = history.shape[1]
    m = 0
    for i in range(start.shape[0] - 1):
        for q in range(start[i], start[i + 1]):
            j = key[q]
            if not reported_entry(i, j, gel, ne_own, pair):
                continue
            o = istart + 3 * m
            ibuf[o] = gel[i]
            ibuf[o + 1] = gel[j] if pair else j
            ibuf[o + 2] = active[q]
            o = fstart + w * m
            for c in range(w):
                fbuf[o + c] = history[q, c]
            m += 1


@jit
def pack_shipped(sel, ei, ej, hist, act, owner, ids, estart, pair, fbuf, fstart, ibuf,
                 istart):
    """Entries ``sel`` of a pool's list (a migrant's contacts) by body id and element
    within the body: ints (id of i's body, i's index in it, then the same of j for a pair
    or the boundary key, touching flag), floats the history row."""
    w = hist.shape[1]
    wi = 5 if pair else 4
    for k in range(sel.shape[0]):
        q = sel[k]
        i = ei[q]
        o = istart + wi * k
        bi = owner[i]
        ibuf[o] = ids[bi]
        ibuf[o + 1] = i - estart[bi]
        if pair:
            j = ej[q]
            bj = owner[j]
            ibuf[o + 2] = ids[bj]
            ibuf[o + 3] = j - estart[bj]
        else:
            ibuf[o + 2] = ej[q]
        ibuf[o + wi - 1] = act[q]
        o = fstart + w * k
        for c in range(w):
            fbuf[o + c] = hist[q, c]
