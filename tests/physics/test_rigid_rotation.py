"""Rotation of non-spherical rigid bodies: torque-free motion against Euler's equations
solved by scipy, conservation of energy and angular momentum, a resting two-sphere body."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dpm
from dpm.shapes import BodyBatch

I_MOMENTS = np.array([1.0, 2.0, 3.0]) * 1e-9  # kg m2, asymmetric
MASS = 1e-3


class Spinner(dpm.Shape):
    """One sphere element at the centre with the asymmetric inertia I_MOMENTS (a stand-in
    for any asymmetric body: free rotation depends on the inertia only)."""

    name = "spinner"

    def build(self, count, density):
        return BodyBatch(np.full(count, MASS), np.tile(I_MOMENTS, (count, 1)),
                         np.ones(count, np.int64), np.zeros((count, 3)), np.full(count, 1e-3),
                         np.full(count, 1e-3))


class Dumbbell(dpm.Shape):
    """Two spheres of radius r at +-d along the body x axis (solid-sphere inertia plus the
    parallel-axis terms; only used for the resting test)."""

    name = "dumbbell"

    def build(self, count, density):
        r, d = 1e-3, 1.5e-3
        m1 = 4 / 3 * np.pi * r**3 * density
        i0 = 0.4 * m1 * r**2
        inertia = np.array([2 * i0, 2 * (i0 + m1 * d**2), 2 * (i0 + m1 * d**2)])
        offsets = np.tile([[-d, 0, 0], [d, 0, 0]], (count, 1))
        return BodyBatch(np.full(count, 2 * m1), np.tile(inertia, (count, 1)),
                         np.full(count, 2, np.int64), offsets, np.full(2 * count, r),
                         np.full(count, d + r))


def _free_rotation(integrator, dt, w0, t_end):
    sim = dpm.Simulation(dt=dt, integrator=integrator, dt_check="off")  # no contacts
    m = dpm.Material("m", density=1000, young=1e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin")
    sim.add_particles(Spinner(), material=m, positions=[[0, 0, 0]], angular_velocities=[w0])
    e0 = sim.kinetic_energy()
    l0 = sim.angular_momentum()
    n = round(t_end / dt)
    every = max(1, n // 2000)
    t, wb, energy, lerr = [], [], [], []
    for _ in range(n // every):
        sim.run(steps=every, progress=False)
        q = sim.bodies.orientation
        wb.append(dpm.measures.to_body(q, sim.bodies.angular_velocity)[0])
        t.append(sim.time)
        energy.append(sim.kinetic_energy() / e0 - 1)
        lerr.append(np.linalg.norm(sim.angular_momentum() - l0) / np.linalg.norm(l0))
    return (np.array(t), np.array(wb), np.array(energy), np.array(lerr),
            np.linalg.norm(sim.bodies.orientation[0]))


def _euler_reference(w0, t):
    i1, i2, i3 = I_MOMENTS

    def rhs(_, w):
        return [(i2 - i3) / i1 * w[1] * w[2], (i3 - i1) / i2 * w[2] * w[0],
                (i1 - i2) / i3 * w[0] * w[1]]

    return solve_ivp(rhs, (0, t[-1]), w0, t_eval=t, rtol=1e-12, atol=1e-14,
                     method="DOP853").y.T


def _flip_times(t, w_mid):
    s = np.sign(w_mid)
    k = np.nonzero(s[1:] != s[:-1])[0]
    return t[k] - w_mid[k] * (t[k + 1] - t[k]) / (w_mid[k + 1] - w_mid[k])


W0 = np.array([0.05, 10.0, 0.05])  # near the intermediate axis: it flips (Dzhanibekov)


def test_intermediate_axis_flip_period_matches_euler_equations():
    t, wb, energy, lerr, qn = _free_rotation("velocity_verlet", 1e-4, W0, 12.0)
    ref = _euler_reference(W0, t)
    flips, ref_flips = _flip_times(t, wb[:, 1]), _flip_times(t, ref[:, 1])
    assert len(ref_flips) >= 3 and len(flips) == len(ref_flips)
    period, ref_period = np.diff(flips).mean(), np.diff(ref_flips).mean()
    assert period == pytest.approx(ref_period, rel=2e-3)
    np.testing.assert_allclose(flips, ref_flips, atol=0.01 * ref_period)
    # the body-frame spin follows the reference between flips too
    assert np.max(np.abs(wb - ref)) < 0.05 * np.linalg.norm(W0)
    assert np.max(np.abs(lerr)) < 1e-9  # DLM: each sub-flow keeps L exactly (round-off)
    assert np.max(np.abs(energy)) < 1e-4
    assert abs(qn - 1) < 1e-14


@pytest.mark.parametrize("integrator, order", [("velocity_verlet", 2), ("symplectic_euler", 1)])
def test_energy_error_against_step_size(integrator, order):
    """Report (in the assertion data) and check the energy error's order in dt."""
    errs = []
    for dt in (4e-4, 2e-4):
        _, _, energy, lerr, _ = _free_rotation(integrator, dt, W0, 3.0)
        errs.append(np.max(np.abs(energy)))
    observed = np.log2(errs[0] / errs[1])
    assert observed == pytest.approx(order, abs=0.35), errs
    if integrator == "velocity_verlet":
        assert errs[1] < 1e-4


def test_dumbbell_rests_on_both_spheres():
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81))
    m = dpm.Material("m", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    floor = sim.add_boundary("plane", material=m)
    tilt = np.array([np.cos(0.05), 0, np.sin(0.05), 0])  # slightly tilted about y
    sim.add_particles(Dumbbell(), material=m, positions=[[0, 0, 1.2e-3]], orientations=[tilt])
    sim.run(until=0.08, progress=False)
    weight = sim.bodies.mass[0] * 9.81
    np.testing.assert_allclose(floor.force, [0, 0, -weight], atol=1e-3 * weight)
    assert int(sim.backend.diag[6]) == 2  # both elements touch the floor
    z = sim.elements.position[:, 2]
    np.testing.assert_allclose(z, z.mean(), atol=1e-7)  # level: the tilt has gone
    assert np.linalg.norm(sim.bodies.angular_velocity) < 1e-3
