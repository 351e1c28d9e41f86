"""Whole-scene measures: kinetic energy, linear and angular momentum."""

from __future__ import annotations

import numpy as np


def to_body(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate world vectors v into the body frames of quaternions q (R(q)^T v):
    v + w t + u x t with t = 2 u x v, u = -(x, y, z) the conjugate's vector part, written
    out by components (the formula ``np.cross`` gave, without its temporaries: the energy
    guard asks this of every body at every kernel call's end)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    v0, v1, v2 = v[:, 0], v[:, 1], v[:, 2]
    t0 = 2.0 * (z * v1 - y * v2)
    t1 = 2.0 * (x * v2 - z * v0)
    t2 = 2.0 * (y * v0 - x * v1)
    out = np.empty(np.shape(v))
    out[:, 0] = v0 + w * t0 + (z * t1 - y * t2)
    out[:, 1] = v1 + w * t1 + (x * t2 - z * t0)
    out[:, 2] = v2 + w * t2 + (y * t0 - x * t1)
    return out


def kinetic_energy(b) -> float:
    """Translational plus rotational kinetic energy [J] of bodies ``b`` (principal frame):
    sum 1/2 m v.v + 1/2 sum_k I_k w_k^2 (w in the body frame)."""
    trans = 0.5 * np.sum(b.mass * np.einsum("ij,ij->i", b.velocity, b.velocity))
    w_body = to_body(b.orientation, b.angular_velocity)
    rot = 0.5 * np.sum(b.inertia * w_body**2)
    return float(trans + rot)


def momentum(b) -> np.ndarray:
    """Total linear momentum [kg m/s]."""
    return (b.mass[:, None] * b.velocity).sum(axis=0)


def angular_momentum(b) -> np.ndarray:
    """Total angular momentum about the origin [kg m2/s]: sum m x cross v + R I R^T w."""
    spin_body = b.inertia * to_body(b.orientation, b.angular_velocity)
    spin = to_body(b.orientation * np.array([1.0, -1.0, -1.0, -1.0]), spin_body)
    orbital = np.cross(b.position, b.mass[:, None] * b.velocity)
    return (orbital + spin).sum(axis=0)
