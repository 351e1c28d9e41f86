"""Prescribed boundary motions (:mod:`dpm.motion`) against independent references.

* ``Motion.rates`` against five-point central differences of ``Motion.pose`` (error
  O(h^4), computed here), for every motion and for compositions;
* the velocity a boundary point gets from the frame rows, v_o + omega x (x - o), against the
  numerical derivative of that point's path x(t) = R(t) x0 + o(t);
* ``Compose`` pose against the composition written out here (R_b R_a, R_b o_a + o_b);
* ``Rotation``: its pivot is a fixed point and has zero velocity; the ramped angle is the
  integral of omega min(t / ramp, 1) (quadrature);
* ``Tumbling`` against Alkhaldi (2007), sec. 4.3.2: r_oc of eq. 4.1, A_lg of eq. 4.3 with
  (omega_b - omega) t -> psi - omega t, eq. 4.4 (case 1, free barrel), eq. 4.5 (case 2,
  fixed), the rates of eqs. 4.11 and 4.14, and psi of the triangular oscillation of eqs.
  4.6-4.7 (case 3). x_g = r_oc + A_lg^T x_l (eq. 4.8), so pose() returns R = A_lg^T.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import dpm
from dpm.motion import Compose, frames

# ----------------------------------------------------------------------------- helpers


def axial(w: np.ndarray) -> np.ndarray:
    """Axial vectors (n, 3) of (nearly) skew matrices (n, 3, 3)."""
    return 0.5 * np.stack([w[:, 2, 1] - w[:, 1, 2], w[:, 0, 2] - w[:, 2, 0],
                           w[:, 1, 0] - w[:, 0, 1]], axis=1)


def five_point(f, t: np.ndarray, h: float):
    """d f / dt by the five-point stencil (error O(h^4)); f returns an array (n, ...)."""
    return (-f(t + 2 * h) + 8 * f(t + h) - 8 * f(t - h) + f(t - 2 * h)) / (12 * h)


def numeric_rates(pose, t: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(do/dt, omega) from a pose function by five-point differences: skew(omega) =
    dR/dt R^T."""
    rdot = five_point(lambda s: pose(s)[0], t, h)
    odot = five_point(lambda s: pose(s)[1], t, h)
    r = pose(t)[0]
    return odot, axial(rdot @ np.transpose(r, (0, 2, 1)))


TUMBLING = dict(omega=3.0, alpha=0.3, beta=-0.2, u=0.05, e=0.02, eccentricity=0.01)

MOTIONS = {
    "translation": lambda: dpm.Translation(velocity=(0.1, -0.2, 0.3)),
    "rotation": lambda: dpm.Rotation(axis=(1, 2, 2), omega=2.5, center=(0.1, 0.2, -0.3)),
    "rotation_rpm_ramp": lambda: dpm.Rotation(axis=(0, 1, 0), rpm=30, center=(0, 0.1, 0),
                                              ramp=0.25),
    "oscillation": lambda: dpm.Oscillation(amplitude=(1e-3, 0, 2e-3), frequency=7.0,
                                           phase=0.4),
    "triangular": lambda: dpm.TriangularOscillation(amplitude=(0, 2e-3, 1e-3), period=0.3),
    "tumbling_free": lambda: dpm.Tumbling(barrel="free", **TUMBLING),
    "tumbling_fixed": lambda: dpm.Tumbling(barrel="fixed", **TUMBLING),
    "tumbling_oscillating": lambda: dpm.Tumbling(barrel="oscillating", oscillation_factor=0.7,
                                                 oscillation_period=0.4, **TUMBLING),
    "compose_rot_osc": lambda: Compose(
        dpm.Rotation(axis=(0, 0, 1), omega=4.0, center=(0.02, 0, 0)),
        dpm.Oscillation(amplitude=(0, 0, 1e-3), frequency=5.0)),
    "compose_tumbling_rot": lambda: dpm.Tumbling(barrel="free", **TUMBLING).then(
        dpm.Rotation(axis=(1, 0, 0), omega=-1.5, center=(0, 0.1, 0))),
}

#: times away from the kinks of ramps and triangle waves (the five-point stencil spans +-2h)
TIMES = np.array([0.013, 0.11, 0.37, 0.52, 0.91, 1.33])


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_rates_are_derivatives_of_pose(name):
    """rates() (closed form, or the default central differences) equals the five-point
    derivative of pose(): do/dt to 1e-7 of the motion's speed scale, omega likewise."""
    m = MOTIONS[name]()
    h = 1e-4 * min(m.time_scale, 1.0)
    v_ref, w_ref = numeric_rates(m.pose, TIMES, h)
    v, w = m.rates(TIMES)
    scale_v = max(np.abs(v_ref).max(), 1e-12)
    scale_w = max(np.abs(w_ref).max(), 1e-12)
    np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-7 * scale_v)
    np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-7 * scale_w)
    # pose is a proper rotation
    r, _ = m.pose(TIMES)
    np.testing.assert_allclose(r @ np.transpose(r, (0, 2, 1)), np.broadcast_to(np.eye(3), r.shape),
                               atol=1e-13)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-13)


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_boundary_point_velocity(name):
    """A point fixed to the boundary, x(t) = R x0 + o, moves with the frame-row velocity
    v_o + omega x (x - o) that the contact kernels use."""
    m = MOTIONS[name]()
    h = 1e-4 * min(m.time_scale, 1.0)
    rng = np.random.default_rng(3)
    fr = frames(m, TIMES)
    for x0 in rng.normal(scale=0.05, size=(4, 3)):
        def path(s, x0=x0):
            r, o = m.pose(s)
            return np.einsum("nij,j->ni", r, x0) + o
        v_ref = five_point(path, TIMES, h)
        x = path(TIMES)
        v = fr[:, 12:15] + np.cross(fr[:, 15:18], x - fr[:, 0:3])
        np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-7 * max(np.abs(v_ref).max(), 1e-9))
    # frame rows: R row-major, x_world = R x_local + o
    r, o = m.pose(TIMES)
    np.testing.assert_array_equal(fr[:, 3:12], r.reshape(len(TIMES), 9))
    np.testing.assert_array_equal(fr[:, 0:3], o)


def test_frames_without_motion_is_identity():
    fr = frames(None, np.array([0.0, 1.0]))
    np.testing.assert_array_equal(fr[:, 3:12], np.tile(np.eye(3).ravel(), (2, 1)))
    assert not fr[:, [0, 1, 2, 12, 13, 14, 15, 16, 17]].any()


def test_compose_pose_and_rates():
    """Compose(a, b, c) pose = c applied to b applied to a, written out here; its rates are
    the derivative of that composed pose (not of Compose.pose)."""
    a = dpm.Rotation(axis=(0, 0, 1), omega=4.0, center=(0.02, 0, 0), ramp=0.05)
    b = dpm.Oscillation(amplitude=(0, 1e-3, 1e-3), frequency=5.0)
    c = dpm.Tumbling(barrel="fixed", **TUMBLING)

    def composed(t):
        ra, oa = a.pose(t)
        rb, ob = b.pose(t)
        rc, oc = c.pose(t)
        r = np.einsum("nij,njk->nik", rc, np.einsum("nij,njk->nik", rb, ra))
        o = np.einsum("nij,nj->ni", rc, np.einsum("nij,nj->ni", rb, oa) + ob) + oc
        return r, o

    m = Compose(a, b, c)
    r, o = m.pose(TIMES)
    r_ref, o_ref = composed(TIMES)
    np.testing.assert_allclose(r, r_ref, atol=1e-14)
    np.testing.assert_allclose(o, o_ref, atol=1e-15)
    v_ref, w_ref = numeric_rates(composed, TIMES, 1e-5)
    v, w = m.rates(TIMES)
    np.testing.assert_allclose(v, v_ref, rtol=0, atol=1e-7 * np.abs(v_ref).max())
    np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-7 * np.abs(w_ref).max())
    # the first pivot is the composition's torque point
    np.testing.assert_array_equal(m.pivot, a.pivot)


@pytest.mark.parametrize("ramp", [0.0, 0.4])
def test_rotation_pivot_is_fixed_and_angle_integrates_speed(ramp):
    c = np.array([0.3, -0.1, 0.2])
    axis = np.array([1.0, -2.0, 0.5])
    m = dpm.Rotation(axis=axis, omega=3.0, center=c, ramp=ramp)
    t = np.linspace(0.0, 1.0, 41)
    r, o = m.pose(t)
    np.testing.assert_allclose(np.einsum("nij,j->ni", r, c) + o, np.tile(c, (len(t), 1)),
                               atol=1e-15)
    fr = frames(m, t)
    v_pivot = fr[:, 12:15] + np.cross(fr[:, 15:18], c - fr[:, 0:3])
    np.testing.assert_allclose(v_pivot, 0.0, atol=1e-15)
    # angle about the axis = integral of omega min(t / ramp, 1)
    n = axis / np.linalg.norm(axis)
    for k, tk in enumerate(t):
        speed = (lambda s: 3.0 * min(s / ramp, 1.0)) if ramp else (lambda s: 3.0)
        ang = quad(speed, 0.0, tk, points=[ramp] if 0 < ramp < tk else None)[0]
        # rotation of a vector normal to the axis by ang about n (Rodrigues, written out)
        p = np.cross(n, [0.0, 0.0, 1.0])
        p /= np.linalg.norm(p)
        expect = p * math.cos(ang) + np.cross(n, p) * math.sin(ang)
        np.testing.assert_allclose(r[k] @ p, expect, atol=1e-13)
    np.testing.assert_allclose(fr[:, 15:18], 3.0 * np.minimum(t / ramp, 1.0)[:, None] * n
                               if ramp else np.tile(3.0 * n, (len(t), 1)), atol=1e-15)


def test_rotation_rpm():
    m = dpm.Rotation(axis=(0, 0, 1), rpm=60)
    _, w = m.rates(np.array([1.0]))
    np.testing.assert_allclose(w[0], [0, 0, 2 * math.pi], rtol=1e-15)


def test_triangular_oscillation_is_piecewise_linear():
    """o = A tri(t / T): 0 -> A in T/2 at constant speed 2 A / T, back in the next T/2."""
    amp = np.array([0.0, 2e-3, -1e-3])
    period = 0.3
    m = dpm.TriangularOscillation(amplitude=amp, period=period)
    t = np.array([0.0, 0.05, 0.15, 0.2, 0.3, 0.375, 0.45 + 0.15])
    frac = np.mod(t, period) / period
    tri = np.where(frac <= 0.5, 2 * frac, 2 - 2 * frac)
    np.testing.assert_allclose(m.pose(t)[1], tri[:, None] * amp, atol=1e-15)
    v, _ = m.rates(np.array([0.05, 0.2]))
    np.testing.assert_allclose(v, [2 * amp / period, -2 * amp / period], rtol=1e-12)


def test_oscillation_closed_form():
    m = dpm.Oscillation(amplitude=(0, 0, 1e-3), frequency=25.0, phase=0.3)
    t = np.array([0.0, 0.01, 0.023])
    w = 2 * math.pi * 25.0
    np.testing.assert_allclose(m.pose(t)[1][:, 2], 1e-3 * np.sin(w * t + 0.3), atol=1e-18)
    np.testing.assert_allclose(m.rates(t)[0][:, 2], 1e-3 * w * np.cos(w * t + 0.3), rtol=1e-12)


# ----------------------------------------------------------------------- tumbling (thesis)


def r_oc(t, omega, alpha, beta, u, e, eccentricity):
    """Eq. 4.1."""
    c, s = np.cos(omega * t), np.sin(omega * t)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    eps = eccentricity
    return np.stack([u * c - u * c * cb + e * s - eps * s + u * s * sa * sb - e * s * ca,
                     u * s - u * s * cb - e * c + eps * c - u * c * sa * sb + e * c * ca,
                     np.full_like(t, u * sb * ca + e * sa)], axis=1)


def a_lg_general(t, psi, omega, alpha, beta):
    """Eq. 4.3 with (omega_b - omega) t written psi - omega t."""
    c, s = np.cos(omega * t), np.sin(omega * t)
    g = psi - omega * t
    cg, sg = np.cos(g), np.sin(g)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    a = np.empty((len(t), 3, 3))
    a[:, 0, 0] = cg * c * cb - cg * s * sa * sb - sg * s * ca
    a[:, 0, 1] = cg * s * cb + cg * c * sa * sb + sg * c * ca
    a[:, 0, 2] = -cg * ca * sb + sg * sa
    a[:, 1, 0] = -sg * c * cb + sg * s * sa * sb - cg * s * ca
    a[:, 1, 1] = -sg * s * cb - sg * c * sa * sb + cg * c * ca
    a[:, 1, 2] = sg * ca * sb + cg * sa
    a[:, 2, 0] = c * sb + s * sa * cb
    a[:, 2, 1] = s * sb - c * sa * cb
    a[:, 2, 2] = ca * cb
    return a


def a_lg_free(t, omega, alpha, beta):
    """Eq. 4.4 (case 1, omega_b = omega)."""
    c, s = np.cos(omega * t), np.sin(omega * t)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    one = np.ones_like(t)
    return np.stack([
        np.stack([c * cb - s * sa * sb, s * cb + c * sa * sb, -ca * sb * one], axis=1),
        np.stack([-s * ca, c * ca, sa * one], axis=1),
        np.stack([c * sb + s * sa * cb, s * sb - c * sa * cb, ca * cb * one], axis=1)], axis=1)


def a_lg_fixed(t, omega, alpha, beta):
    """Eq. 4.5 (case 2, omega_b = 0)."""
    c, s = np.cos(omega * t), np.sin(omega * t)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    one = np.ones_like(t)
    return np.stack([
        np.stack([c**2 * cb - s * c * sa * sb + s**2 * ca, s * c * cb + c**2 * sa * sb - s * c * ca,
                  -c * ca * sb - s * sa], axis=1),
        np.stack([s * c * cb - s**2 * sa * sb - s * c * ca, s**2 * cb + s * c * sa * sb + c**2 * ca,
                  -s * ca * sb + c * sa], axis=1),
        np.stack([c * sb + s * sa * cb, s * sb - c * sa * cb, ca * cb * one], axis=1)], axis=1)


def test_tumbling_free_is_eq_4_4():
    p = TUMBLING
    t = np.linspace(0.0, 2.0, 23)
    r, o = dpm.Tumbling(barrel="free", **p).pose(t)
    a = a_lg_free(t, p["omega"], p["alpha"], p["beta"])
    np.testing.assert_allclose(r, np.transpose(a, (0, 2, 1)), atol=1e-15)
    np.testing.assert_allclose(a, a_lg_general(t, p["omega"] * t, p["omega"], p["alpha"],
                                               p["beta"]), atol=1e-15)
    np.testing.assert_allclose(o, r_oc(t, **p), atol=1e-16)


def test_tumbling_fixed_is_eq_4_5():
    p = TUMBLING
    t = np.linspace(0.0, 2.0, 23)
    r, o = dpm.Tumbling(barrel="fixed", **p).pose(t)
    a = a_lg_fixed(t, p["omega"], p["alpha"], p["beta"])
    np.testing.assert_allclose(r, np.transpose(a, (0, 2, 1)), atol=1e-15)
    np.testing.assert_allclose(o, r_oc(t, **p), atol=1e-16)


def test_tumbling_oscillating_is_eqs_4_3_4_6_4_7():
    """Case 3: psi rises at omega_b = K omega to psi_max = omega_b t_p / 2 (eq. 4.6) and
    falls back at the same rate (eq. 4.7); A_lg is eq. 4.3 with that psi."""
    p = TUMBLING
    k, tp = 0.7, 0.4
    m = dpm.Tumbling(barrel="oscillating", oscillation_factor=k, oscillation_period=tp, **p)
    t = np.linspace(0.0, 1.3, 57)
    wb = k * p["omega"]
    tau = np.mod(t, tp)
    psi = np.where(tau <= tp / 2, wb * tau, wb * (tp - tau))
    np.testing.assert_allclose(m.psi(t), psi, atol=1e-14)
    r, o = m.pose(t)
    a = a_lg_general(t, psi, p["omega"], p["alpha"], p["beta"])
    np.testing.assert_allclose(r, np.transpose(a, (0, 2, 1)), atol=1e-14)
    np.testing.assert_allclose(o, r_oc(t, **p), atol=1e-16)


def test_tumbling_free_rates_are_eqs_4_11_4_14():
    """The thesis' closed-form rates: dr_oc/dt (eq. 4.11) and dA_lg/dt (eq. 4.14);
    omega in the world frame from skew(omega) = dR/dt R^T with R = A_lg^T."""
    p = TUMBLING
    w, al, be, u, e, eps = (p[k] for k in ("omega", "alpha", "beta", "u", "e", "eccentricity"))
    t = np.array([0.1, 0.7, 1.9])
    c, s = np.cos(w * t), np.sin(w * t)
    ca, sa, cb, sb = math.cos(al), math.sin(al), math.cos(be), math.sin(be)
    rdot = w * np.stack([-u * s + u * s * cb + e * c - eps * c + u * c * sa * sb - e * c * ca,
                         u * c - u * c * cb + e * s - eps * s + u * s * sa * sb - e * s * ca,
                         np.zeros_like(t)], axis=1)
    zero = np.zeros_like(t)
    adot = w * np.stack([
        np.stack([-s * cb - c * sa * sb, c * cb - s * sa * sb, zero], axis=1),
        np.stack([-c * ca, -s * ca, zero], axis=1),
        np.stack([-s * sb + c * sa * cb, c * sb + s * sa * cb, zero], axis=1)], axis=1)
    a = a_lg_free(t, w, al, be)
    omega_ref = axial(np.transpose(adot, (0, 2, 1)) @ a)
    v, om = dpm.Tumbling(barrel="free", **p).rates(t)
    np.testing.assert_allclose(v, rdot, rtol=0, atol=1e-8 * np.abs(rdot).max())
    np.testing.assert_allclose(om, omega_ref, rtol=0, atol=1e-8 * w)


def test_motion_parameters_are_checked():
    with pytest.raises(dpm.ParameterError, match="rpm or omega"):
        dpm.Rotation(axis=(0, 0, 1))
    with pytest.raises(dpm.ParameterError, match="axis"):
        dpm.Rotation(axis=(0, 0, 0), omega=1.0)
    with pytest.raises(dpm.ParameterError, match="barrel"):
        dpm.Tumbling(omega=1.0, barrel="spinning")
    with pytest.raises(dpm.ParameterError):
        Compose()
