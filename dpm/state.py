"""Simulation state as structure of arrays (float64, C-contiguous).

Bodies own one or more sphere elements; the contact search sees elements only.
"""

from __future__ import annotations

import numpy as np

from .kernels.config import N_HISTORY


class Bodies:
    """Per-body arrays, one row per body.

    id (n,) int64 unique and stable; position, velocity, angular_velocity, force, torque
    (n, 3); orientation (n, 4) unit quaternion (w, x, y, z), body frame = principal frame;
    mass (n,); inertia (n, 3) principal moments; invmass, invinertia (0 for fixed bodies);
    material, shape (n,) int64 indices; radius (n,) bounding radius; element_start
    (n + 1,): the elements of body b are element_start[b] : element_start[b + 1].
    """

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
        self.element_start = np.zeros(1, np.int64)

    def __len__(self) -> int:
        return len(self.id)

    def append(self, **rows: np.ndarray) -> None:
        for name, value in rows.items():
            old = getattr(self, name)
            new = np.concatenate([old, np.asarray(value).astype(old.dtype)])
            setattr(self, name, np.ascontiguousarray(new))


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
        self.owner = np.concatenate([self.owner, owner.astype(np.int64)])
        self.offset = np.ascontiguousarray(np.concatenate([self.offset, offset]))
        self.radius = np.concatenate([self.radius, radius])
        self.material = np.concatenate([self.material, material.astype(np.int64)])
        self.position = np.zeros((len(self.owner), 3))
        self.reference = np.full((len(self.owner), 3), np.inf)  # forces a rebuild


class _CsrList:
    """A CSR list keyed per element with contact history, active flags and force rows,
    plus the scratch buffers of the next rebuild (same sizes)."""

    FORCE_WIDTH = 9

    def __init__(self, n_elements: int = 0, capacity: int = 0) -> None:
        self.reset(n_elements, capacity)

    def reset(self, n_elements: int, capacity: int) -> None:
        self.start = np.zeros(n_elements + 1, np.int64)
        self.new_start = np.zeros(n_elements + 1, np.int64)
        self._allocate(max(int(capacity), 16))

    def _allocate(self, cap: int) -> None:
        self.key = np.zeros(cap, np.int64)
        self.history = np.zeros((cap, N_HISTORY))
        self.active = np.zeros(cap, np.uint8)
        self.force = np.zeros((cap, self.FORCE_WIDTH))
        self.new_key = np.zeros(cap, np.int64)
        self.new_history = np.zeros((cap, N_HISTORY))
        self.new_active = np.zeros(cap, np.uint8)

    @property
    def capacity(self) -> int:
        return len(self.key)

    @property
    def count(self) -> int:
        return int(self.start[-1])

    def grow(self, needed: int) -> None:
        """Enlarge the buffers to hold ``needed`` entries (with headroom); keep the list."""
        n = self.count
        old = (self.key, self.history, self.active)
        self._allocate(int(needed * 1.25) + 16)
        for new, o in zip((self.key, self.history, self.active), old, strict=True):
            new[:n] = o[:n]


class Contacts(_CsrList):
    """Element pairs: half neighbour list in CSR form (``start``, ``key`` = partner j > i),
    one history row (N_HISTORY floats), active flag and force row (F on i, torque on body
    of i, torque on body of j) per pair; the transposed index ``t_start``/``t_pair``.
    Pairs are within r_i + r_j + skin."""

    def reset(self, n_elements: int, capacity: int) -> None:
        super().reset(n_elements, capacity)
        self.t_start = np.zeros(n_elements + 1, np.int64)

    def _allocate(self, cap: int) -> None:
        super()._allocate(cap)
        self.t_pair = np.zeros(cap, np.int64)

    def grow(self, needed: int) -> None:
        super().grow(needed)  # t_pair is rebuilt with the list

    @property
    def pair_count(self) -> int:
        return self.count


class WallContacts(_CsrList):
    """Element-plane entries (``key`` = plane index) within r + skin, per element, with
    history, active flag and force row (force, torque)."""

    FORCE_WIDTH = 6


class Walls:
    """Packed planes of every plane-type boundary: point, inward normal, velocity, material,
    owning boundary, and the force the particles exert on each plane (last step)."""

    def __init__(self, points, normals, materials, owners) -> None:
        k = len(points)
        self.point = np.ascontiguousarray(np.asarray(points, float).reshape(k, 3))
        self.normal = np.ascontiguousarray(np.asarray(normals, float).reshape(k, 3))
        self.velocity = np.zeros((k, 3))
        self.material = np.asarray(materials, np.int64).reshape(k)
        self.owner = np.asarray(owners, np.int64).reshape(k)  # boundary index of each plane
        self.force = np.zeros((k, 3))
