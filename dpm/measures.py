"""Whole-scene measures: kinetic energy, linear and angular momentum."""

from __future__ import annotations

import numpy as np


def to_body(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate world vectors v into the body frames of quaternions q (R(q)^T v)."""
    w, x, y, z = q.T
    qv = np.stack([-x, -y, -z], axis=1)  # conjugate
    t = 2.0 * np.cross(qv, v)
    return v + w[:, None] * t + np.cross(qv, t)


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
