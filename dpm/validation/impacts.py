"""Many independent impacts in one scene, run through the public API (the real engine).

A group is one :class:`dpm.Simulation`: a plane z = 0 (a rigid wall: its material is the
first species' with 10^6 times its Young's modulus) and any number of impacts laid side by
side along y, far enough apart that they never touch each other. Every scene first binds
the same list of impact models (:func:`dpm.impact.measure.bind`), so all of them run on
one compiled step module, whatever law a group measures.

Geometry and signs (every impact starts touching, overlap 1e-9 R1, so the contact opens
at the first step):

* ``wall``: sphere 1 at (0, y_k, R1 - eps) with velocity (vt1, 0, -vn1) and spin (0, w1, 0);
  its contact point moves along x at vt1 + surf1 with the surface speed surf1 = -w1 R1.
* ``pair``: sphere 1 at (-R1 + eps, y_k, h), sphere 2 at (R2, y_k, h) (h above the plane);
  velocities (vn1, vt1, 0) and (-vn2, vt2, 0), spins (0, 0, w1) and (0, 0, w2); the
  contact points move along y with surface speeds surf1 = w1 R1 and surf2 = -w2 R2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np

#: the impact models every validation scene binds, in this order (the list and order of
#: tests/physics/test_impact_models.py, so both share one compiled step)
BIND = ["linear_spring_dashpot", "maw_linear_spring", "hooke", "hertz_brilliantov",
        "hertz_mindlin", "walton_braun", "linear_cohesion"]

#: the rigid plane's Young's modulus relative to the first species'
WALL_STIFFNESS = 1e6


@dataclass
class Species:
    """A sphere material and the law (model, parameters) it meets the wall and others with."""

    name: str
    density: float
    young: float
    poisson: float
    model: str
    params: dict[str, Any]


@dataclass
class Impact:
    """One impact (see the module docstring for the axes)."""

    geometry: str
    radius1: float
    vn1: float
    vt1: float = 0.0
    w1: float = 0.0
    species1: int = 0
    radius2: float = 0.0
    vn2: float = 0.0
    vt2: float = 0.0
    w2: float = 0.0
    species2: int = 0


@dataclass
class Outcome:
    """What an impact gave, in the impact's own axes (after the contact ended)."""

    restitution: float   #: separation speed / approach speed
    vt1: float           #: tangential velocity of sphere 1 after [m/s]
    surf1: float         #: surface speed of sphere 1's contact point after [m/s]
    w1: float            #: spin of sphere 1 after [rad/s]
    vt2: float = 0.0
    surf2: float = 0.0
    w2: float = 0.0
    momentum: tuple[float, float] = (0.0, 0.0)   #: tangential momentum before, after
    angular: tuple[float, float] = (0.0, 0.0)    #: angular momentum about z, before, after
    force: np.ndarray = field(default_factory=lambda: np.zeros(0))   #: normal force/step
    overlap: np.ndarray = field(default_factory=lambda: np.zeros(0))  #: overlap/step
    dt: float = 0.0


def _reduced(imp: Impact, species: Sequence[Species]) -> tuple[float, float]:
    m1 = 4.0 / 3.0 * math.pi * imp.radius1**3 * species[imp.species1].density
    if imp.geometry == "wall":
        return m1, imp.radius1
    m2 = 4.0 / 3.0 * math.pi * imp.radius2**3 * species[imp.species2].density
    return m1 * m2 / (m1 + m2), imp.radius1 * imp.radius2 / (imp.radius1 + imp.radius2)


def run_group(species: Sequence[Species], impacts: Sequence[Impact], *,
              steps_per_contact: int = 200, record: bool = False) -> list[Outcome]:
    """Run ``impacts`` in one scene until every contact has ended; their outcomes.

    ``record``: sample the normal force and overlap of every impact at every step (one
    ``sim.run(steps=1)`` per step; otherwise the steps run in one call).
    """
    import dpm
    from dpm.impact.measure import bind

    mats = [dpm.Material(s.name, density=s.density, young=s.young, poisson=s.poisson)
            for s in species]
    s0 = species[0]
    wall = dpm.Material("rigid_wall", density=s0.density, young=WALL_STIFFNESS * s0.young,
                        poisson=s0.poisson)
    reg = dpm.registry()
    # the step: the shortest contact of the group resolved by steps_per_contact steps
    times = []
    for imp in impacts:
        sp = species[imp.species1]
        law = reg.lookup("impact_model", sp.model)(**sp.params)
        other = wall if imp.geometry == "wall" else mats[imp.species2]
        meff, reff = _reduced(imp, species)
        times.append(law.contact_time(mats[imp.species1], other, meff, reff,
                                      imp.vn1 + imp.vn2))
    dt = min(times) / steps_per_contact
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, 0.0), integrator="velocity_verlet",
                         dt_check="off", max_overlap=1.0)
    bind(sim, BIND)
    for i, sp in enumerate(species):
        sim.contact(mats[i], wall, model=sp.model, **sp.params)
        for j in range(i, len(species)):
            sim.contact(mats[i], mats[j], model=sp.model, **sp.params)
    sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    rmax = max(max(imp.radius1, imp.radius2) for imp in impacts)
    t_run = 1.6 * max(times)
    vmax = max(abs(imp.vt1) + abs(imp.vt2) + abs(imp.vn1) + abs(imp.vn2) for imp in impacts)
    spacing = 6.0 * rmax + 4.0 * vmax * t_run
    height = 3.0 * rmax
    ids = []
    for k, imp in enumerate(impacts):
        y = k * spacing
        eps = 1e-9 * imp.radius1
        if imp.geometry == "wall":
            a = sim.add_particles("sphere", material=mats[imp.species1], radius=imp.radius1,
                                  positions=[[0.0, y, imp.radius1 - eps]],
                                  velocities=[[imp.vt1, 0.0, -imp.vn1]],
                                  angular_velocities=[[0.0, imp.w1, 0.0]])
            ids.append((int(a[0]), -1))
        elif imp.geometry == "pair":
            a = sim.add_particles("sphere", material=mats[imp.species1], radius=imp.radius1,
                                  positions=[[-imp.radius1 + eps, y, height]],
                                  velocities=[[imp.vn1, imp.vt1, 0.0]],
                                  angular_velocities=[[0.0, 0.0, imp.w1]])
            b = sim.add_particles("sphere", material=mats[imp.species2], radius=imp.radius2,
                                  positions=[[imp.radius2, y, height]],
                                  velocities=[[-imp.vn2, imp.vt2, 0.0]],
                                  angular_velocities=[[0.0, 0.0, imp.w2]])
            ids.append((int(a[0]), int(b[0])))
        else:
            raise ValueError(f"geometry={imp.geometry!r}; allowed: wall, pair")

    def rows() -> dict[int, int]:
        return {int(i): r for r, i in enumerate(sim.bodies.id)}

    def moments(k: int, pair: tuple[int, int], where: dict[int, int]):
        """(tangential momentum, angular momentum about z through the fixed point
        (0, y_k, h)) of the pair of impact k."""
        b = sim.bodies
        r1, r2 = where[pair[0]], where[pair[1]]
        p = b.mass[r1] * b.velocity[r1, 1] + b.mass[r2] * b.velocity[r2, 1]
        c = np.array([0.0, k * spacing, height])
        lz = 0.0
        for r in (r1, r2):
            d = b.position[r] - c
            v = b.velocity[r]
            lz += b.mass[r] * (d[0] * v[1] - d[1] * v[0]) + b.inertia[r, 2] * \
                b.angular_velocity[r, 2]
        return p, lz

    where = rows()
    before = [moments(k, pr, where) if imp.geometry == "pair" else (0.0, 0.0)
              for k, (imp, pr) in enumerate(zip(impacts, ids, strict=True))]

    def overlaps(where: dict[int, int]) -> np.ndarray:
        b = sim.bodies
        out = np.empty(len(impacts))
        for k, (imp, (i, j)) in enumerate(zip(impacts, ids, strict=True)):
            if imp.geometry == "wall":
                out[k] = imp.radius1 - b.position[where[i], 2]
            else:
                d = np.linalg.norm(b.position[where[j]] - b.position[where[i]])
                out[k] = imp.radius1 + imp.radius2 - d
        return out

    def forces(where: dict[int, int]) -> np.ndarray:
        b = sim.bodies
        return np.array([b.force[where[i], 2] if imp.geometry == "wall"
                         else -b.force[where[i], 0]
                         for imp, (i, _) in zip(impacts, ids, strict=True)])

    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # a few bodies: a parallel launch per step would only cost
    fs: list[np.ndarray] = []
    ds: list[np.ndarray] = []
    try:
        n = int(math.ceil(t_run / dt))
        for _ in range(6):
            if record:
                for _ in range(n):
                    sim.run(steps=1, progress=False)
                    where = rows()
                    fs.append(forces(where))
                    ds.append(overlaps(where))
            else:
                sim.run(steps=n, progress=False)
            where = rows()
            if np.all(overlaps(where) < 0.0):
                break
            n = max(1, n // 3)
        else:
            raise RuntimeError("validation impacts: a contact did not end "
                               f"(overlaps {overlaps(where)})")
    finally:
        numba.set_num_threads(threads)
    b = sim.bodies
    force = np.array(fs) if fs else np.zeros((0, len(impacts)))
    overlap = np.array(ds) if ds else np.zeros((0, len(impacts)))
    out = []
    for k, (imp, (i, j)) in enumerate(zip(impacts, ids, strict=True)):
        ri = where[i]
        if imp.geometry == "wall":
            o = Outcome(restitution=b.velocity[ri, 2] / imp.vn1, vt1=b.velocity[ri, 0],
                        surf1=-b.angular_velocity[ri, 1] * imp.radius1,
                        w1=b.angular_velocity[ri, 1])
        else:
            rj = where[j]
            o = Outcome(restitution=(b.velocity[rj, 0] - b.velocity[ri, 0])
                        / (imp.vn1 + imp.vn2),
                        vt1=b.velocity[ri, 1], surf1=b.angular_velocity[ri, 2] * imp.radius1,
                        w1=b.angular_velocity[ri, 2], vt2=b.velocity[rj, 1],
                        surf2=-b.angular_velocity[rj, 2] * imp.radius2,
                        w2=b.angular_velocity[rj, 2])
            after = moments(k, (i, j), where)
            o.momentum = (before[k][0], after[0])
            o.angular = (before[k][1], after[1])
        o.force = force[:, k].copy()
        o.overlap = overlap[:, k].copy()
        o.dt = dt
        out.append(o)
    return out
