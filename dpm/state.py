"""Simulation state as structure of arrays (float64, C-contiguous).

Bodies own one or more sphere elements; the contact search sees elements only.
"""

from __future__ import annotations

import numpy as np

from .errors import SceneError
from .kernels.config import N_HISTORY
from .kernels.entry_order import key_order, row_key_order


def _appended(old: np.ndarray, value) -> np.ndarray:
    """``old`` with the rows of ``value`` added, C-contiguous in ``old``'s dtype. While
    ``old`` is empty the fresh ``value`` is taken without a copy: an all-zero array (a
    sphere's element offsets, the shape index) then keeps its pages unmapped and costs no
    resident memory, and a scene's set-up makes one copy less of each field."""
    value = np.asarray(value)
    if value.shape[1:] != old.shape[1:] or value.ndim != old.ndim:
        raise ValueError(f"rows of shape {value.shape[1:]} (array {value.shape}) appended to "
                         f"rows of shape {old.shape[1:]}")
    if len(old) == 0:
        return np.ascontiguousarray(value, dtype=old.dtype)
    return np.ascontiguousarray(np.concatenate([old, value.astype(old.dtype, copy=False)]))


class Bodies:
    """Per-body arrays, one row per body.

    id (n,) int64 unique and stable; position, velocity, angular_velocity, force, torque
    (n, 3); orientation (n, 4) unit quaternion (w, x, y, z), body frame = principal frame;
    mass (n,); inertia (n, 3) principal moments; invmass, invinertia (0 for fixed bodies);
    material, shape (n,) int64 indices (into ``sim.materials`` and ``sim.shape_names``);
    radius (n,) bounding radius; birth (n,) time of insertion [s]; element_start (n + 1,):
    the elements of body b are element_start[b] : element_start[b + 1].
    """

    #: every per-body array (one row per body)
    ARRAYS = ("id", "position", "velocity", "angular_velocity", "force", "torque", "inertia",
              "invinertia", "orientation", "mass", "invmass", "radius", "material", "shape",
              "birth")

    FIELDS3 = ("position", "velocity", "angular_velocity", "force", "torque", "inertia",
               "invinertia")

    def __init__(self) -> None:
        self.id = np.zeros(0, np.int64)
        for f in self.FIELDS3:
            setattr(self, f, np.zeros((0, 3)))
        self.orientation = np.zeros((0, 4))
        self.mass = np.zeros(0)
        self.invmass = np.zeros(0)
        self.radius = np.zeros(0)
        self.material = np.zeros(0, np.int64)
        self.shape = np.zeros(0, np.int64)
        self.birth = np.zeros(0)
        self.element_start = np.zeros(1, np.int64)
        #: the last ``ghosts`` rows are ghost bodies: copies of bodies that another
        #: process owns (its halo), set by the backend each step; they are not integrated,
        #: their elements take part in the contacts, and their force and torque rows hold
        #: what they received here, for the backend to hand back to the owners. 0 on one
        #: process.
        self.ghosts = 0

    def __len__(self) -> int:
        return len(self.id)

    def append(self, **rows: np.ndarray) -> None:
        """Add rows; the caller hands over fresh arrays, which the first rows keep."""
        for name, value in rows.items():
            setattr(self, name, _appended(getattr(self, name), value))

    def keep(self, mask: np.ndarray) -> None:
        """Keep only the bodies where ``mask`` is True (element_start recomputed)."""
        counts = np.diff(self.element_start)[mask]
        for name in self.ARRAYS:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[mask]))
        self.element_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    def permute(self, order: np.ndarray) -> np.ndarray:
        """Reorder the bodies: new body k is old body ``order[k]`` (a permutation). Each
        body keeps its id, and its elements stay together in their order; returns the
        element order (new element m is old element ``result[m]``)."""
        order = np.asarray(order, np.int64)
        counts = np.diff(self.element_start)
        starts = self.element_start[:-1]
        elem_order = np.repeat(starts[order] - np.cumsum(np.r_[0, counts[order][:-1]]),
                               counts[order]) + np.arange(int(counts.sum()))
        for name in self.ARRAYS:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[order]))
        self.element_start = np.concatenate([[0], np.cumsum(counts[order])]).astype(np.int64)
        return elem_order


class Elements:
    """Per-element arrays: owner body, body-frame offset, radius, world position, material."""

    def __init__(self) -> None:
        self.owner = np.zeros(0, np.int64)
        self.offset = np.zeros((0, 3))
        self.radius = np.zeros(0)
        self.material = np.zeros(0, np.int64)
        self.position = np.zeros((0, 3))
        self.reference = np.zeros((0, 3))

    def __len__(self) -> int:
        return len(self.owner)

    def append(self, owner, offset, radius, material) -> None:
        """Add elements (fresh arrays, kept as they are by the first rows)."""
        self.owner = _appended(self.owner, owner)
        self.offset = _appended(self.offset, offset)
        self.radius = _appended(self.radius, radius)
        self.material = _appended(self.material, material)
        self.position = np.zeros((len(self.owner), 3))
        self.reference = np.full((len(self.owner), 3), np.inf)  # forces a rebuild

    def keep(self, mask: np.ndarray, new_owner: np.ndarray) -> None:
        """Keep the elements where ``mask`` is True; ``new_owner`` maps old body indices
        to new ones."""
        self.owner = np.ascontiguousarray(new_owner[self.owner[mask]])
        for name in ("offset", "radius", "material", "position", "reference"):
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[mask]))

    def permute(self, order: np.ndarray, new_body: np.ndarray) -> None:
        """Reorder the elements: new element m is old element ``order[m]``; ``new_body``
        maps old body indices to new ones. (An element is known by its body's id and its
        index within the body, which a permutation keeps.)"""
        self.owner = np.ascontiguousarray(new_body[self.owner[order]])
        for name in ("offset", "radius", "material", "position", "reference"):
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[order]))


#: partner keys and pair indices (element, primitive and pair numbers stay below 2**31):
#: 4 bytes less per listed pair and per transposed entry than int64
KEY_DTYPE = np.int32
#: the largest list size and element count (so that every index fits)
KEY_MAX = int(np.iinfo(KEY_DTYPE).max)


class _CsrList:
    """A CSR list keyed per element with contact history, active flags and force rows.
    A rebuild writes the new list into scratch arrays of its exact size that live only
    while it runs (see :func:`dpm.kernels.neighbours.build_neighbour_list`)."""

    FORCE_WIDTH = 9
    ALWAYS_ROWS = True

    def __init__(self, n_elements: int = 0, capacity: int = 0) -> None:
        #: history floats per entry (the widest the scene's contact laws declare)
        self.history_width = N_HISTORY
        #: whether the force rows are allocated (see :meth:`use_rows`)
        self.rows = self.ALWAYS_ROWS
        self.reset(n_elements, capacity)

    def use_rows(self, rows: bool) -> None:
        """Allocate the force rows (zeroed) or drop them. The fused force pass of
        one-thread sphere scenes needs none: it adds each pair's force to both bodies as
        it computes it, so a scene then carries no 72-byte row per pair."""
        rows = bool(rows) or self.ALWAYS_ROWS
        if rows != self.rows:
            self.rows = rows
            self.force = np.zeros((self.capacity if rows else 0, self.FORCE_WIDTH))

    def set_history_width(self, width: int) -> None:
        """Give each entry ``width`` history floats, keeping the first ones."""
        width = int(width)
        if width == self.history_width:
            return
        keep = min(width, self.history_width)
        self.history_width = width
        new = np.zeros((len(self.history), width))
        new[:, :keep] = self.history[:, :keep]
        self.history = new

    def reset(self, n_elements: int, capacity: int) -> None:
        if n_elements > KEY_MAX:
            raise SceneError(f"{n_elements} elements: more than the {KEY_MAX} that int32 "
                             "indices allow; split the scene")
        self.start = np.zeros(n_elements + 1, np.int64)
        self._allocate(max(int(capacity), 16))

    def _allocate(self, cap: int) -> None:
        cap = min(cap, KEY_MAX)  # (a list of more entries is refused by grow)
        self.key = np.zeros(cap, KEY_DTYPE)
        self.history = np.zeros((cap, self.history_width))
        self.active = np.zeros(cap, np.uint8)
        self.force = np.zeros((cap if self.rows else 0, self.FORCE_WIDTH))

    @property
    def capacity(self) -> int:
        return len(self.key)

    @property
    def count(self) -> int:
        return int(self.start[-1])

    def resize_rows(self, n_elements: int) -> None:
        """Give new elements (appended) empty rows; the list stays as it is."""
        old = len(self.start) - 1
        if n_elements > old:
            self.start = np.concatenate([self.start, np.full(n_elements - old,
                                                             self.start[-1])])

    def keep_rows(self, keep: np.ndarray, new_index: np.ndarray, remap_keys: bool) -> None:
        """Drop the rows of removed elements (``keep`` False) and, if ``remap_keys``
        (element pairs), the entries whose partner is removed; renumber by
        ``new_index``. Order is kept, so each row stays sorted."""
        n = len(self.start) - 1
        cnt = self.count
        rows = np.repeat(np.arange(n), np.diff(self.start))
        keys = self.key[:cnt]
        valid = keep[rows] & (keep[keys] if remap_keys else True)
        m = int(valid.sum())
        new_keys = new_index[keys[valid]] if remap_keys else keys[valid]
        hist = self.history[:cnt][valid]
        act = self.active[:cnt][valid]
        self.key[:m] = new_keys
        self.history[:m] = hist
        self.active[:m] = act
        n_new = int(keep.sum())
        counts = np.bincount(new_index[rows[valid]], minlength=n_new)
        self.start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    def _rows_of(self) -> np.ndarray:
        return np.repeat(np.arange(len(self.start) - 1), np.diff(self.start))

    def _set_entries(self, rows: np.ndarray, keys: np.ndarray, hist: np.ndarray,
                     act: np.ndarray, n_rows: int) -> None:
        """The list as given (sorted by row, then key): keys, history, flags, CSR start;
        force rows zeroed (the next force evaluation writes the touching ones)."""
        m = len(keys)
        self.key[:m] = keys
        self.history[:m] = hist
        self.active[:m] = act
        self.force[:] = 0.0
        self.start = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n_rows))]
                                    ).astype(np.int64)

    def permute(self, new_index: np.ndarray) -> None:
        """Elements were reordered (old element i is now ``new_index[i]``): the rows move
        with their elements, each entry keeps its key, history and flag."""
        cnt = self.count
        rows = new_index[self._rows_of()]
        keys = self.key[:cnt]
        o = row_key_order(np.ascontiguousarray(rows, np.int64), keys, len(self.start) - 1)
        self._set_entries(rows[o], keys[o], self.history[:cnt][o], self.active[:cnt][o],
                          len(self.start) - 1)

    def grow(self, needed: int) -> None:
        """Enlarge the buffers to hold ``needed`` entries (with headroom); keep the list."""
        if needed > KEY_MAX:
            raise SceneError(f"{needed} list entries: more than the {KEY_MAX} that int32 "
                             "pair indices allow; split the scene")
        n = self.count
        old = (self.key, self.history, self.active)
        self._allocate(int(needed * 1.25) + 16)
        for new, o in zip((self.key, self.history, self.active), old, strict=True):
            new[:n] = o[:n]


class Contacts(_CsrList):
    """Element pairs: half neighbour list in CSR form (``start``, ``key`` = partner j > i),
    one history row (``history_width`` floats), active flag and force row (F on i, torque on body
    of i, torque on body of j) per pair; the transposed index ``t_start``/``t_pair`` (the
    pairs where an element is second, in increasing order). Pairs are within
    r_i + r_j + skin. The force rows and the transposed index exist only while a force pass
    needs them (:meth:`use_rows`): the fused pass of one-thread sphere scenes needs neither
    (``t_pair`` is then empty, ``t_start`` zero and the rebuild skips the transpose)."""

    ALWAYS_ROWS = False

    def use_rows(self, rows: bool) -> None:
        """Force rows and transposed index (built now from the list) or neither."""
        was = self.rows
        super().use_rows(rows)
        if self.rows != was:
            self.t_start = np.zeros(len(self.start), np.int64)
            self.t_pair = np.zeros(self.capacity if self.rows else 0, KEY_DTYPE)
            if self.rows:
                keys = self.key[:self.count]
                np.cumsum(np.bincount(keys, minlength=len(self.start) - 1),
                          out=self.t_start[1:])
                self.t_pair[:len(keys)] = np.argsort(keys, kind="stable")

    def reset(self, n_elements: int, capacity: int) -> None:
        super().reset(n_elements, capacity)
        self.t_start = np.zeros(n_elements + 1, np.int64)

    def _allocate(self, cap: int) -> None:
        super()._allocate(cap)
        self.t_pair = np.zeros(cap if self.rows else 0, KEY_DTYPE)

    def resize_rows(self, n_elements: int) -> None:
        super().resize_rows(n_elements)
        self.t_start = np.zeros(n_elements + 1, np.int64)  # rebuilt with the list

    def keep_rows(self, keep, new_index, remap_keys) -> None:
        super().keep_rows(keep, new_index, remap_keys)
        self.t_start = np.zeros(len(self.start), np.int64)

    def permute(self, new_index: np.ndarray, flips: np.ndarray | None = None) -> None:
        """Elements were reordered (old element i is now ``new_index[i]``): every pair
        keeps its history and flag. A pair whose first element is now the larger index
        is stored the other way round (the list holds j > i), and the history floats
        that are vectors of i relative to j (``flips[pair, slot]``, from the laws' parts:
        the tangential and rolling springs) change sign; scalars (a normal law's plastic
        overlap) stay. ``flips`` None: none change sign."""
        cnt = self.count
        i = new_index[self._rows_of()]
        j = new_index[self.key[:cnt]]
        hist = self.history[:cnt].copy()
        if flips is not None:
            swapped = (i > j)[:, None] & flips[:cnt, :hist.shape[1]]
            hist[swapped] *= -1.0
        lo, hi = np.minimum(i, j), np.maximum(i, j)
        o = row_key_order(np.ascontiguousarray(lo, np.int64), np.ascontiguousarray(hi),
                          len(self.start) - 1)
        self._set_entries(lo[o], hi[o], hist[o], self.active[:cnt][o], len(self.start) - 1)
        if self.rows:  # the transposed index of the reordered list
            keys = self.key[:cnt]
            self.t_start[:] = 0
            np.cumsum(np.bincount(keys, minlength=len(self.start) - 1), out=self.t_start[1:])
            self.t_pair[:cnt] = key_order(keys, len(self.start) - 1)


class WallContacts(_CsrList):
    """Element-primitive entries (``key`` = boundary primitive index) within r + skin, per
    element, with history, active flag and force row (force and torque on the body, torque
    on the boundary about its frame origin); ``tag`` is the contact pass's scratch (the
    feature of a triangle contact)."""

    FORCE_WIDTH = 9

    def _allocate(self, cap: int) -> None:
        super()._allocate(cap)
        self.tag = np.zeros(cap, np.int64)


#: columns of a boundary frame row: origin o [0:3], rotation R [3:12] (row-major, local to
#: world), origin velocity [12:15], angular velocity [15:18]; x_world = R x_local + o
FRAME_WIDTH = 18
IDENTITY_FRAME = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0], float)


#: a boundary of more primitives than this gets a search grid; fewer are tested one by
#: one (a triangle's plane test rejects most in a few ns: on the meshGran port's 18 large
#: triangles the plain loop takes 0.63-0.78 of the grid's time)
GRID_FROM = 32


class BoundaryTable:
    """Packed primitives of every boundary, their boundary frames and search grids.

    Per primitive: ``kind``, ``par`` (geometry in the boundary frame, see
    :mod:`dpm.kernels.boundary_geometry`), ``owner`` (boundary index), ``material``,
    ``ids`` (triangle vertex ids and feature flags). Per boundary: ``frame`` (current),
    ``frame_ref`` (at the last rebuild), ``extent`` (largest distance of its geometry from
    the frame origin; inf if unbounded), ``load`` (force [0:3] and torque about the frame
    origin [3:6] that the particles exert, last step), and its search grid (``grid_int``:
    use grid, dims x3, base cell, first and last primitive; ``grid_flt``: lower corner x3,
    cell size; ``cell_start``/``cell_items``: primitives per cell; ``prim_cells``: each
    primitive's cell range).
    """

    def __init__(self, boundaries, material_index, reach: float) -> None:
        kinds, pars, owners, mats, ids = [], [], [], [], []
        nb = len(boundaries)
        self.grid_int = np.zeros((nb, 8), np.int64)
        self.grid_flt = np.zeros((nb, 4))
        self.extent = np.zeros(nb)
        starts, items = [0], []
        cells_of = []
        first = 0
        for k, bd in enumerate(boundaries):
            prims = bd.primitives()
            n = len(prims.kind)
            kinds.append(prims.kind)
            pars.append(prims.par)
            owners.append(np.full(n, k, np.int64))
            mats.append(np.full(n, material_index(bd.material), np.int64))
            ids.append(prims.ids)
            self.extent[k] = prims.extent
            g = self.grid_int[k]
            g[5] = first
            g[6] = first + n
            lo, hi = prims.lower, prims.upper
            if n > GRID_FROM and np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)):
                lo = lo.min(axis=0) - reach
                hi = hi.max(axis=0) + reach
                size = max(2.0 * reach, float(np.max(hi - lo)) / 1e3)
                dims = np.maximum(np.ceil((hi - lo) / size).astype(np.int64), 1)
                while np.prod(dims) > 8 * n + 64:
                    size *= 1.5
                    dims = np.maximum(np.ceil((hi - lo) / size).astype(np.int64), 1)
                c_lo = np.clip(((prims.lower - lo) / size).astype(np.int64), 0, dims - 1)
                c_hi = np.clip(((prims.upper - lo) / size).astype(np.int64), 0, dims - 1)
                g[0] = 1
                g[1:4] = dims
                g[4] = len(starts) - 1
                self.grid_flt[k, :3] = lo
                self.grid_flt[k, 3] = size
                ncell = int(np.prod(dims))
                buckets = [[] for _ in range(ncell)]
                for p in range(n):
                    for cx in range(c_lo[p, 0], c_hi[p, 0] + 1):
                        for cy in range(c_lo[p, 1], c_hi[p, 1] + 1):
                            for cz in range(c_lo[p, 2], c_hi[p, 2] + 1):
                                buckets[(cx * dims[1] + cy) * dims[2] + cz].append(first + p)
                for bucket in buckets:
                    items.extend(bucket)
                    starts.append(len(items))
                cells_of.append(np.hstack([c_lo, c_hi]))
            else:
                cells_of.append(np.zeros((n, 6), np.int64))
            first += n
        def cat(a, shape, dt):
            return (np.ascontiguousarray(np.concatenate(a)).astype(dt)
                       if a else np.zeros(shape, dt))
        self.kind = cat(kinds, (0,), np.int64)
        self.par = cat(pars, (0, 20), float).reshape(-1, 20)
        self.owner = cat(owners, (0,), np.int64)
        self.material = cat(mats, (0,), np.int64)
        self.ids = cat(ids, (0, 4), np.int64).reshape(-1, 4)
        self.prim_cells = cat(cells_of, (0, 6), np.int64).reshape(-1, 6)
        self.cell_start = np.asarray(starts, np.int64)
        self.cell_items = np.asarray(items or [0], np.int64)
        self.frame = np.tile(IDENTITY_FRAME, (nb, 1))
        self.frame_ref = self.frame[:, :12].copy()
        #: per boundary: force [0:3], torque about the frame origin [3:6] of the last
        #: step, work done on the particles since the first step [6] (J; the running sum,
        #: which ``Boundary.work`` reads)
        self.load = np.zeros((nb, 7))
        #: the search rows of every boundary when on (:meth:`set_enabled` empties a
        #: switched-off boundary's rows: the search then finds none of its primitives)
        self.grid_on = self.grid_int.copy()

    def set_enabled(self, k: int, on: bool) -> None:
        """Let the contact search see boundary ``k`` (``on``) or none of its primitives
        (:mod:`dpm.switches`)."""
        self.grid_int[k] = self.grid_on[k]
        if not on:
            self.grid_int[k, 0] = 0           # no grid: the plain loop over [5, 6) ...
            self.grid_int[k, 6] = self.grid_on[k, 5]   # ... which is empty
            self.load[k, :6] = 0.0

    def __len__(self) -> int:
        return len(self.kind)
