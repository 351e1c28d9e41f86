"""Whole-scene measures against an independent rotation (scipy's)."""

from types import SimpleNamespace

import numpy as np
from scipy.spatial.transform import Rotation

from dpm.measures import angular_momentum, kinetic_energy, to_body


def _random(n, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    return q, rng.normal(size=(n, 3)), rng


def test_to_body_is_the_transposed_rotation_of_the_quaternion():
    q, v, _ = _random(500)
    # dpm's quaternions are (w, x, y, z); scipy's (x, y, z, w)
    rot = Rotation.from_quat(np.c_[q[:, 1:], q[:, :1]])
    assert np.allclose(to_body(q, v), rot.inv().apply(v), rtol=0, atol=1e-13)


def test_kinetic_energy_and_angular_momentum_of_rotated_bodies():
    q, w, rng = _random(200, seed=1)
    b = SimpleNamespace(mass=rng.uniform(1, 2, 200), velocity=rng.normal(size=(200, 3)),
                        orientation=q, angular_velocity=w,
                        inertia=rng.uniform(0.1, 1.0, (200, 3)),
                        position=rng.normal(size=(200, 3)))
    rot = Rotation.from_quat(np.c_[q[:, 1:], q[:, :1]]).as_matrix()  # body -> world
    # inertia tensor in the world frame R diag(I) R^T; E_rot = 1/2 w . (I_world w)
    i_world = np.einsum("nij,nj,nkj->nik", rot, b.inertia, rot)
    e_rot = 0.5 * np.einsum("ni,nij,nj->", w, i_world, w)
    e_trans = 0.5 * np.sum(b.mass * np.sum(b.velocity**2, axis=1))
    assert abs(kinetic_energy(b) - (e_rot + e_trans)) < 1e-12 * (e_rot + e_trans)
    l_ref = (np.cross(b.position, b.mass[:, None] * b.velocity)
             + np.einsum("nij,nj->ni", i_world, w)).sum(axis=0)
    assert np.allclose(angular_momentum(b), l_ref, rtol=1e-12, atol=1e-12)
