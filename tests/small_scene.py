"""The small box scene the I/O, restart and operations tests share (one law, boundary and
integrator: their compiled step module is shared too): spheres of 1 mm in a 10 x 10 x 20 mm
glass box open at the top, a lattice 4 mm deep (``shift`` raises it)."""

from __future__ import annotations

import dpm


def small_scene(friction: float = 0.5, shift: float = 0.0) -> dpm.Simulation:
    sim = dpm.Simulation(dt=2e-5, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=friction)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02),
                     open=("+z",))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.004), spacing=2.1e-3, jitter=4e-5)
    xyz[:, 2] += shift
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz)
    return sim
