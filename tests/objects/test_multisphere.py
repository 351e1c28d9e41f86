"""Bodies from a list of spheres (LIGGGHTS' ``particletemplate/multisphere``).

References: a single sphere (V = 4/3 pi r^3, I = 2/5 m r^2); two and three disjoint
spheres (volumes add, inertia by the parallel-axis theorem); overlapping collinear spheres
against 1-D integrals of the union's circular sections (scipy quad); a non-collinear
overlapping triple against a Monte-Carlo estimate.
"""

import numpy as np
import pytest
from scipy.integrate import quad

import dpm
from dpm.errors import ParameterError
from dpm.shapes.metrics import _in_union
from dpm.shapes.multisphere import Multisphere


def spheres_reference(c, r):
    """Volume, centre and inertia tensor (per density) of disjoint spheres."""
    v = 4 / 3 * np.pi * r**3
    com = (v[:, None] * c).sum(0) / v.sum()
    inertia = np.zeros((3, 3))
    for ci, vi, ri in zip(c, v, r, strict=True):
        d = ci - com
        inertia += 0.4 * vi * ri**2 * np.eye(3) + vi * (d @ d * np.eye(3) - np.outer(d, d))
    return v.sum(), com, inertia


@pytest.mark.parametrize("c, r", [
    ([[0.1, -0.2, 0.3]], [2e-3]),
    ([[0, 0, 0], [3e-3, 1e-3, 0]], [1e-3, 0.5e-3]),
    ([[0, 0, 0], [4e-3, 0, 0], [1e-3, 3e-3, 2e-3]], [1e-3, 1.5e-3, 0.8e-3]),
])
def test_disjoint_spheres_are_exact(c, r):
    c, r = np.array(c, float), np.array(r, float)
    mp = Multisphere(centres=c, radii=r).mass_properties()
    vol, com, inertia = spheres_reference(c, r)
    assert mp.volume == pytest.approx(vol, rel=1e-12)
    np.testing.assert_allclose(mp.centre, com, atol=1e-12 * np.abs(c).max() + 1e-15)
    np.testing.assert_allclose(mp.tensor, inertia, atol=1e-10 * np.abs(inertia).max())


def test_overlapping_collinear_union_against_sections():
    z = np.array([0.0, 1.2e-3, 2.0e-3, 3.5e-3])
    r = np.array([1e-3, 0.8e-3, 1.1e-3, 0.7e-3])
    c = np.column_stack([np.zeros(4), np.zeros(4), z])

    def rho2(s):
        return max(0.0, *(r**2 - (s - z) ** 2))

    lo, hi = (z - r).min(), (z + r).max()
    pts = sorted({*(z - r), *(z + r), *z})
    vol = quad(lambda s: np.pi * rho2(s), lo, hi, points=pts, epsabs=0, epsrel=1e-13,
               limit=400)[0]
    zc = quad(lambda s: np.pi * rho2(s) * s, lo, hi, points=pts, epsabs=0, epsrel=1e-13,
              limit=400)[0] / vol
    i_axis = quad(lambda s: np.pi / 2 * rho2(s) ** 2, lo, hi, points=pts, epsabs=0,
                  epsrel=1e-13, limit=400)[0]
    i_perp = quad(lambda s: np.pi / 4 * rho2(s) ** 2 + np.pi * rho2(s) * (s - zc) ** 2,
                  lo, hi, points=pts, epsabs=0, epsrel=1e-13, limit=400)[0]
    mp = Multisphere(centres=c, radii=r).mass_properties()
    assert mp.volume == pytest.approx(vol, rel=1e-9)
    assert mp.centre[2] == pytest.approx(zc, rel=1e-9)
    np.testing.assert_allclose(np.diag(mp.tensor), [i_perp, i_perp, i_axis], rtol=1e-8)
    # the body built from it
    batch = Multisphere(centres=c, radii=r).build(2, 2500.0)
    np.testing.assert_allclose(batch.mass, 2500 * vol, rtol=1e-9)
    np.testing.assert_allclose(np.sort(batch.inertia[0]),
                               np.sort(2500 * np.array([i_perp, i_perp, i_axis])), rtol=1e-8)
    np.testing.assert_allclose(np.sort(batch.element_radius[:4]), np.sort(r))


def test_overlapping_triple_against_monte_carlo():
    c = np.array([[0, 0, 0], [0.8, 0, 0], [0.3, 0.7, 0.2]])
    r = np.array([0.6, 0.5, 0.45])
    mp = Multisphere(centres=c, radii=r).mass_properties()
    rng = np.random.default_rng(1)
    lo, hi = (c - r[:, None]).min(0), (c + r[:, None]).max(0)
    p = lo + rng.random((1_000_000, 3)) * (hi - lo)
    inside = _in_union(p, c, r)
    frac = inside.mean()
    vol = frac * np.prod(hi - lo)
    assert mp.volume == pytest.approx(vol, rel=4 * np.sqrt((1 - frac) / frac / len(p)))
    np.testing.assert_allclose(mp.centre, p[inside].mean(0), atol=3e-3)


def test_a_sphere_inside_another_adds_nothing_and_bad_input_is_named():
    mp = Multisphere(centres=[[0, 0, 0], [1e-4, 0, 0], [0, 0, 0]],
                     radii=[1e-3, 5e-4, 1e-3]).mass_properties()
    assert mp.volume == pytest.approx(4 / 3 * np.pi * 1e-9, rel=1e-12)
    with pytest.raises(ParameterError, match="radii has 1 values for 2 centres"):
        Multisphere(centres=[[0, 0, 0], [1, 0, 0]], radii=[1.0])
    with pytest.raises(ParameterError, match="must be a list of 3-vectors"):
        Multisphere(centres=[[0, 0]], radii=[1.0])
    with pytest.raises(ParameterError, match="radii > 0"):
        Multisphere(centres=[[0, 0, 0]], radii=[-1.0])


def test_add_particles_by_name():
    sim = dpm.Simulation(dt=1e-5)
    g = dpm.Material("g", density=2500, young=1e7, poisson=0.3)
    sim.add_particles("multisphere", g, positions=[[0, 0, 0], [0.01, 0, 0]],
                      centres=[[0, 0, 0], [2e-3, 0, 0]], radii=[1e-3, 1e-3])
    assert len(sim.bodies) == 2 and len(sim.elements) == 4
    v = 2 * 4 / 3 * np.pi * 1e-9
    np.testing.assert_allclose(sim.bodies.mass, 2500 * v, rtol=1e-12)
