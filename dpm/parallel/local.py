"""One rank's part of the scene: its owned bodies, then its ghosts, with their contacts.

A :class:`LocalScene` holds what the CPU backend's kernels read of a simulation (state
containers, plan, boundary table, constants) for one rank's sub-domain, so that the CPU
backend steps it unchanged. It is assembled from a *pool* of body rows (the host's whole
state when a call starts; this rank's previous rows plus the rows its neighbours sent at
a list rebuild) by choosing the rows that are owned here and those that are ghosts here,
grouped by the rank that owns them:

- body rows keep their ids; elements follow their bodies;
- a contact (pair or boundary entry) is kept with its history when its elements are kept;
  a pair whose elements swap order has its vector history negated (``plan.history_flips``,
  as :meth:`dpm.Simulation.permute`);
- the lists are then Verlet lists of the new rows (at a call's start) or the carried
  entries that the rebuild merges into fresh lists (after a migration).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..state import Bodies, Contacts, Elements, WallContacts


def take(a: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Rows ``rows`` of ``a`` (``np.take`` along the first axis: 3-5x faster than ``a[rows]``
    for 2-D arrays, which numpy indexes through its general path)."""
    return np.take(a, rows, axis=0)


def keep(a: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Rows of ``a`` where ``mask`` (``np.compress``: ~4x faster than ``a[mask]`` in 2-D)."""
    return np.compress(mask, a, axis=0)


def runs_of(rows: np.ndarray, n_head: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``rows`` as runs of consecutive rows, none crossing from the head's ``n_head`` rows
    into the tail: (where each run starts in ``rows``, its first row, its length)."""
    rows = np.asarray(rows, np.int64)
    if len(rows) == 0:
        z = np.zeros(0, np.int64)
        return z, z, z
    brk = (np.diff(rows) != 1) | (rows[1:] == n_head)
    starts = np.concatenate([[0], np.flatnonzero(brk) + 1]).astype(np.int64)
    lengths = np.diff(np.append(starts, len(rows))).astype(np.int64)
    return starts, rows[starts], lengths


def take_two(head: np.ndarray, tail: np.ndarray | None, rows: np.ndarray,
             runs: tuple | None = None) -> np.ndarray:
    """Rows ``rows`` of ``head`` followed by ``tail`` (as if concatenated; None: no
    tail), without joining the two; each run of consecutive rows (a rank's rows kept in
    place) copied as a block (:func:`dpm.kernels.domain.copy_runs`); ``runs``:
    :func:`runs_of` of ``rows``, when several arrays take the same rows."""
    from ..kernels.domain import copy_runs

    out = np.empty((len(rows),) + head.shape[1:], head.dtype)
    if len(rows) == 0:
        return out
    if tail is None:
        tail = head[:0]
    if runs is None:
        runs = runs_of(rows, len(head))
    w = int(np.prod(head.shape[1:], dtype=np.int64))
    copy_runs(np.ascontiguousarray(head).reshape(-1), np.ascontiguousarray(tail).reshape(-1),
              w, *runs, out.reshape(-1))
    return out


def element_rows(estart: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(element indices of body ``rows`` in that order, elements per row)."""
    rows = np.asarray(rows, np.int64)
    if int(estart[-1]) == len(estart) - 1 and np.all(np.diff(estart) == 1):
        # (one element a body: element k of body k)
        return rows, np.ones(len(rows), np.int64)
    counts = estart[rows + 1] - estart[rows]
    if len(rows) == 0:
        return np.zeros(0, np.int64), counts
    first = estart[rows] - np.cumsum(np.r_[0, counts[:-1]])
    return np.repeat(first, counts) + np.arange(int(counts.sum())), counts


@dataclass
class Entries:
    """Contact list entries in some element numbering: pairs (i, j) or boundary entries
    (element i, primitive j), their history rows and touching flags."""

    i: np.ndarray
    j: np.ndarray
    hist: np.ndarray
    act: np.ndarray

    @classmethod
    def of(cls, lst: Any, active_only: bool = False, copy: bool = True) -> Entries:
        """The entries of a CSR list (``active_only``: the touching ones, taken without
        copying the others' history first: a rank lists ~2.5 pairs per touching one;
        ``copy=False``: every entry, history and flags as views of the list)."""
        n = lst.count
        if active_only:
            idx = np.flatnonzero(lst.active[:n])
            i = np.searchsorted(lst.start, idx, side="right") - 1
            return cls(i.astype(np.int64), np.take(lst.key, idx).astype(np.int64),
                       take(lst.history, idx), np.take(lst.active, idx))
        i = np.repeat(np.arange(len(lst.start) - 1), np.diff(lst.start))
        hist, act = lst.history[:n], lst.active[:n]
        return cls(i, lst.key[:n].astype(np.int64), hist.copy() if copy else hist,
                   act.copy() if copy else act)

    @classmethod
    def empty(cls, width: int) -> Entries:
        return cls(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, width)),
                   np.zeros(0, np.uint8))

    def where(self, mask: np.ndarray) -> Entries:
        return Entries(keep(self.i, mask), keep(self.j, mask), keep(self.hist, mask),
                       keep(self.act, mask))

    @staticmethod
    def cat(parts: list[Entries], width: int) -> Entries:
        parts = [p for p in parts if p is not None and len(p.i)]
        if not parts:
            return Entries.empty(width)
        return Entries(np.concatenate([p.i for p in parts]),
                       np.concatenate([p.j for p in parts]),
                       np.concatenate([p.hist for p in parts]),
                       np.concatenate([p.act for p in parts]))


def orient_pairs(e: Entries, mat: np.ndarray, plan: Any) -> Entries:
    """The pairs with i < j: a swapped pair's vector history floats change sign."""
    swap = e.i > e.j
    if np.any(swap):
        hist = e.hist.copy()
        model = plan.pair_model[mat[e.i[swap]], mat[e.j[swap]]]
        flips = plan.history_flips[model][:, :hist.shape[1]]
        sub = hist[swap]
        sub[flips] *= -1.0
        hist[swap] = sub
        e = Entries(np.where(swap, e.j, e.i), np.where(swap, e.i, e.j), hist, e.act)
    return e


def set_entries(lst: Any, n_rows: int, e: Entries, unique: bool = False) -> None:
    """Make ``lst`` hold exactly the entries ``e`` (sorted by row then key; with
    ``unique``, the first of equal (row, key) entries only), growing it if needed."""
    from ..kernels.entry_order import row_key_order

    o = row_key_order(np.ascontiguousarray(e.i, np.int64), np.ascontiguousarray(e.j),
                      int(n_rows))
    i, j = take(e.i, o), take(e.j, o)
    if unique and len(i) > 1:
        first = np.r_[True, (i[1:] != i[:-1]) | (j[1:] != j[:-1])]
        o = o[first]
        i, j = i[first], j[first]
    lst.start = np.zeros(n_rows + 1, np.int64)
    if len(i) > lst.capacity:
        lst.grow(len(i))
    if lst.history.shape[1] != e.hist.shape[1]:
        lst.set_history_width(e.hist.shape[1])
    lst._set_entries(i, j, take(e.hist, o), take(e.act, o), n_rows)
    _transpose(lst, n_rows)


def _transpose(lst: Any, n_rows: int) -> None:
    """A pair list's transposed index (``t_start``, ``t_pair``: the pairs where each
    element is second, in increasing order) of its entries as they now are."""
    from ..kernels.entry_order import key_order

    if isinstance(lst, Contacts):
        lst.t_start = np.zeros(n_rows + 1, np.int64)
        if lst.rows:
            j = lst.key[:lst.count]
            np.cumsum(np.bincount(j, minlength=n_rows), out=lst.t_start[1:])
            lst.t_pair[:len(j)] = key_order(j, int(n_rows))


def set_mapped_entries(lst: Any, n_rows: int, e: Entries, new_el: np.ndarray,
                       first_ghost: int, mat: np.ndarray | None = None,
                       plan: Any = None) -> None:
    """Make ``lst`` hold the entries ``e`` that a rank keeps, renumbered by ``new_el``
    (pool element -> new element, -1: dropped): pairs (``mat`` and ``plan`` given) with
    both elements kept and one owned (below ``first_ghost``), turned to i < j with their
    vector history negated where they swap; boundary entries (``mat`` None) of owned
    elements; the first of equal entries only. The same list as :func:`orient_pairs` and
    :func:`set_entries` (``unique``) after filtering, in compiled passes that copy each
    history row once (:mod:`dpm.kernels.entry_order`)."""
    from ..kernels.entry_order import (
        first_of_equal,
        mapped_entries,
        row_key_order,
        write_entries,
    )

    pairs = mat is not None
    rows, keys, src, swapped = mapped_entries(
        np.ascontiguousarray(e.i, np.int64), np.ascontiguousarray(e.j, np.int64),
        np.ascontiguousarray(new_el, np.int64), int(first_ghost), pairs)
    kept = first_of_equal(rows, keys, row_key_order(rows, keys, int(n_rows)))
    m = len(kept)
    lst.start = np.zeros(n_rows + 1, np.int64)
    if m > lst.capacity:
        lst.grow(m)
    if lst.history.shape[1] != e.hist.shape[1]:
        lst.set_history_width(e.hist.shape[1])
    if pairs:
        model, flips = plan.pair_model, plan.history_flips
    else:
        model, flips = np.zeros((1, 1), np.int64), np.zeros((1, 1), np.bool_)
        swapped, mat = swapped[:0], np.zeros(1, np.int64)
    write_entries(kept, rows, keys, src, swapped, np.ascontiguousarray(e.hist),
                  np.ascontiguousarray(e.act), np.ascontiguousarray(mat), model, flips,
                  int(n_rows), lst.key, lst.history, lst.active, lst.start)
    lst.force[:] = 0.0
    _transpose(lst, n_rows)


@dataclass
class Pool:
    """Body rows to choose from: body arrays (``Bodies.ARRAYS`` and ``element_start``),
    element arrays, the integrator's rows and the velocities the forces see, and the
    contact entries among them (element indices of the pool).

    The arrays are the *head* (a rank's own rows, as views: nothing copied); rows
    received at a migration are the *tail* (:meth:`extend`), numbered after the head's
    and read together with them by :meth:`take` without concatenating the two."""

    bodies: dict
    estart: np.ndarray
    elements: dict
    aux: np.ndarray
    vf: np.ndarray
    wf: np.ndarray
    pairs: Entries
    walls: Entries
    #: the rows appended by :meth:`extend`, laid out as a payload of
    #: :meth:`rows_payload` (``bodies``, ``elements``, ``counts``, ``aux``, ``vf``,
    #: ``wf``); None: none
    tail: dict | None = None

    ELEMENT_FIELDS = ("offset", "radius", "material", "position", "reference")

    @classmethod
    def of(cls, bodies: Bodies, elements: Elements, aux: np.ndarray, vf: np.ndarray,
           wf: np.ndarray, contacts: Contacts, wall_contacts: WallContacts,
           active_only: bool = False) -> Pool:
        return cls({k: getattr(bodies, k) for k in Bodies.ARRAYS}, bodies.element_start,
                   {k: getattr(elements, k) for k in cls.ELEMENT_FIELDS}, aux, vf, wf,
                   Entries.of(contacts, active_only), Entries.of(wall_contacts, active_only))

    def __len__(self) -> int:
        return len(self.bodies["id"]) + (len(self.tail["bodies"]["id"]) if self.tail else 0)

    def ids(self) -> np.ndarray:
        """Every row's body id, head then tail."""
        ids = self.bodies["id"]
        return np.concatenate([ids, self.tail["bodies"]["id"]]) if self.tail else ids

    def take(self, section: str, name: str, rows: np.ndarray, runs: tuple | None = None
             ) -> np.ndarray:
        """Rows ``rows`` (body rows, or element rows for ``section`` "elements") of one
        array, head and tail together, in a fresh array (``runs``: as :func:`take_two`)."""
        if section in ("bodies", "elements"):
            head = getattr(self, section)[name]
            tail = self.tail[section][name] if self.tail else None
        else:
            head, tail = getattr(self, section), (self.tail[section] if self.tail else None)
        return take_two(head, tail, rows, runs)

    def rows_payload(self, rows: np.ndarray) -> dict:
        """The arrays of body ``rows`` (to send to another rank)."""
        er, counts = element_rows(self.estart, rows)
        return {"bodies": {k: take(v, rows) for k, v in self.bodies.items()},
                "counts": counts,
                "elements": {k: take(v, er) for k, v in self.elements.items()},
                "aux": take(self.aux, rows), "vf": take(self.vf, rows),
                "wf": take(self.wf, rows)}

    def extend(self, payloads: list[dict]) -> None:
        """Append the body rows of ``payloads`` (no contact entries) to the tail (the
        head's arrays are not copied)."""
        payloads = [p for p in payloads if p is not None and len(p["counts"])]
        if not payloads:
            return
        if self.tail:
            payloads = [self.tail] + payloads
        self.tail = {
            "bodies": {k: np.concatenate([p["bodies"][k] for p in payloads])
                       for k in self.bodies},
            "elements": {k: np.concatenate([p["elements"][k] for p in payloads])
                         for k in self.elements},
            "counts": np.concatenate([p["counts"] for p in payloads]),
            **{name: np.concatenate([p[name] for p in payloads])
               for name in ("aux", "vf", "wf")}}
        n_head = len(self.bodies["id"])
        counts = np.concatenate([np.diff(self.estart[:n_head + 1]), self.tail["counts"]])
        self.estart = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


class LocalScene:
    """What :class:`dpm.backends.cpu.CpuBackend` reads of a simulation, for one rank."""

    def __init__(self, sim: Any) -> None:
        self.plan = sim.plan
        self.walls = sim.walls
        self.gravity = sim.gravity
        self.skin = sim.skin
        self.max_overlap = sim.max_overlap
        self.sphere_orientation = sim.sphere_orientation
        self.period = sim.period
        self.integrator = sim.integrator
        self.bodies = Bodies()
        self.elements = Elements()
        self.contacts = Contacts()
        self.wall_contacts = WallContacts()
        self.contacts.set_history_width(sim.plan.history_width)
        self.wall_contacts.set_history_width(sim.plan.history_width)
        self.rebuild_count = 0
        #: owned bodies (the first rows; the ghosts follow)
        self.n_owned = 0


def assemble(scene: LocalScene, pool: Pool, owned: np.ndarray, ghosts: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fill ``scene`` with pool rows ``owned`` then ``ghosts`` (in those orders) and the
    pool's contact entries among their elements. Returns (aux, vf, wf) of the new rows."""
    rows = np.concatenate([owned, ghosts]).astype(np.int64)
    # (fresh arrays, not buffers kept from the last rows: with buffers reused the step
    # kernels ran 5-15 % slower on 2 ranks of 1e5 spheres, for a reason not found)
    b = scene.bodies
    runs = runs_of(rows, len(pool.bodies["id"]))
    for k in pool.bodies:
        setattr(b, k, pool.take("bodies", k, rows, runs))
    er, counts = element_rows(pool.estart, rows)
    b.element_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    b.ghosts = int(len(ghosts))
    e = scene.elements
    e.owner = np.repeat(np.arange(len(rows)), counts).astype(np.int64)
    e_runs = runs_of(er, len(pool.elements["radius"]))
    for k in pool.elements:
        setattr(e, k, pool.take("elements", k, er, e_runs))
    new_el = np.full(int(pool.estart[-1]), -1, np.int64)
    new_el[er] = np.arange(len(er))
    # a ghost's entries among ghosts and with boundaries are its owner's work: an entry is
    # kept where an element of it is owned here (as the rank's list rebuilds keep them)
    first_ghost = int(b.element_start[len(owned)])
    set_mapped_entries(scene.contacts, len(er), pool.pairs, new_el, first_ghost,
                       e.material, scene.plan)
    set_mapped_entries(scene.wall_contacts, len(er), pool.walls, new_el, first_ghost)
    scene.n_owned = int(len(owned))
    return (pool.take("aux", "", rows, runs), pool.take("vf", "", rows, runs),
            pool.take("wf", "", rows, runs))
