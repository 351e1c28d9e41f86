"""Measure one collision in the engine: duration, largest overlap, restitution, spin.

Used by the tests and ``benchmarks/impact_models.py`` to compare each model with its
analytic solution. The collision runs through the public :class:`dpm.Simulation` (the
scene's own step kernel), one step per call, and is read from the state after each step.

Geometry: ``"wall"`` (a sphere of radius r1 hits a plane z = 0 of a second material with
the same constants, so the pair's scene context is the sphere's) or ``"pair"`` (spheres r1
and r2 of the same material meet head-on at the origin, zero total momentum). The bodies
touch at t = 0 (overlap 1e-9 r1), so the contact starts at t = 0 and the force a dashpot
has at first touch is in the forces the first step starts from.

Estimates from the samples (step dt): the end of the contact is where the normal force
reaches zero, extrapolated from the last two non-zero samples of F^(1/p) (``end_exponent``
p: 1 when the force ends with a finite slope, as with a dashpot or a cut-off; 3/2 for an
elastic Hertz contact, F ~ d^(3/2)); the largest overlap is the vertex of the parabola
through the three samples around the largest one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

#: the fewest parameters each built-in model needs, for :func:`bind`
MINIMAL_PARAMS: dict[str, dict[str, float]] = {
    "linear_spring_dashpot": {"stiffness": 1.0},
    "walton_braun": {"stiffness": 1.0},
    "hertz_brilliantov": {"dissipation": 0.0},
    "linear_cohesion": {"cohesion_energy_density": 0.0},
}


def bind(sim, models: Sequence[str]) -> None:
    """Give ``sim`` a contact law of each of ``models`` on unused materials, in this order.

    The step module is generated for the laws of a scene in the order they were set, so
    scenes that call this first with the same list share one compiled step (tests and
    benchmarks of many models then compile once instead of once per model). The materials
    carry no body, so these laws are never evaluated.
    """
    from ..material import Material

    for k, name in enumerate(models):
        m = Material(f"_bind_{k}_{name}", density=1.0, young=1.0, poisson=0.0)
        sim.contact(m, m, model=name, **MINIMAL_PARAMS.get(name, {}))


@dataclass
class Collision:
    """What one collision measured (SI units)."""

    duration: float        #: time the normal force is non-zero [s]
    max_overlap: float     #: largest overlap [m]
    restitution: float     #: -(relative normal velocity after) / (before)
    tangential_restitution: float  #: contact-point tangential velocity after / before
    spin: float            #: angular velocity of sphere 1 about y after the contact [rad/s]
    dt: float              #: the step used [s]
    steps: int             #: steps with a non-zero force
    meff: float            #: m* [kg]
    reff: float            #: R* [m]
    end_overlap: float     #: overlap when the force ended [m] (> 0: cut-off or plastic)
    force: np.ndarray      #: normal force on sphere 1 at each step [N]
    overlap: np.ndarray    #: overlap at each step [m]
    sim: Any = None        #: the Simulation, after the contact


def collide(model: str, params: dict[str, Any], *, speed: float, dt: float,
            geometry: str = "wall", radii: tuple[float, ...] = (1e-3,),
            density: float = 2500.0, young: float | None = 1e7, poisson: float | None = 0.3,
            tangential_speed: float = 0.0, integrator: str = "velocity_verlet",
            end_exponent: float = 1.0, max_steps: int = 200000,
            bind_models: Sequence[str] = ()) -> Collision:
    """Run one head-on (or oblique, ``tangential_speed`` along x; wall only) collision.

    ``bind_models``: see :func:`bind` (the measured law is one of them or added after).
    """
    from ..material import Material
    from ..simulation import Simulation

    sim = Simulation(dt=dt, gravity=(0, 0, 0), integrator=integrator, dt_check="off",
                     max_overlap=1.0)
    bind(sim, bind_models)
    mat = Material("m", density=density, young=young, poisson=poisson)
    wall = Material("wall", density=density, young=young, poisson=poisson)
    sim.contact(mat, mat, model=model, **params)
    sim.contact(mat, wall, model=model, **params)
    r1 = float(radii[0])
    eps = 1e-9 * r1  # touching at t = 0: a dashpot's jump falls on the first evaluation
    m1 = 4.0 / 3.0 * math.pi * r1**3 * density
    if geometry == "wall":
        sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
        sim.add_particles("sphere", material=mat, radius=r1, positions=[[0, 0, r1 - eps]],
                          velocities=[[tangential_speed, 0, -speed]])
        meff, reff = m1, r1
    elif geometry == "pair":
        r2 = float(radii[1] if len(radii) > 1 else radii[0])
        m2 = 4.0 / 3.0 * math.pi * r2**3 * density
        v1, v2 = speed * m2 / (m1 + m2), -speed * m1 / (m1 + m2)
        sim.add_particles("sphere", material=mat, radius=[r1, r2],
                          positions=[[-r1 + eps, 0, 0], [r2, 0, 0]],
                          velocities=[[v1, 0, 0], [v2, 0, 0]])
        meff, reff = m1 * m2 / (m1 + m2), r1 * r2 / (r1 + r2)
    else:
        raise ValueError(f"geometry={geometry!r}; allowed: wall, pair")

    def state() -> tuple[float, float]:
        b = sim.bodies
        if geometry == "wall":
            return r1 - b.position[0, 2], -sim.boundaries[0].force[2]
        d = b.position[1, 0] - b.position[0, 0]
        return r1 + r2 - d, -b.force[0, 0]

    fs, ds = [], []
    started = False
    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # one or two bodies: a parallel launch per step only costs
    try:
        for _ in range(max_steps):
            sim.run(steps=1, progress=False)
            d, f = state()
            fs.append(f)
            ds.append(d)
            if f != 0.0:
                started = True
            elif started and d < 0.0:
                break
    finally:
        numba.set_num_threads(threads)
    f = np.array(fs)
    d = np.array(ds)
    t = dt * np.arange(1, len(f) + 1)
    on = np.nonzero(f != 0.0)[0]
    last = on[-1]
    q = 1.0 / end_exponent
    f1 = abs(f[last - 1]) ** q if last > 0 else 0.0
    f2 = abs(f[last]) ** q
    t_end = t[last] + (dt * f2 / (f1 - f2) if f1 > f2 else 0.0)
    nxt = min(last + 1, len(d) - 1)
    d_end = d[last] + (d[nxt] - d[last]) * (t_end - t[last]) / dt
    k = int(np.argmax(d))
    dmax = d[k]
    if 0 < k < len(d) - 1:
        a, b, c = d[k - 1], d[k], d[k + 1]
        den = a - 2 * b + c
        if den < 0:
            dmax = b - 0.125 * (c - a) ** 2 / den
    b = sim.bodies
    if geometry == "wall":
        e = b.velocity[0, 2] / speed
        vt_after = b.velocity[0, 0] - b.angular_velocity[0, 1] * r1  # contact point, x
        et = vt_after / tangential_speed if tangential_speed else float("nan")
    else:
        e = (b.velocity[1, 0] - b.velocity[0, 0]) / speed
        et = float("nan")
    return Collision(duration=float(t_end), max_overlap=float(dmax), restitution=float(e),
                     tangential_restitution=float(et), spin=float(b.angular_velocity[0, 1]),
                     dt=dt, steps=len(on), meff=meff, reff=reff, end_overlap=float(d_end),
                     force=f, overlap=d, sim=sim)
