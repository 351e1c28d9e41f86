"""Where the mesh floor's step goes on one thread and on two (issue "Speed on every kind
of scene").

The fixed floor of ``boundaries.py`` (2,000 spheres resting on a 210 mm floor of 2 m^2
triangles, the sentinel boundaries of every kind), stepped on one thread (the one-thread
form) and on two (the parallel form) in turn, twice: the whole step through ``sim.run``,
and, each in a compiled loop of calls, the integrator's pre-force pass, the fused force
pass, and ``compute_forces`` (the fused pass plus its serial loops over the boundary
entries and the elements). Prints microseconds per step.

    python benchmarks/mesh_floor_threads.py [M] [STEPS]     # M = 10: 200 triangles
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
os.environ.setdefault("DPM_KERNELS", "scene")

import boundaries as B  # noqa: E402
import numba  # noqa: E402
import numpy as np  # noqa: E402
from step_forms import scene  # noqa: E402


def timed(sim, threads, nsteps):
    sim.threads = threads
    sim.run(steps=5, progress=False)
    r0 = sim.rebuild_count
    t = time.perf_counter()
    sim.run(steps=nsteps, progress=False)
    el = time.perf_counter() - t
    return el / nsteps * 1e6, sim.rebuild_count - r0



def loops(mod):
    """Compiled loops of ``reps`` calls of three step parts of module ``mod``."""
    fp, cf, pf = mod.fused_pass, mod.compute_forces, mod.pre_force

    @numba.njit
    def lf(n, ctl, bodies, elems, pairs, walls, bnd):
        for _ in range(n):
            fp(0.0, False, ctl, bodies, elems, pairs, walls, bnd)

    @numba.njit
    def lc(n, ctl, bodies, elems, pairs, walls, bnd, diag):
        for _ in range(n):
            cf(0.0, False, ctl, bodies, elems, pairs, walls, bnd, diag)

    @numba.njit
    def lp(n, ctl, bodies, elems):
        for _ in range(n):
            pf(0.0, ctl, bodies, elems)

    return lf, lc, lp


def main() -> None:
    m = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    reps = int(sys.argv[2]) if len(sys.argv) > 2 else 2000
    sim = scene(m, B.FIXED_FLOOR, 2000)  # (step_forms.py's floor: the same scene)

    def best(fn, *args, k=5):
        b = 1e9
        for _ in range(k):
            t = time.perf_counter()
            fn(*args)
            b = min(b, time.perf_counter() - t)
        return b / reps * 1e6

    cache = {}
    for th in (1, 2, 1, 2):
        timed(sim, th, 200)
        w = best(lambda: sim.run(steps=reps, progress=False), k=3)
        numba.set_num_threads(th)
        sim.backend.sync_form()
        mod = sim.backend.module
        if id(mod) not in cache:
            cache[id(mod)] = loops(mod)
        lf, lc, lp = cache[id(mod)]
        ctl, bodies, elems, pairs, walls, bnd = sim.backend.records()
        diag = np.zeros(8)
        tp = best(lp, reps, ctl, bodies, elems)
        tf = best(lf, reps, ctl, bodies, elems, pairs, walls, bnd)
        tc = best(lc, reps, ctl, bodies, elems, pairs, walls, bnd, diag)
        form = "one-thread" if sim.backend._form[1] else "parallel"
        print(f"threads {th} ({form} form): whole {w:.1f} us/step; pre_force {tp:.1f}, "
              f"fused_pass {tf:.1f}, compute_forces {tc:.1f} (its serial part {tc - tf:.1f})",
              flush=True)


if __name__ == "__main__":
    main()
