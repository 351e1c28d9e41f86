"""Rotation of rigid bodies with principal moments of inertia (I1, I2, I3).

The body frame is the principal frame; q (w, x, y, z) rotates it into the world frame,
omega is kept in the world frame. Two schemes:

- :func:`kick_and_rotate_dlm` (used by velocity Verlet): the symmetric splitting of the free
  rigid body of Dullweber, Leimkuhler & McLachlan (1997, J. Chem. Phys. 107, 5840),
      R1(dt/2) R2(dt/2) R3(dt) R2(dt/2) R1(dt/2),
  where Rk(t) is the exact flow of the kinetic energy term L_k^2 / (2 I_k): a rotation of
  the body about its principal axis k by L_k t / I_k, with L (body frame) rotated back by the
  same angle. Symplectic, time-reversible, second order; keeps L (world) exactly and the
  energy to O(dt^2) without drift.
- :func:`rotate_quaternion_derivative` (used by symplectic Euler): the DPM thesis form
  (Samiei 2012, §2.3): Euler's equations  I w_b' = T_b - w_b x (I w_b)  and
  q' = 1/2 q (x) (0, w_b), both advanced by explicit Euler, q renormalised each step
  (first order, not symplectic; the thesis' explicit scheme).

Isotropic bodies (spheres, cubes, regular tetrahedra: I1 = I2 = I3) take the exact world
frame update w += dt T / I, q <- exp(w dt / 2) q in both integrators.

Every function here takes and returns scalars (a quaternion is q0, q1, q2, q3): the
integrators read a body's rows once and write them once, and no arrays are passed down,
which keeps these calls cheap inside the per-body loops.
"""

import math

from .config import inline_jit, jit


@jit
def rotate(q0, q1, q2, q3, vx, vy, vz):
    """R(q) v (body to world)."""
    tx = 2.0 * (q2 * vz - q3 * vy)
    ty = 2.0 * (q3 * vx - q1 * vz)
    tz = 2.0 * (q1 * vy - q2 * vx)
    return (vx + q0 * tx + (q2 * tz - q3 * ty),
            vy + q0 * ty + (q3 * tx - q1 * tz),
            vz + q0 * tz + (q1 * ty - q2 * tx))


@jit
def rotate_back(q0, q1, q2, q3, vx, vy, vz):
    """R(q)^T v (world to body)."""
    return rotate(q0, -q1, -q2, -q3, vx, vy, vz)


@jit
def normalised(q0, q1, q2, q3):
    n = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    return q0 * n, q1 * n, q2 * n, q3 * n


@jit
def _about_axis(q0, q1, q2, q3, k, angle):
    """q (x) (cos(a/2), sin(a/2) e_k): the body turned about its own axis k."""
    c = math.cos(0.5 * angle)
    s = math.sin(0.5 * angle)
    if k == 0:
        return q0 * c - q1 * s, q1 * c + q0 * s, q2 * c + q3 * s, q3 * c - q2 * s
    if k == 1:
        return q0 * c - q2 * s, q1 * c - q3 * s, q2 * c + q0 * s, q3 * c + q1 * s
    return q0 * c - q3 * s, q1 * c + q2 * s, q2 * c - q1 * s, q3 * c + q0 * s


@jit
def _free_flow(q0, q1, q2, q3, l0, l1, l2, k, ik, t):
    """Exact flow of L_k^2/(2 I_k) for time t (ik = 1/I_k): the body turns by
    phi = L_k t / I_k about its axis k, the body-frame angular momentum by -phi."""
    lk = l0 if k == 0 else (l1 if k == 1 else l2)
    phi = lk * ik * t
    q0, q1, q2, q3 = _about_axis(q0, q1, q2, q3, k, phi)
    c = math.cos(phi)
    s = math.sin(phi)
    if k == 0:
        return q0, q1, q2, q3, l0, c * l1 + s * l2, -s * l1 + c * l2
    if k == 1:
        return q0, q1, q2, q3, -s * l2 + c * l0, l1, c * l2 + s * l0
    return q0, q1, q2, q3, c * l0 + s * l1, -s * l0 + c * l1, l2


@jit
def kick_and_rotate_dlm(q0, q1, q2, q3, wx, wy, wz, tx, ty, tz, i0, i1, i2, h_kick, dt):
    """Kick L += h_kick T (world), then the DLM free rotation over dt.

    i0, i1, i2 are the inverse principal moments. Returns (q, omega world)."""
    a, b, c = rotate_back(q0, q1, q2, q3, wx, wy, wz)
    ux, uy, uz = rotate_back(q0, q1, q2, q3, tx, ty, tz)
    l0 = a / i0 + h_kick * ux
    l1 = b / i1 + h_kick * uy
    l2 = c / i2 + h_kick * uz
    h = 0.5 * dt
    q0, q1, q2, q3, l0, l1, l2 = _free_flow(q0, q1, q2, q3, l0, l1, l2, 0, i0, h)
    q0, q1, q2, q3, l0, l1, l2 = _free_flow(q0, q1, q2, q3, l0, l1, l2, 1, i1, h)
    q0, q1, q2, q3, l0, l1, l2 = _free_flow(q0, q1, q2, q3, l0, l1, l2, 2, i2, dt)
    q0, q1, q2, q3, l0, l1, l2 = _free_flow(q0, q1, q2, q3, l0, l1, l2, 1, i1, h)
    q0, q1, q2, q3, l0, l1, l2 = _free_flow(q0, q1, q2, q3, l0, l1, l2, 0, i0, h)
    q0, q1, q2, q3 = normalised(q0, q1, q2, q3)
    wx, wy, wz = rotate(q0, q1, q2, q3, l0 * i0, l1 * i1, l2 * i2)
    return q0, q1, q2, q3, wx, wy, wz


@jit
def kick(q0, q1, q2, q3, wx, wy, wz, tx, ty, tz, i0, i1, i2, h_kick):
    """omega after L += h_kick T at fixed orientation: omega + R I^-1 R^T h_kick T."""
    ux, uy, uz = rotate_back(q0, q1, q2, q3, tx, ty, tz)
    dx, dy, dz = rotate(q0, q1, q2, q3, h_kick * ux * i0, h_kick * uy * i1, h_kick * uz * i2)
    return wx + dx, wy + dy, wz + dz


@jit
def rotate_quaternion_derivative(q0, q1, q2, q3, wx, wy, wz, tx, ty, tz, i0, i1, i2, dt):
    """One explicit Euler step of Euler's equations and of q' = q (x) (0, w_b) / 2.

    Returns (q, omega world)."""
    a, b, c = rotate_back(q0, q1, q2, q3, wx, wy, wz)
    ux, uy, uz = rotate_back(q0, q1, q2, q3, tx, ty, tz)
    m0 = 1.0 / i0
    m1 = 1.0 / i1
    m2 = 1.0 / i2
    h = 0.5 * dt
    n0 = q0 + h * (-q1 * a - q2 * b - q3 * c)
    n1 = q1 + h * (q0 * a + q2 * c - q3 * b)
    n2 = q2 + h * (q0 * b + q3 * a - q1 * c)
    n3 = q3 + h * (q0 * c + q1 * b - q2 * a)
    n0, n1, n2, n3 = normalised(n0, n1, n2, n3)
    na = a + dt * (ux - (m2 - m1) * b * c) * i0
    nb = b + dt * (uy - (m0 - m2) * c * a) * i1
    nc = c + dt * (uz - (m1 - m0) * a * b) * i2
    wx, wy, wz = rotate(n0, n1, n2, n3, na, nb, nc)
    return n0, n1, n2, n3, wx, wy, wz


#: reciprocals of the Taylor series' divisors in rotate_isotropic
INV_6, INV_12, INV_20, INV_30 = 1.0 / 6.0, 1.0 / 12.0, 1.0 / 20.0, 1.0 / 30.0
INV_42, INV_56, INV_72 = 1.0 / 42.0, 1.0 / 56.0, 1.0 / 72.0


@jit
def rotate_isotropic(q0, q1, q2, q3, wx, wy, wz, dt):
    """q <- exp(omega dt / 2) (x) q for a world-frame omega, renormalised.

    Exact for constant omega over the step (rotation by |omega| dt about omega/|omega|).
    For a rotation angle below 0.1 rad per step cos and sin are replaced by their Taylor
    series to the h^8 term (relative error below 1e-16), which spares two transcendental
    calls per body and step.
    """
    w2 = wx * wx + wy * wy + wz * wz
    if w2 == 0.0:
        return q0, q1, q2, q3
    h2 = 0.25 * w2 * dt * dt  # (half angle)^2
    if h2 < 0.0025:  # half angle < 0.05 rad
        # (products with the reciprocals: the divisions took a quarter of the update)
        a0 = 1.0 - h2 * 0.5 * (1.0 - h2 * INV_12 * (1.0 - h2 * INV_30 * (1.0 - h2 * INV_56)))
        s = 0.5 * dt * (1.0 - h2 * INV_6 * (1.0 - h2 * INV_20 * (1.0 - h2 * INV_42
                                                            * (1.0 - h2 * INV_72))))
    else:
        w = math.sqrt(w2)
        half = 0.5 * w * dt
        s = math.sin(half) / w
        a0 = math.cos(half)
    a1 = wx * s
    a2 = wy * s
    a3 = wz * s
    return normalised(a0 * q0 - a1 * q1 - a2 * q2 - a3 * q3,
                      a0 * q1 + a1 * q0 + a2 * q3 - a3 * q2,
                      a0 * q2 - a1 * q3 + a2 * q0 + a3 * q1,
                      a0 * q3 + a1 * q2 - a2 * q1 + a3 * q0)


@inline_jit
def place_elements(b, b_pos, b_quat, b_estart, e_offset, e_pos):
    """x_e = X_b + R(q_b) offset_e for the elements of body b."""
    for e in range(b_estart[b], b_estart[b + 1]):
        ox, oy, oz = rotate(b_quat[b, 0], b_quat[b, 1], b_quat[b, 2], b_quat[b, 3],
                            e_offset[e, 0], e_offset[e, 1], e_offset[e, 2])
        e_pos[e, 0] = b_pos[b, 0] + ox
        e_pos[e, 1] = b_pos[b, 1] + oy
        e_pos[e, 2] = b_pos[b, 2] + oz
