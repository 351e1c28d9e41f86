"""A short run of ellipsoids and cubes in a turning drum, written with their solid shapes
(``sim.output(..., solids=True)``), for ``scene_snapshot.py --solids``.

    python docs/render/solids_run.py /tmp/solids.h5
"""

from __future__ import annotations

import sys

import numpy as np

import dpm


def main(path: str) -> None:
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    steel = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.4, friction=0.5)
    sim.add_boundary("tube", material=steel, start=(0, -0.01, 0), axis=(0, 1, 0),
                     length=0.02, radius=0.025, caps="both",
                     motion=dpm.Rotation(axis=(0, 1, 0), rpm=30))
    xyz = dpm.lattice((-0.015, -0.006, -0.02), (0.015, 0.006, 0.0), 4.5e-3, jitter=2e-4,
                      seed=1)
    xyz = xyz[np.hypot(xyz[:, 0], xyz[:, 2]) < 0.021]
    q = np.random.default_rng(2).normal(size=(len(xyz), 4))
    sim.add_particles("ellipsoid", material=glass, positions=xyz[0::2], orientations=q[0::2],
                      a=2e-3, b=1e-3)
    sim.add_particles("cube", material=glass, positions=xyz[1::2], orientations=q[1::2],
                      a=2.4e-3)
    sim.output(path, every=0.05, overwrite=True, solids=True)
    sim.run(until=0.3)
    print(f"{len(xyz)} bodies, t = {sim.time:.2f} s -> {path}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "solids.h5")
