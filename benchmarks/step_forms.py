"""The step module's two forms on small and mesh scenes: as compiled (``prange`` loops,
one parallel launch each even on one thread) against a one-thread form (the same
generated module with its ``prange`` loops made plain loops), swapped in turn on the same
scenes in one process (benchmarks/NOTES.md row 46).

The scenes are ``boundaries.mesh_scaling``'s floors (with its far-away sentinel
boundaries, ``sphere_orientation=False``): 1 sphere on 2 triangles, 81 spheres on 200,
2,000 spheres on one 210 mm floor of 200 and of 2,048 triangles. Prints ns per
sphere-step of each form and their ratio, three rounds. The one-thread form is written
beside the cached module (``*_serial.py``) and compiled here (minutes on a cold cache).

    python benchmarks/step_forms.py
"""

from __future__ import annotations

import importlib.util
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

sys.path.insert(0, str(Path(__file__).resolve().parent))

CASES = [(1, None, 1), (10, None, 81), (10, 0.21, 2000), (32, 0.21, 2000)]


def scene(m: int, side: float | None, n_spheres: int):
    import boundaries as B

    import dpm

    cell = 4e-3 if side is None else side / m
    verts, faces = B.grid_floor(m, cell)
    a = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, 0), dt_check="off", threads=1,
                         skin=B.SKIN, sphere_orientation=False)
    sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.contact(a, w, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("mesh", material=w, vertices=verts, faces=faces)
    B.sentinels(sim, w)
    half, r = 0.5 * m * cell, B.R
    rng = np.random.default_rng(1)
    k = max(1, min(int(math.ceil(math.sqrt(n_spheres))), int(2 * half / (2.2 * r))))
    g = (np.arange(k) - 0.5 * (k - 1)) * 2.2 * r
    xy = np.array([(x, y) for x in g for y in g])[:n_spheres]
    xy = xy + rng.uniform(-0.02 * r, 0.02 * r, xy.shape)
    sim.add_particles("sphere", material=a, radius=r,
                      positions=np.c_[xy, np.full(len(xy), r * 0.9999)])
    sim.run(steps=5, progress=False)
    return sim


def one_thread_form(module):
    """The generated module with its ``prange(`` loops made ``range(`` (still compiled
    with parallel=True, which numba then reports it could not use)."""
    path = Path(module.__file__).with_name(Path(module.__file__).stem + "_serial.py")
    path.write_text(Path(module.__file__).read_text().replace("prange(", "range("))
    spec = importlib.util.spec_from_file_location(module.__name__ + "_serial", path)
    out = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = out
    spec.loader.exec_module(out)
    return out


def main() -> None:
    import warnings

    warnings.simplefilter("ignore")  # (numba: "parallel=True ... no transformation")
    sims = [scene(*c) for c in CASES]
    par = sims[0].backend.module
    t0 = time.perf_counter()
    ser = one_thread_form(par)
    for s in sims:  # compile (or load) the one-thread form
        s.backend.module = ser
        s.run(steps=5, progress=False)
    print(f"one-thread form ready in {time.perf_counter() - t0:.0f} s", flush=True)
    for _ in range(3):
        for case, s in zip(CASES, sims, strict=True):
            ns = []
            for mod in (par, ser):
                s.backend.module = mod
                n = max(1000, int(1e6 / len(s.bodies)))
                s.run(steps=200, progress=False)
                t = time.perf_counter()
                s.run(steps=n, progress=False)
                ns.append((time.perf_counter() - t) / n / len(s.bodies) * 1e9)
            print(f"floor m={case[0]} side={case[1]} spheres={case[2]}: ns per sphere-step "
                  f"parallel form {ns[0]:.1f}, one-thread form {ns[1]:.1f}, "
                  f"ratio {ns[1] / ns[0]:.3f}", flush=True)


if __name__ == "__main__":
    main()
