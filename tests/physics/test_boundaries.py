"""Boundaries (plane, box, wall, tube, bend, mesh, sieve) against independent references.

* A sphere resting on each kind carries its weight, at the rest height that the Hertz law
  and the kind's geometry give (closed form, or brentq for a sphere sitting in a sieve hole
  on its 4 or 16 rim contacts).
* A sphere rolling over a flat triangle mesh (pinwheel cells: fan vertices of valence 4
  and 8) has the force history of the same run on the analytic plane, step by step.
* Rotating drum: a sphere at rest relative to the wall moves with omega x r; the torque that
  a body stuck on the wall exerts about the axis is (x - A) x m g (its angular momentum is
  constant) and the drive power is m g v_z.
* A ball rolls along tube -> bend -> tube without leaving the pipe; pipe pieces joined end
  to end give the force history of one unsplit piece.
* Screening: small spheres fall through a vibrating sieve, large ones stay (exact plate;
  Alkhaldi 2007 clearance models, eqs. 4.20/4.21, with per-particle predictions).
* Geometry: triangle closest point against trimesh; slab / surface-of-revolution / torus
  distances against a brute-force minimum over ~1e5 sampled surface points; the sieve
  clearance test against eqs. 4.22-4.25 written out; the element-boundary candidate list
  against the plain double loop, also for a mesh on its search grid in a moved frame.

All scenes use one contact law and carry far-away "sentinel" boundaries of every kind, so
that they share one generated step module (a step module is compiled per set of boundary
kinds, ~30-90 s each on a cold cache); the sentinels never come within reach of a particle.
For the same reason the sphere scenes use the two-pass force sum of the clustered ones; the
fused pass of sphere scenes is checked against it at every boundary kind by a slow test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from scipy.optimize import brentq

import dpm
from dpm.boundaries.mesh import smallest_altitudes, triangle_duals
from dpm.kernels.boundary_geometry import AXI, SIEVE, SLAB, TORUS, TRIANGLE, closest_any
from dpm.kernels.boundary_geometry import triangle_distance_within as bg_triangle_distance_within
from dpm.kernels.boundary_search import brute_force_boundary_pairs
from dpm.kernels.config import jit
from dpm.kernels.neighbours import SLOT_SLACK

G = 9.81
GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
STEEL = dict(density=7800.0, young=2e7, poisson=0.3)
R_BALL = 2e-3
FAR = 10.0


# ------------------------------------------------------------------------------ helpers


def sphere_mass(r: float, density: float = GLASS["density"]) -> float:
    return 4.0 / 3.0 * math.pi * r**3 * density


def estar() -> float:
    """Effective Young modulus glass-steel (Johnson 1985, eq. 4.22)."""
    return 1.0 / ((1 - GLASS["poisson"] ** 2) / GLASS["young"]
                  + (1 - STEEL["poisson"] ** 2) / STEEL["young"])


def hertz_force(delta: float, r: float) -> float:
    """Hertz force of a sphere of radius r on a wall (R* = r): 4/3 E* sqrt(r) delta^1.5."""
    return 4.0 / 3.0 * estar() * math.sqrt(r) * max(delta, 0.0) ** 1.5


def static_overlap(r: float) -> float:
    """Overlap at which the Hertz force carries m g."""
    return (3 * sphere_mass(r) * G / (4 * estar() * math.sqrt(r))) ** (2 / 3)


def sentinels(sim: dpm.Simulation, w: dpm.Material) -> None:
    """One boundary of every kind, 10 m away (see the module docstring)."""
    sim.add_boundary("plane", material=w, point=(0, 0, -FAR), normal=(0, 0, 1))
    sim.add_boundary("wall", material=w, center=(FAR, 0, 0), half_extents=(0.01, 0.01))
    sim.add_boundary("tube", material=w, start=(FAR, FAR, 0), axis=(0, 0, 1), length=0.01,
                     radius=0.01)
    sim.add_boundary("bend", material=w, center=(-FAR, 0, 0), bend_radius=0.05,
                     pipe_radius=0.01, angle=1.0)
    sim.add_boundary("mesh", material=w, vertices=[(0, FAR, 0), (0.01, FAR, 0),
                                                   (0, FAR + 0.01, 0)], faces=[(0, 1, 2)])
    sim.add_boundary("sieve", material=w, center=(0, -FAR, 0), half_extents=(0.01, 0.01),
                     hole=2e-3, bar=1e-3, clearance_model="fixed")


def test_many_kind_scenes_call_closest_from_their_searches():
    """A scene of few boundary kinds inlines its ``closest`` everywhere; past
    ``INLINE_SEARCH_KINDS`` the list searches and checks call one compiled
    ``closest_call`` (an inlined copy per call site made a six-kind module compile ~3x
    longer: each copy types all six kinds' geometry functions anew) while the contact
    loop still inlines it. The same results either way: the sentinel scenes of this module
    have every kind."""
    from dpm.boundaries.primitives import BUILTIN_CODES
    from dpm.kernels.boundary_geometry import PLANE

    laws = [("dpm.kernels.law_hertz_mindlin", "hertz_mindlin")]
    vv = "dpm.kernels.integrate_velocity_verlet"
    few = dpm.plan.render(laws, vv, kinds=[PLANE, TRIANGLE][:dpm.plan.INLINE_SEARCH_KINDS])
    many = dpm.plan.render(laws, vv, kinds=sorted(BUILTIN_CODES))
    assert "\nclosest_call = closest\n" in few and "def closest_call(" not in few
    assert "@jit\ndef closest_call(" in many and "\nclosest_call = closest\n" not in many
    for src in (few, many):
        assert "@inline_jit\ndef closest(" in src
        assert "closest_call(kind[w], par[w]" in src  # the search's and the check's calls
        assert "= closest(kind, row20(w_par, w)" in src  # the contact loop's


def scene(gravity=(0, 0, -G), dt=2e-6, friction=0.5, restitution=0.3, fused=False, **law):
    """(sim, particle material, wall material) with Hertz-Mindlin for both pairs; the
    two-pass force sum unless ``fused`` (see the module docstring)."""
    a = dpm.Material("glass", **GLASS)
    w = dpm.Material("steel", **STEEL)
    sim = dpm.Simulation(dt=dt, gravity=gravity, dt_check="warn")
    sim.backend.force_pass = "auto" if fused else "two_pass"
    sim.contact(a, a, model="hertz_mindlin", restitution=restitution, friction=friction, **law)
    sim.contact(a, w, model="hertz_mindlin", restitution=restitution, friction=friction, **law)
    return sim, a, w


def check_time_step(sim: dpm.Simulation) -> None:
    rep = sim.time_step_report()
    assert rep.steps_per_contact > 50 and sim.dt < 0.1 * rep.rayleigh, rep


# ------------------------------------------------------------------------ resting sphere

R_PIPE = 10e-3
RESTING = {
    # name: (kind, params, start position, rest position as a function of the overlap d)
    "plane": ("plane", {}, (1e-3, 0, R_BALL), lambda d: (1e-3, 0, R_BALL - d)),
    "box": ("box", dict(lower=(-0.02, -0.02, 0), upper=(0.02, 0.02, 0.05), open=("+z",)),
            (1e-3, 0, R_BALL), lambda d: (1e-3, 0, R_BALL - d)),
    "wall": ("wall", dict(center=(0, 0, 0), normal=(0, 0, 1), u=(1, 1, 0),
                          half_extents=(0.01, 0.02), thickness=2e-3),
             (1e-3, 2e-3, 1e-3 + R_BALL), lambda d: (1e-3, 2e-3, 1e-3 + R_BALL - d)),
    "tube_inside": ("tube", dict(start=(0, 0, 0), axis=(1, 0, 0), length=0.05,
                                 radius=R_PIPE),
                    (0.02, 0, -R_PIPE + R_BALL), lambda d: (0.02, 0, -R_PIPE + R_BALL - d)),
    "tube_outside": ("tube", dict(start=(0, 0, 0), axis=(1, 0, 0), length=0.05,
                                  radius=R_PIPE, thickness=1e-3),
                     (0.02, 0, R_PIPE + 0.5e-3 + R_BALL),
                     lambda d: (0.02, 0, R_PIPE + 0.5e-3 + R_BALL - d)),
    "cone_inside": ("tube", dict(start=(0, 0, -0.01), axis=(0, 0, 1), length=0.03,
                                 radius_start=0.0, radius_end=0.03),
                    None, None),
    "bend_inside": ("bend", dict(center=(0, 0, 0), axis=(0, 0, 1), bend_radius=0.05,
                                 pipe_radius=R_PIPE, angle=1.0),
                    (0.05 * math.cos(0.4), 0.05 * math.sin(0.4), -R_PIPE + R_BALL),
                    lambda d: (0.05 * math.cos(0.4), 0.05 * math.sin(0.4),
                               -R_PIPE + R_BALL - d)),
    "mesh": ("mesh", dict(vertices=[(-0.02, -0.02, 0), (0.02, -0.02, 0), (0.02, 0.02, 0),
                                    (-0.02, 0.02, 0)], faces=[(0, 1, 2), (0, 2, 3)]),
             (3e-3, 1e-3, R_BALL), lambda d: (3e-3, 1e-3, R_BALL - d)),
    "sieve_exact_bar": ("sieve", dict(center=(0, 0, 0), half_extents=(0.015, 0.015),
                                      hole=4e-3, bar=2e-3, thickness=1e-3),
                        (3e-3, 0.5e-3, 0.5e-3 + R_BALL),
                        lambda d: (3e-3, 0.5e-3, 0.5e-3 + R_BALL - d)),
    "sieve_radius_bar": ("sieve", dict(center=(0, 0, 0), half_extents=(0.015, 0.015),
                                       hole=4e-3, bar=2e-3, clearance_model="radius",
                                       zeta=0.5),
                         (3e-3, 0.5e-3, R_BALL), lambda d: (3e-3, 0.5e-3, R_BALL - d)),
    "sieve_fixed_over_hole": ("sieve", dict(center=(0, 0, 0), half_extents=(0.015, 0.015),
                                            hole=3e-3, bar=2e-3, clearance_model="fixed",
                                            zeta=0.5),
                              (0, 0, R_BALL), lambda d: (0, 0, R_BALL - d)),
}


@pytest.mark.parametrize("case", [c for c in RESTING if RESTING[c][2] is not None])
def test_resting_sphere_carries_its_weight(case):
    """After settling, the boundary carries exactly m g and the sphere rests where the wall
    surface lies r - d_static from its centre (d_static the Hertz overlap under m g; walls
    use R* = r)."""
    kind, params, start, rest = RESTING[case]
    sim, a, w = scene()
    bd = sim.add_boundary(kind, material=w, **params)
    sentinels(sim, w)
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[start])
    check_time_step(sim)
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    np.testing.assert_allclose(sim.bodies.position[0], rest(static_overlap(R_BALL)), rtol=0,
                               atol=1e-8 * static_overlap(R_BALL))
    assert np.abs(sim.bodies.velocity[0]).max() < 1e-9


def test_resting_sphere_in_a_cone():
    """A sphere in an upright cone (half angle 45 degrees) rests on the ring where its centre
    lies r - d from the mantle: z_c = sqrt(2) (r - d) - 0.01. The ring is one contact of
    Hertz force N(d) whose normals, averaged round the ring, give cos 45 deg along the axis
    (axi_distance's ring quadrature): N cos(45) = m g fixes d."""
    kind, params, _, _ = RESTING["cone_inside"]
    sim, a, w = scene()
    bd = sim.add_boundary(kind, material=w, **params)
    sentinels(sim, w)
    z0 = math.sqrt(2) * R_BALL - 0.01
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[(0, 0, z0)])
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    d = brentq(lambda x: hertz_force(x, R_BALL) - mg * math.sqrt(2), 0, R_BALL, xtol=1e-18)
    np.testing.assert_allclose(sim.bodies.position[0], (0, 0, math.sqrt(2) * (R_BALL - d) - 0.01),
                               rtol=0, atol=1e-8 * d)


@pytest.mark.parametrize("shape, contacts, rho", [
    ("square", 4, 1.5e-3),                          # the 4 side midpoints (rim vertices)
    ("round", 16, 1.5e-3 * math.cos(math.pi / 16)),  # the midpoints of the 16 rim edges
])
def test_sphere_resting_in_a_sieve_hole(shape, contacts, rho):
    """A sphere larger than the hole sits in it on the rim: ``contacts`` equal contacts at
    horizontal distance rho from its axis, each carrying m g / (contacts * z / s), s the
    distance centre-rim. The rest height z follows from the Hertz law (brentq); every rim
    contact is counted once (mesh edge rules). Frictionless: with friction the tangential
    springs keep part of the load after settling (statically indeterminate)."""
    sim, a, w = scene(friction=0.0)
    bd = sim.add_boundary("sieve", material=w, center=(0, 0, 0), half_extents=(0.015, 0.015),
                          hole=3e-3, bar=2e-3, shape=shape)
    sentinels(sim, w)
    sim.add_particles("sphere", material=a, radius=R_BALL,
                      positions=[(0, 0, math.sqrt(R_BALL**2 - rho**2))])
    sim.run(until=0.04, progress=False)
    mg = sphere_mass(R_BALL) * G

    def residual(z):
        s = math.hypot(z, rho)
        return contacts * hertz_force(R_BALL - s, R_BALL) * z / s - mg

    z = brentq(residual, 0.5 * math.sqrt(R_BALL**2 - rho**2), math.sqrt(R_BALL**2 - rho**2),
               xtol=1e-18)
    np.testing.assert_allclose(bd.force, [0, 0, -mg], rtol=0, atol=1e-9 * mg)
    np.testing.assert_allclose(sim.bodies.position[0], [0, 0, z], rtol=0, atol=1e-12)


# ------------------------------------------------------------------ mesh against plane


def pinwheel_floor(n: int, c: float) -> tuple[np.ndarray, np.ndarray]:
    """Flat floor z = 0 over [-n c, n c]^2: square cells of side c, each split into 4
    triangles around a centre vertex (cell corners are fan vertices of 8 triangles, centres
    of 4)."""
    xs = np.arange(-n, n + 1) * c
    verts = [(x, y, 0.0) for x in xs for y in xs]

    def idx(i, j):
        return i * (2 * n + 1) + j

    faces = []
    for i in range(2 * n):
        for j in range(2 * n):
            k = len(verts)
            verts.append((0.5 * (xs[i] + xs[i + 1]), 0.5 * (xs[j] + xs[j + 1]), 0.0))
            a, b, cc, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            faces += [(a, b, k), (b, cc, k), (cc, d, k), (d, a, k)]
    return np.array(verts), np.array(faces)


def force_history(floor: str, x0, v, spin: float, steps: int,
                  land: int | None = None, fused: bool = False) -> tuple[np.ndarray, float]:
    """Boundary force after every step of a sphere started at x0 with velocity v and spin
    ``spin`` times the rolling spin (z x v) / r. With ``land``, the sphere is moved sideways
    after step ``land`` so that the next step puts its centre 1e-9 m on the far side of the
    edge y = 0 (the same shift in both runs)."""
    sim, a, w = scene(fused=fused)
    if floor == "plane":
        bd = sim.add_boundary("plane", material=w)
    else:
        verts, faces = pinwheel_floor(8, 2e-3)
        bd = sim.add_boundary("mesh", material=w, vertices=verts, faces=faces)
        assert len(faces) == 1024
    sentinels(sim, w)
    v = np.asarray(v, float)
    spin_v = spin * np.array([-v[1], v[0], 0.0]) / R_BALL
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[x0], velocities=[v],
                      angular_velocities=[spin_v])
    out = np.empty((steps, 6))
    b = sim.bodies
    for k in range(steps):
        sim.run(steps=1, progress=False)
        out[k, :3] = bd.force
        out[k, 3:] = b.position[0]
        if k == land:  # velocity Verlet: y' = y + dt v + dt^2 F / (2 m)
            b.position[0, 1] = (1e-9 - DT * b.velocity[0, 1]
                                - 0.5 * DT**2 * b.force[0, 1] / b.mass[0])
    return out, sphere_mass(R_BALL) * G


DT = 2e-6
ROLLS = {
    # name: (start, velocity, spin factor, steps)
    "generic": ((-7e-3, -4.3e-3, R_BALL), (0.9, 0.37, 0.0), 1.0, 4000),
    "along_edges_through_vertices": ((-7e-3, 0.0, R_BALL), (1.0, 0.0, 0.0), 1.0, 4000),
    "diagonal_through_fan_vertices": ((-7e-3, -7e-3, R_BALL), (0.7, 0.7, 0.0), 1.0, 4000),
    "sliding_to_rolling": ((-7e-3, -4.3e-3, R_BALL), (0.9, 0.37, 0.0), 0.9, 4000),
    # moved after step 300 so as to land 1e-9 m past the edge y = 0, leaving the triangle of
    # lower index (see force_history)
    "landing_next_to_an_edge": ((-7e-3, -1e-3, R_BALL), (0.9, 0.37, 0.0), 1.0, 500),
}


@pytest.mark.parametrize("name", [
    *[n for n in ROLLS if n != "landing_next_to_an_edge"],
    "landing_next_to_an_edge",
])
def test_mesh_floor_feels_like_the_plane(name):
    """Rolling (or sliding into rolling) across edges and fan vertices of a flat mesh: the
    normal and tangential force on the floor equal those on the analytic plane at every step
    within 1e-6 of m g (no bumps, no double counting, friction history handed over)."""
    x0, v, spin, steps = ROLLS[name]
    land = 300 if name == "landing_next_to_an_edge" else None
    plane, mg = force_history("plane", x0, v, spin, steps, land)
    mesh, _ = force_history("mesh", x0, v, spin, steps, land)
    if land is not None:
        assert 0 < plane[land + 1, 4] < 2e-9
    normal = np.abs(mesh[:, 2] - plane[:, 2]) / mg
    tangential = np.linalg.norm(mesh[:, :2] - plane[:, :2], axis=1) / mg
    travelled = np.linalg.norm(plane[-1, 3:5] - np.asarray(x0)[:2])
    print(f"{name}: travelled {travelled * 1e3:.1f} mm, max |dFn|/mg {normal.max():.2e}, "
          f"max |dFt|/mg {tangential.max():.2e}, max Ft/mg "
          f"{np.linalg.norm(plane[:, :2], axis=1).max() / mg:.2e}")
    assert normal.max() < 1e-6, int(np.argmax(normal))
    assert tangential.max() < 1e-6, int(np.argmax(tangential))


# ------------------------------------------------------------------------ rotating drum

R_DRUM = 20e-3
L_DRUM = 20e-3


def drum_scene(omega: float, gravity, **law):
    sim, a, w = scene(gravity=gravity, **law)
    drum = sim.add_boundary("tube", material=w, start=(0, -L_DRUM / 2, 0), axis=(0, 1, 0),
                            length=L_DRUM, radius=R_DRUM,
                            motion=dpm.Rotation(axis=(0, 1, 0), omega=omega))
    sentinels(sim, w)
    return sim, a, drum


def test_sphere_at_rest_on_a_drum_wall_moves_with_it():
    """Zero gravity, drum at omega = 20 rad/s about its own axis; a sphere on the wall at
    0.8 of the wall speed, no spin. Friction drags it along, rolling resistance (EPSD)
    removes the rolling mode (without it the sphere would roll on forever: centre speed and
    spin on the no-slip line, as a run without it shows). After the transient (~0.15 s) it
    moves as a point of the wall: v = omega x x, spin = omega, at radius R - r + d with
    d the Hertz overlap under m omega^2 (R - r) (to 1e-3 of d)."""
    omega = 20.0
    sim, a, drum = drum_scene(omega, (0, 0, 0), rolling_friction=0.1, rolling_model="epsd")
    rho = R_DRUM - R_BALL
    x0 = np.array([rho * math.sin(0.3), 0, -rho * math.cos(0.3)])
    w = np.array([0.0, omega, 0.0])
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[x0],
                      velocities=[0.8 * np.cross(w, x0)])
    sim.run(until=0.3, progress=False)
    x, v = sim.bodies.position[0], sim.bodies.velocity[0]
    err = np.linalg.norm(v - np.cross(w, x)) / (omega * rho)
    print(f"|v - omega x r| / (omega r) = {err:.2e}")
    # the transient decays exponentially (measured: 1e-5 at 0.125 s, 8e-10 from 0.2 s on)
    assert err < 1e-6
    np.testing.assert_allclose(sim.bodies.angular_velocity[0], w, rtol=0, atol=1e-6 * omega)
    d = brentq(lambda s: hertz_force(s, R_BALL) - sphere_mass(R_BALL) * omega**2 * rho,
               0, R_BALL, xtol=1e-18)
    assert math.hypot(x[0], x[2]) == pytest.approx(R_DRUM - R_BALL + d, abs=1e-3 * d)
    assert x[1] == pytest.approx(0.0, abs=1e-15)


def stuck_on_drum(sim, drum, mass, omega, samples=8, every=0.02):
    """(measured torque about the axis, (x - A) x m g, power, m g v_z, drum force, m (g - a))
    at a few times while a body rides the drum wall up."""
    rows = []
    w = np.array([0.0, omega, 0.0])
    for _ in range(samples):
        sim.run(until=sim.time + every, progress=False)
        x = sim.bodies.position[0]
        v = sim.bodies.velocity[0]
        g = np.array([0, 0, -G])
        acc = np.cross(w, np.cross(w, x))  # uniform circular motion about the axis
        rows.append((drum.torque[1], np.cross(x, mass * g)[1], drum.power(), mass * G * v[2],
                     drum.force.copy(), mass * (g - acc),
                     math.degrees(math.atan2(-x[0], -x[2]))))
    return rows


def test_drum_torque_and_power_of_a_stuck_block():
    """A cube (sphere elements, no rolling resistance) held by friction on the wall of a drum
    turning at 0.5 rad/s rides up from theta = 15 degrees. Its angular momentum about the
    axis is constant (rigid co-rotation at constant omega), so the torque it exerts on the
    drum about the axis is that of its weight, (x - A) x m g = m g rho sin(theta) (rho its
    centre's distance from the axis), the force on the drum is m (g - a) with a the
    centripetal acceleration, and the drive power is the rate of potential energy
    m g v_z = -T . omega. Tolerance 1e-3: the block creeps by < 1e-4 of the wall speed."""
    omega = 0.5
    sim, a, drum = drum_scene(omega, (0, 0, -G), friction=0.8)
    edge = 3e-3
    th = math.radians(15)
    # a face towards the wall, its long edges just inside it (it settles onto them)
    rho = math.sqrt(R_DRUM**2 - (0.5 * edge) ** 2) - 0.5 * edge - 1e-5
    x0 = np.array([-rho * math.sin(th), 0, -rho * math.cos(th)])
    q = np.array([math.cos(th / 2), 0, math.sin(th / 2), 0])
    w = np.array([0, omega, 0])
    sim.add_particles("cube", material=a, a=edge, positions=[x0], orientations=[q],
                      velocities=[np.cross(w, x0)], angular_velocities=[w])
    mass = float(sim.bodies.mass[0])
    sim.run(until=0.04, progress=False)  # settle
    rows = stuck_on_drum(sim, drum, mass, omega)
    for torque, ref, power, p_ref, force, f_ref, deg in rows:
        print(f"theta {deg:6.2f} deg: torque {torque:.6e} ref {ref:.6e}; power {power:.6e} "
              f"ref {p_ref:.6e}")
        assert torque == pytest.approx(ref, rel=1e-3)
        assert power == pytest.approx(p_ref, rel=1e-3)
        assert power == pytest.approx(-torque * omega, rel=1e-12)
        np.testing.assert_allclose(force, f_ref, rtol=0, atol=1e-3 * mass * G)
    assert rows[-1][-1] > rows[0][-1] + 2.0  # it rode up with the wall


def test_drum_torque_and_power_of_a_sphere_held_by_rolling_resistance():
    """As the block test, with a sphere held at theta by friction and EPSD rolling
    resistance (tan theta < mu_r): torque (x - A) x m g = m g (R - r) sin(theta) and power
    m g v_z, to 1e-3."""
    omega = 0.5
    sim, a, drum = drum_scene(omega, (0, 0, -G), friction=0.8, rolling_friction=0.5,
                              rolling_model="epsd")
    rho = R_DRUM - R_BALL
    th = math.radians(15)
    x0 = np.array([-rho * math.sin(th), 0, -rho * math.cos(th)])
    w = np.array([0, omega, 0])
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[x0],
                      velocities=[np.cross(w, x0)], angular_velocities=[w])
    sim.run(until=0.02, progress=False)
    rows = stuck_on_drum(sim, drum, sphere_mass(R_BALL), omega, samples=4)
    for torque, ref, _power, _p_ref, force, f_ref, deg in rows:
        print(f"theta {deg:6.2f} deg: torque {torque:.6e} ref {ref:.6e} "
              f"(ratio {torque / ref:.4f}, R/(R-r) = {R_DRUM / rho:.4f})")
        np.testing.assert_allclose(force, f_ref, rtol=0, atol=1e-3 * sphere_mass(R_BALL) * G)
    for torque, ref, power, p_ref, *_ in rows:
        assert torque == pytest.approx(ref, rel=1e-3)
        assert power == pytest.approx(p_ref, rel=1e-3)


# ------------------------------------------------------------------------------ pipe run

R_P = 6e-3      # pipe radius
R_BEND = 0.03   # bend radius
L_PIPE = 0.05


def pipe_axis_distance(p: np.ndarray) -> float:
    """Distance of p from the pipe axis: segment (0,0,0)-(L,0,0), quarter circle about
    (L, R_b, 0) in z = 0 from (L, 0, 0) to (L + R_b, R_b, 0), segment from there along +y;
    inf beyond the open end."""
    best = math.inf
    if 0 <= p[0] <= L_PIPE:
        best = math.hypot(p[1], p[2])
    q = p - np.array([L_PIPE, R_BEND, 0.0])
    if q[0] >= 0 and q[1] <= 0:
        best = min(best, math.hypot(math.hypot(q[0], q[1]) - R_BEND, q[2]))
    if 0 <= p[1] - R_BEND <= L_PIPE:
        best = min(best, math.hypot(p[0] - L_PIPE - R_BEND, p[2]))
    return best


def test_ball_rolls_through_tube_bend_tube_without_leaking():
    """A ball (r = 2 mm) launched at 0.6 m/s rolling along the bottom of a pipe (radius
    6 mm): tube along x, 90-degree bend (Bend.end_point / end_direction place the second
    tube), tube along y. At every frame (every 100 steps) its centre stays within
    pipe_radius - r + 1e-5 m (a few static overlaps) of the pipe axis, and it reaches the
    far tube."""
    sim, a, w = scene()
    sim.add_boundary("tube", material=w, start=(0, 0, 0), axis=(1, 0, 0), length=L_PIPE,
                     radius=R_P, caps="start")
    bend = sim.add_boundary("bend", material=w, center=(L_PIPE, R_BEND, 0), axis=(0, 0, 1),
                            start_direction=(0, -1, 0), bend_radius=R_BEND, pipe_radius=R_P,
                            angle=math.pi / 2)
    np.testing.assert_allclose(bend.start_point(), [L_PIPE, 0, 0], atol=1e-15)
    np.testing.assert_allclose(bend.end_point(), [L_PIPE + R_BEND, R_BEND, 0], atol=1e-15)
    np.testing.assert_allclose(bend.end_direction(), [0, 1, 0], atol=1e-15)
    sim.add_boundary("tube", material=w, start=bend.end_point(), axis=bend.end_direction(),
                     length=L_PIPE, radius=R_P)
    sentinels(sim, w)
    v0 = 0.6
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[(0.01, 0, -R_P + R_BALL)],
                      velocities=[(v0, 0, 0)], angular_velocities=[(0, v0 / R_BALL, 0)])
    worst, frames, two_pieces = 0.0, 0, 0
    owner = sim.walls  # set at prepare
    while True:
        sim.run(steps=100, progress=False)
        owner = sim.walls.owner
        p = sim.bodies.position[0]
        if p[1] > R_BEND + L_PIPE - R_BALL or sim.time > 0.5:
            break
        frames += 1
        worst = max(worst, pipe_axis_distance(p))
        wc = sim.wall_contacts
        touching = {int(owner[wc.key[q]]) for q in range(wc.start[0], wc.start[1])
                    if wc.active[q]}
        two_pieces += len(touching) > 1
    print(f"{frames} frames, worst axis distance {worst * 1e3:.4f} mm (limit "
          f"{(R_P - R_BALL) * 1e3:.4f} mm), frames touching two pieces: {two_pieces}, "
          f"end time {sim.time:.3f} s")
    assert p[1] > R_BEND + L_PIPE - R_BALL, p  # it came through
    assert worst < R_P - R_BALL + 1e-5


def joined_pipe_history(split: bool, kind: str, steps: int = 1500,
                        fused: bool = False) -> tuple[np.ndarray, float]:
    """Force on the pipe (all pieces) after every step of a ball rolling across the place
    where a split pipe is joined: a straight tube joined at x = 0.02, or a bend joined at
    angle 0.5 rad; the unsplit pipe is the reference."""
    sim, a, w = scene(fused=fused)
    if kind == "tube":
        pieces = ([(0.0, 0.02), (0.02, 0.02)] if split else [(0.0, 0.04)])
        bds = [sim.add_boundary("tube", material=w, start=(x, 0, 0), axis=(1, 0, 0), length=ln,
                                radius=R_P) for x, ln in pieces]
        x0, v = (0.02 - 0.5 * steps * DT * 0.5, 0, -R_P + R_BALL), (0.5, 0, 0)
    else:
        pieces = ([(0.0, 0.5), (0.5, 0.5)] if split else [(0.0, 1.0)])
        bds = [sim.add_boundary("bend", material=w, center=(0, 0, 0), axis=(0, 0, 1),
                                start_direction=(math.cos(p0), math.sin(p0), 0),
                                bend_radius=R_BEND, pipe_radius=R_P, angle=ln)
               for p0, ln in pieces]
        phi0 = 0.5 - 0.5 * steps * DT * 0.3 / R_BEND
        x0 = (R_BEND * math.cos(phi0), R_BEND * math.sin(phi0), -R_P + R_BALL)
        v = (-0.3 * math.sin(phi0), 0.3 * math.cos(phi0), 0)
    sentinels(sim, w)
    v = np.asarray(v, float)
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=[x0], velocities=[v],
                      angular_velocities=[np.cross([0, 0, 1], v) / R_BALL])
    out = np.empty((steps, 3))
    for k in range(steps):
        sim.run(steps=1, progress=False)
        out[k] = sum(b.force for b in bds)
    return out, sphere_mass(R_BALL) * G


@pytest.mark.slow
def test_fused_pass_matches_two_pass_at_every_boundary_kind():
    """Sphere scenes sum forces in the fused pass; it gives the two-pass sum's numbers bit
    for bit on a meshed floor (edge and vertex hand-overs), across a joined bend and in a
    sieve screening (slab, plate, sieve, box: all kinds with the sentinels)."""
    runs = {}
    for fused in (False, True):
        mesh, _ = force_history("mesh", *ROLLS["landing_next_to_an_edge"][:3], 500, land=300,
                                fused=fused)
        bend, _ = joined_pipe_history(True, "bend", 600, fused=fused)
        sim, a, _ = sieve_scene("radius", 0.8, fused=fused)
        sim.add_particles("sphere", material=a, radius=R_SMALL,
                          positions=[(0.0, 0.0, 4 * R_SMALL), (HOLE, 0.0, 7 * R_SMALL)])
        sim.run(steps=3000, progress=False)
        assert sim.backend.module.FUSED == fused
        runs[fused] = (mesh, bend, sim.bodies.position.copy(), sim.boundaries[0].force.copy())
    for x, y in zip(runs[False], runs[True], strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("kind", ["tube", "bend"])
def test_pipe_joint_feels_like_one_piece(kind):
    """A ball rolling across the joint of two tube (or bend) pieces feels the force history
    of the same run in one unsplit piece, within 1e-6 m g at every step."""
    split, mg = joined_pipe_history(True, kind)
    whole, _ = joined_pipe_history(False, kind)
    diff = np.linalg.norm(split - whole, axis=1) / mg
    print(f"{kind}: max |F_split - F_whole| / m g = {diff.max():.3g}, max |F_split| / m g = "
          f"{np.linalg.norm(split, axis=1).max() / mg:.3g}")
    assert diff.max() < 1e-6


# ------------------------------------------------------------------------------ screening

HOLE, BAR = 4e-3, 2e-3
PITCH = HOLE + BAR
HALF = 3.5 * PITCH
R_SMALL, R_LARGE = 1.2e-3, 2.6e-3
AMP, FREQ = 1e-3, 25.0


def sieve_scene(model: str, zeta: float, fused: bool = False):
    sim, a, w = scene(friction=0.3, restitution=0.5, fused=fused)
    sv = sim.add_boundary("sieve", material=w, center=(0, 0, 0), half_extents=(HALF, HALF),
                          hole=HOLE, bar=BAR, clearance_model=model, zeta=zeta,
                          motion=dpm.Oscillation(amplitude=(0, 0, AMP), frequency=FREQ))
    sim.add_boundary("box", material=w, lower=(-HALF, -HALF, -0.03), upper=(HALF, HALF, 0.1),
                     open=("+z",))
    sentinels(sim, w)
    return sim, a, sv


def counts(sim, n_small):
    z = sim.bodies.position[:, 2]
    return int((z[:n_small] < -AMP - R_SMALL).sum()), int((z[n_small:] < -AMP).sum())


def test_screening_exact_sieve():
    """Exact (meshed) plate with square holes of 4 mm, vibrated vertically at 1 mm and 25 Hz
    (2.5 g): 8 spheres of diameter 2.4 mm dropped at random places (over bars and holes)
    all end up below it, 8 of 5.2 mm (larger than the hole) all stay above."""
    sim, a, sv = sieve_scene("exact", 0.0)
    rng = np.random.default_rng(1)
    n = 8
    pts = []
    while len(pts) < 2 * n:
        q = np.array([rng.uniform(-HALF + 3e-3, HALF - 3e-3),
                      rng.uniform(-HALF + 3e-3, HALF - 3e-3), rng.uniform(4e-3, 20e-3)])
        if all(np.linalg.norm(q - o) > 2 * R_LARGE + 1e-3 for o in pts):
            pts.append(q)
    pts = np.array(pts)
    sim.add_particles("sphere", material=a, radius=R_SMALL, positions=pts[:n])
    sim.add_particles("sphere", material=a, radius=R_LARGE, positions=pts[n:])
    check_time_step(sim)
    history = []
    while sim.time < 1.5:
        sim.run(until=sim.time + 0.05, progress=False)
        history.append(counts(sim, n))
        if history[-1][0] == n and sim.time >= 0.3:
            break
    small, large = history[-1]
    print(f"exact sieve, t = {sim.time:.2f} s: small passed {small}/{n}, large passed "
          f"{large}/{n}; passed small per 0.05 s: {[h[0] for h in history]}")
    assert (small, large) == (n, 0)
    assert np.all(sim.bodies.position[n:, 2] > 0.0)


#: offsets (in units of w = hole / 2) of the small spheres from their hole's centre
OFFSETS = [(0.0, 0.0), (0.2, 0.1), (0.35, 0.0), (0.0, 0.45), (0.55, 0.3), (0.3, 0.62),
           (0.75, 0.0), (0.0, 0.85), (0.9, 0.9)]


@pytest.mark.parametrize("model, zeta", [("radius", 0.8), ("fixed", 0.6), ("fixed", 0.0),
                                         ("fixed", 1.0)])
def test_screening_clearance_models(model, zeta):
    """Clearance models (flat plate, vertical vibration, so no sideways motion): a small
    sphere (r < w) falls iff its centre lies over the reduced hole, max(|dx|, |dy|) < w - b
    with b = zeta (w - r) (model 1, eq. 4.20) or b = zeta w (model 2, eq. 4.21); spheres with
    r > w never fall. zeta = 0 opens the whole hole, zeta = 1 (model 2) closes it."""
    sim, a, sv = sieve_scene(model, zeta)
    w = HOLE / 2
    b = zeta * (w - R_SMALL) if model == "radius" else zeta * w
    small = [((i - 4) * PITCH + dx * w, (j - 4) * PITCH + dy * w, 3e-3)
             for (dx, dy), (i, j) in zip(OFFSETS, [(i, j) for i in range(3, 6)
                                                    for j in range(3, 6)], strict=True)]
    predicted = np.array([max(abs(dx), abs(dy)) * w < w - b for dx, dy in OFFSETS])
    if b < w:
        assert all(abs(max(abs(dx), abs(dy)) * w - (w - b)) > 0.04 * w for dx, dy in OFFSETS)
    # large ones over holes and bar crossings of the outer ring of cells
    large = [(-3 * PITCH, -3 * PITCH, 8e-3), (3 * PITCH, 0, 8e-3), (0, 3 * PITCH, 8e-3),
             (-3 * PITCH + 0.5 * PITCH, 2 * PITCH + 0.5 * PITCH, 8e-3)]
    sim.add_particles("sphere", material=a, radius=R_SMALL, positions=small)
    sim.add_particles("sphere", material=a, radius=R_LARGE, positions=large)
    sim.run(until=0.3, progress=False)
    z = sim.bodies.position[:, 2]
    fell = z[:len(small)] < -AMP - R_SMALL
    print(f"{model} zeta={zeta}: reduced half width {(w - b) * 1e3:.2f} mm; small passed "
          f"{int(fell.sum())}/{len(small)} (predicted {int(predicted.sum())}), large passed "
          f"{int((z[len(small):] < 0).sum())}/{len(large)}")
    np.testing.assert_array_equal(fell, predicted)
    assert np.all(z[len(small):] > 0)
    if zeta == 0.0:
        assert fell.all()
    if model == "fixed" and zeta == 1.0:
        assert not fell.any()


def test_sieve_clearance_matches_eqs_4_22_to_4_25():
    """sieve_distance's pass test against Alkhaldi's construction written out: gap aisles
    x_a = w + j (2 w + g), x_b = x_a + g (eq. 4.23); c_x = 0 iff x_a - b <= x <= x_b + b for
    some aisle j (eq. 4.24), likewise c_y; a sphere with r < w falls iff c_x c_y = 1 (eq.
    4.25), b from eq. 4.20 or 4.21. For a sphere of radius r whose centre is 0.8 r above the
    plate (beyond the 3/4 r of the moving-screen extension): a reflected sphere meets the
    plane (dist 0.8 r); a falling one only the rim of the real hole, at distance
    sqrt(gap^2 + (0.8 r)^2), gap = w - max(|dx|, |dy|) from the hole centre."""
    a = dpm.Material("m", density=1000.0)
    w_half, g = 2e-3, 1.5e-3
    pitch = 2 * w_half + g
    radius_plate = 0.02
    n_k = round(radius_plate / pitch + 1)  # eq. 4.22, rounded
    half = (n_k - 0.5) * pitch - 0.5 * g  # outline: the outer holes' far sides
    rng = np.random.default_rng(5)
    falls_seen = 0
    for model, zeta in [("radius", 0.8), ("fixed", 0.6), ("fixed", 0.0)]:
        sv = dpm.boundaries.Sieve(a, center=(0, 0, 0), half_extents=(half, half),
                                  hole=2 * w_half, bar=g, clearance_model=model, zeta=zeta)
        prim = sv.primitives()
        assert prim.kind[0] == SIEVE
        for r in rng.uniform(0.2e-3, w_half * 0.99, 20):
            b = zeta * (w_half - r) if model == "radius" else zeta * w_half
            height = 0.8 * r

            def c(u, b=b):
                for j in range(-(n_k - 1), n_k - 1):
                    xa = w_half + j * pitch
                    if xa - b <= u <= xa + g + b:
                        return 0
                return 1

            for x, y in rng.uniform(-half + w_half, half - w_half, (200, 2)):
                falls = c(x) * c(y) == 1
                d = closest_any(SIEVE, prim.par[0], x, y, height, r)[0]
                if falls:
                    offset = max(abs(x - pitch * round(x / pitch)),
                                 abs(y - pitch * round(y / pitch)))
                    expect = math.hypot(w_half - offset, height)
                    falls_seen += 1
                else:
                    expect = height
                assert d == pytest.approx(expect, rel=1e-12), (model, zeta, r, x, y, falls)
        # larger than the hole: never falls
        assert closest_any(SIEVE, prim.par[0], 0.0, 0.0, 1e-3, 1.01 * w_half)[0] == 1e-3
    assert falls_seen > 1000


# ------------------------------------------------------------------------------ geometry


def random_rotation(rng) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def test_triangle_closest_point_matches_trimesh():
    """Closest point of random (also obtuse and slender) triangles to random points: the
    point x - dist n equals trimesh.triangles.closest_point's to 1e-12 of the size, and the
    feature code (face / edge k / vertex k) matches the barycentric coordinates of trimesh's
    point; with and without the dual vectors of the kernel's face test."""
    rng = np.random.default_rng(11)
    checked = {"face": 0, "edge": 0, "vertex": 0}
    for _ in range(60):
        v = rng.normal(size=(3, 3))
        if rng.random() < 0.3:
            v[2] = v[0] + rng.uniform(0.01, 2) * (v[1] - v[0]) + 0.02 * rng.normal(size=3)
        n = np.cross(v[1] - v[0], v[2] - v[0])
        if np.linalg.norm(n) < 1e-6:
            continue
        n /= np.linalg.norm(n)
        par = np.zeros(20)
        par[0:9] = v.ravel()
        par[10:13] = n
        if rng.random() < 0.5:  # with the dual vectors (the face test first) or without
            par[13:19] = triangle_duals(v[None])[0]
        pts = rng.normal(size=(100, 3)) * 1.5
        # (trimesh.proximity.closest_point runs this after an rtree broad phase)
        ref = trimesh.triangles.closest_point(np.repeat(v[None], len(pts), 0), pts)
        dist_ref = np.linalg.norm(pts - ref, axis=1)
        bary = trimesh.triangles.points_to_barycentric(np.repeat(v[None], len(pts), 0), ref)
        for p, q, dr, bc in zip(pts, ref, dist_ref, bary, strict=True):
            d, nx, ny, nz, feature = closest_any(TRIANGLE, par, *p, 0.1)
            mine = p - d * np.array([nx, ny, nz])
            np.testing.assert_allclose(mine, q, rtol=0, atol=1e-12)
            assert d == pytest.approx(dr, abs=1e-12)
            zero = np.abs(bc) < 1e-9
            if zero.sum() == 0:
                assert feature == 0
                checked["face"] += 1
            elif zero.sum() == 1:
                # edge k = v_{k-1} v_k, k = 1..3: the weight of the opposite vertex is zero
                assert feature == {2: 1, 0: 2, 1: 3}[int(np.argmax(zero))]
                checked["edge"] += 1
            else:
                assert feature == 4 + int(np.argmax(~zero))
                checked["vertex"] += 1
    assert min(checked.values()) > 100, checked


@jit
def _within(par, x, y, z, lim):
    return bg_triangle_distance_within(par, x, y, z, lim)


def test_triangle_distance_bound_never_drops_a_triangle_within_reach():
    """The shortcut of ``triangle_distance_within`` (a triangle certainly farther than
    ``lim`` returns lim without its closest point) against trimesh's exact distance, on
    random (also slender) triangles with a half thickness: where it returns the exact
    answer it equals ``closest_any``'s; where it answers lim, trimesh's distance minus the
    half thickness is at least lim. The smallest altitude in par[19] is 2 area / longest
    edge. The shortcut must also fire (else it saves nothing)."""
    rng = np.random.default_rng(12)
    fired = exact = 0
    for _ in range(60):
        v = rng.normal(size=(3, 3))
        if rng.random() < 0.3:
            v[2] = v[0] + rng.uniform(0.01, 2) * (v[1] - v[0]) + 0.02 * rng.normal(size=3)
        n = np.cross(v[1] - v[0], v[2] - v[0])
        area2 = np.linalg.norm(n)
        if area2 < 1e-6:
            continue
        h = rng.choice([0.0, 0.05])
        par = np.zeros(20)
        par[0:9] = v.ravel()
        par[9] = h
        par[10:13] = n / area2
        par[13:19] = triangle_duals(v[None])[0]
        par[19] = smallest_altitudes(par[None, 13:19])[0]
        longest = max(np.linalg.norm(v[1] - v[0]), np.linalg.norm(v[2] - v[1]),
                      np.linalg.norm(v[0] - v[2]))
        assert par[19] == pytest.approx(area2 / longest, rel=1e-9)
        pts = rng.normal(size=(100, 3)) * 1.5
        ref = trimesh.triangles.closest_point(np.repeat(v[None], len(pts), 0), pts)
        dist_ref = np.linalg.norm(pts - ref, axis=1) - h
        for p, dr in zip(pts, dist_ref, strict=True):
            lim = rng.uniform(0.0, 1.0)
            d, *_ = _within(par, *p, lim)
            if d == lim and not d == pytest.approx(dr, abs=1e-12):
                assert dr >= lim * (1 - 1e-12), (dr, lim)
                fired += 1
            else:
                assert d == pytest.approx(closest_any(TRIANGLE, par, *p, 0.1)[0], abs=1e-15)
                assert d == pytest.approx(dr, abs=1e-12)
                exact += 1
    assert fired > 500 and exact > 500, (fired, exact)


def grid_samples(n_u: int, n_v: int):
    """Cell-centred parameters (u, v) in [0, 1)^2 of an n_u x n_v grid."""
    u = (np.arange(n_u) + 0.5) / n_u
    v = (np.arange(n_v) + 0.5) / n_v
    uu, vv = np.meshgrid(u, v, indexing="ij")
    return uu.ravel(), vv.ravel()


def brute_min(samples: np.ndarray, pts: np.ndarray):
    """(distance, nearest sample) of each point to a point cloud (chunked)."""
    dist = np.empty(len(pts))
    near = np.empty((len(pts), 3))
    for k, p in enumerate(pts):
        d2 = np.einsum("ij,ij->i", samples - p, samples - p)
        j = int(np.argmin(d2))
        dist[k] = math.sqrt(d2[j])
        near[k] = samples[j]
    return dist, near


def check_against_samples(kind, par, samples, spacing, pts, h=0.0, signed_inside=None):
    """dist (+ h) is <= the distance to every sample (it is the true minimum, up to 1e-12)
    and >= it minus half the diagonal of a sampling cell; the normal points from the nearest
    sample to the point (within the angle spacing / distance)."""
    tol = 0.5 * math.hypot(*spacing)
    brute, near = brute_min(samples, pts)
    for k, p in enumerate(pts):
        d, nx, ny, nz, _ = closest_any(kind, par, *p, 1e-3)
        unsigned = d + h
        if signed_inside is not None and signed_inside[k]:
            unsigned = -d
        assert unsigned <= brute[k] + 1e-12, (k, unsigned, brute[k])
        assert unsigned >= brute[k] - tol, (k, unsigned, brute[k], tol)
        if brute[k] > 20 * tol and (signed_inside is None or not signed_inside[k]):
            direction = (p - near[k]) / brute[k]
            assert np.dot(direction, [nx, ny, nz]) > math.cos(2 * tol / brute[k]), k


def test_slab_distance_against_sampled_box():
    """Finite wall (SLAB): box a x b x h rotated; ~1e5 samples over its six faces; points
    outside and inside (inside: minus the distance to the nearest face)."""
    rng = np.random.default_rng(2)
    rot = random_rotation(rng)
    u, v = rot[:, 0], rot[:, 1]
    wn = np.cross(u, v)
    c = np.array([0.1, -0.2, 0.3])
    a, b, h = 1.0, 0.6, 0.2
    par = np.zeros(20)
    par[0:3], par[3:6], par[6:9] = c, u, v
    par[9], par[10], par[11] = a, b, h
    faces = []  # (origin, edge1, edge2) of each face; samples per face by area
    for s in (-1, 1):
        faces.append((c + s * h * wn - a * u - b * v, 2 * a * u, 2 * b * v))
        faces.append((c + s * a * u - b * v - h * wn, 2 * b * v, 2 * h * wn))
        faces.append((c + s * b * v - a * u - h * wn, 2 * a * u, 2 * h * wn))
    spacing = 0.009
    samples = []
    for o, e1, e2 in faces:
        n1 = max(int(np.linalg.norm(e1) / spacing), 1)
        n2 = max(int(np.linalg.norm(e2) / spacing), 1)
        s1, s2 = grid_samples(n1, n2)
        samples.append(o + s1[:, None] * e1 + s2[:, None] * e2)
    samples = np.concatenate(samples)
    assert 8e4 < len(samples) < 1.5e5
    local = rng.uniform(-1.6, 1.6, (300, 3)) * [a, b, 3 * h]
    pts = c + local @ np.array([u, v, wn])
    inside = (np.abs(local[:, 0]) < a) & (np.abs(local[:, 1]) < b) & (np.abs(local[:, 2]) < h)
    assert 5 < inside.sum() < 100
    check_against_samples(SLAB, par, samples, (spacing, spacing), pts, signed_inside=inside)


@pytest.mark.parametrize("segment", [(0.5, 0.0, 0.8, 1.0), (0.0, 0.3, 0.7, 0.3),
                                     (0.6, 0.0, 0.6, 1.2)], ids=["frustum", "disc", "cylinder"])
def test_axi_distance_against_sampled_surface(segment):
    """Surface of revolution of a meridian segment (tube wall, cone, cap) with half thickness
    h: dist + h is the distance to the surface of zero thickness, sampled at ~1e5 points."""
    rng = np.random.default_rng(4)
    rho0, z0, rho1, z1 = segment
    h = 0.05
    axis = random_rotation(rng)[:, 2]
    o = np.array([0.2, 0.1, -0.1])
    par = np.zeros(20)
    par[0:3], par[3:6] = o, axis
    par[6:11] = rho0, z0, rho1, z1, h
    e1 = np.cross(axis, [1.0, 0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    length = math.hypot(rho1 - rho0, z1 - z0)
    n_phi = 900
    n_t = int(1e5 / n_phi)
    t, ph = grid_samples(n_t, n_phi)
    rho = rho0 + t * (rho1 - rho0)
    zz = z0 + t * (z1 - z0)
    ang = 2 * math.pi * ph
    samples = (o + zz[:, None] * axis + (rho * np.cos(ang))[:, None] * e1
               + (rho * np.sin(ang))[:, None] * e2)
    spacing = (length / n_t, 2 * math.pi * max(rho0, rho1) / n_phi)
    local = rng.uniform(-1, 1, (300, 3)) * 1.3 * max(rho0, rho1, 0.5)
    local[:, 2] = rng.uniform(min(z0, z1) - 0.5, max(z0, z1) + 0.5, 300)
    pts = o + local[:, 0:1] * e1 + local[:, 1:2] * e2 + local[:, 2:3] * axis
    check_against_samples(AXI, par, samples, spacing, pts, h=h)


def test_torus_distance_against_sampled_surface():
    """Bend (TORUS segment of 2 rad, R = 1, pipe radius 0.3, half thickness h): dist + h is
    the distance to the sampled pipe surface, for points inside and outside the pipe, and
    beyond its ends (where the rounded end rings are nearest)."""
    rng = np.random.default_rng(6)
    big_r, rp, theta, h = 1.0, 0.3, 2.0, 0.02
    rot = random_rotation(rng)
    c = np.array([0.1, 0.0, -0.2])
    e1, axis = rot[:, 0], rot[:, 2]
    e2 = np.cross(axis, e1)
    par = np.zeros(20)
    par[0:3], par[3:6], par[6:9] = c, axis, e1
    par[9:13] = big_r, rp, theta, h
    n_phi, n_psi = 340, 300
    s_phi, s_psi = grid_samples(n_phi, n_psi)
    phi = theta * s_phi
    psi = 2 * math.pi * s_psi
    radial = np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2
    samples = c + (big_r + rp * np.cos(psi))[:, None] * radial + (rp * np.sin(psi))[:, None] * axis
    spacing = ((big_r + rp) * theta / n_phi, 2 * math.pi * rp / n_psi)
    # points within 0.25 of the pipe wall, along the bend and up to 0.4 rad beyond its ends
    m = 300
    ang = rng.uniform(-0.4, theta + 0.4, m)
    rr = rng.uniform(0.0, rp + 0.25, m)
    sec = rng.uniform(0, 2 * math.pi, m)
    radial = np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2
    pts = c + (big_r + rr * np.cos(sec))[:, None] * radial + (rr * np.sin(sec))[:, None] * axis
    check_against_samples(TORUS, par, samples, spacing, pts, h=h)


# -------------------------------------------------------------------- candidate lists


def pair_set(sim) -> set[tuple[int, int]]:
    wc = sim.wall_contacts
    n = len(sim.elements)
    return {(i, int(wc.key[q])) for i in range(n) for q in range(wc.start[i], wc.start[i + 1])}


def brute_pairs(sim, skin: float) -> set[tuple[int, int]]:
    w = sim.walls
    return set(brute_force_boundary_pairs(sim.elements.position, sim.elements.radius, skin,
                                          w.frame, w.kind, w.par, w.owner))


def place_near(rng, surface_pts, frame_pose, n, gap=(0.2e-3, 2.5e-3)):
    """Sphere centres near local surface points, mapped to the world by (R, o)."""
    r_rot, o = frame_pose
    k = rng.integers(len(surface_pts), size=n)
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    local = surface_pts[k] + dirs * rng.uniform(R_BALL + gap[0], R_BALL + gap[1], n)[:, None]
    return local @ r_rot.T + o


@pytest.mark.parametrize("moved", [False, True])
def test_candidate_list_matches_brute_force(moved):
    """After prepare, the element-primitive list equals the plain double loop over all
    primitives (reach r + skin): a 320-triangle icosphere mesh (> 32: search grid), a tube,
    a bend and a wall; with ``moved`` the mesh carries a tumbling motion whose frame at t = 0
    is rotated and shifted, and after 3000 steps of the run the list is rebuilt at the new
    frame and compared again."""
    rng = np.random.default_rng(8 + moved)
    sim, a, w = scene(gravity=(0, 0, 0))
    ico = trimesh.creation.icosphere(subdivisions=2, radius=0.012)
    motion = (dpm.Tumbling(omega=30.0, alpha=0.3, beta=0.2, u=0.003, e=0.002,
                           eccentricity=0.001) if moved else None)
    # spheres on both sides of the closed icosphere: no side to check
    sim.add_boundary("mesh", material=w, vertices=ico.vertices, faces=ico.faces, motion=motion,
                     side="both")
    sim.add_boundary("tube", material=w, start=(0.05, 0, 0), axis=(1, 1, 0), length=0.02,
                     radius=0.008, caps="end")
    sim.add_boundary("bend", material=w, center=(-0.05, 0, 0), bend_radius=0.02,
                     pipe_radius=0.006, angle=2.0)
    sim.add_boundary("wall", material=w, center=(0, 0.05, 0), half_extents=(0.01, 0.005),
                     thickness=1e-3, normal=(0, 1, 1))
    sentinels(sim, w)
    pose = (np.eye(3), np.zeros(3))
    if moved:
        r0, o0 = motion.pose(np.array([0.0]))
        pose = (r0[0], o0[0])
        assert np.abs(pose[0] - np.eye(3)).max() > 0.1 and np.linalg.norm(pose[1]) > 1e-3
    tri_pts = ico.triangles_center[rng.integers(len(ico.faces), size=60)]
    pts = [place_near(rng, ico.vertices, pose, 60), place_near(rng, tri_pts, pose, 60)]
    cyl = np.array([0.05, 0, 0]) + np.outer(rng.uniform(0, 0.02, 40), [1, 1, 0]) / math.sqrt(2)
    cyl[:, 2] += 0.008 * rng.choice([-1, 1], 40)
    pts.append(place_near(rng, cyl, (np.eye(3), np.zeros(3)), 40))
    ang = rng.uniform(0, 2.0, 40)
    ring = np.c_[-0.05 + 0.02 * np.cos(ang), 0.02 * np.sin(ang), 0.006 * rng.choice([-1, 1], 40)]
    pts.append(place_near(rng, ring, (np.eye(3), np.zeros(3)), 40))
    wall = sim.boundaries[3]
    face = (wall.center + np.outer(rng.uniform(-1, 1, 30), wall.a * wall.u)
            + np.outer(rng.uniform(-1, 1, 30), wall.b * wall.v))
    pts.append(place_near(rng, np.concatenate([face, wall.corners()]), (np.eye(3), np.zeros(3)),
                          40))
    # keep spheres that overlap neither each other nor a boundary (the scene check refuses
    # overlaps); distances by closest_any in each boundary's frame at t = 0
    keep = []
    for p in np.concatenate(pts):
        if any(np.linalg.norm(p - q) <= 2 * R_BALL for q in keep):
            continue
        clear = True
        for bd in sim.boundaries[:4]:
            rr, oo = pose if bd.motion is not None else (np.eye(3), np.zeros(3))
            loc = rr.T @ (p - oo)
            prim = bd.primitives()
            if any(closest_any(k, par, *loc, R_BALL)[0] < R_BALL
                   for k, par in zip(prim.kind, prim.par, strict=True)):
                clear = False
                break
        if clear:
            keep.append(p)
    sim.add_particles("sphere", material=a, radius=R_BALL, positions=np.array(keep))
    sim.run(steps=0, progress=False)  # prepare: lists at the frame of t = 0
    touching = brute_pairs(sim, 0.0)
    assert sim.walls.grid_int[0, 0] == 1  # the mesh uses its search grid
    got, ref = pair_set(sim), brute_pairs(sim, sim.skin)
    assert got == ref
    assert len(ref) > 80 and len(touching) == 0
    by_owner = {int(sim.walls.owner[wk]) for _, wk in ref}
    assert {0, 1, 2, 3} <= by_owner
    # the first build wrote into slots of SLOT_SLACK entries (the list was empty): elements
    # with more took the second pass (over those elements only); a rebuild in place fills
    # slots sized by that list
    per_element = np.diff(sim.wall_contacts.start)
    assert per_element.max() > SLOT_SLACK
    sim.backend.rebuild()
    assert pair_set(sim) == ref
    if moved:
        sim.run(steps=3000, progress=False)
        assert np.abs(sim.walls.frame[0, 3:12] - pose[0].ravel()).max() > 0.1
        sim.backend.rebuild()
        assert pair_set(sim) == brute_pairs(sim, sim.skin)


def test_mesh_transform_scale_rotate_translate_matches_trimesh(tmp_path):
    """A CAD file in mm turned about two axes and shifted: the boundary's vertices equal
    trimesh's own transforms of the file (scale, then the rotations in order, then the
    shift); a rotation keeps a closed mesh's side and volume; bad rotations are named."""
    from trimesh import transformations as tf

    box = trimesh.creation.box((40.0, 20.0, 10.0))  # mm
    box.apply_translation((5.0, 0.0, 0.0))
    box.export(tmp_path / "part.stl")
    steel = dpm.Material("steel", density=7800, young=2e8, poisson=0.3)
    rot = [(0, 0, 1, 90.0), (1, 0, 0, 30.0)]
    mesh = dpm.boundaries.Mesh(steel, file=tmp_path / "part.stl", scale=1e-3, rotate=rot,
                               translate=(0.1, 0.2, 0.3))
    ref = trimesh.load(tmp_path / "part.stl")
    ref.apply_scale(1e-3)
    ref.apply_transform(tf.rotation_matrix(math.radians(90.0), (0, 0, 1)))
    ref.apply_transform(tf.rotation_matrix(math.radians(30.0), (1, 0, 0)))
    ref.apply_translation((0.1, 0.2, 0.3))
    np.testing.assert_allclose(mesh.vertices, ref.vertices, atol=1e-15)
    assert mesh.volume() == pytest.approx(40e-3 * 20e-3 * 10e-3, rel=1e-12)
    assert mesh.side == "outside"
    as_matrix = dpm.boundaries.Mesh(steel, file=tmp_path / "part.stl", scale=1e-3,
                                    rotate=mesh.rotation, translate=(0.1, 0.2, 0.3))
    np.testing.assert_allclose(as_matrix.vertices, ref.vertices, atol=1e-15)
    for bad, msg in [((0, 0, 0, 10.0), "zero axis"), (np.diag([1.0, 1.0, -1.0]),
                     "not a rotation matrix"), ((1, 2, 3), "allowed: \\(ax, ay, az, degrees\\)")]:
        with pytest.raises(dpm.ParameterError, match=f"rotate=.*{msg}"):
            dpm.boundaries.Mesh(steel, file=tmp_path / "part.stl", rotate=bad)


def _spheres_thrown_at_a_coarse_ball(n: int = 120):
    """n spheres (r = 1.4 mm) thrown from a shell at a coarse icosphere (80 triangles, every
    edge and vertex convex and active), zero gravity: many edge and vertex contacts."""
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.01)
    a = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, 0), threads=1)
    sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.contact(a, w, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("mesh", material=w, vertices=np.asarray(ball.vertices),
                     faces=np.asarray(ball.faces))
    rng = np.random.default_rng(3)
    k = np.arange(n) + 0.5  # a Fibonacci sphere of directions
    phi = np.arccos(1 - 2 * k / n)
    theta = np.pi * (1 + 5 ** 0.5) * k
    u = np.c_[np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
    sim.add_particles("sphere", material=a, radius=1.4e-3, positions=0.0128 * u,
                      velocities=-0.6 * u + rng.normal(0, 0.2, u.shape))
    return sim


def test_triangle_shortcut_leaves_the_trajectories_bit_for_bit(monkeypatch):
    """Spheres thrown at a coarse ball mesh (convex edges and vertices) for 8,000 steps:
    the same state bit for bit with the triangles' smallest altitudes (the distance-bound
    shortcut) and with them zeroed (then only a candidate whose plane lies past reach skips
    the exact closest point). The scene is sensitive to a wrong bound: with the altitudes
    3x too large the shortcut drops edge and vertex contacts and the state differs."""
    import dpm.boundaries.mesh as mesh_mod

    def state(sim):
        sim.run(steps=8000, progress=False)
        return np.c_[sim.bodies.position, sim.bodies.velocity, sim.bodies.angular_velocity]

    true_altitudes = mesh_mod.smallest_altitudes
    fast = _spheres_thrown_at_a_coarse_ball()
    assert fast.boundaries[0].primitives().par[:, 19].min() > 0.0
    got = state(fast)
    monkeypatch.setattr(mesh_mod, "smallest_altitudes", lambda duals: np.zeros(len(duals)))
    want = state(_spheres_thrown_at_a_coarse_ball())
    assert np.array_equal(got, want)
    monkeypatch.setattr(mesh_mod, "smallest_altitudes", lambda duals: 3 * true_altitudes(duals))
    wrong = state(_spheres_thrown_at_a_coarse_ball())
    assert not np.array_equal(got, wrong)
