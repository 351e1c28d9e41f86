"""Cold compile of a small scene with a surface of revolution: time to its first 5 steps.

Run with a fresh cache per variant; an A/B of two checkouts runs each with its own
PYTHONPATH in one sitting:

    DPM_CACHE_DIR=$(mktemp -d) python benchmarks/compile_tube_scene.py
"""

import time

t0 = time.perf_counter()
import dpm  # noqa: E402  (the import is part of the time to the first step)

sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
g = dpm.Material("g", density=2500, young=1e7, poisson=0.3)
sim.contact(g, g, model="hertz_mindlin", restitution=0.5, friction=0.5)
sim.add_boundary("tube", material=g, start=(0, 0, 0), axis=(0, 0, 1), length=0.05,
                 radius=0.02, caps="start")
sim.add_particles("sphere", material=g, radius=2e-3,
                  positions=dpm.lattice((-0.01, -0.01, 0.0), (0.01, 0.01, 0.02),
                                        spacing=4.5e-3))
sim.run(steps=5, progress=False)
print("first steps", time.perf_counter() - t0)
