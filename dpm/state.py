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
    material, shape (n,) int64 indices; radius (n,) bounding radius.
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


class Contacts:
    """Half neighbour list (CSR) with contact history, plus scratch buffers for rebuilds.

    ``start`` (m+1,), ``j`` (capacity,), ``history`` (capacity, N_HISTORY); pairs within
    r_i + r_j + skin. ``new_*`` are the rebuild buffers of the same sizes.
    """

    def __init__(self, n_elements: int = 0, capacity: int = 0) -> None:
        self.reset(n_elements, capacity)

    def reset(self, n_elements: int, capacity: int) -> None:
        capacity = max(int(capacity), 16)
        self.start = np.zeros(n_elements + 1, np.int64)
        self.new_start = np.zeros(n_elements + 1, np.int64)
        self.j = np.zeros(capacity, np.int64)
        self.new_j = np.zeros(capacity, np.int64)
        self.history = np.zeros((capacity, N_HISTORY))
        self.new_history = np.zeros((capacity, N_HISTORY))

    @property
    def capacity(self) -> int:
        return len(self.j)

    def grow(self, needed: int) -> None:
        """Enlarge the buffers to hold ``needed`` pairs (with headroom); keep the list."""
        cap = int(needed * 1.5) + 16
        j = np.zeros(cap, np.int64)
        h = np.zeros((cap, N_HISTORY))
        n = self.start[-1]
        j[:n] = self.j[:n]
        h[:n] = self.history[:n]
        self.j, self.history = j, h
        self.new_j = np.zeros(cap, np.int64)
        self.new_history = np.zeros((cap, N_HISTORY))

    @property
    def pair_count(self) -> int:
        return int(self.start[-1])


class Walls:
    """Packed planes of every plane-type boundary: point, inward normal, velocity, material,
    force on the plane (last step), and element-plane contact history (m * planes rows)."""

    def __init__(self, points, normals, materials, owners, n_elements: int) -> None:
        k = len(points)
        self.point = np.ascontiguousarray(np.asarray(points, float).reshape(k, 3))
        self.normal = np.ascontiguousarray(np.asarray(normals, float).reshape(k, 3))
        self.velocity = np.zeros((k, 3))
        self.material = np.asarray(materials, np.int64).reshape(k)
        self.owner = np.asarray(owners, np.int64).reshape(k)  # boundary index of each plane
        self.force = np.zeros((k, 3))
        self.history = np.zeros((max(n_elements * k, 1), N_HISTORY))
