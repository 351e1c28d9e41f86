"""The MPI backend's messages at a list rebuild (migration) and where the host state is
gathered (:meth:`dpm.parallel.backend.MpiBackend.sync_host`):
their layout in one float64 and one int64 buffer each, and their packing and unpacking
(numba kernels of :mod:`dpm.kernels.migrate`). :mod:`dpm.parallel.backend` sends them with
mpi4py's buffer calls: the counts first (``Ialltoall``/``Allgather`` of four int64 per
message: bodies, elements, pair entries, boundary entries), then the payloads
(``Ialltoallv``/``Iallgatherv``, floats and ints at once).

Every message has four sections, each a block of rows in both buffers (floats: state,
history; ints: ids, indices, counts, flags), so that every value arrives exactly.

**Migration** (to rank k: the bodies it will own or hold as ghosts, with the contacts of
those it will own), read by the receiver as the arrays of
:meth:`dpm.parallel.local.Pool.rows_payload` (views of the buffers):

- bodies: floats: the float arrays of ``Bodies.ARRAYS``, the integrator's row, the
  velocities the forces see; ints: the int arrays of ``Bodies.ARRAYS`` (id, material,
  shape), the body's element count, its new owner rank, the ranks to hold it as a ghost
  (one bit per rank, 64 to an int);
- elements: floats: offset, radius, position, reference; ints: material;
- pair entries (the touching contacts of a migrant): floats: history; ints: body id and
  element within the body of either element, touching flag;
- boundary entries: floats: history; ints: body id, element within the body, boundary
  key, touching flag.

(A field's columns follow ``Bodies.ARRAYS`` and ``Pool.ELEMENT_FIELDS`` in order, each
in the buffer of its dtype.)

**Gather** (every rank to all: its owned rows, unpacked straight into the host arrays,
every rank's rows of a field in one kernel call):

- bodies: floats: position, velocity, orientation, angular velocity, force, torque, the
  integrator's row, the velocities the forces see; ints: host row;
- elements: floats: reference (and position, unless the scene is spheres only); ints:
  host element;
- pair entries (those whose first element in host numbering the rank owns): floats:
  history; ints: host elements i and j, touching flag;
- boundary entries (of its owned elements): floats: history; ints: host element,
  boundary key, touching flag.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from ..kernels.migrate import (
    count_reported,
    pack_reported,
    pack_rows,
    pack_shipped,
    put_segments,
    take_segments,
)
from .local import Entries, Pool, element_rows

#: the sections of a message, in buffer order
SECTIONS = ("bodies", "elements", "pairs", "walls")

#: the most values one rank's part of a collective may count (MPI counts are C ints)
MAX_COUNT = 2**31 - 1


def as_2d(a: np.ndarray) -> np.ndarray:
    """``a`` as (rows, columns): a 1-d array as a view of one column."""
    return a if a.ndim == 2 else a[:, None]


def displacements(sizes: np.ndarray) -> np.ndarray:
    """Where each of consecutive parts of ``sizes`` values starts."""
    out = np.zeros(len(sizes), np.int64)
    np.cumsum(sizes[:-1], out=out[1:])
    return out


def mpi_counts(sizes: np.ndarray, what: str) -> tuple[list[int], list[int]]:
    """(counts, displacements) as MPI takes them, refused past C ints."""
    sizes = np.asarray(sizes, np.int64)
    disp = displacements(sizes)
    if len(sizes) and int(disp[-1] + sizes[-1]) > MAX_COUNT:
        raise ParameterError(f"MpiBackend: the {what} message holds "
                             f"{int(sizes.sum())} values, more than MPI's count limit "
                             f"{MAX_COUNT}; use more ranks or a smaller scene")
    return sizes.tolist(), disp.tolist()


class Scratch:
    """Arrays kept from one call to the next, grown as needed (a gather's buffers: fresh
    ones of tens of MB each call would fault their pages in again)."""

    def __init__(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}

    def get(self, name: str, shape: tuple, dtype: Any = np.float64) -> np.ndarray:
        """An uninitialised C-contiguous array ``name`` of ``shape``."""
        n = int(np.prod(shape))
        a = self.arrays.get(name)
        if a is None or a.size < n or a.dtype != dtype:
            a = self.arrays[name] = np.empty(n + n // 4 + 16, dtype)
        return a[:n].reshape(shape)


class Section:
    """The columns of one section's rows: each field in the float or the int buffer, at
    a column of its own, laid out from template arrays (one row per body or element;
    their dtype, trailing shape and order fix the layout, so that it is the same on
    every rank)."""

    def __init__(self, templates: list[tuple[str, np.ndarray]]) -> None:
        self.fields: list[tuple[str, bool, int, int, tuple, np.dtype]] = []
        width = {True: 0, False: 0}
        for name, a in templates:
            kind = a.dtype.kind
            if kind not in "fiub":
                raise TypeError(f"field {name}: dtype {a.dtype} has no buffer")
            is_float = kind == "f"
            w = 1 if a.ndim == 1 else int(a.shape[1])
            self.fields.append((name, is_float, width[is_float], w, a.shape[1:], a.dtype))
            width[is_float] += w
        #: float and int columns of a row
        self.fwidth, self.iwidth = width[True], width[False]

    def pack(self, arrays: dict, rows: np.ndarray, fbuf: np.ndarray, fstart: int,
             ibuf: np.ndarray, istart: int) -> None:
        """Rows ``rows`` of ``arrays`` (by field name) into the section at ``fstart``
        (floats) and ``istart`` (ints)."""
        for name, is_float, col, _w, _shape, _dt in self.fields:
            if is_float:
                pack_rows(rows, as_2d(arrays[name]), fbuf, fstart, self.fwidth, col)
            else:
                pack_rows(rows, as_2d(arrays[name]), ibuf, istart, self.iwidth, col)

    def views(self, fbuf: np.ndarray, fstart: int, ibuf: np.ndarray, istart: int,
              n: int) -> dict[str, np.ndarray]:
        """The fields of the section's ``n`` rows (views of the buffers; an int field in
        its own dtype)."""
        fb = fbuf[fstart:fstart + n * self.fwidth].reshape(n, self.fwidth)
        ib = ibuf[istart:istart + n * self.iwidth].reshape(n, self.iwidth)
        out = {}
        for name, is_float, col, w, shape, dt in self.fields:
            block = fb if is_float else ib
            v = block[:, col] if shape == () else block[:, col:col + w]
            out[name] = v if is_float else v.astype(dt, copy=False)
        return out


def near_words(ranks: int) -> int:
    """int64 words of a body's ghost-rank bits."""
    return (ranks + 63) // 64


def pack_bits(flags: np.ndarray, words: int) -> np.ndarray:
    """(ranks, n) bools as (n, words) int64: bit r % 64 of word r // 64 is flags[r]."""
    out = np.zeros((flags.shape[1], words), np.int64)
    for r in range(flags.shape[0]):
        out[:, r // 64] |= flags[r].astype(np.int64) << (r % 64)
    return out


def unpack_bits(words: np.ndarray, ranks: int) -> np.ndarray:
    """The inverse of :func:`pack_bits`: (ranks, n) bools."""
    out = np.empty((ranks, len(words)), bool)
    for r in range(ranks):
        out[r] = (words[:, r // 64] >> (r % 64)) & 1
    return out


class Migration:
    """The messages of a migration (module docstring), laid out from this rank's pool:
    ``ship[k]`` is None or (body rows, pair entries, boundary entries) for rank k, with
    the bodies' new owners ``owner`` and ghost ranks ``near`` (ranks, pool rows)."""

    def __init__(self, pool: Pool, ranks: int) -> None:
        self.ranks = ranks
        self.words = near_words(ranks)
        bodies = list(pool.bodies.items())
        bodies += [("aux", pool.aux), ("vf", pool.vf), ("wf", pool.wf),
                   ("counts", np.zeros(0, np.int64)), ("owner", np.zeros(0, np.int64)),
                   ("near", np.zeros((0, self.words), np.int64))]
        self.bodies = Section(bodies)
        self.elements = Section([(k, pool.elements[k]) for k in Pool.ELEMENT_FIELDS])
        self.names = list(pool.bodies)
        self.wp = int(pool.pairs.hist.shape[1])
        self.ww = int(pool.walls.hist.shape[1])

    def counts(self, pool: Pool, ship: list) -> np.ndarray:
        """(ranks, 4): bodies, elements, pair and boundary entries to each rank."""
        out = np.zeros((self.ranks, 4), np.int64)
        est = pool.estart
        for k, s in enumerate(ship):
            if s is not None:
                rows, sel_p, sel_w = s
                out[k] = (len(rows), int((est[rows + 1] - est[rows]).sum()), len(sel_p),
                          len(sel_w))
        return out

    def sizes(self, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Floats and ints of each message with ``counts``."""
        f = np.array([self.bodies.fwidth, self.elements.fwidth, self.wp, self.ww], np.int64)
        i = np.array([self.bodies.iwidth, self.elements.iwidth, 5, 4], np.int64)
        return counts @ f, counts @ i

    def pack(self, pool: Pool, e_owner: np.ndarray, owner: np.ndarray, near: np.ndarray,
             ship: list, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The send buffers (floats, ints): the messages to ranks 0, 1, ... in turn."""
        fs, is_ = self.sizes(counts)
        fbuf, ibuf = np.empty(int(fs.sum())), np.empty(int(is_.sum()), np.int64)
        fo, io = displacements(fs), displacements(is_)
        est = pool.estart
        ids = pool.bodies["id"]
        arrays = dict(pool.bodies)
        arrays.update(aux=pool.aux, vf=pool.vf, wf=pool.wf, counts=est[1:] - est[:-1],
                      owner=owner, near=pack_bits(near, self.words))
        for k, s in enumerate(ship):
            if s is None:
                continue
            rows, sel_p, sel_w = s
            nb, ne, n_p, _ = (int(x) for x in counts[k])
            f, i = int(fo[k]), int(io[k])
            self.bodies.pack(arrays, rows, fbuf, f, ibuf, i)
            f += nb * self.bodies.fwidth
            i += nb * self.bodies.iwidth
            er = element_rows(est, rows)[0]
            self.elements.pack(pool.elements, er, fbuf, f, ibuf, i)
            f += ne * self.elements.fwidth
            i += ne * self.elements.iwidth
            p = pool.pairs
            pack_shipped(sel_p, p.i, p.j, p.hist, p.act, e_owner, ids, est, True, fbuf, f,
                         ibuf, i)
            f += n_p * self.wp
            i += n_p * 5
            w = pool.walls
            pack_shipped(sel_w, w.i, w.j, w.hist, w.act, e_owner, ids, est, False, fbuf, f,
                         ibuf, i)
        return fbuf, ibuf

    def unpack(self, counts: np.ndarray, fbuf: np.ndarray, ibuf: np.ndarray
               ) -> list[dict[str, Any] | None]:
        """The received messages (``counts`` from each rank) as dicts: ``bodies``,
        ``counts``, ``elements``, ``aux``, ``vf``, ``wf`` as
        :meth:`~dpm.parallel.local.Pool.rows_payload` gives them, ``owner`` and ``near``
        of the bodies, ``pairs`` (body id, element within the body of i, the same of j,
        history, flag) and ``walls`` (body id, element within the body, key, history,
        flag); None from a rank that sent no bodies."""
        fs, is_ = self.sizes(counts)
        fo, io = displacements(fs), displacements(is_)
        out: list[dict[str, Any] | None] = []
        for s in range(len(counts)):
            nb, ne, n_p, n_w = (int(x) for x in counts[s])
            if nb == 0:
                out.append(None)
                continue
            f, i = int(fo[s]), int(io[s])
            b = self.bodies.views(fbuf, f, ibuf, i, nb)
            f += nb * self.bodies.fwidth
            i += nb * self.bodies.iwidth
            msg: dict[str, Any] = {
                "bodies": {k: b[k] for k in self.names}, "counts": b["counts"],
                "elements": self.elements.views(fbuf, f, ibuf, i, ne),
                "aux": b["aux"], "vf": b["vf"], "wf": b["wf"], "owner": b["owner"],
                "near": unpack_bits(b["near"], self.ranks)}
            f += ne * self.elements.fwidth
            i += ne * self.elements.iwidth
            hp = fbuf[f:f + n_p * self.wp].reshape(n_p, self.wp)
            ip = ibuf[i:i + n_p * 5].reshape(n_p, 5)
            msg["pairs"] = (ip[:, 0], ip[:, 1], ip[:, 2], ip[:, 3], hp,
                            ip[:, 4].astype(np.uint8))
            f += n_p * self.wp
            i += n_p * 5
            hw = fbuf[f:f + n_w * self.ww].reshape(n_w, self.ww)
            iw = ibuf[i:i + n_w * 4].reshape(n_w, 4)
            msg["walls"] = (iw[:, 0], iw[:, 1], iw[:, 2], hw, iw[:, 3].astype(np.uint8))
            out.append(msg)
        return out


class Gather:
    """The messages of a whole-state gather (module docstring): this rank's owned rows to every
    rank, unpacked into the host state. ``n_aux``: the integrator's columns;
    ``positions``: whether element positions travel (not for spheres, whose element
    position is the body's); ``wp``, ``ww``: history columns of pairs and boundary
    entries."""

    BODY_FIELDS = ("position", "velocity", "orientation", "angular_velocity", "force",
                   "torque", "aux", "vf", "wf")

    def __init__(self, n_aux: int, positions: bool, wp: int, ww: int,
                 scratch: Scratch | None = None) -> None:
        #: where the received buffers and the unpacked entries live (kept by the backend)
        self.scratch = scratch if scratch is not None else Scratch()
        widths = (3, 3, 4, 3, 3, 3, n_aux, 3, 3)
        self.body_cols = list(zip(self.BODY_FIELDS, np.cumsum((0,) + widths[:-1]).tolist(),
                                  strict=True))
        self.bf = int(sum(widths))
        self.positions = positions
        self.ef = 6 if positions else 3
        self.wp, self.ww = wp, ww

    def sizes(self, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Floats and ints of each message with ``counts`` (ranks, 4)."""
        f = np.array([self.bf, self.ef, self.wp, self.ww], np.int64)
        i = np.array([1, 1, 3, 3], np.int64)
        return counts @ f, counts @ i

    def buffers(self, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The buffers (floats, ints) that receive every rank's message."""
        fs, is_ = self.sizes(counts)
        return (self.scratch.get("floats", (int(fs.sum()),)),
                self.scratch.get("ints", (int(is_.sum()),), np.int64))

    @staticmethod
    def reported(lst: Any, gel: np.ndarray, ne_own: int, pair: bool) -> int:
        """Entries of a local contact list this rank reports."""
        return int(count_reported(lst.start, lst.key, gel, ne_own, pair))

    def pack(self, arrays: dict, host_rows: np.ndarray, elem: dict, host_elems: np.ndarray,
             contacts: Any, wall_contacts: Any, gel: np.ndarray, counts: np.ndarray,
             fbuf: np.ndarray, ibuf: np.ndarray) -> None:
        """This rank's message into ``fbuf`` and ``ibuf`` (its part of the received
        buffers): the first ``counts[0]`` rows of ``arrays`` (``BODY_FIELDS``) with their
        host rows, the first ``counts[1]`` element rows of ``elem`` (reference,
        position) with their host elements, the reported entries of ``contacts`` and
        ``wall_contacts`` (local element numbering; ``gel``: host element of each)."""
        nb, ne, n_p, _ = (int(x) for x in counts)
        rows = np.arange(nb, dtype=np.int64)
        for name, col in self.body_cols:
            pack_rows(rows, arrays[name], fbuf, 0, self.bf, col)
        ibuf[:nb] = host_rows
        f, i = nb * self.bf, nb
        rows = np.arange(ne, dtype=np.int64)
        pack_rows(rows, elem["reference"], fbuf, f, self.ef, 0)
        if self.positions:
            pack_rows(rows, elem["position"], fbuf, f, self.ef, 3)
        ibuf[i:i + ne] = host_elems
        f += ne * self.ef
        i += ne
        for lst, pair, w, n in ((contacts, True, self.wp, n_p),
                                (wall_contacts, False, self.ww, int(counts[3]))):
            pack_reported(lst.start, lst.key, lst.history, lst.active, gel, ne, pair, fbuf,
                          f, ibuf, i)
            f += n * w
            i += 3 * n

    def unpack(self, counts: np.ndarray, fbuf: np.ndarray, ibuf: np.ndarray, host: dict,
               elem: dict) -> tuple[Entries, Entries]:
        """Every rank's message (``counts`` (ranks, 4), the buffers as received) into
        the host arrays ``host`` (``BODY_FIELDS``) and ``elem`` (reference, position);
        returns the pair and boundary entries, in rank order (host numbering; their
        index and history arrays are scratch, valid until the next gather)."""
        fs, is_ = self.sizes(counts)
        fo, io = displacements(fs), displacements(is_)
        nb, ne, n_p, n_w = (counts[:, c].copy() for c in range(4))
        sc = self.scratch
        rows = sc.get("rows", (int(nb.sum()), 1), np.int64)
        take_segments(ibuf, io, nb, 1, 0, rows)
        rows = rows[:, 0]
        for name, col in self.body_cols:
            put_segments(fbuf, fo, nb, self.bf, col, rows, host[name])
        fo = fo + nb * self.bf
        io = io + nb
        erows = sc.get("element rows", (int(ne.sum()), 1), np.int64)
        take_segments(ibuf, io, ne, 1, 0, erows)
        erows = erows[:, 0]
        put_segments(fbuf, fo, ne, self.ef, 0, erows, elem["reference"])
        if self.positions:
            put_segments(fbuf, fo, ne, self.ef, 3, erows, elem["position"])
        fo = fo + ne * self.ef
        io = io + ne
        out = []
        for n, w, part in ((n_p, self.wp, "pair"), (n_w, self.ww, "boundary")):
            total = int(n.sum())
            ints = sc.get(f"{part} ints", (total, 3), np.int64)
            hist = sc.get(f"{part} history", (total, w))
            take_segments(ibuf, io, n, 3, 0, ints)
            take_segments(fbuf, fo, n, w, 0, hist)
            out.append(Entries(ints[:, 0], ints[:, 1], hist, ints[:, 2].astype(np.uint8)))
            fo = fo + n * w
            io = io + 3 * n
        return out[0], out[1]


__all__ = ["Gather", "Migration", "Scratch", "Section", "mpi_counts"]
