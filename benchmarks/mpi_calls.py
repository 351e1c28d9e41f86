"""Kernel calls and the share of the whole-state gather in a 2-rank box_settle run
(benchmarks/NOTES.md row 37): ``MpiBackend.totals`` after a run, printed by rank 0.

    mpiexec --allow-run-as-root -n 2 python benchmarks/mpi_calls.py [NX NY NZ STEPS]

Default: 40 x 40 x 63 (100,800 spheres), 4,000 steps after 50 of warm-up, one thread per
rank. The mean height is printed to 12 digits so that two variants can be compared.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import os

from box_settle import _example  # noqa: E402

import dpm  # noqa: E402

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module


def main(argv: list[str]) -> None:
    nx, ny, nz, steps = (int(a) for a in (argv or ["40", "40", "63", "4000"]))
    ex = _example()
    sim = ex.build(ex.initial_packing(nx, ny, nz))
    sim.threads = 1
    sim.run(steps=50, progress=False)
    be = sim.backend
    be.totals.clear()
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    tot = be.totals
    if dpm.parallel.rank() == 0:
        print(f"{len(sim.bodies)} bodies, {steps} steps: wall {wall:.2f} s, calls "
              f"{tot.get('calls', 1):.0f}, gather {tot.get('gather_s', 0.0):.3f} s "
              f"({tot.get('gather_s', 0.0) / wall:.1%}), scatter {tot.get('scatter_s', 0.0):.3f}"
              f" s, halo {tot.get('halo_s', 0.0):.2f} s, migrate {tot.get('migrate_s', 0.0):.2f}"
              f" s, mean height {sim.bodies.position[:, 2].mean():.12f} m")


if __name__ == "__main__":
    main(sys.argv[1:])
